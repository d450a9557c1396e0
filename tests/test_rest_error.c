/* test_rest_error.c - the rest-state error (analysis/rest_error.h) and `mpm error`:
 *   - a rotated and translated copy of a cloud has error 0 to round-off, and the rotation
 *     found is the one applied;
 *   - a known displacement of every particle (fixed length, random direction) on top of a rigid
 *     motion gives its length over the rest diagonal;
 *   - particles are matched by id (shuffled, some missing);
 *   - a mirror image is not undone (the rotation has det +1), and a rank-2 matrix still gives a
 *     rotation;
 *   - the command prints the error of a run's frames and refuses bad arguments with exit 2. */
#include "support.h"
#include "analysis/rest_error.h"
#include "cli_support.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define N 1000

/* A rotation from an axis and an angle (Rodrigues). */
static void rotation(const double axis[3], double angle, double R[9]) {
  const double n = sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
  const double k[3] = {axis[0] / n, axis[1] / n, axis[2] / n};
  const double c = cos(angle), s = sin(angle), t = 1 - c;
  const double r[9] = {
      c + k[0] * k[0] * t,        k[0] * k[1] * t - k[2] * s, k[0] * k[2] * t + k[1] * s,
      k[1] * k[0] * t + k[2] * s, c + k[1] * k[1] * t,        k[1] * k[2] * t - k[0] * s,
      k[2] * k[0] * t - k[1] * s, k[2] * k[1] * t + k[0] * s, c + k[2] * k[2] * t};
  memcpy(R, r, sizeof r);
}

typedef struct clouds {
  double q[N][3], p[N][3];
  uint32_t qid[N], pid[N];
  double mass[N];
} clouds;

/* A box-shaped cloud of N points (0.4 x 0.2 x 0.1 m) and its image p = R q + t. */
static void make(clouds *c, const double R[9], const double t[3], uint64_t *rng) {
  for (int i = 0; i < N; ++i) {
    c->q[i][0] = test_rand(rng, 0.3, 0.7);
    c->q[i][1] = test_rand(rng, 0.5, 0.7);
    c->q[i][2] = test_rand(rng, 0.2, 0.3);
    c->qid[i] = c->pid[i] = (uint32_t)(1000 + 7 * i);
    c->mass[i] = test_rand(rng, 0.5, 1.5);
    for (int r = 0; r < 3; ++r)
      c->p[i][r] =
          R[3 * r] * c->q[i][0] + R[3 * r + 1] * c->q[i][1] + R[3 * r + 2] * c->q[i][2] + t[r];
  }
}

static mpm_rest_error compute(const clouds *c, size_t np) {
  const mpm_point_cloud rest = {N, (const double(*)[3])c->q, c->qid, c->mass};
  const mpm_point_cloud final = {np, (const double(*)[3])c->p, c->pid, NULL};
  mpm_rest_error e;
  assert_int_equal(mpm_rest_error_compute(&rest, &final, &e), MPM_OK);
  return e;
}

static void test_rigid_motion_is_removed(void **state) {
  (void)state;
  static clouds c;
  uint64_t rng = 1;
  for (int trial = 0; trial < 5; ++trial) {
    double R[9];
    const double axis[3] = {test_rand(&rng, -1, 1), test_rand(&rng, -1, 1), test_rand(&rng, -1, 1)};
    rotation(axis, test_rand(&rng, 0, 3.1), R);
    const double t[3] = {test_rand(&rng, -1, 1), test_rand(&rng, -1, 1), test_rand(&rng, -1, 1)};
    make(&c, R, t, &rng);
    const mpm_rest_error e = compute(&c, N);
    assert_true(e.mean < 1e-13 && e.max < 1e-13);
    assert_int_equal(e.matched, N);
    for (int k = 0; k < 9; ++k) assert_close(e.R[k], R[k], 1e-12);
    for (int k = 0; k < 3; ++k) assert_close(e.translation[k], t[k], 1e-12);
  }
}

