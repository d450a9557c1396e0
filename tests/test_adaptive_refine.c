/* test_adaptive_refine.c - the multi-level grid rebuilt during the run (domain.refine_every;
 * adaptive/rules.c, Gao et al. sec. 7.1):
 *   - types: a box born with a fine band (a body rule) flies across the domain; the tree follows
 *     its fine particles: every fine particle's box lies in fine leaves after each rebuild, the
 *     cells it left are coarse again, the refined region keeps its size, and mass, momentum and
 *     the APIC angular momentum are kept as on a static tree;
 *   - surface with resampling: the band follows the free surface and the particles follow the
 *     band (fine near the surface, coarse deep inside);
 *   - strain: only where the material is strained;
 *   - a body rule's `within`: only its part in the box is born fine;
 *   - 1 and 2 threads, and a run resumed from a checkpoint taken between two rebuilds, give the
 *     same particles and tree bit for bit;
 *   - key mistakes name the key path. */
#include "scene_json_support.h"
#include "support.h"
#include "resume_support.h"
#include "sim_support.h"

#include "core/parallel.h"
#include "adaptive/adaptive.h"
#include "sim/sim.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* A spinning jello box flying along x, no gravity; `domain` is spliced into the domain. */
static const char *flying_box_until(const char *domain, const char *extra, double end) {
  static char buf[4096];
  snprintf(buf, sizeof buf,
           "{\"domain\": {\"min\": [0,0,0], \"max\": [1,1,1], \"dx\": 0.04, \"levels\": 2%s},"
           " \"gravity\": [0,0,0], \"time\": {\"end\": %g, \"fps\": 20},"
           " \"solver\": {\"transfer\": \"apic\", \"cfl\": 0.5},"
           " \"materials\": [{\"name\": \"j\", \"model\": \"fixed_corotated\", \"E\": 4e4, "
           "\"nu\": 0.3, \"density\": 1000}],"
           " \"bodies\": [{\"name\": \"b\", \"shape\": {\"type\": \"box\", \"center\": "
           "[0.35,0.5,0.5], \"half_extent\": [0.12,0.12,0.12]}, \"material\": \"j\", "
           "\"velocity\": [1.0,0,0], \"angular_velocity\": [0,0,2]}]%s}",
           domain, end, extra);
  return buf;
}
#define flying_box(domain, extra) flying_box_until(domain, extra, 0.3)

#define TYPES_RULES                                                                                \
  ", \"refine_every\": 1, \"refine\": [{\"level\": 1, \"body\": \"b\", \"distance\": 0.03},"       \
  " {\"level\": 1, \"types\": true}]"

static void run_until(mpm_sim *sim, double t) {
  while (sim->time < t)
    if (mpm_sim_step(sim, 0.01) != MPM_OK) fail_msg("step: %s", mpm_sim_last_error(sim));
}

static size_t refined_cells(const mpm_sim *sim) {
  size_t n = 0;
  int32_t(*cells)[4] = mpm_adaptive_tree_cells(sim->adaptive, &n);
  assert_non_null(cells);
  mpm_free(cells);
  return n;
}

