/* test_refinement.c - the non-graded multi-level grid's cells, constrained T-junctions and
 * basis (adaptive/refinement.h) and a particle's GIMP weights on it (adaptive/weights.h),
 * against independent truth:
 *   - one level: every node is real, N_i is the trilinear hat;
 *   - hand-made T-junctions: the rows of Gao eqs. 11-14 (an edge midpoint takes 1/2 + 1/2, a
 *     quarter point 3/4 + 1/4, a face centre 4 x 1/4, a chain through two levels multiplies);
 *   - random non-graded refinements (3 and 4 levels): every node row and every N_i(x) is
 *     non-negative, sums to one and reproduces linear functions; N is C0 across leaf faces
 *     (sampled on both sides of every face a random point is moved to);
 *   - GIMP weights w_ip (Gao eq. 15) on the same grids: non-negative, partition of unity,
 *     sum w x_i = x_p, sum grad w = 0, sum grad w x_i^T = I; the same weights whether the
 *     particle transfers on the finest level its box meets or one finer (the ghost-node
 *     transfer is exact); C1 along lines through level changes (finite differences of w
 *     against the analytic gradient);
 *   - Lian et al.'s free T-junction basis (sec. 5.1, eqs. 8-10), built here in 2D as a
 *     reference only: in the configuration of Fig. 5b it gives a negative N_c, a negative
 *     GIMP weight and a negative nodal mass; ours on the same grid gives none. */
#include "refinement_support.h"
#include "support.h"
#include "adaptive/refinement.h"
#include "adaptive/weights.h"
#include "interp/gimp.h"
#include "interp/kernel.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define MAXT 512

static const int is_double = sizeof(mpm_real) == 8;

static void node_pos(const mpm_refinement *r, int level, const int32_t idx[3], double x[3]) {
  for (int d = 0; d < 3; ++d)
    x[d] = (double)r->origin[d] + (double)idx[d] * (double)mpm_refinement_dx(r, level);
}

/* sum of weights, smallest weight, and |sum w x_i - x| */
static void check_row(const mpm_refinement *r, const mpm_row_term *t, int n, const double x[3],
                      double tol) {
  assert_true(n > 0);
  double s = 0, lin[3] = {0, 0, 0};
  for (int i = 0; i < n; ++i) {
    assert_true(t[i].w > 0);
    s += t[i].w;
    double xi[3];
    node_pos(r, t[i].level, t[i].idx, xi);
    for (int d = 0; d < 3; ++d) lin[d] += t[i].w * xi[d];
    mpm_row_term own;
    assert_true(mpm_refinement_node_is_real(r, t[i].level, t[i].idx, &own));
    assert_int_equal(own.level, t[i].level); /* named by its owner level */
  }
  assert_true(fabs(s - 1) < 1e-12);
  for (int d = 0; d < 3; ++d) assert_true(fabs(lin[d] - x[d]) < tol);
}

static double weight_of(const mpm_row_term *t, int n, int level, int i, int j, int k) {
  for (int e = 0; e < n; ++e)
    if (t[e].level == level && t[e].idx[0] == i && t[e].idx[1] == j && t[e].idx[2] == k)
      return t[e].w;
  return 0;
}

static void test_single_level(void **state) {
  (void)state;
  mpm_refinement r;
  const mpm_real o[3] = {R_(-0.5), 0, R_(0.25)};
  mpm_refinement_init(&r, 1, o, R_(0.1));
  mpm_row_term t[MAXT];
  const int32_t idx[3] = {-3, 7, 2};
  assert_int_equal(mpm_refinement_node_row(&r, 0, idx, t, MAXT), 1);
  assert_true(t[0].w == 1 && t[0].idx[0] == -3 && t[0].idx[1] == 7 && t[0].idx[2] == 2);
  /* N_i(x) is the trilinear hat */
  const mpm_real x[3] = {R_(-0.43), R_(0.52), R_(0.4)};
  const int n = mpm_refinement_basis_at(&r, x, t, MAXT);
  assert_int_equal(n, 8);
  for (int e = 0; e < n; ++e) {
    double h = 1;
    for (int d = 0; d < 3; ++d) {
      const double g = ((double)x[d] - o[d]) / 0.1 - t[e].idx[d];
      h *= 1 - fabs(g);
    }
    assert_true(fabs(h - t[e].w) < (is_double ? 1e-12 : 1e-5));
  }
  mpm_refinement_free(&r);
}

/* Level-0 cell (1,0,0) refined, and its child (2,0,0) refined again: a coarse leaf (0,0,0)
 * borders level-1 and level-2 leaves (non-graded). */
