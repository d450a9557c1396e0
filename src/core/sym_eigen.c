/* sym_eigen.c - cyclic Jacobi for small symmetric matrices (see sym_eigen.h). */
#include "core/sym_eigen.h"

#include <math.h>
#include <string.h>

void mpm_sym_eigen(int n, const double *A, double *lambda, double *V) {
  double a[16];
  memcpy(a, A, (size_t)(n * n) * sizeof *a);
  for (int i = 0; i < n * n; ++i) V[i] = i % (n + 1) == 0;
  for (int sweep = 0; sweep < 50; ++sweep) {
    double off = 0, diag = 0;
    for (int i = 0; i < n; ++i) {
      diag += a[(n + 1) * i] * a[(n + 1) * i];
      for (int j = i + 1; j < n; ++j) off += a[n * i + j] * a[n * i + j];
    }
    if (off <= 1e-32 * diag || off == 0) break;
    for (int p = 0; p < n; ++p)
      for (int r = p + 1; r < n; ++r) {
        const double apr = a[n * p + r];
        if (apr == 0) continue;
        /* the rotation that zeroes a[p][r] (Golub and Van Loan, sec. 8.5) */
        const double theta = (a[n * r + r] - a[n * p + p]) / (2 * apr);
        const double t = (theta >= 0 ? 1 : -1) / (fabs(theta) + sqrt(theta * theta + 1));
        const double c = 1 / sqrt(t * t + 1), s = t * c;
        for (int k = 0; k < n; ++k) { /* columns p and r */
          const double kp = a[n * k + p], kr = a[n * k + r];
          a[n * k + p] = c * kp - s * kr;
          a[n * k + r] = s * kp + c * kr;
        }
        for (int k = 0; k < n; ++k) { /* rows p and r */
          const double pk = a[n * p + k], rk = a[n * r + k];
          a[n * p + k] = c * pk - s * rk;
          a[n * r + k] = s * pk + c * rk;
        }
        for (int k = 0; k < n; ++k) {
          const double kp = V[n * k + p], kr = V[n * k + r];
          V[n * k + p] = c * kp - s * kr;
          V[n * k + r] = s * kp + c * kr;
        }
      }
  }
  for (int i = 0; i < n; ++i) lambda[i] = a[(n + 1) * i];
  for (int i = 1; i < n; ++i) /* ascending, columns with them */
    for (int j = i; j > 0 && lambda[j] < lambda[j - 1]; --j) {
      const double t = lambda[j];
      lambda[j] = lambda[j - 1];
      lambda[j - 1] = t;
      for (int k = 0; k < n; ++k) {
        const double v = V[n * k + j];
        V[n * k + j] = V[n * k + j - 1];
        V[n * k + j - 1] = v;
      }
    }
}
