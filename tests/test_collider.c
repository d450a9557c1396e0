/* test_collider.c - the level sets of the colliders: phi and its normal for every shape,
 * still and inside out (src/collide; Gao et al. 2017 sec. 3.2 step 4).
 *
 * Truth is computed here, independently of the library and in double: distances at hand-picked
 * points (inside, outside, on the surface, beside box edges and corners and cylinder rims),
 * closest-point distances by clamping, and normals as central finite differences of phi.
 * Moving colliders and the boundary rule are tested in test_collider_motion.c. */
#include "support.h"
#include "collider_support.h"
#include "collide/collider.h"

#include <math.h>
#include <string.h>

/* ---- helpers ---------------------------------------------------------------------------- */

/* Two unit vectors completing the unit vector a to an orthonormal frame. */
static void frame(const double a[3], double e1[3], double e2[3]) {
  const double ref[3] = {fabs(a[0]) < 0.6 ? 1 : 0, fabs(a[0]) < 0.6 ? 0 : 1, 0};
  e1[0] = a[1] * ref[2] - a[2] * ref[1];
  e1[1] = a[2] * ref[0] - a[0] * ref[2];
  e1[2] = a[0] * ref[1] - a[1] * ref[0];
  unit3(e1);
  e2[0] = a[1] * e1[2] - a[2] * e1[1];
  e2[1] = a[2] * e1[0] - a[0] * e1[2];
  e2[2] = a[0] * e1[1] - a[1] * e1[0];
}

/* Is the local point f on the surface of the shape (within tol)? */
static int on_surface(const mpm_shape_desc *s, const double f[3], double tol) {
  switch (s->kind) {
  case MPM_SHAPE_BOX: {
    int face = 0;
    for (int d = 0; d < 3; ++d) {
      if (fabs(f[d]) > s->half_extent[d] + tol) return 0;
      if (fabs(fabs(f[d]) - s->half_extent[d]) <= tol) face = 1;
    }
    return face;
  }
  case MPM_SHAPE_SPHERE:
    return fabs(sqrt(dot3(f, f)) - s->radius) <= tol;
  case MPM_SHAPE_CYLINDER: {
    const double h = dot3(f, s->axis);
    double rv[3];
    for (int d = 0; d < 3; ++d) rv[d] = f[d] - h * s->axis[d];
    const double rho = sqrt(dot3(rv, rv));
    if (s->half_height <= 0) return fabs(rho - s->radius) <= tol;
    if (rho > s->radius + tol || fabs(h) > s->half_height + tol) return 0;
    return fabs(rho - s->radius) <= tol || fabs(fabs(h) - s->half_height) <= tol;
  }
  default:
    return fabs(dot3(f, s->axis)) <= tol;
  }
}

/* ---- level sets at known points ------------------------------------------------------------ */

typedef struct known {
  double x[3]; /* offset from the centre (local frame) */
  double phi;
} known;

static void check_known(const mpm_collider_desc *d, const known *k, int count) {
  mpm_collider c;
  assert_int_equal(mpm_collider_init(&c, d), MPM_OK);
  const mpm_collider_pose pose = mpm_collider_pose_at(&c, 0.0);
  const double tol = TOL(2e-6, 1e-13);
  for (int i = 0; i < count; ++i) {
    double x[3], n[3];
    for (int j = 0; j < 3; ++j) x[j] = d->shape.center[j] + k[i].x[j];
    const double phi = phi_at(&pose, x, n);
    assert_close(phi, k[i].phi, tol);
    assert_close(sqrt(dot3(n, n)), 1.0, tol);
  }
  mpm_collider_free(&c);
}

