/* vtu_cells.c - the leaves of the multi-level grid as a VTK UnstructuredGrid of voxels
 * (grid_cells.vtu), so that ParaView shows where the grid is fine: every leaf of level 1 and
 * finer is one VTK_VOXEL cell with CellData `level`; the level-0 leaves (the rest of the domain)
 * are left out. Points are not shared between cells (8 per cell), which keeps the writer one
 * pass over the leaves.
 *
 * Same layout as vtu.c (XML header, UInt64 byte counts, one raw appended block). */
#include "io/io.h"
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
  char head[2048];
  snprintf(
      head, sizeof head,
      "<?xml version=\"1.0\"?>\n"
      "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
      "header_type=\"UInt64\">\n"
      "  <UnstructuredGrid>\n"
      "    <FieldData>\n"
      "      <DataArray type=\"Float64\" Name=\"TIME\" NumberOfTuples=\"1\" "
      "format=\"appended\" offset=\"%llu\"/>\n"
      "    </FieldData>\n"
      "    <Piece NumberOfPoints=\"%zu\" NumberOfCells=\"%zu\">\n"
      "      <Points>\n"
      "        <DataArray type=\"Float32\" Name=\"Points\" NumberOfComponents=\"3\" "
      "format=\"appended\" offset=\"%llu\"/>\n"
      "      </Points>\n"
      "      <CellData>\n"
      "        <DataArray type=\"Int32\" Name=\"level\" format=\"appended\" offset=\"%llu\"/>\n"
      "      </CellData>\n"
      "      <Cells>\n"
      "        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"appended\" "
      "offset=\"%llu\"/>\n"
      "        <DataArray type=\"Int64\" Name=\"offsets\" format=\"appended\" "
      "offset=\"%llu\"/>\n"
      "        <DataArray type=\"UInt8\" Name=\"types\" format=\"appended\" offset=\"%llu\"/>\n"
      "      </Cells>\n"
      "    </Piece>\n"
      "  </UnstructuredGrid>\n"
      "  <AppendedData encoding=\"raw\">\n_",
      (unsigned long long)off[0], 8 * n, n, (unsigned long long)off[1], (unsigned long long)off[2],
      (unsigned long long)off[3], (unsigned long long)off[4], (unsigned long long)off[5]);
  int e = 0;
#define PUT(p, bytes)                                                                              \
  do {                                                                                             \
    errno = 0;                                                                                     \
    if (!e && (bytes) && fwrite((p), 1, (bytes), f.fp) != (bytes)) e = errno ? errno : EIO;        \
  } while (0)
  PUT(head, strlen(head));
  PUT(&sizes[0], 8);
  PUT(&time, sizeof time);
  PUT(&sizes[1], 8);
  PUT(l.xyz, sizes[1]);
  PUT(&sizes[2], 8);
  PUT(l.lvl, sizes[2]);
  PUT(&sizes[3], 8);
  for (size_t c = 0; c < 8 * n; ++c) {
    const int64_t v = (int64_t)c;
    PUT(&v, sizeof v);
  }
  PUT(&sizes[4], 8);
  for (size_t c = 1; c <= n; ++c) {
    const int64_t v = (int64_t)(8 * c);
    PUT(&v, sizeof v);
  }
  PUT(&sizes[5], 8);
  const uint8_t voxel = 11; /* VTK_VOXEL */
  for (size_t c = 0; c < n; ++c) PUT(&voxel, 1);
  const char *tail = "\n  </AppendedData>\n</VTKFile>\n";
  PUT(tail, strlen(tail));
#undef PUT
  mpm_free(l.xyz);
  mpm_free(l.lvl);
  if (e) {
    mpm_atomic_abort(&f);
    return mpm_error_set(err, MPM_ERR_IO, "cannot write '%s': %s", path, strerror(e));
  }
  return mpm_atomic_commit(&f, err);
}
