/* refinement.c - the leaf cells of the multi-level grid and the constrained T-junction basis
 * (Gao et al. 2017, sec. 5.2 and 6.1); see refinement.h. */
#include "adaptive/refinement.h"

#include "core/alloc.h"

#include <assert.h>
#include <math.h>
#include <string.h>

#define EMPTY_KEY UINT64_MAX
#define COORD_OFFSET (1 << (MPM_REFINEMENT_COORD_BITS - 1))

/* ---- cell sets ---- */

static int pack(const int32_t c[3], uint64_t *key) {
  uint64_t k = 0;
  for (int d = 0; d < 3; ++d) {
    const int64_t u = (int64_t)c[d] + COORD_OFFSET;
    if (u < 0 || u >= ((int64_t)1 << MPM_REFINEMENT_COORD_BITS)) return -1;
    k = (k << MPM_REFINEMENT_COORD_BITS) | (uint64_t)u;
  }
  *key = k;
  return 0;
}

static void unpack(uint64_t key, int32_t c[3]) {
  const uint64_t mask = ((uint64_t)1 << MPM_REFINEMENT_COORD_BITS) - 1;
  for (int d = 2; d >= 0; --d) {
    c[d] = (int32_t)((int64_t)(key & mask) - COORD_OFFSET);
    key >>= MPM_REFINEMENT_COORD_BITS;
  }
}

static size_t slot_of(uint64_t key, size_t size) {
  uint64_t h = key * 0x9e3779b97f4a7c15ull;
  h ^= h >> 29;
  return (size_t)h & (size - 1);
}

/* The bit of cell c in the dense index, or -1 when c lies outside it. */
static inline int64_t dense_bit(const mpm_cell_set *s, const int32_t c[3]) {
  int64_t b = 0;
  for (int d = 0; d < 3; ++d) {
    const int64_t u = (int64_t)c[d] - s->lo[d];
    if (u < 0 || u >= s->n[d]) return -1;
    b = b * s->n[d] + u;
  }
  return b;
}

static int set_contains(const mpm_cell_set *s, const int32_t c[3]) {
  uint64_t key;
  if (s->bits) {
    const int64_t b = dense_bit(s, c);
    if (b >= 0) return (int)(s->bits[b >> 6] >> (b & 63) & 1);
  }
  if (s->count == 0 || pack(c, &key)) return 0;
  for (size_t i = slot_of(key, s->size);; i = (i + 1) & (s->size - 1)) {
    if (s->keys[i] == key) return 1;
    if (s->keys[i] == EMPTY_KEY) return 0;
  }
}

int mpm_refinement_same_cells(const mpm_refinement *a, const mpm_refinement *b) {
  if (a->levels != b->levels || a->dx0 != b->dx0) return 0;
  for (int d = 0; d < 3; ++d)
    if (a->origin[d] != b->origin[d]) return 0;
  for (int L = 0; L < a->levels; ++L) {
    const mpm_cell_set *sa = &a->refined[L], *sb = &b->refined[L];
    if (sa->count != sb->count) return 0;
    for (size_t i = 0; i < sa->size; ++i) {
      if (sa->keys[i] == EMPTY_KEY) continue;
      int32_t c[3];
      unpack(sa->keys[i], c);
      if (!set_contains(sb, c)) return 0;
    }
  }
  return 1;
}

static void set_put(uint64_t *keys, size_t size, uint64_t key) {
  size_t i = slot_of(key, size);
  while (keys[i] != EMPTY_KEY && keys[i] != key) i = (i + 1) & (size - 1);
  keys[i] = key;
}

/* Insert c (*inserted: 1, or 0 when it was there already). MPM_OK; MPM_ERR_INVALID when c is out
 * of the coordinate range; MPM_ERR_NOMEM when out of memory. */
static mpm_status set_insert(mpm_cell_set *s, const int32_t c[3], int *inserted) {
  uint64_t key;
  *inserted = 0;
  if (pack(c, &key)) return MPM_ERR_INVALID;
  if (set_contains(s, c)) return MPM_OK;
  if (2 * (s->count + 1) > s->size) {
    const size_t size = s->size ? 2 * s->size : 64;
    uint64_t *keys = mpm_alloc(size * sizeof *keys);
    if (!keys) return MPM_ERR_NOMEM;
    memset(keys, 0xff, size * sizeof *keys);
    for (size_t i = 0; i < s->size; ++i)
      if (s->keys[i] != EMPTY_KEY) set_put(keys, size, s->keys[i]);
    mpm_free(s->keys);
    s->keys = keys;
    s->size = size;
  }
  set_put(s->keys, s->size, key);
  s->count++;
  if (s->bits) {
    const int64_t b = dense_bit(s, c);
    if (b >= 0) s->bits[b >> 6] |= (uint64_t)1 << (b & 63);
  }
  *inserted = 1;
  return MPM_OK;
}

