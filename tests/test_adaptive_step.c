#define _POSIX_C_SOURCE 200809L /* setenv, unsetenv */
/* test_adaptive_step.c - the step on the multi-level grid (adaptive/adaptive.h) and its scene keys
 * (domain.levels, domain.refine):
 *   - one level through the multi-level path gives bitwise the uniform grid's particles (APIC
 *     and FLIP), for 1 and 2 threads;
 *   - two levels: particles are sampled per leaf at their level's spacing, a body flying from
 *     the coarse into the fine half keeps its mass exactly and its linear momentum to round-off
 *     while it crosses (ghost nodes carry every P2G sum to real nodes, Gao eq. 15), with APIC
 *     its angular momentum too (the ghosts' moments, adaptive/apic.c), and the step is the same
 *     for 1 and 2 threads;
 *   - the refinement rules (box, collider distance, body) refine where they say;
 *   - a particle meeting a leaf two levels finer than its type is refused, naming it;
 *   - key mistakes name the key path. */
#include "scene_json_support.h"
#include "support.h"
#include "sim_support.h"

#include "core/parallel.h"
#include "adaptive/adaptive.h"
#include "sim/sim.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void run_steps(mpm_sim *sim, int n) {
  for (int i = 0; i < n; ++i)
    if (mpm_sim_step(sim, 0.01) != MPM_OK) fail_msg("step %d: %s", i, mpm_sim_last_error(sim));
}

/* A spinning jello box flying along x, no gravity, far from walls; `grid` is spliced into the
 * domain object. */
static const char *flying_box(const char *grid, const char *transfer, double cx) {
  static char buf[2048];
  snprintf(buf, sizeof buf,
           "{\"domain\": {\"min\": [0,0,0], \"max\": [1,1,1], \"dx\": 0.04%s},"
           " \"gravity\": [0,0,0], \"time\": {\"end\": 1, \"fps\": 24},"
           " \"solver\": {\"kernel\": \"ugimp\", \"transfer\": \"%s\", \"cfl\": 0.5},"
           " \"materials\": [{\"name\": \"j\", \"model\": \"fixed_corotated\", \"E\": 4e4, "
           "\"nu\": 0.3, \"density\": 1000}],"
           " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [%g,0.5,0.5], "
           "\"half_extent\": [0.12,0.1,0.1]}, \"material\": \"j\", \"velocity\": [0.8,0.1,0], "
           "\"angular_velocity\": [0,0,2]}]}",
           grid, transfer, cx);
  return buf;
}

static void assert_same_particles(const mpm_particles *a, const mpm_particles *b) {
  assert_int_equal(a->count, b->count);
  for (int d = 0; d < 3; ++d) {
    assert_memory_equal(a->x[d], b->x[d], a->count * sizeof(mpm_real));
    assert_memory_equal(a->v[d], b->v[d], a->count * sizeof(mpm_real));
  }
  for (int d = 0; d < 9; ++d) {
    assert_memory_equal(a->F[d], b->F[d], a->count * sizeof(mpm_real));
    assert_memory_equal(a->B[d], b->B[d], a->count * sizeof(mpm_real));
  }
  assert_memory_equal(a->id, b->id, a->count * sizeof(uint32_t));
}

static void test_single_level_is_uniform_bitwise(void **state) {
  (void)state;
  const char *transfers[2] = {"apic", "flip"};
  for (int t = 0; t < 2; ++t)
    for (int threads = 1; threads <= 2; ++threads) {
      mpm_set_threads(threads);
      mpm_sim *u = sim_from_json(flying_box("", transfers[t], 0.45));
      mpm_sim *a = sim_from_json(flying_box(", \"levels\": 1", transfers[t], 0.45));
      assert_null(u->adaptive);
      assert_non_null(a->adaptive);
      run_steps(u, 40); /* past two periodic reorders */
      run_steps(a, 40);
      assert_true(a->time == u->time);
      assert_same_particles(&a->particles, &u->particles);
      mpm_sim_destroy(u);
      mpm_sim_destroy(a);
    }
  mpm_set_threads(1);
}

