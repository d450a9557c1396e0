/* draw.c - the background (sky, ground, colliders) and the particle splats. */
#include "render/render.h"
#include "core/alloc.h"
#include "core/parallel.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define TRACE_STEPS 160
#define TRACE_EPS_REL 1e-3 /* hit tolerance, relative to the domain size */

/* Direction of the ray through the centre of pixel (px, py). */
static void pixel_ray(const mpm_camera *cam, int px, int py, double dir[3]) {
  const double sx = (px + 0.5 - 0.5 * cam->width) / cam->focal;
  const double sy = (py + 0.5 - 0.5 * cam->height) / cam->focal;
  double n = 0;
  for (int d = 0; d < 3; ++d) {
    dir[d] = cam->forward[d] + sx * cam->right[d] - sy * cam->up[d];
    n += dir[d] * dir[d];
  }
  n = 1 / sqrt(n);
  for (int d = 0; d < 3; ++d) dir[d] *= n;
}

static double phi_at(const mpm_collider_pose *pose, const double x[3], double n[3]) {
  const mpm_real xr[3] = {(mpm_real)x[0], (mpm_real)x[1], (mpm_real)x[2]};
  mpm_real nr[3];
  const double phi = (double)mpm_collider_phi(pose, xr, nr);
  for (int d = 0; d < 3; ++d) n[d] = nr[d];
  return phi;
}

/* Distance along the ray to the collider's surface (its far wall for a container, which the
 * camera sees from outside), or INFINITY. The level sets are exact distances or bounds of
 * them, so sphere tracing cannot step through a surface. */
static double trace(const mpm_collider_pose *pose, const double eye[3], const double dir[3],
                    double t_max, double eps, double n_hit[3]) {
  double x[3], n[3], t = 0;
  for (int d = 0; d < 3; ++d) x[d] = eye[d];
  double phi = phi_at(pose, x, n);
  int steps = 0;
  if (phi < 0) {
    if (!pose->collider->desc.inside_out) return INFINITY;  /* the camera is inside the solid */
    while (phi < 0 && steps++ < TRACE_STEPS && t < t_max) { /* enter the container */
      t += fmax(-phi, eps);
      for (int d = 0; d < 3; ++d) x[d] = eye[d] + t * dir[d];
      phi = phi_at(pose, x, n);
    }
  }
  /* a container's wall where the ray came in is not drawn: look for a surface only after the
     ray has been clearly inside the free region */
  int armed = !pose->collider->desc.inside_out || t == 0;
  while (steps++ < TRACE_STEPS && t < t_max) {
    if (phi > 2 * eps) armed = 1;
    if (armed && phi < eps) {
      memcpy(n_hit, n, sizeof n);
      return t;
    }
    t += fmax(phi, eps);
    for (int d = 0; d < 3; ++d) x[d] = eye[d] + t * dir[d];
    phi = phi_at(pose, x, n);
  }
  return INFINITY;
}

