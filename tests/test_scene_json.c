/* test_scene_json.c - the JSON scene loader: a full scene parses into the expected descriptor
 * values (defaults, inline materials, resolved names and paths, normalised directions,
 * resolution -> dx), and every class of mistake is reported with the right status and a
 * message that names the file, the key path and what was expected.
 *
 * This program holds the whole-scene tests, the top level, domain, time, solver and output,
 * JSON syntax, the mistakes common to all keys and loading files; materials are tested in
 * test_scene_json_material.c, shapes, bodies and colliders in test_scene_json_shape.c. */
#include "support.h"
#include "scene_json_support.h"
#include "scene/json_check.h"
#include "scene/scene.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- valid scenes ---------------------------------------------------------------------- */

static void test_full_scene(void **state) {
  (void)state;
  const char *json =
      "{ 'name': 'jello_cubes',"
      "  'domain': { 'min': [0, 0, 0], 'max': [2, 1, 1], 'dx': 0.02,"
      "              'walls': { 'rule': 'separate', 'friction': 0.25, 'cells': 4 } },"
      "  'gravity': [0, 0, -3],"
      "  'time': { 'end': 2.5, 'fps': 30 },"
      "  'solver': { 'kernel': 'ugimp', 'transfer': 'flip', 'flip_alpha': 0.9, 'cfl': 0.3,"
      "              'max_dt': 0.001, 'grid': 'dense', 'gimp_length': 0.01 },"
      "  'materials': [ " JELLO ", " STEEL " ],"
      "  'bodies': ["
      "    { 'name': 'a', 'shape': { 'type': 'box', 'center': [0.5, 0.5, 0.5],"
      "                              'half_extent': [0.1, 0.2, 0.3] },"
      "      'material': 'steel', 'velocity': [1, 2, 3], 'angular_velocity': [0, 0, 4],"
      "      'particles_per_cell': 27, 'jitter': 0.5, 'seed': 42 },"
      "    { 'shape': { 'type': 'cylinder', 'center': [1, 0.5, 0.5], 'radius': 0.1,"
      "                 'axis': [0, 0, 2], 'half_height': 0.2 },"
      "      'material': { 'model': 'neo_hookean', 'E': 5e4, 'nu': 0.45, 'density': 500,"
      "                    'min_stretch': 0.5 } },"
      "    { 'name': 'c', 'shape': { 'type': 'sphere', 'center': [1.5, 0.5, 0.5], 'radius': 0.2 },"
      "      'material': { 'name': 'goo', 'model': 'fixed_corotated', 'E': 1e3, 'nu': 0,"
      "                    'density': 1 } }"
      "  ],"
      "  'colliders': ["
      "    { 'name': 'floor', 'shape': { 'type': 'halfspace', 'point': [0, 0.1, 0],"
      "                                  'normal': [0, 3, 4] },"
      "      'rule': 'sticky', 'friction': 0.5 },"
      "    { 'shape': { 'type': 'cylinder', 'center': [1, 0.2, 0.5], 'radius': 0.05,"
      "                 'axis': [1, 0, 0] },"
      "      'inside_out': true,"
      "      'motion': { 'velocity': [0.1, 0, 0], 'axis': [0, 2, 0], 'angular_speed': -2 } },"
      "    { 'name': 'pusher', 'shape': { 'type': 'box', 'center': [0.2, 0.5, 0.5],"
      "                                   'half_extent': [0.05, 0.05, 0.05] },"
      "      'motion': { 'keyframes': [ { 'time': 0 },"
      "                                 { 'time': 0.5, 'translation': [0.1, 0, 0], 'angle': 1 },"
      "                                 { 'time': 1.5, 'translation': [0.3, 0, 0] } ] } }"
      "  ],"
      "  'output': { 'directory': 'results/run1', 'vtu': false, 'ply': true, 'stats': false }"
      "}";
  mpm_scene s;
  parse_ok(json, &s);
  assert_string_equal(s.path, FILE_NAME);
  assert_string_equal(s.name, "jello_cubes");
  assert_close(s.box_max[0], 2.0, 0);
  assert_close(s.dx, 0.02, 0);
  assert_int_equal(s.wall_rule, MPM_BOUNDARY_SEPARATE);
  assert_close(s.wall_friction, 0.25, 0);
  assert_int_equal(s.wall_cells, 4);
  assert_close(s.gravity[1], 0.0, 0);
  assert_close(s.gravity[2], -3.0, 0);
  assert_close(s.end_time, 2.5, 0);
  assert_close(s.fps, 30.0, 0);
  assert_int_equal(s.solver.kernel, MPM_KERNEL_UGIMP);
  assert_int_equal(s.solver.transfer, MPM_TRANSFER_FLIP);
  assert_int_equal(s.solver.grid, MPM_GRID_DENSE);
  assert_close(s.solver.flip_alpha, 0.9, 0);
  assert_close(s.solver.cfl, 0.3, 0);
  assert_close(s.solver.max_dt, 0.001, 0);
  assert_close(s.solver.gimp_length, 0.01, 0);

  /* two named materials plus two inline ones, appended in body order */
  assert_int_equal(s.material_count, 4);
  assert_string_equal(s.materials[0].name, "jello");
  assert_int_equal(s.materials[1].model, MPM_MODEL_NEO_HOOKEAN);
  assert_close(s.materials[1].E, 2e11, 0);
  assert_close(s.materials[1].min_stretch, 0.2, 0);  /* default */
  assert_string_equal(s.materials[2].name, "body1"); /* unnamed inline: the body's name */
  assert_close(s.materials[2].nu, 0.45, 0);
  assert_close(s.materials[2].min_stretch, 0.5, 0);
  assert_string_equal(s.materials[3].name, "goo");

  assert_int_equal(s.body_count, 3);
  const mpm_body_desc *a = &s.bodies[0];
  assert_string_equal(a->name, "a");
  assert_int_equal(a->material, 1); /* 'steel' */
  assert_int_equal(a->shape.kind, MPM_SHAPE_BOX);
  assert_close(a->shape.half_extent[2], 0.3, 0);
  assert_close(a->velocity[2], 3.0, 0);
  assert_close(a->angular_velocity[2], 4.0, 0);
  assert_close(a->particles_per_cell, 27.0, 0);
  assert_close(a->jitter, 0.5, 0);
  assert_int_equal(a->seed, 42);
  const mpm_body_desc *b = &s.bodies[1];
  assert_string_equal(b->name, "body1");
  assert_int_equal(b->material, 2);
  assert_int_equal(b->shape.kind, MPM_SHAPE_CYLINDER);
  assert_close(b->shape.axis[0], 0.0, 0);
  assert_close(b->shape.axis[2], 1.0, 1e-15); /* normalised */
  assert_close(b->shape.half_height, 0.2, 0);
  assert_close(b->particles_per_cell, 8.0, 0); /* defaults */
  assert_close(b->jitter, 0.0, 0);
  assert_close(b->velocity[0], 0.0, 0);
  assert_int_equal(s.bodies[2].material, 3);

  assert_int_equal(s.collider_count, 3);
  const mpm_collider_desc *f = &s.colliders[0];
  assert_string_equal(f->name, "floor");
  assert_int_equal(f->shape.kind, MPM_SHAPE_HALFSPACE);
  assert_close(f->shape.center[1], 0.1, 0);
  assert_close(f->shape.axis[1], 0.6, 1e-15);
  assert_close(f->shape.axis[2], 0.8, 1e-15);
  assert_int_equal(f->rule, MPM_BOUNDARY_STICKY);
  assert_close(f->friction, 0.5, 0);
  assert_int_equal(f->inside_out, 0);
  assert_int_equal(f->motion.keyframe_count, 0);
  const mpm_collider_desc *r = &s.colliders[1];
  assert_string_equal(r->name, "collider1");
  assert_int_equal(r->rule, MPM_BOUNDARY_SLIP); /* default */
  assert_int_equal(r->inside_out, 1);
  assert_close(r->shape.half_height, 0.0, 0); /* infinite */
  assert_close(r->motion.velocity[0], 0.1, 0);
  assert_close(r->motion.axis[1], 1.0, 1e-15);
  assert_close(r->motion.angular_speed, -2.0, 0);
  const mpm_collider_desc *p = &s.colliders[2];
  assert_int_equal(p->motion.keyframe_count, 3);
  assert_close(p->motion.keyframes[0].translation[0], 0.0, 0);
  assert_close(p->motion.keyframes[1].time, 0.5, 0);
  assert_close(p->motion.keyframes[1].angle, 1.0, 0);
  assert_close(p->motion.keyframes[2].translation[0], 0.3, 0);
  assert_close(p->motion.axis[2], 1.0, 0); /* default axis +z */

  assert_string_equal(s.output.directory, "results/run1");
  assert_int_equal(s.output.vtu, 0);
  assert_int_equal(s.output.ply, 1);
  assert_int_equal(s.output.stats, 0);
  mpm_scene_free(&s);
  assert_null(s.materials);
  assert_int_equal(s.collider_count, 0);
}

