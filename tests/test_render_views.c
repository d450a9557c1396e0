/* test_render_views.c - choosing what `mpm render` shows, from the command line and the public
 * API: the camera (--eye, --target, --fov, each alone keeping the rest of the automatic view,
 * and the camera used printed so that it can be given back), a range of frames (--frames), any
 * array the run wrote (--field pressure, a component such as velocity.y, a tensor's magnitude;
 * a misspelt array named with the arrays the frames have), and a slope (a tilted half-space)
 * drawn as the ground, seen from above, with the material's shadow on it. */
#include "support.h"
#include "cli_support.h"
#include "mpm/mpm.h"
#include "render_support.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* A jelly block resting on a floor, then sliding on nothing (no gravity): pressure and the
 * Cauchy stress written besides the default arrays; frames 0, 1 and 2. */
static const char *block_scene =
    "{\"domain\": {\"min\": [0,0,0], \"max\": [1,1,1], \"dx\": 0.05},"
    " \"gravity\": [0, -9.81, 0], \"time\": {\"end\": 0.1, \"fps\": 20},"
    " \"materials\": [{\"name\": \"jelly\", \"model\": \"fixed_corotated\", \"E\": 1e4,"
    " \"nu\": 0.3, \"density\": 1000}],"
    " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.5,0.3,0.5],"
    "   \"half_extent\": [0.12,0.12,0.12]}, \"material\": \"jelly\", \"velocity\": [0.5,0,0]}],"
    " \"colliders\": [{\"shape\": {\"type\": \"halfspace\", \"point\": [0,0.15,0],"
    "   \"normal\": [0,1,0]}, \"rule\": \"slip\"}],"
    " \"output\": {\"fields\": [\"velocity\", \"mass\", \"volume\", \"J\", \"stress\","
    "   \"material\", \"body\", \"cauchy_stress\", \"pressure\"]}}";

/* The same block resting on a 30-degree slope (a tilted half-space through the domain's
 * centre; the domain's floor far below it). */
static const char *slope_scene =
    "{\"domain\": {\"min\": [0,0,0], \"max\": [1,1,1], \"dx\": 0.05},"
    " \"gravity\": [0, 0, 0], \"time\": {\"end\": 0.05, \"fps\": 20},"
    " \"materials\": [{\"name\": \"jelly\", \"model\": \"fixed_corotated\", \"E\": 1e4,"
    " \"nu\": 0.3, \"density\": 1000}],"
    " \"bodies\": [{\"shape\": {\"type\": \"sphere\", \"center\": [0.5,0.62,0.5],"
    "   \"radius\": 0.1}, \"material\": \"jelly\"}],"
    " \"colliders\": [{\"shape\": {\"type\": \"halfspace\", \"point\": [0.5,0.5,0.5],"
    "   \"normal\": [0.5,0.8660254,0]}, \"rule\": \"sticky\"}]}";

static char dir[600], run_dir[700];

static int setup(void **state) {
  (void)state;
  snprintf(dir, sizeof dir, "%s", test_temp_dir("render_views"));
  char scene[700], args[1600];
  snprintf(scene, sizeof scene, "%s/block.json", dir);
  write_file(scene, block_scene);
  snprintf(run_dir, sizeof run_dir, "%s/block", dir);
  snprintf(args, sizeof args, "run '%s' -o '%s' --quiet", scene, run_dir);
  if (mpm(args) != 0) fail_msg("mpm run failed:\n%s", output);
  return 0;
}

/* `mpm render run_dir --size 160x90 --out run_dir/NAME OPTIONS`: its exit code. */
static int render(const char *name, const char *options) {
  char args[2000];
  snprintf(args, sizeof args, "render '%s' --size 160x90 --out '%s/%s' %s", run_dir, run_dir, name,
           options);
  return mpm(args);
}

static rgb_image picture(const char *name, int frame) {
  char png[900];
  snprintf(png, sizeof png, "%s/%s/frame_%04d.png", run_dir, name, frame);
  return read_png(png);
}

