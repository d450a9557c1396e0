/* test_checkpoint.c - HDF5 checkpoints and resume: a resumed run is bit-identical to an
 * uninterrupted one (library and command line, from frame-end and mid-frame checkpoints);
 * SIGINT and SIGTERM checkpoint and exit with 128 + N; runs killed with SIGKILL at random
 * moments leave every finished frame and their last checkpoint readable, and resume from it;
 * a damaged newest checkpoint falls back on the one before; another scene is refused; a
 * failed checkpoint write keeps the previous file. */
#define _POSIX_C_SOURCE 200809L

#include "cli_support.h"
#include "io/checkpoint.h"
#include "io/io.h"
#include "sim/sim.h"

#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>
#include <unistd.h>

/* A small scene with a plastic and an elastic material, a revolve container and a moving
 * sphere: every kind of state a checkpoint has to carry. */
static const char *SCENE =
    "{\"domain\": {\"min\": [0,0,0], \"max\": [0.6,0.6,0.6], \"dx\": 0.04},\n"
    " \"time\": {\"end\": %g, \"fps\": 20},\n"
    " \"output\": {\"checkpoint_every\": %d},\n"
    " \"materials\": [{\"name\": \"sand\", \"model\": \"drucker_prager\", \"E\": 3.5e5, \"nu\": "
    "0.3, \"density\": 1600},\n"
    "   {\"name\": \"jello\", \"model\": \"fixed_corotated\", \"E\": 1e4, \"nu\": 0.3, "
    "\"density\": 1000}],\n"
    " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.25,0.3,0.25], "
    "\"half_extent\": [0.06,0.06,0.06]}, \"material\": \"sand\"},\n"
    "   {\"shape\": {\"type\": \"sphere\", \"center\": [0.25,0.17,0.25], \"radius\": 0.05}, "
    "\"material\": \"jello\", \"velocity\": [0.2, 0, 0]}],\n"
    " \"colliders\": [{\"shape\": {\"type\": \"revolve\", \"center\": [0.25,0.05,0.25], "
    "\"profile\": [[0,0],[0.2,0],[0.2,0.4],[0,0.4]]}, \"inside_out\": true},\n"
    "   {\"shape\": {\"type\": \"sphere\", \"center\": [0.4,0.3,0.4], \"radius\": 0.03}, "
    "\"motion\": {\"velocity\": [-0.1, 0, 0]}}]}\n";

static void read_text(const char *path, char *buf, size_t cap) {
  FILE *f = fopen(path, "r");
  if (!f) fail_msg("cannot read %s", path);
  const size_t n = fread(buf, 1, cap - 1, f);
  buf[n] = '\0';
  fclose(f);
}

static void write_scene(const char *path, double end, int every) {
  char text[4096];
  snprintf(text, sizeof text, SCENE, end, every);
  write_file(path, text);
}

static mpm_sim *create(const char *scene_path) {
  mpm_sim *sim = NULL;
  char err[1024];
  if (mpm_sim_create_from_file(scene_path, &sim, err, sizeof err) != MPM_OK) fail_msg("%s", err);
  return sim;
}

/* Every array of two particle sets is bitwise equal. */
static void assert_same_particles(const mpm_particles *a, const mpm_particles *b) {
  assert_int_equal(a->count, b->count);
  mpm_real **ra[MPM_PARTICLE_REAL_ARRAYS], **rb[MPM_PARTICLE_REAL_ARRAYS];
  mpm_particles_real_arrays((mpm_particles *)a, ra);
  mpm_particles_real_arrays((mpm_particles *)b, rb);
  for (int k = 0; k < MPM_PARTICLE_REAL_ARRAYS; ++k)
    if (memcmp(*ra[k], *rb[k], a->count * sizeof(mpm_real)))
      fail_msg("particle array %d differs", k);
  assert_memory_equal(a->id, b->id, a->count * sizeof *a->id);
  assert_memory_equal(a->material, b->material, a->count * sizeof *a->material);
}

static long file_size(const char *path) {
  FILE *f = fopen(path, "rb");
  if (!f) return -1;
  fseek(f, 0, SEEK_END);
  long n = ftell(f);
  fclose(f);
  return n;
}

