/* close.c - the closure of the multi-level grid's used slots (Gao et al. 2017,
 * sec. 6.1, adaptive/grid.h: mpm_adaptive_grid_close): which used slots are ghosts, their rows
 * (T-junctions and duplicates), and their parents marked in turn; with the two caches that make
 * it cheap between changes of the tree: the rows of nodes by finest-lattice position, and per
 * block its uniform flag and its nodes' row ids. */
#include "adaptive/grid.h"
#include "adaptive/grid_parts.h"

#include "core/alloc.h"

#include <string.h>

/* ---- the block cache: uniform flags and row ids by (level, block) ---- */

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
    uint64_t *cells = mpm_alloc(2 * size * sizeof *cells);
    uint8_t *cells_known = mpm_alloc(size);
    if (!keys || !uniform || !ids_at || !cells || !cells_known) {
      mpm_free(keys);
      mpm_free(uniform);
      mpm_free(ids_at);
      mpm_free(cells);
      mpm_free(cells_known);
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
        cells[2 * t] = f->cells[2 * s];
        cells[2 * t + 1] = f->cells[2 * s + 1];
        cells_known[t] = f->cells_known[s];
      }
    mpm_free(f->keys);
    mpm_free(f->uniform);
    mpm_free(f->ids_at);
    mpm_free(f->cells);
    mpm_free(f->cells_known);
    f->keys = keys;
    f->uniform = uniform;
    f->ids_at = ids_at;
    f->cells = cells;
    f->cells_known = cells_known;
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
  f->cells_known[s] = 0;
  f->ids_at[s] = UINT32_MAX;
  f->count++;
  return (int64_t)s;
}

mpm_status mpm_adaptive_grid_block_uniform(mpm_adaptive_grid *g, int level, const int32_t bc[3],
                                           int *uniform) {
  const int64_t s = block_slot(g, level, bc);
  if (s < 0) return MPM_ERR_NOMEM;
  *uniform = g->blocks.uniform[s];
  return MPM_OK;
}

/* Whether cell c of `level` is a leaf: not refined, and its parent refined (or level 0). */
static int is_leaf(const mpm_refinement *r, int level, const int32_t c[3]) {
  if (mpm_refinement_is_refined(r, level, c)) return 0;
  if (level == 0) return 1;
  const int32_t parent[3] = {c[0] >> 1, c[1] >> 1, c[2] >> 1}; /* floor: arithmetic shift */
  return mpm_refinement_is_refined(r, level - 1, parent);
}

/* The block's stable cells for a reach of `reach` cells above (and one below) a particle's base
 * cell: every cell from one below to `reach` above a leaf of `level` (the leaves tested once
 * each over the block's pad, then a running AND along each axis). */
enum { STABLE_REACH_MAX = 3, STABLE_PAD = MPM_BLOCK + 1 + STABLE_REACH_MAX };
static uint64_t stable_cells(const mpm_refinement *r, int level, const int32_t bc[3], int reach) {
  const int P = MPM_BLOCK + 1 + reach, W = reach + 2; /* W: one below, the cell, reach above */
  uint8_t leaf[STABLE_PAD][STABLE_PAD][STABLE_PAD], ax[MPM_BLOCK][STABLE_PAD][STABLE_PAD],
      ay[MPM_BLOCK][MPM_BLOCK][STABLE_PAD];
  for (int i = 0; i < P; ++i)
    for (int j = 0; j < P; ++j)
      for (int k = 0; k < P; ++k) {
        const int32_t c[3] = {bc[0] * MPM_BLOCK - 1 + i, bc[1] * MPM_BLOCK - 1 + j,
                              bc[2] * MPM_BLOCK - 1 + k};
        leaf[i][j][k] = (uint8_t)is_leaf(r, level, c);
      }
  for (int i = 0; i < MPM_BLOCK; ++i)
    for (int j = 0; j < P; ++j)
      for (int k = 0; k < P; ++k) {
        uint8_t all = 1;
        for (int o = 0; o < W; ++o) all &= leaf[i + o][j][k];
        ax[i][j][k] = all;
      }
  for (int i = 0; i < MPM_BLOCK; ++i)
    for (int j = 0; j < MPM_BLOCK; ++j)
      for (int k = 0; k < P; ++k) {
        uint8_t all = 1;
        for (int o = 0; o < W; ++o) all &= ax[i][j + o][k];
        ay[i][j][k] = all;
      }
  uint64_t mask = 0;
  for (int i = 0; i < MPM_BLOCK; ++i)
    for (int j = 0; j < MPM_BLOCK; ++j)
      for (int k = 0; k < MPM_BLOCK; ++k) {
        uint8_t all = 1;
        for (int o = 0; o < W; ++o) all &= ay[i][j][k + o];
        if (all) mask |= (uint64_t)1 << (i << 4 | j << 2 | k);
      }
  return mask;
}

