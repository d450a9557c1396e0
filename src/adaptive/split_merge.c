/* split_merge.c - particle split and merge (Gao et al. sec. 7.2; see split_merge.h). */
#include "adaptive/split_merge.h"

#include "core/quat.h"
#include "core/svd3.h"

#include <math.h>
#include <string.h>

mpm_status mpm_split_particle(mpm_particles *p, size_t i, const mpm_split_desc *s,
                              uint32_t *next_id) {
  if (p->count + 7 > p->capacity &&
      mpm_particles_reserve(p, p->count + 7 > 2 * p->capacity ? p->count + 7 : 2 * p->capacity))
    return MPM_ERR_NOMEM;
  double x0[3], v0[3], C[9] = {0}, B[9] = {0};
  for (int d = 0; d < 3; ++d) x0[d] = p->x[d][i], v0[d] = p->v[d][i];
  if (s->apic) /* the parent's velocity gradient, and the children's moment with it */
    for (int c = 0; c < 9; ++c) {
      C[c] = (double)p->B[c][i] / s->D_parent;
      B[c] = C[c] * s->D_child;
    }
  p->mass[i] /= 8;
  p->vol0[i] /= 8;
  p->level[i] += 1;
  const double a = s->half_diagonal / sqrt(3); /* the cube's half side */
  for (int k = 0; k < 8; ++k) {
    const size_t j = k == 0 ? i : p->count++;
    if (k) {
      mpm_particles_copy(p, j, p, i);
      p->id[j] = (*next_id)++;
    }
    const double c[3] = {k & 1 ? a : -a, k & 2 ? a : -a, k & 4 ? a : -a};
    double r[3];
    for (int d = 0; d < 3; ++d) {
      const double *R = s->rotation + 3 * d;
      r[d] = R[0] * c[0] + R[1] * c[1] + R[2] * c[2];
    }
    for (int d = 0; d < 3; ++d) {
      p->x[d][j] = (mpm_real)(x0[d] + r[d]);
      p->xc[d][j] = 0;
      if (s->apic)
        p->v[d][j] =
            (mpm_real)(v0[d] + C[3 * d] * r[0] + C[3 * d + 1] * r[1] + C[3 * d + 2] * r[2]);
    }
    if (s->apic)
      for (int e = 0; e < 9; ++e) p->B[e][j] = (mpm_real)B[e];
  }
  return MPM_OK;
}

/* F = U diag(sigma) V^T in double, from the engine's SVD (in mpm_real). */
static void svd_double(const double F[9], double U[9], double sigma[3], double V[9]) {
  mpm_real f[9], u[9], s[3], v[9];
  for (int c = 0; c < 9; ++c) f[c] = (mpm_real)F[c];
  mpm_svd3(f, u, s, v);
  for (int c = 0; c < 9; ++c) U[c] = u[c], V[c] = v[c];
  for (int c = 0; c < 3; ++c) sigma[c] = s[c];
}

void mpm_merge_F(int n, const double (*F)[9], const double *w, double out[9]) {
  double qu[64][4], qv[64][4], wsum = 0, sigma[3] = {0}, U0[9], V0[9];
  double wk[64];
  if (n > 64) n = 64;
  for (int k = 0; k < n; ++k) {
    double U[9], s[3], V[9];
    svd_double(F[k], U, s, V);
    if (k == 0) memcpy(U0, U, sizeof U0), memcpy(V0, V, sizeof V0);
    /* the column signs (a pair at a time, keeping det U = det V = 1) closest to the first
     * SVD's: the SVD is unique only up to them, and the averages need one choice */
    static const int flips[4][3] = {{1, 1, 1}, {-1, -1, 1}, {-1, 1, -1}, {1, -1, -1}};
    int best = 0;
    double best_dot = -1e300;
    for (int f = 0; f < 4; ++f) {
      double dot = 0;
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c)
          dot += flips[f][c] * (U[3 * r + c] * U0[3 * r + c] + V[3 * r + c] * V0[3 * r + c]);
      if (dot > best_dot) best_dot = dot, best = f;
    }
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) U[3 * r + c] *= flips[best][c], V[3 * r + c] *= flips[best][c];
    mpm_quat_from_matrix(U, qu[k]);
    mpm_quat_from_matrix(V, qv[k]);
    wk[k] = w ? w[k] : 1;
    wsum += wk[k];
    for (int c = 0; c < 3; ++c) sigma[c] += wk[k] * s[c];
  }
  double q[4], U[9], V[9];
  mpm_quat_average(n, (const double(*)[4])qu, wk, q);
  mpm_quat_to_matrix(q, U);
  mpm_quat_average(n, (const double(*)[4])qv, wk, q);
  mpm_quat_to_matrix(q, V);
  for (int c = 0; c < 3; ++c) sigma[c] /= wsum;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) {
      double a = 0;
      for (int k = 0; k < 3; ++k) a += U[3 * r + k] * sigma[k] * V[3 * c + k];
      out[3 * r + c] = a;
    }
}

