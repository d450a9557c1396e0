/* boundary.h - the boundary conditions every unknown and every domain corner obeys: the
 * colliders (level sets with a kinematic motion and a rule, collider.h), then the domain walls
 * (Gao sec. 3.2 step 4), both by position, so that they act alike on grid nodes of any level,
 * on corner DOFs and on the corners of Zhu's particle domains (Zhu sec. 7). */
#ifndef MPM_COLLIDE_BOUNDARY_H
#define MPM_COLLIDE_BOUNDARY_H

#include "collide/collider.h"

/* Colliders and the domain walls. The walls are the planes wall_lo[d] and wall_hi[d] (m); a
 * point more than `depth` beyond one (half a cell for grid nodes, which sit on the lattice; 0
 * for corners: grid/dofs.h, boundary_depth) is in the wall band and gets the wall
 * rule with the inward normal (one axis after the other, after the colliders). `corner`: the
 * point is a domain corner, which meets slip obstacles as separating ones
 * (mpm_boundary_rule_for, collider.h). */
typedef struct mpm_boundary {
  mpm_real wall_lo[3], wall_hi[3];
  mpm_boundary_rule wall_rule;
  mpm_real wall_friction;
  int collider_count;
  const mpm_collider_pose *poses; /* at the end of the step */
} mpm_boundary;

/* The walls alone (after the colliders, in mpm_boundary_apply). */
MPM_ALWAYS_INLINE void mpm_boundary_apply_walls(const mpm_boundary *b, const mpm_real x[3],
                                                mpm_real depth, int corner, mpm_real v[3]) {
  static const mpm_real zero[3] = {0, 0, 0};
  const mpm_boundary_rule rule = mpm_boundary_rule_for(b->wall_rule, corner);
  for (int d = 0; d < 3; ++d) {
    const mpm_real lo_plane = b->wall_lo[d] - depth, hi_plane = b->wall_hi[d] + depth;
    const int lo = x[d]<lo_plane, hi = x[d]> hi_plane;
    if (lo || hi) {
      mpm_real n[3] = {0, 0, 0};
      n[d] = lo ? 1 : -1;
      mpm_boundary_project(rule, b->wall_friction, n, zero, v);
    }
  }
}

/* Apply the colliders, then the walls, to velocity v at position x; depth as above. */
MPM_ALWAYS_INLINE void mpm_boundary_apply(const mpm_boundary *b, const mpm_real x[3],
                                          mpm_real depth, int corner, mpm_real v[3]) {
  for (int c = 0; c < b->collider_count; ++c) mpm_collider_apply(&b->poses[c], x, corner, v);
  mpm_boundary_apply_walls(b, x, depth, corner, v);
}

/* mpm_boundary_apply at a DOF of the given mass, adding to taken[3 c + e] the momentum
 * component e that collider (pose) c's projection took from it, mass (v_before - v_after),
 * kg m/s: what the material gave the collider, whose force on it is that over dt. The same
 * velocities as mpm_boundary_apply, bitwise. */
MPM_ALWAYS_INLINE void mpm_boundary_apply_taken(const mpm_boundary *b, const mpm_real x[3],
                                                mpm_real depth, int corner, mpm_real mass,
                                                mpm_real v[3], double *taken) {
  for (int c = 0; c < b->collider_count; ++c) {
    const mpm_real before[3] = {v[0], v[1], v[2]};
    if (mpm_collider_apply(&b->poses[c], x, corner, v))
      for (int e = 0; e < 3; ++e) taken[3 * c + e] += (double)mass * (double)(before[e] - v[e]);
  }
  mpm_boundary_apply_walls(b, x, depth, corner, v);
}

/* The velocity Coulomb friction mu leaves a point moving at rel relative to an obstacle that
 * stops its normal velocity vn < 0 (normal n): the tangential part, slowed by mu |vn| and
 * stopped if that is enough (static friction), as mpm_boundary_project does; into out, relative
 * to the obstacle. */
MPM_ALWAYS_INLINE void mpm_boundary_friction_velocity(mpm_real mu, const mpm_real rel[3],
                                                      const mpm_real n[3], mpm_real vn,
                                                      mpm_real out[3]) {
  const mpm_real t[3] = {rel[0] - vn * n[0], rel[1] - vn * n[1], rel[2] - vn * n[2]};
  const mpm_real speed = mpm_sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
  const mpm_real limit = mu * mpm_fabs(vn);
  const mpm_real keep = speed > limit ? 1 - limit / speed : 0;
  for (int e = 0; e < 3; ++e) out[e] = keep * t[e];
}

/* The constraints the implicit solve enforces inside CG at a DOF at x (the same colliders and
 * wall bands as mpm_boundary_apply, in the same order): a sticky obstacle fixes the whole
 * velocity (returns -1, its velocity in vo[0]); a slip obstacle constrains the normal
 * component; a separating one only when the predicted velocity v moves into it, (v - vo).n <
 * 0; a corner meets a slip obstacle as a separating one.
 *
 * Friction acts inside the solve: where an obstacle with friction stops the normal motion of
 * vm (the velocity the step brings without the elastic forces: v^n + dt g), the DOF's whole
 * velocity is fixed (returns -2, the velocity in vo[0]) to what Coulomb's rule makes of vm:
 * the normal part stopped, the tangential part slowed by mu times the normal speed stopped, held
 * where that is enough (mpm_boundary_friction_velocity). Not from v itself: v* carries the
 * elastic forces' explicit step, which at an implicit step is no velocity at all. Friction
 * applied only after the solve, to velocities the elastic solve had already balanced, strained
 * the material at the contact by the step's whole sliding: a rubber bunny landing on a floor
 * with friction 0.5 gained 6 J over its start and kept 9 J of elastic energy at rest (511 J with
 * CG solved tightly), a block thrown across it 20 J. Up to 4 normals n[k] with obstacle
 * velocities vo[k]; returns their count. */