static int same_file(const char *a, const char *b) {
  FILE *fa = fopen(a, "rb"), *fb = fopen(b, "rb");
  int same = fa && fb;
  while (same) {
    int ca = fgetc(fa), cb = fgetc(fb);
    if (ca != cb) same = 0;
    if (ca == EOF || cb == EOF) break;
  }
  if (fa) fclose(fa);
  if (fb) fclose(fb);
  return same;
}

/* The frame files of two runs are byte-identical, frames [0, frames]. */
static void assert_same_frames(const char *dir_a, const char *dir_b, int frames) {
  for (int f = 0; f <= frames; ++f) {
    char a[1024], b[1024];
    snprintf(a, sizeof a, "%s/frame_%04d.vtu", dir_a, f);
    snprintf(b, sizeof b, "%s/frame_%04d.vtu", dir_b, f);
    if (!same_file(a, b)) fail_msg("%s and %s differ", a, b);
  }
}

/* Checkpoint names in dir, newest first; returns how many (at most cap). */
static int checkpoints(const char *dir, char names[][256], int cap) {
  DIR *d = opendir(dir);
  if (!d) fail_msg("cannot open %s: %s", dir, strerror(errno));
  int n = 0;
  for (struct dirent *e; (e = readdir(d));)
    if (!strncmp(e->d_name, "checkpoint_", 11) && strstr(e->d_name, ".h5") &&
        !strstr(e->d_name, "damaged") && n < cap)
      snprintf(names[n++], 256, "%s", e->d_name);
  closedir(d);
  for (int i = 0; i < n; ++i) /* newest first */
    for (int j = i + 1; j < n; ++j)
      if (strcmp(names[j], names[i]) > 0) {
        char t[256];
        memcpy(t, names[i], 256);
        memcpy(names[i], names[j], 256);
        memcpy(names[j], t, 256);
      }
  return n;
}

/* Library: a run stopped mid-frame (after a few steps of frame 3), checkpointed and resumed in
 * a new simulation ends with exactly the particles and frames of an uninterrupted run. */
static void test_resume_is_bit_identical(void **state) {
  (void)state;
  const char *dir = test_temp_dir("checkpoint_resume");
  char scene[512], full[512], part[512];
  snprintf(scene, sizeof scene, "%s/scene.json", dir);
  snprintf(full, sizeof full, "%s/full", dir);
  snprintf(part, sizeof part, "%s/part", dir);
  write_scene(scene, 0.3, 2);

  mpm_sim *a = create(scene);
  assert_int_equal(mpm_sim_enable_output(a, full), MPM_OK);
  while (mpm_sim_frame(a) < mpm_sim_frame_count(a))
    assert_int_equal(mpm_sim_advance_frame(a), MPM_OK);

  mpm_sim *b = create(scene);
  assert_int_equal(mpm_sim_enable_output(b, part), MPM_OK);
  for (int f = 0; f < 3; ++f) assert_int_equal(mpm_sim_advance_frame(b), MPM_OK);
  for (int s = 0; s < 5; ++s)
    assert_int_equal(mpm_sim_step(b, b->frame_dt - fmod(b->time, b->frame_dt)), MPM_OK);
  char path[1100];
  assert_int_equal(mpm_sim_write_checkpoint(b, path, sizeof path), MPM_OK);
  const int64_t steps_b = b->steps;
  mpm_sim_destroy(b);

  mpm_sim *c = create(scene);
  char used[1100];
  assert_int_equal(mpm_sim_resume(c, part, used, sizeof used), MPM_OK);
  assert_string_equal(used, path);
  assert_int_equal(c->steps, steps_b);
  assert_int_equal(mpm_sim_frame(c), 3);
  while (mpm_sim_frame(c) < mpm_sim_frame_count(c))
    assert_int_equal(mpm_sim_advance_frame(c), MPM_OK);
  assert_int_equal(c->steps, a->steps);
  assert_true(c->time == a->time);
  assert_same_particles(&a->particles, &c->particles);
  assert_same_frames(full, part, mpm_sim_frame_count(a));
  /* stats rows other than wall time are the same too, the step figures of the frame the
   * checkpoint cut in two included */
  for (int f = 0; f <= mpm_sim_frame_count(a); ++f) {
    assert_true(a->out.stats[f].kinetic == c->out.stats[f].kinetic);
    assert_true(a->out.stats[f].momentum[1] == c->out.stats[f].momentum[1]);
    assert_int_equal(a->out.stats[f].steps, c->out.stats[f].steps);
    assert_true(a->out.stats[f].dt == c->out.stats[f].dt);
    assert_true(a->out.stats[f].dt_min == c->out.stats[f].dt_min);
    assert_true(a->out.stats[f].dt_max == c->out.stats[f].dt_max);
    assert_true(a->out.stats[f].gravitational == c->out.stats[f].gravitational);
    assert_true(a->out.stats[f].total_energy == c->out.stats[f].total_energy);
  }
  /* every 2 frames, the two newest kept */
  char names[8][256];
  assert_int_equal(checkpoints(full, names, 8), 2);
  mpm_sim_destroy(a);
  mpm_sim_destroy(c);
}

