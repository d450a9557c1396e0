/* sparse_grid.c - block hash, per-step activation, particle sort and colouring
 * (see sparse_grid.h for the design). */
#include "grid/sparse_grid.h"
#include "core/alloc.h"
#include "core/parallel.h"

#include <string.h>

#define EMPTY_KEY UINT64_MAX
#define COORD_BIAS (1 << 20)

static inline uint64_t block_key(int32_t bx, int32_t by, int32_t bz) {
  return (uint64_t)(uint32_t)(bx + COORD_BIAS) | ((uint64_t)(uint32_t)(by + COORD_BIAS) << 21) |
         ((uint64_t)(uint32_t)(bz + COORD_BIAS) << 42);
}

static inline size_t hash_slot(uint64_t key, size_t mask) {
  key ^= key >> 31;
  key *= 0x9E3779B97F4A7C15ull;
  key ^= key >> 29;
  return (size_t)key & mask;
}

void mpm_sparse_grid_init(mpm_sparse_grid *g) {
  memset(g, 0, sizeof *g);
}

void mpm_sparse_grid_free(mpm_sparse_grid *g) {
  mpm_free(g->keys);
  mpm_free(g->values);
  mpm_free(g->coord);
  mpm_free(g->neighbor);
  mpm_free(g->cell_start);
  mpm_free(g->color_blocks);
  mpm_free(g->perm);
  mpm_free(g->run_keys);
  memset(g, 0, sizeof *g);
}

size_t mpm_sparse_grid_bytes(const mpm_sparse_grid *g) {
  return g->table_size * (sizeof(uint64_t) + sizeof(int32_t)) +
         g->block_capacity * (sizeof(int32_t) * 3 + sizeof(int32_t) * 8 + sizeof(int32_t)) +
         g->cell_capacity * sizeof(uint32_t) + g->particle_capacity * sizeof(uint32_t) +
         g->run_capacity * sizeof(uint64_t);
}

static int grow_table(mpm_sparse_grid *g, size_t size) {
  mpm_free(g->keys);
  mpm_free(g->values);
  g->keys = mpm_alloc(size * sizeof(uint64_t));
  g->values = mpm_alloc(size * sizeof(int32_t));
  if (!g->keys || !g->values) return -1;
  g->table_size = size;
  memset(g->keys, 0xFF, size * sizeof(uint64_t));
  /* re-insert the blocks already active */
  const size_t mask = size - 1;
  for (size_t b = 0; b < g->block_count; ++b) {
    uint64_t key = block_key(g->coord[b][0], g->coord[b][1], g->coord[b][2]);
    size_t s = hash_slot(key, mask);
    while (g->keys[s] != EMPTY_KEY) s = (s + 1) & mask;
    g->keys[s] = key;
    g->values[s] = (int32_t)b;
  }
  return 0;
}

static int grow_blocks(mpm_sparse_grid *g, size_t cap) {
  int32_t(*coord)[3] = mpm_alloc(cap * sizeof *coord);
  int32_t(*nbr)[8] = mpm_alloc(cap * sizeof *nbr);
  int32_t *colors = mpm_alloc(cap * sizeof *colors);
  if (!coord || !nbr || !colors) {
    mpm_free(coord);
    mpm_free(nbr);
    mpm_free(colors);
    return -1;
  }
  if (g->block_count) {
    memcpy(coord, g->coord, g->block_count * sizeof *coord);
    memcpy(nbr, g->neighbor, g->block_count * sizeof *nbr);
  }
  mpm_free(g->coord);
  mpm_free(g->neighbor);
  mpm_free(g->color_blocks);
  g->coord = coord;
  g->neighbor = nbr;
  g->color_blocks = colors;
  g->block_capacity = cap;
  return 0;
}

/* Index of the block with coordinates (bx,by,bz), inserting it if absent; -1 on OOM. */
static int32_t find_or_insert(mpm_sparse_grid *g, int32_t bx, int32_t by, int32_t bz) {
  const uint64_t key = block_key(bx, by, bz);
  size_t mask = g->table_size - 1;
  size_t s = hash_slot(key, mask);
  while (g->keys[s] != EMPTY_KEY) {
    if (g->keys[s] == key) return g->values[s];
    s = (s + 1) & mask;
  }
  if (g->block_count == g->block_capacity &&
      grow_blocks(g, g->block_capacity ? 2 * g->block_capacity : 1024))
    return -1;
  if (2 * (g->block_count + 1) > g->table_size) {
    if (grow_table(g, 2 * g->table_size)) return -1;
    mask = g->table_size - 1;
    s = hash_slot(key, mask);
    while (g->keys[s] != EMPTY_KEY) s = (s + 1) & mask;
  }
  const int32_t b = (int32_t)g->block_count++;
  g->keys[s] = key;
  g->values[s] = b;
  g->coord[b][0] = bx;
  g->coord[b][1] = by;
  g->coord[b][2] = bz;
  return b;
}

