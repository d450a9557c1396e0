/* test_implicit_newmark.c - the implicit step with Newmark's positions (solver.scheme "newmark":
 * beta = 1/2, gamma = 1; solver/implicit.h): the grid moves by the mean of the step's
 * velocities, and G2P moves and deforms the particles by it (grid.h, vm).
 *   - A block falls freely at steps of a frame (1/60 s): its centre of mass follows
 *     y0 - g t^2 / 2 to the rounding, where backward Euler's lags by g dt t / 2 (checked too, so
 *     the test tells the schemes apart), on the uniform grid and on the multi-level one; its
 *     momentum is M g t, its elastic energy stays near zero, and its total energy never rises.
 *   - 1 and 2 threads give bitwise the same run, and so does a run resumed from a checkpoint.
 *   - Particle domains with "newmark" are refused, naming solver.scheme.
 * A landing with friction with each scheme, and a clamped cantilever (steps in contact are
 * backward Euler's), are test_implicit_balance.c's. */
#include "support.h"
#include "core/parallel.h"
#include "sim/sim.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* A 1e7 Pa block falling from rest for 0.4 s at dt = 1/60 s (dx 8 cm: a step of the fall stays
 * within a cell) with `scheme`, or with `levels` > 0 for 0.2 s at 1/120 s on a multi-level grid
 * whose finer level holds the block's +x half (the guard allows half a fine cell a step). Returns
 * the largest distance of its centre of mass from y0 - g t^2 / 2 over the frames; checks momentum
 * and energy. */
static double free_fall(const char *scheme, int levels) {
  char domain[256], text[2048];
  if (levels)
    snprintf(domain, sizeof domain,
             "\"domain\": {\"min\": [0,0,0], \"max\": [0.96,2.4,0.96], \"dx\": 0.08, "
             "\"levels\": 2, \"refine\": [{\"level\": 1, \"box\": {\"min\": [0.48,0,0], "
             "\"max\": [0.96,2.4,0.96]}}]}");
  else
    snprintf(domain, sizeof domain,
             "\"domain\": {\"min\": [0,0,0], \"max\": [0.96,2.4,0.96], \"dx\": 0.08}");
  snprintf(text, sizeof text,
           "{%s, \"gravity\": [0,-9.81,0], \"time\": {\"end\": %g, \"fps\": 20},"
           " \"solver\": {\"integrator\": \"implicit\", \"dt\": %.10g, \"scheme\": \"%s\","
           " \"preconditioner\": \"multigrid\"},"
           " \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\", \"E\": 1e7, \"nu\": 0.3,"
           " \"density\": 1000}],"
           " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.48,1.6,0.48],"
           " \"half_extent\": [0.16,0.16,0.16]}, \"material\": \"m\", \"jitter\": 0}]}",
           domain, levels ? 0.2 : 0.4, levels ? 1.0 / 120 : 1.0 / 60, scheme);
  mpm_sim *sim = test_sim_from_json(text, "newmark_fall.json");
  assert_int_equal(mpm_sim_enable_output(sim, test_temp_dir("newmark_fall")), MPM_OK);
  const double y0 = test_centre_height(sim);
  double worst = 0;
  while (mpm_sim_frame(sim) < mpm_sim_frame_count(sim)) {
    if (mpm_sim_advance_frame(sim) != MPM_OK) fail_msg("%s", mpm_sim_last_error(sim));
    const double t = sim->time;
    worst = fmax(worst, fabs(test_centre_height(sim) - (y0 - 0.5 * 9.81 * t * t)));
  }
  const double M = sim->out.stats[0].mass, start = sim->out.stats[0].total_energy;
  double elastic = 0;
  for (int f = 1; f <= mpm_sim_frame_count(sim); ++f) {
    const mpm_stats_row *row = &sim->out.stats[f];
    const double p = -M * 9.81 * row->time;
    if (fabs(row->momentum[1] - p) > 1e-4 * fabs(p))
      fail_msg("%s: frame %d: momentum %.9g, M g t = %.9g", scheme, f, row->momentum[1], p);
    if (!(row->total_energy <= start + 1e-5 * fabs(start)))
      fail_msg("%s: frame %d: total energy %.9g J, above the start %.9g J", scheme, f,
               row->total_energy, start);
    /* the solve's tolerance (1e-2 of the weight's impulse) leaves strains of about 1e-4 */
    if (!(fabs(row->elastic) <= 1e-5 * fabs(start)))
      fail_msg("%s: frame %d: elastic energy %.3g J in free fall", scheme, f, row->elastic);
    elastic = fmax(elastic, fabs(row->elastic));
  }
  print_message("%s: elastic energy at most %.3g J (%.2g of the total)\n", scheme, elastic,
                elastic / fabs(start));
  mpm_sim_destroy(sim);
  return worst;
}