/* The implicit integrator (Newton iterations, fixed step): a run checkpointed mid-frame and
 * resumed ends bit-identical, its stats rows' solver figures included. */
static void test_resume_implicit(void **state) {
  (void)state;
  const char *dir = test_temp_dir("checkpoint_implicit");
  char scene[512], full[512], part[512];
  snprintf(scene, sizeof scene, "%s/scene.json", dir);
  snprintf(full, sizeof full, "%s/full", dir);
  snprintf(part, sizeof part, "%s/part", dir);
  char text[4096];
  snprintf(text, sizeof text, SCENE, 0.25, 2);
  const char *key = "\"output\"";
  char *at = strstr(text, key);
  assert_non_null(at);
  char tail[4096];
  snprintf(tail, sizeof tail, "%s", at);
  snprintf(at, sizeof text - (size_t)(at - text),
           "\"solver\": {\"integrator\": \"implicit\", \"dt\": 0.01, "
           "\"newton_iterations\": 2},\n %s",
           tail);
  write_file(scene, text);
  mpm_sim *a = create(scene);
  assert_int_equal(mpm_sim_enable_output(a, full), MPM_OK);
  while (mpm_sim_frame(a) < mpm_sim_frame_count(a))
    assert_int_equal(mpm_sim_advance_frame(a), MPM_OK);
  mpm_sim *b = create(scene);
  assert_int_equal(mpm_sim_enable_output(b, part), MPM_OK);
  for (int f = 0; f < 2; ++f) assert_int_equal(mpm_sim_advance_frame(b), MPM_OK);
  for (int s = 0; s < 2; ++s) { /* two of the frame's five steps, of the frame loop's dt */
    const double remaining = (b->frame + 1) * b->frame_dt - b->time;
    assert_int_equal(mpm_sim_step(b, remaining / ceil(remaining / 0.01 - 1e-6)), MPM_OK);
  }
  char path[1100];
  assert_int_equal(mpm_sim_write_checkpoint(b, path, sizeof path), MPM_OK);
  mpm_sim_destroy(b);
  mpm_sim *c = create(scene);
  char used[1100];
  assert_int_equal(mpm_sim_resume(c, part, used, sizeof used), MPM_OK);
  while (mpm_sim_frame(c) < mpm_sim_frame_count(c))
    assert_int_equal(mpm_sim_advance_frame(c), MPM_OK);
  assert_int_equal(c->steps, a->steps);
  assert_same_particles(&a->particles, &c->particles);
  assert_same_frames(full, part, mpm_sim_frame_count(a));
  for (int f = 0; f <= mpm_sim_frame_count(a); ++f) {
    assert_true(a->out.stats[f].cg_iterations_mean == c->out.stats[f].cg_iterations_mean);
    assert_int_equal(a->out.stats[f].cg_iterations_max, c->out.stats[f].cg_iterations_max);
    assert_true(a->out.stats[f].cg_residual_max == c->out.stats[f].cg_residual_max);
    assert_true(a->out.stats[f].newton_iterations_mean == c->out.stats[f].newton_iterations_mean);
  }
  assert_true(a->out.stats[3].cg_iterations_mean > 0);
  mpm_sim_destroy(a);
  mpm_sim_destroy(c);
}

