/* checkpoint.h - the complete state of a run in one HDF5 file, written atomically and read
 * back with every dimension, type and count checked.
 *
 * What a run needs to continue bit for bit: the particles (every array, in their current
 * memory order, because the order decides the order of floating-point sums), time, step,
 * frame counters, the last dt and the speed that sets the next one, the dt back-off of the
 * retry guard, the fingerprint of the scene, the particle domains (their particles, corner
 * indices, weights, active flags, and the corners' reference and current positions and
 * velocities), and the per-frame records the outputs are
 * rebuilt from (frame times and names for the PVD, stats rows and the colliders' forces for
 * stats.csv). Colliders move
 * as pure functions of time and the sampling's random jitter is spent at creation, so time
 * is their whole state. Every dataset carries a Fletcher-32 checksum: a damaged file is
 * refused instead of resumed. */
#ifndef MPM_IO_CHECKPOINT_H
#define MPM_IO_CHECKPOINT_H

#include "core/error.h"
#include "domain/domain.h"
#include "io/io.h"
#include "core/particles.h"

#include <stdint.h>

#define MPM_CHECKPOINT_VERSION 9
#define MPM_FRAME_NAME_MAX 64
#define MPM_CKPT_SOLVER_FIGURES 12

typedef struct mpm_checkpoint {
  uint64_t scene_hash; /* FNV-1a of the scene text */
  double time, last_dt;
  double max_speed; /* fastest particle after the last step, m/s */
  int64_t steps;
  int frame;          /* frames completed */
  int written_frames; /* frames written (frame 0 included) */
  int dt_level;       /* the retry guard's current halvings of dt */
  int threads;        /* threads of the run that wrote it (informative) */
  uint32_t next_id;   /* the id the next particle made by a split gets (ids are never reused) */
  /* the implicit solver's figures of the frame in progress (stats.csv): steps, CG iterations,
   * Newton iterations, unconverged steps, most CG iterations of a step, largest residual; then
   * the frame's step figures (stats.csv's dt columns): steps, full (not shortened) steps, the
   * sums of both, the shortest and the longest step */
  double solver_figures[MPM_CKPT_SOLVER_FIGURES];
  mpm_particles particles;
  mpm_domain_set domains; /* Zhu's particle domains: particles, corners, weights, active */
  /* the multi-level grid's refined cells when it is rebuilt during the run
   * (domain.refine_every): level, i, j, k of each, tree_count of them */
  int32_t *tree[4];
  uint64_t tree_count;
  /* per-frame records, `records` of them (= written_frames) */
  int records;
  double *frame_times;
  char (*frame_files)[MPM_FRAME_NAME_MAX];
  mpm_stats_row *stats;
  /* the colliders' force columns of stats.csv (0 and NULL for a scene without colliders, and
   * in checkpoints from before them): 3 per collider in each of records + 1 rows, the first the
   * momentum they took in the frame in progress (kg m/s), then the records' mean forces (N) */
  int colliders;
  double *collider_forces;
  /* a digest of each body's mesh file as the run read it (io/input_file.h), 0 for a body
   * without one: mesh_count entries (the scene's bodies) when the scene has a mesh body, else 0
   * and NULL (as in checkpoints from before them) */
  int mesh_count;
  uint64_t *mesh_digests;
  /* colliders moved by a script (collide/collider.h): MPM_COLLIDER_SCRIPT_DOUBLES per collider
   * of the `colliders` when any is scripted, else NULL (as in checkpoints from before them) */
  double *collider_scripts;
} mpm_checkpoint;

/* Write *c to `path` atomically (a temporary in the same directory, renamed when complete).
 * On failure the old file at `path` is untouched and err names the file and what failed. */
mpm_status mpm_checkpoint_write(const char *path, const mpm_checkpoint *c, mpm_error *err);

/* Read a checkpoint. *c is filled (particles and records allocated; release them with
 * mpm_checkpoint_free) or, on any failure, left empty with err naming the file and the
 * dataset or attribute that is missing, damaged or inconsistent. */
mpm_status mpm_checkpoint_read(const char *path, mpm_checkpoint *c, mpm_error *err);

/* The same from the file's bytes in memory (path only names it in messages). */
mpm_status mpm_checkpoint_parse(const void *data, size_t size, const char *path, mpm_checkpoint *c,
                                mpm_error *err);

/* Write the guard header (magic, version, size, digest) into the first 512 bytes of a
 * checkpoint image of `size` bytes, as the writer does; for tools and the fuzz target. */
void mpm_checkpoint_seal(void *image, size_t size);

void mpm_checkpoint_free(mpm_checkpoint *c);

#endif
