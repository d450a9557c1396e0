/* sim_output.c - a simulation's output folder (claimed, locked, its bookkeeping) and what each
 * frame holds: the particles as written with their derived fields (stresses, J, melt, the
 * enrichment categories), checked finite, and the stats row with the run's figures, handed to
 * the simulation's frame writer (frame_writer.h; the files themselves: frame_files.c). */
#include "sim/sim.h"
#include "sim/frame_writer.h"
#include "core/alloc.h"
#include "core/mat3.h"
#include "domain/enrich.h"
#include "io/run_folder.h"
#include "io/staging.h"
#include "scene/sample.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The verdict over every process of a run (one process: st) on a part of the output that may
 * fail on one process alone (out of memory, a non-finite value in its particles) before the
 * frame's reductions: that process must not leave the others waiting in them, so every process
 * stops with the largest status, the others' messages pointing at its message. */
static mpm_status verdict(mpm_sim *sim, mpm_status st, const char *what, int frame) {
  if (!sim->reduction) return st;
  double worst = (double)st;
  mpm_reduce_all(sim->reduction, MPM_REDUCE_MAX, &worst, 1);
  if (worst > 0 && st == MPM_OK) {
    mpm_error_set_elsewhere(&sim->error, (mpm_status)worst,
                            "%s %d: another process of the run failed; its message says why", what,
                            frame);
  }
  return st != MPM_OK ? st : (mpm_status)worst;
}

mpm_status mpm_sim_alloc_output(mpm_sim *sim, int records) {
  mpm_free(sim->out.frame_times);
  mpm_free(sim->out.frame_files);
  mpm_free(sim->out.stats);
  mpm_free(sim->out.stats_forces);
  const size_t n = (size_t)(records > sim->frame_count + 1 ? records : sim->frame_count + 1);
  sim->out.frame_times = mpm_calloc(n, sizeof *sim->out.frame_times);
  sim->out.frame_files = mpm_calloc(n, sizeof *sim->out.frame_files);
  sim->out.stats = mpm_calloc(n, sizeof *sim->out.stats);
  sim->out.stats_forces =
      mpm_calloc(n * 3 * (size_t)sim->collider_count + 1, sizeof *sim->out.stats_forces);
  if (!sim->out.frame_times || !sim->out.frame_files || !sim->out.stats || !sim->out.stats_forces)
    return mpm_error_set(&sim->error, MPM_ERR_NOMEM, "out of memory for output bookkeeping");
  return MPM_OK;
}

mpm_status mpm_sim_claim_output(mpm_sim *sim, const char *dir, int how) {
  /* the run's inputs: never removed, whatever their names (a scene kept as out/scene.json) */
  const mpm_scene *sc = &sim->scene;
  char(*meshes)[MPM_PATH_MAX] = mpm_calloc((size_t)sc->body_count + 1, sizeof *meshes);
  const char **keep = mpm_calloc((size_t)sc->body_count + 2, sizeof *keep);
  if (!meshes || !keep) {
    mpm_free(meshes);
    mpm_free(keep);
    return mpm_error_set(&sim->error, MPM_ERR_NOMEM, "out of memory claiming %s", dir);
  }
  int n = 0;
  if (sc->path[0]) keep[n++] = sc->path;
  for (int b = 0; b < sc->body_count; ++b)
    if (sc->bodies[b].shape.kind == MPM_SHAPE_MESH && sc->bodies[b].shape.mesh_path[0]) {
      mpm_scene_mesh_file(sc, sc->bodies[b].shape.mesh_path, meshes[b], sizeof meshes[b]);
      keep[n++] = meshes[b];
    }
  int lock = -1;
  mpm_status st = MPM_OK;
  const int same = sim->out.lock >= 0 && mpm_same_file(dir, sim->out.dir);
  if (!same) st = mpm_run_folder_lock(dir, &lock, &sim->error);
  if (st == MPM_OK) st = mpm_run_folder_claim(dir, (mpm_run_claim)how, keep, n, &sim->error);
  mpm_free(meshes);
  mpm_free(keep);
  if (st != MPM_OK) {
    mpm_run_folder_unlock(lock);
    return st;
  }
  if (!same) {
    mpm_run_folder_unlock(sim->out.lock);
    sim->out.lock = lock;
  }
  return MPM_OK;
}

