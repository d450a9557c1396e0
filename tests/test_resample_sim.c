/* test_resample_sim.c - particle split and merge in the step on the multi-level grid
 * (domain.resample; adaptive/resample.c, Gao et al. sec. 7.2):
 *   - a spinning box flying from the coarse half into the fine half splits as it enters: every
 *     particle in a fine leaf becomes of the fine type, the total mass stays exactly, the linear
 *     momentum to round-off, and the APIC angular momentum changes by what the splits report
 *     (the step conserves it; the splits' change is its closed form, test_resample.c);
 *   - the same box flying out of the fine half merges once a margin away from it: fewer
 *     particles, mass exact, momentum to round-off, angular momentum kept (merges are exact);
 *   - ids stay unique, and every new id is below next_id; every particle lies in a leaf of the
 *     domain, and no fine leaf cell holds more than max_per_cell after the splits;
 *   - 1 and 2 threads give the same particles bit for bit;
 *   - a run checkpointed mid-frame and resumed ends bit-identical to an uninterrupted one;
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

#define FINE_HALF                                                                                  \
  ", \"levels\": 2, \"refine\": [{\"level\": 1, \"box\": {\"min\": [0.5,0,0], \"max\": [1,1,1]}}]"

/* A spinning jello box flying along x at vx, no gravity; `resample` is domain.resample. */
static const char *flying_box_until(double cx, double vx, const char *resample, const char *extra,
                                    double end) {
  static char buf[2048];
  snprintf(buf, sizeof buf,
           "{\"domain\": {\"min\": [0,0,0], \"max\": [1,1,1], \"dx\": 0.04" FINE_HALF
           ", \"resample\": %s},"
           " \"gravity\": [0,0,0], \"time\": {\"end\": %g, \"fps\": 20},"
           " \"solver\": {\"transfer\": \"apic\", \"cfl\": 0.5},"
           " \"materials\": [{\"name\": \"j\", \"model\": \"fixed_corotated\", \"E\": 4e4, "
           "\"nu\": 0.3, \"density\": 1000}],"
           " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [%g,0.5,0.5], "
           "\"half_extent\": [0.1,0.1,0.1]}, \"material\": \"j\", \"velocity\": [%g,0.1,0], "
           "\"angular_velocity\": [0,0,2]}]%s}",
           resample, end, cx, vx, extra);
  return buf;
}
#define flying_box(cx, vx, resample, extra) flying_box_until(cx, vx, resample, extra, 0.3)

static void run_until(mpm_sim *sim, double t) {
  while (sim->time < t)
    if (mpm_sim_step(sim, 0.01) != MPM_OK) fail_msg("step: %s", mpm_sim_last_error(sim));
}

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

static int by_key(const void *a, const void *b) {
  const uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
  return x < y ? -1 : x > y;
}

static int by_id(const void *a, const void *b) {
  const uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
  return x < y ? -1 : x > y;
}

static void assert_ids_unique(const mpm_sim *sim) {
  const mpm_particles *p = &sim->particles;
  uint32_t *ids = malloc(p->count * sizeof *ids);
  memcpy(ids, p->id, p->count * sizeof *ids);
  qsort(ids, p->count, sizeof *ids, by_id);
  for (size_t i = 1; i < p->count; ++i)
    if (ids[i] == ids[i - 1]) fail_msg("id %u twice", ids[i]);
  assert_true(p->count == 0 || ids[p->count - 1] < sim->next_id);
  free(ids);
}

/* The momenta before and after, and the resampling's own angular momentum change. */
static void check_conservation(mpm_sim *sim, const sums *s0, const mpm_diagnostics *d0) {
  const sums s1 = sum_of(&sim->particles);
#ifndef MPM_USE_DOUBLE
  assert_true(s1.mass == s0->mass); /* float shares of powers of two, summed in double: exact */
#endif
  assert_close(s1.mass, s0->mass, 1e-12 * s0->mass);
  const double pn = sqrt(s0->p[0] * s0->p[0] + s0->p[1] * s0->p[1]);
  for (int d = 0; d < 3; ++d)
    if (fabs(s1.p[d] - s0->p[d]) > TOL(2e-5, 1e-11) * pn)
      fail_msg("momentum[%d] %.9g -> %.9g", d, s0->p[d], s1.p[d]);
  const mpm_diagnostics d1 = mpm_sim_diagnostics(sim);
  const double L0 = fabs(d0->angular_momentum[2]);
  for (int d = 0; d < 3; ++d) {
    const double change = d1.angular_momentum[d] - d0->angular_momentum[d];
    const double reported = sim->adaptive->resample_figures.angular_momentum_change[d];
    if (fabs(change - reported) > TOL(2e-5, 1e-9) * L0)
      fail_msg("angular momentum[%d] changed by %.6g, the resampling reported %.6g (L %.6g)", d,
               change, reported, L0);
  }
}

