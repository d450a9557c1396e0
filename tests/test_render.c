/* test_render.c - `mpm render` and the software renderer (src/render) on a tiny scene: the
 * PNG has the requested size, sky and ground where no particle is, particle colours where the
 * particles project (checked against the camera's own projection of the body's centre), a
 * different colour field changes the pixels, the colliders are drawn, and missing or corrupt
 * folders are clear errors with exit code 2 and nothing written. Images are read back with
 * libpng, independently of the writer's encoder settings. */
#include "support.h"
#include "cli_support.h"
#include "render/render.h"
#include "render_support.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>

static const char *scene_json =
    "{\"domain\": {\"min\": [0,0,0], \"max\": [1,1,1], \"dx\": 0.05},"
    " \"time\": {\"end\": 0.1, \"fps\": 20},"
    " \"materials\": [{\"name\": \"a\", \"model\": \"fixed_corotated\", \"E\": 1e4, \"nu\": 0.3,"
    " \"density\": 1000}, {\"name\": \"b\", \"model\": \"neo_hookean\", \"E\": 1e4, \"nu\": 0.3,"
    " \"density\": 1000}],"
    " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.5,0.5,0.5],"
    "   \"half_extent\": [0.12,0.12,0.12]}, \"material\": \"a\", \"velocity\": [0, 1, 0]},"
    "  {\"shape\": {\"type\": \"sphere\", \"center\": [0.5,0.25,0.5], \"radius\": 0.08},"
    "   \"material\": \"b\"}],"
    " \"colliders\": [{\"shape\": {\"type\": \"halfspace\", \"point\": [0,0.1,0],"
    "   \"normal\": [0,1,0]}, \"rule\": \"sticky\"},"
    "  {\"shape\": {\"type\": \"sphere\", \"center\": [0.8,0.3,0.2], \"radius\": 0.1}}]}";

static void test_render_frames(void **state) {
  (void)state;
  const char *dir = test_temp_dir("render");
  char scene[600], run[1400], args[1400], png[700];
  snprintf(scene, sizeof scene, "%s/scene_in.json", dir);
  FILE *f = fopen(scene, "w");
  assert_non_null(f);
  fputs(scene_json, f);
  fclose(f);
  snprintf(run, sizeof run, "run '%s' -o '%s/out' --frames 2 --quiet", scene, dir);
  assert_int_equal(mpm(run), 0);
  snprintf(png, sizeof png, "%s/out/scene.json", dir);
  assert_true(exists(png)); /* the run keeps its scene for the renderer */

  snprintf(args, sizeof args, "render '%s/out' --size 160x120 --quiet", dir);
  if (mpm(args) != 0) fail_msg("mpm render failed:\n%s", output);
  snprintf(png, sizeof png, "%s/out/render/frame_0000.png", dir);
  rgb_image a = read_png(png);
  assert_int_equal(a.w, 160);
  assert_int_equal(a.h, 120);
  /* the corners are sky or ground */
  assert_true(greyish(&a, 0, 0) && greyish(&a, 159, 0));
  /* particles are drawn in colour */
  int coloured = 0;
  for (int y = 0; y < a.h; ++y)
    for (int x = 0; x < a.w; ++x) coloured += !greyish(&a, x, y);
  print_message("frame 0: %d of %d pixels show particles\n", coloured, a.w * a.h);
  assert_true(coloured > 200);           /* two bodies of about 2,000 particles */
  assert_true(coloured < a.w * a.h / 2); /* and not the whole picture */

  /* another colour field: the same silhouette, other colours */
  snprintf(args, sizeof args,
           "render '%s/out' --size 160x120 --field material --quiet --out '%s/m'", dir, dir);
  if (mpm(args) != 0) fail_msg("mpm render --field material failed:\n%s", output);
  snprintf(png, sizeof png, "%s/m/frame_0000.png", dir);
  rgb_image b = read_png(png);
  long differ = 0;
  for (size_t i = 0; i < (size_t)a.w * (size_t)a.h * 3; ++i) differ += a.px[i] != b.px[i];
  assert_true(differ > 100);
  /* --movie: an MP4 with ffmpeg, else a message saying what to install (exit 1) */
  snprintf(args, sizeof args, "render '%s/out' --size 160x120 --movie --quiet --out '%s/mv'", dir,
           dir);
  const int movie = mpm(args);
  snprintf(png, sizeof png, "%s/mv/movie.mp4", dir);
  if (system("command -v ffmpeg >/dev/null 2>&1") == 0) {
    assert_int_equal(movie, 0);
    assert_true(exists(png));
  } else {
    assert_int_equal(movie, 1);
    if (!strstr(output, "ffmpeg not found") || !strstr(output, "apt-get install ffmpeg"))
      fail_msg("message: %s", output);
    assert_false(exists(png));
  }
  /* frame 2 exists as well */
  snprintf(png, sizeof png, "%s/out/render/frame_0002.png", dir);
  assert_true(exists(png));
  free(a.px);
  free(b.px);
}

