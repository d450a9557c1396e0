/* neo_hookean.c - compressible neo-Hookean elasticity with inversion handling.
 *
 * The model of Zhu et al. 2017 sec. 7 (and Bonet and Wood):
 *   Psi(F) = mu/2 (tr(F^T F) - 3) - mu ln J + lambda/2 (ln J)^2,
 *   P      = mu (F - F^{-T}) + lambda ln J F^{-T},
 *   tau    = P F^T = mu (F F^T - I) + lambda ln J I.
 *
 * Inversion handling (Zhu et al. 2017 sec. 5.3, after Irving, Teran, Fedkiw 2004): with
 * F = U diag(s) V^T (core/svd3.h: U, V rotations, the sign of J in s[2]), every s_i below
 * min_stretch = c is clamped, c_i = max(s_i, c), the stress is evaluated in the diagonal space
 * and rotated back: P = U diag(p(c_1..3)) V^T, p_i = mu c_i + (lambda ln J^ - mu) / c_i,
 * J^ = c_1 c_2 c_3. P is continuous across the clamp and finite for flat and inverted F.
 *
 * Energy in the clamped region: psi(c_1..3) plus the first-order extension
 * sum_i p_i (s_i - c_i). The clamped P is not the gradient of any energy (Irving's extension
 * acts on the stress), so no choice is exactly consistent; this one is continuous across the
 * threshold, satisfies dPsi/ds_i = p_i along every clamped direction (so the work done
 * compressing a flat or inverted particle shows up in the energy), and equals psi(s) when
 * nothing is clamped. psi(c) alone would be flat in the clamped directions.
 *
 * Fast path: sigma_min >= 2 J / ||F||_F^2 (because sigma_1 sigma_2 <= ||F||_F^2 / 2), so when
 * J > 0 and 2 J >= c ||F||_F^2 no clamp can be active and the closed forms above are used
 * without an SVD.
 *
 * dP/dF acting on dF (implicit solve, Zhu et al. 2017 sec. 6):
 *  - unclamped: the exact derivative of the closed form,
 *      dP = mu dF + (mu - lambda ln J) F^{-T} dF^T F^{-T} + lambda tr(F^{-1} dF) F^{-T};
 *  - clamped: Zhu eq. 16, the Hessian of Psi evaluated at the clamped diagonal F^ = diag(c)
 *    acting on U^T dF V and rotated back, i.e. the same formula with F^ in place of F in the
 *    diagonal space. By isotropy this is the exact Hessian of the unclamped energy at
 *    F_c = U diag(c) V^T: symmetric, finite (c_i >= c > 0), and equal to the unclamped
 *    derivative at the threshold. It is not the derivative of the clamped P (which is not
 *    symmetric and has zero stiffness along clamped directions).
 *
 * dpdf_action_definite (Teran et al. 2005; Zhu eqs. 16, 19): the same Hessian at the clamped
 * diagonal c in the diagonal space (material/isotropic.h), psi(c) as above,
 *   A_ii = mu + (mu - lambda ln J^ + lambda) / c_i^2,  A_ij = lambda / (c_i c_j),
 *   l_sym = mu + (mu - lambda ln J^) / (c_i c_j),  l_skew = mu + (lambda ln J^ - mu) / (c_i c_j),
 * each block projected to positive semi-definite (c_i is floored at MPM_REAL_EPS should
 * min_stretch be 0). */
#include "material/material.h"
#include "material/isotropic.h"

#include "core/mat3.h"
#include "core/vecmath.h"
#include "core/svd3.h"

#include <assert.h>

/* J > 0 and 2 J >= c ||F||^2: no singular value is below c. */
static inline int nh_unclamped(const mpm_real F[9], mpm_real J, mpm_real c) {
  return J > 0 && 2 * J >= c * mpm_m3_ddot(F, F);
}

/* The diagonal-space state of a (possibly) clamped F. */
typedef struct nh_diag {
  mpm_real U[9], V[9];
  mpm_real s[3]; /* signed singular values of F */
  mpm_real c[3]; /* clamped: max(s_i, min_stretch) */
  mpm_real p[3]; /* diagonal of P^ at the clamped values */
  mpm_real lnJ;  /* ln(c_1 c_2 c_3) */
} nh_diag;