static void test_types_follow_the_body(void **state) {
  (void)state;
  mpm_sim *sim = sim_from_json(flying_box(TYPES_RULES, ""));
  const mpm_particles *p = &sim->particles;
  size_t fine = 0;
  for (size_t i = 0; i < p->count; ++i) fine += p->level[i] == 1;
  assert_true(fine > 0 && fine < p->count);
  const mpm_diagnostics d0 = mpm_sim_diagnostics(sim);
  run_until(sim, 0.0001);
  const size_t cells0 = refined_cells(sim);
  const mpm_real x_start = (mpm_real)0.27; /* inside the band at the start, behind it at the end */
  run_until(sim, 0.18);                    /* 0.18 m along x */
  assert_true(sim->adaptive->rebuilds >= (long long)sim->steps);
  mpm_sim_between_steps(sim); /* the tree of the particles as they are */
  const mpm_refinement *r = &sim->adaptive->grid.tree;
  for (size_t i = 0; i < p->count; ++i) {
    if (p->level[i] != 1) continue;
    const mpm_real h = (mpm_real)(0.5 * ldexp(sim->adaptive->body_box[0], -1));
    const mpm_real lo[3] = {p->x[0][i] - h, p->x[1][i] - h, p->x[2][i] - h},
                   hi[3] = {p->x[0][i] + h, p->x[1][i] + h, p->x[2][i] + h};
    if (mpm_refinement_coarsest_level_in(r, lo, hi) != 1)
      fail_msg("fine particle id %u's box meets a coarse leaf", p->id[i]);
  }
  const mpm_real behind[3] = {x_start, (mpm_real)0.4, (mpm_real)0.5};
  int32_t cell[3];
  assert_int_equal(mpm_refinement_leaf_at(r, behind, cell), 0);
  const size_t cells1 = refined_cells(sim);
  print_message("types: %zu refined cells at the start, %zu after 0.18 m (%lld rebuilds, %.3f s)\n",
                cells0, cells1, sim->adaptive->rebuilds, sim->adaptive->rebuild_seconds);
  assert_true(cells1 > cells0 / 2 && cells1 < 2 * cells0);
  const mpm_diagnostics d1 = mpm_sim_diagnostics(sim);
  const double L = fabs(d0.angular_momentum[2]), P = fabs(d0.momentum[0]);
  for (int d = 0; d < 3; ++d) {
    if (fabs(d1.momentum[d] - d0.momentum[d]) > TOL(2e-5, 1e-10) * P)
      fail_msg("momentum[%d] %.9g -> %.9g", d, d0.momentum[d], d1.momentum[d]);
    if (fabs(d1.angular_momentum[d] - d0.angular_momentum[d]) > TOL(2e-5, 1e-9) * L)
      fail_msg("angular momentum[%d] %.9g -> %.9g", d, d0.angular_momentum[d],
               d1.angular_momentum[d]);
  }
  mpm_sim_destroy(sim);
}

#define SURFACE_RULES                                                                              \
  ", \"refine_every\": 2, \"refine\": [{\"level\": 1, \"body\": \"b\", \"distance\": 0.03},"       \
  " {\"level\": 1, \"surface\": 0.03}],"                                                           \
  " \"resample\": {\"merge_margin\": 0.25, \"min_per_cell\": 8}"

static void test_surface_band_with_resampling(void **state) {
  (void)state;
  mpm_sim *sim = sim_from_json(flying_box(SURFACE_RULES, ""));
  run_until(sim, 0.2);
  mpm_sim_between_steps(sim);
  const mpm_particles *p = &sim->particles;
  /* fine within the band of the box's surface, coarse well inside it: the box (side 0.24,
   * spinning slowly) is centred near x = 0.55 */
  double cx = 0, cy = 0, cz = 0, m = 0;
  for (size_t i = 0; i < p->count; ++i) {
    cx += (double)p->mass[i] * p->x[0][i];
    cy += (double)p->mass[i] * p->x[1][i];
    cz += (double)p->mass[i] * p->x[2][i];
    m += p->mass[i];
  }
  cx /= m, cy /= m, cz /= m;
  size_t deep = 0, deep_coarse = 0;
  for (size_t i = 0; i < p->count; ++i) {
    const double r =
        fmax(fabs(p->x[0][i] - cx), fmax(fabs(p->x[1][i] - cy), fabs(p->x[2][i] - cz)));
    if (r < 0.03) {
      ++deep;
      deep_coarse += p->level[i] == 0;
    }
  }
  /* merges take 8 at a time: a few may be left over in a cell (9 of 49 with steps that crossed
     the frames' times, 12 of 52 since steps land on them) */
  if (!(deep > 0 && deep_coarse > 0.75 * (double)deep))
    fail_msg("%zu of the %zu particles deep inside are coarse", deep_coarse, deep);
  assert_true(sim->adaptive->resample_figures.splits + sim->adaptive->resample_figures.merges > 0);
  print_message("surface: %zu particles (%zu of %zu deep inside coarse), %lld splits, %lld "
                "merges, %lld rebuilds\n",
                p->count, deep_coarse, deep, sim->adaptive->resample_figures.splits,
                sim->adaptive->resample_figures.merges, sim->adaptive->rebuilds);
  mpm_sim_destroy(sim);
}

