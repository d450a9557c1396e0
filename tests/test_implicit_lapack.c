/* test_implicit_lapack.c - the implicit system of a small body assembled column by column
 * (A e_j, the matrix-free action on unit vectors) against LAPACK:
 *   - A is symmetric to round-off;
 *   - the Jacobi diagonal (Zhu eqs. 17-19, built without the action) equals A's diagonal;
 *   - CG's answer equals LAPACK's direct solve (dposv, Cholesky in double) to the CG
 *     tolerance, without and with boundary constraints (a slip floor and a sticky wall).
 * For material points (quadratic and linear kernels) and particle domains. */
#include "implicit_support.h"

#include <lapacke.h>
#include <stdlib.h>

/* Unknown k of the assembled system: DOF dof[k / 3], component k % 3 (massive DOFs only). */
typedef struct assembled {
  int n;
  size_t *dof;
  double *A, *b;
} assembled;

static void apply_fn(void *user, mpm_real *const x[3], mpm_real *const y[3]) {
  mpm_implicit *s = user;
  mpm_implicit_apply(s, 1, s->apply_scale, x, y);
}

static void check_system(mpm_sim *sim, int constrained, const char *what) {
  mpm_implicit s;
  assert_int_equal(mpm_sim_implicit_system(sim, 5e-3, &s), MPM_OK);
  mpm_dofs *d = s.dofs;
  mpm_real **e = mpm_dofs_vector(d, "t.e"), **Ae = mpm_dofs_vector(d, "t.Ae");
  mpm_real **diag = mpm_dofs_vector(d, "t.diag"), **x = mpm_dofs_vector(d, "t.x");
  mpm_real **b = mpm_dofs_vector(d, "t.b");
  assert_non_null(e && Ae && diag && x && b);
  mpm_implicit_displace(&s, NULL);
  mpm_implicit_build(&s);
  /* the constraints from a velocity that moves into every obstacle */
  for (size_t i = 0; i < d->count; ++i) x[0][i] = -1, x[1][i] = -1, x[2][i] = 0;
  mpm_boundary walls = *s.boundary; /* walls through the body: its bottom and +x layers */
  if (constrained) {
    walls.wall_lo[1] = (mpm_real)(0.59 - 0.08 + 0.5 * sim->scene.dx);
    walls.wall_hi[0] = (mpm_real)(0.62 + 0.1 - 0.5 * sim->scene.dx);
    walls.wall_rule = constrained == 1 ? MPM_BOUNDARY_SLIP : MPM_BOUNDARY_STICKY;
    s.boundary = &walls;
    assert_int_equal(mpm_implicit_constraints(&s, x), MPM_OK);
    assert_true(s.constraint_count > 0);
  }
  /* the unknowns: the massive DOFs */
  assembled a = {0};
  a.dof = calloc(3 * d->count, sizeof *a.dof);
  for (size_t i = 0; i < d->count; ++i)
    if (d->mass[i] > 0)
      for (int c = 0; c < 3; ++c) a.dof[a.n++] = 3 * i + (size_t)c;
  const int n = a.n;
  a.A = calloc((size_t)n * (size_t)n, sizeof *a.A);
  a.b = calloc((size_t)n, sizeof *a.b);
  assert_non_null(a.A && a.b);
  for (int c = 0; c < 3; ++c) memset(e[c], 0, d->count * sizeof(mpm_real));
  for (int j = 0; j < n; ++j) { /* column j = P A P e_j (+ (I - P) e_j: keep it invertible) */
    const size_t dj = a.dof[j] / 3;
    const int cj = (int)(a.dof[j] % 3);
    e[cj][dj] = 1;
    if (constrained) mpm_implicit_project(&s, e);
    apply_fn(&s, e, Ae);
    if (constrained) mpm_implicit_project(&s, Ae);
    for (int k = 0; k < n; ++k) a.A[(size_t)k * n + j] = Ae[a.dof[k] % 3][a.dof[k] / 3];
    for (int c = 0; c < 3; ++c) memset(e[c], 0, d->count * sizeof(mpm_real));
  }
  /* symmetric */
  double amax = 0, asym = 0;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      amax = fmax(amax, fabs(a.A[(size_t)i * n + j]));
      asym = fmax(asym, fabs(a.A[(size_t)i * n + j] - a.A[(size_t)j * n + i]));
    }
  assert_true(asym <= TOL(1e-5, 1e-12) * amax);
  /* the Jacobi diagonal is A's diagonal (unconstrained) */
  mpm_implicit_diagonal(&s, 1, s.apply_scale, diag);
  double dmax = 0;
  if (!constrained)
    for (int k = 0; k < n; ++k) {
      const double dk = diag[a.dof[k] % 3][a.dof[k] / 3], ak = a.A[(size_t)k * n + k];
      dmax = fmax(dmax, fabs(dk - ak) / fabs(ak));
    }
  assert_true(dmax <= TOL(1e-4, 1e-10));
  for (int c = 0; c < 3; ++c) /* massless DOFs: 1, as the solver's preconditioner has it */
    for (size_t i = 0; i < d->count; ++i)
      if (!(diag[c][i] > 0)) diag[c][i] = 1;
  /* rows of constrained components are zero: put 1 there so that A is invertible (DOFs with a
   * round-off mass, a corner on a node, stay: their equation is m x = m v* and K's) */
  for (int k = 0; k < n; ++k) {
    double row = 0;
    for (int j = 0; j < n; ++j) row += fabs(a.A[(size_t)k * n + j]);
    if (row == 0) a.A[(size_t)k * n + k] = 1;
  }
  /* b = P M v* for a random v*; CG from 0 */
  uint64_t rng = 5;
  implicit_random(d, &rng, x);
  for (int c = 0; c < 3; ++c)
    for (size_t i = 0; i < d->count; ++i) b[c][i] = d->mass[i] * x[c][i];
  if (constrained) mpm_implicit_project(&s, b);
  for (int k = 0; k < n; ++k) a.b[k] = b[a.dof[k] % 3][a.dof[k] / 3];
  for (int c = 0; c < 3; ++c) memset(x[c], 0, d->count * sizeof(mpm_real));
  const double tol = TOL(1e-5, 1e-10);
  const mpm_cg_options o = {tol, 10000, 0, 0, NULL, NULL, 0, NULL};
  mpm_cg_result r;
  assert_int_equal(mpm_cg_solve(d, apply_fn,
                                constrained ? (mpm_cg_project_fn)mpm_implicit_project : NULL, &s,
                                diag, b, x, &o, &r),
                   MPM_OK);
  if (!r.converged)
    fail_msg("%s: CG stopped at relative residual %.3g after %d iterations", what,
             r.residual / r.residual0, r.iterations);
  const int info = LAPACKE_dposv(LAPACK_ROW_MAJOR, 'U', n, 1, a.A, n, a.b, 1);
  assert_int_equal(info, 0); /* positive definite */
  double err = 0, ref = 0;
  for (int k = 0; k < n; ++k) {
    const double xk = x[a.dof[k] % 3][a.dof[k] / 3];
    err += (xk - a.b[k]) * (xk - a.b[k]);
    ref += a.b[k] * a.b[k];
  }
  const double rel = sqrt(err / ref);
  if (getenv("MPM_TEST_VERBOSE"))
    for (int k = 0; k < n; ++k) {
      const double xk = x[a.dof[k] % 3][a.dof[k] / 3];
      if (fabs(xk - a.b[k]) > 1e-3 * sqrt(ref / n))
        print_message("unknown %d (DOF %zu, mass %.3g): cg %.6g lapack %.6g\n", k, a.dof[k] / 3,
                      (double)d->mass[a.dof[k] / 3], xk, a.b[k]);
    }
  char jacobi[32] = "(constrained: n/a)";
  if (!constrained) snprintf(jacobi, sizeof jacobi, "%.1e", dmax);
  print_message("%-34s %4d unknowns: |A - A^T| / |A| = %.1e, Jacobi vs diag(A) %s, CG %3d "
                "iterations, |x_cg - x_lapack| / |x| = %.2e\n",
                what, n, asym / amax, jacobi, r.iterations, rel);
  /* the error is at most cond(A) times the residual; A is well conditioned here */
  assert_true(rel <= 100 * tol);
  free(a.dof);
  free(a.A);
  free(a.b);
}

static void test_points(void **state) {
  (void)state;
  static const char *const kernels[] = {"quadratic", "linear"};
  for (int k = 0; k < 2; ++k)
    for (int constrained = 0; constrained <= 2; ++constrained) {
      mpm_sim *sim = implicit_block("fixed_corotated", "", kernels[k], 0, "", 0.12, 8);
      char what[64];
      snprintf(what, sizeof what, "points, %s%s", kernels[k],
               constrained ? (constrained == 1 ? ", slip walls" : ", sticky walls") : "");
      check_system(sim, constrained, what);
      mpm_sim_destroy(sim);
    }
}

static void test_domains(void **state) {
  (void)state;
  mpm_sim *sim = implicit_block("neo_hookean", "", "quadratic", 1, "", 0.12, 8);
  check_system(sim, 0, "domains, linear corner weights");
  mpm_sim_destroy(sim);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_points),
      cmocka_unit_test(test_domains),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
