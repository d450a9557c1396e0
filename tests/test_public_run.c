/* test_public_run.c - the public calls a program needs around a run (include/mpm/mpm.h, issue
 * 17: `mpm run` and `mpm check` are written on them alone): mpm_sim_get_info against the
 * particle view and the other getters, the frame limit, the step callback, the scene's
 * warnings, the next step's dt against the step then taken, the copy of the scene that
 * mpm_sim_enable_output keeps for `mpm render`, and the calls of a run on MPI ranks in a process
 * that is none (tests/mpi runs them on ranks). */
#include "support.h"
#include "mpm/mpm.h"
#include "mpm/plot.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* Two boxes of elastic material points; `overlap` moves the second into the first. */
static mpm_sim *two_boxes(double second_x, const char *kernel) {
  char json[2048];
  snprintf(json, sizeof json,
           "{\"domain\": {\"min\": [0, 0, 0], \"max\": [1, 1, 1], \"dx\": 0.05},"
           " \"time\": {\"end\": 0.1, \"fps\": 40},"
           " \"solver\": {\"kernel\": \"%s\"},"
           " \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\", \"E\": 1e5, \"nu\": 0.3,"
           "   \"density\": 1000}],"
           " \"bodies\": ["
           "  {\"name\": \"a\", \"shape\": {\"type\": \"box\", \"center\": [0.3, 0.5, 0.5],"
           "   \"half_extent\": [0.1, 0.1, 0.1]}, \"material\": \"m\"},"
           "  {\"name\": \"b\", \"shape\": {\"type\": \"box\", \"center\": [%g, 0.5, 0.5],"
           "   \"half_extent\": [0.1, 0.1, 0.1]}, \"material\": \"m\", \"domains\": true}]}",
           kernel, second_x);
  mpm_sim *sim = NULL;
  char err[1024];
  if (mpm_sim_create_from_json(json, NULL, &sim, err, sizeof err) != MPM_OK)
    fail_msg("create: %s", err);
  return sim;
}

static void test_info(void **state) {
  (void)state;
  mpm_sim *sim = two_boxes(0.7, "quadratic");
  mpm_sim_info in;
  assert_int_equal(mpm_sim_get_info(sim, &in, sizeof in), MPM_OK);
  const mpm_particle_view v = mpm_sim_particles(sim);
  assert_int_equal(in.particles, v.count);
  assert_int_equal(in.particles, mpm_sim_particle_count(sim));
  /* the second box has domains: half the particles (both boxes sampled alike) */
  assert_true(in.domain_particles > 0 && in.domain_particles < in.particles);
  assert_int_equal(in.domain_particles * 2, in.particles);
  assert_int_equal(in.bodies, 2);
  assert_int_equal(in.materials, 1);
  assert_int_equal(in.colliders, 0);
  assert_true(in.dx == 0.05 && in.finest_dx == 0.05);
  assert_true(in.fps == 40 && fabs(in.frame_dt - 0.025) < 1e-15 && in.end_time == 0.1);
  assert_int_equal(in.frame_count, 4);
  assert_int_equal(in.frame_count, mpm_sim_frame_count(sim));
  assert_false(in.implicit);
  assert_false(in.output_enabled);
  assert_true(in.memory_bytes > 0);
  assert_true(in.threads >= 1);
  assert_string_equal(in.last_checkpoint, "");
  assert_int_equal(mpm_sim_set_threads(sim, 3), MPM_OK);
  mpm_sim_get_info(sim, &in, sizeof in);
  assert_int_equal(in.threads, 3);
  /* a program built against an older, shorter struct: nothing past its size is written */
  unsigned char bytes[sizeof(mpm_sim_info) + 16];
  memset(bytes, 0xAB, sizeof bytes);
  const size_t older = offsetof(mpm_sim_info, fps);
  assert_int_equal(mpm_sim_get_info(sim, (mpm_sim_info *)(void *)bytes, older), MPM_OK);
  for (size_t k = older; k < sizeof bytes; ++k) assert_int_equal(bytes[k], 0xAB);
  assert_int_equal(((mpm_sim_info *)(void *)bytes)->particles, in.particles);
  assert_int_equal(mpm_sim_get_info(sim, NULL, sizeof in), MPM_ERR_INVALID);
  mpm_sim_destroy(sim);
}

