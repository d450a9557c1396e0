/* test_svd.c - the 3x3 SVD and polar decomposition (src/core/svd3.c, McAdams et al. 2011) and
 * the SIMD batch SVD (core/svd3_lanes.h), each checked on every matrix below,
 * against independent truth: matrices built in double as Q1 diag(s) Q2^T from known singular
 * values s and random rotations, so the expected sigma (with the sign convention of Irving et
 * al. 2004 / Zhu et al. 2017 sec. 5.3) is known exactly. Families: random well-conditioned,
 * near-singular (one sigma 1e-6), rank-deficient, repeated sigma (identity, pure rotations, two
 * equal), inverted (det < 0), F = 0, diagonal matrices with signs and permutations, and plain
 * random matrices. Checked: reconstruction ||U S V^T - F|| / ||F||, orthogonality of U and V,
 * det U = det V = +1, ordering sigma0 >= sigma1 >= |sigma2|, the sign rule, sigma against the
 * known values, and polar R S = F with R a rotation and S symmetric. The worst errors are
 * printed. */
#include "support.h"
#include "core/mat3.h"
#include "core/svd3.h"

#include <math.h>
#include <stdio.h>

typedef struct worst {
  double recon, ortho, det, sigma, polar;
  long count;
} worst;

static worst g_worst;

/* ---- double-precision helpers (independent of the library) -------------------------- */

static void dmul(const double A[9], const double B[9], double C[9]) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      C[3 * r + c] = A[3 * r] * B[c] + A[3 * r + 1] * B[3 + c] + A[3 * r + 2] * B[6 + c];
}

static double ddet(const double A[9]) {
  return A[0] * (A[4] * A[8] - A[5] * A[7]) - A[1] * (A[3] * A[8] - A[5] * A[6]) +
         A[2] * (A[3] * A[7] - A[4] * A[6]);
}

/* Uniform random rotation from a normalized random quaternion. */
static void rand_rotation(uint64_t *rng, double Q[9]) {
  double q[4], n = 0;
  do {
    n = 0;
    for (int i = 0; i < 4; ++i) {
      q[i] = test_rand(rng, -1, 1);
      n += q[i] * q[i];
    }
  } while (n > 1 || n < 1e-4);
  n = sqrt(n);
  const double w = q[0] / n, x = q[1] / n, y = q[2] / n, z = q[3] / n;
  Q[0] = 1 - 2 * (y * y + z * z);
  Q[1] = 2 * (x * y - w * z);
  Q[2] = 2 * (x * z + w * y);
  Q[3] = 2 * (x * y + w * z);
  Q[4] = 1 - 2 * (x * x + z * z);
  Q[5] = 2 * (y * z - w * x);
  Q[6] = 2 * (x * z - w * y);
  Q[7] = 2 * (y * z + w * x);
  Q[8] = 1 - 2 * (x * x + y * y);
}

/* F = Q1 diag(s) Q2^T */
static void compose(const double Q1[9], const double s[3], const double Q2[9], double F[9]) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      F[3 * r + c] = Q1[3 * r] * s[0] * Q2[3 * c] + Q1[3 * r + 1] * s[1] * Q2[3 * c + 1] +
                     Q1[3 * r + 2] * s[2] * Q2[3 * c + 2];
}

static double fro(const double A[9]) {
  double s = 0;
  for (int i = 0; i < 9; ++i) s += A[i] * A[i];
  return sqrt(s);
}

/* ||Q^T Q - I||_max */
static double ortho_err(const mpm_real Q[9]) {
  double e = 0;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) {
      double d = 0;
      for (int k = 0; k < 3; ++k) d += (double)Q[3 * k + r] * Q[3 * k + c];
      e = fmax(e, fabs(d - (r == c)));
    }
  return e;
}

/* ---- the check ------------------------------------------------------------------------ */

/* Decompose F64 (rounded to mpm_real) and check every property. `known` (may be NULL) holds
 * the expected signed singular values in the library's convention. */
