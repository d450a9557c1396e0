/* overlay.h - what the renderer draws over the picture of a frame: text in a small bitmap
 * font (font.c), the colour bar or key of the field the particles are coloured by, and a
 * label such as the frame's time (legend.c). All in pixels of the image, drawn into its
 * linear colour buffer after the scene, so the depth buffer is left as it is. */
#ifndef MPM_RENDER_OVERLAY_H
#define MPM_RENDER_OVERLAY_H

#include "render/render.h"

#define MPM_FONT_W 5       /* glyph columns */
#define MPM_FONT_H 8       /* glyph rows: 7 above the baseline, 1 for descenders */
#define MPM_FONT_ADVANCE 6 /* columns from one glyph to the next */

/* Whether column col, row row (from the top) of character c's glyph is ink. A character the
 * font lacks is drawn as '?'. */
int mpm_font_pixel(char c, int col, int row);
/* Width in pixels of text drawn at an integer scale (each glyph pixel a scale x scale square). */
int mpm_text_width(const char *text, int scale);
/* text with its top-left corner at pixel (x, y), in linear colour rgb; clipped to the image. */
void mpm_render_text(mpm_image *img, int x, int y, int scale, const char *text, const float rgb[3]);

/* A rectangle of pixels [x0, x1) x [y0, y1). */
typedef struct mpm_overlay_box {
  int x0, y0, x1, y1;
} mpm_overlay_box;

/* The font scale for an image of this height: 1 up to 539 rows, 2 at 720, 3 at 1080. */
int mpm_overlay_scale(int height);

/* The key of the colours, in the top-right corner: for a continuous map a vertical colour bar
 * from lo (bottom) to hi (top) with both ends labelled; for MPM_CMAP_CATEGORY a swatch and a
 * name per label 0..count-1. The title names the field and its units. */
typedef struct mpm_legend {
  mpm_colormap map;
  const char *title;
  double lo, hi;
  int count;                /* categories */
  const char *const *names; /* count names, or NULL for "0", "1", ... */
} mpm_legend;

/* The corner the legend covers (the camera's framing keeps the material out of it), and the
 * strip of its colour bar (empty for a key of categories). */
mpm_overlay_box mpm_legend_box(const mpm_legend *legend, int width, int height);
mpm_overlay_box mpm_legend_bar(const mpm_legend *legend, int width, int height);
void mpm_render_legend(mpm_image *img, const mpm_legend *legend);

/* A line of text on a light panel in the top-left corner (the frame's time), and the box it
 * covers. */
mpm_overlay_box mpm_label_box(const char *text, int width, int height);
void mpm_render_label(mpm_image *img, const char *text);

#endif