static void nh_diagonalize(const mpm_material *m, const mpm_real F[9], nh_diag *d) {
  mpm_svd3(F, d->U, d->s, d->V);
  for (int i = 0; i < 3; ++i) d->c[i] = mpm_fmax(d->s[i], m->min_stretch);
  d->lnJ = mpm_log(d->c[0] * d->c[1] * d->c[2]);
  const mpm_real k = m->lambda * d->lnJ - m->mu;
  for (int i = 0; i < 3; ++i) d->p[i] = m->mu * d->c[i] + k / d->c[i];
}

static mpm_real nh_energy(const mpm_material *m, const mpm_real F[9]) {
  const mpm_real J = mpm_m3_det(F);
  if (nh_unclamped(F, J, m->min_stretch)) {
    const mpm_real lnJ = mpm_log(J);
    return R_(0.5) * m->mu * (mpm_m3_ddot(F, F) - 3) - m->mu * lnJ +
           R_(0.5) * m->lambda * lnJ * lnJ;
  }
  nh_diag d;
  nh_diagonalize(m, F, &d);
  const mpm_real cc = d.c[0] * d.c[0] + d.c[1] * d.c[1] + d.c[2] * d.c[2];
  mpm_real psi = R_(0.5) * m->mu * (cc - 3) - m->mu * d.lnJ + R_(0.5) * m->lambda * d.lnJ * d.lnJ;
  for (int i = 0; i < 3; ++i) psi += d.p[i] * (d.s[i] - d.c[i]);
  return psi;
}

static void nh_pk1(const mpm_material *m, const mpm_real F[9], mpm_real P[9]) {
  mpm_real C[9];
  mpm_m3_cofactor(F, C);
  const mpm_real J = F[0] * C[0] + F[1] * C[1] + F[2] * C[2];
  if (nh_unclamped(F, J, m->min_stretch)) {
    /* P = mu F + (lambda ln J - mu) F^{-T}, F^{-T} = C / J */
    const mpm_real k = (m->lambda * mpm_log(J) - m->mu) / J;
    for (int i = 0; i < 9; ++i) P[i] = m->mu * F[i] + k * C[i];
    return;
  }
  nh_diag d;
  nh_diagonalize(m, F, &d);
  mpm_m3_usvt(d.U, d.p, d.V, P);
}

/* dP = mu dF + (mu - lambda lnJ) G dF^T G + lambda tr(G^T dF) G with G = F^{-T}. */
static void nh_dp_closed(const mpm_material *m, const mpm_real G[9], mpm_real lnJ,
                         const mpm_real dF[9], mpm_real dP[9]) {
  mpm_real T[9], GdFtG[9];
  mpm_m3_mul_bt(G, dF, T); /* G dF^T */
  mpm_m3_mul(T, G, GdFtG);
  const mpm_real tr = m->lambda * mpm_m3_ddot(G, dF); /* tr(F^{-1} dF) = F^{-T} : dF */
  const mpm_real k = m->mu - m->lambda * lnJ;
  for (int i = 0; i < 9; ++i) dP[i] = m->mu * dF[i] + k * GdFtG[i] + tr * G[i];
}

static void nh_dpdf_action(const mpm_material *m, const mpm_real F[9], const mpm_real dF[9],
                           mpm_real dP[9]) {
  mpm_real C[9];
  mpm_m3_cofactor(F, C);
  const mpm_real J = F[0] * C[0] + F[1] * C[1] + F[2] * C[2];
  if (nh_unclamped(F, J, m->min_stretch)) {
    const mpm_real inv = 1 / J;
    for (int i = 0; i < 9; ++i) C[i] *= inv;
    nh_dp_closed(m, C, mpm_log(J), dF, dP);
    return;
  }
  /* Zhu eq. 16: the closed form at F^ = diag(c) on dF^ = U^T dF V, rotated back */
  nh_diag d;
  nh_diagonalize(m, F, &d);
  mpm_real T[9], dFh[9], dPh[9];
  mpm_m3_mul_at(d.U, dF, T);
  mpm_m3_mul(T, d.V, dFh);
  const mpm_real G[9] = {1 / d.c[0], 0, 0, 0, 1 / d.c[1], 0, 0, 0, 1 / d.c[2]};
  nh_dp_closed(m, G, d.lnJ, dFh, dPh);
  mpm_m3_mul(d.U, dPh, T);
  mpm_m3_mul_bt(T, d.V, dP);
}

