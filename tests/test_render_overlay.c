/* test_render_overlay.c - the renderer's pieces behind `mpm render`'s default picture, tested
 * on the library: the bitmap font (every glyph distinct, digits drawn pixel for pixel as their
 * glyphs), the colour bar (the map's colours from bottom to top of its strip, labels beside
 * it) and the key of categories, the camera that fits a box into a rectangle of the picture
 * (every corner inside, the rectangle filled along one axis), and the ground's shadow (darker
 * ground under a body, never lighter, sky untouched, darker where it rests than when lifted). */
#include "support.h"
#include "render/overlay.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static const char *const CHARSET =
    "0123456789ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz .,:=-+()/%_^*'?";

static int same_glyph(char a, char b) {
  for (int r = 0; r < MPM_FONT_H; ++r)
    for (int c = 0; c < MPM_FONT_W; ++c)
      if (mpm_font_pixel(a, c, r) != mpm_font_pixel(b, c, r)) return 0;
  return 1;
}

static void test_font_glyphs(void **state) {
  (void)state;
  const size_t n = strlen(CHARSET);
  for (size_t i = 0; i < n; ++i) {
    int ink = 0;
    for (int r = 0; r < MPM_FONT_H; ++r)
      for (int c = 0; c < MPM_FONT_W; ++c) ink += mpm_font_pixel(CHARSET[i], c, r);
    if (CHARSET[i] != ' ' && ink < 2) fail_msg("glyph '%c' has %d pixels of ink", CHARSET[i], ink);
    for (size_t j = 0; j < i; ++j)
      if (same_glyph(CHARSET[i], CHARSET[j]))
        fail_msg("glyphs '%c' and '%c' are the same", CHARSET[i], CHARSET[j]);
  }
  assert_true(same_glyph('~', '?')); /* what the font lacks is a question mark */
  assert_true(same_glyph('\t', '?'));
  assert_int_equal(mpm_font_pixel('1', -1, 0), 0); /* outside the cell */
  assert_int_equal(mpm_font_pixel('1', 0, MPM_FONT_H), 0);
  assert_int_equal(mpm_text_width("12", 3), 3 * (2 * MPM_FONT_ADVANCE - 1));
  assert_int_equal(mpm_text_width("", 3), 0);
}

/* The digits drawn at scale 2: each cell of the picture is its glyph, square for square, and
 * the ten cells differ from each other. */
static void test_font_draws_digits(void **state) {
  (void)state;
  const char *digits = "0123456789";
  const int s = 2, w = mpm_text_width(digits, s) + 4, h = MPM_FONT_H * s + 4;
  mpm_image img;
  mpm_error err;
  mpm_error_clear(&err);
  assert_int_equal(mpm_image_init(&img, w, h, &err), MPM_OK);
  const float white[3] = {1, 1, 1};
  mpm_render_text(&img, 2, 2, s, digits, white);
  static unsigned char cell[10][MPM_FONT_H * 2][MPM_FONT_W * 2];
  for (int k = 0; k < 10; ++k)
    for (int y = 0; y < MPM_FONT_H * s; ++y)
      for (int x = 0; x < MPM_FONT_W * s; ++x) {
        const int px = 2 + k * MPM_FONT_ADVANCE * s + x, py = 2 + y;
        const float v = img.rgb[3 * ((size_t)py * (size_t)w + (size_t)px)];
        cell[k][y][x] = v > 0.5f;
        if (cell[k][y][x] != mpm_font_pixel(digits[k], x / s, y / s))
          fail_msg("digit %c: pixel (%d, %d) is not its glyph's", digits[k], x, y);
      }
  for (int a = 0; a < 10; ++a)
    for (int b = 0; b < a; ++b)
      if (!memcmp(cell[a], cell[b], sizeof cell[a])) fail_msg("digits %d and %d look alike", a, b);
  /* the spacing column between glyphs stays empty, and text is clipped at the edges */
  for (int y = 0; y < h; ++y) assert_true(img.rgb[3 * ((size_t)y * (size_t)w + 2 + 5 * s)] == 0);
  mpm_render_text(&img, -7, h - 3, 4, "88", white); /* mostly outside: no crash */
  mpm_image_free(&img);
}

static void fill_grey(mpm_image *img) {
  for (size_t i = 0; i < 3 * (size_t)img->width * (size_t)img->height; ++i) img->rgb[i] = 0.3f;
}

static int close_to(const float *a, const float b[3], float tol) {
  return fabsf(a[0] - b[0]) < tol && fabsf(a[1] - b[1]) < tol && fabsf(a[2] - b[2]) < tol;
}

