/* adaptive.h - the step on Gao et al.'s multi-level grid (sec. 6.1; docs/adaptive-grid.md).
 *
 * Setup (adaptive/setup.c): the scene's refinement rules (domain.refine) refine the tree, and
 * each body is sampled leaf by leaf at the spacing of the leaf's level, so a particle's type (its
 * `level`) is the level of the leaf it was born in (Gao sec. 7.1).
 *
 * Each step (adaptive/step.c):
 *   sort    every particle's box (side L_p: its body's particle spacing at its type) finds the
 *           finest level its leaves meet (mpm_refinement_finest_level_in); the pair (level, L_p)
 *           is a *transfer grid*, one sparse grid with one uGIMP kernel (a level's own grid, or
 *           an extra grid at that level whose slots are all ghosts). Particles are kept grouped
 *           by transfer grid (contiguous ranges, regrouped when one changes grid), each range is
 *           sorted into its grid, the stencils' nodes are marked used and the ghosts' parents
 *           activated (mpm_adaptive_grid_close)
 *   layout  every transfer grid is a segment of the DOF set; the ghost rows are built
 *   p2g     each range scatters on its grid with the lane kernels as on the uniform grid, then
 *           the ghosts' mass, momentum (and force) go to their real parents (Gao eq. 15)
 *   update  the explicit update of the DOF set (ghosts hold no mass: they are skipped)
 *   g2p     the ghosts take their parents' velocities, then each range gathers from its grid
 * One level and one particle type: one transfer grid without ghosts, the uniform step bitwise.
 *
 * APIC carries the ghosts' moments besides (adaptive/apic.c), so that angular momentum is
 * conserved across level changes. The implicit step solves for every level's real nodes
 * (solver/implicit.h, mpm_implicit_part). Not yet: particle domains on levels (refused by the
 * scene parser). */
#ifndef MPM_ADAPTIVE_ADAPTIVE_H
#define MPM_ADAPTIVE_ADAPTIVE_H

#include "adaptive/grid.h"
#include "collide/collider.h"
#include "core/arena.h"
#include "grid/dofs.h"
#include "scene/scene.h"
#include "transfer/transfer.h"

/* What the multi-level grid reads and changes of the simulation that holds it, bound once when
 * the grid is made (sim/sim.c) and valid while it lives: this folder never sees the simulation
 * object, so any holder that fills these (a rank of a distributed run) can step on levels. */
typedef struct mpm_adaptive_host {
  const mpm_scene *scene;   /* the rules, the bodies, the solver's keys */
  mpm_particles *particles; /* the material points: the sort moves them, resampling makes them */
  mpm_dofs *dofs;           /* the step's unknowns, laid out over the levels */
  mpm_arena *arena;         /* the step's scratch */
  const int64_t *steps;     /* steps taken */
  const double *time;       /* simulated time, s */
  const mpm_real *origin;   /* the domain's lower corner, m, and its level-0 cells per axis */
  const int *cells;
  mpm_collider *const *colliders; /* the scene's colliders (the rules that follow them) */
  const int *material_count;
  const int *reorder_interval; /* the particle order's rule (core/particles.h) */
  uint32_t **iscratch;         /* the permute's per-particle scratch and its capacity */
  size_t *scratch_capacity;
  uint32_t *next_id; /* the id of the next particle a split makes (ids are never reused) */
  mpm_error *error;  /* where the stages leave their errors */
} mpm_adaptive_host;

/* What particle split and merge did since creation (reporting only: not checkpointed). */
typedef struct mpm_resample_figures {
  long long splits, merges;
  double angular_momentum_change[3]; /* what the resampling changed, kg m^2/s */
} mpm_resample_figures;

/* One transfer grid: particles on `level` with box side `box`. */
typedef struct mpm_transfer_grid {
  int level;
  double box; /* L_p, m */
  int G;      /* its sparse grid (mpm_adaptive_grid_at) */
  mpm_kernel kernel;
} mpm_transfer_grid;

