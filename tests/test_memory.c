/* test_memory.c - memory discipline of the step (core/alloc.h, core/arena.h):
 *   - every byte a simulation allocates through mpm_alloc is given back by mpm_sim_destroy
 *     (live bytes return to where they were), for the sparse and the dense grid, APIC and FLIP,
 *     particle domains with releases, and the retry guard;
 *   - once warm, a step allocates nothing: the step's scratch comes from its arena, the DOF set
 *     and the grid keep their capacity, so steps of a body at rest make no mpm_alloc call;
 *   - the arena hands out aligned blocks, serves an overflow and grows to its peak on reset. */
#include "support.h"
#include "sim_support.h"
#include "core/alloc.h"
#include "core/arena.h"
#include "sim/sim.h"

#include <stdint.h>
#include <stdio.h>
#include <string.h>

/* A jelly block and a rubber block with domains in a box; gravity, velocity and the grid kind
 * and transfer are filled in. */
static const char *scene(const char *grid, const char *transfer, double gravity, double speed,
                         int domains) {
  static char buf[2048];
  snprintf(buf, sizeof buf,
           "{\"domain\": {\"min\": [0,0,0], \"max\": [0.6,0.6,0.6], \"dx\": 0.03},"
           " \"gravity\": [0,%g,0], \"time\": {\"end\": 1, \"fps\": 24},"
           " \"solver\": {\"grid\": \"%s\", \"transfer\": \"%s\", \"on_instability\": "
           "\"retry\"},"
           " \"materials\": [{\"name\": \"j\", \"model\": \"fixed_corotated\", \"E\": 2e4, "
           "\"nu\": 0.3, \"density\": 1000}],"
           " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.2,0.3,0.3], "
           "\"half_extent\": [0.06,0.06,0.06]}, \"material\": \"j\", \"velocity\": [%g,0,0]}%s]}",
           gravity, grid, transfer, speed,
           domains ? ", {\"shape\": {\"type\": \"box\", \"center\": [0.4,0.3,0.3], "
                     "\"half_extent\": [0.05,0.04,0.04]}, \"material\": \"j\", \"jitter\": 0, "
                     "\"domains\": true, \"domain_release\": [{\"time\": 0, \"min\": "
                     "[0.42,0,0], \"max\": [1,1,1]}]}"
                   : "");
  return buf;
}

static void test_live_bytes_return(void **state) {
  (void)state;
  const char *grids[2] = {"sparse", "dense"}, *transfers[2] = {"apic", "flip"};
  for (int g = 0; g < 2; ++g)
    for (int t = 0; t < 2; ++t)
      for (int dom = 0; dom < 2; ++dom) {
        if (dom && g == 1) continue; /* domains need the sparse grid */
        const size_t before = mpm_alloc_live_bytes();
        mpm_sim *sim = sim_from_json(scene(grids[g], transfers[t], -9.81, 0.5, dom));
        for (int k = 0; k < 20; ++k)
          if (mpm_sim_step(sim, 1e-3) != MPM_OK) fail_msg("%s", mpm_sim_last_error(sim));
        assert_true(mpm_alloc_live_bytes() > before);
        mpm_sim_destroy(sim);
        if (mpm_alloc_live_bytes() != before)
          fail_msg("%s grid, %s, domains %d: %zu bytes still live after destroy", grids[g],
                   transfers[t], dom, mpm_alloc_live_bytes() - before);
      }
}

static void test_warm_step_allocates_nothing(void **state) {
  (void)state;
  const char *grids[2] = {"sparse", "dense"};
  for (int g = 0; g < 2; ++g) {
    mpm_sim *sim = sim_from_json(scene(grids[g], g ? "flip" : "apic", 0, 0, g == 0));
    for (int k = 0; k < 3; ++k) /* warm-up: capacities and the arena reach their size */
      if (mpm_sim_step(sim, 1e-3) != MPM_OK) fail_msg("%s", mpm_sim_last_error(sim));
    const size_t calls = mpm_alloc_calls();
    for (int k = 0; k < 10; ++k)
      if (mpm_sim_step(sim, 1e-3) != MPM_OK) fail_msg("%s", mpm_sim_last_error(sim));
    if (mpm_alloc_calls() != calls)
      fail_msg("%s grid: %zu allocations in 10 warm steps", grids[g], mpm_alloc_calls() - calls);
    assert_true(sim->step_arena.capacity > 0 || g == 1);
    mpm_sim_destroy(sim);
  }
}

static void test_arena(void **state) {
  (void)state;
  const size_t before = mpm_alloc_live_bytes();
  mpm_arena a;
  mpm_arena_init(&a);
  for (int round = 0; round < 3; ++round) {
    const size_t calls = mpm_alloc_calls();
    unsigned char *p[5];
    for (int k = 0; k < 5; ++k) {
      p[k] = mpm_arena_alloc(&a, 1000 + 37 * (size_t)k);
      assert_non_null(p[k]);
      assert_int_equal((uintptr_t)p[k] % MPM_ALIGN, 0);
      memset(p[k], k, 1000 + 37 * (size_t)k); /* blocks do not overlap: checked below */
    }
    for (int k = 0; k < 5; ++k) assert_int_equal(p[k][999], k);
    if (round == 0) assert_true(a.overflow_count == 5); /* nothing yet: every block overflows */
    if (round > 0) assert_int_equal(mpm_alloc_calls(), calls); /* grown to the peak: no call */
    assert_int_equal(mpm_arena_reset(&a), MPM_OK);
  }
  assert_int_equal(a.grown, 1);
  mpm_arena_free(&a);
  assert_int_equal(mpm_alloc_live_bytes(), before);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_live_bytes_return),
      cmocka_unit_test(test_warm_step_allocates_nothing),
      cmocka_unit_test(test_arena),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
