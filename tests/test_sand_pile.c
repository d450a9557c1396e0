/* test_sand_pile.c - a column of Drucker-Prager sand collapses into a pile whose slope rises
 * with the friction angle (Klar et al. 2016; Gao et al. 2017 sec. 4.2.1): the angle of repose
 * of a granular material grows with its internal friction. Three friction angles, same column. */
#include "support.h"
#include "sim/sim.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

/* Slope angle (degrees) of the settled pile: the top surface height over radial distance from
 * the pile axis, fitted by least squares between 15% and 85% of the pile radius (the 90th
 * percentile distance). */
static int cmp_double(const void *a, const void *b) {
  const double x = *(const double *)a, y = *(const double *)b;
  return x < y ? -1 : x > y;
}

static double pile_slope(const mpm_sim *sim, double cx, double cz, double floor_y) {
  const mpm_particles *p = &sim->particles;
  /* the pile's radius: the 90th percentile of the particles' distances from the axis, so that
     a few grains thrown far away do not stretch the fit over the flat outskirts */
  double *r = malloc(p->count * sizeof *r);
  for (size_t i = 0; i < p->count; ++i) r[i] = hypot(p->x[0][i] - cx, p->x[2][i] - cz);
  qsort(r, p->count, sizeof *r, cmp_double);
  const double radius = r[(size_t)(0.9 * (double)(p->count - 1))];
  free(r);
  enum { BINS = 12 };
  double top[BINS];
  for (int b = 0; b < BINS; ++b) top[b] = -1;
  for (size_t i = 0; i < p->count; ++i) {
    const double ri = hypot(p->x[0][i] - cx, p->x[2][i] - cz);
    const int b = (int)(ri / radius * BINS);
    if (b >= BINS) continue;
    const double h = p->x[1][i] - floor_y;
    if (h > top[b]) top[b] = h;
  }
  /* least-squares line through the top surface between 15% and 85% of the radius */
  double sr = 0, sh = 0, srr = 0, srh = 0;
  int n = 0;
  for (int b = (int)(0.15 * BINS); b < (int)(0.85 * BINS); ++b) {
    if (top[b] < 0) continue;
    const double rb = (b + 0.5) * radius / BINS;
    sr += rb;
    sh += top[b];
    srr += rb * rb;
    srh += rb * top[b];
    ++n;
  }
  const double slope = -(n * srh - sr * sh) / (n * srr - sr * sr);
  return atan(slope) * 180 / 3.14159265358979323846;
}

static double settle(double friction_angle) {
  char json[2048];
  snprintf(json, sizeof json,
           "{\"domain\": {\"min\": [0,0,0], \"max\": [0.8,0.5,0.8], \"dx\": 0.025},"
           " \"gravity\": [0,-9.81,0], \"time\": {\"end\": 1.2, \"fps\": 10},"
           " \"materials\": [{\"name\": \"sand\", \"model\": \"drucker_prager\", \"E\": 3.5e5,"
           "                  \"nu\": 0.3, \"density\": 1600, \"friction_angle\": %g}],"
           " \"bodies\": [{\"shape\": {\"type\": \"cylinder\", \"center\": [0.4,0.2,0.4],"
           "               \"radius\": 0.075, \"axis\": [0,1,0], \"half_height\": 0.125},"
           "               \"material\": \"sand\"}],"
           " \"colliders\": [{\"shape\": {\"type\": \"halfspace\", \"point\": [0,0.07,0],"
           "                  \"normal\": [0,1,0]}, \"rule\": \"sticky\"}]}",
           friction_angle);
  mpm_scene scene;
  mpm_error err;
  mpm_error_clear(&err);
  if (mpm_scene_parse(json, "sand.json", &scene, &err) != MPM_OK) fail_msg("%s", err.message);
  mpm_sim *sim = NULL;
  if (mpm_sim_create_from_scene(&scene, &sim, &err) != MPM_OK) fail_msg("%s", err.message);
  mpm_scene_free(&scene);
  while (mpm_sim_frame(sim) < mpm_sim_frame_count(sim))
    if (mpm_sim_advance_frame(sim) != MPM_OK) fail_msg("%s", mpm_sim_last_error(sim));
  const mpm_diagnostics d = mpm_sim_diagnostics(sim);
  if (d.kinetic > 1e-3 * d.mass) fail_msg("sand still moving: kinetic energy %.3g J", d.kinetic);
  const double slope = pile_slope(sim, 0.4, 0.4, 0.07);
  mpm_sim_destroy(sim);
  return slope;
}

static void test_slope_rises_with_friction_angle(void **state) {
  (void)state;
  const double angles[3] = {15, 30, 45};
  double slope[3];
  for (int k = 0; k < 3; ++k) {
    slope[k] = settle(angles[k]);
    print_message("friction angle %.0f deg: pile slope %.1f deg\n", angles[k], slope[k]);
  }
  assert_true(slope[0] > 0);
  assert_true(slope[1] > slope[0]);
  assert_true(slope[2] > slope[1]);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_slope_rises_with_friction_angle)};
  return cmocka_run_group_tests_name("sand_pile", tests, NULL, NULL);
}
