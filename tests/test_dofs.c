/* test_dofs.c - the DOF set (grid/dofs.h) and the explicit update over it
 * (solver/explicit_update.h), against independent truth:
 *   - layout: segments of a sparse level, a dense level and corners in order; every DOF's
 *     position and segment found by search equals the one enumerated box by box;
 *   - reductions: dot products and max norms equal a plain serial double sum (to round-off) and
 *     are bitwise the same for 1 and 2 threads; axpy and xpby match the formula; named vectors
 *     are found again by name and resized with the layout;
 *   - the explicit update: v^n = p/m and v^{n+1} = v^n + dt (f/m + g) per DOF, the fused form,
 *     massless DOFs zeroed, and the wall band by position: for every grid level it selects the
 *     nodes the index rule of one level selects (node index < wall cells), a finer level's
 *     half-cell nodes too, and corners exactly beyond the plane. */
#include "support.h"
#include "core/parallel.h"
#include "solver/explicit_update.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* A sparse level with the blocks around a few points, a dense level, and 37 corners. */
typedef struct fixture {
  mpm_grid sparse, dense;
  mpm_real *cx[3];
  mpm_dofs d;
} fixture;

#define CORNERS 37

static void fixture_make(fixture *f) {
  const mpm_real origin[3] = {(mpm_real)0.1, (mpm_real)-0.2, (mpm_real)0.05};
  mpm_grid_init_sparse(&f->sparse, 0, origin, (mpm_real)0.05);
  mpm_particles p;
  mpm_particles_init(&p, 16);
  const mpm_real x[4][3] = {
      {0.3f, 0.1f, 0.4f}, {0.9f, 0.2f, 0.4f}, {0.35f, 0.7f, 1.2f}, {0.32f, 0.12f, 0.45f}};
  const mpm_real v[3] = {0, 0, 0};
  for (int i = 0; i < 4; ++i) mpm_particles_push(&p, x[i], v, 1, 1, 0, 0);
  const mpm_kernel k = mpm_kernel_make(MPM_KERNEL_QUADRATIC, f->sparse.dx, f->sparse.dx);
  mpm_arena scratch;
  mpm_arena_init(&scratch);
  assert_int_equal(f->sparse.ops->activate(&f->sparse, &k, 1, &p, &scratch), MPM_OK);
  mpm_arena_free(&scratch);
  mpm_particles_free(&p);
  const int n[3] = {5, 3, 4};
  assert_int_equal(mpm_grid_init_dense(&f->dense, 1, origin, (mpm_real)0.025, n), MPM_OK);
  uint64_t rng = 7;
  for (int d = 0; d < 3; ++d) {
    f->cx[d] = malloc(CORNERS * sizeof(mpm_real));
    for (int c = 0; c < CORNERS; ++c) f->cx[d][c] = (mpm_real)test_rand(&rng, -1, 1);
  }
  mpm_dofs_init(&f->d);
  mpm_dofs_begin_layout(&f->d);
  assert_int_equal(mpm_dofs_add_grid(&f->d, &f->sparse), MPM_OK);
  assert_int_equal(mpm_dofs_add_grid(&f->d, &f->dense), MPM_OK);
  assert_int_equal(mpm_dofs_add_corners(&f->d, CORNERS, (const mpm_real *const *)f->cx), MPM_OK);
  assert_int_equal(mpm_dofs_end_layout(&f->d, MPM_DOF_ALL), MPM_OK);
}

static void fixture_free(fixture *f) {
  mpm_dofs_free(&f->d);
  mpm_grid_free(&f->sparse);
  mpm_grid_free(&f->dense);
  for (int d = 0; d < 3; ++d) free(f->cx[d]);
}

