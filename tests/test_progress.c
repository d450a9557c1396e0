/* test_progress.c - `mpm run`'s progress display (app/progress.c, compiled in here): the time
 * left reads as a duration, it is estimated from the simulated time reached, and within a long
 * frame a line is printed once 10 s of wall time have passed, not before. */
#include "support.h"

#include "../app/progress.c"

#include <stdio.h>
#include <string.h>

static void test_durations(void **state) {
  (void)state;
  char b[32];
  mpm_format_duration(12.4, b, sizeof b);
  assert_string_equal(b, "12 s");
  mpm_format_duration(185, b, sizeof b);
  assert_string_equal(b, "3 min 05 s");
  mpm_format_duration(3720, b, sizeof b);
  assert_string_equal(b, "1 h 02 min");
  mpm_format_duration(-1, b, sizeof b);
  assert_string_equal(b, "--");
}

static void test_lines_within_a_frame(void **state) {
  (void)state;
  char path[512];
  snprintf(path, sizeof path, "%s/progress.txt", test_temp_dir("progress"));
  FILE *saved = stderr, *f = fopen(path, "w+");
  assert_non_null(f);
  stderr = f;
  mpm_progress p;
  mpm_progress_begin(&p, MPM_PROGRESS_LINES, 10, 100);
  p.t0 = 0;
  p.t_end = 1;
  mpm_progress_step(&p, 0, 0.05, 10, 100); /* too soon: nothing */
  p.start -= 20;                           /* 20 s into the run, a quarter of it simulated */
  p.last_time -= 11;
  mpm_progress_step(&p, 0, 0.25, 40, 100);
  stderr = saved;
  rewind(f);
  char text[512] = "";
  const size_t n = fread(text, 1, sizeof text - 1, f);
  text[n] = 0;
  fclose(f);
  if (!strstr(text, "frame 1/10 in progress: t=0.25 s steps=40") || !strstr(text, "eta 1 min 00 s"))
    fail_msg("printed: %s", text);
  assert_null(strstr(text, "t=0.05"));
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_durations),
      cmocka_unit_test(test_lines_within_a_frame),
  };
  return test_cleanup(cmocka_run_group_tests(tests, NULL, NULL));
}
