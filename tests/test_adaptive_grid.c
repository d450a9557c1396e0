/* test_adaptive_grid.c - the multi-level sparse grid's ghost slots (adaptive/grid.h): a
 * P2G and G2P through them against the direct evaluation of w_ip over real nodes
 * (adaptive/weights.h), on a random non-graded tree of 3 levels:
 *   - every particle transfers on the finest level its box meets (uGIMP, any box width); after
 *     the ghost scatter no ghost holds mass, every real node holds exactly the mass of the
 *     direct w_ip, none is negative, and mass and momentum are conserved;
 *   - every ghost's parents are active (close works to a fixed point across levels);
 *   - a linear velocity field on the real nodes, gathered to the ghosts, is exact at every ghost
 *     and the G2P of it is exact at every particle;
 *   - one level: no ghosts at all;
 *   - APIC across levels (docs/adaptive-grid.md): with the ghosts' affine moments A_g in P2G
 *     every real node gets exactly sum_p w_ip m_p (v_p + C_p (x_i - x_p)), and the grid's angular
 *     momentum equals the particles' (x_p x m_p v_p plus the affine part m_p eps : (C_p D_p)^T);
 *     without the moments it does not. In G2P the ghosts' moments M_g and spreads S_g give the
 *     real-node B_p and D_p exactly. */
#include "refinement_support.h"
#include "support.h"
#include "adaptive/grid.h"
#include "adaptive/weights.h"
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

