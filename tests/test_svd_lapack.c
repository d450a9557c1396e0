/* test_svd_lapack.c - mpm_svd3 (src/core/svd3.c) and its lane version mpm_svd3_batch
 * (core/svd3_lanes.h) against LAPACK's dgesvd (Debian liblapacke)
 * as an independent reference, on many matrices of each class: random (entries and
 * Q1 diag(s) Q2^T), near-singular (one sigma ~1e-6), rank-deficient, repeated singular values,
 * inverted (det F < 0), diagonal (signed, permuted) and F = 0.
 *
 * Each F is generated in double, rounded to mpm_real, and the rounded matrix (exactly
 * representable in double) is decomposed by both: by mpm_svd3 in the build's real type and by
 * LAPACKE_dgesvd in double. Checked:
 *   - singular values: |sigma_mpm[i]| = S_lapack[i] to TOL(float, double) relative to ||F||_2
 *     (mpm sorts by magnitude and makes the last one negative iff det F < 0; LAPACK's are
 *     non-negative and sorted), the ordering and the sign rule;
 *   - reconstruction ||U diag(s) V^T - F||_F / ||F||_F and orthogonality max|Q^T Q - I| of both
 *     decompositions (mpm's asserted, LAPACK's asserted at double accuracy; both reported);
 *   - singular vectors: where sigma_i is separated from the others by a gap, the columns u_i and
 *     v_i agree with LAPACK's up to sign, to ~TOL * ||F|| / gap (the perturbation bound), and
 *     the signs pair up: sign(u_i . u_i') sign(v_i . v_i') = sign(sigma_i).
 * The worst errors of each class are printed with print_message. Linked with LAPACKE only here
 * (CMakeLists.txt); the library itself never uses LAPACK. */
#include "support.h"
#include "core/svd3.h"

#include <lapacke.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

/* ---- per-class worst errors ---------------------------------------------------------- */

typedef struct stats {
  const char *name;
  long count, vec_count;
  double sigma; /* max_i |(|s_i|) - S_i| / ||F||_2 */
  double recon_mpm, recon_lapack;
  double ortho_mpm, ortho_lapack;
  double vec;        /* max singular-vector error */
  double vec_scaled; /* max vector error * gap / ||F||_2 (compare with TOL) */
} stats;

enum {
  C_RANDOM,
  C_NEAR_SINGULAR,
  C_RANK_DEFICIENT,
  C_REPEATED,
  C_INVERTED,
  C_DIAGONAL,
  C_ZERO,
  C_COUNT
};
static const char *const CLASS_NAME[C_COUNT] = {
    "random", "near-singular", "rank-deficient", "repeated", "inverted", "diagonal", "F = 0"};
/* per path (support.h: the scalar and the SIMD batch SVD) and class */
static stats g_stats[TEST_SVD_PATHS][C_COUNT];

/* ---- double-precision helpers (independent of the library) --------------------------- */

static double ddet(const double A[9]) {
  return A[0] * (A[4] * A[8] - A[5] * A[7]) - A[1] * (A[3] * A[8] - A[5] * A[6]) +
         A[2] * (A[3] * A[7] - A[4] * A[6]);
}

static double fro(const double A[9]) {
  double s = 0;
  for (int i = 0; i < 9; ++i) s += A[i] * A[i];
  return sqrt(s);
}

/* Uniform random rotation from a normalized random quaternion. */
static void rand_rotation(uint64_t *rng, double Q[9]) {
  double q[4], n;
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

/* F = Q1 diag(s) Q2^T (row-major, columns of Q1 and Q2 are the singular vectors). */
static void compose(const double Q1[9], const double s[3], const double Q2[9], double F[9]) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      F[3 * r + c] = Q1[3 * r] * s[0] * Q2[3 * c] + Q1[3 * r + 1] * s[1] * Q2[3 * c + 1] +
                     Q1[3 * r + 2] * s[2] * Q2[3 * c + 2];
}

