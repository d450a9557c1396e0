/* mpi_frame_writer.c - the frame writer of a run on ranks (sim/frame_writer.h, dist_sim.h).
 *
 * A rank holds the particles of its blocks only, so each rank writes them as a piece of the
 * frame, in the serial writer's formats (io/io.h): frame_NNNN_pRRRR.vtu (VTK XML
 * UnstructuredGrid, the same arrays as frame_NNNN.vtu) and with output.ply frame_NNNN_pRRRR.ply.
 * Rank 0 then writes what names them all: frame_NNNN.pvtu (VTK XML PUnstructuredGrid: the
 * pieces' arrays and one <Piece Source> per rank), frames.pvd and run.pvd listing the .pvtu of
 * every frame (ParaView opens the run from either), and stats.csv, whose figures the simulation
 * already reduced over every rank. Every file goes through the io module's atomic writers
 * (temporary, then rename), as one process's do; an index is written only after every piece it
 * names is, so a reader never finds an index naming a missing piece.
 *
 * A rank that fails (a full disk, out of memory) must not leave the others waiting: the ranks
 * agree after the pieces and after the indexes (mpm_dist_agree), and every rank returns the
 * status and message of the rank where the failure began.
 *
 * The output folder is claimed and locked by rank 0 alone (io/run_folder.h: the lock is one
 * process's flock, and the removal under --overwrite must happen once, before any rank writes);
 * the others learn its verdict and use the folder at the same path. */
#include "dist/dist_sim.h"
#include "core/alloc.h"
#include "io/io.h"
#include "sim/frame_writer.h"
#include "sim/sim.h"

#include <stdio.h>

/* A piece's name: the frame, then the rank (four digits or more, io/run_folder.c's pattern). */
static void piece_name(char *out, size_t cap, int frame, int rank, const char *ext) {
  snprintf(out, cap, "frame_%04d_p%04d.%s", frame, rank, ext);
}

/* Rank 0's files of the frame: the .pvtu, the indexes and stats.csv. */
static mpm_status write_indexes(mpm_sim *sim, const mpm_frame_record *r, int ranks) {
  const mpm_output_desc *o = &sim->scene.output;
  const int frame = r->frame;
  char path[MPM_PATH_MAX + 64];
  mpm_status st = MPM_OK;
  if (o->vtu) {
    enum { NAME = 48 };
    char(*names)[NAME] = mpm_alloc((size_t)ranks * NAME);
    const char **sources = mpm_alloc((size_t)ranks * sizeof *sources);
    if (!names || !sources) {
      st = mpm_error_set(&sim->error, MPM_ERR_NOMEM, "out of memory writing frame %d", frame);
    } else {
      for (int k = 0; k < ranks; ++k) {
        piece_name(names[k], NAME, frame, k, "vtu");
        sources[k] = names[k];
      }
      snprintf(path, sizeof path, "%s/frame_%04d.pvtu", r->dir, frame);
      st = mpm_write_pvtu(path, &r->ff, ranks, sources, &sim->error);
    }
    mpm_free(names);
    mpm_free(sources);
    if (st != MPM_OK) return st;
  }
  if (o->vtu && r->records) {
    const char *files[frame + 1];
    for (int f = 0; f <= frame; ++f) files[f] = sim->out.frame_files[f];
    snprintf(path, sizeof path, "%s/frames.pvd", sim->out.dir);
    st = mpm_write_pvd(path, frame + 1, sim->out.frame_times, files, &sim->error);
    /* run.pvd: the same, as the one part a frame has on ranks (no domains, surfaces or levels) */
    const char *part[] = {"particles"};
    snprintf(path, sizeof path, "%s/run.pvd", sim->out.dir);
    if (st == MPM_OK)
      st = mpm_write_pvd_parts(path, frame + 1, 1, sim->out.frame_times, part, files, &sim->error);
    if (st != MPM_OK) return st;
  }
  if (r->stats_rows > 0) st = mpm_sim_write_stats(sim, r->stats_rows);
  return st;
}

static mpm_status write_frame(mpm_sim *sim, const mpm_frame_record *r) {
  mpm_dist *d = mpm_dist_of(sim);
  const int rank = mpm_dist_rank(d), ranks = mpm_dist_size(d);
  const mpm_output_desc *o = &sim->scene.output;
  char name[48], path[MPM_PATH_MAX + 64];
  mpm_status st = MPM_OK;
  if (!r->records) /* (mpm_sim_write_frame_to refuses a run on ranks before it comes here) */
    st = mpm_error_set(&sim->error, MPM_ERR_INVALID, "a one-off frame is not written on ranks");
  if (st == MPM_OK && o->vtu) {
    piece_name(name, sizeof name, r->frame, rank, "vtu");
    snprintf(path, sizeof path, "%s/%s", r->dir, name);
    st = mpm_write_vtu(path, &r->ff, &sim->error);
  }
  if (st == MPM_OK && o->ply) {
    piece_name(name, sizeof name, r->frame, rank, "ply");
    snprintf(path, sizeof path, "%s/%s", r->dir, name);
    st = mpm_write_ply_points(path, &r->ff, &sim->error);
  }
  st = mpm_dist_agree(d, st, &sim->error); /* every piece is there before an index names it */
  if (st != MPM_OK) return st;
  if (o->vtu) { /* the run's record of its frames, the same on every rank */
    snprintf(sim->out.frame_files[r->frame], sizeof sim->out.frame_files[r->frame],
             "frame_%04d.pvtu", r->frame);
    sim->out.frame_times[r->frame] = sim->time;
  }
  if (rank == 0) st = write_indexes(sim, r, ranks);
  return mpm_dist_agree(d, st, &sim->error);
}

static const char NO_CHECKPOINTS[] =
    "checkpoints are not written on ranks yet (collective HDF5 checkpoints are to come): a run "
    "on ranks cannot be resumed";

static mpm_status write_checkpoint(mpm_sim *sim, const char *path, const mpm_checkpoint *c) {
  (void)c;
  return mpm_error_set(&sim->error, MPM_ERR_INVALID, "%s: %s", path, NO_CHECKPOINTS);
}

/* Rank 0 makes, locks and claims the folder and writes the scene's copy; every rank gets its
 * verdict (and message), and the others take the folder as the run's only when it stands. */
static mpm_status open_folder(mpm_sim *sim, const char *dir, int how) {
  mpm_dist *d = mpm_dist_of(sim);
  const int rank = mpm_dist_rank(d);
  mpm_status st = rank == 0 ? mpm_sim_prepare_output(sim, dir, how) : MPM_OK;
  st = mpm_dist_agree(d, st, &sim->error);
  if (st == MPM_OK && rank != 0) snprintf(sim->out.dir, sizeof sim->out.dir, "%s", dir);
  return st;
}

const mpm_frame_writer mpm_frame_ranks = {
    .name = "ranks",
    .frame = write_frame,
    .checkpoint = write_checkpoint,
    .open = open_folder,
    .no_checkpoints = NO_CHECKPOINTS,
};