/* A simulation of one process is no rank's part: its info says rank 0 of 1 with its own
 * particles, the join is refused here (a build without MPI, or MPI not started: this program
 * is no MPI program) naming why, changing nothing, and the ranks' agreement is its own
 * status. */
static void test_ranks_without_mpi(void **state) {
  (void)state;
  mpm_sim *sim = two_boxes(0.7, "quadratic");
  mpm_sim_info in;
  mpm_sim_get_info(sim, &in, sizeof in);
  assert_int_equal(in.rank, 0);
  assert_int_equal(in.ranks, 1);
  assert_int_equal(in.run_particles, in.particles);
  assert_int_equal(mpm_sim_join_mpi_world(sim), MPM_ERR_INVALID);
  const char *why = mpm_sim_last_error(sim);
  assert_true(strstr(why, "built without MPI") || strstr(why, "MPI is not initialised"));
  mpm_sim_get_info(sim, &in, sizeof in);
  assert_int_equal(in.ranks, 1);
  assert_int_equal(in.run_particles, mpm_sim_particle_count(sim));
  assert_int_equal(mpm_sim_ranks_agree(sim, MPM_OK), MPM_OK);
  assert_int_equal(mpm_sim_ranks_agree(sim, MPM_ERR_IO), MPM_ERR_IO);
  assert_int_equal(mpm_sim_advance_frame(sim), MPM_OK); /* it runs as before */
  mpm_sim_destroy(sim);
}

static void test_frame_limit(void **state) {
  (void)state;
  mpm_sim *sim = two_boxes(0.7, "quadratic");
  assert_int_equal(mpm_sim_set_frame_limit(sim, 0), MPM_ERR_INVALID);
  assert_int_equal(mpm_sim_set_frame_limit(sim, 5), MPM_ERR_INVALID); /* the scene has 4 */
  assert_non_null(strstr(mpm_sim_last_error(sim), "1 to 4 frames"));
  assert_int_equal(mpm_sim_set_frame_limit(sim, 2), MPM_OK);
  assert_int_equal(mpm_sim_frame_count(sim), 2);
  assert_int_equal(mpm_sim_set_frame_limit(sim, 4), MPM_OK); /* back up before output */
  assert_int_equal(mpm_sim_set_frame_limit(sim, 2), MPM_OK);
  assert_int_equal(mpm_sim_enable_output(sim, test_temp_dir("public_run_limit")), MPM_OK);
  /* the output's records are for 2 frames now: only lower */
  assert_int_equal(mpm_sim_set_frame_limit(sim, 3), MPM_ERR_INVALID);
  assert_non_null(strstr(mpm_sim_last_error(sim), "only be lowered"));
  int frames = 0;
  while (mpm_sim_frame(sim) < mpm_sim_frame_count(sim)) {
    assert_int_equal(mpm_sim_advance_frame(sim), MPM_OK);
    ++frames;
  }
  assert_int_equal(frames, 2);
  assert_true(fabs(mpm_sim_time(sim) - 0.05) < 1e-9);
  mpm_sim_info in;
  mpm_sim_get_info(sim, &in, sizeof in);
  assert_true(in.output_enabled);
  assert_int_equal(in.written_frames, 3); /* frame 0, 1 and 2 */
  mpm_sim_destroy(sim);
}

typedef struct step_log {
  int calls;
  int64_t last_steps;
  int monotonic;
} step_log;

static void on_step(void *ctx, const mpm_sim *sim) {
  step_log *log = ctx;
  const int64_t s = mpm_sim_steps(sim);
  if (s != log->last_steps + 1) log->monotonic = 0;
  log->last_steps = s;
  ++log->calls;
}