mpm_status mpm_sim_prepare_output(mpm_sim *sim, const char *dir, int how) {
  mpm_status st = mpm_make_dirs(dir, &sim->error);
  if (st == MPM_OK) st = mpm_sim_claim_output(sim, dir, how);
  if (st != MPM_OK) return st;
  snprintf(sim->out.dir, sizeof sim->out.dir, "%s", dir);
  return mpm_sim_write_scene_copy(sim);
}

/* MPM_ERR_INVALID naming the call when mode is not an mpm_output_mode. */
static mpm_status check_mode(mpm_sim *sim, const char *what, mpm_output_mode mode) {
  if (mode == MPM_OUTPUT_NEW || mode == MPM_OUTPUT_OVERWRITE) return MPM_OK;
  return mpm_error_set(&sim->error, MPM_ERR_INVALID,
                       "%s: mode %d is neither MPM_OUTPUT_NEW nor MPM_OUTPUT_OVERWRITE", what,
                       (int)mode);
}

mpm_status mpm_sim_open_output(mpm_sim *sim, const char *dir, mpm_output_mode mode) {
  if (check_mode(sim, "mpm_sim_open_output", mode) != MPM_OK) return MPM_ERR_INVALID;
  if (dir && strlen(dir) >= sizeof sim->out.dir)
    return mpm_error_set(&sim->error, MPM_ERR_INVALID, "%.64s...: path too long", dir);
  char target[MPM_PATH_MAX];
  snprintf(target, sizeof target, "%s", dir ? dir : sim->out.dir);
  const int how = mode == MPM_OUTPUT_OVERWRITE ? MPM_RUN_CLAIM_OVERWRITE : MPM_RUN_CLAIM_NEW;
  mpm_status st = sim->writer->open ? sim->writer->open(sim, target, how)
                                    : mpm_sim_prepare_output(sim, target, how);
  if (st != MPM_OK) return st;
  st = verdict(sim, mpm_sim_alloc_output(sim, 0), "opening the output for frame", 0);
  if (st != MPM_OK) return st;
  sim->out.enabled = 1;
  sim->out.frame_wall_start = mpm_wall_seconds();
  const int saved = mpm_sim_threads_enter(sim); /* the frame's stress loop is parallel */
  st = mpm_sim_write_frame(sim);
  mpm_sim_threads_leave(sim, saved);
  return st;
}

mpm_status mpm_sim_enable_output(mpm_sim *sim, const char *dir) {
  return mpm_sim_open_output(sim, dir, MPM_OUTPUT_NEW);
}

mpm_status mpm_sim_all_particles(const mpm_sim *sim, mpm_particles *all) {
  const mpm_particles *a = &sim->particles, *d = &sim->domains.particles;
  if (!all->x[0] && mpm_particles_init(all, a->count + sim->domains.active_count + 1))
    return MPM_ERR_NOMEM;
  all->count = 0;
  if (mpm_particles_append_set(all, a, NULL) ||
      mpm_particles_append_set(all, d, sim->domains.active))
    return MPM_ERR_NOMEM;
  return MPM_OK;
}

/* The first particle (in p's order) with a non-finite quantity of those a frame writes, as an
 * MPM_ERR_UNSTABLE naming the frame, the particle, its body and material, and the quantity. J
 * and stress may be NULL (not computed). */
