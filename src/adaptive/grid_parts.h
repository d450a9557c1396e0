/* grid_parts.h - what adaptive/grid.c and adaptive/close.c share of the multi-level
 * grid's inside (not for other modules: adaptive/grid.h is the interface): the transfer grids'
 * numbering, node and block coordinates, and the used-slot marks. */
#ifndef MPM_ADAPTIVE_GRID_PARTS_H
#define MPM_ADAPTIVE_GRID_PARTS_H

#include "adaptive/grid.h"

/* Finest-lattice units per index of `level`, as a shift. */
static inline int fine_shift(const mpm_refinement *r, int level) {
  return r->levels - 1 - level;
}

static inline int32_t block_of(int32_t n) {
  return n >> MPM_BLOCK_BITS;
} /* arithmetic: floor */

static inline int level_of(const mpm_adaptive_grid *g, int G) {
  return G < MPM_LEVELS_MAX ? G : g->extra_level[G - MPM_LEVELS_MAX];
}
static inline mpm_grid *grid_of(mpm_adaptive_grid *g, int G) {
  return G < MPM_LEVELS_MAX ? &g->level[G] : &g->extra[G - MPM_LEVELS_MAX];
}
/* The transfer grid after G in use (the levels, then the extra grids), or -1. */
static inline int next_grid(const mpm_adaptive_grid *g, int G) {
  const int n = g->tree.levels;
  if (G < n - 1) return G + 1;
  if (G < MPM_LEVELS_MAX) return g->extra_count ? MPM_LEVELS_MAX : -1;
  return G + 1 < MPM_LEVELS_MAX + g->extra_count ? G + 1 : -1;
}
#define FOR_GRIDS(g, G) for (int G = 0; G >= 0; G = next_grid(g, G))

static inline int local_of(const int32_t idx[3]) {
  return ((idx[0] & 3) << 4) | ((idx[1] & 3) << 2) | (idx[2] & 3);
}

/* Node idx of block b's slot `local`. */
static inline void node_of(const mpm_sparse_grid *sg, size_t b, int local, int32_t idx[3]) {
  const int32_t *c = sg->coord[b];
  idx[0] = c[0] * MPM_BLOCK + ((local >> 4) & 3);
  idx[1] = c[1] * MPM_BLOCK + ((local >> 2) & 3);
  idx[2] = c[2] * MPM_BLOCK + (local & 3);
}

/* The masks of transfer grid G cover its blocks (new blocks start unused). MPM_OK, or
 * MPM_ERR_NOMEM when out of memory. */
mpm_status mpm_adaptive_ensure_masks(mpm_adaptive_grid *g, int G);

/* Activate node idx of transfer grid G and mark it used. MPM_OK, or MPM_ERR_NOMEM when out of
 * memory. */
mpm_status mpm_adaptive_mark(mpm_adaptive_grid *g, int G, const int32_t idx[3]);

/* Free the row cache (adaptive/close.c). */
void mpm_adaptive_rows_free(struct mpm_row_cache *c);

#endif