static void test_minimal_scene_defaults(void **state) {
  (void)state;
  mpm_scene s;
  parse_ok("{" DOMAIN ", " TIME ", 'materials': [" JELLO "], " BODIES "}", &s);
  assert_string_equal(s.name, "x"); /* the file stem */
  assert_close(s.gravity[0], 0.0, 0);
  assert_close(s.gravity[1], -9.81, 0);
  assert_int_equal(s.wall_rule, MPM_BOUNDARY_SLIP);
  assert_close(s.wall_friction, 0.0, 0);
  assert_int_equal(s.wall_cells, 3);
  assert_close(s.fps, 24.0, 0);
  assert_int_equal(s.solver.kernel, MPM_KERNEL_QUADRATIC);
  assert_int_equal(s.solver.transfer, MPM_TRANSFER_APIC);
  assert_int_equal(s.solver.grid, MPM_GRID_SPARSE);
  assert_close(s.solver.flip_alpha, 0.95, 0);
  assert_close(s.solver.cfl, 0.4, 0);
  assert_close(s.solver.max_dt, 0.0, 0);
  assert_close(s.solver.gimp_length, 0.0, 0);
  assert_string_equal(s.output.directory, "out");
  assert_int_equal(s.output.vtu, 1);
  assert_int_equal(s.output.ply, 1); /* PLY points by default: Houdini and Blender read them */
  assert_int_equal(s.output.stats, 1);
  assert_int_equal(s.material_count, 1);
  assert_int_equal(s.body_count, 1);
  assert_string_equal(s.bodies[0].name, "body0");
  assert_int_equal(s.bodies[0].material, 0);
  assert_int_equal(s.bodies[0].seed, 1);
  assert_int_equal(s.collider_count, 0);
  assert_null(s.colliders);
  mpm_scene_free(&s);

  /* the descriptor defaults on their own */
  mpm_material_desc m = mpm_material_desc_default();
  assert_int_equal(m.model, MPM_MODEL_FIXED_COROTATED);
  assert_close(m.min_stretch, 0.2, 0);
  assert_close(m.friction_angle, 30.0, 0);
  assert_close(m.cohesion, 0.0, 0);
  assert_close(m.yield_stress, 0.0, 0); /* no default: required for von_mises */
  assert_close(m.theta_c, 2.5e-2, 0);
  assert_close(m.theta_s, 7.5e-3, 0);
  assert_close(m.hardening, 10.0, 0);
  mpm_collider_desc c = mpm_collider_desc_default();
  assert_int_equal(c.rule, MPM_BOUNDARY_SLIP);
  assert_null(c.motion.keyframes);
  mpm_body_desc b = mpm_body_desc_default();
  assert_close(b.particles_per_cell, 8.0, 0);
  assert_close(b.shape.mesh_scale, 1.0, 0);
}