static void test_tjunction_rows(void **state) {
  (void)state;
  mpm_refinement r;
  const mpm_real o[3] = {0, 0, 0};
  mpm_refinement_init(&r, 3, o, 1);
  const int32_t c1[3] = {2, 0, 0};
  assert_int_equal(mpm_refinement_refine(&r, 1, c1), MPM_OK);
  const int32_t c0[3] = {1, 0, 0};
  assert_true(mpm_refinement_is_refined(&r, 0, c0)); /* the ancestor came along */
  mpm_row_term t[MAXT];
  double x[3];
  /* (1, 0.25, 0) on the coarse leaf's edge: 3/4 and 1/4 of the edge's ends (Gao's q_c) */
  const int32_t q[3] = {4, 1, 0};
  int n = mpm_refinement_node_row(&r, 2, q, t, MAXT);
  assert_int_equal(n, 2);
  assert_true(weight_of(t, n, 0, 1, 0, 0) == 0.75 && weight_of(t, n, 0, 1, 1, 0) == 0.25);
  assert_false(mpm_refinement_node_is_real(&r, 2, q, NULL));
  /* (1, 0.5, 0.5): the centre of the coarse leaf's face, 4 x 1/4 */
  const int32_t f[3] = {2, 1, 1};
  n = mpm_refinement_node_row(&r, 1, f, t, MAXT);
  assert_int_equal(n, 4);
  assert_true(weight_of(t, n, 0, 1, 0, 0) == 0.25 && weight_of(t, n, 0, 1, 1, 1) == 0.25);
  /* a level-0 corner seen from level 2 is a duplicate of the real level-0 node */
  const int32_t a2[3] = {4, 0, 0}, a0[3] = {1, 0, 0};
  mpm_row_term own;
  assert_true(mpm_refinement_node_is_real(&r, 2, a2, &own));
  assert_true(own.level == 0 && own.idx[0] == 1 && own.idx[1] == 0 && own.idx[2] == 0);
  assert_true(mpm_refinement_node_is_real(&r, 0, a0, NULL));
  /* (1.25, 0.25, 0.25): inside the level-2 leaves, real and owned by level 2 */
  const int32_t in[3] = {5, 1, 1};
  assert_true(mpm_refinement_node_is_real(&r, 2, in, &own) && own.level == 2);
  /* (1.5, 0.25, 0.25): a T-junction on a level-1 leaf's face whose corners are themselves
   * constrained to the level-0 leaves below (z < 0) and beside (y < 0): a chain */
  const int32_t ch[3] = {6, 1, 1};
  n = mpm_refinement_node_row(&r, 2, ch, t, MAXT);
  node_pos(&r, 2, ch, x);
  check_row(&r, t, n, x, 1e-12);
  assert_true(n > 4);
  /* refined nodes inside a coarse leaf (Gao Fig. 10's x^h_11): trilinear in its corners */
  const int32_t mid[3] = {1, 1, 1}; /* (0.25, 0.25, 0.25) at level 2 */
  n = mpm_refinement_node_row(&r, 2, mid, t, MAXT);
  assert_int_equal(n, 8);
  assert_true(weight_of(t, n, 0, 0, 0, 0) == 0.75 * 0.75 * 0.75);
  /* the finest level a box meets */
  const mpm_real lo[3] = {R_(0.2), R_(0.2), R_(0.2)}, hi[3] = {R_(0.8), R_(0.8), R_(0.8)};
  assert_int_equal(mpm_refinement_finest_level_in(&r, lo, hi), 0);
  const mpm_real lo2[3] = {R_(0.6), R_(0.2), R_(0.2)}, hi2[3] = {R_(1.1), R_(0.8), R_(0.8)};
  assert_int_equal(mpm_refinement_finest_level_in(&r, lo2, hi2), 2);
  const mpm_real lo3[3] = {R_(0.6), R_(0.6), R_(0.6)}, hi3[3] = {R_(1.1), R_(0.8), R_(0.8)};
  assert_int_equal(mpm_refinement_finest_level_in(&r, lo3, hi3), 1);
  mpm_refinement_free(&r);
}

#define REGION 3 /* level-0 cells -REGION .. REGION - 1 per axis */

