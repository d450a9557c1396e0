/* grid.c - the level stack of the multi-level grid and its ghost slots (Gao et al.
 * 2017, sec. 6.1): the levels and extra grids, the used-slot marks, the ghosts' rows, their
 * scatter schedule and the scatter and gather through them; see adaptive/grid.h. Which used
 * slots are ghosts, and their rows, come from the closure (adaptive/close.c). */
#include "adaptive/grid.h"
#include "adaptive/grid_parts.h"

#include "core/alloc.h"
#include "core/parallel.h"

#include <string.h>

void mpm_adaptive_grid_init(mpm_adaptive_grid *g, int levels, const mpm_real origin[3],
                            mpm_real dx0) {
  memset(g, 0, sizeof *g);
  mpm_refinement_init(&g->tree, levels, origin, dx0);
  for (int L = 0; L < levels; ++L) {
    mpm_grid_init_sparse(&g->level[L], L, origin, mpm_refinement_dx(&g->tree, L));
  }
  mpm_embedding_init(&g->ghosts);
}

void mpm_adaptive_grid_free(mpm_adaptive_grid *g) {
  for (int L = 0; L < g->tree.levels; ++L) mpm_grid_free(&g->level[L]);
  for (int e = 0; e < g->extra_count; ++e) mpm_grid_free(&g->extra[e]);
  mpm_refinement_free(&g->tree);
  mpm_embedding_free(&g->ghosts);
  mpm_free(g->ghost_slot);
  mpm_free(g->scratch);
  for (int G = 0; G < MPM_TRANSFER_GRIDS_MAX; ++G) {
    mpm_free(g->used[G]);
    mpm_free(g->done[G]);
    mpm_free(g->ghost[G]);
  }
  for (int d = 0; d < 3; ++d) mpm_free(g->offset[d]);
  mpm_free(g->spread);
  mpm_free(g->build.len);
  mpm_free(g->build.terms);
  mpm_free(g->build.where);
  mpm_adaptive_rows_free(&g->rows);
  mpm_free(g->blocks.keys);
  mpm_free(g->blocks.uniform);
  mpm_free(g->blocks.ids_at);
  mpm_free(g->blocks.cells);
  mpm_free(g->blocks.cells_known);
  mpm_free(g->blocks.ids);
  mpm_free(g->blocks.owned);
  mpm_free(g->schedule.key);
  mpm_free(g->schedule.colour);
  mpm_free(g->schedule.table_block);
  mpm_free(g->schedule.table_key);
  mpm_free(g->closing.pending);
  mpm_free(g->closing.count);
  memset(g, 0, sizeof *g);
}

int mpm_adaptive_grid_add_extra(mpm_adaptive_grid *g, int level) {
  if (g->extra_count == MPM_EXTRA_GRIDS_MAX || level < 0 || level >= g->tree.levels) return -1;
  const int e = g->extra_count++;
  mpm_grid_init_sparse(&g->extra[e], level, g->tree.origin, mpm_refinement_dx(&g->tree, level));
  g->extra_level[e] = level;
  return MPM_LEVELS_MAX + e;
}

mpm_grid *mpm_adaptive_grid_at(mpm_adaptive_grid *g, int G) {
  return grid_of(g, G);
}
int mpm_adaptive_grid_level_of(const mpm_adaptive_grid *g, int G) {
  return level_of(g, G);
}
int mpm_adaptive_grid_next(const mpm_adaptive_grid *g, int G) {
  return next_grid(g, G);
}

