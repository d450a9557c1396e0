/* test_implicit_balance.c - the implicit step ends where the body is in balance, not where its
 * solver gives up (solver/implicit.c): the Newton test is on the free DOFs' momentum out of
 * balance, against the impulse of the step's forces (not the body's momentum, not the
 * obstacles' reactions), and a step that cannot tell its answer from no motion keeps its answer.
 *   - A cantilever clamped by a sticky box, at a step 30 times the explicit one, with the
 *     default solver keys: it settles where a tightly solved run settles (it froze short of it,
 *     its velocity exactly 0 from step 75 on), near Euler-Bernoulli's deflection with shear, and
 *     at rest each step costs one Newton iteration and a few CG iterations; it settles within 2%
 *     of the explicit step's static deflection at the same dx (its ringing's mean over whole
 *     periods), and where Jacobi's run does with the multigrid preconditioner.
 *   - A stiff block falls freely: its momentum is M g t and it stays unstrained, its total
 *     energy never above the start (it was held in the air for 0.1 s, then strained by the
 *     explicit step hidden in the initial guess, which grew rounding errors 3000-fold a step). */
#include "support.h"
#include "sim/sim.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* A beam 0.7 m x 0.1 m x 0.1 m (E = 6e7 Pa, nu = 0, 1000 kg/m^3), its first 0.1 m in a sticky
 * box: 0.6 m free. dx = 0.025 m: four cells through the thickness. `solver` keys added. */
static mpm_sim *cantilever(const char *solver) {
  char text[2048];
  snprintf(
      text, sizeof text,
      "{\"domain\": {\"min\": [0,0,0], \"max\": [0.9,0.6,0.3], \"dx\": 0.025},"
      " \"gravity\": [0,-9.81,0], \"time\": {\"end\": 1.0, \"fps\": 4},"
      " \"solver\": {\"integrator\": \"implicit\", \"dt\": 0.01%s},"
      " \"materials\": [{\"name\": \"m\", \"model\": \"fixed_corotated\", \"E\": 6e7, \"nu\": 0,"
      " \"density\": 1000}],"
      " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.45,0.4,0.15],"
      " \"half_extent\": [0.35,0.05,0.05]}, \"material\": \"m\", \"jitter\": 0}],"
      " \"colliders\": [{\"shape\": {\"type\": \"box\", \"center\": [0.1,0.4,0.15],"
      " \"half_extent\": [0.1,0.1,0.1]}, \"rule\": \"sticky\"}]}",
      solver);
  return test_sim_from_json(text, "cantilever.json");
}

/* The mean downward displacement of the particles that start in the last column of cells
 * (x > 0.775 m: the free end), m. */
static double tip_deflection(const mpm_sim *sim, const double *y0, size_t count) {
  const mpm_particles *p = &sim->particles;
  double sum = 0;
  size_t n = 0;
  for (size_t i = 0; i < p->count; ++i) {
    const uint32_t id = p->id[i];
    if (id < count && y0[id] > -1) {
      sum += y0[id] - (double)p->x[1][i];
      ++n;
    }
  }
  assert_true(n > 0);
  return sum / (double)n;
}

/* Runs the cantilever to its end; returns its tip deflection; the stats rows stay in sim. */
static double settle(mpm_sim *sim) {
  const mpm_particles *p = &sim->particles;
  double *y0 = malloc(p->count * sizeof *y0);
  assert_non_null(y0);
  for (size_t i = 0; i < p->count; ++i) y0[i] = -2;
  for (size_t i = 0; i < p->count; ++i)
    if (p->x[0][i] > 0.775) y0[p->id[i]] = (double)p->x[1][i];
  const size_t count = p->count;
  while (mpm_sim_frame(sim) < mpm_sim_frame_count(sim))
    if (mpm_sim_advance_frame(sim) != MPM_OK) fail_msg("%s", mpm_sim_last_error(sim));
  const double d = tip_deflection(sim, y0, count);
  free(y0);
  return d;
}

/* The default keys' settled tip deflection (test_cantilever_settles), for the tests after it. */
static double default_deflection;

static double default_settled(void) {
  if (default_deflection == 0) {
    mpm_sim *sim = cantilever("");
    default_deflection = settle(sim);
    mpm_sim_destroy(sim);
  }
  return default_deflection;
}

