/* step_ctx.h - what the stages of one step share (step.c), and what the grid stacks' stages
 * (grid_stack.h) read and fill of it. Private to src/sim/. */
#ifndef MPM_SIM_STEP_CTX_H
#define MPM_SIM_STEP_CTX_H

#include "solver/explicit_update.h"
#include "solver/implicit.h"
#include "transfer/transfer.h"

typedef struct mpm_step_ctx {
  double dt;
  mpm_transfer_ctx tc;  /* standard particles */
  mpm_transfer_ctx dtc; /* domain corners: the corner kernel */
  mpm_explicit_update update;
  mpm_p2g_output p2g_output;
  int domains;         /* the step has active domain particles */
  mpm_grid_values val; /* the grid level's values (a uniform stack) */
  mpm_grid_values all; /* the values of every DOF */
  mpm_g2p_result r;
  const mpm_particles *bad_set; /* the set r.bad_particle indexes */
  mpm_implicit_result solve;    /* implicit steps */
} mpm_step_ctx;

#endif
