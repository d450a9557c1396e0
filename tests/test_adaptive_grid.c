/* test_adaptive_grid.c - the multi-level sparse grid's ghost slots (grid/adaptive_grid.h): a
 * P2G and G2P through them against the direct evaluation of w_ip over real nodes
 * (interp/adaptive_weights.h), on a random non-graded tree of 3 levels:
 *   - every particle transfers on the finest level its box meets (uGIMP, any box width); after
 *     the ghost scatter no ghost holds mass, every real node holds exactly the mass of the
 *     direct w_ip, none is negative, and mass and momentum are conserved;
 *   - every ghost's parents are active (close works to a fixed point across levels);
 *   - a linear velocity field on the real nodes, gathered to the ghosts, is exact at every ghost
 *     and the G2P of it is exact at every particle;
 *   - one level: no ghosts at all. */
#include "support.h"
#include "grid/adaptive_grid.h"
#include "interp/adaptive_weights.h"
#include "interp/gimp.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define PARTICLES 600
#define REGION 2

static const int is_double = sizeof(mpm_real) == 8;

typedef struct cloud {
  mpm_real x[PARTICLES][3], v[PARTICLES][3], m[PARTICLES], Lp[PARTICLES];
  int level[PARTICLES]; /* transfer level */
} cloud;

static void refine_random(mpm_refinement *r, int L, const int32_t c[3], double p, uint64_t *rng) {
  if (L >= r->levels - 1 || test_rand(rng, 0, 1) >= p) return;
  assert_int_equal(mpm_refinement_refine(r, L, c), 0);
  for (int k = 0; k < 8; ++k) {
    const int32_t ch[3] = {2 * c[0] + (k & 1), 2 * c[1] + ((k >> 1) & 1), 2 * c[2] + (k >> 2)};
    refine_random(r, L + 1, ch, p, rng);
  }
}

/* The uGIMP stencil of particle p on its transfer level: base and width per axis, weights. */
static void stencil(const mpm_adaptive_grid *g, const cloud *c, int p, int base[3], int n[3],
                    mpm_real w[3][MPM_GIMP_NODES_MAX]) {
  const mpm_real dx = mpm_refinement_dx(&g->tree, c->level[p]);
  mpm_real dw[MPM_GIMP_NODES_MAX];
  for (int d = 0; d < 3; ++d) {
    n[d] = mpm_gimp_1d((c->x[p][d] - g->tree.origin[d]) / dx, c->Lp[p] / (2 * dx), &base[d], w[d],
                       dw);
    assert_true(n[d] > 0);
  }
}

static void slot_position(const mpm_adaptive_grid *g, size_t slot, double x[3]) {
  for (int L = 0; L < g->tree.levels; ++L) {
    const mpm_grid *lv = &g->level[L];
    const size_t count = lv->ops->node_count(lv);
    if (slot < lv->dof_begin || slot >= lv->dof_begin + count) continue;
    const size_t node = slot - lv->dof_begin;
    const int32_t *bc = lv->impl.sparse.coord[node / MPM_BLOCK_NODES];
    const int local = (int)(node % MPM_BLOCK_NODES);
    const int32_t idx[3] = {bc[0] * 4 + ((local >> 4) & 3), bc[1] * 4 + ((local >> 2) & 3),
                            bc[2] * 4 + (local & 3)};
    for (int d = 0; d < 3; ++d) x[d] = (double)lv->origin[d] + idx[d] * (double)lv->dx;
    return;
  }
  fail_msg("slot %zu is on no level", slot);
}

