/* io_support.h - shared helpers of the I/O tests (test_io, test_io_atomic): whole files read
 * back, directory listings, test particles, and the clean-up of the tests' temporary
 * directories. Header only: each test program links support.c alone. Include it after
 * defining _POSIX_C_SOURCE. */
#ifndef MPM_TEST_IO_SUPPORT_H
#define MPM_TEST_IO_SUPPORT_H

#include "support.h"
#include "io/io.h"

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* Whole file in a malloc'd, NUL-terminated buffer; NULL when it cannot be read. */
static inline unsigned char *slurp(const char *path, size_t *len) {
  FILE *fp = fopen(path, "rb");
  if (!fp) return NULL;
  fseek(fp, 0, SEEK_END);
  const long n = ftell(fp);
  fseek(fp, 0, SEEK_SET);
  unsigned char *buf = malloc((size_t)n + 1);
  assert_non_null(buf);
  assert_int_equal(fread(buf, 1, (size_t)n, fp), (size_t)n);
  buf[n] = '\0';
  fclose(fp);
  *len = (size_t)n;
  return buf;
}

static inline void assert_file_text(const char *path, const char *expected) {
  size_t len = 0;
  unsigned char *buf = slurp(path, &len);
  assert_non_null(buf);
  assert_string_equal((const char *)buf, expected);
  free(buf);
}

/* Number of entries of a directory other than . and .. */
static inline int dir_entries(const char *dir) {
  DIR *d = opendir(dir);
  assert_non_null(d);
  int n = 0;
  for (struct dirent *e; (e = readdir(d));)
    if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..")) ++n;
  closedir(d);
  return n;
}

static inline void join(char *out, size_t cap, const char *dir, const char *name) {
  snprintf(out, cap, "%s/%s", dir, name);
}

/* n particles with distinct positions, velocities, deformation gradients and shuffled ids;
 * J[i] = det F and a made-up stress. */
static inline void make_particles(mpm_particles *p, size_t n, mpm_real *J, mpm_real *stress) {
  assert_int_equal(mpm_particles_init(p, n), MPM_OK);
  uint64_t rng = 777;
  for (size_t i = 0; i < n; ++i) {
    mpm_real x[3], v[3];
    for (int d = 0; d < 3; ++d) {
      x[d] = (mpm_real)test_rand(&rng, -2.0, 3.0);
      v[d] = (mpm_real)test_rand(&rng, -5.0, 5.0);
    }
    const long k = mpm_particles_push(p, x, v, (mpm_real)test_rand(&rng, 0.1, 2.0),
                                      (mpm_real)test_rand(&rng, 1e-6, 1e-5), (int32_t)(i % 3),
                                      (int32_t)(i % 5) - 1);
    assert_int_equal(k, (long)i);
    p->id[i] = (uint32_t)(1000 + 7 * (n - 1 - i));
    p->level[i] = (int32_t)(i % 4); /* particle types of a multi-level grid */
    for (int c = 0; c < 9; ++c)
      p->F[c][i] = (mpm_real)((c % 4 == 0 ? 1.0 : 0.0) + test_rand(&rng, -0.2, 0.2));
  }
  for (size_t i = 0; i < n; ++i) {
    double F[9];
    for (int c = 0; c < 9; ++c) F[c] = p->F[c][i];
    const double det = F[0] * (F[4] * F[8] - F[5] * F[7]) - F[1] * (F[3] * F[8] - F[5] * F[6]) +
                       F[2] * (F[3] * F[7] - F[4] * F[6]);
    if (J) J[i] = (mpm_real)det;
    if (stress) stress[i] = (mpm_real)(1e5 * (double)i + 0.5);
  }
}

/* After a run with no failure, remove this program's /tmp/mpm-test-<pid>-io-* directories. */
static inline void remove_io_temp_dirs(int failed) {
  if (!failed) { /* keep the files of a failing run for inspection */
    char cmd[128];
    snprintf(cmd, sizeof cmd, "rm -rf /tmp/mpm-test-%d-io-*", (int)getpid());
    if (system(cmd) != 0) fprintf(stderr, "could not remove %s\n", cmd + 7);
  }
}

#endif