/* ---- the tree ---- */

void mpm_refinement_init(mpm_refinement *r, int levels, const mpm_real origin[3], mpm_real dx0) {
  assert(levels >= 1 && levels <= MPM_LEVELS_MAX);
  memset(r, 0, sizeof *r);
  r->levels = levels;
  for (int d = 0; d < 3; ++d) r->origin[d] = origin[d];
  r->dx0 = dx0;
}

void mpm_refinement_free(mpm_refinement *r) {
  for (int L = 0; L < MPM_LEVELS_MAX; ++L) {
    mpm_free(r->refined[L].keys);
    mpm_free(r->refined[L].bits);
  }
  memset(r->refined, 0, sizeof r->refined);
}

/* floor(c / 2^s) for any sign */
static inline int32_t shr_floor(int32_t c, int s) {
  return c >= 0 ? c >> s : -(int32_t)(((uint32_t)(-(c + 1))) >> s) - 1;
}

/* Levels below `level` in finest-lattice units: a level-L index times 2^fine_shift(L). */
static inline int fine_shift(const mpm_refinement *r, int level) {
  return r->levels - 1 - level;
}

mpm_status mpm_refinement_refine(mpm_refinement *r, int level, const int32_t cell[3]) {
  if (level < 0 || level >= r->levels - 1) return MPM_ERR_INVALID;
  for (int L = level; L >= 0; --L) {
    int32_t c[3];
    for (int d = 0; d < 3; ++d) c[d] = shr_floor(cell[d], level - L);
    int inserted;
    const mpm_status st = set_insert(&r->refined[L], c, &inserted);
    if (st != MPM_OK) return st;
    if (!inserted) break; /* its ancestors are refined already */
    r->version++;
  }
  return MPM_OK;
}

int mpm_refinement_is_refined(const mpm_refinement *r, int level, const int32_t cell[3]) {
  if (level < 0 || level >= r->levels - 1) return 0;
  return set_contains(&r->refined[level], cell);
}

int mpm_refinement_leaf_level(const mpm_refinement *r, const int32_t c[3]) {
  for (int L = 0; L < r->levels - 1; ++L) {
    int32_t cl[3];
    for (int d = 0; d < 3; ++d) cl[d] = shr_floor(c[d], fine_shift(r, L));
    if (!set_contains(&r->refined[L], cl)) return L;
  }
  return r->levels - 1;
}

int mpm_refinement_leaf_at(const mpm_refinement *r, const mpm_real x[3], int32_t cell[3]) {
  const mpm_real inv = 1 / mpm_refinement_dx(r, r->levels - 1);
  int32_t c[3];
  for (int d = 0; d < 3; ++d) c[d] = (int32_t)mpm_floor((x[d] - r->origin[d]) * inv);
  const int L = mpm_refinement_leaf_level(r, c);
  for (int d = 0; d < 3; ++d) cell[d] = shr_floor(c[d], fine_shift(r, L));
  return L;
}

/* The coarsest level of the leaves under cell c of level L that meet [lo, hi] (in level L's
 * cell units). */
static int coarsest_under(const mpm_refinement *r, int L, const int32_t c[3], const double lo[3],
                          const double hi[3]) {
  if (L == r->levels - 1 || !set_contains(&r->refined[L], c)) return L;
  int best = r->levels - 1;
  for (int k = 0; k < 8 && best > L + 1; ++k) {
    int32_t child[3];
    double clo[3], chi[3];
    int meets = 1;
    for (int d = 0; d < 3; ++d) {
      child[d] = 2 * c[d] + ((k >> d) & 1);
      clo[d] = 2 * lo[d];
      chi[d] = 2 * hi[d];
      /* the child spans [child, child + 1] in its own units */
      if (chi[d] < (double)child[d] || clo[d] > (double)child[d] + 1) meets = 0;
    }
    if (!meets) continue;
    const int f = coarsest_under(r, L + 1, child, clo, chi);
    if (f < best) best = f;
  }
  return best;
}

