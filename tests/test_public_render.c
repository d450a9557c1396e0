/* test_public_render.c - pictures and plots of a run through the public API alone
 * (include/mpm/render.h, plot.h; issue 17: `mpm render` and `mpm plot` are written on them): a
 * tiny scene run with output, its frames rendered to PNG (mpm_render_run) and into a buffer of
 * the caller's (the PNG's pixels exactly, material drawn in colour over a grey background, the
 * same whatever order or thread count the pictures are drawn in), the choices the renderer
 * reports, the errors that name the folder or the option, and stats.csv read into the public
 * table and plotted. Of the engine's headers only mpm/mpm.h is included here (support.h and
 * the tests' PNG reader aside). */
#include "support.h"
#include "mpm/mpm.h"
#include "render_support.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#ifdef _OPENMP
#include <omp.h>
#endif

/* Two bodies of two materials falling onto a floor (a collider: stats.csv has its force). */
static const char *scene_json =
    "{\"domain\": {\"min\": [0,0,0], \"max\": [1,1,1], \"dx\": 0.05},"
    " \"time\": {\"end\": 0.1, \"fps\": 20},"
    " \"materials\": [{\"name\": \"jelly\", \"model\": \"fixed_corotated\", \"E\": 1e4,"
    " \"nu\": 0.3, \"density\": 1000}, {\"name\": \"rubber\", \"model\": \"neo_hookean\","
    " \"E\": 1e4, \"nu\": 0.3, \"density\": 1000}],"
    " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.4,0.5,0.5],"
    "   \"half_extent\": [0.12,0.12,0.12]}, \"material\": \"jelly\"},"
    "  {\"shape\": {\"type\": \"sphere\", \"center\": [0.7,0.3,0.5], \"radius\": 0.08},"
    "   \"material\": \"rubber\"}],"
    " \"colliders\": [{\"shape\": {\"type\": \"halfspace\", \"point\": [0,0.1,0],"
    "   \"normal\": [0,1,0]}, \"rule\": \"sticky\"}]}";

static char run_dir[700];

static int exists(const char *path) {
  struct stat st;
  return stat(path, &st) == 0;
}

/* Run the scene for 2 frames with output into run_dir (frames 0, 1 and 2). */
static int setup(void **state) {
  (void)state;
  snprintf(run_dir, sizeof run_dir, "%s/run", test_temp_dir("public_render"));
  mpm_sim *sim;
  char err[1024];
  if (mpm_sim_create_from_json(scene_json, NULL, &sim, err, sizeof err) != MPM_OK)
    fail_msg("create: %s", err);
  assert_int_equal(mpm_sim_set_frame_limit(sim, 2), MPM_OK);
  if (mpm_sim_enable_output(sim, run_dir) != MPM_OK) fail_msg("%s", mpm_sim_last_error(sim));
  while (mpm_sim_frame(sim) < mpm_sim_frame_count(sim))
    if (mpm_sim_advance_frame(sim) != MPM_OK) fail_msg("%s", mpm_sim_last_error(sim));
  mpm_sim_destroy(sim);
  return 0;
}

static int coloured_pixels(const unsigned char *px, int w, int h) {
  const rgb_image im = {w, h, (unsigned char *)px};
  int n = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) n += !greyish(&im, x, y);
  return n;
}

typedef struct seen {
  int calls, last_frame;
  char last_png[1200];
} seen;

static void on_picture(void *ctx, const mpm_renderer *r, const char *png_path, double seconds) {
  seen *s = ctx;
  mpm_render_info info;
  assert_int_equal(mpm_renderer_get_info(r, &info, sizeof info), MPM_OK);
  assert_int_equal(info.frame, s->calls); /* in order: frames 0, 1, 2 */
  assert_true(info.particles > 1000 && info.particles_drawn == info.particles);
  assert_true(seconds >= 0);
  s->last_frame = info.frame;
  snprintf(s->last_png, sizeof s->last_png, "%s", png_path);
  ++s->calls;
}