/* The reader gives back exactly what the writer wrote. */
static void test_checkpoint_round_trip(void **state) {
  (void)state;
  const char *dir = test_temp_dir("checkpoint_round_trip");
  char scene[512], out[512];
  snprintf(scene, sizeof scene, "%s/scene.json", dir);
  snprintf(out, sizeof out, "%s/out", dir);
  write_scene(scene, 0.2, 0);
  mpm_sim *a = create(scene);
  assert_int_equal(mpm_sim_enable_output(a, out), MPM_OK);
  assert_int_equal(mpm_sim_advance_frame(a), MPM_OK);
  char path[1100];
  assert_int_equal(mpm_sim_write_checkpoint(a, path, sizeof path), MPM_OK);
  mpm_checkpoint c;
  mpm_error err;
  assert_int_equal(mpm_checkpoint_read(path, &c, &err), MPM_OK);
  assert_same_particles(&a->particles, &c.particles);
  assert_true(c.time == a->time);
  assert_int_equal(c.steps, a->steps);
  assert_int_equal(c.frame, 1);
  assert_int_equal(c.records, 2);
  assert_string_equal(c.frame_files[1], "frame_0001.vtu");
  assert_true(c.stats[1].kinetic == a->out.stats[1].kinetic);
  assert_true(c.scene_hash == a->scene.source_hash);
  mpm_checkpoint_free(&c);

  /* not a checkpoint, truncated, missing */
  char bad[600];
  snprintf(bad, sizeof bad, "%s/bad.h5", dir);
  write_file(bad, "this is not HDF5\n");
  assert_int_equal(mpm_checkpoint_read(bad, &c, &err), MPM_ERR_PARSE);
  assert_non_null(strstr(err.message, "not an mpm checkpoint"));
  FILE *in = fopen(path, "rb");
  const long n = file_size(path);
  char *bytes = malloc((size_t)n);
  assert_int_equal(fread(bytes, 1, (size_t)n, in), (size_t)n);
  fclose(in);
  FILE *o = fopen(bad, "wb");
  fwrite(bytes, 1, (size_t)n / 2, o);
  fclose(o);
  assert_int_not_equal(mpm_checkpoint_read(bad, &c, &err), MPM_OK);
  assert_non_null(strstr(err.message, bad));
  /* one flipped byte in the particle data: the Fletcher-32 checksum catches it */
  bytes[n / 2] ^= 0x5a;
  o = fopen(bad, "wb");
  fwrite(bytes, 1, (size_t)n, o);
  fclose(o);
  assert_int_not_equal(mpm_checkpoint_read(bad, &c, &err), MPM_OK);
  free(bytes);
  snprintf(bad, sizeof bad, "%s/missing.h5", dir);
  assert_int_equal(mpm_checkpoint_read(bad, &c, &err), MPM_ERR_IO);
  mpm_sim_destroy(a);
}

/* A checkpoint that cannot be written (file size limit) fails with a message and leaves the
 * previous checkpoint and no temporary behind. */
static void test_failed_write_keeps_old(void **state) {
  (void)state;
  const char *dir = test_temp_dir("checkpoint_write_fail");
  char scene[512], out[512];
  snprintf(scene, sizeof scene, "%s/scene.json", dir);
  snprintf(out, sizeof out, "%s/out", dir);
  write_scene(scene, 0.2, 0);
  mpm_sim *a = create(scene);
  assert_int_equal(mpm_sim_enable_output(a, out), MPM_OK);
  char first[1100];
  assert_int_equal(mpm_sim_write_checkpoint(a, first, sizeof first), MPM_OK);
  const long size = file_size(first);
  assert_int_equal(mpm_sim_advance_frame(a), MPM_OK);

  struct rlimit old_limit, limit;
  assert_int_equal(getrlimit(RLIMIT_FSIZE, &old_limit), 0);
  limit = old_limit;
  limit.rlim_cur = 4096;
  void (*old_handler)(int) = signal(SIGXFSZ, SIG_IGN);
  assert_int_equal(setrlimit(RLIMIT_FSIZE, &limit), 0);
  const mpm_status st = mpm_sim_write_checkpoint(a, NULL, 0);
  assert_int_equal(setrlimit(RLIMIT_FSIZE, &old_limit), 0);
  signal(SIGXFSZ, old_handler);
  assert_int_equal(st, MPM_ERR_IO);
  assert_non_null(strstr(mpm_sim_last_error(a), "previous checkpoint is kept"));
  assert_int_equal(file_size(first), size);
  char names[8][256];
  assert_int_equal(checkpoints(out, names, 8), 1);
  DIR *d = opendir(out);
  for (struct dirent *e; (e = readdir(d));)
    if (strstr(e->d_name, ".tmp.")) fail_msg("temporary %s left behind", e->d_name);
  closedir(d);
  mpm_sim_destroy(a);
}