/* The camera line `mpm render` prints last: --eye X,Y,Z --target X,Y,Z --fov F. */
static void printed_camera(double eye[3], double target[3], double *fov) {
  const char *at = strstr(output, "camera --eye ");
  if (!at) fail_msg("no camera line in:\n%s", output);
  if (sscanf(at, "camera --eye %lf,%lf,%lf --target %lf,%lf,%lf --fov %lf", &eye[0], &eye[1],
             &eye[2], &target[0], &target[1], &target[2], fov) != 7)
    fail_msg("camera line: %s", at);
}

/* The coloured (particle) pixels' box and count. */
static int coloured(const rgb_image *im, int b[4]) {
  int n = 0;
  b[0] = im->w, b[1] = im->h, b[2] = -1, b[3] = -1;
  for (int y = 0; y < im->h; ++y)
    for (int x = 0; x < im->w; ++x)
      if (!greyish(im, x, y)) {
        ++n;
        b[0] = x < b[0] ? x : b[0], b[1] = y < b[1] ? y : b[1];
        b[2] = x > b[2] ? x : b[2], b[3] = y > b[3] ? y : b[3];
      }
  return n;
}

/* The camera: the automatic one is printed; given back it draws the same picture (to the
 * printed digits: within a pixel); a target alone moves the view with it; an eye straight in
 * front of the block at its height sees it in the middle; a narrower field of view alone makes
 * it larger (the framing refitted) and a wider given view smaller. */
static void test_camera(void **state) {
  (void)state;
  assert_int_equal(render("auto", "--no-legend --no-time --frames 0"), 0);
  double eye[3], target[3], fov;
  printed_camera(eye, target, &fov);
  assert_true(fabs(fov - 35) < 1e-9);
  rgb_image a = picture("auto", 0);
  int ba[4];
  const int na = coloured(&a, ba);
  assert_true(na > 100);
  char opts[600];
  snprintf(opts, sizeof opts,
           "--no-legend --no-time --frames 0 --eye %.9g,%.9g,%.9g "
           "--target %.9g,%.9g,%.9g --fov %.9g",
           eye[0], eye[1], eye[2], target[0], target[1], target[2], fov);
  assert_int_equal(render("again", opts), 0);
  expect_output("the scene's or the given camera");
  rgb_image b = picture("again", 0);
  int bb[4];
  const int nb = coloured(&b, bb);
  print_message("automatic: %d pixels in [%d %d %d %d]; given back: %d in [%d %d %d %d]\n", na,
                ba[0], ba[1], ba[2], ba[3], nb, bb[0], bb[1], bb[2], bb[3]);
  for (int k = 0; k < 4; ++k) assert_true(abs(ba[k] - bb[k]) <= 1);
  /* a target alone: the same direction and distance from it */
  snprintf(opts, sizeof opts, "--no-legend --no-time --frames 0 --target %.9g,%.9g,%.9g",
           target[0] + 0.2, target[1], target[2]);
  assert_int_equal(render("shifted", opts), 0);
  double eye2[3], target2[3], fov2;
  printed_camera(eye2, target2, &fov2);
  for (int d = 0; d < 3; ++d) assert_true(fabs(eye2[d] - (eye[d] + (d == 0 ? 0.2 : 0))) < 1e-3);
  /* in front of the block at its height, looking at its centre: it is in the middle */
  assert_int_equal(render("front", "--no-legend --no-time --frames 0 --eye 0.5,0.3,2.5 "
                                   "--target 0.5,0.3,0.5 --fov 20"),
                   0);
  rgb_image f = picture("front", 0);
  int bf[4];
  coloured(&f, bf);
  const int cx = (bf[0] + bf[2]) / 2, cy = (bf[1] + bf[3]) / 2;
  print_message("front view: block in [%d %d %d %d]\n", bf[0], bf[1], bf[2], bf[3]);
  assert_true(abs(cx - 80) <= 3 && abs(cy - 45) <= 3);
  /* an eye alone looks at the automatic target */
  assert_int_equal(render("eye", "--no-legend --no-time --frames 0 --eye 0.5,2,2"), 0);
  printed_camera(eye2, target2, &fov2);
  for (int d = 0; d < 3; ++d) assert_true(fabs(target2[d] - target[d]) < 1e-3);
  /* the field of view: narrower (refitted: the same framing) and given wider (smaller) */
  snprintf(opts, sizeof opts,
           "--no-legend --no-time --frames 0 --eye %.9g,%.9g,%.9g "
           "--target %.9g,%.9g,%.9g --fov 70",
           eye[0], eye[1], eye[2], target[0], target[1], target[2]);
  assert_int_equal(render("wide", opts), 0);
  rgb_image w = picture("wide", 0);
  int bw[4];
  const int nw = coloured(&w, bw);
  print_message("fov 70 from the same eye: %d pixels against %d\n", nw, na);
  assert_true(nw < na / 2);
  free(a.px), free(b.px), free(f.px), free(w.px);
  /* bad cameras are refused naming the option */
  assert_int_equal(render("bad", "--eye 1,2"), 2);
  expect_output("--eye expects X,Y,Z");
  assert_int_equal(render("bad", "--fov 0.5"), 2);
  expect_output("--fov expects");
  assert_int_equal(render("bad", "--eye 0.5,0.5,0.5 --target 0.5,0.5,0.5"), 2);
  expect_output("the same point");
}