static void test_colour_bar(void **state) {
  (void)state;
  const int w = 640, h = 360;
  mpm_image img;
  mpm_error err;
  mpm_error_clear(&err);
  assert_int_equal(mpm_image_init(&img, w, h, &err), MPM_OK);
  fill_grey(&img);
  const mpm_legend lg = {MPM_CMAP_VIRIDIS, "speed (m/s)", 0, 2.5, 0, NULL};
  const mpm_overlay_box box = mpm_legend_box(&lg, w, h), bar = mpm_legend_bar(&lg, w, h);
  /* the bar inside the box, in the top-right corner, a tall strip */
  assert_true(box.x0 >= 0 && box.x1 <= w && box.y0 >= 0 && box.y1 <= h);
  assert_true(box.x1 > w - 20 && box.y0 < 20);
  assert_true(bar.x0 >= box.x0 && bar.x1 <= box.x1 && bar.y0 >= box.y0 && bar.y1 <= box.y1);
  assert_true(bar.y1 - bar.y0 > h / 4 && bar.x1 > bar.x0);
  mpm_render_legend(&img, &lg);
  const int cx = (bar.x0 + bar.x1) / 2;
  for (int y = bar.y0; y < bar.y1; ++y) {
    const double t = (double)(bar.y1 - 1 - y) / (bar.y1 - bar.y0 - 1);
    float want[3];
    mpm_colormap_eval(MPM_CMAP_VIRIDIS, t, want);
    const float *got = img.rgb + 3 * ((size_t)y * (size_t)w + (size_t)cx);
    if (!close_to(got, want, 1e-5f)) fail_msg("bar row %d is not viridis(%.3f)", y, t);
  }
  /* ink of the labels left of the bar and of the title above it */
  int left = 0, above = 0;
  for (int y = box.y0; y < box.y1; ++y)
    for (int x = box.x0; x < box.x1; ++x) {
      const float *p = img.rgb + 3 * ((size_t)y * (size_t)w + (size_t)x);
      if (p[0] > 0.05f) continue;
      left += x < bar.x0 && y >= bar.y0 - 8;
      above += y < bar.y0 - 8;
    }
  print_message("label ink %d, title ink %d pixels\n", left, above);
  assert_true(left > 20 && above > 30);
  /* outside the box nothing changed */
  assert_true(img.rgb[0] == 0.3f &&
              img.rgb[3 * ((size_t)(h - 1) * (size_t)w + (size_t)w - 1)] == 0.3f);

  /* a key of three categories: each swatch in its colour, no bar */
  fill_grey(&img);
  const char *names[3] = {"jello", NULL, "sand"};
  const mpm_legend key = {MPM_CMAP_CATEGORY, "material", 0, 1, 3, names};
  const mpm_overlay_box kb = mpm_legend_box(&key, w, h), none = mpm_legend_bar(&key, w, h);
  assert_true(none.x0 == none.x1);
  mpm_render_legend(&img, &key);
  for (int k = 0; k < 3; ++k) {
    float want[3];
    mpm_colormap_eval(MPM_CMAP_CATEGORY, k, want);
    int found = 0;
    for (int y = kb.y0; y < kb.y1; ++y)
      for (int x = kb.x0; x < kb.x1; ++x)
        found += close_to(img.rgb + 3 * ((size_t)y * (size_t)w + (size_t)x), want, 1e-6f);
    if (found < 9) fail_msg("category %d: %d pixels of its colour in the key", k, found);
  }
  mpm_image_free(&img);
}

/* The time label: on its panel in the top-left corner, the text's glyphs. */
static void test_label(void **state) {
  (void)state;
  const int w = 320, h = 180;
  mpm_image img;
  mpm_error err;
  mpm_error_clear(&err);
  assert_int_equal(mpm_image_init(&img, w, h, &err), MPM_OK);
  fill_grey(&img);
  const char *text = "t = 1.250 s, frame 50";
  const mpm_overlay_box b = mpm_label_box(text, w, h);
  mpm_render_label(&img, text);
  const int s = mpm_overlay_scale(h), pad = 4 * s;
  assert_true(b.x0 < 10 && b.y0 < 10 && b.x1 > b.x0 + mpm_text_width(text, s));
  for (int k = 0; text[k]; ++k)
    for (int r = 0; r < MPM_FONT_H; ++r)
      for (int c = 0; c < MPM_FONT_W; ++c) {
        const int x = b.x0 + pad + (k * MPM_FONT_ADVANCE + c) * s, y = b.y0 + pad + r * s;
        const float v = img.rgb[3 * ((size_t)y * (size_t)w + (size_t)x)];
        if ((v < 0.1f) != mpm_font_pixel(text[k], c, r))
          fail_msg("label character %d ('%c'), glyph pixel (%d, %d)", k, text[k], c, r);
      }
  assert_int_equal(mpm_overlay_scale(120), 1);
  assert_int_equal(mpm_overlay_scale(720), 2);
  assert_int_equal(mpm_overlay_scale(1080), 3);
  mpm_image_free(&img);
}