static mpm_status scan_frame_fields(mpm_sim *sim, const mpm_particles *p, const mpm_real *J,
                                    const mpm_real *stress, int frame) {
  const long n = (long)p->count;
  long first = n;
#pragma omp parallel for schedule(static) reduction(min : first)
  for (long i = 0; i < n; ++i) {
    int ok = isfinite(p->mass[i]) && isfinite(p->vol0[i]) && isfinite(p->temperature[i]) &&
             (!J || isfinite(J[i])) && (!stress || isfinite(stress[i]));
    for (int d = 0; d < 3; ++d) ok = ok && isfinite(p->x[d][i]) && isfinite(p->v[d][i]);
    if (!ok && i < first) first = i;
  }
  if (first == n) return MPM_OK;
  const long i = first;
  const char *what = !isfinite(p->mass[i])            ? "mass"
                     : !isfinite(p->vol0[i])          ? "volume"
                     : !isfinite(p->temperature[i])   ? "temperature"
                     : J && !isfinite(J[i])           ? "J (det F)"
                     : stress && !isfinite(stress[i]) ? "stress"
                     : !isfinite(p->x[0][i]) || !isfinite(p->x[1][i]) || !isfinite(p->x[2][i])
                         ? "position"
                         : "velocity";
  const double value = !isfinite(p->mass[i])            ? (double)p->mass[i]
                       : !isfinite(p->vol0[i])          ? (double)p->vol0[i]
                       : !isfinite(p->temperature[i])   ? (double)p->temperature[i]
                       : J && !isfinite(J[i])           ? (double)J[i]
                       : stress && !isfinite(stress[i]) ? (double)stress[i]
                                                        : NAN;
  const int m = p->material[i];
  return mpm_error_set(&sim->error, MPM_ERR_UNSTABLE,
                       "frame %d (t = %.6g s, step %lld): particle id %u (body %d, material %d "
                       "'%s') has a non-finite %s (%g); the frame is not written (a value past "
                       "what the %s build holds: check the scene's magnitudes, e.g. "
                       "materials[%d].density, heat.temperature, hardening)",
                       frame, sim->time, (long long)sim->steps, p->id[i], p->body[i], m,
                       sim->scene.materials[m].name, what, value, mpm_real_type(), m);
}

/* One frame, numbered `frame`, into `dir`, through the frame writer: the particles (VTU, PLY),
 * the domains, the embedded and the particle surfaces, as the scene's output keys choose. With
 * `records` (the run's own folder) also the run's indexes and stats.csv, and the frame is
 * counted; without, nothing of the run's bookkeeping is touched (a one-off,
 * mpm_sim_write_frame_to). */
