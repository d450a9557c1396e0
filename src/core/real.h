/* real.h - the engine's real type, chosen at build time (CMake option MPM_DOUBLE).
 *
 * Graphics users run float; the test suite passes in both. Everything that is stored per
 * particle or per grid node uses mpm_real; accumulations that must be exact across thread
 * counts are made deterministic by ordering, not by widening. */
#ifndef MPM_CORE_REAL_H
#define MPM_CORE_REAL_H

#include <math.h>
#include <float.h>

#ifdef MPM_USE_DOUBLE
typedef double mpm_real;
#define MPM_REAL_EPS DBL_EPSILON
#define MPM_REAL_MAX DBL_MAX
#define MPM_REAL_NAME "double"
#define R_(x) (x)
#define mpm_sqrt sqrt
#define mpm_floor floor
#define mpm_fabs fabs
#define mpm_log log
#define mpm_exp exp
#define mpm_sin sin
#define mpm_cos cos
#define mpm_atan2 atan2
#else
typedef float mpm_real;
#define MPM_REAL_EPS FLT_EPSILON
#define MPM_REAL_MAX FLT_MAX
#define MPM_REAL_NAME "float"
#define R_(x) (x##f)
#define mpm_sqrt sqrtf
#define mpm_floor floorf
#define mpm_fabs fabsf
#define mpm_log logf
#define mpm_exp expf
#define mpm_sin sinf
#define mpm_cos cosf
#define mpm_atan2 atan2f
#endif

/* Forced inlining for the small helpers of hot loops. */
#define MPM_ALWAYS_INLINE static inline __attribute__((always_inline))

/* fmin/fmax with C99 semantics (a NaN argument loses), inlined: the libm calls are not inlined
 * without -ffast-math and sit in hot loops. */
static inline mpm_real mpm_fmax(mpm_real a, mpm_real b) {
  return (a > b || b != b) ? a : b;
}
static inline mpm_real mpm_fmin(mpm_real a, mpm_real b) {
  return (a < b || b != b) ? a : b;
}

/* Alignment of every per-particle and per-block array (one AVX-512 line). */
#define MPM_ALIGN 64

#endif
