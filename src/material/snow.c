/* snow.c - the snow model of Stomakhin, Schroeder, Chai, Chu, Teran, Selle 2013 ("A material
 * point method for snow simulation", sec. 5 and 6).
 *
 * Elasticity: fixed-corotated (fixed_corotated.c) with hardened Lame parameters
 *   mu(Jp) = mu_0 exp(xi (1 - Jp)),  lambda(Jp) = lambda_0 exp(xi (1 - Jp))   (eq. 3),
 * Jp = det F^P the plastic state (plastic_initial = 1). The per-particle entries (energy, pk1,
 * dpdf_action[_definite]) take the material as one particle sees it, mpm_material_at(m, Jp)
 * (material.c); kirchhoff_batch reads Jp itself.
 *
 * Plasticity (sec. 7, "update of F^E and F^P"): the singular values of the trial F^E are
 * clamped to [1 - theta_c, 1 + theta_s]; F^E <- U diag(clamped) V^T and
 * Jp <- Jp det(F^E_trial) / det(F^E_new), so that J = Jp det F^E is preserved. An inverted
 * trial (det < 0; its last singular value is negative) is clamped to det > 0 and Jp takes the
 * ratio of magnitudes (the only case where Jp det F^E changes: its sign). Jp is kept in
 * [SNOW_JP_MIN, SNOW_JP_MAX] = [0.1, 10]: the hardening factor then stays within
 * [exp(-9 xi), exp(0.9 xi)] (no overflow for any sane xi; the stiffness, hence the CFL time
 * step, grows at most by exp(0.9 xi)); where this clamp acts J is not preserved. */
#include "material/snow.h"

#include "core/mat3.h"
#include "core/svd3.h"

#include <assert.h>

#define SNOW_JP_MIN R_(0.1)
#define SNOW_JP_MAX R_(10.0)

mpm_real mpm_snow_hardening(const mpm_material *m, mpm_real Jp) {
  const mpm_real jp = mpm_fmin(mpm_fmax(Jp, SNOW_JP_MIN), SNOW_JP_MAX);
  return mpm_exp(m->hardening * (1 - jp));
}

static mpm_real snow_energy(const mpm_material *m, const mpm_real F[9]) {
  return mpm_model_fixed_corotated.energy(m, F);
}

static void snow_pk1(const mpm_material *m, const mpm_real F[9], mpm_real P[9]) {
  mpm_model_fixed_corotated.pk1(m, F, P);
}

static void snow_dpdf_action(const mpm_material *m, const mpm_real F[9], const mpm_real dF[9],
                             mpm_real dP[9]) {
  mpm_model_fixed_corotated.dpdf_action(m, F, dF, dP);
}

static void snow_dpdf_action_definite(const mpm_material *m, const mpm_real F[9],
                                      const mpm_real dF[9], mpm_real dP[9]) {
  mpm_model_fixed_corotated.dpdf_action_definite(m, F, dF, dP);
}

/* The fixed-corotated tau (fixed_corotated.c) with per-particle moduli. */
static void snow_kirchhoff_batch(const mpm_material *m, int n, const mpm_real *const F[9],
                                 const mpm_real *plastic, mpm_real tau[9][MPM_STRESS_CHUNK]) {
  assert(n >= 0 && n <= MPM_STRESS_CHUNK);
  mpm_real scale[MPM_STRESS_CHUNK];
  for (int i = 0; i < n; ++i) scale[i] = plastic ? mpm_snow_hardening(m, plastic[i]) : 1;
  for (int i = 0; i < n; ++i) {
    mpm_real Fi[9], U[9], s[3], V[9];
    for (int c = 0; c < 9; ++c) Fi[c] = F[c][i];
    mpm_svd3(Fi, U, s, V);
    const mpm_real two_mu = 2 * m->mu * scale[i], l = m->lambda * scale[i];
    const mpm_real J = mpm_m3_det(Fi);
    const mpm_real d[3] = {two_mu * s[0] * (s[0] - 1), two_mu * s[1] * (s[1] - 1),
                           two_mu * s[2] * (s[2] - 1)};
    const mpm_real vol = l * (J - 1) * J;
    mpm_real T[9];
    mpm_m3_usvt(U, d, U, T);
    T[0] += vol;
    T[4] += vol;
    T[8] += vol;
    for (int c = 0; c < 9; ++c) tau[c][i] = T[c];
  }
}

static void snow_return_map(const mpm_material *m, int n, mpm_real *const F[9], mpm_real *plastic) {
  const mpm_real lo = 1 - m->theta_c, hi = 1 + m->theta_s;
  for (int i = 0; i < n; ++i) {
    mpm_real Fi[9], U[9], s[3], V[9], c[3];
    for (int k = 0; k < 9; ++k) Fi[k] = F[k][i];
    mpm_svd3(Fi, U, s, V);
    int changed = 0;
    for (int k = 0; k < 3; ++k) {
      c[k] = mpm_fmin(mpm_fmax(s[k], lo), hi);
      changed |= c[k] != s[k];
    }
    if (!changed) continue; /* elastic: F and Jp untouched */
    const mpm_real ratio = mpm_fabs(s[0] * s[1] * s[2]) / (c[0] * c[1] * c[2]);
    plastic[i] = mpm_fmin(mpm_fmax(plastic[i] * ratio, SNOW_JP_MIN), SNOW_JP_MAX);
    mpm_real Fn[9];
    mpm_m3_usvt(U, c, V, Fn);
    for (int k = 0; k < 9; ++k) F[k][i] = Fn[k];
  }
}

const mpm_model mpm_model_snow = {
    .name = "snow",
    .energy = snow_energy,
    .pk1 = snow_pk1,
    .dpdf_action = snow_dpdf_action,
    .dpdf_action_definite = snow_dpdf_action_definite,
    .kirchhoff_batch = snow_kirchhoff_batch,
    .return_map = snow_return_map,
    .plastic_initial = 1,
};
