/* test_plot.c - `mpm plot OUTDIR` as users run it: the seven PNGs from a synthetic stats.csv (of
 * every column layout mpm run has written, collider force columns included) and from a real short
 * run, exit code 2 with the file and line named for a missing directory or a corrupt stats.csv (and
 * no plots directory made), exit code 1 when gnuplot is not on PATH or fails (its messages shown,
 * earlier plots kept, no temporaries left), usage errors. The parts that need gnuplot are skipped,
 * with a message, where it is not installed. */
#include "support.h"
#include "cli_support.h"

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>

static const char *const png_files[] = {
    "energy.png",          "momentum.png",       "angular_momentum.png", "dt.png",
    "steps_per_frame.png", "wall_per_frame.png", "enriched.png"};
enum { PNG_COUNT = sizeof png_files / sizeof png_files[0] };

static const char stats_header[] =
    "frame,time,steps,dt,kinetic_energy,elastic_energy,momentum_x,momentum_y,momentum_z,"
    "angular_momentum_x,angular_momentum_y,angular_momentum_z,mass,particles,wall_seconds\n";

static int have_gnuplot(void) {
  if (system("command -v gnuplot >/dev/null 2>&1") == 0) return 1;
  print_message("[  SKIPPED ] gnuplot is not installed (apt-get install gnuplot-nox): "
                "plots not checked\n");
  return 0;
}

/* A stats.csv as mpm run writes it: `frames` rows (frame 0 the initial state), cumulative
 * steps, per-frame wall seconds. */
static void write_stats(const char *dir, int frames) {
  char path[700];
  snprintf(path, sizeof path, "%s/stats.csv", dir);
  FILE *f = fopen(path, "w");
  assert_non_null(f);
  fputs(stats_header, f);
  long steps = 0;
  for (int i = 0; i < frames; ++i) {
    const double t = i / 24.0, v = 9.81 * t;
    steps += i ? 50 + 3 * i : 0;
    fprintf(f, "%d,%.9g,%ld,%.9g,%.9g,%.9g,0,%.17g,1e-15,%.17g,0,-2e-14,2,1000,%.9g\n", i, t, steps,
            i ? 1e-3 / (1 + i) : 0.0, 0.5 * 2 * v * v, 0.01 * i, -2 * v, 0.5 * v, 0.03 + 0.1 * i);
  }
  fclose(f);
}

/* A stats.csv of every layout mpm run has written: 15 columns (before the implicit solver's), 20
 * (before enriched_percent), 21 (before dt_min, dt_max, gravitational_energy, total_energy) and
 * today's 25; each later one adds columns at the end of the row. */
static void write_stats_layout(const char *dir, int frames, int columns) {
  char path[700];
  snprintf(path, sizeof path, "%s/stats.csv", dir);
  FILE *f = fopen(path, "w");
  assert_non_null(f);
  static const char *const extra[] = {
      ",cg_iterations_mean,cg_iterations_max,cg_residual_max,newton_iterations_mean,"
      "cg_unconverged",
      ",enriched_percent", ",dt_min,dt_max,gravitational_energy,total_energy"};
  const int parts = columns >= 25 ? 3 : columns >= 21 ? 2 : columns >= 20 ? 1 : 0;
  fprintf(f, "%.*s", (int)strlen(stats_header) - 1, stats_header);
  for (int k = 0; k < parts; ++k) fputs(extra[k], f);
  const int colliders = columns > 25 ? (columns - 25) / 3 : 0; /* their forces, at the end */
  for (int c = 0; c < colliders; ++c)
    fprintf(f, ",collider%d_fx,collider%d_fy,collider%d_fz", c, c, c);
  fputc('\n', f);
  long steps = 0;
  for (int i = 0; i < frames; ++i) {
    const double t = i / 24.0, v = 9.81 * t, ke = 0.5 * 2 * v * v, g = 2 * 9.81 * (1 - 0.5 * v * t);
    steps += i ? 50 + 3 * i : 0;
    fprintf(f, "%d,%.9g,%ld,%.9g,%.9g,%.9g,0,%.17g,1e-15,%.17g,0,-2e-14,2,1000,%.9g", i, t, steps,
            i ? 1e-3 / (1 + i) : 0.0, ke, 0.01 * i, -2 * v, 0.5 * v, 0.03 + 0.1 * i);
    if (parts > 0) fputs(",0,0,0,0,0", f);
    if (parts > 1) fprintf(f, ",%g", 2.5 * i);
    if (parts > 2)
      fprintf(f, ",%.9g,%.9g,%.9g,%.9g", i ? 0.6e-3 / (1 + i) : 0.0, i ? 1.1e-3 / (1 + i) : 0.0, g,
              ke + 0.01 * i + g);
    for (int c = 0; c < colliders; ++c) fprintf(f, ",0.5,%g,0", i ? -19.62 : 0.0);
    fputc('\n', f);
  }
  fclose(f);
}

