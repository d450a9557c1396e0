/* input_file.h - opening the files a run reads (scene, meshes, checkpoints, frames, stats) as
 * regular files only.
 *
 * A FIFO given as a scene or a mesh would block fopen forever, and a folder or a device reads
 * as garbage or fails late. The file is opened with O_NONBLOCK (so that the open itself never
 * waits for a writer), then checked with fstat on the descriptor it opened (no
 * check-then-open race), and handed back as a blocking stream. */
#ifndef MPM_IO_INPUT_FILE_H
#define MPM_IO_INPUT_FILE_H

#include "mpm/mpm.h"

#include <stdint.h>
#include <stdio.h>

/* Open `path` for reading. NULL when it cannot be opened or is not a regular file, with the
 * reason in `why` (cap bytes): strerror's text, or "it is a FIFO (named pipe), not a regular
 * file" and the like. *size (may be NULL) gets the file's size in bytes. */
FILE *mpm_open_input(const char *path, long long *size, char *why, size_t cap);

/* A digest of the file's bytes (64 bits; a changed file changes it, for checkpoints that must
 * resume with the inputs they were made from). MPM_OK; MPM_ERR_IO when the file cannot be read,
 * MPM_ERR_NOMEM when out of memory, with the reason in `why`. */
mpm_status mpm_input_digest(const char *path, uint64_t *digest, char *why, size_t cap);

#endif
