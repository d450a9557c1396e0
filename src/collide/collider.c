/* collider.c - analytic level sets of the collider shapes, the collider's velocity field and
 * the grid boundary rule (Gao et al. 2017 sec. 3.2 step 4; Coulomb friction as in Stomakhin
 * et al. 2013).
 *
 * Every shape is written in its local frame, centred at the origin; a world point x maps to
 * p = R^T (x - centre) with the pose of motion.c, and the local normal maps back by R.
 * Distances are exact signed distances (negative inside the solid), so phi is in metres and
 * its gradient, the returned normal, is unit length everywhere it is defined. On the medial
 * axis, where it is not, a fixed choice is returned (the first of the tied faces, +x, or a
 * fixed direction perpendicular to a cylinder's axis). */
#include "collide/collider.h"
#include "core/alloc.h"
#include "core/mat3.h"

#include <assert.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ---- life cycle ---------------------------------------------------------------------- */

static void normalize3(double a[3]) {
  const double len = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
  if (len > 0)
    for (int d = 0; d < 3; ++d) a[d] /= len;
}

mpm_status mpm_collider_init(mpm_collider *c, const mpm_collider_desc *d) {
  memset(&c->script, 0, sizeof c->script);
  c->desc = *d;
  c->desc.motion.keyframes = NULL;
  c->desc.motion.keyframe_count = 0;
  /* the level sets assume unit axes; the scene loader checks they are not zero */
  normalize3(c->desc.shape.axis);
  normalize3(c->desc.motion.axis);
  const int n = d->motion.keyframe_count;
  if (n > 0) {
    assert(d->motion.keyframes);
    mpm_keyframe *k = mpm_alloc((size_t)n * sizeof *k);
    if (!k) return MPM_ERR_NOMEM;
    memcpy(k, d->motion.keyframes, (size_t)n * sizeof *k);
    c->desc.motion.keyframes = k;
    c->desc.motion.keyframe_count = n;
  }
  return MPM_OK;
}

void mpm_collider_free(mpm_collider *c) {
  mpm_free(c->desc.motion.keyframes);
  c->desc.motion.keyframes = NULL;
  c->desc.motion.keyframe_count = 0;
}

/* ---- level sets in the local frame --------------------------------------------------- */

/* Axis-aligned box |p_i| <= h_i: outside, the distance to the nearest point of the box;
 * inside, minus the distance to the nearest face. */
static mpm_real sdf_box(const mpm_shape_desc *s, const mpm_real p[3], mpm_real n[3]) {
  mpm_real q[3], qo[3], out2 = 0;
  for (int d = 0; d < 3; ++d) {
    q[d] = mpm_fabs(p[d]) - (mpm_real)s->half_extent[d];
    qo[d] = mpm_fmax(q[d], 0);
    out2 += qo[d] * qo[d];
  }
  const int imax = q[0] >= q[1] ? (q[0] >= q[2] ? 0 : 2) : (q[1] >= q[2] ? 1 : 2);
  if (out2 > 0) {
    const mpm_real out = mpm_sqrt(out2), inv = 1 / out;
    for (int d = 0; d < 3; ++d) n[d] = (p[d] < 0 ? -qo[d] : qo[d]) * inv;
    return out;
  }
  n[0] = n[1] = n[2] = 0;
  n[imax] = p[imax] < 0 ? -1 : 1;
  return q[imax];
}

static mpm_real sdf_sphere(const mpm_shape_desc *s, const mpm_real p[3], mpm_real n[3]) {
  const mpm_real len = mpm_v3_norm(p);
  if (len > 0) {
    const mpm_real inv = 1 / len;
    for (int d = 0; d < 3; ++d) n[d] = p[d] * inv;
  } else {
    n[0] = 1, n[1] = n[2] = 0;
  }
  return len - (mpm_real)s->radius;
}

/* A fixed unit vector perpendicular to the unit vector a. */
static void perpendicular(const mpm_real a[3], mpm_real e[3]) {
  const mpm_real ref[3] = {mpm_fabs(a[0]) < R_(0.9) ? 1 : 0, mpm_fabs(a[0]) < R_(0.9) ? 0 : 1, 0};
  mpm_v3_cross(a, ref, e);
  const mpm_real inv = 1 / mpm_v3_norm(e);
  for (int d = 0; d < 3; ++d) e[d] *= inv;
}

/* Cylinder of radius r about the unit axis a, capped at |p.a| = H (infinite when H <= 0).
 * In the (radial, axial) half-plane it is the 2D box [0, r] x [-H, H]. */
