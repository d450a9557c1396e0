/* plot.c - a run's per-frame diagnostics drawn with gnuplot to PNG files (mpm/plot.h:
 * mpm_plot_stats, mpm_plot_run; `mpm plot`), from the table of its stats.csv (mpm_stats_read,
 * io/stats_read.c).
 *
 * The CSV is read and checked completely before anything is written: the header must be the
 * one mpm_write_stats_csv writes (25 columns, then three force columns per collider, plotted
 * in collider_forces.png when there are any; the 21 of files from before the step range and the
 * gravitational energy, the 20 of files from before dynamic enrichment and the 15 of files from
 * before the implicit integrator are read too), every row must have its fields and every field must
 * be a finite number (a bad file is refused with the file and line named). Then, for a table of
 * at least two frames:
 *   1. find gnuplot on PATH (not found: MPM_ERR_EXTERNAL, nothing written);
 *   2. create the plots directory and write two temporaries into it: a whitespace-separated
 *      data file with the derived columns (steps per frame, the difference of the cumulative
 *      step count; the total energy of an older file, kinetic + elastic; '?' where a value is
 *      undefined: the per-frame values of frame 0, dt <= 0 on the log scale, the columns an
 *      older file lacks) and the gnuplot script;
 *   3. run gnuplot on the script in the plots directory (gnuplot.c: fork + execv; its messages
 *      are collected and returned if it fails), each PNG going to the temporary name of an
 *      mpm_atomic_file (io/io.h);
 *   4. if gnuplot succeeded, rename every PNG into place (mpm_atomic_commit); otherwise remove
 *      them, leaving any earlier plots as they were. The data file and the script are always
 *      removed.
 * The script picks the pngcairo terminal when this gnuplot has it (GPVAL_TERMINALS), else png.
 *
 * Columns as mpm_write_stats_csv writes them: `steps` is cumulative, `dt` the frame's typical
 * step with `dt_min` and `dt_max` its range (files from before them have the frame's last step
 * in `dt`), `wall_seconds` the wall time of that frame alone (io.h), so it is plotted as it is.
 * Frame 0 is the initial state (no steps; its wall time is only writing the first frame), so
 * the per-frame plots start at frame 1. */
#define _XOPEN_SOURCE 700 /* POSIX 2008 with realpath */

#include "io/io.h"
#include "core/alloc.h"
#include "plot/gnuplot.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* ---- the script and its data ------------------------------------------------------------ */

/* Row i of the table. */
static const double *row(const mpm_stats_table *t, size_t i) {
  return t->values + i * (size_t)t->stride;
}

/* Write `s` as a single-quoted gnuplot string: quotes doubled, control characters as '?'. */
static void put_gp_string(FILE *f, const char *s) {
  fputc('\'', f);
  for (; *s; ++s) {
    if (*s == '\'')
      fputs("''", f);
    else
      fputc((unsigned char)*s < 0x20 ? '?' : *s, f);
  }
  fputc('\'', f);
}

static const char *base_name(const char *path) {
  const char *slash = strrchr(path, '/');
  return slash ? slash + 1 : path;
}

/* Columns of the derived data file. */
enum {
  DAT_FRAME = 1,
  DAT_TIME,
  DAT_DT,
  DAT_KINETIC,
  DAT_ELASTIC,
  DAT_TOTAL,
  DAT_PX,
  DAT_PY,
  DAT_PZ,
  DAT_LX,
  DAT_LY,
  DAT_LZ,
  DAT_STEPS,
  DAT_WALL,
  DAT_ENRICHED,
  DAT_DT_MIN,
  DAT_DT_MAX,
  DAT_GRAVITATIONAL,
  DAT_COLLIDERS /* then per collider its force's x, y, z and magnitude */
};

/* One PNG: its curves are `using X:Y title T` items over the data file. */
typedef struct plot_curve {
  int x, y;
  const char *title; /* NULL: one curve, no legend */
} plot_curve;

typedef struct plot_spec {
  const char *file, *title, *xlabel, *ylabel;
  int log_y;
  plot_curve curves[4];
} plot_spec;

enum { PLOT_COUNT = 7 };
/* with colliders, one more: collider_forces.png (written by write_collider_plot) */
enum { PLOT_MAX = PLOT_COUNT + 1 };