/* Command line: SIGINT and SIGTERM stop with a checkpoint, say how to resume and exit 130 and
 * 143; the resumed runs end with the frames of an uninterrupted run. */
static void run_signal_case(int sig, int code) {
  const char *dir = test_temp_dir(sig == SIGINT ? "checkpoint_sigint" : "checkpoint_sigterm");
  char scene[512], cmd[2048];
  snprintf(scene, sizeof scene, "%s/scene.json", dir);
  write_scene(scene, 2.0, 0);
  snprintf(cmd, sizeof cmd, "'%s' --quiet -o '%s/full'", scene, dir);
  char args[2100];
  snprintf(args, sizeof args, "run %s", cmd);
  assert_int_equal(mpm(args), 0);
  /* the run in the background, stopped by the signal once it has written frame 3 */
  char part[600];
  snprintf(part, sizeof part, "%s/part", dir);
  char log[600];
  snprintf(log, sizeof log, "%s/stderr.txt", dir);
  const pid_t pid = fork();
  assert_true(pid >= 0);
  if (pid == 0) {
    if (!freopen("/dev/null", "w", stdout) || !freopen(log, "w", stderr)) _exit(126);
    execl(test_mpm_bin(), "mpm", "run", scene, "--quiet", "-o", part, (char *)NULL);
    _exit(127);
  }
  char frame3[700];
  snprintf(frame3, sizeof frame3, "%s/frame_0003.vtu", part);
  for (int i = 0; i < 30000 && !exists(frame3); ++i) {
    struct timespec ts = {0, 1000000};
    nanosleep(&ts, NULL);
  }
  kill(pid, sig);
  int status;
  waitpid(pid, &status, 0);
  FILE *f = fopen(log, "r");
  assert_non_null(f);
  size_t n = fread(output, 1, sizeof output - 1, f);
  output[n] = '\0';
  fclose(f);
  assert_true(WIFEXITED(status));
  if (WEXITSTATUS(status) != code)
    fail_msg("exit %d, expected %d:\n%s", WEXITSTATUS(status), code, output);

  expect_output(sig == SIGINT ? "stopped by SIGINT" : "stopped by SIGTERM");
  expect_output("--resume");
  char names[8][256];
  assert_true(checkpoints(part, names, 8) >= 1);
  snprintf(args, sizeof args, "run '%s' --quiet --resume '%s/part'", scene, dir);
  assert_int_equal(mpm(args), 0);
  char full[600];
  snprintf(full, sizeof full, "%s/full", dir);
  assert_same_frames(full, part, 40);
}

static void test_sigint_checkpoints(void **state) {
  (void)state;
  run_signal_case(SIGINT, 130);
}
static void test_sigterm_checkpoints(void **state) {
  (void)state;
  run_signal_case(SIGTERM, 143);
}

/* SIGKILL at random moments: every frame file present reads back, every checkpoint present
 * reads back, and resuming from what is left ends with the uninterrupted run's frames. */