static void test_resolution_sets_dx(void **state) {
  (void)state;
  mpm_scene s;
  parse_ok("{'domain': {'min': [0, -1, 0], 'max': [1, 2, 1.5], 'resolution': 60}, " TIME ", " MATS
           ", 'bodies': [{'shape': {'type': 'box', 'center': [0.5, 0.5, 0.5], 'half_extent': "
           "[0.1, 0.1, 0.1]}, 'material': 'steel'}]}",
           &s);
  assert_close(s.dx, 3.0 / 60.0, 1e-15); /* longest axis (y, 3 m) / 60 */
  assert_int_equal(s.bodies[0].material, 1);
  mpm_scene_free(&s);
}

/* ---- one test per class of mistake ------------------------------------------------------ */

static void test_syntax_errors(void **state) {
  (void)state;
  /* a trailing comma on line 3 */
  expect_error("{\n  'name': 'a',\n  'time': {'end': 1,}\n}", MPM_ERR_PARSE, "line 3, column 21",
               "JSON syntax error near '}': expected a key in double quotes",
               "(a trailing comma before it?)", NULL);
  expect_error("{'a': [1, 2,\n ]}", MPM_ERR_PARSE, "line 2, column 2", "near ']'", "trailing comma",
               NULL);
  /* a missing comma */
  expect_error("{'name': 'a'\n 'time': 1}", MPM_ERR_PARSE, "line 2, column 2",
               "near '\"': expected ',' or '}' after an object member (a missing comma before it?)",
               NULL);
  /* an unquoted word */
  expect_error("{'name': True}", MPM_ERR_PARSE, "line 1, column 10", "near 'True'", NULL);
  /* truncated file */
  expect_error("{'name': 'a',\n 'time': {", MPM_ERR_PARSE, "line 2, column 11",
               "unexpected end of the file: expected a key in double quotes", NULL);
  /* a raw newline inside a string */
  expect_error("{'name': 'ab\ncd'}", MPM_ERR_PARSE, "line 1, column 13", "at the end of the line",
               "strings cannot span lines", NULL);
  /* a bad escape (a Windows path) */
  expect_error("{'name': 'C:\\data'}", MPM_ERR_PARSE, "line 1, column 14", "near 'data'",
               "expected an escape", NULL);
  /* numbers */
  expect_error("{'a': 01}", MPM_ERR_PARSE, "line 1, column 8", "no leading zeros", NULL);
  expect_error("{'a': .5}", MPM_ERR_PARSE, "line 1, column 7", "near '.5': expected a value", NULL);
  /* empty */
  expect_error("  \n", MPM_ERR_PARSE, "the file is empty", NULL);
  /* garbage after the object */
  expect_error("{} x", MPM_ERR_PARSE, "line 1, column 4", "near 'x'", NULL);
  /* comments */
  expect_error("{ // hello\n}", MPM_ERR_PARSE, "line 1, column 3", "comments", NULL);
  /* the top level must be an object */
  expect_error("[1, 2]", MPM_ERR_INVALID, "expected a JSON object", "got an array of 2 elements",
               NULL);
}