/* mpm_render_run writes every frame to RUN_DIR/render (or out_dir), calling back after each. */
static void test_render_run(void **state) {
  (void)state;
  mpm_render_options o = mpm_render_options_default();
  assert_int_equal(o.size, sizeof o);
  assert_int_equal(o.width, 1280);
  assert_int_equal(o.height, 720);
  o.width = 160, o.height = 120;
  seen s = {0, -1, ""};
  char err[1024];
  if (mpm_render_run(run_dir, &o, on_picture, &s, err, sizeof err) != MPM_OK)
    fail_msg("mpm_render_run: %s", err);
  assert_int_equal(s.calls, 3);
  char png[900];
  snprintf(png, sizeof png, "%s/render/frame_0002.png", run_dir);
  assert_string_equal(s.last_png, png);
  for (int k = 0; k < 3; ++k) {
    snprintf(png, sizeof png, "%s/render/frame_%04d.png", run_dir, k);
    rgb_image a = read_png(png);
    assert_int_equal(a.w, 160);
    assert_int_equal(a.h, 120);
    const int n = coloured_pixels(a.px, a.w, a.h);
    assert_true(n > 200 && n < a.w * a.h / 2); /* the two bodies, not the whole picture */
    assert_true(greyish(&a, 0, 0) && greyish(&a, a.w - 1, 0));
    free(a.px);
  }
  /* elsewhere, without callback */
  snprintf(png, sizeof png, "%s/elsewhere/deeper", run_dir);
  o.out_dir = png;
  o.every = 2;
  assert_int_equal(mpm_render_run(run_dir, &o, NULL, NULL, err, sizeof err), MPM_OK);
  snprintf(png, sizeof png, "%s/elsewhere/deeper/frame_0002.png", run_dir);
  assert_true(exists(png));
  snprintf(png, sizeof png, "%s/elsewhere/deeper/frame_0001.png", run_dir);
  assert_false(exists(png)); /* every 2nd */
}

/* A picture into the caller's buffer is the PNG's pixels; the renderer's choices are reported;
 * pictures drawn out of order or on another thread count are the same. */