static int by_cell(const void *x, const void *y) {
  return memcmp(x, y, 4 * sizeof(int32_t));
}

/* A box settling on the floor under its weight (||F - I|| ~ rho g depth / E, up to 0.06 at the
 * bottom, and the waves of its landing). After a rebuild the refined cells are exactly the level-0
 * cells that a strained particle's box overlaps, found here by brute force. */
static void test_strain_rule(void **state) {
  (void)state;
  mpm_sim *sim = sim_from_json(
      "{\"domain\": {\"min\": [0,0,0], \"max\": [1,1,1], \"dx\": 0.04, \"levels\": 2, "
      "\"refine_every\": 1, \"refine\": [{\"level\": 1, \"strain\": 0.04}]},"
      " \"time\": {\"end\": 1, \"fps\": 20}, \"solver\": {\"cfl\": 0.5},"
      " \"materials\": [{\"name\": \"j\", \"model\": \"fixed_corotated\", \"E\": 4e4, "
      "\"nu\": 0.3, \"density\": 1000}],"
      " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.5,0.245,0.5], "
      "\"half_extent\": [0.12,0.12,0.12]}, \"material\": \"j\"}]}");
  run_until(sim, 0.0001);
  assert_int_equal(refined_cells(sim), 0); /* at rest nothing is strained yet */
  run_until(sim, 0.15);
  mpm_sim_between_steps(sim);
  const mpm_particles *p = &sim->particles;
  int32_t(*want)[4] = malloc(27 * p->count * sizeof *want);
  size_t nw = 0, all = 0;
  for (size_t i = 0; i < p->count; ++i) {
    double e = 0;
    for (int c = 0; c < 9; ++c) {
      const double f = (double)p->F[c][i] - (c % 4 == 0);
      e += f * f;
    }
    all += e > 0.04 * 0.04;
    if (!(e > 0.04 * 0.04)) continue;
    const double h = 0.5 * sim->adaptive->body_box[0];
    int32_t lo[3], hi[3];
    for (int d = 0; d < 3; ++d) {
      lo[d] = (int32_t)floor(((double)p->x[d][i] - h) / 0.04);
      hi[d] = (int32_t)floor(((double)p->x[d][i] + h) / 0.04);
    }
    for (int32_t a = lo[0]; a <= hi[0]; ++a)
      for (int32_t b = lo[1]; b <= hi[1]; ++b)
        for (int32_t c = lo[2]; c <= hi[2]; ++c) {
          const int32_t cell[4] = {0, a, b, c};
          memcpy(want[nw++], cell, sizeof cell);
        }
  }
  qsort(want, nw, sizeof *want, by_cell);
  size_t u = 0;
  for (size_t k = 0; k < nw; ++k)
    if (!u || by_cell(want[k], want[u - 1])) memcpy(want[u++], want[k], sizeof *want);
  size_t ng = 0;
  int32_t(*got)[4] = mpm_adaptive_tree_cells(sim->adaptive, &ng);
  qsort(got, ng, sizeof *got, by_cell);
  assert_true(u > 0);
  assert_int_equal(ng, u);
  assert_memory_equal(got, want, u * sizeof *want);
  assert_true(all < p->count / 2); /* selective: most of the box is not that strained */
  print_message("strain: %zu refined cells around %zu of %zu particles\n", ng, all, p->count);
  free(want);
  mpm_free(got);
  mpm_sim_destroy(sim);
}

