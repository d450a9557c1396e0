/* test_kernel.c - weight kernels against their defining properties (Gao sec. 3.3):
 * partition of unity, linear reproduction, non-negativity, sum of gradients zero, gradients
 * equal finite differences of the weights, uGIMP with L_p = dx equals the quadratic B-spline,
 * the wide uGIMP (dx < L_p <= 2 dx, 4 nodes) equals the general box average of interp/gimp.h,
 * the APIC factors reproduce D_p^{-1} (sum a_i (x_i - x_p) = 1, sum a_i = 0), and the paired
 * uGIMP (4 nodes from an even base) is the uGIMP moved by a node. */
#include "support.h"
#include "interp/gimp.h"
#include "interp/kernel.h"
#include "transfer/transfer_lanes.h"

#include <math.h>

static const mpm_kernel_kind kinds[] = {MPM_KERNEL_LINEAR, MPM_KERNEL_QUADRATIC, MPM_KERNEL_CUBIC,
                                        MPM_KERNEL_UGIMP};

/* 3D weight and gradient of stencil node (i,j,k). */
static double w3(const mpm_stencil *s, int i, int j, int k) {
  return (double)s->w[0][i] * s->w[1][j] * s->w[2][k];
}

static void check_kernel_made(const mpm_kernel k, uint64_t rng);

static void check_kernel(mpm_kernel_kind kind, double gimp_len) {
  check_kernel_made(mpm_kernel_make(kind, (mpm_real)0.037, (mpm_real)gimp_len),
                    12345 + (uint64_t)kind);
}

static void check_kernel_made(const mpm_kernel k, uint64_t rng) {
  const double dx = (double)k.dx;
  const double tol = TOL(2e-5, 1e-12);
  for (int trial = 0; trial < 2000; ++trial) {
    mpm_real x[3];
    for (int d = 0; d < 3; ++d) x[d] = (mpm_real)test_rand(&rng, 3 * dx, 40 * dx);
    if (trial < 8) /* exactly on nodes and cell centres too */
      for (int d = 0; d < 3; ++d) x[d] = (mpm_real)((10 + 0.5 * (trial & 1)) * dx);
    mpm_stencil s;
    mpm_kernel_stencil(&k, x, &s);
    const int W = k.width;
    double sum = 0, sx[3] = {0, 0, 0}, sg[3] = {0, 0, 0};
    for (int i = 0; i < W; ++i)
      for (int j = 0; j < W; ++j)
        for (int q = 0; q < W; ++q) {
          double w = w3(&s, i, j, q);
          assert_true(w >= -1e-7); /* every kernel here is non-negative */
          sum += w;
          const int idx[3] = {s.base[0] + i, s.base[1] + j, s.base[2] + q};
          for (int d = 0; d < 3; ++d) sx[d] += w * idx[d] * dx;
          sg[0] += (double)s.dw[0][i] * s.w[1][j] * s.w[2][q];
          sg[1] += (double)s.w[0][i] * s.dw[1][j] * s.w[2][q];
          sg[2] += (double)s.w[0][i] * s.w[1][j] * s.dw[2][q];
        }
    assert_close(sum, 1.0, tol);
    for (int d = 0; d < 3; ++d) {
      assert_close(sx[d], (double)x[d], tol * 40 * dx);
      assert_close(sg[d] * dx, 0.0, tol * 10);
    }
    /* 1D APIC factors: sum a_i = 0 and sum a_i (x_i - x_p) = 1 */
    for (int d = 0; d < 3; ++d) {
      double sa = 0, sar = 0;
      for (int i = 0; i < W; ++i) {
        sa += s.a[d][i];
        sar += s.a[d][i] * ((s.base[d] + i) * dx - x[d]);
      }
      assert_close(sa * dx, 0.0, tol * 50);
      assert_close(sar, 1.0, tol * 50);
    }
  }
}