static void nh_hessian_definite_svd(const mpm_material *m, const mpm_real U[9], const mpm_real s[3],
                                    const mpm_real V[9], mpm_stress_hessian *Hp) {
  mpm_iso_hessian H;
  mpm_real c[3];
  for (int e = 0; e < 9; ++e) H.U[e] = U[e], H.V[e] = V[e];
  const mpm_real cmin = mpm_fmax(m->min_stretch, MPM_REAL_EPS);
  for (int i = 0; i < 3; ++i) c[i] = mpm_fmax(s[i], cmin);
  const mpm_real lnJ = mpm_log(c[0] * c[1] * c[2]);
  const mpm_real mu = m->mu, l = m->lambda;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      H.A[3 * i + j] = i == j ? mu + (mu - l * lnJ + l) / (c[i] * c[i]) : l / (c[i] * c[j]);
  for (int k = 0; k < 3; ++k) {
    const mpm_real cc = c[MPM_ISO_PAIR[k][0]] * c[MPM_ISO_PAIR[k][1]];
    H.lsym[k] = mu + (mu - l * lnJ) / cc;
    H.lskew[k] = mu + (l * lnJ - mu) / cc;
  }
  mpm_iso_make_definite(&H);
  *Hp = H;
}

static void nh_hessian_definite(const mpm_material *m, const mpm_real F[9], mpm_stress_hessian *H) {
  mpm_real U[9], s[3], V[9];
  mpm_svd3(F, U, s, V);
  nh_hessian_definite_svd(m, U, s, V, H);
}

static void nh_dpdf_action_definite(const mpm_material *m, const mpm_real F[9],
                                    const mpm_real dF[9], mpm_real dP[9]) {
  mpm_stress_hessian H;
  nh_hessian_definite(m, F, &H);
  mpm_iso_action(&H, dF, dP);
}

/* Two passes so that the common case stays a branch-free loop: the closed form
 * tau = mu (F F^T - I) + lambda ln J I for every particle, then the few particles that may be
 * clamped are redone in the diagonal space, tau = U diag(p_i s_i) U^T (= P F^T). */
/* P = mu F + (lambda ln J - mu) F^-T (F^-T = cof F / J) as one loop over the chunk with the
 * logarithm vectorized, then the particles that may be clamped through nh_pk1. */
static void nh_pk1_batch(const mpm_material *m, int n, const mpm_real *const F[9],
                         mpm_real P[9][MPM_STRESS_CHUNK]) {
  assert(n >= 0 && n <= MPM_STRESS_CHUNK);
  const mpm_real mu = m->mu, l = m->lambda, c = m->min_stretch;
  mpm_real J[MPM_STRESS_CHUNK], Jc[MPM_STRESS_CHUNK], lnJ[MPM_STRESS_CHUNK];
  int slow[MPM_STRESS_CHUNK], nslow = 0;
  for (int i = 0; i < n; ++i) {
    const mpm_real f0 = F[0][i], f1 = F[1][i], f2 = F[2][i], f3 = F[3][i], f4 = F[4][i],
                   f5 = F[5][i], f6 = F[6][i], f7 = F[7][i], f8 = F[8][i];
    J[i] = f0 * (f4 * f8 - f5 * f7) + f1 * (f5 * f6 - f3 * f8) + f2 * (f3 * f7 - f4 * f6);
    const mpm_real ff =
        f0 * f0 + f1 * f1 + f2 * f2 + f3 * f3 + f4 * f4 + f5 * f5 + f6 * f6 + f7 * f7 + f8 * f8;
    /* clamped (see nh_unclamped), or so flat that the vector logarithm's floor would apply */
    slow[i] = !(J[i] > 0 && 2 * J[i] >= c * ff) || J[i] < MPM_REAL_EPS;
    nslow += slow[i];
    Jc[i] = mpm_fmax(J[i], MPM_REAL_EPS);
  }
  mpm_log_array(n, Jc, lnJ);
  for (int i = 0; i < n; ++i) {
    mpm_real Fi[9], C[9];
    for (int e = 0; e < 9; ++e) Fi[e] = F[e][i];
    mpm_m3_cofactor(Fi, C);
    const mpm_real k = (l * lnJ[i] - mu) / Jc[i];
    for (int e = 0; e < 9; ++e) P[e][i] = mu * Fi[e] + k * C[e];
  }
  if (nslow == 0) return;
  for (int i = 0; i < n; ++i) {
    if (!slow[i]) continue;
    mpm_real Fi[9], Pi[9];
    for (int e = 0; e < 9; ++e) Fi[e] = F[e][i];
    nh_pk1(m, Fi, Pi);
    for (int e = 0; e < 9; ++e) P[e][i] = Pi[e];
  }
}

