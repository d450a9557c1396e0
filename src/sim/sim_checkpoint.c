/* sim_checkpoint.c - a simulation's checkpoints: written into the output directory as
 * checkpoint_<steps>.h5 (zero-padded, so names sort by step), the two newest kept; resumed
 * from the newest one that reads back whole, for the same scene only.
 *
 * The particles are saved in their memory order: P2G sums each node's contributions in the
 * order of the sorted particles, and the sort is stable, so the order is part of the state
 * that makes a resumed run bit-identical to an uninterrupted one (tests/test_checkpoint.c). */
#define _POSIX_C_SOURCE 200809L

#include "core/parallel.h"
#include "domain/enrich.h"
#include "io/checkpoint.h"
#include "io/checkpoint_format.h"
#include "io/run_folder.h"
#include "io/input_file.h"
#include "scene/sample.h"
#include "core/alloc.h"
#include "sim/frame_writer.h"
#include "sim/grid_stack.h"
#include "sim/sim.h"

#include <dirent.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define KEEP_CHECKPOINTS 2
#define NAME_DIGITS 12

void mpm_sim_set_interrupt(mpm_sim *sim, const volatile int *flag) {
  sim->interrupt = flag;
}

/* 1 when `name` is checkpoint_<12 digits>.h5 */
static int is_checkpoint_name(const char *name) {
  if (strncmp(name, "checkpoint_", 11) != 0) return 0;
  for (int i = 0; i < NAME_DIGITS; ++i)
    if (name[11 + i] < '0' || name[11 + i] > '9') return 0;
  return strcmp(name + 11 + NAME_DIGITS, ".h5") == 0;
}

static int by_name_descending(const void *a, const void *b) {
  return -strcmp(*(char *const *)a, *(char *const *)b);
}

/* The checkpoint names in dir, newest first (caller frees each and the array); -1 when the
 * directory cannot be read. */
static int list_checkpoints(const char *dir, char ***out) {
  *out = NULL;
  DIR *d = opendir(dir);
  if (!d) return -1;
  int n = 0, cap = 0;
  char **names = NULL;
  for (struct dirent *e; (e = readdir(d));) {
    if (!is_checkpoint_name(e->d_name)) continue;
    /* only what a run writes: a folder, link or FIFO of that name is not a checkpoint */
    struct stat st;
    if (fstatat(dirfd(d), e->d_name, &st, AT_SYMLINK_NOFOLLOW) != 0 || !S_ISREG(st.st_mode))
      continue;
    if (n == cap) {
      cap = cap ? 2 * cap : 8;
      char **bigger = mpm_realloc(names, (size_t)cap * sizeof *names);
      if (!bigger) break;
      names = bigger;
    }
    if (!(names[n] = mpm_strdup(e->d_name))) break;
    ++n;
  }
  closedir(d);
  if (n) qsort(names, (size_t)n, sizeof *names, by_name_descending);
  *out = names;
  return n;
}

static void free_names(char **names, int n) {
  for (int i = 0; i < n; ++i) mpm_free(names[i]);
  mpm_free(names);
}