static mpm_real sdf_cylinder(const mpm_shape_desc *s, const mpm_real p[3], mpm_real n[3]) {
  const mpm_real a[3] = {(mpm_real)s->axis[0], (mpm_real)s->axis[1], (mpm_real)s->axis[2]};
  const mpm_real h = mpm_v3_dot(p, a);
  mpm_real rv[3] = {p[0] - h * a[0], p[1] - h * a[1], p[2] - h * a[2]};
  const mpm_real rho = mpm_v3_norm(rv);
  const mpm_real dr = rho - (mpm_real)s->radius;
  const mpm_real dh = s->half_height > 0 ? mpm_fabs(h) - (mpm_real)s->half_height : -MPM_REAL_MAX;
  const mpm_real sh = h < 0 ? -1 : 1;
  if (rho > 0) {
    const mpm_real inv = 1 / rho;
    for (int d = 0; d < 3; ++d) rv[d] *= inv;
  } else {
    perpendicular(a, rv);
  }
  if (dr > 0 && dh > 0) { /* beyond the rim: nearest point on the edge circle */
    const mpm_real out = mpm_sqrt(dr * dr + dh * dh), inv = 1 / out;
    for (int d = 0; d < 3; ++d) n[d] = (dr * rv[d] + dh * sh * a[d]) * inv;
    return out;
  }
  if (dr >= dh) { /* the side is nearest */
    for (int d = 0; d < 3; ++d) n[d] = rv[d];
    return dr;
  }
  for (int d = 0; d < 3; ++d) n[d] = sh * a[d]; /* a cap is nearest */
  return dh;
}

/* Half-space through the centre with outward normal a: the solid is p.a < 0. */
static mpm_real sdf_halfspace(const mpm_shape_desc *s, const mpm_real p[3], mpm_real n[3]) {
  for (int d = 0; d < 3; ++d) n[d] = (mpm_real)s->axis[d];
  return mpm_v3_dot(p, n);
}

/* Solid of revolution about the unit axis a through the centre. In the (radial rho, axial h)
 * half-plane the solid is the polygon closed by the profile polyline (first and last points on
 * the axis) and the axis. The axis is a line of symmetry, not a surface, so the distance is to
 * the profile's segments only; inside or outside by the crossing rule (a ray towards +rho,
 * which the closing axis edge at rho = 0 never meets). The normal is the nearest segment's
 * outward normal where the nearest point is inside that segment (exactly the gradient there,
 * and free of the rounding of a short difference vector near the surface), and the direction
 * from the nearest vertex otherwise. */
static mpm_real sdf_revolve(const mpm_shape_desc *s, const mpm_real p[3], mpm_real n[3]) {
  const mpm_real a[3] = {(mpm_real)s->axis[0], (mpm_real)s->axis[1], (mpm_real)s->axis[2]};
  const mpm_real h = mpm_v3_dot(p, a);
  mpm_real er[3] = {p[0] - h * a[0], p[1] - h * a[1], p[2] - h * a[2]};
  const mpm_real rho = mpm_v3_norm(er);
  if (rho > 0) {
    const mpm_real inv = 1 / rho;
    for (int d = 0; d < 3; ++d) er[d] *= inv;
  } else {
    perpendicular(a, er);
  }
  mpm_real best = MPM_REAL_MAX, qr = 0, qh = 0, tr = 0, th = 0, area2 = 0;
  int inside = 0, at_vertex = 0;
  for (int k = 0; k + 1 < s->profile_count; ++k) {
    const mpm_real ar = (mpm_real)s->profile[k][0], ah = (mpm_real)s->profile[k][1];
    const mpm_real br = (mpm_real)s->profile[k + 1][0], bh = (mpm_real)s->profile[k + 1][1];
    const mpm_real dr = br - ar, dh = bh - ah, len2 = dr * dr + dh * dh;
    area2 += ar * bh - br * ah;
    const mpm_real t0 = len2 > 0 ? ((rho - ar) * dr + (h - ah) * dh) / len2 : 0;
    const mpm_real t = mpm_fmin(mpm_fmax(t0, 0), 1);
    const mpm_real cr = ar + t * dr, ch = ah + t * dh;
    const mpm_real d2 = (rho - cr) * (rho - cr) + (h - ch) * (h - ch);
    if (d2 < best) {
      best = d2, qr = cr, qh = ch, tr = dr, th = dh;
      at_vertex = t != t0;
    }
    if ((ah > h) != (bh > h)) {
      const mpm_real cross = ar + (h - ah) * dr / dh;
      if (rho < cross) inside = !inside;
    }
  }
  const mpm_real dist = mpm_sqrt(best);
  /* the outward normal of the nearest segment: (dh, -dr) for a counter-clockwise polygon (the
     closing axis edge adds nothing to the signed area, both its ends having radius 0) */
  const mpm_real len = mpm_sqrt(tr * tr + th * th), o = area2 >= 0 ? 1 : -1;
  mpm_real nr = len > 0 ? o * th / len : 1, nh = len > 0 ? -o * tr / len : 0;
  if (at_vertex && dist > MPM_REAL_EPS * (mpm_fabs(rho) + mpm_fabs(h))) {
    const mpm_real sgn = inside ? -1 : 1;
    nr = sgn * (rho - qr) / dist;
    nh = sgn * (h - qh) / dist;
  }
  for (int d = 0; d < 3; ++d) n[d] = nr * er[d] + nh * a[d];
  return inside ? -dist : dist;
}