static void nh_kirchhoff_batch(const mpm_material *m, int n, const mpm_real *const F[9],
                               const mpm_real *plastic, mpm_real tau[9][MPM_STRESS_CHUNK]) {
  (void)plastic; /* elastic: no plastic state */
  assert(n >= 0 && n <= MPM_STRESS_CHUNK);
  const mpm_real mu = m->mu, l = m->lambda, c = m->min_stretch;
  /* Written as straight loops over the chunk so that the compiler vectorizes them across
   * particles, the logarithm included (core/vecmath.h). */
  mpm_real J[MPM_STRESS_CHUNK], lnJ[MPM_STRESS_CHUNK];
  int nslow = 0;
  for (int i = 0; i < n; ++i) {
    const mpm_real f0 = F[0][i], f1 = F[1][i], f2 = F[2][i], f3 = F[3][i], f4 = F[4][i],
                   f5 = F[5][i], f6 = F[6][i], f7 = F[7][i], f8 = F[8][i];
    J[i] = f0 * (f4 * f8 - f5 * f7) - f1 * (f3 * f8 - f5 * f6) + f2 * (f3 * f7 - f4 * f6);
    const mpm_real ff =
        f0 * f0 + f1 * f1 + f2 * f2 + f3 * f3 + f4 * f4 + f5 * f5 + f6 * f6 + f7 * f7 + f8 * f8;
    nslow += !(J[i] > 0 && 2 * J[i] >= c * ff); /* see nh_unclamped */
  }
  mpm_real Jc[MPM_STRESS_CHUNK];
  for (int i = 0; i < n; ++i) Jc[i] = mpm_fmax(J[i], MPM_REAL_EPS);
  mpm_log_array(n, Jc, lnJ);
  for (int i = 0; i < n; ++i) {
    /* tau = P F^T = mu (F F^T - I) + lambda ln J I */
    const mpm_real f0 = F[0][i], f1 = F[1][i], f2 = F[2][i], f3 = F[3][i], f4 = F[4][i],
                   f5 = F[5][i], f6 = F[6][i], f7 = F[7][i], f8 = F[8][i];
    const mpm_real vol = l * lnJ[i] - mu;
    tau[0][i] = mu * (f0 * f0 + f1 * f1 + f2 * f2) + vol;
    tau[4][i] = mu * (f3 * f3 + f4 * f4 + f5 * f5) + vol;
    tau[8][i] = mu * (f6 * f6 + f7 * f7 + f8 * f8) + vol;
    tau[1][i] = tau[3][i] = mu * (f0 * f3 + f1 * f4 + f2 * f5);
    tau[2][i] = tau[6][i] = mu * (f0 * f6 + f1 * f7 + f2 * f8);
    tau[5][i] = tau[7][i] = mu * (f3 * f6 + f4 * f7 + f5 * f8);
  }
  if (nslow == 0) return;
  for (int i = 0; i < n; ++i) {
    mpm_real Fi[9], T[9];
    for (int k = 0; k < 9; ++k) Fi[k] = F[k][i];
    if (nh_unclamped(Fi, J[i], c)) continue;
    nh_diag d;
    nh_diagonalize(m, Fi, &d);
    const mpm_real ps[3] = {d.p[0] * d.s[0], d.p[1] * d.s[1], d.p[2] * d.s[2]};
    mpm_m3_usvt(d.U, ps, d.U, T);
    for (int k = 0; k < 9; ++k) tau[k][i] = T[k];
  }
}

const mpm_model mpm_model_neo_hookean = {
    .name = "neo_hookean",
    .energy = nh_energy,
    .pk1 = nh_pk1,
    .dpdf_action = nh_dpdf_action,
    .dpdf_action_definite = nh_dpdf_action_definite,
    .hessian_definite = nh_hessian_definite,
    .hessian_definite_svd = nh_hessian_definite_svd,
    .kirchhoff_batch = nh_kirchhoff_batch,
    .pk1_batch = nh_pk1_batch,
    .return_map = NULL,
    .plastic_initial = 1,
};
