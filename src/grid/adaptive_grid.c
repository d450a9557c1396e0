/* adaptive_grid.c - the level stack of the multi-level grid and its ghost slots (Gao et al.
 * 2017, sec. 6.1); see adaptive_grid.h. */
#include "grid/adaptive_grid.h"

#include "core/alloc.h"

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

static void rows_free(struct mpm_row_cache *c);

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
  rows_free(&g->rows);
  mpm_free(g->blocks.keys);
  mpm_free(g->blocks.uniform);
  mpm_free(g->blocks.ids_at);
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

/* Finest-lattice units per index of `level`, as a shift. */
static inline int fine_shift(const mpm_refinement *r, int level) {
  return r->levels - 1 - level;
}

static int32_t block_of(int32_t n) {
  return n >> MPM_BLOCK_BITS;
} /* arithmetic: floor */

static inline int level_of(const mpm_adaptive_grid *g, int G) {
  return G < MPM_LEVELS_MAX ? G : g->extra_level[G - MPM_LEVELS_MAX];
}
static inline mpm_grid *grid_of(mpm_adaptive_grid *g, int G) {
  return G < MPM_LEVELS_MAX ? &g->level[G] : &g->extra[G - MPM_LEVELS_MAX];
}
/* The transfer grid after G in use (the levels, then the extra grids), or -1. */
static int next_grid(const mpm_adaptive_grid *g, int G) {
  const int n = g->tree.levels;
  if (G < n - 1) return G + 1;
  if (G < MPM_LEVELS_MAX) return g->extra_count ? MPM_LEVELS_MAX : -1;
  return G + 1 < MPM_LEVELS_MAX + g->extra_count ? G + 1 : -1;
}
#define FOR_GRIDS(g, G) for (int G = 0; G >= 0; G = next_grid(g, G))

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
static int ensure_masks(mpm_adaptive_grid *g, int G) {
  const size_t n = grid_of(g, G)->impl.sparse.block_count;
  if (n <= g->mask_capacity[G]) return 0;
  size_t cap = g->mask_capacity[G] ? g->mask_capacity[G] : 256;
  while (cap < n) cap *= 2;
  uint64_t **masks[3] = {&g->used[G], &g->done[G], &g->ghost[G]};
  uint64_t *grown[3];
  for (int k = 0; k < 3; ++k)
    if (!(grown[k] = mpm_calloc(cap, sizeof(uint64_t)))) {
      for (int j = 0; j < k; ++j) mpm_free(grown[j]);
      return -1;
    }
  for (int k = 0; k < 3; ++k) {
    if (g->mask_capacity[G]) memcpy(grown[k], *masks[k], g->mask_capacity[G] * sizeof(uint64_t));
    mpm_free(*masks[k]);
    *masks[k] = grown[k];
  }
  g->mask_capacity[G] = cap;
  return 0;
}

static inline int local_of(const int32_t idx[3]) {
  return ((idx[0] & 3) << 4) | ((idx[1] & 3) << 2) | (idx[2] & 3);
}

