/* svd3.c - 3x3 singular value and polar decomposition with minimal branching.
 *
 * Reference: McAdams, Selle, Tamstorf, Teran, Sifakis 2011, "Computing the singular value
 * decomposition of 3x3 matrices with minimal branching and elementary floating point
 * operations", UW-Madison TR1690. The steps follow the report:
 *   1. symmetric eigen-analysis of S = F^T F by cyclic Jacobi with a fixed number of sweeps,
 *      accumulating the rotation V (so det V = +1);
 *   2. B = F V; its columns sorted by decreasing norm with a signed swap (det V stays +1);
 *   3. QR of B by three Givens rotations: B = U R, U = product of the rotations (det U = +1).
 *      R is diagonal up to rounding; sigma = diag(R). Each Givens step makes R_00, R_11 >= 0,
 *      so the sign of det F ends up in sigma[2] (the invertible-elasticity convention of Irving
 *      et al. 2004 used by Zhu et al. 2017 sec. 5.3).
 *   4. (not in the report) a three-comparator network on the result that makes the ordering
 *      sigma0 >= sigma1 >= |sigma2| exact: the column norms of step 2 are sorted, but R's
 *      diagonal can be out of order by an ulp when singular values repeat.
 * Differences from the report: the Jacobi rotations use the exact angle (half-angle formula,
 * Golub and Van Loan alg. 8.4.1, written without dividing by the off-diagonal entry) instead
 * of the quaternion approximation, so fewer sweeps reach full precision; and F is first scaled
 * by its largest entry so that tiny or huge matrices neither underflow nor overflow in F^T F.
 * Everything is straight-line code on constant indices (selects instead of branches), so a
 * later pass can vectorize it across particles. */
#include "core/svd3.h"

#include "core/mat3.h"

#ifdef MPM_USE_DOUBLE
#define SVD_TINY DBL_MIN
#define SVD_SWEEPS 5 /* 4 already reach full precision on the tests; one spare */
#else
#define SVD_TINY FLT_MIN
#define SVD_SWEEPS 4 /* 3 leave errors of a few 1e-6 */
#endif

#define SVD_INLINE static inline __attribute__((always_inline))

/* One Jacobi rotation in the (p, q) plane: S <- J^T S J, V <- V J with J = [c s; -s c] in
 * rows/columns p, q chosen so that (J^T S J)_pq = 0. t = tan(theta) is the smaller root of
 * t^2 + 2 tau t - 1 = 0, tau = (S_qq - S_pp) / (2 S_pq), multiplied through by 2|S_pq|. */
SVD_INLINE void jacobi_rotate(mpm_real S[9], mpm_real V[9], const int p, const int q) {
  const int k = 3 - p - q;
  const mpm_real a = S[3 * p + p], d = S[3 * q + q], b = S[3 * p + q];
  const mpm_real diff = d - a;
  const mpm_real sgn = diff >= 0 ? R_(1.0) : R_(-1.0);
  const mpm_real den = mpm_fabs(diff) + mpm_sqrt(diff * diff + 4 * b * b);
  const mpm_real t = 2 * b * sgn / mpm_fmax(den, SVD_TINY);
  const mpm_real c = 1 / mpm_sqrt(1 + t * t), s = t * c;
  S[3 * p + p] = a - t * b;
  S[3 * q + q] = d + t * b;
  S[3 * p + q] = S[3 * q + p] = 0;
  const mpm_real skp = S[3 * k + p], skq = S[3 * k + q];
  S[3 * k + p] = S[3 * p + k] = c * skp - s * skq;
  S[3 * k + q] = S[3 * q + k] = s * skp + c * skq;
  for (int r = 0; r < 3; ++r) {
    const mpm_real vp = V[3 * r + p], vq = V[3 * r + q];
    V[3 * r + p] = c * vp - s * vq;
    V[3 * r + q] = s * vp + c * vq;
  }
}

/* If column i of B is shorter than column j, swap columns i and j of B and V and negate the
 * new column j of both: a signed permutation with det +1, so B = F V still holds. */
SVD_INLINE void sort_swap(mpm_real B[9], mpm_real V[9], mpm_real n[3], const int i, const int j) {
  const int sw = n[i] < n[j];
  const mpm_real ni = n[i], nj = n[j];
  n[i] = sw ? nj : ni;
  n[j] = sw ? ni : nj;
  for (int r = 0; r < 3; ++r) {
    const mpm_real bi = B[3 * r + i], bj = B[3 * r + j];
    B[3 * r + i] = sw ? bj : bi;
    B[3 * r + j] = sw ? -bi : bj;
    const mpm_real vi = V[3 * r + i], vj = V[3 * r + j];
    V[3 * r + i] = sw ? vj : vi;
    V[3 * r + j] = sw ? -vi : vj;
  }
}

/* Givens rotation G = [c s; -s c] on rows p, q of B that zeroes B_q,col and leaves
 * B_p,col = sqrt(B_p,col^2 + B_q,col^2) >= 0; U <- U G^T so that U B stays invariant. */