static void test_buffer(void **state) {
  (void)state;
  mpm_render_options o = mpm_render_options_default();
  o.width = 160, o.height = 120;
  char err[1024];
  mpm_renderer *r;
  if (mpm_renderer_create(run_dir, &o, &r, err, sizeof err) != MPM_OK)
    fail_msg("mpm_renderer_create: %s", err);
  mpm_render_info info;
  assert_int_equal(mpm_renderer_get_info(r, &info, sizeof info), MPM_OK);
  assert_int_equal(info.pictures, 3);
  assert_int_equal(info.width, 160);
  assert_int_equal(info.frame, -1);
  /* the bodies fall freely, all alike: by material (by speed they would be one colour) */
  assert_int_equal(info.field, MPM_RENDER_FIELD_MATERIAL);
  assert_int_equal(info.colormap, MPM_RENDER_COLORMAP_CATEGORY);
  assert_true(info.range_lo == 0 && info.range_hi == 1);
  assert_false(info.scene_camera);
  assert_int_equal(info.framing, MPM_RENDER_FRAMING_MATERIAL);
  assert_true(info.fps == 20);
  assert_true(info.threads >= 1);
  assert_string_equal(info.run_dir, run_dir);
  char want[900];
  snprintf(want, sizeof want, "%s/render", run_dir);
  assert_string_equal(info.out_dir, want);

  const size_t size = 3 * 160 * 120;
  unsigned char *px = malloc(size), *again = malloc(size);
  assert_non_null(px);
  assert_non_null(again);
  assert_int_equal(mpm_renderer_pixels(r, px, size), MPM_ERR_INVALID); /* nothing drawn yet */
  assert_int_equal(mpm_renderer_draw(r, 3), MPM_ERR_INVALID);
  if (!strstr(mpm_renderer_last_error(r), "picture 3 out of range"))
    fail_msg("message: %s", mpm_renderer_last_error(r));
  /* picture 2 first, then 0: the camera was fixed before either */
  assert_int_equal(mpm_renderer_draw(r, 2), MPM_OK);
  assert_int_equal(mpm_renderer_draw(r, 0), MPM_OK);
  assert_string_equal(mpm_renderer_last_error(r), "");
  assert_int_equal(mpm_renderer_pixels(r, px, size - 1), MPM_ERR_INVALID); /* too small */
  assert_int_equal(mpm_renderer_pixels(r, px, size), MPM_OK);
  assert_int_equal(mpm_renderer_get_info(r, &info, sizeof info), MPM_OK);
  assert_int_equal(info.frame, 0);
  assert_true(info.time == 0);
  assert_true(info.particles > 1000);
  assert_int_equal(info.surfaces, 0);
  const int n = coloured_pixels(px, 160, 120);
  print_message("picture 0: %d of %d pixels show particles\n", n, 160 * 120);
  assert_true(n > 200 && n < 160 * 120 / 2);
  /* the PNG holds exactly these pixels (folders made on the way) */
  char png[900];
  snprintf(png, sizeof png, "%s/buffer/a/b/frame_0000.png", run_dir);
  assert_int_equal(mpm_renderer_write_png(r, png), MPM_OK);
  rgb_image a = read_png(png);
  assert_int_equal(a.w, 160);
  assert_int_equal(a.h, 120);
  assert_memory_equal(a.px, px, size);
  free(a.px);
  /* and mpm_render_run's picture of frame 0, drawn in order, is the same */
  snprintf(png, sizeof png, "%s/render/frame_0000.png", run_dir);
  if (exists(png)) {
    rgb_image b = read_png(png);
    assert_memory_equal(b.px, px, size);
    free(b.px);
  }
  mpm_renderer_destroy(r);

  /* one thread for the renderer's calls: the same picture, and the caller's count restored */
#ifdef _OPENMP
  const int before = omp_get_max_threads();
#endif
  o.threads = 1;
  assert_int_equal(mpm_renderer_create(run_dir, &o, &r, err, sizeof err), MPM_OK);
  assert_int_equal(mpm_renderer_get_info(r, &info, sizeof info), MPM_OK);
  assert_int_equal(info.threads, 1);
  assert_int_equal(mpm_renderer_draw(r, 0), MPM_OK);
  assert_int_equal(mpm_renderer_pixels(r, again, size), MPM_OK);
  assert_memory_equal(again, px, size);
#ifdef _OPENMP
  assert_int_equal(omp_get_max_threads(), before);
#endif
  mpm_renderer_destroy(r);

  /* coloured by speed: other pixels */
  o.threads = 0;
  o.field = MPM_RENDER_FIELD_VELOCITY;
  assert_int_equal(mpm_renderer_create(run_dir, &o, &r, err, sizeof err), MPM_OK);
  assert_int_equal(mpm_renderer_get_info(r, &info, sizeof info), MPM_OK);
  assert_int_equal(info.colormap, MPM_RENDER_COLORMAP_VIRIDIS);
  assert_true(info.range_lo == 0 && info.range_hi > 0);
  assert_int_equal(mpm_renderer_draw(r, 0), MPM_OK);
  assert_int_equal(mpm_renderer_pixels(r, again, size), MPM_OK);
  assert_true(memcmp(again, px, size) != 0);
  mpm_renderer_destroy(r);
  mpm_renderer_destroy(NULL);
  free(px);
  free(again);
}

static void expect_error(const char *err, const char *needle) {
  if (!strstr(err, needle)) fail_msg("expected '%s' in the message: %s", needle, err);
}