/* max |Q^T Q - I| */
static double ortho_err(const double Q[9]) {
  double e = 0;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) {
      double d = 0;
      for (int k = 0; k < 3; ++k) d += Q[3 * k + r] * Q[3 * k + c];
      e = fmax(e, fabs(d - (r == c)));
    }
  return e;
}

static double recon_err(const double U[9], const double s[3], const double V[9],
                        const double F[9]) {
  double G[9];
  compose(U, s, V, G);
  for (int i = 0; i < 9; ++i) G[i] -= F[i];
  const double nf = fro(F);
  return nf > 0 ? fro(G) / nf : fro(G);
}

/* Column c of a row-major 3x3 matrix. */
static void column(const double Q[9], int c, double v[3]) {
  for (int r = 0; r < 3; ++r) v[r] = Q[3 * r + c];
}

/* ---- the comparison ------------------------------------------------------------------- */

static void check_path(int path, const double F64[9], int cls, const char *what_in) {
  char what[200]; /* failure messages name the path */
  snprintf(what, sizeof what, "%s [%s]", what_in, test_svd_path_name[path]);
  /* the same tolerances as tests/test_svd.c for mpm's own properties */
  const double tol = TOL(4e-6, 4e-15);
  const double tol_lapack = 1e-13; /* LAPACK in double, whatever the build's real type */
  stats *st = &g_stats[path][cls];

  /* the matrix both decompose: F rounded to mpm_real, exactly representable in double */
  mpm_real F[9], U[9], s[3], V[9];
  double Fd[9];
  for (int i = 0; i < 9; ++i) {
    F[i] = (mpm_real)F64[i];
    Fd[i] = (double)F[i];
  }
  test_svd_path(path, F, U, s, V);
  double Um[9], Vm[9], sm[3];
  for (int i = 0; i < 9; ++i) {
    Um[i] = U[i];
    Vm[i] = V[i];
  }
  for (int i = 0; i < 3; ++i) {
    sm[i] = s[i];
    assert_true(isfinite(sm[i]));
  }

  /* LAPACK: A = UL diag(SL) VT, row-major; dgesvd overwrites A */
  double A[9], SL[3], UL[9], VT[9], VL[9], superb[2];
  memcpy(A, Fd, sizeof A);
  const lapack_int info =
      LAPACKE_dgesvd(LAPACK_ROW_MAJOR, 'A', 'A', 3, 3, A, 3, SL, UL, 3, VT, 3, superb);
  if (info != 0) fail_msg("%s: LAPACKE_dgesvd info %d", what, (int)info);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) VL[3 * r + c] = VT[3 * c + r];

  const double n2 = SL[0]; /* ||F||_2 */
  const double scale = n2 > 0 ? n2 : 1;

  /* reference sanity: LAPACK at double accuracy */
  const double rl = recon_err(UL, SL, VL, Fd);
  const double ol = fmax(ortho_err(UL), ortho_err(VL));
  if (rl > tol_lapack || ol > tol_lapack)
    fail_msg("%s: LAPACK reference off: recon %.3g ortho %.3g", what, rl, ol);

  /* mpm: reconstruction, orthogonality, proper rotations, ordering, sign rule */
  const double rm = recon_err(Um, sm, Vm, Fd);
  const double om = fmax(ortho_err(Um), ortho_err(Vm));
  const double dm = fmax(fabs(ddet(Um) - 1), fabs(ddet(Vm) - 1));
  if (rm > tol || om > tol || dm > 2 * tol)
    fail_msg("%s: mpm recon %.3g ortho %.3g |det-1| %.3g (sigma %.9g %.9g %.9g)", what, rm, om, dm,
             sm[0], sm[1], sm[2]);
  if (!(sm[0] >= sm[1] && sm[1] >= fabs(sm[2])))
    fail_msg("%s: order violated: %.9g %.9g %.9g", what, sm[0], sm[1], sm[2]);
  const double dF = ddet(Fd);
  if (fabs(dF) > TOL(1e-4, 1e-10) * n2 * n2 * n2 && (sm[2] < 0) != (dF < 0))
    fail_msg("%s: sign rule: det F %.3g but sigma2 %.3g", what, dF, sm[2]);

  /* singular values: magnitudes against LAPACK's */
  for (int i = 0; i < 3; ++i) {
    const double e = fabs(fabs(sm[i]) - SL[i]) / scale;
    if (e > tol)
      fail_msg("%s: |sigma[%d]| = %.12g, LAPACK %.12g (err %.3g of ||F||)", what, i, fabs(sm[i]),
               SL[i], e);
    st->sigma = fmax(st->sigma, e);
  }

  /* singular vectors where sigma_i is separated: equal up to sign, signs paired */
  for (int i = 0; i < 3; ++i) {
    double gap = INFINITY;
    for (int j = 0; j < 3; ++j)
      if (j != i) gap = fmin(gap, fabs(SL[i] - SL[j]));
    if (!(gap > 1e-3 * scale)) continue; /* repeated (or nearly): vectors not unique */
    double um[3], ul[3], vm[3], vl[3];
    column(Um, i, um);
    column(UL, i, ul);
    column(Vm, i, vm);
    column(VL, i, vl);
    double du = 0, dv = 0, eu_p = 0, eu_m = 0, ev_p = 0, ev_m = 0;
    for (int k = 0; k < 3; ++k) {
      du += um[k] * ul[k];
      dv += vm[k] * vl[k];
      eu_p = fmax(eu_p, fabs(um[k] - ul[k]));
      eu_m = fmax(eu_m, fabs(um[k] + ul[k]));
      ev_p = fmax(ev_p, fabs(vm[k] - vl[k]));
      ev_m = fmax(ev_m, fabs(vm[k] + vl[k]));
    }
    const double e = fmax(fmin(eu_p, eu_m), fmin(ev_p, ev_m));
    /* both sides err by about eps ||F|| / gap: mpm at TOL, LAPACK at double accuracy */
    const double bound = 4 * (tol + 4e-15) * scale / gap;
    if (e > bound)
      fail_msg("%s: singular vector %d differs from LAPACK's by %.3g (gap %.3g of ||F||, "
               "bound %.3g)",
               what, i, e, gap / scale, bound);
    /* sigma_i u_i v_i^T must be the same rank-one term: the signs of u and v flip together,
     * or oppositely when mpm's sigma_i is the negative one. Only meaningful when sigma_i is
     * clearly nonzero. */
    if (SL[i] > 1e3 * tol * scale) {
      const double su = du < 0 ? -1 : 1, sv = dv < 0 ? -1 : 1, ss = sm[i] < 0 ? -1 : 1;
      if (su * sv * ss < 0)
        fail_msg("%s: sign pairing of singular pair %d differs from LAPACK's (u.u' %.3g, "
                 "v.v' %.3g, sigma %.9g)",
                 what, i, du, dv, sm[i]);
    }
    st->vec = fmax(st->vec, e);
    st->vec_scaled = fmax(st->vec_scaled, e * gap / scale);
    st->vec_count++;
  }

  st->recon_mpm = fmax(st->recon_mpm, rm);
  st->recon_lapack = fmax(st->recon_lapack, rl);
  st->ortho_mpm = fmax(st->ortho_mpm, om);
  st->ortho_lapack = fmax(st->ortho_lapack, ol);
  st->count++;
}

