/* svd3_lanes.h - the 3x3 SVD of core/svd3.c with one matrix per SIMD lane.
 *
 * The same algorithm and sign convention as mpm_svd3 (McAdams et al. 2011 with exact Jacobi
 * angles; see svd3.c for the steps): every branch of the scalar code is already a select, so
 * the lane version is the same straight-line code on mpm_vn vectors, and it agrees with the
 * scalar one to rounding (tests/test_svd_batch.c). Header-only so that a model's stress batch
 * can use U, sigma and V while they are still in registers instead of storing them. */
#ifndef MPM_CORE_SVD3_LANES_H
#define MPM_CORE_SVD3_LANES_H

#include "core/lanes.h"

#ifdef MPM_USE_DOUBLE
#define MPM_SVD_LANES_TINY DBL_MIN
#define MPM_SVD_LANES_SWEEPS 5
#define MPM_SVD_LANES_MIN_SWEEPS 3
#define MPM_SVD_LANES_OFF_TOL DBL_EPSILON
#else
#define MPM_SVD_LANES_TINY FLT_MIN
#define MPM_SVD_LANES_SWEEPS 4
#define MPM_SVD_LANES_MIN_SWEEPS 2
#define MPM_SVD_LANES_OFF_TOL FLT_EPSILON
#endif

/* One Jacobi rotation in the (p, q) plane of the symmetric S (only S[3i+j], i <= j, is kept
 * up to date), accumulated into V, for G groups. Each statement is issued for every group
 * before the next one, so the instruction stream interleaves the groups' dependency chains
 * (a plain loop over groups around the whole rotation leaves that to the out-of-order
 * scheduler, whose window is too small for it).
 *
 * The angle is the exact one: with diff = S_qq - S_pp, r = sqrt(diff^2 + 4 S_pq^2) and
 * den = |diff| + r, t = tan(theta) = 2 S_pq sgn(diff) / den is the smaller root of
 * t^2 + 2 tau t - 1 = 0 (Golub and Van Loan alg. 8.4.1), and since 1 + t^2 = 2 r / den,
 *   c = 1 / sqrt(1 + t^2) = den k,  s = t c = 2 S_pq sgn(diff) k,  k = 1 / sqrt(2 r den):
 * one square root and one division on the chain, with t's division beside it. Where S_pq and
 * diff both vanish (r = 0) the rotation is the identity. */
MPM_ALWAYS_INLINE void mpm_svd_lanes_jacobi(const int G, mpm_vn S[][9], mpm_vn V[][9], const int p,
                                            const int q) {
  const int k = 3 - p - q;
  const int pk = p < k ? 3 * p + k : 3 * k + p, qk = q < k ? 3 * q + k : 3 * k + q;
  const mpm_vn zero = {0}, tiny = mpm_vn_splat(MPM_SVD_LANES_TINY);
  mpm_vn diff[G], b2[G], den[G], t[G], c[G], s[G];
  for (int g = 0; g < G; ++g) diff[g] = S[g][3 * q + q] - S[g][3 * p + p];
  for (int g = 0; g < G; ++g) b2[g] = mpm_vn_negate_if(diff[g] < zero, 2 * S[g][3 * p + q]);
  for (int g = 0; g < G; ++g)
    den[g] = mpm_vn_abs(diff[g]) + mpm_vn_sqrt(diff[g] * diff[g] + b2[g] * b2[g]);
  for (int g = 0; g < G; ++g) t[g] = b2[g] / mpm_vn_max(den[g], tiny);
  for (int g = 0; g < G; ++g) c[g] = 1 / mpm_vn_sqrt(1 + t[g] * t[g]);
  for (int g = 0; g < G; ++g) s[g] = t[g] * c[g];
  for (int g = 0; g < G; ++g) {
    const mpm_vn tb = t[g] * S[g][3 * p + q];
    S[g][3 * p + p] -= tb;
    S[g][3 * q + q] += tb;
    S[g][3 * p + q] = zero;
  }
  for (int g = 0; g < G; ++g) {
    const mpm_vn skp = S[g][pk], skq = S[g][qk];
    S[g][pk] = c[g] * skp - s[g] * skq;
    S[g][qk] = s[g] * skp + c[g] * skq;
  }
  for (int rr = 0; rr < 3; ++rr)
    for (int g = 0; g < G; ++g) {
      const mpm_vn vp = V[g][3 * rr + p], vq = V[g][3 * rr + q];
      V[g][3 * rr + p] = c[g] * vp - s[g] * vq;
      V[g][3 * rr + q] = s[g] * vp + c[g] * vq;
    }
}

