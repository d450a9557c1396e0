/* test_progress.c - `mpm run`'s progress display (app/progress.c, compiled in here): the time
 * left reads as a duration, it is estimated from the simulated time reached, and within a long
 * frame a line is printed once 10 s of wall time have passed, not before. */
#include "support.h"

#include <math.h>

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

/* A run whose frames cost 1 s each, 0.95 s of it at the frame's end (its particle surface and
 * files): after the third frame, at the last step of the fourth (when the bar stays while the
 * surface is made), the time left is what the frames still cost, within 25% (it was 34% short:
 * the simulated time of the frame was counted, its surface not). The estimate follows frames
 * that grow dearer from the last ones, and a frame slower than those from its own pace. */
static void test_eta_counts_frame_outputs(void **state) {
  (void)state;
  mpm_progress p;
  mpm_progress_begin(&p, MPM_PROGRESS_QUIET, 10, 100);
  p.t0 = 0, p.t_end = 1;
  const double start = p.start;
  for (int k = 0; k <= 3; ++k) mark(&p, start + k, 0.1 * k); /* the start and 3 frames */
  p.elapsed = 3.05;                                          /* the 4th frame's steps done */
  const double left = 0.95 + 6, eta = eta_of(&p, 0.4);
  print_message("eta %.2f s, left %.2f s\n", eta, left);
  assert_true(fabs(eta / left - 1) < 0.25);
  /* frames growing dearer (1, 2, ..., 6 s; the next 4 cost 7 to 10 s): the last 4 frames'
     pace is used (4.5 s a frame), not the run's mean (3.5 s) */
  mpm_progress_begin(&p, MPM_PROGRESS_QUIET, 10, 100);
  p.t0 = 0, p.t_end = 1;
  double wall = p.start;
  mark(&p, wall, 0);
  for (int k = 1; k <= 6; ++k) mark(&p, wall += k, 0.1 * k);
  p.elapsed = wall - p.start;
  const double recent = eta_of(&p, 0.6);
  print_message("growing frames: eta %.1f s (the mean would say %.1f, they cost 34)\n", recent,
                p.elapsed / 0.6 * 0.4);
  assert_true(recent > p.elapsed / 0.6 * 0.4 * 1.2);
  /* a frame slower than the last ones: its own pace */
  p.elapsed += 30;
  assert_true(eta_of(&p, 0.65) >= 30 / 0.05 * 0.35 - 1e-9);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_durations),
      cmocka_unit_test(test_lines_within_a_frame),
      cmocka_unit_test(test_eta_counts_frame_outputs),
  };
  return test_cleanup(cmocka_run_group_tests(tests, NULL, NULL));
}