static void test_free_fall(void **state) {
  (void)state;
  for (int levels = 0; levels < 2; ++levels) {
    const double nm = free_fall("newmark", levels), be = free_fall("backward_euler", levels);
    /* backward Euler's lag at the end: g dt t / 2 = 33 mm (uniform), 8 mm (levels) */
    print_message("%s grid: centre of mass off y0 - g t^2 / 2 by at most %.3g m (Newmark), "
                  "%.3g m (backward Euler)\n",
                  levels ? "multi-level" : "uniform", nm, be);
    assert_true(be > (levels ? 0.006 : 0.025));
    /* float: the particles' positions near 1.9 m round to 1e-7 m, the 30 steps' sums on them */
    assert_true(nm < TOL(2e-5, 1e-9));
  }
}

/* A spinning rubber ball thrown down onto a slip floor, 12 steps of 1/120 s, multigrid: some in
 * flight (Newmark's), the rest in contact. */
static mpm_sim *spin_run(void) {
  mpm_sim *sim = test_sim_from_json(
      "{\"domain\": {\"min\": [0,0,0], \"max\": [0.6,0.6,0.6], \"dx\": 0.03},"
      " \"gravity\": [0,-9.81,0], \"time\": {\"end\": 0.1, \"fps\": 10},"
      " \"solver\": {\"integrator\": \"implicit\", \"dt\": 0.0083333333, \"scheme\": \"newmark\","
      " \"preconditioner\": \"multigrid\"},"
      " \"materials\": [{\"name\": \"rubber\", \"model\": \"neo_hookean\", \"E\": 1e6,"
      " \"nu\": 0.4, \"density\": 1100}],"
      " \"bodies\": [{\"shape\": {\"type\": \"sphere\", \"center\": [0.3,0.3,0.3],"
      " \"radius\": 0.1}, \"material\": \"rubber\", \"velocity\": [0.4,-1,0],"
      " \"angular_velocity\": [0,4,0]}],"
      " \"colliders\": [{\"shape\": {\"type\": \"halfspace\", \"point\": [0,0.1,0],"
      " \"normal\": [0,1,0]}, \"rule\": \"slip\"}]}",
      "newmark_spin.json");
  while (mpm_sim_frame(sim) < mpm_sim_frame_count(sim))
    if (mpm_sim_advance_frame(sim) != MPM_OK) fail_msg("%s", mpm_sim_last_error(sim));
  return sim;
}

static void test_threads_bitwise(void **state) {
  (void)state;
  mpm_sim *r[2];
  for (int t = 0; t < 2; ++t) {
    mpm_set_threads(t + 1);
    r[t] = spin_run();
  }
  mpm_set_threads(0);
  test_assert_same_particles(r[0], r[1]);
  assert_int_equal(r[0]->cg_iterations, r[1]->cg_iterations);
  mpm_sim_destroy(r[0]);
  mpm_sim_destroy(r[1]);
}

/* A run checkpointed after a frame of Newmark steps and resumed ends bitwise as the whole run
 * (the scheme keeps no state of its own: v^n is P2G's). */
