/* test_vecmath.c - the array logarithm and exponential against libm: the logarithm over many
 * decades and near 1, the exponential over its whole clamped range and near 0, where the
 * plastic return maps use it. */
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

static void test_exp_matches_libm(void **state) {
  (void)state;
  enum { N = 4096 };
  mpm_real x[N], y[N];
  uint64_t rng = 9;
  double worst = 0;
  for (int round = 0; round < 50; ++round) {
    for (int i = 0; i < N; ++i)
      x[i] = (mpm_real)((i & 1) ? test_rand(&rng, MPM_EXP_LO_ARG, MPM_EXP_HI_ARG)
                                : test_rand(&rng, -0.5, 0.5));
    x[0] = 0;
    x[1] = (mpm_real)0.34657359; /* ln2 / 2: the edge of the reduced range */
    x[2] = MPM_EXP_LO_ARG;
    x[3] = MPM_EXP_HI_ARG;
    mpm_exp_array(N, x, y);
    for (int i = 0; i < N; ++i) {
      const double ref = exp((double)x[i]);
      const double err = fabs((double)y[i] - ref) / ref;
      if (err > worst) worst = err;
    }
  }
  assert_true(y[0] == 1);
  /* outside the range: clamped, finite and positive */
  x[0] = (mpm_real)-1e4;
  x[1] = (mpm_real)1e4;
  mpm_exp_array(2, x, y);
  assert_true(y[0] > 0 && isfinite(y[1]) && y[1] > 1);
  print_message("array exp: worst relative error %.3g\n", worst);
  assert_true(worst < TOL(5e-7, 2e-15));
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_log_matches_libm),
                                     cmocka_unit_test(test_exp_matches_libm)};
  return cmocka_run_group_tests_name("vecmath", tests, NULL, NULL);
}