/* Bad folders and options fail with the status and a message naming them; nothing is made. */
static void test_errors(void **state) {
  (void)state;
  char err[1024], dir[900];
  mpm_renderer *r = (mpm_renderer *)&r;
  snprintf(dir, sizeof dir, "%s/nowhere", run_dir);
  assert_int_equal(mpm_renderer_create(dir, NULL, &r, err, sizeof err), MPM_ERR_IO);
  assert_null(r);
  expect_error(err, "nowhere: no such folder");
  assert_int_equal(mpm_render_run(dir, NULL, NULL, NULL, err, sizeof err), MPM_ERR_IO);
  expect_error(err, "nowhere");
  snprintf(dir, sizeof dir, "%s/empty", run_dir);
  assert_int_equal(mkdir(dir, 0777), 0);
  assert_int_equal(mpm_renderer_create(dir, NULL, &r, err, sizeof err), MPM_ERR_INVALID);
  expect_error(err, "no frame_NNNN.vtu files");
  snprintf(dir, sizeof dir, "%s/empty/render", run_dir);
  assert_false(exists(dir));

  mpm_render_options o = mpm_render_options_default();
  o.width = 10;
  assert_int_equal(mpm_renderer_create(run_dir, &o, &r, err, sizeof err), MPM_ERR_INVALID);
  expect_error(err, "mpm_render_options.width");
  o = mpm_render_options_default();
  o.margin = 0.9;
  assert_int_equal(mpm_renderer_create(run_dir, &o, &r, err, sizeof err), MPM_ERR_INVALID);
  expect_error(err, "mpm_render_options.margin");
  o = mpm_render_options_default();
  o.size = 0; /* not started from the default */
  assert_int_equal(mpm_renderer_create(run_dir, &o, &r, err, sizeof err), MPM_ERR_INVALID);
  expect_error(err, "mpm_render_options_default");
  o = mpm_render_options_default();
  o.field = MPM_RENDER_FIELD_TEMPERATURE; /* the run has no heat */
  assert_int_equal(mpm_renderer_create(run_dir, &o, &r, err, sizeof err), MPM_ERR_INVALID);
  expect_error(err, "frame_0000.vtu: the frames have no 'temperature' array");
  o = mpm_render_options_default();
  o.grid = 1; /* a uniform grid */
  assert_int_equal(mpm_renderer_create(run_dir, &o, &r, err, sizeof err), MPM_ERR_INVALID);
  expect_error(err, "grid_cells.vtu");
  o = mpm_render_options_default();
  o.scene = "/nonexistent/scene.json";
  assert_int_equal(mpm_renderer_create(run_dir, &o, &r, err, sizeof err), MPM_ERR_IO);
  expect_error(err, "/nonexistent/scene.json");

  /* the names, both ways */
  mpm_render_field f = MPM_RENDER_FIELD_AUTO;
  assert_int_equal(mpm_render_field_from_name("stress", &f), MPM_OK);
  assert_int_equal(f, MPM_RENDER_FIELD_STRESS);
  assert_string_equal(mpm_render_field_name(MPM_RENDER_FIELD_MELT), "melt");
  assert_int_equal(mpm_render_field_from_name("colour", &f), MPM_ERR_INVALID);
  assert_int_equal(f, MPM_RENDER_FIELD_STRESS);
  assert_null(mpm_render_field_name(MPM_RENDER_FIELD_AUTO));
  mpm_render_colormap c;
  assert_int_equal(mpm_render_colormap_from_name("coolwarm", &c), MPM_OK);
  assert_int_equal(c, MPM_RENDER_COLORMAP_COOLWARM);
  assert_string_equal(mpm_render_colormap_name(MPM_RENDER_COLORMAP_CATEGORY), "category");
  mpm_render_framing fr;
  assert_int_equal(mpm_render_framing_from_name("follow", &fr), MPM_OK);
  assert_int_equal(fr, MPM_RENDER_FRAMING_FOLLOW);
  assert_string_equal(mpm_render_framing_name(MPM_RENDER_FRAMING_DOMAIN), "domain");
  assert_string_equal(mpm_status_string(MPM_ERR_EXTERNAL), "external program failed");
}