static void random_tree(mpm_refinement *r, int levels, uint64_t seed) {
  const mpm_real o[3] = {R_(-0.3), R_(0.2), R_(0.1)};
  mpm_refinement_init(r, levels, o, R_(0.25));
  uint64_t rng = seed;
  for (int32_t i = -REGION; i < REGION; ++i)
    for (int32_t j = -REGION; j < REGION; ++j)
      for (int32_t k = -REGION; k < REGION; ++k) {
        const int32_t c[3] = {i, j, k};
        test_refine_random(r, 0, c, 0.45, &rng);
      }
}

static void random_point(const mpm_refinement *r, uint64_t *rng, mpm_real x[3]) {
  for (int d = 0; d < 3; ++d)
    x[d] = r->origin[d] + (mpm_real)(test_rand(rng, -REGION + 0.5, REGION - 0.5) * r->dx0);
}

static void test_random_rows_and_basis(void **state) {
  (void)state;
  const double tol = is_double ? 1e-9 : 2e-5;
  for (int levels = 3; levels <= 4; ++levels) {
    mpm_refinement r;
    random_tree(&r, levels, 17u + (uint64_t)levels);
    uint64_t rng = 99;
    mpm_row_term t[MAXT];
    int chains = 0;
    /* every node row: random nodes of every level */
    for (int s = 0; s < 3000; ++s) {
      const int L = (int)test_rand(&rng, 0, levels);
      const int span = REGION << L;
      int32_t idx[3];
      for (int d = 0; d < 3; ++d) idx[d] = (int32_t)test_rand(&rng, -span, span);
      const int n = mpm_refinement_node_row(&r, L, idx, t, MAXT);
      double x[3];
      node_pos(&r, L, idx, x);
      check_row(&r, t, n, x, 1e-12);
      mpm_row_term own;
      if (mpm_refinement_node_is_real(&r, L, idx, &own)) {
        assert_int_equal(n, 1);
        assert_true(t[0].w == 1 && t[0].level == own.level);
      } else {
        chains += n > 4;
      }
    }
    assert_true(chains > 0); /* the trees do have non-graded chains */
    /* N_i(x) at random points, and continuity across the faces of the leaf holding them */
    double worst_jump = 0;
    for (int s = 0; s < 2000; ++s) {
      mpm_real x[3];
      random_point(&r, &rng, x);
      int n = mpm_refinement_basis_at(&r, x, t, MAXT);
      double xd[3] = {x[0], x[1], x[2]};
      check_row(&r, t, n, xd, tol);
      int32_t cell[3];
      const int L = mpm_refinement_leaf_at(&r, x, cell);
      const double dxf = (double)mpm_refinement_dx(&r, levels - 1);
      const int axis = s % 3;
      /* move x onto the leaf's lower face along `axis`, and step off both sides */
      const double face = (double)r.origin[axis] + cell[axis] * (double)mpm_refinement_dx(&r, L);
      const double eps = (is_double ? 1e-7 : 1e-3) * dxf;
      mpm_real xm[3] = {x[0], x[1], x[2]}, xp[3] = {x[0], x[1], x[2]};
      xm[axis] = (mpm_real)(face - eps);
      xp[axis] = (mpm_real)(face + eps);
      mpm_row_term a[MAXT], b[MAXT];
      const int na = mpm_refinement_basis_at(&r, xm, a, MAXT);
      const int nb = mpm_refinement_basis_at(&r, xp, b, MAXT);
      assert_true(na > 0 && nb > 0);
      for (int e = 0; e < na; ++e) {
        const double j =
            fabs(a[e].w - weight_of(b, nb, a[e].level, a[e].idx[0], a[e].idx[1], a[e].idx[2]));
        if (j > worst_jump) worst_jump = j;
      }
      for (int e = 0; e < nb; ++e) {
        const double j =
            fabs(b[e].w - weight_of(a, na, b[e].level, b[e].idx[0], b[e].idx[1], b[e].idx[2]));
        if (j > worst_jump) worst_jump = j;
      }
      (void)n;
    }
    /* |grad N| <= 1/dx_finest, so the two sides differ by at most about 2 eps / dx_finest */
    print_message("levels %d: largest jump of N across a leaf face %.2e\n", levels, worst_jump);
    assert_true(worst_jump < (is_double ? 1e-6 : 1e-2));
    mpm_refinement_free(&r);
  }
}

