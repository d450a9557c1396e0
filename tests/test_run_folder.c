/* test_run_folder.c - an output folder holds one run, and nothing else in it or outside it is
 * lost (io/run_folder.h, mpm_sim_open_output):
 *   - --overwrite removes exactly the files a run writes: files whose names merely start like
 *     the run's, folders (empty or not) and the scene being run are kept byte for byte; a link
 *     or a folder bearing a run file's name refuses the whole, removing nothing;
 *   - one simulation writes into a folder at a time: a second one (in this process or another,
 *     new, overwriting or resuming) is refused while the first holds the folder;
 *   - the writers' temporaries are never opened through a link or over a planted file (frames,
 *     stats, checkpoints), and a resume removes the temporaries a killed run left;
 *   - a folder named like a checkpoint is not read as one. */
#define _POSIX_C_SOURCE 200809L

#include "cli_support.h"
#include "mpm/mpm.h"
#include "io/run_folder.h"

#include <errno.h>
#include <stdlib.h>
#include <sys/types.h>
#include <unistd.h>

/* A falling elastic box; `checkpoint_every` frames between checkpoints. */
static void scene_text(char *out, size_t cap, double end, int checkpoint_every) {
  snprintf(out, cap,
           "{\"domain\": {\"min\": [0,0,0], \"max\": [1,1,1], \"dx\": 0.1},"
           " \"time\": {\"end\": %g, \"fps\": 20},"
           " \"output\": {\"checkpoint_every\": %d},"
           " \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\", \"E\": 1e4, \"nu\": 0.3,"
           "   \"density\": 1000}],"
           " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.5,0.5,0.5],"
           "   \"half_extent\": [0.2,0.2,0.2]}, \"material\": \"m\"}]}",
           end, checkpoint_every);
}

static void join(char *out, size_t cap, const char *dir, const char *name) {
  snprintf(out, cap, "%s/%s", dir, name);
}

/* The file's bytes (NUL-terminated; caller frees), NULL when it cannot be read. */
static char *slurp(const char *path) {
  FILE *f = fopen(path, "rb");
  if (!f) return NULL;
  char *text = calloc(1, 1 << 16);
  const size_t n = fread(text, 1, (1 << 16) - 1, f);
  text[n] = '\0';
  fclose(f);
  return text;
}

static void assert_text(const char *path, const char *expected) {
  char *got = slurp(path);
  if (!got) fail_msg("%s is gone", path);
  if (strcmp(got, expected)) fail_msg("%s changed: '%s', expected '%s'", path, got, expected);
  free(got);
}

static int is_link(const char *path) {
  struct stat st;
  return lstat(path, &st) == 0 && S_ISLNK(st.st_mode);
}

static mpm_sim *create_sim(const char *json) {
  mpm_sim *sim = NULL;
  char err[1024];
  if (mpm_sim_create_from_json(json, NULL, &sim, err, sizeof err) != MPM_OK)
    fail_msg("create: %s", err);
  return sim;
}

/* ---------------------------------------------------------------- names */