static mpm_status write_frame(mpm_sim *sim, const char *dir, int frame, int records) {
  mpm_particles combined;
  memset(&combined, 0, sizeof combined);
  const int has_domains = sim->domains.particles.count > 0;
  /* the enrichment categories of the state written (the marks the next step will use) */
  if (has_domains && mpm_sim_all_particles(sim, &combined))
    return mpm_error_set(&sim->error, MPM_ERR_NOMEM, "out of memory writing frame %d",
                         sim->out.written_frames);
  if (has_domains) {
    const mpm_status marked = mpm_sim_mark_enrichment(sim);
    if (marked != MPM_OK) {
      mpm_particles_free(&combined);
      return marked;
    }
  }
  const mpm_particles *p = has_domains ? &combined : &sim->particles;
  const mpm_output_desc *o = &sim->scene.output;
  mpm_status st = MPM_OK;
  mpm_real *J = NULL, *stress = NULL, *melt = NULL, *cauchy = NULL, *pressure = NULL;
  int32_t *category = NULL;
  const int heat = sim->scene.heat.enabled;
  const unsigned fields = o->fields ? o->fields : mpm_output_fields_default(heat);
  const int want_cauchy = o->vtu && (fields >> MPM_FIELD_CAUCHY_STRESS & 1u);
  const int want_pressure = o->vtu && (fields >> MPM_FIELD_PRESSURE & 1u);
  if (o->vtu || o->ply) {
    J = mpm_alloc((p->count + 1) * sizeof(mpm_real));
    stress = mpm_alloc((p->count + 1) * sizeof(mpm_real));
    category = mpm_alloc((p->count + 1) * sizeof(int32_t));
    melt = heat ? mpm_alloc((p->count + 1) * sizeof(mpm_real)) : NULL;
    cauchy = want_cauchy ? mpm_alloc((9 * p->count + 1) * sizeof(mpm_real)) : NULL;
    pressure = want_pressure ? mpm_alloc((p->count + 1) * sizeof(mpm_real)) : NULL;
    if (!J || !stress || !category || (heat && !melt) || (want_cauchy && !cauchy) ||
        (want_pressure && !pressure))
      st = mpm_error_set(&sim->error, MPM_ERR_NOMEM, "out of memory writing frame %d", frame);
    const long n = st == MPM_OK ? (long)p->count : 0;
#pragma omp parallel for schedule(static)
    for (long i = 0; i < n; ++i) {
      mpm_real tau[9];
      J[i] = mpm_sim_kirchhoff(sim, p, (size_t)i, tau);
      stress[i] = mpm_von_mises(tau, J[i]);
      if (cauchy || pressure) {
        const mpm_real inv_J = 1 / J[i]; /* Cauchy from first Piola: sigma = P F^T / J */
        if (cauchy)
          for (int c = 0; c < 9; ++c) cauchy[9 * i + c] = tau[c] * inv_J;
        if (pressure) pressure[i] = -(tau[0] + tau[4] + tau[8]) * inv_J / 3;
      }
      if (melt)
        melt[i] = mpm_material_melt_fraction(&sim->materials[p->material[i]], p->temperature[i]);
    }
  }
  /* nothing non-finite goes into a frame: the step's guard scans positions and F, but a mass,
     a temperature or a stress can overflow alone (a density of 1e308, a temperature of 1e308,
     a snow hardening of 1e300 wrote inf into every frame and exited 0) */
  if (st == MPM_OK) st = scan_frame_fields(sim, p, J, stress, frame);
  st = verdict(sim, st, "frame", frame);
  if (st != MPM_OK) goto done;
  if (category) { /* as mpm_sim_all_particles orders them: material points, then active domains */
    size_t j = 0;
    for (; j < sim->particles.count; ++j) category[j] = -1;
    for (size_t q = 0; q < sim->domains.particles.count; ++q)
      if (sim->domains.active[q]) category[j++] = sim->domains.enrich.category[q];
  }
  mpm_frame_record r = {frame, dir, records, has_domains, {0}, 0};
  r.ff =
      (mpm_frame_fields){p, J, stress, sim->time, category, heat, melt, fields, cauchy, pressure};
  if (records && o->stats) { /* the run's figures (over every process) for stats.csv */
    mpm_diagnostics d = mpm_sim_diagnostics(sim);
    mpm_stats_row *row = &sim->out.stats[frame];
    row->frame = frame;
    row->time = sim->time;
    const mpm_step_figures *sp = &sim->step_figures;
    row->dt = sp->full_steps ? sp->full_sum / (double)sp->full_steps
              : sp->steps    ? sp->sum / (double)sp->steps
                             : 0;
    row->dt_min = sp->min;
    row->dt_max = sp->max;
    row->steps = (long long)sim->steps;
    row->kinetic = d.kinetic;
    row->elastic = d.elastic;
    row->gravitational = d.gravitational;
    row->total_energy = d.kinetic + d.elastic + d.gravitational;
    for (int k = 0; k < 3; ++k) {
      row->momentum[k] = d.momentum[k];
      row->angular_momentum[k] = d.angular_momentum[k];
    }
    row->mass = d.mass;
    row->wall_seconds = mpm_wall_seconds() - sim->out.frame_wall_start;
    row->particles = p->count;
    if (sim->reduction) { /* every process's particles */
      double all = (double)p->count;
      mpm_reduce_all(sim->reduction, MPM_REDUCE_SUM, &all, 1);
      row->particles = (size_t)all;
    }
    const mpm_solver_figures *sf = &sim->solver_figures;
    const double steps = sf->steps > 0 ? (double)sf->steps : 1;
    row->cg_iterations_mean = (double)sf->cg_iterations / steps;
    row->newton_iterations_mean = (double)sf->newton_iterations / steps;
    row->cg_iterations_max = sf->cg_max;
    row->cg_residual_max = sf->residual_max;
    row->cg_unconverged = sf->cg_unconverged;
    const mpm_domain_enrichment *en = &sim->domains.enrich;
    row->enriched_percent =
        sim->domains.active_count
            ? 100.0 * (double)en->particles[MPM_DOMAIN_ENRICHED] / (double)sim->domains.active_count
            : 0;
    /* the colliders' mean force over the frame: the momentum they took over its time */
    const int nc = sim->collider_count;
    double *force = sim->out.stats_forces + 3 * (size_t)frame * (size_t)nc;
    for (int k = 0; k < 3 * nc; ++k) force[k] = sp->sum > 0 ? sim->collider_frame[k] / sp->sum : 0;
    /* each process of a run took the reactions of the nodes it owns (the same dt on all) */
    mpm_reduce_all(sim->reduction, MPM_REDUCE_SUM, force, 3 * nc);
    r.stats_rows = frame + 1;
  }
  st = sim->writer->frame(sim, &r);
  if (st != MPM_OK) goto done;
  if (records) sim->out.written_frames++;
done:
  mpm_particles_free(&combined);
  mpm_free(J);
  mpm_free(stress);
  mpm_free(category);
  mpm_free(melt);
  mpm_free(cauchy);
  mpm_free(pressure);
  return st;
}

