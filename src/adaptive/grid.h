/* grid.h - Gao et al.'s multi-level sparse grid (sec. 6.1, Fig. 10): one sparse level
 * per refinement level, and the ghost slots that carry values between them.
 *
 * Every active node of every level is a slot of the DOF set (level L's slots are DOFs
 * level[L].dof_begin + node). A slot that is a real node owned by its level (adaptive/refinement.h)
 * is an unknown of the step. Every other slot is a *ghost*: a T-junction, a refined node inside
 * a coarser leaf, or a duplicate of a real node owned by another level. A ghost has an embedding
 * row over real slots, its node's row E_gi (Gao eq. 15), fully resolved, so one pass carries
 * every ghost at once.
 *   after P2G   mpm_adaptive_grid_scatter: u_i += sum_g E_gi u_g over ghosts g, then u_g = 0
 *   before G2P  mpm_adaptive_grid_gather:  u_g = sum_i E_gi u_i
 * Particles transfer on the finest level their box meets; what they scatter there reaches the
 * real nodes exactly (the basis is piecewise trilinear on that level; tests/test_refinement.c).
 *
 * Only *used* slots take part: those a particle's stencil reaches, and the parents of used
 * ghosts. A sparse block activates 64 nodes at once, and most of a block's other nodes near a
 * level change are ghosts; giving them rows (and activating their parents, whose blocks hold
 * more ghosts) would spread the active region far beyond the material.
 *
 * Per step: the levels are activated from their particles, their stencils' nodes marked used
 * (mpm_adaptive_grid_activate_box for boxes of nodes does both), mpm_adaptive_grid_close
 * activates and marks every used ghost's parents, the caller lays out the DOF set with the
 * levels, and mpm_adaptive_grid_build_rows fills the ghost rows with DOF indices. */
#ifndef MPM_ADAPTIVE_GRID_H
#define MPM_ADAPTIVE_GRID_H

#include "grid/embedding.h"
#include "grid/grid.h"
#include "adaptive/refinement.h"

/* Transfer grids beside the levels' own: a sparse grid runs one kernel (so the lane kernels
 * serve as they are), and particles whose box differs from the one of their level's grid
 * (another particle type, Gao et al. sec. 7.1) transfer on a grid of their own at that level.
 * Every slot of such a grid is a ghost: a real node of the level is a duplicate whose row is
 * the level grid's slot, with weight 1. */
#define MPM_EXTRA_GRIDS_MAX 58
#define MPM_TRANSFER_GRIDS_MAX (MPM_LEVELS_MAX + MPM_EXTRA_GRIDS_MAX)

