/* error.c - status codes and messages. */
#include "core/error.h"

#include <stdarg.h>
#include <stdio.h>

/* The message from fmt and ap, the status, and whether the failure was another process's. */
static void set(mpm_error *err, mpm_status status, int elsewhere, const char *fmt, va_list ap) {
  vsnprintf(err->message, sizeof err->message, fmt, ap);
  err->status = status;
  err->elsewhere = elsewhere;
}

mpm_status mpm_error_set(mpm_error *err, mpm_status status, const char *fmt, ...) {
  if (err) {
    va_list ap;
    va_start(ap, fmt);
    set(err, status, 0, fmt, ap);
    va_end(ap);
  }
  return status;
}

mpm_status mpm_error_set_elsewhere(mpm_error *err, mpm_status status, const char *fmt, ...) {
  if (err) {
    va_list ap;
    va_start(ap, fmt);
    set(err, status, 1, fmt, ap);
    va_end(ap);
  }
  return status;
}

void mpm_error_clear(mpm_error *err) {
  if (err) {
    err->status = MPM_OK;
    err->message[0] = '\0';
    err->elsewhere = 0;
  }
}

const char *mpm_status_string(mpm_status s) {
  switch (s) {
  case MPM_OK:
    return "ok";
  case MPM_ERR_IO:
    return "i/o error";
  case MPM_ERR_PARSE:
    return "parse error";
  case MPM_ERR_INVALID:
    return "invalid input";
  case MPM_ERR_NOMEM:
    return "out of memory";
  case MPM_ERR_UNSTABLE:
    return "simulation unstable";
  case MPM_ERR_INTERRUPTED:
    return "interrupted";
  case MPM_ERR_EXTERNAL:
    return "external program failed";
  }
  return "unknown status";
}
