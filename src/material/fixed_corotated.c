/* fixed_corotated.c - the fixed-corotated hyperelastic model.
 *
 * Stomakhin, Howes, Schroeder, Teran 2012 ("Energetically consistent invertible elasticity"),
 * as used by Gao et al. 2017 sec. 4.1:
 *   Psi(F) = mu ||F - R||_F^2 + lambda/2 (J - 1)^2,   F = R S (polar), J = det F,
 *   P      = 2 mu (F - R) + lambda (J - 1) cof(F),     cof(F) = J F^{-T},
 *   tau    = P F^T = 2 mu (F - R) F^T + lambda (J - 1) J I.
 * R comes from the sign-convention SVD (core/svd3.h), so R is a proper rotation also for
 * inverted F and every formula holds for singular F (the cofactor needs no inverse).
 *
 * dP/dF acting on dF (the implicit solve, Zhu et al. 2017 sec. 6, eqs. 14-15) is the exact
 * derivative:
 *   dP = 2 mu (dF - dR) + lambda (cof(F) : dF) cof(F) + lambda (J - 1) dcof(F)[dF],
 * with dR = U W V^T, W skew, W_ij = (dF^_ij - dF^_ji) / (sigma_i + sigma_j) for dF^ = U^T dF V
 * (the derivative of the rotation of the polar decomposition; see e.g. Twigg and
 * Kacic-Alesic 2010 or Stomakhin et al. 2012 sec. 4). sigma_i + sigma_j >= 0 by the SVD
 * convention and vanishes only where R itself is not differentiable (two singular values of
 * equal magnitude and opposite sign); there the denominator is clamped to a small positive
 * value, which bounds the rotational stiffness instead of letting it blow up.
 *
 * dpdf_action_definite (Teran et al. 2005; Zhu eqs. 16, 19): the same derivative in the
 * diagonal space (material/isotropic.h) with psi(s) = mu sum (s_i - 1)^2 + lambda/2 (J - 1)^2,
 *   A_ii = 2 mu + lambda (J/s_i)^2,  A_ij = lambda (J/s_i)(J/s_j) + lambda (J - 1) s_k,
 *   l_sym = 2 mu - lambda (J - 1) s_k,  l_skew = 2 mu - 4 mu / (s_i + s_j) + lambda (J - 1) s_k
 * ({i, j, k} = {0, 1, 2}; J/s_i is the product of the other two), each block projected to
 * positive semi-definite. The s_i + s_j floor is the one above. */
#include "material/material.h"
#include "material/chunk_svd.h"
#include "material/isotropic.h"
#include "material/snow.h"

#include "core/mat3.h"
#include "core/svd3.h"

#include <assert.h>

/* Smallest allowed sigma_i + sigma_j in dR (relative to the largest singular value). */
#ifdef MPM_USE_DOUBLE
#define FCR_SUM_FLOOR 1e-8
#else
#define FCR_SUM_FLOOR 3e-4f
#endif

static mpm_real fcr_energy(const mpm_material *m, const mpm_real F[9]) {
  mpm_real U[9], s[3], V[9];
  mpm_svd3(F, U, s, V);
  const mpm_real J = mpm_m3_det(F);
  const mpm_real a = s[0] - 1, b = s[1] - 1, c = s[2] - 1;
  return m->mu * (a * a + b * b + c * c) + R_(0.5) * m->lambda * (J - 1) * (J - 1);
}

static void fcr_pk1(const mpm_material *m, const mpm_real F[9], mpm_real P[9]) {
  mpm_real R[9], S[9], C[9];
  mpm_polar3(F, R, S);
  mpm_m3_cofactor(F, C);
  const mpm_real J = F[0] * C[0] + F[1] * C[1] + F[2] * C[2];
  const mpm_real two_mu = 2 * m->mu, lj = m->lambda * (J - 1);
  for (int i = 0; i < 9; ++i) P[i] = two_mu * (F[i] - R[i]) + lj * C[i];
}

/* The cofactor entries are C_k = A_a A_b - A_c A_d with these (a, b, c, d) (see mat3.h). */
static const int COF_IDX[9][4] = {{4, 8, 5, 7}, {5, 6, 3, 8}, {3, 7, 4, 6},
                                  {2, 7, 1, 8}, {0, 8, 2, 6}, {1, 6, 0, 7},
                                  {1, 5, 2, 4}, {2, 3, 0, 5}, {0, 4, 1, 3}};