/* ---- world-frame queries -------------------------------------------------------------- */

mpm_real mpm_collider_phi(const mpm_collider_pose *pose, const mpm_real x[3], mpm_real n[3]) {
  const mpm_collider_desc *d = &pose->collider->desc;
  const mpm_real *R = pose->R;
  const mpm_real r[3] = {x[0] - pose->center[0], x[1] - pose->center[1], x[2] - pose->center[2]};
  mpm_real p[3], nl[3], phi;
  for (int j = 0; j < 3; ++j) p[j] = R[j] * r[0] + R[3 + j] * r[1] + R[6 + j] * r[2]; /* R^T r */
  switch (d->shape.kind) {
  case MPM_SHAPE_BOX:
    phi = sdf_box(&d->shape, p, nl);
    break;
  case MPM_SHAPE_SPHERE:
    phi = sdf_sphere(&d->shape, p, nl);
    break;
  case MPM_SHAPE_CYLINDER:
    phi = sdf_cylinder(&d->shape, p, nl);
    break;
  case MPM_SHAPE_HALFSPACE:
    phi = sdf_halfspace(&d->shape, p, nl);
    break;
  case MPM_SHAPE_REVOLVE:
    phi = sdf_revolve(&d->shape, p, nl);
    break;
  default: /* meshes are bodies only; the loader rejects them here */
    assert(0 && "collider shape must be box, sphere, cylinder, half-space or revolve");
    nl[0] = 1, nl[1] = nl[2] = 0;
    phi = MPM_REAL_MAX;
    break;
  }
  const mpm_real sign = d->inside_out ? -1 : 1;
  mpm_m3_mulv(R, nl, n);
  for (int j = 0; j < 3; ++j) n[j] *= sign;
  return sign * phi;
}

void mpm_collider_velocity(const mpm_collider_pose *pose, const mpm_real x[3], mpm_real v[3]) {
  const mpm_real r[3] = {x[0] - pose->center[0], x[1] - pose->center[1], x[2] - pose->center[2]};
  mpm_v3_cross(pose->omega, r, v);
  for (int d = 0; d < 3; ++d) v[d] += pose->velocity[d];
}

int mpm_collider_apply(const mpm_collider_pose *pose, const mpm_real x[3], int corner,
                       mpm_real v[3]) {
  mpm_real n[3];
  if (mpm_collider_phi(pose, x, n) > 0) return 0;
  mpm_real vo[3];
  mpm_collider_velocity(pose, x, vo);
  const mpm_collider_desc *d = &pose->collider->desc;
  mpm_boundary_project(mpm_boundary_rule_for(d->rule, corner), (mpm_real)d->friction, n, vo, v);
  return 1;
}

/* ---- the boundary rule ---------------------------------------------------------------- */

void mpm_boundary_project(mpm_boundary_rule rule, mpm_real friction, const mpm_real n[3],
                          const mpm_real vo[3], mpm_real v[3]) {
  if (rule == MPM_BOUNDARY_STICKY) {
    for (int d = 0; d < 3; ++d) v[d] = vo[d];
    return;
  }
  mpm_real vt[3] = {v[0] - vo[0], v[1] - vo[1], v[2] - vo[2]}; /* relative velocity */
  const mpm_real vn = mpm_v3_dot(vt, n);
  if (rule == MPM_BOUNDARY_SEPARATE && vn >= 0) return; /* separating: left alone */
  for (int d = 0; d < 3; ++d) vt[d] -= vn * n[d];
  /* Coulomb: the tangential speed drops by friction * |vn|, and stops if that is enough */
  const mpm_real speed = mpm_v3_norm(vt), limit = friction * mpm_fabs(vn);
  const mpm_real scale = speed <= limit ? 0 : 1 - limit / speed;
  for (int d = 0; d < 3; ++d) v[d] = vo[d] + scale * vt[d];
}