/* The masks of transfer grid G cover its blocks (new blocks start unused). */
mpm_status mpm_adaptive_ensure_masks(mpm_adaptive_grid *g, int G) {
  const size_t n = grid_of(g, G)->impl.sparse.block_count;
  if (n <= g->mask_capacity[G]) return MPM_OK;
  size_t cap = g->mask_capacity[G] ? g->mask_capacity[G] : 256;
  while (cap < n) cap *= 2;
  uint64_t **masks[3] = {&g->used[G], &g->done[G], &g->ghost[G]};
  uint64_t *grown[3];
  for (int k = 0; k < 3; ++k)
    if (!(grown[k] = mpm_calloc(cap, sizeof(uint64_t)))) {
      for (int j = 0; j < k; ++j) mpm_free(grown[j]);
      return MPM_ERR_NOMEM;
    }
  for (int k = 0; k < 3; ++k) {
    if (g->mask_capacity[G]) memcpy(grown[k], *masks[k], g->mask_capacity[G] * sizeof(uint64_t));
    mpm_free(*masks[k]);
    *masks[k] = grown[k];
  }
  g->mask_capacity[G] = cap;
  return MPM_OK;
}

/* Activate node idx of transfer grid G and mark it used. */
mpm_status mpm_adaptive_mark(mpm_adaptive_grid *g, int G, const int32_t idx[3]) {
  const int32_t bc[3] = {idx[0] >> MPM_BLOCK_BITS, idx[1] >> MPM_BLOCK_BITS,
                         idx[2] >> MPM_BLOCK_BITS};
  const int32_t b = mpm_sparse_grid_touch(&grid_of(g, G)->impl.sparse, bc);
  if (b < 0 || mpm_adaptive_ensure_masks(g, G)) return MPM_ERR_NOMEM;
  g->used[G][b] |= (uint64_t)1 << local_of(idx);
  return MPM_OK;
}

void mpm_adaptive_grid_clear_marks(mpm_adaptive_grid *g) {
  for (int G = 0; G < MPM_TRANSFER_GRIDS_MAX; ++G)
    if (g->mask_capacity[G]) {
      memset(g->used[G], 0, g->mask_capacity[G] * sizeof(uint64_t));
      memset(g->done[G], 0, g->mask_capacity[G] * sizeof(uint64_t));
      memset(g->ghost[G], 0, g->mask_capacity[G] * sizeof(uint64_t));
    }
  g->ghost_count = 0;
}

mpm_status mpm_adaptive_grid_activate_box(mpm_adaptive_grid *g, int level, const int32_t lo[3],
                                          const int32_t hi[3]) {
  for (int32_t a = lo[0]; a <= hi[0]; ++a)
    for (int32_t b = lo[1]; b <= hi[1]; ++b)
      for (int32_t c = lo[2]; c <= hi[2]; ++c) {
        const int32_t idx[3] = {a, b, c};
        if (mpm_adaptive_mark(g, level, idx) != MPM_OK) return MPM_ERR_NOMEM;
      }
  return MPM_OK;
}

void mpm_adaptive_grid_stencil_masks(int W, uint64_t reach[MPM_BLOCK_NODES][8]) {
  memset(reach, 0, MPM_BLOCK_NODES * 8 * sizeof(uint64_t));
  for (int c = 0; c < MPM_BLOCK_NODES; ++c)
    for (int i = 0; i < W; ++i)
      for (int j = 0; j < W; ++j)
        for (int k = 0; k < W; ++k) {
          const int px = ((c >> 4) & 3) + i, py = ((c >> 2) & 3) + j, pz = (c & 3) + k;
          reach[c][(px >> 2) << 2 | (py >> 2) << 1 | (pz >> 2)] |=
              (uint64_t)1 << ((px & 3) << 4 | (py & 3) << 2 | (pz & 3));
        }
}