static void test_split_entering_the_fine_half(void **state) {
  (void)state;
  mpm_sim *sim = sim_from_json(flying_box(0.36, 0.8, "{\"merge\": false}", ""));
  const size_t n0 = sim->particles.count;
  const sums s0 = sum_of(&sim->particles);
  const mpm_diagnostics d0 = mpm_sim_diagnostics(sim);
  run_until(sim, 0.15); /* the front has moved 0.12 m into the fine half */
  const mpm_particles *p = &sim->particles;
  assert_true(sim->adaptive->resample_figures.splits > 0);
  assert_int_equal(sim->adaptive->resample_figures.merges, 0);
  assert_int_equal(p->count, n0 + 7 * (size_t)sim->adaptive->resample_figures.splits);
  /* after the last resampling, every particle inside a fine leaf is fine */
  mpm_sim_between_steps(sim);
  const mpm_refinement *r = &sim->adaptive->grid.tree;
  size_t fine = 0;
  for (size_t i = 0; i < p->count; ++i) {
    const mpm_real x[3] = {p->x[0][i], p->x[1][i], p->x[2][i]};
    int32_t cell[3];
    const int leaf = mpm_refinement_leaf_at(r, x, cell);
    if (leaf == 1 && p->level[i] != 1)
      fail_msg("particle id %u of type %d in a leaf of level 1", p->id[i], p->level[i]);
    fine += p->level[i] == 1;
  }
  assert_true(fine > n0 / 2);
  /* every particle in a leaf of the domain, and no fine leaf cell past the limit (2 x 8) */
  uint64_t *keys = malloc(p->count * sizeof *keys);
  size_t nk = 0;
  for (size_t i = 0; i < p->count; ++i) {
    const mpm_real x[3] = {p->x[0][i], p->x[1][i], p->x[2][i]};
    int32_t c[3];
    for (int d = 0; d < 3; ++d) assert_true(x[d] > 0 && x[d] < 1);
    if (mpm_refinement_leaf_at(r, x, c) != 1) continue;
    keys[nk++] =
        ((uint64_t)(uint32_t)c[0] << 42) | ((uint64_t)(uint32_t)c[1] << 21) | (uint32_t)c[2];
  }
  qsort(keys, nk, sizeof *keys, by_key);
  size_t most = 0;
  for (size_t k = 0, run = 0; k < nk; ++k) {
    run = k && keys[k] == keys[k - 1] ? run + 1 : 1;
    most = run > most ? run : most;
  }
  free(keys);
  assert_true(most <= 16);
  assert_ids_unique(sim);
  check_conservation(sim, &s0, &d0);
  print_message("split: %zu -> %zu particles, %lld splits, angular momentum change %.3g of %.3g\n",
                n0, p->count, sim->adaptive->resample_figures.splits,
                sim->adaptive->resample_figures.angular_momentum_change[2], d0.angular_momentum[2]);
  mpm_sim_destroy(sim);
}

/* The limit on a cell: a split would put 8 particles in a fine leaf cell; allowing 4 stops
 * every split. */
static void test_split_limit(void **state) {
  (void)state;
  mpm_sim *sim =
      sim_from_json(flying_box(0.36, 0.8, "{\"merge\": false, \"max_per_cell\": 4}", ""));
  run_until(sim, 0.1);
  assert_int_equal(sim->adaptive->resample_figures.splits, 0);
  for (size_t i = 0; i < sim->particles.count; ++i) assert_int_equal(sim->particles.level[i], 0);
  mpm_sim_destroy(sim);
}

static void test_merge_leaving_the_fine_half(void **state) {
  (void)state;
  mpm_sim *sim = sim_from_json(flying_box(0.64, -0.8, "{\"split\": false}", ""));
  const size_t n0 = sim->particles.count;
  for (size_t i = 0; i < n0; ++i) assert_int_equal(sim->particles.level[i], 1);
  const sums s0 = sum_of(&sim->particles);
  const mpm_diagnostics d0 = mpm_sim_diagnostics(sim);
  run_until(sim, 0.25); /* the back has moved 0.2 m, past 0.5 and a margin */
  const mpm_particles *p = &sim->particles;
  assert_true(sim->adaptive->resample_figures.merges > 0);
  assert_int_equal(sim->adaptive->resample_figures.splits, 0);
  assert_int_equal(p->count, n0 - 7 * (size_t)sim->adaptive->resample_figures.merges);
  size_t coarse = 0;
  for (size_t i = 0; i < p->count; ++i) coarse += p->level[i] == 0;
  assert_int_equal(coarse, sim->adaptive->resample_figures.merges);
  /* merges keep the APIC angular momentum exactly: what it changed is the step's round-off */
  for (int d = 0; d < 3; ++d)
    assert_true(fabs(sim->adaptive->resample_figures.angular_momentum_change[d]) <
                TOL(1e-5, 1e-12) * fabs(d0.angular_momentum[2]));
  assert_ids_unique(sim);
  check_conservation(sim, &s0, &d0);
  print_message("merge: %zu -> %zu particles, %lld merges\n", n0, p->count,
                sim->adaptive->resample_figures.merges);
  mpm_sim_destroy(sim);
}