#define FINE_HALF                                                                                  \
  ", \"levels\": 2, \"refine\": [{\"level\": 1, \"box\": {\"min\": [0.5,0,0], \"max\": [1,1,1]}}]"

typedef struct sums {
  double mass, p[3];
} sums;

static sums sum_of(const mpm_particles *p) {
  sums s = {0, {0, 0, 0}};
  for (size_t i = 0; i < p->count; ++i) {
    s.mass += (double)p->mass[i];
    for (int d = 0; d < 3; ++d) s.p[d] += (double)p->mass[i] * (double)p->v[d][i];
  }
  return s;
}

static void test_two_levels_conserve_across_the_level_change(void **state) {
  (void)state;
  const char *transfers[2] = {"apic", "flip"};
  for (int t = 0; t < 2; ++t) {
    mpm_sim *sim = sim_from_json(flying_box(FINE_HALF, transfers[t], 0.45));
    const mpm_particles *p = &sim->particles;
    /* the box spans x in [0.33, 0.57]: coarse particles (h = 0.02) left of 0.48 (the level-0
     * cell holding x = 0.5 is refined), fine ones (0.01) right of it, up to their jitter, each
     * with its level's mass */
    size_t coarse = 0, fine = 0;
    for (size_t i = 0; i < p->count; ++i) {
      if (p->level[i] == 0) {
        assert_true(p->x[0][i] < 0.48f + 0.01f);
        assert_float_equal(p->mass[i], 1000 * 0.02 * 0.02 * 0.02, 1e-9);
        ++coarse;
      } else {
        assert_int_equal(p->level[i], 1);
        assert_true(p->x[0][i] > 0.48f - 0.005f);
        assert_float_equal(p->mass[i], 1000 * 0.01 * 0.01 * 0.01, 1e-10);
        ++fine;
      }
    }
    assert_true(coarse > 0 && fine > 0);
    const sums s0 = sum_of(p);
    const mpm_diagnostics d0 = mpm_sim_diagnostics(sim);
    run_steps(sim, 1);
    const mpm_adaptive *a = sim->adaptive;
    assert_true(a->grid.ghost_count > 0);
    assert_true(a->tgrid_count >= 3); /* (0, coarse), (1, fine), (1, coarse at the change) */
    run_steps(sim, 80);
    const sums s1 = sum_of(p);
    assert_float_equal(s1.mass, s0.mass, 1e-12 * s0.mass);
    const double pn = sqrt(s0.p[0] * s0.p[0] + s0.p[1] * s0.p[1]);
    for (int d = 0; d < 3; ++d)
      if (fabs(s1.p[d] - s0.p[d]) > 2e-5 * pn)
        fail_msg("%s: momentum[%d] %.9g -> %.9g", transfers[t], d, s0.p[d], s1.p[d]);
    /* APIC: the ghosts' moments keep the angular momentum (with the affine part) across the
     * level change; without them it fell by 3% in 0.4 s (docs/adaptive-grid.md) */
    if (t == 0) {
      const mpm_diagnostics d1 = mpm_sim_diagnostics(sim);
      const double L0 = fabs(d0.angular_momentum[2]);
      assert_true(L0 > 1);
      for (int d = 0; d < 3; ++d)
        if (fabs(d1.angular_momentum[d] - d0.angular_momentum[d]) > 2e-6 * L0)
          fail_msg("angular momentum[%d] %.9g -> %.9g", d, d0.angular_momentum[d],
                   d1.angular_momentum[d]);
      assert_true(sim->adaptive->boundary_count > 0);
    }
    /* the body moved on: part of the coarse particles now transfer on the fine level */
    int crossed = 0;
    for (int k = 0; k < a->tgrid_count; ++k)
      crossed |= a->tgrid[k].level == 1 && a->tgrid[k].box > 0.015 && a->range[k + 1] > a->range[k];
    assert_true(crossed);
    mpm_sim_destroy(sim);
  }
}

