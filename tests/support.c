/* support.c - shared helpers for the cmocka test programs. */
#include "support.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

double test_rand(uint64_t *s, double lo, double hi) {
  uint64_t x = *s ? *s : 0x9E3779B97F4A7C15ull;
  x ^= x >> 12;
  x ^= x << 25;
  x ^= x >> 27;
  *s = x;
  double u = (double)((x * 0x2545F4914F6CDD1Dull) >> 11) * (1.0 / 9007199254740992.0);
  return lo + (hi - lo) * u;
}

void assert_close_msg(double a, double b, double tol, const char *what) {
  if (!(fabs(a - b) <= tol)) {
    fail_msg("%s: %.9g vs %.9g differ by %.3g > %.3g", what, a, b, fabs(a - b), tol);
  }
}

const char *test_temp_dir(const char *name) {
  static char buf[512];
  snprintf(buf, sizeof buf, "/tmp/mpm-test-%d-%s", (int)getpid(), name);
  char cmd[1100];
  snprintf(cmd, sizeof cmd, "rm -rf '%s' && mkdir -p '%s'", buf, buf);
  if (system(cmd) != 0) fail_msg("cannot create %s", buf);
  return buf;
}

const char *test_mpm_bin(void) {
  return getenv("MPM_BIN");
}
