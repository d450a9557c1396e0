/* test_quat_lapack.c - unit quaternions and their average (src/core/quat.c) against
 * independent truth: the largest eigenvector of M = sum w q q^T from LAPACK's dsyev (Debian
 * liblapacke; Markley et al. 2007 define the average as that vector), the closed form for
 * rotations about one axis (the mean angle), sign invariance, the rotation-matrix round trip,
 * the Jacobi eigen-solver (core/sym_eigen.c) against dsyev, and the uniformity of random rotations
 * (the mean of R is zero). */
#include "support.h"
#include "core/quat.h"
#include "core/sym_eigen.h"

#include <lapacke.h>
#include <math.h>
#include <string.h>

static void random_quat(uint64_t *s, double q[4]) {
  const double u[3] = {test_rand(s, 0, 1), test_rand(s, 0, 1), test_rand(s, 0, 1)};
  mpm_quat_uniform(u, q);
}

static double qdist(const double a[4], const double b[4]) { /* blind to the sign */
  double p = 0, m = 0;
  for (int i = 0; i < 4; ++i)
    p += (a[i] - b[i]) * (a[i] - b[i]), m += (a[i] + b[i]) * (a[i] + b[i]);
  return sqrt(fmin(p, m));
}

static void test_matrix_round_trip(void **state) {
  (void)state;
  uint64_t s = 7;
  for (int t = 0; t < 1000; ++t) {
    double q[4], R[9], back[4], RtR[9] = {0};
    random_quat(&s, q);
    mpm_quat_to_matrix(q, R);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        for (int k = 0; k < 3; ++k) RtR[3 * i + j] += R[3 * k + i] * R[3 * k + j];
    for (int c = 0; c < 9; ++c) assert_close(RtR[c], c % 4 == 0, 1e-12);
    const double det = R[0] * (R[4] * R[8] - R[5] * R[7]) - R[1] * (R[3] * R[8] - R[5] * R[6]) +
                       R[2] * (R[3] * R[7] - R[4] * R[6]);
    assert_close(det, 1, 1e-12);
    mpm_quat_from_matrix(R, back);
    assert_true(back[0] >= 0);
    if (qdist(q, back) > 1e-12) fail_msg("round trip %g", qdist(q, back));
  }
  /* a half turn (w = 0): the pivot is a vector part */
  const double half[4] = {0, 0, 0.6, 0.8};
  double R[9], back[4];
  mpm_quat_to_matrix(half, R);
  mpm_quat_from_matrix(R, back);
  assert_true(qdist(half, back) < 1e-12);
}

static void test_eigen_against_lapack(void **state) {
  (void)state;
  uint64_t s = 11;
  for (int t = 0; t < 400; ++t) {
    const int n = 3 + t % 2;
    double A[16], lapack[16], w[4], lambda[4], V[16];
    for (int i = 0; i < n; ++i)
      for (int j = i; j < n; ++j) A[n * i + j] = A[n * j + i] = test_rand(&s, -1, 1);
    if (t % 4 < 2) A[n + 1] = A[0]; /* near-repeated diagonals too */
    memcpy(lapack, A, sizeof A);
    assert_int_equal(LAPACKE_dsyev(LAPACK_ROW_MAJOR, 'V', 'U', n, lapack, n, w), 0);
    mpm_sym_eigen(n, A, lambda, V);
    for (int k = 0; k < n; ++k) assert_close(lambda[k], w[k], 1e-12);
    for (int k = 0; k < n; ++k) /* A v = lambda v, |v| = 1 */
      for (int r = 0; r < n; ++r) {
        double Av = 0, vv = 0;
        for (int c = 0; c < n; ++c)
          Av += A[n * r + c] * V[n * c + k], vv += V[n * c + k] * V[n * c + k];
        assert_close(Av, lambda[k] * V[n * r + k], 1e-11);
        assert_close(vv, 1, 1e-12);
      }
  }
}

