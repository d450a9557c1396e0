/* sim.c - building and destroying a simulation, and the public handle's accessors. */
#include "sim/sim.h"
#include "io/run_folder.h"
#include "sim/frame_writer.h"
#include "sim/grid_stack.h"
#include "domain/enrich.h"
#include "core/alloc.h"
#include "core/parallel.h"
#include "scene/sample.h"

#include <cjson/cJSON.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static mpm_status oom(mpm_error *err, const char *what) {
  return mpm_error_set(err, MPM_ERR_NOMEM, "out of memory allocating %s", what);
}

/* More steps than this in one frame means the run would not finish in any useful time. */
#define MAX_STEPS_PER_FRAME 1e7

/* A scene whose CFL step (from the stiffest material's wave speed) or solver.max_dt makes a
 * frame take more than MAX_STEPS_PER_FRAME steps is refused, naming what sets the step: such
 * a run would look like a hang. Particle speeds only shorten the step further. */
static mpm_status check_steps_per_frame(const mpm_sim *sim, mpm_error *err) {
  const mpm_scene *sc = &sim->scene;
  double c = 0;
  int stiff = -1;
  for (int m = 0; m < sim->material_count; ++m)
    if (sim->materials[m].wave_speed > c) c = sim->materials[m].wave_speed, stiff = m;
  double dt_cfl = c > 0 ? sc->solver.cfl * sc->dx / c : INFINITY;
  if (sc->solver.integrator == MPM_INTEGRATOR_IMPLICIT) /* no wave-speed bound */
    dt_cfl = sc->solver.dt > 0 ? sc->solver.dt : INFINITY;
  const double dt = sc->solver.max_dt > 0 ? fmin(dt_cfl, sc->solver.max_dt) : dt_cfl;
  const double steps = 1.0 / (sc->fps * dt);
  if (!(steps > MAX_STEPS_PER_FRAME)) return MPM_OK;
  if (sc->solver.integrator == MPM_INTEGRATOR_IMPLICIT && dt == sc->solver.dt)
    return mpm_error_set(err, MPM_ERR_INVALID,
                         "%s: solver.dt = %g s makes %.3g steps per frame (at %g frames per "
                         "second); expected at most %g: raise solver.dt",
                         sc->path, sc->solver.dt, steps, sc->fps, MAX_STEPS_PER_FRAME);
  if (sc->solver.max_dt > 0 && sc->solver.max_dt <= dt_cfl)
    return mpm_error_set(err, MPM_ERR_INVALID,
                         "%s: solver.max_dt = %g s makes %.3g steps per frame (at %g frames per "
                         "second); expected at most %g: raise solver.max_dt",
                         sc->path, sc->solver.max_dt, steps, sc->fps, MAX_STEPS_PER_FRAME);
  return mpm_error_set(err, MPM_ERR_INVALID,
                       "%s: materials[%d] ('%s'): E = %g Pa and density %g kg/m^3 give a wave "
                       "speed of %.3g m/s, so the CFL step is %.3g s and a frame takes %.3g "
                       "steps; expected at most %g: lower E, raise the density or dx, or lower "
                       "the frame rate",
                       sc->path, stiff, sc->materials[stiff].name, sc->materials[stiff].E,
                       sc->materials[stiff].density, c, dt_cfl, steps, MAX_STEPS_PER_FRAME);
}

/* The largest initial speed of a body's points: its velocity and its spin times the distance
 * from the centre of its box to a corner (a bound). */
static double initial_speed_bound(const mpm_scene *sc) {
  double vmax = 0;
  for (int b = 0; b < sc->body_count; ++b) {
    const mpm_body_desc *bd = &sc->bodies[b];
    double v = 0, w = 0, r = 0;
    for (int d = 0; d < 3; ++d) {
      v += bd->velocity[d] * bd->velocity[d];
      w += bd->angular_velocity[d] * bd->angular_velocity[d];
      const double h = 0.5 * (bd->shape.bounds_hi[d] - bd->shape.bounds_lo[d]);
      r += h * h;
    }
    vmax = fmax(vmax, sqrt(v) + sqrt(w) * sqrt(r));
  }
  return vmax;
}

static mpm_status create(mpm_scene *scene, mpm_sim **out, mpm_error *err, int sample);

