/* stats_read.c - reading `mpm run`'s stats.csv back (mpm/plot.h: mpm_stats_read; `mpm plot`):
 * the header must be one that mpm_write_stats_csv (stats_csv.c) wrote (today's, or an earlier
 * version's, with three force columns per collider after total_energy), every row must have its
 * fields, and every field must be a finite number. */
#define _XOPEN_SOURCE 700 /* getline */
#include "core/error.h"
#include "core/alloc.h"
#include "io/input_file.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Files of earlier versions end here: before the implicit integrator, before dynamic enrichment,
 * before the step range and the gravitational energy. */
enum {
  COL_LEGACY_COUNT = MPM_STATS_CG_ITERATIONS_MEAN,
  COL_SOLVER_COUNT = MPM_STATS_ENRICHED_PERCENT,
  COL_ENRICHED_COUNT = MPM_STATS_DT_MIN,
  COL_COUNT = MPM_STATS_COLUMNS
};

static const char *const column_names[COL_COUNT] = {"frame",
                                                    "time",
                                                    "steps",
                                                    "dt",
                                                    "kinetic_energy",
                                                    "elastic_energy",
                                                    "momentum_x",
                                                    "momentum_y",
                                                    "momentum_z",
                                                    "angular_momentum_x",
                                                    "angular_momentum_y",
                                                    "angular_momentum_z",
                                                    "mass",
                                                    "particles",
                                                    "wall_seconds",
                                                    "cg_iterations_mean",
                                                    "cg_iterations_max",
                                                    "cg_residual_max",
                                                    "newton_iterations_mean",
                                                    "cg_unconverged",
                                                    "enriched_percent",
                                                    "dt_min",
                                                    "dt_max",
                                                    "gravitational_energy",
                                                    "total_energy"};

const char *mpm_stats_column_name(mpm_stats_column column) {
  return (int)column >= 0 && (int)column < COL_COUNT ? column_names[column] : NULL;
}

void mpm_stats_free(mpm_stats_table *t) {
  if (!t) return;
  mpm_free(t->values);
  mpm_free(t->forces);
  mpm_free(t->path);
  memset(t, 0, sizeof *t);
}

/* Cut a line at its end-of-line characters. */
static void chomp(char *line) {
  size_t n = strlen(line);
  while (n > 0 && (line[n - 1] == '\n' || line[n - 1] == '\r')) line[--n] = '\0';
}

static int is_blank(const char *s) {
  for (; *s; ++s)
    if (*s != ' ' && *s != '\t') return 0;
  return 1;
}

/* Split `line` in place at commas into at most `max` fields; returns the number of fields
 * there are (which may exceed max: only the first max are stored). */
static int split_fields(char *line, char **fields, int max) {
  int n = 0;
  for (char *p = line;; ++p) {
    char *comma = strchr(p, ',');
    if (n < max) fields[n] = p;
    ++n;
    if (!comma) break;
    *comma = '\0';
    p = comma;
  }
  return n;
}

/* Most collider force columns read (3 per collider). */
#define COLLIDER_COLUMNS_MAX 3000

/* The header's columns: COL_COUNT, or COL_ENRICHED_COUNT, COL_SOLVER_COUNT or COL_LEGACY_COUNT
 * for a file of an earlier version (the columns it lacks read as 0); *extra: the collider
 * force columns after total_energy (collider<c>_fx, _fy, _fz for c = 0, 1, ...), 0 without
 * colliders or in an earlier file. */
static mpm_status check_header(const char *path, char *line, int *columns, int *extra,
                               mpm_error *err) {
  char *fields[COL_COUNT + COLLIDER_COLUMNS_MAX];
  const int n = split_fields(line, fields, COL_COUNT + COLLIDER_COLUMNS_MAX);
  *columns = n < COL_COUNT ? n : COL_COUNT;
  *extra = n > COL_COUNT ? n - COL_COUNT : 0;
  for (int c = 0; c < COL_COUNT && c < n; ++c)
    if (strcmp(fields[c], column_names[c]) != 0)
      return mpm_error_set(err, MPM_ERR_PARSE,
                           "%s: line 1: not an mpm stats header: column %d is '%.60s', expected "
                           "'%s'",
                           path, c + 1, fields[c], column_names[c]);
  if (*extra > COLLIDER_COLUMNS_MAX || *extra % 3)
    return mpm_error_set(err, MPM_ERR_PARSE,
                         "%s: line 1: not an mpm stats header: %d columns after total_energy, "
                         "expected three per collider (at most %d)",
                         path, *extra, COLLIDER_COLUMNS_MAX);
  for (int k = 0; k < *extra; ++k) {
    char want[48];
    snprintf(want, sizeof want, "collider%d_f%c", k / 3, "xyz"[k % 3]);
    if (strcmp(fields[COL_COUNT + k], want) != 0)
      return mpm_error_set(err, MPM_ERR_PARSE,
                           "%s: line 1: not an mpm stats header: column %d is '%.60s', expected "
                           "'%s'",
                           path, COL_COUNT + k + 1, fields[COL_COUNT + k], want);
  }
  if (n < COL_COUNT && n != COL_ENRICHED_COUNT && n != COL_SOLVER_COUNT && n != COL_LEGACY_COUNT)
    return mpm_error_set(err, MPM_ERR_PARSE,
                         "%s: line 1: not an mpm stats header: %d columns, expected %d (frame, "
                         "time, ..., total_energy), %d (frame, time, ..., enriched_percent), %d "
                         "(frame, time, ..., cg_unconverged) or %d (frame, time, ..., "
                         "wall_seconds)",
                         path, n, COL_COUNT, COL_ENRICHED_COUNT, COL_SOLVER_COUNT,
                         COL_LEGACY_COUNT);
  return MPM_OK;
}