/* The box [lo, hi] in level-0 cell units, as every query here computes it. */
static void to_units(const mpm_refinement *r, const mpm_real lo[3], const mpm_real hi[3],
                     double a[3], double b[3]) {
  for (int d = 0; d < 3; ++d) {
    a[d] = ((double)lo[d] - (double)r->origin[d]) / (double)r->dx0;
    b[d] = ((double)hi[d] - (double)r->origin[d]) / (double)r->dx0;
  }
}

int mpm_refinement_coarsest_level_in(const mpm_refinement *r, const mpm_real lo[3],
                                     const mpm_real hi[3]) {
  double a[3], b[3];
  to_units(r, lo, hi, a, b);
  int32_t c0[3], c1[3];
  for (int d = 0; d < 3; ++d) {
    c0[d] = (int32_t)floor(a[d]);
    c1[d] = (int32_t)floor(b[d]);
  }
  int best = r->levels - 1;
  for (int32_t i = c0[0]; i <= c1[0]; ++i)
    for (int32_t j = c0[1]; j <= c1[1]; ++j)
      for (int32_t k = c0[2]; k <= c1[2]; ++k) {
        const int32_t c[3] = {i, j, k};
        const int f = coarsest_under(r, 0, c, a, b);
        if (f < best) best = f;
        if (best == 0) return 0; /* nothing goes past it */
      }
  return best;
}

/* 1 when a cell of set s lies in the index box l .. h (inclusive). */
static int any_in(const mpm_cell_set *s, const int32_t l[3], const int32_t h[3]) {
  for (int32_t i = l[0]; i <= h[0]; ++i)
    for (int32_t j = l[1]; j <= h[1]; ++j)
      for (int32_t k = l[2]; k <= h[2]; ++k) {
        const int32_t c[3] = {i, j, k};
        if (set_contains(s, c)) return 1;
      }
  return 0;
}

/* The finest level of the leaves meeting the box, without descending the tree: a leaf of level
 * L + 1 meets the box exactly when its refined parent of level L does (the children cover their
 * parent), so the answer is one more than the finest level with a refined cell meeting the box
 * (finest level first), or 0. It asks about the cells the first version's descent reached, so
 * that the answer is its answer bit for bit: closed at every level (a cell touching the box
 * counts), but only under the level-0 cells from the one holding the box's low corner on. */
int mpm_refinement_finest_level_in(const mpm_refinement *r, const mpm_real lo[3],
                                   const mpm_real hi[3]) {
  double a[3], b[3];
  to_units(r, lo, hi, a, b);
  int32_t c0[3];
  for (int d = 0; d < 3; ++d) c0[d] = (int32_t)floor(a[d]);
  for (int L = r->levels - 2; L >= 0; --L) {
    const mpm_cell_set *s = &r->refined[L];
    if (!s->count) continue;
    const double scale = (double)((int64_t)1 << L); /* exact: the descent's doublings */
    int32_t l[3], h[3];
    for (int d = 0; d < 3; ++d) {
      const int32_t touch = (int32_t)ceil(a[d] * scale) - 1, first = c0[d] * (1 << L);
      l[d] = touch > first ? touch : first;
      h[d] = (int32_t)floor(b[d] * scale);
    }
    if (any_in(s, l, h)) return L + 1;
  }
  return 0;
}

/* ---- nodes and their rows ---- */

/* The coarsest leaf around finest-lattice point X: its level, and the octant it lies in. */
static int coarsest_leaf_around(const mpm_refinement *r, const int32_t X[3], int *octant) {
  int k = r->levels, best = 0;
  for (int o = 0; o < 8; ++o) {
    int32_t c[3];
    for (int d = 0; d < 3; ++d) c[d] = X[d] - 1 + ((o >> d) & 1);
    const int L = mpm_refinement_leaf_level(r, c);
    if (L < k) {
      k = L;
      best = o;
    }
  }
  *octant = best;
  return k;
}

static int aligned(const int32_t X[3], int s) {
  const int32_t m = ((int32_t)1 << s) - 1;
  return !(X[0] & m) && !(X[1] & m) && !(X[2] & m);
}

