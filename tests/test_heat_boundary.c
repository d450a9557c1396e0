/* test_heat_boundary.c - a slab heated by a held hot collider against the semi-infinite
 * solution T = Ts + (T0 - Ts) erf(x / (2 sqrt(alpha t))) (x from the slab's face):
 *   - the profile is monotone (no layer colder than the one behind it: conduction cannot make
 *     one) and bounded by the temperatures present (T0 = 20 and Ts = 120), also when the source
 *     stops half a cell short of the slab;
 *   - the depth where the slab is half-way (T = 70) is within 4% of the solution's
 *     0.9539 sqrt(alpha t), and moves by at most 3% when the slab and source are shifted by half
 *     a cell against the grid;
 *   - the heat the slab took in is within 6% of the solution's 2 rho c (Ts - T0) sqrt(alpha t / pi)
 *     per unit area;
 *   - heat.pic's share acts per second, not per step: the depth with pic = 1 (the default) or 4
 *     is the same (within 1%) at dt and at dt / 4.
 * Before: the same slab shifted by half a cell heated 12% less deep, layers next to the source
 * were colder than the ones behind them, a source half a cell short left a layer at 11 degrees
 * (below both temperatures present), and the PIC share deepened the profile by 12% at dt and 49%
 * at dt / 4. */
#include "support.h"
#include "mpm/mpm.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define T0 20.0
#define TS 120.0
#define ALPHA 4e-3 /* k / (rho c) = 4000 / (1000 * 1000), m^2/s */
#define T_END 1.0
#define DX 0.01

typedef struct profile {
  int layers;
  double x[128], T[128]; /* layer depth from the face (m) and mean temperature */
  double lo, hi;         /* the coldest and hottest particle */
  double heat;           /* taken in per unit area, J/m^2 */
  double half_depth;     /* where the layers' temperature falls through 70 (m) */
} profile;

/* The slab x in [face, 0.4] (y, z in [0.035, 0.055]) at T0, a source box up to face - gap at Ts,
 * run to T_END; the layers of particles (planes x = const) averaged. */
static profile run_slab(double face, double gap, double pic, double max_dt) {
  char json[4096], pic_key[64] = ""; /* pic < 0: the default */
  if (pic >= 0) snprintf(pic_key, sizeof pic_key, ", \"pic\": %g", pic);
  const double src_hi = face - gap, src_lo = 0.0;
  snprintf(json, sizeof json,
           "{\"domain\": {\"min\": [0, 0, 0], \"max\": [0.45, 0.09, 0.09], \"dx\": %g},"
           " \"gravity\": [0, 0, 0], \"time\": {\"end\": %g, \"fps\": 1},"
           " \"solver\": {\"max_dt\": %g},"
           " \"heat\": {\"temperature\": %g%s},"
           " \"materials\": [{\"name\": \"m\", \"model\": \"fixed_corotated\", \"E\": 1e3,"
           "   \"nu\": 0.3, \"density\": 1000, \"specific_heat\": 1000, \"conductivity\": %g}],"
           " \"colliders\": [{\"shape\": {\"type\": \"box\", \"center\": [%.17g, 0.045, 0.045],"
           "   \"half_extent\": [%.17g, 0.2, 0.2]}, \"rule\": \"sticky\", \"temperature\": %g}],"
           " \"bodies\": [{\"material\": \"m\", \"shape\": {\"type\": \"box\","
           "   \"center\": [%.17g, 0.045, 0.045], \"half_extent\": [%.17g, 0.01, 0.01]}}]}",
           DX, T_END, max_dt, T0, pic_key, ALPHA * 1e6, 0.5 * (src_lo + src_hi),
           0.5 * (src_hi - src_lo), TS, 0.5 * (face + 0.4), 0.5 * (0.4 - face));
  mpm_sim *sim;
  char err[2048];
  if (mpm_sim_create_from_json(json, NULL, &sim, err, sizeof err) != MPM_OK) fail_msg("%s", err);
  while (mpm_sim_frame(sim) < mpm_sim_frame_count(sim))
    if (mpm_sim_advance_frame(sim) != MPM_OK) fail_msg("%s", mpm_sim_last_error(sim));
  const mpm_particle_view v = mpm_sim_particles(sim);
  profile pr;
  memset(&pr, 0, sizeof pr);
  pr.lo = INFINITY, pr.hi = -INFINITY;
  double sum[128] = {0}, xs[128] = {0}, heat = 0, mass = 0;
  int count[128] = {0};
  const double h = DX / 2; /* 8 particles per cell */
  for (size_t i = 0; i < v.count; ++i) {
    const double x = v.real_size == 4 ? ((const float *)v.x[0])[i] : ((const double *)v.x[0])[i];
    const double T =
        v.real_size == 4 ? ((const float *)v.temperature)[i] : ((const double *)v.temperature)[i];
    const double m = v.real_size == 4 ? ((const float *)v.mass)[i] : ((const double *)v.mass)[i];
    const int k = (int)floor((x - face) / h);
    if (k < 0 || k >= 128) fail_msg("particle at x = %g outside the slab", x);
    sum[k] += T, xs[k] += x - face, count[k]++;
    pr.lo = fmin(pr.lo, T), pr.hi = fmax(pr.hi, T);
    heat += m * 1000 * (T - T0), mass += m;
  }
  pr.heat = heat / (0.02 * 0.02);
  for (int k = 0; k < 128 && count[k]; ++k, ++pr.layers) {
    pr.x[k] = xs[k] / count[k];
    pr.T[k] = sum[k] / count[k];
  }
  pr.half_depth = NAN;
  const double half = 0.5 * (T0 + TS);
  for (int k = 0; k + 1 < pr.layers; ++k)
    if (pr.T[k] >= half && pr.T[k + 1] < half) {
      pr.half_depth =
          pr.x[k] + (pr.T[k] - half) / (pr.T[k] - pr.T[k + 1]) * (pr.x[k + 1] - pr.x[k]);
      break;
    }
  mpm_sim_destroy(sim);
  return pr;
}

