/* test_collider_revolve.c - the solid-of-revolution collider (src/collide/collider.c,
 * sdf_revolve) against independent truth:
 *   - a profile that traces a capped cylinder gives the cylinder's level set and normal
 *     (the cylinder shape is tested on its own in test_collider);
 *   - an hourglass profile: the sign of phi against the analytic radius r(h) of the profile,
 *     |phi| against the distance to a dense sampling of the profile, and the normal against
 *     central differences of phi, at random points in a tilted, shifted frame;
 *   - points on the surface give phi = 0 and the outward segment normal. */
#include "support.h"
#include "scene/scene.h"
#include "collide/collider.h"

#include <math.h>
#include <string.h>

static void check_phi(const mpm_collider_pose *pose, const double x[3], double *phi, double n[3]) {
  mpm_real xr[3], nr[3];
  for (int j = 0; j < 3; ++j) xr[j] = (mpm_real)x[j];
  *phi = mpm_collider_phi(pose, xr, nr);
  for (int j = 0; j < 3; ++j) n[j] = nr[j];
}

static mpm_collider_desc revolve_desc(const double (*profile)[2], int count, const double c[3],
                                      const double axis[3]) {
  mpm_collider_desc d = mpm_collider_desc_default();
  d.shape.kind = MPM_SHAPE_REVOLVE;
  memcpy(d.shape.center, c, sizeof d.shape.center);
  memcpy(d.shape.axis, axis, sizeof d.shape.axis);
  d.shape.profile_count = count;
  for (int k = 0; k < count; ++k) {
    d.shape.profile[k][0] = profile[k][0];
    d.shape.profile[k][1] = profile[k][1];
  }
  return d;
}

static void test_cylinder_profile(void **state) {
  (void)state;
  const double R = 0.4, H = 0.3, c[3] = {0.1, -0.2, 0.3};
  const double axis[3] = {0, 0.6, 0.8};
  const double prof[4][2] = {{0, -H}, {R, -H}, {R, H}, {0, H}};
  mpm_collider_desc dr = revolve_desc(prof, 4, c, axis);
  mpm_collider_desc dc = mpm_collider_desc_default();
  dc.shape.kind = MPM_SHAPE_CYLINDER;
  memcpy(dc.shape.center, c, sizeof c);
  memcpy(dc.shape.axis, axis, sizeof axis);
  dc.shape.radius = R;
  dc.shape.half_height = H;
  mpm_collider cr, cc;
  assert_int_equal(mpm_collider_init(&cr, &dr), MPM_OK);
  assert_int_equal(mpm_collider_init(&cc, &dc), MPM_OK);
  const mpm_collider_pose pr = mpm_collider_pose_at(&cr, 0), pc = mpm_collider_pose_at(&cc, 0);
  uint64_t rng = 3;
  const double tol = TOL(2e-6, 1e-12);
  int compared = 0;
  for (int t = 0; t < 20000; ++t) {
    double x[3], phr, phc, nr[3], nc[3];
    for (int j = 0; j < 3; ++j) x[j] = c[j] + test_rand(&rng, -0.8, 0.8);
    check_phi(&pr, x, &phr, nr);
    check_phi(&pc, x, &phc, nc);
    assert_close(phr, phc, tol);
    /* normals agree except on the inner medial surface, where side and cap are equally
       near and either is a valid one-sided gradient */
    double r[3], h = 0, rho2 = 0;
    for (int j = 0; j < 3; ++j) r[j] = x[j] - c[j];
    for (int j = 0; j < 3; ++j) h += r[j] * axis[j];
    for (int j = 0; j < 3; ++j) rho2 += (r[j] - h * axis[j]) * (r[j] - h * axis[j]);
    const double side = R - sqrt(rho2), cap = H - fabs(h);
    if (phr < 0 && fabs(side - cap) < 1e-3) continue;
    if (sqrt(rho2) < 1e-3) continue; /* on the axis the radial direction is a convention */
    /* float: the shapes' own rounding of a difference vector of length |phi| */
    const double tol_n = TOL(2e-7, 1e-14) / fmax(fabs(phr), 1e-3);
    for (int j = 0; j < 3; ++j) assert_close(nr[j], nc[j], tol_n);
    ++compared;
  }
  assert_true(compared > 15000);
  mpm_collider_free(&cr);
  mpm_collider_free(&cc);
}

/* The hourglass used by examples/sand_hourglass.json, in its own units. */
static const double HG[][2] = {{0, -0.3},   {0.2, -0.3}, {0.2, -0.12}, {0.02, 0.0},
                               {0.2, 0.12}, {0.2, 0.3},  {0, 0.3}};
enum { HG_N = sizeof HG / sizeof HG[0] };

/* Profile radius at height h (the profile is a graph r(h) between its end heights). */
static double hg_radius(double h) {
  for (int k = 1; k + 2 < HG_N; ++k) {
    const double h0 = HG[k][1], h1 = HG[k + 1][1];
    if (h >= h0 && h <= h1) return HG[k][0] + (h - h0) / (h1 - h0) * (HG[k + 1][0] - HG[k][0]);
  }
  return -1; /* outside the height range */
}

