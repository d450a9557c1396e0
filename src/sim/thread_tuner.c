/* thread_tuner.c - measuring the step's thread count (see thread_tuner.h). */
#define _POSIX_C_SOURCE 200809L /* strcasecmp */
#include "sim/thread_tuner.h"

#include "core/parallel.h"

#include <stdlib.h>
#include <string.h>
#include <strings.h>

#define FIRST_INTERVAL 20
#define MAX_INTERVAL 640
#define WIN 0.85 /* the other count must be this much faster to switch */

static void start(mpm_thread_tuner *t) {
  const char *env = getenv("MPM_THREADS_TUNE"), *policy = getenv("OMP_WAIT_POLICY");
  /* passive threads sleep at barriers: 2 threads then keep their share of a busy machine, and
   * measuring a step or two mistakes the load's noise for the count's cost (with five busy loops
   * beside jello_cubes: 4.8-5.0 s passive, 5.6-6.0 s passive and tuned), so only spinning
   * threads are tuned */
  const int passive = policy && !strcasecmp(policy, "passive");
  t->allowed = !(env && !strcmp(env, "0"));
  t->max = mpm_thread_count();
  t->enabled = t->allowed && !passive && t->max > 1;
  t->small = 0;
  t->use_max = 1;
  t->probing = 0;
  t->interval = FIRST_INTERVAL;
  t->countdown = 2; /* a step or two to warm up on max, then the first probe */
  t->cost[0] = t->cost[1] = 0;
}

void mpm_thread_tuner_before(mpm_thread_tuner *t, size_t particles) {
  if (t->enabled < 0) start(t);
  if (t->enabled >= 0 && mpm_thread_count() != t->max) start(t); /* the caller set a new count */
  t->small = t->allowed && t->max > 1 && particles < MPM_SMALL_STEP_PARTICLES;
  if (t->small) {
    mpm_set_threads(1);
    return;
  }
  if (!t->enabled) return;
  t->probing = t->countdown <= 0;
  const int on_max = t->probing ? !t->use_max : t->use_max;
  if (!on_max) mpm_set_threads(1);
}

void mpm_thread_tuner_after(mpm_thread_tuner *t, double seconds) {
  if (t->small) { /* the caller's count again; a small step's time tells nothing of the rest */
    mpm_set_threads(t->max);
    t->small = 0;
    return;
  }
  if (t->enabled <= 0) return;
  mpm_set_threads(t->max); /* the caller's count again, outside the step */
  if (!(seconds > 0)) return;
  const int which = t->probing ? !t->use_max : t->use_max;
  /* the count in use: smoothed over steps, so that one slow step (a page fault, a burst of load)
   * decides little; a probe's count: its fresh time (what it measured before is stale) */
  t->cost[which] =
      t->cost[which] > 0 && !t->probing ? 0.7 * t->cost[which] + 0.3 * seconds : seconds;
  if (!t->probing) {
    --t->countdown;
    return;
  }
  const int cur = t->use_max;
  if (t->cost[cur] > 0 && t->cost[!cur] < WIN * t->cost[cur]) {
    t->use_max = !cur; /* the probe won */
    t->interval = FIRST_INTERVAL;
    t->switches++;
  } else if (t->interval < MAX_INTERVAL) {
    t->interval *= 2;
  }
  t->countdown = t->interval;
  t->probing = 0;
}