mpm_status mpm_adaptive_grid_mark_sorted(mpm_adaptive_grid *g, int G, int W) {
  mpm_sparse_grid *sg = &grid_of(g, G)->impl.sparse;
  if (mpm_adaptive_ensure_masks(g, G)) return MPM_ERR_NOMEM;
  uint64_t reach[MPM_BLOCK_NODES][8];
  mpm_adaptive_grid_stencil_masks(W, reach);
  /* particles of one (block, material, cell) share their stencil: mark it once, through the
   * owner block's pad (its blocks are active since the sort: no lookups). Blocks in parallel:
   * pads overlap, so the marks are ORed atomically (the same bits for any order) */
  const long owners = (long)sg->owner_count;
  const size_t nmat = (size_t)sg->material_count;
  uint64_t *used = g->used[G];
#pragma omp parallel for schedule(static) if (owners > 64)
  for (long b = 0; b < owners; ++b) {
    uint64_t mark[8] = {0, 0, 0, 0, 0, 0, 0, 0};
    for (int c = 0; c < MPM_BLOCK_NODES; ++c) {
      int any = 0;
      for (size_t m = 0; m < nmat && !any; ++m) {
        const size_t q = ((size_t)b * nmat + m) * MPM_BLOCK_NODES + (size_t)c;
        any = sg->cell_start[q + 1] > sg->cell_start[q];
      }
      if (!any) continue;
      for (int o = 0; o < 8; ++o) mark[o] |= reach[c][o];
    }
    for (int o = 0; o < 8; ++o)
      if (mark[o]) __atomic_fetch_or(&used[sg->neighbor[b][o]], mark[o], __ATOMIC_RELAXED);
  }
  return MPM_OK;
}

int64_t mpm_adaptive_grid_slot(const mpm_adaptive_grid *g, int level, const int32_t idx[3]) {
  const mpm_grid *lv = &g->level[level];
  const int32_t bc[3] = {block_of(idx[0]), block_of(idx[1]), block_of(idx[2])};
  const int32_t b = mpm_sparse_grid_find(&lv->impl.sparse, bc);
  if (b < 0) return -1;
  const int local = local_of(idx);
  return (int64_t)lv->dof_begin + (int64_t)b * MPM_BLOCK_NODES + local;
}

static mpm_status reserve_ghosts(mpm_adaptive_grid *g, size_t n) {
  if (n <= g->ghost_capacity) return MPM_OK;
  size_t cap = g->ghost_capacity ? g->ghost_capacity : 1024;
  while (cap < n) cap *= 2;
  uint32_t *slot = mpm_alloc(cap * sizeof *slot);
  mpm_real *scratch = mpm_alloc(4 * cap * sizeof *scratch);
  mpm_real *spread = mpm_alloc(6 * cap * sizeof(mpm_real));
  if (!slot || !scratch || !spread) {
    mpm_free(slot);
    mpm_free(scratch);
    mpm_free(spread);
    return MPM_ERR_NOMEM;
  }
  mpm_free(g->spread);
  g->spread = spread; /* filled by build_rows after every ghost is known */
  if (g->ghost_count) memcpy(slot, g->ghost_slot, g->ghost_count * sizeof *slot);
  mpm_free(g->ghost_slot);
  mpm_free(g->scratch);
  g->ghost_slot = slot;
  g->scratch = scratch;
  g->ghost_capacity = cap;
  return MPM_OK;
}

/* The ghosts' scatter in parallel, the same sums for any number of threads: ghosts grouped by
 * the level-0 block they lie in, coloured by its parity. A ghost's parents lie less than two
 * level-0 cells from it (build_rows checks, else the scatter stays serial), so ghosts in two
 * blocks of one colour, 4 level-0 cells apart at least, never share a parent. MPM_OK, or
 * MPM_ERR_NOMEM when out of memory. */