static void test_cantilever_settles(void **state) {
  (void)state;
  mpm_sim *sim = cantilever("");
  assert_int_equal(mpm_sim_enable_output(sim, test_temp_dir("cantilever")), MPM_OK);
  const double d = default_deflection = settle(sim);
  mpm_stats_row rest[2]; /* its last two frames, at rest */
  memcpy(rest, &sim->out.stats[3], sizeof rest);
  mpm_sim_destroy(sim);
  /* where a run solved to 1e-4 with up to 4 Newton iterations settles */
  mpm_sim *tight = cantilever(", \"newton_iterations\": 4, \"cg_tolerance\": 1e-4");
  const double ref = settle(tight);
  mpm_sim_destroy(tight);
  /* Euler-Bernoulli with shear (Timoshenko, kappa = 5/6) at the particles' mean x, 0.7875 m:
   * w(s) = q (s^4 - 4 L s^3 + 6 L^2 s^2) / (24 E I) + q (L s - s^2 / 2) / (kappa G A),
   * s = 0.5875 of L = 0.6 from the clamp's face (the two layers of particles past 0.775 m) */
  const double q = 1000 * 9.81 * 0.01, EI = 6e7 * 1e-4 / 12, kGA = 5.0 / 6 * 3e7 * 0.01;
  const double L = 0.6, s = 0.5875;
  const double beam = q * (pow(s, 4) - 4 * L * pow(s, 3) + 6 * L * L * s * s) / (24 * EI) +
                      q * (L * s - s * s / 2) / kGA;
  print_message("tip deflection %.6g m, tightly solved %.6g m (%+.2f%%), beam theory %.6g m "
                "(%+.1f%%)\n",
                d, ref, 100 * (d / ref - 1), beam, 100 * (d / beam - 1));
  if (fabs(d / ref - 1) > 5e-3)
    fail_msg("settled at %.6g m, %.2f%% from the tightly solved %.6g m", d, 100 * (d / ref - 1),
             ref);
  /* four cells through the thickness: the discretization's own error, a few percent */
  assert_true(fabs(d / beam - 1) < 0.08);
  /* at rest, each step one Newton iteration and at most 5 CG ones */
  for (int f = 0; f < 2; ++f)
    if (!(rest[f].newton_iterations_mean <= 1 && rest[f].cg_iterations_mean <= 5))
      fail_msg("frame %d, at rest: %.2f Newton and %.2f CG iterations per step", f + 3,
               rest[f].newton_iterations_mean, rest[f].cg_iterations_mean);
}

/* The same cantilever run explicitly (APIC at its CFL step, 4e-5 s) for 0.5 s, undamped: it
 * rings about its static deflection (about 11 Hz), so the mean tip deflection over whole periods
 * (from the first to the last upward crossing of the mean, the mean taken again over them) is
 * where it would come to rest. The implicit step, 250 times longer, settles within 2% of it at
 * the same dx. (A drag region makes a poor reference: the damped beam crept for a second, 2.5%
 * short at 0.4 s with 30 1/s and drifting away with 100 1/s.) */
static void test_cantilever_against_explicit(void **state) {
  (void)state;
  const char *text =
      "{\"domain\": {\"min\": [0,0,0], \"max\": [0.9,0.6,0.3], \"dx\": 0.025},"
      " \"gravity\": [0,-9.81,0], \"time\": {\"end\": 0.5, \"fps\": 1000},"
      " \"solver\": {\"transfer\": \"apic\"},"
      " \"materials\": [{\"name\": \"m\", \"model\": \"fixed_corotated\", \"E\": 6e7, \"nu\": 0,"
      " \"density\": 1000}],"
      " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.45,0.4,0.15],"
      " \"half_extent\": [0.35,0.05,0.05]}, \"material\": \"m\", \"jitter\": 0}],"
      " \"colliders\": [{\"shape\": {\"type\": \"box\", \"center\": [0.1,0.4,0.15],"
      " \"half_extent\": [0.1,0.1,0.1]}, \"rule\": \"sticky\"}]}";
  mpm_sim *ex = test_sim_from_json(text, "cantilever_explicit.json");
  const mpm_particles *p = &ex->particles;
  double *y0 = malloc(p->count * sizeof *y0), d[500];
  assert_non_null(y0);
  for (size_t i = 0; i < p->count; ++i) y0[i] = -2;
  for (size_t i = 0; i < p->count; ++i)
    if (p->x[0][i] > 0.775) y0[p->id[i]] = (double)p->x[1][i];
  const size_t count = p->count;
  int n = 0;
  while (mpm_sim_frame(ex) < mpm_sim_frame_count(ex) && n < 500) {
    if (mpm_sim_advance_frame(ex) != MPM_OK) fail_msg("%s", mpm_sim_last_error(ex));
    d[n++] = tip_deflection(ex, y0, count);
  }
  free(y0);
  const long long steps = (long long)ex->steps;
  mpm_sim_destroy(ex);
  double mean = 0;
  for (int k = 0; k < n; ++k) mean += d[k];
  mean /= n;
  int first = -1, last = -1, periods = 0;
  for (int it = 0; it < 3; ++it) {
    first = last = -1, periods = 0;
    for (int k = 1; k < n; ++k)
      if (d[k - 1] < mean && d[k] >= mean) {
        if (first < 0) first = k;
        last = k, ++periods;
      }
    assert_true(periods >= 4);
    double m = 0;
    for (int k = first; k < last; ++k) m += d[k];
    mean = m / (last - first);
  }
  const double di = default_settled();
  print_message("explicit (%lld steps): mean tip deflection over %d periods %.6g m; implicit at "
                "dt = 0.01 s: %.6g m (%+.2f%%)\n",
                steps, periods - 1, mean, di, 100 * (di / mean - 1));
  assert_true(fabs(di / mean - 1) < 0.02);
}