static void test_unknown_keys(void **state) {
  (void)state;
  expect_error(SCENE_WITH(", 'solver': {'kernal': 'cubic'}"), MPM_ERR_INVALID,
               "scenes/x.json: solver.kernal: unknown key; did you mean 'kernel'?", NULL);
  expect_error(SCENE_WITH(", 'gravty': [0, 0, 0]"), MPM_ERR_INVALID,
               "scenes/x.json: gravty: unknown key; did you mean 'gravity'?", NULL);
  /* nothing close: list the allowed keys */
  expect_error(SCENE_WITH(", 'output': {'format': 'vtk'}"), MPM_ERR_INVALID,
               "output.format: unknown key; allowed keys: directory, vtu, ply, stats", NULL);
  /* deep in a body's shape, qualified by the shape type */
  expect_error("{" DOMAIN ", " TIME ", " MATS ", 'bodies': [" BODY ", {'shape': {'type': 'box', "
               "'center': [0.5, 0.5, 0.5], 'half_extents': [0.1, 0.1, 0.1]}, 'material': "
               "'jello'}]}",
               MPM_ERR_INVALID,
               "bodies[1].shape.half_extents: unknown key for a box shape; did you mean "
               "'half_extent'?",
               NULL);
  /* a key of another shape type */
  expect_error("{" DOMAIN ", " TIME ", " MATS ", 'bodies': [{'shape': {'type': 'box', "
               "'center': [0.5, 0.5, 0.5], 'half_extent': [0.1, 0.1, 0.1], 'radius': 1}, "
               "'material': 'jello'}]}",
               MPM_ERR_INVALID, "bodies[0].shape.radius: unknown key for a box shape",
               "allowed keys: type, center, half_extent", NULL);
  /* keys are case-sensitive */
  expect_error("{" DOMAIN ", " TIME ", 'materials': [{'name': 'jello', 'model': "
               "'fixed_corotated', 'e': 1e5, 'nu': 0.3, 'density': 1000}], " BODIES "}",
               MPM_ERR_INVALID, "materials[0].e: unknown key; did you mean 'E'?", "case-sensitive",
               NULL);
  /* inside keyframes */
  expect_error(SCENE_WITH(", 'colliders': [{'shape': " SPHERE ", 'motion': {'keyframes': "
                          "[{'time': 0, 'angel': 1}]}}]"),
               MPM_ERR_INVALID,
               "colliders[0].motion.keyframes[0].angel: unknown key; did you mean 'angle'?", NULL);
}