MPM_ALWAYS_INLINE int mpm_boundary_constraints(const mpm_boundary *b, const mpm_real x[3],
                                               mpm_real depth, int corner, const mpm_real v[3],
                                               const mpm_real vm[3], mpm_real n[4][3],
                                               mpm_real vo[4][3]) {
  int count = 0;
  for (int c = 0; c < b->collider_count; ++c) {
    mpm_real nc[3], vc[3];
    if (mpm_collider_phi(&b->poses[c], x, nc) > 0) continue;
    mpm_collider_velocity(&b->poses[c], x, vc);
    const mpm_boundary_rule rule = mpm_boundary_rule_for(b->poses[c].collider->desc.rule, corner);
    if (rule == MPM_BOUNDARY_STICKY) {
      for (int e = 0; e < 3; ++e) vo[0][e] = vc[e];
      return -1;
    }
    const mpm_real vn = (v[0] - vc[0]) * nc[0] + (v[1] - vc[1]) * nc[1] + (v[2] - vc[2]) * nc[2];
    const mpm_real rel[3] = {vm[0] - vc[0], vm[1] - vc[1], vm[2] - vc[2]};
    const mpm_real vmn = rel[0] * nc[0] + rel[1] * nc[1] + rel[2] * nc[2];
    const mpm_real mu = (mpm_real)b->poses[c].collider->desc.friction;
    if (mu > 0 && vmn < 0) {
      mpm_real t[3];
      mpm_boundary_friction_velocity(mu, rel, nc, vmn, t);
      for (int e = 0; e < 3; ++e) vo[0][e] = vc[e] + t[e];
      return -2;
    }
    if (rule == MPM_BOUNDARY_SEPARATE && vn >= 0) continue;
    if (count < 4) {
      for (int e = 0; e < 3; ++e) n[count][e] = nc[e], vo[count][e] = vc[e];
      ++count;
    }
  }
  const mpm_boundary_rule wall_rule = mpm_boundary_rule_for(b->wall_rule, corner);
  for (int d = 0; d < 3; ++d) {
    const mpm_real lo_plane = b->wall_lo[d] - depth, hi_plane = b->wall_hi[d] + depth;
    const int lo = x[d]<lo_plane, hi = x[d]> hi_plane;
    if (!lo && !hi) continue;
    if (wall_rule == MPM_BOUNDARY_STICKY) {
      vo[0][0] = vo[0][1] = vo[0][2] = 0;
      return -1;
    }
    const mpm_real s = lo ? 1 : -1;
    if (b->wall_friction > 0 && s * vm[d] < 0) {
      mpm_real nw[3] = {0, 0, 0};
      nw[d] = s;
      mpm_boundary_friction_velocity(b->wall_friction, vm, nw, s * vm[d], vo[0]);
      return -2;
    }
    if (wall_rule == MPM_BOUNDARY_SEPARATE && s * v[d] >= 0) continue;
    if (count < 4) {
      n[count][0] = n[count][1] = n[count][2] = 0;
      n[count][d] = s;
      vo[count][0] = vo[count][1] = vo[count][2] = 0;
      ++count;
    }
  }
  return count;
}

/* The velocity v of a point at x that moves by dt v, corrected so that it ends on the surface
 * of a slip or separating collider it would enter (v -= (phi(x + dt v) / dt) n) and on the
 * plane of a slip or separating domain wall it would cross (Zhu sec. 7: collided domain
 * corners are projected to the surface along the normal; as a velocity, so that F, which the
 * same velocity updates, sees the projection). Sticky obstacles hold what they grip: nothing
 * is moved. For points that no grid node carries: enriched domain corners. */
MPM_ALWAYS_INLINE void mpm_boundary_project_motion(const mpm_boundary *b, const mpm_real x[3],
                                                   mpm_real dt, mpm_real v[3]) {
  for (int c = 0; c < b->collider_count; ++c) {
    if (b->poses[c].collider->desc.rule == MPM_BOUNDARY_STICKY) continue;
    const mpm_real y[3] = {x[0] + dt * v[0], x[1] + dt * v[1], x[2] + dt * v[2]};
    mpm_real n[3];
    const mpm_real phi = mpm_collider_phi(&b->poses[c], y, n);
    if (phi < 0)
      for (int d = 0; d < 3; ++d) v[d] -= phi / dt * n[d];
  }
  if (b->wall_rule == MPM_BOUNDARY_STICKY) return;
  for (int d = 0; d < 3; ++d) {
    const mpm_real y = x[d] + dt * v[d];
    if (y < b->wall_lo[d]) v[d] = (b->wall_lo[d] - x[d]) / dt;
    if (y > b->wall_hi[d]) v[d] = (b->wall_hi[d] - x[d]) / dt;
  }
}

#endif