static void test_two_levels_threads_bitwise(void **state) {
  (void)state;
  mpm_set_threads(1);
  mpm_sim *a = sim_from_json(flying_box(FINE_HALF, "apic", 0.45));
  run_steps(a, 40);
  mpm_set_threads(2);
  mpm_sim *b = sim_from_json(flying_box(FINE_HALF, "apic", 0.45));
  run_steps(b, 40);
  mpm_set_threads(1);
  assert_same_particles(&a->particles, &b->particles);
  mpm_sim_destroy(a);
  mpm_sim_destroy(b);
}

/* Three levels, bands around the body (Gao's static refinement), APIC: 1 and 2 threads give the
 * same particles bit for bit. The body is large enough that the sort's parallel loops (the
 * used-slot marks, the ghost rows' entries, the APIC boundary cells) run in parallel: more than
 * 64 owner blocks on the finest grid, 1024 ghosts and MPM_PARALLEL_MIN boundary particles. */
static void test_three_levels_threads_bitwise(void **state) {
  (void)state;
  const char *grid = ", \"levels\": 3, \"refine\": [{\"level\": 1, \"body\": 0, \"distance\": "
                     "0.04}, {\"level\": 2, \"body\": 0, \"distance\": 0.02}]";
  mpm_sim *s[2];
  for (int t = 0; t < 2; ++t) {
    mpm_set_threads(t + 1);
    s[t] = sim_from_json(flying_box(grid, "apic", 0.45));
    run_steps(s[t], 6);
  }
  mpm_set_threads(1);
  const mpm_adaptive *a = s[1]->adaptive;
  const mpm_grid *fine = mpm_adaptive_grid_at((mpm_adaptive_grid *)&a->grid, 2);
  assert_true(fine->impl.sparse.owner_count > 64);
  assert_true(a->grid.ghost_count > 1024);
  assert_true(a->boundary_count > MPM_PARALLEL_MIN);
  assert_same_particles(&s[0]->particles, &s[1]->particles);
  for (int t = 0; t < 2; ++t) mpm_sim_destroy(s[t]);
}

static int leaf_level(const mpm_sim *sim, double x, double y, double z) {
  const mpm_real p[3] = {(mpm_real)x, (mpm_real)y, (mpm_real)z};
  int32_t cell[3];
  return mpm_refinement_leaf_at(&sim->adaptive->grid.tree, p, cell);
}

