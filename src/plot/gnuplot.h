/* gnuplot.h - running gnuplot for the plots (plot.c): found on PATH as execvp would search it,
 * and run on a script in a folder with its messages collected, shown only when it fails. */
#ifndef MPM_PLOT_GNUPLOT_H
#define MPM_PLOT_GNUPLOT_H

#include "mpm/mpm.h"

#include <stddef.h>

/* The absolute path of `name` found on PATH into out (of size bytes); 0 when it is not there. */
int mpm_gnuplot_find(const char *name, char *out, size_t size);

/* Run `GNUPLOT SCRIPT` in `dir`, stdin from /dev/null, stdout and stderr collected. MPM_OK when
 * it exits with 0; else MPM_ERR_EXTERNAL with what happened in `what` (of cap bytes: "gnuplot
 * failed (exit status 3)") and its messages in *messages (from mpm_alloc: mpm_free them;
 * NUL-terminated, the first 64 KiB and a note when there were more; NULL when none were
 * collected). */
mpm_status mpm_gnuplot_run(const char *gnuplot, const char *dir, const char *script, char *what,
                           size_t cap, char **messages);

#endif