static void assert_same(const mpm_sim *a, const mpm_sim *b) {
  const mpm_particles *pa = &a->particles, *pb = &b->particles;
  assert_int_equal(pa->count, pb->count);
  mpm_real **ra[MPM_PARTICLE_REAL_ARRAYS], **rb[MPM_PARTICLE_REAL_ARRAYS];
  mpm_particles_real_arrays((mpm_particles *)pa, ra);
  mpm_particles_real_arrays((mpm_particles *)pb, rb);
  for (int k = 0; k < MPM_PARTICLE_REAL_ARRAYS; ++k)
    if (memcmp(*ra[k], *rb[k], pa->count * sizeof(mpm_real))) fail_msg("array %d differs", k);
  assert_memory_equal(pa->id, pb->id, pa->count * sizeof(uint32_t));
  size_t na = 0, nb = 0;
  int32_t(*ca)[4] = mpm_adaptive_tree_cells(a->adaptive, &na),
  (*cb)[4] = mpm_adaptive_tree_cells(b->adaptive, &nb);
  assert_int_equal(na, nb);
  assert_memory_equal(ca, cb, na * sizeof *ca);
  mpm_free(ca);
  mpm_free(cb);
}

static void test_threads_bitwise(void **state) {
  (void)state;
  mpm_sim *s[2];
  for (int t = 0; t < 2; ++t) {
    mpm_set_threads(t + 1);
    s[t] = sim_from_json(flying_box(SURFACE_RULES, ""));
    run_until(s[t], 0.08);
  }
  mpm_set_threads(1);
  assert_same(s[0], s[1]);
  mpm_sim_destroy(s[0]);
  mpm_sim_destroy(s[1]);
}

/* one step past a rebuild: the tree is the rules' of an earlier state */
static int before_rebuild(const mpm_sim *sim) {
  return sim->steps % 3 != 1;
}

static void test_resume_between_rebuilds(void **state) {
  (void)state;
  mpm_sim *a, *c;
  resume_pair("refine_resume",
              flying_box_until(", \"refine_every\": 3, \"refine\": [{\"level\": 1, \"body\": "
                               "\"b\", \"distance\": 0.03}, {\"level\": 1, \"surface\": 0.03}], "
                               "\"resample\": {}",
                               ", \"output\": {\"checkpoint_every\": 1}", 0.15),
              1, 0, before_rebuild, &a, &c);
  assert_same(a, c);
  mpm_sim_destroy(a);
  mpm_sim_destroy(c);
}

#define RF_SCENE(D)                                                                                \
  "{'domain': {'min': [0, 0, 0], 'max': [1, 1, 1], 'dx': 0.05, " D "}, "                           \
  "'time': {'end': 0.1, 'fps': 10}, 'materials': [{'name': 'm', 'model': 'fixed_corotated', "      \
  "'E': 1e4, 'nu': 0.3, 'density': 1000}], 'bodies': [{'name': 'b', 'shape': {'type': "            \
  "'sphere', 'center': [0.5, 0.5, 0.5], 'radius': 0.1}, 'material': 'm'}]}"

/* A body rule's `within`: only the part of the body's band in the box is born fine (Gao sec. 9:
 * refine where contact will be, not the whole free surface). */