/* Sorted copy of b's entries in a's order (0 where missing): max |a - b| of weights. */
static double weights_differ(const mpm_adaptive_weight *a, int na, const mpm_adaptive_weight *b,
                             int nb) {
  double worst = 0;
  for (int i = 0; i < na; ++i) {
    double wb = 0;
    for (int j = 0; j < nb; ++j)
      if (a[i].level == b[j].level && !memcmp(a[i].idx, b[j].idx, sizeof a[i].idx)) wb = b[j].w;
    worst = fmax(worst, fabs(a[i].w - wb));
  }
  for (int j = 0; j < nb; ++j) {
    double wa = 0;
    for (int i = 0; i < na; ++i)
      if (a[i].level == b[j].level && !memcmp(a[i].idx, b[j].idx, sizeof a[i].idx)) wa = a[i].w;
    worst = fmax(worst, fabs(b[j].w - wa));
  }
  return worst;
}

/* The particle's box side: the spacing of the leaf holding it (particle type matched to the
 * level, Gao sec. 7.1), so boxes near level changes reach into finer leaves. */
static mpm_real particle_length(const mpm_refinement *r, const mpm_real x[3]) {
  int32_t cell[3];
  return mpm_refinement_dx(r, mpm_refinement_leaf_at(r, x, cell));
}

static void test_gimp_weights(void **state) {
  (void)state;
  const double tol = is_double ? 1e-9 : 3e-5;
  for (int levels = 3; levels <= 4; ++levels) {
    mpm_refinement r;
    random_tree(&r, levels, 5u + (uint64_t)levels);
    uint64_t rng = 7;
    static mpm_adaptive_weight w[MAXT], w2[MAXT];
    int finer_used = 0;
    double worst_level = 0;
    for (int s = 0; s < 1500; ++s) {
      mpm_real x[3];
      random_point(&r, &rng, x);
      const mpm_real Lp = particle_length(&r, x);
      int used;
      const int n = mpm_adaptive_weights(&r, x, Lp, -1, w, MAXT, &used);
      assert_true(n > 0);
      double sw = 0, lin[3] = {0, 0, 0}, sg[3] = {0, 0, 0}, G[3][3] = {{0}};
      for (int e = 0; e < n; ++e) {
        assert_true(w[e].w >= -1e-7); /* non-negative up to the precision's round-off */
        sw += w[e].w;
        double xi[3];
        node_pos(&r, w[e].level, w[e].idx, xi);
        for (int d = 0; d < 3; ++d) {
          lin[d] += w[e].w * xi[d];
          sg[d] += w[e].dw[d];
          for (int c = 0; c < 3; ++c) G[d][c] += w[e].dw[c] * xi[d];
        }
      }
      assert_true(fabs(sw - 1) < tol);
      for (int d = 0; d < 3; ++d) {
        assert_true(fabs(lin[d] - x[d]) < tol);
        assert_true(fabs(sg[d]) * Lp < tol * 10);
        for (int c = 0; c < 3; ++c) assert_true(fabs(G[d][c] - (d == c)) < tol * 10);
      }
      /* one level finer gives the same weights (a ghost-node transfer is exact) */
      int32_t cell[3];
      finer_used += used > mpm_refinement_leaf_at(&r, x, cell);
      if (used + 1 < levels) {
        const int n2 = mpm_adaptive_weights(&r, x, Lp, used + 1, w2, MAXT, NULL);
        assert_true(n2 > 0);
        worst_level = fmax(worst_level, weights_differ(w, n, w2, n2));
      }
    }
    print_message("levels %d: %d of 1500 particles transfer on a level finer than their own; "
                  "weights at one level finer differ by at most %.2e\n",
                  levels, finer_used, worst_level);
    assert_true(finer_used > 0);
    assert_true(worst_level < tol);
    mpm_refinement_free(&r);
  }
}

/* C1 along lines: w_ip(x0 + t e) sampled through level changes; central differences against
 * the analytic directional derivative. */
