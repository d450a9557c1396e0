/* test_embedding.c - the embedding operator (grid/embedding.h) against independent truth.
 *
 * Carriers at random points embedded in a dense grid level by the linear, quadratic and cubic
 * B-spline weights (rows built here from the kernel's 1D factors and the dense node numbering,
 * not by the domain code):
 *   - every row sums to one, so the transpose conserves mass and momentum;
 *   - E reproduces a linear field given at the nodes (the B-splines reproduce linear
 *     functions);
 *   - E and its transpose are adjoint: <E u, c> = <u, E^T c>;
 *   - the scheduled scatter is bitwise the same for 1 and 2 threads and equals the serial
 *     scatter to round-off; rows keyed -1 take no part;
 *   - identity rows (an enriched corner that is its own DOF) copy and add values unchanged. */
#include "support.h"
#include "core/parallel.h"
#include "grid/embedding.h"
#include "interp/kernel.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define N 20 /* nodes per axis of the level */
#define CARRIERS 500

typedef struct setup {
  mpm_real dx, origin[3];
  mpm_real *x[3];      /* carrier positions */
  int32_t *key;        /* base block of each carrier's stencil */
  uint8_t colour[125]; /* of the 5^3 blocks of 4^3 nodes */
  mpm_embedding E;
} setup;

static size_t node(int i, int j, int k) {
  return ((size_t)i * N + (size_t)j) * N + (size_t)k;
}

static void build(setup *s, mpm_kernel_kind kind, uint64_t seed) {
  memset(s, 0, sizeof *s);
  s->dx = (mpm_real)0.1;
  s->origin[0] = (mpm_real)-1;
  s->origin[1] = (mpm_real)0.5;
  s->origin[2] = (mpm_real)2;
  const mpm_kernel k = mpm_kernel_make(kind, s->dx, s->dx);
  uint64_t rng = seed;
  for (int d = 0; d < 3; ++d) s->x[d] = malloc(CARRIERS * sizeof(mpm_real));
  s->key = malloc(CARRIERS * sizeof *s->key);
  mpm_embedding_init(&s->E);
  assert_int_equal(mpm_embedding_layout(&s->E, CARRIERS, NULL, 64), MPM_OK);
  for (int a = 0; a < CARRIERS; ++a) {
    mpm_real xr[3];
    for (int d = 0; d < 3; ++d) {
      xr[d] = (mpm_real)test_rand(&rng, 3, N - 5) * s->dx; /* stencils stay in the level */
      s->x[d][a] = s->origin[d] + xr[d];
    }
    mpm_stencil st;
    mpm_kernel_stencil(&k, xr, &st);
    for (int i = 0; i < k.width; ++i)
      for (int j = 0; j < k.width; ++j)
        for (int l = 0; l < k.width; ++l) {
          const mpm_real w = st.w[0][i] * st.w[1][j] * st.w[2][l];
          mpm_embedding_push(&s->E, (size_t)a,
                             (uint32_t)node(st.base[0] + i, st.base[1] + j, st.base[2] + l), w);
        }
    const int b[3] = {st.base[0] >> 2, st.base[1] >> 2, st.base[2] >> 2};
    s->key[a] = (b[0] * 5 + b[1]) * 5 + b[2];
  }
  for (int b = 0; b < 125; ++b)
    s->colour[b] = (uint8_t)(((b / 25) & 1) << 2 | (((b / 5) % 5) & 1) << 1 | ((b % 5) & 1));
}

static void release(setup *s) {
  for (int d = 0; d < 3; ++d) free(s->x[d]);
  free(s->key);
  mpm_embedding_free(&s->E);
}

static void node_position(const setup *s, size_t n, mpm_real x[3]) {
  const int idx[3] = {(int)(n / (N * N)), (int)(n / N % N), (int)(n % N)};
  for (int d = 0; d < 3; ++d) x[d] = s->origin[d] + (mpm_real)idx[d] * s->dx;
}

