/* colormap.c - colour maps as piecewise-linear tables in linear RGB.
 *
 * viridis: control points of matplotlib's viridis (van der Walt and Smith 2015), sampled at
 * nine evenly spaced stops and converted from sRGB to linear; coolwarm: Moreland's diverging
 * map ("Diverging Color Maps for Scientific Visualization", 2009) at five stops; category: a
 * ten-colour qualitative palette, label k taking colour k mod 10. */
#include "render/render.h"

#include <math.h>
#include <string.h>

/* sRGB 0..255 stops */
static const unsigned char VIRIDIS[9][3] = {{68, 1, 84},    {71, 44, 122},  {59, 81, 139},
                                            {44, 113, 142}, {33, 144, 141}, {39, 173, 129},
                                            {92, 200, 99},  {170, 220, 50}, {253, 231, 37}};
static const unsigned char COOLWARM[5][3] = {
    {59, 76, 192}, {141, 176, 254}, {221, 221, 221}, {244, 154, 123}, {180, 4, 38}};
static const unsigned char CATEGORY[10][3] = {
    {31, 119, 180}, {255, 127, 14},  {44, 160, 44},   {214, 39, 40},  {148, 103, 189},
    {140, 86, 75},  {227, 119, 194}, {127, 127, 127}, {188, 189, 34}, {23, 190, 207}};

static float linear(unsigned char c) {
  const double s = c / 255.0;
  return (float)(s <= 0.04045 ? s / 12.92 : pow((s + 0.055) / 1.055, 2.4));
}

static void table(const unsigned char (*stops)[3], int n, double t, float rgb[3]) {
  t = t < 0 ? 0 : (t > 1 ? 1 : t);
  if (t != t) t = 0;
  const double x = t * (n - 1);
  int i = (int)x;
  if (i >= n - 1) i = n - 2;
  const double f = x - i;
  for (int c = 0; c < 3; ++c)
    rgb[c] = (float)((1 - f) * linear(stops[i][c]) + f * linear(stops[i + 1][c]));
}

void mpm_colormap_eval(mpm_colormap map, double t, float rgb[3]) {
  switch (map) {
  case MPM_CMAP_COOLWARM:
    table(COOLWARM, 5, t, rgb);
    break;
  case MPM_CMAP_CATEGORY: {
    int k = (int)lrint(t);
    k = ((k % 10) + 10) % 10;
    for (int c = 0; c < 3; ++c) rgb[c] = linear(CATEGORY[k][c]);
    break;
  }
  default:
    table(VIRIDIS, 9, t, rgb);
    break;
  }
}

int mpm_colormap_of(const char *name) {
  if (!strcmp(name, "viridis")) return MPM_CMAP_VIRIDIS;
  if (!strcmp(name, "coolwarm")) return MPM_CMAP_COOLWARM;
  if (!strcmp(name, "category")) return MPM_CMAP_CATEGORY;
  return -1;
}
