/* test_render_defaults.c - what `mpm render RUN_DIR` draws by default, on small runs: the
 * camera frames the material (its pixels span most of the picture, clear of the edges, and far
 * more of it than with --frame domain), the ground is darker beside a body on the floor than
 * with --no-shadow, the colour bar's gradient is in its strip and the time label says the
 * frame's time (and --no-legend, --no-time leave them out), and a run at rest is coloured by
 * material (by body when the bodies share one material; a moving one by speed). */
#include "support.h"
#include "cli_support.h"
#include "render/overlay.h"
#include "render_support.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* A 2 m domain with two bodies of two materials at rest on the floor near one corner: no
 * gravity, so nothing moves. */
static const char *rest_scene =
    "{\"domain\": {\"min\": [0,0,0], \"max\": [2,2,2], \"dx\": 0.05},"
    " \"gravity\": [0, 0, 0], \"time\": {\"end\": 0.1, \"fps\": 20},"
    " \"materials\": [{\"name\": \"jelly\", \"model\": \"fixed_corotated\", \"E\": 1e4,"
    " \"nu\": 0.3, \"density\": 1000}, {\"name\": \"rubber\", \"model\": \"neo_hookean\","
    " \"E\": 1e4, \"nu\": 0.3, \"density\": 1000}],"
    " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.5,0.32,0.5],"
    "   \"half_extent\": [0.15,0.12,0.15]}, \"material\": \"jelly\"},"
    "  {\"shape\": {\"type\": \"sphere\", \"center\": [0.85,0.3,0.5], \"radius\": 0.1},"
    "   \"material\": \"rubber\"}],"
    " \"colliders\": [{\"shape\": {\"type\": \"halfspace\", \"point\": [0,0.2,0],"
    "   \"normal\": [0,1,0]}, \"rule\": \"sticky\"}]}";

static char run_dir[700];

static int setup(void **state) {
  (void)state;
  const char *dir = test_temp_dir("render_defaults");
  char scene[600], args[1400];
  snprintf(scene, sizeof scene, "%s/rest.json", dir);
  write_file(scene, rest_scene);
  snprintf(run_dir, sizeof run_dir, "%s/rest", dir);
  snprintf(args, sizeof args, "run '%s' -o '%s' --frames 1 --quiet", scene, run_dir);
  if (mpm(args) != 0) fail_msg("mpm run failed:\n%s", output);
  return 0;
}

/* Run a scene for one frame into out and render it small: what mpm printed is in output. */
static void run_and_render(const char *scene, const char *out) {
  char args[1600];
  snprintf(args, sizeof args, "run '%s' -o '%s' --frames 1 --quiet", scene, out);
  if (mpm(args) != 0) fail_msg("mpm run failed:\n%s", output);
  snprintf(args, sizeof args, "render '%s' --size 160x90", out);
  if (mpm(args) != 0) fail_msg("mpm render failed:\n%s", output);
}

/* Render the run with extra options into run_dir/NAME and read frame 0 back. */
static rgb_image render(const char *name, const char *options) {
  char args[2000], png[900];
  snprintf(args, sizeof args, "render '%s' --size 320x180 --out '%s/%s' %s", run_dir, run_dir, name,
           options);
  if (mpm(args) != 0) fail_msg("mpm %s failed:\n%s", args, output);
  snprintf(png, sizeof png, "%s/%s/frame_0000.png", run_dir, name);
  return read_png(png);
}

/* The bounding box of the coloured (particle) pixels. */
static void coloured_bounds(const rgb_image *im, int b[4]) {
  b[0] = im->w, b[1] = im->h, b[2] = -1, b[3] = -1;
  for (int y = 0; y < im->h; ++y)
    for (int x = 0; x < im->w; ++x)
      if (!greyish(im, x, y)) {
        if (x < b[0]) b[0] = x;
        if (y < b[1]) b[1] = y;
        if (x > b[2]) b[2] = x;
        if (y > b[3]) b[3] = y;
      }
}