static void test_known_displacement(void **state) {
  (void)state;
  static clouds c;
  uint64_t rng = 2;
  double R[9];
  const double axis[3] = {0.3, -1, 0.5}, t[3] = {0.1, -0.2, 0.05};
  rotation(axis, 0.8, R);
  make(&c, R, t, &rng);
  const double eps = 1e-3; /* every particle displaced by 1 mm in a random direction */
  for (int i = 0; i < N; ++i) {
    double d[3], n = 0;
    for (int k = 0; k < 3; ++k) d[k] = test_rand(&rng, -1, 1), n += d[k] * d[k];
    n = sqrt(n);
    for (int k = 0; k < 3; ++k) c.p[i][k] += eps * d[k] / n;
  }
  const mpm_rest_error e = compute(&c, N);
  const double diag = sqrt(0.4 * 0.4 + 0.2 * 0.2 + 0.1 * 0.1);
  print_message("1 mm displacements: mean %.4e (expected about %.4e), max %.4e, diagonal %.4f\n",
                e.mean, eps / diag, e.max, e.diagonal);
  /* the best fit absorbs a little of the noise: a bit under eps / diag, never above by much */
  assert_true(e.mean > 0.95 * eps / e.diagonal && e.mean < 1.01 * eps / e.diagonal);
  assert_true(e.max < 1.1 * eps / e.diagonal);
  assert_close(e.diagonal, diag, 0.01);
}

static void test_matching_by_id(void **state) {
  (void)state;
  static clouds c;
  uint64_t rng = 3;
  double R[9];
  const double axis[3] = {1, 1, 0}, t[3] = {0, 0.3, 0};
  rotation(axis, 0.4, R);
  make(&c, R, t, &rng);
  for (int i = N - 1; i > 0; --i) { /* shuffle the final frame */
    const int j = (int)test_rand(&rng, 0, i + 1);
    for (int k = 0; k < 3; ++k) {
      const double x = c.p[i][k];
      c.p[i][k] = c.p[j][k];
      c.p[j][k] = x;
    }
    const uint32_t id = c.pid[i];
    c.pid[i] = c.pid[j];
    c.pid[j] = id;
  }
  const mpm_rest_error e = compute(&c, N - 100); /* and drop 100 particles */
  assert_int_equal(e.matched, N - 100);
  assert_true(e.mean < 1e-13);
  /* no common particle */
  for (int i = 0; i < N; ++i) c.pid[i] += 1;
  const mpm_point_cloud rest = {N, (const double(*)[3])c.q, c.qid, NULL};
  const mpm_point_cloud final = {N, (const double(*)[3])c.p, c.pid, NULL};
  mpm_rest_error e2;
  assert_int_equal(mpm_rest_error_compute(&rest, &final, &e2), MPM_ERR_INVALID);
}

static double det(const double M[9]) {
  return M[0] * (M[4] * M[8] - M[5] * M[7]) - M[1] * (M[3] * M[8] - M[5] * M[6]) +
         M[2] * (M[3] * M[7] - M[4] * M[6]);
}

static void test_reflections_and_rank(void **state) {
  (void)state;
  static clouds c;
  uint64_t rng = 4;
  const double mirror[9] = {-1, 0, 0, 0, 1, 0, 0, 0, 1}, t[3] = {0, 0, 0};
  make(&c, mirror, t, &rng);
  const mpm_rest_error e = compute(&c, N);
  assert_close(det(e.R), 1, 1e-12);
  assert_true(e.mean > 0.05); /* a mirror image is not a rest state */
  /* a rank-2 matrix (a flat cloud) still gives a rotation */
  const double A[9] = {2, 0, 0, 0, 1, 0, 0, 0, 0};
  double R[9];
  mpm_nearest_rotation(A, R);
  assert_close(det(R), 1, 1e-12);
  for (int k = 0; k < 9; ++k) assert_close(R[k], k % 4 == 0 ? 1 : 0, 1e-12);
}

