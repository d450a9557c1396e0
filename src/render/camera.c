/* camera.c - the pinhole camera: basis from eye and target, and automatic framing. */
#include "render/render.h"

#include <math.h>

static void normalize(double v[3]) {
  const double n = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  if (n > 0)
    for (int d = 0; d < 3; ++d) v[d] /= n;
}

static void cross(const double a[3], const double b[3], double c[3]) {
  c[0] = a[1] * b[2] - a[2] * b[1];
  c[1] = a[2] * b[0] - a[0] * b[2];
  c[2] = a[0] * b[1] - a[1] * b[0];
}

void mpm_camera_setup(mpm_camera *cam, int width, int height) {
  for (int d = 0; d < 3; ++d) cam->forward[d] = cam->target[d] - cam->eye[d];
  normalize(cam->forward);
  const double world_up[3] = {0, 1, 0}, world_z[3] = {0, 0, -1};
  cross(cam->forward, world_up, cam->right);
  if (fabs(cam->right[0]) + fabs(cam->right[1]) + fabs(cam->right[2]) < 1e-9)
    cross(cam->forward, world_z, cam->right); /* looking straight up or down */
  normalize(cam->right);
  cross(cam->right, cam->forward, cam->up);
  cam->width = width;
  cam->height = height;
  cam->focal = 0.5 * height / tan(0.5 * cam->fov_deg * 3.14159265358979323846 / 180);
}

void mpm_camera_default_view(double view[3]) {
  view[0] = 0.55, view[1] = 0.5, view[2] = 1.0; /* front right, above */
  normalize(view);
}

mpm_camera mpm_camera_frame_box(const double lo[3], const double hi[3], int width, int height) {
  mpm_camera cam;
  double c[3], r = 0;
  for (int d = 0; d < 3; ++d) {
    c[d] = 0.5 * (lo[d] + hi[d]);
    r += 0.25 * (hi[d] - lo[d]) * (hi[d] - lo[d]);
  }
  r = sqrt(r);
  cam.fov_deg = 35;
  /* the bounding sphere fits the narrower of the two fields of view */
  const double half_v = 0.5 * cam.fov_deg * 3.14159265358979323846 / 180;
  const double half_h = atan(tan(half_v) * width / height);
  const double dist = 0.85 * r / sin(fmin(half_v, half_h)); /* a box fills less than its sphere */
  double dir[3];
  mpm_camera_default_view(dir);
  for (int d = 0; d < 3; ++d) {
    cam.target[d] = c[d];
    cam.eye[d] = c[d] + dist * dir[d];
  }
  cam.target[1] -= 0.1 * r; /* look a little below the centre: floors matter */
  mpm_camera_setup(&cam, width, height);
  return cam;
}

/* The eye is c - D forward + a right + b up for the box's centre c and the fixed view
 * direction. A corner p (camera coordinates x, y, z relative to c) lands in the pixel columns
 * [u0, u1] (relative to the image's centre) when k0 (z + D) <= x - a <= k1 (z + D) with
 * k = u / focal: every corner bounds a from both sides by lines in D, so the nearest D that
 * admits an a is (A1 - A0) / (k1 - k0) with A1 = max(x - k1 z), A0 = min(x - k0 z). Rows
 * alike. Exact for a pinhole camera. */
static double fit_distance(const double *x, const double *z, double k0, double k1) {
  double A1 = -INFINITY, A0 = INFINITY;
  for (int k = 0; k < 8; ++k) {
    A1 = fmax(A1, x[k] - k1 * z[k]);
    A0 = fmin(A0, x[k] - k0 * z[k]);
  }
  return (A1 - A0) / (k1 - k0);
}

/* The shift a at distance D that centres the corners' projections (x - a) / (z + D) between
 * k0 and k1: their extremes' sum falls as a grows, so bisection finds it. */
static double centre_shift(const double *x, const double *z, double k0, double k1, double D) {
  double lo = -INFINITY, hi = INFINITY;
  for (int k = 0; k < 8; ++k) { /* a within the corners' own span keeps every one inside */
    lo = fmax(lo, x[k] - k1 * (z[k] + D));
    hi = fmin(hi, x[k] - k0 * (z[k] + D));
  }
  if (!(lo <= hi)) return 0.5 * (lo + hi);
  for (int it = 0; it < 100; ++it) {
    const double a = 0.5 * (lo + hi);
    double mn = INFINITY, mx = -INFINITY;
    for (int k = 0; k < 8; ++k) {
      const double q = (x[k] - a) / (z[k] + D);
      mn = fmin(mn, q), mx = fmax(mx, q);
    }
    if (mn + mx > k0 + k1)
      lo = a;
    else
      hi = a;
  }
  return 0.5 * (lo + hi);
}

mpm_camera mpm_camera_fit_box(const double lo[3], const double hi[3], int width, int height,
                              const int rect[4], const double view[3], double fov_deg) {
  mpm_camera cam;
  double c[3], r = 0;
  for (int d = 0; d < 3; ++d) {
    c[d] = 0.5 * (lo[d] + hi[d]);
    r += 0.25 * (hi[d] - lo[d]) * (hi[d] - lo[d]);
  }
  r = fmax(sqrt(r), 1e-6);
  cam.fov_deg = fov_deg > 0 ? fov_deg : 35;
  double dir[3];
  if (view) {
    for (int d = 0; d < 3; ++d) dir[d] = view[d];
    normalize(dir);
  } else {
    mpm_camera_default_view(dir);
  }
  for (int d = 0; d < 3; ++d) {
    cam.target[d] = c[d];
    cam.eye[d] = c[d] + dir[d];
  }
  mpm_camera_setup(&cam, width, height); /* the basis, for the fit below */
  double x[8], y[8], z[8];
  for (int k = 0; k < 8; ++k) {
    double p[3] = {k & 1 ? hi[0] : lo[0], k & 2 ? hi[1] : lo[1], k & 4 ? hi[2] : lo[2]};
    x[k] = y[k] = z[k] = 0;
    for (int d = 0; d < 3; ++d) {
      x[k] += (p[d] - c[d]) * cam.right[d];
      y[k] += (p[d] - c[d]) * cam.up[d];
      z[k] += (p[d] - c[d]) * cam.forward[d];
    }
  }
  /* pixel bounds as offsets from the centre, up positive for the rows */
  const double f = cam.focal;
  const double u0 = (rect[0] - 0.5 * width) / f, u1 = (rect[2] - 0.5 * width) / f;
  const double v0 = (0.5 * height - rect[3]) / f, v1 = (0.5 * height - rect[1]) / f;
  double D = fmax(fmax(fit_distance(x, z, u0, u1), fit_distance(y, z, v0, v1)), 0);
  double zmin = INFINITY;
  for (int k = 0; k < 8; ++k) zmin = fmin(zmin, z[k]);
  D = fmax(D, 0.05 * r - zmin); /* never inside the box */
  const double a = centre_shift(x, z, u0, u1, D), b = centre_shift(y, z, v0, v1, D);
  for (int d = 0; d < 3; ++d) {
    cam.target[d] = c[d] + a * cam.right[d] + b * cam.up[d];
    cam.eye[d] = cam.target[d] - D * cam.forward[d];
  }
  mpm_camera_setup(&cam, width, height);
  return cam;
}
