/* grid_stack.h - the grids a simulation transfers on, behind one table of operations.
 *
 * A grid stack is chosen once, when the simulation is made: one uniform level (sparse or dense,
 * with Zhu's particle domains and their enriched corners) is a stack of one (grid_uniform.c);
 * Gao's multi-level grid is a stack of its levels and transfer grids (grid_levels.c, over
 * src/adaptive/). The step (step.c), the frame loop, the outputs and the checkpoints ask the
 * table and never which stack they hold, as the step asks mpm_model for a material and
 * mpm_grid_ops for a level; a stack of another shape (a rank's part of a distributed grid) is
 * one more table. */
#ifndef MPM_SIM_GRID_STACK_H
#define MPM_SIM_GRID_STACK_H

#include "core/error.h"
#include "io/checkpoint.h"
#include "scene/scene.h"
#include "sim/step_ctx.h"

#include <mpm/mpm.h>

typedef struct mpm_sim mpm_sim;

typedef struct mpm_grid_stack_ops {
  const char *name;
  /* Made after the simulation's materials, colliders and level-0 geometry, before any body
   * is sampled; destroy frees what make made (also after a failed make). */
  mpm_status (*make)(mpm_sim *sim, mpm_error *err);
  void (*destroy)(mpm_sim *sim);
  /* Sample body b into the simulation's particles (ids and plastic state are the caller's). */
  mpm_status (*sample_body)(mpm_sim *sim, int b, mpm_error *err);
  /* The finest spacing in use (the CFL step's dx), m. */
  double (*finest_dx)(const mpm_sim *sim);

  /* The step's stages (step.c, in this order): sort the particles into the grids with the
   * step's kernels and activate what their stencils reach; lay the DOF set out over the grids'
   * nodes (and the enriched corners) and clear what P2G sums (c->all: every DOF's values);
   * particles -> grid; the implicit system's parts (the material points by grid); grid ->
   * particles (c->r, c->bad_set). */
  mpm_status (*sort)(mpm_sim *sim, mpm_step_ctx *c);
  mpm_status (*layout)(mpm_sim *sim, mpm_step_ctx *c, unsigned fields);
  mpm_status (*p2g)(mpm_sim *sim, mpm_step_ctx *c);
  void (*implicit_parts)(mpm_sim *sim, mpm_implicit *s);
  mpm_status (*g2p)(mpm_sim *sim, mpm_step_ctx *c);

  /* Between steps (frame.c, before the guard saves the state): the grid made anew from the
   * material, and the particles resampled to it. */
  mpm_status (*refine)(mpm_sim *sim);
  mpm_status (*resample)(mpm_sim *sim);
  /* An edit moved the particles: what the sort kept from the last step no longer holds. */
  void (*particles_moved)(mpm_sim *sim);
  /* mpm_sim_add_body is supported (the rules of a multi-level grid are the scene's). */
  int adds_bodies;

  /* The grid's own state in a checkpoint (a tree the run rebuilt), written and read back. */
  mpm_status (*save)(mpm_sim *sim, mpm_checkpoint *c);
  mpm_status (*load)(mpm_sim *sim, const mpm_checkpoint *c);
  /* The grid's files of a frame (the multi-level grid's leaves: at frame 0, and every frame
   * while it moves), and the per-frame part run.pvd lists for them (NULL: none). */
  mpm_status (*write_frame)(mpm_sim *sim, int frame);
  const char *(*frame_part)(const mpm_sim *sim);
  /* Its figures in mpm_sim_get_info's answer. */
  void (*info)(const mpm_sim *sim, mpm_sim_info *in);
} mpm_grid_stack_ops;

/* The stack a scene asks for (scene.levels > 0: the multi-level grid). */
const mpm_grid_stack_ops *mpm_grid_stack_for(const mpm_scene *scene);

extern const mpm_grid_stack_ops mpm_grid_uniform;
extern const mpm_grid_stack_ops mpm_grid_levels;

#endif
