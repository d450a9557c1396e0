/* partition.h - which rank owns which part of the grid in a distributed run: the level-0 blocks
 * of the sparse grid, in the Morton order of their block coordinates, cut into one contiguous
 * range per rank so that the ranks' weights (particles, and active nodes) are equal within a
 * block's weight.
 *
 * A range is kept as the Morton keys where it starts, not as a list of blocks, so that every
 * block has an owner, also one that no particle has reached yet: a particle belongs to the owner
 * of its block wherever it moves. Morton order keeps each range compact in space (a rank's halo,
 * the blocks of other ranks next to its own, grows with the range's surface, not its volume).
 * Pure functions on the keys: the same keys and weights give the same cut on every rank. */
#ifndef MPM_DIST_PARTITION_H
#define MPM_DIST_PARTITION_H

#include "core/error.h"

#include <stddef.h>
#include <stdint.h>

/* Block coordinates are taken within [-2^20, 2^20) on each axis (a sparse grid of 4-node blocks
 * spans 4 million cells per axis): 21 bits each, interleaved x, y, z from the top. */
#define MPM_MORTON_BITS 21

/* The Morton key of block coordinates c (each within the range above). */
uint64_t mpm_morton_key(const int32_t c[3]);
/* The block coordinates of a key (the inverse). */
void mpm_morton_coords(uint64_t key, int32_t c[3]);

typedef struct mpm_partition {
  int ranks;
  /* rank r owns the keys in [start[r], start[r + 1]); start[0] = 0, start[ranks] = UINT64_MAX
     (no block has that key: the top bit is never set) */
  uint64_t *start;
} mpm_partition;

/* Cut `count` blocks (keys, need not be sorted or distinct: a repeated key's weights add) of
 * nonnegative weights into `ranks` contiguous ranges of Morton order whose weights are as equal
 * as whole blocks allow: the cut before rank r is placed at the block boundary nearest to r / ranks
 * of the total weight. With no weight at all the blocks are cut by count. A rank may own no block
 * (fewer blocks than ranks). MPM_OK; MPM_ERR_INVALID for ranks < 1; MPM_ERR_NOMEM. */
mpm_status mpm_partition_cut(mpm_partition *pt, int ranks, size_t count, const uint64_t *keys,
                             const double *weights);
void mpm_partition_free(mpm_partition *pt);

/* The rank that owns key (binary search over the starts). */
int mpm_partition_owner(const mpm_partition *pt, uint64_t key);

/* The weight of each rank's range (ranks values) for the blocks given (weights NULL: one each,
 * as for the cut), and the imbalance: the largest rank weight over the mean (1 when even, and
 * when there is no weight). */
double mpm_partition_weights(const mpm_partition *pt, size_t count, const uint64_t *keys,
                             const double *weights, double *rank_weight);

#endif