mpm_status mpm_sim_create_from_scene(mpm_scene *scene, mpm_sim **out, mpm_error *err) {
  return create(scene, out, err, 1);
}

mpm_status mpm_sim_create_unsampled(mpm_scene *scene, mpm_sim **out, mpm_error *err) {
  return create(scene, out, err, 0);
}

static mpm_status create(mpm_scene *scene, mpm_sim **out, mpm_error *err, int sample) {
  *out = NULL;
  mpm_sim *sim = mpm_calloc(1, sizeof *sim);
  if (!sim) return oom(err, "the simulation");
  sim->scene = *scene;
  memset(scene, 0, sizeof *scene); /* the simulation owns the arrays now */
  sim->out.lock = -1;
  const mpm_scene *sc = &sim->scene;
  /* refuse a scene the machine cannot hold before allocating anything for it */
  mpm_status st = mpm_scene_check_memory(sc, err);
  if (st != MPM_OK) goto fail;
  mpm_scene_memory_estimate(sc, &sim->expected_particles); /* levels add theirs below */

  /* materials */
  sim->material_count = sc->material_count;
  sim->materials =
      mpm_calloc((size_t)(sc->material_count > 0 ? sc->material_count : 1), sizeof *sim->materials);
  if (!sim->materials) {
    st = oom(err, "materials");
    goto fail;
  }
  sim->base_materials =
      mpm_calloc((size_t)(sc->material_count > 0 ? sc->material_count : 1), sizeof *sim->materials);
  if (!sim->base_materials) {
    st = oom(err, "materials");
    goto fail;
  }
  for (int m = 0; m < sc->material_count; ++m) {
    mpm_material_init(&sim->materials[m], &sc->materials[m]);
    if (!sim->materials[m].model) {
      st = mpm_error_set(err, MPM_ERR_INVALID,
                         "%s: materials[%d] ('%s'): model %d is not available in this build",
                         sc->path, m, sc->materials[m].name, (int)sc->materials[m].model);
      goto fail;
    }
    sim->base_materials[m] = sim->materials[m];
    if (sc->materials[m].strength_count > 0) {
      sim->has_strength = 1;
      /* the CFL bound holds for the stiffest the schedule makes the material */
      double fmax = 0;
      for (int k = 0; k < sc->materials[m].strength_count; ++k)
        fmax = fmax > sc->materials[m].strength[k][1] ? fmax : sc->materials[m].strength[k][1];
      sim->materials[m].wave_speed *= (mpm_real)sqrt(fmax);
      sim->base_materials[m].wave_speed = sim->materials[m].wave_speed;
    }
  }
  mpm_sim_apply_strength(sim, 0);
  st = check_steps_per_frame(sim, err);
  if (st != MPM_OK) goto fail;

  /* colliders */
  sim->collider_count = sc->collider_count;
  sim->colliders = mpm_calloc((size_t)(sc->collider_count + 1), sizeof *sim->colliders);
  sim->poses = mpm_calloc((size_t)(sc->collider_count + 1), sizeof *sim->poses);
  sim->collider_step = mpm_calloc(6 * (size_t)sc->collider_count + 1, sizeof(double));
  sim->collider_frame = sim->collider_step + 3 * sc->collider_count;
  if (!sim->colliders || !sim->poses || !sim->collider_step) {
    st = oom(err, "colliders");
    goto fail;
  }
  for (int c = 0; c < sc->collider_count; ++c)
    if (mpm_collider_init(&sim->colliders[c], &sc->colliders[c])) {
      st = oom(err, "collider keyframes");
      goto fail;
    }
  /* body-force regions (their count set as each is built, so that destroy frees what is) */
  sim->force_colliders = mpm_calloc((size_t)(sc->force_count + 1), sizeof *sim->force_colliders);
  sim->force_regions = mpm_calloc((size_t)(sc->force_count + 1), sizeof *sim->force_regions);
  if (!sim->force_colliders || !sim->force_regions) {
    st = oom(err, "body-force regions");
    goto fail;
  }
  for (int f = 0; f < sc->force_count; ++f, ++sim->force_count)
    if (mpm_collider_init(&sim->force_colliders[f], &sc->forces[f].region)) {
      st = oom(err, "body-force region keyframes");
      goto fail;
    }

  /* grid geometry */
  for (int d = 0; d < 3; ++d) {
    sim->origin[d] = (mpm_real)sc->box_min[d];
    sim->cells[d] = (int)lround((sc->box_max[d] - sc->box_min[d]) / sc->dx);
  }
  /* particles */
  if (mpm_particles_init(&sim->particles, 1024)) {
    st = oom(err, "particles");
    goto fail;
  }
  mpm_domain_set_init(&sim->domains);
  sim->stack = mpm_grid_stack_for(sc);
  sim->writer = &mpm_frame_files;
  if ((st = sim->stack->make(sim, err)) != MPM_OK) goto fail;
  uint32_t next_id = 0;
  for (int b = 0; sample && b < sc->body_count; ++b) {
    const size_t first = sim->particles.count;
    st = sim->stack->sample_body(sim, b, err);
    if (st != MPM_OK) goto fail;
    for (size_t i = first; i < sim->particles.count; ++i) {
      sim->particles.id[i] = next_id++;
      sim->particles.plastic[i] = sim->materials[sim->particles.material[i]].model->plastic_initial;
    }
    if (sc->bodies[b].domains) { /* the body's particles move into the domain set */
      char name[MPM_NAME_MAX + 64];
      snprintf(name, sizeof name, "%s: bodies[%d] (\"%s\")", sc->path, b, sc->bodies[b].name);
      const size_t dfirst = sim->domains.particles.count;
      const double h = mpm_sample_spacing(sc, b);
      st = mpm_domain_set_add_lattice(&sim->domains, &sim->particles, first, sc->box_min, h, name,
                                      err);
      if (st != MPM_OK) goto fail;
      const mpm_body_desc *bd = &sc->bodies[b];
      const mpm_enrichment_body settings = {.epsilon = (mpm_real)bd->enrichment,
                                            .exit_k = (mpm_real)bd->enrichment_exit,
                                            .spacing = (mpm_real)h,
                                            .bend = (mpm_real)bd->enrichment_hourglass,
                                            .metric = bd->enrichment_metric,
                                            .hourglass_all = bd->hourglass,
                                            .contact = bd->enrichment_contact,
                                            .surface_contact = bd->enrichment_surface_contact,
                                            .self_contact = bd->enrichment_self_contact,
                                            .exit_wait = bd->enrichment_exit_wait};
      if (mpm_enrichment_set_body(&sim->domains, b, settings)) {
        st = oom(err, "the enrichment thresholds");
        goto fail;
      }

      if (sc->bodies[b].shape.kind == MPM_SHAPE_MESH) { /* keep the mesh, embedded */
        mpm_embedded_surface *grown =
            mpm_realloc(sim->surfaces, (size_t)(sim->surface_count + 1) * sizeof *grown);
        if (!grown) {
          st = oom(err, "embedded surfaces");
          goto fail;
        }
        sim->surfaces = grown;
        mpm_mesh mesh;
        st = mpm_sample_body_mesh(sc, b, &mesh, err);
        if (st == MPM_OK)
          st = mpm_embed_surface(&sim->surfaces[sim->surface_count], b, &mesh, &sim->domains,
                                 dfirst, sc->box_min, h, err);
        mpm_mesh_free(&mesh);
        if (st != MPM_OK) goto fail;
        sim->surface_count++;
      }
    }
  }
  sim->next_id = next_id;
  /* sampling appended particle by particle: the arrays' doublings may have left half unused */
  if (mpm_particles_fit(&sim->particles) || mpm_particles_fit(&sim->domains.particles)) {
    st = oom(err, "particles");
    goto fail;
  }
  if (sample && (st = mpm_sim_digest_meshes(sim, err)) != MPM_OK) goto fail;

  /* kernel: uGIMP's particle box defaults to the particle spacing of the first body */
  double lp = sc->solver.gimp_length;
  if (!(lp > 0)) {
    double ppc = sc->body_count ? sc->bodies[0].particles_per_cell : 8;
    lp = sc->dx / cbrt(ppc > 1 ? ppc : 1);
  }
  sim->kernel = mpm_kernel_make(sc->solver.kernel, (mpm_real)sc->dx, (mpm_real)lp);
  sim->domain_kernel =
      mpm_kernel_make(sc->solver.domain_kernel, (mpm_real)sc->dx, (mpm_real)sc->dx);

  if (sc->solver.grid == MPM_GRID_DENSE) {
    const int n[3] = {sim->cells[0] + 3, sim->cells[1] + 3, sim->cells[2] + 3};
    if (mpm_grid_init_dense(&sim->grid, 0, sim->origin, (mpm_real)sc->dx, n)) {
      st = oom(err, "the dense grid");
      goto fail;
    }
  } else {
    mpm_grid_init_sparse(&sim->grid, 0, sim->origin, (mpm_real)sc->dx);
  }
  mpm_dofs_init(&sim->dofs);
  mpm_heat_init(&sim->heat);
  mpm_arena_init(&sim->step_arena);
  sim->reorder_interval = 16;
  sim->threads.enabled = -1; /* decided at the first step */

  /* time */
  sim->frame_dt = 1.0 / sc->fps;
  sim->frame_count = (int)ceil(sc->end_time * sc->fps - 1e-9);
  if (sim->frame_count < 1) sim->frame_count = 1;
  sim->wave_speed = 0;
  /* the implicit step is bounded by particle motion alone (no wave-speed bound) */
  for (int m = 0; m < sim->material_count && sc->solver.integrator == MPM_INTEGRATOR_EXPLICIT; ++m)
    if (sim->materials[m].wave_speed > sim->wave_speed)
      sim->wave_speed = sim->materials[m].wave_speed;
  mpm_real vmax2 = 0;
  for (size_t i = 0; i < sim->particles.count; ++i) {
    mpm_real v2 = 0;
    for (int d = 0; d < 3; ++d) v2 += sim->particles.v[d][i] * sim->particles.v[d][i];
    if (v2 > vmax2) vmax2 = v2;
  }
  for (size_t i = 0; i < sim->domains.particles.count; ++i) {
    mpm_real v2 = 0;
    for (int d = 0; d < 3; ++d)
      v2 += sim->domains.particles.v[d][i] * sim->domains.particles.v[d][i];
    if (v2 > vmax2) vmax2 = v2;
  }
  sim->max_speed = sample ? mpm_sqrt(vmax2) : (mpm_real)initial_speed_bound(sc);
  snprintf(sim->out.dir, sizeof sim->out.dir, "%s", sc->output.directory);
  *out = sim;
  return MPM_OK;
fail:
  mpm_sim_destroy(sim);
  return st;
}

