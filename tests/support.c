/* support.c - shared helpers for the cmocka test programs. */
#include "support.h"
#include "analysis/rest_error.h"
#include "core/svd3.h"
#include "domain/domain.h"
#include "scene/scene.h"
#include "sim/sim.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
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

/* the folders test_temp_dir made, for test_cleanup */
#define TEMP_DIRS_MAX 64
static char temp_dirs[TEMP_DIRS_MAX][512];
static int temp_dir_count;
static int cleaned;     /* test_cleanup ran */
static long owner = -1; /* the process that made the folders (not a forked child) */

/* A test program that makes folders must hand its result to test_cleanup (main returns
 * test_cleanup(cmocka_run_group_tests(...))), or a passing run leaves them in /tmp: that
 * program fails here, naming the folders. */
static void check_cleaned(void) {
  if (cleaned || (long)getpid() != owner || !temp_dir_count) return;
  fprintf(stderr, "test program made %s and others but never called test_cleanup: they are left\n",
          temp_dirs[0]);
  _exit(1);
}

const char *test_temp_dir(const char *name) {
  static char buf[512];
  if (owner < 0) {
    owner = (long)getpid();
    atexit(check_cleaned);
  }
  snprintf(buf, sizeof buf, "/tmp/mpm-test-%d-%s", (int)getpid(), name);
  char cmd[1100];
  snprintf(cmd, sizeof cmd, "rm -rf '%s' && mkdir -p '%s'", buf, buf);
  if (system(cmd) != 0) fail_msg("cannot create %s", buf);
  int known = 0;
  for (int k = 0; k < temp_dir_count; ++k) known |= !strcmp(temp_dirs[k], buf);
  if (!known && temp_dir_count < TEMP_DIRS_MAX)
    snprintf(temp_dirs[temp_dir_count++], sizeof temp_dirs[0], "%s", buf);
  return buf;
}

int test_cleanup(int failures) {
  cleaned = 1;
  for (int k = 0; k < temp_dir_count; ++k) {
    if (failures) {
      fprintf(stderr, "test files kept in %s\n", temp_dirs[k]);
      continue;
    }
    char cmd[1100];
    snprintf(cmd, sizeof cmd, "rm -rf '%.512s'", temp_dirs[k]);
    if (system(cmd) != 0) fprintf(stderr, "could not remove %s\n", temp_dirs[k]);
  }
  return failures;
}

const char *test_mpm_bin(void) {
  return getenv("MPM_BIN");
}

const char *const test_svd_path_name[TEST_SVD_PATHS] = {"mpm_svd3", "mpm_svd3_batch"};

void test_svd_path(int path, const mpm_real F[9], mpm_real U[9], mpm_real s[3], mpm_real V[9]) {
  if (path == TEST_SVD_SCALAR) {
    mpm_svd3(F, U, s, V);
    return;
  }
  enum { N = 64 }; /* more than one SIMD batch */
  static uint64_t rng = 77;
  mpm_real Fb[9][N], Ub[9][N], sb[3][N], Vb[9][N];
  const int lane = (int)test_rand(&rng, 0, N);
  for (int c = 0; c < 9; ++c)
    for (int l = 0; l < N; ++l) Fb[c][l] = l == lane ? F[c] : (mpm_real)test_rand(&rng, -2, 2);
  const mpm_real *Fp[9];
  mpm_real *Up[9], *Vp[9], *sp[3];
  for (int c = 0; c < 9; ++c) {
    Fp[c] = Fb[c];
    Up[c] = Ub[c];
    Vp[c] = Vb[c];
  }
  for (int c = 0; c < 3; ++c) sp[c] = sb[c];
  mpm_svd3_batch(N, Fp, Up, sp, Vp);
  for (int c = 0; c < 9; ++c) {
    U[c] = Ub[c][lane];
    V[c] = Vb[c][lane];
  }
  for (int c = 0; c < 3; ++c) s[c] = sb[c][lane];
}