static void test_missing_keys(void **state) {
  (void)state;
  expect_error("{'domain': {'min': [0, 0, 0], 'dx': 0.1}, " TIME ", " MATS ", " BODIES "}",
               MPM_ERR_INVALID, "scenes/x.json: domain: missing required key 'max'", NULL);
  expect_error("{" DOMAIN ", " TIME ", " MATS "}", MPM_ERR_INVALID,
               "scenes/x.json: missing required key 'bodies'", NULL);
  expect_error("{" DOMAIN ", " MATS ", " BODIES "}", MPM_ERR_INVALID,
               "scenes/x.json: missing required key 'time'", NULL);
  expect_error("{" DOMAIN ", " TIME ", 'materials': [{'name': 'jello', 'model': "
               "'fixed_corotated', 'nu': 0.3, 'density': 1000}], " BODIES "}",
               MPM_ERR_INVALID, "materials[0]: missing required key 'E'", NULL);
  expect_error("{" DOMAIN ", " TIME ", " MATS ", 'bodies': [{'shape': " SPHERE "}]}",
               MPM_ERR_INVALID, "bodies[0]: missing required key 'material'", NULL);
  expect_error("{" DOMAIN ", " TIME ", " MATS ", 'bodies': [{'shape': {'center': [0, 0, 0]}, "
               "'material': 'jello'}]}",
               MPM_ERR_INVALID, "bodies[0].shape: missing required key 'type'",
               "box, sphere, cylinder, mesh", NULL);
  /* a body cylinder needs a finite height */
  expect_error("{" DOMAIN ", " TIME ", " MATS ", 'bodies': [{'shape': {'type': 'cylinder', "
               "'center': [0.5, 0.5, 0.5], 'radius': 0.1}, 'material': 'jello'}]}",
               MPM_ERR_INVALID, "bodies[0].shape: missing required key 'half_height'", NULL);
  /* neither dx nor resolution */
  expect_error("{'domain': {'min': [0, 0, 0], 'max': [1, 1, 1]}, " TIME ", " MATS ", " BODIES "}",
               MPM_ERR_INVALID, "domain: missing required key 'dx'", "'resolution'", NULL);
  /* no bodies at all */
  expect_error("{" DOMAIN ", " TIME ", " MATS ", 'bodies': []}", MPM_ERR_INVALID,
               "bodies: expected at least one body, got an empty array", NULL);
}

static void test_wrong_types(void **state) {
  (void)state;
  expect_error("{'domain': {'min': 'origin', 'max': [1, 1, 1], 'dx': 0.1}, " TIME ", " MATS
               ", " BODIES "}",
               MPM_ERR_INVALID,
               "domain.min: expected an array of 3 numbers (m), got a string ('origin')", NULL);
  expect_error(SCENE_WITH(", 'gravity': [0, -9.81]"), MPM_ERR_INVALID,
               "gravity: expected an array of 3 numbers (m/s^2), got an array of 2 elements", NULL);
  expect_error(SCENE_WITH(", 'gravity': [0, '-9.81', 0]"), MPM_ERR_INVALID,
               "gravity[1]: expected a number (m/s^2), got a string ('-9.81')", NULL);
  expect_error(SCENE_WITH(", 'output': {'vtu': 1}"), MPM_ERR_INVALID,
               "output.vtu: expected true or false, got a number (1)", NULL);
  expect_error(SCENE_WITH(", 'name': 7"), MPM_ERR_INVALID,
               "name: expected a string, got a "
               "number (7)",
               NULL);
  expect_error(SCENE_WITH(", 'solver': []"), MPM_ERR_INVALID,
               "solver: expected an object of solver options, got an empty array", NULL);
  expect_error("{" DOMAIN ", " TIME ", 'materials': {}, " BODIES "}", MPM_ERR_INVALID,
               "materials: expected an array of material objects, got an object", NULL);
  expect_error("{" DOMAIN ", " TIME ", " MATS ", 'bodies': [{'shape': " SPHERE ", 'material': 3}]}",
               MPM_ERR_INVALID,
               "bodies[0].material: expected a material name (a string) or a material object, "
               "got a number (3)",
               NULL);
  expect_error(SCENE_WITH(", 'colliders': [{'shape': " SPHERE ", 'motion': {'keyframes': {}}}]"),
               MPM_ERR_INVALID,
               "colliders[0].motion.keyframes: expected an array of keyframe objects, got an "
               "object",
               NULL);
  /* seeds are integers */
  expect_error("{" DOMAIN ", " TIME ", " MATS ", 'bodies': [{'shape': " SPHERE
               ", 'material': 'jello', 'seed': 2.5}]}",
               MPM_ERR_INVALID, "bodies[0].seed: expected an integer in [0, 4294967295], got 2.5",
               NULL);
}