/* Activate node idx of transfer grid G and mark it used; 1 when the mark is new, 0, or -1. */
static int mark(mpm_adaptive_grid *g, int G, const int32_t idx[3]) {
  const int32_t bc[3] = {idx[0] >> MPM_BLOCK_BITS, idx[1] >> MPM_BLOCK_BITS,
                         idx[2] >> MPM_BLOCK_BITS};
  const int32_t b = mpm_sparse_grid_touch(&grid_of(g, G)->impl.sparse, bc);
  if (b < 0 || ensure_masks(g, G)) return -1;
  const uint64_t bit = (uint64_t)1 << local_of(idx);
  if (g->used[G][b] & bit) return 0;
  g->used[G][b] |= bit;
  return 1;
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

int mpm_adaptive_grid_activate_box(mpm_adaptive_grid *g, int level, const int32_t lo[3],
                                   const int32_t hi[3]) {
  for (int32_t a = lo[0]; a <= hi[0]; ++a)
    for (int32_t b = lo[1]; b <= hi[1]; ++b)
      for (int32_t c = lo[2]; c <= hi[2]; ++c) {
        const int32_t idx[3] = {a, b, c};
        if (mark(g, level, idx) < 0) return -1;
      }
  return 0;
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

int mpm_adaptive_grid_mark_sorted(mpm_adaptive_grid *g, int G, int W) {
  mpm_sparse_grid *sg = &grid_of(g, G)->impl.sparse;
  if (ensure_masks(g, G)) return -1;
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
  return 0;
}

static void node_of(const mpm_sparse_grid *sg, size_t b, int local, int32_t idx[3]) {
  const int32_t *c = sg->coord[b];
  idx[0] = c[0] * MPM_BLOCK + ((local >> 4) & 3);
  idx[1] = c[1] * MPM_BLOCK + ((local >> 2) & 3);
  idx[2] = c[2] * MPM_BLOCK + (local & 3);
}

/* ---- the row cache ---- */

#define ROW_EMPTY UINT64_MAX

static void rows_free(struct mpm_row_cache *c) {
  mpm_free(c->keys);
  mpm_free(c->entry);
  mpm_free(c->entries);
  mpm_free(c->terms);
  memset(c, 0, sizeof *c);
}

static inline size_t row_slot(uint64_t key, size_t size) {
  uint64_t h = key * 0x9e3779b97f4a7c15ull;
  h ^= h >> 31;
  return (size_t)h & (size - 1);
}

/* The cache's entry for node idx of `level` at finest-lattice position key, made on first use
 * (a real node: its owner level; else its row). NULL when out of memory or when the row needs
 * more than MPM_ROW_MAX entries. */
static const struct mpm_row_entry *row_of(mpm_adaptive_grid *g, int level, const int32_t idx[3],
                                          uint64_t key) {
  struct mpm_row_cache *c = &g->rows;
  if (c->version != g->tree.version) { /* the tree changed: forget every row */
    if (c->size) memset(c->keys, 0xff, c->size * sizeof *c->keys);
    c->count = c->term_count = 0;
    c->version = g->tree.version;
  }
  if (c->size)
    for (size_t s = row_slot(key, c->size);; s = (s + 1) & (c->size - 1)) {
      if (c->keys[s] == key) return &c->entries[c->entry[s]];
      if (c->keys[s] == ROW_EMPTY) break;
    }
  if (2 * (c->count + 1) > c->size) { /* grow the table, keep the entries */
    const size_t size = c->size ? 2 * c->size : 4096;
    uint64_t *keys = mpm_alloc(size * sizeof *keys);
    uint32_t *entry = mpm_alloc(size * sizeof *entry);
    if (!keys || !entry) {
      mpm_free(keys);
      mpm_free(entry);
      return NULL;
    }
    memset(keys, 0xff, size * sizeof *keys);
    for (size_t s = 0; s < c->size; ++s)
      if (c->keys[s] != ROW_EMPTY) {
        size_t t = row_slot(c->keys[s], size);
        while (keys[t] != ROW_EMPTY) t = (t + 1) & (size - 1);
        keys[t] = c->keys[s];
        entry[t] = c->entry[s];
      }
    mpm_free(c->keys);
    mpm_free(c->entry);
    c->keys = keys;
    c->entry = entry;
    c->size = size;
  }
  if (mpm_grow((void **)&c->entries, &c->entry_capacity, c->count + 1, sizeof *c->entries) ||
      mpm_grow((void **)&c->terms, &c->term_capacity, c->term_count + MPM_ROW_MAX,
               sizeof *c->terms))
    return NULL;
  struct mpm_row_entry *e = &c->entries[c->count];
  mpm_row_term own;
  if (mpm_refinement_node_is_real(&g->tree, level, idx, &own)) {
    e->owner = own.level;
    e->start = e->len = 0;
  } else {
    const int n =
        mpm_refinement_node_row(&g->tree, level, idx, c->terms + c->term_count, MPM_ROW_MAX);
    if (n < 0) return NULL;
    e->owner = -1;
    e->start = (uint32_t)c->term_count;
    e->len = (uint32_t)n;
    c->term_count += (size_t)n;
  }
  size_t s = row_slot(key, c->size);
  while (c->keys[s] != ROW_EMPTY) s = (s + 1) & (c->size - 1);
  c->keys[s] = key;
  c->entry[s] = (uint32_t)c->count;
  return &c->entries[c->count++];
}

static uint32_t *block_ids(mpm_adaptive_grid *g, int level, const int32_t bc[3]);
static int64_t block_slot_find(const mpm_adaptive_grid *g, int level, const int32_t bc[3]);

/* The row cache's entry of node idx of `level`, through its block's ids (block_ids). NULL when
 * out of memory or past MPM_ROW_MAX. */
static const struct mpm_row_entry *entry_of(mpm_adaptive_grid *g, int level, const int32_t idx[3],
                                            uint32_t *ids) {
  const int local = local_of(idx);
  if (ids[local] != UINT32_MAX) return &g->rows.entries[ids[local]];
  const int shift = fine_shift(&g->tree, level);
  uint64_t key = 0; /* the position on the finest lattice, 21 bits per axis */
  for (int d = 0; d < 3; ++d) {
    const int64_t u =
        (int64_t)idx[d] * ((int64_t)1 << shift) + ((int64_t)1 << (MPM_REFINEMENT_COORD_BITS - 1));
    if (u < 0 || u >= ((int64_t)1 << MPM_REFINEMENT_COORD_BITS)) return NULL;
    key = (key << MPM_REFINEMENT_COORD_BITS) | (uint64_t)u;
  }
  const struct mpm_row_entry *e = row_of(g, level, idx, key);
  if (e) {
    ids[local] = (uint32_t)(e - g->rows.entries);
    if (e->owner == level) /* see owned_of */
      g->blocks.owned[(size_t)(ids - g->blocks.ids) / MPM_BLOCK_NODES] |= (uint64_t)1 << local;
  }
  return e;
}

/* The nodes of a block (its ids, from block_ids) known to be real nodes owned by its level: a
 * mask of local indices, set as their rows are first looked up. */
static inline uint64_t owned_of(const mpm_adaptive_grid *g, const uint32_t *ids) {
  return g->blocks.owned[(size_t)(ids - g->blocks.ids) / MPM_BLOCK_NODES];
}

/* The row of a slot of transfer grid G, or 0 when the slot is a real node owned by its level
 * on the level's own grid. On an extra grid every slot is a ghost: a real node owned by the
 * level is a duplicate of the level grid's slot; a real node owned by a coarser level is a
 * duplicate of that level's slot on any grid. `ids`: the slot's block's (block_ids). -1 past
 * MPM_ROW_MAX or when out of memory. */
/* The row of a duplicate: node idx of `level`, a real node owned by `owner`, is the owner's node
 * at the same position. 1 term. */
static int duplicate_row(int level, int owner, const int32_t idx[3], mpm_row_term *row) {
  row[0].level = owner;
  for (int d = 0; d < 3; ++d) /* exact: the same position as a node of the owner */
    row[0].idx[d] =
        owner < level ? idx[d] / (1 << (level - owner)) : idx[d] * (1 << (owner - level));
  row[0].w = 1;
  return 1;
}

static int slot_row(mpm_adaptive_grid *g, int G, const int32_t idx[3], uint32_t *ids,
                    mpm_row_term *row) {
  const int level = level_of(g, G);
  const struct mpm_row_entry *e = entry_of(g, level, idx, ids);
  if (!e) return -1;
  if (e->owner >= 0) { /* real */
    if (e->owner == level && G < MPM_LEVELS_MAX) return 0;
    return duplicate_row(level, e->owner, idx, row);
  }
  memcpy(row, g->rows.terms + e->start, e->len * sizeof *row);
  return (int)e->len;
}

/* Room in g->build for the ghosts of one block (64) and their rows. 0, or -1 when out of
 * memory. */
static int reserve_block_ghosts(mpm_adaptive_grid *g) {
  const size_t a = g->build.count + MPM_BLOCK_NODES;
  return mpm_grow((void **)&g->build.len, &g->build.len_cap, a, sizeof *g->build.len) ||
         mpm_grow((void **)&g->build.where, &g->build.where_cap, a, sizeof *g->build.where) ||
         mpm_grow((void **)&g->build.terms, &g->build.terms_cap,
                  g->build.term_count + MPM_BLOCK_NODES * MPM_ROW_MAX, sizeof *g->build.terms);
}

/* Record ghost (G, b, local), its row's n terms already at build.terms[build.term_count ..),
 * for build_rows (room made by reserve_block_ghosts). */
static void record_ghost(mpm_adaptive_grid *g, int G, size_t b, int local, int n) {
  const size_t a = g->build.count;
  g->build.len[a] = (uint32_t)n;
  g->build.where[a][0] = (uint32_t)G;
  g->build.where[a][1] = (uint32_t)b;
  g->build.where[a][2] = (uint32_t)local;
  g->build.term_count += (size_t)n;
  g->build.count = a + 1;
}

/* Close block b of transfer grid G on the serial path: look its pending slots' rows up (made in
 * the caches on first use), record its ghosts and mark their parents (activating their
 * blocks). 0, or -1 when out of memory or past MPM_ROW_MAX. */
static int close_block_serial(mpm_adaptive_grid *g, int G, size_t b, uint64_t pending) {
  const mpm_sparse_grid *sg = &grid_of(g, G)->impl.sparse;
  const int level = level_of(g, G);
  if (!pending) return 0;
  if (G < MPM_LEVELS_MAX) { /* a block of owned real nodes has no rows */
    const int u = mpm_adaptive_grid_block_uniform(g, G, sg->coord[b]);
    if (u < 0) return -1;
    if (u) return 0;
  }
  uint32_t *ids = block_ids(g, level, sg->coord[b]);
  if (!ids) return -1;
  /* a real node owned by the level has no row on the level's grid; on an extra grid it is a
   * duplicate of the level grid's node (slot_row), here without the lookup */
  const uint64_t own = owned_of(g, ids);
  if (G < MPM_LEVELS_MAX) pending &= ~own;
  if (pending && reserve_block_ghosts(g)) return -1;
  while (pending) {
    const int local = __builtin_ctzll(pending);
    pending &= pending - 1;
    int32_t idx[3];
    node_of(sg, b, local, idx);
    mpm_row_term *row = g->build.terms + g->build.term_count;
    int n;
    if (own >> local & 1) { /* slot_row's duplicate of the level grid's node */
      n = duplicate_row(level, level, idx, row);
    } else {
      n = slot_row(g, G, idx, ids, row);
      if (n < 0) return -1;
    }
    if (n) {
      g->ghost[G][b] |= (uint64_t)1 << local;
      record_ghost(g, G, b, local, n);
    }
    /* parents are real nodes of the level grids: their own rows are empty, so nothing more
     * follows from them */
    for (int t = 0; t < n; ++t)
      if (mark(g, row[t].level, row[t].idx) < 0) return -1;
  }
  return 0;
}

/* Block b of transfer grid G (its pending slots) closed from the caches alone, changing none of
 * them and activating no block, so that blocks run in parallel. Without `at`: its ghosts and
 * their row terms counted into count[0..1]; -1 when a lookup misses or a parent's block is not
 * active (the block then takes the serial path). With `at` (after a counting pass returned 0):
 * its ghosts recorded from build index at[0] and term index at[1] on, as the serial path would
 * (parents' blocks are active, their used bits not needed: a parent's own row is empty). */
static int close_block_cached(mpm_adaptive_grid *g, int G, size_t b, uint64_t pending,
                              uint32_t count[2], const uint32_t at[2]) {
  const mpm_sparse_grid *sg = &grid_of(g, G)->impl.sparse;
  const int level = level_of(g, G);
  if (count) count[0] = count[1] = 0;
  if (!pending) return 0;
  const struct mpm_block_flags *f = &g->blocks;
  const int64_t s = block_slot_find(g, level, sg->coord[b]);
  if (s < 0) return -1;
  if (G < MPM_LEVELS_MAX && f->uniform[s]) return 0;
  if (f->ids_at[s] == UINT32_MAX) return -1;
  const uint32_t *ids = f->ids + (size_t)f->ids_at[s] * MPM_BLOCK_NODES;
  const uint64_t own = f->owned[f->ids_at[s]];
  if (G < MPM_LEVELS_MAX) pending &= ~own;
  uint32_t ghosts = 0, terms = 0;
  mpm_row_term local_row[MPM_ROW_MAX];
  while (pending) {
    const int local = __builtin_ctzll(pending);
    pending &= pending - 1;
    int32_t idx[3];
    node_of(sg, b, local, idx);
    mpm_row_term *row = at ? g->build.terms + at[1] + terms : local_row;
    int n;
    if (own >> local & 1) {
      n = duplicate_row(level, level, idx, row);
    } else {
      if (ids[local] == UINT32_MAX) return -1;
      const struct mpm_row_entry *e = &g->rows.entries[ids[local]];
      if (e->owner >= 0)
        n = e->owner == level && G < MPM_LEVELS_MAX ? 0 : duplicate_row(level, e->owner, idx, row);
      else {
        memcpy(row, g->rows.terms + e->start, e->len * sizeof *row);
        n = (int)e->len;
      }
    }
    if (!n) continue;
    if (at) {
      const size_t a = at[0] + ghosts;
      g->ghost[G][b] |= (uint64_t)1 << local;
      g->build.len[a] = (uint32_t)n;
      g->build.where[a][0] = (uint32_t)G;
      g->build.where[a][1] = (uint32_t)b;
      g->build.where[a][2] = (uint32_t)local;
    } else {
      for (int t = 0; t < n; ++t) {
        const int32_t bc[3] = {block_of(row[t].idx[0]), block_of(row[t].idx[1]),
                               block_of(row[t].idx[2])};
        if (mpm_sparse_grid_find(&g->level[row[t].level].impl.sparse, bc) < 0) return -1;
      }
    }
    ghosts++;
    terms += (uint32_t)n;
  }
  if (count) count[0] = ghosts, count[1] = terms;
  return 0;
}

/* The ghosts among the used slots, grid by grid in block order, with their rows; their parents
 * active. Blocks whose rows the caches hold (every step between two rebuilds, nearly all) are
 * counted and then recorded in parallel; the others take the serial path in their turn, so
 * that records, caches and new blocks come in the serial order whatever the threads. */
int mpm_adaptive_grid_close(mpm_adaptive_grid *g) {
  g->build.count = g->build.term_count = 0;
  FOR_GRIDS(g, G) {
    if (ensure_masks(g, G)) return -1;
    const mpm_sparse_grid *sg = &grid_of(g, G)->impl.sparse;
    const long nb = (long)sg->block_count;
    if (mpm_grow((void **)&g->closing.pending, &g->closing.pending_cap, (size_t)nb + 1,
                 sizeof *g->closing.pending) ||
        mpm_grow((void **)&g->closing.count, &g->closing.count_cap, (size_t)nb + 1,
                 sizeof *g->closing.count))
      return -1;
    uint64_t *pend = g->closing.pending;
    uint32_t(*count)[2] = g->closing.count;
    /* the caches are the tree's (else every block takes the serial path, which renews them) */
    const int cached = g->rows.version == g->tree.version &&
                       g->blocks.version == g->tree.version + 1 && g->blocks.size;
    uint64_t *used = g->used[G], *done = g->done[G];
#pragma omp parallel for schedule(dynamic, 32) if (nb > 256)
    for (long b = 0; b < nb; ++b) {
      const uint64_t p = used[b] & ~done[b];
      done[b] |= p;
      pend[b] = p;
      if (!cached || close_block_cached(g, G, (size_t)b, p, count[b], NULL))
        count[b][0] = UINT32_MAX;
    }
    for (long b = 0; b < nb; ++b) {
      if (count[b][0] == UINT32_MAX) {
        if (close_block_serial(g, G, (size_t)b, pend[b])) return -1;
        pend[b] = 0; /* done */
        continue;
      }
      const uint32_t ghosts = count[b][0], terms = count[b][1];
      if (!ghosts) {
        pend[b] = 0;
        continue;
      }
      const size_t a = g->build.count + ghosts, t = g->build.term_count + terms;
      if (mpm_grow((void **)&g->build.len, &g->build.len_cap, a, sizeof *g->build.len) ||
          mpm_grow((void **)&g->build.where, &g->build.where_cap, a, sizeof *g->build.where) ||
          mpm_grow((void **)&g->build.terms, &g->build.terms_cap, t, sizeof *g->build.terms))
        return -1;
      count[b][0] = (uint32_t)g->build.count; /* now where its records start */
      count[b][1] = (uint32_t)g->build.term_count;
      g->build.count = a;
      g->build.term_count = t;
    }
    /* slots the serial path marked on this grid itself, new blocks included (parents of its
     * own level: real, so without rows; not expected, but closed as the serial loop would) */
    if (ensure_masks(g, G)) return -1;
    for (size_t b = 0; b < sg->block_count; ++b) {
      const uint64_t p = g->used[G][b] & ~g->done[G][b];
      if (!p) continue;
      g->done[G][b] |= p;
      if (close_block_serial(g, G, b, p)) return -1;
    }
#pragma omp parallel for schedule(dynamic, 32) if (nb > 256)
    for (long b = 0; b < nb; ++b)
      if (pend[b]) close_block_cached(g, G, (size_t)b, pend[b], NULL, count[b]);
  }
  return 0;
}

int64_t mpm_adaptive_grid_slot(const mpm_adaptive_grid *g, int level, const int32_t idx[3]) {
  const mpm_grid *lv = &g->level[level];
  const int32_t bc[3] = {block_of(idx[0]), block_of(idx[1]), block_of(idx[2])};
  const int32_t b = mpm_sparse_grid_find(&lv->impl.sparse, bc);
  if (b < 0) return -1;
  const int local = local_of(idx);
  return (int64_t)lv->dof_begin + (int64_t)b * MPM_BLOCK_NODES + local;
}

static int reserve_ghosts(mpm_adaptive_grid *g, size_t n) {
  if (n <= g->ghost_capacity) return 0;
  size_t cap = g->ghost_capacity ? g->ghost_capacity : 1024;
  while (cap < n) cap *= 2;
  uint32_t *slot = mpm_alloc(cap * sizeof *slot);
  mpm_real *scratch = mpm_alloc(4 * cap * sizeof *scratch);
  mpm_real *spread = mpm_alloc(6 * cap * sizeof(mpm_real));
  if (!slot || !scratch || !spread) {
    mpm_free(slot);
    mpm_free(scratch);
    mpm_free(spread);
    return -1;
  }
  mpm_free(g->spread);
  g->spread = spread; /* filled by build_rows after every ghost is known */
  if (g->ghost_count) memcpy(slot, g->ghost_slot, g->ghost_count * sizeof *slot);
  mpm_free(g->ghost_slot);
  mpm_free(g->scratch);
  g->ghost_slot = slot;
  g->scratch = scratch;
  g->ghost_capacity = cap;
  return 0;
}

/* The ghosts' scatter in parallel, the same sums for any number of threads: ghosts grouped by
 * the level-0 block they lie in, coloured by its parity. A ghost's parents lie less than two
 * level-0 cells from it (build_rows checks, else the scatter stays serial), so ghosts in two
 * blocks of one colour, 4 level-0 cells apart at least, never share a parent. 0, or -1 when out
 * of memory. */
static int build_schedule(mpm_adaptive_grid *g) {
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
    if (!g->schedule.table_size) return -1;
  }
  size = g->schedule.table_size;
  if (mpm_grow((void **)&g->schedule.key, &g->schedule.key_cap, n + 1, sizeof(int32_t)) ||
      mpm_grow((void **)&g->schedule.colour, &g->schedule.colour_cap, runs + 1, 1))
    return -1;
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

int mpm_adaptive_grid_build_rows(mpm_adaptive_grid *g) {
  /* the ghosts close() found, in its order (grid, block, slot); the build arrays are kept from
   * step to step: fresh pages for tens of MB every step cost more than filling them */
  const uint32_t *len = g->build.len, (*where)[3] = g->build.where;
  const mpm_row_term *terms = g->build.terms;
  g->ghost_count = 0;
  if (reserve_ghosts(g, g->build.count + 1)) return -1;
  g->ghost_count = g->build.count;
  int status = -1;
  if (mpm_embedding_layout(&g->ghosts, g->ghost_count, len, 0)) goto done;
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
      goto done;
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
  if (inactive) goto done;
  status = far ? 0 : build_schedule(g);
done:
  return status;
}

void mpm_adaptive_grid_scatter(mpm_adaptive_grid *g, int fields, mpm_real *const *u) {
  const size_t n = g->ghost_count;
  if (!n) return;
  for (int f0 = 0; f0 < fields; f0 += 3) {
    const int k = fields - f0 < 3 ? fields - f0 : 3;
    const mpm_real *c[3];
    for (int j = 0; j < k; ++j) {
      mpm_real *cj = g->scratch + (size_t)j * g->ghost_capacity;
      for (size_t a = 0; a < n; ++a) {
        cj[a] = u[f0 + j][g->ghost_slot[a]];
        u[f0 + j][g->ghost_slot[a]] = 0;
      }
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
    for (int j = 0; j < k; ++j)
      for (size_t a = 0; a < n; ++a) u[f0 + j][g->ghost_slot[a]] = c[j][a];
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
    for (size_t a = 0; a < n; ++a) {
      cj[a] = u[j][g->ghost_slot[a]];
      u[j][g->ghost_slot[a]] = 0;
    }
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

static inline uint64_t block_flags_key(int level, const int32_t bc[3]) {
  uint64_t key = (uint64_t)level;
  for (int d = 0; d < 3; ++d) key = key << 20 | ((uint64_t)(bc[d] + (1 << 19)) & 0xfffff);
  return key;
}

static inline size_t block_flags_hash(uint64_t key, size_t size) {
  return (size_t)((key * 0x9e3779b97f4a7c15ull) >> 20) & (size - 1);
}

/* The hash slot of (level, block bc) in g->blocks if it was made (block_slot), else -1; reads
 * only (the caller checked that the table is the tree's). */
static int64_t block_slot_find(const mpm_adaptive_grid *g, int level, const int32_t bc[3]) {
  const struct mpm_block_flags *f = &g->blocks;
  if (!f->size) return -1;
  const uint64_t key = block_flags_key(level, bc);
  for (size_t s = block_flags_hash(key, f->size); f->keys[s] != UINT64_MAX;
       s = (s + 1) & (f->size - 1))
    if (f->keys[s] == key) return (int64_t)s;
  return -1;
}

/* The hash slot of (level, block bc) in g->blocks, made (with its uniform flag) on first use;
 * the table is emptied when the tree changes. -1 when out of memory. */
static int64_t block_slot(mpm_adaptive_grid *g, int level, const int32_t bc[3]) {
  struct mpm_block_flags *f = &g->blocks;
  const mpm_refinement *r = &g->tree;
  if (f->version != r->version + 1) { /* + 1: a fresh cache is never valid */
    if (f->size) memset(f->keys, 0xff, f->size * sizeof *f->keys);
    f->count = f->id_blocks = 0;
    f->version = r->version + 1;
  }
  const uint64_t key = block_flags_key(level, bc);
  if (2 * (f->count + 1) > f->size) {
    const size_t size = f->size ? 2 * f->size : 4096;
    uint64_t *keys = mpm_alloc(size * sizeof *keys);
    uint8_t *uniform = mpm_alloc(size);
    uint32_t *ids_at = mpm_alloc(size * sizeof *ids_at);
    if (!keys || !uniform || !ids_at) {
      mpm_free(keys);
      mpm_free(uniform);
      mpm_free(ids_at);
      return -1;
    }
    memset(keys, 0xff, size * sizeof *keys);
    for (size_t s = 0; s < f->size; ++s)
      if (f->keys[s] != UINT64_MAX) {
        size_t t = block_flags_hash(f->keys[s], size);
        while (keys[t] != UINT64_MAX) t = (t + 1) & (size - 1);
        keys[t] = f->keys[s];
        uniform[t] = f->uniform[s];
        ids_at[t] = f->ids_at[s];
      }
    mpm_free(f->keys);
    mpm_free(f->uniform);
    mpm_free(f->ids_at);
    f->keys = keys;
    f->uniform = uniform;
    f->ids_at = ids_at;
    f->size = size;
  }
  size_t s = block_flags_hash(key, f->size);
  for (; f->keys[s] != UINT64_MAX; s = (s + 1) & (f->size - 1))
    if (f->keys[s] == key) return (int64_t)s;
  const double dx = (double)mpm_refinement_dx(r, level);
  mpm_real lo[3], hi[3];
  for (int d = 0; d < 3; ++d) {
    lo[d] =
        (mpm_real)((double)r->origin[d] + ((double)bc[d] * MPM_BLOCK - MPM_UNIFORM_MARGIN) * dx);
    hi[d] = (mpm_real)((double)r->origin[d] +
                       ((double)bc[d] * MPM_BLOCK + MPM_BLOCK + MPM_UNIFORM_MARGIN) * dx);
  }
  const int u = mpm_refinement_finest_level_in(r, lo, hi) == level &&
                mpm_refinement_coarsest_level_in(r, lo, hi) == level;
  f->keys[s] = key;
  f->uniform[s] = (uint8_t)u;
  f->ids_at[s] = UINT32_MAX;
  f->count++;
  return (int64_t)s;
}

int mpm_adaptive_grid_block_uniform(mpm_adaptive_grid *g, int level, const int32_t bc[3]) {
  const int64_t s = block_slot(g, level, bc);
  return s < 0 ? -1 : g->blocks.uniform[s];
}

/* The row-cache ids of the nodes of (level, block bc): valid until the next call (the pool may
 * move). NULL when out of memory. */
static uint32_t *block_ids(mpm_adaptive_grid *g, int level, const int32_t bc[3]) {
  struct mpm_block_flags *f = &g->blocks;
  const int64_t s = block_slot(g, level, bc);
  if (s < 0) return NULL;
  if (f->ids_at[s] == UINT32_MAX) {
    if (mpm_grow((void **)&f->ids, &f->id_capacity, (f->id_blocks + 1) * MPM_BLOCK_NODES,
                 sizeof *f->ids))
      return NULL;
    if (mpm_grow((void **)&f->owned, &f->owned_capacity, f->id_blocks + 1, sizeof *f->owned))
      return NULL;
    memset(f->ids + f->id_blocks * MPM_BLOCK_NODES, 0xff, MPM_BLOCK_NODES * sizeof *f->ids);
    f->owned[f->id_blocks] = 0;
    f->ids_at[s] = (uint32_t)f->id_blocks++;
  }
  return f->ids + (size_t)f->ids_at[s] * MPM_BLOCK_NODES;
}

size_t mpm_adaptive_grid_bytes(const mpm_adaptive_grid *g) {
  size_t b = mpm_refinement_bytes(&g->tree) + mpm_embedding_bytes(&g->ghosts) +
             g->ghost_capacity * (sizeof(uint32_t) + 10 * sizeof(mpm_real)) +
             3 * g->offset_capacity * sizeof(mpm_real) + g->build.len_cap * sizeof(uint32_t) +
             g->build.terms_cap * sizeof(mpm_row_term) +
             g->build.where_cap * sizeof *g->build.where +
             g->blocks.id_capacity * sizeof(uint32_t) + g->blocks.owned_capacity * sizeof(uint64_t);
  FOR_GRIDS(g, G)
  b += grid_of((mpm_adaptive_grid *)g, G)->ops->bytes(grid_of((mpm_adaptive_grid *)g, G));
  return b;
}