static void test_box_known(void **state) {
  (void)state;
  mpm_collider_desc d = make_desc(MPM_SHAPE_BOX);
  set3(d.shape.center, 0.3, -0.2, 0.5);
  set3(d.shape.half_extent, 1.0, 2.0, 3.0);
  const known k[] = {
      {{0, 0, 0}, -1.0},            /* centre: nearest faces are x = +-1 */
      {{0.5, 0, 0}, -0.5},          /* inside */
      {{0, -1.75, 0.1}, -0.25},     /* inside, near the -y face */
      {{0.2, 0.3, 2.9}, -0.1},      /* inside, near the +z face */
      {{0.95, 1.9, 2.9}, -0.05},    /* inside, by a corner */
      {{1.5, 0, 0}, 0.5},           /* outside a face */
      {{-0.3, -2.25, 1.0}, 0.25},   /* outside a face */
      {{1.0, 0.3, 0.2}, 0.0},       /* on a face */
      {{-1.0, 2.0, 3.0}, 0.0},      /* on a corner */
      {{2.0, 3.0, 0.0}, sqrt(2.0)}, /* beside an edge */
      {{-1.3, 0.5, -3.4}, 0.5},     /* beside an edge: sqrt(.09 + .16) */
      {{2.0, 3.0, 4.0}, sqrt(3.0)}, /* beyond a corner */
      {{-1.1, -2.2, 3.2}, sqrt(0.01 + 0.04 + 0.04)},
  };
  check_known(&d, k, (int)(sizeof k / sizeof k[0]));
}

static void test_sphere_known(void **state) {
  (void)state;
  mpm_collider_desc d = make_desc(MPM_SHAPE_SPHERE);
  set3(d.shape.center, -1.0, 2.0, 0.25);
  d.shape.radius = 0.75;
  const known k[] = {
      {{0, 0, 0}, -0.75},      {{0.25, 0, 0}, -0.5},     {{0, 0.75, 0}, 0.0},
      {{0.6, 0.0, 0.8}, 0.25}, {{-2.0, 2.0, 1.0}, 2.25}, {{0.3, -0.4, 0}, -0.25},
  };
  check_known(&d, k, (int)(sizeof k / sizeof k[0]));
}

/* Cylinder points are given in (radial e1, radial e2, axial a) coordinates and placed on a
 * tilted axis, so the same table checks the axis handling. */
static void check_cylinder(const double axis[3], double half_height, const known *k, int count) {
  mpm_collider_desc d = make_desc(MPM_SHAPE_CYLINDER);
  set3(d.shape.center, 0.4, 0.1, -0.7);
  memcpy(d.shape.axis, axis, sizeof d.shape.axis);
  unit3(d.shape.axis);
  d.shape.radius = 1.0;
  d.shape.half_height = half_height;
  double e1[3], e2[3];
  frame(d.shape.axis, e1, e2);
  known w[16];
  for (int i = 0; i < count; ++i) {
    for (int j = 0; j < 3; ++j)
      w[i].x[j] = k[i].x[0] * e1[j] + k[i].x[1] * e2[j] + k[i].x[2] * d.shape.axis[j];
    w[i].phi = k[i].phi;
  }
  check_known(&d, w, count);
}

static void test_cylinder_known(void **state) {
  (void)state;
  /* radius 1, half height 2 */
  const known capped[] = {
      {{0, 0, 0}, -1.0},          /* on the axis: the side is nearest */
      {{0.5, 0, 0}, -0.5},        /* inside, radial */
      {{0, 0.2, 1.8}, -0.2},      /* inside, near the top cap */
      {{0.3, 0, -1.9}, -0.1},     /* inside, near the bottom cap */
      {{0.9, 0, 1.95}, -0.05},    /* inside, by the rim */
      {{2.0, 0, 0}, 1.0},         /* outside the side */
      {{0, -1.0, 0.7}, 0.0},      /* on the side */
      {{0.5, 0, 2.0}, 0.0},       /* on the cap */
      {{0, 0, 3.0}, 1.0},         /* above the cap, on the axis */
      {{0.5, 0.2, -2.5}, 0.5},    /* below the cap */
      {{2.0, 0, 3.0}, sqrt(2.0)}, /* beyond the rim */
      {{0, -1.3, -2.4}, 0.5},     /* beyond the rim: sqrt(.09 + .16) */
      {{0.6, 0.8, 2.0}, 0.0},     /* on the rim */
  };
  const int nc = (int)(sizeof capped / sizeof capped[0]);
  const double z[3] = {0, 0, 1}, tilted[3] = {1.0, -2.0, 0.5}, x[3] = {1, 0, 0};
  check_cylinder(z, 2.0, capped, nc);
  check_cylinder(tilted, 2.0, capped, nc);
  check_cylinder(x, 2.0, capped, nc);
  /* infinite: half_height <= 0 */
  const known infinite[] = {
      {{0, 0, 0}, -1.0},    {{0, 0, 100.0}, -1.0},    {{0.6, 0.8, -50.0}, 0.0},
      {{3.0, 0, 7.0}, 2.0}, {{0, -0.25, 2.0}, -0.75},
  };
  const int ni = (int)(sizeof infinite / sizeof infinite[0]);
  check_cylinder(z, 0.0, infinite, ni);
  check_cylinder(tilted, -1.0, infinite, ni);
}

