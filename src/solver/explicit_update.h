/* explicit_update.h - the explicit update of the DOF set (Gao sec. 3.2 steps 3-4), and the
 * boundary rules every DOF and every domain corner obeys.
 *
 * For each DOF with mass: v^n = p / m, v^{n+1} = v^n + dt (f / m + g), then the colliders and
 * the domain walls act on v^{n+1} at the DOF's position. Positions come from the DOF set (a
 * grid node of any level, a corner), so the same update serves every level and kind. A DOF
 * without mass gets zero velocities. */
#ifndef MPM_SOLVER_EXPLICIT_UPDATE_H
#define MPM_SOLVER_EXPLICIT_UPDATE_H

#include "collide/collider.h"
#include "solver/dofs.h"

/* What P2G left in the DOF set. */
typedef enum mpm_p2g_output {
  MPM_P2G_MOMENTUM_FORCE, /* v0 holds the momentum, f the force */
  MPM_P2G_IMPULSE         /* v0 holds the momentum after the force impulse, m v + dt f (the
                             fused APIC P2G); there is no f, and v0 becomes the velocity after
                             that impulse, which nothing reads (APIC has no FLIP increment) */
} mpm_p2g_output;

/* Colliders and the domain walls. The walls are the planes wall_lo[d] and wall_hi[d] (m); a
 * point more than a segment's boundary_depth beyond one is in the wall band and gets the wall
 * rule with the inward normal (one axis after the other, after the colliders). */
typedef struct mpm_boundary {
  mpm_real wall_lo[3], wall_hi[3];
  mpm_boundary_rule wall_rule;
  mpm_real wall_friction;
  int collider_count;
  const mpm_collider_pose *poses; /* at the end of the step */
} mpm_boundary;

/* Apply the colliders, then the walls, to velocity v at position x; depth as above. */
MPM_ALWAYS_INLINE void mpm_boundary_apply(const mpm_boundary *b, const mpm_real x[3],
                                          mpm_real depth, mpm_real v[3]) {
  for (int c = 0; c < b->collider_count; ++c) mpm_collider_apply(&b->poses[c], x, v);
  static const mpm_real zero[3] = {0, 0, 0};
  for (int d = 0; d < 3; ++d) {
    const int lo = x[d]<b->wall_lo[d] - depth, hi = x[d]> b->wall_hi[d] + depth;
    if (lo || hi) {
      mpm_real n[3] = {0, 0, 0};
      n[d] = lo ? 1 : -1;
      mpm_boundary_project(b->wall_rule, b->wall_friction, n, zero, v);
    }
  }
}

typedef struct mpm_explicit_update {
  mpm_real dt;         /* s */
  mpm_real gravity[3]; /* m/s^2 */
  mpm_boundary boundary;
} mpm_explicit_update;

/* The update of every DOF of d (parallel over the boxes of each grid segment and over chunks
 * of corners; independent per DOF, so deterministic). Reads mass, v0 and (for
 * MPM_P2G_MOMENTUM_FORCE) f; writes v0 = v^n and v = v^{n+1}. */
void mpm_dofs_explicit_update(const mpm_explicit_update *u, mpm_p2g_output in, mpm_dofs *d);

#endif