static void run(int levels, uint64_t seed) {
  mpm_adaptive_grid g;
  const mpm_real o[3] = {R_(0.1), R_(-0.2), R_(0.05)};
  mpm_adaptive_grid_init(&g, levels, o, R_(0.25));
  uint64_t rng = seed;
  for (int32_t i = -REGION; i < REGION; ++i)
    for (int32_t j = -REGION; j < REGION; ++j)
      for (int32_t k = -REGION; k < REGION; ++k) {
        const int32_t c[3] = {i, j, k};
        refine_random(&g.tree, 0, c, 0.5, &rng);
      }
  static cloud c;
  for (int p = 0; p < PARTICLES; ++p) {
    for (int d = 0; d < 3; ++d) {
      c.x[p][d] = o[d] + (mpm_real)(test_rand(&rng, -REGION + 0.3, REGION - 0.3) * 0.25);
      c.v[p][d] = (mpm_real)test_rand(&rng, -1, 1);
    }
    c.m[p] = (mpm_real)test_rand(&rng, 0.5, 2);
    int32_t cell[3];
    c.Lp[p] = mpm_refinement_dx(&g.tree, mpm_refinement_leaf_at(&g.tree, c.x[p], cell));
    mpm_real lo[3], hi[3];
    for (int d = 0; d < 3; ++d) {
      lo[d] = c.x[p][d] - c.Lp[p] / 2;
      hi[d] = c.x[p][d] + c.Lp[p] / 2;
    }
    c.level[p] = mpm_refinement_finest_level_in(&g.tree, lo, hi);
    int base[3], n[3];
    mpm_real w[3][MPM_GIMP_NODES_MAX];
    stencil(&g, &c, p, base, n, w);
    const int32_t blo[3] = {base[0], base[1], base[2]};
    const int32_t bhi[3] = {base[0] + n[0] - 1, base[1] + n[1] - 1, base[2] + n[2] - 1};
    assert_int_equal(mpm_adaptive_grid_activate_box(&g, c.level[p], blo, bhi), 0);
  }
  assert_int_equal(mpm_adaptive_grid_close(&g), 0);
  size_t total = 0;
  for (int L = 0; L < levels; ++L) {
    g.level[L].dof_begin = total;
    total += g.level[L].ops->node_count(&g.level[L]);
  }
  assert_int_equal(mpm_adaptive_grid_build_rows(&g), 0);
  print_message("%d levels: %zu slots, %zu ghosts, %zu row entries, %zu bytes\n", levels, total,
                g.ghost_count, (size_t)g.ghosts.row_start[g.ghost_count],
                mpm_adaptive_grid_bytes(&g));
  if (levels == 1) {
    assert_int_equal(g.ghost_count, 0);
  } else {
    assert_true(g.ghost_count > 0);
  }
  mpm_real *u[4];
  double *ref = calloc(total, sizeof *ref);
  uint8_t *ghost = calloc(total, 1);
  for (int k = 0; k < 4; ++k) u[k] = calloc(total, sizeof(mpm_real));
  for (size_t a = 0; a < g.ghost_count; ++a) ghost[g.ghost_slot[a]] = 1;
  /* P2G on each particle's level, and the reference over real nodes */
  double mass = 0, mom[3] = {0, 0, 0};
  static mpm_adaptive_weight rw[1024];
  for (int p = 0; p < PARTICLES; ++p) {
    int base[3], n[3];
    mpm_real w[3][MPM_GIMP_NODES_MAX];
    stencil(&g, &c, p, base, n, w);
    for (int i = 0; i < n[0]; ++i)
      for (int j = 0; j < n[1]; ++j)
        for (int k = 0; k < n[2]; ++k) {
          const int32_t idx[3] = {base[0] + i, base[1] + j, base[2] + k};
          const int64_t s = mpm_adaptive_grid_slot(&g, c.level[p], idx);
          assert_true(s >= 0);
          const mpm_real mw = c.m[p] * w[0][i] * w[1][j] * w[2][k];
          u[0][s] += mw;
          for (int d = 0; d < 3; ++d) u[1 + d][s] += mw * c.v[p][d];
        }
    mass += c.m[p];
    for (int d = 0; d < 3; ++d) mom[d] += (double)c.m[p] * c.v[p][d];
    const int nr = mpm_adaptive_weights(&g.tree, c.x[p], c.Lp[p], -1, rw, 1024, NULL);
    assert_true(nr > 0);
    for (int e = 0; e < nr; ++e) {
      const int64_t s = mpm_adaptive_grid_slot(&g, rw[e].level, rw[e].idx);
      assert_true(s >= 0); /* every real node a particle reaches is an active slot */
      assert_false(ghost[s]);
      ref[s] += c.m[p] * rw[e].w;
    }
  }
  mpm_adaptive_grid_scatter(&g, 4, u);
  double smass = 0, smom[3] = {0, 0, 0}, worst = 0, least = 0;
  for (size_t s = 0; s < total; ++s) {
    if (ghost[s]) {
      for (int k = 0; k < 4; ++k) assert_true(u[k][s] == 0);
      continue;
    }
    smass += u[0][s];
    for (int d = 0; d < 3; ++d) smom[d] += u[1 + d][s];
    worst = fmax(worst, fabs(u[0][s] - ref[s]));
    least = fmin(least, u[0][s]);
  }
  const double tol = is_double ? 1e-12 : 2e-5;
  print_message("%d levels: mass %.9g of %.9g, largest |m_i - sum_p m_p w_ip| %.2e, least m_i "
                "%.2e\n",
                levels, smass, mass, worst, least);
  assert_true(fabs(smass - mass) < tol * mass);
  for (int d = 0; d < 3; ++d) assert_true(fabs(smom[d] - mom[d]) < tol * mass);
  assert_true(worst < tol * 4); /* float: sums of ~30 terms of about 1 */
  assert_true(least >= -tol);
  /* a linear field on the real slots, gathered to the ghosts */
  const double A[3][3] = {{0.3, -1.2, 0.5}, {2.0, 0.1, -0.7}, {-0.4, 0.9, 1.1}};
  const double b[3] = {0.2, -0.3, 0.5};
  for (size_t s = 0; s < total; ++s) {
    double x[3];
    slot_position(&g, s, x);
    for (int d = 0; d < 3; ++d)
      u[1 + d][s] = ghost[s] ? 1e30f : (mpm_real)(A[d][0] * x[0] + A[d][1] * x[1] + A[d][2] * x[2] + b[d]);
  }
  mpm_adaptive_grid_gather(&g, 3, u + 1);
  double worst_ghost = 0;
  for (size_t a = 0; a < g.ghost_count; ++a) {
    double x[3];
    slot_position(&g, g.ghost_slot[a], x);
    for (int d = 0; d < 3; ++d)
      worst_ghost = fmax(worst_ghost, fabs(u[1 + d][g.ghost_slot[a]] -
                                           (A[d][0] * x[0] + A[d][1] * x[1] + A[d][2] * x[2] + b[d])));
  }
  double worst_g2p = 0;
  for (int p = 0; p < PARTICLES; ++p) {
    int base[3], n[3];
    mpm_real w[3][MPM_GIMP_NODES_MAX];
    stencil(&g, &c, p, base, n, w);
    double vp[3] = {0, 0, 0};
    for (int i = 0; i < n[0]; ++i)
      for (int j = 0; j < n[1]; ++j)
        for (int k = 0; k < n[2]; ++k) {
          const int32_t idx[3] = {base[0] + i, base[1] + j, base[2] + k};
          const int64_t s = mpm_adaptive_grid_slot(&g, c.level[p], idx);
          const double wg = (double)w[0][i] * w[1][j] * w[2][k];
          for (int d = 0; d < 3; ++d) vp[d] += wg * u[1 + d][s];
        }
    for (int d = 0; d < 3; ++d)
      worst_g2p = fmax(worst_g2p, fabs(vp[d] - (A[d][0] * c.x[p][0] + A[d][1] * c.x[p][1] +
                                                A[d][2] * c.x[p][2] + b[d])));
  }
  print_message("%d levels: linear field: largest error at a ghost %.2e, at a particle %.2e\n",
                levels, worst_ghost, worst_g2p);
  const double vtol = is_double ? 1e-12 : 1e-5;
  assert_true(worst_ghost < vtol && worst_g2p < vtol);
  for (int k = 0; k < 4; ++k) free(u[k]);
  free(ref);
  free(ghost);
  mpm_adaptive_grid_free(&g);
}

static void test_one_level(void **state) {
  (void)state;
  run(1, 3);
}

static void test_three_levels(void **state) {
  (void)state;
  run(3, 5);
}

static void test_four_levels(void **state) {
  (void)state;
  run(4, 8);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_one_level),
      cmocka_unit_test(test_three_levels),
      cmocka_unit_test(test_four_levels),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
