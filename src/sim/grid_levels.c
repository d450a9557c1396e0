/* grid_levels.c - the grid stack of Gao et al.'s multi-level grid (grid_stack.h): the levels and
 * transfer grids of src/adaptive/, bound to the simulation through their host (the particles,
 * the DOF set, the step's scratch and clock). Particle domains are not on levels (the scene
 * parser refuses them), so the step's domain parts never run on this stack. */
#include "sim/grid_stack.h"

#include "adaptive/adaptive.h"
#include "adaptive/cells_vtu.h"
#include "core/alloc.h"
#include "sim/sim.h"

#include <stdio.h>

static mpm_status make(mpm_sim *sim, mpm_error *err) {
  const mpm_adaptive_host host = {.scene = &sim->scene,
                                  .particles = &sim->particles,
                                  .dofs = &sim->dofs,
                                  .arena = &sim->step_arena,
                                  .steps = &sim->steps,
                                  .time = &sim->time,
                                  .origin = sim->origin,
                                  .cells = sim->cells,
                                  .colliders = &sim->colliders,
                                  .material_count = &sim->material_count,
                                  .reorder_interval = &sim->reorder_interval,
                                  .iscratch = &sim->iscratch,
                                  .scratch_capacity = &sim->scratch_capacity,
                                  .next_id = &sim->next_id,
                                  .error = &sim->error};
  const mpm_status st = mpm_adaptive_setup(&host, &sim->adaptive, err);
  if (st == MPM_OK) sim->expected_particles = sim->adaptive->expected_particles;
  return st;
}

static void destroy(mpm_sim *sim) {
  mpm_adaptive_free(sim->adaptive);
  sim->adaptive = NULL;
}

static mpm_status sample_body(mpm_sim *sim, int b, mpm_error *err) {
  return mpm_adaptive_sample_body(sim->adaptive, b, err);
}

static double finest_dx(const mpm_sim *sim) {
  return mpm_adaptive_finest_dx(sim->adaptive);
}

static mpm_status sort(mpm_sim *sim, mpm_step_ctx *c) {
  (void)c;
  return mpm_adaptive_sort(sim->adaptive);
}

static mpm_status layout(mpm_sim *sim, mpm_step_ctx *c, unsigned fields) {
  const mpm_status st = mpm_adaptive_layout(sim->adaptive, fields);
  c->all = mpm_dofs_values(&sim->dofs);
  return st;
}

static mpm_status p2g(mpm_sim *sim, mpm_step_ctx *c) {
  mpm_adaptive_p2g(sim->adaptive, &c->tc, c->p2g_output == MPM_P2G_IMPULSE);
  return MPM_OK;
}

/* The material points by transfer grid, the ghosts' rows (solver/implicit.h). */
static void implicit_parts(mpm_sim *sim, mpm_implicit *s) {
  mpm_adaptive *a = sim->adaptive;
  s->grid = NULL;
  for (int t = 0; t < a->tgrid_count; ++t)
    s->part[t] =
        (mpm_implicit_part){mpm_adaptive_grid_at(&a->grid, a->tgrid[t].G), a->tgrid[t].kernel,
                            a->range[t], a->range[t + 1] - a->range[t]};
  s->part_count = a->tgrid_count;
  s->levels = a->grid.tree.levels > 1 ? &a->grid : NULL;
}

static mpm_status g2p(mpm_sim *sim, mpm_step_ctx *c) {
  c->r = mpm_adaptive_g2p(sim->adaptive, &c->tc);
  c->bad_set = &sim->particles;
  return MPM_OK;
}

static mpm_status refine(mpm_sim *sim) {
  return mpm_adaptive_refine(sim->adaptive);
}

static mpm_status resample(mpm_sim *sim) {
  return mpm_adaptive_resample(sim->adaptive);
}

/* The grid keeps a particle's transfer grid while its block stays inside one level's region,
 * which a step's motion cannot leave unseen but a jump can: ask again. */
static void particles_moved(mpm_sim *sim) {
  sim->adaptive->stable_step = -1;
}

