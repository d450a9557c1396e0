/* test_mat3.c - the inline 3x3 math of src/core/mat3.h against independent double-precision
 * computations on random matrices: products (A B, A B^T, A^T B, A x), transpose, the
 * determinant against the Leibniz sum over permutations, the cofactor against det * A^{-T}
 * with A^{-1} from Gauss-Jordan elimination (and F^T cof(F) = det F I for singular F), the
 * inverse, the Frobenius product and trace, U diag(s) V^T, vector dot/cross/norm, and the
 * Rodrigues rotation: orthogonal with det +1, fixes its axis, and turns counter-clockwise
 * (right-hand rule) by the given angle. */
#include "support.h"
#include "core/mat3.h"

#include <math.h>

#define N_TRIALS 2000
static const double PI = 3.14159265358979323846;

/* relative tolerance of one product of O(1) entries in the build's precision */
static const double TOL_OP = TOL(2e-6, 1e-14);

static void rand_m(uint64_t *rng, mpm_real A[9], double Ad[9]) {
  for (int i = 0; i < 9; ++i) {
    A[i] = (mpm_real)test_rand(rng, -2, 2);
    Ad[i] = A[i];
  }
}

static void dmul(const double A[9], const double B[9], double C[9]) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) {
      double s = 0;
      for (int k = 0; k < 3; ++k) s += A[3 * r + k] * B[3 * k + c];
      C[3 * r + c] = s;
    }
}

static void dtrans(const double A[9], double B[9]) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) B[3 * c + r] = A[3 * r + c];
}

static void assert_m_close(const mpm_real A[9], const double B[9], double tol) {
  for (int i = 0; i < 9; ++i) assert_close(A[i], B[i], tol);
}

/* Leibniz: sum over the 6 permutations of sign(p) prod A[i][p(i)]. */
static double leibniz_det(const double A[9]) {
  static const int perm[6][3] = {{0, 1, 2}, {1, 2, 0}, {2, 0, 1}, {0, 2, 1}, {2, 1, 0}, {1, 0, 2}};
  static const int sign[6] = {1, 1, 1, -1, -1, -1};
  double d = 0;
  for (int p = 0; p < 6; ++p) d += sign[p] * A[perm[p][0]] * A[3 + perm[p][1]] * A[6 + perm[p][2]];
  return d;
}

/* Gauss-Jordan with partial pivoting; returns 0 for a singular matrix. */
static int gauss_jordan_inverse(const double A[9], double B[9]) {
  double M[3][6];
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 6; ++c) M[r][c] = c < 3 ? A[3 * r + c] : (c - 3 == r);
  for (int col = 0; col < 3; ++col) {
    int piv = col;
    for (int r = col + 1; r < 3; ++r)
      if (fabs(M[r][col]) > fabs(M[piv][col])) piv = r;
    if (M[piv][col] == 0) return 0;
    for (int c = 0; c < 6; ++c) {
      double t = M[col][c];
      M[col][c] = M[piv][c];
      M[piv][c] = t;
    }
    const double inv = 1 / M[col][col];
    for (int c = 0; c < 6; ++c) M[col][c] *= inv;
    for (int r = 0; r < 3; ++r) {
      if (r == col) continue;
      const double f = M[r][col];
      for (int c = 0; c < 6; ++c) M[r][c] -= f * M[col][c];
    }
  }
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) B[3 * r + c] = M[r][c + 3];
  return 1;
}

