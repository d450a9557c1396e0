/* test_soak.c - a block resting on the floor for many steps: no energy growth and no drift.
 *
 * A neo-Hookean block (E = 100 kPa) is dropped from 1 mm onto a sticky floor and left to rest.
 * APIC damps the block's elastic ringing only slowly, so "at rest" is checked as energy: after
 * the first half of the run the total energy (kinetic + elastic + gravitational) must not grow,
 * the kinetic energy must stay a small fraction of m g h, the centre of mass must not creep
 * sideways or sink, and the mass is kept exactly. The test runs 1,500 steps; the soak of the
 * robustness issue is the same run with SOAK_STEPS=100000 (figures printed). */
#include "support.h"
#include "sim/sim.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

static void centre_of_mass(const mpm_sim *sim, double c[3]) {
  const mpm_particles *p = &sim->particles;
  double m = 0;
  c[0] = c[1] = c[2] = 0;
  for (size_t i = 0; i < p->count; ++i) {
    m += p->mass[i];
    for (int d = 0; d < 3; ++d) c[d] += p->mass[i] * p->x[d][i];
  }
  for (int d = 0; d < 3; ++d) c[d] /= m;
}

static void test_block_at_rest(void **state) {
  (void)state;
  const long steps = getenv("SOAK_STEPS") ? atol(getenv("SOAK_STEPS")) : 1500;
  const char *json =
      "{\"domain\": {\"min\": [0,0,0], \"max\": [0.6,0.5,0.6], \"dx\": 0.025},"
      " \"time\": {\"end\": 1e6, \"fps\": 1},"
      " \"materials\": [{\"name\": \"jello\", \"model\": \"neo_hookean\", \"E\": 1e5, \"nu\": 0.3,"
      "                  \"density\": 1000}],"
      " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.3,0.176,0.3],"
      "               \"half_extent\": [0.1,0.1,0.1]}, \"material\": \"jello\"}],"
      " \"colliders\": [{\"shape\": {\"type\": \"halfspace\", \"point\": [0,0.075,0],"
      "                  \"normal\": [0,1,0]}, \"rule\": \"sticky\"}]}";
  mpm_scene scene;
  mpm_error err;
  mpm_error_clear(&err);
  if (mpm_scene_parse(json, "soak.json", &scene, &err) != MPM_OK) fail_msg("%s", err.message);
  mpm_sim *sim = NULL;
  if (mpm_sim_create_from_scene(&scene, &sim, &err) != MPM_OK) fail_msg("%s", err.message);
  mpm_scene_free(&scene);
  const long settle = steps / 2;
  double c0[3] = {0}, c1[3], ke_settled = 0, ke_max_after = 0, t_settled = 0, e_settled = 0;
  double e_max_after = -INFINITY;
  const double mass0 = mpm_sim_diagnostics(sim).mass;
  for (long s = 0; s < steps; ++s) {
    if (mpm_sim_step(sim, 1e9) != MPM_OK) fail_msg("step %ld: %s", s, mpm_sim_last_error(sim));
    if (s == settle) {
      centre_of_mass(sim, c0);
      const mpm_diagnostics d = mpm_sim_diagnostics(sim);
      ke_settled = d.kinetic;
      e_settled = d.kinetic + d.elastic + d.mass * 9.81 * c0[1];
      t_settled = mpm_sim_time(sim);
    } else if (s > settle && s % 25 == 0) {
      const mpm_diagnostics d = mpm_sim_diagnostics(sim);
      double c[3];
      centre_of_mass(sim, c);
      ke_max_after = fmax(ke_max_after, d.kinetic);
      e_max_after = fmax(e_max_after, d.kinetic + d.elastic + d.mass * 9.81 * c[1]);
    }
  }
  centre_of_mass(sim, c1);
  const mpm_diagnostics d = mpm_sim_diagnostics(sim);
  const double drift = hypot(c1[0] - c0[0], c1[2] - c0[2]), sink = c0[1] - c1[1];
  /* the block's potential energy scale: m g h with h its half height */
  const double scale = d.mass * 9.81 * 0.1;
  print_message("soak: %ld steps, %.3f s simulated (from %.3f s on): kinetic energy %.3g J then, "
                "at most %.3g J after, %.3g J at the end (m g h = %.3g J); total energy %.6g J "
                "then, at most %.6g J after (growth %.3g of m g h); centre of mass drift %.3g m "
                "sideways, %.3g m down; mass change %.3g\n",
                steps, mpm_sim_time(sim), t_settled, ke_settled, ke_max_after, d.kinetic, scale,
                e_settled, e_max_after, (e_max_after - e_settled) / scale, drift, sink,
                d.mass / mass0 - 1);
  assert_true(d.mass == mass0);
  assert_true(e_max_after <= e_settled + 1e-4 * scale); /* no energy growth */
  assert_true(ke_max_after < 3e-2 * scale);             /* ringing, not moving */
  assert_true(drift < 1e-4);                            /* 0.1 mm: no creep sideways */
  assert_true(fabs(sink) < 3e-3);                       /* nor sink into the floor */
  mpm_sim_destroy(sim);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_block_at_rest)};
  return cmocka_run_group_tests_name("soak", tests, NULL, NULL);
}
