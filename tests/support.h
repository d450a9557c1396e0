/* support.h - shared helpers for the cmocka test programs. */
#ifndef MPM_TEST_SUPPORT_H
#define MPM_TEST_SUPPORT_H

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "core/real.h"

/* A tolerance scaled to the build's real type: tol_f for float builds, tol_d for double. */
#ifdef MPM_USE_DOUBLE
#define TOL(tol_f, tol_d) (tol_d)
#else
#define TOL(tol_f, tol_d) (tol_f)
#endif

/* Deterministic uniform random numbers in [lo, hi) (xorshift64*). */
double test_rand(uint64_t *state, double lo, double hi);

/* |a - b| <= tol, with a message naming what was compared. */
void assert_close_msg(double a, double b, double tol, const char *what);
#define assert_close(a, b, tol)                                                                    \
  assert_close_msg((double)(a), (double)(b), (double)(tol), #a " ~ " #b)

/* A fresh empty directory under /tmp for a test's files; returns a static buffer. */
const char *test_temp_dir(const char *name);

/* Path of the mpm program (from MPM_BIN, set by ctest) or NULL. */
const char *test_mpm_bin(void);

#endif
