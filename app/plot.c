/* plot.c - `mpm plot OUTDIR`: read the per-frame diagnostics a run wrote to OUTDIR/stats.csv
 * (io/stats_csv.c) and draw them with gnuplot to PNG files in OUTDIR/plots/.
 *
 * The CSV is read and checked completely before anything is written: the header must be the
 * one mpm_write_stats_csv writes (25 columns, then three force columns per collider, plotted
 * in collider_forces.png when there are any; the 21 of files from before the step range and the
 * gravitational energy, the 20 of files from before dynamic enrichment and the 15 of files from
 * before the implicit integrator are read too), every row must have its fields and every field must
 * be a finite number (a bad file is an input error, exit 2, with the file and line named). Then:
 *   1. find gnuplot on PATH (not found: exit 1, nothing written);
 *   2. create the plots directory and write two temporaries into it: a whitespace-separated
 *      data file with the derived columns (steps per frame, the difference of the cumulative
 *      step count; the total energy of an older file, kinetic + elastic; '?' where a value is
 *      undefined: the per-frame values of frame 0, dt <= 0 on the log scale, the columns an
 *      older file lacks) and the gnuplot script;
 *   3. run gnuplot on the script in the plots directory (fork + execv; its messages are
 *      collected and shown if it fails), each PNG going to the temporary name of an
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

#include "cli.h"
#include "io/io.h"
#include "plot_stats.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

/* ---- gnuplot ---------------------------------------------------------------------------- */