static mpm_status parse_row(const char *path, long line_no, char *line, int columns, int extra,
                            double *row, double *forces, mpm_error *err) {
  char *fields[COL_COUNT + COLLIDER_COLUMNS_MAX];
  const int n = split_fields(line, fields, COL_COUNT + COLLIDER_COLUMNS_MAX);
  for (int c = columns; c < COL_COUNT; ++c) row[c] = 0;
  if (n != columns + extra)
    return mpm_error_set(err, MPM_ERR_PARSE, "%s: line %ld: %d fields, expected %d", path, line_no,
                         n, columns + extra);
  for (int c = 0; c < columns + extra; ++c) {
    const char *s = fields[c];
    char *end;
    errno = 0;
    const double v = strtod(s, &end);
    const int parsed = end != s && is_blank(end);
    if (!parsed || !isfinite(v))
      return mpm_error_set(err, MPM_ERR_PARSE, "%s: line %ld: field %d (%s) is %s: '%.60s'", path,
                           line_no, c + 1, c < COL_COUNT ? column_names[c] : "a collider force",
                           parsed ? "not a finite number" : "not a number", s);
    if (c < columns)
      row[c] = v;
    else
      forces[c - columns] = v;
  }
  return MPM_OK;
}

/* Read and check the whole file; blank lines are skipped. */
static mpm_status read_table(const char *path, mpm_stats_table *t, mpm_error *err) {
  t->stride = COL_COUNT;
  if (!(t->path = mpm_strdup(path)))
    return mpm_error_set(err, MPM_ERR_NOMEM, "%s: out of memory", path);
  char why[128];
  FILE *f = mpm_open_input(path, NULL, why, sizeof why);
  if (!f)
    return mpm_error_set(err, MPM_ERR_IO,
                         "cannot open '%s': %s (is this the output directory "
                         "of 'mpm run'?)",
                         path, why);
  char *line = NULL;
  size_t cap = 0, capacity = 0;
  long line_no = 0;
  int columns = COL_COUNT, extra = 0;
  mpm_status st = MPM_OK;
  errno = 0;
  while (getline(&line, &cap, f) >= 0) {
    ++line_no;
    chomp(line);
    if (line_no == 1) {
      st = check_header(path, line, &columns, &extra, err);
      if (st != MPM_OK) break;
      continue;
    }
    if (is_blank(line)) continue;
    if (t->rows == capacity) {
      const size_t want = capacity ? 2 * capacity : 256;
      double *grown = mpm_realloc(t->values, want * COL_COUNT * sizeof *t->values);
      if (grown) t->values = grown;
      double *grown_forces =
          grown ? mpm_realloc(t->forces, want * (size_t)(extra + 1) * sizeof *t->forces) : NULL;
      if (!grown_forces) {
        st = mpm_error_set(err, MPM_ERR_NOMEM, "%s: out of memory at line %ld", path, line_no);
        break;
      }
      t->forces = grown_forces;
      capacity = want;
    }
    st = parse_row(path, line_no, line, columns, extra, t->values + t->rows * COL_COUNT,
                   t->forces + t->rows * (size_t)extra, err);
    if (st != MPM_OK) break;
    ++t->rows;
  }
  t->columns = columns;
  t->colliders = extra / 3;
  const int read_error = ferror(f);
  const int read_errno = errno;
  free(line); /* getline's, from malloc */
  fclose(f);
  if (st == MPM_OK && read_error)
    st = mpm_error_set(err, MPM_ERR_IO, "cannot read '%s': %s", path,
                       strerror(read_errno ? read_errno : EIO));
  else if (st == MPM_OK && line_no == 0)
    st = mpm_error_set(err, MPM_ERR_PARSE,
                       "%s: line 1: the file is empty (expected the header "
                       "'frame,time,...,wall_seconds')",
                       path);
  return st;
}

mpm_status mpm_stats_read(const char *path, mpm_stats_table *out, char *err, size_t errlen) {
  if (err && errlen) err[0] = '\0';
  if (!out) return MPM_ERR_INVALID;
  memset(out, 0, sizeof *out);
  mpm_error e;
  mpm_error_clear(&e);
  const mpm_status st = path ? read_table(path, out, &e)
                             : mpm_error_set(&e, MPM_ERR_INVALID, "mpm_stats_read: no file given");
  if (st != MPM_OK) {
    mpm_stats_free(out);
    if (err && errlen) snprintf(err, errlen, "%s", e.message);
  }
  return st;
}