static void check(const double F64[9], const double *known, const char *what) {
  const double tol_recon = TOL(4e-6, 4e-15), tol_ortho = TOL(4e-6, 4e-15);
  const double tol_sigma = TOL(4e-6, 4e-15);
  mpm_real F[9], U[9], s[3], V[9];
  double Fd[9];
  for (int i = 0; i < 9; ++i) {
    F[i] = (mpm_real)F64[i];
    Fd[i] = F[i];
  }
  const double nf = fro(Fd);
  /* both implementations: the scalar mpm_svd3 and the SIMD batch (support.h) */
  for (int path = 0; path < TEST_SVD_PATHS; ++path) {
    test_svd_path(path, F, U, s, V);
    double Ud[9], Vd[9], sd[3] = {s[0], s[1], s[2]}, G[9], D[9];
    for (int i = 0; i < 9; ++i) {
      Ud[i] = U[i];
      Vd[i] = V[i];
    }
    compose(Ud, sd, Vd, G);
    for (int i = 0; i < 9; ++i) D[i] = G[i] - Fd[i];
    const double recon = nf > 0 ? fro(D) / nf : fro(D);
    const double ortho = fmax(ortho_err(U), ortho_err(V));
    const double det = fmax(fabs(ddet(Ud) - 1), fabs(ddet(Vd) - 1));
    for (int i = 0; i < 3; ++i) assert_true(isfinite(s[i]));
    if (recon > tol_recon || ortho > tol_ortho || det > 2 * tol_ortho)
      fail_msg("%s [%s]: recon %.3g ortho %.3g det %.3g (sigma %.9g %.9g %.9g)", what,
               test_svd_path_name[path], recon, ortho, det, (double)s[0], (double)s[1],
               (double)s[2]);
    g_worst.recon = fmax(g_worst.recon, recon);
    g_worst.ortho = fmax(g_worst.ortho, ortho);
    g_worst.det = fmax(g_worst.det, det);
    g_worst.count++;

    /* ordering (exact, no tolerance) */
    if (!(s[0] >= s[1] && s[1] >= fabs((double)s[2])))
      fail_msg("%s [%s]: order violated: %.9g %.9g %.9g", what, test_svd_path_name[path],
               (double)s[0], (double)s[1], (double)s[2]);
    /* sign rule wherever det F is clearly away from zero in this precision */
    const double dF = ddet(Fd);
    if (fabs(dF) > TOL(1e-4, 1e-10) * nf * nf * nf) {
      if ((s[2] < 0) != (dF < 0))
        fail_msg("%s [%s]: sign rule: det F %.3g but sigma2 %.3g", what, test_svd_path_name[path],
                 dF, (double)s[2]);
    }
    if (known) {
      const double smax = fmax(fabs(known[0]), 1e-300);
      for (int i = 0; i < 3; ++i) {
        const double e = fabs(s[i] - known[i]) / smax;
        if (e > tol_sigma)
          fail_msg("%s [%s]: sigma[%d] = %.12g, expected %.12g (rel. err %.3g)", what,
                   test_svd_path_name[path], i, (double)s[i], known[i], e);
        g_worst.sigma = fmax(g_worst.sigma, e);
      }
    }
  }

  /* polar decomposition */
  mpm_real R[9], S[9], RS[9];
  mpm_polar3(F, R, S);
  mpm_m3_mul(R, S, RS);
  double pe = 0;
  for (int i = 0; i < 9; ++i) pe = fmax(pe, fabs((double)RS[i] - Fd[i]));
  pe /= fmax(nf, 1e-300);
  double Rd[9];
  for (int i = 0; i < 9; ++i) Rd[i] = R[i];
  pe = fmax(pe, ortho_err(R));
  pe = fmax(pe, fabs(ddet(Rd) - 1));
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < r; ++c)
      pe = fmax(pe, fabs((double)S[3 * r + c] - S[3 * c + r]) / fmax(nf, 1e-300));
  if (nf == 0) pe = fabs(ddet(Rd) - 1) + ortho_err(R);
  if (pe > 2 * tol_recon) fail_msg("%s: polar error %.3g", what, pe);
  g_worst.polar = fmax(g_worst.polar, pe);
}

/* Sort |s| descending, attach the sign of the product to the last one. */
static void expected_sigma(const double s[3], double e[3]) {
  double a[3] = {fabs(s[0]), fabs(s[1]), fabs(s[2])};
  for (int i = 0; i < 3; ++i)
    for (int j = i + 1; j < 3; ++j)
      if (a[j] > a[i]) {
        double t = a[i];
        a[i] = a[j];
        a[j] = t;
      }
  const double sign = s[0] * s[1] * s[2] < 0 ? -1 : 1;
  e[0] = a[0];
  e[1] = a[1];
  e[2] = sign * a[2];
}

/* Random Q1 diag(s) Q2^T for a given s (any signs, any order). */
static void check_with_sigma(uint64_t *rng, const double s[3], const char *what) {
  double Q1[9], Q2[9], F[9], e[3];
  rand_rotation(rng, Q1);
  rand_rotation(rng, Q2);
  compose(Q1, s, Q2, F);
  expected_sigma(s, e);
  check(F, e, what);
}

/* ---- the families ----------------------------------------------------------------------- */

static void test_random_well_conditioned(void **state) {
  (void)state;
  uint64_t rng = 1;
  for (int t = 0; t < 20000; ++t) {
    double s[3];
    for (int i = 0; i < 3; ++i) s[i] = test_rand(&rng, 0.2, 3.0);
    check_with_sigma(&rng, s, "well-conditioned");
  }
}