/* Absolute path of `name` found on PATH (as execvp would search it), or 0. */
static int find_on_path(const char *name, char *out, size_t size) {
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
static void write_data(FILE *f, const stats_table *t, int dt_log) {
  const int current = t->columns >= COL_COUNT; /* step range and gravitational energy */
  for (size_t i = 0; i < t->count; ++i) {
    const double *r = t->rows[i];
    fprintf(f, "%.17g %.17g", r[COL_FRAME], r[COL_TIME]);
    put_dt(f, r[COL_DT], 1, dt_log);
    fputc(' ', f);
    /* an older file's total is kinetic + elastic, all it knows */
    fprintf(f, "%.17g %.17g %.17g", r[COL_KINETIC], r[COL_ELASTIC],
            current ? r[COL_TOTAL] : r[COL_KINETIC] + r[COL_ELASTIC]);
    for (int c = COL_PX; c <= COL_LZ; ++c) fprintf(f, " %.17g", r[c]);
    if (i == 0)
      fputs(" ? ?", f);
    else
      fprintf(f, " %.17g %.17g", r[COL_STEPS] - t->rows[i - 1][COL_STEPS], r[COL_WALL]);
    fprintf(f, " %.17g", r[COL_ENRICHED]);
    put_dt(f, r[COL_DT_MIN], current && i > 0, dt_log);
    put_dt(f, r[COL_DT_MAX], current && i > 0, dt_log);
    if (current)
      fprintf(f, " %.17g", r[COL_GRAVITATIONAL]);
    else
      fputs(" ?", f);
    /* a frame's mean force over its steps: none for frame 0, the initial state */
    const double *F = t->forces + i * (size_t)t->extra;
    for (int c = 0; c < t->extra / 3; ++c) {
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
                                const stats_table *t) {
  const int colliders = t->extra / 3;
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

static plot_ranges find_ranges(const stats_table *t) {
  plot_ranges r = {0, INFINITY, 0};
  for (size_t i = 0; i < t->count; ++i)
    for (int c = 0; c < 3; ++c) {
      const int col = c == 0 ? COL_DT : c == 1 ? COL_DT_MIN : COL_DT_MAX;
      const double dt = t->rows[i][col]; /* 0 where a file lacks the column */
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
                         const char *run_name, const stats_table *t, const plot_ranges *r) {
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
  fprintf(f, "set pointsize %s\n", t->count <= 60 ? "0.8" : "0");
  fputs("data = ", f);
  put_gp_string(f, data_name);
  fputc('\n', f);
  const double frames = t->rows[t->count - 1][COL_FRAME] - t->rows[0][COL_FRAME];
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
  if (t->extra) write_collider_plot(f, png_names[PLOT_COUNT], run_name, t);
  fputs("\nunset output\n", f);
}

/* gnuplot's messages are kept (the first GP_MESSAGES_MAX bytes) and shown only when it fails:
 * on success they are warnings about data (an empty range of a single frame) that would only
 * be noise. */
#define GP_MESSAGES_MAX (64 * 1024)

/* Run `gnuplot SCRIPT` in `dir` with its stderr (and stdout) collected; on failure print them
 * and say so. Returns 0 on success. */
static int run_gnuplot(const char *gnuplot, const char *dir, const char *script) {
  int fds[2];
  if (pipe(fds) != 0) {
    fprintf(stderr, "mpm plot: cannot start %s: pipe: %s\n", gnuplot, strerror(errno));
    return -1;
  }
  fflush(stdout);
  fflush(stderr);
  const pid_t pid = fork();
  if (pid < 0) {
    fprintf(stderr, "mpm plot: cannot start %s: %s\n", gnuplot, strerror(errno));
    close(fds[0]);
    close(fds[1]);
    return -1;
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
      fprintf(stderr, "mpm plot: cannot enter '%s': %s\n", dir, strerror(errno));
      _exit(127);
    }
    char *const args[] = {(char *)"gnuplot", (char *)script, NULL};
    execv(gnuplot, args);
    fprintf(stderr, "mpm plot: cannot run %s: %s\n", gnuplot, strerror(errno));
    _exit(127);
  }
  close(fds[1]);
  static char messages[GP_MESSAGES_MAX];
  size_t kept = 0;
  int truncated = 0;
  for (;;) {
    char chunk[4096];
    const ssize_t n = read(fds[0], chunk, sizeof chunk);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    const size_t room = sizeof messages - kept, take = (size_t)n < room ? (size_t)n : room;
    memcpy(messages + kept, chunk, take);
    kept += take;
    truncated |= take < (size_t)n;
  }
  close(fds[0]);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) {
      fprintf(stderr, "mpm plot: waiting for gnuplot: %s\n", strerror(errno));
      return -1;
    }
  }
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return 0;
  fwrite(messages, 1, kept, stderr);
  if (truncated) fputs("\n[... more gnuplot messages left out]\n", stderr);
  if (WIFEXITED(status))
    fprintf(stderr, "mpm plot: gnuplot failed (exit status %d)\n", WEXITSTATUS(status));
  else
    fprintf(stderr, "mpm plot: gnuplot was killed by signal %d\n",
            WIFSIGNALED(status) ? WTERMSIG(status) : 0);
  return -1;
}

/* ---- the command ------------------------------------------------------------------------ */

static void usage(FILE *out) {
  fprintf(out, "usage: mpm plot OUTDIR [--out DIR] [--quiet]\n"
               "  plot OUTDIR/stats.csv (written by 'mpm run') to DIR (default OUTDIR/plots):\n"
               "  energy.png, momentum.png, angular_momentum.png, dt.png, steps_per_frame.png,\n"
               "  wall_per_frame.png, enriched.png, and collider_forces.png for a run with\n"
               "  colliders; needs gnuplot\n");
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

/* Write the data and the script, run gnuplot, commit the PNGs. */
static int plot_stats(const stats_table *t, const char *run_name, const char *gnuplot,
                      const char *dir, int quiet) {
  mpm_error err;
  mpm_error_clear(&err);
  if (mpm_make_dirs(dir, &err) != MPM_OK) {
    fprintf(stderr, "mpm plot: %s\n", err.message);
    return MPM_EXIT_FAILURE;
  }
  plot_files pf;
  memset(&pf, 0, sizeof pf);
  char path[1100];
  const char *png_names[PLOT_MAX];
  const int count = PLOT_COUNT + (t->extra > 0);
  /* The temporaries the atomic files reserve: the PNGs are renamed into place after gnuplot
   * has written them; the data file and the script are never committed, only removed. */
  mpm_status st = MPM_OK;
  for (int p = 0; p < count && st == MPM_OK; ++p) {
    snprintf(path, sizeof path, "%s/%s", dir,
             p < PLOT_COUNT ? plots[p].file : "collider_forces.png");
    st = mpm_atomic_open(&pf.png[p], path, &err);
    png_names[p] = base_name(pf.png[p].temp_path);
  }
  if (st == MPM_OK) {
    snprintf(path, sizeof path, "%s/stats.dat", dir);
    st = mpm_atomic_open(&pf.data, path, &err);
  }
  if (st == MPM_OK) {
    snprintf(path, sizeof path, "%s/plot.gp", dir);
    st = mpm_atomic_open(&pf.script, path, &err);
  }
  if (st != MPM_OK) {
    fprintf(stderr, "mpm plot: %s\n", err.message);
    plot_files_abort(&pf);
    return MPM_EXIT_FAILURE;
  }

  const plot_ranges ranges = find_ranges(t);
  write_data(pf.data.fp, t, ranges.dt_log);
  write_script(pf.script.fp, base_name(pf.data.temp_path), png_names, run_name, t, &ranges);
  const int data_failed = fflush(pf.data.fp) != 0 || ferror(pf.data.fp);
  const int script_failed = fflush(pf.script.fp) != 0 || ferror(pf.script.fp);
  if (data_failed || script_failed) {
    fprintf(stderr, "mpm plot: cannot write '%s': %s\n",
            data_failed ? pf.data.temp_path : pf.script.temp_path, strerror(errno));
    plot_files_abort(&pf);
    return MPM_EXIT_FAILURE;
  }

  if (run_gnuplot(gnuplot, dir, base_name(pf.script.temp_path)) != 0) {
    fprintf(stderr, "mpm plot: nothing was written to %s/\n", dir);
    plot_files_abort(&pf);
    return MPM_EXIT_FAILURE;
  }
  mpm_atomic_abort(&pf.data);
  mpm_atomic_abort(&pf.script);
  for (int p = 0; p < count; ++p) {
    struct stat sb;
    if (stat(pf.png[p].temp_path, &sb) != 0 || sb.st_size == 0) {
      fprintf(stderr, "mpm plot: gnuplot wrote no image for %s\n", pf.png[p].final_path);
      plot_files_abort(&pf);
      return MPM_EXIT_FAILURE;
    }
  }
  for (int p = 0; p < count; ++p) {
    if (mpm_atomic_commit(&pf.png[p], &err) != MPM_OK) {
      fprintf(stderr, "mpm plot: %s\n", err.message);
      plot_files_abort(&pf);
      return MPM_EXIT_FAILURE;
    }
    if (!quiet) printf("wrote %s\n", pf.png[p].final_path);
  }
  return MPM_EXIT_OK;
}

int mpm_cmd_plot(int argc, char **argv) {
  const char *run_dir = NULL, *out_dir = NULL;
  int quiet = 0;
  for (int i = 0; i < argc; ++i) {
    if (!strcmp(argv[i], "--out") || !strcmp(argv[i], "-o")) {
      if (i + 1 >= argc || !argv[i + 1][0]) {
        fprintf(stderr, "mpm plot: %s needs a directory\n", argv[i]);
        usage(stderr);
        return MPM_EXIT_USAGE;
      }
      out_dir = argv[++i];
    } else if (!strcmp(argv[i], "--quiet") || !strcmp(argv[i], "-q")) {
      quiet = 1;
    } else if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
      usage(stdout);
      return MPM_EXIT_OK;
    } else if (argv[i][0] == '-') {
      fprintf(stderr, "mpm plot: unknown option '%s'\n", argv[i]);
      usage(stderr);
      return MPM_EXIT_USAGE;
    } else if (!run_dir) {
      run_dir = argv[i];
    } else {
      fprintf(stderr, "mpm plot: more than one directory given ('%s' and '%s')\n", run_dir,
              argv[i]);
      usage(stderr);
      return MPM_EXIT_USAGE;
    }
  }
  if (!run_dir || !run_dir[0]) {
    usage(stderr);
    return MPM_EXIT_USAGE;
  }

  struct stat sb;
  const int stat_failed = stat(run_dir, &sb) != 0;
  if (stat_failed || !S_ISDIR(sb.st_mode)) {
    fprintf(stderr, "mpm plot: '%s' %s (expected the output directory of 'mpm run')\n", run_dir,
            !stat_failed      ? "is not a directory"
            : errno == ENOENT ? "does not exist"
                              : strerror(errno));
    return MPM_EXIT_USAGE;
  }
  char csv_path[1024], plots_dir[1024];
  const int n1 = snprintf(csv_path, sizeof csv_path, "%s/stats.csv", run_dir);
  const int n2 = out_dir ? snprintf(plots_dir, sizeof plots_dir, "%s", out_dir)
                         : snprintf(plots_dir, sizeof plots_dir, "%s/plots", run_dir);
  if (n1 < 0 || (size_t)n1 >= sizeof csv_path || n2 < 0 || (size_t)n2 >= sizeof plots_dir) {
    fprintf(stderr, "mpm plot: path too long: '%s'\n", out_dir ? out_dir : run_dir);
    return MPM_EXIT_USAGE;
  }

  mpm_error err;
  mpm_error_clear(&err);
  stats_table table;
  const mpm_status st = mpm_stats_read(csv_path, &table, &err);
  if (st != MPM_OK) {
    fprintf(stderr, "mpm plot: %s\n", err.message);
    return st == MPM_ERR_NOMEM ? MPM_EXIT_FAILURE : MPM_EXIT_USAGE;
  }

  char gnuplot[4096];
  if (!find_on_path("gnuplot", gnuplot, sizeof gnuplot)) {
    fprintf(stderr, "mpm plot: gnuplot not found; install it with: apt-get install gnuplot-nox\n");
    mpm_stats_table_free(&table);
    return MPM_EXIT_FAILURE;
  }

  /* the run's name for the titles: the last component of its directory */
  char *abs = realpath(run_dir, NULL);
  char run_name[256];
  const char *name = base_name(abs ? abs : run_dir);
  snprintf(run_name, sizeof run_name, "%s", name[0] ? name : run_dir);
  free(abs);

  const int code = plot_stats(&table, run_name, gnuplot, plots_dir, quiet);
  mpm_stats_table_free(&table);
  return code;
}
