/* rest_error.c - shape matching and the rest-state error (see rest_error.h). */
#include "analysis/rest_error.h"
#include "core/alloc.h"

#include "core/sym_eigen.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* S = Q diag(l) Q^T with the eigenvalues in decreasing order. */
static void symmetric_eigen(const double S[9], double l[3], double Q[9]) {
  double up[3], V[9];
  mpm_sym_eigen(3, S, up, V);
  for (int k = 0; k < 3; ++k) {
    l[k] = up[2 - k];
    for (int i = 0; i < 3; ++i) Q[3 * i + k] = V[3 * i + 2 - k];
  }
}

static void cross(const double a[3], const double b[3], double c[3]) {
  c[0] = a[1] * b[2] - a[2] * b[1];
  c[1] = a[2] * b[0] - a[0] * b[2];
  c[2] = a[0] * b[1] - a[1] * b[0];
}

static double det3(const double M[9]) {
  return M[0] * (M[4] * M[8] - M[5] * M[7]) - M[1] * (M[3] * M[8] - M[5] * M[6]) +
         M[2] * (M[3] * M[7] - M[4] * M[6]);
}

void mpm_nearest_rotation(const double A[9], double R[9]) {
  /* A = U S V^T from the eigenvectors V of A^T A; U's columns A v_k / s_k, completed to an
   * orthonormal basis where A is rank-deficient */
  double AtA[9];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      AtA[3 * i + j] = A[i] * A[j] + A[3 + i] * A[3 + j] + A[6 + i] * A[6 + j];
  double l[3], V[9];
  symmetric_eigen(AtA, l, V);
  double u[3][3];
  int rank = 0;
  for (int k = 0; k < 3; ++k) {
    const double v[3] = {V[k], V[3 + k], V[6 + k]};
    double w[3];
    for (int i = 0; i < 3; ++i) w[i] = A[3 * i] * v[0] + A[3 * i + 1] * v[1] + A[3 * i + 2] * v[2];
    for (int j = 0; j < rank; ++j) { /* Gram-Schmidt against the columns so far */
      const double d = w[0] * u[j][0] + w[1] * u[j][1] + w[2] * u[j][2];
      for (int i = 0; i < 3; ++i) w[i] -= d * u[j][i];
    }
    const double n = sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
    if (!(n > 1e-12 * sqrt(fmax(l[0], 0)))) break;
    for (int i = 0; i < 3; ++i) u[rank][i] = w[i] / n;
    ++rank;
  }
  if (rank == 0) { /* no information: the identity */
    static const double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    memcpy(R, I, sizeof I);
    return;
  }
  if (rank == 1) { /* any unit vector perpendicular to u0 */
    const double e[3] = {fabs(u[0][0]) < 0.9 ? 1.0 : 0.0, fabs(u[0][0]) < 0.9 ? 0.0 : 1.0, 0};
    cross(u[0], e, u[1]);
    const double n = sqrt(u[1][0] * u[1][0] + u[1][1] * u[1][1] + u[1][2] * u[1][2]);
    for (int i = 0; i < 3; ++i) u[1][i] /= n;
  }
  if (rank <= 2) cross(u[0], u[1], u[2]);
  double U[9];
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) U[3 * i + k] = u[k][i];
  /* the reflection fix: R = U diag(1, 1, det(U V^T)) V^T */
  const double s = det3(U) * det3(V) < 0 ? -1 : 1;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      R[3 * i + j] =
          U[3 * i] * V[3 * j] + U[3 * i + 1] * V[3 * j + 1] + s * U[3 * i + 2] * V[3 * j + 2];
}

/* A cloud's (id, index) pairs in id order. */
typedef struct id_index {
  uint32_t id;
  size_t i;
} id_index;

static int by_id(const void *a, const void *b) {
  const uint32_t x = ((const id_index *)a)->id, y = ((const id_index *)b)->id;
  return x < y ? -1 : x > y;
}

static id_index *id_order(const mpm_point_cloud *c) {
  id_index *o = mpm_alloc((c->n + 1) * sizeof *o);
  if (!o) return NULL;
  for (size_t i = 0; i < c->n; ++i) o[i] = (id_index){c->id[i], i};
  qsort(o, c->n, sizeof *o, by_id);
  return o;
}

mpm_status mpm_rest_error_compute(const mpm_point_cloud *rest, const mpm_point_cloud *final,
                                  mpm_rest_error *out) {
  memset(out, 0, sizeof *out);
  id_index *ro = id_order(rest), *fo = id_order(final);
  size_t(*pair)[2] = mpm_alloc((rest->n + 1) * sizeof *pair);
  if (!ro || !fo || !pair) {
    mpm_free(ro), mpm_free(fo), mpm_free(pair);
    return MPM_ERR_NOMEM;
  }
  /* matched pairs (rest index, final index), by merging the id orders */
  size_t n = 0;
  for (size_t i = 0, j = 0; i < rest->n && j < final->n;) {
    const uint32_t a = ro[i].id, b = fo[j].id;
    if (a == b) {
      pair[n][0] = ro[i++].i;
      pair[n][1] = fo[j++].i;
      ++n;
    } else if (a < b) {
      ++i;
    } else {
      ++j;
    }
  }
  mpm_free(ro);
  mpm_free(fo);
  mpm_status st = MPM_ERR_INVALID;
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  double m = 0, qc[3] = {0, 0, 0}, pc[3] = {0, 0, 0};
  for (size_t k = 0; k < n; ++k) {
    const double *q = rest->x[pair[k][0]], *p = final->x[pair[k][1]];
    const double w = rest->mass ? rest->mass[pair[k][0]] : 1;
    m += w;
    for (int d = 0; d < 3; ++d) {
      qc[d] += w * q[d], pc[d] += w * p[d];
      lo[d] = fmin(lo[d], q[d]), hi[d] = fmax(hi[d], q[d]);
    }
  }
  const double diag =
      n ? sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
               (hi[2] - lo[2]) * (hi[2] - lo[2]))
        : 0;
  if (n > 0 && m > 0 && diag > 0) {
    for (int d = 0; d < 3; ++d) qc[d] /= m, pc[d] /= m;
    double A[9] = {0}; /* A_pq = sum m (p - p_c)(q - q_c)^T */
    for (size_t k = 0; k < n; ++k) {
      const double *q = rest->x[pair[k][0]], *p = final->x[pair[k][1]];
      const double w = rest->mass ? rest->mass[pair[k][0]] : 1;
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) A[3 * r + c] += w * (p[r] - pc[r]) * (q[c] - qc[c]);
    }
    mpm_nearest_rotation(A, out->R);
    double sum = 0, worst = 0;
    for (size_t k = 0; k < n; ++k) {
      const double *q = rest->x[pair[k][0]], *p = final->x[pair[k][1]];
      double e2 = 0;
      for (int r = 0; r < 3; ++r) {
        const double g = out->R[3 * r] * (q[0] - qc[0]) + out->R[3 * r + 1] * (q[1] - qc[1]) +
                         out->R[3 * r + 2] * (q[2] - qc[2]) + pc[r] - p[r];
        e2 += g * g;
      }
      const double e = sqrt(e2);
      sum += e;
      worst = fmax(worst, e);
    }
    out->mean = sum / (double)n / diag;
    out->max = worst / diag;
    out->diagonal = diag;
    out->matched = n;
    for (int r = 0; r < 3; ++r)
      out->translation[r] =
          pc[r] - (out->R[3 * r] * qc[0] + out->R[3 * r + 1] * qc[1] + out->R[3 * r + 2] * qc[2]);
    st = MPM_OK;
  }
  mpm_free(pair);
  return st;
}