static mpm_status build_schedule(mpm_adaptive_grid *g) {
  const size_t n = g->ghost_count;
  const uint32_t(*where)[3] = g->build.where;
  /* ghosts of one block are consecutive: at most one key per run of a block, so a table twice
   * the runs' count never fills */
  size_t runs = 0;
  for (size_t a = 0; a < n; ++a)
    runs += a == 0 || where[a][0] != where[a - 1][0] || where[a][1] != where[a - 1][1];
  size_t size = 1024;
  while (size < 2 * runs) size *= 2;
  if (size > g->schedule.table_size) {
    mpm_free(g->schedule.table_block);
    mpm_free(g->schedule.table_key);
    g->schedule.table_block = mpm_alloc(size * sizeof(uint64_t));
    g->schedule.table_key = mpm_alloc(size * sizeof(int32_t));
    g->schedule.table_size = g->schedule.table_block && g->schedule.table_key ? size : 0;
    if (!g->schedule.table_size) return MPM_ERR_NOMEM;
  }
  size = g->schedule.table_size;
  if (mpm_grow((void **)&g->schedule.key, &g->schedule.key_cap, n + 1, sizeof(int32_t)) ||
      mpm_grow((void **)&g->schedule.colour, &g->schedule.colour_cap, runs + 1, 1))
    return MPM_ERR_NOMEM;
  memset(g->schedule.table_block, 0xff, size * sizeof(uint64_t));
  int32_t keys = 0, key = -1;
  for (size_t a = 0; a < n; ++a) {
    if (a == 0 || where[a][0] != where[a - 1][0] || where[a][1] != where[a - 1][1]) {
      const int G = (int)where[a][0], L = level_of(g, G);
      const int32_t *c = grid_of(g, G)->impl.sparse.coord[where[a][1]];
      uint64_t block = 0;
      for (int d = 0; d < 3; ++d) /* arithmetic shift: floor */
        block = block << 21 | ((uint64_t)((c[d] >> L) + (1 << 20)) & 0x1fffff);
      size_t s = (size_t)((block * 0x9e3779b97f4a7c15ull) >> 24) & (size - 1);
      while (g->schedule.table_block[s] != UINT64_MAX && g->schedule.table_block[s] != block)
        s = (s + 1) & (size - 1);
      if (g->schedule.table_block[s] == UINT64_MAX) {
        g->schedule.table_block[s] = block;
        g->schedule.table_key[s] = keys;
        g->schedule.colour[keys++] =
            (uint8_t)(((c[0] >> L) & 1) << 2 | ((c[1] >> L) & 1) << 1 | ((c[2] >> L) & 1));
      }
      key = g->schedule.table_key[s];
    }
    g->schedule.key[a] = key;
  }
  return mpm_embedding_schedule(&g->ghosts, g->schedule.key, (size_t)keys, g->schedule.colour);
}