/* All seven PNGs in dir, and collider_forces.png when the run had colliders, non-empty, with the
 * PNG signature; nothing else there (no temporaries left behind). */
static void expect_pngs_of(const char *dir, int colliders) {
  static const unsigned char signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  char path[800];
  for (int i = 0; i < PNG_COUNT; ++i) {
    snprintf(path, sizeof path, "%s/%s", dir, png_files[i]);
    FILE *f = fopen(path, "rb");
    if (!f) fail_msg("missing %s; mpm said:\n%s", path, output);
    unsigned char head[8] = {0};
    const size_t n = fread(head, 1, sizeof head, f);
    fseek(f, 0, SEEK_END);
    const long size = ftell(f);
    fclose(f);
    if (n != 8 || memcmp(head, signature, 8) != 0) fail_msg("%s is not a PNG file", path);
    if (size < 1000) fail_msg("%s has only %ld bytes", path, size);
  }
  DIR *d = opendir(dir);
  assert_non_null(d);
  int entries = 0;
  for (struct dirent *e; (e = readdir(d));) {
    if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, "..")) continue;
    ++entries;
    if (!strstr(e->d_name, ".png") || e->d_name[0] == '.')
      fail_msg("left in %s: %s", dir, e->d_name);
  }
  closedir(d);
  snprintf(path, sizeof path, "%s/collider_forces.png", dir);
  FILE *f = fopen(path, "rb");
  if (colliders && !f) fail_msg("missing %s; mpm said:\n%s", path, output);
  if (!colliders && f) fail_msg("%s written for a run without colliders", path);
  if (f) {
    fseek(f, 0, SEEK_END);
    if (ftell(f) < 1000) fail_msg("%s has only %ld bytes", path, ftell(f));
    fclose(f);
  }
  assert_int_equal(entries, PNG_COUNT + (colliders > 0));
}

static void expect_pngs(const char *dir) {
  expect_pngs_of(dir, 0);
}

static void test_synthetic_stats(void **state) {
  (void)state;
  const char *tmp = test_temp_dir("plot-synthetic");
  char dir[600], args[1400], plots[700];
  snprintf(dir, sizeof dir, "%s", tmp);
  write_stats(dir, 5);
  if (!have_gnuplot()) return;
  snprintf(args, sizeof args, "plot '%s'", dir);
  if (mpm(args) != 0) fail_msg("mpm plot failed:\n%s", output);
  snprintf(plots, sizeof plots, "%s/plots", dir);
  expect_pngs(plots);
  for (int i = 0; i < PNG_COUNT; ++i) expect_output(png_files[i]); /* one line per file */
  /* again, over the existing plots, to --out with --quiet: nothing printed */
  snprintf(plots, sizeof plots, "%s/elsewhere/deeper", dir);
  snprintf(args, sizeof args, "plot '%s' --out '%s' --quiet", dir, plots);
  if (mpm(args) != 0) fail_msg("mpm plot --out failed:\n%s", output);
  assert_int_equal((int)strlen(output), 0);
  expect_pngs(plots);
  /* the smallest plottable run: the initial state and one frame */
  write_stats(dir, 2);
  snprintf(args, sizeof args, "plot '%s' -q", dir);
  if (mpm(args) != 0) fail_msg("mpm plot of 2 frames failed:\n%s", output);
  assert_int_equal((int)strlen(output), 0); /* gnuplot's warnings about one point stay quiet */
}

/* Files of every layout plot (the columns an older file lacks are left out of the plots), and
 * today's with the force columns of one and of two colliders. */
