/* hencky_stvk.c - St. Venant-Kirchhoff elasticity in Hencky strain (Gao et al. 2017 eq. 7),
 * the elastic model of Drucker-Prager sand (Klar et al. 2016) and von Mises plasticity
 * (Gao sec. 4.2.2). The formulas, the treatment of inverted F and the stable forms of the
 * stress derivative are written out in hencky.h; the diagonal-space derivative and its
 * definiteness fix (Teran et al. 2005) in isotropic.h. */
#include "material/hencky.h"
#include "material/chunk_svd.h"

#include "core/mat3.h"
#include "core/svd3.h"
#include "core/vecmath.h"

#include <assert.h>

typedef struct hencky_diag {
  mpm_real U[9], V[9];
  mpm_real sgn[3]; /* sign(sigma_i), +1 at 0 */
  mpm_real a[3];   /* |sigma_i| */
  mpm_real c[3];   /* max(|sigma_i|, floor) */
  mpm_real e[3];   /* log c_i */
  mpm_real tr;     /* sum e_i */
  mpm_real h[3];   /* dpsi/dc_i */
} hencky_diag;

static void hencky_diagonalize(const mpm_material *m, const mpm_real F[9], hencky_diag *d) {
  mpm_real s[3];
  mpm_svd3(F, d->U, s, d->V);
  for (int i = 0; i < 3; ++i) {
    d->sgn[i] = s[i] < 0 ? R_(-1.0) : R_(1.0);
    d->a[i] = mpm_fabs(s[i]);
    d->c[i] = mpm_fmax(d->a[i], MPM_HENCKY_FLOOR);
    d->e[i] = mpm_log(d->c[i]);
  }
  d->tr = d->e[0] + d->e[1] + d->e[2];
  for (int i = 0; i < 3; ++i) d->h[i] = (2 * m->mu * d->e[i] + m->lambda * d->tr) / d->c[i];
}

mpm_real mpm_hencky_energy(const mpm_material *m, const mpm_real F[9]) {
  hencky_diag d;
  hencky_diagonalize(m, F, &d);
  mpm_real psi = m->mu * (d.e[0] * d.e[0] + d.e[1] * d.e[1] + d.e[2] * d.e[2]) +
                 R_(0.5) * m->lambda * d.tr * d.tr;
  for (int i = 0; i < 3; ++i) psi += d.h[i] * (d.a[i] - d.c[i]); /* 0 unless clamped */
  return psi;
}

void mpm_hencky_pk1(const mpm_material *m, const mpm_real F[9], mpm_real P[9]) {
  hencky_diag d;
  hencky_diagonalize(m, F, &d);
  const mpm_real g[3] = {d.sgn[0] * d.h[0], d.sgn[1] * d.h[1], d.sgn[2] * d.h[2]};
  mpm_m3_usvt(d.U, g, d.V, P);
}

static void hencky_hessian(const mpm_material *m, const mpm_real F[9], mpm_iso_hessian *H) {
  hencky_diag d;
  hencky_diagonalize(m, F, &d);
  mpm_m3_copy(d.U, H->U);
  mpm_m3_copy(d.V, H->V);
  const mpm_real mu2 = 2 * m->mu, l = m->lambda;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const mpm_real hij =
          i == j ? (mu2 + l - mu2 * d.e[i] - l * d.tr) / (d.c[i] * d.c[i]) : l / (d.c[i] * d.c[j]);
      H->A[3 * i + j] = d.sgn[i] * d.sgn[j] * hij;
    }
  for (int k = 0; k < 3; ++k) {
    const int i = MPM_ISO_PAIR[k][0], j = MPM_ISO_PAIR[k][1];
    const mpm_real cc = d.c[i] * d.c[j];
    const mpm_real dminus =
        (mu2 * (d.c[j] * mpm_log_divdiff(d.c[i], d.c[j]) - d.e[j]) - l * d.tr) / cc;
    const mpm_real dplus = (d.h[i] + d.h[j]) / (d.c[i] + d.c[j]);
    const int same = d.sgn[i] == d.sgn[j];
    H->lsym[k] = same ? dminus : dplus;
    H->lskew[k] = same ? dplus : dminus;
  }
}

void mpm_hencky_dpdf_action(const mpm_material *m, const mpm_real F[9], const mpm_real dF[9],
                            mpm_real dP[9]) {
  mpm_iso_hessian H;
  hencky_hessian(m, F, &H);
  mpm_iso_action(&H, dF, dP);
}

void mpm_hencky_hessian_definite(const mpm_material *m, const mpm_real F[9],
                                 mpm_stress_hessian *H) {
  hencky_hessian(m, F, H);
  mpm_iso_make_definite(H);
}

void mpm_hencky_dpdf_action_definite(const mpm_material *m, const mpm_real F[9],
                                     const mpm_real dF[9], mpm_real dP[9]) {
  mpm_iso_hessian H;
  mpm_hencky_hessian_definite(m, F, &H);
  mpm_iso_action(&H, dF, dP);
}

