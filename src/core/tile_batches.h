/* tile_batches.h - a Gauss-Seidel pass over items that touch what lies near them, run in
 * parallel with a result that does not depend on the thread count.
 *
 * Each item is bound to a cube of a lattice of tiles (its tile coordinates, given). The tiles
 * are coloured by the parity of their coordinates (8 colours): two tiles of one colour are a
 * whole tile apart along some axis, so when every item touches only what lies within half a
 * tile's side of its own tile (the caller sizes the tiles so), the tiles of one colour touch
 * disjoint things. A pass takes the colours in turn; the tiles of a colour may run on any
 * threads at once, each tile's items in their given order by one thread. The order of the whole
 * pass (colour, then tile, then item) is set by the items alone.
 *
 * Used by the contacts of enriched corners (domain/enrich_contact.c: a corner and the grid nodes
 * of its stencil; domain/enrich_surface_contact.c: a corner and the corners of a face near it),
 * whose impulses change what the next impulse reads. */
#ifndef MPM_CORE_TILE_BATCHES_H
#define MPM_CORE_TILE_BATCHES_H

#include "mpm/mpm.h"
#include "core/arena.h"

#include <stddef.h>
#include <stdint.h>

#define MPM_TILE_COLOURS 8

typedef struct mpm_tile_batches {
  uint32_t *item;     /* the items (their indices) in the pass's order */
  size_t *tile_start; /* tile t's items: item[tile_start[t] .. tile_start[t + 1]) */
  size_t tiles;       /* nonempty tiles */
  size_t colour_start[MPM_TILE_COLOURS + 1]; /* colour k's tiles: colour_start[k] .. [k + 1] */
} mpm_tile_batches;

/* Batches for n items, item i in the tile of coordinates tile[i], scratch
 * from `scratch` (valid until its reset). MPM_OK, or MPM_ERR_NOMEM. */
mpm_status mpm_tile_batches_build(size_t n, const int32_t (*tile)[3], mpm_arena *scratch,
                                  mpm_tile_batches *out);

#endif