static void assert_same_particles(const mpm_particles *a, const mpm_particles *b) {
  assert_int_equal(a->count, b->count);
  mpm_real **ra[MPM_PARTICLE_REAL_ARRAYS], **rb[MPM_PARTICLE_REAL_ARRAYS];
  mpm_particles_real_arrays((mpm_particles *)a, ra);
  mpm_particles_real_arrays((mpm_particles *)b, rb);
  for (int k = 0; k < MPM_PARTICLE_REAL_ARRAYS; ++k)
    if (memcmp(*ra[k], *rb[k], a->count * sizeof(mpm_real))) fail_msg("array %d differs", k);
  assert_memory_equal(a->id, b->id, a->count * sizeof(uint32_t));
  assert_memory_equal(a->level, b->level, a->count * sizeof(int32_t));
}

/* A box across the level change that moves both ways: splits and merges in one run. */
static const char *both_ways(void) {
  return flying_box(0.5, 0.6, "{\"merge_margin\": 0.5}", "");
}

static void test_threads_bitwise(void **state) {
  (void)state;
  mpm_sim *a[2];
  for (int t = 0; t < 2; ++t) {
    mpm_set_threads(t + 1);
    a[t] = sim_from_json(both_ways());
    run_until(a[t], 0.2);
  }
  mpm_set_threads(1);
  assert_true(a[0]->adaptive->resample_figures.splits > 0);
  assert_same_particles(&a[0]->particles, &a[1]->particles);
  assert_int_equal(a[0]->next_id, a[1]->next_id);
  mpm_sim_destroy(a[0]);
  mpm_sim_destroy(a[1]);
}

static void test_resume_bit_identical(void **state) {
  (void)state;
  mpm_sim *a, *c;
  resume_pair("resample_resume",
              flying_box_until(0.45, 0.8, "{}", ", \"output\": {\"checkpoint_every\": 1}", 0.15), 1,
              3, NULL, &a, &c);
  assert_true(a->adaptive->resample_figures.splits > 0);
  assert_int_equal(c->next_id, a->next_id);
  assert_same_particles(&a->particles, &c->particles);
  mpm_sim_destroy(a);
  mpm_sim_destroy(c);
}

#define RS_SCENE(D)                                                                                \
  "{'domain': {'min': [0, 0, 0], 'max': [1, 1, 1], 'dx': 0.05, " D "}, "                           \
  "'time': {'end': 0.1, 'fps': 10}, 'materials': [{'name': 'm', 'model': 'fixed_corotated', "      \
  "'E': 1e4, 'nu': 0.3, 'density': 1000}], 'bodies': [{'name': 'b', 'shape': {'type': "            \
  "'sphere', 'center': [0.5, 0.5, 0.5], 'radius': 0.1}, 'material': 'm'}]}"

static void test_key_errors(void **state) {
  (void)state;
  expect_error(RS_SCENE("'resample': {}"), MPM_ERR_INVALID, "domain.resample", "domain.levels",
               NULL);
  expect_error(RS_SCENE("'levels': 2, 'resample': {'splt': true}"), MPM_ERR_INVALID,
               "domain.resample.splt", "split", NULL);
  expect_error(RS_SCENE("'levels': 2, 'resample': {'every': 0}"), MPM_ERR_INVALID,
               "domain.resample.every", NULL);
  expect_error(RS_SCENE("'levels': 2, 'resample': {'merge': 1}"), MPM_ERR_INVALID,
               "domain.resample.merge", NULL);
  expect_error(RS_SCENE("'levels': 2, 'resample': {'bodies': ['nobody']}"), MPM_ERR_INVALID,
               "domain.resample.bodies[0]", "'nobody'", NULL);
  expect_error(RS_SCENE("'levels': 2, 'resample': []"), MPM_ERR_INVALID, "domain.resample",
               "object", NULL);
  mpm_scene s;
  parse_ok(RS_SCENE("'levels': 2, 'resample': {'bodies': ['b'], 'merge': false, 'every': 4}"), &s);
  assert_true(s.resample.enabled && s.resample.split && !s.resample.merge);
  assert_int_equal(s.resample.every, 4);
  assert_true(s.bodies[0].resample);
  mpm_scene_free(&s);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_split_entering_the_fine_half), cmocka_unit_test(test_split_limit),
      cmocka_unit_test(test_merge_leaving_the_fine_half),  cmocka_unit_test(test_threads_bitwise),
      cmocka_unit_test(test_resume_bit_identical),         cmocka_unit_test(test_key_errors),
  };
  return test_cleanup(cmocka_run_group_tests(tests, NULL, NULL));
}