static void test_out_of_range(void **state) {
  (void)state;
  /* the brief's own example: an inline material of the third body */
  expect_error("{" DOMAIN ", " TIME ", " MATS ", 'bodies': [" BODY ", " BODY ", {'shape': " SPHERE
               ", 'material': {'model': 'neo_hookean', 'E': -5, 'nu': 0.3, 'density': 1}}]}",
               MPM_ERR_INVALID,
               "scenes/x.json: bodies[2].material.E: expected a number > 0 (Pa), "
               "got -5",
               NULL);
  expect_error("{" DOMAIN ", " TIME ", 'materials': [{'name': 'j', 'model': 'neo_hookean', "
               "'E': 1, 'nu': 0.5, 'density': 1}], " BODIES "}",
               MPM_ERR_INVALID, "materials[0].nu: expected a number in (-1, 0.5), got 0.5", NULL);
  expect_error(SCENE_WITH(", 'solver': {'cfl': 0}"), MPM_ERR_INVALID,
               "solver.cfl: expected a number in (0, 1], got 0", NULL);
  expect_error(SCENE_WITH(", 'solver': {'gimp_length': 0.11}"), MPM_ERR_INVALID,
               "solver.gimp_length: expected a number in [0, 0.1] (m, at most 2 dx", "got 0.11",
               NULL);
  expect_error("{'domain': {'min': [0, 0, 0], 'max': [1, 1, 1], 'dx': 0.05, 'walls': {'cells': "
               "1}}, " TIME ", " MATS ", " BODIES "}",
               MPM_ERR_INVALID, "domain.walls.cells: expected an integer in [2, 16] (cells), got 1",
               NULL);
  expect_error("{" DOMAIN ", " TIME ", " MATS ", 'bodies': [{'shape': " SPHERE
               ", 'material': 'jello', 'jitter': 1.5}]}",
               MPM_ERR_INVALID, "bodies[0].jitter: expected a number in [0, 1]", "got 1.5", NULL);
  expect_error("{" DOMAIN ", " TIME ", " MATS ", 'bodies': [{'shape': " SPHERE
               ", 'material': 'jello', 'particles_per_cell': 0}]}",
               MPM_ERR_INVALID, "bodies[0].particles_per_cell: expected a number in (0, 1000]",
               NULL);
  expect_error("{" DOMAIN ", 'time': {'end': -1}, " MATS ", " BODIES "}", MPM_ERR_INVALID,
               "time.end: expected a number > 0 (s), got -1", NULL);
  expect_error("{" DOMAIN ", " TIME ", " MATS ", 'bodies': [{'shape': {'type': 'box', 'center': "
               "[0.5, 0.5, 0.5], 'half_extent': [0.1, 0, 0.1]}, 'material': 'jello'}]}",
               MPM_ERR_INVALID, "bodies[0].shape.half_extent[1]: expected a number > 0 (m), got 0",
               NULL);
  expect_error(SCENE_WITH(", 'colliders': [{'shape': {'type': 'halfspace', 'point': [0, 0, 0], "
                          "'normal': [0, 0, 0]}}]"),
               MPM_ERR_INVALID, "colliders[0].shape.normal: expected a nonzero direction vector",
               NULL);
  expect_error(SCENE_WITH(", 'colliders': [{'shape': " SPHERE ", 'friction': -0.1}]"),
               MPM_ERR_INVALID, "colliders[0].friction: expected a number >= 0", "got -0.1", NULL);
  expect_error("{'domain': {'min': [0, 0, 0], 'max': [1, 1, 1], 'resolution': 4}, " TIME ", " MATS
               ", " BODIES "}",
               MPM_ERR_INVALID, "domain.resolution: expected an integer in [8, 1048576]", "got 4",
               NULL);
}

static void test_domain_errors(void **state) {
  (void)state;
  expect_error("{'domain': {'min': [0, 0, 0], 'max': [1, 0, 1], 'dx': 0.05}, " TIME ", " MATS
               ", " BODIES "}",
               MPM_ERR_INVALID,
               "domain.max[1]: expected a number > 0 (m, greater than min[1]), "
               "got 0",
               NULL);
  expect_error("{'domain': {'min': [0, 0, 0], 'max': [1, 1, 0.3], 'dx': 0.05}, " TIME ", " MATS
               ", " BODIES "}",
               MPM_ERR_INVALID, "domain.max[2]: expected a number > 0.4", "8*dx", "got 0.3", NULL);
  expect_error(
      "{'domain': {'min': [0, 0, 0], 'max': [1, 1, 1], 'dx': 0.05, 'resolution': 20}, " TIME
      ", " MATS ", " BODIES "}",
      MPM_ERR_INVALID, "domain: expected exactly one of 'dx' or 'resolution', got both", NULL);
}