void mpm_sim_apply_strength(mpm_sim *sim, double t) {
  if (!sim->has_strength) return;
  for (int m = 0; m < sim->material_count; ++m) {
    const double f = mpm_material_strength(&sim->scene.materials[m], t);
    mpm_material *cur = &sim->materials[m];
    *cur = sim->base_materials[m]; /* wave_speed stays the schedule's largest (the CFL bound) */
    cur->mu = (mpm_real)(f * (double)cur->mu);
    cur->lambda = (mpm_real)(f * (double)cur->lambda);
  }
}

/* Release the active domain particles inside [lo, hi] whose body allows it at this time
 * (body < 0: any body, no time condition); the count released goes to *count. */
static mpm_status release_box(mpm_sim *sim, int body, const double lo[3], const double hi[3],
                              size_t *count) {
  mpm_domain_set *s = &sim->domains;
  for (size_t i = 0; i < s->particles.count; ++i) {
    if (!s->active[i] || (body >= 0 && s->particles.body[i] != body)) continue;
    int inside = 1;
    for (int d = 0; d < 3; ++d)
      inside &= s->particles.x[d][i] >= lo[d] && s->particles.x[d][i] <= hi[d];
    if (!inside) continue;
    if (mpm_domain_set_release(s, i, &sim->particles))
      return mpm_error_set(&sim->error, MPM_ERR_NOMEM, "out of memory switching domains off");
    ++*count;
  }
  return MPM_OK;
}