/* The names the writers make are a run's; names that merely start like them are not. */
static void test_run_file_names(void **state) {
  (void)state;
  static const char *const run[] = {"frame_0000.vtu",
                                    "frame_12345.ply",
                                    "frames.pvd",
                                    "run.pvd",
                                    "stats.csv",
                                    "scene.json",
                                    "domains_0003.vtu",
                                    "grid_cells.vtu",
                                    "grid_cells_0010.vtu",
                                    "surface_body2_0001.obj",
                                    "surface_body0_0001.vtp",
                                    "surface_0004.ply",
                                    "surface_b3_0004.obj",
                                    "levelset_0001.vdb",
                                    "levelset_b1_0001.vdb",
                                    "checkpoint_000000000120.h5",
                                    "checkpoint_000000000120.h5.damaged",
                                    "frame_0002.pvtu",
                                    "frame_0002_p0003.vtu",
                                    "frame_0002_p0000.ply"};
  static const char *const temp[] = {".frame_0001.vtu.tmp.123", ".stats.csv.tmp.9.2",
                                     ".frame_0002_p0001.vtu.tmp.5", ".frame_0002.pvtu.tmp.5",
                                     ".checkpoint_000000000120.h5.tmp.77"};
  static const char *const not_run[] = {"frame_notes.txt",
                                        "frame_001.vtu",
                                        "frame_0001.vtu.bak",
                                        "frame_0001.vtk",
                                        "surface_scan.stl",
                                        "checkpoint_plan.md",
                                        "checkpoint_12.h5",
                                        "domains_list.txt",
                                        "levelset_ideas.txt",
                                        "grid_cells_todo.txt",
                                        "stats.csv~",
                                        "scene.json.orig",
                                        ".frame_0001.vtu.tmp.",
                                        ".frame_0001.vtu.tmp.x",
                                        ".notes.tmp.1",
                                        "frame_backup_full",
                                        ".mpm.lock",
                                        "surface_body_0001.obj",
                                        "frame_0002_p3.vtu",
                                        "frame_0002_p0003.vtu.old",
                                        "frame_0002.pvtu.bak"};
  for (size_t k = 0; k < sizeof run / sizeof run[0]; ++k)
    if (mpm_run_file_kind_of(run[k]) != MPM_RUN_FILE) fail_msg("%s is a run's file", run[k]);
  for (size_t k = 0; k < sizeof temp / sizeof temp[0]; ++k)
    if (mpm_run_file_kind_of(temp[k]) != MPM_RUN_FILE_TEMP)
      fail_msg("%s is a run's temporary", temp[k]);
  for (size_t k = 0; k < sizeof not_run / sizeof not_run[0]; ++k)
    if (mpm_run_file_kind_of(not_run[k]) != MPM_RUN_FILE_NONE)
      fail_msg("%s is not a run's file", not_run[k]);
}

/* ---------------------------------------------------------------- --overwrite */

/* The user's files in a run folder: names that start like a run's, and what they hold. */
static const char *const user_files[][2] = {
    {"frame_notes.txt", "notes on frames\n"},
    {"surface_scan.stl", "solid scan\n"},
    {"checkpoint_plan.md", "# plan\n"},
    {"domains_list.txt", "domains\n"},
    {"levelset_ideas.txt", "ideas\n"},
    {"grid_cells_todo.txt", "todo\n"},
    {"stats.csv.bak", "frame,time\n"},
    {"frame_12.vtu", "too few digits for a frame of a run\n"},
    {"checkpoint_1.h5", "not twelve digits\n"},
    {".frame_notes.txt.tmp.12", "a hidden file of mine\n"},
    {"frame_backup_full/frame_0001.vtu", "a backup\n"},
};

static void test_overwrite_removes_only_run_files(void **state) {
  (void)state;
  const char *dir = test_temp_dir("overwrite");
  char out[600], scene[700], text[2048], args[2000], path[900];
  join(out, sizeof out, dir, "out");
  /* the scene being run lives in the output folder, under the name of the run's copy */
  join(scene, sizeof scene, out, "scene.json");
  mkdir(out, 0755);
  scene_text(text, sizeof text, 0.2, 2);
  write_file(scene, text);
  char sibling[700];
  join(sibling, sizeof sibling, dir, "first.json"); /* the first run's own scene */
  write_file(sibling, text);
  snprintf(args, sizeof args, "run '%s' -o '%s' --quiet", sibling, out);
  assert_int_equal(mpm(args), 2); /* scene.json there is a run's file name: refused */
  expect_output("holds the files of a run");
  assert_text(scene, text);
  snprintf(args, sizeof args, "run '%s' -o '%s' --quiet --overwrite", scene, out);
  assert_int_equal(mpm(args), 0); /* the scene given is kept, though named like a run file */
  assert_text(scene, text);
  join(path, sizeof path, out, "frame_0004.vtu");
  assert_true(exists(path));
  /* the user's files, an empty folder and a full one named like frames */
  join(path, sizeof path, out, "frame_backup_full");
  mkdir(path, 0755);
  join(path, sizeof path, out, "frame_empty");
  mkdir(path, 0755);
  for (size_t k = 0; k < sizeof user_files / sizeof user_files[0]; ++k) {
    join(path, sizeof path, out, user_files[k][0]);
    write_file(path, user_files[k][1]);
  }
  snprintf(args, sizeof args, "run '%s' -o '%s' --quiet --overwrite --frames 2", scene, out);
  if (mpm(args) != 0) fail_msg("overwrite: %s", output);
  for (size_t k = 0; k < sizeof user_files / sizeof user_files[0]; ++k) {
    join(path, sizeof path, out, user_files[k][0]);
    assert_text(path, user_files[k][1]);
  }
  join(path, sizeof path, out, "frame_empty");
  assert_true(exists(path));
  assert_text(scene, text);
  join(path, sizeof path, out, "frame_0004.vtu"); /* the earlier run's later frames are gone */
  assert_false(exists(path));
  join(path, sizeof path, out, "frame_0002.vtu");
  assert_true(exists(path));
}

