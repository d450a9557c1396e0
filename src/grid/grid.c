/* grid.c - the two variants of the grid interface (grid.h): their tables of operations. */
#include "grid/grid.h"

#include <string.h>

/* ---- sparse: one box per 4x4x4 block, blocks in activation order ---- */

static int sparse_activate(mpm_grid *g, const mpm_kernel *k, int material_count,
                           const mpm_particles *p, mpm_arena *scratch) {
  return mpm_sparse_grid_sort(&g->impl.sparse, k, g->origin, material_count, p, scratch);
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

static const mpm_grid_ops sparse_ops = {"sparse",          sparse_activate,  sparse_particle_order,
                                        sparse_node_count, sparse_box_count, sparse_box,
                                        sparse_bytes,      sparse_free};

/* ---- dense: every node always there, one box per x-slab ---- */

static int dense_activate(mpm_grid *g, const mpm_kernel *k, int material_count,
                          const mpm_particles *p, mpm_arena *scratch) {
  (void)g, (void)k, (void)material_count, (void)p, (void)scratch;
  return 0;
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

static const mpm_grid_ops dense_ops = {"dense",          dense_activate,  dense_particle_order,
                                       dense_node_count, dense_box_count, dense_box,
                                       dense_bytes,      dense_free};

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

int mpm_grid_init_dense(mpm_grid *g, int level, const mpm_real origin[3], mpm_real dx,
                        const int n[3]) {
  init_common(g, level, origin, dx);
  g->ops = &dense_ops;
  g->kind = MPM_GRID_DENSE;
  for (int d = 0; d < 3; ++d) {
    if (n[d] <= 0) return -1;
    g->impl.dense.n[d] = n[d];
  }
  g->impl.dense.count = (size_t)n[0] * (size_t)n[1] * (size_t)n[2];
  return 0;
}