mpm_status mpm_adaptive_grid_build_rows(mpm_adaptive_grid *g) {
  /* the ghosts close() found, in its order (grid, block, slot); the build arrays are kept from
   * step to step: fresh pages for tens of MB every step cost more than filling them */
  const uint32_t *len = g->build.len, (*where)[3] = g->build.where;
  const mpm_row_term *terms = g->build.terms;
  g->ghost_count = 0;
  if (reserve_ghosts(g, g->build.count + 1)) return MPM_ERR_NOMEM;
  g->ghost_count = g->build.count;
  const mpm_status laid = mpm_embedding_layout(&g->ghosts, g->ghost_count, len, 0);
  if (laid != MPM_OK) return laid;
  const size_t entries = g->ghosts.row_start[g->ghost_count];
  if (entries > g->offset_capacity) {
    size_t cap = g->offset_capacity ? g->offset_capacity : 4096;
    while (cap < entries) cap *= 2;
    for (int d = 0; d < 3; ++d) {
      mpm_free(g->offset[d]);
      g->offset[d] = mpm_alloc(cap * sizeof(mpm_real));
    }
    g->offset_capacity = cap;
    if (!g->offset[0] || !g->offset[1] || !g->offset[2]) {
      g->offset_capacity = 0;
      return MPM_ERR_NOMEM;
    }
  }
  /* each ghost's slot now that the layout is known, its entries, their APIC offsets and its
   * spread, ghosts in parallel (row a's terms are terms[row_start[a] ..): the layout packs the
   * rows by len) */
  const double fine = (double)mpm_refinement_dx(&g->tree, g->tree.levels - 1);
  const long ghosts = (long)g->ghost_count;
  const int64_t reach = (int64_t)2 << fine_shift(&g->tree, 0); /* 2 level-0 cells */
  int inactive = 0, far = 0;
#pragma omp parallel for schedule(static) reduction(| : inactive, far) if (ghosts > 1024)
  for (long a = 0; a < ghosts; ++a) {
    const mpm_grid *lv = grid_of(g, (int)where[a][0]);
    g->ghost_slot[a] = (uint32_t)(lv->dof_begin + where[a][1] * MPM_BLOCK_NODES + where[a][2]);
    const int level = level_of(g, (int)where[a][0]);
    int32_t idx[3]; /* the ghost's node */
    node_of(&lv->impl.sparse, where[a][1], (int)where[a][2], idx);
    const mpm_row_term *row = terms + g->ghosts.row_start[a];
    double S[6] = {0, 0, 0, 0, 0, 0};
    for (uint32_t t = 0; t < len[a]; ++t) {
      const int64_t col = mpm_adaptive_grid_slot(g, row[t].level, row[t].idx);
      if (col < 0) { /* a parent not active: close() was not called */
        inactive = 1;
        break;
      }
      const uint32_t e = g->ghosts.row_start[a] + g->ghosts.row_len[a];
      mpm_embedding_push(&g->ghosts, (size_t)a, (uint32_t)col, (mpm_real)row[t].w);
      /* x_i - x_g exactly: both on the finest lattice */
      double r[3];
      for (int d = 0; d < 3; ++d) {
        const int64_t Xi =
            (int64_t)row[t].idx[d] * ((int64_t)1 << fine_shift(&g->tree, row[t].level));
        const int64_t Xg = (int64_t)idx[d] * ((int64_t)1 << fine_shift(&g->tree, level));
        r[d] = (double)(Xi - Xg) * fine;
        far |= Xi - Xg >= reach || Xg - Xi >= reach;
        g->offset[d][e] = (mpm_real)(row[t].w * r[d]);
      }
      S[0] += row[t].w * r[0] * r[0];
      S[1] += row[t].w * r[1] * r[1];
      S[2] += row[t].w * r[2] * r[2];
      S[3] += row[t].w * r[0] * r[1];
      S[4] += row[t].w * r[0] * r[2];
      S[5] += row[t].w * r[1] * r[2];
    }
    for (int q = 0; q < 6; ++q) g->spread[6 * (size_t)a + (size_t)q] = (mpm_real)S[q];
  }
  if (inactive) return MPM_ERR_INVALID; /* a parent not active: close() was not called */
  return far ? MPM_OK : build_schedule(g);
}

/* The ghosts' values of field u into c, their slots in u zeroed; and back, c into the ghosts'
 * slots. In parallel: every ghost has a slot of its own. */
static void ghosts_take(const mpm_adaptive_grid *g, mpm_real *u, mpm_real *c) {
  const long n = (long)g->ghost_count;
  const uint32_t *slot = g->ghost_slot;
#pragma omp parallel for schedule(static) if (n > MPM_PARALLEL_MIN)
  for (long a = 0; a < n; ++a) {
    c[a] = u[slot[a]];
    u[slot[a]] = 0;
  }
}

static void ghosts_put(const mpm_adaptive_grid *g, const mpm_real *c, mpm_real *u) {
  const long n = (long)g->ghost_count;
  const uint32_t *slot = g->ghost_slot;
#pragma omp parallel for schedule(static) if (n > MPM_PARALLEL_MIN)
  for (long a = 0; a < n; ++a) u[slot[a]] = c[a];
}

void mpm_adaptive_grid_scatter(mpm_adaptive_grid *g, int fields, mpm_real *const *u) {
  const size_t n = g->ghost_count;
  if (!n) return;
  for (int f0 = 0; f0 < fields; f0 += 3) {
    const int k = fields - f0 < 3 ? fields - f0 : 3;
    const mpm_real *c[3];
    for (int j = 0; j < k; ++j) {
      mpm_real *cj = g->scratch + (size_t)j * g->ghost_capacity;
      ghosts_take(g, u[f0 + j], cj);
      c[j] = cj;
    }
    mpm_embedding_scatter(&g->ghosts, k, c, u + f0);
  }
}

