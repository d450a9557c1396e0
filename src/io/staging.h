/* staging.h - files that reach a folder together or not at all: written first into a private
 * staging folder inside it, then moved in by name, after every name was checked.
 *
 * A one-off frame (mpm_sim_write_frame_to) writes a set of files whose names only the writers
 * know (the scene's output keys choose them). Writing them straight into a user's folder would
 * find a clash only at the file that clashes, with the earlier ones already there; staged, the
 * names are the files actually written, every one is checked against the folder before any
 * moves, and without `replace` none is replaced even by a file that appears meanwhile (each
 * move is a link, which refuses an existing name, then an unlink). */
#ifndef MPM_IO_STAGING_H
#define MPM_IO_STAGING_H

#include "core/error.h"

#include <stddef.h>

/* Make a fresh staging folder inside `dir` (which must exist): dir/.mpm-stage.XXXXXX, mode
 * 0700, its path into staging (cap bytes). MPM_ERR_IO naming dir when it cannot be made. */
mpm_status mpm_staging_open(const char *dir, char *staging, size_t cap, mpm_error *err);

/* Move every file of `staging` into `dir` under its name, in name order, and remove the
 * staging folder. Before anything moves, each name is looked up in dir: without `replace` any
 * existing entry refuses the whole (MPM_ERR_INVALID naming the entries); with it, an entry
 * that is not a regular file (a folder, a symbolic link) refuses it (MPM_ERR_IO). The names
 * moved are written to `names` (cap bytes, may be NULL), one per line. On failure the staging
 * folder is left for mpm_staging_discard. */
mpm_status mpm_staging_publish(const char *staging, const char *dir, int replace, char *names,
                               size_t cap, mpm_error *err);

/* Remove a staging folder and the regular files in it (nothing else: a staging folder holds
 * only what the writers put there). Missing: nothing to do. */
void mpm_staging_discard(const char *staging);

#endif