/* dcof(F)[dF]: the directional derivative of the (quadratic) cofactor map. */
static void cofactor_derivative(const mpm_real F[9], const mpm_real dF[9], mpm_real dC[9]) {
  for (int k = 0; k < 9; ++k) {
    const int a = COF_IDX[k][0], b = COF_IDX[k][1], c = COF_IDX[k][2], d = COF_IDX[k][3];
    dC[k] = dF[a] * F[b] + F[a] * dF[b] - dF[c] * F[d] - F[c] * dF[d];
  }
}

static void fcr_dpdf_action(const mpm_material *m, const mpm_real F[9], const mpm_real dF[9],
                            mpm_real dP[9]) {
  mpm_real U[9], s[3], V[9];
  mpm_svd3(F, U, s, V);

  /* dR = U W V^T with W skew from dF^ = U^T dF V */
  mpm_real T[9], dFh[9];
  mpm_m3_mul_at(U, dF, T);
  mpm_m3_mul(T, V, dFh);
  const mpm_real sum_floor = FCR_SUM_FLOOR * mpm_fmax(s[0], MPM_REAL_EPS);
  const mpm_real w01 = (dFh[1] - dFh[3]) / mpm_fmax(s[0] + s[1], sum_floor);
  const mpm_real w02 = (dFh[2] - dFh[6]) / mpm_fmax(s[0] + s[2], sum_floor);
  const mpm_real w12 = (dFh[5] - dFh[7]) / mpm_fmax(s[1] + s[2], sum_floor);
  const mpm_real W[9] = {0, w01, w02, -w01, 0, w12, -w02, -w12, 0};
  mpm_real UW[9], dR[9];
  mpm_m3_mul(U, W, UW);
  mpm_m3_mul_bt(UW, V, dR);

  /* volumetric part */
  mpm_real C[9], dC[9];
  mpm_m3_cofactor(F, C);
  cofactor_derivative(F, dF, dC);
  const mpm_real J = F[0] * C[0] + F[1] * C[1] + F[2] * C[2];
  const mpm_real dJ = mpm_m3_ddot(C, dF);
  const mpm_real two_mu = 2 * m->mu, l = m->lambda;
  for (int i = 0; i < 9; ++i)
    dP[i] = two_mu * (dF[i] - dR[i]) + l * dJ * C[i] + l * (J - 1) * dC[i];
}

static void fcr_hessian_definite_svd(const mpm_material *m, const mpm_real U[9],
                                     const mpm_real s[3], const mpm_real V[9],
                                     mpm_stress_hessian *Hp) {
  mpm_iso_hessian H;
  for (int e = 0; e < 9; ++e) H.U[e] = U[e], H.V[e] = V[e];
  const mpm_real two_mu = 2 * m->mu, l = m->lambda;
  const mpm_real J = s[0] * s[1] * s[2];
  const mpm_real Js[3] = {s[1] * s[2], s[0] * s[2], s[0] * s[1]};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      H.A[3 * i + j] =
          i == j ? two_mu + l * Js[i] * Js[i] : l * Js[i] * Js[j] + l * (J - 1) * s[3 - i - j];
  const mpm_real sum_floor = FCR_SUM_FLOOR * mpm_fmax(s[0], MPM_REAL_EPS);
  for (int k = 0; k < 3; ++k) {
    const int i = MPM_ISO_PAIR[k][0], j = MPM_ISO_PAIR[k][1];
    const mpm_real vk = l * (J - 1) * s[3 - i - j];
    H.lsym[k] = two_mu - vk;
    H.lskew[k] = two_mu - 2 * two_mu / mpm_fmax(s[i] + s[j], sum_floor) + vk;
  }
  mpm_iso_make_definite(&H);
  *Hp = H;
}

static void fcr_hessian_definite(const mpm_material *m, const mpm_real F[9],
                                 mpm_stress_hessian *H) {
  mpm_real U[9], s[3], V[9];
  mpm_svd3(F, U, s, V);
  fcr_hessian_definite_svd(m, U, s, V, H);
}

static void fcr_dpdf_action_definite(const mpm_material *m, const mpm_real F[9],
                                     const mpm_real dF[9], mpm_real dP[9]) {
  mpm_stress_hessian H;
  fcr_hessian_definite(m, F, &H);
  mpm_iso_action(&H, dF, dP);
}