static void test_sigkill_at_random_moments(void **state) {
  (void)state;
  const char *dir = test_temp_dir("checkpoint_sigkill");
  char scene[512], full[600], part[600], args[2100];
  snprintf(scene, sizeof scene, "%s/scene.json", dir);
  snprintf(full, sizeof full, "%s/full", dir);
  snprintf(part, sizeof part, "%s/part", dir);
  write_scene(scene, 1.0, 1); /* a checkpoint every frame: kills land inside its writes too */
  snprintf(args, sizeof args, "run '%s' --quiet -o '%s'", scene, full);
  struct timespec t0, t1;
  clock_gettime(CLOCK_MONOTONIC, &t0);
  assert_int_equal(mpm(args), 0);
  clock_gettime(CLOCK_MONOTONIC, &t1);
  /* the kills land within the whole run's time, so that the first run (from the start) is
     always killed, on a fast machine too (this run takes 0.2 s on one, where fixed delays of
     up to 0.35 s let every round finish now and then) */
  const double whole = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
  const int frames = 20;

  uint64_t rng = 0x9e3779b97f4a7c15ull ^ (uint64_t)time(NULL);
  int kills = 0;
  for (int round = 0; round < 6; ++round) {
    /* start (or resume) and kill after a random delay */
    const int have = round > 0 && exists(part);
    char names[8][256];
    const int resumable = have && checkpoints(part, names, 8) > 0;
    const pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
      if (!freopen("/dev/null", "w", stderr)) _exit(126);
      if (resumable)
        execl(test_mpm_bin(), "mpm", "run", scene, "--quiet", "--resume", part, (char *)NULL);
      else
        /* no checkpoint yet: start over (the frames a killed run left are replaced) */
        execl(test_mpm_bin(), "mpm", "run", scene, "--quiet", "-o", part, "--overwrite",
              (char *)NULL);
      _exit(127);
    }
    const double delay = test_rand(&rng, 0.1 * whole, 0.8 * whole);
    struct timespec ts = {0, (long)(delay * 1e9)};
    nanosleep(&ts, NULL);
    kill(pid, SIGKILL);
    int status;
    waitpid(pid, &status, 0);
    if (WIFSIGNALED(status)) ++kills;
    /* whatever is on disk now is whole */
    for (int f = 0; f <= frames; ++f) {
      char path[700];
      snprintf(path, sizeof path, "%s/frame_%04d.vtu", part, f);
      if (!exists(path)) continue;
      mpm_vtu_frame fr;
      mpm_error err;
      if (mpm_read_vtu(path, &fr, &err) != MPM_OK) fail_msg("after SIGKILL: %s", err.message);
      mpm_vtu_frame_free(&fr);
    }
    const int n = exists(part) ? checkpoints(part, names, 8) : 0;
    for (int i = 0; i < n; ++i) {
      char path[2700];
      snprintf(path, sizeof path, "%s/%s", part, names[i]);
      mpm_checkpoint c;
      mpm_error err;
      if (mpm_checkpoint_read(path, &c, &err) != MPM_OK) fail_msg("after SIGKILL: %s", err.message);
      mpm_checkpoint_free(&c);
    }
  }
  assert_true(kills > 0);
  char names[8][256];
  /* every kill may have landed before the run made its folder (a loaded machine: the delays
     are fractions of an unloaded run's time; the sanitizer stage of CI failed here once) */
  if (exists(part) && checkpoints(part, names, 8) > 0)
    snprintf(args, sizeof args, "run '%s' --quiet --resume '%s'", scene, part);
  else
    snprintf(args, sizeof args, "run '%s' --quiet -o '%s' --overwrite", scene, part);
  assert_int_equal(mpm(args), 0);
  assert_same_frames(full, part, frames);
}

/* The newest checkpoint damaged: the one before is used and the damaged one set aside; a
 * changed scene is refused; a directory without checkpoints says so. */
static void test_resume_fallbacks_and_refusals(void **state) {
  (void)state;
  const char *dir = test_temp_dir("checkpoint_fallback");
  char scene[512], out[600], args[2100];
  snprintf(scene, sizeof scene, "%s/scene.json", dir);
  snprintf(out, sizeof out, "%s/out", dir);
  write_scene(scene, 0.3, 2);
  snprintf(args, sizeof args, "run '%s' --quiet -o '%s' --frames 5", scene, out);
  assert_int_equal(mpm(args), 0);
  char names[8][256];
  assert_int_equal(checkpoints(out, names, 8), 2);
  char newest[900], older[900];
  snprintf(newest, sizeof newest, "%s/%s", out, names[0]);
  snprintf(older, sizeof older, "%s/%s", out, names[1]);
  write_file(newest, "garbage");
  snprintf(args, sizeof args, "run '%s' --resume '%s'", scene, out);
  assert_int_equal(mpm(args), 0);
  expect_output(older);
  char damaged[920];
  snprintf(damaged, sizeof damaged, "%s.damaged", newest);
  assert_true(exists(damaged));

  /* the run is now complete: resuming it again says so and simulates nothing (issue 17: it
   * re-simulated the frames after the last checkpoint) */
  char stats[700], before[65536], after[65536];
  snprintf(stats, sizeof stats, "%s/stats.csv", out);
  read_text(stats, before, sizeof before);
  snprintf(args, sizeof args, "run '%s' --resume '%s'", scene, out);
  assert_int_equal(mpm(args), 0);
  expect_output("is complete");
  read_text(stats, after, sizeof after);
  assert_string_equal(before, after);

  /* another scene */
  char other[512];
  snprintf(other, sizeof other, "%s/other.json", dir);
  write_scene(other, 0.35, 2);
  snprintf(args, sizeof args, "run '%s' --resume '%s'", other, out);
  assert_int_equal(mpm(args), 2);
  expect_output("another scene");

  /* nothing to resume */
  snprintf(args, sizeof args, "run '%s' --resume '%s'", scene, dir);
  assert_int_equal(mpm(args), 2);
  expect_output("no checkpoint to resume from");
  snprintf(args, sizeof args, "run '%s' --resume '%s' -o /elsewhere", scene, out);
  assert_int_equal(mpm(args), 2);
}