/* A tree rebuilt during the run is state: the rules made it from an earlier step's material. */
static mpm_status save(mpm_sim *sim, mpm_checkpoint *c) {
  if (sim->scene.refine_every <= 0) return MPM_OK;
  size_t count = 0;
  int32_t(*cells)[4] = mpm_adaptive_tree_cells(sim->adaptive, &count);
  if (!cells)
    return mpm_error_set(&sim->error, MPM_ERR_NOMEM, "out of memory for the refined cells");
  c->tree_count = count;
  for (int k = 0; k < 4; ++k) {
    c->tree[k] = mpm_alloc((count + 1) * sizeof(int32_t));
    for (size_t i = 0; c->tree[k] && i < count; ++i) c->tree[k][i] = cells[i][k];
  }
  mpm_free(cells);
  if (!c->tree[0] || !c->tree[1] || !c->tree[2] || !c->tree[3]) {
    for (int k = 0; k < 4; ++k) {
      mpm_free(c->tree[k]);
      c->tree[k] = NULL;
    }
    return mpm_error_set(&sim->error, MPM_ERR_NOMEM, "out of memory for the refined cells");
  }
  return MPM_OK;
}

static mpm_status load(mpm_sim *sim, const mpm_checkpoint *c) {
  if (sim->scene.refine_every <= 0) return MPM_OK;
  int32_t(*cells)[4] = mpm_alloc((c->tree_count + 1) * sizeof *cells);
  if (!cells) return mpm_error_set(&sim->error, MPM_ERR_NOMEM, "out of memory for the tree");
  for (size_t i = 0; i < c->tree_count; ++i)
    for (int k = 0; k < 4; ++k) cells[i][k] = c->tree[k][i];
  const mpm_status st = mpm_adaptive_set_tree(sim->adaptive, (const int32_t(*)[4])cells,
                                              (size_t)c->tree_count, &sim->error);
  mpm_free(cells);
  return st;
}

static mpm_status write_frame(mpm_sim *sim, int frame) {
  char path[MPM_PATH_MAX + 64];
  if (frame == 0) { /* the refinement at the start */
    snprintf(path, sizeof path, "%s/grid_cells.vtu", sim->out.dir);
    const mpm_status st =
        mpm_write_cells_vtu(path, &sim->adaptive->grid.tree, sim->time, &sim->error);
    if (st != MPM_OK) return st;
  }
  if (sim->scene.refine_every > 0) { /* and as it moves */
    snprintf(path, sizeof path, "%s/grid_cells_%04d.vtu", sim->out.dir, frame);
    return mpm_write_cells_vtu(path, &sim->adaptive->grid.tree, sim->time, &sim->error);
  }
  return MPM_OK;
}

/* a tree per frame while it moves */
static const char *frame_part(const mpm_sim *sim) {
  return sim->scene.refine_every > 0 ? "grid_cells" : NULL;
}

static void info(const mpm_sim *sim, mpm_sim_info *in) {
  const mpm_adaptive *a = sim->adaptive;
  in->refining = sim->scene.refine_every > 0;
  if (in->refining) {
    in->refinements = a->rebuilds;
    in->refinement_seconds = a->rebuild_seconds;
    in->refinements_unchanged = a->unchanged_rebuilds;
  }
  in->splits = a->resample_figures.splits;
  in->merges = a->resample_figures.merges;
  for (int d = 0; d < 3; ++d)
    in->angular_momentum_change[d] = a->resample_figures.angular_momentum_change[d];
}

const mpm_grid_stack_ops mpm_grid_levels = {
    .name = "levels",
    .make = make,
    .destroy = destroy,
    .sample_body = sample_body,
    .finest_dx = finest_dx,
    .sort = sort,
    .layout = layout,
    .p2g = p2g,
    .implicit_parts = implicit_parts,
    .g2p = g2p,
    .refine = refine,
    .resample = resample,
    .particles_moved = particles_moved,
    .adds_bodies = 0,
    .save = save,
    .load = load,
    .write_frame = write_frame,
    .frame_part = frame_part,
    .info = info,
};