SVD_INLINE void givens_qr(mpm_real B[9], mpm_real U[9], const int p, const int q, const int col) {
  const mpm_real a = B[3 * p + col], b = B[3 * q + col];
  const mpm_real r2 = a * a + b * b;
  const int ok = r2 > SVD_TINY;
  const mpm_real inv = 1 / mpm_sqrt(mpm_fmax(r2, SVD_TINY));
  const mpm_real c = ok ? a * inv : R_(1.0), s = ok ? b * inv : R_(0.0);
  for (int k = 0; k < 3; ++k) {
    const mpm_real bp = B[3 * p + k], bq = B[3 * q + k];
    B[3 * p + k] = c * bp + s * bq;
    B[3 * q + k] = -s * bp + c * bq;
  }
  for (int r = 0; r < 3; ++r) {
    const mpm_real up = U[3 * r + p], uq = U[3 * r + q];
    U[3 * r + p] = c * up + s * uq;
    U[3 * r + q] = -s * up + c * uq;
  }
}

/* If sigma0 < sigma1: swap them and the columns 0, 1 of U and V, negating the new column 1 of
 * both (U P diag(s') P^T V^T = U diag(s) V^T for the signed permutation P, det P = +1). */
SVD_INLINE void order_01(mpm_real U[9], mpm_real s[3], mpm_real V[9]) {
  const int sw = s[0] < s[1];
  const mpm_real s0 = s[0], s1 = s[1];
  s[0] = sw ? s1 : s0;
  s[1] = sw ? s0 : s1;
  for (int r = 0; r < 3; ++r) {
    const mpm_real u0 = U[3 * r], u1 = U[3 * r + 1], v0 = V[3 * r], v1 = V[3 * r + 1];
    U[3 * r] = sw ? u1 : u0;
    U[3 * r + 1] = sw ? -u0 : u1;
    V[3 * r] = sw ? v1 : v0;
    V[3 * r + 1] = sw ? -v0 : v1;
  }
}

/* If sigma1 < |sigma2|: swap them as above; if sigma2 was negative, the negative value moved
 * to position 1, so also negate sigma1, sigma2 and columns 1, 2 of U (U diag(1,-1,-1) is still
 * a rotation), which puts the sign back on the last one. */
SVD_INLINE void order_12(mpm_real U[9], mpm_real s[3], mpm_real V[9]) {
  const int sw = s[1] < mpm_fabs(s[2]);
  const int neg = sw && s[2] < 0;
  const mpm_real s1 = s[1], s2 = s[2];
  s[1] = sw ? (neg ? -s2 : s2) : s1;
  s[2] = sw ? (neg ? -s1 : s1) : s2;
  for (int r = 0; r < 3; ++r) {
    const mpm_real u1 = U[3 * r + 1], u2 = U[3 * r + 2], v1 = V[3 * r + 1], v2 = V[3 * r + 2];
    U[3 * r + 1] = sw ? (neg ? -u2 : u2) : u1;
    U[3 * r + 2] = sw ? (neg ? u1 : -u1) : u2;
    V[3 * r + 1] = sw ? v2 : v1;
    V[3 * r + 2] = sw ? -v1 : v2;
  }
}

void mpm_svd3(const mpm_real F[9], mpm_real U[9], mpm_real sigma[3], mpm_real V[9]) {
  /* scale by the largest entry: A = F / scale has entries in [-1, 1] */
  mpm_real amax = 0;
  for (int i = 0; i < 9; ++i) amax = mpm_fmax(amax, mpm_fabs(F[i]));
  const mpm_real scale = mpm_fmax(amax, SVD_TINY), inv = 1 / scale;
  mpm_real A[9];
  for (int i = 0; i < 9; ++i) A[i] = F[i] * inv;

  /* 1. Jacobi eigen-analysis of S = A^T A */
  mpm_real S[9];
  mpm_m3_mul_at(A, A, S);
  mpm_m3_identity(V);
  for (int sweep = 0; sweep < SVD_SWEEPS; ++sweep) {
    jacobi_rotate(S, V, 0, 1);
    jacobi_rotate(S, V, 0, 2);
    jacobi_rotate(S, V, 1, 2);
  }

  /* 2. B = A V, columns sorted by decreasing norm */
  mpm_real B[9];
  mpm_m3_mul(A, V, B);
  mpm_real n[3];
  for (int c = 0; c < 3; ++c) n[c] = B[c] * B[c] + B[3 + c] * B[3 + c] + B[6 + c] * B[6 + c];
  sort_swap(B, V, n, 0, 1);
  sort_swap(B, V, n, 0, 2);
  sort_swap(B, V, n, 1, 2);

  /* 3. QR of B by Givens rotations; R's diagonal carries the singular values */
  mpm_m3_identity(U);
  givens_qr(B, U, 0, 1, 0);
  givens_qr(B, U, 0, 2, 0);
  givens_qr(B, U, 1, 2, 1);
  sigma[0] = B[0] * scale;
  sigma[1] = B[4] * scale;
  sigma[2] = B[8] * scale;

  /* 4. exact ordering (a bubble network: 01, 12, 01) */
  order_01(U, sigma, V);
  order_12(U, sigma, V);
  order_01(U, sigma, V);
}

void mpm_polar3(const mpm_real F[9], mpm_real R[9], mpm_real S[9]) {
  mpm_real U[9], sigma[3], V[9];
  mpm_svd3(F, U, sigma, V);
  mpm_m3_mul_bt(U, V, R);
  mpm_m3_usvt(V, sigma, V, S);
}
