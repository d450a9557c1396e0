/* test_transfer_operators.c - the separate transfer operators (transfer/operators.h) against
 * independent truth, on the sparse grid and the dense reference, for every kernel:
 *   - mass, momentum (APIC affine part included) and the stress divergence equal sums made
 *     here particle by particle from the kernel's stencil and the model's stress (P F^T);
 *   - mass and momentum plus the stress divergence equal the fused PIC/FLIP P2G;
 *   - the gradient gather of a linear field is its matrix at every particle (B-splines and
 *     uGIMP reproduce linear fields: sum_i x_i grad w_ip^T = I, sum_i grad w_ip = 0);
 *   - the matrix scatter and the gradient gather are adjoint;
 *   - sparse equals dense node by node, and 1 and 2 threads give bitwise the same results. */
#include "support.h"
#include "scene/scene.h"
#include "core/parallel.h"
#include "grid/dofs.h"
#include "transfer/operators.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define NP 700

typedef struct world {
  mpm_particles p;
  mpm_material mat[2];
  mpm_transfer_ctx ctx;
  mpm_grid grid;
  mpm_arena scratch;
  mpm_dofs dofs;
  mpm_grid_values val;
} world;

static const mpm_real ORIGIN[3] = {(mpm_real)-0.2, (mpm_real)0.1, (mpm_real)0.3};
#define DX ((mpm_real)0.05)
#define NODES 24 /* dense: nodes per axis */

static void world_make(world *w, mpm_kernel_kind kind, mpm_transfer_kind transfer,
                       mpm_grid_kind grid, uint64_t seed) {
  memset(w, 0, sizeof *w);
  mpm_particles_init(&w->p, NP);
  uint64_t rng = seed;
  for (int i = 0; i < NP; ++i) {
    mpm_real x[3], v[3];
    for (int d = 0; d < 3; ++d) {
      x[d] = ORIGIN[d] + DX * (mpm_real)test_rand(&rng, 4, NODES - 6);
      v[d] = (mpm_real)test_rand(&rng, -1, 1);
    }
    const long k = mpm_particles_push(&w->p, x, v, (mpm_real)test_rand(&rng, 0.5, 1.5),
                                      (mpm_real)test_rand(&rng, 1e-5, 2e-5), i % 3 == 0, 0);
    for (int c = 0; c < 9; ++c) {
      w->p.F[c][k] = (c % 4 == 0 ? 1 : 0) + (mpm_real)test_rand(&rng, -0.2, 0.2);
      w->p.B[c][k] = (mpm_real)test_rand(&rng, -1e-3, 1e-3);
    }
  }
  mpm_material_desc md = mpm_material_desc_default();
  md.model = MPM_MODEL_NEO_HOOKEAN;
  md.E = 1e4;
  mpm_material_init(&w->mat[0], &md);
  md.model = MPM_MODEL_FIXED_COROTATED;
  md.E = 3e4;
  mpm_material_init(&w->mat[1], &md);
  mpm_transfer_ctx *t = &w->ctx;
  t->kernel = mpm_kernel_make(kind, DX, DX * (mpm_real)0.6);
  t->dt = (mpm_real)1e-3;
  t->transfer = transfer;
  t->flip_alpha = (mpm_real)0.95;
  t->materials = w->mat;
  t->material_count = 2;
  for (int d = 0; d < 3; ++d) {
    t->origin[d] = ORIGIN[d];
    t->clamp_lo[d] = -100;
    t->clamp_hi[d] = 100;
  }
  const int n[3] = {NODES, NODES, NODES};
  if (grid == MPM_GRID_SPARSE)
    mpm_grid_init_sparse(&w->grid, 0, ORIGIN, DX);
  else
    assert_int_equal(mpm_grid_init_dense(&w->grid, 0, ORIGIN, DX, n), MPM_OK);
  mpm_arena_init(&w->scratch);
  assert_int_equal(w->grid.ops->activate(&w->grid, &t->kernel, 2, &w->p, &w->scratch), MPM_OK);
  mpm_dofs_init(&w->dofs);
  mpm_dofs_begin_layout(&w->dofs);
  assert_int_equal(mpm_dofs_add_grid(&w->dofs, &w->grid), MPM_OK);
  assert_int_equal(mpm_dofs_end_layout(&w->dofs, MPM_DOF_ALL), MPM_OK);
  mpm_dofs_clear(&w->dofs, MPM_DOF_ALL);
  w->val = mpm_dofs_grid_values(&w->dofs, &w->grid);
}