/* A range of frames: only those are drawn; a range without frames is refused. */
static void test_frames(void **state) {
  (void)state;
  char png[900];
  assert_int_equal(render("range", "--frames 1:2 --quiet"), 0);
  for (int k = 0; k < 3; ++k) {
    snprintf(png, sizeof png, "%s/range/frame_%04d.png", run_dir, k);
    assert_int_equal(exists(png), k >= 1);
  }
  assert_int_equal(render("one", "--frames 1 --quiet"), 0);
  snprintf(png, sizeof png, "%s/one/frame_0002.png", run_dir);
  assert_false(exists(png));
  assert_int_equal(render("open", "--frames 2: --quiet"), 0);
  snprintf(png, sizeof png, "%s/open/frame_0001.png", run_dir);
  assert_false(exists(png));
  assert_int_equal(render("none", "--frames 7:9"), 2);
  expect_output("no frame_NNNN.vtu files numbered 7 to 9");
  assert_int_equal(render("none", "--frames 3:1"), 2);
  expect_output("--frames expects");
}

/* Any array the run wrote: pressure, a component (a signed one centred on 0), a tensor's magnitude;
 * the misspelt and the impossible named. */
static void test_any_field(void **state) {
  (void)state;
  assert_int_equal(render("pressure", "--field pressure --frames 1"), 0);
  expect_output("pressure ");
  expect_output("(160x90, pressure ");
  rgb_image p = picture("pressure", 1);
  int b[4];
  assert_true(coloured(&p, b) > 50);
  free(p.px);
  assert_int_equal(render("vy", "--field velocity.x --frames 1"), 0);
  expect_output("velocity.x ");
  assert_int_equal(render("sxy", "--field cauchy_stress.xy --frames 1 --quiet"), 0);
  assert_int_equal(render("snorm", "--field cauchy_stress --frames 1"), 0);
  expect_output("(160x90, cauchy_stress ");
  assert_int_equal(render("bad", "--field presure"), 2);
  expect_output("no 'presure' array (they have: velocity, mass, volume, J, stress, material");
  expect_output("pressure");
  assert_int_equal(render("bad", "--field mass.x"), 2);
  expect_output("'mass' has 1 component: no component 'x'");
  /* through the API: the label and the range reported */
  mpm_render_options o = mpm_render_options_default();
  o.width = 64, o.height = 36, o.field_array = "cauchy_stress.xy"; /* signed */
  o.first_frame = 1, o.last_frame = 1;
  mpm_renderer *r;
  char err[1024];
  if (mpm_renderer_create(run_dir, &o, &r, err, sizeof err) != MPM_OK) fail_msg("%s", err);
  mpm_render_info info;
  assert_int_equal(mpm_renderer_get_info(r, &info, sizeof info), MPM_OK);
  assert_int_equal(info.field, MPM_RENDER_FIELD_ARRAY);
  assert_string_equal(info.field_label, "cauchy_stress.xy");
  assert_int_equal(info.pictures, 1);
  assert_int_equal(info.first_frame, 1);
  assert_int_equal(info.last_frame, 1);
  assert_true(info.range_lo < 0 && info.range_hi == -info.range_lo);
  assert_int_equal(info.colormap, MPM_RENDER_COLORMAP_COOLWARM);
  assert_int_equal(mpm_renderer_draw(r, 0), MPM_OK);
  mpm_renderer_destroy(r);
  o.field_array = "";
  assert_int_equal(mpm_renderer_create(run_dir, &o, &r, err, sizeof err), MPM_ERR_INVALID);
  if (!strstr(err, "mpm_render_options.field_array")) fail_msg("message: %s", err);
}

