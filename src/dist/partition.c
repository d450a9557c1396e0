/* partition.c - the level-0 blocks cut into ranks along their Morton order (partition.h). */
#include "dist/partition.h"
#include "core/alloc.h"

#include <math.h>
#include <stdlib.h>

#define COORD_OFFSET (1 << (MPM_MORTON_BITS - 1))

/* The 21 low bits of v spread to every third bit (bit b to bit 3 b). */
static uint64_t spread(uint64_t v) {
  v &= 0x1fffffu;
  v = (v | v << 32) & 0x1f00000000ffffull;
  v = (v | v << 16) & 0x1f0000ff0000ffull;
  v = (v | v << 8) & 0x100f00f00f00f00full;
  v = (v | v << 4) & 0x10c30c30c30c30c3ull;
  v = (v | v << 2) & 0x1249249249249249ull;
  return v;
}

/* The inverse: every third bit gathered into the 21 low bits. */
static uint32_t gather(uint64_t v) {
  v &= 0x1249249249249249ull;
  v = (v ^ (v >> 2)) & 0x10c30c30c30c30c3ull;
  v = (v ^ (v >> 4)) & 0x100f00f00f00f00full;
  v = (v ^ (v >> 8)) & 0x1f0000ff0000ffull;
  v = (v ^ (v >> 16)) & 0x1f00000000ffffull;
  v = (v ^ (v >> 32)) & 0x1fffffull;
  return (uint32_t)v;
}

uint64_t mpm_morton_key(const int32_t c[3]) {
  const uint64_t x = (uint64_t)(int64_t)(c[0] + COORD_OFFSET);
  const uint64_t y = (uint64_t)(int64_t)(c[1] + COORD_OFFSET);
  const uint64_t z = (uint64_t)(int64_t)(c[2] + COORD_OFFSET);
  return spread(x) << 2 | spread(y) << 1 | spread(z);
}

void mpm_morton_coords(uint64_t key, int32_t c[3]) {
  c[0] = (int32_t)gather(key >> 2) - COORD_OFFSET;
  c[1] = (int32_t)gather(key >> 1) - COORD_OFFSET;
  c[2] = (int32_t)gather(key) - COORD_OFFSET;
}

typedef struct keyed {
  uint64_t key;
  double weight;
} keyed;

static int by_key(const void *a, const void *b) {
  const uint64_t x = ((const keyed *)a)->key, y = ((const keyed *)b)->key;
  return x < y ? -1 : x > y;
}

mpm_status mpm_partition_cut(mpm_partition *pt, int ranks, size_t count, const uint64_t *keys,
                             const double *weights) {
  pt->ranks = 0;
  pt->start = NULL;
  if (ranks < 1) return MPM_ERR_INVALID;
  pt->start = mpm_alloc(((size_t)ranks + 1) * sizeof *pt->start);
  keyed *b = mpm_alloc((count + 1) * sizeof *b);
  double *prefix = mpm_alloc((count + 1) * sizeof *prefix);
  if (!pt->start || !b || !prefix) {
    mpm_free(b);
    mpm_free(prefix);
    mpm_partition_free(pt);
    return MPM_ERR_NOMEM;
  }
  pt->ranks = ranks;
  double total = 0;
  for (size_t i = 0; i < count; ++i) {
    b[i].key = keys[i];
    b[i].weight = weights && weights[i] > 0 ? weights[i] : 0;
    total += b[i].weight;
  }
  const int by_count = !(total > 0); /* no weight given: every block weighs one */
  qsort(b, count, sizeof *b, by_key);
  size_t n = 0; /* distinct keys, a repeated key's weights added */
  for (size_t i = 0; i < count; ++i) {
    const double w = by_count ? 1.0 : b[i].weight;
    if (n > 0 && b[n - 1].key == b[i].key) {
      b[n - 1].weight += w;
    } else {
      b[n].key = b[i].key;
      b[n].weight = w;
      ++n;
    }
  }
  /* prefix[k]: the weight of the first k blocks, summed in key order (the same on every rank) */
  prefix[0] = 0;
  for (size_t k = 0; k < n; ++k) prefix[k + 1] = prefix[k] + b[k].weight;
  total = prefix[n];
  pt->start[0] = 0;
  pt->start[ranks] = UINT64_MAX;
  size_t k = 0;
  for (int r = 1; r < ranks; ++r) {
    /* the boundary nearest to the target, never before the previous rank's (ties: the earlier) */
    const double target = total * (double)r / (double)ranks;
    while (k < n && fabs(prefix[k + 1] - target) < fabs(prefix[k] - target)) ++k;
    pt->start[r] = k < n ? b[k].key : (n > 0 ? b[n - 1].key + 1 : 0);
  }
  mpm_free(b);
  mpm_free(prefix);
  return MPM_OK;
}

void mpm_partition_free(mpm_partition *pt) {
  mpm_free(pt->start);
  pt->start = NULL;
  pt->ranks = 0;
}

int mpm_partition_owner(const mpm_partition *pt, uint64_t key) {
  /* the last r with start[r] <= key */
  int lo = 0, hi = pt->ranks - 1;
  while (lo < hi) {
    const int mid = (lo + hi + 1) / 2;
    if (pt->start[mid] <= key)
      lo = mid;
    else
      hi = mid - 1;
  }
  return lo;
}

double mpm_partition_weights(const mpm_partition *pt, size_t count, const uint64_t *keys,
                             const double *weights, double *rank_weight) {
  for (int r = 0; r < pt->ranks; ++r) rank_weight[r] = 0;
  double total = 0;
  for (size_t i = 0; i < count; ++i) {
    const double w = !weights ? 1.0 : weights[i] > 0 ? weights[i] : 0;
    rank_weight[mpm_partition_owner(pt, keys[i])] += w;
    total += w;
  }
  if (!(total > 0)) return 1;
  double most = 0;
  for (int r = 0; r < pt->ranks; ++r)
    if (rank_weight[r] > most) most = rank_weight[r];
  return most / (total / pt->ranks);
}