mpm_status mpm_sim_apply_domain_releases(mpm_sim *sim) {
  if (!sim->domains.active_count) return MPM_OK;
  size_t released = 0;
  for (int b = 0; b < sim->scene.body_count; ++b) {
    const mpm_body_desc *body = &sim->scene.bodies[b];
    for (int r = 0; r < body->release_count; ++r)
      if (sim->time >= body->release[r].time) {
        mpm_status st = release_box(sim, b, body->release[r].min, body->release[r].max, &released);
        if (st != MPM_OK) return st;
      }
  }
  /* melting (Zhu sec. 7: the domains of the particles the heat source reaches are disabled,
   * so that the topology can change): a domain particle leaves its domain once its
   * temperature passes its material's melting point */
  mpm_domain_set *s = &sim->domains;
  int melts = 0;
  for (int m = 0; m < sim->material_count; ++m) melts |= sim->materials[m].melting;
  for (size_t i = 0; i < s->particles.count && melts; ++i) {
    if (!s->active[i]) continue;
    const mpm_material *m = &sim->materials[s->particles.material[i]];
    if (!m->melting || !(s->particles.temperature[i] > m->melt_point)) continue;
    if (mpm_domain_set_release(s, i, &sim->particles))
      return mpm_error_set(&sim->error, MPM_ERR_NOMEM, "out of memory switching domains off");
    ++released;
    ++sim->melted_domains;
  }
  if (released && mpm_domain_set_rebuild(&sim->domains))
    return mpm_error_set(&sim->error, MPM_ERR_NOMEM, "out of memory switching domains off");
  return MPM_OK;
}