/* tau = 2 mu (F - R) F^T + lambda (J - 1) J I, with (F - R) F^T = U diag(s (s - 1)) U^T
 * (F F^T = U S^2 U^T and R F^T = U S U^T), symmetric by construction; J = det F from F's
 * entries (more accurate near J = 1 than the product of the singular values). The SVDs of the chunk
 * come from one SIMD batch (chunk_svd.h); the rest is a unit-stride loop over particles, which the
 * compiler vectorizes. */
void mpm_fcr_kirchhoff_scaled(const mpm_material *m, int n, const mpm_real *const F[9],
                              const mpm_real *scale, mpm_real tau[9][MPM_STRESS_CHUNK]) {
  mpm_chunk_svd d;
  mpm_chunk_svd_compute(n, F, &d);
  const mpm_real two_mu = 2 * m->mu, l = m->lambda;
  mpm_real dg[3][MPM_STRESS_CHUNK], iso[MPM_STRESS_CHUNK], ones[MPM_STRESS_CHUNK];
  if (!scale) {
    for (int i = 0; i < n; ++i) ones[i] = 1;
    scale = ones;
  }
  for (int i = 0; i < n; ++i) {
    const mpm_real J = F[0][i] * (F[4][i] * F[8][i] - F[5][i] * F[7][i]) -
                       F[1][i] * (F[3][i] * F[8][i] - F[5][i] * F[6][i]) +
                       F[2][i] * (F[3][i] * F[7][i] - F[4][i] * F[6][i]);
    const mpm_real mk = two_mu * scale[i];
    for (int k = 0; k < 3; ++k) dg[k][i] = mk * d.s[k][i] * (d.s[k][i] - 1);
    iso[i] = l * scale[i] * (J - 1) * J;
  }
  mpm_chunk_svd_tau(n, &d, (const mpm_real(*)[MPM_STRESS_CHUNK])dg, iso, tau);
}

/* P = 2 mu (F - R) + lambda (J - 1) cof F, with F - R = U diag(s - 1) V^T from the chunk's
 * SVDs (R = U V^T: the signed singular values keep U and V rotations, as mpm_polar3's R) and the
 * cofactor and J from F's entries, as fcr_pk1. */
static void fcr_pk1_batch(const mpm_material *m, int n, const mpm_real *const F[9],
                          mpm_real P[9][MPM_STRESS_CHUNK]) {
  mpm_chunk_svd d;
  mpm_chunk_svd_compute(n, F, &d);
  const mpm_real two_mu = 2 * m->mu, l = m->lambda;
  mpm_real dg[3][MPM_STRESS_CHUNK];
  for (int k = 0; k < 3; ++k)
    for (int i = 0; i < n; ++i) dg[k][i] = two_mu * (d.s[k][i] - 1);
  mpm_chunk_svd_pk1(n, &d, (const mpm_real(*)[MPM_STRESS_CHUNK])dg, P);
  for (int i = 0; i < n; ++i) {
    mpm_real Fi[9], C[9];
    for (int e = 0; e < 9; ++e) Fi[e] = F[e][i];
    mpm_m3_cofactor(Fi, C);
    const mpm_real lj = l * (Fi[0] * C[0] + Fi[1] * C[1] + Fi[2] * C[2] - 1);
    for (int e = 0; e < 9; ++e) P[e][i] += lj * C[e];
  }
}

static void fcr_kirchhoff_batch(const mpm_material *m, int n, const mpm_real *const F[9],
                                const mpm_real *plastic, mpm_real tau[9][MPM_STRESS_CHUNK]) {
  (void)plastic; /* elastic: no plastic state */
  mpm_fcr_kirchhoff_scaled(m, n, F, NULL, tau);
}

const mpm_model mpm_model_fixed_corotated = {
    .name = "fixed_corotated",
    .energy = fcr_energy,
    .pk1 = fcr_pk1,
    .dpdf_action = fcr_dpdf_action,
    .dpdf_action_definite = fcr_dpdf_action_definite,
    .hessian_definite = fcr_hessian_definite,
    .hessian_definite_svd = fcr_hessian_definite_svd,
    .kirchhoff_batch = fcr_kirchhoff_batch,
    .pk1_batch = fcr_pk1_batch,
    .return_map = NULL,
    .plastic_initial = 1,
};