static void test_linear(void **state) {
  (void)state;
  check_kernel(MPM_KERNEL_LINEAR, 0);
}
static void test_quadratic(void **state) {
  (void)state;
  check_kernel(MPM_KERNEL_QUADRATIC, 0);
}
static void test_cubic(void **state) {
  (void)state;
  check_kernel(MPM_KERNEL_CUBIC, 0);
}
static void test_ugimp(void **state) {
  (void)state;
  check_kernel(MPM_KERNEL_UGIMP, 0.037 * 0.5);
  check_kernel(MPM_KERNEL_UGIMP, 0.037 * 0.3);
  check_kernel(MPM_KERNEL_UGIMP, 0.037);
  /* the wide box, 4 nodes per axis (a particle one level coarser than its transfer level) */
  check_kernel(MPM_KERNEL_UGIMP, 0.037 * 1.01);
  check_kernel(MPM_KERNEL_UGIMP, 0.037 * 1.5);
  check_kernel(MPM_KERNEL_UGIMP, 0.037 * 2);
}

/* The wide uGIMP (dx < L_p <= 2 dx) against the general box average of interp/gimp.h, its
 * gradients against finite differences, and its SIMD lanes against the scalar kernel. */
static void test_wide_ugimp(void **state) {
  (void)state;
  const double dx = 0.05;
  static const double lengths[] = {1.01, 1.3, 1.5, 1.77, 2.0};
  for (size_t c = 0; c < sizeof lengths / sizeof lengths[0]; ++c) {
    const mpm_kernel k =
        mpm_kernel_make(MPM_KERNEL_UGIMP, (mpm_real)dx, (mpm_real)(lengths[c] * dx));
    assert_int_equal(k.width, 4);
    uint64_t rng = 5 + c;
    for (int trial = 0; trial < 2000; ++trial) {
      const double xg = test_rand(&rng, -6, 6);
      mpm_real w[4], dw[4], a[4];
      const int base = mpm_kernel_1d(&k, (mpm_real)xg, w, dw, a);
      mpm_real gw[MPM_GIMP_NODES_MAX], gdw[MPM_GIMP_NODES_MAX];
      int gbase;
      const int gn = mpm_gimp_1d((mpm_real)xg, k.half_len, &gbase, gw, gdw);
      for (int i = 0; i < gn; ++i) {
        const int j = gbase + i - base;
        if (j < 0 || j > 3) {
          assert_true(fabs((double)gw[i]) < TOL(1e-6, 1e-14)); /* outside: no weight */
          continue;
        }
        assert_close(w[j], gw[i], TOL(2e-6, 1e-13));
        assert_close(dw[j] * dx, gdw[i], TOL(2e-5, 1e-12));
      }
      /* finite differences where the stencil stays */
      const double h = TOL(1e-3, 1e-6);
      mpm_real wp[4], wm[4], scratch[4];
      if (mpm_kernel_1d(&k, (mpm_real)(xg + h), wp, scratch, a) != base ||
          mpm_kernel_1d(&k, (mpm_real)(xg - h), wm, scratch, a) != base)
        continue;
      for (int i = 0; i < 4; ++i)
        assert_close(((double)wp[i] - wm[i]) / (2 * h), (double)dw[i] * dx, TOL(5e-3, 1e-6));
    }
    /* lanes */
    for (int trial = 0; trial < 100; ++trial) {
      mpm_real xs[3][MPM_LANES];
      uint32_t idx[MPM_LANES];
      for (int l = 0; l < MPM_LANES; ++l) {
        idx[l] = (uint32_t)l;
        for (int d = 0; d < 3; ++d)
          xs[d][l] = (mpm_real)((10 + d + k.shift + test_rand(&rng, 0.01, 0.99)) * dx);
      }
      const mpm_real *x[3] = {xs[0], xs[1], xs[2]};
      const mpm_real origin[3] = {0, 0, 0};
      int lb[3];
      mpm_lane_stencil s;
      mpm_lane_stencil_eval(k.width, &k, x, origin, idx, MPM_LANES, 1, 1, lb, &s);
      for (int l = 0; l < MPM_LANES; ++l)
        for (int d = 0; d < 3; ++d) {
          mpm_real w[4], dw[4], a[4];
          assert_int_equal(mpm_kernel_1d(&k, xs[d][l] / (mpm_real)dx, w, dw, a), lb[d]);
          for (int q = 0; q < 4; ++q) {
            assert_close(s.w[d][q][l], w[q], TOL(2e-6, 1e-13));
            assert_close(s.dw[d][q][l] * dx, dw[q] * dx, TOL(2e-5, 1e-12));
            assert_close(s.a[d][q][l] * dx, a[q] * dx, TOL(2e-4, 1e-11));
          }
        }
    }
  }
}

