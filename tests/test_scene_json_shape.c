/* test_scene_json_shape.c - shapes, bodies and colliders in the JSON scene loader: bodies
 * must lie inside the domain minus the wall band, collider motion and keyframes are checked,
 * the scene is emptied on an error after allocation, and mesh bodies are loaded from files
 * resolved against the scene's directory (missing and broken meshes name the key path). */
#include "support.h"
#include "scene_json_support.h"
#include "scene/scene.h"

#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

/* ---- one test per class of mistake ------------------------------------------------------ */

static void test_body_outside_domain(void **state) {
  (void)state;
  /* band: [0.15, 0.85] on every axis (3 cells of 0.05) */
  expect_error("{" DOMAIN ", " TIME ", " MATS ", 'bodies': [" BODY ", {'shape': {'type': "
               "'sphere', 'center': [0.5, 0.2, 0.5], 'radius': 0.1}, 'material': 'jello'}]}",
               MPM_ERR_INVALID, "scenes/x.json: bodies[1].shape: expected the body's bounding box",
               "wall band of 3 cells", "[0.15, 0.15, 0.15] .. [0.85, 0.85, 0.85]",
               "sticks out by 0.05 m on -y", NULL);
  expect_error("{" DOMAIN ", " TIME ", " MATS ", 'bodies': [{'shape': {'type': 'box', 'center': "
               "[0.5, 0.5, 0.5], 'half_extent': [0.4, 0.1, 0.5]}, 'material': 'jello'}]}",
               MPM_ERR_INVALID, "bodies[0].shape: ", "0.05 m on -x, 0.05 m on +x",
               "0.15 m on -z, 0.15 m on +z", NULL);
  /* a tilted cylinder: bounding box from axis, radius and half height */
  expect_error("{" DOMAIN ", " TIME ", " MATS ", 'bodies': [{'shape': {'type': 'cylinder', "
               "'center': [0.5, 0.5, 0.5], 'radius': 0.1, 'axis': [1, 0, 0], 'half_height': 0.4}, "
               "'material': 'jello'}]}",
               MPM_ERR_INVALID, "bodies[0].shape: ", "0.05 m on -x", NULL);
  /* touching the band exactly is fine */
  mpm_scene s;
  parse_ok("{" DOMAIN ", " TIME ", " MATS ", 'bodies': [{'shape': {'type': 'box', 'center': "
           "[0.5, 0.5, 0.5], 'half_extent': [0.35, 0.35, 0.35]}, 'material': 'jello'}]}",
           &s);
  mpm_scene_free(&s);
}

static void test_motion_errors(void **state) {
  (void)state;
  expect_error(SCENE_WITH(", 'colliders': [{'shape': " SPHERE ", 'motion': {'keyframes': ["
                          "{'time': 0}, {'time': 0.5}, {'time': 0.5}]}}]"),
               MPM_ERR_INVALID,
               "colliders[0].motion.keyframes[2].time: expected a number > 0.5 (s, later than "
               "keyframes[1].time), got 0.5",
               NULL);
  expect_error(SCENE_WITH(", 'colliders': [{'shape': " SPHERE ", 'motion': {'velocity': [1, 0, "
                          "0], 'keyframes': [{'time': 0}]}}]"),
               MPM_ERR_INVALID,
               "colliders[0].motion: expected either 'keyframes' or "
               "'velocity'/'angular_speed', got both",
               NULL);
  expect_error(SCENE_WITH(", 'colliders': [{'shape': " SPHERE ", 'motion': {'keyframes': ["
                          "{'translation': [0, 0, 0]}]}}]"),
               MPM_ERR_INVALID, "colliders[0].motion.keyframes[0]: missing required key 'time'",
               NULL);
}