static void check_kernel(mpm_kernel_kind kind) {
  setup s;
  build(&s, kind, 17 + (uint64_t)kind);
  const mpm_embedding *E = &s.E;
  /* partition of unity per row */
  for (size_t a = 0; a < E->rows; ++a) {
    double sum = 0;
    for (uint32_t e = E->row_start[a]; e < E->row_start[a] + E->row_len[a]; ++e) {
      assert_true(E->w[e] >= 0);
      sum += E->w[e];
    }
    assert_close(sum, 1, TOL(1e-6, 1e-14));
  }
  /* mass and momentum through the transpose */
  static mpm_real m[CARRIERS], p[CARRIERS], um[N * N * N], up[N * N * N];
  uint64_t rng = 3;
  double m_c = 0, p_c = 0;
  for (int a = 0; a < CARRIERS; ++a) {
    m[a] = (mpm_real)test_rand(&rng, 0.1, 2);
    p[a] = m[a] * (mpm_real)test_rand(&rng, -3, 3);
    m_c += m[a];
    p_c += p[a];
  }
  memset(um, 0, sizeof um);
  memset(up, 0, sizeof up);
  const mpm_real *c2[2] = {m, p};
  mpm_real *u2[2] = {um, up};
  mpm_embedding_scatter(E, 2, c2, u2);
  double m_u = 0, p_u = 0;
  for (size_t n = 0; n < N * N * N; ++n) {
    m_u += um[n];
    p_u += up[n];
  }
  assert_close(m_u, m_c, TOL(1e-5, 1e-13) * m_c);
  assert_close(p_u, p_c, TOL(1e-5, 1e-13) * m_c * 3);
  /* linear reproduction: u = A x + b at the nodes, gathered at the carriers */
  static mpm_real lin[3][N * N * N], got[3][CARRIERS];
  const double A[3][3] = {{0.3, -1.2, 0.7}, {2.0, 0.1, -0.4}, {-0.5, 0.9, 1.1}},
               bv[3] = {1, -2, 0.5};
  for (size_t n = 0; n < N * N * N; ++n) {
    mpm_real x[3];
    node_position(&s, n, x);
    for (int r = 0; r < 3; ++r)
      lin[r][n] = (mpm_real)(A[r][0] * x[0] + A[r][1] * x[1] + A[r][2] * x[2] + bv[r]);
  }
  const mpm_real *u3[3] = {lin[0], lin[1], lin[2]};
  mpm_real *c3[3] = {got[0], got[1], got[2]};
  mpm_embedding_gather(E, 3, u3, c3);
  for (int a = 0; a < CARRIERS; ++a)
    for (int r = 0; r < 3; ++r) {
      const double want = A[r][0] * s.x[0][a] + A[r][1] * s.x[1][a] + A[r][2] * s.x[2][a] + bv[r];
      assert_close(got[r][a], want, TOL(2e-5, 1e-12) * 8);
    }
  /* adjointness: <E u, c> = <u, E^T c> with u = lin[0], c = m */
  double lhs = 0, rhs = 0;
  for (int a = 0; a < CARRIERS; ++a) lhs += (double)got[0][a] * m[a];
  for (size_t n = 0; n < N * N * N; ++n) rhs += (double)lin[0][n] * um[n];
  assert_close(lhs, rhs, TOL(1e-4, 1e-11) * fabs(lhs));
  release(&s);
}

static void test_quadratic(void **state) {
  (void)state;
  check_kernel(MPM_KERNEL_QUADRATIC);
}

static void test_linear_and_cubic(void **state) {
  (void)state;
  check_kernel(MPM_KERNEL_LINEAR);
  check_kernel(MPM_KERNEL_CUBIC);
}

static void test_schedule(void **state) {
  (void)state;
  setup s;
  build(&s, MPM_KERNEL_QUADRATIC, 91);
  static mpm_real m[CARRIERS], serial[N * N * N], one[N * N * N], two[N * N * N];
  uint64_t rng = 5;
  for (int a = 0; a < CARRIERS; ++a) m[a] = (mpm_real)test_rand(&rng, -1, 1);
  const mpm_real *c[1] = {m};
  memset(serial, 0, sizeof serial);
  mpm_real *u[1] = {serial};
  mpm_embedding_scatter(&s.E, 1, c, u);
  s.key[7] = -1; /* row 7 takes no part */
  assert_int_equal(mpm_embedding_schedule(&s.E, s.key, 125, s.colour), MPM_OK);
  mpm_set_threads(1);
  memset(one, 0, sizeof one);
  u[0] = one;
  mpm_embedding_scatter(&s.E, 1, c, u);
  mpm_set_threads(2);
  memset(two, 0, sizeof two);
  u[0] = two;
  mpm_embedding_scatter(&s.E, 1, c, u);
  assert_memory_equal(one, two, sizeof one);
  /* the scheduled scatter is the serial one without row 7 */
  for (uint32_t e = s.E.row_start[7]; e < s.E.row_start[7] + s.E.row_len[7]; ++e)
    serial[s.E.col[e]] -= s.E.w[e] * m[7];
  for (size_t n = 0; n < N * N * N; ++n) assert_close(one[n], serial[n], TOL(1e-5, 1e-14));
  release(&s);
}

static void test_identity_rows(void **state) {
  (void)state;
  mpm_embedding E;
  mpm_embedding_init(&E);
  const uint32_t len[4] = {1, 1, 2, 1};
  assert_int_equal(mpm_embedding_layout(&E, 4, len, 0), MPM_OK);
  mpm_embedding_push(&E, 0, 5, 1);
  mpm_embedding_push(&E, 1, 2, 1);
  mpm_embedding_push(&E, 2, 2, (mpm_real)0.25); /* a T-junction-like row of two parents */
  mpm_embedding_push(&E, 2, 3, (mpm_real)0.75);
  mpm_embedding_push(&E, 3, 0, 1);
  mpm_real u[6] = {1, 2, 3, 4, 5, 6}, c[4];
  const mpm_real *uu[1] = {u};
  mpm_real *cc[1] = {c};
  mpm_embedding_gather(&E, 1, uu, cc);
  assert_true(c[0] == 6 && c[1] == 3 && c[3] == 1);
  assert_close(c[2], 0.25 * 3 + 0.75 * 4, 1e-6);
  mpm_real add[4] = {10, 20, 40, 30}, dof[6] = {0};
  const mpm_real *ca[1] = {add};
  mpm_real *ua[1] = {dof};
  mpm_embedding_scatter(&E, 1, ca, ua);
  assert_true(dof[5] == 10 && dof[0] == 30 && dof[2] == 30 && dof[3] == 30);
  mpm_embedding_free(&E);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_quadratic),
      cmocka_unit_test(test_linear_and_cubic),
      cmocka_unit_test(test_schedule),
      cmocka_unit_test(test_identity_rows),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