typedef struct mpm_adaptive {
  mpm_adaptive_host host;
  mpm_adaptive_grid grid;
  double *body_box; /* per body: L_p of its type-0 particles (its particle spacing), m */
  mpm_transfer_grid tgrid[MPM_TRANSFER_GRIDS_MAX];
  int tgrid_count;
  size_t range[MPM_TRANSFER_GRIDS_MAX + 1]; /* transfer grid t's particles: range[t] .. [t+1) */
  uint8_t *of;                              /* per particle: its transfer grid this step */
  /* per particle: it stays on its transfer grid next step (its block's region holds leaves of
   * the block's level only, mpm_adaptive_grid_block_uniform: a particle moves less than a cell
   * per step), valid for the step numbered stable_step */
  uint8_t *stable;
  /* per (body, type) half its box, and per level met its transfer grid (adaptive/step.c) */
  mpm_real *box_half;
  int8_t *box_tgrid;
  size_t box_half_capacity, box_tgrid_capacity;
  int64_t stable_step;
  uint32_t *perm;
  size_t capacity;
  /* APIC across levels (adaptive/apic.c): per DOF slot its ghost when the ghost's row has
   * several real nodes (written, and read, only where block_multi's bit is set); the particles
   * whose stencils reach such ghosts; the ghosts' moments (9 per ghost interleaved, then 9 planes
   * of ghost_count) and the boundary particles' B corrections */
  int32_t *ghost_of;
  size_t ghost_of_capacity;
  uint64_t *block_multi; /* per block of 64 DOF slots: a bit per slot holding such a ghost */
  size_t block_multi_capacity;
  uint32_t *block_count; /* per owner block of a transfer grid: its boundary cells' counts */
  size_t block_count_capacity;
  uint64_t *stable_cells; /* per owner block of a transfer grid: its stable cells (the sort) */
  size_t stable_cells_capacity;
  /* the boundary particles (those whose stencils reach such ghosts): boundary_count of them.
   * Per occupied cell c of a transfer grid whose stencil reaches such ghosts (a boundary cell),
   * its entries cell_ghost[cell[c] .. cell[c + 1]) (the stencil node and the ghost), and per
   * entry the affine moment its particles bring (9, added by the P2G lanes) */
  size_t boundary_count;
  uint32_t *cell;
  size_t cell_count, cell_capacity;
  mpm_stencil_ghost *cell_ghost;
  size_t cell_ghost_count, cell_ghost_capacity;
  mpm_real *affine;
  size_t affine_capacity;
  /* the lanes' view (transfer.h, mpm_ghost_apic): per cell q of transfer grid t, from
   * cell_map_begin[t] on, its boundary cell c or MPM_NOT_BOUNDARY */
  uint32_t *cell_of;
  size_t cell_of_capacity;
  size_t cell_map_begin[MPM_TRANSFER_GRIDS_MAX];
  /* the same entries by ghost, for the ghosts' sums in parallel: ghost g's are
   * ghost_entry[ghost_start[g] .. ghost_start[g + 1]) in cell order */
  uint32_t *ghost_start, *ghost_entry;
  size_t ghost_start_capacity, ghost_entry_capacity;
  /* the ghosts' moments: 9 per ghost interleaved (G2P), then 9 planes of ghost_count (P2G) */
  mpm_real *moment;
  size_t moment_capacity;
  long long rebuilds;           /* trees made by domain.refine_every since creation */
  long long unchanged_rebuilds; /* of those, the ones equal to the tree in use (kept) */
  double rebuild_seconds;       /* their wall time */
  mpm_resample_figures resample_figures;
  double expected_particles; /* the particles the levels will hold, estimated at setup */
} mpm_adaptive;

/* The multi-level grid of host's scene in *out (set before anything can fail, so that
 * mpm_adaptive_free frees what was made): the tree from the scene's rules (the colliders must
 * exist), the per-body boxes, the transfer grids, the particles expected (checked against the
 * memory). */
mpm_status mpm_adaptive_setup(const mpm_adaptive_host *host, mpm_adaptive **out, mpm_error *err);
void mpm_adaptive_free(mpm_adaptive *a);
/* Sample body b level by level (the host's particles grow; types set). */
mpm_status mpm_adaptive_sample_body(mpm_adaptive *a, int b, mpm_error *err);

/* The stages (sim/step.c calls them for a multi-level grid). */
mpm_status mpm_adaptive_sort(mpm_adaptive *a);
mpm_status mpm_adaptive_layout(mpm_adaptive *a, unsigned fields);
void mpm_adaptive_p2g(mpm_adaptive *a, const mpm_transfer_ctx *tc, int impulse);
mpm_g2p_result mpm_adaptive_g2p(mpm_adaptive *a, const mpm_transfer_ctx *tc);

/* APIC across levels (adaptive/apic.c), for steps with solver.transfer = apic: after the
 * layout, the boundary cells; the lanes' view of transfer grid t (for its P2G and G2P, which do
 * the particles' part: transfer/ghost_apic_lanes.h); before the lanes' P2G, the entries' affine
 * moments cleared; after it, the ghosts' affine moments, then the ghost scatter with them (in place
 * of mpm_adaptive_grid_scatter); before the lanes' G2P (the ghosts' velocities gathered), the
 * ghosts' velocity moments. */
mpm_status mpm_adaptive_apic_prepare(mpm_adaptive *a);
mpm_ghost_apic mpm_adaptive_apic_view(mpm_adaptive *a, int t);
void mpm_adaptive_apic_before_p2g(mpm_adaptive *a);
void mpm_adaptive_apic_after_p2g(mpm_adaptive *a);
void mpm_adaptive_apic_scatter(mpm_adaptive *a, int impulse);
void mpm_adaptive_apic_g2p_before(mpm_adaptive *a);

/* The refinement rules (adaptive/rules.c) applied to tree r: at setup (rebuild 0: box,
 * collider at t = 0, body from its samples) or at a rebuild (box, collider at the time, surface,
 * types and strain from the particles). */
mpm_status mpm_adaptive_apply_rules(mpm_adaptive *a, mpm_refinement *r, int rebuild,
                                    mpm_error *err);
/* The dense index of tree r over the domain. MPM_OK, or MPM_ERR_NOMEM when out of memory. */
mpm_status mpm_adaptive_index_tree(mpm_adaptive *a, mpm_refinement *r);
/* Between steps, every domain.refine_every steps: a new tree from the rules. */
mpm_status mpm_adaptive_refine(mpm_adaptive *a);
/* The refined cells (level, i, j, k), for checkpoints: a new array (mpm_free it), NULL when out of
 * memory or on a uniform grid; and a tree from them in place of the current one. */
int32_t (*mpm_adaptive_tree_cells(const mpm_adaptive *a, size_t *count))[4];
mpm_status mpm_adaptive_set_tree(mpm_adaptive *a, const int32_t (*cells)[4], size_t count,
                                 mpm_error *err);

/* Particle split and merge at the end of a step (adaptive/resample.c, Gao sec. 7.2), every
 * domain.resample.every steps; nothing without domain.resample. */
mpm_status mpm_adaptive_resample(mpm_adaptive *a);

/* The finest spacing in use (the CFL step's dx). */
double mpm_adaptive_finest_dx(const mpm_adaptive *a);

#endif