typedef struct mpm_adaptive_grid {
  mpm_refinement tree;
  mpm_grid level[MPM_LEVELS_MAX]; /* sparse; level[L].dx = dx_0 / 2^L, one origin */
  mpm_grid extra[MPM_EXTRA_GRIDS_MAX];
  int extra_level[MPM_EXTRA_GRIDS_MAX];
  int extra_count;
  mpm_embedding ghosts; /* row a: ghost a; columns: DOF indices of real slots */
  uint32_t *ghost_slot; /* DOF index of ghost a's own slot */
  size_t ghost_count, ghost_capacity;
  /* per level and block, a bit per node: the slot is used (a particle's stencil reaches it, or
   * it is a ghost's parent), and its ghost row's parents are active (done) */
  uint64_t *used[MPM_TRANSFER_GRIDS_MAX], *done[MPM_TRANSFER_GRIDS_MAX];
  uint64_t *ghost[MPM_TRANSFER_GRIDS_MAX];      /* the used slots close() found to be ghosts */
  size_t mask_capacity[MPM_TRANSFER_GRIDS_MAX]; /* by transfer grid (mpm_adaptive_grid_at) */
  mpm_real *scratch; /* 4 x ghost_capacity values for scatter and gather */
  /* APIC across levels (docs/adaptive-grid.md): per row entry e of ghost g and real slot i,
   * offset[j][e] = E_gi (x_i - x_g)_j; per ghost, spread S_g = sum_i E_gi (x_i - x_g)(x_i - x_g)^T
   * as xx, yy, zz, xy, xz, yz, the 6 of a ghost side by side (spread[6 g ..]) */
  mpm_real *offset[3];
  size_t offset_capacity;
  mpm_real *spread;
  struct { /* the ghosts close() found, for build_rows: per ghost its row's length and its
              slot (grid, block, local index), and the rows */
    uint32_t *len;
    mpm_row_term *terms;
    uint32_t (*where)[3];
    size_t len_cap, terms_cap, where_cap, count, term_count;
  } build;
  /* the ghosts' scatter schedule (build_rows, grid/scatter_schedule.h): per ghost its key, the
   * level-0 block it lies in; per key its colour, the block's parity; a table from blocks to
   * keys */
  struct {
    int32_t *key;
    uint8_t *colour;
    uint64_t *table_block;
    int32_t *table_key;
    size_t key_cap, colour_cap, table_size;
  } schedule;
  /* close()'s scratch per block of the grid it closes: the block's pending slots, and its
   * ghosts and row terms as the parallel pass counts them (UINT32_MAX ghosts: the block takes
   * the serial path), then where its records start in build */
  struct {
    uint64_t *pending;
    uint32_t (*count)[2];
    size_t pending_cap, count_cap;
  } closing;
  /* the nodes' rows, kept from step to step while the tree does not change (tree.version):
   * keyed by the node's position on the finest lattice, the owner level of a real node (row
   * empty) or the row of a constrained one, terms[start .. start + len) */
  struct mpm_row_cache {
    uint64_t version;
    uint64_t *keys;
    uint32_t *entry;
    size_t size, count;
    struct mpm_row_entry {
      int32_t owner; /* real: its owner level; constrained: -1 */
      uint32_t start, len;
    } * entries;
    size_t entry_capacity;
    mpm_row_term *terms;
    size_t term_count, term_capacity;
  } rows;
  /* per (level, block), while the tree stands: whether its region holds leaves of the level only
   * (mpm_adaptive_grid_block_uniform), and its nodes' entries in the row cache (64 ids from
   * ids[ids_at], made when first asked; UINT32_MAX: not looked up yet), so that close() and
   * build_rows() find a node's row through one lookup per block instead of one per node */
  struct mpm_block_flags {
    uint64_t version;
    uint64_t *keys;
    uint8_t *uniform;
    uint64_t *cells;      /* per block, two: its stable cells for reaches 2 and 3 (below) */
    uint8_t *cells_known; /* which of the two were computed since the block's flags were made */
    uint32_t *ids_at;
    size_t size, count;
    uint32_t *ids;
    size_t id_blocks, id_capacity; /* in blocks of MPM_BLOCK_NODES ids */
    uint64_t *owned;               /* per block of ids: its nodes owned by its level (a mask) */
    size_t owned_capacity;
  } blocks;
} mpm_adaptive_grid;

/* levels in 1..MPM_LEVELS_MAX, all cells leaves; refine through g->tree. */
void mpm_adaptive_grid_init(mpm_adaptive_grid *g, int levels, const mpm_real origin[3],
                            mpm_real dx0);
void mpm_adaptive_grid_free(mpm_adaptive_grid *g);

static inline int mpm_adaptive_grid_levels(const mpm_adaptive_grid *g) {
  return g->tree.levels;
}

/* Forget every used mark (a new step: the levels' blocks are activated anew). */
void mpm_adaptive_grid_clear_marks(mpm_adaptive_grid *g);

/* Activate the nodes lo .. hi (inclusive, node indices of `level`) and mark them used. Serial.
 * MPM_OK, or MPM_ERR_NOMEM when out of memory. */
mpm_status mpm_adaptive_grid_activate_box(mpm_adaptive_grid *g, int level, const int32_t lo[3],
                                          const int32_t hi[3]);

/* Transfer grids are numbered G: level L's own grid is G = L; extra grids follow from
 * G = MPM_LEVELS_MAX. A new extra grid at `level` (no nodes yet): its number, or -1 when
 * MPM_EXTRA_GRIDS_MAX are in use. */
int mpm_adaptive_grid_add_extra(mpm_adaptive_grid *g, int level);
/* Transfer grid G, its level, and the one after G (start at 0; -1 after the last). */
mpm_grid *mpm_adaptive_grid_at(mpm_adaptive_grid *g, int G);
int mpm_adaptive_grid_level_of(const mpm_adaptive_grid *g, int G);
int mpm_adaptive_grid_next(const mpm_adaptive_grid *g, int G);

/* After transfer grid G's particles were sorted into it (mpm_sparse_grid_sort, which resets its
 * blocks, so before any other activation of it this step): mark the W^3 stencil of every
 * occupied base node used. MPM_OK, or MPM_ERR_NOMEM when out of memory. */
mpm_status mpm_adaptive_grid_mark_sorted(mpm_adaptive_grid *g, int G, int W);

/* Per cell c of a block (its local index) and pad block o (as mpm_sparse_grid.neighbor: the
 * x, y, z offsets as bits 2, 1, 0), the nodes of o that the W^3 stencil based at c covers, as a
 * mask of local indices. */
void mpm_adaptive_grid_stencil_masks(int W, uint64_t reach[MPM_BLOCK_NODES][8]);

