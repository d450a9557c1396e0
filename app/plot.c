/* plot.c - `mpm plot OUTDIR`: OUTDIR/stats.csv read and checked whole (mpm_stats_read) and
 * plotted with gnuplot (mpm_plot_stats; mpm/plot.h and src/plot/plot.c say how) to PNG files in
 * OUTDIR/plots/ or --out DIR, a line per file written. A missing or bad file is an input error
 * (exit 2, the file and the line named), and so is a run of fewer than 2 frames; gnuplot missing
 * or failing (its messages shown) or a file that cannot be written is a failure (exit 1), with
 * any earlier plots left as they were. On the public API alone. */
#define _POSIX_C_SOURCE 200809L /* stat */

#include "cli.h"
#include "mpm/mpm.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

static void usage(FILE *out) {
  fprintf(out, "usage: mpm plot OUTDIR [--out DIR] [--quiet]\n"
               "  plot OUTDIR/stats.csv (written by 'mpm run') to DIR (default OUTDIR/plots):\n"
               "  energy.png, momentum.png, angular_momentum.png, dt.png, steps_per_frame.png,\n"
               "  wall_per_frame.png, enriched.png, and collider_forces.png for a run with\n"
               "  colliders; needs gnuplot\n");
}

static void print_written(void *ctx, const char *png_path) {
  (void)ctx;
  printf("wrote %s\n", png_path);
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
      static const char *const known[] = {"--out", "-o", "--quiet", "-q", "--help", NULL};
      mpm_cli_unknown_option("plot", argv[i], known);
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

  /* room for gnuplot's messages (the library keeps their first 64 KiB) */
  static char err[72 * 1024];
  mpm_stats_table table;
  mpm_status st = mpm_stats_read(csv_path, &table, err, sizeof err);
  if (st != MPM_OK) {
    fprintf(stderr, "mpm plot: %s\n", err);
    return st == MPM_ERR_NOMEM ? MPM_EXIT_FAILURE : MPM_EXIT_USAGE;
  }
  mpm_plot_options po = mpm_plot_options_default();
  po.out_dir = plots_dir;
  st = mpm_plot_stats(&table, &po, quiet ? NULL : print_written, NULL, err, sizeof err);
  mpm_stats_free(&table);
  if (st != MPM_OK) {
    fprintf(stderr, "mpm plot: %s\n", err);
    return st == MPM_ERR_INVALID ? MPM_EXIT_USAGE : MPM_EXIT_FAILURE; /* too few frames: input */
  }
  return MPM_EXIT_OK;
}
