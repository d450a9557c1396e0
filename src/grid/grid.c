/* grid.c - the two variants of the grid interface (grid.h): their tables of operations. */
#include "grid/grid.h"
#include "core/alloc.h"
#include "core/parallel.h"

#include <string.h>

/* ---- sparse: one box per 4x4x4 block, blocks in activation order ---- */

static mpm_status sparse_activate(mpm_grid *g, const mpm_kernel *k, int material_count,
                                  const mpm_particles *p, mpm_arena *scratch) {
  return mpm_sparse_grid_sort(&g->impl.sparse, k, g->origin, material_count, p, scratch);
}

/* The 8 blocks of the pad of base block bb (the block and its forward neighbours), through the
 * cursor's cache of the last base block: carriers such as corners come in lattice order, so
 * neighbours mostly share their base block. With `activate` (g itself) missing blocks are
 * activated, else only found. -1 when one is missing or out of memory. */
static int pad_blocks(const mpm_sparse_grid *g, mpm_sparse_grid *activate, const int32_t bb[3],
                      mpm_grid_cursor *c) {
  if (bb[0] == c->key[0] && bb[1] == c->key[1] && bb[2] == c->key[2]) return 0;
  for (int o = 0; o < 8; ++o) {
    const int32_t bc[3] = {bb[0] + ((o >> 2) & 1), bb[1] + ((o >> 1) & 1), bb[2] + (o & 1)};
    c->blocks[o] = activate ? mpm_sparse_grid_touch(activate, bc) : mpm_sparse_grid_find(g, bc);
    if (c->blocks[o] < 0) {
      mpm_grid_cursor_init(c);
      return -1;
    }
  }
  for (int d = 0; d < 3; ++d) c->key[d] = bb[d];
  return 0;
}

/* The base block of point i's stencil, packed (21 bits an axis, as the grid's coordinates
 * allow), or UINT64_MAX when the point is not used. */
static inline uint64_t point_block(const mpm_grid *g, const mpm_kernel *k,
                                   const mpm_real *const x[3], const uint8_t *use, size_t i) {
  if (use && !use[i]) return UINT64_MAX;
  const mpm_real xr[3] = {x[0][i] - g->origin[0], x[1][i] - g->origin[1], x[2][i] - g->origin[2]};
  int base[3];
  mpm_kernel_base(k, xr, base);
  uint64_t key = 0;
  for (int d = 0; d < 3; ++d)
    key = key << 21 | (uint64_t)((uint32_t)((base[d] >> MPM_BLOCK_BITS) + (1 << 20)) & 0x1FFFFF);
  return key;
}

/* The points' base blocks in parallel, each thread listing where its range's block changes
 * (from the index of its first point on: points such as domain corners come in block order,
 * so runs are long and the list short); then the pads of those blocks activated in point
 * order, one thread (the grid's insertions are serial). */
static mpm_status sparse_activate_points(mpm_grid *g, const mpm_kernel *k, size_t n,
                                         const mpm_real *const x[3], const uint8_t *use) {
  mpm_sparse_grid *sg = &g->impl.sparse;
  if (mpm_reserve((void **)&sg->run_keys, &sg->run_capacity, n + 1, sizeof *sg->run_keys))
    return MPM_ERR_NOMEM;
  uint64_t *keys = sg->run_keys;
  enum { MAX_THREADS = 256 };
  int threads = n >= MPM_PARALLEL_MIN ? mpm_thread_count() : 1;
  if (threads > MAX_THREADS) threads = MAX_THREADS;
  size_t first[MAX_THREADS], count[MAX_THREADS];
  int team = 1; /* the threads the region was given */
#pragma omp parallel num_threads(threads) if (threads > 1)
  {
    const int T = mpm_thread_team(), t = mpm_thread_id();
    const size_t i0 = n * (size_t)t / (size_t)T, i1 = n * (size_t)(t + 1) / (size_t)T;
    size_t m = 0;
    uint64_t last = UINT64_MAX;
    for (size_t i = i0; i < i1; ++i) {
      const uint64_t b = point_block(g, k, x, use, i);
      if (b == UINT64_MAX || b == last) continue;
      keys[i0 + m++] = last = b;
    }
    first[t] = i0;
    count[t] = m;
#pragma omp single nowait
    team = T;
  }
  mpm_grid_cursor c;
  mpm_grid_cursor_init(&c);
  for (int t = 0; t < team; ++t)
    for (size_t r = 0; r < count[t]; ++r) {
      const uint64_t key = keys[first[t] + r];
      int32_t bb[3];
      for (int d = 0; d < 3; ++d) bb[d] = (int32_t)((key >> (21 * (2 - d))) & 0x1FFFFF) - (1 << 20);
      if (pad_blocks(sg, sg, bb, &c)) return MPM_ERR_NOMEM; /* touching fails only so */
    }
  return MPM_OK;
}

