/* test_cli.c - the `mpm` program as users run it: exit codes (0 ok, 1 simulation failure,
 * 2 usage or input error), messages that name the file and key path, `check` writes nothing,
 * and a short run of an example writes VTU frames, a PVD index and stats. */
#include "support.h"
#include "cli_support.h"
#include "scene/scene.h"

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>

static const char *good_scene = "{\"domain\": {\"min\": [0,0,0], \"max\": [1,1,1], \"dx\": 0.05},"
                                " \"time\": {\"end\": 0.2, \"fps\": 20},"
                                " \"materials\": [{\"name\": \"jello\", \"model\": "
                                "\"fixed_corotated\", \"E\": 1e4, \"nu\": 0.3, \"density\": 1000}],"
                                " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": "
                                "[0.5,0.5,0.5], \"half_extent\": [0.1,0.1,0.1]},"
                                "               \"material\": \"jello\"}]}";

static void test_help_and_version(void **state) {
  (void)state;
  assert_int_equal(mpm("--version"), 0);
  expect_output("mpm ");
  /* the program's threads spin a while, then sleep, unless the environment says otherwise
     (app/main.c) */
  assert_int_equal(mpm_env("env -u OMP_WAIT_POLICY -u GOMP_SPINCOUNT", "--version"), 0);
  expect_output("OpenMP threads spin 10000 times, then sleep");
  assert_int_equal(mpm_env("env -u OMP_WAIT_POLICY GOMP_SPINCOUNT=500", "--version"), 0);
  expect_output("OpenMP threads spin 500 times");
  assert_int_equal(mpm_env("env OMP_WAIT_POLICY=active", "--version"), 0);
  expect_output("OpenMP threads wait active");
  assert_int_equal(mpm("--help"), 0);
  expect_output("mpm run");
  assert_int_equal(mpm(""), 2);
  assert_int_equal(mpm("frobnicate"), 2);
  expect_output("unknown command");
  assert_int_equal(mpm("run"), 2);
  assert_int_equal(mpm("run x.json --threads zero"), 2);
  expect_output("--threads");
}

static void test_missing_file(void **state) {
  (void)state;
  assert_int_equal(mpm("check /nonexistent/scene.json"), 2);
  expect_output("/nonexistent/scene.json");
}

static void test_bad_scenes_exit_2_and_write_nothing(void **state) {
  (void)state;
  const char *dir = test_temp_dir("cli-bad");
  char path[600], out[600], args[1400];
  struct {
    const char *json, *needle1, *needle2;
  } cases[] = {
      {"{\"domain\": {\"min\": [0,0,0], \"max\": [1,1,1], \"dx\": 0.05}, \"time\": {\"end\": 1}, "
       "\"solver\": {\"kernal\": \"cubic\"}, \"materials\": [], \"bodies\": []}",
       "solver.kernal", "kernel"},
      {"{\"domain\": {\"min\": [0,0,0], \"max\": [1,1,1], \"dx\": 0.05}, \"time\": {\"end\": 1},"
       " \"materials\": [{\"name\": \"j\", \"model\": \"neo_hookean\", \"E\": -5, \"nu\": 0.3, "
       "\"density\": 1000}],"
       " \"bodies\": [{\"shape\": {\"type\": \"sphere\", \"center\": [0.5,0.5,0.5], \"radius\": "
       "0.1}, \"material\": \"j\"}]}",
       "materials[0].E", "> 0"},
      {"{\"domain\": {\"min\": [0,0,0], \"max\": [1,1,1], \"dx\": 0.05},\n \"time\": {\"end\": "
       "1,}\n}",
       "line", "JSON"},
  };
  for (size_t c = 0; c < sizeof cases / sizeof cases[0]; ++c) {
    snprintf(path, sizeof path, "%s/bad%zu.json", dir, c);
    snprintf(out, sizeof out, "%s/out%zu", dir, c);
    write_file(path, cases[c].json);
    snprintf(args, sizeof args, "check '%s'", path);
    assert_int_equal(mpm(args), 2);
    expect_output(path);
    expect_output(cases[c].needle1);
    expect_output(cases[c].needle2);
    snprintf(args, sizeof args, "run '%s' -o '%s' --quiet", path, out);
    assert_int_equal(mpm(args), 2);
    assert_false(exists(out)); /* nothing simulated or written */
  }
}

