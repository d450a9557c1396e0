/* run_folder.c - an output folder holds one run (run_folder.h): the run's file names, the
 * folder's lock and the removal of an earlier run's files.
 *
 * The folder is opened once and every look and removal goes through that descriptor
 * (fstatat, unlinkat with AT_SYMLINK_NOFOLLOW semantics), so a folder renamed or a link
 * planted between the check and the removal cannot redirect a removal outside it. */
#define _GNU_SOURCE /* O_DIRECTORY, O_NOFOLLOW, O_CLOEXEC, fdopendir, flock */

#include "io/run_folder.h"
#include "core/alloc.h"

#include <ctype.h>
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

/* The names the writers make (sim_output.c, sim_surface.c, sim_checkpoint.c,
 * sim_scene_copy.c; a run on ranks: dist/mpi_frame_writer.c, its pieces frame_NNNN_pRRRR.*). In a
 * pattern '#' is a frame number (4 digits or more, as "%04d" prints it), '%' a body index (1 digit
 * or more), '@' the 12 digits of a checkpoint's step; every other character stands for itself. */
static const char *const run_patterns[] = {
    "frame_#.vtu",
    "frame_#.ply",
    "frames.pvd",
    "run.pvd",
    "frame_#.pvtu",
    "frame_#_p#.vtu",
    "frame_#_p#.ply",
    "stats.csv",
    "scene.json",
    "domains_#.vtu",
    "grid_cells.vtu",
    "grid_cells_#.vtu",
    "surface_body%_#.obj",
    "surface_body%_#.ply",
    "surface_body%_#.vtp",
    "surface_#.obj",
    "surface_#.ply",
    "surface_b%_#.obj",
    "surface_b%_#.ply",
    "levelset_#.vdb",
    "levelset_b%_#.vdb",
    "checkpoint_@.h5",
    "checkpoint_@.h5.damaged",
};

/* Digits at s: how many (0 when none). */
static size_t digits_at(const char *s) {
  size_t n = 0;
  while (isdigit((unsigned char)s[n])) ++n;
  return n;
}

/* Whether s, from its start, matches pattern p up to p's end; *used is how much of s it took. */
static int match_prefix(const char *s, const char *p, size_t *used) {
  const char *start = s;
  for (; *p; ++p) {
    if (*p == '#' || *p == '%' || *p == '@') {
      const size_t n = digits_at(s);
      if ((*p == '#' && n < 4) || (*p == '%' && n < 1) || (*p == '@' && n != 12)) return 0;
      s += n;
    } else if (*s++ != *p) {
      return 0;
    }
  }
  *used = (size_t)(s - start);
  return 1;
}

/* Whether `rest` is what follows a run file's name in a temporary's: ".tmp.PID", with a ".N"
 * for a retry after a name clash (atomic_file.c). */
static int is_temp_suffix(const char *rest) {
  if (strncmp(rest, ".tmp.", 5) != 0) return 0;
  rest += 5;
  if (!digits_at(rest)) return 0;
  for (; *rest; ++rest)
    if (!isdigit((unsigned char)*rest) && *rest != '.') return 0;
  return 1;
}

mpm_run_file_kind mpm_run_file_kind_of(const char *name) {
  for (size_t k = 0; k < sizeof run_patterns / sizeof run_patterns[0]; ++k) {
    size_t used = 0;
    if (match_prefix(name, run_patterns[k], &used) && name[used] == '\0') return MPM_RUN_FILE;
    if (name[0] == '.' && match_prefix(name + 1, run_patterns[k], &used) &&
        is_temp_suffix(name + 1 + used))
      return MPM_RUN_FILE_TEMP;
  }
  return MPM_RUN_FILE_NONE;
}

int mpm_same_file(const char *a, const char *b) {
  struct stat sa, sb;
  return a && b && stat(a, &sa) == 0 && stat(b, &sb) == 0 && sa.st_dev == sb.st_dev &&
         sa.st_ino == sb.st_ino;
}

/* ---------------------------------------------------------------- the lock */