static int to_fine(const mpm_refinement *r, int level, const int32_t idx[3], int32_t X[3]) {
  const int s = fine_shift(r, level);
  const int64_t lim = (int64_t)1 << (MPM_REFINEMENT_COORD_BITS - 1);
  for (int d = 0; d < 3; ++d) {
    const int64_t v = (int64_t)idx[d] * ((int64_t)1 << s);
    if (v < -lim || v >= lim) return -1;
    X[d] = (int32_t)v;
  }
  return 0;
}

static int add_term(mpm_row_term *row, int n, int max, int level, const int32_t idx[3], double w) {
  for (int t = 0; t < n; ++t)
    if (row[t].level == level && row[t].idx[0] == idx[0] && row[t].idx[1] == idx[1] &&
        row[t].idx[2] == idx[2]) {
      row[t].w += w;
      return n;
    }
  if (n >= max) return -1;
  row[n].level = level;
  for (int d = 0; d < 3; ++d) row[n].idx[d] = idx[d];
  row[n].w = w;
  return n + 1;
}

/* Adds scale times the row of finest-lattice point X to row[0..n); the new count or -1. The
 * point is real when it is a lattice node of the coarsest leaf around it (then it is a corner
 * of every leaf around it); otherwise it takes the trilinear interpolation of that leaf's
 * corners (Gao sec. 5.2: "T-junction nodes are constrained to move with their parent nodes at
 * cell corners"), each resolved in turn at a coarser or equal level, so the chain ends. */
static int resolve(const mpm_refinement *r, const int32_t X[3], double scale, mpm_row_term *row,
                   int n, int max) {
  int octant;
  const int k = coarsest_leaf_around(r, X, &octant);
  const int s = fine_shift(r, k);
  if (aligned(X, s)) {
    int32_t idx[3];
    for (int d = 0; d < 3; ++d) idx[d] = shr_floor(X[d], s);
    return add_term(row, n, max, k, idx, scale);
  }
  int32_t X0[3];
  double t[3];
  for (int d = 0; d < 3; ++d) {
    const int32_t cell = shr_floor(X[d] - 1 + ((octant >> d) & 1), s);
    X0[d] = cell * ((int32_t)1 << s);
    t[d] = (double)(X[d] - X0[d]) / (double)((int32_t)1 << s); /* exact: a dyadic fraction */
  }
  for (int q = 0; q < 8 && n >= 0; ++q) {
    double w = scale;
    int32_t Y[3];
    for (int d = 0; d < 3; ++d) {
      const int bit = (q >> d) & 1;
      w *= bit ? t[d] : 1 - t[d];
      Y[d] = X0[d] + (bit << s);
    }
    if (w != 0) n = resolve(r, Y, w, row, n, max);
  }
  return n;
}

int mpm_refinement_node_is_real(const mpm_refinement *r, int level, const int32_t idx[3],
                                mpm_row_term *owner) {
  int32_t X[3];
  if (to_fine(r, level, idx, X)) return 0;
  int octant;
  const int k = coarsest_leaf_around(r, X, &octant);
  const int s = fine_shift(r, k);
  if (!aligned(X, s)) return 0;
  if (owner) {
    owner->level = k;
    for (int d = 0; d < 3; ++d) owner->idx[d] = shr_floor(X[d], s);
    owner->w = 1;
  }
  return 1;
}

int mpm_refinement_node_row(const mpm_refinement *r, int level, const int32_t idx[3],
                            mpm_row_term *row, int max) {
  int32_t X[3];
  if (to_fine(r, level, idx, X)) return -1;
  return resolve(r, X, 1.0, row, 0, max);
}

int mpm_refinement_basis_at(const mpm_refinement *r, const mpm_real x[3], mpm_row_term *terms,
                            int max) {
  int32_t cell[3];
  const int L = mpm_refinement_leaf_at(r, x, cell);
  const double dx = (double)mpm_refinement_dx(r, L);
  double t[3];
  for (int d = 0; d < 3; ++d) {
    t[d] = ((double)x[d] - (double)r->origin[d]) / dx - (double)cell[d];
    t[d] = t[d] < 0 ? 0 : t[d] > 1 ? 1 : t[d];
  }
  int n = 0;
  for (int q = 0; q < 8 && n >= 0; ++q) {
    double w = 1;
    int32_t idx[3];
    for (int d = 0; d < 3; ++d) {
      const int bit = (q >> d) & 1;
      w *= bit ? t[d] : 1 - t[d];
      idx[d] = cell[d] + bit;
    }
    if (w == 0) continue;
    int32_t X[3];
    if (to_fine(r, L, idx, X)) return -1;
    n = resolve(r, X, w, terms, n, max);
  }
  return n;
}