/* Every scene shipped in examples/ and examples/zhu/ passes `mpm check`. */
static void test_check_examples(void **state) {
  (void)state;
  static const char *const dirs[] = {"examples", "examples/zhu", "examples/gao"};
  int checked = 0;
  for (size_t k = 0; k < sizeof dirs / sizeof dirs[0]; ++k) {
    DIR *d = opendir(dirs[k]);
    if (!d) fail_msg("cannot list %s", dirs[k]);
    for (struct dirent *e = readdir(d); e; e = readdir(d)) {
      const size_t n = strlen(e->d_name);
      if (n < 6 || strcmp(e->d_name + n - 5, ".json")) continue;
      char args[600];
      snprintf(args, sizeof args, "check %s/%s", dirs[k], e->d_name);
      if (mpm(args) != 0) fail_msg("%s/%s: %s", dirs[k], e->d_name, output);
      expect_output("ok");
      /* the examples start where they mean to (no overlaps, nothing inside an obstacle) */
      if (strstr(output, "overlap") || strstr(output, "start inside"))
        fail_msg("%s/%s: %s", dirs[k], e->d_name, output);
      ++checked;
    }
    closedir(d);
  }
  print_message("%d example scenes checked\n", checked);
  assert_true(checked >= 25);
}

/* Issue 17 defect 7: the linear kernel on material points is the cell-crossing instability;
 * check and run warn and say why (with another kernel, no warning). And check prints the first
 * step's dt and the steps per frame, with a warning past 10^4. */
static void test_linear_kernel_warning(void **state) {
  (void)state;
  char dir[400];
  snprintf(dir, sizeof dir, "%s", test_temp_dir("linwarn"));
  char path[512], args[1200];
  static const char *const scenes[] = {"linear", "quadratic"};
  for (int c = 0; c < 2; ++c) {
    char json[1024];
    snprintf(json, sizeof json,
             "{\"domain\": {\"min\": [0, 0, 0], \"max\": [1, 1, 1], \"dx\": 0.1}, "
             "\"time\": {\"end\": 0.02, \"fps\": 100}, \"solver\": {\"kernel\": \"%s\"}, "
             "\"materials\": [{\"name\": \"jelly\", \"model\": \"fixed_corotated\", "
             "\"E\": 1e4, \"nu\": 0.3, \"density\": 1000}], "
             "\"bodies\": [{\"material\": \"jelly\", \"shape\": {\"type\": \"box\", "
             "\"center\": [0.5, 0.5, 0.5], \"half_extent\": [0.15, 0.15, 0.15]}}]}",
             scenes[c]);
    snprintf(path, sizeof path, "%s/%s.json", dir, scenes[c]);
    write_file(path, json);
    snprintf(args, sizeof args, "check '%s'", path);
    assert_int_equal(mpm(args), 0);
    if (c == 0) {
      expect_output("warning");
      expect_output("cell-crossing");
      expect_output("ugimp");
      snprintf(args, sizeof args, "run '%s' -o '%s/out' --quiet", path, dir);
      assert_int_equal(mpm(args), 0);
      expect_output("cell-crossing");
    } else {
      assert_null(strstr(output, "warning"));
      expect_output("steps per frame");
    }
  }
  /* issue 17: past 10^4 steps per frame check warns (a modulus typed in the wrong unit, E = 1e13
     Pa, on a 1 cm grid) */
  write_file(path, "{\"domain\": {\"min\": [0, 0, 0], \"max\": [1, 1, 1], \"dx\": 0.01}, "
                   "\"time\": {\"end\": 0.1, \"fps\": 24}, "
                   "\"materials\": [{\"name\": \"steel\", \"model\": \"fixed_corotated\", "
                   "\"E\": 1e13, \"nu\": 0.3, \"density\": 1000}], "
                   "\"bodies\": [{\"material\": \"steel\", \"shape\": {\"type\": \"box\", "
                   "\"center\": [0.5, 0.5, 0.5], \"half_extent\": [0.02, 0.02, 0.02]}}]}");
  snprintf(args, sizeof args, "check '%s'", path);
  assert_int_equal(mpm(args), 0);
  expect_output("steps per frame");
  expect_output("more than 10^4");
}

/* A friction angle in radians by mistake (0.61 for 35 degrees) is accepted, as the key takes
 * degrees, but check warns of it with the key path and the angle it would be; 30 degrees does
 * not warn. */