/* The same cantilever preconditioned by the multigrid (solver/multigrid.h): it settles where
 * Jacobi's run does, within what the tolerance allows (1e-2 of the weight's impulse: a body at
 * rest within 1% of its deflection is balanced to it; measured: 0.03% apart in float, 0.78% in
 * double, where the multigrid's run came to rest within the tolerance on the far side), and at
 * rest a step costs one Newton iteration and a few CG ones. */
static void test_cantilever_multigrid(void **state) {
  (void)state;
  const double dj = default_settled();
  mpm_sim *sim = cantilever(", \"preconditioner\": \"multigrid\"");
  assert_int_equal(mpm_sim_enable_output(sim, test_temp_dir("cantilever_multigrid")), MPM_OK);
  const double d = settle(sim);
  mpm_stats_row rest[2];
  memcpy(rest, &sim->out.stats[3], sizeof rest);
  mpm_sim_destroy(sim);
  print_message("multigrid: tip deflection %.6g m, Jacobi %.6g m (%+.2f%%); at rest %.2f Newton, "
                "%.2f CG iterations per step\n",
                d, dj, 100 * (d / dj - 1), rest[1].newton_iterations_mean,
                rest[1].cg_iterations_mean);
  assert_true(fabs(d / dj - 1) < 1e-2);
  for (int f = 0; f < 2; ++f)
    assert_true(rest[f].newton_iterations_mean <= 1 && rest[f].cg_iterations_mean <= 5);
}

/* With solver.scheme "newmark": a step where an obstacle acts is backward Euler (implicit.h:
 * with Newmark's positions there a rubber bunny landing at the CFL rate rebounded faster than its
 * step allowed, and one resting on a floor with friction slowly gained strain). The clamped
 * cantilever is in contact at every step: it settles bitwise where the default run does. */
static void test_cantilever_newmark(void **state) {
  (void)state;
  mpm_sim *sim = cantilever(", \"scheme\": \"newmark\"");
  const double d = settle(sim);
  mpm_sim_destroy(sim);
  assert_true(d == default_settled());
}

/* Zhu's single linearized step (newton_iterations 1) on the same cantilever: it stopped at step
 * 9 with a CFL violation (a particle at 2 m/s); it runs, and sags as the Newton runs do. */
static void test_cantilever_single_step(void **state) {
  (void)state;
  mpm_sim *sim = cantilever(", \"newton_iterations\": 1");
  const double d = settle(sim);
  mpm_sim_destroy(sim);
  print_message("Zhu's single step: tip deflection %.6g m\n", d);
  assert_true(d > 0.0030 && d < 0.0037);
}

