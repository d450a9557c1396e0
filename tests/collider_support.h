/* collider_support.h - shared helpers of the collider tests (test_collider,
 * test_collider_motion): small vector helpers in double, phi through the library, a Rodrigues
 * rotation, the five shapes every test runs over, their moving variant, and the reference
 * signed distance. Header only: each test program links support.c alone. */
#ifndef MPM_TEST_COLLIDER_SUPPORT_H
#define MPM_TEST_COLLIDER_SUPPORT_H

#include "support.h"
#include "collide/collider.h"

#include <math.h>
#include <string.h>

static inline mpm_collider_desc make_desc(mpm_shape_kind kind) {
  mpm_collider_desc d;
  memset(&d, 0, sizeof d);
  d.shape.kind = kind;
  d.rule = MPM_BOUNDARY_SLIP;
  return d;
}

static inline void set3(double a[3], double x, double y, double z) {
  a[0] = x, a[1] = y, a[2] = z;
}

static inline void unit3(double a[3]) {
  const double l = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
  for (int d = 0; d < 3; ++d) a[d] /= l;
}

/* phi and normal at a double point, through the library */
static inline double phi_at(const mpm_collider_pose *pose, const double x[3], double n[3]) {
  const mpm_real xr[3] = {(mpm_real)x[0], (mpm_real)x[1], (mpm_real)x[2]};
  mpm_real nr[3];
  const double phi = (double)mpm_collider_phi(pose, xr, nr);
  if (n)
    for (int d = 0; d < 3; ++d) n[d] = (double)nr[d];
  return phi;
}

/* Rotation by theta about the unit axis a, in double (Rodrigues: R = I + s K + (1-c) K^2). */
static inline void rot(const double a[3], double theta, double R[9]) {
  const double K[9] = {0, -a[2], a[1], a[2], 0, -a[0], -a[1], a[0], 0};
  const double s = sin(theta), c = cos(theta);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      double k2 = 0;
      for (int m = 0; m < 3; ++m) k2 += K[3 * i + m] * K[3 * m + j];
      R[3 * i + j] = (i == j) + s * K[3 * i + j] + (1 - c) * k2;
    }
}

static inline double dot3(const double a[3], const double b[3]) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* The shapes every test runs over: a box, a sphere, a capped cylinder on a tilted axis, an
 * infinite cylinder and a tilted half-space, all away from the origin. */
enum { SHAPES = 5 };
static inline mpm_collider_desc shape_desc(int which) {
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
static inline double ref_phi(const mpm_shape_desc *s, const double p[3], double *margin) {
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

/* The same collider, moving: a constant velocity and a spin about a tilted axis. */
static inline mpm_collider_desc moving(mpm_collider_desc d) {
  set3(d.motion.velocity, 0.4, -0.3, 0.2);
  set3(d.motion.axis, 1.0, 2.0, -0.5);
  unit3(d.motion.axis);
  d.motion.angular_speed = 0.9;
  return d;
}

#endif