/* Gradients equal central differences of the weights (1D factors, in double builds tight). */
static void test_gradients_match_finite_differences(void **state) {
  (void)state;
  const double dx = 0.1;
  for (size_t kk = 0; kk < sizeof kinds / sizeof kinds[0]; ++kk) {
    mpm_kernel k = mpm_kernel_make(kinds[kk], (mpm_real)dx, (mpm_real)(0.6 * dx));
    uint64_t rng = 99;
    for (int trial = 0; trial < 500; ++trial) {
      double x = test_rand(&rng, 1.0, 2.0);
      const double h = TOL(1e-3, 1e-6) * dx;
      mpm_real w[4], dw[4], a[4], wp[4], wm[4], scratch[4];
      int base = mpm_kernel_1d(&k, (mpm_real)(x / dx), w, dw, a);
      int bp = mpm_kernel_1d(&k, (mpm_real)((x + h) / dx), wp, scratch, a);
      int bm = mpm_kernel_1d(&k, (mpm_real)((x - h) / dx), wm, scratch, a);
      if (bp != base || bm != base) continue; /* stencil changes across a cell face */
      /* the linear kernel's derivative jumps at nodes: skip points within h of a node */
      for (int i = 0; i < k.width; ++i) {
        double fd = ((double)wp[i] - wm[i]) / (2 * h);
        assert_close(fd * dx, (double)dw[i] * dx, TOL(5e-3, 1e-6));
      }
    }
  }
}

/* Gao sec. 3.3: uGIMP with L_p = dx is exactly the quadratic B-spline. */
static void test_ugimp_equals_quadratic(void **state) {
  (void)state;
  const double dx = 0.05;
  mpm_kernel q = mpm_kernel_make(MPM_KERNEL_QUADRATIC, (mpm_real)dx, 0);
  mpm_kernel g = mpm_kernel_make(MPM_KERNEL_UGIMP, (mpm_real)dx, (mpm_real)dx);
  uint64_t rng = 7;
  for (int trial = 0; trial < 5000; ++trial) {
    mpm_real x = (mpm_real)(test_rand(&rng, 0.2, 3.0) / dx);
    mpm_real wq[4], dq[4], aq[4], wg[4], dg[4], ag[4];
    int bq = mpm_kernel_1d(&q, x, wq, dq, aq);
    int bg = mpm_kernel_1d(&g, x, wg, dg, ag);
    assert_int_equal(bq, bg);
    for (int i = 0; i < 3; ++i) {
      assert_close(wq[i], wg[i], TOL(2e-6, 1e-14));
      assert_close(dq[i] * dx, dg[i] * dx, TOL(2e-5, 1e-12));
      assert_close(aq[i] * dx, ag[i] * dx, TOL(2e-4, 1e-10));
    }
  }
}

/* The quadratic APIC factor is the textbook 4/dx^2 w (x_i - x_p). */
static void test_quadratic_apic_factor(void **state) {
  (void)state;
  const double dx = 0.25;
  mpm_kernel q = mpm_kernel_make(MPM_KERNEL_QUADRATIC, (mpm_real)dx, 0);
  mpm_real w[4], dw[4], a[4];
  double x = 1.37;
  int base = mpm_kernel_1d(&q, (mpm_real)(x / dx), w, dw, a);
  for (int i = 0; i < 3; ++i)
    assert_close(a[i], 4.0 / (dx * dx) * w[i] * ((base + i) * dx - x), TOL(1e-4, 1e-12));
}

