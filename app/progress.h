/* progress.h - progress display of `mpm run`: a redrawn bar on a terminal, one plain line per
 * frame otherwise, nothing with --quiet. Within a long frame the bar is redrawn every half second
 * and a line is printed every 10 s (mpm_progress_step). The time left is estimated from the
 * wall time per simulated second of the last frames completed, which counts everything a frame
 * costs (its steps, and its files, particle surfaces and checkpoints written at its end), less
 * the time already spent on the frame in progress; before the first frame completes, from the
 * simulated time reached. Printed as a duration (`eta 3 min 05 s`). */
#ifndef MPM_APP_PROGRESS_H
#define MPM_APP_PROGRESS_H

#include <stddef.h>
#include <stdint.h>

typedef enum { MPM_PROGRESS_QUIET, MPM_PROGRESS_LINES, MPM_PROGRESS_BAR } mpm_progress_mode;
/* Completed frames the time left is estimated from (the most recent ones: a run whose frames
 * grow dearer is followed). */
#define MPM_PROGRESS_WINDOW 4

typedef struct mpm_progress {
  mpm_progress_mode mode;
  int frames;
  int first_frame;     /* frame the run started (or resumed) from */
  int64_t first_steps; /* steps taken before it */
  double start, elapsed;
  int64_t last_steps;
  double last_time;
  int drawn;
  double t0, t_end; /* simulated time at the start (or resumption) and at the end, s */
  /* the wall and simulated times of the start and of the last frames completed (a ring of
     MPM_PROGRESS_WINDOW + 1): the rate of the recent frames, their outputs included */
  double mark_wall[MPM_PROGRESS_WINDOW + 1], mark_sim[MPM_PROGRESS_WINDOW + 1];
  int marks;
} mpm_progress;

void mpm_progress_begin(mpm_progress *p, mpm_progress_mode mode, int frames, size_t particles);
/* extra: appended to the line (the implicit solver's figures), or NULL. */
void mpm_progress_update(mpm_progress *p, int frame, double sim_time, int64_t steps,
                         size_t particles, const char *extra);
/* After a step inside a frame: redraws (or prints a line) when enough wall time has passed. */
void mpm_progress_step(mpm_progress *p, int frame, double sim_time, int64_t steps,
                       size_t particles);
void mpm_progress_end(mpm_progress *p);
/* The time left as a duration: "12 s", "3 min 05 s", "1 h 02 min", "--" when unknown. */
void mpm_format_duration(double seconds, char *buf, size_t n);

#endif