mpm_status mpm_sim_write_checkpoint(mpm_sim *sim, char *path, size_t cap) {
  if (sim->writer->no_checkpoints)
    return mpm_error_set(&sim->error, MPM_ERR_INVALID, "no checkpoint: %s",
                         sim->writer->no_checkpoints);
  if (!sim->out.enabled)
    return mpm_error_set(
        &sim->error, MPM_ERR_INVALID,
        "a checkpoint needs an output directory: call mpm_sim_enable_output first");
  if (sim->failed != MPM_OK) /* its state is not one to resume from */
    return mpm_error_set(&sim->error, sim->failed,
                         "no checkpoint of a simulation that failed at step %lld (%s)",
                         (long long)sim->steps, sim->failed_message);
  mpm_checkpoint c;
  memset(&c, 0, sizeof c);
  c.scene_hash = sim->scene.source_hash;
  c.time = sim->time;
  c.last_dt = sim->last_dt;
  c.max_speed = (double)sim->max_speed;
  c.steps = sim->steps;
  c.frame = sim->frame;
  c.written_frames = sim->out.written_frames;
  c.dt_level = sim->retry.dt_level;
  c.threads = mpm_thread_count();
  c.next_id = sim->next_id;
  const mpm_solver_figures *sf = &sim->solver_figures;
  const mpm_step_figures *sp = &sim->step_figures;
  const double figures[MPM_CKPT_SOLVER_FIGURES] = {(double)sf->steps,
                                                   (double)sf->cg_iterations,
                                                   (double)sf->newton_iterations,
                                                   (double)sf->cg_unconverged,
                                                   (double)sf->cg_max,
                                                   sf->residual_max,
                                                   (double)sp->steps,
                                                   (double)sp->full_steps,
                                                   sp->sum,
                                                   sp->full_sum,
                                                   sp->min,
                                                   sp->max};
  memcpy(c.solver_figures, figures, sizeof figures);
  c.particles = sim->particles; /* borrowed, not freed */
  c.domains = sim->domains;
  c.records = sim->out.written_frames;
  c.frame_times = sim->out.frame_times;
  c.frame_files = sim->out.frame_files;
  c.stats = sim->out.stats;
  /* the colliders' columns: the frame in progress's sums, then the rows' forces */
  const size_t nf = 3 * (size_t)sim->collider_count;
  double *forces = NULL;
  if (nf) {
    forces = mpm_alloc(((size_t)c.records + 1) * nf * sizeof *forces);
    if (!forces)
      return mpm_error_set(&sim->error, MPM_ERR_NOMEM, "out of memory writing a checkpoint");
    memcpy(forces, sim->collider_frame, nf * sizeof *forces);
    memcpy(forces + nf, sim->out.stats_forces, (size_t)c.records * nf * sizeof *forces);
    c.colliders = sim->collider_count;
    c.collider_forces = forces;
  }
  /* the colliders a script moves, when any is (a run without scripts writes what it did) */
  _Static_assert(MPM_CKPT_SCRIPT_DOUBLES == MPM_COLLIDER_SCRIPT_DOUBLES, "script layout");
  double *scripts = NULL;
  int scripted = 0;
  for (int k = 0; k < sim->collider_count; ++k) scripted |= sim->colliders[k].script.on;
  if (scripted) {
    scripts = mpm_alloc((size_t)sim->collider_count * MPM_CKPT_SCRIPT_DOUBLES * sizeof *scripts);
    if (!scripts) {
      mpm_free(forces);
      return mpm_error_set(&sim->error, MPM_ERR_NOMEM, "out of memory writing a checkpoint");
    }
    for (int k = 0; k < sim->collider_count; ++k)
      mpm_collider_script_save(&sim->colliders[k], scripts + (size_t)k * MPM_CKPT_SCRIPT_DOUBLES);
    c.collider_scripts = scripts;
  }
  if (sim->mesh_digests) { /* borrowed */
    c.mesh_count = sim->scene.body_count;
    c.mesh_digests = sim->mesh_digests;
  }
  char file[MPM_PATH_MAX + 32];
  snprintf(file, sizeof file, "%s/checkpoint_%0*lld.h5", sim->out.dir, NAME_DIGITS,
           (long long)sim->steps);
  /* the grid's own state (a tree the run rebuilt) */
  mpm_status st = sim->stack->save(sim, &c);
  if (st == MPM_OK) st = sim->writer->checkpoint(sim, file, &c);
  for (int k = 0; k < 4; ++k) mpm_free(c.tree[k]);
  mpm_free(forces);
  mpm_free(scripts);
  if (st != MPM_OK) return st;
  snprintf(sim->out.last_checkpoint, sizeof sim->out.last_checkpoint, "%s", file);
  if (path && cap) snprintf(path, cap, "%s", file);
  /* keep the newest few: one may be damaged later, the run can fall back on the one before */
  char **names;
  const int n = list_checkpoints(sim->out.dir, &names);
  for (int i = KEEP_CHECKPOINTS; i < n; ++i) {
    char old[MPM_PATH_MAX + 32];
    snprintf(old, sizeof old, "%s/%s", sim->out.dir, names[i]);
    remove(old);
  }
  if (n > 0) free_names(names, n);
  return MPM_OK;
}