static void test_average_against_lapack(void **state) {
  (void)state;
  uint64_t s = 13;
  double worst = 0;
  for (int t = 0; t < 300; ++t) {
    const int n = 2 + t % 9;
    double q[16][4], w[16], M[16] = {0}, e[4], avg[4];
    double centre[4];
    random_quat(&s, centre);
    for (int k = 0; k < n; ++k) {
      /* a spread about a centre, with random signs (q and -q are one rotation) */
      double d[4];
      for (int i = 0; i < 4; ++i) d[i] = centre[i] + test_rand(&s, -0.3, 0.3);
      const double norm = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2] + d[3] * d[3]);
      const double sign = test_rand(&s, 0, 1) < 0.5 ? -1 : 1;
      for (int i = 0; i < 4; ++i) q[k][i] = sign * d[i] / norm;
      w[k] = test_rand(&s, 0.2, 2);
      for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) M[4 * r + c] += w[k] * q[k][r] * q[k][c];
    }
    assert_int_equal(LAPACKE_dsyev(LAPACK_ROW_MAJOR, 'V', 'U', 4, M, 4, e), 0);
    const double ref[4] = {M[3], M[7], M[11], M[15]}; /* the largest eigenvalue's column */
    mpm_quat_average(n, (const double(*)[4])q, w, avg);
    const double d = qdist(avg, ref);
    worst = fmax(worst, d);
    if (d > 1e-9) fail_msg("average %d: %g from LAPACK", t, d);
    double dot = 0;
    for (int i = 0; i < 4; ++i) dot += avg[i] * q[0][i];
    assert_true(dot >= 0); /* the sign of the first input */
  }
  print_message("quaternion average against dsyev: worst %.2e\n", worst);
}

static void test_average_one_axis(void **state) {
  (void)state;
  /* rotations about one axis average to the mean angle (half-angles under pi/2 apart) */
  const double axis[3] = {0.48, -0.6, 0.64};
  const double angles[5] = {0.1, 0.5, 0.9, 1.3, 0.7};
  double q[5][4], mean = 0;
  for (int k = 0; k < 5; ++k) {
    q[k][0] = cos(angles[k] / 2);
    for (int d = 0; d < 3; ++d) q[k][d + 1] = sin(angles[k] / 2) * axis[d];
    if (k % 2) /* signs do not matter */
      for (int i = 0; i < 4; ++i) q[k][i] = -q[k][i];
    mean += angles[k] / 5;
  }
  double avg[4];
  mpm_quat_average(5, (const double(*)[4])q, NULL, avg);
  /* equal weights about one axis: the eigenvector is at the mean of the half-angles' directions
   * on the circle, which is the angle whose tangent is sum sin / sum cos */
  double sc = 0, ss = 0;
  for (int k = 0; k < 5; ++k) sc += cos(angles[k]), ss += sin(angles[k]);
  const double circ = atan2(ss, sc); /* the principal eigen-direction of sum (c, s)(c, s)^T */
  const double want[4] = {cos(circ / 2), sin(circ / 2) * axis[0], sin(circ / 2) * axis[1],
                          sin(circ / 2) * axis[2]};
  assert_true(qdist(avg, want) < 1e-12);
  assert_true(fabs(circ - mean) < 0.05); /* close to the arithmetic mean for a small spread */
}

static void test_uniform_rotations(void **state) {
  (void)state;
  uint64_t s = 17;
  double mean[9] = {0};
  const int n = 20000;
  for (int t = 0; t < n; ++t) {
    double q[4], R[9];
    random_quat(&s, q);
    const double norm = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    assert_close(norm, 1, 1e-12);
    mpm_quat_to_matrix(q, R);
    for (int c = 0; c < 9; ++c) mean[c] += R[c] / n;
  }
  /* Haar measure: E[R] = 0; the sample mean's spread is about 1 / sqrt(3 n) */
  for (int c = 0; c < 9; ++c)
    if (fabs(mean[c]) > 5 / sqrt(3.0 * n)) fail_msg("E[R][%d] = %g", c, mean[c]);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_matrix_round_trip),      cmocka_unit_test(test_eigen_against_lapack),
      cmocka_unit_test(test_average_against_lapack), cmocka_unit_test(test_average_one_axis),
      cmocka_unit_test(test_uniform_rotations),
  };
  return test_cleanup(cmocka_run_group_tests(tests, NULL, NULL));
}
