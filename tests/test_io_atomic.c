/* test_io_atomic.c - atomic file rules and mkdir -p (src/io).
 *
 * Atomic files: a commit replaces the old file, an abort or any failure (missing directory,
 * file size limit hit mid-write, rename onto a directory) leaves the old file as it was and
 * no temporary behind, and the message names the path; every frame writer fails this way on
 * a missing directory. mkdir -p creates nested directories and names the component that is a
 * regular file. */
#define _POSIX_C_SOURCE 200809L

#include "support.h"
#include "io_support.h"
#include "io/io.h"

#include <dirent.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

/* ---------------------------------------------------------------- helpers */

static void spit(const char *path, const char *text) {
  FILE *fp = fopen(path, "wb");
  assert_non_null(fp);
  fputs(text, fp);
  assert_int_equal(fclose(fp), 0);
}

/* Whether any entry of dir looks like an atomic-write temporary. */
static int dir_has_temp(const char *dir) {
  DIR *d = opendir(dir);
  assert_non_null(d);
  int found = 0;
  for (struct dirent *e; (e = readdir(d));)
    if (strstr(e->d_name, ".tmp.")) found = 1;
  closedir(d);
  return found;
}

/* ---------------------------------------------------------------- atomic files */

static void test_atomic_commit_replaces(void **state) {
  (void)state;
  char dir[512], dot_dir[512];
  snprintf(dir, sizeof dir, "%s", test_temp_dir("io-atomic-commit"));
  snprintf(dot_dir, sizeof dot_dir, "%s", test_temp_dir("io-atomic-cwd"));
  char path[600];
  join(path, sizeof path, dir, "out.txt");
  spit(path, "old content that is longer than the new one\n");
  mpm_atomic_file f;
  mpm_error err = {0};
  assert_int_equal(mpm_atomic_open(&f, path, &err), MPM_OK);
  fputs("new\n", f.fp);
  /* before the commit the old file is still there, next to one temporary */
  assert_file_text(path, "old content that is longer than the new one\n");
  assert_int_equal(dir_entries(dir), 2);
  assert_true(dir_has_temp(dir));
  assert_int_equal(mpm_atomic_commit(&f, &err), MPM_OK);
  assert_file_text(path, "new\n");
  assert_int_equal(dir_entries(dir), 1);
  assert_false(dir_has_temp(dir));
  mpm_atomic_abort(&f); /* harmless after a commit */
  assert_file_text(path, "new\n");

  /* a bare file name: the temporary goes into the working directory */
  const char *cwd_name = "bare.txt";
  char old_cwd[1024];
  assert_non_null(getcwd(old_cwd, sizeof old_cwd));
  assert_int_equal(chdir(dot_dir), 0);
  assert_int_equal(mpm_atomic_open(&f, cwd_name, &err), MPM_OK);
  fputs("here\n", f.fp);
  assert_int_equal(mpm_atomic_commit(&f, &err), MPM_OK);
  assert_int_equal(chdir(old_cwd), 0);
  join(path, sizeof path, dot_dir, cwd_name);
  assert_file_text(path, "here\n");
  assert_int_equal(dir_entries(dot_dir), 1);
}

static void test_atomic_abort_keeps_old(void **state) {
  (void)state;
  const char *dir = test_temp_dir("io-atomic-abort");
  char path[600];
  join(path, sizeof path, dir, "keep.txt");
  spit(path, "previous\n");
  mpm_atomic_file f;
  mpm_error err = {0};
  assert_int_equal(mpm_atomic_open(&f, path, &err), MPM_OK);
  fputs("half a fr", f.fp);
  mpm_atomic_abort(&f);
  assert_null(f.fp);
  assert_file_text(path, "previous\n");
  assert_int_equal(dir_entries(dir), 1);
  assert_false(dir_has_temp(dir));
  mpm_atomic_abort(&f); /* twice is harmless */
  assert_file_text(path, "previous\n");
}

static void assert_io_error_names(mpm_status st, const mpm_error *err, const char *path) {
  assert_int_equal(st, MPM_ERR_IO);
  assert_int_equal(err->status, MPM_ERR_IO);
  if (!strstr(err->message, path)) fail_msg("message '%s' does not name '%s'", err->message, path);
}

static void test_missing_directory(void **state) {
  (void)state;
  const char *tmp = test_temp_dir("io-missing");
  char dir[600], path[700];
  join(dir, sizeof dir, tmp, "no/such/dir");
  join(path, sizeof path, dir, "frame.vtu");
  mpm_atomic_file f;
  mpm_error err = {0};
  assert_io_error_names(mpm_atomic_open(&f, path, &err), &err, path);
  assert_null(f.fp);
  mpm_atomic_abort(&f); /* nothing to clean up, nothing breaks */

  mpm_particles p;
  make_particles(&p, 5, NULL, NULL);
  mpm_frame_fields ff = {&p, NULL, NULL, 0.0, NULL, 0, NULL, 0, NULL, NULL};
  mpm_error_clear(&err);
  assert_io_error_names(mpm_write_vtu(path, &ff, &err), &err, path);
  mpm_error_clear(&err);
  assert_io_error_names(mpm_write_ply_points(path, &ff, &err), &err, path);
  const double t = 0;
  const char *files[1] = {"a.vtu"};
  mpm_error_clear(&err);
  assert_io_error_names(mpm_write_pvd(path, 1, &t, files, &err), &err, path);
  mpm_stats_row row = {0};
  mpm_error_clear(&err);
  assert_io_error_names(mpm_write_stats_csv(path, 1, &row, &err), &err, path);
  assert_int_equal(dir_entries(tmp), 0);
  mpm_particles_free(&p);
}