mpm_status mpm_adaptive_grid_block_stable_cells(mpm_adaptive_grid *g, int level,
                                                const int32_t bc[3], int reach, uint64_t *mask) {
  if (reach < 2 || reach > STABLE_REACH_MAX) {
    *mask = 0; /* not a reach the cache keeps: no cell is stable */
    return MPM_OK;
  }
  const int64_t s = block_slot(g, level, bc);
  if (s < 0) return MPM_ERR_NOMEM;
  struct mpm_block_flags *f = &g->blocks;
  if (f->uniform[s]) {
    *mask = ~(uint64_t)0;
    return MPM_OK;
  }
  const int which = reach - 2;
  if (!(f->cells_known[s] >> which & 1)) {
    f->cells[2 * s + (size_t)which] = stable_cells(&g->tree, level, bc, reach);
    f->cells_known[s] |= (uint8_t)(1 << which);
  }
  *mask = f->cells[2 * s + (size_t)which];
  return MPM_OK;
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

/* ---- the row cache ---- */

#define ROW_EMPTY UINT64_MAX

void mpm_adaptive_rows_free(struct mpm_row_cache *c) {
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

/* The cache's entry for node idx of `level` at finest-lattice position key into *out, made on
 * first use (a real node: its owner level; else its row). MPM_OK; MPM_ERR_NOMEM when out of
 * memory; MPM_ERR_INVALID when the row needs more than MPM_ROW_MAX entries. */
static mpm_status row_of(mpm_adaptive_grid *g, int level, const int32_t idx[3], uint64_t key,
                         const struct mpm_row_entry **out) {
  struct mpm_row_cache *c = &g->rows;
  if (c->version != g->tree.version) { /* the tree changed: forget every row */
    if (c->size) memset(c->keys, 0xff, c->size * sizeof *c->keys);
    c->count = c->term_count = 0;
    c->version = g->tree.version;
  }
  if (c->size)
    for (size_t s = row_slot(key, c->size);; s = (s + 1) & (c->size - 1)) {
      if (c->keys[s] == key) {
        *out = &c->entries[c->entry[s]];
        return MPM_OK;
      }
      if (c->keys[s] == ROW_EMPTY) break;
    }
  if (2 * (c->count + 1) > c->size) { /* grow the table, keep the entries */
    const size_t size = c->size ? 2 * c->size : 4096;
    uint64_t *keys = mpm_alloc(size * sizeof *keys);
    uint32_t *entry = mpm_alloc(size * sizeof *entry);
    if (!keys || !entry) {
      mpm_free(keys);
      mpm_free(entry);
      return MPM_ERR_NOMEM;
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
    return MPM_ERR_NOMEM;
  struct mpm_row_entry *e = &c->entries[c->count];
  mpm_row_term own;
  if (mpm_refinement_node_is_real(&g->tree, level, idx, &own)) {
    e->owner = own.level;
    e->start = e->len = 0;
  } else {
    const int n =
        mpm_refinement_node_row(&g->tree, level, idx, c->terms + c->term_count, MPM_ROW_MAX);
    if (n < 0) return MPM_ERR_INVALID;
    e->owner = -1;
    e->start = (uint32_t)c->term_count;
    e->len = (uint32_t)n;
    c->term_count += (size_t)n;
  }
  size_t s = row_slot(key, c->size);
  while (c->keys[s] != ROW_EMPTY) s = (s + 1) & (c->size - 1);
  c->keys[s] = key;
  c->entry[s] = (uint32_t)c->count;
  *out = &c->entries[c->count++];
  return MPM_OK;
}

/* The row cache's entry of node idx of `level` into *out, through its block's ids (block_ids).
 * MPM_OK; MPM_ERR_NOMEM when out of memory; MPM_ERR_INVALID past MPM_ROW_MAX or outside the
 * coordinate range. */
static mpm_status entry_of(mpm_adaptive_grid *g, int level, const int32_t idx[3], uint32_t *ids,
                           const struct mpm_row_entry **out) {
  const int local = local_of(idx);
  if (ids[local] != UINT32_MAX) {
    *out = &g->rows.entries[ids[local]];
    return MPM_OK;
  }
  const int shift = fine_shift(&g->tree, level);
  uint64_t key = 0; /* the position on the finest lattice, 21 bits per axis */
  for (int d = 0; d < 3; ++d) {
    const int64_t u =
        (int64_t)idx[d] * ((int64_t)1 << shift) + ((int64_t)1 << (MPM_REFINEMENT_COORD_BITS - 1));
    if (u < 0 || u >= ((int64_t)1 << MPM_REFINEMENT_COORD_BITS)) return MPM_ERR_INVALID;
    key = (key << MPM_REFINEMENT_COORD_BITS) | (uint64_t)u;
  }
  const struct mpm_row_entry *e;
  const mpm_status st = row_of(g, level, idx, key, &e);
  if (st != MPM_OK) return st;
  ids[local] = (uint32_t)(e - g->rows.entries);
  if (e->owner == level) /* see owned_of */
    g->blocks.owned[(size_t)(ids - g->blocks.ids) / MPM_BLOCK_NODES] |= (uint64_t)1 << local;
  *out = e;
  return MPM_OK;
}

/* The nodes of a block (its ids, from block_ids) known to be real nodes owned by its level: a
 * mask of local indices, set as their rows are first looked up. */
static inline uint64_t owned_of(const mpm_adaptive_grid *g, const uint32_t *ids) {
  return g->blocks.owned[(size_t)(ids - g->blocks.ids) / MPM_BLOCK_NODES];
}

/* The row of a slot of transfer grid G (its length in *n), or 0 terms when the slot is a real
 * node owned by its level on the level's own grid. On an extra grid every slot is a ghost: a real
 * node owned by the level is a duplicate of the level grid's slot; a real node owned by a coarser
 * level is a duplicate of that level's slot on any grid. `ids`: the slot's block's (block_ids).
 * MPM_OK, or entry_of's failure. */
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

static mpm_status slot_row(mpm_adaptive_grid *g, int G, const int32_t idx[3], uint32_t *ids,
                           mpm_row_term *row, int *n) {
  const int level = level_of(g, G);
  const struct mpm_row_entry *e;
  const mpm_status st = entry_of(g, level, idx, ids, &e);
  if (st != MPM_OK) return st;
  if (e->owner >= 0) /* real */
    *n = e->owner == level && G < MPM_LEVELS_MAX ? 0 : duplicate_row(level, e->owner, idx, row);
  else {
    memcpy(row, g->rows.terms + e->start, e->len * sizeof *row);
    *n = (int)e->len;
  }
  return MPM_OK;
}

/* Room in g->build for the ghosts of one block (64) and their rows. MPM_OK, or MPM_ERR_NOMEM
 * when out of memory. */
static mpm_status reserve_block_ghosts(mpm_adaptive_grid *g) {
  const size_t a = g->build.count + MPM_BLOCK_NODES;
  if (mpm_grow((void **)&g->build.len, &g->build.len_cap, a, sizeof *g->build.len) ||
      mpm_grow((void **)&g->build.where, &g->build.where_cap, a, sizeof *g->build.where) ||
      mpm_grow((void **)&g->build.terms, &g->build.terms_cap,
               g->build.term_count + MPM_BLOCK_NODES * MPM_ROW_MAX, sizeof *g->build.terms))
    return MPM_ERR_NOMEM;
  return MPM_OK;
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
 * blocks). MPM_OK; MPM_ERR_NOMEM when out of memory; MPM_ERR_INVALID past MPM_ROW_MAX. */
static mpm_status close_block_serial(mpm_adaptive_grid *g, int G, size_t b, uint64_t pending) {
  const mpm_sparse_grid *sg = &grid_of(g, G)->impl.sparse;
  const int level = level_of(g, G);
  if (!pending) return MPM_OK;
  if (G < MPM_LEVELS_MAX) { /* a block of owned real nodes has no rows */
    int u;
    if (mpm_adaptive_grid_block_uniform(g, G, sg->coord[b], &u) != MPM_OK) return MPM_ERR_NOMEM;
    if (u) return MPM_OK;
  }
  uint32_t *ids = block_ids(g, level, sg->coord[b]);
  if (!ids) return MPM_ERR_NOMEM;
  /* a real node owned by the level has no row on the level's grid; on an extra grid it is a
   * duplicate of the level grid's node (slot_row), here without the lookup */
  const uint64_t own = owned_of(g, ids);
  if (G < MPM_LEVELS_MAX) pending &= ~own;
  if (pending && reserve_block_ghosts(g) != MPM_OK) return MPM_ERR_NOMEM;
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
      const mpm_status st = slot_row(g, G, idx, ids, row, &n);
      if (st != MPM_OK) return st;
    }
    if (n) {
      g->ghost[G][b] |= (uint64_t)1 << local;
      record_ghost(g, G, b, local, n);
    }
    /* parents are real nodes of the level grids: their own rows are empty, so nothing more
     * follows from them */
    for (int t = 0; t < n; ++t)
      if (mpm_adaptive_mark(g, row[t].level, row[t].idx) != MPM_OK) return MPM_ERR_NOMEM;
  }
  return MPM_OK;
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
mpm_status mpm_adaptive_grid_close(mpm_adaptive_grid *g) {
  g->build.count = g->build.term_count = 0;
  FOR_GRIDS(g, G) {
    if (mpm_adaptive_ensure_masks(g, G)) return MPM_ERR_NOMEM;
    const mpm_sparse_grid *sg = &grid_of(g, G)->impl.sparse;
    const long nb = (long)sg->block_count;
    if (mpm_grow((void **)&g->closing.pending, &g->closing.pending_cap, (size_t)nb + 1,
                 sizeof *g->closing.pending) ||
        mpm_grow((void **)&g->closing.count, &g->closing.count_cap, (size_t)nb + 1,
                 sizeof *g->closing.count))
      return MPM_ERR_NOMEM;
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
        const mpm_status st = close_block_serial(g, G, (size_t)b, pend[b]);
        if (st != MPM_OK) return st;
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
        return MPM_ERR_NOMEM;
      count[b][0] = (uint32_t)g->build.count; /* now where its records start */
      count[b][1] = (uint32_t)g->build.term_count;
      g->build.count = a;
      g->build.term_count = t;
    }
    /* slots the serial path marked on this grid itself, new blocks included (parents of its
     * own level: real, so without rows; not expected, but closed as the serial loop would) */
    if (mpm_adaptive_ensure_masks(g, G)) return MPM_ERR_NOMEM;
    for (size_t b = 0; b < sg->block_count; ++b) {
      const uint64_t p = g->used[G][b] & ~g->done[G][b];
      if (!p) continue;
      g->done[G][b] |= p;
      const mpm_status st = close_block_serial(g, G, b, p);
      if (st != MPM_OK) return st;
    }
#pragma omp parallel for schedule(dynamic, 32) if (nb > 256)
    for (long b = 0; b < nb; ++b)
      if (pend[b]) close_block_cached(g, G, (size_t)b, pend[b], NULL, count[b]);
  }
  return MPM_OK;
}