static void test_halfspace_known(void **state) {
  (void)state;
  mpm_collider_desc d = make_desc(MPM_SHAPE_HALFSPACE);
  set3(d.shape.center, 0, 0.25, 0); /* a point on the plane */
  set3(d.shape.axis, 0, 1, 0);      /* outward normal: the solid is y < 0.25 */
  mpm_collider c;
  assert_int_equal(mpm_collider_init(&c, &d), MPM_OK);
  mpm_collider_pose pose = mpm_collider_pose_at(&c, 0.0);
  const double tol = TOL(1e-6, 1e-14);
  const double x1[3] = {3, 1.25, -2}, x2[3] = {-7, -0.75, 4}, x3[3] = {1, 0.25, 1};
  double n[3];
  assert_close(phi_at(&pose, x1, n), 1.0, tol);
  assert_close(n[1], 1.0, tol);
  assert_close(phi_at(&pose, x2, n), -1.0, tol);
  assert_close(phi_at(&pose, x3, n), 0.0, tol);
  mpm_collider_free(&c);
  /* a tilted plane through the origin: phi = x.n with n = (1, 1, 1)/sqrt 3 */
  set3(d.shape.center, 0, 0, 0);
  set3(d.shape.axis, 1, 1, 1); /* not unit: init normalises */
  assert_int_equal(mpm_collider_init(&c, &d), MPM_OK);
  pose = mpm_collider_pose_at(&c, 0.0);
  const double x4[3] = {1, 2, -0.5};
  assert_close(phi_at(&pose, x4, n), 2.5 / sqrt(3.0), tol);
  for (int j = 0; j < 3; ++j) assert_close(n[j], 1 / sqrt(3.0), tol);
  mpm_collider_free(&c);
}

/* ---- random points: distance, closest point and normal ------------------------------------ */

/* A static collider of each shape at random points: phi equals the reference distance, the
 * normal has unit length, x - phi n lies on the surface, and inside_out negates both. */
static void test_random_points_distance(void **state) {
  (void)state;
  uint64_t rng = 77;
  const double tol = TOL(4e-6, 1e-12);
  for (int s = 0; s < SHAPES; ++s) {
    mpm_collider_desc d = shape_desc(s), dio = d;
    dio.inside_out = 1;
    mpm_collider c, cio;
    assert_int_equal(mpm_collider_init(&c, &d), MPM_OK);
    assert_int_equal(mpm_collider_init(&cio, &dio), MPM_OK);
    const mpm_collider_pose pose = mpm_collider_pose_at(&c, 0.0);
    const mpm_collider_pose pio = mpm_collider_pose_at(&cio, 0.0);
    for (int trial = 0; trial < 3000; ++trial) {
      double x[3], p[3], n[3], nio[3], f[3];
      for (int j = 0; j < 3; ++j) {
        /* points spread from deep inside to well outside, some on the symmetry planes */
        p[j] = test_rand(&rng, -2.5, 2.5);
        if (trial % 17 == 0) p[j] = 0;
        x[j] = d.shape.center[j] + p[j];
      }
      for (int j = 0; j < 3; ++j) p[j] = (double)(mpm_real)x[j] - d.shape.center[j];
      const double phi = phi_at(&pose, x, n);
      assert_close(phi, ref_phi(&d.shape, p, NULL), tol);
      assert_close(sqrt(dot3(n, n)), 1.0, tol);
      for (int j = 0; j < 3; ++j) f[j] = p[j] - phi * n[j];
      if (!on_surface(&d.shape, f, 10 * tol)) fail_msg("shape %d: x - phi n is off the surface", s);
      const double phio = phi_at(&pio, x, nio);
      assert_close(phio, -phi, tol);
      for (int j = 0; j < 3; ++j) assert_close(nio[j], -n[j], tol);
    }
    mpm_collider_free(&c);
    mpm_collider_free(&cio);
  }
}