int32_t mpm_sparse_grid_find(const mpm_sparse_grid *g, const int32_t c[3]) {
  if (!g->table_size) return -1;
  const uint64_t key = block_key(c[0], c[1], c[2]);
  const size_t mask = g->table_size - 1;
  size_t s = hash_slot(key, mask);
  while (g->keys[s] != EMPTY_KEY) {
    if (g->keys[s] == key) return g->values[s];
    s = (s + 1) & mask;
  }
  return -1;
}

/* Per-particle packed position key: block coordinates (19 bits each, biased) and the cell of the
 * base node in its block (6 bits). */
#define PKEY_BIAS (1 << 18)
static inline uint64_t particle_key(int64_t ix, int64_t iy, int64_t iz) {
  /* all in 64-bit integers so that the loop calling this vectorizes */
  const uint64_t bx = (uint64_t)((ix >> MPM_BLOCK_BITS) + PKEY_BIAS);
  const uint64_t by = (uint64_t)((iy >> MPM_BLOCK_BITS) + PKEY_BIAS);
  const uint64_t bz = (uint64_t)((iz >> MPM_BLOCK_BITS) + PKEY_BIAS);
  const uint64_t cell = (uint64_t)((ix & 3) << 4 | (iy & 3) << 2 | (iz & 3));
  return (bx | by << 19 | bz << 38) << 6 | cell;
}

/* Chunks of the parallel passes: one per thread, at most this many. */
#define MPM_MAX_CHUNKS 256

static int ensure_u32(uint32_t **a, size_t *cap, size_t need) {
  if (need <= *cap) return 0;
  mpm_free(*a);
  *cap = need + need / 2;
  *a = mpm_alloc(*cap * sizeof(uint32_t));
  return *a ? 0 : -1;
}

