/* collider_script.c - colliders moved by a script between steps (collider.h,
 * mpm_sim_set_collider_pose): a robot's gripper or a shot's animated prop driven from Python.
 *
 * The script sets where the collider is at the end of the next step; over that step it moves
 * there at a constant velocity and angular velocity, the pose change over dt (the rotation's by
 * the axis and angle of R_to R_now^T), which is what the grid's boundary rule gives the material
 * it touches. Then it stands at that pose until the script sets another. */
#include "collide/collider.h"
#include "core/quat.h"

#include <math.h>
#include <string.h>

/* The angular velocity that turns R0 into R1 over dt: the rotation vector of R1 R0^T over dt. */
static void angular_velocity(const double R0[9], const double R1[9], double dt, double w[3]) {
  double Rel[9], q[4];
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      Rel[3 * r + c] =
          R1[3 * r] * R0[3 * c] + R1[3 * r + 1] * R0[3 * c + 1] + R1[3 * r + 2] * R0[3 * c + 2];
  mpm_quat_from_matrix(Rel, q); /* w >= 0: the angle is in [0, pi] */
  const double s = sqrt(q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  const double angle = 2 * atan2(s, q[0]);
  for (int d = 0; d < 3; ++d) w[d] = s > 0 && dt > 0 ? q[1 + d] / s * angle / dt : 0;
}

/* The velocity and angular velocity of a step of dt to the pose set. */
static void step_motion(const mpm_collider_script *s, double dt, double v[3], double w[3]) {
  for (int d = 0; d < 3; ++d) v[d] = dt > 0 ? (s->to_center[d] - s->center[d]) / dt : 0;
  angular_velocity(s->R, s->to_R, dt, w);
}

static mpm_collider_pose make_pose(const mpm_collider *c, const double center[3], const double R[9],
                                   const double v[3], const double w[3]) {
  mpm_collider_pose p;
  p.collider = c;
  for (int d = 0; d < 3; ++d) {
    p.center[d] = (mpm_real)center[d];
    p.velocity[d] = (mpm_real)v[d];
    p.omega[d] = (mpm_real)w[d];
  }
  for (int k = 0; k < 9; ++k) p.R[k] = (mpm_real)R[k];
  return p;
}

mpm_collider_pose mpm_collider_script_pose(const mpm_collider *c) {
  const mpm_collider_script *s = &c->script;
  return make_pose(c, s->center, s->R, s->velocity, s->omega);
}

mpm_collider_pose mpm_collider_pose_over(const mpm_collider *c, double t0, double t1) {
  const mpm_collider_script *s = &c->script;
  if (!s->on) return mpm_collider_pose_at(c, t1);
  const double zero[3] = {0, 0, 0};
  if (!s->pending) return make_pose(c, s->center, s->R, zero, zero);
  double v[3], w[3];
  step_motion(s, t1 - t0, v, w);
  return make_pose(c, s->to_center, s->to_R, v, w);
}

void mpm_collider_script_set(mpm_collider *c, double t, const double center[3], const double R[9]) {
  mpm_collider_script *s = &c->script;
  if (!s->on) { /* from where the scene's motion has it now, standing */
    const mpm_collider_pose p = mpm_collider_pose_at(c, t);
    for (int d = 0; d < 3; ++d) s->center[d] = p.center[d];
    for (int k = 0; k < 9; ++k) s->R[k] = p.R[k];
    memset(s->velocity, 0, sizeof s->velocity);
    memset(s->omega, 0, sizeof s->omega);
    s->on = 1;
  }
  memcpy(s->to_center, center, sizeof s->to_center);
  memcpy(s->to_R, R, sizeof s->to_R);
  s->pending = 1;
}

void mpm_collider_script_commit(mpm_collider *c, double dt) {
  mpm_collider_script *s = &c->script;
  if (!s->on) return;
  if (!s->pending) {
    memset(s->velocity, 0, sizeof s->velocity);
    memset(s->omega, 0, sizeof s->omega);
    return;
  }
  step_motion(s, dt, s->velocity, s->omega);
  memcpy(s->center, s->to_center, sizeof s->center);
  memcpy(s->R, s->to_R, sizeof s->R);
  s->pending = 0;
}

void mpm_collider_script_save(const mpm_collider *c, double *out) {
  const mpm_collider_script *s = &c->script;
  int k = 0;
  out[k++] = s->on;
  out[k++] = s->pending;
  for (int d = 0; d < 3; ++d) out[k++] = s->center[d];
  for (int d = 0; d < 9; ++d) out[k++] = s->R[d];
  for (int d = 0; d < 3; ++d) out[k++] = s->to_center[d];
  for (int d = 0; d < 9; ++d) out[k++] = s->to_R[d];
  for (int d = 0; d < 3; ++d) out[k++] = s->velocity[d];
  for (int d = 0; d < 3; ++d) out[k++] = s->omega[d];
}

void mpm_collider_script_load(mpm_collider *c, const double *in) {
  mpm_collider_script *s = &c->script;
  int k = 0;
  s->on = in[k++] != 0;
  s->pending = in[k++] != 0;
  for (int d = 0; d < 3; ++d) s->center[d] = in[k++];
  for (int d = 0; d < 9; ++d) s->R[d] = in[k++];
  for (int d = 0; d < 3; ++d) s->to_center[d] = in[k++];
  for (int d = 0; d < 9; ++d) s->to_R[d] = in[k++];
  for (int d = 0; d < 3; ++d) s->velocity[d] = in[k++];
  for (int d = 0; d < 3; ++d) s->omega[d] = in[k++];
}
