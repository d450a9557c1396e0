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
/* At the end of main: removes the folders test_temp_dir made when no test failed (failures
 * == 0), else names them on stderr, where the failing test's files are; returns failures. Use
 * as return test_cleanup(cmocka_run_group_tests(...)). */
int test_cleanup(int failures);

/* A simulation of the scene text (`name` for messages); fails the test with the loader's or
 * the constructor's message. */
struct mpm_sim;
struct mpm_sim *test_sim_from_json(const char *text, const char *name);

/* The height (y) of the material points' centre of mass, m. */
double test_centre_height(const struct mpm_sim *sim);

/* Asserts two runs' material points bitwise equal: count, x, v and F. */
void test_assert_same_particles(const struct mpm_sim *a, const struct mpm_sim *b);

/* A small elastic block at rest in zero gravity, with domains, and one moving sphere collider
 * (the public API's and the allocator hook's tests). */
extern const char *const test_block_json;

/* The rest-state error (analysis/rest_error.h) of the simulation's domain particles against
 * their reference positions (from their corners' reference positions). */
double test_domain_rest_error(const struct mpm_sim *sim);

/* Every domain particle's F made the gradient of its corners' positions (F = sum_a x_a g_qa^T,
 * as the step keeps it), and its position and velocity from its corners. */
struct mpm_domain_set;
void test_domain_match_corners(struct mpm_domain_set *s);

/* Path of the mpm program (from MPM_BIN, set by ctest) or NULL. */
const char *test_mpm_bin(void);

/* The two implementations of the 3x3 SVD (core/svd3.h): the scalar mpm_svd3 and the SIMD
 * mpm_svd3_batch the stress kernels use. For the batch, F goes into a random lane of a full
 * batch whose other lanes hold random matrices (lane independence, full-vector code). */
enum { TEST_SVD_SCALAR, TEST_SVD_BATCH, TEST_SVD_PATHS };
extern const char *const test_svd_path_name[TEST_SVD_PATHS];
void test_svd_path(int path, const mpm_real F[9], mpm_real U[9], mpm_real s[3], mpm_real V[9]);

#endif
