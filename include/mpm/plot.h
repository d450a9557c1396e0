/* plot.h - a run's per-frame diagnostics: stats.csv (energies, momenta, the time step, wall
 * time, the implicit solver's figures, the colliders' reaction forces) read into a table, and
 * plotted with gnuplot to PNG files (`mpm plot`).
 *
 *   mpm_stats_table t;
 *   if (mpm_stats_read("out/stats.csv", &t, err, sizeof err) == MPM_OK) {
 *     const double *last = t.values + (t.rows - 1) * t.stride;
 *     printf("total energy %g J\n", last[MPM_STATS_TOTAL_ENERGY]);
 *     mpm_stats_free(&t);
 *   }
 *   mpm_plot_run("out", NULL, NULL, NULL, err, sizeof err); // out/plots/energy.png, ...
 *
 * Included by mpm.h; include <mpm/mpm.h>. */
#ifndef MPM_PLOT_H
#define MPM_PLOT_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/// The columns of stats.csv in the order `mpm run` writes them (docs/scene-format.md, "stats.csv").
/// Files of earlier versions end after WALL_SECONDS, CG_UNCONVERGED or ENRICHED_PERCENT.
typedef enum mpm_stats_column {
  MPM_STATS_FRAME = 0,
  MPM_STATS_TIME,           /* s */
  MPM_STATS_STEPS,          /* cumulative */
  MPM_STATS_DT,             /* the frame's typical step, s */
  MPM_STATS_KINETIC_ENERGY, /* J */
  MPM_STATS_ELASTIC_ENERGY, /* J */
  MPM_STATS_MOMENTUM_X,     /* kg m/s */
  MPM_STATS_MOMENTUM_Y,
  MPM_STATS_MOMENTUM_Z,
  MPM_STATS_ANGULAR_MOMENTUM_X, /* about the origin, kg m^2/s */
  MPM_STATS_ANGULAR_MOMENTUM_Y,
  MPM_STATS_ANGULAR_MOMENTUM_Z,
  MPM_STATS_MASS, /* kg */
  MPM_STATS_PARTICLES,
  MPM_STATS_WALL_SECONDS, /* the wall time of this frame alone, s */
  MPM_STATS_CG_ITERATIONS_MEAN,
  MPM_STATS_CG_ITERATIONS_MAX,
  MPM_STATS_CG_RESIDUAL_MAX,
  MPM_STATS_NEWTON_ITERATIONS_MEAN,
  MPM_STATS_CG_UNCONVERGED,
  MPM_STATS_ENRICHED_PERCENT,
  MPM_STATS_DT_MIN,               /* s */
  MPM_STATS_DT_MAX,               /* s */
  MPM_STATS_GRAVITATIONAL_ENERGY, /* J */
  MPM_STATS_TOTAL_ENERGY,         /* J */
  MPM_STATS_COLUMNS
} mpm_stats_column;

/// The column's name in the file's header ("frame", "kinetic_energy", ...); static storage,
/// NULL out of range.
MPM_API const char *mpm_stats_column_name(mpm_stats_column column);

/// A stats.csv read whole. The arrays are owned by the table (mpm_stats_free).
typedef struct mpm_stats_table {
  size_t rows;    /* frames read, in the file's order */
  int columns;    /* the file's columns of the set above: MPM_STATS_COLUMNS, or fewer for a
                     file of an earlier version (those it lacks read as 0) */
  int stride;     /* values per row: values[row * stride + MPM_STATS_TIME] */
  double *values; /* rows * stride */
  int colliders;  /* colliders with force columns (collider<c>_fx, _fy, _fz after total_energy) */
  double *forces; /* rows * colliders * 3: the mean force on collider c over the frame (the
                     momentum it took from the material per second), N, at
                     forces[(row * colliders + c) * 3 + axis] */
  char *path;     /* the file read */
} mpm_stats_table;

/// Read and check a whole stats.csv: the header must be one `mpm run` wrote (today's or an
/// earlier version's), every row must have its fields and every field must be a finite number;
/// blank lines are skipped. On failure the table is empty and err (may be NULL) names the file,
/// the line and the column: MPM_ERR_IO, MPM_ERR_PARSE, MPM_ERR_NOMEM.
MPM_API mpm_status mpm_stats_read(const char *path, mpm_stats_table *out, char *err, size_t errlen);
/// Free a table's arrays (the struct is zeroed); a zeroed table is fine.
MPM_API void mpm_stats_free(mpm_stats_table *t);

/// How to plot. Start from mpm_plot_options_default() (sized as mpm_render_options is).
typedef struct mpm_plot_options {
  size_t size;         /* sizeof(mpm_plot_options), set by the default */
  const char *out_dir; /* default NULL: the folder of the stats file, then plots/ */
  const char *title;   /* the run's name in the titles; default NULL: the name of the folder
                          that holds the stats file */
  const char *gnuplot; /* the gnuplot program; default NULL: gnuplot found on PATH */
} mpm_plot_options;

MPM_API void mpm_plot_options_init(mpm_plot_options *opts, size_t size);

static inline mpm_plot_options mpm_plot_options_default(void) {
  mpm_plot_options o;
  mpm_plot_options_init(&o, sizeof o);
  return o;
}

/// After each PNG of a plotting pass is in place (its path).
typedef void (*mpm_plot_callback)(void *ctx, const char *png_path);

/// Plot a table with gnuplot into opts->out_dir (made when missing; opts NULL: the defaults):
/// energy.png, momentum.png, angular_momentum.png, dt.png, steps_per_frame.png,
/// wall_per_frame.png, enriched.png, and collider_forces.png when the run has colliders. The
/// PNGs are written to temporary names and renamed into place only when gnuplot succeeded, so a
/// failure leaves earlier plots as they were. MPM_ERR_INVALID for a table of fewer than 2 frames
/// (the per-frame plots start at frame 1), MPM_ERR_EXTERNAL when gnuplot is not found or fails
/// (err then holds its messages), MPM_ERR_IO when a file cannot be written.
MPM_API mpm_status mpm_plot_stats(const mpm_stats_table *t, const mpm_plot_options *opts,
                                  mpm_plot_callback callback, void *ctx, char *err, size_t errlen);

/// RUN_DIR/stats.csv read (mpm_stats_read) and plotted (mpm_plot_stats) into opts->out_dir,
/// default RUN_DIR/plots. MPM_ERR_IO for a run_dir that is not a folder.
MPM_API mpm_status mpm_plot_run(const char *run_dir, const mpm_plot_options *opts,
                                mpm_plot_callback callback, void *ctx, char *err, size_t errlen);

#ifdef __cplusplus
}
#endif
#endif
