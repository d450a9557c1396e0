/* grid_edges.c - a renderer's `grid` option (`mpm render --grid`): the multi-level grid's cells
 * as line segments over the particles, from the grid_cells VTU files a run on levels writes. */
#define _POSIX_C_SOURCE 200809L

#include "render/renderer.h"
#include "core/alloc.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

static int cmp_u64(const void *a, const void *b) {
  const uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
  return x < y ? -1 : x > y;
}

/* The edges of the multi-level grid's fine leaves (OUTDIR/grid_cells_NNNN.vtu of a frame when
 * the run rebuilt its grid, else OUTDIR/grid_cells.vtu: 8 corners per voxel)
 * on the surfaces of the levels' regions, each once, coloured by level (the edge length):
 * segments for mpm_render_lines. MPM_OK with
 * *n = 0 when the run has no such file; the status with err on a bad file or no memory. */
mpm_status mpm_render_grid_edges(const char *dir, int frame, float **ab, float **rgb, size_t *n,
                                 mpm_error *err) {
  *n = 0;
  char path[4200];
  snprintf(path, sizeof path, "%s/grid_cells_%04d.vtu", dir, frame);
  /* a run without a grid file has no edges; a file that is there is read (and refused when
     it is not a regular file) */
  if (access(path, F_OK) != 0) {
    snprintf(path, sizeof path, "%s/grid_cells.vtu", dir);
    if (access(path, F_OK) != 0) return MPM_OK;
  }
  mpm_vtu_frame fr;
  const mpm_status st = mpm_read_vtu(path, &fr, err);
  if (st != MPM_OK) return st;
  const mpm_vtu_array *pts = mpm_vtu_frame_array(&fr, "Points");
  const size_t cells = pts ? (size_t)fr.point_count / 8 : 0;
  double lo[3] = {INFINITY, INFINITY, INFINITY}, h = INFINITY;
  for (size_t c = 0; c < cells; ++c) {
    const float *p = pts->data + 24 * c;
    h = fmin(h, (double)(p[3] - p[0])); /* corner 1 is corner 0 + x */
    for (int d = 0; d < 3; ++d) lo[d] = fmin(lo[d], (double)p[d]);
  }
  /* an edge: its start on the finest lattice (18 bits per axis), axis and length exponent */
  uint64_t *key = mpm_alloc((12 * cells + 1) * sizeof *key);
  if (!key) {
    mpm_vtu_frame_free(&fr);
    return mpm_error_set(err, MPM_ERR_NOMEM, "%s: out of memory for the grid's edges", path);
  }
  size_t m = 0;
  static const int from[12] = {0, 2, 4, 6, 0, 1, 4, 5, 0, 1, 2, 3};
  static const int axis[12] = {0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2, 2};
  for (size_t c = 0; c < cells; ++c) {
    const float *p = pts->data + 24 * c;
    const double size = (double)(p[3] - p[0]);
    const int e = (int)lround(log2(size / h));
    for (int k = 0; k < 12; ++k) {
      uint64_t q = 0;
      for (int d = 0; d < 3; ++d)
        q = q << 18 | ((uint64_t)lround(((double)p[3 * from[k] + d] - lo[d]) / h) & 0x3ffff);
      key[m++] = (q << 2 | (uint64_t)axis[k]) << 4 | (uint64_t)(e & 15);
    }
  }
  qsort(key, m, sizeof *key, cmp_u64);
  /* each edge once, and only those on the surface of a level's region: an edge inside one is
   * shared by 4 cells of its size */
  size_t u = 0;
  for (size_t k = 0; k < m;) {
    size_t j = k;
    while (j < m && key[j] == key[k]) ++j;
    if (j - k < 4) key[u++] = key[k];
    k = j;
  }
  *ab = mpm_alloc((6 * u + 1) * sizeof **ab);
  *rgb = mpm_alloc((3 * u + 1) * sizeof **rgb);
  if (!*ab || !*rgb) {
    mpm_free(key);
    mpm_vtu_frame_free(&fr);
    return mpm_error_set(err, MPM_ERR_NOMEM, "%s: out of memory for the grid's edges", path);
  }
  for (size_t k = 0; k < u; ++k) {
    const int e = (int)(key[k] & 15), ax = (int)(key[k] >> 4 & 3);
    const uint64_t q = key[k] >> 6;
    const double len = h * (double)(1 << e);
    for (int d = 0; d < 3; ++d) {
      const double x = lo[d] + h * (double)((q >> (18 * (2 - d))) & 0x3ffff);
      (*ab)[6 * k + d] = (float)x;
      (*ab)[6 * k + 3 + d] = (float)(x + (d == ax ? len : 0));
    }
    /* the finest level light, coarser ones darker */
    mpm_colormap_eval(MPM_CMAP_VIRIDIS, 1 - 0.3 * e, *rgb + 3 * k);
  }
  *n = u;
  mpm_free(key);
  mpm_vtu_frame_free(&fr);
  return MPM_OK;
}