static void check(const double F64[9], int cls, const char *what) {
  for (int path = 0; path < TEST_SVD_PATHS; ++path) check_path(path, F64, cls, what);
}

/* Q1 diag(s) Q2^T with random rotations, for given s (any signs, any order). */
static void check_with_sigma(uint64_t *rng, const double s[3], int cls, const char *what) {
  double Q1[9], Q2[9], F[9];
  rand_rotation(rng, Q1);
  rand_rotation(rng, Q2);
  compose(Q1, s, Q2, F);
  check(F, cls, what);
}

/* ---- the classes ------------------------------------------------------------------------ */

static void test_random(void **state) {
  (void)state;
  uint64_t rng = 101;
  for (int t = 0; t < 10000; ++t) {
    double F[9];
    const double sc = pow(10.0, test_rand(&rng, -6, 6));
    for (int i = 0; i < 9; ++i) F[i] = sc * test_rand(&rng, -1, 1);
    check(F, C_RANDOM, "random entries");
    double s[3];
    for (int i = 0; i < 3; ++i) s[i] = test_rand(&rng, 0.2, 3.0);
    check_with_sigma(&rng, s, C_RANDOM, "random well-conditioned");
  }
  for (int t = 0; t < 200; ++t) { /* tiny and huge */
    double s[3];
    const double sc = (t & 1) ? 1e-30 : 1e30;
    for (int i = 0; i < 3; ++i) s[i] = sc * test_rand(&rng, 0.2, 3.0);
    check_with_sigma(&rng, s, C_RANDOM, "tiny/huge scale");
  }
}