mpm_status mpm_sparse_grid_sort(mpm_sparse_grid *g, const mpm_kernel *k, const mpm_real origin[3],
                                int material_count, const mpm_particles *p, mpm_arena *scratch) {
  const size_t n = p->count;
  if (n > g->particle_capacity || !g->perm) {
    mpm_free(g->perm);
    g->perm = mpm_alloc((n + 1) * sizeof(uint32_t));
    if (!g->perm) return MPM_ERR_NOMEM;
    g->particle_capacity = n;
  }
  uint64_t *pk = mpm_arena_alloc(scratch, (n + 1) * sizeof(uint64_t));
  uint32_t *pkey = mpm_arena_alloc(scratch, (n + 1) * sizeof(uint32_t));
  if (!pk || !pkey) return MPM_ERR_NOMEM;
  if (!g->table_size && grow_table(g, 4096)) return MPM_ERR_NOMEM;
  memset(g->keys, 0xFF, g->table_size * sizeof(uint64_t));
  g->block_count = 0;
  g->material_count = material_count;

  /* 1. base node of each particle's stencil -> (owner block, cell in block), in parallel */
  const mpm_real inv_dx = k->inv_dx, shift = k->shift;
  const int32_t pair = mpm_kernel_base_mask(k);
  const mpm_real *x0 = p->x[0], *x1 = p->x[1], *x2 = p->x[2];
#pragma omp parallel for schedule(static)
  for (long i = 0; i < (long)n; ++i) {
    /* int32 first: that conversion vectorizes, the direct one to int64 does not */
    const int32_t ix = (int32_t)mpm_floor((x0[i] - origin[0]) * inv_dx - shift) & pair;
    const int32_t iy = (int32_t)mpm_floor((x1[i] - origin[1]) * inv_dx - shift) & pair;
    const int32_t iz = (int32_t)mpm_floor((x2[i] - origin[2]) * inv_dx - shift) & pair;
    pk[i] = particle_key(ix, iy, iz);
  }
  /* 2. block indices through the hash. Particles come mostly in runs of one block (they were
   *    sorted before), so only run starts are looked up: the runs are found in parallel, looked
   *    up serially in particle order (first-seen order: deterministic for any thread count),
   *    and the indices are spread over the runs in parallel again. */
  const int threads = mpm_thread_count();
  const int nch = threads < MPM_MAX_CHUNKS ? threads : MPM_MAX_CHUNKS;
  size_t run_count[MPM_MAX_CHUNKS + 1] = {0};
#pragma omp parallel for schedule(static, 1)
  for (int t = 0; t < nch; ++t) {
    const size_t lo = n * (size_t)t / (size_t)nch, hi = n * (size_t)(t + 1) / (size_t)nch;
    size_t c = 0;
    for (size_t i = lo; i < hi; ++i) c += i == lo || (pk[i] >> 6) != (pk[i - 1] >> 6);
    run_count[t + 1] = c;
  }
  for (int t = 0; t < nch; ++t) run_count[t + 1] += run_count[t];
  uint32_t *runs = mpm_arena_alloc(scratch, (run_count[nch] + 1) * sizeof(uint32_t));
  if (!runs) return MPM_ERR_NOMEM;
#pragma omp parallel for schedule(static, 1)
  for (int t = 0; t < nch; ++t) {
    const size_t lo = n * (size_t)t / (size_t)nch, hi = n * (size_t)(t + 1) / (size_t)nch;
    size_t r = run_count[t];
    for (size_t i = lo; i < hi; ++i)
      if (i == lo || (pk[i] >> 6) != (pk[i - 1] >> 6)) runs[r++] = (uint32_t)i;
  }
  const uint64_t mask19 = (1u << 19) - 1;
  for (size_t r = 0; r < run_count[nch]; ++r) {
    const uint64_t bk = pk[runs[r]] >> 6;
    const int32_t b = find_or_insert(g, (int32_t)(bk & mask19) - PKEY_BIAS,
                                     (int32_t)((bk >> 19) & mask19) - PKEY_BIAS,
                                     (int32_t)((bk >> 38) & mask19) - PKEY_BIAS);
    if (b < 0) return MPM_ERR_NOMEM;
    pkey[runs[r]] = (uint32_t)b;
  }
#pragma omp parallel for schedule(static, 1)
  for (int t = 0; t < nch; ++t) {
    const size_t lo = n * (size_t)t / (size_t)nch, hi = n * (size_t)(t + 1) / (size_t)nch;
    size_t r = run_count[t];
    uint32_t cur = 0;
    for (size_t i = lo; i < hi; ++i) {
      if (r < run_count[t + 1] && runs[r] == i) {
        cur = pkey[i];
        ++r;
      }
      pkey[i] = cur;
    }
  }
  g->owner_count = g->block_count;
  g->particle_count = n;

  /* 3. stable counting sort by (block, material, cell), with per-chunk histograms: the result is
   *    the unique stable order, the same for any number of threads. */
  const size_t keys = g->owner_count * (size_t)material_count * MPM_BLOCK_NODES;
  uint32_t *hist = mpm_arena_alloc(scratch, (keys * (size_t)nch + 1) * sizeof(uint32_t));
  if (ensure_u32(&g->cell_start, &g->cell_capacity, keys + 1) || !hist) return MPM_ERR_NOMEM;
  uint32_t *cs = g->cell_start;
  const int32_t *mat = p->material;
#pragma omp parallel for schedule(static, 1)
  for (int t = 0; t < nch; ++t) {
    uint32_t *h = hist + (size_t)t * keys;
    memset(h, 0, keys * sizeof(uint32_t));
    const size_t lo = n * (size_t)t / (size_t)nch, hi = n * (size_t)(t + 1) / (size_t)nch;
    for (size_t i = lo; i < hi; ++i) {
      const uint32_t key =
          (pkey[i] * (uint32_t)material_count + (uint32_t)mat[i]) * MPM_BLOCK_NODES +
          (uint32_t)(pk[i] & 63);
      pkey[i] = key;
      h[key]++;
    }
  }
  uint32_t run = 0;
  for (size_t key = 0; key < keys; ++key) {
    cs[key] = run;
    for (int t = 0; t < nch; ++t) {
      const uint32_t c = hist[(size_t)t * keys + key];
      hist[(size_t)t * keys + key] = run;
      run += c;
    }
  }
  cs[keys] = run;
#pragma omp parallel for schedule(static, 1)
  for (int t = 0; t < nch; ++t) {
    uint32_t *h = hist + (size_t)t * keys;
    const size_t lo = n * (size_t)t / (size_t)nch, hi = n * (size_t)(t + 1) / (size_t)nch;
    for (size_t i = lo; i < hi; ++i) g->perm[h[pkey[i]]++] = (uint32_t)i;
  }

  /* 3. activate the 7 forward neighbours of every owner block (its pad) */
  for (size_t b = 0; b < g->owner_count; ++b) {
    const int32_t cx = g->coord[b][0], cy = g->coord[b][1], cz = g->coord[b][2];
    for (int o = 0; o < 8; ++o) {
      int32_t nb = find_or_insert(g, cx + ((o >> 2) & 1), cy + ((o >> 1) & 1), cz + (o & 1));
      if (nb < 0) return MPM_ERR_NOMEM;
      g->neighbor[b][o] = nb;
    }
  }

  /* 4. colour owner blocks by coordinate parity */
  size_t count[8] = {0};
  for (size_t b = 0; b < g->owner_count; ++b)
    count[(g->coord[b][0] & 1) << 2 | (g->coord[b][1] & 1) << 1 | (g->coord[b][2] & 1)]++;
  g->color_start[0] = 0;
  for (int c = 0; c < 8; ++c) g->color_start[c + 1] = g->color_start[c] + count[c];
  size_t cursor[8];
  for (int c = 0; c < 8; ++c) cursor[c] = g->color_start[c];
  for (size_t b = 0; b < g->owner_count; ++b) {
    int c = (g->coord[b][0] & 1) << 2 | (g->coord[b][1] & 1) << 1 | (g->coord[b][2] & 1);
    g->color_blocks[cursor[c]++] = (int32_t)b;
  }
  return MPM_OK;
}

int32_t mpm_sparse_grid_touch(mpm_sparse_grid *g, const int32_t c[3]) {
  if (!g->table_size && grow_table(g, 4096)) return -1;
  return find_or_insert(g, c[0], c[1], c[2]);
}
