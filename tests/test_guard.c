/* test_guard.c - the instability guards and the retry with a smaller dt: a CFL violation, a
 * particle leaving the domain and an inversion the model cannot evaluate each stop the step
 * with the step, time, particle id, body, material and quantity named; in retry mode the CFL
 * case is undone and redone with halved steps until it is stable, and gives up after
 * solver.max_retries halvings; the scene keys are checked. */
#include "support.h"
#include "sim/sim.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* A jello block (E = 1e4 Pa: wave speed 3.7 m/s, dt = 4.4 ms at dx = 4 cm). */
static const char *BLOCK =
    "{\"domain\": {\"min\": [0,0,0], \"max\": [1,1,1], \"dx\": 0.04},\n"
    " \"time\": {\"end\": 0.1, \"fps\": 10},\n"
    " \"solver\": {\"on_instability\": \"%s\", \"max_retries\": %d},\n"
    " \"materials\": [{\"name\": \"jello\", \"model\": \"%s\", \"E\": 1e4, \"nu\": 0.3, "
    "\"density\": 1000}],\n"
    " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.3,0.5,0.5], "
    "\"half_extent\": [0.08,0.08,0.08]}, \"material\": \"jello\"}]}\n";

static mpm_sim *block(const char *action, int retries, const char *model) {
  char text[2048];
  snprintf(text, sizeof text, BLOCK, action, retries, model);
  mpm_scene scene;
  mpm_error err;
  if (mpm_scene_parse(text, "block.json", &scene, &err) != MPM_OK) fail_msg("%s", err.message);
  mpm_sim *sim = NULL;
  if (mpm_sim_create_from_scene(&scene, &sim, &err) != MPM_OK) fail_msg("%s", err.message);
  mpm_scene_free(&scene);
  return sim;
}

/* Every particle at 50 m/s along x while the solver still believes they are at rest: the
 * next dt is chosen for the wave speed alone and the block moves 5 cells in it. */
static void launch(mpm_sim *sim) {
  for (size_t i = 0; i < sim->particles.count; ++i) sim->particles.v[0][i] = 50;
  sim->max_speed = 0;
}

static void expect_message(const mpm_sim *sim, const char *needle) {
  if (!strstr(mpm_sim_last_error(sim), needle))
    fail_msg("expected '%s' in: %s", needle, mpm_sim_last_error(sim));
}

static void test_cfl_violation_stops(void **state) {
  (void)state;
  mpm_sim *sim = block("stop", 8, "fixed_corotated");
  launch(sim);
  assert_int_equal(mpm_sim_step(sim, 0), MPM_ERR_UNSTABLE);
  expect_message(sim, "violated the CFL condition");
  expect_message(sim, "at step 1 ");
  expect_message(sim, "particle id ");
  expect_message(sim, "material 0 'jello'");
  expect_message(sim, "cells in one step");
  mpm_sim_destroy(sim);
}

/* A block with particle domains, launched at 50 m/s as launch() does. */
static mpm_sim *domain_block(const char *action) {
  char text[2048];
  snprintf(text, sizeof text, BLOCK, action, 8, "fixed_corotated");
  const char *key = "\"material\": \"jello\"}";
  const char *at = strstr(text, key);
  assert_non_null(at);
  char fixed[2100]; /* the body with "domains": true added (not enriched: the dt of the grid) */
  snprintf(fixed, sizeof fixed,
           "%.*s\"material\": \"jello\", \"domains\": true, \"enrichment\": 0}%s", (int)(at - text),
           text, at + strlen(key));
  mpm_scene scene;
  mpm_error err;
  if (mpm_scene_parse(fixed, "block.json", &scene, &err) != MPM_OK) fail_msg("%s", err.message);
  mpm_sim *sim = NULL;
  if (mpm_sim_create_from_scene(&scene, &sim, &err) != MPM_OK) fail_msg("%s", err.message);
  mpm_scene_free(&scene);
  assert_true(sim->domains.active_count > 0);
  for (size_t c = 0; c < sim->domains.corner_count; ++c) sim->domains.cv[0][c] = 50;
  mpm_domain_set_sync_particles(&sim->domains);
  sim->max_speed = 0;
  return sim;
}