void mpm_merge_particles(mpm_particles *p, const uint32_t *idx, int n, int apic) {
  double M = 0, V = 0, xc[3] = {0}, mv[3] = {0}, plastic = 0, heat = 0, F[64][9], w[64], B[9] = {0};
  if (n > 64) n = 64;
  for (int k = 0; k < n; ++k) {
    const size_t j = idx[k];
    const double m = p->mass[j];
    M += m;
    V += p->vol0[j];
    plastic += m * p->plastic[j];
    heat += m * p->temperature[j]; /* one material: heat capacity in proportion to mass */
    w[k] = m;
    for (int d = 0; d < 3; ++d) xc[d] += p->x[d][j], mv[d] += m * p->v[d][j];
    for (int c = 0; c < 9; ++c) F[k][c] = p->F[c][j];
  }
  for (int d = 0; d < 3; ++d) xc[d] /= n; /* the geometric centre (Gao sec. 7.2) */
  if (apic) /* the moment about the new centre: sum m (B + v (x - xc)^T) */
    for (int k = 0; k < n; ++k) {
      const size_t j = idx[k];
      const double m = p->mass[j];
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c)
          B[3 * r + c] += m * (p->B[3 * r + c][j] + p->v[r][j] * ((double)p->x[c][j] - xc[c]));
    }
  double Fm[9];
  mpm_merge_F(n, (const double(*)[9])F, w, Fm);
  const size_t i = idx[0];
  for (int d = 0; d < 3; ++d) {
    p->x[d][i] = (mpm_real)xc[d];
    p->xc[d][i] = 0;
    p->v[d][i] = (mpm_real)(mv[d] / M);
  }
  for (int c = 0; c < 9; ++c) {
    p->F[c][i] = (mpm_real)Fm[c];
    if (apic) p->B[c][i] = (mpm_real)(B[c] / M);
  }
  p->mass[i] = (mpm_real)M;
  p->vol0[i] = (mpm_real)V;
  p->plastic[i] = (mpm_real)(plastic / M);
  p->temperature[i] = (mpm_real)(heat / M);
  p->level[i] -= 1;
  for (int k = 1; k < n; ++k) p->mass[idx[k]] = 0;
}

void mpm_particles_angular_momentum(const mpm_particles *p, const uint32_t *idx, size_t n,
                                    double L[3]) {
  L[0] = L[1] = L[2] = 0;
  for (size_t k = 0; k < n; ++k) {
    const size_t i = idx ? idx[k] : k;
    const double m = p->mass[i], x[3] = {p->x[0][i], p->x[1][i], p->x[2][i]},
                 v[3] = {p->v[0][i], p->v[1][i], p->v[2][i]};
    L[0] += m * (x[1] * v[2] - x[2] * v[1] + (double)p->B[7][i] - (double)p->B[5][i]);
    L[1] += m * (x[2] * v[0] - x[0] * v[2] + (double)p->B[2][i] - (double)p->B[6][i]);
    L[2] += m * (x[0] * v[1] - x[1] * v[0] + (double)p->B[3][i] - (double)p->B[1][i]);
  }
}
