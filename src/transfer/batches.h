/* batches.h - the one walk over a sparse grid's particles that every transfer takes: owner
 * block -> material -> cell -> batch of up to MPM_LANES particles (SIMD lanes), and the pads
 * that carry a block's neighbourhood of node values.
 *
 * Particles are sorted by (owner block, material, base cell) (sparse_grid.h), so a batch
 * shares its base node and hence every grid node it touches (transfer_lanes.h), and a
 * material's particles of one block are one range of the particle order: the constitutive
 * model runs on them in chunks (stresses before P2G, the return map after G2P). The fused
 * explicit P2G and G2P (p2g.c, g2p.c) and the separate operators (operators.c) all walk the
 * particles with mpm_batches_next; a pad is filled from or added to the DOF values with
 * mpm_pad_gather and mpm_pad_add. Private to src/transfer. */
#ifndef MPM_TRANSFER_BATCHES_H
#define MPM_TRANSFER_BATCHES_H

#include "core/lanes.h"
#include "grid/sparse_grid.h"

/* A walk over the batches of one owner block. */
typedef struct mpm_batches {
  const mpm_sparse_grid *g;
  size_t q0, q, q1;   /* cell runs of the block: q0 + material * 64 + cell */
  uint32_t next, end; /* next position of the particle order, end of the current cell */
  /* the current batch */
  int material;
  uint32_t pos;         /* first position of the batch in the particle order */
  int n;                /* particles in the batch, 1..MPM_LANES */
  const uint32_t *idx;  /* their indices: g->perm + pos */
  int material_first;   /* the first batch of its material in this block */
  int material_last;    /* the last one */
  uint32_t range_begin; /* the positions of the material's particles in this block */
  uint32_t range_end;
} mpm_batches;

MPM_ALWAYS_INLINE void mpm_batches_begin(mpm_batches *it, const mpm_sparse_grid *g, size_t b) {
  it->g = g;
  it->q0 = it->q = b * (size_t)g->material_count * MPM_BLOCK_NODES;
  it->q1 = it->q0 + (size_t)g->material_count * MPM_BLOCK_NODES;
  it->next = g->cell_start[it->q];
  it->end = g->cell_start[it->q + 1];
}

/* Advance to the next batch; 0 when the block has no more. */
MPM_ALWAYS_INLINE int mpm_batches_next(mpm_batches *it) {
  const uint32_t *cs = it->g->cell_start;
  while (it->next >= it->end) { /* the next cell with particles */
    if (++it->q >= it->q1) return 0;
    it->next = cs[it->q];
    it->end = cs[it->q + 1];
  }
  const size_t m = (it->q - it->q0) / MPM_BLOCK_NODES;
  it->material = (int)m;
  it->range_begin = cs[it->q0 + m * MPM_BLOCK_NODES];
  it->range_end = cs[it->q0 + (m + 1) * MPM_BLOCK_NODES];
  it->pos = it->next;
  it->n = (int)(it->end - it->next < MPM_LANES ? it->end - it->next : MPM_LANES);
  it->idx = it->g->perm + it->pos;
  it->next += (uint32_t)it->n;
  it->material_first = it->pos == it->range_begin;
  it->material_last = it->next == it->range_end;
  return 1;
}

/* The pad of owner block b: the 8 blocks its stencils reach (the block and its 7 forward
 * neighbours), as an AoS array of MPM_PAD^3 nodes with `stride` reals each. Stencils reach only
 * W - 1 nodes into the forward blocks, so only those nodes are copied. */

/* pad[node * stride + k] = a[k][node's DOF] for k < count. */
MPM_ALWAYS_INLINE void mpm_pad_gather(const int W, const mpm_sparse_grid *g, int32_t b, int count,
                                      const mpm_real *const *a, int stride, mpm_real *pad) {
  for (int o = 0; o < 8; ++o) {
    const size_t nb = (size_t)g->neighbor[b][o] * MPM_BLOCK_NODES;
    const int ox = ((o >> 2) & 1) * MPM_BLOCK, oy = ((o >> 1) & 1) * MPM_BLOCK,
              oz = (o & 1) * MPM_BLOCK;
    const int ni = ox ? W - 1 : MPM_BLOCK, nj = oy ? W - 1 : MPM_BLOCK, nk = oz ? W - 1 : MPM_BLOCK;
    for (int i = 0; i < ni; ++i)
      for (int j = 0; j < nj; ++j)
        for (int k = 0; k < nk; ++k) {
          mpm_real *dst =
              &pad[((ox + i) * MPM_PAD * MPM_PAD + (oy + j) * MPM_PAD + oz + k) * stride];
          const size_t n = nb + (size_t)((i * MPM_BLOCK + j) * MPM_BLOCK + k);
          for (int c = 0; c < count; ++c) dst[c] = a[c][n];
        }
  }
}

/* a[k][node's DOF] += pad[node * stride + k] for k < count (the rest of the pad is zero). */
MPM_ALWAYS_INLINE void mpm_pad_add(const int W, const mpm_sparse_grid *g, int32_t b, int count,
                                   const mpm_real *pad, int stride, mpm_real *const *a) {
  for (int o = 0; o < 8; ++o) {
    const size_t nb = (size_t)g->neighbor[b][o] * MPM_BLOCK_NODES;
    const int ox = ((o >> 2) & 1) * MPM_BLOCK, oy = ((o >> 1) & 1) * MPM_BLOCK,
              oz = (o & 1) * MPM_BLOCK;
    const int ni = ox ? W - 1 : MPM_BLOCK, nj = oy ? W - 1 : MPM_BLOCK, nk = oz ? W - 1 : MPM_BLOCK;
    for (int i = 0; i < ni; ++i)
      for (int j = 0; j < nj; ++j)
        for (int k = 0; k < nk; ++k) {
          const mpm_real *src =
              &pad[((ox + i) * MPM_PAD * MPM_PAD + (oy + j) * MPM_PAD + oz + k) * stride];
          const size_t n = nb + (size_t)((i * MPM_BLOCK + j) * MPM_BLOCK + k);
          for (int c = 0; c < count; ++c) a[c][n] += src[c];
        }
  }
}

/* Ask for the `count` arrays' values of the 8 blocks of b's pad (rw: 1 to write them). */
#define MPM_PAD_PREFETCH(g, b, count, a, rw)                                                       \
  do {                                                                                             \
    for (int o_ = 0; o_ < 8; ++o_) {                                                               \
      const size_t nb_ = (size_t)(g)->neighbor[b][o_] * MPM_BLOCK_NODES;                           \
      for (int c_ = 0; c_ < (count); ++c_)                                                         \
        for (int q_ = 0; q_ < MPM_BLOCK_NODES; q_ += 64 / (int)sizeof(mpm_real))                   \
          __builtin_prefetch(&(a)[c_][nb_ + (size_t)q_], rw);                                      \
    }                                                                                              \
  } while (0)

/* The offset in a pad of a batch's base node, for owner block b with block origin org. */
MPM_ALWAYS_INLINE long mpm_pad_offset(const int base[3], const int org[3]) {
  return (long)(base[0] - org[0]) * MPM_PAD * MPM_PAD + (long)(base[1] - org[1]) * MPM_PAD +
         (long)(base[2] - org[2]);
}

#endif
