/* staging.c - a set of files moved into a folder together, after every name was checked
 * (staging.h). Every look and move goes through descriptors of the two folders, so a folder
 * renamed or a link planted meanwhile cannot redirect a move. */
#define _GNU_SOURCE /* O_DIRECTORY, O_CLOEXEC, mkdtemp */

#include "io/staging.h"
#include "core/alloc.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

mpm_status mpm_staging_open(const char *dir, char *staging, size_t cap, mpm_error *err) {
  if ((size_t)snprintf(staging, cap, "%s/.mpm-stage.XXXXXX", dir) >= cap)
    return mpm_error_set(err, MPM_ERR_INVALID, "%s: path too long", dir);
  if (!mkdtemp(staging)) /* mkdir: made new, never through a link */
    return mpm_error_set(err, MPM_ERR_IO, "%s: cannot make a staging folder there: %s", dir,
                         strerror(errno));
  return MPM_OK;
}

static int by_name(const void *a, const void *b) {
  return strcmp(*(char *const *)a, *(char *const *)b);
}

/* The names of the regular files in the folder open at fd (no dot files: an atomic writer's
 * temporary that outlived its writer), sorted; *count of them. NULL on failure. */
static char **list_files(int fd, size_t *count) {
  const int again = dup(fd);
  DIR *d = again >= 0 ? fdopendir(again) : NULL;
  if (!d) {
    if (again >= 0) close(again);
    return NULL;
  }
  size_t n = 0, cap = 16;
  char **names = mpm_alloc(cap * sizeof *names);
  struct dirent *e;
  while (names && (e = readdir(d))) {
    struct stat st;
    if (e->d_name[0] == '.' || fstatat(fd, e->d_name, &st, AT_SYMLINK_NOFOLLOW) != 0 ||
        !S_ISREG(st.st_mode))
      continue;
    if (n == cap) {
      char **more = mpm_realloc(names, 2 * cap * sizeof *names);
      if (!more) break;
      names = more;
      cap *= 2;
    }
    if (!(names[n] = mpm_strdup(e->d_name))) break;
    ++n;
  }
  const int failed = !names || e != NULL;
  closedir(d);
  if (failed) {
    for (size_t i = 0; names && i < n; ++i) mpm_free(names[i]);
    mpm_free(names);
    return NULL;
  }
  qsort(names, n, sizeof *names, by_name);
  *count = n;
  return names;
}

mpm_status mpm_staging_publish(const char *staging, const char *dir, int replace, char *names,
                               size_t cap, mpm_error *err) {
  if (names && cap) names[0] = 0;
  const int from = open(staging, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  const int to = open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  size_t n = 0;
  char **files = from >= 0 && to >= 0 ? list_files(from, &n) : NULL;
  mpm_status st = MPM_OK;
  if (from < 0 || to < 0 || !files) {
    st = mpm_error_set(err, MPM_ERR_IO, "%s: cannot read the folder: %s",
                       from < 0 || !files ? staging : dir, strerror(errno));
    goto done;
  }
  /* every name checked before any moves */
  char clash[512] = "";
  int clashes = 0;
  for (size_t i = 0; i < n; ++i) {
    struct stat old;
    if (fstatat(to, files[i], &old, AT_SYMLINK_NOFOLLOW) != 0) continue; /* a new name */
    if (replace && S_ISREG(old.st_mode)) continue;
    if (replace) {
      st = mpm_error_set(err, MPM_ERR_IO,
                         "%s/%s is not a regular file (a folder or a link): nothing was written, "
                         "nothing replaced",
                         dir, files[i]);
      goto done;
    }
    const size_t len = strlen(clash);
    if (clashes++ < 4) snprintf(clash + len, sizeof clash - len, "%s%s", len ? ", " : "", files[i]);
  }
  if (clashes) {
    st = mpm_error_set(err, MPM_ERR_INVALID,
                       "%s already holds %d of the frame's files (%s%s); nothing was written "
                       "(ask to overwrite them, or choose another folder)",
                       dir, clashes, clash, clashes > 4 ? ", ..." : "");
    goto done;
  }
  size_t used = 0;
  for (size_t i = 0; i < n; ++i) {
    /* a link refuses an existing name however it came there: without replace nothing is lost */
    const int moved =
        replace ? renameat(from, files[i], to, files[i]) : linkat(from, files[i], to, files[i], 0);
    if (moved != 0) {
      st = mpm_error_set(err, MPM_ERR_IO, "%s/%s: cannot write it: %s%s", dir, files[i],
                         strerror(errno),
                         i ? " (the files before it in name order were written)" : "");
      goto done;
    }
    if (!replace) unlinkat(from, files[i], 0);
    if (names && used < cap) {
      snprintf(names + used, cap - used, "%s\n", files[i]);
      used += strlen(names + used);
    }
  }
  if (rmdir(staging) != 0)
    st = mpm_error_set(err, MPM_ERR_IO, "%s: cannot remove it: %s", staging, strerror(errno));
done:
  for (size_t i = 0; files && i < n; ++i) mpm_free(files[i]);
  mpm_free(files);
  if (from >= 0) close(from);
  if (to >= 0) close(to);
  return st;
}

void mpm_staging_discard(const char *staging) {
  const int fd = open(staging, O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
  if (fd < 0) return;
  const int again = dup(fd);
  DIR *d = again >= 0 ? fdopendir(again) : NULL;
  if (!d && again >= 0) close(again);
  for (struct dirent *e; d && (e = readdir(d));) {
    struct stat st;
    if (fstatat(fd, e->d_name, &st, AT_SYMLINK_NOFOLLOW) == 0 && S_ISREG(st.st_mode))
      unlinkat(fd, e->d_name, 0);
  }
  if (d) closedir(d);
  close(fd);
  rmdir(staging);
}