/* A link or a folder bearing a run file's name: the overwrite is refused and nothing goes,
 * neither the run's files nor what the link points to. */
static void test_overwrite_refuses_links_and_folders(void **state) {
  (void)state;
  const char *dir = test_temp_dir("overwrite-links");
  char out[600], scene[700], text[2048], args[2000], path[900], victim[700];
  join(out, sizeof out, dir, "out");
  join(scene, sizeof scene, dir, "s.json");
  join(victim, sizeof victim, dir, "victim.txt");
  scene_text(text, sizeof text, 0.1, 1);
  write_file(scene, text);
  write_file(victim, "precious\n");
  snprintf(args, sizeof args, "run '%s' -o '%s' --quiet", scene, out);
  assert_int_equal(mpm(args), 0);
  static const char *const planted[] = {"frame_0007.vtu", "checkpoint_000000000100.h5"};
  for (int k = 0; k < 2; ++k) {
    join(path, sizeof path, out, planted[k]);
    if (k == 0) assert_int_equal(symlink(victim, path), 0);
    if (k == 1) assert_int_equal(mkdir(path, 0755), 0);
    snprintf(args, sizeof args, "run '%s' -o '%s' --quiet --overwrite", scene, out);
    assert_int_not_equal(mpm(args), 0);
    expect_output(planted[k]);
    expect_output(k == 0 ? "a symbolic link" : "a folder");
    expect_output("nothing was removed");
    char kept[900];
    join(kept, sizeof kept, out, "frame_0001.vtu");
    assert_true(exists(kept));
    join(kept, sizeof kept, out, "stats.csv");
    assert_true(exists(kept));
    assert_text(victim, "precious\n");
    if (k == 0) {
      assert_true(is_link(path));
      assert_int_equal(unlink(path), 0);
    }
  }
}

/* ---------------------------------------------------------------- one run at a time */

/* This process holds the folder: `mpm run` into it is refused whether new, overwriting or
 * resuming, and the holder's files stay; once released, the folder is free. */
