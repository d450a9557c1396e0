/* von_mises.c - von Mises (J2) plasticity with Hencky-StVK elasticity, Gao et al. 2017
 * sec. 4.2.2: the closed-form return map in principal Hencky strain (after Klar et al. 2016).
 *
 * eps = log(|sigma|) of the trial F^E (floored as in hencky.h). The Kirchhoff deviator is
 * dev tau = 2 mu dev(eps), and the admissible set is ||dev eps|| <= sigma_y / (2 mu), i.e.
 * ||dev tau|| <= sigma_y, exactly as Gao writes the projection (in terms of the von Mises
 * equivalent sqrt(3/2) ||dev tau|| the radius is sqrt(3/2) sigma_y). Outside it,
 *   H = eps - dgamma dev(eps) / ||dev(eps)||,  dgamma = ||dev(eps)|| - sigma_y / (2 mu),
 * the radial (associative) return: tr(eps), hence det F^E, is unchanged. The projected F^E is
 * U diag(exp(H)) V^T (det > 0). Perfect plasticity: no hardening, the plastic state is unused
 * and left untouched (plastic_initial = 1). Inside the cylinder F is not written. */
#include "material/hencky.h"

#include "core/vecmath.h"
#include "material/chunk_svd.h"

/* In passes over the chunk as in drucker_prager.c: SVDs, array logarithm, the radial return
 * per particle, array exponential, write-back of the particles that yielded. */
static void vm_return_map(const mpm_material *m, int n, mpm_real *const F[9], mpm_real *plastic) {
  (void)plastic;
  const mpm_real radius = m->yield_stress / (2 * m->mu);
  mpm_chunk_svd d;
  mpm_chunk_svd_compute(n, (const mpm_real *const *)F, &d);
  mpm_real e[3][MPM_STRESS_CHUNK], sn[3][MPM_STRESS_CHUNK];
  int write[MPM_STRESS_CHUNK];
  for (int k = 0; k < 3; ++k) {
    mpm_real c[MPM_STRESS_CHUNK]; /* |sigma| clamped to the floor */
    for (int i = 0; i < n; ++i) c[i] = mpm_fmax(mpm_fabs(d.s[k][i]), MPM_HENCKY_FLOOR);
    mpm_log_array(n, c, e[k]);
  }
  for (int i = 0; i < n; ++i) {
    const mpm_real mean = (e[0][i] + e[1][i] + e[2][i]) / 3;
    const mpm_real dev[3] = {e[0][i] - mean, e[1][i] - mean, e[2][i] - mean};
    const mpm_real nd = mpm_sqrt(dev[0] * dev[0] + dev[1] * dev[1] + dev[2] * dev[2]);
    write[i] = nd > radius;
    const mpm_real f = write[i] ? (nd - radius) / nd : 0; /* elastic: unchanged */
    for (int k = 0; k < 3; ++k) e[k][i] -= f * dev[k];
  }
  for (int k = 0; k < 3; ++k) mpm_exp_array(n, e[k], sn[k]);
  for (int i = 0; i < n; ++i)
    if (write[i]) {
      const mpm_real si[3] = {sn[0][i], sn[1][i], sn[2][i]};
      mpm_chunk_svd_write_F(&d, i, si, F);
    }
}

const mpm_model mpm_model_von_mises = {
    .name = "von_mises",
    .energy = mpm_hencky_energy,
    .pk1 = mpm_hencky_pk1,
    .dpdf_action = mpm_hencky_dpdf_action,
    .dpdf_action_definite = mpm_hencky_dpdf_action_definite,
    .hessian_definite = mpm_hencky_hessian_definite,
    .kirchhoff_batch = mpm_hencky_kirchhoff_batch,
    .pk1_batch = mpm_hencky_pk1_batch,
    .return_map = vm_return_map,
    .plastic_initial = 1,
};
