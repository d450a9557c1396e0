/* parallel.h - the one place OpenMP is included; the engine builds without it too. */
#ifndef MPM_CORE_PARALLEL_H
#define MPM_CORE_PARALLEL_H

/* Element-wise loops over fewer items than this run on one thread (an OpenMP region costs a
 * few microseconds of fork and barrier; CG on a small body runs dozens of them per iteration).
 * Used as `#pragma omp parallel for if (n > MPM_PARALLEL_MIN)`: the results do not depend on
 * it. */
#define MPM_PARALLEL_MIN 16384

#ifdef _OPENMP
#include <omp.h>
static inline int mpm_thread_count(void) {
  return omp_get_max_threads();
}
static inline int mpm_thread_id(void) {
  return omp_get_thread_num();
}
static inline int mpm_thread_team(void) { /* the threads of the current region */
  return omp_get_num_threads();
}
static inline void mpm_set_threads(int n) {
  if (n > 0) omp_set_num_threads(n);
}
#else
static inline int mpm_thread_count(void) {
  return 1;
}
static inline int mpm_thread_id(void) {
  return 0;
}
static inline int mpm_thread_team(void) {
  return 1;
}
static inline void mpm_set_threads(int n) {
  (void)n;
}
#endif

#endif