static void test_every_layout(void **state) {
  (void)state;
  static const int layouts[] = {15, 20, 21, 25, 28, 31};
  for (int k = 0; k < 6; ++k) {
    char name[64], args[1400], plots[700];
    snprintf(name, sizeof name, "plot-layout-%d", layouts[k]);
    const char *dir = test_temp_dir(name);
    write_stats_layout(dir, 6, layouts[k]);
    if (!have_gnuplot()) return;
    snprintf(args, sizeof args, "plot '%s' --quiet", dir);
    if (mpm(args) != 0) fail_msg("mpm plot of a %d-column file failed:\n%s", layouts[k], output);
    snprintf(plots, sizeof plots, "%s/plots", dir);
    expect_pngs_of(plots, layouts[k] > 25 ? (layouts[k] - 25) / 3 : 0);
  }
  /* a header of 22 columns is no layout mpm wrote */
  const char *dir = test_temp_dir("plot-layout-22");
  write_stats_layout(dir, 3, 21);
  char path[700], args[1400];
  snprintf(path, sizeof path, "%s/stats.csv", dir);
  FILE *f = fopen(path, "w");
  assert_non_null(f);
  fprintf(f,
          "%.*s,cg_iterations_mean,cg_iterations_max,cg_residual_max,newton_iterations_mean,"
          "cg_unconverged,enriched_percent,dt_min\n0",
          (int)strlen(stats_header) - 1, stats_header);
  fclose(f);
  snprintf(args, sizeof args, "plot '%s'", dir);
  assert_int_equal(mpm(args), 2);
  expect_output("22 columns");
  /* after total_energy only whole colliders, named in order */
  static const char *const bad[] = {",collider0_fx,collider0_fy",
                                    ",collider0_fx,collider0_fy,collider1_fz"};
  static const char *const said[] = {"2 columns after total_energy", "column 28 is 'collider1_fz'"};
  for (int k = 0; k < 2; ++k) {
    write_stats_layout(dir, 3, 25);
    f = fopen(path, "w");
    assert_non_null(f);
    fprintf(f,
            "%.*s,cg_iterations_mean,cg_iterations_max,cg_residual_max,newton_iterations_mean,"
            "cg_unconverged,enriched_percent,dt_min,dt_max,gravitational_energy,total_energy%s\n",
            (int)strlen(stats_header) - 1, stats_header, bad[k]);
    fclose(f);
    assert_int_equal(mpm(args), 2);
    expect_output(said[k]);
  }
}

static void test_missing_directory(void **state) {
  (void)state;
  assert_int_equal(mpm("plot /nonexistent/run-dir"), 2);
  expect_output("/nonexistent/run-dir");
  /* a directory without stats.csv */
  const char *dir = test_temp_dir("plot-empty");
  char args[1400], path[700];
  snprintf(args, sizeof args, "plot '%s'", dir);
  assert_int_equal(mpm(args), 2);
  snprintf(path, sizeof path, "%s/stats.csv", dir);
  expect_output(path);
  snprintf(path, sizeof path, "%s/plots", dir);
  assert_false(exists(path));
}

static void test_corrupt_stats(void **state) {
  (void)state;
  const char *tmp = test_temp_dir("plot-corrupt");
  char dir[600], csv[700], args[1400], path[800];
  snprintf(dir, sizeof dir, "%s", tmp);
  snprintf(csv, sizeof csv, "%s/stats.csv", dir);
  const char *ok_rows = "0,0,0,0,0,0,0,0,0,0,0,0,1,10,0.1\n"
                        "1,0.1,5,0.02,1,0,0,0,0,0,0,0,1,10,0.1\n";
  char text[4096];
  struct {
    const char *rows, *needle1, *needle2;
    int line;
  } cases[] = {
      {NULL, "line 1", "steps", 1}, /* bad header */
      {"2,0.2,10,0.02,abc,0,0,0,0,0,0,0,1,10,0.1\n", "field 5", "abc", 4},
      {"2,0.2,10,0.02,1,0,0,0,0,0,0,0,1,10\n", "14 fields", "15", 4},
      {"2,0.2,10,0.02,1,,0,0,0,0,0,0,1,10,0.1\n", "field 6", "elastic_energy", 4},
      {"2,0.2,10,0.02,1,inf,0,0,0,0,0,0,1,10,0.1\n", "field 6", "finite", 4},
  };
  for (size_t c = 0; c < sizeof cases / sizeof cases[0]; ++c) {
    if (cases[c].rows)
      snprintf(text, sizeof text, "%s%s%s", stats_header, ok_rows, cases[c].rows);
    else
      snprintf(text, sizeof text, "frame,time,step,dt\n%s", ok_rows);
    write_file(csv, text);
    snprintf(args, sizeof args, "plot '%s'", dir);
    assert_int_equal(mpm(args), 2);
    expect_output(csv);
    char line[32];
    snprintf(line, sizeof line, "line %d", cases[c].line);
    expect_output(line);
    expect_output(cases[c].needle1);
    expect_output(cases[c].needle2);
    snprintf(path, sizeof path, "%s/plots", dir);
    assert_false(exists(path));
    snprintf(args, sizeof args, "plot '%s' --out '%s/out'", dir, dir);
    assert_int_equal(mpm(args), 2);
    snprintf(path, sizeof path, "%s/out", dir);
    assert_false(exists(path));
  }
  /* a header and no frames: nothing to draw */
  write_file(csv, stats_header);
  snprintf(args, sizeof args, "plot '%s'", dir);
  assert_int_equal(mpm(args), 2);
  expect_output("at least 2");
}