static void test_random_entries(void **state) {
  (void)state;
  uint64_t rng = 2;
  for (int t = 0; t < 20000; ++t) {
    double F[9];
    const double scale = pow(10.0, test_rand(&rng, -6, 6));
    for (int i = 0; i < 9; ++i) F[i] = scale * test_rand(&rng, -1, 1);
    check(F, NULL, "random entries");
  }
}

static void test_near_singular(void **state) {
  (void)state;
  uint64_t rng = 3;
  for (int t = 0; t < 5000; ++t) {
    double s[3] = {test_rand(&rng, 0.5, 2), test_rand(&rng, 0.5, 2), 1e-6};
    if (t & 1) s[2] = -1e-6; /* nearly flat and inverted */
    check_with_sigma(&rng, s, "near-singular");
  }
}

static void test_rank_deficient(void **state) {
  (void)state;
  uint64_t rng = 4;
  for (int t = 0; t < 5000; ++t) {
    double s[3] = {test_rand(&rng, 0.5, 2), test_rand(&rng, 0.5, 2), 0};
    if (t % 3 == 1) s[1] = 0;           /* rank 1 */
    if (t % 3 == 2) s[0] = s[1] = 1e-3; /* rank 2 with two equal sigma at a small scale */
    check_with_sigma(&rng, s, "rank-deficient");
  }
  /* exactly singular with integer entries: rows 1 and 2 dependent */
  const double F1[9] = {1, 2, 3, 2, 4, 6, 0, 1, 1};
  check(F1, NULL, "integer rank 2");
  const double F2[9] = {1, 2, 3, 2, 4, 6, -1, -2, -3};
  check(F2, NULL, "integer rank 1");
}

static void test_repeated(void **state) {
  (void)state;
  uint64_t rng = 5;
  const double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  const double one[3] = {1, 1, 1};
  check(I, one, "identity");
  for (int t = 0; t < 5000; ++t) {
    double Q[9];
    rand_rotation(&rng, Q);
    check(Q, one, "rotation");
    const double a = test_rand(&rng, 0.2, 3), b = test_rand(&rng, 0.2, 3);
    const double s1[3] = {a, a, b}, s2[3] = {a, b, b}, s3[3] = {a, a, a}, s4[3] = {a, a, -a};
    const double s5[3] = {a, b, -b};
    check_with_sigma(&rng, s1, "two equal (a a b)");
    check_with_sigma(&rng, s2, "two equal (a b b)");
    check_with_sigma(&rng, s3, "three equal");
    check_with_sigma(&rng, s4, "three equal, inverted");
    check_with_sigma(&rng, s5, "two equal magnitude, inverted");
  }
}

static void test_inverted(void **state) {
  (void)state;
  uint64_t rng = 6;
  for (int t = 0; t < 20000; ++t) {
    double s[3];
    for (int i = 0; i < 3; ++i) s[i] = test_rand(&rng, 0.1, 3.0);
    s[t % 3] = -s[t % 3]; /* one negative in any position */
    if (t % 7 == 0) s[0] = s[1] = s[2] = -s[t % 3] * (t % 2 ? 1 : 0.5); /* -a I-like */
    check_with_sigma(&rng, s, "inverted");
  }
  /* reflections */
  const double Rx[9] = {-1, 0, 0, 0, 1, 0, 0, 0, 1}, m1[3] = {1, 1, -1};
  check(Rx, m1, "reflection");
  const double mI[9] = {-1, 0, 0, 0, -1, 0, 0, 0, -1};
  check(mI, m1, "-I");
}

static void test_zero(void **state) {
  (void)state;
  const double Z[9] = {0}, z[3] = {0, 0, 0};
  check(Z, z, "F = 0");
  mpm_real F[9] = {0}, U[9], s[3], V[9];
  mpm_svd3(F, U, s, V);
  for (int i = 0; i < 9; ++i) {
    assert_close(U[i], (i % 4 == 0), 0);
    assert_close(V[i], (i % 4 == 0), 0);
  }
  /* tiny and huge matrices */
  uint64_t rng = 7;
  for (int t = 0; t < 200; ++t) {
    double s3[3] = {test_rand(&rng, 0.2, 3), test_rand(&rng, 0.2, 3), test_rand(&rng, 0.2, 3)};
    const double sc = (t & 1) ? 1e-30 : 1e30;
    for (int i = 0; i < 3; ++i) s3[i] *= sc;
    check_with_sigma(&rng, s3, "tiny/huge scale");
  }
}