/* Distance in the half-plane from (rho, h) to the profile, by dense sampling. */
static double hg_distance(double rho, double h) {
  double best = INFINITY;
  for (int k = 0; k + 1 < HG_N; ++k)
    for (int i = 0; i <= 4000; ++i) {
      const double t = i / 4000.0;
      const double r = HG[k][0] + t * (HG[k + 1][0] - HG[k][0]);
      const double z = HG[k][1] + t * (HG[k + 1][1] - HG[k][1]);
      best = fmin(best, hypot(rho - r, h - z));
    }
  return best;
}

static void test_hourglass(void **state) {
  (void)state;
  const double c[3] = {0.3, 0.5, 0.3}, axis[3] = {0.28, 0.96, 0}; /* unit: 0.28^2 + 0.96^2 */
  mpm_collider_desc d = revolve_desc(HG, HG_N, c, axis);
  mpm_collider col;
  assert_int_equal(mpm_collider_init(&col, &d), MPM_OK);
  const mpm_collider_pose pose = mpm_collider_pose_at(&col, 0);
  uint64_t rng = 11;
  double worst_dist = 0, worst_grad = 0;
  int inside_count = 0;
  for (int t = 0; t < 3000; ++t) {
    double x[3], phi, n[3];
    for (int j = 0; j < 3; ++j) x[j] = c[j] + test_rand(&rng, -0.4, 0.4);
    check_phi(&pose, x, &phi, n);
    /* local coordinates: height along the axis, distance from it */
    double r[3], h = 0;
    for (int j = 0; j < 3; ++j) r[j] = x[j] - c[j];
    for (int j = 0; j < 3; ++j) h += r[j] * axis[j];
    double rho2 = 0;
    for (int j = 0; j < 3; ++j) rho2 += (r[j] - h * axis[j]) * (r[j] - h * axis[j]);
    const double rho = sqrt(rho2), rad = hg_radius(h);
    const int inside = rad > 0 && rho < rad;
    const double dist = hg_distance(rho, h);
    if (dist > 1e-3) { /* away from the surface the sign is unambiguous */
      if (inside != (phi < 0))
        fail_msg("point %d (rho %.4f, h %.4f): phi %.5f but inside = %d", t, rho, h, phi, inside);
    }
    inside_count += inside;
    worst_dist = fmax(worst_dist, fabs(fabs(phi) - dist));
    /* the normal is the gradient of phi where phi is smooth (not near the medial axis or the
       axis of revolution): compare with central differences */
    const double eps = 1e-4;
    double g[3], gn = 0;
    for (int j = 0; j < 3; ++j) {
      double xp[3], xm[3], pp, pm, dummy[3];
      memcpy(xp, x, sizeof xp);
      memcpy(xm, x, sizeof xm);
      xp[j] += eps;
      xm[j] -= eps;
      check_phi(&pose, xp, &pp, dummy);
      check_phi(&pose, xm, &pm, dummy);
      g[j] = (pp - pm) / (2 * eps);
      gn += g[j] * g[j];
    }
    if (fabs(sqrt(gn) - 1) < 1e-2 && rho > 0.01) { /* smooth here */
      double e = 0;
      for (int j = 0; j < 3; ++j) e = fmax(e, fabs(g[j] - n[j]));
      worst_grad = fmax(worst_grad, e);
      if (e > TOL(2e-2, 1e-3)) /* central differences near curved (vertex) regions */
        fail_msg("point %d: normal differs from grad phi by %.3g", t, e);
    }
  }
  print_message("revolve hourglass: %d of 3000 points inside; worst | |phi| - distance | %.3g "
                "(sampling spacing 1e-4), worst |n - grad phi| %.3g\n",
                inside_count, worst_dist, worst_grad);
  assert_true(inside_count > 300);
  assert_true(worst_dist < TOL(2e-4, 1e-4));
  /* on the surface: phi = 0, normal = outward segment normal (on the upper cone of the neck
     the glass widens upwards, so the outward normal points out and down) */
  double x[3], phi, n[3];
  const double hn = 0.06, rn = 0.02 + (0.2 - 0.02) * 0.5; /* midpoint of the upper cone */
  const double e_r[3] = {0, 0, 1};                        /* perpendicular to the axis */
  for (int j = 0; j < 3; ++j) x[j] = c[j] + hn * axis[j] + rn * e_r[j];
  check_phi(&pose, x, &phi, n);
  assert_close(phi, 0, TOL(2e-6, 1e-12));
  const double len = hypot(0.18, 0.12); /* the segment (0.02, 0) -> (0.2, 0.12) */
  const double nr = 0.12 / len, nh = -0.18 / len;
  for (int j = 0; j < 3; ++j) assert_close(n[j], nr * e_r[j] + nh * axis[j], TOL(1e-5, 1e-12));
  mpm_collider_free(&col);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_cylinder_profile),
                                     cmocka_unit_test(test_hourglass)};
  return cmocka_run_group_tests_name("collider revolve", tests, NULL, NULL);
}