static void test_layout_and_positions(void **state) {
  (void)state;
  fixture f;
  fixture_make(&f);
  const size_t ns = f.sparse.ops->node_count(&f.sparse), nd = 5 * 3 * 4;
  assert_true(ns >= 8 * MPM_BLOCK_NODES); /* at least one owner block and its pad */
  assert_int_equal(f.d.count, ns + nd + CORNERS);
  assert_int_equal(f.sparse.dof_begin, 0);
  assert_int_equal(f.dense.dof_begin, ns);
  /* enumerate every grid DOF box by box, independently of mpm_dofs_position */
  const mpm_grid *levels[2] = {&f.sparse, &f.dense};
  size_t seen = 0;
  for (int l = 0; l < 2; ++l) {
    const mpm_grid *g = levels[l];
    for (size_t b = 0; b < g->ops->box_count(g); ++b) {
      const mpm_node_box box = g->ops->box(g, b);
      size_t i = g->dof_begin + box.first;
      for (int a = 0; a < box.n[0]; ++a)
        for (int e = 0; e < box.n[1]; ++e)
          for (int c = 0; c < box.n[2]; ++c, ++i) {
            const int idx[3] = {box.lo[0] + a, box.lo[1] + e, box.lo[2] + c};
            mpm_real x[3];
            mpm_dofs_position(&f.d, i, x);
            for (int d = 0; d < 3; ++d)
              assert_true(x[d] == g->origin[d] + (mpm_real)idx[d] * g->dx);
            const mpm_dof_segment *s = mpm_dofs_segment_of(&f.d, i);
            assert_int_equal(s->kind, MPM_DOF_GRID_NODE);
            assert_int_equal(s->level, g->level);
            ++seen;
          }
    }
  }
  assert_int_equal(seen, ns + nd);
  for (int c = 0; c < CORNERS; ++c) {
    mpm_real x[3];
    mpm_dofs_position(&f.d, ns + nd + (size_t)c, x);
    for (int d = 0; d < 3; ++d) assert_true(x[d] == f.cx[d][c]);
    assert_int_equal(mpm_dofs_segment_of(&f.d, ns + nd + (size_t)c)->kind, MPM_DOF_CORNER);
  }
  assert_null(mpm_dofs_segment_of(&f.d, f.d.count));
  fixture_free(&f);
}

static void test_reductions(void **state) {
  (void)state;
  fixture f;
  fixture_make(&f);
  mpm_real **a = mpm_dofs_vector(&f.d, "r"), **b = mpm_dofs_vector(&f.d, "p");
  assert_non_null(a);
  assert_non_null(b);
  assert_ptr_equal(mpm_dofs_vector(&f.d, "r"), a);
  uint64_t rng = 11;
  for (size_t i = 0; i < f.d.count; ++i) {
    f.d.mass[i] = (mpm_real)test_rand(&rng, 0, 2);
    for (int c = 0; c < 3; ++c) {
      a[c][i] = (mpm_real)test_rand(&rng, -1, 1);
      b[c][i] = (mpm_real)test_rand(&rng, -1, 1);
    }
  }
  double plain = 0, weighted = 0, amax = 0;
  for (size_t i = 0; i < f.d.count; ++i)
    for (int c = 0; c < 3; ++c) {
      plain += (double)a[c][i] * b[c][i];
      weighted += (double)f.d.mass[i] * a[c][i] * b[c][i];
      amax = fmax(amax, fabs((double)a[c][i]));
    }
  mpm_set_threads(1);
  const double d1 = mpm_dofs_dot(&f.d, NULL, a, b), w1 = mpm_dofs_dot(&f.d, f.d.mass, a, b);
  mpm_set_threads(2);
  const double d2 = mpm_dofs_dot(&f.d, NULL, a, b), w2 = mpm_dofs_dot(&f.d, f.d.mass, a, b);
  assert_true(memcmp(&d1, &d2, sizeof d1) == 0); /* bitwise, whatever the threads */
  assert_true(memcmp(&w1, &w2, sizeof w1) == 0);
  assert_close(d1, plain, 1e-12 * f.d.count);
  assert_close(w1, weighted, 1e-12 * f.d.count);
  assert_true(mpm_dofs_max_abs(&f.d, a) == amax);
  /* y = a + 0.5 b, then y += -2 a gives 0.5 b - a */
  mpm_real **y = mpm_dofs_vector(&f.d, "y");
  mpm_dofs_copy(&f.d, b, y);
  mpm_dofs_xpby(&f.d, a, (mpm_real)0.5, y);
  mpm_dofs_axpy(&f.d, (mpm_real)-2, a, y);
  for (size_t i = 0; i < f.d.count; i += 17)
    for (int c = 0; c < 3; ++c)
      assert_close(y[c][i], (mpm_real)0.5 * b[c][i] - a[c][i], TOL(1e-6, 1e-15));
  /* a bigger layout resizes the vectors */
  mpm_dofs_begin_layout(&f.d);
  assert_int_equal(mpm_dofs_add_grid(&f.d, &f.sparse), MPM_OK);
  assert_int_equal(mpm_dofs_add_grid(&f.d, &f.dense), MPM_OK);
  assert_int_equal(mpm_dofs_add_grid(&f.d, &f.dense), MPM_OK);
  assert_int_equal(mpm_dofs_add_corners(&f.d, CORNERS, (const mpm_real *const *)f.cx), MPM_OK);
  assert_int_equal(mpm_dofs_end_layout(&f.d, MPM_DOF_MASS | MPM_DOF_V), MPM_OK);
  assert_null(f.d.f[0]);
  a = mpm_dofs_vector(&f.d, "r");
  for (size_t i = 0; i < f.d.count; ++i) /* the whole new range is there (values are stale) */
    for (int c = 0; c < 3; ++c) a[c][i] = c == 2;
  assert_close(mpm_dofs_dot(&f.d, NULL, a, a), (double)f.d.count, 0);
  fixture_free(&f);
}