static void test_near_singular(void **state) {
  (void)state;
  uint64_t rng = 102;
  for (int t = 0; t < 5000; ++t) {
    double s[3] = {test_rand(&rng, 0.5, 2), test_rand(&rng, 0.5, 2), 1e-6};
    if (t & 1) s[2] = -1e-6; /* nearly flat and inverted */
    if (t % 3 == 0) s[2] *= test_rand(&rng, 0.5, 5);
    check_with_sigma(&rng, s, C_NEAR_SINGULAR, "near-singular");
  }
}

static void test_rank_deficient(void **state) {
  (void)state;
  uint64_t rng = 103;
  for (int t = 0; t < 5000; ++t) {
    double s[3] = {test_rand(&rng, 0.5, 2), test_rand(&rng, 0.5, 2), 0};
    if (t % 3 == 1) s[1] = 0;           /* rank 1 */
    if (t % 3 == 2) s[0] = s[1] = 1e-3; /* rank 2, two equal sigma at a small scale */
    check_with_sigma(&rng, s, C_RANK_DEFICIENT, "rank-deficient");
  }
  const double F1[9] = {1, 2, 3, 2, 4, 6, 0, 1, 1};
  check(F1, C_RANK_DEFICIENT, "integer rank 2");
  const double F2[9] = {1, 2, 3, 2, 4, 6, -1, -2, -3};
  check(F2, C_RANK_DEFICIENT, "integer rank 1");
}

