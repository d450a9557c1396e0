/* frame_writer.h - where a simulation's frames and checkpoints go, behind one table.
 *
 * The simulation makes what a frame holds (frame_record: the particles as written, their
 * derived fields, checked finite; the stats row with the run's figures over every process) and
 * hands it to its writer; a checkpoint likewise hands over the state to keep. The writer decides
 * the files: the default (frame_files.c) writes every file of the frame from this process, as a
 * single process does; a distributed run gives its ranks a writer that writes their pieces or
 * gathers them. */
#ifndef MPM_SIM_FRAME_WRITER_H
#define MPM_SIM_FRAME_WRITER_H

#include "io/checkpoint.h"
#include "io/io.h"

typedef struct mpm_sim mpm_sim;

typedef struct mpm_frame_record {
  int frame;       /* its number */
  const char *dir; /* the folder it goes to */
  /* the run's own folder: its indexes (frames.pvd, run.pvd) and stats.csv are written, and the
   * frame counted; 0 for a one-off (mpm_sim_write_frame_to) */
  int records;
  int has_domains;     /* particles holds the active domain particles after the points */
  mpm_frame_fields ff; /* the particles as written (material points, then active domain
                          particles) with their derived fields */
  int stats_rows;      /* the rows of stats.csv (frame + 1 with records and output.stats) */
} mpm_frame_record;

typedef struct mpm_frame_writer {
  const char *name;
  mpm_status (*frame)(mpm_sim *sim, const mpm_frame_record *r);
  mpm_status (*checkpoint)(mpm_sim *sim, const char *path, const mpm_checkpoint *c);
  /* Make dir the run's folder (mpm_sim_open_output): made, locked and claimed (`how`, an
   * mpm_run_claim), out.dir set and the scene's copy written. NULL: this process does it all
   * (mpm_sim_prepare_output); a run on ranks lets one rank do it and gives every rank its
   * verdict, since the lock is one process's. */
  mpm_status (*open)(mpm_sim *sim, const char *dir, int how);
  /* Why this writer writes no checkpoint, or NULL: then mpm_sim_write_checkpoint and
   * mpm_sim_resume are refused with it, and output.checkpoint_every writes nothing. */
  const char *no_checkpoints;
} mpm_frame_writer;

/* This process writes every file (the default). */
extern const mpm_frame_writer mpm_frame_files;

/* What the default writer's open does (see open above): the folder made, locked and claimed by
 * this process, out.dir set, the scene's copy written. */
mpm_status mpm_sim_prepare_output(mpm_sim *sim, const char *dir, int how);

/* stats.csv in the run's folder, its first `rows` rows (every writer's, from the one process
 * that writes it). */
mpm_status mpm_sim_write_stats(mpm_sim *sim, int rows);

#endif