mpm_status mpm_run_folder_lock(const char *dir, int *fd, mpm_error *err) {
  *fd = -1;
  char path[4200];
  if (snprintf(path, sizeof path, "%s/%s", dir, MPM_RUN_LOCK_NAME) >= (int)sizeof path)
    return mpm_error_set(err, MPM_ERR_IO, "%.64s...: path too long", dir);
  /* O_NOFOLLOW: a link planted at the lock's name is not followed; O_NONBLOCK: a FIFO there
     does not hang the open (fstat refuses it below) */
  const int f = open(path, O_RDWR | O_CREAT | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC, 0644);
  if (f < 0)
    return mpm_error_set(err, MPM_ERR_IO, "cannot lock the output folder %s: %s: %s", dir, path,
                         errno == ELOOP ? "a symbolic link stands at the lock file's name"
                                        : strerror(errno));
  struct stat st;
  if (fstat(f, &st) != 0 || !S_ISREG(st.st_mode)) {
    close(f);
    return mpm_error_set(err, MPM_ERR_IO,
                         "cannot lock the output folder %s: %s is not a regular file", dir, path);
  }
  if (flock(f, LOCK_EX | LOCK_NB) != 0) {
    const int e = errno;
    if (e == EWOULDBLOCK) {
      char text[32] = "";
      const ssize_t n = pread(f, text, sizeof text - 1, 0);
      text[n > 0 ? n : 0] = '\0';
      const long pid = strtol(text, NULL, 10);
      close(f);
      char who[64] = "another process";
      if (pid > 0) snprintf(who, sizeof who, "process %ld", pid);
      return mpm_error_set(err, MPM_ERR_IO,
                           "the output folder %s is in use: another simulation (%s) is writing "
                           "into it and holds %s; an output folder holds one run at a time",
                           dir, who, path);
    }
    /* a file system without flock (some network mounts): the run goes on unlocked */
    if (e != ENOLCK && e != EOPNOTSUPP && e != EINVAL) {
      close(f);
      return mpm_error_set(err, MPM_ERR_IO, "cannot lock the output folder %s: %s: %s", dir, path,
                           strerror(e));
    }
  }
  /* who holds it, for the message another run gets */
  char text[32];
  const int n = snprintf(text, sizeof text, "%ld\n", (long)getpid());
  if (ftruncate(f, 0) != 0 || pwrite(f, text, (size_t)n, 0) != n) {
    /* the lock holds without the note */
  }
  *fd = f;
  return MPM_OK;
}

void mpm_run_folder_unlock(int fd) {
  if (fd >= 0) close(fd); /* closing the last descriptor releases the flock */
}

/* ---------------------------------------------------------------- claiming the folder */

typedef struct found_list {
  char **names;
  int count, cap;
} found_list;

static int found_push(found_list *l, const char *name) {
  if (l->count == l->cap) {
    const int cap = l->cap ? 2 * l->cap : 16;
    char **bigger = mpm_realloc(l->names, (size_t)cap * sizeof *bigger);
    if (!bigger) return -1;
    l->names = bigger;
    l->cap = cap;
  }
  if (!(l->names[l->count] = mpm_strdup(name))) return -1;
  ++l->count;
  return 0;
}

static void found_free(found_list *l) {
  for (int i = 0; i < l->count; ++i) mpm_free(l->names[i]);
  mpm_free(l->names);
}

/* Whether the entry (by its own stat, links not followed) is one of the kept inputs: the same
 * file as an input, or the same link as one given through a link. */
static int is_kept(const struct stat *entry, const struct stat *keep, int keep_count) {
  for (int k = 0; k < keep_count; ++k)
    if (keep[k].st_ino && entry->st_dev == keep[k].st_dev && entry->st_ino == keep[k].st_ino)
      return 1;
  return 0;
}

