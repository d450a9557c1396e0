/* atomic_file.c - crash-safe file replacement and mkdir -p for the frame writers.
 *
 * A writer creates `dir/.name.tmp.<pid>` next to the final path (a new file: O_EXCL and
 * O_NOFOLLOW, so that a file or link planted at that predictable name is never opened; another
 * name is tried), writes everything there, and commits: the stream is flushed and closed with every
 * step checked (ENOSPC, EFBIG, EIO show up at flush or close time with buffered stdio), and only
 * then is the temporary renamed over the final path. rename() within one directory is atomic on
 * POSIX file systems, so a reader (ParaView polling a directory) sees either the old complete file
 * or the new complete file, never a truncated one. On any failure the temporary is removed and the
 * old file is left as it was. No fsync: this protects against crashes of the program, not of the
 * machine. */
#define _POSIX_C_SOURCE 200809L

#include "io/io.h"

#include <errno.h>
#include <fcntl.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

/* Size of the stdio buffer of a frame file: frames are megabytes, written sequentially. */
#define ATOMIC_BUFFER_BYTES (1 << 16)

/* Retries after a name clash (a stale temporary of an earlier process with our pid, or a name
 * planted there): `.name.tmp.PID`, then `.name.tmp.PID.1`, ... */
#define TEMP_TRIES 100

int mpm_temp_create(const char *path, char *temp, size_t cap, mpm_error *err) {
  /* same directory as the final path, so that rename() never crosses file systems */
  const char *slash = strrchr(path, '/');
  const int dir_len = slash ? (int)(slash - path + 1) : 0;
  const char *base = slash ? slash + 1 : path;
  for (int k = 0; k < TEMP_TRIES; ++k) {
    const int n =
        k ? snprintf(temp, cap, "%.*s.%s.tmp.%ld.%d", dir_len, path, base, (long)getpid(), k)
          : snprintf(temp, cap, "%.*s.%s.tmp.%ld", dir_len, path, base, (long)getpid());
    if (n < 0 || (size_t)n >= cap) {
      mpm_error_set(err, MPM_ERR_IO, "cannot write '%s': path too long", path);
      break;
    }
    /* a new file or nothing: O_EXCL never opens what is there, O_NOFOLLOW never a link's
       target (O_EXCL alone already refuses a link; both say so) */
    const int fd = open(temp, O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0666);
    if (fd >= 0) return fd;
    if (errno != EEXIST) {
      mpm_error_set(err, MPM_ERR_IO, "cannot create '%s' (temporary for '%s'): %s", temp, path,
                    strerror(errno));
      break;
    }
    if (k + 1 == TEMP_TRIES)
      mpm_error_set(err, MPM_ERR_IO,
                    "cannot create a temporary for '%s': %d names beside it are taken (%s)", path,
                    TEMP_TRIES, temp);
  }
  temp[0] = '\0';
  return -1;
}

mpm_status mpm_atomic_open(mpm_atomic_file *f, const char *path, mpm_error *err) {
  memset(f, 0, sizeof *f);
  if (!path || !path[0])
    return mpm_error_set(err, MPM_ERR_IO, "cannot write a file with an empty path");
  const size_t len = strlen(path);
  if (len >= sizeof f->final_path || path[len - 1] == '/')
    return mpm_error_set(err, MPM_ERR_IO, "cannot write '%s': %s", path,
                         len >= sizeof f->final_path ? "path too long" : "path names a directory");
  memcpy(f->final_path, path, len + 1);

  const int fd = mpm_temp_create(path, f->temp_path, sizeof f->temp_path, err);
  if (fd < 0) {
    f->temp_path[0] = '\0'; /* nothing was created: abort must not remove anything */
    return MPM_ERR_IO;
  }
  f->fp = fdopen(fd, "wb");
  if (!f->fp) {
    const int e = errno;
    close(fd);
    remove(f->temp_path);
    f->temp_path[0] = '\0';
    return mpm_error_set(err, MPM_ERR_NOMEM, "cannot write '%s': %s", path, strerror(e));
  }
  setvbuf(f->fp, NULL, _IOFBF, ATOMIC_BUFFER_BYTES);
  return MPM_OK;
}

/* Remove the temporary and report `what` failed with errno value e. */
static mpm_status commit_fail(mpm_atomic_file *f, const char *what, int e, mpm_error *err) {
  if (f->temp_path[0]) remove(f->temp_path);
  f->temp_path[0] = '\0';
  return mpm_error_set(err, MPM_ERR_IO, "cannot write '%s': %s failed: %s", f->final_path, what,
                       strerror(e));
}

mpm_status mpm_atomic_commit(mpm_atomic_file *f, mpm_error *err) {
  if (!f->fp)
    return mpm_error_set(err, MPM_ERR_IO, "cannot write '%s': file is not open", f->final_path);
  FILE *fp = f->fp;
  f->fp = NULL;
  /* an earlier fwrite failed: its data may be gone from the buffer even if a retry succeeds */
  const int had_error = ferror(fp);
  errno = 0;
  const int flush_failed = fflush(fp) != 0;
  const int flush_errno = errno;
  errno = 0;
  const int close_failed = fclose(fp) != 0;
  const int close_errno = errno;
  if (flush_failed) return commit_fail(f, "flush", flush_errno ? flush_errno : EIO, err);
  if (had_error) return commit_fail(f, "write", EIO, err);
  if (close_failed) return commit_fail(f, "close", close_errno ? close_errno : EIO, err);
  if (rename(f->temp_path, f->final_path) != 0) return commit_fail(f, "rename", errno, err);
  f->temp_path[0] = '\0';
  return MPM_OK;
}

void mpm_atomic_abort(mpm_atomic_file *f) {
  if (f->fp) fclose(f->fp);
  f->fp = NULL;
  if (f->temp_path[0]) remove(f->temp_path);
  f->temp_path[0] = '\0';
}

/* Create one directory level; EEXIST is fine when the existing thing is a directory. */
static mpm_status make_one(const char *full, const char *prefix, mpm_error *err) {
  if (mkdir(prefix, 0777) == 0) return MPM_OK;
  const int e = errno;
  struct stat st;
  if (stat(prefix, &st) == 0) {
    if (S_ISDIR(st.st_mode)) return MPM_OK;
    return mpm_error_set(err, MPM_ERR_IO,
                         "cannot create directory '%s': '%s' exists and is not a directory", full,
                         prefix);
  }
  return mpm_error_set(err, MPM_ERR_IO, "cannot create directory '%s': at '%s': %s", full, prefix,
                       strerror(e));
}

mpm_status mpm_make_dirs(const char *path, mpm_error *err) {
  if (!path || !path[0])
    return mpm_error_set(err, MPM_ERR_IO, "cannot create a directory with an empty path");
  char buf[1024];
  const size_t len = strlen(path);
  if (len >= sizeof buf)
    return mpm_error_set(err, MPM_ERR_IO, "cannot create directory '%s': path too long", path);
  memcpy(buf, path, len + 1);
  /* every prefix ending before a '/' (skipping the root and repeated slashes), then the whole */
  for (size_t i = 1; i < len; ++i) {
    if (buf[i] != '/' || buf[i - 1] == '/') continue;
    buf[i] = '\0';
    const mpm_status s = make_one(path, buf, err);
    buf[i] = '/';
    if (s != MPM_OK) return s;
  }
  return make_one(path, buf, err);
}