static int plotted;
static void on_plot(void *ctx, const char *png_path) {
  (void)ctx;
  assert_true(exists(png_path));
  ++plotted;
}

/* stats.csv into the public table, and its plots. */
static void test_stats_and_plot(void **state) {
  (void)state;
  char path[900], err[8192];
  snprintf(path, sizeof path, "%s/stats.csv", run_dir);
  mpm_stats_table t;
  if (mpm_stats_read(path, &t, err, sizeof err) != MPM_OK) fail_msg("mpm_stats_read: %s", err);
  assert_int_equal(t.rows, 3);
  assert_int_equal(t.columns, MPM_STATS_COLUMNS);
  assert_true(t.stride >= MPM_STATS_COLUMNS);
  assert_int_equal(t.colliders, 1);
  assert_string_equal(t.path, path);
  for (size_t i = 0; i < t.rows; ++i) {
    const double *r = t.values + i * (size_t)t.stride;
    assert_true(r[MPM_STATS_FRAME] == (double)i);
    assert_true(fabs(r[MPM_STATS_TIME] - 0.05 * (double)i) < 1e-9);
    assert_true(r[MPM_STATS_PARTICLES] > 1000);
    assert_true(r[MPM_STATS_MASS] > 0);
  }
  assert_true(t.values[2 * (size_t)t.stride + MPM_STATS_STEPS] > 0);
  assert_string_equal(mpm_stats_column_name(MPM_STATS_TOTAL_ENERGY), "total_energy");
  assert_null(mpm_stats_column_name(MPM_STATS_COLUMNS));

  /* gnuplot that is not there: nothing written */
  mpm_plot_options po = mpm_plot_options_default();
  assert_int_equal(po.size, sizeof po);
  po.gnuplot = "/nonexistent/gnuplot";
  assert_int_equal(mpm_plot_stats(&t, &po, NULL, NULL, err, sizeof err), MPM_ERR_EXTERNAL);
  expect_error(err, "/nonexistent/gnuplot");
  snprintf(path, sizeof path, "%s/plots", run_dir);
  assert_false(exists(path));
  if (system("command -v gnuplot >/dev/null 2>&1") == 0) {
    plotted = 0;
    if (mpm_plot_run(run_dir, NULL, on_plot, NULL, err, sizeof err) != MPM_OK)
      fail_msg("mpm_plot_run: %s", err);
    assert_int_equal(plotted, 8); /* seven and the collider's force */
    snprintf(path, sizeof path, "%s/plots/collider_forces.png", run_dir);
    assert_true(exists(path));
  } else {
    print_message("[  SKIPPED ] gnuplot is not installed: plots not drawn\n");
  }
  /* one frame is too few to plot */
  t.rows = 1;
  assert_int_equal(mpm_plot_stats(&t, NULL, NULL, NULL, err, sizeof err), MPM_ERR_INVALID);
  expect_error(err, "need at least 2");
  t.rows = 3;
  mpm_stats_free(&t);
  assert_null(t.values);
  mpm_stats_free(&t); /* a zeroed table */

  snprintf(path, sizeof path, "%s/nowhere/stats.csv", run_dir);
  assert_int_equal(mpm_stats_read(path, &t, err, sizeof err), MPM_ERR_IO);
  expect_error(err, path);
  assert_int_equal(mpm_plot_run("/nonexistent/run", NULL, NULL, NULL, err, sizeof err), MPM_ERR_IO);
  expect_error(err, "/nonexistent/run");
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_render_run),
                                     cmocka_unit_test(test_buffer), cmocka_unit_test(test_errors),
                                     cmocka_unit_test(test_stats_and_plot)};
  return test_cleanup(cmocka_run_group_tests_name("public_render", tests, setup, NULL));
}