static void test_step_callback(void **state) {
  (void)state;
  mpm_sim *sim = two_boxes(0.7, "quadratic");
  step_log log = {0, 0, 1};
  mpm_sim_set_step_callback(sim, on_step, &log);
  assert_int_equal(mpm_sim_advance_frame(sim), MPM_OK);
  print_message("one frame: %d steps, %d callbacks\n", (int)mpm_sim_steps(sim), log.calls);
  assert_true(log.calls > 1);
  assert_int_equal(log.calls, mpm_sim_steps(sim)); /* once after every step, in order */
  assert_true(log.monotonic);
  mpm_sim_set_step_callback(sim, NULL, &log); /* removed */
  assert_int_equal(mpm_sim_advance_frame(sim), MPM_OK);
  assert_true(mpm_sim_steps(sim) > log.calls);
  assert_int_equal(log.calls, log.last_steps);
  mpm_sim_destroy(sim);
}

static void test_warnings(void **state) {
  (void)state;
  char text[8192];
  mpm_sim *sim = two_boxes(0.7, "quadratic"); /* apart, a stable kernel: nothing */
  assert_int_equal(mpm_sim_warnings(sim, text, sizeof text), 0);
  assert_string_equal(text, "");
  mpm_sim_destroy(sim);
  /* overlapping boxes and the linear kernel: two warnings, one line each */
  sim = two_boxes(0.35, "linear");
  const int n = mpm_sim_warnings(sim, text, sizeof text);
  print_message("%d warnings:\n%s\n", n, text);
  assert_int_equal(n, 2);
  assert_non_null(strstr(text, "cell-crossing"));
  assert_non_null(strstr(text, "overlap"));
  assert_non_null(strchr(text, '\n'));
  assert_int_not_equal(text[strlen(text) - 1], '\n');
  assert_int_equal(mpm_sim_warnings(sim, NULL, 0), 2); /* the count alone */
  /* once the run is under way the starting positions are past: the kernel's warning stays */
  assert_int_equal(mpm_sim_step(sim, 1e-4), MPM_OK);
  assert_int_equal(mpm_sim_warnings(sim, text, sizeof text), 1);
  assert_null(strstr(text, "overlap"));
  mpm_sim_destroy(sim);
}

/* The dt reported for the next step is the step then taken (with no smaller bound given). */
static void test_next_dt(void **state) {
  (void)state;
  mpm_sim *sim = two_boxes(0.7, "quadratic");
  double dt = 0;
  assert_int_equal(mpm_sim_next_dt(sim, &dt), MPM_OK);
  print_message("next dt %.6g s\n", dt);
  assert_true(dt > 0 && dt < 0.025);
  assert_int_equal(mpm_sim_step(sim, 1.0), MPM_OK);
  assert_true(fabs(mpm_sim_time(sim) - dt) <= 1e-12 * dt);
  /* after a frame's worth of motion it is the next step's again */
  for (int k = 0; k < 20; ++k) assert_int_equal(mpm_sim_step(sim, 1.0), MPM_OK);
  const double t = mpm_sim_time(sim);
  assert_int_equal(mpm_sim_next_dt(sim, &dt), MPM_OK);
  assert_int_equal(mpm_sim_step(sim, 1.0), MPM_OK);
  assert_true(fabs(mpm_sim_time(sim) - t - dt) <= 1e-9 * dt);
  mpm_sim_destroy(sim);
}

static char *read_all(const char *path) {
  FILE *f = fopen(path, "rb");
  if (!f) return NULL;
  static char text[1 << 16];
  const size_t n = fread(text, 1, sizeof text - 1, f);
  fclose(f);
  text[n] = 0;
  return text;
}

/* sim's output folder keeps the scene as scene.json, holding each of the NULL-terminated
 * `texts`, and that copy makes the same simulation (positions and velocities to the bit). */
