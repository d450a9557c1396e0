/* test_collider.c - level-set colliders, their motion and the boundary rule
 * (src/collide; Gao et al. 2017 sec. 3.2 step 4).
 *
 * Truth is computed here, independently of the library and in double: distances at hand-picked
 * points (inside, outside, on the surface, beside box edges and corners and cylinder rims),
 * closest-point distances by clamping, normals as central finite differences of phi, moving
 * poses from a Rodrigues rotation written here, collider velocities as finite differences of a
 * material point's trajectory, and the boundary rule from its definition. */
#include "support.h"
#include "collide/collider.h"

#include <math.h>
#include <string.h>

/* ---- helpers ---------------------------------------------------------------------------- */

static mpm_collider_desc make_desc(mpm_shape_kind kind) {
  mpm_collider_desc d;
  memset(&d, 0, sizeof d);
  d.shape.kind = kind;
  d.rule = MPM_BOUNDARY_SLIP;
  return d;
}

static void set3(double a[3], double x, double y, double z) {
  a[0] = x, a[1] = y, a[2] = z;
}

static void unit3(double a[3]) {
  const double l = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
  for (int d = 0; d < 3; ++d) a[d] /= l;
}

/* phi and normal at a double point, through the library */
static double phi_at(const mpm_collider_pose *pose, const double x[3], double n[3]) {
  const mpm_real xr[3] = {(mpm_real)x[0], (mpm_real)x[1], (mpm_real)x[2]};
  mpm_real nr[3];
  const double phi = (double)mpm_collider_phi(pose, xr, nr);
  if (n)
    for (int d = 0; d < 3; ++d) n[d] = (double)nr[d];
  return phi;
}

/* Rotation by theta about the unit axis a, in double (Rodrigues: R = I + s K + (1-c) K^2). */
static void rot(const double a[3], double theta, double R[9]) {
  const double K[9] = {0, -a[2], a[1], a[2], 0, -a[0], -a[1], a[0], 0};
  const double s = sin(theta), c = cos(theta);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      double k2 = 0;
      for (int m = 0; m < 3; ++m) k2 += K[3 * i + m] * K[3 * m + j];
      R[3 * i + j] = (i == j) + s * K[3 * i + j] + (1 - c) * k2;
    }
}

static double dot3(const double a[3], const double b[3]) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

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

/* The shapes every test runs over: a box, a sphere, a capped cylinder on a tilted axis, an
 * infinite cylinder and a tilted half-space, all away from the origin. */
enum { SHAPES = 5 };
static mpm_collider_desc shape_desc(int which) {
  mpm_collider_desc d;
  switch (which) {
  case 0:
    d = make_desc(MPM_SHAPE_BOX);
    set3(d.shape.half_extent, 1.0, 0.6, 1.4);
    break;
  case 1:
    d = make_desc(MPM_SHAPE_SPHERE);
    d.shape.radius = 1.3;
    break;
  case 2:
    d = make_desc(MPM_SHAPE_CYLINDER);
    set3(d.shape.axis, 0.3, 1.0, -0.4);
    unit3(d.shape.axis);
    d.shape.radius = 0.8;
    d.shape.half_height = 1.1;
    break;
  case 3:
    d = make_desc(MPM_SHAPE_CYLINDER);
    set3(d.shape.axis, -0.2, 0.1, 1.0);
    unit3(d.shape.axis);
    d.shape.radius = 0.9;
    d.shape.half_height = 0;
    break;
  default:
    d = make_desc(MPM_SHAPE_HALFSPACE);
    set3(d.shape.axis, 0.2, 1.0, 0.3);
    unit3(d.shape.axis);
    break;
  }
  set3(d.shape.center, 0.7, -0.4, 1.1);
  return d;
}

/* Reference signed distance of a shape at the local point p (centre at the origin), from the
 * closest point of the solid (outside) or the nearest face (inside). *margin is the distance
 * from p to the nearest place where phi is not smooth (medial axis, the planes where the
 * nearest feature of a box or cylinder changes), so finite differences are valid within it. */