static void test_explicit_update(void **state) {
  (void)state;
  fixture f;
  fixture_make(&f);
  mpm_dofs *d = &f.d;
  uint64_t rng = 5;
  mpm_real p[3][4096], fo[3][4096];
  assert_true(d->count <= 4096);
  for (size_t i = 0; i < d->count; ++i) {
    d->mass[i] = i % 5 == 0 ? 0 : (mpm_real)test_rand(&rng, 0.1, 2);
    for (int c = 0; c < 3; ++c) {
      d->v0[c][i] = p[c][i] = (mpm_real)test_rand(&rng, -1, 1);
      d->f[c][i] = fo[c][i] = (mpm_real)test_rand(&rng, -10, 10);
    }
  }
  mpm_explicit_update u;
  memset(&u, 0, sizeof u);
  u.dt = (mpm_real)1e-3;
  u.gravity[1] = (mpm_real)-9.81;
  for (int c = 0; c < 3; ++c) { /* walls far away */
    u.boundary.wall_lo[c] = -100;
    u.boundary.wall_hi[c] = 100;
  }
  mpm_dofs_explicit_update(&u, MPM_P2G_MOMENTUM_FORCE, d);
  for (size_t i = 0; i < d->count; ++i)
    for (int c = 0; c < 3; ++c) {
      if (i % 5 == 0) {
        assert_true(d->v[c][i] == 0 && d->v0[c][i] == 0);
        continue;
      }
      const double v0 = (double)p[c][i] / d->mass[i];
      const double v = v0 + 1e-3 * ((double)fo[c][i] / d->mass[i] + (c == 1 ? -9.81 : 0));
      assert_close(d->v0[c][i], v0, TOL(1e-5, 1e-12) * fabs(v0) + 1e-30);
      assert_close(d->v[c][i], v, TOL(1e-5, 1e-12) * (fabs(v) + 1e-3));
    }
  /* the fused form: v0 holds m v + dt f already, no force is read */
  for (size_t i = 0; i < d->count; ++i)
    for (int c = 0; c < 3; ++c) {
      d->v0[c][i] = p[c][i];
      d->f[c][i] = NAN;
    }
  mpm_dofs_explicit_update(&u, MPM_P2G_IMPULSE, d);
  for (size_t i = 1; i < d->count; i += 5)
    assert_close(d->v[1][i], (double)p[1][i] / d->mass[i] - 9.81e-3, TOL(1e-5, 1e-12));
  fixture_free(&f);
}

/* The wall band by position selects, on a level of spacing dx, the nodes with index < 3 or
 * > cells - 3 (the old index rule); on a level of dx / 2 also the half-cell nodes beyond the
 * planes; a corner exactly when it is beyond a plane. Sticky walls zero the velocity. */
