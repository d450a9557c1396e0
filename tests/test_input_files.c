/* test_input_files.c - the files a run reads are regular files or refused (io/input_file.h):
 * a FIFO given as the scene, as a mesh, named like a checkpoint or standing as a frame that
 * `mpm render` and `mpm error` read never blocks; each command answers within seconds, naming
 * the file and what it is. Every command runs under timeout(1), so a hang fails the test
 * instead of stalling the suite. */
#define _POSIX_C_SOURCE 200809L

#include "cli_support.h"

#include <stdlib.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

/* Seconds a command may take before it counts as blocked (they answer in milliseconds). */
#define BLOCKED_S 20

/* `mpm ARGS` under timeout: its exit code, 124 when it blocked. */
static int mpm_timed(const char *args) {
  char env[64];
  snprintf(env, sizeof env, "timeout %d", BLOCKED_S);
  const int code = mpm_env(env, args);
  if (code == 124) fail_msg("mpm %s blocked for %d s:\n%s", args, BLOCKED_S, output);
  return code;
}

static const char *SCENE = "{\"domain\": {\"min\": [0,0,0], \"max\": [1,1,1], \"dx\": 0.1},"
                           " \"time\": {\"end\": 0.1, \"fps\": 20},"
                           " \"output\": {\"checkpoint_every\": 1},"
                           " \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\", "
                           "\"E\": 1e4, \"nu\": 0.3, \"density\": 1000}],"
                           " \"bodies\": [{\"shape\": %s, \"material\": \"m\"}]}";

static const char *BOX = "{\"type\": \"box\", \"center\": [0.5,0.5,0.5], \"half_extent\": "
                         "[0.2,0.2,0.2]}";

static void test_fifo_scene_and_mesh(void **state) {
  (void)state;
  const char *dir = test_temp_dir("fifo-scene");
  char fifo[600], scene[600], mesh[600], text[1400], shape[800], args[2000];
  snprintf(fifo, sizeof fifo, "%s/scene.json", dir);
  assert_int_equal(mkfifo(fifo, 0644), 0);
  snprintf(args, sizeof args, "check '%s'", fifo);
  assert_int_equal(mpm_timed(args), 2);
  expect_output(fifo);
  expect_output("a FIFO (named pipe), not a regular file");
  snprintf(args, sizeof args, "run '%s' -o '%s/out' --quiet", fifo, dir);
  assert_int_equal(mpm_timed(args), 2);
  expect_output("a FIFO (named pipe)");
  /* a mesh body whose file is a FIFO */
  snprintf(mesh, sizeof mesh, "%s/bunny.obj", dir);
  assert_int_equal(mkfifo(mesh, 0644), 0);
  snprintf(shape, sizeof shape,
           "{\"type\": \"mesh\", \"file\": \"%s\", \"center\": [0.5,0.5,0.5], \"scale\": 0.3}",
           mesh);
  snprintf(text, sizeof text, SCENE, shape);
  snprintf(scene, sizeof scene, "%s/mesh.json", dir);
  write_file(scene, text);
  snprintf(args, sizeof args, "check '%s'", scene);
  assert_int_equal(mpm_timed(args), 2);
  expect_output("bodies[0].shape.file");
  expect_output(mesh);
  expect_output("a FIFO (named pipe)");
}

/* A mesh file is capped as a scene is (64 MiB): a 2 GiB file (sparse: no disk used) is refused
 * by its size before it is read, naming the size, the limit and the key; the shape's
 * max_file_mb lowers or raises the cap (a small cube refused under 0.0001 MiB, read under the
 * default). */