static void test_products(void **state) {
  (void)state;
  uint64_t rng = 11;
  for (int t = 0; t < N_TRIALS; ++t) {
    mpm_real A[9], B[9], C[9], x[3], y[3];
    double Ad[9], Bd[9], Cd[9], At[9], Bt[9];
    rand_m(&rng, A, Ad);
    rand_m(&rng, B, Bd);
    const double tol = 12 * TOL_OP;
    mpm_m3_mul(A, B, C);
    dmul(Ad, Bd, Cd);
    assert_m_close(C, Cd, tol);
    dtrans(Bd, Bt);
    mpm_m3_mul_bt(A, B, C);
    dmul(Ad, Bt, Cd);
    assert_m_close(C, Cd, tol);
    dtrans(Ad, At);
    mpm_m3_mul_at(A, B, C);
    dmul(At, Bd, Cd);
    assert_m_close(C, Cd, tol);
    mpm_m3_transpose(A, C);
    assert_m_close(C, At, 0);
    mpm_m3_copy(A, C);
    assert_m_close(C, Ad, 0);
    for (int i = 0; i < 3; ++i) x[i] = (mpm_real)test_rand(&rng, -2, 2);
    mpm_m3_mulv(A, x, y);
    for (int r = 0; r < 3; ++r)
      assert_close(y[r], Ad[3 * r] * x[0] + Ad[3 * r + 1] * x[1] + Ad[3 * r + 2] * x[2], tol);
    double dd = 0;
    for (int i = 0; i < 9; ++i) dd += Ad[i] * Bd[i];
    assert_close(mpm_m3_ddot(A, B), dd, 36 * TOL_OP);
    assert_close(mpm_m3_trace(A), Ad[0] + Ad[4] + Ad[8], tol);
  }
  mpm_real I[9];
  mpm_m3_identity(I);
  const double Id[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  assert_m_close(I, Id, 0);
}

static void test_det_cofactor_inverse(void **state) {
  (void)state;
  uint64_t rng = 12;
  for (int t = 0; t < N_TRIALS; ++t) {
    mpm_real A[9], C[9], B[9];
    double Ad[9], inv[9];
    rand_m(&rng, A, Ad);
    const double det = leibniz_det(Ad);
    assert_close(mpm_m3_det(A), det, 40 * TOL_OP);
    if (fabs(det) < 0.05) continue; /* keep the inverse well conditioned */
    assert_true(gauss_jordan_inverse(Ad, inv));
    /* cof(A) = det A^{-T} */
    mpm_m3_cofactor(A, C);
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) assert_close(C[3 * r + c], det * inv[3 * c + r], 20 * TOL_OP);
    /* inverse, and the determinant it returns */
    const mpm_real d = mpm_m3_inverse(A, B);
    assert_close(d, det, 40 * TOL_OP);
    /* perturbation bound: relative error ~ cond(A) eps */
    double na = 0, ni = 0, imax = 0;
    for (int i = 0; i < 9; ++i) {
      na += Ad[i] * Ad[i];
      ni += inv[i] * inv[i];
      imax = fmax(imax, fabs(inv[i]));
    }
    const double cond = sqrt(na * ni);
    for (int i = 0; i < 9; ++i) assert_close(B[i], inv[i], 20 * TOL_OP * cond * imax);
    /* and A A^{-1} = I */
    mpm_real P[9];
    mpm_m3_mul(A, B, P);
    for (int i = 0; i < 9; ++i) assert_close(P[i], (i % 4 == 0), 20 * TOL_OP * cond);
  }
  /* the cofactor stays meaningful for singular matrices: A^T cof(A) = det(A) I = 0 */
  for (int t = 0; t < N_TRIALS; ++t) {
    mpm_real A[9], C[9], P[9];
    double Ad[9];
    rand_m(&rng, A, Ad);
    for (int c = 0; c < 3; ++c) A[6 + c] = (mpm_real)(0.5 * A[c] - 0.25 * A[3 + c]);
    mpm_m3_cofactor(A, C);
    mpm_m3_mul_at(A, C, P);
    for (int i = 0; i < 9; ++i) assert_close(P[i], 0, 60 * TOL_OP);
    double cn = 0;
    for (int i = 0; i < 9; ++i) cn += (double)C[i] * C[i];
    assert_true(cn > 0 || fabs(mpm_m3_det(A)) == 0); /* rank 2: cof(A) != 0 in general */
  }
}