static void test_folder_held_refuses_other_runs(void **state) {
  (void)state;
  const char *dir = test_temp_dir("lock");
  char out[600], scene[700], text[2048], args[2000], path[900];
  join(out, sizeof out, dir, "out");
  join(scene, sizeof scene, dir, "s.json");
  scene_text(text, sizeof text, 0.1, 1);
  write_file(scene, text);
  mpm_sim *sim = create_sim(text);
  assert_int_equal(mpm_sim_open_output(sim, out, MPM_OUTPUT_NEW), MPM_OK);
  assert_int_equal(mpm_sim_advance_frame(sim), MPM_OK);
  assert_int_equal(mpm_sim_write_checkpoint(sim, NULL, 0), MPM_OK);
  char pid[32];
  snprintf(pid, sizeof pid, "process %ld", (long)getpid());
  const char *const modes[] = {"-o '%s' --overwrite", "-o '%s'", "--resume '%s'"};
  for (int m = 0; m < 3; ++m) {
    char how[800];
    snprintf(how, sizeof how, modes[m], out);
    snprintf(args, sizeof args, "run '%s' %s --quiet", scene, how);
    assert_int_not_equal(mpm(args), 0);
    expect_output("is in use");
    expect_output(pid);
    join(path, sizeof path, out, "frame_0001.vtu");
    assert_true(exists(path));
  }
  /* another simulation of this process too */
  mpm_sim *other = create_sim(text);
  assert_int_equal(mpm_sim_open_output(other, out, MPM_OUTPUT_OVERWRITE), MPM_ERR_IO);
  assert_non_null(strstr(mpm_sim_last_error(other), "is in use"));
  assert_int_equal(mpm_sim_resume(other, out, NULL, 0), MPM_ERR_IO);
  assert_int_equal(mpm_sim_advance_frame(sim), MPM_OK); /* the holder goes on */
  mpm_sim_destroy(sim);
  /* released: the other simulation resumes it */
  assert_int_equal(mpm_sim_resume(other, out, NULL, 0), MPM_OK);
  mpm_sim_destroy(other);
  snprintf(args, sizeof args, "run '%s' -o '%s' --quiet --overwrite", scene, out);
  assert_int_equal(mpm(args), 0);
}

/* ---------------------------------------------------------------- temporaries */

/* Links planted at the writers' temporary names (this process's: .NAME.tmp.PID) for the next
 * frame, stats.csv and the next checkpoint: the run writes its files and the links' target is
 * untouched. */
static void test_temporaries_never_follow_links(void **state) {
  (void)state;
  const char *dir = test_temp_dir("temp-links");
  char out[600], victim[700], text[2048], path[900];
  join(out, sizeof out, dir, "out");
  join(victim, sizeof victim, dir, "victim.txt");
  write_file(victim, "precious\n");
  scene_text(text, sizeof text, 0.1, 0);
  mpm_sim *sim = create_sim(text);
  assert_int_equal(mpm_sim_open_output(sim, out, MPM_OUTPUT_NEW), MPM_OK);
  const long pid = (long)getpid();
  char planted[3][900];
  snprintf(planted[0], sizeof planted[0], "%s/.frame_0001.vtu.tmp.%ld", out, pid);
  snprintf(planted[1], sizeof planted[1], "%s/.stats.csv.tmp.%ld", out, pid);
  /* and a regular file of someone else's at the checkpoint's: not truncated either */
  for (int k = 0; k < 2; ++k) assert_int_equal(symlink(victim, planted[k]), 0);
  assert_int_equal(mpm_sim_advance_frame(sim), MPM_OK);
  char ckpt[900];
  snprintf(planted[2], sizeof planted[2], "%s/.checkpoint_%012lld.h5.tmp.%ld", out,
           (long long)mpm_sim_steps(sim), pid);
  write_file(planted[2], "someone's\n");
  assert_int_equal(mpm_sim_write_checkpoint(sim, ckpt, sizeof ckpt), MPM_OK);
  assert_text(victim, "precious\n");
  assert_text(planted[2], "someone's\n");
  for (int k = 0; k < 2; ++k) assert_true(is_link(planted[k]));
  join(path, sizeof path, out, "frame_0001.vtu");
  assert_false(is_link(path));
  assert_true(exists(path));
  mpm_sim_destroy(sim);
  /* the written checkpoint reads back */
  sim = create_sim(text);
  assert_int_equal(mpm_sim_resume(sim, out, NULL, 0), MPM_OK);
  assert_int_equal(mpm_sim_frame(sim), 1);
  mpm_sim_destroy(sim);
}

/* A run killed mid-write leaves its temporaries (.checkpoint_*.h5.tmp.PID, .frame_*.tmp.PID):
 * the resume removes them, and keeps hidden files of other names and planted links. */