/* Reference uGIMP weight in double: the hat's antiderivative differenced (fine in double). */
static double ugimp_ref(double f, int i, double h) {
  double hi = f - i + h, lo = f - i - h;
  double H[2];
  double t[2] = {lo, hi};
  for (int q = 0; q < 2; ++q) {
    double x = t[q];
    H[q] = x <= -1 ? 0 : x <= 0 ? 0.5 * (x + 1) * (x + 1) : x < 1 ? 1 - 0.5 * (1 - x) * (1 - x) : 1;
  }
  return (H[1] - H[0]) / (2 * h);
}

/* Weights near the edge of uGIMP's support must stay accurate (and never negative) in float:
 * particles on a lattice of spacing dx/2 with L_p = dx/2 put box edges exactly on nodes, and
 * round-off moves them by ~1e-4 cells, where a difference of antiderivatives near 1 has no
 * correct digit left. That once gave nodes tiny negative masses and blew simulations up. */
static void test_ugimp_edge_weights_accurate(void **state) {
  (void)state;
  const double dx = 0.015, h = 0.25;
  mpm_kernel k = mpm_kernel_make(MPM_KERNEL_UGIMP, (mpm_real)dx, (mpm_real)(dx / 2));
  uint64_t rng = 3;
  double worst = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const double lattice = (20 + (trial % 40)) * 0.5 + 0.25;
    const double xg = lattice + test_rand(&rng, -2e-4, 2e-4);
    mpm_real w[4], dw[4], a[4];
    const int base = mpm_kernel_1d(&k, (mpm_real)xg, w, dw, a);
    const double f = (double)(mpm_real)xg - base;
    for (int i = 0; i < 3; ++i) {
      const double ref = ugimp_ref(f, i, h);
      assert_true(w[i] >= 0);
      const double err = fabs(w[i] - ref) / (ref + TOL(1e-4, 1e-8));
      if (err > worst) worst = err;
    }
  }
  print_message("uGIMP edge weights: worst error relative to (w + floor) %.3g\n", worst);
  assert_true(worst < TOL(2e-6, 1e-7)); /* in double the reference itself limits the check */
}

/* The SIMD lane stencils of the sparse transfers equal the scalar kernel of the dense grid. */
static void test_lane_stencils_match_scalar(void **state) {
  (void)state;
  const double dx = 0.02;
  for (size_t kk = 0; kk < sizeof kinds / sizeof kinds[0]; ++kk) {
    mpm_kernel k = mpm_kernel_make(kinds[kk], (mpm_real)dx, (mpm_real)(0.4 * dx));
    uint64_t rng = 11 + kk;
    for (int trial = 0; trial < 200; ++trial) {
      /* 8 particles in one base cell: choose the cell, then offsets inside it */
      mpm_real xs[3][MPM_LANES];
      uint32_t idx[MPM_LANES];
      for (int l = 0; l < MPM_LANES; ++l) {
        idx[l] = (uint32_t)l;
        for (int d = 0; d < 3; ++d)
          xs[d][l] = (mpm_real)((10 + d + k.shift + test_rand(&rng, 0.01, 0.99)) * dx);
      }
      const mpm_real *x[3] = {xs[0], xs[1], xs[2]};
      const mpm_real origin[3] = {0, 0, 0};
      const int n = 1 + trial % MPM_LANES;
      int base[3];
      mpm_lane_stencil s;
      mpm_lane_stencil_eval(k.width, &k, x, origin, idx, n, trial % 2, 1, base, &s);
      for (int l = 0; l < n; ++l)
        for (int d = 0; d < 3; ++d) {
          mpm_real w[4], dw[4], a[4];
          const int b = mpm_kernel_1d(&k, xs[d][l] / (mpm_real)dx, w, dw, a);
          assert_int_equal(b, base[d]);
          for (int q = 0; q < k.width; ++q) {
            assert_close(s.w[d][q][l], w[q], TOL(2e-6, 1e-13));
            assert_close(s.dw[d][q][l] * dx, dw[q] * dx, TOL(2e-5, 1e-12));
            assert_close(s.a[d][q][l] * dx, a[q] * dx, TOL(2e-4, 1e-11));
          }
        }
    }
  }
}

