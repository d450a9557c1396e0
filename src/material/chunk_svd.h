/* chunk_svd.h - private to src/material/: the SVDs of one chunk of particles, for the batch
 * entries (kirchhoff_batch, return_map) of the SVD-based models. One mpm_svd3_batch call
 * (core/svd3_lanes.h, SIMD across particles) fills [component][particle] arrays, which the
 * model's own loops over particles then read with unit stride, so they vectorize too. */
#ifndef MPM_MATERIAL_CHUNK_SVD_H
#define MPM_MATERIAL_CHUNK_SVD_H

#include "core/svd3.h"
#include "material/material.h"

#include <assert.h>

typedef struct mpm_chunk_svd {
  _Alignas(MPM_ALIGN) mpm_real U[9][MPM_STRESS_CHUNK];
  _Alignas(MPM_ALIGN) mpm_real V[9][MPM_STRESS_CHUNK];
  _Alignas(MPM_ALIGN) mpm_real s[3][MPM_STRESS_CHUNK]; /* signed, as mpm_svd3 */
} mpm_chunk_svd;

/* F = U diag(s) V^T for the n <= MPM_STRESS_CHUNK particles whose components start at F[c]. */
static inline void mpm_chunk_svd_compute(int n, const mpm_real *const F[9], mpm_chunk_svd *d) {
  assert(n >= 0 && n <= MPM_STRESS_CHUNK);
  mpm_real *U[9], *V[9], *s[3];
  for (int c = 0; c < 9; ++c) {
    U[c] = d->U[c];
    V[c] = d->V[c];
  }
  for (int c = 0; c < 3; ++c) s[c] = d->s[c];
  mpm_svd3_batch(n, F, U, s, V);
}

/* Row-major U and V of particle i. */
static inline void mpm_chunk_svd_get(const mpm_chunk_svd *d, int i, mpm_real U[9], mpm_real V[9]) {
  for (int c = 0; c < 9; ++c) {
    U[c] = d->U[c][i];
    V[c] = d->V[c][i];
  }
}

/* F[.][i] = U_i diag(sn) V_i^T: a plastic projection writing back particle i's new elastic F. */
static inline void mpm_chunk_svd_write_F(const mpm_chunk_svd *d, int i, const mpm_real sn[3],
                                         mpm_real *const F[9]) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      F[3 * r + c][i] = d->U[3 * r][i] * sn[0] * d->V[3 * c][i] +
                        d->U[3 * r + 1][i] * sn[1] * d->V[3 * c + 1][i] +
                        d->U[3 * r + 2][i] * sn[2] * d->V[3 * c + 2][i];
}

/* tau[.][i] = U_i diag(dg[0][i], dg[1][i], dg[2][i]) U_i^T + iso[i] I for the chunk's n
 * particles: the Kirchhoff stress of an isotropic model from its principal values. Each of the
 * six distinct entries is written out, so the loop over particles vectorizes. */
static inline void mpm_chunk_svd_tau(int n, const mpm_chunk_svd *d,
                                     const mpm_real dg[3][MPM_STRESS_CHUNK],
                                     const mpm_real iso[MPM_STRESS_CHUNK],
                                     mpm_real tau[9][MPM_STRESS_CHUNK]) {
  const mpm_real(*U)[MPM_STRESS_CHUNK] = d->U;
#define MPM_UDU(r, q)                                                                              \
  (U[3 * r][i] * dg[0][i] * U[3 * q][i] + U[3 * r + 1][i] * dg[1][i] * U[3 * q + 1][i] +           \
   U[3 * r + 2][i] * dg[2][i] * U[3 * q + 2][i])
  for (int i = 0; i < n; ++i) {
    const mpm_real t00 = MPM_UDU(0, 0) + iso[i], t11 = MPM_UDU(1, 1) + iso[i];
    const mpm_real t22 = MPM_UDU(2, 2) + iso[i];
    const mpm_real t01 = MPM_UDU(0, 1), t02 = MPM_UDU(0, 2), t12 = MPM_UDU(1, 2);
    tau[0][i] = t00;
    tau[4][i] = t11;
    tau[8][i] = t22;
    tau[1][i] = tau[3][i] = t01;
    tau[2][i] = tau[6][i] = t02;
    tau[5][i] = tau[7][i] = t12;
  }
#undef MPM_UDU
}

/* P[.][i] = U_i diag(dg[0][i], dg[1][i], dg[2][i]) V_i^T for the chunk's n particles: the first
 * Piola-Kirchhoff stress of an isotropic model from its principal values (pk1_batch). */
static inline void mpm_chunk_svd_pk1(int n, const mpm_chunk_svd *d,
                                     const mpm_real dg[3][MPM_STRESS_CHUNK],
                                     mpm_real P[9][MPM_STRESS_CHUNK]) {
  const mpm_real(*U)[MPM_STRESS_CHUNK] = d->U, (*V)[MPM_STRESS_CHUNK] = d->V;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      for (int i = 0; i < n; ++i)
        P[3 * r + c][i] = U[3 * r][i] * dg[0][i] * V[3 * c][i] +
                          U[3 * r + 1][i] * dg[1][i] * V[3 * c + 1][i] +
                          U[3 * r + 2][i] * dg[2][i] * V[3 * c + 2][i];
}

#endif
