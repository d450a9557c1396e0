/* test_frame_writer.c - every frame and checkpoint of a run goes through the simulation's frame
 * writer (sim/frame_writer.h), the seam a distributed run fills with writers of its own:
 *   - a writer that passes everything on to the files writer sees frame 0 when the output opens,
 *     each frame after, and each checkpoint, with the run's figures (stats rows) and the
 *     particles as written;
 *   - a writer that writes nothing leaves no frame, stats or checkpoint file in the folder (so
 *     nothing else writes them behind its back). */
#include "support.h"
#include "sim/frame_writer.h"
#include "sim/sim.h"

#include <dirent.h>
#include <stdio.h>
#include <string.h>

static int frames_seen, checkpoints_seen, pass_on;
static size_t particles_seen;

static mpm_status frame(mpm_sim *sim, const mpm_frame_record *r) {
  assert_int_equal(r->frame, frames_seen);
  assert_int_equal(r->records, 1);
  assert_int_equal(r->stats_rows, r->frame + 1);
  particles_seen = r->ff.particles->count;
  ++frames_seen;
  return pass_on ? mpm_frame_files.frame(sim, r) : MPM_OK;
}

static mpm_status checkpoint(mpm_sim *sim, const char *path, const mpm_checkpoint *c) {
  assert_int_equal(c->particles.count, sim->particles.count);
  ++checkpoints_seen;
  return pass_on ? mpm_frame_files.checkpoint(sim, path, c) : MPM_OK;
}

static const mpm_frame_writer counting = {
    .name = "counting", .frame = frame, .checkpoint = checkpoint};

static const char *scene =
    "{\"domain\": {\"min\": [0,0,0], \"max\": [0.4,0.4,0.4], \"dx\": 0.04},"
    " \"gravity\": [0,-9.81,0], \"time\": {\"end\": 0.03, \"fps\": 100},"
    " \"output\": {\"vtu\": true, \"ply\": true, \"stats\": true, \"checkpoint_every\": 1},"
    " \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\", \"E\": 1e5, \"nu\": 0.3,"
    " \"density\": 1000}],"
    " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.2,0.2,0.2],"
    " \"half_extent\": [0.06,0.06,0.06]}, \"material\": \"m\"}]}";

/* The files in dir whose names start with `prefix`. */
static int count_files(const char *dir, const char *prefix) {
  DIR *d = opendir(dir);
  assert_non_null(d);
  int n = 0;
  for (struct dirent *e; (e = readdir(d));) n += strncmp(e->d_name, prefix, strlen(prefix)) == 0;
  closedir(d);
  return n;
}

static void run(const char *name, int pass) {
  frames_seen = checkpoints_seen = 0;
  pass_on = pass;
  mpm_sim *sim = test_sim_from_json(scene, "frame_writer.json");
  mpm_sim_set_writer(sim, &counting);
  const char *dir = test_temp_dir(name);
  assert_int_equal(mpm_sim_open_output(sim, dir, MPM_OUTPUT_OVERWRITE), MPM_OK);
  while (mpm_sim_frame(sim) < mpm_sim_frame_count(sim))
    if (mpm_sim_advance_frame(sim) != MPM_OK) fail_msg("%s", mpm_sim_last_error(sim));
  assert_int_equal(frames_seen, mpm_sim_frame_count(sim) + 1);
  assert_int_equal(checkpoints_seen, mpm_sim_frame_count(sim) - 1); /* none at the end */
  assert_int_equal(particles_seen, sim->particles.count);
  const int expect = pass ? 1 : 0;
  assert_int_equal(count_files(dir, "frame_") > 0, expect);
  assert_int_equal(count_files(dir, "stats.csv"), expect);
  assert_int_equal(count_files(dir, "checkpoint_") > 0, expect);
  mpm_sim_destroy(sim);
}

static void test_every_frame_and_checkpoint_goes_through(void **state) {
  (void)state;
  run("frame_writer_files", 1);
}

static void test_nothing_written_behind_the_writer(void **state) {
  (void)state;
  run("frame_writer_none", 0);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_every_frame_and_checkpoint_goes_through),
      cmocka_unit_test(test_nothing_written_behind_the_writer),
  };
  return test_cleanup(cmocka_run_group_tests(tests, NULL, NULL));
}