static mpm_status sparse_stencil_nodes(const mpm_grid *g, const int32_t base[3], int W,
                                       mpm_grid_cursor *c, uint32_t *nodes, int32_t *key,
                                       uint8_t *colour) {
  const int32_t bb[3] = {base[0] >> MPM_BLOCK_BITS, base[1] >> MPM_BLOCK_BITS,
                         base[2] >> MPM_BLOCK_BITS};
  if (pad_blocks(&g->impl.sparse, NULL, bb, c)) return MPM_ERR_INVALID; /* a block missing */
  int e = 0;
  for (int i = 0; i < W; ++i)
    for (int j = 0; j < W; ++j)
      for (int l = 0; l < W; ++l) {
        const int32_t n[3] = {base[0] + i, base[1] + j, base[2] + l};
        const int o = (((n[0] >> MPM_BLOCK_BITS) - bb[0]) << 2) |
                      (((n[1] >> MPM_BLOCK_BITS) - bb[1]) << 1) |
                      ((n[2] >> MPM_BLOCK_BITS) - bb[2]);
        const int local = ((n[0] & 3) << 4) | ((n[1] & 3) << 2) | (n[2] & 3);
        nodes[e++] = (uint32_t)c->blocks[o] * MPM_BLOCK_NODES + (uint32_t)local;
      }
  *key = c->blocks[0];
  *colour = (uint8_t)((bb[0] & 1) << 2 | (bb[1] & 1) << 1 | (bb[2] & 1));
  return MPM_OK;
}

static size_t sparse_scatter_key_count(const mpm_grid *g) {
  return g->impl.sparse.block_count;
}

static uint32_t *sparse_particle_order(mpm_grid *g) {
  return g->impl.sparse.perm;
}

static size_t sparse_node_count(const mpm_grid *g) {
  return g->impl.sparse.block_count * MPM_BLOCK_NODES;
}

static size_t sparse_box_count(const mpm_grid *g) {
  return g->impl.sparse.block_count;
}

static mpm_node_box sparse_box(const mpm_grid *g, size_t b) {
  const int32_t *c = g->impl.sparse.coord[b];
  const mpm_node_box box = {b * MPM_BLOCK_NODES,
                            {c[0] * MPM_BLOCK, c[1] * MPM_BLOCK, c[2] * MPM_BLOCK},
                            {MPM_BLOCK, MPM_BLOCK, MPM_BLOCK}};
  return box;
}

static size_t sparse_bytes(const mpm_grid *g) {
  return mpm_sparse_grid_bytes(&g->impl.sparse);
}

static void sparse_free(mpm_grid *g) {
  mpm_sparse_grid_free(&g->impl.sparse);
}

static const mpm_grid_ops sparse_ops = {"sparse",
                                        sparse_activate,
                                        sparse_activate_points,
                                        sparse_stencil_nodes,
                                        sparse_scatter_key_count,
                                        sparse_particle_order,
                                        sparse_node_count,
                                        sparse_box_count,
                                        sparse_box,
                                        sparse_bytes,
                                        sparse_free};
/* ---- dense: every node always there, one box per x-slab ---- */

static mpm_status dense_activate(mpm_grid *g, const mpm_kernel *k, int material_count,
                                 const mpm_particles *p, mpm_arena *scratch) {
  (void)g, (void)k, (void)material_count, (void)p, (void)scratch;
  return MPM_OK;
}

static mpm_status dense_activate_points(mpm_grid *g, const mpm_kernel *k, size_t n,
                                        const mpm_real *const x[3], const uint8_t *use) {
  (void)g, (void)k, (void)n, (void)x, (void)use;
  return MPM_OK;
}