static void test_friction_angle_warning(void **state) {
  (void)state;
  char dir[400], path[512], args[1200];
  snprintf(dir, sizeof dir, "%s", test_temp_dir("friction"));
  static const double angles[] = {0.61, 30};
  for (int c = 0; c < 2; ++c) {
    char json[1024];
    snprintf(json, sizeof json,
             "{\"domain\": {\"min\": [0, 0, 0], \"max\": [1, 1, 1], \"dx\": 0.1}, "
             "\"time\": {\"end\": 0.02, \"fps\": 100}, "
             "\"materials\": [{\"name\": \"sand\", \"model\": \"drucker_prager\", "
             "\"E\": 3.5e5, \"nu\": 0.3, \"density\": 1600, \"friction_angle\": %g}], "
             "\"bodies\": [{\"material\": \"sand\", \"shape\": {\"type\": \"box\", "
             "\"center\": [0.5, 0.5, 0.5], \"half_extent\": [0.15, 0.15, 0.15]}}]}",
             angles[c]);
    snprintf(path, sizeof path, "%s/sand%d.json", dir, c);
    write_file(path, json);
    snprintf(args, sizeof args, "check '%s'", path);
    assert_int_equal(mpm(args), 0);
    if (c == 0) {
      expect_output("warning");
      expect_output("materials[0].friction_angle is 0.61 degrees");
      expect_output("35 degrees");
    } else {
      assert_null(strstr(output, "warning"));
    }
  }
}

/* A heat conductivity that makes conduction take more than 100 substeps a step (1e30 W/(m K),
 * a unit slip: 10^6 substeps, minutes a step) is warned of by check, with the count; an
 * ordinary one is not. */
static void test_heat_cost_warning(void **state) {
  (void)state;
  char dir[400], path[512], args[1200];
  snprintf(dir, sizeof dir, "%s", test_temp_dir("heatcost"));
  static const double k[] = {1e30, 0.5};
  for (int c = 0; c < 2; ++c) {
    char json[1024];
    snprintf(json, sizeof json,
             "{\"domain\": {\"min\": [0, 0, 0], \"max\": [1, 1, 1], \"dx\": 0.1}, "
             "\"time\": {\"end\": 0.02, \"fps\": 100}, \"heat\": {\"temperature\": 20}, "
             "\"materials\": [{\"name\": \"wax\", \"model\": \"neo_hookean\", "
             "\"E\": 1e4, \"nu\": 0.3, \"density\": 1000, \"conductivity\": %g}], "
             "\"bodies\": [{\"material\": \"wax\", \"shape\": {\"type\": \"box\", "
             "\"center\": [0.5, 0.5, 0.5], \"half_extent\": [0.15, 0.15, 0.15]}}]}",
             k[c]);
    snprintf(path, sizeof path, "%s/heat%d.json", dir, c);
    write_file(path, json);
    snprintf(args, sizeof args, "check '%s'", path);
    assert_int_equal(mpm(args), 0);
    if (c == 0) {
      expect_output("warning");
      expect_output("heat: conduction needs 1000000 (the cap) substeps per step");
      expect_output("materials[].conductivity");
    } else {
      assert_null(strstr(output, "warning"));
    }
  }
}

/* A mistyped command or option gets "did you mean" (as scene keys do); a far one does not. mpm
 * check on an implicit scene says the implicit step's rule, not the explicit wave-speed one. */
static void test_did_you_mean_and_implicit_check(void **state) {
  (void)state;
  static const struct {
    const char *args, *said;
  } slips[] = {
      {"rnu x.json", "did you mean 'run'?"},
      {"run x.json --overwrit", "did you mean '--overwrite'?"},
      {"run x.json --thread 2", "did you mean '--threads'?"},
      {"render out --feild J", "did you mean '--field'?"},
      {"plot out --quite", "did you mean '--quiet'?"},
  };
  for (size_t k = 0; k < sizeof slips / sizeof slips[0]; ++k) {
    assert_int_equal(mpm(slips[k].args), 2);
    expect_output(slips[k].said);
  }
  assert_int_equal(mpm("run x.json --zzzz"), 2);
  assert_null(strstr(output, "did you mean"));
  assert_int_equal(mpm("check examples/stiff_bar_bending.json"), 0);
  expect_output("implicit: the scene's fixed solver.dt");
  assert_null(strstr(output, "wave speed"));
}

