#define _POSIX_C_SOURCE 200809L /* setenv, unsetenv */
/* test_thread_tuner.c - the step's thread count chosen by measuring (sim/thread_tuner.h), fed
 * with made-up step times: it starts on the caller's count, probes one thread after two steps,
 * switches when the probe is faster by the margin and stays when it is not (probing half as
 * often each time it stays), restores the caller's count after every step, starts over when the
 * caller sets another count, and does nothing with MPM_THREADS_TUNE=0, passive threads or one
 * thread. */
#include "support.h"

#include "core/parallel.h"
#include "sim/thread_tuner.h"

#include <stdlib.h>

/* One step through the tuner taking `one` seconds on 1 thread and `many` on more; the count it
 * ran on. */
static int step(mpm_thread_tuner *t, double one, double many) {
  mpm_thread_tuner_before(t, 1u << 20);
  const int n = mpm_thread_count();
  mpm_thread_tuner_after(t, n == 1 ? one : many);
  return n;
}

static void test_switches_to_the_faster_count(void **state) {
  (void)state;
#ifndef _OPENMP
  skip();
#endif
  unsetenv("MPM_THREADS_TUNE");
  unsetenv("OMP_WAIT_POLICY"); /* the tuner is for spinning threads (ctest sets passive ones) */
  mpm_set_threads(2);
  mpm_thread_tuner t = {.enabled = -1};
  /* a busy machine: 1 thread takes 1 s, 2 threads 2 s */
  assert_int_equal(step(&t, 1, 2), 2);
  assert_int_equal(step(&t, 1, 2), 2);
  assert_int_equal(step(&t, 1, 2), 1);     /* the probe */
  assert_int_equal(t.use_max, 0);          /* it won: 1 thread from now on */
  assert_int_equal(mpm_thread_count(), 2); /* the caller's count outside the step */
  for (int k = 0; k < 20; ++k) assert_int_equal(step(&t, 1, 2), 1);
  assert_int_equal(step(&t, 1, 2), 2); /* probing 2 threads again */
  assert_int_equal(t.use_max, 0);      /* it lost */
  assert_int_equal(t.interval, 40);    /* so the next probe comes twice as late */
  /* the machine becomes idle: 2 threads take 0.5 s; the next probe of 2 threads wins */
  int n = 1, steps = 0;
  while (n == 1 && steps < 100) n = step(&t, 1, 0.5), ++steps;
  assert_int_equal(n, 2);
  assert_int_equal(steps, 41);
  assert_int_equal(t.use_max, 1);
  assert_int_equal(t.switches, 2);
  /* within the margin (1 thread only 10% faster) it stays on 2 */
  for (int k = 0; k < 200; ++k) step(&t, 0.9, 1);
  assert_int_equal(t.use_max, 1);
  /* the caller sets 1 thread: the tuner starts over and, with one thread, does nothing */
  mpm_set_threads(1);
  for (int k = 0; k < 10; ++k) assert_int_equal(step(&t, 1, 2), 1);
  assert_int_equal(t.enabled, 0);
  mpm_set_threads(2);
  assert_int_equal(step(&t, 1, 2), 2);
  assert_int_equal(t.enabled, 1);
}

static void test_environment_turns_it_off(void **state) {
  (void)state;
  setenv("MPM_THREADS_TUNE", "0", 1);
  mpm_set_threads(2);
  mpm_thread_tuner t = {.enabled = -1};
  for (int k = 0; k < 50; ++k) assert_int_equal(step(&t, 1, 100), mpm_thread_count());
  assert_int_equal(t.enabled, 0);
  unsetenv("MPM_THREADS_TUNE");
  /* passive threads are not tuned */
  setenv("OMP_WAIT_POLICY", "passive", 1);
  mpm_thread_tuner p = {.enabled = -1};
  for (int k = 0; k < 50; ++k) assert_int_equal(step(&p, 1, 100), 2);
  assert_int_equal(p.enabled, 0);
}

/* A step of fewer than MPM_SMALL_STEP_PARTICLES particles runs on one thread, spinning or
 * passive, and the caller's count is back after it; MPM_THREADS_TUNE=0 keeps the caller's. */
static void test_small_steps_run_on_one_thread(void **state) {
  (void)state;
#ifndef _OPENMP
  skip();
#endif
  unsetenv("MPM_THREADS_TUNE");
  setenv("OMP_WAIT_POLICY", "passive", 1);
  mpm_set_threads(2);
  mpm_thread_tuner t = {.enabled = -1};
  for (int k = 0; k < 5; ++k) {
    mpm_thread_tuner_before(&t, MPM_SMALL_STEP_PARTICLES - 1);
    assert_int_equal(mpm_thread_count(), 1);
    mpm_thread_tuner_after(&t, 1);
    assert_int_equal(mpm_thread_count(), 2);
    mpm_thread_tuner_before(&t, MPM_SMALL_STEP_PARTICLES);
    assert_int_equal(mpm_thread_count(), 2);
    mpm_thread_tuner_after(&t, 1);
  }
  setenv("MPM_THREADS_TUNE", "0", 1);
  mpm_thread_tuner off = {.enabled = -1};
  mpm_thread_tuner_before(&off, 10);
  assert_int_equal(mpm_thread_count(), 2);
  mpm_thread_tuner_after(&off, 1);
  unsetenv("MPM_THREADS_TUNE");
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_switches_to_the_faster_count),
      cmocka_unit_test(test_environment_turns_it_off),
      cmocka_unit_test(test_small_steps_run_on_one_thread),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