/* Particle domains (Zhu et al.) are part of the state: a bar with domains, stretched by grips,
 * dynamically enriched (Zhu sec. 5, with the exit threshold's hysteresis: last step's flags
 * are state and travel in the checkpoint) and half of them switched off during the run,
 * resumed from a checkpoint ends with the same frames, domain meshes (with their enrichment
 * categories) and stats as an uninterrupted run; with hourglass control on every particle and
 * the bend threshold (enrichment_hourglass: most of the bar is enriched by it in the first
 * frames, before K(F) reaches 0.6), settings of the scene the resumed run keeps
 * (mpm_enrichment_move_settings). */
static void test_resume_with_domains(void **state) {
  (void)state;
  const char *dir = test_temp_dir("checkpoint_domains");
  char scene[512], args[2100];
  snprintf(scene, sizeof scene, "%s/bar.json", dir);
  write_file(scene,
             "{\"domain\": {\"min\": [0, 0.3, 0.3], \"max\": [1.6, 0.7, 0.7], \"dx\": 0.04},"
             " \"gravity\": [0, 0, 0], \"time\": {\"end\": 1.0, \"fps\": 8},"
             " \"output\": {\"checkpoint_every\": 3},"
             " \"materials\": [{\"name\": \"rubber\", \"model\": \"neo_hookean\", \"E\": "
             "2e4, \"nu\": 0.3, \"density\": 1000}],"
             " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.8, 0.5, 0.5], "
             "\"half_extent\": [0.2, 0.04, 0.04]}, \"material\": \"rubber\", \"domains\": true,"
             " \"enrichment\": 0.6, \"enrichment_exit\": 0.999, \"enrichment_hourglass\": "
             "0.01, \"hourglass\": \"all\","
             " \"domain_release\": [{\"time\": 0.5, \"min\": [0.9, 0, 0], \"max\": [2, 1, 1]}]}],"
             " \"colliders\": [{\"shape\": {\"type\": \"box\", \"center\": [0.6, 0.5, 0.5], "
             "\"half_extent\": [0.05, 0.08, 0.08]}, \"rule\": \"sticky\", \"motion\": "
             "{\"velocity\": [-0.4, 0, 0]}, \"active\": [0, 0.6]},"
             " {\"shape\": {\"type\": \"box\", \"center\": [1.0, 0.5, 0.5], \"half_extent\": "
             "[0.05, 0.08, 0.08]}, \"rule\": \"sticky\"}]}");
  snprintf(args, sizeof args, "run '%s' --quiet -o '%s/full'", scene, dir);
  assert_int_equal(mpm(args), 0);
  snprintf(args, sizeof args, "run '%s' --quiet -o '%s/part' --frames 5", scene, dir);
  assert_int_equal(mpm(args), 0);
  snprintf(args, sizeof args, "run '%s' --quiet --resume '%s/part'", scene, dir);
  assert_int_equal(mpm(args), 0);
  char full[600], part[600];
  snprintf(full, sizeof full, "%s/full", dir);
  snprintf(part, sizeof part, "%s/part", dir);
  assert_same_frames(full, part, 8);
  for (int f = 0; f <= 8; ++f) {
    char a[700], b[700];
    snprintf(a, sizeof a, "%s/domains_%04d.vtu", full, f);
    snprintf(b, sizeof b, "%s/domains_%04d.vtu", part, f);
    if (!same_file(a, b)) fail_msg("%s and %s differ", a, b);
  }
  /* the run enriched: the last frames report enriched particles */
  char path[700];
  snprintf(path, sizeof path, "%s/stats.csv", full);
  FILE *fp = fopen(path, "r");
  assert_non_null(fp);
  char line[1024];
  double enriched = 0, least = 100;
  while (fgets(line, sizeof line, fp)) {
    /* enriched_percent is the 21st column (later columns were added after it) */
    const char *field = line;
    for (int k = 0; k < 20 && field; ++k) {
      field = strchr(field, ',');
      if (field) ++field;
    }
    if (field && line[0] != 'f' && line[0] != '0') {
      enriched = fmax(enriched, atof(field));
      least = fmin(least, atof(field));
    }
  }
  fclose(fp);
  print_message("enriched_percent of the run's frames: %g to %g\n", least, enriched);
  assert_true(enriched > 0 && least < 100);
}