static void assert_copy_runs_the_same(mpm_sim *sim, const char *dir, const char *const *texts) {
  if (mpm_sim_enable_output(sim, dir) != MPM_OK) fail_msg("%s", mpm_sim_last_error(sim));
  char path[1200];
  snprintf(path, sizeof path, "%s/scene.json", dir);
  const char *text = read_all(path);
  assert_non_null(text);
  for (const char *const *t = texts; *t; ++t)
    if (!strstr(text, *t)) fail_msg("scene.json holds no %s", *t);
  mpm_sim *copy = NULL;
  char err[1024];
  if (mpm_sim_create_from_file(path, &copy, err, sizeof err) != MPM_OK) fail_msg("%s", err);
  const mpm_particle_view a = mpm_sim_particles(sim), b = mpm_sim_particles(copy);
  assert_int_equal(a.count, b.count);
  assert_memory_equal(a.v[0], b.v[0], a.count * a.real_size);
  assert_memory_equal(a.x[0], b.x[0], a.count * a.real_size);
  mpm_sim_destroy(copy);
}

/* mpm_sim_enable_output keeps the scene as scene.json (mesh files by absolute path), and that
 * copy makes the same simulation. */
static void test_scene_copy(void **state) {
  (void)state;
  mpm_sim *sim = NULL;
  char err[1024];
  assert_int_equal(mpm_sim_create_from_file("examples/ball_bunny.json", &sim, err, sizeof err),
                   MPM_OK);
  static const char *const bunny_by_absolute_path[] = {"\"/", "meshes/bunny", NULL};
  assert_copy_runs_the_same(sim, test_temp_dir("public_run_copy"), bunny_by_absolute_path);
  mpm_sim_destroy(sim);
}

/* The copy keeps every number's bits: 0.30000000000000004 is one bit above 0.3, which cJSON's own
 * printer (15 digits, accepted within an epsilon) wrote as 0.3. From JSON text and from a def. */
static const char *const one_bit_above[] = {"0.30000000000000004", NULL};

static void test_scene_copy_exact(void **state) {
  (void)state;
  static const char *const json =
      "{\"domain\": {\"min\": [0, 0, 0], \"max\": [1, 1, 1], \"dx\": 0.1},"
      " \"time\": {\"end\": 0.1},"
      " \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\", \"E\": 1e4, \"nu\": 0.3,"
      "  \"density\": 1000}],"
      " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.5, 0.5, 0.5],"
      "  \"half_extent\": [0.1, 0.1, 0.1]}, \"material\": \"m\","
      "  \"velocity\": [0.30000000000000004, 0, 0]}]}";
  mpm_sim *sim = NULL;
  char err[1024];
  if (mpm_sim_create_from_json(json, NULL, &sim, err, sizeof err) != MPM_OK) fail_msg("%s", err);
  assert_copy_runs_the_same(sim, test_temp_dir("public_run_copy_json"), one_bit_above);
  mpm_sim_destroy(sim);

  mpm_material_def m = mpm_material_def_default();
  m.name = "m";
  m.E = 1e4;
  mpm_body_def box = mpm_body_def_default();
  box.shape.center[0] = box.shape.center[1] = box.shape.center[2] = 0.5;
  box.shape.half_extent[0] = box.shape.half_extent[1] = box.shape.half_extent[2] = 0.1;
  box.velocity[0] = 0.30000000000000004;
  mpm_scene_def def = mpm_scene_def_default();
  def.domain.dx = 0.1;
  def.time.end = 0.1;
  def.materials = &m, def.material_count = 1;
  def.bodies = &box, def.body_count = 1;
  if (mpm_sim_create_from_def(&def, NULL, &sim, err, sizeof err) != MPM_OK) fail_msg("%s", err);
  assert_copy_runs_the_same(sim, test_temp_dir("public_run_copy_def"), one_bit_above);
  mpm_sim_destroy(sim);
}

/* The rest-state error between two frame files (Zhu et al. 2017; `mpm error`): a frame against
 * itself is 0 with every particle matched; a rigidly moved copy (the frame one step later of a
 * body in free flight moves almost rigidly) is small; files that are not frames are refused with
 * their name. */
