/* input_file.c - opening a run's input files as regular files only (input_file.h). */
#define _POSIX_C_SOURCE 200809L

#include "io/input_file.h"
#include "core/alloc.h"
#include "core/hash.h"

#include <errno.h>
#include <fcntl.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static const char *kind_of(mode_t mode) {
  if (S_ISDIR(mode)) return "a folder";
  if (S_ISFIFO(mode)) return "a FIFO (named pipe)";
  if (S_ISSOCK(mode)) return "a socket";
  if (S_ISCHR(mode) || S_ISBLK(mode)) return "a device";
  return "not a file";
}

FILE *mpm_open_input(const char *path, long long *size, char *why, size_t cap) {
  if (size) *size = 0;
  const int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    snprintf(why, cap, "%s", strerror(errno));
    return NULL;
  }
  struct stat st;
  if (fstat(fd, &st) != 0) {
    snprintf(why, cap, "%s", strerror(errno));
    close(fd);
    return NULL;
  }
  if (!S_ISREG(st.st_mode)) {
    snprintf(why, cap, "it is %s, not a regular file", kind_of(st.st_mode));
    close(fd);
    return NULL;
  }
  /* reads of a regular file never wait; the flag is cleared all the same, for stdio */
  const int flags = fcntl(fd, F_GETFL);
  if (flags >= 0) (void)fcntl(fd, F_SETFL, flags & ~O_NONBLOCK);
  FILE *f = fdopen(fd, "rb");
  if (!f) {
    snprintf(why, cap, "%s", strerror(errno));
    close(fd);
    return NULL;
  }
  if (size) *size = (long long)st.st_size;
  return f;
}

mpm_status mpm_input_digest(const char *path, uint64_t *digest, char *why, size_t cap) {
  *digest = 0;
  FILE *f = mpm_open_input(path, NULL, why, cap);
  if (!f) return MPM_ERR_IO;
  enum { PIECE = 1 << 16 };
  unsigned char *buf = mpm_alloc(PIECE);
  if (!buf) {
    fclose(f);
    snprintf(why, cap, "out of memory");
    return MPM_ERR_NOMEM;
  }
  /* pieces of a fixed size (fread fills each from a regular file), so the same bytes always
     give the same digest */
  uint64_t h = 0x6d706d696e707574ull;
  size_t n;
  while ((n = fread(buf, 1, PIECE, f)) > 0) h = mpm_hash64_words(buf, n, h);
  const int failed = ferror(f);
  mpm_free(buf);
  fclose(f);
  if (failed) {
    snprintf(why, cap, "read error");
    return MPM_ERR_IO;
  }
  *digest = h;
  return MPM_OK;
}