static void test_framing(void **state) {
  (void)state;
  rgb_image a = render("framed", "--no-legend --no-time --no-shadow --field material");
  rgb_image d =
      render("domain", "--no-legend --no-time --no-shadow --field material --frame domain");
  int b[4], bd[4];
  coloured_bounds(&a, b);
  coloured_bounds(&d, bd);
  print_message("material framing: x %d..%d, y %d..%d; domain framing: x %d..%d, y %d..%d\n", b[0],
                b[2], b[1], b[3], bd[0], bd[2], bd[1], bd[3]);
  assert_true(b[2] >= 0); /* the material is in the picture */
  /* clear of the edges by most of the default margin (0.06 of 180 rows: 11 pixels) */
  assert_true(b[0] >= 6 && b[1] >= 6 && b[2] <= a.w - 7 && b[3] <= a.h - 7);
  /* and as large as that allows along one axis */
  const int wx = b[2] - b[0] + 1, wy = b[3] - b[1] + 1;
  assert_true(wx > 0.8 * (a.w - 22) || wy > 0.75 * (a.h - 22));
  /* the domain's framing shows the same material much smaller */
  const int dx = bd[2] - bd[0] + 1, dy = bd[3] - bd[1] + 1;
  assert_true(dx > 0 && wx > 2 * dx && wy > 2 * dy);
  /* --margin 0.3 leaves a wider border */
  rgb_image m = render("margin", "--no-legend --no-time --no-shadow --field material --margin 0.3");
  int bm[4];
  coloured_bounds(&m, bm);
  assert_true(bm[1] >= 40 && bm[3] <= m.h - 41 && bm[3] - bm[1] < wy);
  free(a.px), free(d.px), free(m.px);
}

static void test_shadow(void **state) {
  (void)state;
  rgb_image s = render("shadow", "--no-legend --no-time");
  rgb_image n = render("no_shadow", "--no-legend --no-time --no-shadow");
  long darker = 0, lighter = 0;
  for (int y = 0; y < s.h; ++y)
    for (int x = 0; x < s.w; ++x) {
      int d = 0;
      for (int c = 0; c < 3; ++c) d += pixel(&n, x, y)[c] - pixel(&s, x, y)[c];
      darker += d > 12;
      lighter += d < -3;
    }
  print_message("the shadow darkens %ld pixels, lightens %ld\n", darker, lighter);
  assert_true(darker > 300);
  assert_int_equal(lighter, 0);
  /* the particles themselves are drawn alike */
  long same = 0, particles = 0;
  for (int y = 0; y < s.h; ++y)
    for (int x = 0; x < s.w; ++x)
      if (!greyish(&n, x, y)) {
        ++particles;
        same += !memcmp(pixel(&n, x, y), pixel(&s, x, y), 3);
      }
  assert_true(particles > 1000 && same == particles);
  free(s.px), free(n.px);
}

/* The colour bar in the strip mpm_legend_bar names, and the time label's glyphs; none of
 * either with --no-legend --no-time. */
static void test_legend_and_time(void **state) {
  (void)state;
  rgb_image a = render("legend", "--field velocity --no-shadow");
  rgb_image b = render("bare", "--field velocity --no-shadow --no-legend --no-time");
  const mpm_legend lg = {MPM_CMAP_VIRIDIS, "speed (m/s)", 0, 1, 0, NULL};
  const mpm_overlay_box bar = mpm_legend_bar(&lg, a.w, a.h);
  const int cx = (bar.x0 + bar.x1) / 2;
  int match = 0, match_bare = 0;
  for (int y = bar.y0; y < bar.y1; ++y) {
    float want[3];
    mpm_colormap_eval(MPM_CMAP_VIRIDIS, (double)(bar.y1 - 1 - y) / (bar.y1 - bar.y0 - 1), want);
    match += pixel_is(&a, cx, y, want, 2);
    match_bare += pixel_is(&b, cx, y, want, 2);
  }
  print_message("colour bar: %d of %d rows match viridis (%d without the legend)\n", match,
                bar.y1 - bar.y0, match_bare);
  assert_int_equal(match, bar.y1 - bar.y0);
  assert_true(match_bare < 3);
  /* "t = 0.000 s, frame 0": each glyph pixel dark, the pixels between light */
  const char *text = "t = 0.000 s, frame 0";
  const mpm_overlay_box lb = mpm_label_box(text, a.w, a.h);
  const int s = mpm_overlay_scale(a.h), pad = 4 * s;
  int ink = 0, ink_bare = 0;
  for (int k = 0; text[k]; ++k)
    for (int r = 0; r < MPM_FONT_H; ++r)
      for (int c = 0; c < MPM_FONT_W; ++c) {
        const int x = lb.x0 + pad + (k * MPM_FONT_ADVANCE + c) * s, y = lb.y0 + pad + r * s;
        const int dark = pixel(&a, x, y)[0] < 40;
        if (dark != mpm_font_pixel(text[k], c, r))
          fail_msg("time label '%s', character %d, glyph pixel (%d, %d)\n%s", text, k, c, r,
                   output);
        ink += dark;
        ink_bare += pixel(&b, x, y)[0] < 40;
      }
  print_message("time label: %d pixels of ink (%d without it)\n", ink, ink_bare);
  assert_true(ink > 100);
  assert_int_equal(ink_bare, 0);
  free(a.px), free(b.px);
}

