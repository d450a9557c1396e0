/* boundary.h - the boundary conditions every unknown and every domain corner obeys: the
 * colliders (level sets with a kinematic motion and a rule, collider.h), then the domain walls
 * (Gao sec. 3.2 step 4), both by position, so that they act alike on grid nodes of any level,
 * on corner DOFs and on the corners of Zhu's particle domains (Zhu sec. 7). */
#ifndef MPM_COLLIDE_BOUNDARY_H
#define MPM_COLLIDE_BOUNDARY_H

#include "collide/collider.h"

/* Colliders and the domain walls. The walls are the planes wall_lo[d] and wall_hi[d] (m); a
 * point more than `depth` beyond one (half a cell for grid nodes, which sit on the lattice; 0
 * for corners: solver/dofs.h, boundary_depth) is in the wall band and gets the wall
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
    const mpm_real lo_plane = b->wall_lo[d] - depth, hi_plane = b->wall_hi[d] + depth;
    const int lo = x[d]<lo_plane, hi = x[d]> hi_plane;
    if (lo || hi) {
      mpm_real n[3] = {0, 0, 0};
      n[d] = lo ? 1 : -1;
      mpm_boundary_project(b->wall_rule, b->wall_friction, n, zero, v);
    }
  }
}

#endif
