/* grid_update.h - the grid velocity update (Gao sec. 3.2 steps 3-4): v^n = (m v)/m,
 * v^{n+1} = v^n + dt (f / m + g), then colliders and domain walls. Works on any grid through
 * node ranges, so the sparse and the dense grid share it. */
#ifndef MPM_SOLVER_GRID_UPDATE_H
#define MPM_SOLVER_GRID_UPDATE_H

#include "collide/collider.h"
#include "grid/dense_grid.h"
#include "grid/sparse_grid.h"

typedef struct mpm_grid_update_ctx {
  mpm_real dt;
  /* 1 when P2G already added dt * force to the momentum (sparse grid with APIC): the force
     channels are then not read (they hold the last step's velocities, not zeros) */
  int force_in_momentum;
  mpm_real gravity[3];
  mpm_real origin[3], dx;
  /* domain walls: a node whose index along axis d is < wall_lo[d] or > wall_hi[d] is in the
     wall band and gets the wall rule with the inward normal */
  int wall_lo[3], wall_hi[3];
  mpm_boundary_rule wall_rule;
  mpm_real wall_friction;
  int collider_count;
  const mpm_collider_pose *poses; /* at the end of the step */
} mpm_grid_update_ctx;

void mpm_grid_update_sparse(const mpm_grid_update_ctx *u, mpm_sparse_grid *g);
void mpm_grid_update_dense(const mpm_grid_update_ctx *u, mpm_dense_grid *g);

/* The update of one node; exposed for tests. idx = global node index. */
void mpm_grid_update_node(const mpm_grid_update_ctx *u, const int idx[3], mpm_real *m,
                          mpm_real mv[3], mpm_real f[3]);

#endif