/* A revolve collider: the profile is read in order, and malformed outlines are named. */
static void test_revolve_profile(void **state) {
  (void)state;
  mpm_scene s;
  parse_ok(SCENE_WITH(", 'colliders': [{'shape': {'type': 'revolve', 'center': [0.5, 0.5, 0.5], "
                      "'profile': [[0, -0.3], [0.2, -0.3], [0.2, -0.1], [0.03, 0], [0.2, 0.1], "
                      "[0.2, 0.3], [0, 0.3]]}, 'inside_out': true}]"),
           &s);
  assert_int_equal(s.collider_count, 1);
  const mpm_shape_desc *sh = &s.colliders[0].shape;
  assert_int_equal(sh->kind, MPM_SHAPE_REVOLVE);
  assert_int_equal(sh->profile_count, 7);
  assert_true(sh->profile[3][0] == 0.03 && sh->profile[3][1] == 0);
  assert_true(sh->axis[0] == 0 && sh->axis[1] == 1 && sh->axis[2] == 0); /* default +y */
  mpm_scene_free(&s);
#define REVOLVE(P)                                                                                 \
  SCENE_WITH(                                                                                      \
      ", 'colliders': [{'shape': {'type': 'revolve', 'center': [0.5, 0.5, 0.5], 'profile': " P     \
      "}}]")
  expect_error(REVOLVE("[[0, 0], [0.1, 0]]"), MPM_ERR_INVALID,
               "colliders[0].shape.profile: expected 3 to 32 points, got 2", NULL);
  expect_error(REVOLVE("[[0.1, 0], [0.1, 0.1], [0, 0.1]]"), MPM_ERR_INVALID,
               "colliders[0].shape.profile[0]: expected radius 0 (the profile starts and ends on "
               "the axis), got 0.1",
               NULL);
  expect_error(REVOLVE("[[0, 0], [-0.1, 0.1], [0, 0.2]]"), MPM_ERR_INVALID,
               "colliders[0].shape.profile[1]: expected a radius >= 0 m, got -0.1", NULL);
  expect_error(REVOLVE("[[0, 0], [0.1, 0], [0.1, 0], [0, 0.2]]"), MPM_ERR_INVALID,
               "colliders[0].shape.profile[2]: expected a point different from the one before",
               NULL);
  expect_error(REVOLVE("[[0, 0], [0.1], [0, 0.2]]"), MPM_ERR_INVALID,
               "colliders[0].shape.profile[1]: expected a point [radius, height] of two finite "
               "numbers in m",
               NULL);
  /* a bow tie: segment 0-1 crosses segment 2-3 */
  expect_error(REVOLVE("[[0, 0], [0.2, 0.2], [0.2, 0], [0.05, 0.3], [0, 0.3]]"), MPM_ERR_INVALID,
               "colliders[0].shape.profile: expected a simple outline, but segment 0-1 meets "
               "segment 2-3",
               NULL);
#undef REVOLVE
  expect_error("{" DOMAIN ", " TIME ", " MATS ", 'bodies': [{'shape': {'type': 'revolve', "
               "'profile': [[0, 0], [0.1, 0], [0, 0.1]]}, 'material': 'jello'}]}",
               MPM_ERR_INVALID,
               "bodies[0].shape.type: expected one of box, sphere, cylinder, mesh, got 'revolve'",
               NULL);
}

/* The scene is emptied on an error found after keyframes and inline materials were
 * allocated (run under valgrind or ASan to see that nothing leaks). */
static void test_error_after_allocation(void **state) {
  (void)state;
  expect_error("{" DOMAIN ", " TIME ", 'materials': [], 'bodies': [{'shape': " SPHERE
               ", 'material': " JELLO "}], 'colliders': [{'shape': " SPHERE ", 'motion': "
               "{'keyframes': [{'time': 0}, {'time': 1}]}}, {'shape': " SPHERE
               ", 'rule': 'glue'}]}",
               MPM_ERR_INVALID, "colliders[1].rule", NULL);
  expect_error("{" DOMAIN ", " TIME ", " MATS ", " BODIES ", 'output': {'stats': 'yes'}}",
               MPM_ERR_INVALID, "output.stats: expected true or false, got a string ('yes')", NULL);
}

/* ---- files ------------------------------------------------------------------------------ */

