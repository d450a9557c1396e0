/* triangles.c - pass 2c of render.h: triangle meshes (the particle surfaces of output.surface)
 * as shaded, depth-tested triangles.
 *
 * Each vertex gets the area-weighted normal of its triangles; a triangle is rasterized in
 * screen space with perspective-correct depth and normal (barycentrics over 1/z), lit like the
 * particle splats (light from the upper left, towards the viewer) with a soft rim term. Rows of
 * the image are split among threads: each thread draws every triangle into its own rows only,
 * so the picture does not depend on the thread count. */
#include "render/render.h"
#include "core/alloc.h"
#include "core/parallel.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Camera-space position: along right, up and forward from the eye. */
static void to_camera(const mpm_camera *cam, const float p[3], double c[3]) {
  double rel[3];
  for (int d = 0; d < 3; ++d) rel[d] = p[d] - cam->eye[d];
  c[0] = c[1] = c[2] = 0;
  for (int d = 0; d < 3; ++d) {
    c[0] += rel[d] * cam->right[d];
    c[1] += rel[d] * cam->up[d];
    c[2] += rel[d] * cam->forward[d];
  }
}

mpm_status mpm_render_triangles(mpm_image *img, const mpm_camera *cam, size_t vertex_count,
                                const float *xyz, size_t triangle_count, const uint32_t *tri,
                                const float rgb[3], mpm_error *err) {
  const int w = img->width, h = img->height;
  /* per vertex: screen x, y, camera z, and the camera-space normal */
  double *sv = mpm_alloc((6 * vertex_count + 1) * sizeof *sv);
  if (!sv)
    return mpm_error_set(err, MPM_ERR_NOMEM, "out of memory for %zu surface vertices",
                         vertex_count);
  memset(sv, 0, (6 * vertex_count + 1) * sizeof *sv);
  for (size_t v = 0; v < vertex_count; ++v) {
    double q[3];
    to_camera(cam, xyz + 3 * v, q);
    sv[6 * v] = 0.5 * w + cam->focal * q[0] / fmax(q[2], 1e-9);
    sv[6 * v + 1] = 0.5 * h - cam->focal * q[1] / fmax(q[2], 1e-9);
    sv[6 * v + 2] = q[2];
  }
  for (size_t t = 0; t < triangle_count; ++t) { /* area-weighted vertex normals */
    const float *a = xyz + 3 * tri[3 * t], *b = xyz + 3 * tri[3 * t + 1],
                *c = xyz + 3 * tri[3 * t + 2];
    double e1[3], e2[3], n[3];
    for (int d = 0; d < 3; ++d) e1[d] = b[d] - a[d], e2[d] = c[d] - a[d];
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    double nc[3] = {0, 0, 0}; /* into camera space */
    for (int d = 0; d < 3; ++d) {
      nc[0] += n[d] * cam->right[d];
      nc[1] += n[d] * cam->up[d];
      nc[2] -= n[d] * cam->forward[d]; /* z towards the viewer, as the splats' normals */
    }
    for (int k = 0; k < 3; ++k)
      for (int d = 0; d < 3; ++d) sv[6 * tri[3 * t + (size_t)k] + 3 + (size_t)d] += nc[d];
  }
  const double L[3] = {-0.42, 0.62, 0.66};
#pragma omp parallel
  {
    const int T = mpm_thread_count(), id = mpm_thread_id();
    const int row0 = h * id / T, row1 = h * (id + 1) / T;
    for (size_t t = 0; t < triangle_count; ++t) {
      const double *A = sv + 6 * tri[3 * t], *B = sv + 6 * tri[3 * t + 1],
                   *C = sv + 6 * tri[3 * t + 2];
      if (A[2] <= 1e-6 || B[2] <= 1e-6 || C[2] <= 1e-6) continue; /* behind the eye */
      const double area = (B[0] - A[0]) * (C[1] - A[1]) - (B[1] - A[1]) * (C[0] - A[0]);
      if (area == 0) continue;
      const int y0 = (int)fmax(floor(fmin(A[1], fmin(B[1], C[1]))), row0);
      const int y1 = (int)fmin(ceil(fmax(A[1], fmax(B[1], C[1]))), row1 - 1);
      if (y0 > y1) continue;
      const int x0 = (int)fmax(floor(fmin(A[0], fmin(B[0], C[0]))), 0);
      const int x1 = (int)fmin(ceil(fmax(A[0], fmax(B[0], C[0]))), w - 1);
      for (int py = y0; py <= y1; ++py)
        for (int px = x0; px <= x1; ++px) {
          const double x = px + 0.5, y = py + 0.5;
          /* barycentrics (both windings: a closed surface's back faces are hidden by depth) */
          const double la = ((B[0] - x) * (C[1] - y) - (B[1] - y) * (C[0] - x)) / area;
          const double lb = ((C[0] - x) * (A[1] - y) - (C[1] - y) * (A[0] - x)) / area;
          const double lc = 1 - la - lb;
          if (la < 0 || lb < 0 || lc < 0) continue;
          const double iz = la / A[2] + lb / B[2] + lc / C[2];
          const float z = (float)(1 / iz);
          const size_t i = (size_t)py * (size_t)w + (size_t)px;
          if (z >= img->depth[i]) continue;
          double n[3], nn = 0;
          for (int d = 0; d < 3; ++d) {
            n[d] = (la * A[3 + d] / A[2] + lb * B[3 + d] / B[2] + lc * C[3 + d] / C[2]) / iz;
            nn += n[d] * n[d];
          }
          nn = nn > 0 ? 1 / sqrt(nn) : 0;
          double ndl = 0;
          for (int d = 0; d < 3; ++d) ndl += n[d] * nn * L[d];
          const double facing = fabs(n[2] * nn);
          const float shade = (float)(0.25 + 0.65 * fmax(0, ndl) + 0.1 * (1 - facing));
          img->depth[i] = z;
          for (int c = 0; c < 3; ++c) img->rgb[3 * i + (size_t)c] = shade * rgb[c];
        }
    }
  }
  mpm_free(sv);
  return MPM_OK;
}