/* Swap columns i, j of B and V where column i is shorter, negating the new column j. */
MPM_ALWAYS_INLINE void mpm_svd_lanes_sort(mpm_vn B[9], mpm_vn V[9], mpm_vn n[3], const int i,
                                          const int j) {
  const mpm_vn_index sw = n[i] < n[j];
  const mpm_vn ni = n[i], nj = n[j];
  n[i] = mpm_vn_select(sw, nj, ni);
  n[j] = mpm_vn_select(sw, ni, nj);
  for (int r = 0; r < 3; ++r) {
    const mpm_vn bi = B[3 * r + i], bj = B[3 * r + j];
    B[3 * r + i] = mpm_vn_select(sw, bj, bi);
    B[3 * r + j] = mpm_vn_select(sw, -bi, bj);
    const mpm_vn vi = V[3 * r + i], vj = V[3 * r + j];
    V[3 * r + i] = mpm_vn_select(sw, vj, vi);
    V[3 * r + j] = mpm_vn_select(sw, -vi, vj);
  }
}

/* Givens rotation on rows p, q of B zeroing B[q][col], accumulated into U, for G groups
 * statement by statement (see mpm_svd_lanes_jacobi). */
MPM_ALWAYS_INLINE void mpm_svd_lanes_givens(const int G, mpm_vn B[][9], mpm_vn U[][9], const int p,
                                            const int q, const int col) {
  const mpm_vn zero = {0}, tiny = mpm_vn_splat(MPM_SVD_LANES_TINY);
  mpm_vn r2[G], inv[G], c[G], s[G];
  for (int g = 0; g < G; ++g)
    r2[g] = B[g][3 * p + col] * B[g][3 * p + col] + B[g][3 * q + col] * B[g][3 * q + col];
  for (int g = 0; g < G; ++g) inv[g] = 1 / mpm_vn_sqrt(mpm_vn_max(r2[g], tiny));
  for (int g = 0; g < G; ++g) {
    const mpm_vn_index ok = r2[g] > tiny;
    c[g] = mpm_vn_select(ok, B[g][3 * p + col] * inv[g], zero + 1);
    s[g] = mpm_vn_select(ok, B[g][3 * q + col] * inv[g], zero);
  }
  for (int k = 0; k < 3; ++k)
    for (int g = 0; g < G; ++g) {
      const mpm_vn bp = B[g][3 * p + k], bq = B[g][3 * q + k];
      B[g][3 * p + k] = c[g] * bp + s[g] * bq;
      B[g][3 * q + k] = c[g] * bq - s[g] * bp;
    }
  for (int r = 0; r < 3; ++r)
    for (int g = 0; g < G; ++g) {
      const mpm_vn up = U[g][3 * r + p], uq = U[g][3 * r + q];
      U[g][3 * r + p] = c[g] * up + s[g] * uq;
      U[g][3 * r + q] = c[g] * uq - s[g] * up;
    }
}

/* Where sigma_i < sigma_j (i = 0, j = 1): swap them and columns i, j of U and V, negating the
 * new column j of both. */
MPM_ALWAYS_INLINE void mpm_svd_lanes_order01(mpm_vn U[9], mpm_vn s[3], mpm_vn V[9]) {
  const mpm_vn_index sw = s[0] < s[1];
  const mpm_vn s0 = s[0], s1 = s[1];
  s[0] = mpm_vn_select(sw, s1, s0);
  s[1] = mpm_vn_select(sw, s0, s1);
  for (int r = 0; r < 3; ++r) {
    const mpm_vn u0 = U[3 * r], u1 = U[3 * r + 1], v0 = V[3 * r], v1 = V[3 * r + 1];
    U[3 * r] = mpm_vn_select(sw, u1, u0);
    U[3 * r + 1] = mpm_vn_select(sw, -u0, u1);
    V[3 * r] = mpm_vn_select(sw, v1, v0);
    V[3 * r + 1] = mpm_vn_select(sw, -v0, v1);
  }
}

/* Where sigma_1 < |sigma_2|: swap them as above, moving a negative sign back to the last one
 * (svd3.c, order_12). */
MPM_ALWAYS_INLINE void mpm_svd_lanes_order12(mpm_vn U[9], mpm_vn s[3], mpm_vn V[9]) {
  const mpm_vn zero = {0};
  const mpm_vn_index sw = s[1] < mpm_vn_abs(s[2]);
  const mpm_vn_index neg = sw & (s[2] < zero);
  const mpm_vn s1 = s[1], s2 = s[2];
  s[1] = mpm_vn_select(sw, mpm_vn_negate_if(neg, s2), s1);
  s[2] = mpm_vn_select(sw, mpm_vn_negate_if(neg, s1), s2);
  for (int r = 0; r < 3; ++r) {
    const mpm_vn u1 = U[3 * r + 1], u2 = U[3 * r + 2], v1 = V[3 * r + 1], v2 = V[3 * r + 2];
    U[3 * r + 1] = mpm_vn_select(sw, mpm_vn_negate_if(neg, u2), u1);
    U[3 * r + 2] = mpm_vn_select(sw, mpm_vn_negate_if(~neg, u1), u2);
    V[3 * r + 1] = mpm_vn_select(sw, v2, v1);
    V[3 * r + 2] = mpm_vn_select(sw, -v1, v2);
  }
}

