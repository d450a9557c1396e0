/* refinement.h - the cells of Gao et al.'s non-graded multi-level grid (sec. 5) and the
 * constrained basis N_i that lives on them (sec. 5.2, eqs. 11-14).
 *
 * Levels 0 .. levels-1 share one origin; level L has spacing dx_L = dx_0 / 2^L, so node idx of
 * level L is node 2 idx of level L + 1. Every level-0 cell is a leaf unless it is refined into
 * its 8 children, and so on down: the leaves tile space, and a leaf may border leaves any number
 * of levels finer (non-graded). A cell is refined only when its parent is.
 *
 * Nodes. A node of any level is *real* when it is a corner of every leaf around it; otherwise
 * (a T-junction on a coarser leaf's face or edge, or a "refined node" inside a coarser leaf, Gao
 * sec. 6.1) it is constrained: its value is the trilinear interpolation of the corners of the
 * coarsest leaf around it, corners that may be constrained in turn. Resolving the chain gives
 * each node a row of weights over real nodes - the embedding row E_gi of Gao eq. 15 - and the
 * basis N_i(x) of a real node i is the trilinear interpolation of those rows over the leaf that
 * holds x. N_i is C0 (octree faces and edges are dyadic, so two leaves sharing a face agree on
 * it), non-negative, a partition of unity and reproduces linear functions (tests/
 * test_refinement.c checks each on random non-graded refinements).
 *
 * A real node's identity does not depend on the level it is seen from: it is *owned* by the
 * level k of the coarsest leaf around it and named (k, index at level k). The same node seen at
 * a finer level is a duplicate (a "ghost" collocated with a real node) whose row is (k, 1).
 *
 * Positions inside the structure are integers of the finest level's lattice, so every weight
 * is a dyadic rational and computed exactly. */
#ifndef MPM_ADAPTIVE_REFINEMENT_H
#define MPM_ADAPTIVE_REFINEMENT_H

#include "mpm/mpm.h"
#include "core/real.h"

#include <stddef.h>
#include <stdint.h>

#define MPM_LEVELS_MAX 6
/* Level coordinates (cells or nodes) must lie in [-2^20, 2^20) at the finest level. */
#define MPM_REFINEMENT_COORD_BITS 21
/* Most real nodes one constrained node can depend on (a chain through every level). */
#define MPM_ROW_MAX 64

/* A set of cells of one level, open addressing on packed coordinates. */
typedef struct mpm_cell_set {
  uint64_t *keys;
  size_t size, count; /* size: a power of two, or 0 */
  /* optional dense index of the cells lo .. lo + n (a bit per cell), which lookups inside that
   * box use instead of the hash: a step asks the tree several times per particle */
  uint64_t *bits;
  int32_t lo[3], n[3];
} mpm_cell_set;

typedef struct mpm_refinement {
  int levels; /* >= 1 */
  mpm_real origin[3];
  mpm_real dx0;
  mpm_cell_set refined[MPM_LEVELS_MAX]; /* level L's cells that have children (L < levels - 1) */
  uint64_t version; /* counts the refinements: caches of rows are valid while it stays */
} mpm_refinement;

/* A real node (level, idx) and a weight: one entry of an embedding row or of a basis list. */
typedef struct mpm_row_term {
  int32_t idx[3];
  int32_t level;
  double w;
} mpm_row_term;

/* One uniform level (nothing refined). levels in 1..MPM_LEVELS_MAX. */
void mpm_refinement_init(mpm_refinement *r, int levels, const mpm_real origin[3], mpm_real dx0);
void mpm_refinement_free(mpm_refinement *r);

static inline mpm_real mpm_refinement_dx(const mpm_refinement *r, int level) {
  return r->dx0 / (mpm_real)(1 << level);
}

/* 1 when a and b refine the same cells (the same tree up to its version), else 0. */
int mpm_refinement_same_cells(const mpm_refinement *a, const mpm_refinement *b);

