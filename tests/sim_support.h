/* sim_support.h - a simulation from an inline JSON scene, for the tests that step one. */
#ifndef MPM_TEST_SIM_SUPPORT_H
#define MPM_TEST_SIM_SUPPORT_H

#include "support.h"
#include "sim/sim.h"

/* The scene parsed and built; any error fails the test with its message. */
static inline mpm_sim *sim_from_json(const char *json) {
  mpm_scene scene;
  mpm_error err;
  mpm_error_clear(&err);
  if (mpm_scene_parse(json, "test.json", &scene, &err) != MPM_OK)
    fail_msg("scene: %s", err.message);
  mpm_sim *sim = NULL;
  if (mpm_sim_create_from_scene(&scene, &sim, &err) != MPM_OK) fail_msg("sim: %s", err.message);
  mpm_scene_free(&scene);
  return sim;
}

#endif
