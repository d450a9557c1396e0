/* ground.c - the plane the material stands on: drawn checkered, with the shadow on it, and
 * reached down to by the camera's framing. A level floor (the domain's, or a half-space collider
 * facing up) or a tilted half-space collider (a slope): the plane is kept as a point, its unit
 * normal and two unit tangents, so the background, the shadow and the framing treat both alike. */
#include "render/render.h"

#include <math.h>

static double dot3(const double a[3], const double b[3]) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

void mpm_ground_make(mpm_ground *g, const double point[3], const double normal[3]) {
  double n = sqrt(dot3(normal, normal));
  for (int d = 0; d < 3; ++d) {
    g->point[d] = point[d];
    g->normal[d] = n > 0 ? normal[d] / n : (d == 1);
  }
  /* e1: the x axis in the plane (for a level floor exactly x, so its checkers are x and z) */
  const double *m = g->normal;
  double e1[3] = {1 - m[0] * m[0], -m[0] * m[1], -m[0] * m[2]};
  n = sqrt(dot3(e1, e1));
  if (n < 1e-6) e1[0] = 0, e1[1] = 0, e1[2] = 1, n = 1; /* a wall facing x: not a ground */
  for (int d = 0; d < 3; ++d) g->e1[d] = e1[d] / n;
  /* e2 = e1 x normal: z for a level floor */
  g->e2[0] = g->e1[1] * m[2] - g->e1[2] * m[1];
  g->e2[1] = g->e1[2] * m[0] - g->e1[0] * m[2];
  g->e2[2] = g->e1[0] * m[1] - g->e1[1] * m[0];
  g->level = m[0] == 0 && m[2] == 0;
}

void mpm_ground_level(mpm_ground *g, double y) {
  const double p[3] = {0, y, 0}, n[3] = {0, 1, 0};
  mpm_ground_make(g, p, n);
}

double mpm_ground_height(const mpm_ground *g, const double x[3]) {
  if (g->level) return x[1] - g->point[1];
  const double r[3] = {x[0] - g->point[0], x[1] - g->point[1], x[2] - g->point[2]};
  return dot3(r, g->normal);
}

double mpm_ground_y_at(const mpm_ground *g, double x, double z) {
  const double *n = g->normal, *p = g->point;
  return p[1] - ((x - p[0]) * n[0] + (z - p[2]) * n[2]) / n[1];
}

double mpm_ground_hit(const mpm_ground *g, const double eye[3], const double dir[3]) {
  const double dn = dot3(dir, g->normal);
  if (!(dn < -1e-9)) return INFINITY; /* parallel, or seen from below */
  const double r[3] = {g->point[0] - eye[0], g->point[1] - eye[1], g->point[2] - eye[2]};
  const double t = g->level ? (g->point[1] - eye[1]) / dir[1] : dot3(r, g->normal) / dn;
  return t > 0 ? t : INFINITY;
}

void mpm_ground_coords(const mpm_ground *g, const double x[3], double *u, double *w) {
  if (g->level) {
    *u = x[0], *w = x[2];
    return;
  }
  const double r[3] = {x[0] - g->point[0], x[1] - g->point[1], x[2] - g->point[2]};
  *u = dot3(r, g->e1), *w = dot3(r, g->e2);
}

void mpm_ground_point(const mpm_ground *g, double u, double w, double x[3]) {
  if (g->level) {
    x[0] = u, x[1] = g->point[1], x[2] = w;
    return;
  }
  for (int d = 0; d < 3; ++d) x[d] = g->point[d] + u * g->e1[d] + w * g->e2[d];
}