static void test_resume_removes_stale_temporaries(void **state) {
  (void)state;
  const char *dir = test_temp_dir("stale");
  char out[600], text[2048], path[900], victim[700];
  join(out, sizeof out, dir, "out");
  join(victim, sizeof victim, dir, "victim.txt");
  write_file(victim, "precious\n");
  scene_text(text, sizeof text, 0.2, 1);
  mpm_sim *sim = create_sim(text);
  assert_int_equal(mpm_sim_open_output(sim, out, MPM_OUTPUT_NEW), MPM_OK);
  assert_int_equal(mpm_sim_advance_frame(sim), MPM_OK);
  assert_int_equal(mpm_sim_write_checkpoint(sim, NULL, 0), MPM_OK);
  mpm_sim_destroy(sim);
  static const char *const stale[] = {".checkpoint_000000000099.h5.tmp.4242",
                                      ".frame_0002.vtu.tmp.77", ".stats.csv.tmp.77.3",
                                      ".surface_b1_0002.ply.tmp.8"};
  static const char *const kept[] = {".notes.tmp.5", ".checkpoint_plan.tmp.3",
                                     ".frame_0002.vtu.tmp.x"};
  for (size_t k = 0; k < sizeof stale / sizeof stale[0]; ++k) {
    join(path, sizeof path, out, stale[k]);
    write_file(path, "half a file");
  }
  for (size_t k = 0; k < sizeof kept / sizeof kept[0]; ++k) {
    join(path, sizeof path, out, kept[k]);
    write_file(path, "mine\n");
  }
  char link[900];
  join(link, sizeof link, out, ".frame_0003.vtu.tmp.9");
  assert_int_equal(symlink(victim, link), 0);
  sim = create_sim(text);
  assert_int_equal(mpm_sim_resume(sim, out, NULL, 0), MPM_OK);
  for (size_t k = 0; k < sizeof stale / sizeof stale[0]; ++k) {
    join(path, sizeof path, out, stale[k]);
    if (exists(path)) fail_msg("the stale temporary %s is left", path);
  }
  for (size_t k = 0; k < sizeof kept / sizeof kept[0]; ++k) {
    join(path, sizeof path, out, kept[k]);
    assert_text(path, "mine\n");
  }
  assert_true(is_link(link));
  assert_text(victim, "precious\n");
  assert_int_equal(mpm_sim_advance_frame(sim), MPM_OK);
  mpm_sim_destroy(sim);
}

/* A folder named like the newest checkpoint is not read as one: the resume takes the newest
 * real checkpoint. */
static void test_folder_named_like_a_checkpoint(void **state) {
  (void)state;
  const char *dir = test_temp_dir("ckpt-folder");
  char out[600], text[2048], path[900], scene[700], args[2000];
  join(out, sizeof out, dir, "out");
  join(scene, sizeof scene, dir, "s.json");
  scene_text(text, sizeof text, 0.15, 1);
  write_file(scene, text);
  snprintf(args, sizeof args, "run '%s' -o '%s' --quiet --frames 2", scene, out);
  assert_int_equal(mpm(args), 0);
  join(path, sizeof path, out, "checkpoint_999999999999.h5");
  assert_int_equal(mkdir(path, 0755), 0);
  snprintf(args, sizeof args, "run '%s' --resume '%s' --quiet", scene, out);
  if (mpm(args) != 0) fail_msg("resume: %s", output);
  join(path, sizeof path, out, "frame_0003.vtu");
  assert_true(exists(path));
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_run_file_names),
      cmocka_unit_test(test_overwrite_removes_only_run_files),
      cmocka_unit_test(test_overwrite_refuses_links_and_folders),
      cmocka_unit_test(test_folder_held_refuses_other_runs),
      cmocka_unit_test(test_temporaries_never_follow_links),
      cmocka_unit_test(test_resume_removes_stale_temporaries),
      cmocka_unit_test(test_folder_named_like_a_checkpoint),
  };
  return test_cleanup(cmocka_run_group_tests_name("run_folder", tests, NULL, NULL));
}