/* Pixel coordinates of p through cam. */
static void project(const mpm_camera *cam, const double p[3], double *u, double *v) {
  double q[3] = {0, 0, 0};
  for (int d = 0; d < 3; ++d) {
    q[0] += (p[d] - cam->eye[d]) * cam->right[d];
    q[1] += (p[d] - cam->eye[d]) * cam->up[d];
    q[2] += (p[d] - cam->eye[d]) * cam->forward[d];
  }
  assert_true(q[2] > 0);
  *u = 0.5 * cam->width + cam->focal * q[0] / q[2];
  *v = 0.5 * cam->height - cam->focal * q[1] / q[2];
}

static void test_camera_fit(void **state) {
  (void)state;
  const double boxes[2][6] = {{0, 0, 0, 1, 1, 1}, {2, 0.1, -1, 2.4, 1.9, -0.8}};
  const int rects[2][4] = {{20, 10, 300, 170}, {5, 40, 150, 175}};
  for (int b = 0; b < 2; ++b)
    for (int r = 0; r < 2; ++r) {
      const double *lo = boxes[b], *hi = boxes[b] + 3;
      const int *rc = rects[r];
      const mpm_camera cam = mpm_camera_fit_box(lo, hi, 320, 180, rc, NULL, 0);
      double u0 = INFINITY, u1 = -INFINITY, v0 = INFINITY, v1 = -INFINITY;
      for (int k = 0; k < 8; ++k) {
        const double p[3] = {k & 1 ? hi[0] : lo[0], k & 2 ? hi[1] : lo[1], k & 4 ? hi[2] : lo[2]};
        double u, v;
        project(&cam, p, &u, &v);
        u0 = fmin(u0, u), u1 = fmax(u1, u), v0 = fmin(v0, v), v1 = fmax(v1, v);
      }
      print_message("box %d in rect %d: x %.2f..%.2f, y %.2f..%.2f\n", b, r, u0, u1, v0, v1);
      const double tol = 1e-6;
      assert_true(u0 >= rc[0] - tol && u1 <= rc[2] + tol && v0 >= rc[1] - tol && v1 <= rc[3] + tol);
      /* as near as that allows: one axis spans its side of the rectangle */
      const int fills_x = u0 < rc[0] + 1e-3 && u1 > rc[2] - 1e-3;
      const int fills_y = v0 < rc[1] + 1e-3 && v1 > rc[3] - 1e-3;
      assert_true(fills_x || fills_y);
      /* and centred along the other */
      assert_true(fabs(0.5 * (u0 + u1) - 0.5 * (rc[0] + rc[2])) < 1e-3 * 320 ||
                  fabs(0.5 * (v0 + v1) - 0.5 * (rc[1] + rc[3])) < 1e-3 * 180);
      assert_true(fills_x ? fabs(0.5 * (v0 + v1) - 0.5 * (rc[1] + rc[3])) < 0.5
                          : fabs(0.5 * (u0 + u1) - 0.5 * (rc[0] + rc[2])) < 0.5);
    }
}

/* A block of particles over [0.4, 0.6] x [y0, y0 + 0.2] x [0.4, 0.6], spacing 0.02. */
static size_t block(float *xyz, double y0) {
  size_t n = 0;
  for (int i = 0; i < 10; ++i)
    for (int j = 0; j < 10; ++j)
      for (int k = 0; k < 10; ++k) {
        xyz[3 * n] = (float)(0.41 + 0.02 * i);
        xyz[3 * n + 1] = (float)(y0 + 0.01 + 0.02 * j);
        xyz[3 * n + 2] = (float)(0.41 + 0.02 * k);
        ++n;
      }
  return n;
}

/* The ground's darkening by a block at height y0 over the ground g (a level floor at 0, or a
 * slope through (0.5, 0, 0.5), the block then turned onto it): pixels darker, pixels lighter
 * (none allowed), the largest darkening of one channel. */