mpm_status mpm_sim_write_frame(mpm_sim *sim) {
  if (sim->out.written_frames > sim->frame_count)
    return mpm_error_set(&sim->error, MPM_ERR_INVALID, "more frames than the scene has");
  return write_frame(sim, sim->out.dir, sim->out.written_frames, 1);
}

mpm_status mpm_sim_write_frame_to(mpm_sim *sim, const char *dir, mpm_output_mode mode,
                                  char *written, size_t cap) {
  if (written && cap) written[0] = 0;
  if (check_mode(sim, "mpm_sim_write_frame_to", mode) != MPM_OK) return MPM_ERR_INVALID;
  if (sim->reduction) /* each process holds a part: its folder and lock would be its own */
    return mpm_error_set(&sim->error, MPM_ERR_INVALID,
                         "mpm_sim_write_frame_to: a one-off frame is not written by the "
                         "processes of a distributed run yet");
  if (!dir || !dir[0])
    return mpm_error_set(&sim->error, MPM_ERR_INVALID, "mpm_sim_write_frame_to: no folder");
  if (strlen(dir) >= MPM_PATH_MAX)
    return mpm_error_set(&sim->error, MPM_ERR_INVALID, "%.64s...: path too long", dir);
  mpm_status st = mpm_make_dirs(dir, &sim->error);
  if (st != MPM_OK) return st;
  /* the run's own folder holds the run's record of its frames, which a one-off would break */
  if (sim->out.enabled && mpm_same_file(dir, sim->out.dir))
    return mpm_error_set(&sim->error, MPM_ERR_INVALID,
                         "%s is this simulation's output folder: its frames there are the run's "
                         "own; write the one-off frame into another folder",
                         dir);
  int lock = -1; /* no run writes there meanwhile */
  st = mpm_run_folder_lock(dir, &lock, &sim->error);
  if (st != MPM_OK) return st;
  char staging[MPM_PATH_MAX + 32];
  st = mpm_staging_open(dir, staging, sizeof staging, &sim->error);
  if (st == MPM_OK) {
    const int saved = mpm_sim_threads_enter(sim);
    st = write_frame(sim, staging, sim->frame, 0);
    mpm_sim_threads_leave(sim, saved);
    if (st == MPM_OK)
      st = mpm_staging_publish(staging, dir, mode == MPM_OUTPUT_OVERWRITE, written, cap,
                               &sim->error);
    mpm_staging_discard(staging);
  }
  mpm_run_folder_unlock(lock);
  return st;
}
