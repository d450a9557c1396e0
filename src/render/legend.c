/* legend.c - the colour bar (or the key of categories) and the time label over a picture.
 *
 * Both sit on a light, translucent panel, so dark text reads over sky, ground and material
 * alike. Sizes follow the font's scale (overlay.h), which grows with the image's height, so a
 * legend covers about the same share of a small preview and of a 1080p frame. The boxes are
 * computed by the same functions the drawing uses, so the camera's framing can keep clear of
 * exactly what is drawn. */
#include "render/overlay.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

static const float INK[3] = {0.015f, 0.015f, 0.02f};
static const float PANEL[3] = {1, 1, 1};
#define PANEL_ALPHA 0.62f

int mpm_overlay_scale(int height) {
  const int s = (height + 180) / 360;
  return s < 1 ? 1 : s;
}

/* A value as a label: three significant digits, exponents without '+' or leading zeros. */
static void format_value(double v, char *buf, size_t cap) {
  char raw[48];
  snprintf(raw, sizeof raw, "%.3g", fabs(v) < 1e-12 ? 0.0 : v);
  size_t o = 0;
  for (const char *p = raw; *p && o + 1 < cap; ++p) {
    buf[o++] = *p;
    if (*p == 'e') {
      ++p;
      if (*p == '-') buf[o++] = '-';
      if (*p == '+' || *p == '-') ++p;
      while (*p == '0' && p[1]) ++p;
      --p;
    }
  }
  buf[o] = 0;
}

static int category_name(const mpm_legend *lg, int k, char *buf, size_t cap) {
  if (lg->names && lg->names[k])
    snprintf(buf, cap, "%s", lg->names[k]);
  else
    snprintf(buf, cap, "%d", k);
  return (int)strlen(buf);
}

/* Everything the layout depends on, in pixels. */
typedef struct layout {
  int s, pad, line, bar_w, bar_h, label_w, box_w, box_h;
} layout;

static layout layout_of(const mpm_legend *lg, int height) {
  layout L;
  L.s = mpm_overlay_scale(height);
  L.pad = 4 * L.s;
  L.line = (MPM_FONT_H + 3) * L.s;
  const int title_w = mpm_text_width(lg->title ? lg->title : "", L.s);
  int inner;
  if (lg->map == MPM_CMAP_CATEGORY) {
    L.label_w = 0;
    for (int k = 0; k < lg->count; ++k) {
      char name[160];
      category_name(lg, k, name, sizeof name);
      const int nw = mpm_text_width(name, L.s);
      if (nw > L.label_w) L.label_w = nw;
    }
    L.bar_w = 7 * L.s; /* the swatch */
    L.bar_h = 0;
    inner = L.bar_w + L.pad + L.label_w;
    L.box_h = L.pad + L.line * (1 + lg->count) + L.pad;
  } else {
    char a[48], b[48];
    format_value(lg->lo, a, sizeof a);
    format_value(lg->hi, b, sizeof b);
    const int wa = mpm_text_width(a, L.s), wb = mpm_text_width(b, L.s);
    L.label_w = wa > wb ? wa : wb;
    L.bar_w = 10 * L.s;
    L.bar_h = (int)(0.36 * height);
    if (L.bar_h < 4 * L.line) L.bar_h = 4 * L.line;
    inner = L.label_w + L.pad + L.bar_w;
    /* title, half a glyph above the bar for its top label, the bar, half a glyph below */
    L.box_h = L.pad + L.line + MPM_FONT_H * L.s / 2 + L.bar_h + MPM_FONT_H * L.s / 2 + 2 * L.pad;
  }
  if (title_w > inner) inner = title_w;
  L.box_w = L.pad + inner + L.pad;
  return L;
}

mpm_overlay_box mpm_legend_box(const mpm_legend *lg, int width, int height) {
  const layout L = layout_of(lg, height);
  const mpm_overlay_box b = {width - L.pad - L.box_w, L.pad, width - L.pad, L.pad + L.box_h};
  return b;
}

mpm_overlay_box mpm_legend_bar(const mpm_legend *lg, int width, int height) {
  const layout L = layout_of(lg, height);
  const mpm_overlay_box box = mpm_legend_box(lg, width, height);
  mpm_overlay_box b = {box.x1, box.y0, box.x1, box.y0}; /* empty */
  if (lg->map == MPM_CMAP_CATEGORY) return b;
  b.x1 = box.x1 - L.pad;
  b.x0 = b.x1 - L.bar_w;
  b.y0 = box.y0 + L.pad + L.line + MPM_FONT_H * L.s / 2;
  b.y1 = b.y0 + L.bar_h;
  return b;
}