static const plot_spec plots[PLOT_COUNT] = {
    {"energy.png",
     "energy",
     "time (s)",
     "energy (J)",
     0,
     {{DAT_TIME, DAT_KINETIC, "kinetic"},
      {DAT_TIME, DAT_ELASTIC, "elastic"},
      {DAT_TIME, DAT_GRAVITATIONAL, "gravitational"},
      {DAT_TIME, DAT_TOTAL, "total"}}},
    {"momentum.png",
     "linear momentum",
     "time (s)",
     "momentum (kg m/s)",
     0,
     {{DAT_TIME, DAT_PX, "p_x"}, {DAT_TIME, DAT_PY, "p_y"}, {DAT_TIME, DAT_PZ, "p_z"}}},
    {"angular_momentum.png",
     "angular momentum about the origin",
     "time (s)",
     "angular momentum (kg m^2/s)",
     0,
     {{DAT_TIME, DAT_LX, "L_x"}, {DAT_TIME, DAT_LY, "L_y"}, {DAT_TIME, DAT_LZ, "L_z"}}},
    {"dt.png",
     "time step per frame",
     "time (s)",
     "dt (s)",
     1,
     {{DAT_TIME, DAT_DT, "typical"},
      {DAT_TIME, DAT_DT_MIN, "shortest"},
      {DAT_TIME, DAT_DT_MAX, "longest"}}},
    {"steps_per_frame.png", "steps per frame", "frame", "steps", 0, {{DAT_FRAME, DAT_STEPS, NULL}}},
    {"wall_per_frame.png",
     "wall time per frame",
     "frame",
     "wall time (s)",
     0,
     {{DAT_FRAME, DAT_WALL, NULL}}},
    /* Zhu et al. 2017 Figs. 6, 10 */
    {"enriched.png",
     "enriched domain particles",
     "time (s)",
     "enriched particles (%)",
     0,
     {{DAT_TIME, DAT_ENRICHED, NULL}}},
};

/* A step for the dt plot: '?' where it is undefined (frame 0, or a log scale and dt <= 0). */
static void put_dt(FILE *f, double dt, int have, int dt_log) {
  if (!have || (dt_log && !(dt > 0)))
    fputs(" ?", f);
  else
    fprintf(f, " %.17g", dt);
}

/* Derived data: one line per frame, '?' (gnuplot's missing value here) where undefined. */
static void write_data(FILE *f, const mpm_stats_table *t, int dt_log) {
  const int current = t->columns >= MPM_STATS_COLUMNS; /* step range and gravitational energy */
  for (size_t i = 0; i < t->rows; ++i) {
    const double *r = row(t, i);
    fprintf(f, "%.17g %.17g", r[MPM_STATS_FRAME], r[MPM_STATS_TIME]);
    put_dt(f, r[MPM_STATS_DT], 1, dt_log);
    fputc(' ', f);
    /* an older file's total is kinetic + elastic, all it knows */
    fprintf(f, "%.17g %.17g %.17g", r[MPM_STATS_KINETIC_ENERGY], r[MPM_STATS_ELASTIC_ENERGY],
            current ? r[MPM_STATS_TOTAL_ENERGY]
                    : r[MPM_STATS_KINETIC_ENERGY] + r[MPM_STATS_ELASTIC_ENERGY]);
    for (int c = MPM_STATS_MOMENTUM_X; c <= MPM_STATS_ANGULAR_MOMENTUM_Z; ++c)
      fprintf(f, " %.17g", r[c]);
    if (i == 0)
      fputs(" ? ?", f);
    else
      fprintf(f, " %.17g %.17g", r[MPM_STATS_STEPS] - row(t, i - 1)[MPM_STATS_STEPS],
              r[MPM_STATS_WALL_SECONDS]);
    fprintf(f, " %.17g", r[MPM_STATS_ENRICHED_PERCENT]);
    put_dt(f, r[MPM_STATS_DT_MIN], current && i > 0, dt_log);
    put_dt(f, r[MPM_STATS_DT_MAX], current && i > 0, dt_log);
    if (current)
      fprintf(f, " %.17g", r[MPM_STATS_GRAVITATIONAL_ENERGY]);
    else
      fputs(" ?", f);
    /* a frame's mean force over its steps: none for frame 0, the initial state */
    const double *F = t->forces + i * 3 * (size_t)t->colliders;
    for (int c = 0; c < t->colliders; ++c) {
      if (i == 0) {
        fputs(" ? ? ? ?", f);
        continue;
      }
      const double *Fc = F + 3 * c;
      fprintf(f, " %.17g %.17g %.17g %.17g", Fc[0], Fc[1], Fc[2],
              sqrt(Fc[0] * Fc[0] + Fc[1] * Fc[1] + Fc[2] * Fc[2]));
    }
    fputc('\n', f);
  }
}