static void test_real_run(void **state) {
  (void)state;
  const char *tmp = test_temp_dir("plot-run");
  char dir[600], args[1400], plots[700];
  snprintf(dir, sizeof dir, "%s/out", tmp);
  snprintf(args, sizeof args, "run examples/jello_cubes.json -o '%s' --frames 3 --quiet", dir);
  if (mpm(args) != 0) fail_msg("mpm run failed:\n%s", output);
  if (!have_gnuplot()) return;
  snprintf(args, sizeof args, "plot '%s'", dir);
  if (mpm(args) != 0) fail_msg("mpm plot failed:\n%s", output);
  snprintf(plots, sizeof plots, "%s/plots", dir);
  expect_pngs_of(plots, 1); /* jello_cubes has a floor: its force is plotted too */
}

static void test_gnuplot_missing_or_failing(void **state) {
  (void)state;
  const char *tmp = test_temp_dir("plot-nognuplot");
  char dir[600], args[1400], path[800], env[1400];
  snprintf(dir, sizeof dir, "%s", tmp);
  write_stats(dir, 4);
  snprintf(args, sizeof args, "plot '%s'", dir);
  assert_int_equal(mpm_env("PATH=/nonexistent", args), 1);
  expect_output("mpm plot: gnuplot not found; install it with: apt-get install gnuplot-nox");
  snprintf(path, sizeof path, "%s/plots", dir);
  assert_false(exists(path));

  /* a gnuplot that fails: its message reaches the user, earlier plots stay, no temporaries */
  snprintf(path, sizeof path, "%s/bin", dir);
  assert_int_equal(mkdir(path, 0777), 0);
  snprintf(path, sizeof path, "%s/bin/gnuplot", dir);
  write_file(path, "#!/bin/sh\necho 'gnuplot says: no luck' >&2\nexit 3\n");
  assert_int_equal(chmod(path, 0755), 0);
  snprintf(path, sizeof path, "%s/plots", dir);
  assert_int_equal(mkdir(path, 0777), 0);
  snprintf(path, sizeof path, "%s/plots/energy.png", dir);
  write_file(path, "old");
  snprintf(env, sizeof env, "PATH='%s/bin':\"$PATH\"", dir);
  assert_int_equal(mpm_env(env, args), 1);
  expect_output("gnuplot says: no luck");
  expect_output("gnuplot failed");
  FILE *f = fopen(path, "r");
  assert_non_null(f);
  char old[8] = {0};
  assert_int_equal((int)fread(old, 1, sizeof old - 1, f), 3);
  fclose(f);
  assert_string_equal(old, "old");
  snprintf(path, sizeof path, "%s/plots", dir);
  DIR *d = opendir(path);
  assert_non_null(d);
  for (struct dirent *e; (e = readdir(d));) {
    const char *name = e->d_name;
    if (strcmp(name, ".") && strcmp(name, "..") && strcmp(name, "energy.png"))
      fail_msg("left in %s after the failure: %s", path, name);
  }
  closedir(d);
}

static void test_usage(void **state) {
  (void)state;
  assert_int_equal(mpm("plot"), 2);
  expect_output("usage: mpm plot");
  assert_int_equal(mpm("plot /tmp --frobnicate"), 2);
  expect_output("--frobnicate");
  expect_output("usage: mpm plot");
  assert_int_equal(mpm("plot /tmp --out"), 2);
  expect_output("--out");
  assert_int_equal(mpm("plot /tmp /var"), 2);
  assert_int_equal(mpm("plot --help"), 0);
  expect_output("usage: mpm plot");
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_synthetic_stats),
      cmocka_unit_test(test_every_layout),
      cmocka_unit_test(test_missing_directory),
      cmocka_unit_test(test_corrupt_stats),
      cmocka_unit_test(test_real_run),
      cmocka_unit_test(test_gnuplot_missing_or_failing),
      cmocka_unit_test(test_usage),
  };
  return test_cleanup(cmocka_run_group_tests(tests, NULL, NULL));
}
