/* progress.c - progress display of `mpm run` (see progress.h). */
#ifndef _POSIX_C_SOURCE /* clock_gettime (test_progress includes this file after its own) */
#define _POSIX_C_SOURCE 200809L
#endif
#include "progress.h"

#include <stdio.h>
#include <time.h>

/* Wall time, monotonic, s. */
static double wall_seconds(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void mpm_progress_begin(mpm_progress *p, mpm_progress_mode mode, int frames, size_t particles) {
  (void)particles;
  p->mode = mode;
  p->frames = frames;
  p->start = p->last_time = wall_seconds();
  p->elapsed = 0;
  p->last_steps = 0;
  p->first_frame = 0;
  p->first_steps = 0;
  p->drawn = 0;
  p->t0 = 0;
  p->t_end = 0;
  p->marks = 0;
}

/* A completed frame (or the start: the first mark is taken at the first call, with t0). */
static void mark(mpm_progress *p, double wall, double sim_time) {
  const int n = MPM_PROGRESS_WINDOW + 1, k = p->marks % n;
  p->mark_wall[k] = wall;
  p->mark_sim[k] = sim_time;
  p->marks++;
}

void mpm_format_duration(double s, char *buf, size_t n) {
  if (!(s >= 0) || s > 1e8) {
    snprintf(buf, n, "--");
    return;
  }
  const long t = (long)(s + 0.5);
  if (t >= 3600)
    snprintf(buf, n, "%ld h %02ld min", t / 3600, (t / 60) % 60);
  else if (t >= 60)
    snprintf(buf, n, "%ld min %02ld s", t / 60, t % 60);
  else
    snprintf(buf, n, "%ld s", t);
}

/* The time left. With frames completed: the wall time per simulated second of the last ones
 * (up to MPM_PROGRESS_WINDOW), everything they cost included, times the simulated time left
 * from the last one, less what the frame in progress has taken so far (but never less than the
 * frame in progress's own pace gives for its rest). Before that, from the simulated time
 * reached since the start. */
static double eta_of(const mpm_progress *p, double sim_time) {
  const double now = p->start + p->elapsed;
  if (p->marks >= 2) {
    const int n = MPM_PROGRESS_WINDOW + 1, last = (p->marks - 1) % n;
    const int back = p->marks - 1 < MPM_PROGRESS_WINDOW ? p->marks - 1 : MPM_PROGRESS_WINDOW;
    const int first = (p->marks - 1 - back) % n;
    const double dsim = p->mark_sim[last] - p->mark_sim[first];
    const double dwall = p->mark_wall[last] - p->mark_wall[first];
    if (dsim > 0 && dwall >= 0) {
      const double rate = dwall / dsim, in_frame = now - p->mark_wall[last];
      double eta = rate * (p->t_end - p->mark_sim[last]) - in_frame;
      const double partial = sim_time - p->mark_sim[last];
      if (partial > 0 && in_frame > 0) { /* this frame is slower than the last ones */
        const double own = in_frame / partial * (p->t_end - sim_time);
        if (own > eta) eta = own;
      }
      return eta > 0 ? eta : 0;
    }
  }
  const double done = sim_time - p->t0, left = p->t_end - sim_time;
  return done > 0 && p->elapsed > 0 ? p->elapsed / done * left : -1;
}

static void draw(mpm_progress *p, int frame, double sim_time, int64_t steps, size_t particles,
                 const char *extra, int within) {
  const char *sep = extra && extra[0] ? "  " : "";
  if (!extra) extra = "";
  const double rate = p->elapsed > 0 ? (double)(steps - p->first_steps) / p->elapsed : 0;
  char eta_s[32];
  mpm_format_duration(eta_of(p, sim_time), eta_s, sizeof eta_s);
  if (p->mode == MPM_PROGRESS_BAR) {
    const int width = 28;
    const double f = p->t_end > p->t0 ? (sim_time - p->t0) / (p->t_end - p->t0) : 1;
    const double whole = (double)p->first_frame / (p->frames > 0 ? p->frames : 1);
    int fill = (int)((whole + (1 - whole) * f) * width);
    if (fill > width) fill = width;
    char bar[64];
    for (int i = 0; i < width; ++i) bar[i] = i < fill ? '#' : '.';
    bar[width] = '\0';
    fprintf(stderr, "\r[%s] frame %d/%d  t=%.4g s  %.0f steps/s  eta %s  %zu particles%s%s\033[K",
            bar, frame, p->frames, sim_time, rate, eta_s, particles, sep, extra);
    fflush(stderr);
    p->drawn = 1;
  } else if (within) {
    fprintf(stderr, "frame %d/%d in progress: t=%.6g s steps=%lld steps/s=%.1f eta %s\n", frame,
            p->frames, sim_time, (long long)steps, rate, eta_s);
  } else {
    fprintf(stderr, "frame %d/%d t=%.6g s steps=%lld steps/s=%.1f eta %s particles=%zu%s%s\n",
            frame, p->frames, sim_time, (long long)steps, rate, eta_s, particles, sep, extra);
  }
}

void mpm_progress_update(mpm_progress *p, int frame, double sim_time, int64_t steps,
                         size_t particles, const char *extra) {
  const double now = wall_seconds();
  p->elapsed = now - p->start;
  if (p->marks == 0) mark(p, p->start, p->t0);
  mark(p, now, sim_time);
  if (p->mode == MPM_PROGRESS_QUIET) return;
  draw(p, frame, sim_time, steps, particles, extra, 0);
  p->last_steps = steps;
  p->last_time = now;
}

void mpm_progress_step(mpm_progress *p, int frame, double sim_time, int64_t steps,
                       size_t particles) {
  if (p->mode == MPM_PROGRESS_QUIET) return;
  const double now = wall_seconds();
  if (now - p->last_time < (p->mode == MPM_PROGRESS_BAR ? 0.5 : 10)) return;
  p->elapsed = now - p->start;
  draw(p, frame + 1, sim_time, steps, particles, NULL, 1); /* the frame being computed */
  p->last_steps = steps;
  p->last_time = now;
}

void mpm_progress_end(mpm_progress *p) {
  p->elapsed = wall_seconds() - p->start;
  if (p->mode == MPM_PROGRESS_BAR && p->drawn) fputc('\n', stderr);
}