static void test_refinement_rules(void **state) {
  (void)state;
  /* a sphere collider of radius 0.1 at (0.5, 0.3, 0.5): refined to level 2 within 0.05 of its
   * surface; the body refined to level 1 where it is */
  mpm_sim *sim = sim_from_json(
      "{\"domain\": {\"min\": [0,0,0], \"max\": [1,1,1], \"dx\": 0.04, \"levels\": 3,"
      "  \"refine\": [{\"level\": 2, \"collider\": \"ball\", \"distance\": 0.05},"
      "              {\"level\": 1, \"body\": 0}]},"
      " \"gravity\": [0,0,0], \"time\": {\"end\": 1, \"fps\": 24},"
      " \"materials\": [{\"name\": \"j\", \"model\": \"fixed_corotated\", \"E\": 4e4, "
      "\"nu\": 0.3, \"density\": 1000}],"
      " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.5,0.7,0.5], "
      "\"half_extent\": [0.1,0.1,0.1]}, \"material\": \"j\"}],"
      " \"colliders\": [{\"name\": \"ball\", \"shape\": {\"type\": \"sphere\", \"center\": "
      "[0.5,0.3,0.5], \"radius\": 0.1}}]}");
  assert_int_equal(leaf_level(sim, 0.5, 0.41, 0.5), 2); /* just above the ball's surface */
  assert_int_equal(leaf_level(sim, 0.5, 0.18, 0.5), 2); /* just below it */
  assert_int_equal(leaf_level(sim, 0.5, 0.3, 0.5), 0);  /* its centre, 0.1 deep */
  assert_int_equal(leaf_level(sim, 0.9, 0.9, 0.9), 0);  /* far away */
  assert_int_equal(leaf_level(sim, 0.5, 0.7, 0.5), 1);  /* inside the body */
  /* the body's particles have the type of their leaf */
  const mpm_particles *p = &sim->particles;
  for (size_t i = 0; i < p->count; ++i)
    assert_int_equal(p->level[i], leaf_level(sim, p->x[0][i], p->x[1][i], p->x[2][i]));
  mpm_sim_destroy(sim);

  /* a band of 0.03 m under a ball's surface at level 2: coarse inside, fine at the surface, and
   * every particle's type its leaf's */
  sim = sim_from_json(
      "{\"domain\": {\"min\": [0,0,0], \"max\": [1,1,1], \"dx\": 0.04, \"levels\": 3,"
      "  \"refine\": [{\"level\": 2, \"body\": \"ball\", \"distance\": 0.03}]},"
      " \"gravity\": [0,0,0], \"time\": {\"end\": 1, \"fps\": 24},"
      " \"materials\": [{\"name\": \"j\", \"model\": \"fixed_corotated\", \"E\": 4e4, "
      "\"nu\": 0.3, \"density\": 1000}],"
      " \"bodies\": [{\"name\": \"ball\", \"shape\": {\"type\": \"sphere\", \"center\": "
      "[0.5,0.5,0.5], \"radius\": 0.2}, \"material\": \"j\"}]}");
  assert_int_equal(leaf_level(sim, 0.5, 0.5, 0.5), 0);
  assert_int_equal(leaf_level(sim, 0.5, 0.69, 0.5), 2);
  assert_int_equal(leaf_level(sim, 0.31, 0.5, 0.5), 2);
  p = &sim->particles;
  size_t fine = 0;
  for (size_t i = 0; i < p->count; ++i) {
    const double r =
        sqrt(pow(p->x[0][i] - 0.5, 2) + pow(p->x[1][i] - 0.5, 2) + pow(p->x[2][i] - 0.5, 2));
    if (p->level[i] == 2) {
      ++fine;
      /* the band (the distance in the max norm: up to sqrt(3) of it deep), up to the level-1
       * cell a band sample refines */
      assert_true(r > 0.2 - sqrt(3) * 0.03 - sqrt(3) * 0.02);
    }
    if (r > 0.19) assert_int_equal(p->level[i], 2);
    assert_int_equal(p->level[i], leaf_level(sim, p->x[0][i], p->x[1][i], p->x[2][i]));
  }
  assert_true(fine > 0 && fine < p->count);
  mpm_sim_destroy(sim);
}

static void test_steep_refinement_is_refused(void **state) {
  (void)state;
  /* level 0 beside level 3 (the box starts on a level-0 cell face, so no level between): the
   * coarse particles (box 0.02 m) at the change meet leaves of 0.005 m */
  mpm_sim *sim = sim_from_json(flying_box(
      ", \"levels\": 4, \"refine\": [{\"level\": 3, \"box\": {\"min\": [0.52,0,0], \"max\": "
      "[1,1,1]}}]",
      "apic", 0.45));
  mpm_status st = MPM_OK;
  for (int k = 0; k < 50 && st == MPM_OK; ++k) st = mpm_sim_step(sim, 0.01); /* moving on */
  assert_int_equal(st, MPM_ERR_INVALID);
  const char *m = mpm_sim_last_error(sim);
  if (!strstr(m, "of type 0") || !strstr(m, "meets a leaf of level 3") ||
      !strstr(m, "domain.refine"))
    fail_msg("message: %s", m);
  mpm_sim_destroy(sim);
}

