/* refinement_support.h - random non-graded trees for the multi-level grid's tests. */
#ifndef MPM_TEST_REFINEMENT_SUPPORT_H
#define MPM_TEST_REFINEMENT_SUPPORT_H

#include "support.h"
#include "adaptive/refinement.h"

/* Refines cell c of level L with probability p, then its children likewise, down to the finest
 * level: trees where a coarse leaf may border leaves several levels finer. */
static inline void test_refine_random(mpm_refinement *r, int L, const int32_t c[3], double p,
                                      uint64_t *rng) {
  if (L >= r->levels - 1 || test_rand(rng, 0, 1) >= p) return;
  assert_int_equal(mpm_refinement_refine(r, L, c), MPM_OK);
  for (int k = 0; k < 8; ++k) {
    const int32_t ch[3] = {2 * c[0] + (k & 1), 2 * c[1] + ((k >> 1) & 1), 2 * c[2] + (k >> 2)};
    test_refine_random(r, L + 1, ch, p, rng);
  }
}

#endif