static void world_free(world *w) {
  mpm_particles_free(&w->p);
  mpm_dofs_free(&w->dofs);
  mpm_grid_free(&w->grid);
  mpm_arena_free(&w->scratch);
}

/* The DOF of node idx of the level (independently of the transfer code: through the block
 * hash for the sparse grid, the row-major numbering for the dense one). */
static size_t node_dof(const world *w, const int idx[3]) {
  if (w->grid.kind == MPM_GRID_DENSE) return ((size_t)idx[0] * NODES + idx[1]) * NODES + idx[2];
  const int32_t b[3] = {idx[0] >> 2, idx[1] >> 2, idx[2] >> 2};
  const int32_t blk = mpm_sparse_grid_find(&w->grid.impl.sparse, b);
  assert_true(blk >= 0);
  return (size_t)blk * 64 + (size_t)(((idx[0] & 3) * 4 + (idx[1] & 3)) * 4 + (idx[2] & 3));
}

/* Visit particle i's stencil: node DOF, weight, gradient, APIC factor vector. */
typedef void (*visit_fn)(void *u, size_t i, size_t n, double w, const double gw[3],
                         const double a[3]);
static void visit_stencil(const world *w, size_t i, visit_fn f, void *u) {
  const mpm_kernel *k = &w->ctx.kernel;
  const mpm_real xr[3] = {w->p.x[0][i] - ORIGIN[0], w->p.x[1][i] - ORIGIN[1],
                          w->p.x[2][i] - ORIGIN[2]};
  mpm_stencil s;
  mpm_kernel_stencil(k, xr, &s);
  for (int a = 0; a < k->width; ++a)
    for (int b = 0; b < k->width; ++b)
      for (int c = 0; c < k->width; ++c) {
        const int idx[3] = {s.base[0] + a, s.base[1] + b, s.base[2] + c};
        const double wx = s.w[0][a], wy = s.w[1][b], wz = s.w[2][c];
        const double gw[3] = {s.dw[0][a] * wy * wz, wx * s.dw[1][b] * wz, wx * wy * s.dw[2][c]};
        const double av[3] = {s.a[0][a] * wy * wz, wx * s.a[1][b] * wz, wx * wy * s.a[2][c]};
        f(u, i, node_dof(w, idx), wx * wy * wz, gw, av);
      }
}

typedef struct truth {
  const world *w;
  int apic;
  double *m, *q[3], *f[3];
  double K[9]; /* -V0 tau of the particle visited */
} truth;

static void add_truth(void *u, size_t i, size_t n, double wt, const double gw[3],
                      const double a[3]) {
  truth *t = u;
  const mpm_particles *p = &t->w->p;
  t->m[n] += wt * p->mass[i];
  for (int d = 0; d < 3; ++d) {
    double q = wt * p->mass[i] * p->v[d][i];
    if (t->apic)
      for (int e = 0; e < 3; ++e) q += p->mass[i] * p->B[3 * d + e][i] * a[e];
    t->q[d][n] += q;
    for (int e = 0; e < 3; ++e) t->f[d][n] += t->K[3 * d + e] * gw[e];
  }
}