void mpm_render_background(mpm_image *img, const mpm_camera *cam, const mpm_ground *ground,
                           const double lo[3], const double hi[3],
                           const mpm_collider_pose *colliders, int collider_count,
                           int ground_collider) {
  const int w = img->width, h = img->height;
  double size = 0;
  for (int d = 0; d < 3; ++d) size = fmax(size, hi[d] - lo[d]);
  const double eps = TRACE_EPS_REL * size, far = 20 * size;
  const double cell = size / 16; /* ground checker */
  const double light[3] = {0.35, 0.85, 0.4};
#pragma omp parallel for schedule(dynamic, 4)
  for (int py = 0; py < h; ++py)
    for (int px = 0; px < w; ++px) {
      double dir[3];
      pixel_ray(cam, px, py, dir);
      /* sky: a soft vertical gradient */
      const double up = 0.5 * (dir[1] + 1);
      float rgb[3] = {(float)(0.55 + 0.25 * up), (float)(0.6 + 0.25 * up),
                      (float)(0.68 + 0.25 * up)};
      double best = INFINITY;
      /* ground plane */
      {
        const double t = mpm_ground_hit(ground, cam->eye, dir);
        if (t < far) {
          double p[3], u, v;
          for (int d = 0; d < 3; ++d) p[d] = cam->eye[d] + t * dir[d];
          mpm_ground_coords(ground, p, &u, &v);
          const double x = p[0], z = p[2];
          const int inside = x >= lo[0] && x <= hi[0] && z >= lo[2] && z <= hi[2];
          const int check = ((int)floor(u / cell) + (int)floor(v / cell)) & 1;
          const float g = inside ? (check ? 0.62f : 0.52f) : 0.42f;
          const float fog = (float)exp(-t / (6 * size));
          for (int c = 0; c < 3; ++c) rgb[c] = fog * g + (1 - fog) * rgb[c];
          best = t;
        }
      }
      /* colliders */
      for (int k = 0; k < collider_count; ++k) {
        if (k == ground_collider) continue; /* drawn as the ground plane */
        double n[3];
        const double t = trace(&colliders[k], cam->eye, dir, fmin(best, far), eps, n);
        if (t < best) {
          best = t;
          double ndl = 0, ndv = 0;
          for (int d = 0; d < 3; ++d) {
            ndl += n[d] * light[d];
            ndv -= n[d] * dir[d];
          }
          const double side = ndv < 0 ? -1 : 1; /* a far wall is seen from behind its normal */
          const float shade = (float)(0.35 + 0.55 * fmax(0, side * ndl));
          const float base[3] = {0.55f, 0.6f, 0.7f};
          for (int c = 0; c < 3; ++c) rgb[c] = shade * base[c];
        }
      }
      const size_t i = (size_t)py * (size_t)w + (size_t)px;
      memcpy(img->rgb + 3 * i, rgb, sizeof rgb);
      double z = 0;
      for (int d = 0; d < 3; ++d) z += dir[d] * cam->forward[d];
      img->depth[i] = isfinite(best) ? (float)(best * z) : INFINITY;
    }
}

/* Point p in camera space: along right, up and forward from the eye. */
static void to_camera(const mpm_camera *cam, const float p[3], double c[3]) {
  double rel[3], x = 0, y = 0, z = 0;
  for (int d = 0; d < 3; ++d) rel[d] = p[d] - cam->eye[d];
  for (int d = 0; d < 3; ++d) {
    x += rel[d] * cam->right[d];
    y += rel[d] * cam->up[d];
    z += rel[d] * cam->forward[d];
  }
  c[0] = x, c[1] = y, c[2] = z;
}

/* One particle into a colour and depth buffer. */
static void splat(int w, int h, float *rgb, float *depth, const mpm_camera *cam, const float p[3],
                  float r, const float col[3]) {
  double q[3];
  to_camera(cam, p, q);
  const double x = q[0], y = q[1], z = q[2];
  if (z <= r) return; /* behind or around the eye */
  const double cx = 0.5 * w + cam->focal * x / z, cy = 0.5 * h - cam->focal * y / z;
  const double rp = fmax(cam->focal * r / z, 0.5);
  const int x0 = (int)floor(cx - rp), x1 = (int)ceil(cx + rp);
  const int y0 = (int)floor(cy - rp), y1 = (int)ceil(cy + rp);
  if (x1 < 0 || y1 < 0 || x0 >= w || y0 >= h) return;
  /* light from the upper left, towards the viewer (camera space: x right, y up, z to eye) */
  const double L[3] = {-0.42, 0.62, 0.66};
  const float nearest = (float)(z - r); /* no pixel of the sphere is nearer */
  for (int py = y0 < 0 ? 0 : y0; py <= y1 && py < h; ++py)
    for (int px = x0 < 0 ? 0 : x0; px <= x1 && px < w; ++px) {
      const size_t i = (size_t)py * (size_t)w + (size_t)px;
      /* hidden whole: skip the square root (the depth below is never nearer, so the picture
         is the same) */
      if (nearest >= depth[i]) continue;
      const double dx = (px + 0.5 - cx) / rp, dy = (py + 0.5 - cy) / rp;
      const double d2 = dx * dx + dy * dy;
      if (d2 > 1) continue;
      const double nz = sqrt(1 - d2);
      const float dep = (float)(z - r * nz);
      if (dep >= depth[i]) continue;
      depth[i] = dep;
      const double ndl = dx * L[0] - dy * L[1] + nz * L[2];
      const float shade = (float)(0.3 + 0.7 * fmax(0, ndl));
      for (int c = 0; c < 3; ++c) rgb[3 * i + c] = shade * col[c];
    }
}