void mpm_adaptive_grid_scatter_squared(mpm_adaptive_grid *g, int fields, mpm_real *const *u) {
  const mpm_embedding *E = &g->ghosts;
  for (int f = 0; f < fields; ++f) {
    mpm_real *uf = u[f];
    for (size_t a = 0; a < g->ghost_count; ++a) {
      const mpm_real val = uf[g->ghost_slot[a]];
      uf[g->ghost_slot[a]] = 0;
      const uint32_t e1 = E->row_start[a] + E->row_len[a];
      for (uint32_t e = E->row_start[a]; e < e1; ++e) uf[E->col[e]] += E->w[e] * E->w[e] * val;
    }
  }
}

void mpm_adaptive_grid_gather(mpm_adaptive_grid *g, int fields, mpm_real *const *u) {
  const size_t n = g->ghost_count;
  if (!n) return;
  for (int f0 = 0; f0 < fields; f0 += 3) {
    const int k = fields - f0 < 3 ? fields - f0 : 3;
    mpm_real *c[3];
    const mpm_real *uu[3];
    for (int j = 0; j < k; ++j) {
      c[j] = g->scratch + (size_t)j * g->ghost_capacity;
      uu[j] = u[f0 + j];
    }
    mpm_embedding_gather(&g->ghosts, k, uu, c);
    for (int j = 0; j < k; ++j) ghosts_put(g, c[j], u[f0 + j]);
  }
}

void mpm_adaptive_grid_scatter_apic(mpm_adaptive_grid *g, int fields, mpm_real *const *u,
                                    const mpm_real *const A[9]) {
  const size_t n = g->ghost_count;
  if (!n) return;
  /* mass and momentum with the moments in one pass (the order of a plain scatter), the rest
     plainly after */
  const int k = fields < 4 ? fields : 4;
  const mpm_real *c[4];
  for (int j = 0; j < k; ++j) {
    mpm_real *cj = g->scratch + (size_t)j * g->ghost_capacity;
    ghosts_take(g, u[j], cj);
    c[j] = cj;
  }
  const mpm_real *const off[3] = {g->offset[0], g->offset[1], g->offset[2]};
  mpm_real *const um[3] = {u[1], u[2], u[3]};
  mpm_embedding_scatter_moments(&g->ghosts, k, c, u, off, A, um);
  if (fields > 4) mpm_adaptive_grid_scatter(g, fields - 4, u + 4);
}

void mpm_adaptive_grid_gather_moments(const mpm_adaptive_grid *g, const mpm_real *const v[3],
                                      mpm_real *const M[9]) {
  if (!g->ghost_count) return;
  const mpm_real *const off[3] = {g->offset[0], g->offset[1], g->offset[2]};
  mpm_embedding_gather_moments(&g->ghosts, v, off, M);
}

size_t mpm_adaptive_grid_bytes(const mpm_adaptive_grid *g) {
  size_t b =
      mpm_refinement_bytes(&g->tree) + mpm_embedding_bytes(&g->ghosts) +
      g->ghost_capacity * (sizeof(uint32_t) + 10 * sizeof(mpm_real)) +
      3 * g->offset_capacity * sizeof(mpm_real) + g->build.len_cap * sizeof(uint32_t) +
      g->build.terms_cap * sizeof(mpm_row_term) + g->build.where_cap * sizeof *g->build.where +
      g->blocks.id_capacity * sizeof(uint32_t) + g->blocks.owned_capacity * sizeof(uint64_t) +
      g->blocks.size * (3 * sizeof(uint64_t) + sizeof(uint32_t) + 2);
  FOR_GRIDS(g, G)
  b += grid_of((mpm_adaptive_grid *)g, G)->ops->bytes(grid_of((mpm_adaptive_grid *)g, G));
  return b;
}
