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

#include "core/mat3.h"
#include "core/svd3.h"

static void vm_return_map(const mpm_material *m, int n, mpm_real *const F[9], mpm_real *plastic) {
  (void)plastic;
  const mpm_real radius = m->yield_stress / (2 * m->mu);
  for (int i = 0; i < n; ++i) {
    mpm_real Fi[9], U[9], s[3], V[9], e[3];
    for (int c = 0; c < 9; ++c) Fi[c] = F[c][i];
    mpm_svd3(Fi, U, s, V);
    for (int k = 0; k < 3; ++k) e[k] = mpm_log(mpm_fmax(mpm_fabs(s[k]), MPM_HENCKY_FLOOR));
    const mpm_real mean = (e[0] + e[1] + e[2]) / 3;
    const mpm_real dev[3] = {e[0] - mean, e[1] - mean, e[2] - mean};
    const mpm_real nd = mpm_sqrt(dev[0] * dev[0] + dev[1] * dev[1] + dev[2] * dev[2]);
    if (!(nd > radius)) continue; /* elastic */
    const mpm_real f = (nd - radius) / nd;
    const mpm_real sn[3] = {mpm_exp(e[0] - f * dev[0]), mpm_exp(e[1] - f * dev[1]),
                            mpm_exp(e[2] - f * dev[2])};
    mpm_real Fn[9];
    mpm_m3_usvt(U, sn, V, Fn);
    for (int c = 0; c < 9; ++c) F[c][i] = Fn[c];
  }
}

const mpm_model mpm_model_von_mises = {
    .name = "von_mises",
    .energy = mpm_hencky_energy,
    .pk1 = mpm_hencky_pk1,
    .dpdf_action = mpm_hencky_dpdf_action,
    .dpdf_action_definite = mpm_hencky_dpdf_action_definite,
    .kirchhoff_batch = mpm_hencky_kirchhoff_batch,
    .return_map = vm_return_map,
    .plastic_initial = 1,
};