static void test_gimp_c1_along_lines(void **state) {
  (void)state;
  mpm_refinement r;
  random_tree(&r, 3, 23);
  uint64_t rng = 31;
  const double dxf = (double)mpm_refinement_dx(&r, 2);
  const double h = (is_double ? 1e-4 : 2e-2) * dxf;
  static mpm_adaptive_weight a[MAXT], b[MAXT], c[MAXT];
  double worst = 0, scale = 0;
  int level_changes = 0;
  for (int line = 0; line < 12; ++line) {
    mpm_real x0[3];
    random_point(&r, &rng, x0);
    double e[3] = {test_rand(&rng, -1, 1), test_rand(&rng, -1, 1), test_rand(&rng, -1, 1)};
    const double en = sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
    for (int d = 0; d < 3; ++d) e[d] /= en;
    const mpm_real Lp = mpm_refinement_dx(&r, 1); /* one particle type along the whole line */
    int last_level = -1;
    for (int s = 0; s < 200; ++s) {
      const double t = (s - 100) * 0.01 * (double)r.dx0;
      mpm_real x[3], xm[3], xp[3];
      for (int d = 0; d < 3; ++d) {
        x[d] = (mpm_real)((double)x0[d] + t * e[d]);
        xm[d] = (mpm_real)((double)x0[d] + (t - h) * e[d]);
        xp[d] = (mpm_real)((double)x0[d] + (t + h) * e[d]);
      }
      int used;
      /* all three at the finest level: the same exact weights, without rounding from
         choosing different levels at the three points */
      const int n = mpm_adaptive_weights(&r, x, Lp, -1, a, MAXT, &used);
      const int nm = mpm_adaptive_weights(&r, xm, Lp, 2, b, MAXT, NULL);
      const int np = mpm_adaptive_weights(&r, xp, Lp, 2, c, MAXT, NULL);
      assert_true(n > 0 && nm > 0 && np > 0);
      if (last_level >= 0 && used != last_level) ++level_changes;
      last_level = used;
      for (int k = 0; k < n; ++k) {
        double wm = 0, wp = 0;
        for (int j = 0; j < nm; ++j)
          if (b[j].level == a[k].level && !memcmp(b[j].idx, a[k].idx, sizeof b[j].idx)) wm = b[j].w;
        for (int j = 0; j < np; ++j)
          if (c[j].level == a[k].level && !memcmp(c[j].idx, a[k].idx, sizeof c[j].idx)) wp = c[j].w;
        const double fd = (wp - wm) / (2 * h);
        const double an = a[k].dw[0] * e[0] + a[k].dw[1] * e[1] + a[k].dw[2] * e[2];
        worst = fmax(worst, fabs(fd - an));
        scale = fmax(scale, fabs(an));
      }
    }
  }
  print_message("C1 along lines: %d level changes crossed, largest |FD - grad w . e| %.2e of "
                "largest |grad w . e| %.2e\n",
                level_changes, worst, scale);
  assert_true(level_changes > 0);
  assert_true(worst < (is_double ? 1e-3 : 5e-2) * scale);
  mpm_refinement_free(&r);
}

/* ---- Lian et al. 2015, as Gao sec. 5.1 states it, in 2D (reference only) ----
 * Cell 1 = [-1, 1]^2 in its own coordinates, T-junction b at (1, 0) (finer cells on the right)
 * and d at (0, 1) (finer cells on top): N_b = (1 + x)(1 - |y|)/2, N_d = (1 - |x|)(1 + y)/2
 * (eq. 9), and the corner c next to both, at (1, 1): N_c = H_c - N_b / 2 - N_d / 2 (eq. 10)
 * with H_c = (1 + x)(1 + y)/4. (The paper prints H_c with (1 - y), the hat of the corner
 * (1, -1), which d does not touch; with either, N_c(0.5, 0.1) < 0 as the paper says.) */
static double lian_Nc(double x, double y) {
  const double Hc = 0.25 * (1 + x) * (1 + y);
  const double Nb = 0.5 * (1 + x) * (1 - fabs(y));
  const double Nd = 0.5 * (1 - fabs(x)) * (1 + y);
  return Hc - 0.5 * Nb - 0.5 * Nd;
}

/* its GIMP weight: N_c averaged over a particle box (midpoint rule, exact enough) */
static double lian_wc(double xp, double yp, double half) {
  const int m = 200;
  double s = 0;
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j) {
      const double x = xp - half + (i + 0.5) * 2 * half / m;
      const double y = yp - half + (j + 0.5) * 2 * half / m;
      s += lian_Nc(x, y);
    }
  return s / (m * m);
}

/* 16 particles of 1 kg in the strip where N_c < 0 (Lian coordinates) */
static void strip_particle(int i, int j, double *x, double *y) {
  *x = 0.1 + 0.1 * i;
  *y = 0.05 + 0.05 * j;
}