size_t mpm_refinement_bytes(const mpm_refinement *r) {
  size_t b = 0;
  for (int L = 0; L < MPM_LEVELS_MAX; ++L) b += r->refined[L].size * sizeof(uint64_t);
  return b;
}

size_t mpm_refinement_fine_leaves(const mpm_refinement *r,
                                  void (*visit)(void *ctx, int level, const int32_t cell[3]),
                                  void *ctx) {
  size_t n = 0;
  for (int L = 0; L + 1 < r->levels; ++L) {
    const mpm_cell_set *s = &r->refined[L];
    for (size_t i = 0; i < s->size; ++i) {
      if (s->keys[i] == EMPTY_KEY) continue;
      int32_t c[3];
      unpack(s->keys[i], c);
      for (int o = 0; o < 8; ++o) {
        const int32_t child[3] = {2 * c[0] + ((o >> 2) & 1), 2 * c[1] + ((o >> 1) & 1),
                                  2 * c[2] + (o & 1)};
        if (L + 2 < r->levels && set_contains(&r->refined[L + 1], child)) continue;
        if (visit) visit(ctx, L + 1, child);
        ++n;
      }
    }
  }
  return n;
}

void mpm_refinement_refined_cells(const mpm_refinement *r,
                                  void (*visit)(void *ctx, int level, const int32_t cell[3]),
                                  void *ctx) {
  for (int L = 0; L + 1 < r->levels; ++L) {
    const mpm_cell_set *s = &r->refined[L];
    for (size_t i = 0; i < s->size; ++i) {
      if (s->keys[i] == EMPTY_KEY) continue;
      int32_t c[3];
      unpack(s->keys[i], c);
      visit(ctx, L, c);
    }
  }
}

mpm_status mpm_refinement_index_dense(mpm_refinement *r, const int32_t lo0[3], const int32_t n0[3],
                                      size_t max_bytes) {
  size_t total = 0;
  for (int L = 0; L + 1 < r->levels; ++L) {
    mpm_cell_set *s = &r->refined[L];
    uint64_t cells = 1;
    int32_t lo[3], n[3];
    for (int d = 0; d < 3; ++d) {
      lo[d] = lo0[d] * (1 << L);
      n[d] = n0[d] * (1 << L);
      cells *= (uint64_t)n[d];
    }
    const size_t bytes = (size_t)((cells + 63) / 64) * sizeof(uint64_t);
    if (total + bytes > max_bytes) break; /* finer levels stay on the hash */
    uint64_t *bits = mpm_calloc((size_t)((cells + 63) / 64), sizeof(uint64_t));
    if (!bits) return MPM_ERR_NOMEM;
    mpm_free(s->bits);
    s->bits = bits;
    for (int d = 0; d < 3; ++d) {
      s->lo[d] = lo[d];
      s->n[d] = n[d];
    }
    for (size_t i = 0; i < s->size; ++i) {
      if (s->keys[i] == EMPTY_KEY) continue;
      int32_t c[3];
      unpack(s->keys[i], c);
      const int64_t b = dense_bit(s, c);
      if (b >= 0) bits[b >> 6] |= (uint64_t)1 << (b & 63);
    }
    total += bytes;
  }
  return MPM_OK;
}

/* As mpm_refinement_finest_level_in, with the open box: a refined cell [c, c + 1] counts
 * when it overlaps (a, b) with some volume, c < b and c + 1 > a, so at every level the cells
 * floor(a) .. ceil(b) - 1. */
int mpm_refinement_finest_level_overlapping(const mpm_refinement *r, const double a[3],
                                            const double b[3]) {
  for (int L = r->levels - 2; L >= 0; --L) {
    const mpm_cell_set *s = &r->refined[L];
    if (!s->count) continue;
    const double scale = (double)((int64_t)1 << L);
    int32_t l[3], h[3];
    for (int d = 0; d < 3; ++d) {
      l[d] = (int32_t)floor(a[d] * scale);
      h[d] = (int32_t)ceil(b[d] * scale) - 1;
    }
    if (any_in(s, l, h)) return L + 1;
  }
  return 0;
}