/* The colliders' reaction forces over time (stats.csv's collider<c>_f columns, the momentum a
 * collider took from the material per second of the frame): with one collider its components
 * and magnitude, with more the magnitude of each. */
static void write_collider_plot(FILE *f, const char *png_name, const char *run_name,
                                const mpm_stats_table *t) {
  const int colliders = t->colliders;
  fputs("\nset output ", f);
  put_gp_string(f, png_name);
  fputs("\nset title ", f);
  char title[600];
  snprintf(title, sizeof title, "force on the colliders: %s", run_name);
  put_gp_string(f, title);
  fputs(" noenhanced\nset xlabel 'time (s)'\nset ylabel 'force (N)'\n"
        "set key below horizontal spacing 1.3 width 2\nset ytics autofreq\nunset logscale y\n"
        "set xtics autofreq\nset offsets 0, 0, graph 0.05, graph 0.05\nplot ",
        f);
  if (colliders == 1) {
    static const char *const names[4] = {"F_x", "F_y", "F_z", "|F|"};
    for (int k = 0; k < 4; ++k)
      fprintf(f, "%sdata using %d:%d lw 2 title 'collider 0 %s'", k ? ", \\\n     " : "", DAT_TIME,
              DAT_COLLIDERS + k, names[k]);
  } else {
    for (int c = 0; c < colliders; ++c)
      fprintf(f, "%sdata using %d:%d lw 2 title 'collider %d |F|'", c ? ", \\\n     " : "",
              DAT_TIME, DAT_COLLIDERS + 4 * c + 3, c);
  }
  fputc('\n', f);
}

/* What the script needs to know about the data beyond the file. */
typedef struct plot_ranges {
  int dt_log;          /* some dt > 0: log scale */
  double dt_lo, dt_hi; /* the positive dt range */
} plot_ranges;

static plot_ranges find_ranges(const mpm_stats_table *t) {
  plot_ranges r = {0, INFINITY, 0};
  for (size_t i = 0; i < t->rows; ++i)
    for (int c = 0; c < 3; ++c) {
      const int col = c == 0 ? MPM_STATS_DT : c == 1 ? MPM_STATS_DT_MIN : MPM_STATS_DT_MAX;
      const double dt = row(t, i)[col]; /* 0 where a file lacks the column */
      if (!(dt > 0)) continue;
      r.dt_log = 1;
      r.dt_lo = fmin(r.dt_lo, dt);
      r.dt_hi = fmax(r.dt_hi, dt);
    }
  return r;
}

/* gnuplot labels a log axis at powers of ten only; a dt range of a decade or two would get
 * one or two labels, so list 1-9 (or 1, 2, 5) times each power of ten instead. */
static void write_log_tics(FILE *f, double lo, double hi) {
  const double decades = log10(hi / lo);
  if (decades > 3) return;
  static const double fine[] = {1, 2, 3, 4, 5, 6, 7, 8, 9}, coarse[] = {1, 2, 5};
  const double *m = decades <= 1.5 ? fine : coarse;
  const int nm = decades <= 1.5 ? 9 : 3;
  const char *sep = "set ytics (";
  for (int d = (int)floor(log10(lo)); d <= (int)floor(log10(hi)) + 1; ++d) {
    for (int k = 0; k < nm; ++k) {
      fprintf(f, "%s%.3e", sep, m[k] * pow(10, d));
      sep = ", ";
    }
  }
  fputs(")\n", f);
}

