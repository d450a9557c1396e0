/* resume_support.h - a run and its checkpointed, resumed twin, for the tests that check that a
 * resumed run ends bit-identical to an uninterrupted one. Header only. */
#ifndef MPM_TEST_RESUME_SUPPORT_H
#define MPM_TEST_RESUME_SUPPORT_H

#include "support.h"
#include "sim/sim.h"

#include <math.h>
#include <stdio.h>

static inline mpm_sim *resume_create(const char *scene_path) {
  mpm_sim *sim = NULL;
  char err[1024];
  if (mpm_sim_create_from_file(scene_path, &sim, err, sizeof err) != MPM_OK) fail_msg("%s", err);
  return sim;
}

/* Scene text `text` (with output.checkpoint_every) run to its end in a fresh folder named
 * `name` (*full), and the same run stopped after `frames` frames and then `steps` more steps,
 * or more while steps_left(sim) says so (NULL: exactly `steps`), checkpointed, destroyed, and
 * resumed in a new simulation to the end (*resumed). */
static inline void resume_pair(const char *name, const char *text, int frames, int steps,
                               int (*steps_left)(const mpm_sim *), mpm_sim **full,
                               mpm_sim **resumed) {
  const char *dir = test_temp_dir(name);
  char scene[512], a_dir[512], b_dir[512];
  snprintf(scene, sizeof scene, "%s/scene.json", dir);
  snprintf(a_dir, sizeof a_dir, "%s/full", dir);
  snprintf(b_dir, sizeof b_dir, "%s/part", dir);
  FILE *f = fopen(scene, "w");
  if (!f || fputs(text, f) == EOF || fclose(f)) fail_msg("cannot write %s", scene);
  mpm_sim *a = resume_create(scene);
  assert_int_equal(mpm_sim_enable_output(a, a_dir), MPM_OK);
  while (mpm_sim_frame(a) < mpm_sim_frame_count(a))
    assert_int_equal(mpm_sim_advance_frame(a), MPM_OK);
  mpm_sim *b = resume_create(scene);
  assert_int_equal(mpm_sim_enable_output(b, b_dir), MPM_OK);
  for (int k = 0; k < frames; ++k) assert_int_equal(mpm_sim_advance_frame(b), MPM_OK);
  for (int s = 0; s < steps || (steps_left && steps_left(b)); ++s)
    assert_int_equal(mpm_sim_step(b, b->frame_dt - fmod(b->time, b->frame_dt)), MPM_OK);
  char path[1100], used[1100];
  assert_int_equal(mpm_sim_write_checkpoint(b, path, sizeof path), MPM_OK);
  mpm_sim_destroy(b);
  mpm_sim *c = resume_create(scene);
  assert_int_equal(mpm_sim_resume(c, b_dir, used, sizeof used), MPM_OK);
  assert_string_equal(used, path);
  while (mpm_sim_frame(c) < mpm_sim_frame_count(c))
    assert_int_equal(mpm_sim_advance_frame(c), MPM_OK);
  assert_int_equal(c->steps, a->steps);
  *full = a;
  *resumed = c;
}

#endif
