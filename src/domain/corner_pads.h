/* corner_pads.h - the corner <-> grid half of the domain transfers (domain_transfer.h) on the
 * sparse grid, applied from the corners' positions instead of the embedding's stored rows.
 *
 * Why: the rows of the corners' embedding (grid/embedding.h) hold, for the linear hat, 8
 * entries of weight, column and 3 APIC factors: 160 bytes a corner, written by P2G and read by
 * the scatter and again by G2P, in the order of the scatter's groups (base blocks), which is
 * not the corners' order. At 200k corners that is ~100 MB of memory traffic a step that does
 * not stay in cache, and the scatter waited on it: the domain step was 6x the material-point
 * step (issue 13). The corners of one group share a base block, so their stencils reach only
 * that block and its 7 forward neighbours: the group's nodes are read into a small pad, every
 * corner's stencil is evaluated from its position and accumulated there, lane by lane, as the
 * material points' transfers do (transfer/p2g.c), and the pad's lanes are summed and added to
 * the nodes once.
 *
 * The corners of a group are sorted by the cell of their base node, so that those of one cell
 * share every node and are taken as SIMD lanes (transfer/transfer_lanes.h's lane stencils),
 * and their values are laid out in that order (P2G writes them there), so that a batch loads
 * with vector loads. The step numbers the corners in this order now and then
 * (mpm_domain_order_corners), so that the values kept by corner (positions, velocities, B_a) move
 * with vector loads and stores too. The colours run in turn and each group adds its pad to the
 * nodes once: deterministic for any number of threads. The terms are those of the rows, summed in
 * another order (lanes, then nodes): equal to rounding (tests/test_domain.c compares them, and pads
 * against rows on the dense grid in test_domain_sim). The rows are still built where they are
 * applied as a matrix: the implicit step's Hessian (domain_hessian.c), and the dense grid. */
#ifndef MPM_DOMAIN_CORNER_PADS_H
#define MPM_DOMAIN_CORNER_PADS_H

#include "mpm/mpm.h"
#include "core/arena.h"
#include "grid/grid.h"
#include "grid/scatter_schedule.h"
#include "interp/kernel.h"

struct mpm_domain_set;

#define MPM_CORNER_PADS_NONE UINT32_MAX /* the position of an unused corner */

typedef struct mpm_corner_pads {
  int on;                        /* this step's corner transfers go through the pads */
  mpm_scatter_schedule schedule; /* groups of corners by base block (memory kept across steps) */
  int32_t *block;                /* step scratch: per corner, its base block (its key), or < 0 */
  int32_t (*pad)[8];             /* step scratch: per group, the 8 blocks of its pad */
  int32_t (*org)[3];             /* step scratch: per group, its base block's first node */
  uint8_t *cell;                 /* step scratch: per corner, its base node's cell in its block */
  /* step scratch: the pads' order of the corners, position k -> corner row[k]: the groups'
   * corners (each group's by cell), then the enriched ones; P2G's corner values are laid out
   * in it (so that a batch of corners is contiguous) */
  uint32_t *row;
  uint32_t *pos;                    /* per corner: its position, or MPM_CORNER_PADS_NONE */
  uint32_t *in_space;               /* the groups in the order of their positions */
  size_t positions, grid_positions; /* all; of the groups (the enriched follow) */
  size_t breaks; /* positions k of the groups whose corner is not row[k - 1] + 1 */
  uint32_t (*cell_start)[MPM_BLOCK_NODES + 1]; /* per group: row[] of each cell (absolute) */
  uint32_t grid_dofs;   /* the DOF of the level's node 0 (set by P2G: the layout follows) */
  uint32_t corner_dofs; /* the DOF of enriched corner 0 (likewise) */
  mpm_real origin[3];   /* the level's node (0, 0, 0), m */
} mpm_corner_pads;

void mpm_corner_pads_free(mpm_corner_pads *P);

/* Group the used corners of s by the base block of their stencils on sparse level g (enriched
 * corners are rows of their own: their DOFs), with kernel k; scratch from the step's arena.
 * MPM_OK; MPM_ERR_NOMEM when out of memory; MPM_ERR_INVALID when a block is missing (cannot
 * happen after mpm_domain_activate). */
mpm_status mpm_corner_pads_plan(mpm_corner_pads *P, const struct mpm_domain_set *s,
                                const mpm_grid *g, const mpm_kernel *k, mpm_arena *scratch);

/* values[f][DOF] += omega_i(x_a) carrier[f][k] for the 7 fields (mass, momentum, force) of
 * corner a = P->row[k], and with apic the affine moment sum_j a_j (m_a B_a)[3k + j] added to
 * values[1 + k] (momentum), m_a = carrier[0] and B_a = s->cB by corner, as
 * mpm_embedding_scatter_moments does with the rows. Each thread's pad of lanes comes from
 * scratch: MPM_OK, or MPM_ERR_NOMEM when out of memory. */
mpm_status mpm_corner_pads_scatter(const mpm_corner_pads *P, const struct mpm_domain_set *s,
                                   const mpm_kernel *k, const mpm_real *const carrier[7], int apic,
                                   mpm_real *const values[7], mpm_arena *scratch);

/* The grid's velocities at the corners, and the corners moved with them (G2P's corner half):
 * for every used corner v^g_a = sum_i omega_i(x_a) v_i (into s->corner_pack), with apic s->cB =
 * (sum_i v_i a_i^T) D_a (enriched corners: from their DOFs, B_a = 0), and the corner moved by
 * mpm_corner_move with the FLIP increment sum_i omega_i(x_a) (v_i - v0_i). Returns the largest
 * |v^g|^2. */
struct mpm_corner_motion;
mpm_real mpm_corner_pads_gather(const mpm_corner_pads *P, struct mpm_domain_set *s,
                                const mpm_kernel *k, const mpm_real *const v[3],
                                const mpm_real *const v0[3],
                                const struct mpm_corner_motion *motion);

#endif
