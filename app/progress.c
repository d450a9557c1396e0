/* progress.c - progress display of `mpm run` (see progress.h). */
#include "progress.h"
#include "solver/sim.h"

#include <stdio.h>

void mpm_progress_begin(mpm_progress *p, mpm_progress_mode mode, int frames, size_t particles) {
  (void)particles;
  p->mode = mode;
  p->frames = frames;
  p->start = p->last_time = mpm_wall_seconds();
  p->elapsed = 0;
  p->last_steps = 0;
  p->first_frame = 0;
  p->first_steps = 0;
  p->drawn = 0;
}

static void format_eta(double s, char *buf, size_t n) {
  if (s < 0 || s > 1e7) {
    snprintf(buf, n, "--:--");
    return;
  }
  long t = (long)(s + 0.5);
  if (t >= 3600)
    snprintf(buf, n, "%ld:%02ld:%02ld", t / 3600, (t / 60) % 60, t % 60);
  else
    snprintf(buf, n, "%ld:%02ld", t / 60, t % 60);
}

void mpm_progress_update(mpm_progress *p, int frame, double sim_time, int64_t steps,
                         size_t particles, const char *extra) {
  const char *sep = extra && extra[0] ? "  " : "";
  if (!extra) extra = "";
  const double now = mpm_wall_seconds();
  p->elapsed = now - p->start;
  if (p->mode == MPM_PROGRESS_QUIET) return;
  const double rate = p->elapsed > 0 ? (double)(steps - p->first_steps) / p->elapsed : 0;
  const int done = frame - p->first_frame;
  const double eta = done > 0 ? p->elapsed / done * (p->frames - frame) : -1;
  char eta_s[32];
  format_eta(eta, eta_s, sizeof eta_s);
  if (p->mode == MPM_PROGRESS_BAR) {
    const int width = 28;
    int fill = p->frames > 0 ? (int)((double)frame / p->frames * width) : width;
    char bar[64];
    for (int i = 0; i < width; ++i) bar[i] = i < fill ? '#' : '.';
    bar[width] = '\0';
    fprintf(stderr, "\r[%s] frame %d/%d  t=%.4g s  %.0f steps/s  ETA %s  %zu particles%s%s\033[K",
            bar, frame, p->frames, sim_time, rate, eta_s, particles, sep, extra);
    fflush(stderr);
    p->drawn = 1;
  } else {
    fprintf(stderr, "frame %d/%d t=%.6g s steps=%lld steps/s=%.1f eta=%s particles=%zu%s%s\n",
            frame, p->frames, sim_time, (long long)steps, rate, eta_s, particles, sep, extra);
  }
  p->last_steps = steps;
  p->last_time = now;
}

void mpm_progress_end(mpm_progress *p) {
  p->elapsed = mpm_wall_seconds() - p->start;
  if (p->mode == MPM_PROGRESS_BAR && p->drawn) fputc('\n', stderr);
}