/* --grid draws the multi-level grid's fine cells over a run on levels (the pixels change, the
 * picture stays mostly sky and ground there), and on a uniform run it says why it cannot. */
static void test_render_grid(void **state) {
  (void)state;
  const char *dir = test_temp_dir("render_grid");
  char scene[600], args[1600], png[700];
  snprintf(scene, sizeof scene, "%s/levels.json", dir);
  FILE *f = fopen(scene, "w");
  assert_non_null(f);
  fputs(
      "{\"domain\": {\"min\": [0,0,0], \"max\": [1,1,1], \"dx\": 0.05, \"levels\": 2,"
      " \"refine\": [{\"level\": 1, \"body\": 0, \"distance\": 0.05}]},"
      " \"time\": {\"end\": 0.05, \"fps\": 20},"
      " \"materials\": [{\"name\": \"a\", \"model\": \"fixed_corotated\", \"E\": 1e4, \"nu\": 0.3,"
      " \"density\": 1000}],"
      " \"bodies\": [{\"shape\": {\"type\": \"sphere\", \"center\": [0.5,0.5,0.5],"
      " \"radius\": 0.15}, \"material\": \"a\"}]}",
      f);
  fclose(f);
  snprintf(args, sizeof args, "run '%s' -o '%s/out' --frames 1 --quiet", scene, dir);
  if (mpm(args) != 0) fail_msg("mpm run failed:\n%s", output);
  snprintf(args, sizeof args, "render '%s/out' --size 160x120 --quiet --out '%s/plain'", dir, dir);
  if (mpm(args) != 0) fail_msg("mpm render failed:\n%s", output);
  snprintf(args, sizeof args, "render '%s/out' --size 160x120 --quiet --grid --out '%s/grid'", dir,
           dir);
  if (mpm(args) != 0) fail_msg("mpm render --grid failed:\n%s", output);
  snprintf(png, sizeof png, "%s/plain/frame_0000.png", dir);
  rgb_image a = read_png(png);
  snprintf(png, sizeof png, "%s/grid/frame_0000.png", dir);
  rgb_image b = read_png(png);
  long differ = 0;
  for (size_t i = 0; i < (size_t)a.w * (size_t)a.h; ++i)
    differ += memcmp(a.px + 3 * i, b.px + 3 * i, 3) != 0;
  print_message("--grid changed %ld of %d pixels\n", differ, a.w * a.h);
  assert_true(differ > 100);
  assert_true(greyish(&b, 0, 0) && greyish(&b, 159, 119)); /* the corners stay sky and ground */
  free(a.px);
  free(b.px);
  /* a uniform run has no cells to draw */
  snprintf(scene, sizeof scene, "%s/uniform.json", dir);
  f = fopen(scene, "w");
  assert_non_null(f);
  fputs(scene_json, f);
  fclose(f);
  snprintf(args, sizeof args, "run '%s' -o '%s/u' --frames 1 --quiet", scene, dir);
  assert_int_equal(mpm(args), 0);
  snprintf(args, sizeof args, "render '%s/u' --quiet --grid", dir);
  assert_int_equal(mpm(args), 2);
  if (!strstr(output, "grid_cells.vtu")) fail_msg("message: %s", output);
}

/* The camera projects the domain's centre to the middle of the picture, and the renderer
 * draws a single particle there in its colour over a background. */
