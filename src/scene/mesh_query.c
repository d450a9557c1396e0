/* mesh_query.c - what a triangle mesh is asked once read (see mesh.h): its bounds, its edges by
 * how many triangles share them (boundary: a hole; more than two: not a 2-manifold) and the
 * generalized-winding-number inside test.
 *
 * Inside test: the generalized winding number of Jacobson, Kavan and Sorkine-Hornung,
 * "Robust inside-outside segmentation using generalized winding numbers" (SIGGRAPH 2013),
 * with the solid angle of a triangle from Van Oosterom and Strackee (1983):
 *   tan(Omega/2) = a.(b x c) / (|a||b||c| + (a.b)|c| + (b.c)|a| + (c.a)|b|),
 * a, b, c the corners relative to the query point. w = sum Omega / 4 pi is 1 inside and 0
 * outside a closed mesh, and degrades gracefully (w ~ 1/2 only near holes) for open ones. */
#include "scene/mesh.h"
#include "core/alloc.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

void mpm_mesh_bounds(const mpm_mesh *mesh, double lo[3], double hi[3]) {
  for (int d = 0; d < 3; ++d) {
    lo[d] = mesh->vertex_count ? INFINITY : 0;
    hi[d] = mesh->vertex_count ? -INFINITY : 0;
  }
  for (int i = 0; i < mesh->vertex_count; ++i)
    for (int d = 0; d < 3; ++d) {
      double x = mesh->vertices[3 * i + d];
      if (x < lo[d]) lo[d] = x;
      if (x > hi[d]) hi[d] = x;
    }
}

static int cmp_u64(const void *a, const void *b) {
  uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
  return (x > y) - (x < y);
}

mpm_status mpm_mesh_edge_check(const mpm_mesh *mesh, mpm_mesh_edges *out) {
  memset(out, 0, sizeof *out);
  out->a = out->b = -1;
  size_t n = 0;
  uint64_t *keys =
      mpm_alloc((size_t)(mesh->triangle_count ? mesh->triangle_count : 1) * 3 * sizeof *keys);
  if (!keys) return MPM_ERR_NOMEM;
  for (int t = 0; t < mesh->triangle_count; ++t)
    for (int k = 0; k < 3; ++k) {
      uint32_t a = (uint32_t)mesh->triangles[3 * t + k];
      uint32_t b = (uint32_t)mesh->triangles[3 * t + (k + 1) % 3];
      if (a == b) continue; /* a degenerate triangle's collapsed edge */
      keys[n++] = a < b ? ((uint64_t)a << 32 | b) : ((uint64_t)b << 32 | a);
    }
  qsort(keys, n, sizeof *keys, cmp_u64);
  for (size_t i = 0; i < n;) {
    size_t j = i;
    while (j < n && keys[j] == keys[i]) ++j;
    if (j - i == 1) ++out->boundary;
    if (j - i > 2 && out->non_manifold++ == 0) {
      out->a = (int)(keys[i] >> 32);
      out->b = (int)(keys[i] & 0xffffffffu);
      out->shared = (int)(j - i);
    }
    i = j;
  }
  mpm_free(keys);
  /* the first non-manifold edge's triangles, in the file's order */
  int found = 0;
  for (int t = 0; out->shared && t < mesh->triangle_count && found < 4; ++t)
    for (int k = 0; k < 3; ++k) {
      const int a = mesh->triangles[3 * t + k], b = mesh->triangles[3 * t + (k + 1) % 3];
      if ((a == out->a && b == out->b) || (a == out->b && b == out->a)) {
        out->triangles[found++] = t;
        break;
      }
    }
  return MPM_OK;
}

long mpm_mesh_boundary_edges(const mpm_mesh *mesh) {
  mpm_mesh_edges e;
  return mpm_mesh_edge_check(mesh, &e) != MPM_OK ? -1 : e.boundary;
}

double mpm_mesh_winding_number(const mpm_mesh *mesh, const double p[3]) {
  double sum = 0;
  for (int t = 0; t < mesh->triangle_count; ++t) {
    double a[3], b[3], c[3];
    const int *tri = &mesh->triangles[3 * t];
    for (int d = 0; d < 3; ++d) {
      a[d] = mesh->vertices[3 * tri[0] + d] - p[d];
      b[d] = mesh->vertices[3 * tri[1] + d] - p[d];
      c[d] = mesh->vertices[3 * tri[2] + d] - p[d];
    }
    double la = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    double lb = sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
    double lc = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    double det = a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
                 a[2] * (b[0] * c[1] - b[1] * c[0]);
    double ab = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    double bc = b[0] * c[0] + b[1] * c[1] + b[2] * c[2];
    double ca = c[0] * a[0] + c[1] * a[1] + c[2] * a[2];
    sum += atan2(det, la * lb * lc + ab * lc + bc * la + ca * lb);
  }
  const double pi = 3.14159265358979323846;
  return sum / (2 * pi); /* Omega = 2 atan2(...), w = sum Omega / 4 pi */
}

int mpm_mesh_inside(const mpm_mesh *mesh, const double p[3]) {
  return fabs(mpm_mesh_winding_number(mesh, p)) > 0.5;
}
