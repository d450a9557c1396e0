/* cells_vtu.c - the leaves of the multi-level grid as a VTK UnstructuredGrid of voxels
 * (grid_cells.vtu), so that ParaView shows where the grid is fine: every leaf of level 1 and
 * finer is one VTK_VOXEL cell with CellData `level`; the level-0 leaves (the rest of the domain)
 * are left out. Points are not shared between cells (8 per cell), which keeps the writer one
 * pass over the leaves.
 *
 * Same layout as vtu.c (XML header, UInt64 byte counts, one raw appended block). */
#include "adaptive/cells_vtu.h"

#include "io/io.h"
#include "io/vtu_stream.h"
#include "core/alloc.h"

#include <errno.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

typedef struct leaves {
  const mpm_refinement *r;
  float *xyz;   /* 24 per leaf */
  int32_t *lvl; /* 1 per leaf */
  size_t n;
} leaves;

static void collect(void *ctx, int level, const int32_t cell[3]) {
  leaves *l = ctx;
  const double dx = (double)mpm_refinement_dx(l->r, level);
  float *p = l->xyz + 24 * l->n;
  /* VTK_VOXEL corner order: x fastest, then y, then z */
  for (int k = 0; k < 8; ++k) {
    const int32_t c[3] = {cell[0] + (k & 1), cell[1] + ((k >> 1) & 1), cell[2] + ((k >> 2) & 1)};
    for (int d = 0; d < 3; ++d) p[3 * k + d] = (float)((double)l->r->origin[d] + c[d] * dx);
  }
  l->lvl[l->n++] = level;
}

mpm_status mpm_write_cells_vtu(const char *path, const mpm_refinement *r, double time,
                               mpm_error *err) {
  const size_t n = mpm_refinement_fine_leaves(r, NULL, NULL);
  leaves l = {r, mpm_alloc((24 * n + 1) * sizeof(float)), mpm_alloc((n + 1) * sizeof(int32_t)), 0};
  if (!l.xyz || !l.lvl) {
    mpm_free(l.xyz);
    mpm_free(l.lvl);
    return mpm_error_set(err, MPM_ERR_NOMEM, "out of memory writing '%s'", path);
  }
  mpm_refinement_fine_leaves(r, collect, &l);
  const uint64_t sizes[6] = {sizeof(double), 24 * n * sizeof(float), n * 4, 8 * n * 8, n * 8, n};
  uint64_t off[6], at = 0;
  for (int k = 0; k < 6; ++k) {
    off[k] = at;
    at += 8 + sizes[k];
  }
  mpm_atomic_file f;
  mpm_status st = mpm_atomic_open(&f, path, err);
  if (st != MPM_OK) {
    mpm_free(l.xyz);
    mpm_free(l.lvl);
    return st;
  }
  mpm_vtu_stream o = {f.fp, 0};
  mpm_vtu_begin(&o);
  mpm_vtu_data_array(&o, 1, "Float64", "TIME", 1, 1, off[0]);
  mpm_vtu_piece(&o, 8 * n, n);
  mpm_vtu_section(&o, "Points", 1, NULL);
  mpm_vtu_data_array(&o, 0, "Float32", "Points", 3, 0, off[1]);
  mpm_vtu_section(&o, "Points", 0, NULL);
  mpm_vtu_section(&o, "CellData", 1, NULL);
  mpm_vtu_data_array(&o, 0, "Int32", "level", 1, 0, off[2]);
  mpm_vtu_section(&o, "CellData", 0, NULL);
  mpm_vtu_section(&o, "Cells", 1, NULL);
  mpm_vtu_data_array(&o, 0, "Int64", "connectivity", 1, 0, off[3]);
  mpm_vtu_data_array(&o, 0, "Int64", "offsets", 1, 0, off[4]);
  mpm_vtu_data_array(&o, 0, "UInt8", "types", 1, 0, off[5]);
  mpm_vtu_section(&o, "Cells", 0, NULL);
  mpm_vtu_end_head(&o);
  mpm_vtu_put_count(&o, sizes[0]);
  mpm_vtu_put(&o, &time, sizeof time);
  mpm_vtu_put_count(&o, sizes[1]);
  mpm_vtu_put(&o, l.xyz, sizes[1]);
  mpm_vtu_put_count(&o, sizes[2]);
  mpm_vtu_put(&o, l.lvl, sizes[2]);
  mpm_vtu_put_count(&o, sizes[3]);
  for (size_t c = 0; c < 8 * n; ++c) {
    const int64_t v = (int64_t)c;
    mpm_vtu_put(&o, &v, sizeof v);
  }
  mpm_vtu_put_count(&o, sizes[4]);
  for (size_t c = 1; c <= n; ++c) {
    const int64_t v = (int64_t)(8 * c);
    mpm_vtu_put(&o, &v, sizeof v);
  }
  mpm_vtu_put_count(&o, sizes[5]);
  const uint8_t voxel = 11; /* VTK_VOXEL */
  for (size_t c = 0; c < n; ++c) mpm_vtu_put(&o, &voxel, 1);
  mpm_vtu_finish(&o);
  mpm_free(l.xyz);
  mpm_free(l.lvl);
  if (o.err) {
    mpm_atomic_abort(&f);
    return mpm_error_set(err, MPM_ERR_IO, "cannot write '%s': %s", path, strerror(o.err));
  }
  return mpm_atomic_commit(&f, err);
}