mpm_status mpm_sim_release_domains(mpm_sim *sim, const double lo[3], const double hi[3],
                                   size_t *count) {
  size_t released = 0;
  mpm_status st = release_box(sim, -1, lo, hi, &released);
  if (st == MPM_OK && released && mpm_domain_set_rebuild(&sim->domains))
    st = mpm_error_set(&sim->error, MPM_ERR_NOMEM, "out of memory switching domains off");
  if (count) *count = released;
  return st;
}

/* The simulation of a parsed scene, keeping `copy` (the output folder's scene.json) when made;
 * the scene is freed either way. */
static mpm_status create_keeping_copy(mpm_scene *scene, char *copy, mpm_sim **out, mpm_error *err) {
  mpm_status st = mpm_sim_create_from_scene(scene, out, err);
  mpm_scene_free(scene);
  if (st == MPM_OK)
    (*out)->scene_copy = copy;
  else
    mpm_free(copy);
  return st;
}

mpm_status mpm_sim_create_from_file(const char *scene_path, mpm_sim **out, char *errbuf,
                                    size_t errlen) {
  mpm_error err;
  mpm_error_clear(&err);
  mpm_scene scene;
  char *text = NULL; /* the file is read once: the copy kept is the scene that runs */
  mpm_status st = mpm_scene_load_text(scene_path, &scene, &text, &err);
  if (st == MPM_OK) {
    char *copy = mpm_scene_copy_text(text, &scene);
    mpm_free(text);
    st = create_keeping_copy(&scene, copy, out, &err);
  }
  if (st != MPM_OK && errbuf && errlen) snprintf(errbuf, errlen, "%s", err.message);
  return st;
}

mpm_status mpm_sim_create_from_json(const char *json_text, const char *base_dir, mpm_sim **out,
                                    char *errbuf, size_t errlen) {
  /* the scene's path names it in messages and resolves its mesh files (against its folder) */
  char path[MPM_PATH_MAX + 16];
  if (base_dir && base_dir[0])
    snprintf(path, sizeof path, "%.*s/<json>", MPM_PATH_MAX, base_dir);
  else
    snprintf(path, sizeof path, "<json>");
  mpm_error err;
  mpm_error_clear(&err);
  mpm_scene scene;
  *out = NULL;
  mpm_status st = json_text ? mpm_scene_parse(json_text, path, &scene, &err)
                            : mpm_error_set(&err, MPM_ERR_INVALID, "no scene text given (NULL)");
  if (st == MPM_OK)
    st = create_keeping_copy(&scene, mpm_scene_copy_text(json_text, &scene), out, &err);
  if (st != MPM_OK && errbuf && errlen) snprintf(errbuf, errlen, "%s", err.message);
  return st;
}

