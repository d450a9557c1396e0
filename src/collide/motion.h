/* motion.h - kinematic motion of a collider (private to src/collide).
 *
 * A motion is a translation of the collider's centre and a rotation by an angle about a fixed
 * axis through that centre. Without keyframes both grow linearly in time (constant velocity
 * and angular speed); with keyframes both are piecewise linear between the keyframes and held
 * at the end values outside their span. Evaluated in double: time and accumulated angles lose
 * too much in float over a long run. */
#ifndef MPM_COLLIDE_MOTION_H
#define MPM_COLLIDE_MOTION_H

#include "collide/collider_desc.h"

typedef struct mpm_motion_state {
  double translation[3]; /* offset of the centre from its rest position, m */
  double angle;          /* rotation about the motion axis, rad */
  double velocity[3];    /* d translation / dt, m/s (0 outside a keyframe span) */
  double angular_speed;  /* d angle / dt, rad/s (0 outside a keyframe span) */
} mpm_motion_state;

/* The motion at time t (s). Keyframe times must be strictly increasing. At a keyframe time the
 * slopes are those of the segment that starts there; at or after the last keyframe and before
 * the first they are 0. */
mpm_motion_state mpm_motion_eval(const mpm_motion_desc *m, double t);

#endif
