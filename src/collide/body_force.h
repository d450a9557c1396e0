/* body_force.h - body-force regions (Zhu et al. 2017 Fig. 9: a rabbit sucked out of a cup
 * through a straw): inside a region, an acceleration on top of gravity.
 *
 * A region is a collider's level set (collider.h: any collider shape, its motion, its
 * `active` window); a point is inside where phi <= 0, the same test the boundary rules use.
 * The scene's schedule scales the acceleration over time. Like gravity, the acceleration
 * acts on the DOFs (grid nodes of any level, enriched domain corners) at their positions, in
 * the explicit update and in the implicit step's predictor and incremental potential. */
#ifndef MPM_COLLIDE_BODY_FORCE_H
#define MPM_COLLIDE_BODY_FORCE_H

#include "collide/collider.h"

/* One region as it acts during a step. */
typedef struct mpm_force_region {
  mpm_collider_pose pose;   /* the region's pose at the end of the step */
  mpm_real acceleration[3]; /* with the schedule's factor at the end of the step, m/s^2 */
} mpm_force_region;

/* a += the accelerations of the regions containing x. */
MPM_ALWAYS_INLINE void mpm_force_regions_add(const mpm_force_region *r, int count,
                                             const mpm_real x[3], mpm_real a[3]) {
  for (int k = 0; k < count; ++k) {
    mpm_real n[3];
    if (mpm_collider_phi(&r[k].pose, x, n) <= 0)
      for (int d = 0; d < 3; ++d) a[d] += r[k].acceleration[d];
  }
}

#endif
