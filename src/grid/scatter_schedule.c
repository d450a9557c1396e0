/* scatter_schedule.c - grouping and colouring of a scatter's rows (see scatter_schedule.h). */
#include "grid/scatter_schedule.h"
#include "core/alloc.h"
#include "core/parallel.h"

#include <string.h>

void mpm_scatter_schedule_init(mpm_scatter_schedule *s) {
  memset(s, 0, sizeof *s);
}

void mpm_scatter_schedule_free(mpm_scatter_schedule *s) {
  mpm_free(s->group_row);
  mpm_free(s->group_start);
  mpm_free(s->key_group);
  mpm_free(s->own_row);
  mpm_free(s->count);
  mpm_free(s->own_at);
  memset(s, 0, sizeof *s);
}

size_t mpm_scatter_schedule_bytes(const mpm_scatter_schedule *s) {
  return (s->group_row_capacity + s->group_capacity + s->own_row_capacity + s->count_capacity) *
             sizeof(uint32_t) +
         s->key_capacity * sizeof(int32_t) + s->own_at_capacity * sizeof(size_t);
}

/* Groups numbered in colour order, then key order, from the keys' row counts (used: > 0);
 * group_start from the counts. Returns the number of groups. */
static size_t number_groups(mpm_scatter_schedule *s, const uint32_t *count, size_t key_count,
                            const uint8_t *key_colour) {
  int32_t *kg = s->key_group;
  size_t groups = 0;
  for (int colour = 0; colour < MPM_SCHEDULE_COLOURS; ++colour) {
    s->colour_start[colour] = groups;
    for (size_t k = 0; k < key_count; ++k)
      if (count[k] && key_colour[k] == colour) kg[k] = (int32_t)groups++;
  }
  s->colour_start[MPM_SCHEDULE_COLOURS] = groups;
  return groups;
}

mpm_status mpm_scatter_schedule_build(mpm_scatter_schedule *s, size_t rows, const int32_t *key,
                                      size_t key_count, const uint8_t *key_colour) {
  s->built = 0;
  if (mpm_reserve((void **)&s->key_group, &s->key_capacity, key_count + 1, sizeof(int32_t)))
    return MPM_ERR_NOMEM;
  int32_t *kg = s->key_group;
  for (size_t k = 0; k < key_count; ++k) kg[k] = -1;
  /* a counting sort of the rows by group, stable in row order, in parallel: each thread counts
   * the keys of its range of rows, the groups' rows are laid out key by key and thread by
   * thread, and each thread writes its rows at its offsets: the same order for any number of
   * threads. Per thread a count per key: one thread where that would outnumber the rows. */
  int threads = mpm_thread_count();
  if (rows < MPM_PARALLEL_MIN || (size_t)threads * (key_count + 1) > rows) threads = 1;
  const size_t stride = key_count + 1;
  if (mpm_reserve((void **)&s->count, &s->count_capacity, (size_t)threads * stride + stride,
                  sizeof *s->count) ||
      mpm_reserve((void **)&s->own_at, &s->own_at_capacity, (size_t)threads + 1, sizeof *s->own_at))
    return MPM_ERR_NOMEM;
  uint32_t *count = s->count;
  size_t *own_at = s->own_at;
  memset(count, 0, ((size_t)threads * stride + stride) * sizeof *count);
  memset(own_at, 0, ((size_t)threads + 1) * sizeof *own_at);
  uint32_t *total = count + (size_t)threads * stride;
  int failed = 0;
#pragma omp parallel num_threads(threads) if (threads > 1)
  {
    const int T = mpm_thread_team(), t = mpm_thread_id();
    const size_t a0 = rows * (size_t)t / (size_t)T, a1 = rows * (size_t)(t + 1) / (size_t)T;
    uint32_t *mine = count + (size_t)t * stride;
    size_t own = 0;
    for (size_t a = a0; a < a1; ++a)
      if (key[a] >= 0)
        mine[key[a]]++;
      else if (key[a] == MPM_SCHEDULE_OWN_COLUMNS)
        ++own;
    own_at[t + 1] = own;
#pragma omp barrier
#pragma omp single
    {
      for (int u = 0; u < T; ++u) own_at[u + 1] += own_at[u];
      for (size_t k = 0; k < key_count; ++k)
        for (int u = 0; u < T; ++u) total[k] += count[(size_t)u * stride + k];
      const size_t groups = number_groups(s, total, key_count, key_colour);
      if (mpm_reserve((void **)&s->own_row, &s->own_row_capacity, own_at[T] + 1,
                      sizeof(uint32_t)) ||
          mpm_reserve((void **)&s->group_start, &s->group_capacity, groups + 2, sizeof(uint32_t)) ||
          mpm_reserve((void **)&s->group_row, &s->group_row_capacity, rows + 1, sizeof(uint32_t)))
        failed = 1;
      if (!failed) {
        s->own_rows = own_at[T];
        uint32_t *start = s->group_start;
        memset(start, 0, (groups + 1) * sizeof *start);
        for (size_t k = 0; k < key_count; ++k)
          if (kg[k] >= 0) start[kg[k] + 1] = total[k];
        for (size_t q = 0; q < groups; ++q) start[q + 1] += start[q];
        /* each thread's first place for key k: after the rows of k of the threads before it */
        for (size_t k = 0; k < key_count; ++k) {
          if (kg[k] < 0) continue;
          uint32_t at = start[kg[k]];
          for (int u = 0; u < T; ++u) {
            const uint32_t n = count[(size_t)u * stride + k];
            count[(size_t)u * stride + k] = at;
            at += n;
          }
        }
      }
    }
    if (!failed) {
      size_t own_next = own_at[t];
      for (size_t a = a0; a < a1; ++a)
        if (key[a] >= 0)
          s->group_row[mine[key[a]]++] = (uint32_t)a;
        else if (key[a] == MPM_SCHEDULE_OWN_COLUMNS)
          s->own_row[own_next++] = (uint32_t)a;
    }
  }
  if (failed) return MPM_ERR_NOMEM;
  s->built = 1;
  return MPM_OK;
}
