/* motion.c - a collider's kinematic pose at time t: centre, rotation, velocity and angular
 * velocity (scene.h mpm_motion_desc). The pose is computed once per step; every grid node then
 * maps its position to the collider's local frame with it (collider.c). */
#include "collide/collider.h"
#include "collide/motion.h"
#include "core/mat3.h"

#include <assert.h>
#include <math.h>

#define MPM_TWO_PI 6.283185307179586476925286766559

mpm_motion_state mpm_motion_eval(const mpm_motion_desc *m, double t) {
  mpm_motion_state s;
  const int n = m->keyframe_count;
  if (n <= 0 || !m->keyframes) {
    for (int d = 0; d < 3; ++d) {
      s.translation[d] = m->velocity[d] * t;
      s.velocity[d] = m->velocity[d];
    }
    s.angle = m->angular_speed * t;
    s.angular_speed = m->angular_speed;
    return s;
  }
  const mpm_keyframe *k = m->keyframes;
  if (t < k[0].time || t >= k[n - 1].time) { /* held at the end values, at rest */
    const mpm_keyframe *e = t < k[0].time ? &k[0] : &k[n - 1];
    for (int d = 0; d < 3; ++d) {
      s.translation[d] = e->translation[d];
      s.velocity[d] = 0;
    }
    s.angle = e->angle;
    s.angular_speed = 0;
    return s;
  }
  /* k[lo].time <= t < k[hi].time, narrowed to one segment */
  int lo = 0, hi = n - 1;
  while (hi - lo > 1) {
    const int mid = lo + (hi - lo) / 2;
    if (k[mid].time <= t)
      lo = mid;
    else
      hi = mid;
  }
  const double span = k[hi].time - k[lo].time;
  assert(span > 0 && "keyframe times must be strictly increasing");
  const double u = (t - k[lo].time) / span;
  for (int d = 0; d < 3; ++d) {
    const double delta = k[hi].translation[d] - k[lo].translation[d];
    s.translation[d] = k[lo].translation[d] + u * delta;
    s.velocity[d] = delta / span;
  }
  const double dangle = k[hi].angle - k[lo].angle;
  s.angle = k[lo].angle + u * dangle;
  s.angular_speed = dangle / span;
  return s;
}

mpm_collider_pose mpm_collider_pose_at(const mpm_collider *c, double t) {
  if (c->script.on) return mpm_collider_script_pose(c);
  const mpm_collider_desc *d = &c->desc;
  const mpm_motion_state s = mpm_motion_eval(&d->motion, t);
  mpm_collider_pose p;
  p.collider = c;
  for (int i = 0; i < 3; ++i) {
    p.center[i] = (mpm_real)(d->shape.center[i] + s.translation[i]);
    p.velocity[i] = (mpm_real)s.velocity[i];
  }
  const double *ax = d->motion.axis;
  const double len = sqrt(ax[0] * ax[0] + ax[1] * ax[1] + ax[2] * ax[2]);
  if (len > 0) {
    const mpm_real a[3] = {(mpm_real)(ax[0] / len), (mpm_real)(ax[1] / len),
                           (mpm_real)(ax[2] / len)};
    /* reduce the angle in double so that float builds keep their digits over long runs */
    mpm_m3_axis_angle(a, (mpm_real)fmod(s.angle, MPM_TWO_PI), p.R);
    for (int i = 0; i < 3; ++i) p.omega[i] = (mpm_real)(ax[i] / len * s.angular_speed);
  } else { /* no axis: no rotation */
    mpm_m3_identity(p.R);
    for (int i = 0; i < 3; ++i) p.omega[i] = 0;
  }
  return p;
}
