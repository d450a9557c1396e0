/* progress.h - progress display of `mpm run`: a redrawn bar on a terminal, one plain line per
 * frame otherwise, nothing with --quiet. */
#ifndef MPM_APP_PROGRESS_H
#define MPM_APP_PROGRESS_H

#include <stddef.h>
#include <stdint.h>

typedef enum { MPM_PROGRESS_QUIET, MPM_PROGRESS_LINES, MPM_PROGRESS_BAR } mpm_progress_mode;

typedef struct mpm_progress {
  mpm_progress_mode mode;
  int frames;
  int first_frame;     /* frame the run started (or resumed) from */
  int64_t first_steps; /* steps taken before it */
  double start, elapsed;
  int64_t last_steps;
  double last_time;
  int drawn;
} mpm_progress;

void mpm_progress_begin(mpm_progress *p, mpm_progress_mode mode, int frames, size_t particles);
/* extra: appended to the line (the implicit solver's figures), or NULL. */
void mpm_progress_update(mpm_progress *p, int frame, double sim_time, int64_t steps,
                         size_t particles, const char *extra);
void mpm_progress_end(mpm_progress *p);

#endif