/* Issue 17: check and run report bodies that overlap (twice as dense there) and bodies that
 * start inside a slip collider; a sticky one holding material is a grip and is not reported. */
static void test_placement_warnings(void **state) {
  (void)state;
  char dir[400], path[512], args[1200];
  snprintf(dir, sizeof dir, "%s", test_temp_dir("placement"));
  snprintf(path, sizeof path, "%s/placed.json", dir);
  write_file(path, "{\"domain\": {\"min\": [0,0,0], \"max\": [1,1,1], \"dx\": 0.05},"
                   " \"time\": {\"end\": 0.05, \"fps\": 20},"
                   " \"materials\": [{\"name\": \"j\", \"model\": \"fixed_corotated\", \"E\": 1e4,"
                   " \"nu\": 0.3, \"density\": 1000}],"
                   " \"bodies\": [{\"name\": \"a\", \"shape\": {\"type\": \"box\", \"center\":"
                   " [0.5,0.5,0.5], \"half_extent\": [0.1,0.1,0.1]}, \"material\": \"j\"},"
                   " {\"name\": \"b\", \"shape\": {\"type\": \"sphere\", \"center\": [0.6,0.5,0.5],"
                   " \"radius\": 0.08}, \"material\": \"j\"},"
                   " {\"name\": \"c\", \"shape\": {\"type\": \"box\", \"center\": [0.5,0.75,0.5],"
                   " \"half_extent\": [0.1,0.05,0.1]}, \"material\": \"j\"}],"
                   " \"colliders\": [{\"name\": \"ball\", \"shape\": {\"type\": \"sphere\","
                   " \"center\": [0.5,0.4,0.5], \"radius\": 0.05}},"
                   " {\"name\": \"grip\", \"rule\": \"sticky\", \"shape\": {\"type\": \"box\","
                   " \"center\": [0.5,0.8,0.5], \"half_extent\": [0.2,0.02,0.2]}}]}");
  snprintf(args, sizeof args, "check '%s'", path);
  assert_int_equal(mpm(args), 0);
  expect_output("bodies[0] (\"a\") and bodies[1] (\"b\") overlap");
  expect_output("start inside colliders[0] (\"ball\")");
  if (strstr(output, "grip") || strstr(output, "bodies[2]")) fail_msg("output: %s", output);
  snprintf(args, sizeof args, "run '%s' -o '%s/out' --quiet", path, dir);
  assert_int_equal(mpm(args), 0);
  expect_output("overlap");
}

/* Issue 17: a user's clone has no ../shared/, so the README cites both papers itself, and the
 * licence and citation files are there. */
static void test_readme_cites_papers(void **state) {
  (void)state;
  static char text[65536];
  FILE *f = fopen("README.md", "r");
  assert_non_null(f);
  const size_t n = fread(text, 1, sizeof text - 1, f);
  fclose(f);
  text[n] = '\0';
  assert_null(strstr(text, "../shared"));
  assert_non_null(strstr(text, "10.1145/3130800.3130879"));
  assert_non_null(strstr(text, "Dynamically Enriched MPM for\n  Invertible Elasticity"));
  assert_non_null(strstr(text, "What is built, and what is not yet"));
  assert_true(exists("LICENSE") && exists("CITATION.cff"));
}

/* The shape object examples/meshes/README.md shows parses (issue 17: it once documented a key,
 * mesh_scale, that the parser rejects). */
static void test_meshes_readme_shape(void **state) {
  (void)state;
  FILE *f = fopen("examples/meshes/README.md", "r");
  assert_non_null(f);
  char text[16384];
  const size_t n = fread(text, 1, sizeof text - 1, f);
  fclose(f);
  text[n] = '\0';
  const char *at = strstr(text, "in the shape object");
  assert_non_null(at);
  const char *a = strstr(at, "\"shape\": {");
  assert_non_null(a);
  const char *b = strchr(a, '}');
  assert_non_null(b);
  char shape[512];
  snprintf(shape, sizeof shape, "%.*s", (int)(b + 1 - a), a);
  for (char *c = shape; *c; ++c)
    if (*c == '\n') *c = ' ';
  char scene[2048];
  snprintf(
      scene, sizeof scene,
      "{\"domain\": {\"min\": [0,0,0], \"max\": [1,1,1], \"dx\": 0.05}, \"time\": "
      "{\"end\": 0.1}, \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\", \"E\": 1e4, "
      "\"nu\": 0.3, \"density\": 1000}],"
      " \"bodies\": [{%s, \"material\": \"m\"}]}",
      shape);
  mpm_scene sc;
  mpm_error err;
  /* mesh paths resolve against the scene's directory: examples/ */
  if (mpm_scene_parse(scene, "examples/readme.json", &sc, &err) != MPM_OK)
    fail_msg("%s: %s", shape, err.message);
  mpm_scene_free(&sc);
}

