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

#include "material/chunk_svd.h"

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

static void snow_hessian_definite(const mpm_material *m, const mpm_real F[9],
                                  mpm_stress_hessian *H) {
  mpm_model_fixed_corotated.hessian_definite(m, F, H);
}

/* The fixed-corotated tau (fixed_corotated.c) with per-particle moduli. */
static void snow_kirchhoff_batch(const mpm_material *m, int n, const mpm_real *const F[9],
                                 const mpm_real *plastic, mpm_real tau[9][MPM_STRESS_CHUNK]) {
  assert(n >= 0 && n <= MPM_STRESS_CHUNK);
  if (!plastic) {
    mpm_fcr_kirchhoff_scaled(m, n, F, NULL, tau);
    return;
  }
  mpm_real scale[MPM_STRESS_CHUNK];
  for (int i = 0; i < n; ++i) scale[i] = mpm_snow_hardening(m, plastic[i]);
  mpm_fcr_kirchhoff_scaled(m, n, F, scale, tau);
}

/* Clamp the singular values to [1 - theta_c, 1 + theta_s] (Stomakhin et al. 2013 sec. 7);
 * particles already inside keep F and Jp bitwise. */
static void snow_return_map(const mpm_material *m, int n, mpm_real *const F[9], mpm_real *plastic) {
  const mpm_real lo = 1 - m->theta_c, hi = 1 + m->theta_s;
  mpm_chunk_svd d;
  mpm_chunk_svd_compute(n, (const mpm_real *const *)F, &d);
  for (int i = 0; i < n; ++i) {
    const mpm_real s[3] = {d.s[0][i], d.s[1][i], d.s[2][i]};
    mpm_real c[3];
    int changed = 0;
    for (int k = 0; k < 3; ++k) {
      c[k] = mpm_fmin(mpm_fmax(s[k], lo), hi);
      changed |= c[k] != s[k];
    }
    if (!changed) continue; /* elastic: F and Jp untouched */
    const mpm_real ratio = mpm_fabs(s[0] * s[1] * s[2]) / (c[0] * c[1] * c[2]);
    plastic[i] = mpm_fmin(mpm_fmax(plastic[i] * ratio, SNOW_JP_MIN), SNOW_JP_MAX);
    mpm_chunk_svd_write_F(&d, i, c, F);
  }
}
const mpm_model mpm_model_snow = {
    .name = "snow",
    .energy = snow_energy,
    .pk1 = snow_pk1,
    .dpdf_action = snow_dpdf_action,
    .dpdf_action_definite = snow_dpdf_action_definite,
    .hessian_definite = snow_hessian_definite,
    .kirchhoff_batch = snow_kirchhoff_batch,
    .return_map = snow_return_map,
    .plastic_initial = 1,
};
