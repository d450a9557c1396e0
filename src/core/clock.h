/* clock.h - the wall clock the stage timings, the progress line and the solvers' figures read. */
#ifndef MPM_CORE_CLOCK_H
#define MPM_CORE_CLOCK_H

/* Seconds since an arbitrary start, monotonic. */
double mpm_wall_seconds(void);

#endif
