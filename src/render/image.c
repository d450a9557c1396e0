/* image.c - the float framebuffer, its 8-bit sRGB pixels and their PNG encoding (libpng),
 * written atomically. */
#include "render/render.h"
#include "core/alloc.h"
#include "io/io.h"

#include <math.h>
#include <png.h>
#include <stdlib.h>
#include <string.h>

mpm_status mpm_image_init(mpm_image *img, int width, int height, mpm_error *err) {
  memset(img, 0, sizeof *img);
  if (width < 1 || height < 1 || width > 16384 || height > 16384)
    return mpm_error_set(err, MPM_ERR_INVALID, "image size %dx%d out of range (1..16384)", width,
                         height);
  const size_t n = (size_t)width * (size_t)height;
  img->rgb = mpm_calloc(3 * n, sizeof(float));
  img->depth = mpm_alloc(n * sizeof(float));
  if (!img->rgb || !img->depth) {
    mpm_image_free(img);
    return mpm_error_set(err, MPM_ERR_NOMEM, "out of memory for a %dx%d image", width, height);
  }
  for (size_t i = 0; i < n; ++i) img->depth[i] = INFINITY;
  img->width = width;
  img->height = height;
  return MPM_OK;
}

void mpm_image_free(mpm_image *img) {
  mpm_free(img->rgb);
  mpm_free(img->depth);
  memset(img, 0, sizeof *img);
}

/* Linear [0, 1] to 8-bit sRGB (IEC 61966-2-1). */
static unsigned char to_srgb8(float v) {
  v = v < 0 ? 0 : (v > 1 ? 1 : v);
  const double s = v <= 0.0031308 ? 12.92 * v : 1.055 * pow(v, 1 / 2.4) - 0.055;
  return (unsigned char)lrint(s * 255);
}

void mpm_image_to_srgb8(const mpm_image *img, unsigned char *rgb) {
  const size_t n = 3 * (size_t)img->width * (size_t)img->height;
  for (size_t i = 0; i < n; ++i) rgb[i] = to_srgb8(img->rgb[i]);
}

mpm_status mpm_image_write_png(const mpm_image *img, const char *path, mpm_error *err) {
  mpm_atomic_file af;
  mpm_status st = mpm_atomic_open(&af, path, err);
  if (st != MPM_OK) return st;
  const int w = img->width, h = img->height;
  unsigned char *row = mpm_alloc((size_t)w * 3);
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
  png_infop info = png ? png_create_info_struct(png) : NULL;
  if (!row || !png || !info) {
    if (png) png_destroy_write_struct(&png, info ? &info : NULL);
    mpm_free(row);
    mpm_atomic_abort(&af);
    return mpm_error_set(err, MPM_ERR_NOMEM, "%s: out of memory for the PNG encoder", path);
  }
  if (setjmp(png_jmpbuf(png))) { /* libpng reports its errors by longjmp */
    png_destroy_write_struct(&png, &info);
    mpm_free(row);
    mpm_atomic_abort(&af);
    return mpm_error_set(err, MPM_ERR_IO, "%s: PNG encoding failed", path);
  }
  png_init_io(png, af.fp);
  png_set_IHDR(png, info, (png_uint_32)w, (png_uint_32)h, 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_set_sRGB(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
  png_write_info(png, info);
  for (int y = 0; y < h; ++y) {
    const float *src = img->rgb + (size_t)y * (size_t)w * 3;
    for (int x = 0; x < 3 * w; ++x) row[x] = to_srgb8(src[x]);
    png_write_row(png, row);
  }
  png_write_end(png, info);
  png_destroy_write_struct(&png, &info);
  mpm_free(row);
  return mpm_atomic_commit(&af, err);
}