static void check_mass_momentum_force(mpm_kernel_kind kind, mpm_transfer_kind transfer,
                                      mpm_grid_kind grid) {
  world w;
  world_make(&w, kind, transfer, grid, 41 + (uint64_t)kind);
  mpm_p2g_mass_momentum(&w.ctx, &w.grid, &w.val, &w.p);
  mpm_p2g_stress_force(&w.ctx, &w.grid, w.val.f, &w.p);
  const size_t nd = w.dofs.count;
  truth t = {&w, transfer == MPM_TRANSFER_APIC, calloc(nd, sizeof(double)), {0}, {0}, {0}};
  for (int d = 0; d < 3; ++d) {
    t.q[d] = calloc(nd, sizeof(double));
    t.f[d] = calloc(nd, sizeof(double));
  }
  double fbig = 0, qmax = 0, mmax = 0;
  for (size_t i = 0; i < w.p.count; ++i) {
    const mpm_material *mat = &w.mat[w.p.material[i]];
    mpm_real F[9], P[9];
    for (int c = 0; c < 9; ++c) F[c] = w.p.F[c][i];
    mat->model->pk1(mat, F, P);
    for (int r = 0; r < 3; ++r) /* tau = P F^T */
      for (int c = 0; c < 3; ++c) {
        double s = 0;
        for (int e = 0; e < 3; ++e) s += (double)P[3 * r + e] * F[3 * c + e];
        t.K[3 * r + c] = -(double)w.p.vol0[i] * s;
      }
    visit_stencil(&w, i, add_truth, &t);
  }
  for (size_t n = 0; n < nd; ++n) {
    mmax = fmax(mmax, t.m[n]);
    for (int d = 0; d < 3; ++d) {
      qmax = fmax(qmax, fabs(t.q[d][n]));
      fbig = fmax(fbig, fabs(t.f[d][n]));
    }
  }
  assert_true(mmax > 0 && qmax > 0 && fbig > 0);
  const double tol = TOL(2e-5, 1e-11);
  for (size_t n = 0; n < nd; ++n) {
    assert_close(w.val.mass[n], t.m[n], tol * mmax);
    for (int d = 0; d < 3; ++d) {
      assert_close(w.val.v0[d][n], t.q[d][n], tol * qmax);
      assert_close(w.val.f[d][n], t.f[d][n], TOL(5e-5, 1e-10) * fbig);
    }
  }
  /* PIC/FLIP: the fused P2G gives the same mass, momentum and force */
  if (transfer == MPM_TRANSFER_FLIP) {
    world v;
    world_make(&v, kind, transfer, grid, 41 + (uint64_t)kind);
    mpm_p2g(&v.ctx, &v.grid, &v.val, &v.p);
    for (size_t n = 0; n < nd; ++n) {
      assert_close(v.val.mass[n], w.val.mass[n], tol * mmax);
      for (int d = 0; d < 3; ++d) {
        assert_close(v.val.v0[d][n], w.val.v0[d][n], tol * qmax);
        assert_close(v.val.f[d][n], w.val.f[d][n], TOL(5e-5, 1e-10) * fbig);
      }
    }
    world_free(&v);
  }
  free(t.m);
  for (int d = 0; d < 3; ++d) {
    free(t.q[d]);
    free(t.f[d]);
  }
  world_free(&w);
}

static void test_mass_momentum_force(void **state) {
  (void)state;
  for (int kind = 0; kind < 4; ++kind)
    for (int grid = 0; grid < 2; ++grid) {
      check_mass_momentum_force((mpm_kernel_kind)kind, MPM_TRANSFER_APIC, (mpm_grid_kind)grid);
      check_mass_momentum_force((mpm_kernel_kind)kind, MPM_TRANSFER_FLIP, (mpm_grid_kind)grid);
    }
}

/* Per-particle matrices as 9 arrays. */
typedef struct mats {
  mpm_real *c[9];
} mats;
static mats mats_new(size_t n) {
  mats m;
  for (int k = 0; k < 9; ++k) m.c[k] = calloc(n, sizeof(mpm_real));
  return m;
}
static void mats_free(mats *m) {
  for (int k = 0; k < 9; ++k) free(m->c[k]);
}

static void test_gradient_of_linear_field(void **state) {
  (void)state;
  const double A[9] = {0.3, -1.2, 0.7, 2.0, 0.1, -0.4, -0.5, 0.9, 1.1}, bv[3] = {1, -2, 0.5};
  for (int kind = 0; kind < 4; ++kind)
    for (int grid = 0; grid < 2; ++grid) {
      world w;
      world_make(&w, (mpm_kernel_kind)kind, MPM_TRANSFER_APIC, (mpm_grid_kind)grid, 7);
      mpm_real **u = mpm_dofs_vector(&w.dofs, "u");
      for (size_t n = 0; n < w.dofs.count; ++n) {
        mpm_real x[3];
        mpm_dofs_position(&w.dofs, n, x);
        for (int d = 0; d < 3; ++d)
          u[d][n] = (mpm_real)(A[3 * d] * x[0] + A[3 * d + 1] * x[1] + A[3 * d + 2] * x[2] + bv[d]);
      }
      mats G = mats_new(w.p.count);
      mpm_gather_gradients(&w.ctx, &w.grid, (const mpm_real *const *)u, &w.p, G.c);
      for (size_t i = 0; i < w.p.count; ++i)
        for (int k = 0; k < 9; ++k)
          if (fabs(G.c[k][i] - A[k]) > TOL(2e-3, 1e-9))
            fail_msg("kernel %d, %s grid: G[%d] of particle %zu is %.8g, expected %.8g", kind,
                     grid ? "dense" : "sparse", k, i, (double)G.c[k][i], A[k]);
      mats_free(&G);
      world_free(&w);
    }
}

