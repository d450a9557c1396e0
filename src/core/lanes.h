/* lanes.h - vectors of reals for code that runs one particle per lane.
 *
 * GCC vector extensions (no intrinsics): the compiler maps them to AVX/AVX-512 registers or
 * splits them into narrower ones, so the same source runs on any x86-64 or AArch64 target.
 * Two widths:
 *   mpm_vl: MPM_LANES reals (8 floats, 4 doubles), the particles of one cell in the
 *           transfers, MPM_LANES at a time (transfer/transfer_lanes.h);
 *   mpm_vn: MPM_NLANES reals in 32 bytes (8 floats or 4 doubles), one AVX register, for long
 *           straight-line kernels such as the batch SVD (core/svd3_lanes.h), where a vector
 *           wider than a register would be split with poor code for the selects.
 * Each comes with the same small set of lane-wise operations, prefixed mpm_vl_ and mpm_vn_. */
#ifndef MPM_CORE_LANES_H
#define MPM_CORE_LANES_H

#include "core/real.h"

#include <stdint.h>

/* In the double build one AVX register too (4 lanes: a cell's 8 particles in two batches).
   Eight doubles, two registers, made GCC 12 build the transfers' vectors through the stack (a
   broadcast became eight scalar stores and four 16-byte reloads, which store forwarding cannot
   serve): the double build's explicit step cost 4.4 times the float one's (docs/performance.md). */
#ifdef MPM_USE_DOUBLE
#define MPM_LANES 4
#else
#define MPM_LANES 8
#endif
#define MPM_NLANES ((int)(32 / sizeof(mpm_real)))
typedef mpm_real mpm_vl __attribute__((vector_size(MPM_LANES * sizeof(mpm_real))));
/* Eight reals, whatever the lanes: the sums of eight lane vectors (transfer_lanes.h). */
typedef mpm_real mpm_v8 __attribute__((vector_size(8 * sizeof(mpm_real))));
typedef mpm_real mpm_vn __attribute__((vector_size(32)));
#ifdef MPM_USE_DOUBLE
typedef int64_t mpm_vl_index __attribute__((vector_size(MPM_LANES * sizeof(int64_t))));
typedef int64_t mpm_vn_index __attribute__((vector_size(32)));
#define MPM_VL_SIGN_BIT INT64_MIN
#else
typedef int32_t mpm_vl_index __attribute__((vector_size(MPM_LANES * sizeof(int32_t))));
typedef int32_t mpm_vn_index __attribute__((vector_size(32)));
#define MPM_VL_SIGN_BIT INT32_MIN
#endif

/* The lane-wise operations of vector type V with mask type VI, named P_splat, P_select, ...:
 *   splat(s)              every lane s;
 *   select(mask, a, b)    mask ? a : b per lane (mask lanes all ones or all zeros, as a
 *                         comparison yields);
 *   min, max, abs;
 *   negate_if(mask, a)    -a where mask, a elsewhere (xor of the sign bit);
 *   sqrt(x)               written per lane, which GCC turns into one vector square root (the
 *                         build has -fno-math-errno, so sqrt needs no errno path). */
#define MPM_LANE_OPS(V, VI, P)                                                                     \
  MPM_ALWAYS_INLINE V P##_splat(mpm_real s) {                                                      \
    const V zero = {0};                                                                            \
    return zero + s;                                                                               \
  }                                                                                                \
  MPM_ALWAYS_INLINE V P##_select(VI mask, V a, V b) {                                              \
    return (V)(((VI)a & mask) | ((VI)b & ~mask));                                                  \
  }                                                                                                \
  MPM_ALWAYS_INLINE V P##_min(V a, V b) {                                                          \
    return P##_select(a < b, a, b);                                                                \
  }                                                                                                \
  MPM_ALWAYS_INLINE V P##_max(V a, V b) {                                                          \
    return P##_select(a > b, a, b);                                                                \
  }                                                                                                \
  MPM_ALWAYS_INLINE V P##_abs(V a) {                                                               \
    return P##_max(a, -a);                                                                         \
  }                                                                                                \
  MPM_ALWAYS_INLINE V P##_negate_if(VI mask, V a) {                                                \
    const VI zero = {0};                                                                           \
    return (V)((VI)a ^ (mask & (zero + MPM_VL_SIGN_BIT)));                                         \
  }                                                                                                \
  MPM_ALWAYS_INLINE V P##_sqrt(V x) {                                                              \
    V r;                                                                                           \
    for (int l = 0; l < (int)(sizeof(V) / sizeof(mpm_real)); ++l) r[l] = mpm_sqrt(x[l]);           \
    return r;                                                                                      \
  }

MPM_LANE_OPS(mpm_vl, mpm_vl_index, mpm_vl)
MPM_LANE_OPS(mpm_vn, mpm_vn_index, mpm_vn)

/* Flush-to-zero and denormals-are-zero for a stretch of vector code: converged iterations
 * (the SVD's Jacobi off-diagonals) underflow into the subnormal range, where every operation
 * takes a slow microcode path. Values below the smallest normal number carry no information
 * there. mpm_ftz_begin returns the previous mode for mpm_ftz_end; a no-op where the mode is not
 * known. */
#if defined(__SSE__)
#include <xmmintrin.h>
MPM_ALWAYS_INLINE unsigned mpm_ftz_begin(void) {
  const unsigned old = _mm_getcsr();
  _mm_setcsr(old | 0x8040u); /* FTZ (bit 15) | DAZ (bit 6) */
  return old;
}
MPM_ALWAYS_INLINE void mpm_ftz_end(unsigned old) {
  _mm_setcsr(old);
}
#elif defined(__aarch64__)
MPM_ALWAYS_INLINE unsigned mpm_ftz_begin(void) {
  uint64_t fpcr;
  __asm__ volatile("mrs %0, fpcr" : "=r"(fpcr));
  __asm__ volatile("msr fpcr, %0" ::"r"(fpcr | (1ull << 24))); /* FZ */
  return (unsigned)fpcr;
}
MPM_ALWAYS_INLINE void mpm_ftz_end(unsigned old) {
  __asm__ volatile("msr fpcr, %0" ::"r"((uint64_t)old));
}
#else
MPM_ALWAYS_INLINE unsigned mpm_ftz_begin(void) {
  return 0;
}
MPM_ALWAYS_INLINE void mpm_ftz_end(unsigned old) {
  (void)old;
}
#endif

#endif