/* A scene whose refined cells need more memory than allowed is refused before its particles are
 * sampled, with the count the tree gives (the level-0 estimate alone would pass). */
static void test_refined_memory_is_checked(void **state) {
  (void)state;
  setenv("MPM_MEMORY_LIMIT", "150M", 1);
  const char *json =
      "{\"domain\": {\"min\": [0,0,0], \"max\": [1,1,1], \"dx\": 0.05, \"levels\": 3,"
      "  \"refine\": [{\"level\": 2, \"box\": {\"min\": [0.2,0.2,0.2], \"max\": [0.8,0.8,0.8]}}]},"
      " \"time\": {\"end\": 1, \"fps\": 24},"
      " \"materials\": [{\"name\": \"j\", \"model\": \"fixed_corotated\", \"E\": 4e4, "
      "\"nu\": 0.3, \"density\": 1000}],"
      " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.5,0.5,0.5], "
      "\"half_extent\": [0.3,0.3,0.3]}, \"material\": \"j\"}]}";
  mpm_scene scene;
  mpm_error err;
  mpm_error_clear(&err);
  assert_int_equal(mpm_scene_parse(json, "big.json", &scene, &err), MPM_OK);
  mpm_sim *sim = NULL;
  const mpm_status st = mpm_sim_create_from_scene(&scene, &sim, &err);
  mpm_scene_free(&scene);
  unsetenv("MPM_MEMORY_LIMIT");
  assert_int_equal(st, MPM_ERR_INVALID);
  assert_null(sim);
  if (!strstr(err.message, "fewer refined cells") || !strstr(err.message, "8.85e+05"))
    fail_msg("message: %s", err.message);
}

#define LEVELS_DOMAIN "'domain': {'min': [0, 0, 0], 'max': [1, 1, 1], 'dx': 0.05, "
#define LEVELS_SCENE(D, X) "{" LEVELS_DOMAIN D "}, " TIME ", " MATS ", " BODIES X "}"

static void test_key_errors(void **state) {
  (void)state;
  expect_error(LEVELS_SCENE("'levels': 7", ""), MPM_ERR_INVALID, "domain.levels", "[1, 6]", NULL);
  expect_error(LEVELS_SCENE("'refine': []", ""), MPM_ERR_INVALID, "domain.refine", "domain.levels",
               NULL);
  expect_error(LEVELS_SCENE("'levels': 2, 'refine': [{'level': 2, 'box': {'min': [0,0,0], "
                            "'max': [1,1,1]}}]",
                            ""),
               MPM_ERR_INVALID, "domain.refine[0].level", "[1, 1]", NULL);
  expect_error(LEVELS_SCENE("'levels': 2, 'refine': [{'level': 1}]", ""), MPM_ERR_INVALID,
               "domain.refine[0]", "exactly one of 'box', 'collider', 'body', 'surface'", NULL);
  expect_error(LEVELS_SCENE("'levels': 2, 'refine': [{'level': 1, 'box': {'min': [0,0,0], "
                            "'max': [1,0,1]}}]",
                            ""),
               MPM_ERR_INVALID, "domain.refine[0].box.max", "along y", NULL);
  expect_error(LEVELS_SCENE("'levels': 2, 'refine': [{'level': 1, 'collider': 'wall', "
                            "'distance': 0.1}]",
                            ""),
               MPM_ERR_INVALID, "domain.refine[0].collider", "no colliders", NULL);
  expect_error(LEVELS_SCENE("'levels': 2, 'refine': [{'level': 1, 'body': 'nobody'}]", ""),
               MPM_ERR_INVALID, "domain.refine[0].body", "'nobody'", NULL);
  expect_error(LEVELS_SCENE("'levels': 2, 'refine': [{'level': 1, 'box': {'min': [0,0,0], "
                            "'max': [1,1,1]}, 'distance': 1}]",
                            ""),
               MPM_ERR_INVALID, "domain.refine[0].distance",
               "collider, body, types and strain rules only", NULL);
  expect_error(LEVELS_SCENE("'levels': 2, 'refine': [{'level': 1, 'body': 0, 'distance': 0}]", ""),
               MPM_ERR_INVALID, "domain.refine[0].distance", "> 0", NULL);
  expect_error(LEVELS_SCENE("'levels': 2", ", 'solver': {'kernel': 'quadratic'}"), MPM_ERR_INVALID,
               "solver.kernel", "\"ugimp\"", NULL);
  expect_error(LEVELS_SCENE("'levels': 2", ", 'solver': {'grid': 'dense'}"), MPM_ERR_INVALID,
               "solver.grid", "sparse", NULL);
  /* the default kernel on levels is uGIMP */
  mpm_scene s;
  parse_ok(LEVELS_SCENE("'levels': 2, 'refine': [{'level': 1, 'body': 0}]", ""), &s);
  assert_int_equal(s.levels, 2);
  assert_int_equal(s.refine_count, 1);
  assert_int_equal(s.refine[0].kind, MPM_REFINE_BODY);
  assert_int_equal(s.solver.kernel, MPM_KERNEL_UGIMP);
  mpm_scene_free(&s);
}