struct mpm_sim *test_sim_from_json(const char *text, const char *name) {
  mpm_scene scene;
  mpm_error err;
  if (mpm_scene_parse(text, name, &scene, &err) != MPM_OK) fail_msg("%s", err.message);
  mpm_sim *sim = NULL;
  if (mpm_sim_create_from_scene(&scene, &sim, &err) != MPM_OK) fail_msg("%s", err.message);
  mpm_scene_free(&scene);
  return sim;
}

double test_centre_height(const struct mpm_sim *sim) {
  const mpm_particles *p = &sim->particles;
  double m = 0, my = 0;
  for (size_t i = 0; i < p->count; ++i) {
    m += p->mass[i];
    my += (double)p->mass[i] * p->x[1][i];
  }
  return my / m;
}

void test_assert_same_particles(const struct mpm_sim *a, const struct mpm_sim *b) {
  const mpm_particles *p = &a->particles, *q = &b->particles;
  assert_int_equal(p->count, q->count);
  for (int c = 0; c < 3; ++c) {
    assert_memory_equal(p->x[c], q->x[c], p->count * sizeof(mpm_real));
    assert_memory_equal(p->v[c], q->v[c], p->count * sizeof(mpm_real));
  }
  for (int c = 0; c < 9; ++c) assert_memory_equal(p->F[c], q->F[c], p->count * sizeof(mpm_real));
}

/* Rest-state error of the domain particles against their reference positions. */
double test_domain_rest_error(const struct mpm_sim *sim) {
  const mpm_domain_set *s = &sim->domains;
  const size_t n = s->particles.count;
  double(*X)[3] = malloc(n * sizeof *X), (*x)[3] = malloc(n * sizeof *x);
  for (size_t q = 0; q < n; ++q)
    for (int d = 0; d < 3; ++d) {
      double c = 0;
      for (int a = 0; a < MPM_HEX_CORNERS; ++a) c += s->w[q][a] * s->cX[d][s->corner[q][a]];
      X[q][d] = c;
      x[q][d] = s->particles.x[d][q];
    }
  const mpm_point_cloud rest = {n, (const double(*)[3])X, s->particles.id, NULL};
  const mpm_point_cloud final = {n, (const double(*)[3])x, s->particles.id, NULL};
  mpm_rest_error r;
  assert_int_equal(mpm_rest_error_compute(&rest, &final, &r), MPM_OK);
  free(X);
  free(x);
  return r.mean;
}

/* Every particle's F made the gradient of its corners' positions (F = sum_a x_a g_qa^T, as the
 * step keeps it), and its position and velocity from its corners. */
void test_domain_match_corners(struct mpm_domain_set *s) {
  for (size_t q = 0; q < s->particles.count; ++q)
    for (int r = 0; r < 3; ++r)
      for (int t = 0; t < 3; ++t) {
        double f = 0;
        for (int a = 0; a < MPM_HEX_CORNERS; ++a)
          f += (double)s->cx[r][s->corner[q][a]] * (double)s->g[q][a][t];
        s->particles.F[3 * r + t][q] = (mpm_real)f;
      }
  mpm_domain_set_sync_particles(s);
}

const char *const test_block_json =
    "{\"name\": \"block\", \"domain\": {\"min\": [0, 0, 0], \"max\": [0.5, 0.5, 0.5], \"dx\": "
    "0.05},"
    " \"gravity\": [0, 0, 0], \"time\": {\"end\": 0.1, \"fps\": 20},"
    " \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\", \"E\": 1e4, \"nu\": 0.3,"
    "  \"density\": 1000}],"
    " \"bodies\": [{\"name\": \"b\", \"shape\": {\"type\": \"box\", \"center\": [0.25, 0.25, 0.25],"
    "  \"half_extent\": [0.1, 0.1, 0.1]}, \"material\": \"m\", \"domains\": true}],"
    " \"colliders\": [{\"name\": \"pusher\", \"shape\": {\"type\": \"sphere\", \"center\": [0.05, "
    "0.05, 0.05],"
    "  \"radius\": 0.02}, \"rule\": \"slip\", \"motion\": {\"velocity\": [0.5, 0, 0]},"
    "  \"active\": [0.05, 1]}]}";
