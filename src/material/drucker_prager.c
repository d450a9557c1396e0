/* drucker_prager.c - Drucker-Prager plasticity for sand with Hencky-StVK elasticity.
 *
 * Klar, Gast, Pradhana, Fu, Schroeder, Jiang, Teran 2016, "Drucker-Prager elastoplasticity for
 * sand animation", sec. 7.3: the return map is a closed-form projection in principal Hencky
 * strain eps = log(sigma) (sigma = singular values of the trial F^E; |sigma| floored as in
 * hencky.h), with the volume correction of Tampubolon, Gast, Klar, Fu, Teran, Jiang, Museth
 * 2017 ("Multi-species simulation of porous sand and water mixtures", sec. 4.3.1) against the
 * spurious volume gain of the tip projection (Gao et al. 2017 sec. 4.2.1).
 *
 * Yield condition (Kirchhoff stress tau = 2 mu eps + lambda tr(eps) I in principal space):
 *   ||dev tau|| + alpha tr(tau) - k <= 0,
 *   alpha = sqrt(2/3) 2 sin(phi) / (3 - sin(phi))  (Klar eq. 27: the cone through the
 *           compressive meridian of Mohr-Coulomb with friction angle phi),
 *   k     = sqrt(2/3) 6 c cos(phi) / (3 - sin(phi)) (the same Mohr-Coulomb match applied to the
 *           cohesion c, Pa; k = 0 for dry sand).
 * The cone's apex lies at tr(tau) = k / alpha = 3 c cot(phi), the Mohr-Coulomb apex, i.e. at
 * tr(eps) = T_tip = 3 c cot(phi) / (3 lambda + 2 mu) (0 for c = 0; +inf for phi = 0, c > 0).
 * Divided by 2 mu, in strain: dgamma = ||dev eps|| + alpha (3 lambda + 2 mu)/(2 mu) tr(eps)
 * - k/(2 mu) (Klar eq. 28 with d = 3, shifted by the cohesion).
 *
 * Plastic state v = accumulated log volume correction (Tampubolon 2017), v >= 0, initial 0:
 * the log volume that tip projections moved into F^P while the grains separated. With
 * T = tr(eps_trial) and T_eff = T + v:
 *  1. T_eff >= T_tip (expansion, or compression that has not yet used up the stored
 *     separation): project to the tip, eps = T_tip/3 (1,1,1), v <- T_eff - T_tip. The
 *     material is stress-free (dry sand) until it is compressed back to where it separated.
 *  2. otherwise the stored separation is spent first: eps' = eps + v/3 (1,1,1), v <- 0; then
 *     dgamma(eps') <= 0: elastic (F untouched when v was 0, bitwise);
 *     else shrink the deviator: eps = eps' - dgamma dev(eps') / ||dev(eps')||, which lands
 *     on the cone (tr unchanged, the non-associative flow of Klar sec. 7.3).
 * T_eff is conserved by every case: tr(eps_new) + v_new = tr(eps_trial) + v_old.
 * A projected F is written U diag(exp(eps)) V^T, so a projected inverted particle leaves with
 * det F^E > 0. */
#include "material/hencky.h"

#include "core/vecmath.h"
#include "material/chunk_svd.h"

#include <math.h>

typedef struct dp_params {
  mpm_real cone;  /* alpha (3 lambda + 2 mu) / (2 mu) */
  mpm_real shift; /* k / (2 mu) */
  mpm_real tip;   /* T_tip */
} dp_params;