/* The paired uGIMP (mpm_kernel_paired): the kernel's defining properties, its base the even
 * node at or below the uGIMP base, its 4 weights the uGIMP's 3 moved up one node when that base
 * is odd, and its SIMD lanes, 8 particles from a 2 x 2 x 2 block of cells, equal to the scalar
 * kernel. */
static void test_paired_ugimp(void **state) {
  (void)state;
  const double dx = 0.037;
  static const double lengths[] = {0.75, 0.9, 1.0};
  for (size_t c = 0; c < sizeof lengths / sizeof lengths[0]; ++c) {
    const mpm_kernel u =
        mpm_kernel_make(MPM_KERNEL_UGIMP, (mpm_real)dx, (mpm_real)(lengths[c] * dx));
    const mpm_kernel k = mpm_kernel_paired(u);
    assert_int_equal(k.kind, MPM_KERNEL_UGIMP_PAIRED);
    assert_int_equal(k.width, 4);
    check_kernel_made(k, 77 + c);
    uint64_t rng = 99 + c;
    for (int trial = 0; trial < 2000; ++trial) {
      const mpm_real xg = (mpm_real)test_rand(&rng, -7, 7);
      mpm_real w[4], dw[4], a[4], wu[4], dwu[4], au[4];
      const int b = mpm_kernel_1d(&k, xg, w, dw, a), bu = mpm_kernel_1d(&u, xg, wu, dwu, au);
      assert_int_equal(b & 1, 0);
      assert_true(bu == b || bu == b + 1);
      const int o = bu - b;
      assert_true(w[o == 0 ? 3 : 0] == 0 && dw[o == 0 ? 3 : 0] == 0 && a[o == 0 ? 3 : 0] == 0);
      for (int q = 0; q < 3; ++q) {
        assert_true(w[q + o] == wu[q]);
        assert_true(dw[q + o] == dwu[q]);
        assert_true(a[q + o] == au[q]);
      }
    }
    const mpm_kernel *kinds2[1] = {&k};
    for (int trial = 0; trial < 200; ++trial) {
      mpm_real xs[3][MPM_LANES];
      uint32_t idx[MPM_LANES];
      for (int l = 0; l < MPM_LANES; ++l) {
        idx[l] = (uint32_t)l;
        for (int d = 0; d < 3; ++d) /* bases 10 + 2 d and 11 + 2 d: one pair */
          xs[d][l] = (mpm_real)((10 + 2 * d + k.shift + test_rand(&rng, 0.01, 1.99)) * dx);
      }
      const mpm_real *x[3] = {xs[0], xs[1], xs[2]};
      const mpm_real origin[3] = {0, 0, 0};
      const int n = 1 + trial % MPM_LANES;
      int base[3];
      mpm_lane_stencil s;
      mpm_lane_stencil_eval(4, kinds2[0], x, origin, idx, n, trial % 2, 1, base, &s);
      for (int l = 0; l < n; ++l)
        for (int d = 0; d < 3; ++d) {
          mpm_real w[4], dw[4], a[4];
          const int b = mpm_kernel_1d(&k, xs[d][l] / (mpm_real)dx, w, dw, a);
          assert_int_equal(b, base[d]);
          for (int q = 0; q < 4; ++q) {
            assert_close(s.w[d][q][l], w[q], TOL(2e-6, 1e-13));
            assert_close(s.dw[d][q][l] * dx, dw[q] * dx, TOL(2e-5, 1e-12));
            assert_close(s.a[d][q][l] * dx, a[q] * dx, TOL(2e-4, 1e-11));
          }
        }
    }
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_linear),
      cmocka_unit_test(test_quadratic),
      cmocka_unit_test(test_cubic),
      cmocka_unit_test(test_ugimp),
      cmocka_unit_test(test_wide_ugimp),
      cmocka_unit_test(test_gradients_match_finite_differences),
      cmocka_unit_test(test_ugimp_equals_quadratic),
      cmocka_unit_test(test_quadratic_apic_factor),
      cmocka_unit_test(test_ugimp_edge_weights_accurate),
      cmocka_unit_test(test_lane_stencils_match_scalar),
      cmocka_unit_test(test_paired_ugimp),
  };
  return cmocka_run_group_tests_name("kernel", tests, NULL, NULL);
}