mpm_status mpm_sim_digest_meshes(mpm_sim *sim, mpm_error *err) {
  const mpm_scene *sc = &sim->scene;
  for (int b = 0; b < sc->body_count; ++b) {
    if (sc->bodies[b].shape.kind != MPM_SHAPE_MESH) continue;
    if (!sim->mesh_digests &&
        !(sim->mesh_digests = mpm_calloc((size_t)sc->body_count, sizeof(uint64_t))))
      return mpm_error_set(err, MPM_ERR_NOMEM, "out of memory for the mesh digests");
    char file[2 * MPM_PATH_MAX], why[128];
    mpm_scene_mesh_file(sc, sc->bodies[b].shape.mesh_path, file, sizeof file);
    if (mpm_input_digest(file, &sim->mesh_digests[b], why, sizeof why))
      return mpm_error_set(err, MPM_ERR_IO, "%s: bodies[%d].shape.file: cannot read '%s': %s",
                           sc->path, b, file, why);
  }
  return MPM_OK;
}

/* Check a checkpoint that read back whole against this simulation's scene. */
static mpm_status check_fits(const mpm_sim *sim, const mpm_checkpoint *c, const char *file,
                             mpm_error *err) {
  if (c->scene_hash != sim->scene.source_hash)
    return mpm_error_set(err, MPM_ERR_INVALID,
                         "%s was written from another scene than %s (or from an earlier version "
                         "of it): resume with the scene the run started with, or start a new run "
                         "in another output directory",
                         file, sim->scene.path);
  /* the meshes the bodies were made from: the same files, byte for byte */
  const mpm_scene *sc = &sim->scene;
  if (c->mesh_count && c->mesh_count != sc->body_count)
    return mpm_error_set(err, MPM_ERR_INVALID,
                         "%s was written for %d bodies and %s has %d: resume with the scene the "
                         "run started with",
                         file, c->mesh_count, sc->path, sc->body_count);
  for (int b = 0; b < c->mesh_count; ++b) {
    const uint64_t now = sim->mesh_digests ? sim->mesh_digests[b] : 0;
    if (c->mesh_digests[b] == now) continue;
    char mesh[2 * MPM_PATH_MAX] = "no mesh";
    if (sc->bodies[b].shape.kind == MPM_SHAPE_MESH)
      mpm_scene_mesh_file(sc, sc->bodies[b].shape.mesh_path, mesh, sizeof mesh);
    return mpm_error_set(err, MPM_ERR_INVALID,
                         "%s: bodies[%d].shape.file: the mesh file %s is not the one %s was "
                         "written with (its content changed): resume with the mesh the run "
                         "started with, or start a new run",
                         sc->path, b, mesh, file);
  }
  /* the particle domains the bodies make (a checkpoint from before the digests: a mesh that
     changed shows here) */
  if (c->domains.particles.count != sim->domains.particles.count ||
      c->domains.corner_count != sim->domains.corner_count)
    return mpm_error_set(err, MPM_ERR_INVALID,
                         "%s holds %zu domain particles and %zu corners, and the bodies of %s make "
                         "%zu and %zu: it was written from other bodies or meshes",
                         file, c->domains.particles.count, c->domains.corner_count, sc->path,
                         sim->domains.particles.count, sim->domains.corner_count);
  if (c->written_frames != c->frame + 1 || c->frame > sim->frame_count ||
      c->time > sim->scene.end_time * (1 + 1e-12))
    return mpm_error_set(err, MPM_ERR_PARSE,
                         "%s: frame %d, %d frames written and t = %g s do not fit the scene's %d "
                         "frames to %g s",
                         file, c->frame, c->written_frames, c->time, sim->frame_count,
                         sim->scene.end_time);
  for (int pass = 0; pass < 2; ++pass) {
    const mpm_particles *p = pass ? &c->domains.particles : &c->particles;
    for (size_t i = 0; i < p->count; ++i)
      if (p->material[i] < 0 || p->material[i] >= sim->material_count || p->body[i] < 0 ||
          p->body[i] >= sim->scene.body_count || !(p->mass[i] > 0) || !(p->vol0[i] > 0))
        return mpm_error_set(err, MPM_ERR_PARSE,
                             "%s: particle %zu has material %d, body %d, mass %g, volume %g; the "
                             "scene has %d materials and %d bodies",
                             file, i, p->material[i], p->body[i], (double)p->mass[i],
                             (double)p->vol0[i], sim->material_count, sim->scene.body_count);
  }
  return MPM_OK;
}