static void test_camera_and_splat(void **state) {
  (void)state;
  const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
  mpm_camera cam = mpm_camera_frame_box(lo, hi, 64, 48);
  mpm_image img;
  mpm_error err;
  mpm_error_clear(&err);
  assert_int_equal(mpm_image_init(&img, 64, 48, &err), MPM_OK);
  mpm_ground flat;
  mpm_ground_level(&flat, 0);
  mpm_render_background(&img, &cam, &flat, lo, hi, NULL, 0, -1);
  const float xyz[3] = {(float)cam.target[0], (float)cam.target[1], (float)cam.target[2]};
  const float red[3] = {1, 0, 0};
  assert_int_equal(mpm_render_particles(&img, &cam, 1, xyz, NULL, 0.05f, red, &err), MPM_OK);
  const float *c = img.rgb + 3 * (24 * 64 + 32);
  assert_true(c[0] > 0.2f && c[1] == 0 && c[2] == 0); /* shaded red at the centre */
  const float *corner = img.rgb;
  assert_true(corner[1] > 0.3f); /* sky is not red */
  mpm_image_free(&img);
  /* colour maps: ends and clamping */
  float lo_c[3], hi_c[3], over[3];
  mpm_colormap_eval(MPM_CMAP_VIRIDIS, 0, lo_c);
  mpm_colormap_eval(MPM_CMAP_VIRIDIS, 1, hi_c);
  mpm_colormap_eval(MPM_CMAP_VIRIDIS, 7, over);
  assert_true(lo_c[2] > lo_c[1] && hi_c[0] > hi_c[2]); /* purple to yellow */
  assert_true(memcmp(hi_c, over, sizeof over) == 0);
  assert_int_equal(mpm_colormap_of("coolwarm"), MPM_CMAP_COOLWARM);
  assert_int_equal(mpm_colormap_of("rainbow"), -1);
}

/* The scene's camera: looking straight at the box from +z, the box fills the middle of the
 * picture and the corners show the sky. */
static void test_scene_camera(void **state) {
  (void)state;
  const char *dir = test_temp_dir("render-camera");
  char scene[600], args[1400], png[700];
  snprintf(scene, sizeof scene, "%s/scene_in.json", dir);
  char *json = malloc(strlen(scene_json) + 200);
  assert_non_null(json);
  strcpy(json, scene_json);
  json[strlen(json) - 1] = 0; /* drop the closing brace */
  strcat(json, ", \"camera\": {\"eye\": [0.5, 0.5, 2.0], \"target\": [0.5, 0.5, 0.5], "
               "\"fov\": 20}}");
  write_file(scene, json);
  free(json);
  snprintf(args, sizeof args, "run '%s' -o '%s/out' --frames 1 --quiet --render", scene, dir);
  if (mpm(args) != 0) fail_msg("mpm run --render failed:\n%s", output);
  snprintf(png, sizeof png, "%s/out/render/frame_0000.png", dir);
  rgb_image a = read_png(png);
  assert_int_equal(a.w, 1280); /* the default size */
  assert_false(greyish(&a, a.w / 2, a.h / 2));
  assert_true(greyish(&a, 2, 2) && greyish(&a, a.w - 3, 2));
  free(a.px);
}

static void test_errors(void **state) {
  (void)state;
  const char *dir = test_temp_dir("render-errors");
  char args[1400], path[700];
  snprintf(args, sizeof args, "render '%s/nowhere'", dir);
  assert_int_equal(mpm(args), 2);
  if (!strstr(output, "nowhere: no such folder")) fail_msg("message: %s", output);
  snprintf(args, sizeof args, "render '%s'", dir); /* empty folder */
  assert_int_equal(mpm(args), 2);
  if (!strstr(output, "no frame_NNNN.vtu")) fail_msg("message: %s", output);
  /* a corrupt frame */
  snprintf(path, sizeof path, "%s/frame_0000.vtu", dir);
  FILE *f = fopen(path, "w");
  assert_non_null(f);
  fputs("<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\">garbage", f);
  fclose(f);
  snprintf(args, sizeof args, "render '%s'", dir);
  assert_int_equal(mpm(args), 2);
  if (!strstr(output, "frame_0000.vtu: not a particle frame written by mpm"))
    fail_msg("message: %s", output);
  snprintf(path, sizeof path, "%s/render", dir);
  assert_false(exists(path)); /* nothing written */
  assert_int_equal(mpm("render"), 2);
  assert_int_equal(mpm("render x --size 10"), 2);
  assert_int_equal(mpm("render x --field colour"), 2);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_render_frames), cmocka_unit_test(test_render_grid),
      cmocka_unit_test(test_camera_and_splat), cmocka_unit_test(test_scene_camera),
      cmocka_unit_test(test_errors)};
  return test_cleanup(cmocka_run_group_tests_name("render", tests, NULL, NULL));
}