static void test_command(void **state) {
  (void)state;
  const char *dir = test_temp_dir("rest_error_cli");
  char scene[600], args[2048];
  snprintf(scene, sizeof scene, "%s/scene.json", dir);
  write_file(scene, "{\"domain\": {\"min\": [0,0,0], \"max\": [0.6,0.6,0.6], \"dx\": 0.05},"
                    " \"gravity\": [0, 0, 0], \"time\": {\"end\": 0.1, \"fps\": 20},"
                    " \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\", \"E\": 1e4, "
                    "\"nu\": 0.3, \"density\": 1000}],"
                    " \"bodies\": [{\"shape\": {\"type\": \"sphere\", \"center\": [0.3,0.3,0.25],"
                    " \"radius\": 0.08}, \"material\": \"m\", \"velocity\": [0.5, 0, 0]},"
                    " {\"shape\": {\"type\": \"sphere\", \"center\": [0.3,0.3,0.4], \"radius\": "
                    "0.04}, \"material\": \"m\"}]}");
  snprintf(args, sizeof args, "run '%s' -o '%s/out' --quiet", scene, dir);
  if (mpm(args) != 0) fail_msg("%s", output);
  snprintf(args, sizeof args, "error '%s/out' 0 2", dir);
  assert_int_equal(mpm(args), 0);
  expect_output("rest-state error: mean");
  expect_output("particles matched");
  snprintf(args, sizeof args, "error '%s/out/frame_0000.vtu' '%s/out/frame_0000.vtu'", dir, dir);
  assert_int_equal(mpm(args), 0);
  expect_output("mean 0.000e+00");
  /* one body: the small sphere alone (its 8 cells' particles, fewer than the two bodies') */
  snprintf(args, sizeof args, "error '%s/out' 0 2", dir);
  assert_int_equal(mpm(args), 0);
  const char *all = strstr(output, "(");
  assert_non_null(all);
  const long n_all = strtol(all + 1, NULL, 10);
  snprintf(args, sizeof args, "error '%s/out' 0 2 --body 1", dir);
  assert_int_equal(mpm(args), 0);
  const char *one = strstr(output, "(");
  assert_non_null(one);
  const long n_one = strtol(one + 1, NULL, 10);
  print_message("particles matched: %ld of both bodies, %ld of body 1\n", n_all, n_one);
  assert_true(n_one > 0 && n_one < n_all / 4);
  snprintf(args, sizeof args, "error '%s/out' 0 2 --body 7", dir);
  assert_int_equal(mpm(args), 2);
  expect_output("no particle id is in both frames");
  snprintf(args, sizeof args, "error '%s/out' 0 2 --body x", dir);
  assert_int_equal(mpm(args), 2);
  snprintf(args, sizeof args, "error '%s/out'", dir);
  assert_int_equal(mpm(args), 2);
  expect_output("usage: mpm error");
  snprintf(args, sizeof args, "error '%s/out' 0", dir); /* two arguments are two frame files */
  assert_int_equal(mpm(args), 2);
  expect_output("/out: cannot open: it is a folder, not a regular file");
  snprintf(args, sizeof args, "error '%s/out' 0 9", dir);
  assert_int_equal(mpm(args), 2);
  expect_output("frame_0009.vtu");
  snprintf(args, sizeof args, "error '%s' '%s'", scene, scene);
  assert_int_equal(mpm(args), 2);
  expect_output("scene.json");
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_rigid_motion_is_removed),
      cmocka_unit_test(test_known_displacement),
      cmocka_unit_test(test_matching_by_id),
      cmocka_unit_test(test_reflections_and_rank),
      cmocka_unit_test(test_command),
  };
  return test_cleanup(cmocka_run_group_tests(tests, NULL, NULL));
}