/* Stencils are keyed by virtual 4x4x4 blocks of the dense lattice, coloured by parity, as the
 * sparse grid's blocks are. */
static mpm_status dense_stencil_nodes(const mpm_grid *g, const int32_t base[3], int W,
                                      mpm_grid_cursor *c, uint32_t *nodes, int32_t *key,
                                      uint8_t *colour) {
  (void)c;
  const int *n = g->impl.dense.n;
  for (int d = 0; d < 3; ++d)
    if (base[d] < 0 || base[d] + W > n[d]) return MPM_ERR_INVALID;
  int e = 0;
  for (int i = 0; i < W; ++i)
    for (int j = 0; j < W; ++j)
      for (int l = 0; l < W; ++l)
        nodes[e++] = (uint32_t)(((base[0] + i) * n[1] + base[1] + j) * n[2] + base[2] + l);
  const int32_t bb[3] = {base[0] >> MPM_BLOCK_BITS, base[1] >> MPM_BLOCK_BITS,
                         base[2] >> MPM_BLOCK_BITS};
  const int32_t nb[3] = {(n[0] >> MPM_BLOCK_BITS) + 1, (n[1] >> MPM_BLOCK_BITS) + 1,
                         (n[2] >> MPM_BLOCK_BITS) + 1};
  *key = (bb[0] * nb[1] + bb[1]) * nb[2] + bb[2];
  *colour = (uint8_t)((bb[0] & 1) << 2 | (bb[1] & 1) << 1 | (bb[2] & 1));
  return MPM_OK;
}

static size_t dense_scatter_key_count(const mpm_grid *g) {
  const int *n = g->impl.dense.n;
  return (size_t)((n[0] >> MPM_BLOCK_BITS) + 1) * (size_t)((n[1] >> MPM_BLOCK_BITS) + 1) *
         (size_t)((n[2] >> MPM_BLOCK_BITS) + 1);
}

static uint32_t *dense_particle_order(mpm_grid *g) {
  (void)g;
  return NULL;
}

static size_t dense_node_count(const mpm_grid *g) {
  return g->impl.dense.count;
}

static size_t dense_box_count(const mpm_grid *g) {
  return (size_t)g->impl.dense.n[0];
}

static mpm_node_box dense_box(const mpm_grid *g, size_t b) {
  const int *n = g->impl.dense.n;
  const mpm_node_box box = {b * (size_t)n[1] * (size_t)n[2], {(int32_t)b, 0, 0}, {1, n[1], n[2]}};
  return box;
}

static size_t dense_bytes(const mpm_grid *g) {
  (void)g;
  return 0;
}

static void dense_free(mpm_grid *g) {
  memset(&g->impl.dense, 0, sizeof g->impl.dense);
}

static const mpm_grid_ops dense_ops = {"dense",
                                       dense_activate,
                                       dense_activate_points,
                                       dense_stencil_nodes,
                                       dense_scatter_key_count,
                                       dense_particle_order,
                                       dense_node_count,
                                       dense_box_count,
                                       dense_box,
                                       dense_bytes,
                                       dense_free};
static void init_common(mpm_grid *g, int level, const mpm_real origin[3], mpm_real dx) {
  memset(g, 0, sizeof *g);
  g->level = level;
  for (int d = 0; d < 3; ++d) g->origin[d] = origin[d];
  g->dx = dx;
}

void mpm_grid_init_sparse(mpm_grid *g, int level, const mpm_real origin[3], mpm_real dx) {
  init_common(g, level, origin, dx);
  g->ops = &sparse_ops;
  g->kind = MPM_GRID_SPARSE;
  mpm_sparse_grid_init(&g->impl.sparse);
}

mpm_status mpm_grid_init_dense(mpm_grid *g, int level, const mpm_real origin[3], mpm_real dx,
                               const int n[3]) {
  init_common(g, level, origin, dx);
  g->ops = &dense_ops;
  g->kind = MPM_GRID_DENSE;
  for (int d = 0; d < 3; ++d) {
    if (n[d] <= 0) return MPM_ERR_INVALID;
    g->impl.dense.n[d] = n[d];
  }
  g->impl.dense.count = (size_t)n[0] * (size_t)n[1] * (size_t)n[2];
  return MPM_OK;
}