static double ref_phi(const mpm_shape_desc *s, const double p[3], double *margin) {
  switch (s->kind) {
  case MPM_SHAPE_BOX: {
    double out2 = 0, inside = INFINITY, m = INFINITY, q[3];
    int in = 1;
    for (int d = 0; d < 3; ++d) {
      const double h = s->half_extent[d];
      const double c = fmin(fmax(p[d], -h), h); /* closest point of the box */
      out2 += (p[d] - c) * (p[d] - c);
      if (fabs(p[d]) > h) in = 0;
      q[d] = h - fabs(p[d]);
      inside = fmin(inside, q[d]);
      m = fmin(m, fabs(q[d]));
    }
    if (in) /* inside: ties between the nearest faces, and the midplane between a pair */
      for (int d = 0; d < 3; ++d) m = fmin(m, q[d] > inside ? q[d] - inside : fabs(p[d]));
    if (margin) *margin = m;
    return in ? -inside : sqrt(out2);
  }
  case MPM_SHAPE_SPHERE: {
    const double l = sqrt(dot3(p, p));
    if (margin) *margin = l;
    return l - s->radius;
  }
  case MPM_SHAPE_CYLINDER: {
    const double h = dot3(p, s->axis);
    double rv[3];
    for (int d = 0; d < 3; ++d) rv[d] = p[d] - h * s->axis[d];
    const double rho = sqrt(dot3(rv, rv)), R = s->radius;
    if (s->half_height <= 0) {
      if (margin) *margin = rho;
      return rho - R;
    }
    const double H = s->half_height;
    const double rc = fmin(rho, R), hc = fmin(fmax(h, -H), H);
    const int in = rho <= R && fabs(h) <= H;
    const double dr = R - rho, dh = H - fabs(h);
    if (margin) {
      double m = fmin(fmin(fabs(dr), fabs(dh)), rho);
      if (in) m = fmin(m, dh < dr ? fmin(dr - dh, fabs(h)) : dh - dr); /* the caps' midplane */
      *margin = m;
    }
    return in ? -fmin(dr, dh) : sqrt((rho - rc) * (rho - rc) + (h - hc) * (h - hc));
  }
  default:
    if (margin) *margin = INFINITY;
    return dot3(p, s->axis);
  }
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
  assert_int_equal(mpm_collider_init(&c, d), 0);
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
  assert_int_equal(mpm_collider_init(&c, &d), 0);
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
  assert_int_equal(mpm_collider_init(&c, &d), 0);
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
    assert_int_equal(mpm_collider_init(&c, &d), 0);
    assert_int_equal(mpm_collider_init(&cio, &dio), 0);
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
    assert_int_equal(mpm_collider_init(&c, &d), 0);
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

static mpm_collider_desc moving(mpm_collider_desc d) {
  set3(d.motion.velocity, 0.4, -0.3, 0.2);
  set3(d.motion.axis, 1.0, 2.0, -0.5);
  unit3(d.motion.axis);
  d.motion.angular_speed = 0.9;
  return d;
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
    assert_int_equal(mpm_collider_init(&c, &d), 0);
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

/* ---- motion -----------------------------------------------------------------------------------
 */

/* A translated and rotated collider at time t has the static shape's phi at the inversely
 * transformed point, and its normal is the static normal rotated. */
static void test_moving_phi(void **state) {
  (void)state;
  uint64_t rng = 99;
  const double tol = TOL(2e-5, 1e-12);
  const double times[3] = {0.0, 1.7, -2.3};
  for (int s = 0; s < SHAPES; ++s) {
    const mpm_collider_desc d0 = shape_desc(s), d = moving(d0);
    mpm_collider c0, c;
    assert_int_equal(mpm_collider_init(&c0, &d0), 0);
    assert_int_equal(mpm_collider_init(&c, &d), 0);
    const mpm_collider_pose still = mpm_collider_pose_at(&c0, 5.0); /* no motion: any time */
    for (int ti = 0; ti < 3; ++ti) {
      const double t = times[ti];
      const mpm_collider_pose pose = mpm_collider_pose_at(&c, t);
      double R[9], ctr[3];
      rot(d.motion.axis, d.motion.angular_speed * t, R);
      for (int j = 0; j < 3; ++j) ctr[j] = d.shape.center[j] + d.motion.velocity[j] * t;
      for (int trial = 0; trial < 500; ++trial) {
        double x[3], r[3], xs[3], p[3], n[3], ns[3], margin;
        for (int j = 0; j < 3; ++j) x[j] = ctr[j] + test_rand(&rng, -2.5, 2.5);
        for (int j = 0; j < 3; ++j) r[j] = x[j] - ctr[j];
        for (int j = 0; j < 3; ++j) {
          p[j] = R[j] * r[0] + R[3 + j] * r[1] + R[6 + j] * r[2]; /* R^T r */
          xs[j] = d.shape.center[j] + p[j];
        }
        const double phi = phi_at(&pose, x, n), phis = phi_at(&still, xs, ns);
        assert_close(phi, phis, tol);
        ref_phi(&d.shape, p, &margin);
        if (margin < 1e-3) continue; /* the normal may pick another tied face */
        for (int j = 0; j < 3; ++j)
          assert_close(n[j], R[3 * j] * ns[0] + R[3 * j + 1] * ns[1] + R[3 * j + 2] * ns[2], tol);
      }
    }
    mpm_collider_free(&c0);
    mpm_collider_free(&c);
  }
}

/* Pose at t against the definition: centre + v t and the Rodrigues rotation. */
static void check_pose(const mpm_collider_pose *pose, const double ctr[3], const double R[9],
                       const double v[3], const double w[3]) {
  const double tol = TOL(2e-6, 1e-13);
  for (int j = 0; j < 3; ++j) {
    assert_close(pose->center[j], ctr[j], tol * 4);
    assert_close(pose->velocity[j], v[j], tol);
    assert_close(pose->omega[j], w[j], tol);
  }
  for (int j = 0; j < 9; ++j) assert_close(pose->R[j], R[j], tol);
}

/* x(t) of the material point with local coordinates q: centre(t) + R(t) q, from the poses. */
static void trajectory(const mpm_collider *c, double t, const double q[3], double x[3]) {
  const mpm_collider_pose p = mpm_collider_pose_at(c, t);
  for (int i = 0; i < 3; ++i)
    x[i] = p.center[i] + p.R[3 * i] * q[0] + p.R[3 * i + 1] * q[1] + p.R[3 * i + 2] * q[2];
}

/* The collider velocity at a material point equals (x(t+h) - x(t-h)) / 2h. */
static void check_velocity_fd(const mpm_collider *c, double t, uint64_t *rng) {
  const double h = TOL(1e-2, 1e-5), tol = TOL(2e-3, 1e-7);
  const mpm_collider_pose pose = mpm_collider_pose_at(c, t);
  for (int trial = 0; trial < 50; ++trial) {
    double q[3], x[3], xp[3], xm[3];
    for (int j = 0; j < 3; ++j) q[j] = test_rand(rng, -1.5, 1.5);
    trajectory(c, t, q, x);
    trajectory(c, t + h, q, xp);
    trajectory(c, t - h, q, xm);
    const mpm_real xr[3] = {(mpm_real)x[0], (mpm_real)x[1], (mpm_real)x[2]};
    mpm_real v[3];
    mpm_collider_velocity(&pose, xr, v);
    for (int j = 0; j < 3; ++j) assert_close(v[j], (xp[j] - xm[j]) / (2 * h), tol);
  }
}

static void test_constant_motion(void **state) {
  (void)state;
  uint64_t rng = 5;
  const mpm_collider_desc d = moving(shape_desc(0));
  mpm_collider c;
  assert_int_equal(mpm_collider_init(&c, &d), 0);
  const double times[5] = {0.0, 0.35, 1.9, 4.0, 40.0}; /* 36 rad: several turns */
  for (int ti = 0; ti < 5; ++ti) {
    const double t = times[ti];
    double R[9], ctr[3], w[3];
    rot(d.motion.axis, d.motion.angular_speed * t, R);
    for (int j = 0; j < 3; ++j) {
      ctr[j] = d.shape.center[j] + d.motion.velocity[j] * t;
      w[j] = d.motion.axis[j] * d.motion.angular_speed;
    }
    const mpm_collider_pose pose = mpm_collider_pose_at(&c, t);
    check_pose(&pose, ctr, R, d.motion.velocity, w);
    check_velocity_fd(&c, t, &rng);
  }
  mpm_collider_free(&c);

  /* pure translation with no rotation axis at all */
  mpm_collider_desc dt = shape_desc(1);
  set3(dt.motion.velocity, -1.0, 0.5, 2.0);
  assert_int_equal(mpm_collider_init(&c, &dt), 0);
  const double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, zero[3] = {0, 0, 0};
  double ctr[3];
  for (int j = 0; j < 3; ++j) ctr[j] = dt.shape.center[j] + dt.motion.velocity[j] * 1.5;
  const mpm_collider_pose pose = mpm_collider_pose_at(&c, 1.5);
  check_pose(&pose, ctr, I, dt.motion.velocity, zero);
  check_velocity_fd(&c, 1.5, &rng);
  mpm_collider_free(&c);
}

static void test_keyframes(void **state) {
  (void)state;
  uint64_t rng = 6;
  mpm_keyframe k[3];
  memset(k, 0, sizeof k);
  k[0].time = 0.5;
  set3(k[0].translation, 0.2, 0.0, -0.1);
  k[0].angle = 0.1;
  k[1].time = 1.5;
  set3(k[1].translation, 1.2, -2.0, 0.4);
  k[1].angle = 1.3;
  k[2].time = 2.0;
  set3(k[2].translation, 1.0, 0.0, 0.0);
  k[2].angle = -0.3;
  mpm_collider_desc d = shape_desc(2);
  set3(d.motion.axis, 0.0, 0.6, 0.8);
  set3(d.motion.velocity, 9, 9, 9); /* ignored when there are keyframes */
  d.motion.angular_speed = 9;
  d.motion.keyframe_count = 3;
  d.motion.keyframes = k;
  mpm_collider c;
  assert_int_equal(mpm_collider_init(&c, &d), 0);
  /* the collider owns a copy: changing the scene's array afterwards changes nothing */
  mpm_keyframe saved[3];
  memcpy(saved, k, sizeof k);
  memset(k, 0, sizeof k);
  assert_ptr_not_equal(c.desc.motion.keyframes, k);

  /* mid-segment: piecewise linear pose, slopes as velocities */
  const double mids[2] = {0.9, 1.8};
  for (int m = 0; m < 2; ++m) {
    const int i = m;
    const double t = mids[m], span = saved[i + 1].time - saved[i].time;
    const double u = (t - saved[i].time) / span;
    double R[9], ctr[3], v[3], w[3];
    const double angle = saved[i].angle + u * (saved[i + 1].angle - saved[i].angle);
    rot(d.motion.axis, angle, R);
    for (int j = 0; j < 3; ++j) {
      const double dtr = saved[i + 1].translation[j] - saved[i].translation[j];
      ctr[j] = d.shape.center[j] + saved[i].translation[j] + u * dtr;
      v[j] = dtr / span;
      w[j] = d.motion.axis[j] * (saved[i + 1].angle - saved[i].angle) / span;
    }
    const mpm_collider_pose pose = mpm_collider_pose_at(&c, t);
    check_pose(&pose, ctr, R, v, w);
    check_velocity_fd(&c, t, &rng);
  }

  /* held outside the span, at rest */
  const double zero[3] = {0, 0, 0};
  const double outside[4] = {-3.0, 0.2, 2.0, 7.5};
  for (int m = 0; m < 4; ++m) {
    const mpm_keyframe *e = outside[m] < saved[0].time ? &saved[0] : &saved[2];
    double R[9], ctr[3];
    rot(d.motion.axis, e->angle, R);
    for (int j = 0; j < 3; ++j) ctr[j] = d.shape.center[j] + e->translation[j];
    const mpm_collider_pose pose = mpm_collider_pose_at(&c, outside[m]);
    check_pose(&pose, ctr, R, zero, zero);
  }
  /* at the first keyframe the pose is the keyframe's */
  {
    double R[9], ctr[3];
    rot(d.motion.axis, saved[0].angle, R);
    for (int j = 0; j < 3; ++j) ctr[j] = d.shape.center[j] + saved[0].translation[j];
    const mpm_collider_pose pose = mpm_collider_pose_at(&c, saved[0].time);
    const double tol = TOL(2e-6, 1e-13);
    for (int j = 0; j < 3; ++j) assert_close(pose.center[j], ctr[j], tol);
    for (int j = 0; j < 9; ++j) assert_close(pose.R[j], R[j], tol);
  }
  mpm_collider_free(&c);
  assert_null(c.desc.motion.keyframes);

  /* a single keyframe: a fixed offset at every time */
  d.motion.keyframes = saved + 1;
  d.motion.keyframe_count = 1;
  assert_int_equal(mpm_collider_init(&c, &d), 0);
  for (int m = 0; m < 3; ++m) {
    const mpm_collider_pose pose = mpm_collider_pose_at(&c, -1.0 + 2.0 * m);
    double R[9], ctr[3];
    rot(d.motion.axis, saved[1].angle, R);
    for (int j = 0; j < 3; ++j) ctr[j] = d.shape.center[j] + saved[1].translation[j];
    check_pose(&pose, ctr, R, zero, zero);
  }
  mpm_collider_free(&c);
}

/* A rotating collider moves the material with it: a node at the surface of a spinning sphere
 * gets omega x r from a sticky rule. */
static void test_collider_velocity_rotation(void **state) {
  (void)state;
  mpm_collider_desc d = make_desc(MPM_SHAPE_SPHERE);
  d.shape.radius = 1.0;
  set3(d.motion.axis, 0, 0, 1);
  d.motion.angular_speed = 2.0;
  set3(d.motion.velocity, 0.5, 0, 0);
  d.rule = MPM_BOUNDARY_STICKY;
  mpm_collider c;
  assert_int_equal(mpm_collider_init(&c, &d), 0);
  const mpm_collider_pose pose = mpm_collider_pose_at(&c, 2.0); /* centre (1, 0, 0) */
  const mpm_real x[3] = {1, R_(0.9), 0};
  mpm_real v[3] = {3, 4, 5};
  assert_int_equal(mpm_collider_apply(&pose, x, v), 1);
  /* 0.5 x^ + 2 z^ x 0.9 y^ = (0.5 - 1.8, 0, 0) */
  assert_close(v[0], -1.3, TOL(1e-6, 1e-14));
  assert_close(v[1], 0.0, TOL(1e-6, 1e-14));
  assert_close(v[2], 0.0, TOL(1e-6, 1e-14));
  mpm_collider_free(&c);
}

/* ---- boundary rule
 * ------------------------------------------------------------------------------- */

static void project(mpm_boundary_rule rule, double mu, const double n[3], const double vo[3],
                    const double v[3], double out[3]) {
  const mpm_real nr[3] = {(mpm_real)n[0], (mpm_real)n[1], (mpm_real)n[2]};
  const mpm_real vor[3] = {(mpm_real)vo[0], (mpm_real)vo[1], (mpm_real)vo[2]};
  mpm_real vr[3] = {(mpm_real)v[0], (mpm_real)v[1], (mpm_real)v[2]};
  mpm_boundary_project(rule, (mpm_real)mu, nr, vor, vr);
  for (int d = 0; d < 3; ++d) out[d] = (double)vr[d];
}

/* Split v - vo into normal and tangential parts along n. */
static void split(const double n[3], const double vo[3], const double v[3], double *vn,
                  double vt[3]) {
  double r[3];
  for (int d = 0; d < 3; ++d) r[d] = v[d] - vo[d];
  *vn = dot3(r, n);
  for (int d = 0; d < 3; ++d) vt[d] = r[d] - *vn * n[d];
}

static void test_boundary_rules(void **state) {
  (void)state;
  uint64_t rng = 31;
  const double tol = TOL(2e-5, 1e-12);
  for (int trial = 0; trial < 500; ++trial) {
    double n[3], vo[3], v[3], out[3];
    for (int d = 0; d < 3; ++d) {
      n[d] = test_rand(&rng, -1, 1);
      vo[d] = test_rand(&rng, -2, 2);
      v[d] = test_rand(&rng, -3, 3);
    }
    unit3(n);
    double vn, vt[3];
    split(n, vo, v, &vn, vt);
    const double speed = sqrt(dot3(vt, vt));

    /* sticky: the obstacle's velocity, whatever the friction */
    project(MPM_BOUNDARY_STICKY, 0.7, n, vo, v, out);
    for (int d = 0; d < 3; ++d) assert_close(out[d], vo[d], tol);

    /* slip without friction: normal part removed, tangential kept */
    project(MPM_BOUNDARY_SLIP, 0.0, n, vo, v, out);
    double on, ot[3];
    split(n, vo, out, &on, ot);
    assert_close(on, 0.0, tol);
    for (int d = 0; d < 3; ++d) assert_close(ot[d], vt[d], tol);

    /* separate: a separating velocity is left exactly alone, an approaching one slips */
    project(MPM_BOUNDARY_SEPARATE, 0.5, n, vo, v, out);
    if (vn > 0) {
      for (int d = 0; d < 3; ++d) assert_close(out[d], v[d], TOL(1e-6, 1e-15) * 4);
    } else {
      split(n, vo, out, &on, ot);
      assert_close(on, 0.0, tol);
    }

    /* friction: tangential speed reduced by mu |vn| along the same direction, or stopped */
    const double mu = test_rand(&rng, 0.0, 1.5);
    const mpm_boundary_rule rules[2] = {MPM_BOUNDARY_SLIP, MPM_BOUNDARY_SEPARATE};
    for (int ri = 0; ri < 2; ++ri) {
      if (rules[ri] == MPM_BOUNDARY_SEPARATE && vn >= 0) continue;
      project(rules[ri], mu, n, vo, v, out);
      split(n, vo, out, &on, ot);
      assert_close(on, 0.0, tol);
      const double expect = fmax(0.0, speed - mu * fabs(vn));
      assert_close(sqrt(dot3(ot, ot)), expect, tol);
      if (expect > 0)
        for (int d = 0; d < 3; ++d) assert_close(ot[d] * speed, vt[d] * expect, tol * 4);
    }
  }
  /* by hand: floor normal +y, still obstacle, v = (3, -1, 0), mu = 0.5 -> (2.5, 0, 0) */
  const double n[3] = {0, 1, 0}, vo[3] = {0, 0, 0}, v[3] = {3, -1, 0};
  double out[3];
  project(MPM_BOUNDARY_SLIP, 0.5, n, vo, v, out);
  assert_close(out[0], 2.5, tol);
  assert_close(out[1], 0.0, tol);
  /* mu = 4: |vt| = 3 <= 4 -> stopped */
  project(MPM_BOUNDARY_SEPARATE, 4.0, n, vo, v, out);
  for (int d = 0; d < 3; ++d) assert_close(out[d], 0.0, tol);
  /* separating: no friction */
  const double up[3] = {3, 1, 0};
  project(MPM_BOUNDARY_SEPARATE, 4.0, n, vo, up, out);
  for (int d = 0; d < 3; ++d) assert_close(out[d], up[d], tol);
  /* moving obstacle: only the relative velocity is projected */
  const double belt[3] = {1, 0, 0}, w[3] = {1, -2, 0.5};
  project(MPM_BOUNDARY_SLIP, 0.0, n, belt, w, out);
  assert_close(out[0], 1.0, tol);
  assert_close(out[1], 0.0, tol);
  assert_close(out[2], 0.5, tol);
}

/* apply(): nodes outside are untouched; nodes inside get the rule with the collider's normal
 * and velocity at that node. */
static void test_apply(void **state) {
  (void)state;
  uint64_t rng = 8;
  for (int s = 0; s < SHAPES; ++s) {
    for (int io = 0; io < 2; ++io) {
      mpm_collider_desc d = moving(shape_desc(s));
      d.inside_out = io;
      d.rule = (mpm_boundary_rule)(s % 3);
      d.friction = 0.3;
      mpm_collider c;
      assert_int_equal(mpm_collider_init(&c, &d), 0);
      const mpm_collider_pose pose = mpm_collider_pose_at(&c, 0.6);
      int inside = 0, outside = 0;
      for (int trial = 0; trial < 600; ++trial) {
        mpm_real x[3], v[3], v0[3], n[3], vo[3];
        for (int j = 0; j < 3; ++j) {
          x[j] = pose.center[j] + (mpm_real)test_rand(&rng, -1.6, 1.6);
          v[j] = v0[j] = (mpm_real)test_rand(&rng, -3, 3);
        }
        const mpm_real phi = mpm_collider_phi(&pose, x, n);
        const int changed = mpm_collider_apply(&pose, x, v);
        if (phi > 0) {
          ++outside;
          assert_int_equal(changed, 0);
          assert_memory_equal(v, v0, sizeof v);
        } else {
          ++inside;
          assert_int_equal(changed, 1);
          mpm_collider_velocity(&pose, x, vo);
          mpm_boundary_project(d.rule, (mpm_real)d.friction, n, vo, v0);
          for (int j = 0; j < 3; ++j) assert_close(v[j], v0[j], TOL(1e-6, 1e-14));
        }
      }
      assert_true(inside > 20 && outside > 20);
      mpm_collider_free(&c);
    }
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
      cmocka_unit_test(test_moving_phi),
      cmocka_unit_test(test_constant_motion),
      cmocka_unit_test(test_keyframes),
      cmocka_unit_test(test_collider_velocity_rotation),
      cmocka_unit_test(test_boundary_rules),
      cmocka_unit_test(test_apply),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