static void panel(mpm_image *img, mpm_overlay_box b) {
  for (int y = b.y0 < 0 ? 0 : b.y0; y < b.y1 && y < img->height; ++y)
    for (int x = b.x0 < 0 ? 0 : b.x0; x < b.x1 && x < img->width; ++x) {
      float *p = img->rgb + 3 * ((size_t)y * (size_t)img->width + (size_t)x);
      for (int c = 0; c < 3; ++c) p[c] = (1 - PANEL_ALPHA) * p[c] + PANEL_ALPHA * PANEL[c];
    }
}

static void fill(mpm_image *img, mpm_overlay_box b, const float rgb[3]) {
  for (int y = b.y0 < 0 ? 0 : b.y0; y < b.y1 && y < img->height; ++y)
    for (int x = b.x0 < 0 ? 0 : b.x0; x < b.x1 && x < img->width; ++x)
      memcpy(img->rgb + 3 * ((size_t)y * (size_t)img->width + (size_t)x), rgb, 3 * sizeof(float));
}

void mpm_render_legend(mpm_image *img, const mpm_legend *lg) {
  const layout L = layout_of(lg, img->height);
  const mpm_overlay_box box = mpm_legend_box(lg, img->width, img->height);
  panel(img, box);
  const int title_w = mpm_text_width(lg->title ? lg->title : "", L.s);
  mpm_render_text(img, box.x1 - L.pad - title_w, box.y0 + L.pad, L.s, lg->title ? lg->title : "",
                  INK);
  if (lg->map == MPM_CMAP_CATEGORY) {
    for (int k = 0; k < lg->count; ++k) {
      const int y = box.y0 + L.pad + L.line * (k + 1);
      const int x = box.x0 + L.pad;
      float rgb[3];
      mpm_colormap_eval(MPM_CMAP_CATEGORY, k, rgb);
      const mpm_overlay_box sw = {x, y, x + L.bar_w, y + L.bar_w};
      fill(img, sw, rgb);
      char name[160];
      category_name(lg, k, name, sizeof name);
      mpm_render_text(img, x + L.bar_w + L.pad, y, L.s, name, INK);
    }
    return;
  }
  const mpm_overlay_box bar = mpm_legend_bar(lg, img->width, img->height);
  /* a thin dark frame sets the bar off the panel, whose grey its middle colours may match */
  const mpm_overlay_box frame = {bar.x0 - L.s, bar.y0 - L.s, bar.x1 + L.s, bar.y1 + L.s};
  const float edge[3] = {0.1f, 0.1f, 0.11f};
  fill(img, frame, edge);
  const int rows = bar.y1 - bar.y0;
  for (int y = bar.y0; y < bar.y1; ++y) { /* hi at the top */
    const double t = rows > 1 ? (double)(bar.y1 - 1 - y) / (rows - 1) : 0;
    float rgb[3];
    mpm_colormap_eval(lg->map, t, rgb);
    const mpm_overlay_box row = {bar.x0, y, bar.x1, y + 1};
    fill(img, row, rgb);
  }
  char a[48], b[48];
  format_value(lg->hi, b, sizeof b);
  format_value(lg->lo, a, sizeof a);
  const int half = MPM_FONT_H * L.s / 2;
  mpm_render_text(img, bar.x0 - L.pad - mpm_text_width(b, L.s), bar.y0 - half, L.s, b, INK);
  mpm_render_text(img, bar.x0 - L.pad - mpm_text_width(a, L.s), bar.y1 - half, L.s, a, INK);
}

mpm_overlay_box mpm_label_box(const char *text, int width, int height) {
  (void)width;
  const int s = mpm_overlay_scale(height), pad = 4 * s;
  const mpm_overlay_box b = {pad, pad, pad + 2 * pad + mpm_text_width(text, s),
                             pad + 2 * pad + MPM_FONT_H * s};
  return b;
}

void mpm_render_label(mpm_image *img, const char *text) {
  const int s = mpm_overlay_scale(img->height), pad = 4 * s;
  const mpm_overlay_box b = mpm_label_box(text, img->width, img->height);
  panel(img, b);
  mpm_render_text(img, b.x0 + pad, b.y0 + pad, s, text, INK);
}