static void test_lian_negative_ours_not(void **state) {
  (void)state;
  /* Gao's example point x = 0.5, y = 0.1 */
  assert_true(lian_Nc(0.5, 0.1) < 0);
  /* a particle there, box side 0.2 (a tenth of the cell) */
  const double wc = lian_wc(0.5, 0.1, 0.1);
  print_message("Lian et al.: N_c(0.5, 0.1) = %.4f, GIMP weight %.4f\n", lian_Nc(0.5, 0.1), wc);
  assert_true(wc < 0);
  /* a nodal mass: the strip's particles give m_c < 0 */
  double mc = 0;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      double x, y;
      strip_particle(i, j, &x, &y);
      mc += lian_wc(x, y, 0.04);
    }
  print_message("Lian et al.: nodal mass at c from 16 particles of 1 kg: %.4f kg\n", mc);
  assert_true(mc < 0);

  /* ours, the same grid in 3D: coarse cell (0,0,0) of side 1, its +x and +y neighbours
   * refined (b on the +x face, d on the +y face) */
  mpm_refinement r;
  const mpm_real o[3] = {0, 0, 0};
  mpm_refinement_init(&r, 2, o, 1);
  const int32_t right[3] = {1, 0, 0}, top[3] = {0, 1, 0};
  assert_int_equal(mpm_refinement_refine(&r, 0, right), MPM_OK);
  assert_int_equal(mpm_refinement_refine(&r, 0, top), MPM_OK);
  mpm_row_term t[MAXT];
  static mpm_adaptive_weight w[MAXT];
  double least_N = 1, least_w = 1, least_m = 1;
  uint64_t rng = 3;
  for (int s = 0; s < 4000; ++s) {
    const mpm_real x[3] = {(mpm_real)test_rand(&rng, 0, 1), (mpm_real)test_rand(&rng, 0, 1),
                           (mpm_real)test_rand(&rng, 0.2, 0.8)};
    const int n = mpm_refinement_basis_at(&r, x, t, MAXT);
    for (int e = 0; e < n; ++e) least_N = fmin(least_N, t[e].w);
    const int m = mpm_adaptive_weights(&r, x, R_(0.5), -1, w, MAXT, NULL);
    for (int e = 0; e < m; ++e) least_w = fmin(least_w, w[e].w);
  }
  /* the same 16 particles (mapped to the unit cell, box side 0.04): no nodal mass negative */
  static mpm_adaptive_weight acc[MAXT];
  int na = 0;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      double lx, ly;
      strip_particle(i, j, &lx, &ly);
      const mpm_real x[3] = {(mpm_real)((lx + 1) / 2), (mpm_real)((ly + 1) / 2), R_(0.5)};
      const int m = mpm_adaptive_weights(&r, x, R_(0.04), -1, w, MAXT, NULL);
      for (int e = 0; e < m; ++e) {
        int k = 0;
        while (k < na &&
               !(acc[k].level == w[e].level && !memcmp(acc[k].idx, w[e].idx, sizeof acc[k].idx)))
          ++k;
        if (k == na) {
          acc[na] = w[e];
          acc[na++].w = 0;
        }
        acc[k].w += w[e].w;
      }
    }
  for (int k = 0; k < na; ++k) least_m = fmin(least_m, acc[k].w);
  print_message("ours: least N %.3g, least GIMP weight %.3g, least nodal mass %.3g kg\n", least_N,
                least_w, least_m);
  assert_true(least_N >= 0 && least_w >= -1e-7 && least_m >= -1e-7);
  mpm_refinement_free(&r);
}

/* The general-width 1D GIMP weights equal kernel.h's uGIMP when the box fits one cell. */
static void test_gimp_matches_ugimp(void **state) {
  (void)state;
  const mpm_real dx = R_(0.1);
  const mpm_kernel k = mpm_kernel_make(MPM_KERNEL_UGIMP, dx, dx);
  uint64_t rng = 11;
  for (int s = 0; s < 1000; ++s) {
    const mpm_real xg = (mpm_real)test_rand(&rng, -5, 5);
    mpm_real w[MPM_GIMP_NODES_MAX], dw[MPM_GIMP_NODES_MAX];
    int base;
    const int n = mpm_gimp_1d(xg, R_(0.5), &base, w, dw);
    mpm_real uw[4], udw[4], ua[4];
    const int ub = mpm_kernel_1d(&k, xg, uw, udw, ua);
    for (int i = 0; i < n; ++i) {
      const int j = base + i - ub;
      const mpm_real ref = j >= 0 && j < 3 ? uw[j] : 0;
      const mpm_real dref = j >= 0 && j < 3 ? udw[j] * dx : 0;
      assert_true(fabs((double)w[i] - (double)ref) < (is_double ? 1e-12 : 1e-6));
      assert_true(fabs((double)dw[i] - (double)dref) < (is_double ? 1e-12 : 1e-5));
    }
  }
}

/* The dense index answers as the hash does, inside its box and outside (it covers only part of
 * the tree here, and refinements after indexing keep it in step). */