static void test_usvt_and_vectors(void **state) {
  (void)state;
  uint64_t rng = 13;
  for (int t = 0; t < N_TRIALS; ++t) {
    mpm_real U[9], V[9], s[3], A[9], a[3], b[3], c[3];
    double Ud[9], Vd[9], S[9] = {0}, T[9], Vt[9], E[9];
    rand_m(&rng, U, Ud);
    rand_m(&rng, V, Vd);
    for (int i = 0; i < 3; ++i) {
      s[i] = (mpm_real)test_rand(&rng, -2, 2);
      S[4 * i] = s[i];
      a[i] = (mpm_real)test_rand(&rng, -2, 2);
      b[i] = (mpm_real)test_rand(&rng, -2, 2);
    }
    mpm_m3_usvt(U, s, V, A);
    dmul(Ud, S, T);
    dtrans(Vd, Vt);
    dmul(T, Vt, E);
    assert_m_close(A, E, 50 * TOL_OP);
    assert_close(mpm_v3_dot(a, b), (double)a[0] * b[0] + (double)a[1] * b[1] + (double)a[2] * b[2],
                 12 * TOL_OP);
    mpm_v3_cross(a, b, c);
    assert_close(c[0], (double)a[1] * b[2] - (double)a[2] * b[1], 12 * TOL_OP);
    assert_close(c[1], (double)a[2] * b[0] - (double)a[0] * b[2], 12 * TOL_OP);
    assert_close(c[2], (double)a[0] * b[1] - (double)a[1] * b[0], 12 * TOL_OP);
    /* the cross product is orthogonal to both factors */
    assert_close(mpm_v3_dot(c, a), 0, 60 * TOL_OP);
    assert_close(mpm_v3_dot(c, b), 0, 60 * TOL_OP);
    assert_close(mpm_v3_norm(a),
                 sqrt((double)a[0] * a[0] + (double)a[1] * a[1] + (double)a[2] * a[2]),
                 12 * TOL_OP);
  }
}

static void test_axis_angle(void **state) {
  (void)state;
  uint64_t rng = 14;
  /* the textbook case: +90 degrees about z takes x to y */
  const mpm_real z[3] = {0, 0, 1}, ex[3] = {1, 0, 0};
  mpm_real R[9], y[3];
  mpm_m3_axis_angle(z, (mpm_real)(PI / 2), R);
  mpm_m3_mulv(R, ex, y);
  assert_close(y[0], 0, 4 * TOL_OP);
  assert_close(y[1], 1, 4 * TOL_OP);
  assert_close(y[2], 0, 4 * TOL_OP);
  for (int t = 0; t < N_TRIALS; ++t) {
    double ad[3], n = 0;
    for (int i = 0; i < 3; ++i) {
      ad[i] = test_rand(&rng, -1, 1);
      n += ad[i] * ad[i];
    }
    if (n < 1e-3) continue;
    n = sqrt(n);
    mpm_real a[3];
    for (int i = 0; i < 3; ++i) a[i] = (mpm_real)(ad[i] / n);
    const double th = test_rand(&rng, -PI, PI);
    mpm_m3_axis_angle(a, (mpm_real)th, R);
    /* a rotation: R^T R = I, det R = 1 */
    mpm_real P[9];
    mpm_m3_mul_at(R, R, P);
    for (int i = 0; i < 9; ++i) assert_close(P[i], (i % 4 == 0), 12 * TOL_OP);
    assert_close(mpm_m3_det(R), 1, 12 * TOL_OP);
    /* fixes its axis */
    mpm_m3_mulv(R, a, y);
    for (int i = 0; i < 3; ++i) assert_close(y[i], a[i], 12 * TOL_OP);
    /* v orthogonal to a goes to cos(th) v + sin(th) (a x v) (right-hand rule) */
    double v[3] = {test_rand(&rng, -1, 1), test_rand(&rng, -1, 1), test_rand(&rng, -1, 1)};
    const double ad2[3] = {a[0], a[1], a[2]};
    const double va = v[0] * ad2[0] + v[1] * ad2[1] + v[2] * ad2[2];
    for (int i = 0; i < 3; ++i) v[i] -= va * ad2[i];
    const double axv[3] = {ad2[1] * v[2] - ad2[2] * v[1], ad2[2] * v[0] - ad2[0] * v[2],
                           ad2[0] * v[1] - ad2[1] * v[0]};
    mpm_real vr[3] = {(mpm_real)v[0], (mpm_real)v[1], (mpm_real)v[2]};
    mpm_m3_mulv(R, vr, y);
    for (int i = 0; i < 3; ++i) assert_close(y[i], cos(th) * v[i] + sin(th) * axv[i], 20 * TOL_OP);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_products),
      cmocka_unit_test(test_det_cofactor_inverse),
      cmocka_unit_test(test_usvt_and_vectors),
      cmocka_unit_test(test_axis_angle),
  };
  return cmocka_run_group_tests_name("mat3", tests, NULL, NULL);
}