mpm_status mpm_sim_create_from_def(const mpm_scene_def *def, const char *base_dir, mpm_sim **out,
                                   char *errbuf, size_t errlen) {
  mpm_error err;
  mpm_error_clear(&err);
  mpm_status st;
  if (!out) {
    st = mpm_error_set(&err, MPM_ERR_INVALID,
                       "<def>: no place for the simulation given (out is NULL)");
  } else {
    *out = NULL;
    mpm_scene scene;
    cJSON *tree = NULL; /* the def's tree, checked as a scene file's; kept as scene.json */
    st = mpm_scene_from_def(def, base_dir, &scene, &tree, &err);
    if (st == MPM_OK) {
      char *copy = mpm_scene_copy_tree(tree, &scene);
      cJSON_Delete(tree);
      st = create_keeping_copy(&scene, copy, out, &err);
    }
  }
  if (st != MPM_OK && errbuf && errlen) snprintf(errbuf, errlen, "%s", err.message);
  return st;
}

void mpm_sim_destroy(mpm_sim *sim) {
  if (!sim) return;
  mpm_particles_free(&sim->particles);
  mpm_particles_free(&sim->retry.backup);
  mpm_particles_free(&sim->retry.domain_backup);
  mpm_particles_free(&sim->views.particles);
  mpm_keep_free(&sim->views.keep, sim->views.derived);
  mpm_keep_free(&sim->views.keep, sim->views.corner);
  mpm_keep_clear(&sim->views.keep); /* whatever a binding still holds: the handle is gone */
  for (int k = 0; k < 18; ++k) mpm_free(sim->retry.corner_backup[k]);
  mpm_domain_set_free(&sim->domains);
  for (int i = 0; i < sim->surface_count; ++i) mpm_embedded_surface_free(&sim->surfaces[i]);
  mpm_free(sim->surfaces);
  mpm_free(sim->materials);
  if (sim->colliders)
    for (int c = 0; c < sim->collider_count; ++c) mpm_collider_free(&sim->colliders[c]);
  mpm_free(sim->colliders);
  mpm_free(sim->poses);
  mpm_free(sim->collider_step);
  if (sim->force_colliders)
    for (int f = 0; f < sim->force_count; ++f) mpm_collider_free(&sim->force_colliders[f]);
  mpm_free(sim->force_colliders);
  mpm_free(sim->force_regions);
  mpm_free(sim->base_materials);
  mpm_grid_free(&sim->grid);
  if (sim->stack) sim->stack->destroy(sim);
  mpm_dofs_free(&sim->dofs);
  mpm_heat_free(&sim->heat);
  mpm_arena_free(&sim->step_arena);
  mpm_free(sim->iscratch);
  mpm_free(sim->out.frame_times);
  mpm_free(sim->out.frame_files);
  mpm_free(sim->out.stats);
  mpm_free(sim->out.stats_forces);
  mpm_scene_free(&sim->scene);
  mpm_free(sim->scene_copy);
  mpm_free(sim->mesh_digests);
  mpm_run_folder_unlock(sim->out.lock); /* after the last file is written */
  mpm_free(sim);
}

const char *mpm_sim_last_error(const mpm_sim *sim) {
  return sim->error.message;
}
double mpm_sim_time(const mpm_sim *sim) {
  return sim->time;
}
int64_t mpm_sim_steps(const mpm_sim *sim) {
  return sim->steps;
}
int mpm_sim_frame(const mpm_sim *sim) {
  return sim->frame;
}
int mpm_sim_frame_count(const mpm_sim *sim) {
  return sim->frame_count;
}

mpm_status mpm_sim_set_threads(mpm_sim *sim, int threads) {
  if (threads < 0)
    return mpm_error_set(&sim->error, MPM_ERR_INVALID,
                         "mpm_sim_set_threads: expected a thread count >= 0 (0: the caller's "
                         "OpenMP setting), got %d",
                         threads);
  sim->thread_request = threads;
  return MPM_OK;
}

int mpm_sim_threads_enter(const mpm_sim *sim) {
  const int saved = mpm_thread_count();
  if (sim->thread_request > 0 && sim->thread_request != saved) mpm_set_threads(sim->thread_request);
  return saved;
}

void mpm_sim_threads_leave(const mpm_sim *sim, int saved) {
  if (sim->thread_request > 0 && mpm_thread_count() != saved) mpm_set_threads(saved);
}

void mpm_sim_set_reduction(mpm_sim *sim, const mpm_reduction *reduction) {
  sim->reduction = reduction;
  sim->dofs.reduction = reduction;
}

void mpm_sim_set_writer(mpm_sim *sim, const mpm_frame_writer *writer) {
  sim->writer = writer ? writer : &mpm_frame_files;
}