static void test_rest_error_frames(void **state) {
  (void)state;
  mpm_sim *sim = two_boxes(0.7, "quadratic");
  const char *dir = test_temp_dir("public_run_rest");
  assert_int_equal(mpm_sim_enable_output(sim, dir), MPM_OK);
  assert_int_equal(mpm_sim_advance_frame(sim), MPM_OK);
  char rest[1200], final[1200], err[1024];
  snprintf(rest, sizeof rest, "%s/frame_0000.vtu", dir);
  snprintf(final, sizeof final, "%s/frame_0001.vtu", dir);
  mpm_rest_error_result e;
  assert_int_equal(mpm_rest_error_frames(rest, rest, -1, &e, err, sizeof err), MPM_OK);
  assert_int_equal(e.matched, mpm_sim_particle_count(sim));
  assert_int_equal(e.rest_particles, e.matched);
  assert_true(e.mean == 0 && e.max == 0 && e.rotation_degrees < 1e-3);
  /* body 1 alone (the box with domains): half the particles; after a frame of falling the
     box has moved down but kept its shape: the error is tiny beside the fall */
  assert_int_equal(mpm_rest_error_frames(rest, final, 1, &e, err, sizeof err), MPM_OK);
  print_message("body 1 after a frame: mean %.3g, max %.3g, translation y %.4g m\n", e.mean, e.max,
                e.translation[1]);
  assert_int_equal(e.matched * 2, mpm_sim_particle_count(sim));
  assert_true(e.translation[1] < -1e-4);        /* it fell */
  assert_true(e.max < 1e-4 && e.mean <= e.max); /* free fall does not deform it */
  assert_int_equal(mpm_rest_error_frames("/nonexistent/frame.vtu", final, -1, &e, err, sizeof err),
                   MPM_ERR_IO);
  assert_non_null(strstr(err, "/nonexistent/frame.vtu"));
  snprintf(rest, sizeof rest, "%s/stats.csv", dir);
  assert_int_not_equal(mpm_rest_error_frames(rest, final, -1, &e, err, sizeof err), MPM_OK);
  assert_non_null(strstr(err, "stats.csv"));
  mpm_sim_destroy(sim);
}

/* mpm_sim_step and mpm_sim_advance_frame are one frame loop: a step never passes the frame's
 * time, a step that lands on it completes the frame (counted, written), so time and the frames'
 * records only go forward whatever the mix of calls; past the end time both refuse. */
static void test_step_and_frame_agree(void **state) {
  (void)state;
  mpm_sim *sim = two_boxes(0.7, "quadratic"); /* 40 frames per second to 0.1 s: 4 frames */
  char out[600];
  snprintf(out, sizeof out, "%s", test_temp_dir("step-frame"));
  assert_int_equal(mpm_sim_enable_output(sim, out), MPM_OK);
  double last = 0;
  int calls = 0;
  while (mpm_sim_frame(sim) < mpm_sim_frame_count(sim)) {
    const int frame = mpm_sim_frame(sim);
    /* steps of 7 ms (not a divisor of the frame's 25 ms) for frames 0 and 2, whole frames else */
    const mpm_status st = frame % 2 == 0 ? mpm_sim_step(sim, 0.007) : mpm_sim_advance_frame(sim);
    assert_int_equal(st, MPM_OK);
    assert_true(mpm_sim_time(sim) > last);
    assert_true(mpm_sim_time(sim) <= (frame + 1) * 0.025 + 1e-12);
    if (mpm_sim_frame(sim) > frame) /* landed on the frame's time */
      assert_true(fabs(mpm_sim_time(sim) - (frame + 1) * 0.025) < 1e-12);
    last = mpm_sim_time(sim);
    assert_true(++calls < 100);
  }
  assert_true(fabs(mpm_sim_time(sim) - 0.1) < 1e-12);
  assert_int_equal(mpm_sim_step(sim, 0.007), MPM_ERR_INVALID);
  assert_non_null(strstr(mpm_sim_last_error(sim), "end time"));
  assert_int_equal(mpm_sim_advance_frame(sim), MPM_ERR_INVALID);
  mpm_sim_destroy(sim);
  /* stats.csv: a row per frame at the frame's time */
  char path[700], err[512];
  snprintf(path, sizeof path, "%s/stats.csv", out);
  mpm_stats_table t;
  assert_int_equal(mpm_stats_read(path, &t, err, sizeof err), MPM_OK);
  assert_int_equal(t.rows, 5);
  for (size_t r = 0; r < t.rows; ++r)
    assert_true(fabs(t.values[r * (size_t)t.stride + MPM_STATS_TIME] - 0.025 * (double)r) < 1e-9);
  mpm_stats_free(&t);
}