static void write_script(FILE *f, const char *data_name, const char *const *png_names,
                         const char *run_name, const mpm_stats_table *t, const plot_ranges *r) {
  fputs("# written by mpm plot\n"
        "if (strstrt(GPVAL_TERMINALS, ' pngcairo ') > 0) {\n"
        "  set terminal pngcairo size 960,600 enhanced font 'sans,11' linewidth 1.5\n"
        "} else {\n"
        "  set terminal png size 960,600 enhanced\n"
        "}\n"
        "set datafile missing '?'\n"
        "set style data linespoints\n"
        "set grid\n"
        "set format y '%g'\n",
        f);
  /* points show single frames on short runs; on long runs they would only clutter */
  fprintf(f, "set pointsize %s\n", t->rows <= 60 ? "0.8" : "0");
  fputs("data = ", f);
  put_gp_string(f, data_name);
  fputc('\n', f);
  const double frames = row(t, t->rows - 1)[MPM_STATS_FRAME] - row(t, 0)[MPM_STATS_FRAME];
  for (int p = 0; p < PLOT_COUNT; ++p) {
    const plot_spec *s = &plots[p];
    fputs("\nset output ", f);
    put_gp_string(f, png_names[p]);
    fputs("\nset title ", f);
    char title[600];
    snprintf(title, sizeof title, "%s: %s", s->title, run_name);
    put_gp_string(f, title);
    fprintf(f, " noenhanced\nset xlabel '%s'\nset ylabel '%s'\n", s->xlabel, s->ylabel);
    /* the legend below the graph, where it hides no curve */
    fputs(s->curves[1].x ? "set key below horizontal spacing 1.3 width 2\n" : "unset key\n", f);
    fputs("set ytics autofreq\n", f);
    if (s->log_y && r->dt_log) {
      fputs("set logscale y\n", f);
      write_log_tics(f, r->dt_lo, r->dt_hi);
    } else {
      fputs("unset logscale y\n", f);
    }
    /* a frame axis: integer tics on a short run, and half a frame of margin so that the
     * first and last points are not drawn on the border */
    if (s->curves[0].x == DAT_FRAME)
      fprintf(f, "set xtics %s\nset offsets 0.5, 0.5, graph 0.05, graph 0.05\n",
              frames <= 20 ? "1" : "autofreq");
    else if (s->log_y && r->dt_log) /* a log axis already ends at whole decades */
      fputs("set xtics autofreq\nset offsets 0, 0, 0, 0\n", f);
    else
      fputs("set xtics autofreq\nset offsets 0, 0, graph 0.05, graph 0.05\n", f);
    fputs("plot ", f);
    for (int c = 0; c < 4 && s->curves[c].x; ++c) {
      fprintf(f, "%sdata using %d:%d lw 2 ", c ? ", \\\n     " : "", s->curves[c].x,
              s->curves[c].y);
      if (s->curves[c].title)
        fprintf(f, "title '%s'", s->curves[c].title);
      else
        fputs("notitle", f);
    }
    fputc('\n', f);
  }
  if (t->colliders) write_collider_plot(f, png_names[PLOT_COUNT], run_name, t);
  fputs("\nunset output\n", f);
}

/* The files of one plotting pass; `open` ones are removed by plot_files_abort. */
typedef struct plot_files {
  mpm_atomic_file png[PLOT_MAX], data, script;
} plot_files;

static void plot_files_abort(plot_files *pf) {
  for (int p = 0; p < PLOT_MAX; ++p) mpm_atomic_abort(&pf->png[p]);
  mpm_atomic_abort(&pf->data);
  mpm_atomic_abort(&pf->script);
}