static void test_resume_bitwise(void **state) {
  (void)state;
  const char *dir = test_temp_dir("newmark_resume");
  char scene[512], full[512], part[512], path[1100];
  snprintf(scene, sizeof scene, "%s/scene.json", dir);
  snprintf(full, sizeof full, "%s/full", dir);
  snprintf(part, sizeof part, "%s/part", dir);
  FILE *f = fopen(scene, "w");
  assert_non_null(f);
  fputs("{\"domain\": {\"min\": [0,0,0], \"max\": [0.96,2.4,0.96], \"dx\": 0.08},"
        " \"gravity\": [0,-9.81,0], \"time\": {\"end\": 0.1, \"fps\": 20},"
        " \"solver\": {\"integrator\": \"implicit\", \"dt\": 0.0166666667,"
        " \"scheme\": \"newmark\", \"preconditioner\": \"multigrid\"},"
        " \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\", \"E\": 1e7,"
        " \"nu\": 0.3, \"density\": 1000}],"
        " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.48,1.6,0.48],"
        " \"half_extent\": [0.16,0.16,0.16]}, \"material\": \"m\","
        " \"angular_velocity\": [0,3,1]}]}",
        f);
  assert_int_equal(fclose(f), 0);
  mpm_sim *r[3];
  char err[1024];
  for (int k = 0; k < 3; ++k)
    if (mpm_sim_create_from_file(scene, &r[k], err, sizeof err) != MPM_OK) fail_msg("%s", err);
  assert_int_equal(mpm_sim_enable_output(r[0], full), MPM_OK);
  while (mpm_sim_frame(r[0]) < mpm_sim_frame_count(r[0]))
    assert_int_equal(mpm_sim_advance_frame(r[0]), MPM_OK);
  assert_int_equal(mpm_sim_enable_output(r[1], part), MPM_OK);
  assert_int_equal(mpm_sim_advance_frame(r[1]), MPM_OK);
  assert_int_equal(mpm_sim_write_checkpoint(r[1], path, sizeof path), MPM_OK);
  mpm_sim_destroy(r[1]);
  assert_int_equal(mpm_sim_resume(r[2], part, path, sizeof path), MPM_OK);
  while (mpm_sim_frame(r[2]) < mpm_sim_frame_count(r[2]))
    assert_int_equal(mpm_sim_advance_frame(r[2]), MPM_OK);
  assert_int_equal(r[0]->steps, r[2]->steps);
  test_assert_same_particles(r[0], r[2]);
  mpm_sim_destroy(r[0]);
  mpm_sim_destroy(r[2]);
}

static void test_domains_refused(void **state) {
  (void)state;
  mpm_scene scene;
  mpm_error err;
  const char *text =
      "{\"domain\": {\"min\": [0,0,0], \"max\": [1,1,1], \"dx\": 0.1},"
      " \"time\": {\"end\": 1, \"fps\": 10},"
      " \"solver\": {\"integrator\": \"implicit\", \"scheme\": \"newmark\"},"
      " \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\", \"E\": 1e6, \"nu\": 0.3,"
      " \"density\": 1000}],"
      " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.5,0.5,0.5],"
      " \"half_extent\": [0.2,0.2,0.2]}, \"material\": \"m\", \"jitter\": 0, \"domains\": true}]}";
  assert_int_equal(mpm_scene_parse(text, "newmark_domains.json", &scene, &err), MPM_ERR_INVALID);
  print_message("%s\n", err.message);
  assert_non_null(strstr(err.message, "solver.scheme"));
  assert_non_null(strstr(err.message, "bodies[0]"));
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_free_fall),

      cmocka_unit_test(test_threads_bitwise),
      cmocka_unit_test(test_resume_bitwise),
      cmocka_unit_test(test_domains_refused),
  };
  return test_cleanup(cmocka_run_group_tests_name("implicit_newmark", tests, NULL, NULL));
}
