/* gnuplot.c - gnuplot found on PATH and run for the plots (gnuplot.h): fork and execv with its
 * output collected through a pipe, so that a library caller's terminal sees none of it. */
#define _XOPEN_SOURCE 700 /* fork, execv, realpath */

#include "plot/gnuplot.h"
#include "core/alloc.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

int mpm_gnuplot_find(const char *name, char *out, size_t size) {
  const char *path = getenv("PATH");
  if (!path) path = "/usr/local/bin:/usr/bin:/bin";
  for (const char *p = path;;) {
    const char *colon = strchr(p, ':');
    const int len = colon ? (int)(colon - p) : (int)strlen(p);
    char candidate[4096];
    const int n = snprintf(candidate, sizeof candidate, "%.*s%s%s", len, p, len ? "/" : "./", name);
    struct stat st;
    if (n > 0 && (size_t)n < sizeof candidate && stat(candidate, &st) == 0 && S_ISREG(st.st_mode) &&
        access(candidate, X_OK) == 0) {
      /* made absolute (gnuplot runs in the plots directory), symbolic links kept */
      char cwd[4096];
      const int m = candidate[0] == '/'       ? snprintf(out, size, "%s", candidate)
                    : getcwd(cwd, sizeof cwd) ? snprintf(out, size, "%s/%s", cwd, candidate)
                                              : -1;
      if (m > 0 && (size_t)m < size) return 1;
    }
    if (!colon) return 0;
    p = colon + 1;
  }
}

/* gnuplot's messages are kept (the first GP_MESSAGES_MAX bytes) and shown only when it fails:
 * on success they are warnings about data (an empty range of a single frame) that would only
 * be noise. */
#define GP_MESSAGES_MAX (64 * 1024)

mpm_status mpm_gnuplot_run(const char *gnuplot, const char *dir, const char *script, char *what,
                           size_t cap, char **messages) {
  *messages = NULL;
  char *kept_text = mpm_alloc(GP_MESSAGES_MAX + 64);
  if (!kept_text) {
    snprintf(what, cap, "cannot start %s: out of memory", gnuplot);
    return MPM_ERR_EXTERNAL;
  }
  int fds[2];
  if (pipe(fds) != 0) {
    snprintf(what, cap, "cannot start %s: pipe: %s", gnuplot, strerror(errno));
    mpm_free(kept_text);
    return MPM_ERR_EXTERNAL;
  }
  /* what the caller's buffers hold goes out before gnuplot's, not twice */
  fflush(stdout);
  fflush(stderr);
  const pid_t pid = fork();
  if (pid < 0) {
    snprintf(what, cap, "cannot start %s: %s", gnuplot, strerror(errno));
    close(fds[0]);
    close(fds[1]);
    mpm_free(kept_text);
    return MPM_ERR_EXTERNAL;
  }
  if (pid == 0) {
    const int null_fd = open("/dev/null", O_RDONLY);
    if (null_fd >= 0) {
      dup2(null_fd, STDIN_FILENO);
      close(null_fd);
    }
    dup2(fds[1], STDOUT_FILENO);
    dup2(fds[1], STDERR_FILENO);
    close(fds[0]);
    close(fds[1]);
    if (chdir(dir) != 0) {
      fprintf(stderr, "cannot enter '%s': %s\n", dir, strerror(errno));
      _exit(127);
    }
    char *const args[] = {(char *)"gnuplot", (char *)script, NULL};
    execv(gnuplot, args);
    fprintf(stderr, "cannot run %s: %s\n", gnuplot, strerror(errno));
    _exit(127);
  }
  close(fds[1]);
  size_t kept = 0;
  int truncated = 0;
  for (;;) {
    char chunk[4096];
    const ssize_t n = read(fds[0], chunk, sizeof chunk);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    const size_t room = GP_MESSAGES_MAX - kept, take = (size_t)n < room ? (size_t)n : room;
    memcpy(kept_text + kept, chunk, take);
    kept += take;
    truncated |= take < (size_t)n;
  }
  close(fds[0]);
  kept_text[kept] = '\0';
  if (truncated) strcat(kept_text, "\n[... more gnuplot messages left out]\n");
  int status = 0;
  while (waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) {
      snprintf(what, cap, "waiting for gnuplot: %s", strerror(errno));
      *messages = kept_text;
      return MPM_ERR_EXTERNAL;
    }
  }
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) {
    mpm_free(kept_text);
    return MPM_OK;
  }
  if (WIFEXITED(status))
    snprintf(what, cap, "gnuplot failed (exit status %d)", WEXITSTATUS(status));
  else
    snprintf(what, cap, "gnuplot was killed by signal %d",
             WIFSIGNALED(status) ? WTERMSIG(status) : 0);
  *messages = kept_text;
  return MPM_ERR_EXTERNAL;
}