/* A 1e9 Pa block of 4096 particles falling from rest at dt = 0.2 ms, far from everything. */
static void test_free_fall_exact(void **state) {
  (void)state;
  mpm_sim *sim = test_sim_from_json(
      "{\"domain\": {\"min\": [0,0,0], \"max\": [0.6,1.2,0.6], \"dx\": 0.02},"
      " \"gravity\": [0,-9.81,0], \"time\": {\"end\": 0.04, \"fps\": 50},"
      " \"solver\": {\"integrator\": \"implicit\", \"dt\": 0.0002},"
      " \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\", \"E\": 1e9, \"nu\": 0.3,"
      " \"density\": 1000}],"
      " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.3,0.8,0.3],"
      " \"half_extent\": [0.08,0.08,0.08]}, \"material\": \"m\", \"jitter\": 0}]}",
      "fall.json");
  assert_int_equal(mpm_sim_enable_output(sim, test_temp_dir("fall")), MPM_OK);
  while (mpm_sim_frame(sim) < mpm_sim_frame_count(sim))
    if (mpm_sim_advance_frame(sim) != MPM_OK) fail_msg("%s", mpm_sim_last_error(sim));
  const double M = sim->out.stats[0].mass, start = sim->out.stats[0].total_energy;
  for (int f = 1; f <= mpm_sim_frame_count(sim); ++f) {
    const mpm_stats_row *row = &sim->out.stats[f];
    const double p = -M * 9.81 * row->time;
    if (fabs(row->momentum[1] - p) > 1e-4 * fabs(p))
      fail_msg("frame %d: momentum %.9g, M g t = %.9g", f, row->momentum[1], p);
    if (!(row->total_energy <= start * (1 + 1e-6)))
      fail_msg("frame %d: total energy %.9g J, %.3g of the start above it", f, row->total_energy,
               row->total_energy / start - 1);
    /* in float, F's rounding walks over the 300 steps (a few ulps: 7e-4 J); it was 30 times
       that, from the explicit step in the initial guess */
    if (!(fabs(row->elastic) <= TOL(1e-4, 1e-9) * start))
      fail_msg("frame %d: elastic energy %.3g J in free fall", f, row->elastic);
  }
  mpm_sim_destroy(sim);
}

/* A rubber block (E = 1e7 Pa) thrown spinning onto a floor with friction 0.5, at a step 60 times
 * the explicit one, with each scheme (Newmark's in its flight): its total energy never rises
 * above the start, and once it rests its elastic energy is a small part of what it brought down.
 * Friction applied after the solve, to the velocities the solve had balanced, strained the
 * contact layer by the whole step's sliding: the block gained energy at the impact and kept it
 * as strain at rest. */
static void test_landing_with_friction(void **state) {
  (void)state;
  static const char *const schemes[] = {"backward_euler", "newmark"};
  for (int k = 0; k < 2; ++k) {
    char json[1600];
    snprintf(json, sizeof json,
             "{\"domain\": {\"min\": [0,0,0], \"max\": [1,0.6,0.6], \"dx\": 0.02},"
             " \"gravity\": [0,-9.81,0], \"time\": {\"end\": 0.5, \"fps\": 24},"
             " \"solver\": {\"integrator\": \"implicit\", \"dt\": 0.0041666667,"
             " \"scheme\": \"%s\"},"
             " \"materials\": [{\"name\": \"rubber\", \"model\": \"neo_hookean\", \"E\": 1e7,"
             " \"nu\": 0.4, \"density\": 1100}],"
             " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.4,0.26,0.3],"
             " \"half_extent\": [0.08,0.08,0.08]}, \"material\": \"rubber\", \"jitter\": 0,"
             " \"velocity\": [1,0,0], \"angular_velocity\": [0,2,0]}],"
             " \"colliders\": [{\"shape\": {\"type\": \"halfspace\", \"point\": [0,0.1,0],"
             " \"normal\": [0,1,0]}, \"rule\": \"separate\", \"friction\": 0.5}]}",
             schemes[k]);
    mpm_sim *sim = test_sim_from_json(json, "landing.json");
    assert_int_equal(mpm_sim_enable_output(sim, test_temp_dir("landing")), MPM_OK);
    while (mpm_sim_frame(sim) < mpm_sim_frame_count(sim))
      if (mpm_sim_advance_frame(sim) != MPM_OK) fail_msg("%s", mpm_sim_last_error(sim));
    const double start = sim->out.stats[0].total_energy;
    const double brought = start - sim->out.stats[mpm_sim_frame_count(sim)].gravitational;
    double worst = -INFINITY;
    for (int f = 1; f <= mpm_sim_frame_count(sim); ++f) {
      const mpm_stats_row *row = &sim->out.stats[f];
      worst = fmax(worst, row->total_energy - start);
      print_message("%s frame %2d: kinetic %.4f, elastic %.4f, total %+.5f J from the start\n",
                    schemes[k], f, row->kinetic, row->elastic, row->total_energy - start);
    }
    const mpm_stats_row *end = &sim->out.stats[mpm_sim_frame_count(sim)];
    print_message("%s: the most above the start: %.3g J (%.2g of it); at rest %.4f J elastic of "
                  "the %.3f J it brought down\n",
                  schemes[k], worst, worst / start, end->elastic, brought);
    assert_true(worst <= 1e-5 * fabs(start));
    assert_true(end->elastic < 0.05 * brought);
    mpm_sim_destroy(sim);
  }
}

