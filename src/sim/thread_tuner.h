/* thread_tuner.h - the number of threads a step runs on, chosen by measuring (issue 17: fast on a
 * busy machine by default).
 *
 * On a machine whose other cores are busy (a host application, a render, a second simulation),
 * every barrier of a step waits for the thread the OS has descheduled, and a step on 2 threads
 * can take twice as long as on 1. The OpenMP wait policy cannot be changed once the runtime is
 * loaded, and a passive policy costs 40% on an idle machine. So the step measures instead: it
 * runs on the threads the caller allows (`max`) or on 1, whichever its recent steps found faster,
 * and now and then probes the other count with one step. A probe that confirms the choice makes
 * the next probe come twice as late (up to every 640 steps); a probe that wins switches.
 *
 * The count is set for the step only: the caller's OpenMP setting is restored after it (a host
 * application's own parallel regions keep theirs). Results do not depend on the thread count
 * (every reduction has a fixed order), so switching changes only the time. MPM_THREADS_TUNE=0 in
 * the environment, or tuner.enabled = 0, keeps the caller's count (benchmarks do).
 *
 * Small steps run on one thread, spinning or passive: a step of fewer than
 * MPM_SMALL_STEP_PARTICLES particles (material points and domain particles) has too little work
 * per parallel region for a second thread to pay for its wake-ups (passive threads sleep at
 * every barrier: Zhu's scenes of about 2,000 particles took 1.6 times as long on 2 threads as on
 * 1, and at 5,500 still 8% longer; at 6,900, 8% less). MPM_THREADS_TUNE=0 turns this off too
 * (the tests' thread-count comparisons). */
#define MPM_SMALL_STEP_PARTICLES 4096
#ifndef MPM_SIM_THREAD_TUNER_H
#define MPM_SIM_THREAD_TUNER_H

#include <stddef.h>

typedef struct mpm_thread_tuner {
  int enabled;    /* -1: not decided yet (the environment is read at the first step) */
  int max;        /* the threads the caller set (mpm_set_threads, --threads, OMP_NUM_THREADS) */
  int use_max;    /* the choice: max threads (1) or one (0) */
  int probing;    /* this step runs on the other count */
  int interval;   /* steps between probes */
  int countdown;  /* steps until the next probe */
  double cost[2]; /* seconds per step on 1 thread [0] and on max [1], smoothed; 0: unknown */
  long long switches;
  int allowed; /* not turned off by MPM_THREADS_TUNE=0 */
  int small;   /* this step runs on one thread for its size */
} mpm_thread_tuner;

/* Before a step of `particles` particles: set the threads it runs on. */
void mpm_thread_tuner_before(mpm_thread_tuner *t, size_t particles);
/* After it: its raw step's wall time, seconds. */
void mpm_thread_tuner_after(mpm_thread_tuner *t, double seconds);

#endif