static void test_body_rule_within(void **state) {
  (void)state;
  size_t fine[2] = {0, 0};
  for (int w = 0; w < 2; ++w) {
    mpm_sim *sim = sim_from_json(flying_box(
        w ? ", \"refine\": [{\"level\": 1, \"body\": \"b\", \"distance\": 0.03, \"within\": "
            "{\"min\": [0.4, 0, 0], \"max\": [1, 1, 1]}}]"
          : ", \"refine\": [{\"level\": 1, \"body\": \"b\", \"distance\": 0.03}]",
        ""));
    const mpm_particles *p = &sim->particles;
    mpm_real lo = 1;
    for (size_t i = 0; i < p->count; ++i)
      if (p->level[i] == 1) {
        fine[w]++;
        lo = p->x[0][i] < lo ? p->x[0][i] : lo;
      }
    print_message("within: %s, %zu fine particles of %zu, the least x of a fine one %.4f\n",
                  w ? "x >= 0.4" : "none", fine[w], p->count, (double)lo);
    /* the box x in [0.23, 0.47]: the band's cells of level 0 (0.04 m) at x >= 0.4 only, or
       every face's */
    if (w)
      assert_true(lo >= (mpm_real)0.4);
    else
      assert_true(lo < (mpm_real)0.25);
    mpm_sim_destroy(sim);
  }
  assert_true(fine[1] > 0 && 3 * fine[1] < fine[0]);
}

static void test_key_errors(void **state) {
  (void)state;
  expect_error(RF_SCENE("'levels': 2, 'refine': [{'level': 1, 'box': {'min': [0, 0, 0], 'max': "
                        "[1, 1, 1]}, 'within': {'min': [0, 0, 0], 'max': [1, 1, 1]}}]"),
               MPM_ERR_INVALID, "domain.refine[0].within", "body rules only", NULL);
  expect_error(RF_SCENE("'levels': 2, 'refine': [{'level': 1, 'body': 'b', 'within': {'min': [0, "
                        "0, 0], 'max': [1, 0, 1]}}]"),
               MPM_ERR_INVALID, "domain.refine[0].within.max", "greater than min", NULL);
  expect_error(RF_SCENE("'refine_every': 2"), MPM_ERR_INVALID, "domain.refine_every",
               "domain.levels", NULL);
  expect_error(RF_SCENE("'levels': 2, 'refine': [{'level': 1, 'types': true}]"), MPM_ERR_INVALID,
               "domain.refine[0].types", "domain.refine_every", NULL);
  expect_error(RF_SCENE("'levels': 2, 'refine_every': 1, 'refine': [{'level': 1, 'types': "
                        "false}]"),
               MPM_ERR_INVALID, "domain.refine[0].types", "expected true", NULL);
  expect_error(RF_SCENE("'levels': 2, 'refine_every': 1, 'refine': [{'level': 1, 'surface': 0}]"),
               MPM_ERR_INVALID, "domain.refine[0].surface", "> 0", NULL);
  expect_error(RF_SCENE("'levels': 2, 'refine_every': 1, 'refine': [{'level': 1, 'surface': 0.1, "
                        "'body': 'x'}]"),
               MPM_ERR_INVALID, "domain.refine[0].body", "'x'", NULL);
  expect_error(RF_SCENE("'levels': 2, 'refine_every': 1, 'refine': [{'level': 1, 'surface': 0.1, "
                        "'distance': 0.1}]"),
               MPM_ERR_INVALID, "domain.refine[0].distance", NULL);
  expect_error(RF_SCENE("'levels': 2, 'refine_every': 1, 'refine': [{'level': 1, 'strain': 0.1, "
                        "'types': true}]"),
               MPM_ERR_INVALID, "domain.refine[0]", "exactly one", NULL);
  expect_error(RF_SCENE("'levels': 2, 'refine_every': -1"), MPM_ERR_INVALID, "domain.refine_every",
               NULL);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_types_follow_the_body),
      cmocka_unit_test(test_surface_band_with_resampling),
      cmocka_unit_test(test_strain_rule),
      cmocka_unit_test(test_threads_bitwise),
      cmocka_unit_test(test_resume_between_rebuilds),
      cmocka_unit_test(test_body_rule_within),
      cmocka_unit_test(test_key_errors),
  };
  return test_cleanup(cmocka_run_group_tests(tests, NULL, NULL));
}