static void test_repeated(void **state) {
  (void)state;
  uint64_t rng = 104;
  const double Id[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  check(Id, C_REPEATED, "identity");
  for (int t = 0; t < 3000; ++t) {
    double Q[9];
    rand_rotation(&rng, Q);
    check(Q, C_REPEATED, "rotation");
    const double a = test_rand(&rng, 0.2, 3), b = test_rand(&rng, 0.2, 3);
    const double s1[3] = {a, a, b}, s2[3] = {a, b, b}, s3[3] = {a, a, a}, s4[3] = {a, a, -a};
    const double s5[3] = {a, b, -b};
    check_with_sigma(&rng, s1, C_REPEATED, "two equal (a a b)");
    check_with_sigma(&rng, s2, C_REPEATED, "two equal (a b b)");
    check_with_sigma(&rng, s3, C_REPEATED, "three equal");
    check_with_sigma(&rng, s4, C_REPEATED, "three equal, inverted");
    check_with_sigma(&rng, s5, C_REPEATED, "two equal magnitude, inverted");
  }
}

static void test_inverted(void **state) {
  (void)state;
  uint64_t rng = 105;
  for (int t = 0; t < 10000; ++t) {
    double s[3];
    for (int i = 0; i < 3; ++i) s[i] = test_rand(&rng, 0.1, 3.0);
    s[t % 3] = -s[t % 3]; /* one negative in any position */
    if (t % 4 == 0)       /* three negative */
      for (int i = 0; i < 3; ++i) s[i] = -s[i];
    check_with_sigma(&rng, s, C_INVERTED, "inverted");
  }
  const double Rx[9] = {-1, 0, 0, 0, 1, 0, 0, 0, 1};
  check(Rx, C_INVERTED, "reflection");
  const double mI[9] = {-1, 0, 0, 0, -1, 0, 0, 0, -1};
  check(mI, C_INVERTED, "-I");
}

static void test_diagonal(void **state) {
  (void)state;
  uint64_t rng = 106;
  for (int t = 0; t < 5000; ++t) {
    double s[3], F[9] = {0};
    for (int i = 0; i < 3; ++i) s[i] = test_rand(&rng, -3, 3);
    if (t % 5 == 0) s[1] = s[0];
    if (t % 11 == 0) s[2] = 0;
    for (int i = 0; i < 3; ++i) F[4 * i] = s[i];
    check(F, C_DIAGONAL, "diagonal");
    double P[9] = {0};
    P[1] = s[0];
    P[5] = s[1];
    P[6] = s[2];
    check(P, C_DIAGONAL, "permuted diagonal");
  }
}

static void test_zero(void **state) {
  (void)state;
  const double Z[9] = {0};
  check(Z, C_ZERO, "F = 0");
  mpm_real F[9] = {0}, U[9], s[3], V[9];
  for (int path = 0; path < TEST_SVD_PATHS; ++path) {
    test_svd_path(path, F, U, s, V);
    for (int i = 0; i < 3; ++i) assert_true(s[i] == 0);
  }
}

static void test_report(void **state) {
  (void)state;
  for (int path = 0; path < TEST_SVD_PATHS; ++path) {
    stats all = {.name = "all"};
    print_message("%s (%s) vs LAPACKE_dgesvd (double); sigma and vector errors relative to "
                  "||F||_2, reconstruction relative to ||F||_F\n",
                  test_svd_path_name[path], MPM_REAL_NAME);
    print_message("%-15s %6s %10s %11s %11s %11s %11s %10s %12s\n", "class", "count", "sigma",
                  "recon mpm", "recon LAPACK", "ortho mpm", "ortho LAPACK", "vectors",
                  "vec*gap/|F|");
    for (int c = 0; c < C_COUNT; ++c) {
      const stats *st = &g_stats[path][c];
      print_message("%-15s %6ld %10.3g %11.3g %11.3g %11.3g %11.3g %10.3g %12.3g\n", CLASS_NAME[c],
                    st->count, st->sigma, st->recon_mpm, st->recon_lapack, st->ortho_mpm,
                    st->ortho_lapack, st->vec, st->vec_scaled);
      all.count += st->count;
      all.sigma = fmax(all.sigma, st->sigma);
      all.recon_mpm = fmax(all.recon_mpm, st->recon_mpm);
      all.recon_lapack = fmax(all.recon_lapack, st->recon_lapack);
      all.ortho_mpm = fmax(all.ortho_mpm, st->ortho_mpm);
      all.ortho_lapack = fmax(all.ortho_lapack, st->ortho_lapack);
      all.vec = fmax(all.vec, st->vec);
      all.vec_scaled = fmax(all.vec_scaled, st->vec_scaled);
      assert_true(st->count > 0); /* every class ran on every path */
    }
    print_message("%-15s %6ld %10.3g %11.3g %11.3g %11.3g %11.3g %10.3g %12.3g\n", all.name,
                  all.count, all.sigma, all.recon_mpm, all.recon_lapack, all.ortho_mpm,
                  all.ortho_lapack, all.vec, all.vec_scaled);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_random),         cmocka_unit_test(test_near_singular),
      cmocka_unit_test(test_rank_deficient), cmocka_unit_test(test_repeated),
      cmocka_unit_test(test_inverted),       cmocka_unit_test(test_diagonal),
      cmocka_unit_test(test_zero),           cmocka_unit_test(test_report),
  };
  return cmocka_run_group_tests_name("svd3 vs LAPACK", tests, NULL, NULL);
}