/* F = U diag(sigma) V^T lane by lane, with the conventions of mpm_svd3 (svd3.h), for G
 * independent groups of MPM_NLANES matrices. The steps are long chains of dependent square
 * roots and divisions, so one group leaves the vector units waiting on latency; each step is
 * issued for all G groups in turn (G a compile-time constant at the call site) so that the
 * chains overlap. */
MPM_ALWAYS_INLINE void mpm_svd3_lanes(const int G, const mpm_vn F[][9], mpm_vn U[][9],
                                      mpm_vn sigma[][3], mpm_vn V[][9]) {
  const mpm_vn zero = {0}, one = zero + 1;
  mpm_vn scale[G], S[G][9], A[G][9], B[G][9], n[G][3];
  for (int g = 0; g < G; ++g) {
    mpm_vn amax = zero;
    for (int i = 0; i < 9; ++i) amax = mpm_vn_max(amax, mpm_vn_abs(F[g][i]));
    scale[g] = mpm_vn_max(amax, mpm_vn_splat(MPM_SVD_LANES_TINY));
    const mpm_vn inv = 1 / scale[g];
    for (int i = 0; i < 9; ++i) A[g][i] = F[g][i] * inv;
    /* 1. Jacobi eigen-analysis of S = A^T A (upper triangle) */
    for (int i = 0; i < 3; ++i)
      for (int j = i; j < 3; ++j)
        S[g][3 * i + j] = A[g][i] * A[g][j] + A[g][3 + i] * A[g][3 + j] + A[g][6 + i] * A[g][6 + j];
    for (int i = 0; i < 9; ++i) V[g][i] = (i % 4 == 0) ? one : zero;
  }
  for (int sweep = 0; sweep < MPM_SVD_LANES_SWEEPS; ++sweep) {
    mpm_svd_lanes_jacobi(G, S, V, 0, 1);
    mpm_svd_lanes_jacobi(G, S, V, 0, 2);
    mpm_svd_lanes_jacobi(G, S, V, 1, 2);
    /* Stop early once every lane of every group is diagonal to eps^2 of its trace: a
     * further rotation could only turn eigenvectors whose eigenvalues agree to that
     * level, which leaves the SVD (B = A V, then QR) unchanged to rounding. Cyclic Jacobi
     * converges quadratically, so this usually saves the last sweep. */
    if (sweep + 1 >= MPM_SVD_LANES_MIN_SWEEPS && sweep + 1 < MPM_SVD_LANES_SWEEPS) {
      mpm_vn_index open = {0};
      for (int g = 0; g < G; ++g) {
        const mpm_vn off =
            mpm_vn_max(mpm_vn_max(mpm_vn_abs(S[g][1]), mpm_vn_abs(S[g][2])), mpm_vn_abs(S[g][5]));
        open |= off > MPM_SVD_LANES_OFF_TOL * (S[g][0] + S[g][4] + S[g][8]);
      }
      int any = 0;
      for (int l = 0; l < MPM_NLANES; ++l) any |= open[l] != 0;
      if (!any) break;
    }
  }
  for (int g = 0; g < G; ++g) {
    /* 2. B = A V, columns sorted by decreasing norm */
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        B[g][3 * i + j] =
            A[g][3 * i] * V[g][j] + A[g][3 * i + 1] * V[g][3 + j] + A[g][3 * i + 2] * V[g][6 + j];
    for (int c = 0; c < 3; ++c)
      n[g][c] = B[g][c] * B[g][c] + B[g][3 + c] * B[g][3 + c] + B[g][6 + c] * B[g][6 + c];
    mpm_svd_lanes_sort(B[g], V[g], n[g], 0, 1);
    mpm_svd_lanes_sort(B[g], V[g], n[g], 0, 2);
    mpm_svd_lanes_sort(B[g], V[g], n[g], 1, 2);
    for (int i = 0; i < 9; ++i) U[g][i] = (i % 4 == 0) ? one : zero;
  }
  /* 3. QR of B by Givens rotations */
  mpm_svd_lanes_givens(G, B, U, 0, 1, 0);
  mpm_svd_lanes_givens(G, B, U, 0, 2, 0);
  mpm_svd_lanes_givens(G, B, U, 1, 2, 1);
  for (int g = 0; g < G; ++g) {
    sigma[g][0] = B[g][0] * scale[g];
    sigma[g][1] = B[g][4] * scale[g];
    sigma[g][2] = B[g][8] * scale[g];
    /* 4. exact ordering */
    mpm_svd_lanes_order01(U[g], sigma[g], V[g]);
    mpm_svd_lanes_order12(U[g], sigma[g], V[g]);
    mpm_svd_lanes_order01(U[g], sigma[g], V[g]);
  }
}

#endif