mpm_status mpm_render_particles(mpm_image *img, const mpm_camera *cam, size_t n, const float *xyz,
                                const float *radius, float radius_all, const float *rgb,
                                mpm_error *err) {
  const int w = img->width, h = img->height, T = mpm_thread_count();
  const size_t pixels = (size_t)w * (size_t)h;
  float *bufs = mpm_alloc((size_t)T * pixels * 4 * sizeof(float));
  if (!bufs) return mpm_error_set(err, MPM_ERR_NOMEM, "out of memory for %d render buffers", T);
#pragma omp parallel num_threads(T)
  {
    const int t = mpm_thread_id();
    float *col = bufs + (size_t)t * pixels * 4, *dep = col + 3 * pixels;
    for (size_t i = 0; i < pixels; ++i) dep[i] = img->depth[i]; /* the background occludes */
    /* contiguous particle ranges per thread: the merge below is then independent of
       scheduling, and ties in depth go to the lower thread, i.e. the lower particle range */
    const size_t a = n * (size_t)t / (size_t)T, b = n * (size_t)(t + 1) / (size_t)T;
    for (size_t p = a; p < b; ++p)
      splat(w, h, col, dep, cam, xyz + 3 * p, radius ? radius[p] : radius_all, rgb + 3 * p);
#pragma omp barrier
#pragma omp for schedule(static)
    for (size_t i = 0; i < pixels; ++i) {
      float best = img->depth[i];
      int who = -1;
      for (int k = 0; k < T; ++k) {
        const float dk = bufs[(size_t)k * pixels * 4 + 3 * pixels + i];
        if (dk < best) {
          best = dk;
          who = k;
        }
      }
      if (who >= 0) {
        memcpy(img->rgb + 3 * i, bufs + (size_t)who * pixels * 4 + 3 * i, 3 * sizeof(float));
        img->depth[i] = best;
      }
    }
  }
  mpm_free(bufs);
  return MPM_OK;
}

/* Camera-space projection: pixel coordinates and depth; 0 when behind the eye. */
static int project(const mpm_camera *cam, int w, int h, const float p[3], double out[3]) {
  double q[3];
  to_camera(cam, p, q);
  const double x = q[0], y = q[1], z = q[2];
  if (z <= 1e-6) return 0;
  out[0] = 0.5 * w + cam->focal * x / z;
  out[1] = 0.5 * h - cam->focal * y / z;
  out[2] = z;
  return 1;
}

void mpm_render_lines(mpm_image *img, const mpm_camera *cam, size_t n, const float *ab,
                      const float *rgb, float alpha) {
  const int w = img->width, h = img->height;
  /* serial: segments overlap and blending is order-dependent, so one order for any threads */
  for (size_t s = 0; s < n; ++s) {
    double a[3], b[3];
    if (!project(cam, w, h, ab + 6 * s, a) || !project(cam, w, h, ab + 6 * s + 3, b)) continue;
    const double len = fmax(fabs(b[0] - a[0]), fabs(b[1] - a[1]));
    const int steps = (int)fmin(ceil(len), 8192.0);
    for (int k = 0; k <= steps; ++k) {
      const double t = steps ? (double)k / steps : 0;
      const int px = (int)floor(a[0] + t * (b[0] - a[0])),
                py = (int)floor(a[1] + t * (b[1] - a[1]));
      if (px < 0 || py < 0 || px >= w || py >= h) continue;
      const size_t i = (size_t)py * (size_t)w + (size_t)px;
      /* perspective-correct depth along the segment, a little in front so a face's own edges
         show */
      const double z = 1 / ((1 - t) / a[2] + t / b[2]);
      if (z > img->depth[i] * 1.0005f) continue;
      for (int c = 0; c < 3; ++c)
        img->rgb[3 * i + c] = (1 - alpha) * img->rgb[3 * i + c] + alpha * rgb[3 * s + c];
    }
  }
}
