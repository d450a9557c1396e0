/* test_vecmath.c - the array logarithm against libm over many decades and near 1. */
#include "support.h"
#include "core/vecmath.h"

#include <math.h>

static void test_log_matches_libm(void **state) {
  (void)state;
  enum { N = 4096 };
  mpm_real x[N], y[N];
  uint64_t rng = 5;
  double worst = 0;
  for (int round = 0; round < 50; ++round) {
    for (int i = 0; i < N; ++i) {
      /* half near 1 (where stresses live), half over many decades */
      const double e = (i & 1) ? test_rand(&rng, -30, 30) : test_rand(&rng, -0.3, 0.3);
      x[i] = (mpm_real)pow(10.0, e);
    }
    x[0] = 1;
    x[1] = (mpm_real)0.5;
    x[2] = (mpm_real)2;
    x[3] = (mpm_real)1.41421356237309504880;
    mpm_log_array(N, x, y);
    for (int i = 0; i < N; ++i) {
      const double ref = log((double)x[i]);
      const double err = fabs((double)y[i] - ref) / fmax(fabs(ref), 1e-3);
      if (err > worst) worst = err;
    }
  }
  assert_true(y[0] == 0);
  print_message("array log: worst relative error %.3g\n", worst);
  assert_true(worst < TOL(5e-7, 2e-15));
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_log_matches_libm)};
  return cmocka_run_group_tests_name("vecmath", tests, NULL, NULL);
}
