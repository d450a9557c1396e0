/* body_force.h - body-force regions (Zhu et al. 2017 Fig. 9: a rabbit sucked out of a cup
 * through a straw): inside a region, an acceleration on top of gravity.
 *
 * A region is a collider's level set (collider.h: any collider shape, its motion, its
 * `active` window); a point is inside where phi <= 0, the same test the boundary rules use.
 * The scene's schedule scales the acceleration over time. Like gravity, the acceleration
 * acts on the DOFs (grid nodes of any level, enriched domain corners) at their positions, in
 * the explicit update and in the implicit step's predictor and incremental potential.
 *
 * A region may also drag: dv/dt = -drag v, taken implicitly over the step, v <- v / (1 +
 * dt drag), which damps any drag rate without overshoot and leaves a body at rest alone (it
 * brings bodies to rest without holding them deformed, as friction would). In the explicit
 * update it follows the forces; in the implicit step it follows the solve (an operator split,
 * first order as the step), before the boundary rules. */
#ifndef MPM_COLLIDE_BODY_FORCE_H
#define MPM_COLLIDE_BODY_FORCE_H

#include "collide/collider.h"

/* One region as it acts during a step. */
typedef struct mpm_force_region {
  mpm_collider_pose pose;   /* the region's pose at the end of the step */
  mpm_real acceleration[3]; /* with the schedule's factor at the end of the step, m/s^2 */
  mpm_real drag;            /* with the schedule's factor, 1/s */
} mpm_force_region;

/* a += the accelerations of the regions containing x; returns the sum of their drag rates. */
MPM_ALWAYS_INLINE mpm_real mpm_force_regions_add(const mpm_force_region *r, int count,
                                                 const mpm_real x[3], mpm_real a[3]) {
  mpm_real drag = 0;
  for (int k = 0; k < count; ++k) {
    mpm_real n[3];
    if (mpm_collider_phi(&r[k].pose, x, n) <= 0) {
      for (int d = 0; d < 3; ++d) a[d] += r[k].acceleration[d];
      drag += r[k].drag;
    }
  }
  return drag;
}

/* The velocity v after a step dt under the drag rate `drag` (above). */
MPM_ALWAYS_INLINE void mpm_force_drag(mpm_real drag, mpm_real dt, mpm_real v[3]) {
  if (drag > 0) {
    const mpm_real keep = 1 / (1 + dt * drag);
    for (int d = 0; d < 3; ++d) v[d] *= keep;
  }
}

#endif
