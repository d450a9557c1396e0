/* isotropic.h - private to src/material/: the stress derivative of an isotropic energy in the
 * diagonal (SVD) space, and its positive semi-definite projection.
 *
 * For Psi(F) = psi(sigma_1, sigma_2, sigma_3), F = U diag(sigma) V^T (core/svd3.h signs), the
 * action dP = (dP/dF) : dF is U dP^ V^T with dF^ = U^T dF V and (Irving et al. 2004; Teran,
 * Sifakis, Irving, Fedkiw 2005, "Robust quasistatic finite elements and flesh simulation"):
 *  - diagonal entries:  dP^_ii = sum_j A_ij dF^_jj,  A_ij = d2 psi / dsigma_i dsigma_j;
 *  - each pair i < j:  with p = (dF^_ij + dF^_ji) / 2 and q = (dF^_ij - dF^_ji) / 2,
 *      dP^_ij = l_sym p + l_skew q,  dP^_ji = l_sym p - l_skew q,
 *      l_sym = (g_i - g_j) / (sigma_i - sigma_j),  l_skew = (g_i + g_j) / (sigma_i + sigma_j),
 *    g_i = dpsi/dsigma_i. (The 2x2 "twist/flip" block [[a, b], [b, a]] with a = (l_sym +
 *    l_skew)/2, b = (l_sym - l_skew)/2 has eigenvalues l_sym and l_skew.)
 * Each model supplies A and the six l's in a numerically stable form (the quotients have
 * finite limits that the models write out).
 *
 * The definiteness fix (Teran et al. 2005 sec. 5; Zhu et al. 2017 eqs. 16 and 19): the 9x9
 * Hessian is block diagonal in this basis (one 3x3 block A and three 2x2 blocks), so clamping
 * the eigenvalues of each block at zero gives the nearest positive semi-definite Hessian with
 * the same eigenvectors. A is diagonalized by cyclic Jacobi in double. */
#ifndef MPM_MATERIAL_ISOTROPIC_H
#define MPM_MATERIAL_ISOTROPIC_H

#include "core/mat3.h"
#include "core/real.h"

#include <math.h>

#include "material/material.h"

/* A: d2 psi / dsigma_i dsigma_j, symmetric, row-major; lsym, lskew: pairs (0,1), (0,2), (1,2)
 * (material.h) */
typedef mpm_stress_hessian mpm_iso_hessian;

static const int MPM_ISO_PAIR[3][2] = {{0, 1}, {0, 2}, {1, 2}};

/* Replace A by its projection onto the positive semi-definite cone (Jacobi eigenvalues,
 * negatives set to zero), and the twist/flip eigenvalues l by max(l, 0). */