static void test_non_finite(void **state) {
  (void)state;
  expect_error("{" DOMAIN ", " TIME ", 'materials': [{'name': 'j', 'model': 'neo_hookean', "
               "'E': 1e999, 'nu': 0.3, 'density': 1}], " BODIES "}",
               MPM_ERR_INVALID,
               "materials[0].E: expected a number > 0 (Pa), got a number too "
               "large to represent",
               NULL);
  expect_error(SCENE_WITH(", 'gravity': [0, -1e400, 0]"), MPM_ERR_INVALID,
               "gravity[1]: expected a number (m/s^2), got a number too large", "-infinity", NULL);
}

static void test_duplicate_keys(void **state) {
  (void)state;
  expect_error("{'domain': {'min': [0, 0, 0], 'max': [1, 1, 1], 'dx': 0.05, 'dx': 0.1}, " TIME
               ", " MATS ", " BODIES "}",
               MPM_ERR_INVALID, "domain.dx: duplicate key", NULL);
  expect_error(SCENE_WITH(", 'bodies': []"), MPM_ERR_INVALID, "bodies: duplicate key", NULL);
  expect_error(
      "{" DOMAIN ", " TIME ", 'materials': [" JELLO ", " JELLO "], " BODIES "}", MPM_ERR_INVALID,
      "materials[1].name: expected a unique material name, got 'jello' (materials[0]", NULL);
}

static void test_enum_errors(void **state) {
  (void)state;
  expect_error(SCENE_WITH(", 'colliders': [{'shape': " SPHERE ", 'rule': 'sticky2'}]"),
               MPM_ERR_INVALID,
               "colliders[0].rule: expected one of sticky, slip, separate, got 'sticky2'", NULL);
  expect_error(SCENE_WITH(", 'solver': {'kernel': 'qudratic'}"), MPM_ERR_INVALID,
               "solver.kernel: expected one of linear, quadratic, cubic, ugimp, got 'qudratic'; "
               "did you mean 'quadratic'?",
               NULL);
  expect_error(SCENE_WITH(", 'solver': {'transfer': 'pic'}"), MPM_ERR_INVALID,
               "solver.transfer: expected one of apic, flip, got 'pic'", NULL);
  expect_error("{" DOMAIN ", " TIME ", 'materials': [{'name': 'j', 'model': 'neohookean', "
               "'E': 1, 'nu': 0.3, 'density': 1}], " BODIES "}",
               MPM_ERR_INVALID,
               "materials[0].model: expected one of fixed_corotated, neo_hookean, hencky_stvk, "
               "drucker_prager, von_mises, snow, got 'neohookean'; did you mean 'neo_hookean'?",
               NULL);
  expect_error("{" DOMAIN ", " TIME ", " MATS ", 'bodies': [{'shape': {'type': 'halfspace', "
               "'point': [0, 0, 0], 'normal': [0, 1, 0]}, 'material': 'jello'}]}",
               MPM_ERR_INVALID,
               "bodies[0].shape.type: expected one of box, sphere, cylinder, "
               "mesh, got 'halfspace'",
               NULL);
  expect_error(SCENE_WITH(", 'colliders': [{'shape': {'type': 'mesh', 'file': 'a.obj', "
                          "'center': [0, 0, 0]}}]"),
               MPM_ERR_INVALID,
               "colliders[0].shape.type: expected one of box, sphere, cylinder, "
               "halfspace, revolve, got 'mesh'",
               NULL);
}

static void test_did_you_mean(void **state) {
  (void)state;
  assert_int_equal(mpm_json_edit_distance("kernal", "kernel"), 1);
  assert_int_equal(mpm_json_edit_distance("knerel", "kernel"), 2); /* two transpositions */
  assert_int_equal(mpm_json_edit_distance("E", "e"), 0);
  static const char *const names[] = {"kernel", "transfer", "flip_alpha", "cfl", NULL};
  assert_string_equal(mpm_json_suggest("trasnfer", names), "transfer");
  assert_string_equal(mpm_json_suggest("clf", names), "cfl");
  assert_null(mpm_json_suggest("zzz", names));
  assert_null(mpm_json_suggest("x", names));
  char buf[64];
  assert_string_equal(mpm_json_format_number(0.1, buf, sizeof buf), "0.1");
  assert_string_equal(mpm_json_format_number(-5, buf, sizeof buf), "-5");
  assert_string_equal(mpm_json_format_number(1e-7, buf, sizeof buf), "1e-07");
  assert_string_equal(mpm_json_format_number(0.1 + 0.2, buf, sizeof buf), "0.30000000000000004");
}

/* ---- files ------------------------------------------------------------------------------ */