/* Write the data and the script, run gnuplot, commit the PNGs; failures into err. */
static mpm_status write_plots(const mpm_stats_table *t, const char *run_name, const char *gnuplot,
                              const char *dir, mpm_plot_callback callback, void *ctx,
                              mpm_error *err, char *out, size_t outlen) {
  mpm_status st = mpm_make_dirs(dir, err);
  if (st != MPM_OK) return st;
  plot_files pf;
  memset(&pf, 0, sizeof pf);
  char path[1100];
  const char *png_names[PLOT_MAX];
  const int count = PLOT_COUNT + (t->colliders > 0);
  /* The temporaries the atomic files reserve: the PNGs are renamed into place after gnuplot
   * has written them; the data file and the script are never committed, only removed. */
  for (int p = 0; p < count && st == MPM_OK; ++p) {
    snprintf(path, sizeof path, "%s/%s", dir,
             p < PLOT_COUNT ? plots[p].file : "collider_forces.png");
    st = mpm_atomic_open(&pf.png[p], path, err);
    png_names[p] = base_name(pf.png[p].temp_path);
  }
  if (st == MPM_OK) {
    snprintf(path, sizeof path, "%s/stats.dat", dir);
    st = mpm_atomic_open(&pf.data, path, err);
  }
  if (st == MPM_OK) {
    snprintf(path, sizeof path, "%s/plot.gp", dir);
    st = mpm_atomic_open(&pf.script, path, err);
  }
  if (st != MPM_OK) {
    plot_files_abort(&pf);
    return st;
  }

  const plot_ranges ranges = find_ranges(t);
  write_data(pf.data.fp, t, ranges.dt_log);
  write_script(pf.script.fp, base_name(pf.data.temp_path), png_names, run_name, t, &ranges);
  const int data_failed = fflush(pf.data.fp) != 0 || ferror(pf.data.fp);
  const int script_failed = fflush(pf.script.fp) != 0 || ferror(pf.script.fp);
  if (data_failed || script_failed) {
    st = mpm_error_set(err, MPM_ERR_IO, "cannot write '%s': %s",
                       data_failed ? pf.data.temp_path : pf.script.temp_path, strerror(errno));
    plot_files_abort(&pf);
    return st;
  }

  char what[600], *messages;
  st = mpm_gnuplot_run(gnuplot, dir, base_name(pf.script.temp_path), what, sizeof what, &messages);
  if (st != MPM_OK) {
    /* gnuplot's messages can be longer than an mpm_error holds: straight to the caller's */
    size_t n = messages ? strlen(messages) : 0;
    while (n > 0 && messages[n - 1] == '\n') --n;
    if (out && outlen)
      snprintf(out, outlen, "%s; nothing was written to %s/%s%.*s", what, dir, n ? "\n" : "",
               (int)n, n ? messages : "");
    mpm_free(messages);
    plot_files_abort(&pf);
    return mpm_error_set(err, st, "%s; nothing was written to %s/", what, dir);
  }
  mpm_atomic_abort(&pf.data);
  mpm_atomic_abort(&pf.script);
  for (int p = 0; p < count; ++p) {
    struct stat sb;
    if (stat(pf.png[p].temp_path, &sb) != 0 || sb.st_size == 0) {
      st = mpm_error_set(err, MPM_ERR_EXTERNAL, "gnuplot wrote no image for %s",
                         pf.png[p].final_path);
      plot_files_abort(&pf);
      return st;
    }
  }
  for (int p = 0; p < count; ++p) {
    if ((st = mpm_atomic_commit(&pf.png[p], err)) != MPM_OK) {
      plot_files_abort(&pf);
      return st;
    }
    if (callback) callback(ctx, pf.png[p].final_path);
  }
  return MPM_OK;
}

/* ---- the public calls ------------------------------------------------------------------ */

void mpm_plot_options_init(mpm_plot_options *opts, size_t size) {
  if (!opts || size < sizeof opts->size) return;
  mpm_plot_options o;
  memset(&o, 0, sizeof o);
  o.size = size < sizeof o ? size : sizeof o;
  memcpy(opts, &o, o.size);
}

/* The folder that holds the file `path` ("." for a bare name). */
static void folder_of(const char *path, char *dir, size_t cap) {
  const char *slash = strrchr(path, '/');
  if (!slash)
    snprintf(dir, cap, ".");
  else if (slash == path)
    snprintf(dir, cap, "/");
  else
    snprintf(dir, cap, "%.*s", (int)(slash - path), path);
}

/* The gnuplot to run: `name` as it is when it holds a '/' (made absolute: gnuplot runs in the
 * plots folder), else found on PATH. */
static mpm_status find_gnuplot(const char *name, char *out, size_t cap, mpm_error *err) {
  if (strchr(name, '/')) {
    char *abs = realpath(name, NULL);
    const int n = abs ? snprintf(out, cap, "%s", abs) : -1;
    free(abs); /* realpath's, from malloc */
    if (n > 0 && (size_t)n < cap && access(out, X_OK) == 0) return MPM_OK;
    return mpm_error_set(err, MPM_ERR_EXTERNAL, "gnuplot '%s' is not a program that can run", name);
  }
  if (mpm_gnuplot_find(name, out, cap)) return MPM_OK;
  return mpm_error_set(err, MPM_ERR_EXTERNAL,
                       "%s not found; install it with: apt-get install gnuplot-nox", name);
}

