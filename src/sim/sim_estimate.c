/* sim_estimate.c - what a scene will need, read from its description without sampling its
 * bodies (mpm/mpm.h: mpm_scene_estimate_file; `mpm check` on a scene too large to sample in a
 * moment): the simulation is built as mpm_sim_create_from_file builds it, every check of the
 * scene made, but no particle placed, and its figures read off. */
#include "sim/sim.h"

#include <stdio.h>
#include <string.h>

mpm_status mpm_scene_estimate_file(const char *path, mpm_scene_estimate *out, size_t size,
                                   char *errbuf, size_t errlen) {
  if (errbuf && errlen) errbuf[0] = '\0';
  if (!out) return MPM_ERR_INVALID;
  mpm_error err;
  mpm_error_clear(&err);
  mpm_scene scene;
  mpm_sim *sim = NULL;
  mpm_status st = mpm_scene_load(path, &scene, &err);
  if (st == MPM_OK) {
    st = mpm_sim_create_unsampled(&scene, &sim, &err);
    mpm_scene_free(&scene);
  }
  if (st != MPM_OK) {
    if (errbuf && errlen) snprintf(errbuf, errlen, "%s", err.message);
    return st;
  }
  const mpm_scene *sc = &sim->scene;
  mpm_scene_estimate e;
  memset(&e, 0, sizeof e);
  e.particles = sim->expected_particles;
  e.memory_bytes = mpm_scene_memory_for(sc, sim->expected_particles);
  e.available_bytes = mpm_available_memory();
  e.first_dt = mpm_sim_cfl_dt(sim);
  e.frame_dt = sim->frame_dt;
  e.dx = sc->dx;
  e.finest_dx = mpm_sim_finest_dx(sim);
  e.bodies = sc->body_count;
  e.materials = sim->material_count;
  e.colliders = sim->collider_count;
  e.frame_count = sim->frame_count;
  e.implicit = sc->solver.integrator == MPM_INTEGRATOR_IMPLICIT;
  mpm_sim_destroy(sim);
  memcpy(out, &e, size < sizeof e ? size : sizeof e);
  return MPM_OK;
}
