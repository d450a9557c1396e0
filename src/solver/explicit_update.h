/* explicit_update.h - the explicit update of the DOF set (Gao sec. 3.2 steps 3-4), and the
 * boundary rules every DOF and every domain corner obeys.
 *
 * For each DOF with mass: v^n = p / m, v^{n+1} = v^n + dt (f / m + g), g gravity plus the
 * body-force regions at the DOF, then the colliders and
 * the domain walls act on v^{n+1} at the DOF's position. Positions come from the DOF set (a
 * grid node of any level, a corner), so the same update serves every level and kind. A DOF
 * without mass gets zero velocities. */
#ifndef MPM_SOLVER_EXPLICIT_UPDATE_H
#define MPM_SOLVER_EXPLICIT_UPDATE_H

#include "mpm/mpm.h"
#include "collide/body_force.h"
#include "collide/boundary.h"
#include "core/arena.h"
#include "grid/dofs.h"

/* What P2G left in the DOF set. */
typedef enum mpm_p2g_output {
  MPM_P2G_MOMENTUM_FORCE, /* v0 holds the momentum, f the force */
  MPM_P2G_IMPULSE         /* v0 holds the momentum after the force impulse, m v + dt f (the
                             fused APIC P2G); there is no f, and v0 becomes the velocity after
                             that impulse, which nothing reads (APIC has no FLIP increment) */
} mpm_p2g_output;

typedef struct mpm_explicit_update {
  mpm_real dt;         /* s */
  mpm_real gravity[3]; /* m/s^2 */
  int region_count;    /* body-force regions acting on top of gravity (collide/body_force.h) */
  const mpm_force_region *regions;
  mpm_boundary boundary;
  /* The momentum the colliders take (their reaction forces in stats.csv): NULL, or
   * 3 * boundary.collider_count doubles, kg m/s, that the update adds to (pose c's component
   * e at 3 c + e; mpm_boundary_apply_taken). Summed per grid box and per chunk of corners,
   * then over them in order, so the sums do not depend on the thread count. */
  double *taken;
  mpm_arena *arena; /* with taken: the per-box sums' scratch */
} mpm_explicit_update;

/* The update of every DOF of d (parallel over the boxes of each grid segment and over chunks
 * of corners; independent per DOF, so deterministic). Reads mass, v0 and (for
 * MPM_P2G_MOMENTUM_FORCE) f; writes v0 = v^n and v = v^{n+1}. MPM_OK, or MPM_ERR_NOMEM when the
 * arena has no room for the sums of u->taken (nothing is updated then). */
mpm_status mpm_dofs_explicit_update(const mpm_explicit_update *u, mpm_p2g_output in, mpm_dofs *d);

#endif