/* An implicit scene's fixed solver.dt longer than a frame takes one step per frame (it used to
 * take a step of the whole dt); solver.max_dt bounds solver.dt too. */
static void test_implicit_dt_fits_the_frame(void **state) {
  (void)state;
  static const double dts[][2] = {{5e4, 0}, {0.02, 0.004}};
  for (int k = 0; k < 2; ++k) {
    char json[2048];
    snprintf(json, sizeof json,
             "{\"domain\": {\"min\": [0,0,0], \"max\": [1,1,1], \"dx\": 0.1},"
             " \"time\": {\"end\": 0.1, \"fps\": 24},"
             " \"solver\": {\"integrator\": \"implicit\", \"dt\": %g, \"max_dt\": %g},"
             " \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\", \"E\": 1e4,"
             "   \"nu\": 0.3, \"density\": 1000}],"
             " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.5,0.5,0.5],"
             "   \"half_extent\": [0.2,0.2,0.2]}, \"material\": \"m\"}]}",
             dts[k][0], dts[k][1]);
    mpm_sim *sim = NULL;
    char err[1024];
    if (mpm_sim_create_from_json(json, NULL, &sim, err, sizeof err) != MPM_OK)
      fail_msg("create: %s", err);
    char out[600];
    snprintf(out, sizeof out, "%s", test_temp_dir("implicit-dt"));
    assert_int_equal(mpm_sim_enable_output(sim, out), MPM_OK);
    assert_int_equal(mpm_sim_advance_frame(sim), MPM_OK);
    assert_true(fabs(mpm_sim_time(sim) - 1.0 / 24) < 1e-12);
    /* one step of the frame; eleven of at most 4 ms */
    assert_int_equal(mpm_sim_steps(sim), k == 0 ? 1 : 11);
    mpm_sim_destroy(sim);
    char path[700];
    snprintf(path, sizeof path, "%s/stats.csv", out);
    mpm_stats_table t;
    assert_int_equal(mpm_stats_read(path, &t, err, sizeof err), MPM_OK);
    const double *row = t.values + (size_t)t.stride;
    if (!(row[MPM_STATS_DT_MAX] <= (k == 0 ? 1.0 / 24 : 0.004) * (1 + 1e-9)))
      fail_msg("solver.dt %g, max_dt %g: the longest step of the frame took %g s", dts[k][0],
               dts[k][1], row[MPM_STATS_DT_MAX]);
    mpm_stats_free(&t);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_info),
      cmocka_unit_test(test_ranks_without_mpi),
      cmocka_unit_test(test_frame_limit),
      cmocka_unit_test(test_step_callback),
      cmocka_unit_test(test_warnings),
      cmocka_unit_test(test_next_dt),
      cmocka_unit_test(test_scene_copy),
      cmocka_unit_test(test_scene_copy_exact),
      cmocka_unit_test(test_rest_error_frames),
      cmocka_unit_test(test_step_and_frame_agree),
      cmocka_unit_test(test_implicit_dt_fits_the_frame),
  };
  return test_cleanup(cmocka_run_group_tests(tests, NULL, NULL));
}