/* The same with particle domains: the corners carry the velocity, the guard names the domain
 * particle; in retry mode the domain particles and corners are restored and the step redone. */
static void test_cfl_violation_domains(void **state) {
  (void)state;
  mpm_sim *sim = domain_block("stop");
  assert_int_equal(mpm_sim_step(sim, 0), MPM_ERR_UNSTABLE);
  expect_message(sim, "violated the CFL condition");
  expect_message(sim, "domain particle id ");
  mpm_sim_destroy(sim);

  sim = domain_block("retry");
  const mpm_domain_set *s = &sim->domains;
  /* the first step renumbers the corners (mpm_domain_order_corners): a corner is found through
   * its particle */
  const double x0 = s->cx[0][s->corner[0][0]], dt_cfl = mpm_sim_cfl_dt(sim);
  assert_int_equal(mpm_sim_step(sim, 0), MPM_OK);
  assert_int_equal(sim->retry.dt_level, 3);
  assert_close(sim->last_dt, dt_cfl / 8, 1e-9);
  /* the corner moved once, by the redone step, not by the undone ones */
  assert_close(s->cx[0][s->corner[0][0]] - x0, 50 * sim->last_dt, 0.05 * 50 * sim->last_dt);
  /* the restored corners are the renumbered ones: every particle's corners around it */
  double far = 0;
  for (size_t q = 0; q < s->particles.count; ++q)
    for (int a = 0; a < 8; ++a)
      for (int d = 0; d < 3; ++d)
        far = fmax(far, fabs(s->cx[d][s->corner[q][a]] - s->particles.x[d][q]));
  assert_true(far < 0.75 * sim->scene.dx);
  mpm_sim_destroy(sim);
}

static void test_retry_halves_dt_until_stable(void **state) {
  (void)state;
  mpm_sim *sim = block("retry", 8, "fixed_corotated");
  launch(sim);
  const double dt_cfl = mpm_sim_cfl_dt(sim);
  assert_int_equal(mpm_sim_step(sim, 0), MPM_OK);
  /* 50 m/s needs dt <= dx / 50 = 0.8 ms: three halvings of 4.4 ms */
  assert_int_equal(sim->retry.dt_level, 3);
  assert_int_equal(sim->retry.retries, 3);
  assert_int_equal(sim->steps, 1);
  assert_close(sim->last_dt, dt_cfl / 8, 1e-9);
  assert_close(sim->time, dt_cfl / 8, 1e-9);
  for (size_t i = 0; i < sim->particles.count; ++i) {
    assert_true(isfinite(sim->particles.x[0][i]));
    assert_true(sim->particles.v[0][i] * sim->last_dt <= 0.04);
  }
  /* the rest of the frame runs on (now CFL-bounded) steps; a halving is given back */
  assert_int_equal(mpm_sim_advance_frame(sim), MPM_OK);
  assert_int_equal(sim->retry.dt_level, 2);
  mpm_sim_destroy(sim);
}

static void test_retry_gives_up(void **state) {
  (void)state;
  mpm_sim *sim = block("retry", 2, "fixed_corotated");
  launch(sim);
  assert_int_equal(mpm_sim_step(sim, 0), MPM_ERR_UNSTABLE);
  expect_message(sim, "violated the CFL condition");
  expect_message(sim, "after halving dt 2 times");
  assert_int_equal(sim->steps, 1);
  mpm_sim_destroy(sim);
}