/* A particle moved by mpm_sim_set_positions is classified again: deep in the coarse half its
 * block was uniform (its transfer grid kept from step to step without a query); moved into the
 * fine half it must transfer on the fine level. The kept grid put it on the coarse one. */
static void test_moved_particle_is_classified_again(void **state) {
  (void)state;
  mpm_sim *sim = sim_from_json(flying_box(FINE_HALF, "apic", 0.45));
  run_steps(sim, 2);
  const mpm_particles *p = &sim->particles;
  const mpm_adaptive *a = sim->adaptive;
  size_t pick = p->count;
  for (size_t i = 0; i < p->count && pick == p->count; ++i)
    if (p->level[i] == 0 && p->x[0][i] < 0.38f && a->stable[i]) pick = i;
  assert_true(pick < p->count); /* a coarse particle whose grid is kept */
  const uint32_t id = p->id[pick];
  const double to[3] = {0.75, 0.5, 0.5};
  assert_int_equal(mpm_sim_set_positions(sim, 1, &id, to), MPM_OK);
  run_steps(sim, 1);
  size_t at = p->count;
  for (size_t i = 0; i < p->count; ++i)
    if (p->id[i] == id) at = i;
  assert_true(at < p->count);
  int t = 0;
  while (t < a->tgrid_count && a->range[t + 1] <= at) ++t;
  assert_int_equal(a->tgrid[t].level, 1);
  mpm_sim_destroy(sim);
}

/* Every particle's transfer grid is the one a full query of the tree gives at the positions
 * the step started from, kept grids included (a particle whose cell's neighbourhood is one
 * level's leaves keeps its grid without a query: mpm_adaptive_grid_block_stable_cells), while
 * bodies fly across one and two changes of level. */
/* A soft box flying fast across the levels: its particles move most of a cell each step (the
 * CFL step is set by the motion, not the sound speed), so that a kept grid whose window is a
 * cell short is caught. */
static const char *fast_box(const char *grid, double cx, double sign) {
  static char buf[2048];
  snprintf(buf, sizeof buf,
           "{\"domain\": {\"min\": [0,0,0], \"max\": [1,1,1], \"dx\": 0.04%s},"
           " \"gravity\": [0,0,0], \"time\": {\"end\": 1, \"fps\": 24},"
           " \"solver\": {\"kernel\": \"ugimp\", \"transfer\": \"apic\", \"cfl\": 0.95},"
           " \"materials\": [{\"name\": \"j\", \"model\": \"fixed_corotated\", \"E\": 10, "
           "\"nu\": 0.3, \"density\": 1000}],"
           " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [%g,0.5,0.5], "
           "\"half_extent\": [0.1,0.1,0.1]}, \"material\": \"j\", \"velocity\": [%g,-1.3,0.7], "
           "\"angular_velocity\": [0,0,4]}]}",
           grid, cx, 3 * sign);
  return buf;
}