mpm_status mpm_run_folder_claim(const char *dir, mpm_run_claim how, const char *const *keep,
                                int keep_count, mpm_error *err) {
  const int dfd = open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dfd < 0) {
    if (errno == ENOENT) return MPM_OK; /* a new folder */
    return mpm_error_set(err, MPM_ERR_IO, "cannot read the output folder %s: %s", dir,
                         strerror(errno));
  }
  /* the inputs, by what they name and, when given through a link, by the link itself */
  struct stat kept[2 * 64];
  int kept_count = 0;
  for (int k = 0; k < keep_count && kept_count + 2 <= (int)(sizeof kept / sizeof kept[0]); ++k) {
    if (!keep[k]) continue;
    struct stat s;
    if (stat(keep[k], &s) == 0) kept[kept_count++] = s;
    if (lstat(keep[k], &s) == 0) kept[kept_count++] = s;
  }
  const int listing = dup(dfd);
  DIR *d = listing >= 0 ? fdopendir(listing) : NULL;
  if (!d) {
    if (listing >= 0) close(listing);
    close(dfd);
    return mpm_error_set(err, MPM_ERR_IO, "cannot read the output folder %s: %s", dir,
                         strerror(errno));
  }
  found_list files = {0}; /* what the claim removes (or refuses) */
  const char *bad = NULL; /* the first that is not a regular file */
  char bad_name[256] = "";
  mpm_status st = MPM_OK;
  for (struct dirent *e = readdir(d); e; e = readdir(d)) {
    const mpm_run_file_kind kind = mpm_run_file_kind_of(e->d_name);
    if (kind == MPM_RUN_FILE_NONE || (how == MPM_RUN_CLAIM_RESUME && kind != MPM_RUN_FILE_TEMP))
      continue;
    struct stat s;
    if (fstatat(dfd, e->d_name, &s, AT_SYMLINK_NOFOLLOW) != 0) continue; /* gone meanwhile */
    if (is_kept(&s, kept, kept_count)) continue;
    if (!S_ISREG(s.st_mode)) {
      /* a resume leaves what it did not write alone; the others refuse it below */
      if (how == MPM_RUN_CLAIM_RESUME) continue;
      if (!bad) {
        snprintf(bad_name, sizeof bad_name, "%.255s", e->d_name);
        bad = S_ISDIR(s.st_mode)   ? "a folder"
              : S_ISLNK(s.st_mode) ? "a symbolic link"
                                   : "not a regular file";
      }
      continue;
    }
    if (found_push(&files, e->d_name)) {
      st = mpm_error_set(err, MPM_ERR_NOMEM, "out of memory listing the output folder %s", dir);
      break;
    }
  }
  closedir(d);
  if (st == MPM_OK && how == MPM_RUN_CLAIM_NEW && (files.count || bad)) {
    const int n = files.count;
    st = mpm_error_set(
        err, MPM_ERR_INVALID,
        "%s holds the files of a run (%s%s%s%s%s, %d in all); an output folder holds one run: "
        "resume that one, overwrite it, or write this one elsewhere",
        dir, n > 0 ? files.names[0] : bad_name, n > 1 ? ", " : "", n > 1 ? files.names[1] : "",
        n > 2 ? ", " : "", n > 2 ? files.names[2] : "", n + (bad != NULL));
  } else if (st == MPM_OK && how == MPM_RUN_CLAIM_OVERWRITE && bad) {
    st = mpm_error_set(err, MPM_ERR_IO,
                       "cannot overwrite the run in %s: %s/%s is %s, which a run never writes; "
                       "nothing was removed (move it away, or write this run elsewhere)",
                       dir, dir, bad_name, bad);
  } else if (st == MPM_OK && how != MPM_RUN_CLAIM_NEW && files.count &&
             faccessat(dfd, ".", W_OK | X_OK, AT_EACCESS) != 0) {
    st = mpm_error_set(err, MPM_ERR_IO,
                       "cannot remove the earlier run's files from %s (%s, %d in all): %s; "
                       "nothing was removed",
                       dir, files.names[0], files.count, strerror(errno));
  } else if (st == MPM_OK && how != MPM_RUN_CLAIM_NEW) {
    for (int i = 0; i < files.count && st == MPM_OK; ++i)
      if (unlinkat(dfd, files.names[i], 0) != 0 && errno != ENOENT)
        st = mpm_error_set(err, MPM_ERR_IO, "cannot remove %s/%s: %s", dir, files.names[i],
                           strerror(errno));
  }
  found_free(&files);
  close(dfd);
  return st;
}
