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
  double dir[3] = {0.55, 0.5, 1.0};                         /* front right, above */
  normalize(dir);
  for (int d = 0; d < 3; ++d) {
    cam.target[d] = c[d];
    cam.eye[d] = c[d] + dist * dir[d];
  }
  cam.target[1] -= 0.1 * r; /* look a little below the centre: floors matter */
  mpm_camera_setup(&cam, width, height);
  return cam;
}