static dp_params dp_params_of(const mpm_material *m) {
  const double phi = m->friction_angle, sp = sin(phi), cp = cos(phi);
  const double mu = m->mu, l = m->lambda, c = m->cohesion;
  const double alpha = sqrt(2.0 / 3.0) * 2 * sp / (3 - sp);
  const double k = sqrt(2.0 / 3.0) * 6 * c * cp / (3 - sp);
  dp_params p;
  p.cone = (mpm_real)(alpha * (3 * l + 2 * mu) / (2 * mu));
  p.shift = (mpm_real)(k / (2 * mu));
  if (k <= 0)
    p.tip = 0;
  else if (alpha > 0)
    p.tip = (mpm_real)(k / (alpha * (3 * l + 2 * mu)));
  else
    p.tip = (mpm_real)INFINITY;
  return p;
}

/* Over a chunk: the SVDs in one SIMD batch, the Hencky strains by one array logarithm, the
 * projection below per particle (cheap scalar logic with the case split), then one array
 * exponential for the particles whose F changes. Particles that stay inside the cone with no
 * stored separation keep F bitwise. */
static void dp_return_map(const mpm_material *m, int n, mpm_real *const F[9], mpm_real *plastic) {
  const dp_params p = dp_params_of(m);
  mpm_chunk_svd d;
  mpm_chunk_svd_compute(n, (const mpm_real *const *)F, &d);
  mpm_real e[3][MPM_STRESS_CHUNK], en[3][MPM_STRESS_CHUNK], sn[3][MPM_STRESS_CHUNK];
  int write[MPM_STRESS_CHUNK];
  for (int k = 0; k < 3; ++k) {
    mpm_real c[MPM_STRESS_CHUNK]; /* |sigma| clamped to the floor */
    for (int i = 0; i < n; ++i) c[i] = mpm_fmax(mpm_fabs(d.s[k][i]), MPM_HENCKY_FLOOR);
    mpm_log_array(n, c, e[k]);
  }
  for (int i = 0; i < n; ++i) {
    mpm_real ei[3] = {e[0][i], e[1][i], e[2][i]};
    const mpm_real v = plastic[i];
    const mpm_real teff = ei[0] + ei[1] + ei[2] + v;
    write[i] = 1;
    if (teff >= p.tip) { /* case 1: the tip */
      for (int k = 0; k < 3; ++k) en[k][i] = p.tip / 3;
      plastic[i] = teff - p.tip;
      continue;
    }
    if (v != 0) { /* spend the stored separation */
      for (int k = 0; k < 3; ++k) ei[k] += v / 3;
      plastic[i] = 0;
    }
    const mpm_real mean = teff / 3;
    const mpm_real dev[3] = {ei[0] - mean, ei[1] - mean, ei[2] - mean};
    const mpm_real nd = mpm_sqrt(dev[0] * dev[0] + dev[1] * dev[1] + dev[2] * dev[2]);
    const mpm_real dgamma = nd + p.cone * teff - p.shift;
    if (dgamma <= 0 || !(nd > 0)) { /* inside the cone */
      write[i] = v != 0;
      for (int k = 0; k < 3; ++k) en[k][i] = ei[k];
      continue;
    }
    const mpm_real f = dgamma / nd;
    for (int k = 0; k < 3; ++k) en[k][i] = ei[k] - f * dev[k];
  }
  for (int k = 0; k < 3; ++k) mpm_exp_array(n, en[k], sn[k]);
  for (int i = 0; i < n; ++i)
    if (write[i]) {
      const mpm_real si[3] = {sn[0][i], sn[1][i], sn[2][i]};
      mpm_chunk_svd_write_F(&d, i, si, F);
    }
}

const mpm_model mpm_model_drucker_prager = {
    .name = "drucker_prager",
    .energy = mpm_hencky_energy,
    .pk1 = mpm_hencky_pk1,
    .dpdf_action = mpm_hencky_dpdf_action,
    .dpdf_action_definite = mpm_hencky_dpdf_action_definite,
    .hessian_definite = mpm_hencky_hessian_definite,
    .kirchhoff_batch = mpm_hencky_kirchhoff_batch,
    .pk1_batch = mpm_hencky_pk1_batch,
    .return_map = dp_return_map,
    .plastic_initial = 0,
};