static void test_mesh_size_cap(void **state) {
  (void)state;
  const char *dir = test_temp_dir("mesh-cap");
  char mesh[600], scene[600], text[1400], shape[800], args[2000];
  snprintf(mesh, sizeof mesh, "%s/huge.obj", dir);
  FILE *f = fopen(mesh, "w");
  assert_non_null(f);
  fputs("v 0 0 0\n", f);
  fclose(f);
  assert_int_equal(truncate(mesh, 2048L * 1024 * 1024), 0);
  snprintf(shape, sizeof shape,
           "{\"type\": \"mesh\", \"file\": \"%s\", \"center\": [0.5,0.5,0.5], \"scale\": 0.3}",
           mesh);
  snprintf(text, sizeof text, SCENE, shape);
  snprintf(scene, sizeof scene, "%s/huge.json", dir);
  write_file(scene, text);
  snprintf(args, sizeof args, "check '%s'", scene);
  assert_int_equal(mpm_timed(args), 2);
  expect_output("bodies[0].shape.file");
  expect_output("the file is 2048.0 MiB, more than the 64 MiB a mesh file may be");
  expect_output("max_file_mb");
  /* a closed cube of 12 triangles */
  snprintf(mesh, sizeof mesh, "%s/cube.obj", dir);
  write_file(mesh, "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
                   "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n");
  const char *caps[2] = {", \"max_file_mb\": 0.0001", ""};
  for (int k = 0; k < 2; ++k) {
    snprintf(shape, sizeof shape,
             "{\"type\": \"mesh\", \"file\": \"%s\", \"center\": [0.5,0.5,0.5], "
             "\"scale\": 0.3%s}",
             mesh, caps[k]);
    snprintf(text, sizeof text, SCENE, shape);
    snprintf(scene, sizeof scene, "%s/cube%d.json", dir, k);
    write_file(scene, text);
    snprintf(args, sizeof args, "check '%s'", scene);
    assert_int_equal(mpm_timed(args), k ? 0 : 2);
    if (!k) expect_output("more than the 0.0001 MiB a mesh file may be");
  }
  /* a box has no file to cap */
  snprintf(shape, sizeof shape,
           "{\"type\": \"box\", \"center\": [0.5,0.5,0.5], "
           "\"half_extent\": [0.2,0.2,0.2], \"max_file_mb\": 100}");
  snprintf(text, sizeof text, SCENE, shape);
  write_file(scene, text);
  assert_int_equal(mpm_timed(args), 2);
  expect_output("max_file_mb");
}

/* A run's folder with FIFOs where a checkpoint, a frame and stats.csv would be. */
static void test_fifo_in_a_run_folder(void **state) {
  (void)state;
  const char *dir = test_temp_dir("fifo-run");
  char scene[600], out[600], text[1400], path[800], args[2000];
  snprintf(scene, sizeof scene, "%s/s.json", dir);
  snprintf(out, sizeof out, "%s/out", dir);
  snprintf(text, sizeof text, SCENE, BOX);
  write_file(scene, text);
  snprintf(args, sizeof args, "run '%s' -o '%s' --quiet --frames 1", scene, out);
  assert_int_equal(mpm_timed(args), 0);
  /* named like the newest checkpoint: not one; the resume takes the real one */
  snprintf(path, sizeof path, "%s/checkpoint_999999999999.h5", out);
  assert_int_equal(mkfifo(path, 0644), 0);
  snprintf(args, sizeof args, "run '%s' --resume '%s' --quiet", scene, out);
  if (mpm_timed(args) != 0) fail_msg("resume: %s", output);
  /* a frame that render and error read, and the stats plot reads */
  snprintf(path, sizeof path, "%s/frame_0001.vtu", out);
  assert_int_equal(unlink(path), 0);
  assert_int_equal(mkfifo(path, 0644), 0);
  snprintf(args, sizeof args, "render '%s' --quiet", out);
  assert_int_not_equal(mpm_timed(args), 0);
  expect_output("frame_0001.vtu");
  expect_output("a FIFO (named pipe)");
  snprintf(args, sizeof args, "error '%s/frame_0000.vtu' '%s'", out, path);
  assert_int_not_equal(mpm_timed(args), 0);
  expect_output("a FIFO (named pipe)");
  snprintf(path, sizeof path, "%s/stats.csv", out);
  assert_int_equal(unlink(path), 0);
  assert_int_equal(mkfifo(path, 0644), 0);
  snprintf(args, sizeof args, "plot '%s' --quiet", out);
  assert_int_not_equal(mpm_timed(args), 0);
  expect_output("a FIFO (named pipe)");
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_fifo_scene_and_mesh),
      cmocka_unit_test(test_mesh_size_cap),
      cmocka_unit_test(test_fifo_in_a_run_folder),
  };
  return test_cleanup(cmocka_run_group_tests_name("input_files", tests, NULL, NULL));
}
