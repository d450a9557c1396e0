/* input_file.c - opening a run's input files as regular files only (input_file.h). */
#define _POSIX_C_SOURCE 200809L

#include "io/input_file.h"

#include <errno.h>
#include <fcntl.h>
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
