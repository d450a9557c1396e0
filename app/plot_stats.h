/* plot_stats.h - `mpm plot`'s reading of stats.csv (plot_stats.c): the columns
 * mpm_write_stats_csv writes (io/stats_csv.c), and the whole file read and checked into a table
 * before anything is plotted. */
#ifndef MPM_APP_PLOT_STATS_H
#define MPM_APP_PLOT_STATS_H

#include "core/error.h"

#include <stddef.h>

enum {
  COL_FRAME,
  COL_TIME,
  COL_STEPS,
  COL_DT,
  COL_KINETIC,
  COL_ELASTIC,
  COL_PX,
  COL_PY,
  COL_PZ,
  COL_LX,
  COL_LY,
  COL_LZ,
  COL_MASS,
  COL_PARTICLES,
  COL_WALL,
  COL_LEGACY_COUNT, /* files written before the implicit integrator end here */
  COL_CG_MEAN = COL_LEGACY_COUNT,
  COL_CG_MAX,
  COL_CG_RESIDUAL,
  COL_NEWTON_MEAN,
  COL_CG_UNCONVERGED,
  COL_SOLVER_COUNT, /* files written before dynamic enrichment end here */
  COL_ENRICHED = COL_SOLVER_COUNT,
  COL_ENRICHED_COUNT, /* files written before the step range and gravitational energy end here */
  COL_DT_MIN = COL_ENRICHED_COUNT,
  COL_DT_MAX,
  COL_GRAVITATIONAL,
  COL_TOTAL,
  COL_COUNT
};

typedef struct stats_table {
  double (*rows)[COL_COUNT];
  double *forces; /* `extra` per row: the colliders' mean force over the frame (x, y, z), N */
  size_t count, capacity;
  int columns; /* the file's: fewer than COL_COUNT for a file of an earlier version */
  int extra;   /* the collider force columns, 3 per collider */
} stats_table;

/* Read and check the whole file; blank lines are skipped. Needs at least two frames, so that
 * every plot (the per-frame ones start at frame 1) has a point. Errors name the file, the line
 * and the column (MPM_ERR_IO, MPM_ERR_PARSE, MPM_ERR_NOMEM); the table is empty then. */
mpm_status mpm_stats_read(const char *path, stats_table *t, mpm_error *err);
void mpm_stats_table_free(stats_table *t);

#endif
