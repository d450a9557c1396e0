/* test_cg.c - the conjugate gradient solver of the DOF set (solver/cg.h) on an independent
 * symmetric positive definite operator A = D (x) I + L (x) C (D a positive diagonal, L a
 * weighted graph Laplacian over the DOFs, C a 3x3 SPD coupling of the components):
 *   - A x = b is solved to the tolerance and x equals the x* that made b;
 *   - the Jacobi diagonal cuts the iterations of a badly scaled D;
 *   - with a projection (sticky DOFs: a component fixed at zero; slip DOFs: a normal removed)
 *     the solution stays in the admissible subspace and its projected residual is small;
 *   - the solution and the iteration count are bitwise the same for 1 and 2 threads. */
#include "support.h"
#include "core/parallel.h"
#include "solver/cg.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define N 3000

typedef struct system {
  mpm_dofs d;
  mpm_real *pos[3];
  double D[N], Lw[N]; /* edge weights of i ~ i + 1 and i ~ i + 17 (Lw[i] for both) */
  double C[9];
} system_t;

static void apply(void *user, mpm_real *const x[3], mpm_real *const y[3]) {
  const system_t *s = user;
  for (long i = 0; i < N; ++i)
    for (int c = 0; c < 3; ++c) {
      double v = s->D[i] * x[c][i];
      const long nb[4] = {i - 1, i + 1, i - 17, i + 17};
      for (int e = 0; e < 3; ++e) {
        double lap = 0;
        for (int k = 0; k < 4; ++k) {
          if (nb[k] < 0 || nb[k] >= N) continue;
          const long lo = nb[k] < i ? nb[k] : i;
          lap += s->Lw[lo] * ((double)x[e][i] - x[e][nb[k]]);
        }
        v += s->C[3 * c + e] * lap;
      }
      y[c][i] = (mpm_real)v;
    }
}

static const double SLIP_N[3] = {0.70710678118654752, 0.70710678118654752, 0};
static void project(void *user, mpm_real *const v[3]) {
  (void)user;
  for (long i = 0; i < N; ++i) {
    if (i % 35 == 0) { /* both: y fixed and no motion along n, so x is fixed too */
      v[0][i] = v[1][i] = 0;
    } else if (i % 5 == 0) { /* sticky in y */
      v[1][i] = 0;
    } else if (i % 7 == 0) { /* slip: the normal part removed */
      const double vn = SLIP_N[0] * v[0][i] + SLIP_N[1] * v[1][i] + SLIP_N[2] * v[2][i];
      for (int c = 0; c < 3; ++c) v[c][i] -= (mpm_real)(vn * SLIP_N[c]);
    }
  }
}

static void make(system_t *s, double scale_spread, uint64_t seed) {
  memset(s, 0, sizeof *s);
  uint64_t rng = seed;
  for (int i = 0; i < N; ++i) {
    s->D[i] = pow(10, test_rand(&rng, -scale_spread, scale_spread));
    s->Lw[i] = test_rand(&rng, 0.1, 1);
  }
  const double C[9] = {1.0, 0.3, 0.1, 0.3, 0.8, 0.2, 0.1, 0.2, 0.6}; /* SPD */
  memcpy(s->C, C, sizeof C);
  for (int c = 0; c < 3; ++c) s->pos[c] = calloc(N, sizeof(mpm_real));
  mpm_dofs_init(&s->d);
  mpm_dofs_begin_layout(&s->d);
  assert_int_equal(mpm_dofs_add_corners(&s->d, N, (const mpm_real *const *)s->pos), MPM_OK);
  assert_int_equal(mpm_dofs_end_layout(&s->d, MPM_DOF_V), MPM_OK);
}

static void release(system_t *s) {
  mpm_dofs_free(&s->d);
  for (int c = 0; c < 3; ++c) free(s->pos[c]);
}

