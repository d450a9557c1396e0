/* mat3.h - small vector and 3x3 matrix math, inline, on plain arrays.
 *
 * Matrices are row-major mpm_real[9]: A[3*r + c]. Functions take output last and allow no
 * aliasing between inputs and outputs unless stated. Tested in tests/test_mat3.c. */
#ifndef MPM_CORE_MAT3_H
#define MPM_CORE_MAT3_H

#include "core/real.h"

static inline void mpm_m3_identity(mpm_real A[9]) {
  for (int i = 0; i < 9; ++i) A[i] = 0;
  A[0] = A[4] = A[8] = 1;
}

static inline void mpm_m3_copy(const mpm_real A[9], mpm_real B[9]) {
  for (int i = 0; i < 9; ++i) B[i] = A[i];
}

/* C = A B */
static inline void mpm_m3_mul(const mpm_real A[9], const mpm_real B[9], mpm_real C[9]) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      C[3 * r + c] = A[3 * r] * B[c] + A[3 * r + 1] * B[3 + c] + A[3 * r + 2] * B[6 + c];
}

/* C = A B^T */
static inline void mpm_m3_mul_bt(const mpm_real A[9], const mpm_real B[9], mpm_real C[9]) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      C[3 * r + c] =
          A[3 * r] * B[3 * c] + A[3 * r + 1] * B[3 * c + 1] + A[3 * r + 2] * B[3 * c + 2];
}

/* C = A^T B */
static inline void mpm_m3_mul_at(const mpm_real A[9], const mpm_real B[9], mpm_real C[9]) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      C[3 * r + c] = A[r] * B[c] + A[3 + r] * B[3 + c] + A[6 + r] * B[6 + c];
}

static inline void mpm_m3_transpose(const mpm_real A[9], mpm_real B[9]) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) B[3 * c + r] = A[3 * r + c];
}

/* y = A x */
static inline void mpm_m3_mulv(const mpm_real A[9], const mpm_real x[3], mpm_real y[3]) {
  for (int r = 0; r < 3; ++r) y[r] = A[3 * r] * x[0] + A[3 * r + 1] * x[1] + A[3 * r + 2] * x[2];
}

static inline mpm_real mpm_m3_det(const mpm_real A[9]) {
  return A[0] * (A[4] * A[8] - A[5] * A[7]) - A[1] * (A[3] * A[8] - A[5] * A[6]) +
         A[2] * (A[3] * A[7] - A[4] * A[6]);
}

/* Cofactor matrix: cof(A) = det(A) A^{-T}, defined for singular A too. */
static inline void mpm_m3_cofactor(const mpm_real A[9], mpm_real C[9]) {
  C[0] = A[4] * A[8] - A[5] * A[7];
  C[1] = A[5] * A[6] - A[3] * A[8];
  C[2] = A[3] * A[7] - A[4] * A[6];
  C[3] = A[2] * A[7] - A[1] * A[8];
  C[4] = A[0] * A[8] - A[2] * A[6];
  C[5] = A[1] * A[6] - A[0] * A[7];
  C[6] = A[1] * A[5] - A[2] * A[4];
  C[7] = A[2] * A[3] - A[0] * A[5];
  C[8] = A[0] * A[4] - A[1] * A[3];
}

/* A^{-1}; returns the determinant (the result is garbage when it is 0). */
static inline mpm_real mpm_m3_inverse(const mpm_real A[9], mpm_real B[9]) {
  mpm_real C[9];
  mpm_m3_cofactor(A, C);
  mpm_real det = A[0] * C[0] + A[1] * C[1] + A[2] * C[2];
  mpm_real inv = 1 / det;
  mpm_m3_transpose(C, B);
  for (int i = 0; i < 9; ++i) B[i] *= inv;
  return det;
}

/* A : B (Frobenius inner product) */
static inline mpm_real mpm_m3_ddot(const mpm_real A[9], const mpm_real B[9]) {
  mpm_real s = 0;
  for (int i = 0; i < 9; ++i) s += A[i] * B[i];
  return s;
}

static inline mpm_real mpm_m3_trace(const mpm_real A[9]) {
  return A[0] + A[4] + A[8];
}

/* U diag(s) V^T */
static inline void mpm_m3_usvt(const mpm_real U[9], const mpm_real s[3], const mpm_real V[9],
                               mpm_real A[9]) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      A[3 * r + c] = U[3 * r] * s[0] * V[3 * c] + U[3 * r + 1] * s[1] * V[3 * c + 1] +
                     U[3 * r + 2] * s[2] * V[3 * c + 2];
}

static inline mpm_real mpm_v3_dot(const mpm_real a[3], const mpm_real b[3]) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static inline void mpm_v3_cross(const mpm_real a[3], const mpm_real b[3], mpm_real c[3]) {
  c[0] = a[1] * b[2] - a[2] * b[1];
  c[1] = a[2] * b[0] - a[0] * b[2];
  c[2] = a[0] * b[1] - a[1] * b[0];
}

static inline mpm_real mpm_v3_norm(const mpm_real a[3]) {
  return mpm_sqrt(mpm_v3_dot(a, a));
}

/* Rotation matrix for angle theta (rad) about the unit axis a (Rodrigues). */
static inline void mpm_m3_axis_angle(const mpm_real a[3], mpm_real theta, mpm_real R[9]) {
  mpm_real c = mpm_cos(theta), s = mpm_sin(theta), t = 1 - c;
  R[0] = c + t * a[0] * a[0];
  R[1] = t * a[0] * a[1] - s * a[2];
  R[2] = t * a[0] * a[2] + s * a[1];
  R[3] = t * a[0] * a[1] + s * a[2];
  R[4] = c + t * a[1] * a[1];
  R[5] = t * a[1] * a[2] - s * a[0];
  R[6] = t * a[0] * a[2] - s * a[1];
  R[7] = t * a[1] * a[2] + s * a[0];
  R[8] = c + t * a[2] * a[2];
}

#endif
