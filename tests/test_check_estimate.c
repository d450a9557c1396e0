/* test_check_estimate.c - what a scene needs, read from its description without sampling its
 * bodies (mpm_scene_estimate_file; `mpm check` on a large scene): the expected particles agree
 * with the sampled count within 6% on the shipped scenes of every kind (analytic shapes, mesh
 * bodies by their enclosed volume, revolve containers, a multi-level grid, particle domains),
 * and a scene of 10^8 particles is answered at once, with every key still checked and the
 * memory still compared with the machine's, where sampling it took 75 s and 14.8 GB. */
#include "support.h"
#include "cli_support.h"
#include "mpm/mpm.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void test_estimate_matches_sampling(void **state) {
  (void)state;
  static const char *const scenes[] = {"examples/sphere_bounce.json",
                                       "examples/bunny_drop.json",
                                       "examples/sand_hourglass.json",
                                       "examples/snowball.json",
                                       "examples/gao/jello_collision_adaptive.json",
                                       "examples/gao/hourglass_adaptive.json",
                                       "examples/zhu/bunny_hit_by_ball.json"};
  for (size_t k = 0; k < sizeof scenes / sizeof scenes[0]; ++k) {
    char path[1024], err[2048];
    snprintf(path, sizeof path, "%s/%s", MPM_SOURCE_DIR, scenes[k]);
    mpm_scene_estimate e;
    if (mpm_scene_estimate_file(path, &e, sizeof e, err, sizeof err) != MPM_OK)
      fail_msg("estimate: %s", err);
    mpm_sim *sim;
    if (mpm_sim_create_from_file(path, &sim, err, sizeof err) != MPM_OK)
      fail_msg("create: %s", err);
    mpm_sim_info in;
    assert_int_equal(mpm_sim_get_info(sim, &in, sizeof in), MPM_OK);
    const double ratio = e.particles / (double)in.particles;
    double dt = 0;
    assert_int_equal(mpm_sim_next_dt(sim, &dt), MPM_OK);
    print_message("%-45s expected %9.0f, sampled %9zu (%.3f); first dt %.3g against %.3g s\n",
                  scenes[k], e.particles, in.particles, ratio, e.first_dt, dt);
    assert_true(fabs(ratio - 1) < 0.06);
    assert_true(fabs(e.memory_bytes / in.memory_bytes - 1) < 0.06);
    assert_true(e.available_bytes > 0);
    assert_int_equal(e.frame_count, in.frame_count);
    assert_int_equal(e.bodies, in.bodies);
    assert_int_equal(e.materials, in.materials);
    assert_int_equal(e.colliders, in.colliders);
    assert_true(e.dx == in.dx && e.finest_dx == in.finest_dx);
    /* the step from the bodies' initial speeds bounds the sampled one's from below */
    assert_true(e.first_dt > 0 && e.first_dt <= dt * (1 + 1e-9));
    mpm_sim_destroy(sim);
  }
}

/* A block of about 10^8 particles (dx 1 mm): `mpm check` answers from the description in a
 * moment, says so, and still refuses a bad key and a machine too small. */
static void test_check_large_scene(void **state) {
  (void)state;
  const char *dir = test_temp_dir("check-estimate");
  static const char *const fmt =
      "{\"domain\": {\"min\": [0,0,0], \"max\": [1,1,1], \"dx\": 0.001},"
      " \"time\": {\"end\": 0.1, \"fps\": 10},"
      " \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\", \"E\": 1e4,"
      " \"nu\": 0.3, \"density\": 1000%s}],"
      " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.5,0.5,0.5],"
      " \"half_extent\": [0.12,0.12,0.12]}, \"material\": \"m\", \"velocity\": [0, -2, 0]}]}";
  char scene[700], text[1400], args[1600];
  snprintf(scene, sizeof scene, "%s/big.json", dir);
  snprintf(text, sizeof text, fmt, "");
  write_file(scene, text);
  snprintf(args, sizeof args, "check '%s'", scene);
  assert_int_equal(mpm_env("MPM_MEMORY_LIMIT=1000G timeout 20", args), 0);
  expect_output("ok (about 111 million particles from the bodies' volumes, not sampled");
  expect_output("the bodies were not sampled");
  expect_output("--sample");
  expect_output("first step dt = ");
  /* the memory is still weighed against the machine's */
  assert_int_equal(mpm_env("MPM_MEMORY_LIMIT=1G timeout 20", args), 2);
  expect_output("the scene needs about "); /* GiB: 19.3 in float, more in double */
  /* and every key still checked */
  snprintf(text, sizeof text, fmt, ", \"yield_stres\": 1");
  write_file(scene, text);
  assert_int_equal(mpm_env("MPM_MEMORY_LIMIT=1000G timeout 20", args), 2);
  expect_output("materials[0]");
  /* a small scene is sampled, and --sample says the same */
  snprintf(args, sizeof args, "check '%s/examples/jello_cubes.json'", MPM_SOURCE_DIR);
  assert_int_equal(mpm(args), 0);
  expect_output("ok (16000 particles");
  snprintf(args, sizeof args, "check --sample '%s/examples/jello_cubes.json'", MPM_SOURCE_DIR);
  assert_int_equal(mpm(args), 0);
  expect_output("ok (16000 particles");
  assert_int_equal(mpm("check --sampel x.json"), 2);
  expect_output("did you mean '--sample'");
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_estimate_matches_sampling),
                                     cmocka_unit_test(test_check_large_scene)};
  return test_cleanup(cmocka_run_group_tests_name("check_estimate", tests, NULL, NULL));
}