static void test_dense_index_agrees(void **state) {
  (void)state;
  mpm_refinement r;
  random_tree(&r, 4, 31);
  enum { N = 4000 };
  int32_t cell[N][3], level[N], leaf[N];
  uint64_t rng = 7;
  for (int q = 0; q < N; ++q) {
    level[q] = (int32_t)test_rand(&rng, 0, 3);
    for (int d = 0; d < 3; ++d)
      cell[q][d] = (int32_t)floor(test_rand(&rng, -REGION - 1, REGION + 1) * (1 << level[q]));
  }
  int refined[N];
  for (int q = 0; q < N; ++q) refined[q] = mpm_refinement_is_refined(&r, level[q], cell[q]);
  for (int q = 0; q < N; ++q) {
    int32_t c[3];
    for (int d = 0; d < 3; ++d) c[d] = cell[q][d] * (1 << (3 - level[q]));
    leaf[q] = mpm_refinement_leaf_level(&r, c);
  }
  const int32_t lo0[3] = {-REGION, -2, -REGION}, n0[3] = {2 * REGION, 3, 2 * REGION - 1};
  assert_int_equal(mpm_refinement_index_dense(&r, lo0, n0, (size_t)1 << 20), MPM_OK);
  assert_non_null(r.refined[0].bits);
  for (int q = 0; q < N; ++q) {
    assert_int_equal(mpm_refinement_is_refined(&r, level[q], cell[q]), refined[q]);
    int32_t c[3];
    for (int d = 0; d < 3; ++d) c[d] = cell[q][d] * (1 << (3 - level[q]));
    assert_int_equal(mpm_refinement_leaf_level(&r, c), leaf[q]);
  }
  /* a refinement after indexing shows in the index */
  const int32_t fresh[3] = {REGION - 1, 0, REGION - 2};
  assert_int_equal(mpm_refinement_refine(&r, 2, fresh), MPM_OK);
  assert_true(mpm_refinement_is_refined(&r, 2, fresh));
  const int32_t parent[3] = {fresh[0] / 2, 0, fresh[2] / 2};
  assert_true(mpm_refinement_is_refined(&r, 1, parent));
  mpm_refinement_free(&r);
}

/* The finest level of the leaves holding the finest-level cells f0 .. f1 (inclusive). */
static int finest_leaf_in(const mpm_refinement *r, const int32_t f0[3], const int32_t f1[3]) {
  int finest = 0;
  for (int32_t i = f0[0]; i <= f1[0]; ++i)
    for (int32_t j = f0[1]; j <= f1[1]; ++j)
      for (int32_t k = f0[2]; k <= f1[2]; ++k) {
        const int32_t c[3] = {i, j, k};
        const int L = mpm_refinement_leaf_level(r, c);
        if (L > finest) finest = L;
      }
  return finest;
}

/* The finest level a box meets, against the leaves themselves: every finest-level cell that
 * meets the box (closed: touching counts) and its leaf's level, the largest of them. The query
 * takes, as the tree descent it replaced did, the level-0 cells from the one holding the box's
 * low corner on (a leaf below that cell, touching the box's low face, does not count). Boxes of
 * every width up to two level-0 cells, half of them snapped to the finest lattice's half cells
 * so that their faces lie on cell faces. */
static void test_finest_level_in_against_leaves(void **state) {
  (void)state;
  for (int levels = 2; levels <= 4; ++levels) {
    mpm_refinement r;
    random_tree(&r, levels, 40 + (uint64_t)levels);
    const int fs = levels - 1; /* finest cells per level-0 cell, as a shift */
    const double fine = (double)r.dx0 / (1 << fs);
    uint64_t rng = 11;
    int seen[MPM_LEVELS_MAX] = {0};
    for (int q = 0; q < 3000; ++q) {
      mpm_real lo[3], hi[3];
      const double w = test_rand(&rng, 0, 2) * (double)r.dx0;
      for (int d = 0; d < 3; ++d) {
        double a = test_rand(&rng, -REGION + 0.2, REGION - 2.2) * (double)r.dx0;
        double b = a + w;
        if (q % 2) { /* on the half cells of the finest lattice */
          a = floor(a / (0.5 * fine)) * 0.5 * fine;
          b = floor(b / (0.5 * fine)) * 0.5 * fine;
        }
        lo[d] = r.origin[d] + (mpm_real)a;
        hi[d] = r.origin[d] + (mpm_real)b;
      }
      int32_t f0[3], f1[3];
      for (int d = 0; d < 3; ++d) {
        const double a = ((double)lo[d] - (double)r.origin[d]) / (double)r.dx0;
        const double b = ((double)hi[d] - (double)r.origin[d]) / (double)r.dx0;
        const int32_t touch = (int32_t)ceil(a * (1 << fs)) - 1;
        const int32_t first = (int32_t)floor(a) * (1 << fs);
        f0[d] = touch > first ? touch : first;
        f1[d] = (int32_t)floor(b * (1 << fs));
      }
      const int expect = finest_leaf_in(&r, f0, f1);
      assert_int_equal(mpm_refinement_finest_level_in(&r, lo, hi), expect);
      seen[expect]++;
    }
    for (int L = 0; L < levels; ++L) assert_true(seen[L] > 0); /* every answer was asked for */
    mpm_refinement_free(&r);
  }
}