/* Take over the checkpoint's state (its particles and records are moved into sim). */
static mpm_status install(mpm_sim *sim, mpm_checkpoint *c) {
  mpm_status st = mpm_sim_alloc_output(sim, c->records);
  if (st != MPM_OK) return st;
  if ((st = sim->stack->load(sim, c)) != MPM_OK) return st;
  mpm_particles_free(&sim->particles);
  sim->particles = c->particles;
  memset(&c->particles, 0, sizeof c->particles);
  /* the enrichment thresholds and spacings are the scene's (they stay); the marks are made
   * anew from the state, as every step makes them */
  mpm_domain_enrichment settings = {0};
  mpm_enrichment_move_settings(&settings, &sim->domains.enrich);
  mpm_domain_set_free(&sim->domains);
  sim->domains = c->domains;
  memset(&c->domains, 0, sizeof c->domains);
  mpm_enrichment_move_settings(&sim->domains.enrich, &settings);
  sim->domains.enrich.valid = 0;
  sim->time = c->time;
  sim->last_dt = c->last_dt;
  sim->max_speed = (mpm_real)c->max_speed;
  sim->steps = c->steps;
  sim->next_id = c->next_id;
  sim->frame = c->frame;
  sim->out.written_frames = c->written_frames;
  sim->retry.dt_level = c->dt_level;
  mpm_solver_figures *sf = &sim->solver_figures;
  memset(sf, 0, sizeof *sf);
  sf->steps = (long long)c->solver_figures[0];
  sf->cg_iterations = (long long)c->solver_figures[1];
  sf->newton_iterations = (long long)c->solver_figures[2];
  sf->cg_unconverged = (long long)c->solver_figures[3];
  sf->cg_max = (int)c->solver_figures[4];
  sf->residual_max = c->solver_figures[5];
  mpm_step_figures *sp = &sim->step_figures;
  sp->steps = (long long)c->solver_figures[6];
  sp->full_steps = (long long)c->solver_figures[7];
  sp->sum = c->solver_figures[8];
  sp->full_sum = c->solver_figures[9];
  sp->min = c->solver_figures[10];
  sp->max = c->solver_figures[11];
  for (int i = 0; i < c->records; ++i) {
    sim->out.frame_times[i] = c->frame_times[i];
    memcpy(sim->out.frame_files[i], c->frame_files[i], sizeof sim->out.frame_files[i]);
    sim->out.stats[i] = c->stats[i];
  }
  /* the colliders' columns (a checkpoint from before them has none: zeros) */
  const size_t nf = 3 * (size_t)sim->collider_count;
  memset(sim->collider_frame, 0, nf * sizeof *sim->collider_frame);
  if (c->colliders == sim->collider_count && nf) {
    memcpy(sim->collider_frame, c->collider_forces, nf * sizeof *sim->collider_frame);
    memcpy(sim->out.stats_forces, c->collider_forces + nf,
           (size_t)c->records * nf * sizeof(double));
  }
  if (c->collider_scripts && c->colliders == sim->collider_count)
    for (int k = 0; k < sim->collider_count; ++k)
      mpm_collider_script_load(&sim->colliders[k],
                               c->collider_scripts + (size_t)k * MPM_CKPT_SCRIPT_DOUBLES);
  sim->out.enabled = 1;
  sim->out.frame_wall_start = mpm_wall_seconds();
  return MPM_OK;
}