static inline void mpm_iso_make_definite(mpm_iso_hessian *h) {
  for (int k = 0; k < 3; ++k) {
    h->lsym[k] = mpm_fmax(h->lsym[k], 0);
    h->lskew[k] = mpm_fmax(h->lskew[k], 0);
  }
  double a[9], q[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  for (int i = 0; i < 9; ++i) a[i] = h->A[i];
  for (int i = 0; i < 3; ++i) /* symmetrize exactly */
    for (int j = 0; j < i; ++j) a[3 * i + j] = a[3 * j + i] = 0.5 * (a[3 * i + j] + a[3 * j + i]);
  const double scale = fabs(a[0]) + fabs(a[4]) + fabs(a[8]) + fabs(a[1]) + fabs(a[2]) + fabs(a[5]);
  if (!(scale > 0)) return;
  /* positive definite by its leading minors (Sylvester): A stays as is, which is what the
     eigenvalues below would conclude, without the sweeps (most particles of an elastic body
     are here; the sweeps were half of the implicit step's Hessian build) */
  const double m2 = a[0] * a[4] - a[1] * a[1];
  const double m3 = a[0] * (a[4] * a[8] - a[5] * a[5]) - a[1] * (a[1] * a[8] - a[5] * a[2]) +
                    a[2] * (a[1] * a[5] - a[4] * a[2]);
  if (a[0] > 0 && m2 > 0 && m3 > 0) return;
  for (int sweep = 0; sweep < 12; ++sweep) {
    const double off = fabs(a[1]) + fabs(a[2]) + fabs(a[5]);
    if (off <= 1e-18 * scale) break;
    for (int k = 0; k < 3; ++k) {
      const int p = MPM_ISO_PAIR[k][0], r = MPM_ISO_PAIR[k][1];
      const double apr = a[3 * p + r];
      if (apr == 0) continue;
      /* Givens rotation zeroing a_pr (Golub and Van Loan, sec. 8.5) */
      const double theta = (a[3 * r + r] - a[3 * p + p]) / (2 * apr);
      const double t = (theta >= 0 ? 1.0 : -1.0) / (fabs(theta) + sqrt(theta * theta + 1));
      const double c = 1 / sqrt(t * t + 1), s = t * c;
      for (int i = 0; i < 3; ++i) { /* a <- a J (columns p, r) */
        const double aip = a[3 * i + p], air = a[3 * i + r];
        a[3 * i + p] = c * aip - s * air;
        a[3 * i + r] = s * aip + c * air;
      }
      for (int i = 0; i < 3; ++i) { /* a <- J^T a (rows p, r) */
        const double api = a[3 * p + i], ari = a[3 * r + i];
        a[3 * p + i] = c * api - s * ari;
        a[3 * r + i] = s * api + c * ari;
      }
      for (int i = 0; i < 3; ++i) { /* q <- q J */
        const double qip = q[3 * i + p], qir = q[3 * i + r];
        q[3 * i + p] = c * qip - s * qir;
        q[3 * i + r] = s * qip + c * qir;
      }
    }
  }
  const double l[3] = {fmax(a[0], 0), fmax(a[4], 0), fmax(a[8], 0)};
  if (a[0] >= 0 && a[4] >= 0 && a[8] >= 0) return; /* already semi-definite: keep A as is */
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      h->A[3 * i + j] = (mpm_real)(q[3 * i] * l[0] * q[3 * j] + q[3 * i + 1] * l[1] * q[3 * j + 1] +
                                   q[3 * i + 2] * l[2] * q[3 * j + 2]);
}

/* dP = U dP^(U^T dF V) V^T with the blocks above. */
static inline void mpm_iso_action(const mpm_iso_hessian *h, const mpm_real dF[9], mpm_real dP[9]) {
  mpm_real T[9], d[9], p[9];
  mpm_m3_mul_at(h->U, dF, T);
  mpm_m3_mul(T, h->V, d);
  for (int i = 0; i < 3; ++i)
    p[4 * i] = h->A[3 * i] * d[0] + h->A[3 * i + 1] * d[4] + h->A[3 * i + 2] * d[8];
  for (int k = 0; k < 3; ++k) {
    const int i = MPM_ISO_PAIR[k][0], j = MPM_ISO_PAIR[k][1];
    const mpm_real sy = R_(0.5) * (d[3 * i + j] + d[3 * j + i]);
    const mpm_real sk = R_(0.5) * (d[3 * i + j] - d[3 * j + i]);
    p[3 * i + j] = h->lsym[k] * sy + h->lskew[k] * sk;
    p[3 * j + i] = h->lsym[k] * sy - h->lskew[k] * sk;
  }
  mpm_m3_mul(h->U, p, T);
  mpm_m3_mul_bt(T, h->V, dP);
}

/* (log a - log b) / (a - b) for a, b > 0, accurate also for a ~ b:
 * = 2 atanh(z) / (z (a + b)) with z = (a - b) / (a + b), atanh(z)/z = 1 + z^2/3 + z^4/5 + ... */
static inline mpm_real mpm_log_divdiff(mpm_real a, mpm_real b) {
  const double z = ((double)a - (double)b) / ((double)a + (double)b);
  const double z2 = z * z;
  const double q = fabs(z) < 1e-3 ? 1 + z2 * (1.0 / 3 + z2 * (1.0 / 5)) : atanh(z) / z;
  return (mpm_real)(2 * q / ((double)a + (double)b));
}

#endif