/* The uGIMP stencil of particle p on its transfer level: base and width per axis, weights. */
static void stencil(const mpm_adaptive_grid *g, const cloud *c, int p, int base[3], int n[3],
                    mpm_real w[3][MPM_GIMP_NODES_MAX]) {
  const mpm_real dx = mpm_refinement_dx(&g->tree, c->level[p]);
  mpm_real dw[MPM_GIMP_NODES_MAX];
  for (int d = 0; d < 3; ++d) {
    n[d] =
        mpm_gimp_1d((c->x[p][d] - g->tree.origin[d]) / dx, c->Lp[p] / (2 * dx), &base[d], w[d], dw);
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

static size_t setup(mpm_adaptive_grid *g, cloud *c, int levels, uint64_t seed);

/* The ghosts' scatter schedule: built, every ghost in one group, and no two groups of one colour
 * with a parent in common (the parallel scatter's condition, grid/scatter_schedule.h). */
static void check_schedule(const mpm_adaptive_grid *g, size_t total) {
  const mpm_embedding *E = &g->ghosts;
  const mpm_scatter_schedule *S = &E->schedule;
  assert_true(S->built);
  int32_t *owner = malloc(total * sizeof *owner); /* per column: the group that wrote it */
  size_t rows = 0;
  for (int colour = 0; colour < MPM_SCHEDULE_COLOURS; ++colour) {
    for (size_t i = 0; i < total; ++i) owner[i] = -1;
    for (size_t q = S->colour_start[colour]; q < S->colour_start[colour + 1]; ++q)
      for (uint32_t j = S->group_start[q]; j < S->group_start[q + 1]; ++j, ++rows) {
        const uint32_t a = S->group_row[j];
        for (uint32_t e = E->row_start[a]; e < E->row_start[a] + E->row_len[a]; ++e) {
          assert_true(owner[E->col[e]] == -1 || owner[E->col[e]] == (int32_t)q);
          owner[E->col[e]] = (int32_t)q;
        }
      }
  }
  assert_int_equal(rows + S->own_rows, g->ghost_count);
  free(owner);
}

static void run(int levels, uint64_t seed) {
  static mpm_adaptive_grid g;
  static cloud c;
  const size_t total = setup(&g, &c, levels, seed);
  print_message("%d levels: %zu slots, %zu ghosts, %zu row entries, %zu bytes\n", levels, total,
                g.ghost_count, (size_t)g.ghosts.row_start[g.ghost_count],
                mpm_adaptive_grid_bytes(&g));
  if (levels == 1) {
    assert_int_equal(g.ghost_count, 0);
  } else {
    assert_true(g.ghost_count > 0);
    check_schedule(&g, total);
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
      u[1 + d][s] =
          ghost[s] ? 1e30f : (mpm_real)(A[d][0] * x[0] + A[d][1] * x[1] + A[d][2] * x[2] + b[d]);
  }
  mpm_adaptive_grid_gather(&g, 3, u + 1);
  double worst_ghost = 0;
  for (size_t a = 0; a < g.ghost_count; ++a) {
    double x[3];
    slot_position(&g, g.ghost_slot[a], x);
    for (int d = 0; d < 3; ++d)
      worst_ghost =
          fmax(worst_ghost, fabs(u[1 + d][g.ghost_slot[a]] -
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

/* Mark the stencil of every particle of the cloud used (activating its blocks). */
static void mark_cloud(mpm_adaptive_grid *g, const cloud *c) {
  for (int p = 0; p < PARTICLES; ++p) {
    int base[3], n[3];
    mpm_real w[3][MPM_GIMP_NODES_MAX];
    stencil(g, c, p, base, n, w);
    const int32_t blo[3] = {base[0], base[1], base[2]};
    const int32_t bhi[3] = {base[0] + n[0] - 1, base[1] + n[1] - 1, base[2] + n[2] - 1};
    assert_int_equal(mpm_adaptive_grid_activate_box(g, c->level[p], blo, bhi), MPM_OK);
  }
}

/* The tree, the cloud and the activated, closed, laid-out grid of run(), for the APIC test. */
static size_t setup(mpm_adaptive_grid *g, cloud *c, int levels, uint64_t seed) {
  const mpm_real o[3] = {R_(0.1), R_(-0.2), R_(0.05)};
  mpm_adaptive_grid_init(g, levels, o, R_(0.25));
  uint64_t rng = seed;
  for (int32_t i = -REGION; i < REGION; ++i)
    for (int32_t j = -REGION; j < REGION; ++j)
      for (int32_t k = -REGION; k < REGION; ++k) {
        const int32_t cc[3] = {i, j, k};
        test_refine_random(&g->tree, 0, cc, 0.5, &rng);
      }
  for (int p = 0; p < PARTICLES; ++p) {
    for (int d = 0; d < 3; ++d) {
      c->x[p][d] = o[d] + (mpm_real)(test_rand(&rng, -REGION + 0.3, REGION - 0.3) * 0.25);
      c->v[p][d] = (mpm_real)test_rand(&rng, -1, 1);
    }
    c->m[p] = (mpm_real)test_rand(&rng, 0.5, 2);
    int32_t cell[3];
    c->Lp[p] = mpm_refinement_dx(&g->tree, mpm_refinement_leaf_at(&g->tree, c->x[p], cell));
    mpm_real lo[3], hi[3];
    for (int d = 0; d < 3; ++d) {
      lo[d] = c->x[p][d] - c->Lp[p] / 2;
      hi[d] = c->x[p][d] + c->Lp[p] / 2;
    }
    c->level[p] = mpm_refinement_finest_level_in(&g->tree, lo, hi);
  }
  mark_cloud(g, c);
  assert_int_equal(mpm_adaptive_grid_close(g), MPM_OK);
  size_t total = 0;
  for (int L = 0; L < levels; ++L) {
    g->level[L].dof_begin = total;
    total += g->level[L].ops->node_count(&g->level[L]);
  }
  assert_int_equal(mpm_adaptive_grid_build_rows(g), MPM_OK);
  return total;
}

static void cross_add(double L[3], const double a[3], const double b[3], double s) {
  L[0] += s * (a[1] * b[2] - a[2] * b[1]);
  L[1] += s * (a[2] * b[0] - a[0] * b[2]);
  L[2] += s * (a[0] * b[1] - a[1] * b[0]);
}

static void test_apic_across_levels(void **state) {
  (void)state;
  static mpm_adaptive_grid g;
  static cloud c;
  const size_t total = setup(&g, &c, 3, 41);
  uint64_t rng = 77;
  static double C[PARTICLES][9];
  for (int p = 0; p < PARTICLES; ++p)
    for (int q = 0; q < 9; ++q) C[p][q] = test_rand(&rng, -2, 2);
  int32_t *ghost_of = malloc(total * sizeof *ghost_of);
  for (size_t s = 0; s < total; ++s) ghost_of[s] = -1;
  for (size_t a = 0; a < g.ghost_count; ++a) ghost_of[g.ghost_slot[a]] = (int32_t)a;
  mpm_real *u[4], *u_plain[4], *A[9];
  for (int k = 0; k < 4; ++k) {
    u[k] = calloc(total, sizeof(mpm_real));
    u_plain[k] = calloc(total, sizeof(mpm_real));
  }
  for (int q = 0; q < 9; ++q) A[q] = calloc(g.ghost_count + 1, sizeof(mpm_real));
  double *ref[3];
  for (int d = 0; d < 3; ++d) ref[d] = calloc(total, sizeof(double));
  static mpm_adaptive_weight rw[1024];
  static double D[PARTICLES][9];
  double Lp[3] = {0, 0, 0};
  for (int p = 0; p < PARTICLES; ++p) {
    int base[3], n[3];
    mpm_real w[3][MPM_GIMP_NODES_MAX];
    stencil(&g, &c, p, base, n, w);
    for (int i = 0; i < n[0]; ++i)
      for (int j = 0; j < n[1]; ++j)
        for (int k = 0; k < n[2]; ++k) {
          const int32_t idx[3] = {base[0] + i, base[1] + j, base[2] + k};
          const int64_t s = mpm_adaptive_grid_slot(&g, c.level[p], idx);
          double xs[3];
          slot_position(&g, (size_t)s, xs);
          const double mw = (double)c.m[p] * w[0][i] * w[1][j] * w[2][k];
          for (int e = 0; e < 2; ++e) (e ? u_plain : u)[0][s] += (mpm_real)mw;
          for (int d = 0; d < 3; ++d) {
            double pd = c.v[p][d];
            for (int q = 0; q < 3; ++q) pd += C[p][3 * d + q] * (xs[q] - c.x[p][q]);
            u[1 + d][s] += (mpm_real)(mw * pd);
            u_plain[1 + d][s] += (mpm_real)(mw * pd);
          }
          if (ghost_of[s] >= 0)
            for (int q = 0; q < 9; ++q) A[q][ghost_of[s]] += (mpm_real)(mw * C[p][q]);
        }
    /* the reference over real nodes, and D_p there */
    const int nr = mpm_adaptive_weights(&g.tree, c.x[p], c.Lp[p], -1, rw, 1024, NULL);
    memset(D[p], 0, sizeof D[p]);
    for (int e = 0; e < nr; ++e) {
      const int64_t s = mpm_adaptive_grid_slot(&g, rw[e].level, rw[e].idx);
      double xi[3], r[3];
      slot_position(&g, (size_t)s, xi);
      for (int d = 0; d < 3; ++d) r[d] = xi[d] - c.x[p][d];
      for (int d = 0; d < 3; ++d) {
        double pd = c.v[p][d];
        for (int q = 0; q < 3; ++q) pd += C[p][3 * d + q] * r[q];
        ref[d][s] += c.m[p] * rw[e].w * pd;
        for (int q = 0; q < 3; ++q) D[p][3 * d + q] += rw[e].w * r[d] * r[q];
      }
    }
    /* the particle's angular momentum: x_p x m_p v_p + m_p eps_abc (C_p D_p)_cb */
    const double xp[3] = {c.x[p][0], c.x[p][1], c.x[p][2]};
    const double vp[3] = {c.v[p][0], c.v[p][1], c.v[p][2]};
    cross_add(Lp, xp, vp, c.m[p]);
    double CD[9] = {0};
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b)
        for (int q = 0; q < 3; ++q) CD[3 * a + b] += C[p][3 * a + q] * D[p][3 * q + b];
    Lp[0] += c.m[p] * (CD[3 * 2 + 1] - CD[3 * 1 + 2]);
    Lp[1] += c.m[p] * (CD[3 * 0 + 2] - CD[3 * 2 + 0]);
    Lp[2] += c.m[p] * (CD[3 * 1 + 0] - CD[3 * 0 + 1]);
  }
  const mpm_real *const Ac[9] = {A[0], A[1], A[2], A[3], A[4], A[5], A[6], A[7], A[8]};
  mpm_adaptive_grid_scatter_apic(&g, 4, u, Ac);
  mpm_adaptive_grid_scatter(&g, 4, u_plain);
  double worst = 0, worst_plain = 0, Lg[3] = {0, 0, 0}, Lg_plain[3] = {0, 0, 0}, scale = 0;
  for (size_t s = 0; s < total; ++s) {
    if (ghost_of[s] >= 0) continue;
    double xs[3];
    slot_position(&g, s, xs);
    const double pi[3] = {u[1][s], u[2][s], u[3][s]};
    const double pp[3] = {u_plain[1][s], u_plain[2][s], u_plain[3][s]};
    cross_add(Lg, xs, pi, 1);
    cross_add(Lg_plain, xs, pp, 1);
    for (int d = 0; d < 3; ++d) {
      worst = fmax(worst, fabs(pi[d] - ref[d][s]));
      worst_plain = fmax(worst_plain, fabs(pp[d] - ref[d][s]));
      scale = fmax(scale, fabs(ref[d][s]));
    }
  }
  double dL = 0, dL_plain = 0, Ln = 0;
  for (int d = 0; d < 3; ++d) {
    dL = fmax(dL, fabs(Lg[d] - Lp[d]));
    dL_plain = fmax(dL_plain, fabs(Lg_plain[d] - Lp[d]));
    Ln = fmax(Ln, fabs(Lp[d]));
  }
  print_message("APIC P2G across levels: largest |p_i - ref| %.2e (without ghost moments %.2e) of "
                "%.2e; angular momentum error %.2e (without %.2e) of %.2e\n",
                worst, worst_plain, scale, dL, dL_plain, Ln);
  const double tol = is_double ? 1e-12 : 3e-5;
  assert_true(worst < tol * scale);
  assert_true(dL < tol * 10 * Ln);
  assert_true(worst_plain > 1e3 * tol * scale && dL_plain > 1e3 * tol * Ln);

  /* G2P: a random velocity on the real slots; B_p and D_p through the ghosts */
  for (size_t s = 0; s < total; ++s)
    for (int d = 0; d < 3; ++d)
      u[1 + d][s] = ghost_of[s] >= 0 ? 0 : (mpm_real)test_rand(&rng, -1, 1);
  mpm_adaptive_grid_gather(&g, 3, u + 1);
  mpm_real *M[9];
  for (int q = 0; q < 9; ++q) M[q] = calloc(g.ghost_count + 1, sizeof(mpm_real));
  const mpm_real *const vv[3] = {u[1], u[2], u[3]};
  mpm_adaptive_grid_gather_moments(&g, vv, M);
  double worst_B = 0, worst_D = 0, Bscale = 0;
  for (int p = 0; p < PARTICLES; ++p) {
    int base[3], n[3];
    mpm_real w[3][MPM_GIMP_NODES_MAX];
    stencil(&g, &c, p, base, n, w);
    double B[9] = {0}, Dg[9] = {0};
    for (int i = 0; i < n[0]; ++i)
      for (int j = 0; j < n[1]; ++j)
        for (int k = 0; k < n[2]; ++k) {
          const int32_t idx[3] = {base[0] + i, base[1] + j, base[2] + k};
          const int64_t s = mpm_adaptive_grid_slot(&g, c.level[p], idx);
          double xs[3], r[3];
          slot_position(&g, (size_t)s, xs);
          for (int d = 0; d < 3; ++d) r[d] = xs[d] - c.x[p][d];
          const double wg = (double)w[0][i] * w[1][j] * w[2][k];
          const int32_t a = ghost_of[s];
          const double Sg[9] = {a >= 0 ? g.spread[6 * a + 0] : 0, a >= 0 ? g.spread[6 * a + 3] : 0,
                                a >= 0 ? g.spread[6 * a + 4] : 0, a >= 0 ? g.spread[6 * a + 3] : 0,
                                a >= 0 ? g.spread[6 * a + 1] : 0, a >= 0 ? g.spread[6 * a + 5] : 0,
                                a >= 0 ? g.spread[6 * a + 4] : 0, a >= 0 ? g.spread[6 * a + 5] : 0,
                                a >= 0 ? g.spread[6 * a + 2] : 0};
          for (int d = 0; d < 3; ++d)
            for (int q = 0; q < 3; ++q) {
              B[3 * d + q] += wg * (u[1 + d][s] * r[q] + (a >= 0 ? M[3 * d + q][a] : 0));
              Dg[3 * d + q] += wg * (r[d] * r[q] + Sg[3 * d + q]);
            }
        }
    const int nr = mpm_adaptive_weights(&g.tree, c.x[p], c.Lp[p], -1, rw, 1024, NULL);
    double Bref[9] = {0};
    for (int e = 0; e < nr; ++e) {
      const int64_t s = mpm_adaptive_grid_slot(&g, rw[e].level, rw[e].idx);
      double xi[3];
      slot_position(&g, (size_t)s, xi);
      for (int d = 0; d < 3; ++d)
        for (int q = 0; q < 3; ++q) Bref[3 * d + q] += rw[e].w * u[1 + d][s] * (xi[q] - c.x[p][q]);
    }
    for (int q = 0; q < 9; ++q) {
      worst_B = fmax(worst_B, fabs(B[q] - Bref[q]));
      worst_D = fmax(worst_D, fabs(Dg[q] - D[p][q]));
      Bscale = fmax(Bscale, fabs(Bref[q]));
    }
  }
  print_message("APIC G2P across levels: largest |B_p - ref| %.2e of %.2e, |D_p - ref| %.2e\n",
                worst_B, Bscale, worst_D);
  assert_true(worst_B < tol * 10 * Bscale);
  assert_true(worst_D < tol * 0.25 * 0.25);
  for (int q = 0; q < 9; ++q) {
    free(A[q]);
    free(M[q]);
  }
  for (int k = 0; k < 4; ++k) {
    free(u[k]);
    free(u_plain[k]);
  }
  for (int d = 0; d < 3; ++d) free(ref[d]);
  free(ghost_of);
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

/* A second close of the same marks, the tree unchanged, finds every row in the caches (the
 * path that runs blocks in parallel): the same ghosts, rows and blocks as the first close, which
 * took the serial path and filled the caches. */
static void test_close_from_caches(void **state) {
  (void)state;
  static mpm_adaptive_grid g;
  static cloud c;
  for (int levels = 3; levels <= 4; ++levels) {
    const size_t total = setup(&g, &c, levels, 11 + (uint64_t)levels);
    const size_t n = g.build.count, nt = g.build.term_count;
    assert_true(n > 0);
    uint32_t *len = malloc(n * sizeof *len), (*where)[3] = malloc(n * sizeof *where);
    mpm_row_term *terms = malloc(nt * sizeof *terms);
    uint32_t *slot = malloc(n * sizeof *slot);
    memcpy(len, g.build.len, n * sizeof *len);
    memcpy(where, g.build.where, n * sizeof *where);
    memcpy(terms, g.build.terms, nt * sizeof *terms);
    memcpy(slot, g.ghost_slot, n * sizeof *slot);
    size_t blocks[MPM_LEVELS_MAX];
    for (int L = 0; L < levels; ++L) blocks[L] = g.level[L].impl.sparse.block_count;
    mpm_adaptive_grid_clear_marks(&g);
    mark_cloud(&g, &c);
    assert_int_equal(mpm_adaptive_grid_close(&g), MPM_OK);
    assert_int_equal(g.build.count, n);
    assert_int_equal(g.build.term_count, nt);
    assert_memory_equal(g.build.len, len, n * sizeof *len);
    assert_memory_equal(g.build.where, where, n * sizeof *where);
    assert_memory_equal(g.build.terms, terms, nt * sizeof *terms);
    size_t total2 = 0;
    for (int L = 0; L < levels; ++L) {
      assert_int_equal(g.level[L].impl.sparse.block_count, blocks[L]);
      g.level[L].dof_begin = total2;
      total2 += g.level[L].ops->node_count(&g.level[L]);
    }
    assert_int_equal(total2, total);
    assert_int_equal(mpm_adaptive_grid_build_rows(&g), MPM_OK);
    assert_memory_equal(g.ghost_slot, slot, n * sizeof *slot);
    print_message("%d levels: %zu ghosts, %zu row terms, the same from the caches\n", levels, n,
                  nt);
    free(len);
    free(where);
    free(terms);
    free(slot);
    mpm_adaptive_grid_free(&g);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_one_level),         cmocka_unit_test(test_three_levels),
      cmocka_unit_test(test_four_levels),       cmocka_unit_test(test_apic_across_levels),
      cmocka_unit_test(test_close_from_caches),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