/* An output folder holds one run (issue 17: a second run into a folder left the first one's
 * later frames and checkpoints behind, and render and --resume mixed them in): a folder with a
 * run's files is refused, naming them and --overwrite; --overwrite removes them first; files
 * that are not a run's are kept. */
static void test_output_folder_holds_one_run(void **state) {
  (void)state;
  const char *dir = test_temp_dir("one_run");
  char scene[600], args[1600], path[900];
  snprintf(scene, sizeof scene, "%s/s.json", dir);
  write_file(scene, good_scene);
  snprintf(path, sizeof path, "%s/out/notes.txt", dir);
  char out[700];
  snprintf(out, sizeof out, "%s/out", dir);
  mkdir(out, 0755);
  write_file(path, "mine");
  snprintf(args, sizeof args, "run '%s' -o '%s' --quiet --frames 4", scene, out);
  assert_int_equal(mpm(args), 0); /* a folder without a run's files is fine */
  char frame4[900], frame2[900];
  snprintf(frame4, sizeof frame4, "%s/frame_0004.vtu", out);
  snprintf(frame2, sizeof frame2, "%s/frame_0002.vtu", out);
  assert_true(exists(frame4));
  snprintf(args, sizeof args, "run '%s' -o '%s' --quiet --frames 2", scene, out);
  assert_int_equal(mpm(args), 2);
  expect_output("holds the files of a run");
  expect_output("--overwrite");
  expect_output("--resume");
  assert_true(exists(frame4)); /* nothing touched */
  snprintf(args, sizeof args, "run '%s' -o '%s' --quiet --frames 2 --overwrite", scene, out);
  assert_int_equal(mpm(args), 0);
  assert_true(exists(frame2));
  assert_false(exists(frame4)); /* the old run's later frames are gone, */
  assert_true(exists(path));    /* the user's file is kept */
}

/* Every subcommand answers --help with exit 0 and all of its options (issue 17); `mpm --help`
 * lists render's options too. */
static void test_subcommand_help(void **state) {
  (void)state;
  static const struct {
    const char *cmd, *options[16];
  } subs[] = {
      {"run",
       {"-o DIR", "--overwrite", "--resume", "--threads", "--frames", "--render", "--quiet", NULL}},
      {"check", {"SCENE.json", NULL}},
      {"render",
       {"--field", "--size", "--colormap", "--range", "--every", "--scene", "--out", "--movie",
        "--quiet", "--frame", "--margin", "--no-shadow", "--no-legend", "--no-time", "--grid",
        NULL}},
      {"plot", {"--out", "--quiet", NULL}},
      {"error", {"REST_FRAME", "--body", NULL}},
      {"bench", {"transfer", "step", "stress", "checkpoint", "domains", "implicit", NULL}},
  };
  for (size_t k = 0; k < sizeof subs / sizeof subs[0]; ++k) {
    char args[64];
    snprintf(args, sizeof args, "%s --help", subs[k].cmd);
    if (mpm(args) != 0) fail_msg("mpm %s: exit %s", args, output);
    char head[32];
    snprintf(head, sizeof head, "mpm %s", subs[k].cmd);
    expect_output(head);
    for (int o = 0; subs[k].options[o]; ++o) expect_output(subs[k].options[o]);
  }
  assert_int_equal(mpm("--help"), 0);
  expect_output("--range LO:HI");
  expect_output("--colormap");
  assert_int_equal(mpm("nonsense --help"), 2);
  expect_output("unknown command 'nonsense'");
}

static long count_occurrences(const char *text, const char *needle) {
  long n = 0;
  for (const char *p = strstr(text, needle); p; p = strstr(p + 1, needle)) ++n;
  return n;
}