static mpm_status resume_from(mpm_sim *sim, const char *dir, char **names, int n, char *path,
                              size_t cap);

mpm_status mpm_sim_resume(mpm_sim *sim, const char *dir, char *path, size_t cap) {
  if (sim->writer->no_checkpoints)
    return mpm_error_set(&sim->error, MPM_ERR_INVALID, "cannot resume %s: %s", dir,
                         sim->writer->no_checkpoints);
  if (strlen(dir) >= sizeof sim->out.dir)
    return mpm_error_set(&sim->error, MPM_ERR_INVALID, "%.64s...: path too long", dir);
  char **names;
  const int n = list_checkpoints(dir, &names);
  if (n < 0)
    return mpm_error_set(&sim->error, MPM_ERR_IO, "%s: cannot read the output directory", dir);
  /* the folder is this run's from here (no other simulation writes there while it resumes):
     its stale temporaries are a killed run's, and go */
  const int had_lock = sim->out.lock >= 0;
  mpm_status claimed = mpm_sim_claim_output(sim, dir, MPM_RUN_CLAIM_RESUME);
  if (claimed != MPM_OK) {
    free_names(names, n);
    return claimed;
  }
  mpm_status st = resume_from(sim, dir, names, n, path, cap);
  if (st != MPM_OK && !had_lock) { /* nothing resumed: the folder is free again */
    mpm_run_folder_unlock(sim->out.lock);
    sim->out.lock = -1;
  }
  return st;
}

/* mpm_sim_resume once the folder is locked: the newest checkpoint of `names` that fits. */
static mpm_status resume_from(mpm_sim *sim, const char *dir, char **names, int n, char *path,
                              size_t cap) {
  if (n == 0) {
    mpm_free(names);
    return mpm_error_set(&sim->error, MPM_ERR_IO,
                         "%s: no checkpoint to resume from (checkpoint_*.h5); runs write one every "
                         "output.checkpoint_every frames and when stopped by Ctrl-C or SIGTERM",
                         dir);
  }
  mpm_status st = MPM_ERR_PARSE;
  mpm_error first;
  mpm_error_clear(&first);
  int used = -1;
  for (int i = 0; i < n && used < 0; ++i) {
    char file[MPM_PATH_MAX + 32];
    snprintf(file, sizeof file, "%s/%s", dir, names[i]);
    mpm_checkpoint c;
    mpm_error e;
    mpm_error_clear(&e);
    st = mpm_checkpoint_read(file, &c, &e);
    if (st == MPM_OK) st = check_fits(sim, &c, file, &e);
    if (st == MPM_OK) {
      st = install(sim, &c);
      if (st == MPM_OK) {
        used = i;
        snprintf(sim->out.last_checkpoint, sizeof sim->out.last_checkpoint, "%s", file);
        snprintf(sim->out.dir, sizeof sim->out.dir, "%s", dir);
      }
    }
    mpm_checkpoint_free(&c);
    if (st == MPM_ERR_INVALID || st == MPM_ERR_NOMEM) { /* another scene: no older one fits */
      sim->error = e;
      free_names(names, n);
      return st;
    }
    if (st != MPM_OK && first.status == MPM_OK) first = e;
  }
  if (used < 0) {
    free_names(names, n);
    return mpm_error_set(&sim->error, st, "no usable checkpoint in %s (%d tried); the newest: %s",
                         dir, n, first.message);
  }
  /* newer checkpoints that did not read back are set aside, so that the next pruning and the
   * next resume see only good ones */
  for (int i = 0; i < used; ++i) {
    char from[MPM_PATH_MAX + 32], to[MPM_PATH_MAX + 48];
    snprintf(from, sizeof from, "%s/%s", dir, names[i]);
    snprintf(to, sizeof to, "%s/%s.damaged", dir, names[i]);
    rename(from, to);
  }
  if (path && cap) snprintf(path, cap, "%s", sim->out.last_checkpoint);
  free_names(names, n);
  return MPM_OK;
}