/* A slope is the ground: drawn under the material with its shadow (rendering with and without
 * the shadow differs on the slope), and seen from above (the camera on its upper side). */
static void test_slope_ground(void **state) {
  (void)state;
  char scene[700], out[800], args[2000];
  snprintf(scene, sizeof scene, "%s/slope.json", dir);
  write_file(scene, slope_scene);
  snprintf(out, sizeof out, "%s/slope", dir);
  snprintf(args, sizeof args, "run '%s' -o '%s' --quiet --frames 1", scene, out);
  if (mpm(args) != 0) fail_msg("mpm run failed:\n%s", output);
  snprintf(args, sizeof args,
           "render '%s' --size 320x180 --frames 0 --field material --no-legend --no-time "
           "--out '%s/lit'",
           out, out);
  assert_int_equal(mpm(args), 0);
  double eye[3], target[3], fov;
  printed_camera(eye, target, &fov);
  /* the eye over the slope's upper side: (eye - point) . normal > 0, well above it */
  const double n[3] = {0.5, 0.8660254, 0};
  double h = 0;
  for (int d = 0; d < 3; ++d) h += (eye[d] - 0.5) * n[d];
  double v[3], vn = 0, len = 0;
  for (int d = 0; d < 3; ++d) v[d] = eye[d] - target[d], len += v[d] * v[d];
  for (int d = 0; d < 3; ++d) vn += v[d] * n[d] / sqrt(len);
  print_message("eye %.3f over the slope; the view at %.1f degrees to it\n", h,
                asin(vn) * 180 / 3.14159265358979);
  assert_true(h > 0 && vn > 0.3);
  snprintf(args, sizeof args,
           "render '%s' --size 320x180 --frames 0 --field material --no-legend --no-time "
           "--no-shadow --out '%s/unlit'",
           out, out);
  assert_int_equal(mpm(args), 0);
  char png[900];
  snprintf(png, sizeof png, "%s/lit/frame_0000.png", out);
  rgb_image lit = read_png(png);
  snprintf(png, sizeof png, "%s/unlit/frame_0000.png", out);
  rgb_image unlit = read_png(png);
  int darker = 0;
  for (int i = 0; i < 320 * 180; ++i) {
    darker += lit.px[3 * i] + 8 < unlit.px[3 * i];
  }
  print_message("%d pixels of the slope darkened by the shadow\n", darker);
  assert_true(darker > 200);
  free(lit.px), free(unlit.px);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_camera), cmocka_unit_test(test_frames),
                                     cmocka_unit_test(test_any_field),
                                     cmocka_unit_test(test_slope_ground)};
  return test_cleanup(cmocka_run_group_tests_name("render_views", tests, setup, NULL));
}
