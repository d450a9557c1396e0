/* run_folder.h - an output folder holds one run: the names of the files a run writes, a lock
 * held while a simulation writes into the folder, and the removal of a run's files before a new
 * run overwrites it.
 *
 * Three rules keep a user's files safe (docs/scene-format.md, "Output folder"):
 *   - Only the files a run writes are ever removed, recognised by their exact names
 *     (frame_0001.vtu, checkpoint_000000000120.h5, stats.csv, ...; mpm_run_file_kind). Never a
 *     folder, a symbolic link or anything else that is not a regular file, never an input of
 *     the run (its scene file, its meshes), and nothing is removed until every candidate has
 *     been checked.
 *   - One simulation writes into a folder at a time: an advisory lock (flock) on the folder's
 *     lock file, taken before the folder is looked at and held until the simulation is
 *     destroyed, refuses a second one, in this process or another.
 *   - Temporaries of the atomic writers (.NAME.tmp.PID) left by a killed run are removed by the
 *     next run that holds the lock (a resume or an overwrite): while it holds it, no other
 *     writer can own one. */
#ifndef MPM_IO_RUN_FOLDER_H
#define MPM_IO_RUN_FOLDER_H

#include "core/error.h"

#include <stddef.h>

/* The lock file's name inside the output folder (kept after the run: removing a lock file
 * lets two later runs lock two different files). */
#define MPM_RUN_LOCK_NAME ".mpm.lock"

typedef enum mpm_run_file_kind {
  MPM_RUN_FILE_NONE = 0, /* not a file a run writes */
  MPM_RUN_FILE = 1,      /* a run's output: frames, meshes, checkpoints, stats, indexes */
  MPM_RUN_FILE_TEMP = 2, /* an atomic writer's temporary of such a file */
} mpm_run_file_kind;

/* What the name (no folder) is, by the exact patterns of the run's writers. */
mpm_run_file_kind mpm_run_file_kind_of(const char *name);

/* Take the folder's lock (creating the lock file; the folder must exist). On success *fd is
 * the lock's descriptor (close it to release). MPM_ERR_IO naming the folder and the process
 * that holds it when another simulation writes there. */
mpm_status mpm_run_folder_lock(const char *dir, int *fd, mpm_error *err);

/* Release a lock from mpm_run_folder_lock (fd < 0: nothing). */
void mpm_run_folder_unlock(int fd);

/* How mpm_run_folder_claim treats a folder that holds a run's files. */
typedef enum mpm_run_claim {
  MPM_RUN_CLAIM_NEW = 0,       /* refuse it, naming some of the files */
  MPM_RUN_CLAIM_OVERWRITE = 1, /* remove them (all checked first) */
  MPM_RUN_CLAIM_RESUME = 2,    /* keep them; remove only stale temporaries */
} mpm_run_claim;

/* Make the folder ready for a run that holds its lock. `keep` lists `keep_count` paths (the
 * run's inputs: scene file, meshes; NULL entries skipped) that are never removed nor counted,
 * whatever their names. NEW: MPM_ERR_INVALID when the folder holds a run's files or
 * temporaries. OVERWRITE: every run file and temporary is removed, after all were checked;
 * MPM_ERR_IO, removing nothing, when one of them is not a regular file (a folder, a link) or
 * cannot be removed. RESUME: stale temporaries removed. A missing folder is fine. */
mpm_status mpm_run_folder_claim(const char *dir, mpm_run_claim how, const char *const *keep,
                                int keep_count, mpm_error *err);

/* 1 when the two paths name the same existing file (the same device and inode). */
int mpm_same_file(const char *a, const char *b);

#endif