/* A write that fails midway (file size limit: EFBIG, as ENOSPC would) leaves the old file. */
static void test_write_failure_keeps_old(void **state) {
  (void)state;
  const char *dir = test_temp_dir("io-efbig");
  char path[600];
  join(path, sizeof path, dir, "frame.vtu");
  spit(path, "old frame\n");
  mpm_particles p;
  make_particles(&p, 5000, NULL, NULL); /* about 300 KB of VTU */
  mpm_frame_fields ff = {&p, NULL, NULL, 0.0, NULL, 0, NULL, 0, NULL, NULL};

  struct rlimit old_limit, limit;
  assert_int_equal(getrlimit(RLIMIT_FSIZE, &old_limit), 0);
  limit = old_limit;
  limit.rlim_cur = 64 * 1024;
  void (*old_handler)(int) = signal(SIGXFSZ, SIG_IGN);
  assert_int_equal(setrlimit(RLIMIT_FSIZE, &limit), 0);
  mpm_error err = {0};
  const mpm_status st_vtu = mpm_write_vtu(path, &ff, &err);
  mpm_error err_ply = {0};
  const mpm_status st_ply = mpm_write_ply_points(path, &ff, &err_ply);
  /* a caller that ignores its fwrite results still gets the failure from the commit */
  mpm_error err_raw = {0};
  mpm_atomic_file f;
  mpm_status st_raw = mpm_atomic_open(&f, path, &err_raw);
  if (st_raw == MPM_OK) {
    static const char block[4096];
    for (int k = 0; k < 40; ++k) (void)!fwrite(block, 1, sizeof block, f.fp);
    st_raw = mpm_atomic_commit(&f, &err_raw);
  }
  assert_int_equal(setrlimit(RLIMIT_FSIZE, &old_limit), 0);
  signal(SIGXFSZ, old_handler);

  assert_io_error_names(st_vtu, &err, path);
  assert_io_error_names(st_ply, &err_ply, path);
  assert_io_error_names(st_raw, &err_raw, path);
  assert_null(f.fp);
  assert_file_text(path, "old frame\n");
  assert_int_equal(dir_entries(dir), 1);
  assert_false(dir_has_temp(dir));
  mpm_particles_free(&p);
}

/* The rename itself fails (the final path is a non-empty directory). */
static void test_rename_failure(void **state) {
  (void)state;
  const char *dir = test_temp_dir("io-rename");
  char path[600], inner[700];
  join(path, sizeof path, dir, "target");
  assert_int_equal(mkdir(path, 0777), 0);
  join(inner, sizeof inner, path, "inside.txt");
  spit(inner, "x");
  mpm_atomic_file f;
  mpm_error err = {0};
  assert_int_equal(mpm_atomic_open(&f, path, &err), MPM_OK);
  fputs("data", f.fp);
  assert_io_error_names(mpm_atomic_commit(&f, &err), &err, path);
  assert_null(f.fp);
  assert_false(dir_has_temp(dir));
  assert_int_equal(dir_entries(dir), 1);
  assert_file_text(inner, "x");
}

static int is_dir(const char *path) {
  struct stat st;
  return stat(path, &st) == 0 && S_ISDIR(st.st_mode);
}

static void test_make_dirs(void **state) {
  (void)state;
  const char *tmp = test_temp_dir("io-mkdirs");
  char base[600], path[700];
  snprintf(base, sizeof base, "%s", tmp);
  mpm_error err = {0};

  join(path, sizeof path, base, "a/b//c/d/");
  assert_int_equal(mpm_make_dirs(path, &err), MPM_OK);
  join(path, sizeof path, base, "a/b/c/d");
  assert_true(is_dir(path));
  assert_int_equal(mpm_make_dirs(path, &err), MPM_OK); /* existing is fine */
  join(path, sizeof path, base, "a/b/e");
  assert_int_equal(mpm_make_dirs(path, &err), MPM_OK);
  assert_true(is_dir(path));

  /* a regular file in the way is named */
  char file[700];
  join(file, sizeof file, base, "a/plain");
  spit(file, "not a directory");
  join(path, sizeof path, base, "a/plain/x/y");
  assert_io_error_names(mpm_make_dirs(path, &err), &err, path);
  char quoted[710];
  snprintf(quoted, sizeof quoted, "'%s'", file);
  if (!strstr(err.message, quoted) || !strstr(err.message, "not a directory"))
    fail_msg("message '%s' does not name the file '%s'", err.message, file);
  /* also when the file is the last component */
  mpm_error_clear(&err);
  assert_io_error_names(mpm_make_dirs(file, &err), &err, file);
  assert_file_text(file, "not a directory");

  mpm_error_clear(&err);
  assert_int_equal(mpm_make_dirs("", &err), MPM_ERR_IO);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_atomic_commit_replaces), cmocka_unit_test(test_atomic_abort_keeps_old),
      cmocka_unit_test(test_missing_directory),      cmocka_unit_test(test_write_failure_keeps_old),
      cmocka_unit_test(test_rename_failure),         cmocka_unit_test(test_make_dirs),
  };
  const int failed = cmocka_run_group_tests(tests, NULL, NULL);
  remove_io_temp_dirs(failed);
  return test_cleanup(failed);
}