/* At rest the default colours by material, in the key's colours; a moving run by speed. */
static void test_material_by_default(void **state) {
  (void)state;
  char args[2000];
  snprintf(args, sizeof args, "render '%s' --size 320x180 --out '%s/auto'", run_dir, run_dir);
  if (mpm(args) != 0) fail_msg("mpm render failed:\n%s", output);
  expect_output("material 0..1");
  rgb_image a = render("auto_q", "--quiet");
  rgb_image m = render("material", "--quiet --field material");
  assert_true(!memcmp(a.px, m.px, (size_t)a.w * (size_t)a.h * 3));
  /* the key: both materials' swatches */
  const char *names[2] = {"jelly", "rubber"};
  const mpm_legend key = {MPM_CMAP_CATEGORY, "material", 0, 1, 2, names};
  const mpm_overlay_box kb = mpm_legend_box(&key, a.w, a.h);
  for (int k = 0; k < 2; ++k) {
    float want[3];
    mpm_colormap_eval(MPM_CMAP_CATEGORY, k, want);
    int found = 0;
    for (int y = kb.y0; y < kb.y1; ++y)
      for (int x = kb.x0; x < kb.x1; ++x) found += pixel_is(&a, x, y, want, 1);
    if (found < 9) fail_msg("material %d: %d pixels of its swatch in the key", k, found);
  }
  /* asked for, speed it is, though uniform */
  snprintf(args, sizeof args, "render '%s' --size 320x180 --out '%s/v' --field velocity", run_dir,
           run_dir);
  if (mpm(args) != 0) fail_msg("mpm render failed:\n%s", output);
  expect_output("velocity 0..");
  free(a.px), free(m.px);
  /* a run that moves: speed by default */
  const char *dir = test_temp_dir("render_defaults_moving");
  char scene[600], out[700];
  snprintf(scene, sizeof scene, "%s/moving.json", dir);
  char *json = malloc(strlen(rest_scene) + 64);
  assert_non_null(json);
  strcpy(json, rest_scene);
  char *at = strstr(json, "\"material\": \"rubber\"");
  assert_non_null(at);
  const char *v = "\"velocity\": [0, 0, 1], ";
  memmove(at + strlen(v), at, strlen(at) + 1);
  memcpy(at, v, strlen(v));
  write_file(scene, json);
  free(json);
  snprintf(out, sizeof out, "%s/out", dir);
  run_and_render(scene, out);
  expect_output("velocity 0..");
  /* at rest with one material for both bodies: by body */
  snprintf(scene, sizeof scene, "%s/one_material.json", dir);
  json = malloc(strlen(rest_scene) + 1);
  assert_non_null(json);
  strcpy(json, rest_scene);
  at = strstr(json, "\"material\": \"rubber\"");
  assert_non_null(at);
  memcpy(at + strlen("\"material\": \""), "jelly\" ", strlen("jelly\" "));
  write_file(scene, json);
  free(json);
  snprintf(out, sizeof out, "%s/one", dir);
  run_and_render(scene, out);
  expect_output("body 0..1");
}

static void test_option_errors(void **state) {
  (void)state;
  char args[1000];
  snprintf(args, sizeof args, "render '%s' --frame sideways", run_dir);
  assert_int_equal(mpm(args), 2);
  expect_output("--frame expects material, follow or domain");
  snprintf(args, sizeof args, "render '%s' --margin 0.9", run_dir);
  assert_int_equal(mpm(args), 2);
  expect_output("--margin expects");
  /* --frame follow renders (a camera per frame) */
  rgb_image f = render("follow", "--frame follow --quiet");
  assert_int_equal(f.w, 320);
  free(f.px);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_framing), cmocka_unit_test(test_shadow),
                                     cmocka_unit_test(test_legend_and_time),
                                     cmocka_unit_test(test_material_by_default),
                                     cmocka_unit_test(test_option_errors)};
  return test_cleanup(cmocka_run_group_tests_name("render_defaults", tests, setup, NULL));
}
