/* stress_window.h - Kirchhoff stresses for the particles a P2G batch walk visits, evaluated
 * ahead in chunks of one material through the model's batch entry (material/material.h), so
 * that its SIMD SVD sees full vectors. Private to src/transfer (p2g.c, operators.c). */
#ifndef MPM_TRANSFER_STRESS_WINDOW_H
#define MPM_TRANSFER_STRESS_WINDOW_H

#include "core/particles.h"
#include "material/material.h"

#include <stdint.h>
#include <string.h>

/* A melting material's stresses, one particle at a time: its moduli depend on the particle's
 * temperature (material.h, mpm_material_at_temperature), so the batch entry's one set of
 * moduli does not apply. tau = P F^T. */
static inline void melting_stress(const mpm_material *mat, const mpm_particles *p,
                                  const uint32_t *idx, int n, mpm_real tau[9][MPM_STRESS_CHUNK]) {
  for (int q = 0; q < n; ++q) {
    const uint32_t i = idx ? idx[q] : (uint32_t)q;
    mpm_real F[9], P[9];
    for (int c = 0; c < 9; ++c) F[c] = p->F[c][i];
    const mpm_material m = mpm_material_at_temperature(mat, p->plastic[i], p->temperature[i]);
    m.model->pk1(&m, F, P);
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c)
        tau[3 * r + c][q] =
            P[3 * r] * F[3 * c] + P[3 * r + 1] * F[3 * c + 1] + P[3 * r + 2] * F[3 * c + 2];
  }
}

/* Kirchhoff stresses of particles idx[0..n) (all of material `mat`) into tau. */
MPM_ALWAYS_INLINE void chunk_stress(const mpm_material *mat, const mpm_particles *p,
                                    const uint32_t *idx, int n, mpm_real tau[9][MPM_STRESS_CHUNK]) {
  if (mat->melting) {
    melting_stress(mat, p, idx, n, tau);
    return;
  }
  mpm_real Fbuf[9][MPM_STRESS_CHUNK], plastic[MPM_STRESS_CHUNK];
  const mpm_real *Fp[9];
  for (int c = 0; c < 9; ++c) {
    const mpm_real *src = p->F[c];
    for (int q = 0; q < n; ++q) Fbuf[c][q] = src[idx[q]];
    Fp[c] = Fbuf[c];
  }
  for (int q = 0; q < n; ++q) plastic[q] = p->plastic[idx[q]];
  mat->model->kirchhoff_batch(mat, n, Fp, plastic, tau);
}

/* Stresses of the particles of one block and material, evaluated ahead in windows of up to
 * STRESS_WINDOW consecutive positions of the particle order (perm): the model's batch entry
 * then sees chunks of MPM_STRESS_CHUNK particles instead of the up to MPM_LANES of one cell,
 * which its SIMD SVD (core/svd3_lanes.h) needs to fill its vectors. */
#define STRESS_WINDOW (4 * MPM_STRESS_CHUNK)
typedef struct stress_window {
  uint32_t begin, count; /* perm positions [begin, begin + count) */
  mpm_real tau[9][STRESS_WINDOW];
} stress_window;

/* Make positions [j, j + n) of perm available in w; `end` is the end of the material's range
 * of positions in this block (a window never reaches past it). A batch that straddles the end
 * of the window starts the next one, so at most MPM_LANES - 1 stresses per window are
 * evaluated twice. */
static inline void stress_window_need(stress_window *w, const mpm_material *mat,
                                      const mpm_particles *p, const uint32_t *perm, uint32_t j,
                                      int n, uint32_t end) {
  if (j >= w->begin && j + (uint32_t)n <= w->begin + w->count) return;
  w->begin = j;
  w->count = end - j < STRESS_WINDOW ? end - j : STRESS_WINDOW;
  for (uint32_t k0 = 0; k0 < w->count; k0 += MPM_STRESS_CHUNK) {
    const int k = (int)(w->count - k0 < MPM_STRESS_CHUNK ? w->count - k0 : MPM_STRESS_CHUNK);
    const uint32_t *idx = perm + j + k0;
    int contiguous = 1; /* positions of several cells: check every one */
    for (int q = 1; q < k; ++q) contiguous &= idx[q] == idx[0] + (uint32_t)q;
    mpm_real tau[9][MPM_STRESS_CHUNK];
    if (contiguous && !mat->melting) { /* the model reads F in place */
      const mpm_real *Fp[9];
      for (int c = 0; c < 9; ++c) Fp[c] = p->F[c] + idx[0];
      mat->model->kirchhoff_batch(mat, k, Fp, p->plastic + idx[0], tau);
    } else {
      chunk_stress(mat, p, idx, k, tau);
    }
    for (int c = 0; c < 9; ++c) memcpy(&w->tau[c][k0], tau[c], (size_t)k * sizeof(mpm_real));
  }
}

#endif
