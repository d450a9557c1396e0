/* vecmath.h - elementary functions over arrays, written so that the compiler vectorizes them
 * across particles (libm's scalar calls are not vectorized without -ffast-math).
 *
 * mpm_log_array: natural logarithm of positive normal numbers. x = 2^e m with m in
 * [sqrt(1/2), sqrt(2)), then log m = 2 atanh(s), s = (m - 1)/(m + 1), |s| < 0.1716, summed as
 * the odd series 2 (s + s^3/3 + s^5/5 + ...) to the real type's precision (6 terms for float,
 * 12 for double). Accurate to a few ulp; tested against libm in tests/test_vecmath.c.
 *
 * mpm_exp_array: exponential, x clamped to the range whose result is a normal number. x = k ln2
 * + r with k the nearest integer to x / ln2 and r reduced in two parts (Cody and Waite: ln2 =
 * hi + lo, hi with trailing zero bits so k hi is exact), |r| <= ln2 / 2; exp r by its Taylor
 * series to r^7 / 7! (float) or r^13 / 13! (double), whose remainder is below half an ulp; 2^k
 * assembled from its exponent bits. */
#ifndef MPM_CORE_VECMATH_H
#define MPM_CORE_VECMATH_H

#include "core/real.h"

#include <stdint.h>
#include <string.h>

#ifdef MPM_USE_DOUBLE
typedef uint64_t mpm_real_bits;
#define MPM_MANT_BITS 52
#define MPM_EXP_BIAS 1023
#define MPM_LOG_TERMS 12
#define MPM_EXP_DEGREE 13
#define MPM_EXP_LO_ARG (-708.0)
#define MPM_EXP_HI_ARG 709.0
#define MPM_LN2_HI 6.93147180369123816490e-01
#define MPM_LN2_LO 1.90821492927058770002e-10
#else
typedef uint32_t mpm_real_bits;
#define MPM_MANT_BITS 23
#define MPM_EXP_BIAS 127
#define MPM_LOG_TERMS 6
#define MPM_EXP_DEGREE 7
#define MPM_EXP_LO_ARG (-87.0f)
#define MPM_EXP_HI_ARG 88.0f
#define MPM_LN2_HI 0.693359375f
#define MPM_LN2_LO (-2.12194440e-4f)
#endif

/* out[i] = log(x[i]) for positive normal x[i] (callers clamp first). */
static inline void mpm_log_array(int n, const mpm_real *restrict x, mpm_real *restrict out) {
  const mpm_real_bits mant_mask = ((mpm_real_bits)1 << MPM_MANT_BITS) - 1;
  const mpm_real_bits one_bits = (mpm_real_bits)MPM_EXP_BIAS << MPM_MANT_BITS;
  const mpm_real ln2 = (mpm_real)0.69314718055994530942, sqrt2 = (mpm_real)1.41421356237309504880;
  for (int i = 0; i < n; ++i) {
    mpm_real_bits b;
    memcpy(&b, &x[i], sizeof b);
    const mpm_real e = (mpm_real)((int64_t)(b >> MPM_MANT_BITS) - MPM_EXP_BIAS);
    const mpm_real_bits mb = (b & mant_mask) | one_bits;
    mpm_real m;
    memcpy(&m, &mb, sizeof m); /* m in [1, 2) */
    const int big = m > sqrt2;
    const mpm_real mm = big ? m * R_(0.5) : m;
    const mpm_real ee = big ? e + 1 : e;
    const mpm_real s = (mm - 1) / (mm + 1), s2 = s * s;
    /* Horner on the odd series: s (2 + s2 (2/3 + s2 (2/5 + ...))) */
    mpm_real poly = (mpm_real)2.0 / (2 * MPM_LOG_TERMS - 1);
    for (int k = MPM_LOG_TERMS - 2; k >= 0; --k) poly = (mpm_real)2.0 / (2 * k + 1) + s2 * poly;
    out[i] = ee * ln2 + s * poly;
  }
}

/* out[i] = exp(x[i]) for x[i] in [MPM_EXP_LO_ARG, MPM_EXP_HI_ARG] (clamped outside). */
static inline void mpm_exp_array(int n, const mpm_real *restrict x, mpm_real *restrict out) {
  const mpm_real inv_ln2 = (mpm_real)1.44269504088896340736;
  for (int i = 0; i < n; ++i) {
    const mpm_real xc = mpm_fmin(mpm_fmax(x[i], MPM_EXP_LO_ARG), MPM_EXP_HI_ARG);
    const mpm_real k = mpm_floor(xc * inv_ln2 + R_(0.5));
    const mpm_real r = (xc - k * MPM_LN2_HI) - k * MPM_LN2_LO;
    /* Horner: 1 + r (1 + r/2 (1 + r/3 (...))) */
    mpm_real p = 1;
    for (int j = MPM_EXP_DEGREE; j >= 1; --j) p = 1 + r * p * ((mpm_real)1 / (mpm_real)j);
    const mpm_real_bits b = (mpm_real_bits)((int64_t)k + MPM_EXP_BIAS) << MPM_MANT_BITS;
    mpm_real two_k;
    memcpy(&two_k, &b, sizeof two_k);
    out[i] = p * two_k;
  }
}

#endif