static void test_load_files(void **state) {
  (void)state;
  const char *dir = test_temp_dir("scene_json_load");
  char path[600], bad[600];
  mpm_scene s;
  mpm_error err;

  /* a missing file: I/O error naming the file and the reason */
  snprintf(bad, sizeof bad, "%s/nope.json", dir);
  assert_int_equal(mpm_scene_load(bad, &s, &err), MPM_ERR_IO);
  assert_non_null(strstr(err.message, bad));
  assert_non_null(strstr(err.message, "No such file or directory"));
  assert_null(s.bodies);

  /* a directory */
  assert_int_equal(mpm_scene_load(dir, &s, &err), MPM_ERR_IO);
  assert_non_null(strstr(err.message, dir));
  assert_non_null(
      strstr(err.message, "cannot open the scene file: it is a folder, not a regular file"));

  /* a binary file */
  snprintf(bad, sizeof bad, "%s/binary.json", dir);
  FILE *f = fopen(bad, "wb");
  assert_non_null(f);
  fwrite("{\n \0\0", 1, 5, f);
  fclose(f);
  assert_int_equal(mpm_scene_load(bad, &s, &err), MPM_ERR_PARSE);
  assert_non_null(strstr(err.message, "line 2, column 2"));
  assert_non_null(strstr(err.message, "NUL byte"));

  /* a good file: read, parsed, named after its stem */
  snprintf(path, sizeof path, "%s/drop_test.json", dir);
  write_file(path, q(SCENE_WITH("")));
  assert_int_equal(mpm_scene_load(path, &s, &err), MPM_OK);
  assert_string_equal(s.name, "drop_test");
  assert_string_equal(s.path, path);
  assert_int_equal(s.body_count, 1);
  mpm_scene_free(&s);

  /* errors in a loaded file carry its path */
  snprintf(path, sizeof path, "%s/broken.json", dir);
  write_file(path, q(SCENE_WITH(", 'solver': {'cfl': 2}")));
  assert_int_equal(mpm_scene_load(path, &s, &err), MPM_ERR_INVALID);
  assert_non_null(strstr(err.message, path));
  assert_non_null(strstr(err.message, "solver.cfl: expected a number in (0, 1], got 2"));
}

/* camera: the view of `mpm render` */
static void test_camera(void **state) {
  (void)state;
  mpm_scene s;
  parse_ok(SCENE_WITH(", 'camera': {'eye': [2, 1, 3], 'target': [0.5, 0.4, 0.5], 'fov': 40}"), &s);
  assert_int_equal(s.camera.set, 1);
  assert_true(s.camera.eye[2] == 3 && s.camera.target[1] == 0.4 && s.camera.fov == 40);
  mpm_scene_free(&s);
  parse_ok(SCENE_WITH(""), &s);
  assert_int_equal(s.camera.set, 0); /* the renderer frames the domain */
  assert_true(s.camera.fov == 35);
  mpm_scene_free(&s);
  expect_error(SCENE_WITH(", 'camera': {'eye': [1, 1, 1], 'target': [1, 1, 1]}"), MPM_ERR_INVALID,
               "camera.target: expected a point other than the eye", NULL);
  expect_error(SCENE_WITH(", 'camera': {'eye': [1, 1, 1], 'target': [0, 0, 0], 'fov': 180}"),
               MPM_ERR_INVALID, "camera.fov: expected a number in (1, 170)", NULL);
  expect_error(SCENE_WITH(", 'camera': {'target': [0, 0, 0]}"), MPM_ERR_INVALID,
               "camera: missing required key 'eye'", NULL);
  expect_error(SCENE_WITH(", 'camera': {'eye': [1, 1, 1], 'target': [0, 0, 0], 'up': [0, 1, 0]}"),
               MPM_ERR_INVALID, "camera.up: unknown key; allowed keys: eye, target, fov", NULL);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_full_scene),
      cmocka_unit_test(test_minimal_scene_defaults),
      cmocka_unit_test(test_resolution_sets_dx),
      cmocka_unit_test(test_syntax_errors),
      cmocka_unit_test(test_unknown_keys),
      cmocka_unit_test(test_missing_keys),
      cmocka_unit_test(test_wrong_types),
      cmocka_unit_test(test_out_of_range),
      cmocka_unit_test(test_domain_errors),
      cmocka_unit_test(test_non_finite),
      cmocka_unit_test(test_duplicate_keys),
      cmocka_unit_test(test_enum_errors),
      cmocka_unit_test(test_did_you_mean),
      cmocka_unit_test(test_load_files),
      cmocka_unit_test(test_camera),
  };
  return test_cleanup(cmocka_run_group_tests(tests, NULL, NULL));
}