static void test_particle_leaving_domain(void **state) {
  (void)state;
  mpm_sim *sim = block("stop", 8, "fixed_corotated");
  /* particle 7 on the G2P clamp at the floor: it went through the whole wall band */
  sim->particles.x[1][7] = (mpm_real)(sim->scene.box_min[1] + sim->scene.dx);
  const unsigned moved = sim->particles.id[7]; /* the step reorders the particles */
  assert_int_equal(mpm_sim_step(sim, 0), MPM_ERR_UNSTABLE);
  expect_message(sim, "left the domain");
  char id[64];
  snprintf(id, sizeof id, "particle id %u ", moved);
  expect_message(sim, id);
  mpm_sim_destroy(sim);
}

static void test_inversion_model_cannot_take(void **state) {
  (void)state;
  mpm_sim *sim = block("stop", 8, "neo_hookean");
  assert_int_equal(mpm_sim_guard_check(sim, 1e-3), MPM_OK);
  /* inverted F: fine with the min_stretch clamp (scene default 0.2), not without it */
  sim->particles.F[0][11] = -1;
  assert_int_equal(mpm_sim_guard_check(sim, 1e-3), MPM_OK);
  sim->materials[0].min_stretch = 0;
  assert_int_equal(mpm_sim_guard_check(sim, 1e-3), MPM_ERR_UNSTABLE);
  expect_message(sim, "inverted deformation gradient (det F = -1)");
  expect_message(sim, "min_stretch");
  char id[64];
  snprintf(id, sizeof id, "particle id %u ", sim->particles.id[11]);
  expect_message(sim, id);
  mpm_sim_destroy(sim);
}

static void test_guard_scene_keys(void **state) {
  (void)state;
  const char *base =
      "{\"domain\": {\"min\": [0,0,0], \"max\": [1,1,1], \"dx\": 0.1},"
      " \"time\": {\"end\": 1, \"fps\": 10},"
      " \"materials\": [{\"name\": \"m\", \"model\": \"fixed_corotated\", \"E\": 1e4, "
      "\"nu\": 0.3, \"density\": 1000}],"
      " \"bodies\": [{\"shape\": {\"type\": \"sphere\", \"center\": [0.5,0.5,0.5], "
      "\"radius\": 0.2}, \"material\": \"m\"}], %s}";
  const struct {
    const char *extra, *message;
  } bad[] = {
      {"\"solver\": {\"on_instability\": \"ignore\"}", "solver.on_instability"},
      {"\"solver\": {\"max_retries\": 0}", "solver.max_retries"},
      {"\"output\": {\"checkpoint_every\": -1}", "output.checkpoint_every"},
      {"\"output\": {\"checkpoint_every\": 2.5}", "output.checkpoint_every"},
  };
  char text[2048];
  for (size_t k = 0; k < sizeof bad / sizeof bad[0]; ++k) {
    mpm_scene scene;
    mpm_error err;
    snprintf(text, sizeof text, base, bad[k].extra);
    assert_int_not_equal(mpm_scene_parse(text, "s.json", &scene, &err), MPM_OK);
    if (!strstr(err.message, bad[k].message))
      fail_msg("expected '%s' in: %s", bad[k].message, err.message);
  }
  mpm_scene scene;
  mpm_error err;
  snprintf(text, sizeof text, base, "\"output\": {\"checkpoint_every\": 0}");
  assert_int_equal(mpm_scene_parse(text, "s.json", &scene, &err), MPM_OK);
  assert_int_equal(scene.output.checkpoint_every, 0);
  assert_int_equal(scene.solver.on_instability, MPM_INSTABILITY_STOP);
  assert_int_equal(scene.solver.max_retries, 8);
  mpm_scene_free(&scene);
}

/* A simulation whose step failed does not step again: mpm_sim_step, mpm_sim_advance_frame and
 * mpm_sim_write_checkpoint return the failure's status, naming its step, and leave the state
 * as it was; an interrupt is not a failure: the next call goes on. */
