/* collider.h - analytic level-set colliders with kinematic motion, and the boundary rule.
 *
 * A collider is a shape (half-space, box, sphere, cylinder; inside-out for containers) whose
 * signed distance phi is negative inside the solid. Its pose moves with a kinematic motion
 * (constant velocity, rotation about an axis, or keyframes). Grid nodes (and, later, Zhu's
 * domain corners) inside a collider get the boundary rule of Gao sec. 3.2 step 4: sticky,
 * slip, or separate, with Coulomb friction. */
#ifndef MPM_COLLIDE_COLLIDER_H
#define MPM_COLLIDE_COLLIDER_H

#include "mpm/mpm.h"
#include "collide/collider_desc.h"
#include "core/real.h"

/* A collider moved by a script between steps (collider_script.c, mpm_sim_set_collider_pose):
 * from the first pose set it follows the script, not its scene motion. */
typedef struct mpm_collider_script {
  int on, pending;              /* following a script; a pose set for the next step */
  double center[3], R[9];       /* the pose now (R row-major, local -> world) */
  double to_center[3], to_R[9]; /* the pose the next step ends at (pending) */
  double velocity[3], omega[3]; /* over the last step: the pose change over its dt */
} mpm_collider_script;

/* The script's state as 32 doubles (on, pending, center, R, to_center, to_R, velocity, omega):
 * checkpoints carry it. */
#define MPM_COLLIDER_SCRIPT_DOUBLES 32

typedef struct mpm_collider {
  mpm_collider_desc desc; /* copy; keyframes are owned by the collider */
  mpm_collider_script script;
} mpm_collider;

/* The collider's pose at one time, evaluated once per step and then used for every node. */
typedef struct mpm_collider_pose {
  const mpm_collider *collider;
  mpm_real center[3];   /* current centre, m */
  mpm_real R[9];        /* current rotation (local -> world) */
  mpm_real velocity[3]; /* translational velocity of the centre, m/s */
  mpm_real omega[3];    /* angular velocity, rad/s */
} mpm_collider_pose;

/* A collider from its description d. MPM_OK, or MPM_ERR_NOMEM when out of memory. */
mpm_status mpm_collider_init(mpm_collider *c, const mpm_collider_desc *d);
void mpm_collider_free(mpm_collider *c);

/* The pose at time t: the scene's motion, or a scripted collider's pose now with the velocity
 * of its last step. */
mpm_collider_pose mpm_collider_pose_at(const mpm_collider *c, double t);
/* The pose a step from t0 to t1 ends at, with the velocity the step gives the obstacle: the
 * scene's motion at t1, or for a scripted collider the pose set, reached at a constant velocity
 * and angular velocity over the step (its pose change over dt), or held still. */
mpm_collider_pose mpm_collider_pose_over(const mpm_collider *c, double t0, double t1);
/* Script the collider: it ends the next step at this pose (centre m, rotation row-major). The
 * first call starts the script from the scene motion's pose at time t. */
void mpm_collider_script_set(mpm_collider *c, double t, const double center[3], const double R[9]);
/* After a step of dt: a scripted collider is at the pose set, its velocities those of the
 * step (or zero when it stood). */
void mpm_collider_script_commit(mpm_collider *c, double dt);
/* A scripted collider's pose now, with the velocities of its last step. */
mpm_collider_pose mpm_collider_script_pose(const mpm_collider *c);
/* The script's state to and from MPM_COLLIDER_SCRIPT_DOUBLES doubles. */
void mpm_collider_script_save(const mpm_collider *c, double *out);
void mpm_collider_script_load(mpm_collider *c, const double *in);

/* Signed distance (negative inside the solid; with inside_out the solid is the outside) and
 * the unit outward normal of the solid at x (pointing into the free region). */
mpm_real mpm_collider_phi(const mpm_collider_pose *pose, const mpm_real x[3], mpm_real n[3]);

/* Velocity of the collider's material point at x, m/s. */
void mpm_collider_velocity(const mpm_collider_pose *pose, const mpm_real x[3], mpm_real v[3]);

/* The rule a domain corner meets (corner != 0) where a grid node meets `rule`: a slip
 * obstacle lets a corner go. A grid node in an obstacle's band is one of many that carry the
 * material, which leaves the obstacle through the nodes beyond the band; a corner is the
 * material's own node, and a slip rule that removed its outgoing normal velocity too would hold
 * it on the surface it was projected to (Zhu sec. 7) for good: a body pressed flat against a
 * slip wall would stay flat. So corners meet slip obstacles as frictionless separating ones. */
static inline mpm_boundary_rule mpm_boundary_rule_for(mpm_boundary_rule rule, int corner) {
  return corner && rule == MPM_BOUNDARY_SLIP ? MPM_BOUNDARY_SEPARATE : rule;
}

/* Apply the boundary rule (as met by a corner when `corner`, above) to the velocity v at x if
 * x is inside (phi <= 0). Returns 1 if v was changed. */
int mpm_collider_apply(const mpm_collider_pose *pose, const mpm_real x[3], int corner,
                       mpm_real v[3]);

/* The rule itself, shared with the domain walls: given the unit normal n and the obstacle
 * velocity vo, project v (sticky: v = vo; slip: remove the normal part of v - vo; separate:
 * remove it only when (v - vo).n < 0), then Coulomb friction on the tangential part:
 * |vt| <- max(0, |vt| - friction * |vn removed|). */
void mpm_boundary_project(mpm_boundary_rule rule, mpm_real friction, const mpm_real n[3],
                          const mpm_real vo[3], mpm_real v[3]);

#endif
