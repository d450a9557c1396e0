/* error.h - status codes and the error message that travels with them.
 *
 * Library code never exits: a function that can fail returns an mpm_status and writes a
 * message naming the file, key path, step or particle concerned into an mpm_error. Internal
 * functions that take no mpm_error return the status alone (MPM_OK, or MPM_ERR_NOMEM when out of
 * memory, MPM_ERR_INVALID and the like), and their caller writes the message; failures are
 * positive, so callers test `!= MPM_OK`, never `< 0`. */
#ifndef MPM_CORE_ERROR_H
#define MPM_CORE_ERROR_H

#include "mpm/mpm.h"

typedef struct mpm_error {
  mpm_status status;
  char message[1024];
  /* the failure is another process's of a distributed run, which this message only points at
     (its own names the cause); 0 after every mpm_error_set */
  int elsewhere;
} mpm_error;

/* Set err (if non-NULL) to status and a printf-style message; returns status. */
mpm_status mpm_error_set(mpm_error *err, mpm_status status, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
/* The same for a failure that is another process's (elsewhere set): the message points at it. */
mpm_status mpm_error_set_elsewhere(mpm_error *err, mpm_status status, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
void mpm_error_clear(mpm_error *err);

#endif