static void shadow_on(const mpm_ground *g, double y0, int *darker, int *lighter, float *most) {
  const mpm_ground flat = *g;
  const double lo[3] = {0.2, g->level ? 0 : -0.2, 0.2}, hi[3] = {0.8, 0.6, 0.8};
  const int w = 320, h = 180;
  const int rect[4] = {10, 10, 310, 170};
  const mpm_camera cam = mpm_camera_fit_box(lo, hi, w, h, rect, NULL, 0);
  mpm_image a, b;
  mpm_error err;
  mpm_error_clear(&err);
  assert_int_equal(mpm_image_init(&a, w, h, &err), MPM_OK);
  assert_int_equal(mpm_image_init(&b, w, h, &err), MPM_OK);
  mpm_render_background(&a, &cam, &flat, lo, hi, NULL, 0, -1);
  mpm_render_background(&b, &cam, &flat, lo, hi, NULL, 0, -1);
  static float xyz[3 * 1000];
  const size_t n = block(xyz, y0);
  if (!g->level) /* onto the slope: (x - 0.5, y, z - 0.5) in the plane's frame */
    for (size_t i = 0; i < n; ++i) {
      const double u = xyz[3 * i] - 0.5, y = xyz[3 * i + 1], v = xyz[3 * i + 2] - 0.5;
      for (int d = 0; d < 3; ++d)
        xyz[3 * i + d] = (float)(g->point[d] + u * g->e1[d] + y * g->normal[d] + v * g->e2[d]);
    }
  assert_int_equal(mpm_render_ground_shadow(&b, &cam, &flat, n, xyz, NULL, 0.015f, &err), MPM_OK);
  *darker = *lighter = 0;
  *most = 0;
  for (int i = 0; i < w * h; ++i) {
    const float d = a.rgb[3 * i] - b.rgb[3 * i];
    *darker += d > 1e-3f;
    *lighter += d < -1e-6f;
    if (d > *most) *most = d;
    if (d != 0 && a.rgb[3 * i + 1] > 0.5f && !isfinite(a.depth[i])) fail_msg("sky darkened");
  }
  assert_true(memcmp(a.depth, b.depth, (size_t)w * (size_t)h * sizeof(float)) == 0);
  mpm_image_free(&a);
  mpm_image_free(&b);
}

static void test_ground_shadow(void **state) {
  (void)state;
  mpm_ground grounds[2];
  mpm_ground_level(&grounds[0], 0);
  const double p[3] = {0.5, 0, 0.5}, n[3] = {0.5, 0.8660254037844386, 0}; /* 30 degrees */
  mpm_ground_make(&grounds[1], p, n);
  for (int k = 0; k < 2; ++k) {
    int darker, lighter, darker_up, lighter_up;
    float most, most_up;
    shadow_on(&grounds[k], 0, &darker, &lighter, &most);
    shadow_on(&grounds[k], 0.4, &darker_up, &lighter_up, &most_up);
    print_message("%s: resting: %d pixels darker (by up to %.3f); lifted 0.4: %d (%.3f)\n",
                  k ? "slope" : "floor", darker, most, darker_up, most_up);
    assert_int_equal(lighter, 0);
    assert_int_equal(lighter_up, 0);
    assert_true(darker > 1000);    /* the ground under and around the block's foot */
    assert_true(darker_up > 1000); /* a lifted block still casts a shadow */
    assert_true(most > 0.15f);
    assert_true(most > most_up + 0.03f); /* darkest where it touches the ground */
  }
  const mpm_ground flat = grounds[0];
  /* no particles over the ground: nothing to do */
  mpm_image img;
  mpm_error err;
  mpm_error_clear(&err);
  assert_int_equal(mpm_image_init(&img, 32, 18, &err), MPM_OK);
  const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
  const mpm_camera cam = mpm_camera_frame_box(lo, hi, 32, 18);
  mpm_render_background(&img, &cam, &flat, lo, hi, NULL, 0, -1);
  const float below[3] = {0.5f, -1, 0.5f};
  assert_int_equal(mpm_render_ground_shadow(&img, &cam, &flat, 1, below, NULL, 0.01f, &err),
                   MPM_OK);
  assert_int_equal(mpm_render_ground_shadow(&img, &cam, &flat, 0, NULL, NULL, 0.01f, &err), MPM_OK);
  mpm_image_free(&img);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_font_glyphs), cmocka_unit_test(test_font_draws_digits),
      cmocka_unit_test(test_colour_bar),  cmocka_unit_test(test_label),
      cmocka_unit_test(test_camera_fit),  cmocka_unit_test(test_ground_shadow)};
  return test_cleanup(cmocka_run_group_tests_name("render_overlay", tests, NULL, NULL));
}