static void test_adjoint_threads_and_dense(void **state) {
  (void)state;
  for (int kind = 0; kind < 4; ++kind) {
    world s, d;
    world_make(&s, (mpm_kernel_kind)kind, MPM_TRANSFER_APIC, MPM_GRID_SPARSE, 13);
    world_make(&d, (mpm_kernel_kind)kind, MPM_TRANSFER_APIC, MPM_GRID_DENSE, 13);
    uint64_t rng = 77;
    mats M = mats_new(NP), G1 = mats_new(NP), G2 = mats_new(NP);
    for (int k = 0; k < 9; ++k)
      for (int i = 0; i < NP; ++i) M.c[k][i] = (mpm_real)test_rand(&rng, -1, 1);
    mpm_real **u = mpm_dofs_vector(&s.dofs, "u");
    for (size_t n = 0; n < s.dofs.count; ++n)
      for (int c = 0; c < 3; ++c) u[c][n] = (mpm_real)test_rand(&rng, -1, 1);
    /* scatter and gather with 1 and 2 threads */
    mpm_real **f1 = mpm_dofs_vector(&s.dofs, "f1"), **f2 = mpm_dofs_vector(&s.dofs, "f2");
    for (int c = 0; c < 3; ++c) {
      memset(f1[c], 0, s.dofs.count * sizeof(mpm_real));
      memset(f2[c], 0, s.dofs.count * sizeof(mpm_real));
    }
    mpm_set_threads(1);
    mpm_scatter_matrices(&s.ctx, &s.grid, f1, (const mpm_real *const *)M.c, &s.p);
    mpm_gather_gradients(&s.ctx, &s.grid, (const mpm_real *const *)u, &s.p, G1.c);
    mpm_set_threads(2);
    mpm_scatter_matrices(&s.ctx, &s.grid, f2, (const mpm_real *const *)M.c, &s.p);
    mpm_gather_gradients(&s.ctx, &s.grid, (const mpm_real *const *)u, &s.p, G2.c);
    for (int c = 0; c < 3; ++c) assert_memory_equal(f1[c], f2[c], s.dofs.count * sizeof(mpm_real));
    for (int k = 0; k < 9; ++k) assert_memory_equal(G1.c[k], G2.c[k], NP * sizeof(mpm_real));
    /* adjointness: sum_p <G_p(u), M_p> = sum_i <u_i, f_i(M)> */
    double lhs = 0, rhs = 0, scale = 0;
    for (int i = 0; i < NP; ++i)
      for (int k = 0; k < 9; ++k) {
        lhs += (double)G1.c[k][i] * M.c[k][i];
        scale += fabs((double)G1.c[k][i] * M.c[k][i]);
      }
    for (size_t n = 0; n < s.dofs.count; ++n)
      for (int c = 0; c < 3; ++c) rhs += (double)u[c][n] * f1[c][n];
    assert_close(lhs, rhs, TOL(1e-5, 1e-12) * scale);
    /* the dense reference, node by node at equal positions */
    mpm_real **fd = mpm_dofs_vector(&d.dofs, "f");
    for (int c = 0; c < 3; ++c) memset(fd[c], 0, d.dofs.count * sizeof(mpm_real));
    mpm_scatter_matrices(&d.ctx, &d.grid, fd, (const mpm_real *const *)M.c, &d.p);
    double fscale = 0;
    for (size_t n = 0; n < s.dofs.count; ++n)
      for (int c = 0; c < 3; ++c) fscale = fmax(fscale, fabs((double)f1[c][n]));
    for (size_t n = 0; n < s.dofs.count; ++n) {
      mpm_real x[3];
      mpm_dofs_position(&s.dofs, n, x);
      int idx[3], inside = 1;
      for (int c = 0; c < 3; ++c) {
        idx[c] = (int)lround((x[c] - ORIGIN[c]) / DX);
        inside &= idx[c] >= 0 && idx[c] < NODES;
      }
      const size_t m = inside ? node_dof(&d, idx) : 0;
      for (int c = 0; c < 3; ++c)
        assert_close(f1[c][n], inside ? fd[c][m] : 0, TOL(2e-5, 1e-12) * fscale);
    }
    mats_free(&M);
    mats_free(&G1);
    mats_free(&G2);
    world_free(&s);
    world_free(&d);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_mass_momentum_force),
      cmocka_unit_test(test_gradient_of_linear_field),
      cmocka_unit_test(test_adjoint_threads_and_dense),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