static void test_run_writes_frames(void **state) {
  (void)state;
  const char *dir = test_temp_dir("cli-run");
  char scene[600], out[600], args[1400], path[700];
  snprintf(scene, sizeof scene, "%s/scene.json", dir);
  snprintf(out, sizeof out, "%s/out", dir);
  write_file(scene, good_scene);
  snprintf(args, sizeof args, "run '%s' -o '%s' --threads 2", scene, out);
  if (mpm(args) != 0) fail_msg("run failed: %s", output);
  expect_output("frame 4/4"); /* plain progress lines when not on a terminal */
  for (int f = 0; f <= 4; ++f) {
    snprintf(path, sizeof path, "%s/frame_%04d.vtu", out, f);
    if (!exists(path)) fail_msg("missing %s", path);
  }
  /* the PVD lists the 5 frames (initial state + 4) */
  snprintf(path, sizeof path, "%s/frames.pvd", out);
  FILE *f = fopen(path, "r");
  assert_non_null(f);
  char pvd[8192];
  size_t n = fread(pvd, 1, sizeof pvd - 1, f);
  pvd[n] = '\0';
  fclose(f);
  assert_int_equal(count_occurrences(pvd, "<DataSet"), 5);
  assert_non_null(strstr(pvd, "frame_0004.vtu"));
  /* the VTU header announces the particles */
  snprintf(path, sizeof path, "%s/frame_0004.vtu", out);
  f = fopen(path, "rb");
  assert_non_null(f);
  char head[4096];
  n = fread(head, 1, sizeof head - 1, f);
  head[n] = '\0';
  fclose(f);
  assert_non_null(strstr(head, "<VTKFile"));
  assert_non_null(strstr(head, "NumberOfPoints=\"512\""));
  assert_non_null(strstr(head, "velocity"));
  /* stats: header + 5 rows */
  snprintf(path, sizeof path, "%s/stats.csv", out);
  f = fopen(path, "r");
  assert_non_null(f);
  int lines = 0;
  char line[2048];
  while (fgets(line, sizeof line, f)) ++lines;
  fclose(f);
  assert_int_equal(lines, 6);
  /* --frames stops early, --quiet prints nothing */
  snprintf(args, sizeof args, "run '%s' -o '%s/short' --frames 1 --quiet", scene, dir);
  assert_int_equal(mpm(args), 0);
  assert_int_equal((int)strlen(output), 0);
  snprintf(path, sizeof path, "%s/short/frame_0001.vtu", dir);
  assert_true(exists(path));
  snprintf(path, sizeof path, "%s/short/frame_0002.vtu", dir);
  assert_false(exists(path));
}

/* The default demo scene, for two frames: a VTU per frame, listed in the PVD. */
static void test_run_example_scene(void **state) {
  (void)state;
  const char *dir = test_temp_dir("cli-example");
  char args[1400], path[700];
  snprintf(args, sizeof args, "run examples/jello_cubes.json -o '%s/out' --frames 2 --quiet", dir);
  if (mpm(args) != 0) fail_msg("run failed: %s", output);
  for (int f = 0; f <= 2; ++f) {
    snprintf(path, sizeof path, "%s/out/frame_%04d.vtu", dir, f);
    if (!exists(path)) fail_msg("missing %s", path);
    snprintf(path, sizeof path, "%s/out/frame_%04d.ply", dir, f);
    if (!exists(path)) fail_msg("missing %s", path);
  }
  snprintf(path, sizeof path, "%s/out/frames.pvd", dir);
  FILE *f = fopen(path, "r");
  assert_non_null(f);
  char pvd[8192];
  size_t n = fread(pvd, 1, sizeof pvd - 1, f);
  pvd[n] = '\0';
  fclose(f);
  assert_int_equal(count_occurrences(pvd, "<DataSet"), 3);
  snprintf(path, sizeof path, "%s/out/frame_0002.vtu", dir);
  f = fopen(path, "rb");
  assert_non_null(f);
  char head[4096];
  n = fread(head, 1, sizeof head - 1, f);
  head[n] = '\0';
  fclose(f);
  assert_non_null(strstr(head, "NumberOfPoints=\"16000\""));
}

