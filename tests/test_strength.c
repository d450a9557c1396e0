/* test_strength.c - strength schedules (a material's moduli scaled by keyframes over time; Zhu
 * et al. 2017 Fig. 5): the factor's interpolation; a stretched block feels no force at strength
 * 0 and the full force at strength 1; a block on a floor collapses while its strength is low and
 * stands up again when it comes back; bad schedules are refused with their key path. */
#include "support.h"
#include "sim/sim.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

static const char *SCENE =
    "{\"domain\": {\"min\": [0,0,0], \"max\": [0.8,0.8,0.8], \"dx\": 0.04},"
    " \"gravity\": [0, %g, 0], \"time\": {\"end\": %g, \"fps\": 20},"
    " \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\", \"E\": 1e5, \"nu\": 0.3,"
    " \"density\": 1000%s}],"
    " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.4,0.28,0.4], \"half_extent\": "
    "[0.08,0.08,0.08]}, \"material\": \"m\", \"jitter\": 0}],"
    " \"colliders\": [{\"shape\": {\"type\": \"halfspace\", \"point\": [0, 0.2, 0], \"normal\": "
    "[0, 1, 0]}, \"rule\": \"sticky\"}]}";

static mpm_sim *make(double g, double end, const char *strength) {
  char text[2048];
  snprintf(text, sizeof text, SCENE, g, end, strength);
  return test_sim_from_json(text, "strength.json");
}

static void test_interpolation(void **state) {
  (void)state;
  mpm_material_desc m = mpm_material_desc_default();
  assert_true(mpm_material_strength(&m, 3.0) == 1);
  m.strength_count = 3;
  const double k[3][2] = {{0.1, 1}, {0.3, 0}, {0.5, 2}};
  memcpy(m.strength, k, sizeof k);
  assert_close(mpm_material_strength(&m, 0.0), 1, 1e-15);   /* held before the first */
  assert_close(mpm_material_strength(&m, 0.2), 0.5, 1e-12); /* linear between */
  assert_close(mpm_material_strength(&m, 0.4), 1, 1e-12);
  assert_close(mpm_material_strength(&m, 0.9), 2, 1e-15); /* held after the last */
}

/* Largest particle speed after one step of a block stretched by 20%, no gravity. */
static double speed_after_step(const char *strength) {
  mpm_sim *sim = make(0, 1, strength);
  mpm_particles *p = &sim->particles;
  for (size_t i = 0; i < p->count; ++i) p->F[0][i] = (mpm_real)1.2;
  assert_int_equal(mpm_sim_step(sim, 1e-3), MPM_OK);
  double vmax = 0;
  for (size_t i = 0; i < p->count; ++i)
    for (int d = 0; d < 3; ++d) vmax = fmax(vmax, fabs((double)p->v[d][i]));
  mpm_sim_destroy(sim);
  return vmax;
}

static void test_force_scales(void **state) {
  (void)state;
  const double full = speed_after_step(""), off = speed_after_step(", \"strength\": [[0, 0]]");
  const double half = speed_after_step(", \"strength\": [[0, 0.5]]");
  print_message("stretched block, speed after one step: strength 1 %.4g, 0.5 %.4g, 0 %.4g m/s\n",
                full, half, off);
  assert_true(full > 1e-3);
  assert_true(off == 0);
  assert_close(half / full, 0.5, 0.02);
}

static double top(const mpm_sim *sim) {
  const mpm_particles *p = &sim->particles;
  double y = -1;
  for (size_t i = 0; i < p->count; ++i) y = fmax(y, p->x[1][i]);
  return y;
}

static void test_collapse_and_recover(void **state) {
  (void)state;
  mpm_sim *sim = make(-9.81, 0.8, ", \"strength\": [[0, 1], [0.05, 0.01], [0.3, 0.01], [0.35, 1]]");
  const double h0 = top(sim);
  double low = h0;
  while (sim->frame < sim->frame_count) {
    assert_int_equal(mpm_sim_advance_frame(sim), MPM_OK);
    if (sim->time <= 0.35) low = fmin(low, top(sim));
  }
  const double h_end = top(sim);
  print_message("strength schedule: top of the block %.4f m at rest, %.4f m while weak, %.4f m "
                "after recovery\n",
                h0, low, h_end);
  assert_true(h0 - low > 0.03);                     /* it collapsed */
  assert_true(fabs(h_end - h0) < 0.3 * (h0 - low)); /* and stood up again */
  mpm_sim_destroy(sim);
}

static void test_bad_schedules(void **state) {
  (void)state;
  static const char *const bad[] = {", \"strength\": []", ", \"strength\": [[0.2, 1], [0.1, 1]]",
                                    ", \"strength\": [[0, -1]]", ", \"strength\": [0, 1]",
                                    ", \"strength\": 2"};
  for (size_t k = 0; k < sizeof bad / sizeof bad[0]; ++k) {
    char text[2048];
    snprintf(text, sizeof text, SCENE, -9.81, 1.0, bad[k]);
    mpm_scene scene;
    mpm_error err;
    assert_int_not_equal(mpm_scene_parse(text, "strength.json", &scene, &err), MPM_OK);
    if (!strstr(err.message, "materials[0].strength"))
      fail_msg("expected the key path in: %s", err.message);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_interpolation),
      cmocka_unit_test(test_force_scales),
      cmocka_unit_test(test_collapse_and_recover),
      cmocka_unit_test(test_bad_schedules),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