static double exact_half_depth(void) {
  return 0.9538725524 * sqrt(ALPHA * T_END); /* 2 erfinv(1/2) sqrt(alpha t) */
}

static void print_profile(const char *what, const profile *p) {
  print_message(
      "%s: half depth %.4f m (solution %.4f, %+.1f%%), heat %+.1f%%, T in [%.2f, %.2f]\n", what,
      p->half_depth, exact_half_depth(), 100 * (p->half_depth / exact_half_depth() - 1),
      100 * (p->heat / (2 * 1e6 * (TS - T0) * sqrt(ALPHA * T_END / 3.14159265358979)) - 1), p->lo,
      p->hi);
  char line[2048];
  size_t at = 0;
  for (int k = 0; k < 16 && k < p->layers; ++k)
    at += (size_t)snprintf(line + at, sizeof line - at, " %.2f", p->T[k]);
  print_message("  first layers:%s\n", line);
}

static int monotone(const profile *p) {
  for (int k = 0; k + 1 < p->layers; ++k)
    if (p->T[k + 1] > p->T[k] + 1e-3) return 0;
  return 1;
}

static void test_slab_against_erf(void **state) {
  (void)state;
  const double exact = exact_half_depth();
  const profile on_node = run_slab(0.10, 0, -1, 0);
  const profile mid_cell = run_slab(0.105, 0, -1, 0);
  const profile gap = run_slab(0.10, 0.5 * DX, -1, 0);
  print_profile("face on a node", &on_node);
  print_profile("face mid-cell", &mid_cell);
  print_profile("source half a cell short", &gap);
  const profile *all[3] = {&on_node, &mid_cell, &gap};
  for (int k = 0; k < 3; ++k) {
    assert_true(monotone(all[k]));
    assert_true(all[k]->lo >= T0 - 1e-3 && all[k]->hi <= TS + 1e-3);
  }
  for (int k = 0; k < 2; ++k) {
    assert_true(fabs(all[k]->half_depth / exact - 1) < 0.04);
    const double q = all[k]->heat / (2 * 1e6 * (TS - T0) * sqrt(ALPHA * T_END / 3.14159265358979));
    assert_true(fabs(q - 1) < 0.06);
  }
  assert_true(fabs(on_node.half_depth - mid_cell.half_depth) / exact < 0.03);
}

static void test_pic_independent_of_dt(void **state) {
  (void)state;
  /* the default share (pic 1) and a stronger one (4), each at two steps 4 times apart */
  const profile a = run_slab(0.10, 0, 1, 2e-3), b = run_slab(0.10, 0, 1, 5e-4);
  const profile c = run_slab(0.10, 0, 4, 2e-3), e = run_slab(0.10, 0, 4, 5e-4);
  print_profile("pic 1, dt 2e-3", &a);
  print_profile("pic 1, dt 5e-4", &b);
  print_profile("pic 4, dt 2e-3", &c);
  print_profile("pic 4, dt 5e-4", &e);
  assert_true(fabs(a.half_depth - b.half_depth) / exact_half_depth() < 0.01);
  assert_true(fabs(c.half_depth - e.half_depth) / exact_half_depth() < 0.01);
  assert_true(monotone(&a) && monotone(&b) && monotone(&c) && monotone(&e));
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_slab_against_erf),
                                     cmocka_unit_test(test_pic_independent_of_dt)};
  return cmocka_run_group_tests_name("heat_boundary", tests, NULL, NULL);
}