/* A rubber ball (E = 1e7 Pa) thrown spinning onto a floor with friction 0.5, at steps of a
 * frame (1/60 s, some 200 explicit steps), with each preconditioner: once it rests (the last
 * quarter second of the second), a step is at most one Newton iteration and 5 CG iterations.
 * The residuals' norm counted the nodes at the edge of a particle's stencil as whole ones
 * (implicit.c, jacobi()): at rest Jacobi paid 15 CG iterations every step, and the multigrid
 * 13, 6 and 2 a step in the frames the test checks (a rubber bunny 40 a step, with 2 Newton
 * iterations). */
static void test_rest_on_friction_floor(void **state) {
  (void)state;
  for (int k = 0; k < 2; ++k) {
    char json[1600];
    snprintf(json, sizeof json,
             "{\"domain\": {\"min\": [0,0,0], \"max\": [0.6,0.5,0.6], \"dx\": 0.02},"
             " \"gravity\": [0,-9.81,0], \"time\": {\"end\": 1.0, \"fps\": 20},"
             " \"solver\": {\"integrator\": \"implicit\", \"dt\": 0.0166666667,"
             " \"preconditioner\": \"%s\"},"
             " \"materials\": [{\"name\": \"rubber\", \"model\": \"neo_hookean\", \"E\": 1e7,"
             " \"nu\": 0.4, \"density\": 1100}],"
             " \"bodies\": [{\"shape\": {\"type\": \"sphere\", \"center\": [0.25,0.25,0.3],"
             " \"radius\": 0.1}, \"material\": \"rubber\", \"velocity\": [0.4,0,0],"
             " \"angular_velocity\": [0,2,0]}],"
             " \"colliders\": [{\"shape\": {\"type\": \"halfspace\", \"point\": [0,0.1,0],"
             " \"normal\": [0,1,0]}, \"rule\": \"separate\", \"friction\": 0.5}]}",
             k ? "multigrid" : "jacobi");
    mpm_sim *sim = test_sim_from_json(json, "rest.json");
    assert_int_equal(mpm_sim_enable_output(sim, test_temp_dir("rest")), MPM_OK);
    while (mpm_sim_frame(sim) < mpm_sim_frame_count(sim))
      if (mpm_sim_advance_frame(sim) != MPM_OK) fail_msg("%s", mpm_sim_last_error(sim));
    const int frames = mpm_sim_frame_count(sim);
    for (int f = 1; f <= frames; ++f) {
      const mpm_stats_row *row = &sim->out.stats[f];
      print_message("%s frame %2d: kinetic %.3g J, %.2f Newton and %.1f CG iterations a step\n",
                    k ? "multigrid" : "jacobi", f, row->kinetic, row->newton_iterations_mean,
                    row->cg_iterations_mean);
    }
    /* the last five frames (a quarter of a second) at rest */
    for (int f = frames - 4; f <= frames; ++f) {
      const mpm_stats_row *row = &sim->out.stats[f];
      assert_true(row->kinetic < 1e-6);
      assert_true(row->newton_iterations_mean <= 1);
      assert_true(row->cg_iterations_mean <= 5);
    }
    mpm_sim_destroy(sim);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_cantilever_settles),
      cmocka_unit_test(test_cantilever_single_step),
      cmocka_unit_test(test_cantilever_newmark),
      cmocka_unit_test(test_cantilever_multigrid),
      cmocka_unit_test(test_cantilever_against_explicit),
      cmocka_unit_test(test_free_fall_exact),
      cmocka_unit_test(test_landing_with_friction),
      cmocka_unit_test(test_rest_on_friction_floor),
  };
  return test_cleanup(cmocka_run_group_tests_name("implicit_balance", tests, NULL, NULL));
}