/* The particles' transfer level (mpm_refinement_finest_level_overlapping): the finest level of
 * the leaves a box overlaps with some volume, against the leaves themselves; and for boxes on
 * the lattice (as sampled particles' are), whose faces lie on cell faces, the weights at that
 * level equal those at the finer level of the leaves the closed box merely touches. */
static void test_transfer_level_ignores_touching_leaves(void **state) {
  (void)state;
  const double tol = is_double ? 1e-9 : 3e-5;
  for (int levels = 3; levels <= 4; ++levels) {
    mpm_refinement r;
    random_tree(&r, levels, 60 + (uint64_t)levels);
    const int fs = levels - 1;
    uint64_t rng = 13;
    int coarser = 0;
    double worst = 0;
    static mpm_adaptive_weight w[MAXT], w2[MAXT];
    for (int s = 0; s < 2000; ++s) {
      const int q = (int)test_rand(&rng, 0, levels - 0.001); /* the particle's type */
      const double dq = (double)r.dx0 / (1 << q);
      mpm_real x[3];
      for (int d = 0; d < 3; ++d) { /* a lattice point of type q: box faces on cell faces */
        const double m = floor(test_rand(&rng, -REGION + 1, REGION - 1) * (1 << q));
        x[d] = r.origin[d] + (mpm_real)((m + (test_rand(&rng, 0, 1) < 0.5 ? 0.25 : 0.75)) * dq);
      }
      const mpm_real Lp = (mpm_real)(0.5 * dq);
      double a[3], b[3];
      mpm_real lo[3], hi[3];
      int32_t f0[3], f1[3];
      for (int d = 0; d < 3; ++d) {
        lo[d] = x[d] - (mpm_real)(0.5 * Lp);
        hi[d] = x[d] + (mpm_real)(0.5 * Lp);
        a[d] = ((double)lo[d] - (double)r.origin[d]) / (double)r.dx0;
        b[d] = ((double)hi[d] - (double)r.origin[d]) / (double)r.dx0;
        f0[d] = (int32_t)floor(a[d] * (1 << fs));
        f1[d] = (int32_t)ceil(b[d] * (1 << fs)) - 1;
      }
      const int expect = finest_leaf_in(&r, f0, f1);
      const int open = mpm_refinement_finest_level_overlapping(&r, a, b);
      assert_int_equal(open, expect);
      const int closed = mpm_refinement_finest_level_in(&r, lo, hi);
      assert_true(open <= closed);
      if (open == closed || (double)Lp > 2 * (double)mpm_refinement_dx(&r, closed)) continue;
      const int n = mpm_adaptive_weights(&r, x, Lp, open, w, MAXT, NULL);
      const int n2 = mpm_adaptive_weights(&r, x, Lp, closed, w2, MAXT, NULL);
      assert_true(n > 0 && n2 > 0);
      worst = fmax(worst, weights_differ(w, n, w2, n2));
      coarser++;
    }
    print_message("levels %d: %d of 2000 lattice boxes transfer on a coarser level than the "
                  "leaves they touch; weights differ by at most %.2e\n",
                  levels, coarser, worst);
    assert_true(coarser > 0);
    assert_true(worst < tol);
    mpm_refinement_free(&r);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_single_level),
      cmocka_unit_test(test_tjunction_rows),
      cmocka_unit_test(test_random_rows_and_basis),
      cmocka_unit_test(test_gimp_weights),
      cmocka_unit_test(test_gimp_c1_along_lines),
      cmocka_unit_test(test_lian_negative_ours_not),
      cmocka_unit_test(test_gimp_matches_ugimp),
      cmocka_unit_test(test_dense_index_agrees),
      cmocka_unit_test(test_finest_level_in_against_leaves),
      cmocka_unit_test(test_transfer_level_ignores_touching_leaves),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
