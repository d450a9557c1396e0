/* test_collider_active.c - colliders that act over a time window (`active: [start, end]`): a
 * grip that lets go. A block hangs from a sticky grip that covers its top layer; while the grip
 * is active the block's top stays put; after `end` the whole block falls freely, and its centre
 * of mass follows the free fall started at `end`. A scene key with a bad window is refused
 * with its key path. */
#include "support.h"
#include "sim/sim.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

static const char *SCENE =
    "{\"domain\": {\"min\": [0,0,0], \"max\": [0.8,1.2,0.8], \"dx\": 0.04},"
    " \"gravity\": [0, -10, 0], \"time\": {\"end\": 0.3, \"fps\": 20},"
    " \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\", \"E\": 2e5, \"nu\": 0.3,"
    " \"density\": 1000}],"
    " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.4,0.8,0.4], \"half_extent\": "
    "[0.08,0.08,0.08]}, \"material\": \"m\", \"jitter\": 0}],"
    " \"colliders\": [{\"name\": \"grip\", \"shape\": {\"type\": \"box\", \"center\": "
    "[0.4,0.9,0.4], \"half_extent\": [0.15,0.04,0.15]}, \"rule\": \"sticky\"%s}]}";

static void test_grip_lets_go(void **state) {
  (void)state;
  char text[2048];
  snprintf(text, sizeof text, SCENE, ", \"active\": [0, 0.1]");
  mpm_sim *sim = test_sim_from_json(text, "grip.json");
  const double y0 = test_centre_height(sim);
  for (int f = 0; f < 2; ++f) assert_int_equal(mpm_sim_advance_frame(sim), MPM_OK); /* t = 0.1 */
  const double y_held = test_centre_height(sim);
  /* held: the block sags a little under its weight but does not fall (free fall: 5 cm) */
  assert_true(y0 - y_held < 0.02);
  const mpm_particles *p = &sim->particles;
  double vy = 0, m = 0;
  for (size_t i = 0; i < p->count; ++i) m += p->mass[i], vy += (double)p->mass[i] * p->v[1][i];
  vy /= m;
  for (int f = 2; f < 6; ++f) assert_int_equal(mpm_sim_advance_frame(sim), MPM_OK); /* t = 0.3 */
  const double y_end = test_centre_height(sim), T = 0.2;
  const double expected = y_held + vy * T - 0.5 * 10 * T * T; /* free fall from the release */
  print_message("grip: centre of mass %.4f -> %.4f held (t = 0.1 s) -> %.4f at 0.3 s; free fall "
                "from the release gives %.4f\n",
                y0, y_held, y_end, expected);
  assert_true(fabs(y_end - expected) < 0.01);
  mpm_sim_destroy(sim);
  /* the same grip always active holds the block to the end */
  snprintf(text, sizeof text, SCENE, "");
  sim = test_sim_from_json(text, "grip.json");
  while (sim->frame < sim->frame_count) assert_int_equal(mpm_sim_advance_frame(sim), MPM_OK);
  assert_true(y0 - test_centre_height(sim) < 0.02);
  mpm_sim_destroy(sim);
}

static void test_bad_window(void **state) {
  (void)state;
  static const char *const bad[] = {", \"active\": [0.2, 0.1]", ", \"active\": [-1, 1]",
                                    ", \"active\": 3", ", \"active\": [0, 1, 2]"};
  for (size_t k = 0; k < sizeof bad / sizeof bad[0]; ++k) {
    char text[2048];
    snprintf(text, sizeof text, SCENE, bad[k]);
    mpm_scene scene;
    mpm_error err;
    assert_int_not_equal(mpm_scene_parse(text, "grip.json", &scene, &err), MPM_OK);
    if (!strstr(err.message, "colliders[0].active"))
      fail_msg("expected the key path in: %s", err.message);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_grip_lets_go),
      cmocka_unit_test(test_bad_window),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