/* Where the gradient is undefined a unit vector still comes back. */
static void test_degenerate_normals(void **state) {
  (void)state;
  for (int s = 0; s < SHAPES; ++s) {
    mpm_collider_desc d = shape_desc(s);
    mpm_collider c;
    assert_int_equal(mpm_collider_init(&c, &d), MPM_OK);
    const mpm_collider_pose pose = mpm_collider_pose_at(&c, 0.0);
    double n[3];
    phi_at(&pose, d.shape.center, n); /* the centre: box, sphere and cylinder medial axis */
    assert_close(sqrt(dot3(n, n)), 1.0, TOL(1e-6, 1e-14));
    double x[3];
    for (int j = 0; j < 3; ++j) x[j] = d.shape.center[j] + 0.5 * d.shape.axis[j];
    phi_at(&pose, x, n); /* on a cylinder's axis */
    assert_close(sqrt(dot3(n, n)), 1.0, TOL(1e-6, 1e-14));
    mpm_collider_free(&c);
  }
}

/* The normal is the gradient of phi: central differences at random points away from the
 * medial axis, for every shape on a moving, rotated pose. */
static void test_normal_is_gradient(void **state) {
  (void)state;
  uint64_t rng = 4242;
  const double h = TOL(1e-2, 1e-5), tol = TOL(2e-3, 1e-7), t = 0.7;
  for (int s = 0; s < SHAPES; ++s) {
    const mpm_collider_desc d = moving(shape_desc(s));
    mpm_collider c;
    assert_int_equal(mpm_collider_init(&c, &d), MPM_OK);
    const mpm_collider_pose pose = mpm_collider_pose_at(&c, t);
    double R[9], ctr[3];
    rot(d.motion.axis, d.motion.angular_speed * t, R);
    for (int j = 0; j < 3; ++j) ctr[j] = d.shape.center[j] + d.motion.velocity[j] * t;
    int tested = 0;
    for (int trial = 0; trial < 4000; ++trial) {
      double x[3], r[3], p[3], n[3], margin;
      for (int j = 0; j < 3; ++j) x[j] = ctr[j] + test_rand(&rng, -2.5, 2.5);
      for (int j = 0; j < 3; ++j) r[j] = x[j] - ctr[j];
      for (int j = 0; j < 3; ++j) p[j] = R[j] * r[0] + R[3 + j] * r[1] + R[6 + j] * r[2];
      ref_phi(&d.shape, p, &margin);
      if (margin < TOL(0.2, 0.05)) continue; /* FD error ~ h^2 / margin^2 on curved parts */
      ++tested;
      phi_at(&pose, x, n);
      assert_close(sqrt(dot3(n, n)), 1.0, TOL(1e-6, 1e-14));
      for (int j = 0; j < 3; ++j) {
        double xp[3] = {x[0], x[1], x[2]}, xm[3] = {x[0], x[1], x[2]};
        xp[j] += h;
        xm[j] -= h;
        const double g = (phi_at(&pose, xp, NULL) - phi_at(&pose, xm, NULL)) / (2 * h);
        if (fabs(n[j] - g) > tol)
          fail_msg("shape %d, p = (%g %g %g), margin %g: n[%d] = %g, FD %g", s, p[0], p[1], p[2],
                   margin, j, n[j], g);
      }
    }
    assert_true(tested > 1000);
    mpm_collider_free(&c);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_box_known),
      cmocka_unit_test(test_sphere_known),
      cmocka_unit_test(test_cylinder_known),
      cmocka_unit_test(test_halfspace_known),
      cmocka_unit_test(test_random_points_distance),
      cmocka_unit_test(test_degenerate_normals),
      cmocka_unit_test(test_normal_is_gradient),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