static void test_blow_up_is_reported(void **state) {
  (void)state;
  const char *dir = test_temp_dir("cli-blowup");
  char scene[600], args[1400];
  snprintf(scene, sizeof scene, "%s/scene.json", dir);
  write_file(scene, "{\"domain\": {\"min\": [0,0,0], \"max\": [1,1,1], \"dx\": 0.05},"
                    " \"time\": {\"end\": 0.2, \"fps\": 20},"
                    " \"materials\": [{\"name\": \"j\", \"model\": \"fixed_corotated\", \"E\": "
                    "1e4, \"nu\": 0.3, \"density\": 1000}],"
                    " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.5,0.5,0.5], "
                    "\"half_extent\": [0.1,0.1,0.1]},"
                    "               \"material\": \"j\", \"velocity\": [1e30, 0, 0]}]}");
  snprintf(args, sizeof args, "run '%s' -o '%s/out' --quiet", scene, dir);
  assert_int_equal(mpm(args), 1);
  expect_output("blew up at step");
  expect_output("particle id");
}

/* A scene that needs more memory than the process may use is refused before anything is
 * allocated or written, with the estimate (MPM_MEMORY_LIMIT stands in for a small machine). */
static void test_memory_refusal(void **state) {
  (void)state;
  const char *dir = test_temp_dir("memory");
  char scene[600], args[1400], out[700];
  snprintf(scene, sizeof scene, "%s/s.json", dir);
  write_file(scene, good_scene);
  snprintf(args, sizeof args, "check '%s'", scene);
  assert_int_equal(mpm(args), 0);
  expect_output("MiB)");
  snprintf(args, sizeof args, "run '%s' -o '%s/out' --quiet", scene, dir);
  assert_int_equal(mpm_env("MPM_MEMORY_LIMIT=1M", args), 2);
  expect_output("s.json: the scene needs about");
  /* the limit is named as what it is, in a unit that does not round it to 0 */
  expect_output("but MPM_MEMORY_LIMIT allows 1 MiB; use a larger dx");
  assert_int_equal(mpm_env("MPM_MEMORY_LIMIT=20MB", args), 2);
  expect_output("MPM_MEMORY_LIMIT allows 20 MiB");
  /* a malformed limit is an error naming the variable, not silently ignored */
  assert_int_equal(mpm_env("MPM_MEMORY_LIMIT=abc", args), 2);
  expect_output("MPM_MEMORY_LIMIT: expected a positive number of bytes");
  expect_output("got 'abc'");
  assert_int_equal(mpm_env("MPM_MEMORY_LIMIT=4X", args), 2);
  expect_output("got '4X'");
  snprintf(out, sizeof out, "%s/out", dir);
  assert_false(exists(out));
  /* a 1 m cube at dx = 2 mm: a billion particles, more than any machine here */
  write_file(scene, "{\"domain\": {\"min\": [0,0,0], \"max\": [1.2,1.2,1.2], \"dx\": 0.002},"
                    " \"time\": {\"end\": 0.1}, \"materials\": [{\"name\": \"j\", \"model\": "
                    "\"neo_hookean\", \"E\": 1e4, \"nu\": 0.3, \"density\": 1000}],"
                    " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.6,0.6,0.6],"
                    " \"half_extent\": [0.5,0.5,0.5]}, \"material\": \"j\"}]}");
  snprintf(args, sizeof args, "check '%s'", scene);
  assert_int_equal(mpm(args), 2);
  expect_output("1e+09 particles");
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_memory_refusal),
      cmocka_unit_test(test_help_and_version),
      cmocka_unit_test(test_missing_file),
      cmocka_unit_test(test_bad_scenes_exit_2_and_write_nothing),
      cmocka_unit_test(test_check_examples),
      cmocka_unit_test(test_linear_kernel_warning),
      cmocka_unit_test(test_friction_angle_warning),
      cmocka_unit_test(test_did_you_mean_and_implicit_check),
      cmocka_unit_test(test_heat_cost_warning),
      cmocka_unit_test(test_placement_warnings),
      cmocka_unit_test(test_readme_cites_papers),
      cmocka_unit_test(test_meshes_readme_shape),
      cmocka_unit_test(test_subcommand_help),
      cmocka_unit_test(test_output_folder_holds_one_run),
      cmocka_unit_test(test_run_writes_frames),
      cmocka_unit_test(test_run_example_scene),
      cmocka_unit_test(test_blow_up_is_reported),
  };
  return test_cleanup(cmocka_run_group_tests_name("cli", tests, NULL, NULL));
}
