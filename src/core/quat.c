/* quat.c - unit quaternions, their average (Markley et al. 2007) and random rotations. */
#include "core/quat.h"

#include "core/sym_eigen.h"

#include <math.h>
#include <string.h>

void mpm_quat_to_matrix(const double q[4], double R[9]) {
  const double w = q[0], x = q[1], y = q[2], z = q[3];
  R[0] = 1 - 2 * (y * y + z * z);
  R[1] = 2 * (x * y - w * z);
  R[2] = 2 * (x * z + w * y);
  R[3] = 2 * (x * y + w * z);
  R[4] = 1 - 2 * (x * x + z * z);
  R[5] = 2 * (y * z - w * x);
  R[6] = 2 * (x * z - w * y);
  R[7] = 2 * (y * z + w * x);
  R[8] = 1 - 2 * (x * x + y * y);
}

void mpm_quat_from_matrix(const double R[9], double q[4]) {
  const double t = R[0] + R[4] + R[8];
  /* 4 w^2 = 1 + t, 4 x^2 = 1 + R00 - R11 - R22, ...: pivot on the largest */
  const double c[4] = {t, R[0], R[4], R[8]};
  int k = 0;
  for (int i = 1; i < 4; ++i)
    if (c[i] > c[k]) k = i;
  double s;
  switch (k) {
  case 0:
    s = 2 * sqrt(fmax(1 + t, 0));
    q[0] = 0.25 * s;
    q[1] = (R[7] - R[5]) / s;
    q[2] = (R[2] - R[6]) / s;
    q[3] = (R[3] - R[1]) / s;
    break;
  case 1:
    s = 2 * sqrt(fmax(1 + R[0] - R[4] - R[8], 0));
    q[0] = (R[7] - R[5]) / s;
    q[1] = 0.25 * s;
    q[2] = (R[1] + R[3]) / s;
    q[3] = (R[2] + R[6]) / s;
    break;
  case 2:
    s = 2 * sqrt(fmax(1 - R[0] + R[4] - R[8], 0));
    q[0] = (R[2] - R[6]) / s;
    q[1] = (R[1] + R[3]) / s;
    q[2] = 0.25 * s;
    q[3] = (R[5] + R[7]) / s;
    break;
  default:
    s = 2 * sqrt(fmax(1 - R[0] - R[4] + R[8], 0));
    q[0] = (R[3] - R[1]) / s;
    q[1] = (R[2] + R[6]) / s;
    q[2] = (R[5] + R[7]) / s;
    q[3] = 0.25 * s;
    break;
  }
  const double n = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  const double sign = q[0] < 0 ? -1 : 1;
  for (int i = 0; i < 4; ++i) q[i] *= sign / n;
}

void mpm_quat_average(int n, const double (*q)[4], const double *w, double out[4]) {
  double M[16] = {0};
  for (int i = 0; i < n; ++i) {
    const double wi = w ? w[i] : 1;
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) M[4 * r + c] += wi * q[i][r] * q[i][c];
  }
  double lambda[4], V[16];
  mpm_sym_eigen(4, M, lambda, V);
  double dot = 0, norm = 0;
  for (int r = 0; r < 4; ++r) {
    out[r] = V[4 * r + 3];
    dot += out[r] * q[0][r];
    norm += out[r] * out[r];
  }
  const double s = (dot < 0 ? -1 : 1) / sqrt(norm);
  for (int r = 0; r < 4; ++r) out[r] *= s;
}

void mpm_quat_uniform(const double u[3], double q[4]) {
  const double two_pi = 6.283185307179586;
  const double a = sqrt(1 - u[0]), b = sqrt(u[0]);
  q[0] = b * cos(two_pi * u[2]);
  q[1] = a * sin(two_pi * u[1]);
  q[2] = a * cos(two_pi * u[1]);
  q[3] = b * sin(two_pi * u[2]);
}