/* A checkpoint resumes only with the meshes its run read: a mesh body with particle domains and
 * its embedded surface, whose mesh file is replaced after the checkpoint (the scene text the
 * same), is refused with exit 2 naming the key and the file (it crashed in the surface's
 * embedding, or wrote a wrong surface); the same bytes written back resume. */
static void test_resume_refuses_changed_mesh(void **state) {
  (void)state;
  static const char *const cube = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\n"
                                  "v 1 1 1\nv 0 1 1\nf 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\n"
                                  "f 4 8 7 3\nf 1 5 8 4\nf 2 3 7 6\n";
  /* in the same box as the cube: the scene text and the body's bounds unchanged */
  static const char *const octahedron = "v 1 .5 .5\nv 0 .5 .5\nv .5 1 .5\nv .5 0 .5\n"
                                        "v .5 .5 1\nv .5 .5 0\nf 1 3 5\nf 3 2 5\nf 2 4 5\n"
                                        "f 4 1 5\nf 3 1 6\nf 2 3 6\nf 4 2 6\nf 1 4 6\n";
  const char *dir = test_temp_dir("ckpt-mesh");
  char mesh[600], scene[600], out[600], args[2000];
  snprintf(mesh, sizeof mesh, "%s/body.obj", dir);
  snprintf(scene, sizeof scene, "%s/s.json", dir);
  snprintf(out, sizeof out, "%s/out", dir);
  write_file(mesh, cube);
  write_file(scene,
             "{\"domain\": {\"min\": [0,0,0], \"max\": [1,1,1], \"dx\": 0.1},"
             " \"time\": {\"end\": 0.15, \"fps\": 20}, \"output\": {\"checkpoint_every\": 1},"
             " \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\", \"E\": 1e4,"
             "   \"nu\": 0.3, \"density\": 1000}],"
             " \"bodies\": [{\"shape\": {\"type\": \"mesh\", \"file\": \"body.obj\","
             "   \"center\": [0.5,0.5,0.5], \"scale\": 0.4}, \"material\": \"m\","
             "   \"domains\": true}]}");
  snprintf(args, sizeof args, "run '%s' -o '%s' --quiet --frames 1", scene, out);
  if (mpm(args) != 0) fail_msg("%s", output);
  write_file(mesh, octahedron);
  snprintf(args, sizeof args, "run '%s' --resume '%s' --quiet", scene, out);
  assert_int_equal(mpm(args), 2);
  expect_output("bodies[0].shape.file");
  expect_output(mesh);
  expect_output("content changed");
  write_file(mesh, cube);
  if (mpm(args) != 0) fail_msg("%s", output);
  char last[700];
  snprintf(last, sizeof last, "%s/surface_body0_0003.obj", out);
  assert_true(exists(last));
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_resume_is_bit_identical),
      cmocka_unit_test(test_resume_implicit),
      cmocka_unit_test(test_checkpoint_round_trip),
      cmocka_unit_test(test_failed_write_keeps_old),
      cmocka_unit_test(test_sigint_checkpoints),
      cmocka_unit_test(test_sigterm_checkpoints),
      cmocka_unit_test(test_sigkill_at_random_moments),
      cmocka_unit_test(test_resume_fallbacks_and_refusals),
      cmocka_unit_test(test_resume_with_domains),
      cmocka_unit_test(test_resume_refuses_changed_mesh),
  };
  return test_cleanup(cmocka_run_group_tests(tests, NULL, NULL));
}
