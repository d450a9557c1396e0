/* ordered_sum.c - see ordered_sum.h. */
#include "core/ordered_sum.h"

double mpm_ordered_sum(size_t n, double (*term)(const void *ctx, size_t i), const void *ctx) {
  size_t size = (n + MPM_ORDERED_SUM_CHUNKS - 1) / MPM_ORDERED_SUM_CHUNKS;
  if (size < MPM_ORDERED_SUM_MIN) size = MPM_ORDERED_SUM_MIN;
  const long chunks = (long)((n + size - 1) / size);
  double part[MPM_ORDERED_SUM_CHUNKS];
#pragma omp parallel for schedule(dynamic, 1) if (chunks > 1)
  for (long h = 0; h < chunks; ++h) {
    const size_t end = ((size_t)h + 1) * size < n ? ((size_t)h + 1) * size : n;
    double s = 0;
    for (size_t i = (size_t)h * size; i < end; ++i) s += term(ctx, i);
    part[h] = s;
  }
  double total = 0;
  for (long h = 0; h < chunks; ++h) total += part[h];
  return total;
}