static void test_diagonal(void **state) {
  (void)state;
  uint64_t rng = 8;
  for (int t = 0; t < 5000; ++t) {
    double s[3], F[9] = {0}, e[3];
    for (int i = 0; i < 3; ++i) s[i] = test_rand(&rng, -3, 3);
    if (t % 5 == 0) s[1] = s[0];
    if (t % 11 == 0) s[2] = 0;
    for (int i = 0; i < 3; ++i) F[4 * i] = s[i];
    expected_sigma(s, e);
    check(F, e, "diagonal");
    /* a signed permutation of the diagonal (still a "diagonal" SVD problem) */
    double P[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
    P[1] = s[0];
    P[5] = s[1];
    P[6] = s[2];
    check(P, e, "permuted diagonal");
  }
}

/* The batch on every count of matrices (partial SIMD batches, more than one batch, none) agrees
 * with the scalar SVD particle by particle, and a non-finite matrix in one lane leaves the
 * other lanes' results unchanged. */
static void test_batch_counts_and_lanes(void **state) {
  (void)state;
  enum { NMAX = 100 };
  static mpm_real F[9][NMAX], U[9][NMAX], V[9][NMAX], S[3][NMAX];
  const mpm_real *Fp[9];
  mpm_real *Up[9], *Vp[9], *Sp[3];
  for (int c = 0; c < 9; ++c) {
    Fp[c] = F[c];
    Up[c] = U[c];
    Vp[c] = V[c];
  }
  for (int c = 0; c < 3; ++c) Sp[c] = S[c];
  uint64_t rng = 31;
  const int counts[] = {0, 1, 3, 7, 8, 9, 31, 32, 33, 63, 64, 65, NMAX};
  for (size_t t = 0; t < sizeof counts / sizeof counts[0]; ++t) {
    const int n = counts[t];
    for (int c = 0; c < 9; ++c)
      for (int i = 0; i < NMAX; ++i) F[c][i] = (mpm_real)test_rand(&rng, -2, 2);
    for (int c = 0; c < 3; ++c)
      for (int i = 0; i < NMAX; ++i) S[c][i] = -7; /* beyond n: must stay untouched */
    mpm_svd3_batch(n, Fp, Up, Sp, Vp);
    for (int i = 0; i < NMAX; ++i) {
      if (i >= n) {
        assert_true(S[0][i] == -7 && S[2][i] == -7);
        continue;
      }
      mpm_real Fi[9], Ui[9], si[3], Vi[9];
      for (int c = 0; c < 9; ++c) Fi[c] = F[c][i];
      mpm_svd3(Fi, Ui, si, Vi);
      double nf = 0;
      for (int c = 0; c < 9; ++c) nf += (double)Fi[c] * Fi[c];
      nf = sqrt(nf);
      for (int c = 0; c < 3; ++c) assert_close(S[c][i], si[c], TOL(4e-6, 4e-15) * nf);
    }
  }
  /* lane independence: a NaN matrix among finite ones */
  for (int c = 0; c < 9; ++c)
    for (int i = 0; i < 16; ++i) F[c][i] = (mpm_real)test_rand(&rng, -2, 2);
  mpm_svd3_batch(16, Fp, Up, Sp, Vp);
  mpm_real ref[3][16];
  for (int c = 0; c < 3; ++c)
    for (int i = 0; i < 16; ++i) ref[c][i] = S[c][i];
  F[4][5] = (mpm_real)NAN;
  mpm_svd3_batch(16, Fp, Up, Sp, Vp);
  for (int i = 0; i < 16; ++i)
    for (int c = 0; c < 3; ++c) {
      if (i == 5) continue;
      if (S[c][i] != ref[c][i]) fail_msg("lane %d changed by a NaN in lane 5", i);
    }
}

static void test_report(void **state) {
  (void)state;
  print_message("svd3 (%s, %ld decompositions): worst reconstruction %.3g, orthogonality %.3g, "
                "|det-1| %.3g, sigma vs known %.3g, polar %.3g\n",
                MPM_REAL_NAME, g_worst.count, g_worst.recon, g_worst.ortho, g_worst.det,
                g_worst.sigma, g_worst.polar);
}

/* The product of a composition check with dmul keeps the helper honest. */
static void test_helpers(void **state) {
  (void)state;
  uint64_t rng = 9;
  double Q[9], QT[9], P[9];
  rand_rotation(&rng, Q);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) QT[3 * c + r] = Q[3 * r + c];
  dmul(Q, QT, P);
  for (int i = 0; i < 9; ++i) assert_close(P[i], (i % 4 == 0), 1e-14);
  assert_close(ddet(Q), 1, 1e-14);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_helpers),        cmocka_unit_test(test_random_well_conditioned),
      cmocka_unit_test(test_random_entries), cmocka_unit_test(test_near_singular),
      cmocka_unit_test(test_rank_deficient), cmocka_unit_test(test_repeated),
      cmocka_unit_test(test_inverted),       cmocka_unit_test(test_zero),
      cmocka_unit_test(test_diagonal),       cmocka_unit_test(test_batch_counts_and_lanes),
      cmocka_unit_test(test_report),
  };
  return cmocka_run_group_tests_name("svd3", tests, NULL, NULL);
}
