/* sparse_grid.h - the paged sparse grid: 4x4x4-node blocks found through a hash of block
 * coordinates, activated from particle positions every step and iterated as a list.
 *
 * Why a block hash and not SPGrid's virtual-memory mapping: the hash needs no OS tricks (no
 * reserved terabyte address range, no madvise), works the same on every platform and for
 * domains of any extent, and its cost is one lookup per block per step, not per node, because
 * every transfer works on whole blocks (a particle sees its owner block and 7 neighbours
 * through an 8x8x8 pad). Memory is proportional to the blocks the material touches.
 *
 * Per step: mpm_sparse_grid_sort assigns particles to owner blocks (the block of their
 * stencil's base node), counting-sorts them by (block, material, cell), and activates the forward
 * neighbours; transfers then run block by block. Owner blocks are split into 8 colours by the
 * parity of their coordinates: blocks of one colour are two blocks apart, so their pads never
 * overlap and P2G runs them in parallel with plain stores - no atomics - and a node receives
 * the colours in a fixed order, so results are bitwise the same for any thread count. */
#ifndef MPM_GRID_SPARSE_GRID_H
#define MPM_GRID_SPARSE_GRID_H

#include "mpm/mpm.h"
#include "core/arena.h"
#include "grid/block.h"
#include "interp/kernel.h"
#include "core/particles.h"

#include <stddef.h>
#include <stdint.h>

typedef struct mpm_sparse_grid {
  /* hash table: block key -> block index (open addressing, linear probing) */
  uint64_t *keys;
  int32_t *values;
  size_t table_size; /* power of two */
  /* blocks: [0, owner_count) own particles, the rest are neighbours (halo) */
  size_t block_count, block_capacity, owner_count;
  int32_t (*coord)[3];
  int32_t (*neighbor)[8]; /* per owner block: the 8 blocks its pad covers */
  /* Particles are sorted by (owner block b, material m, base-node cell c in the block): those
   * of one (b, m, c) are perm[cell_start[q] .. cell_start[q+1]) with q = (b*nmat + m)*64 + c.
   * They share their base node, hence their whole stencil of grid nodes, which the transfers
   * exploit by processing them as SIMD lanes (transfer_lanes.h). */
  uint32_t *cell_start;
  size_t cell_capacity;
  int material_count;
  /* owner blocks by colour: color_blocks[color_start[c] .. color_start[c+1]) */
  int32_t *color_blocks;
  size_t color_start[9];
  /* the sorted order (the sort's keys, runs and per-thread histograms are step scratch) */
  uint32_t *perm;
  size_t particle_capacity;
  size_t particle_count; /* particles sorted by the last mpm_sparse_grid_sort */
  /* the point activation's base blocks where they change, each thread's from the index of its
   * first point (kept: a warm step allocates nothing) */
  uint64_t *run_keys;
  size_t run_capacity;
} mpm_sparse_grid;

void mpm_sparse_grid_init(mpm_sparse_grid *g);
void mpm_sparse_grid_free(mpm_sparse_grid *g);

/* Assign particles to owner blocks, sort them by (block, material, cell) into `perm` (particle j of
 * the sorted order is perm[j]), activate the pads and colour the owner blocks (see the file
 * comment). The particle arrays are not moved; the caller reorders them now and then with
 * mpm_particles_permute. The sort's keys and histograms come from `scratch` (taken back when the
 * step ends). MPM_OK, or MPM_ERR_NOMEM when out of memory. */
mpm_status mpm_sparse_grid_sort(mpm_sparse_grid *g, const mpm_kernel *k, const mpm_real origin[3],
                                int material_count, const mpm_particles *p, mpm_arena *scratch);

/* Bytes held by the grid (hash, block lists, particle order), for memory reports; the node
 * values live in the DOF set. */
size_t mpm_sparse_grid_bytes(const mpm_sparse_grid *g);

/* The particles of owner block b and material m: perm[*begin .. *end). */
static inline void mpm_sparse_grid_run(const mpm_sparse_grid *g, size_t b, int m, uint32_t *begin,
                                       uint32_t *end) {
  const size_t q = (b * (size_t)g->material_count + (size_t)m) * MPM_BLOCK_NODES;
  *begin = g->cell_start[q];
  *end = g->cell_start[q + MPM_BLOCK_NODES];
}

/* Index of the block at block coordinates c, activated (as a halo block, after the owner
 * blocks of the last sort) when it was not active; -1 when out of memory. For point sets that
 * are not sorted but scatter into the grid, such as Zhu's domain corners. */
int32_t mpm_sparse_grid_touch(mpm_sparse_grid *g, const int32_t c[3]);

/* Index of the block at block coordinates c, or -1. */
int32_t mpm_sparse_grid_find(const mpm_sparse_grid *g, const int32_t c[3]);

#endif