static void test_failed_simulation_refuses_steps(void **state) {
  (void)state;
  mpm_sim *sim = block("stop", 8, "fixed_corotated");
  assert_int_equal(mpm_sim_enable_output(sim, test_temp_dir("guard-failed")), MPM_OK);
  volatile int flag = 1;
  mpm_sim_set_interrupt(sim, &flag);
  assert_int_equal(mpm_sim_advance_frame(sim), MPM_ERR_INTERRUPTED);
  flag = 0;
  assert_int_equal(mpm_sim_step(sim, 0), MPM_OK); /* usable after an interrupt */
  launch(sim);
  assert_int_equal(mpm_sim_step(sim, 0), MPM_ERR_UNSTABLE);
  const long long steps = sim->steps;
  const double time = sim->time;
  const mpm_real x = sim->particles.x[0][0];
  for (int k = 0; k < 3; ++k) {
    const mpm_status st = k == 0   ? mpm_sim_step(sim, 0)
                          : k == 1 ? mpm_sim_advance_frame(sim)
                                   : mpm_sim_write_checkpoint(sim, NULL, 0);
    assert_int_equal(st, MPM_ERR_UNSTABLE);
    expect_message(sim, "failed at step");
    expect_message(sim, "violated the CFL condition"); /* the first failure, kept */
  }
  assert_int_equal(sim->steps, steps);
  assert_true(sim->time == time);
  assert_true(sim->particles.x[0][0] == x);
  mpm_sim_destroy(sim);
}

/* A value past what the real type holds reaches a frame (a heat temperature whose heat m c T
 * overflows: 1e38 in float, 1e308 in double): the frame is not written, the call says which
 * particle and quantity, and the simulation stops there (it wrote inf into every frame and
 * exited 0). */
static void test_non_finite_frame_refused(void **state) {
  (void)state;
  mpm_scene scene;
  mpm_error err;
  const char *text =
      "{\"domain\": {\"min\": [0,0,0], \"max\": [1,1,1], \"dx\": 0.1},"
      " \"time\": {\"end\": 0.2, \"fps\": 20}, \"heat\": {\"temperature\": %g},"
      " \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\", \"E\": 1e4, \"nu\": 0.3,"
      " \"density\": 1000, \"conductivity\": 1}],"
      " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.5,0.5,0.5],"
      " \"half_extent\": [0.15,0.15,0.15]}, \"material\": \"m\"}]}";
  /* a temperature the real type holds whose heat (m c T) it does not */
  char json[1024];
  snprintf(json, sizeof json, text, TOL(1e38, 1e308));
  if (mpm_scene_parse(json, "hot.json", &scene, &err) != MPM_OK) fail_msg("%s", err.message);
  mpm_sim *sim = NULL;
  if (mpm_sim_create_from_scene(&scene, &sim, &err) != MPM_OK) fail_msg("%s", err.message);
  mpm_scene_free(&scene);
  mpm_status st = mpm_sim_enable_output(sim, test_temp_dir("guard-hot"));
  while (st == MPM_OK && mpm_sim_frame(sim) < mpm_sim_frame_count(sim))
    st = mpm_sim_advance_frame(sim);
  assert_int_equal(st, MPM_ERR_UNSTABLE);
  expect_message(sim, "has a non-finite temperature");
  expect_message(sim, "particle id ");
  expect_message(sim, "heat.temperature");
  assert_int_equal(mpm_sim_advance_frame(sim), MPM_ERR_UNSTABLE); /* and it stops there */
  mpm_sim_destroy(sim);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_cfl_violation_stops),
      cmocka_unit_test(test_failed_simulation_refuses_steps),
      cmocka_unit_test(test_non_finite_frame_refused),
      cmocka_unit_test(test_cfl_violation_domains),
      cmocka_unit_test(test_retry_halves_dt_until_stable),
      cmocka_unit_test(test_retry_gives_up),
      cmocka_unit_test(test_particle_leaving_domain),
      cmocka_unit_test(test_inversion_model_cannot_take),
      cmocka_unit_test(test_guard_scene_keys),
  };
  return test_cleanup(cmocka_run_group_tests(tests, NULL, NULL));
}