/* b = A x* for a random x*, x = 0; returns the iteration count. */
static int solve(system_t *s, int jacobi, int projected, double tol, mpm_cg_result *res,
                 double *err) {
  mpm_real **xs = mpm_dofs_vector(&s->d, "x*"), **b = mpm_dofs_vector(&s->d, "b");
  mpm_real **diag = mpm_dofs_vector(&s->d, "diag"), **x = s->d.v;
  uint64_t rng = 3;
  for (int i = 0; i < N; ++i)
    for (int c = 0; c < 3; ++c) {
      xs[c][i] = (mpm_real)test_rand(&rng, -1, 1);
      x[c][i] = 0;
      /* the diagonal of A: D + (sum of incident edge weights) C_cc */
      double deg = 0;
      const long nb[4] = {i - 1, i + 1, i - 17, i + 17};
      for (int k = 0; k < 4; ++k)
        if (nb[k] >= 0 && nb[k] < N) deg += s->Lw[nb[k] < i ? nb[k] : i];
      diag[c][i] = (mpm_real)(s->D[i] + deg * s->C[4 * c]);
    }
  if (projected) project(s, xs);
  apply(s, xs, b);
  const mpm_cg_options o = {tol, 2000, 0, 0, NULL, NULL, 0, NULL};
  assert_int_equal(mpm_cg_solve(&s->d, apply, projected ? project : NULL, s, jacobi ? diag : NULL,
                                b, x, &o, res),
                   MPM_OK);
  double e = 0, xn = 0;
  for (int i = 0; i < N; ++i)
    for (int c = 0; c < 3; ++c) {
      e = fmax(e, fabs((double)x[c][i] - xs[c][i]));
      xn = fmax(xn, fabs((double)xs[c][i]));
    }
  *err = e / xn;
  return res->iterations;
}

static void test_solves_spd_system(void **state) {
  (void)state;
  system_t s;
  make(&s, 0.5, 1);
  mpm_cg_result r;
  double err;
  solve(&s, 1, 0, TOL(1e-6, 1e-12), &r, &err);
  assert_true(r.converged);
  assert_true(r.residual <= TOL(1e-6, 1e-12) * r.residual0);
  if (err > TOL(1e-4, 1e-10)) fail_msg("x differs from x* by %g (relative)", err);
  release(&s);
}

static void test_jacobi_helps_badly_scaled(void **state) {
  (void)state;
  system_t s;
  make(&s, 2.5, 2); /* D over five decades */
  mpm_cg_result plain, jac;
  double e1, e2;
  solve(&s, 0, 0, TOL(1e-5, 1e-10), &plain, &e1);
  solve(&s, 1, 0, TOL(1e-5, 1e-10), &jac, &e2);
  print_message("CG iterations, D over five decades: %d without, %d with Jacobi\n",
                plain.iterations, jac.iterations);
  assert_true(jac.converged);
  assert_true(jac.iterations * 2 < plain.iterations || !plain.converged);
  release(&s);
}

static void test_projection_and_threads(void **state) {
  (void)state;
  system_t s;
  make(&s, 1, 3);
  mpm_cg_result r1, r2;
  double err;
  mpm_set_threads(1);
  solve(&s, 1, 1, TOL(1e-6, 1e-12), &r1, &err);
  mpm_real *x1[3];
  for (int c = 0; c < 3; ++c) {
    x1[c] = malloc(N * sizeof(mpm_real));
    memcpy(x1[c], s.d.v[c], N * sizeof(mpm_real));
  }
  mpm_set_threads(2);
  solve(&s, 1, 1, TOL(1e-6, 1e-12), &r2, &err);
  assert_true(r1.converged);
  assert_int_equal(r1.iterations, r2.iterations);
  for (int c = 0; c < 3; ++c) assert_memory_equal(x1[c], s.d.v[c], N * sizeof(mpm_real));
  /* the solution is admissible: P x = x, and it is the projected x* */
  for (int i = 0; i < N; ++i) {
    if (i % 5 == 0) assert_true(s.d.v[1][i] == 0);
    if (i % 7 == 0) {
      const double vn = SLIP_N[0] * s.d.v[0][i] + SLIP_N[1] * s.d.v[1][i];
      assert_close(vn, 0, TOL(1e-5, 1e-12));
    }
  }
  if (err > TOL(1e-4, 1e-10)) fail_msg("projected solve: x differs from x* by %g", err);
  for (int c = 0; c < 3; ++c) free(x1[c]);
  release(&s);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_solves_spd_system),
      cmocka_unit_test(test_jacobi_helps_badly_scaled),
      cmocka_unit_test(test_projection_and_threads),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