static void test_wall_band(void **state) {
  (void)state;
  const mpm_real origin[3] = {(mpm_real)-0.3, (mpm_real)0.2, (mpm_real)1.1};
  const mpm_real dx = (mpm_real)0.04;
  const int cells = 20, wall = 3;
  mpm_grid coarse, fine;
  const int n0[3] = {cells + 3, 2, 2}, n1[3] = {2 * cells + 5, 2, 2};
  assert_int_equal(mpm_grid_init_dense(&coarse, 0, origin, dx, n0), MPM_OK);
  assert_int_equal(mpm_grid_init_dense(&fine, 1, origin, dx / 2, n1), MPM_OK);
  mpm_real *cx[3], line[64];
  for (int k = 0; k < 64; ++k) line[k] = origin[0] + dx * (mpm_real)(k - 4) * (mpm_real)0.37;
  mpm_real zero[64] = {0}, mid[64];
  for (int k = 0; k < 64; ++k) mid[k] = origin[1] + (mpm_real)0.5;
  cx[0] = line;
  cx[1] = mid;
  cx[2] = zero;
  for (int k = 0; k < 64; ++k) zero[k] = origin[2] + (mpm_real)0.5;
  mpm_dofs d;
  mpm_dofs_init(&d);
  mpm_dofs_begin_layout(&d);
  assert_int_equal(mpm_dofs_add_grid(&d, &coarse), MPM_OK);
  assert_int_equal(mpm_dofs_add_grid(&d, &fine), MPM_OK);
  assert_int_equal(mpm_dofs_add_corners(&d, 64, (const mpm_real *const *)cx), MPM_OK);
  assert_int_equal(mpm_dofs_end_layout(&d, MPM_DOF_ALL), MPM_OK);
  mpm_dofs_clear(&d, MPM_DOF_ALL);
  for (size_t i = 0; i < d.count; ++i) {
    d.mass[i] = 1;
    d.v0[0][i] = 1; /* moving +x, into the upper wall */
  }
  mpm_explicit_update u;
  memset(&u, 0, sizeof u);
  u.dt = (mpm_real)1e-3;
  u.boundary.wall_rule = MPM_BOUNDARY_STICKY;
  for (int c = 0; c < 3; ++c) {
    u.boundary.wall_lo[c] = origin[c] + (mpm_real)wall * dx;
    u.boundary.wall_hi[c] = origin[c] + (mpm_real)(cells - wall) * dx;
  }
  u.boundary.wall_lo[1] = u.boundary.wall_lo[2] = -100; /* only the x walls */
  u.boundary.wall_hi[1] = u.boundary.wall_hi[2] = 100;
  mpm_dofs_explicit_update(&u, MPM_P2G_MOMENTUM_FORCE, &d);
  for (size_t i = 0; i < d.count; ++i) {
    const mpm_dof_segment *s = mpm_dofs_segment_of(&d, i);
    mpm_real x[3];
    mpm_dofs_position(&d, i, x);
    int expect;
    if (s->kind == MPM_DOF_CORNER) {
      expect = x[0] < u.boundary.wall_lo[0] || x[0] > u.boundary.wall_hi[0];
    } else {
      /* node index along x on its level, from the position */
      const int level = s->level, idx = (int)lround((x[0] - origin[0]) / (dx / (1 << level)));
      const int scale = 1 << level;
      expect = idx < wall * scale || idx > (cells - wall) * scale;
    }
    if (expect != (d.v[0][i] == 0))
      fail_msg("DOF %zu (%s, x = %.6f): in the wall band %d, v = %g", i,
               s->kind == MPM_DOF_CORNER ? "corner" : "node", (double)x[0], expect,
               (double)d.v[0][i]);
  }
  mpm_dofs_free(&d);
  mpm_grid_free(&coarse);
  mpm_grid_free(&fine);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_layout_and_positions),
      cmocka_unit_test(test_reductions),
      cmocka_unit_test(test_explicit_update),
      cmocka_unit_test(test_wall_band),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