static void test_mesh_bodies(void **state) {
  (void)state;
  const char *dir = test_temp_dir("scene_json_mesh");
  char sub[600], mesh[700], path[700], want[2000];
  snprintf(sub, sizeof sub, "%s/meshes", dir);
  assert_int_equal(mkdir(sub, 0755), 0);
  /* a unit cube from -1 to 1 (bounding box side 2) */
  snprintf(mesh, sizeof mesh, "%s/cube.obj", sub);
  write_file(mesh, "# cube\nv -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\n"
                   "v -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n"
                   "f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\n"
                   "f 4 8 7\nf 4 7 3\nf 1 5 8\nf 1 8 4\nf 2 3 7\nf 2 7 6\n");
  mpm_scene s;
  mpm_error err;

  /* scale 0.2: bounding box 0.4 m wide around the centre, inside the band */
  snprintf(path, sizeof path, "%s/mesh_ok.json", dir);
  write_file(path, q("{" DOMAIN ", " TIME ", " MATS ", 'bodies': [{'shape': {'type': 'mesh', "
                     "'file': 'meshes/cube.obj', 'center': [0.5, 0.5, 0.5], 'scale': 0.2}, "
                     "'material': 'jello'}]}"));
  if (mpm_scene_load(path, &s, &err) != MPM_OK) fail_msg("%s", err.message);
  assert_int_equal(s.bodies[0].shape.kind, MPM_SHAPE_MESH);
  assert_string_equal(s.bodies[0].shape.mesh_path, mesh); /* resolved against the scene dir */
  assert_close(s.bodies[0].shape.mesh_scale, 0.2, 0);
  mpm_scene_free(&s);

  /* scale 0.4 makes it 0.8 m wide: out of the band by 0.05 m on every side */
  snprintf(path, sizeof path, "%s/mesh_big.json", dir);
  write_file(path, q("{" DOMAIN ", " TIME ", " MATS ", 'bodies': [{'shape': {'type': 'mesh', "
                     "'file': 'meshes/cube.obj', 'center': [0.5, 0.5, 0.5], 'scale': 0.4}, "
                     "'material': 'jello'}]}"));
  assert_int_equal(mpm_scene_load(path, &s, &err), MPM_ERR_INVALID);
  assert_non_null(strstr(err.message, "bodies[0].shape: expected the body's bounding box"));
  assert_non_null(strstr(err.message, "0.05 m on -x"));
  assert_non_null(strstr(err.message, "the mesh is 2 x 2 x 2 in file units, times scale 0.4"));

  /* a missing mesh: the resolved path and the system's reason */
  snprintf(path, sizeof path, "%s/mesh_missing.json", dir);
  write_file(path, q("{" DOMAIN ", " TIME ", " MATS ", 'bodies': [{'shape': {'type': 'mesh', "
                     "'file': 'meshes/bunny.obj', 'center': [0.5, 0.5, 0.5]}, "
                     "'material': 'jello'}]}"));
  assert_int_equal(mpm_scene_load(path, &s, &err), MPM_ERR_IO);
  snprintf(want, sizeof want,
           "%s: bodies[0].shape.file: cannot open mesh file '%s/bunny.obj': "
           "No such file or directory",
           path, sub);
  if (!strstr(err.message, want)) fail_msg("'%s' not in: %s", want, err.message);
  assert_null(s.bodies);

  /* a mesh file that is not a mesh: the mesh reader's message under the key path */
  char junk[700];
  snprintf(junk, sizeof junk, "%s/junk.obj", sub);
  write_file(junk, "hello\n");
  snprintf(path, sizeof path, "%s/mesh_junk.json", dir);
  write_file(path, q("{" DOMAIN ", " TIME ", " MATS ", 'bodies': [{'shape': {'type': 'mesh', "
                     "'file': 'meshes/junk.obj', 'center': [0.5, 0.5, 0.5]}, "
                     "'material': 'jello'}]}"));
  mpm_status st = mpm_scene_load(path, &s, &err);
  assert_true(st == MPM_ERR_PARSE || st == MPM_ERR_INVALID);
  assert_non_null(strstr(err.message, "bodies[0].shape.file: "));
  if (!strstr(err.message, junk)) fail_msg("'%s' not in: %s", junk, err.message);

  /* mesh scale must be positive */
  expect_error("{" DOMAIN ", " TIME ", " MATS ", 'bodies': [{'shape': {'type': 'mesh', "
               "'file': 'a.obj', 'center': [0.5, 0.5, 0.5], 'scale': 0}, 'material': 'jello'}]}",
               MPM_ERR_INVALID, "bodies[0].shape.scale: expected a number > 0", NULL);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_body_outside_domain), cmocka_unit_test(test_motion_errors),
      cmocka_unit_test(test_revolve_profile),     cmocka_unit_test(test_error_after_allocation),
      cmocka_unit_test(test_mesh_bodies),
  };
  return test_cleanup(cmocka_run_group_tests(tests, NULL, NULL));
}