/* Refine cell `cell` of `level` (0 <= level < levels - 1) and every ancestor. MPM_OK;
 * MPM_ERR_NOMEM when out of memory; MPM_ERR_INVALID when the level is out of range or the cell
 * lies outside the coordinate range. */
mpm_status mpm_refinement_refine(mpm_refinement *r, int level, const int32_t cell[3]);
int mpm_refinement_is_refined(const mpm_refinement *r, int level, const int32_t cell[3]);

/* The level of the leaf holding the finest-level cell c. */
int mpm_refinement_leaf_level(const mpm_refinement *r, const int32_t c[3]);

/* The leaf holding point x (m): its level, and its cell index at that level. */
int mpm_refinement_leaf_at(const mpm_refinement *r, const mpm_real x[3], int32_t cell[3]);

/* The finest level of the leaves that meet the box [lo, hi] (m; closed, so a leaf touching the
 * box counts: choosing a finer level than needed costs a wider stencil, never accuracy), with
 * one exception kept from the first version, which descended from the level-0 cells holding the
 * box: leaves in a level-0 cell below the one holding the box's low corner (on any axis) do not
 * count where they only touch the box's low face (tests/test_refinement.c,
 * test_finest_level_in_against_leaves). */
int mpm_refinement_finest_level_in(const mpm_refinement *r, const mpm_real lo[3],
                                   const mpm_real hi[3]);

/* The finest level of the leaves that overlap the open box (a, b), given in level-0 cell units
 * (a = (lo - origin) / dx0 in double), with some volume: a leaf touching the box at a face, edge or
 * corner does not count. The particles' transfer level (adaptive/step.c): the box's weights
 * are the basis's averages over the box, which leaves meeting it in a set of no volume do not
 * change. */
int mpm_refinement_finest_level_overlapping(const mpm_refinement *r, const double a[3],
                                            const double b[3]);

/* The coarsest level of the leaves that meet the box [lo, hi] (closed, as above). */
int mpm_refinement_coarsest_level_in(const mpm_refinement *r, const mpm_real lo[3],
                                     const mpm_real hi[3]);

/* Whether node idx of `level` is real; its owner (level, index) in *owner when it is. */
int mpm_refinement_node_is_real(const mpm_refinement *r, int level, const int32_t idx[3],
                                mpm_row_term *owner);

/* The embedding row of node idx of `level`: real nodes and weights (summing to one, all > 0),
 * at most `max` of them. Its count, or -1 when more than max would be needed. */
int mpm_refinement_node_row(const mpm_refinement *r, int level, const int32_t idx[3],
                            mpm_row_term *row, int max);

/* The real nodes i with N_i(x) > 0 and their values N_i(x). Count, or -1 past max. */
int mpm_refinement_basis_at(const mpm_refinement *r, const mpm_real x[3], mpm_row_term *terms,
                            int max);

/* Call visit(ctx, level, cell) for every leaf of level 1 and finer (the children of refined
 * cells that are not refined themselves), level by level in the cell sets' order. The leaves of
 * level 0 (the rest of space) are not visited. Returns their count. */
size_t mpm_refinement_fine_leaves(const mpm_refinement *r,
                                  void (*visit)(void *ctx, int level, const int32_t cell[3]),
                                  void *ctx);

/* Call visit(ctx, level, cell) for every refined cell (a cell with children), coarsest level
 * first, in the cell sets' order. */
void mpm_refinement_refined_cells(const mpm_refinement *r,
                                  void (*visit)(void *ctx, int level, const int32_t cell[3]),
                                  void *ctx);

/* Index the refined cells of the levels densely over the level-0 cells lo0 .. lo0 + n0 (each
 * level's box scaled to its cells), from the coarsest level down while the bitmaps stay within
 * max_bytes together. Lookups give the same answers, faster. MPM_OK, or MPM_ERR_NOMEM when out of
 * memory. */
mpm_status mpm_refinement_index_dense(mpm_refinement *r, const int32_t lo0[3], const int32_t n0[3],
                                      size_t max_bytes);

size_t mpm_refinement_bytes(const mpm_refinement *r);

#endif