static mpm_status plot_table(const mpm_stats_table *t, const mpm_plot_options *in,
                             mpm_plot_callback callback, void *ctx, mpm_error *err, char *out,
                             size_t outlen) {
  mpm_plot_options o;
  memset(&o, 0, sizeof o);
  if (in) {
    if (in->size < sizeof in->size)
      return mpm_error_set(err, MPM_ERR_INVALID,
                           "mpm_plot_options.size: %zu (start from mpm_plot_options_default())",
                           in->size);
    memcpy(&o, in, in->size < sizeof o ? in->size : sizeof o);
  }
  if (!t) return mpm_error_set(err, MPM_ERR_INVALID, "mpm_plot_stats: no table given");
  const char *file = t->path ? t->path : "the stats table";
  if (t->rows < 2 || !t->values || t->stride < MPM_STATS_COLUMNS)
    return mpm_error_set(err, MPM_ERR_INVALID,
                         "%s: %zu frame%s: need at least 2 (the initial state and one simulated "
                         "frame) to plot",
                         file, t->rows, t->rows == 1 ? "" : "s");
  char gnuplot[4096];
  mpm_status st = find_gnuplot(o.gnuplot ? o.gnuplot : "gnuplot", gnuplot, sizeof gnuplot, err);
  if (st != MPM_OK) return st;
  char folder[4096], dir[1024], run_name[256];
  folder_of(t->path ? t->path : "stats.csv", folder, sizeof folder);
  const int n = o.out_dir ? snprintf(dir, sizeof dir, "%s", o.out_dir)
                          : snprintf(dir, sizeof dir, "%s/plots", folder);
  if (n < 0 || (size_t)n >= sizeof dir) /* the atomic files' names must fit too */
    return mpm_error_set(err, MPM_ERR_IO, "cannot write plots to '%s': path too long",
                         o.out_dir ? o.out_dir : folder);
  if (o.title) {
    snprintf(run_name, sizeof run_name, "%.255s", o.title);
  } else { /* the run's name: the last component of its folder */
    char *abs = realpath(folder, NULL);
    const char *name = base_name(abs ? abs : folder);
    snprintf(run_name, sizeof run_name, "%.255s", name[0] ? name : folder);
    free(abs); /* realpath's, from malloc */
  }
  return write_plots(t, run_name, gnuplot, dir, callback, ctx, err, out, outlen);
}

mpm_status mpm_plot_stats(const mpm_stats_table *t, const mpm_plot_options *opts,
                          mpm_plot_callback callback, void *ctx, char *err, size_t errlen) {
  if (err && errlen) err[0] = '\0';
  mpm_error e;
  mpm_error_clear(&e);
  const mpm_status st = plot_table(t, opts, callback, ctx, &e, err, errlen);
  if (st != MPM_OK && err && errlen && !err[0]) snprintf(err, errlen, "%s", e.message);
  return st;
}

mpm_status mpm_plot_run(const char *run_dir, const mpm_plot_options *opts,
                        mpm_plot_callback callback, void *ctx, char *err, size_t errlen) {
  if (err && errlen) err[0] = '\0';
  struct stat sb;
  const int stat_failed = !run_dir || stat(run_dir, &sb) != 0;
  if (stat_failed || !S_ISDIR(sb.st_mode)) {
    if (err && errlen)
      snprintf(err, errlen, "'%s' %s (expected the output directory of 'mpm run')",
               run_dir ? run_dir : "(null)",
               !stat_failed      ? "is not a directory"
               : errno == ENOENT ? "does not exist"
                                 : strerror(errno));
    return MPM_ERR_IO;
  }
  char path[4200];
  snprintf(path, sizeof path, "%s/stats.csv", run_dir);
  mpm_stats_table t;
  mpm_status st = mpm_stats_read(path, &t, err, errlen);
  if (st != MPM_OK) return st;
  st = mpm_plot_stats(&t, opts, callback, ctx, err, errlen);
  mpm_stats_free(&t);
  return st;
}
