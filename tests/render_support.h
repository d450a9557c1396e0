/* render_support.h - reading back the renderer's PNGs in tests (test_render*.c), with libpng's
 * simplified API, independently of the writer's encoder settings; and the 8-bit sRGB a linear
 * colour is written as, to compare pixels with colour maps. */
#ifndef MPM_TEST_RENDER_SUPPORT_H
#define MPM_TEST_RENDER_SUPPORT_H

#include "support.h"

#include <math.h>
#include <png.h>
#include <stdlib.h>
#include <string.h>

typedef struct rgb_image {
  int w, h;
  unsigned char *px; /* w * h * 3 */
} rgb_image;

static inline rgb_image read_png(const char *path) {
  rgb_image im = {0, 0, NULL};
  png_image pi;
  memset(&pi, 0, sizeof pi);
  pi.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&pi, path)) fail_msg("%s: not a PNG: %s", path, pi.message);
  pi.format = PNG_FORMAT_RGB;
  im.w = (int)pi.width;
  im.h = (int)pi.height;
  im.px = malloc(PNG_IMAGE_SIZE(pi));
  assert_non_null(im.px);
  if (!png_image_finish_read(&pi, NULL, im.px, 0, NULL)) fail_msg("%s: %s", path, pi.message);
  return im;
}

static inline const unsigned char *pixel(const rgb_image *im, int x, int y) {
  return im->px + 3 * ((size_t)y * (size_t)im->w + (size_t)x);
}

/* Is the pixel grey (sky or ground), i.e. no colour-mapped particle? */
static inline int greyish(const rgb_image *im, int x, int y) {
  const unsigned char *p = pixel(im, x, y);
  const int mx = p[0] > p[1] ? (p[0] > p[2] ? p[0] : p[2]) : (p[1] > p[2] ? p[1] : p[2]);
  const int mn = p[0] < p[1] ? (p[0] < p[2] ? p[0] : p[2]) : (p[1] < p[2] ? p[1] : p[2]);
  return mx - mn < 40;
}

/* A linear channel as the PNG stores it (IEC 61966-2-1). */
static inline int srgb8(float v) {
  v = v < 0 ? 0 : (v > 1 ? 1 : v);
  const double s = v <= 0.0031308 ? 12.92 * v : 1.055 * pow(v, 1 / 2.4) - 0.055;
  return (int)lrint(s * 255);
}

/* Whether the pixel is the linear colour rgb, within tol levels per channel. */
static inline int pixel_is(const rgb_image *im, int x, int y, const float rgb[3], int tol) {
  const unsigned char *p = pixel(im, x, y);
  for (int c = 0; c < 3; ++c)
    if (abs(p[c] - srgb8(rgb[c])) > tol) return 0;
  return 1;
}

#endif