/* Three passes: the SVDs, one vectorized logarithm over the 3n clamped |sigma|, then
 * tau = U diag(d) U^T with d_i = (2 mu eps_i + lambda tr eps) |sigma_i| / c_i as a straight
 * loop over the chunk. */
void mpm_hencky_kirchhoff_batch(const mpm_material *m, int n, const mpm_real *const F[9],
                                const mpm_real *plastic, mpm_real tau[9][MPM_STRESS_CHUNK]) {
  (void)plastic; /* the elasticity does not depend on the plastic state */
  assert(n >= 0 && n <= MPM_STRESS_CHUNK);
  mpm_chunk_svd d;
  mpm_chunk_svd_compute(n, F, &d);
  mpm_real a[3][MPM_STRESS_CHUNK], c[3 * MPM_STRESS_CHUNK], e[3 * MPM_STRESS_CHUNK];
  for (int k = 0; k < 3; ++k)
    for (int i = 0; i < n; ++i) {
      a[k][i] = mpm_fabs(d.s[k][i]);
      c[k * MPM_STRESS_CHUNK + i] = mpm_fmax(a[k][i], MPM_HENCKY_FLOOR);
    }
  for (int k = 0; k < 3; ++k) mpm_log_array(n, c + k * MPM_STRESS_CHUNK, e + k * MPM_STRESS_CHUNK);
  const mpm_real mu2 = 2 * m->mu, l = m->lambda;
  const mpm_real *e0 = e, *e1 = e + MPM_STRESS_CHUNK, *e2 = e + 2 * MPM_STRESS_CHUNK;
  const mpm_real *c0 = c, *c1 = c + MPM_STRESS_CHUNK, *c2 = c + 2 * MPM_STRESS_CHUNK;
  mpm_real dg[3][MPM_STRESS_CHUNK], iso[MPM_STRESS_CHUNK];
  for (int i = 0; i < n; ++i) {
    const mpm_real lt = l * (e0[i] + e1[i] + e2[i]);
    dg[0][i] = (mu2 * e0[i] + lt) * (a[0][i] / c0[i]);
    dg[1][i] = (mu2 * e1[i] + lt) * (a[1][i] / c1[i]);
    dg[2][i] = (mu2 * e2[i] + lt) * (a[2][i] / c2[i]);
    iso[i] = 0;
  }
  mpm_chunk_svd_tau(n, &d, (const mpm_real(*)[MPM_STRESS_CHUNK])dg, iso, tau);
}

/* P = U diag(sgn_i h_i) V^T, h_i = (2 mu e_i + lambda tr e) / c_i (mpm_hencky_pk1), from the
 * chunk's SVDs and one vectorized logarithm. */
void mpm_hencky_pk1_batch(const mpm_material *m, int n, const mpm_real *const F[9],
                          mpm_real P[9][MPM_STRESS_CHUNK]) {
  assert(n >= 0 && n <= MPM_STRESS_CHUNK);
  mpm_chunk_svd d;
  mpm_chunk_svd_compute(n, F, &d);
  mpm_real c[3 * MPM_STRESS_CHUNK], e[3 * MPM_STRESS_CHUNK];
  for (int k = 0; k < 3; ++k)
    for (int i = 0; i < n; ++i)
      c[k * MPM_STRESS_CHUNK + i] = mpm_fmax(mpm_fabs(d.s[k][i]), MPM_HENCKY_FLOOR);
  for (int k = 0; k < 3; ++k) mpm_log_array(n, c + k * MPM_STRESS_CHUNK, e + k * MPM_STRESS_CHUNK);
  const mpm_real mu2 = 2 * m->mu, l = m->lambda;
  mpm_real dg[3][MPM_STRESS_CHUNK];
  for (int i = 0; i < n; ++i) {
    const mpm_real lt = l * (e[i] + e[MPM_STRESS_CHUNK + i] + e[2 * MPM_STRESS_CHUNK + i]);
    for (int k = 0; k < 3; ++k) {
      const mpm_real h = (mu2 * e[k * MPM_STRESS_CHUNK + i] + lt) / c[k * MPM_STRESS_CHUNK + i];
      dg[k][i] = d.s[k][i] < 0 ? -h : h;
    }
  }
  mpm_chunk_svd_pk1(n, &d, (const mpm_real(*)[MPM_STRESS_CHUNK])dg, P);
}

const mpm_model mpm_model_hencky_stvk = {
    .name = "hencky_stvk",
    .energy = mpm_hencky_energy,
    .pk1 = mpm_hencky_pk1,
    .dpdf_action = mpm_hencky_dpdf_action,
    .dpdf_action_definite = mpm_hencky_dpdf_action_definite,
    .hessian_definite = mpm_hencky_hessian_definite,
    .kirchhoff_batch = mpm_hencky_kirchhoff_batch,
    .pk1_batch = mpm_hencky_pk1_batch,
    .return_map = NULL,
    .plastic_initial = 1,
};