static void check_classified(const char *grid, double cx, double sign, int steps) {
  mpm_sim *sim = sim_from_json(fast_box(grid, cx, sign));
  const mpm_particles *p = &sim->particles;
  const mpm_adaptive *a = sim->adaptive;
  const mpm_refinement *r = &a->grid.tree;
  const int levels = r->levels;
  size_t kept = 0, checked = 0;
  for (int k = 0; k < steps; ++k) {
    /* the positions the next step starts from, by id */
    const size_t n = p->count;
    uint32_t top = 0;
    for (size_t i = 0; i < n; ++i) top = p->id[i] > top ? p->id[i] : top;
    double *x0 = malloc(3 * ((size_t)top + 1) * sizeof *x0);
    assert_non_null(x0);
    for (size_t i = 0; i < n; ++i)
      for (int d = 0; d < 3; ++d) x0[3 * p->id[i] + (size_t)d] = (double)p->x[d][i];
    const int stable_valid = a->stable && a->stable_step == sim->steps;
    for (size_t i = 0; i < n && stable_valid; ++i) kept += a->stable[i];
    run_steps(sim, 1);
    int t = 0;
    for (size_t i = 0; i < p->count; ++i) {
      while (a->range[t + 1] <= i) ++t;
      const int q = p->level[i], b = p->body[i];
      const mpm_real half = a->box_half[b * levels + q];
      double lo[3], hi[3];
      for (int d = 0; d < 3; ++d) { /* as classify computes the box */
        const mpm_real xd = (mpm_real)x0[3 * p->id[i] + (size_t)d];
        lo[d] = ((double)(xd - half) - (double)r->origin[d]) / (double)r->dx0;
        hi[d] = ((double)(xd + half) - (double)r->origin[d]) / (double)r->dx0;
      }
      const int L = mpm_refinement_finest_level_overlapping(r, lo, hi);
      const int expect = a->box_tgrid[(b * levels + q) * levels + L];
      if (expect != t)
        fail_msg("step %d: particle id %u has transfer grid %d, the tree says %d", k, p->id[i], t,
                 expect);
      ++checked;
    }
    free(x0);
  }
  print_message("%zu classifications checked, %zu of them kept without a query\n", checked, kept);
  assert_true(kept > checked / 10);
  mpm_sim_destroy(sim);
}

static void test_kept_transfer_grids_are_exact(void **state) {
  (void)state;
  check_classified(FINE_HALF, 0.75, -1, 30); /* leaving the fine half */
  check_classified(FINE_HALF, 0.45, 1, 30);
  check_classified(", \"levels\": 3, \"refine\": [{\"level\": 1, \"box\": {\"min\": [0.45,0,0], "
                   "\"max\": [1,1,1]}}, {\"level\": 2, \"box\": {\"min\": [0.55,0,0], \"max\": "
                   "[1,1,1]}}]",
                   0.4, 1, 30);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_single_level_is_uniform_bitwise),
      cmocka_unit_test(test_two_levels_conserve_across_the_level_change),
      cmocka_unit_test(test_two_levels_threads_bitwise),
      cmocka_unit_test(test_three_levels_threads_bitwise),
      cmocka_unit_test(test_refinement_rules),
      cmocka_unit_test(test_steep_refinement_is_refused),
      cmocka_unit_test(test_refined_memory_is_checked),
      cmocka_unit_test(test_key_errors),
      cmocka_unit_test(test_moved_particle_is_classified_again),
      cmocka_unit_test(test_kept_transfer_grids_are_exact),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
