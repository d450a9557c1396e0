/* cli_support.h - running the `mpm` program from a test (test_cli, test_plot, test_render):
 * the binary comes from MPM_BIN (set by ctest), stderr is merged into the kept output. */
#ifndef MPM_TEST_CLI_SUPPORT_H
#define MPM_TEST_CLI_SUPPORT_H

#include "support.h"

#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>

static char output[65536]; /* what the last command printed */

/* Run `ENV 'mpm' ARGS` through the shell (env is a prefix such as "PATH=/x" or ""), keep its
 * output, return its exit code. */
static inline int mpm_env(const char *env, const char *args) {
  const char *bin = test_mpm_bin();
  if (!bin) fail_msg("MPM_BIN is not set (run through ctest)");
  char cmd[4096];
  snprintf(cmd, sizeof cmd, "%s '%s' %s 2>&1", env, bin, args);
  FILE *f = popen(cmd, "r");
  assert_non_null(f);
  size_t n = fread(output, 1, sizeof output - 1, f);
  output[n] = '\0';
  int status = pclose(f);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

static inline int mpm(const char *args) {
  return mpm_env("", args);
}

static inline void expect_output(const char *needle) {
  if (!strstr(output, needle)) fail_msg("expected '%s' in the output:\n%s", needle, output);
}

static inline void write_file(const char *path, const char *text) {
  FILE *f = fopen(path, "w");
  assert_non_null(f);
  fputs(text, f);
  fclose(f);
}

static inline int exists(const char *path) {
  struct stat st;
  return stat(path, &st) == 0;
}

#endif