/* Activate and mark the parents of every used ghost, and record the ghosts with their rows for
 * mpm_adaptive_grid_build_rows. Parents are real, so one pass over the used slots suffices.
 * Serial. MPM_OK; MPM_ERR_NOMEM when out of memory; MPM_ERR_INVALID when a row needs more than
 * MPM_ROW_MAX entries. */
mpm_status mpm_adaptive_grid_close(mpm_adaptive_grid *g);

/* After the DOF layout (each level's dof_begin set): the rows of the ghosts the last
 * mpm_adaptive_grid_close found. MPM_OK; MPM_ERR_NOMEM when out of memory; MPM_ERR_INVALID when
 * a ghost's parent is not active (mpm_adaptive_grid_close was not called). */
mpm_status mpm_adaptive_grid_build_rows(mpm_adaptive_grid *g);

/* The slot (DOF index) of node idx of `level`, or -1 when it is not active. */
int64_t mpm_adaptive_grid_slot(const mpm_adaptive_grid *g, int level, const int32_t idx[3]);

/* u_i += sum_g E_gi u_g for the `fields` DOF arrays u[k], then u_g = 0 at every ghost. Serial in
 * row order (deterministic). */
void mpm_adaptive_grid_scatter(mpm_adaptive_grid *g, int fields, mpm_real *const *u);

/* u_i += sum_g E_gi^2 u_g, then u_g = 0 at every ghost: diag(E^T D E) for a diagonal D held at
 * the slots (the implicit step's Jacobi preconditioner, solver/implicit.h). Serial. */
void mpm_adaptive_grid_scatter_squared(mpm_adaptive_grid *g, int fields, mpm_real *const *u);

/* u_g = sum_i E_gi u_i at every ghost, for the `fields` DOF arrays u[k]. */
void mpm_adaptive_grid_gather(mpm_adaptive_grid *g, int fields, mpm_real *const *u);

/* APIC P2G through the ghosts: besides the scatter of the `fields` arrays u (which must hold
 * the momentum in u[1..3]), u[1 + k][i] += sum_j offset[j][e] A[3 k + j][g] for each ghost g,
 * where A_g = sum_p w_gp m_p C_p (row-major, per ghost) is the affine moment the particles left
 * at the ghost: the real nodes get m_p C_p (x_i - x_p) exactly. Ghosts are zeroed after. */
void mpm_adaptive_grid_scatter_apic(mpm_adaptive_grid *g, int fields, mpm_real *const *u,
                                    const mpm_real *const A[9]);

/* APIC G2P through the ghosts: M[3 k + j][g] = sum_i E_gi v_k,i (x_i - x_g)_j for each ghost g
 * (after mpm_adaptive_grid_gather has set v_g), so that B_p = sum_g w_gp (v_g (x_g - x_p)^T +
 * M_g) is the exact sum over real nodes; with the spread S_g, D_p likewise. */
void mpm_adaptive_grid_gather_moments(const mpm_adaptive_grid *g, const mpm_real *const v[3],
                                      mpm_real *const M[9]);

/* Whether the region of block bc (block coordinates) of `level`, widened by
 * MPM_UNIFORM_MARGIN cells on every side, holds leaves of that level only: then every node of the
 * block is a real node owned by the level, and a particle whose stencil's base node lies in the
 * block and moves less than a cell keeps meeting leaves of that level only. Cached while the
 * tree stands. The answer (1 or 0) in *uniform: MPM_OK, or MPM_ERR_NOMEM when out of memory. */
#define MPM_UNIFORM_MARGIN 3
mpm_status mpm_adaptive_grid_block_uniform(mpm_adaptive_grid *g, int level, const int32_t bc[3],
                                           int *uniform);

/* The cells of block bc of `level` (bit (x << 4 | y << 2 | z) for the cell at (x, y, z) in the
 * block) whose neighbours from one below to `reach` above on every axis (reach 2 or 3; none
 * else) are leaves of that level. A particle's box meets, over a step, cells from one below its
 * base cell to a reach above that its kernel sets (adaptive/step.c, mark_stable, says how): then
 * it meets leaves of that level only, and its transfer grid stays. Cell by cell, since near a
 * change of level most of a block's cells are still far enough from it. All of them for a
 * uniform block. Cached while the tree stands. MPM_OK, or MPM_ERR_NOMEM when out of memory. */
mpm_status mpm_adaptive_grid_block_stable_cells(mpm_adaptive_grid *g, int level,
                                                const int32_t bc[3], int reach, uint64_t *mask);

size_t mpm_adaptive_grid_bytes(const mpm_adaptive_grid *g);

#endif
