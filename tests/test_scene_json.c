/* test_scene_json.c - the JSON scene loader: a full scene parses into the expected descriptor
 * values (defaults, inline materials, resolved names and paths, normalised directions,
 * resolution -> dx), and every class of mistake is reported with the right status and a
 * message that names the file, the key path and what was expected. */
#include "support.h"
#include "scene/json_check.h"
#include "scene/scene.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* Scenes are written with single quotes for readability; q() turns them into JSON. */
static char *q(const char *s) {
  static char buf[8192];
  size_t n = strlen(s);
  assert_true(n < sizeof buf);
  for (size_t i = 0; i <= n; ++i) buf[i] = s[i] == '\'' ? '"' : s[i];
  return buf;
}

#define DOMAIN "'domain': {'min': [0, 0, 0], 'max': [1, 1, 1], 'dx': 0.05}"
#define TIME "'time': {'end': 1}"
#define JELLO "{'name': 'jello', 'model': 'fixed_corotated', 'E': 1e5, 'nu': 0.3, 'density': 1000}"
#define STEEL "{'name': 'steel', 'model': 'neo_hookean', 'E': 2e11, 'nu': 0.28, 'density': 7800}"
#define MATS "'materials': [" JELLO ", " STEEL "]"
#define SPHERE "{'type': 'sphere', 'center': [0.5, 0.5, 0.5], 'radius': 0.1}"
#define BODY "{'shape': " SPHERE ", 'material': 'jello'}"
#define BODIES "'bodies': [" BODY "]"
/* A valid scene with one extra top-level member X spliced in (X starts with a comma). */
#define SCENE_WITH(X) "{" DOMAIN ", " TIME ", " MATS ", " BODIES X "}"

static const char *FILE_NAME = "scenes/x.json";

/* Parse and expect failure with `status`; every NULL-terminated needle must be in the
 * message, as must the file name. The scene must be left empty. */
static void expect_error(const char *json_single_quoted, mpm_status status, ...) {
  mpm_scene s;
  mpm_error err;
  mpm_error_clear(&err);
  mpm_status st = mpm_scene_parse(q(json_single_quoted), FILE_NAME, &s, &err);
  if (st != status)
    fail_msg("status %d, expected %d; message: %s; input: %s", st, status, err.message,
             json_single_quoted);
  assert_int_equal(err.status, status);
  if (strncmp(err.message, "scenes/x.json: ", 15) != 0)
    fail_msg("message does not start with the file: %s", err.message);
  va_list ap;
  va_start(ap, status);
  for (const char *needle = va_arg(ap, const char *); needle; needle = va_arg(ap, const char *))
    if (!strstr(err.message, needle)) fail_msg("'%s' not in message: %s", needle, err.message);
  va_end(ap);
  assert_null(s.materials);
  assert_null(s.bodies);
  assert_null(s.colliders);
  assert_int_equal(s.material_count + s.body_count + s.collider_count, 0);
}

static void parse_ok(const char *json_single_quoted, mpm_scene *s) {
  mpm_error err;
  mpm_error_clear(&err);
  mpm_status st = mpm_scene_parse(q(json_single_quoted), FILE_NAME, s, &err);
  if (st != MPM_OK) fail_msg("unexpected error: %s", err.message);
}

static void write_file(const char *path, const char *text) {
  FILE *f = fopen(path, "wb");
  assert_non_null(f);
  fputs(text, f);
  fclose(f);
}

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
  assert_close(s.domain_max[0], 2.0, 0);
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
  assert_int_equal(s.output.ply, 0);
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

/* Each model name parses into its kind; the model's own keys land in the struct and the
 * ones left out keep their defaults. */
static void test_plastic_models(void **state) {
  (void)state;
  const char *json =
      "{" DOMAIN ", " TIME ", 'materials': ["
      "  {'name': 'hs', 'model': 'hencky_stvk', 'E': 2e5, 'nu': 0.25, 'density': 900},"
      "  {'name': 'sand', 'model': 'drucker_prager', 'E': 3.5e5, 'nu': 0.3, 'density': 1600,"
      "   'friction_angle': 35, 'cohesion': 25},"
      "  {'name': 'dry', 'model': 'drucker_prager', 'E': 3.5e5, 'nu': 0.3, 'density': 1600},"
      "  {'name': 'goo', 'model': 'von_mises', 'E': 1e4, 'nu': 0.4, 'density': 1000,"
      "   'yield_stress': 300},"
      "  {'name': 'snow', 'model': 'snow', 'E': 1.4e5, 'nu': 0.2, 'density': 400,"
      "   'theta_c': 0.02, 'theta_s': 0.005, 'hardening': 0},"
      "  {'name': 'powder', 'model': 'snow', 'E': 1.4e5, 'nu': 0.2, 'density': 400},"
      "  {'name': 'frictionless', 'model': 'drucker_prager', 'E': 1e5, 'nu': 0.3,"
      "   'density': 1600, 'friction_angle': 0}"
      "], 'bodies': [{'shape': " SPHERE ", 'material': 'sand'},"
      "  {'shape': " SPHERE ", 'material': {'model': 'von_mises', 'E': 1e4, 'nu': 0.3,"
      "   'density': 1000, 'yield_stress': 1e-3}}]}";
  mpm_scene s;
  parse_ok(json, &s);
  assert_int_equal(s.material_count, 8);
  const mpm_material_desc *m = s.materials;
  assert_int_equal(m[0].model, MPM_MODEL_HENCKY_STVK);
  assert_close(m[0].E, 2e5, 0);
  assert_close(m[0].nu, 0.25, 0);
  assert_close(m[0].density, 900, 0);

  assert_int_equal(m[1].model, MPM_MODEL_DRUCKER_PRAGER);
  assert_close(m[1].friction_angle, 35.0, 0); /* degrees, as given */
  assert_close(m[1].cohesion, 25.0, 0);
  assert_int_equal(m[2].model, MPM_MODEL_DRUCKER_PRAGER);
  assert_close(m[2].friction_angle, 30.0, 0); /* defaults */
  assert_close(m[2].cohesion, 0.0, 0);

  assert_int_equal(m[3].model, MPM_MODEL_VON_MISES);
  assert_close(m[3].yield_stress, 300.0, 0);

  assert_int_equal(m[4].model, MPM_MODEL_SNOW);
  assert_close(m[4].theta_c, 0.02, 0);
  assert_close(m[4].theta_s, 0.005, 0);
  assert_close(m[4].hardening, 0.0, 0); /* 0 is allowed: no hardening */
  assert_int_equal(m[5].model, MPM_MODEL_SNOW);
  assert_close(m[5].theta_c, 2.5e-2, 0); /* defaults (Stomakhin et al. 2013) */
  assert_close(m[5].theta_s, 7.5e-3, 0);
  assert_close(m[5].hardening, 10.0, 0);

  assert_close(m[6].friction_angle, 0.0, 0); /* the closed end of [0, 90) */

  /* the inline von Mises material of body 1 */
  assert_int_equal(s.bodies[1].material, 7);
  assert_int_equal(m[7].model, MPM_MODEL_VON_MISES);
  assert_string_equal(m[7].name, "body1");
  assert_close(m[7].yield_stress, 1e-3, 0);
  mpm_scene_free(&s);
}

static void test_lame(void **state) {
  (void)state;
  double mu, lambda;
  mpm_lame(1e5, 0.25, &mu, &lambda);
  assert_close(mu, 4e4, 1e-9);
  assert_close(lambda, 4e4, 1e-9);
  mpm_lame(2.0, 0.0, &mu, &lambda);
  assert_close(mu, 1.0, 0);
  assert_close(lambda, 0.0, 0);
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
  expect_error(SCENE_WITH(", 'solver': {'gimp_length': 0.06}"), MPM_ERR_INVALID,
               "solver.gimp_length: expected a number in [0, 0.05] (m, at most dx", "got 0.06",
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

/* A material with model M and extra members X (X starts with a comma), as materials[1]. */
#define MAT1(M, X)                                                                                 \
  "{" DOMAIN ", " TIME ", 'materials': [" JELLO ", {'name': 'm', 'model': '" M "', 'E': 1e5, "     \
  "'nu': 0.3, 'density': 1000" X "}], " BODIES "}"

static void test_material_parameter_ranges(void **state) {
  (void)state;
  /* the message format of the brief, to the letter */
  expect_error(MAT1("drucker_prager", ", 'friction_angle': 95"), MPM_ERR_INVALID,
               "scenes/x.json: materials[1].friction_angle: expected a number in [0, 90) "
               "(degrees), got 95",
               NULL);
  expect_error(MAT1("drucker_prager", ", 'friction_angle': 90"), MPM_ERR_INVALID,
               "materials[1].friction_angle: expected a number in [0, 90) (degrees), got 90", NULL);
  expect_error(MAT1("drucker_prager", ", 'friction_angle': -1"), MPM_ERR_INVALID,
               "materials[1].friction_angle: expected a number in [0, 90) (degrees), got -1", NULL);
  expect_error(MAT1("drucker_prager", ", 'friction_angle': '30'"), MPM_ERR_INVALID,
               "materials[1].friction_angle: expected a number in [0, 90) (degrees), got a "
               "string ('30')",
               NULL);
  expect_error(MAT1("drucker_prager", ", 'cohesion': -0.5"), MPM_ERR_INVALID,
               "scenes/x.json: materials[1].cohesion: expected a number >= 0 (Pa), got -0.5", NULL);
  expect_error(MAT1("von_mises", ", 'yield_stress': 0"), MPM_ERR_INVALID,
               "scenes/x.json: materials[1].yield_stress: expected a number > 0 (Pa), got 0", NULL);
  expect_error(MAT1("von_mises", ", 'yield_stress': -100"), MPM_ERR_INVALID,
               "materials[1].yield_stress: expected a number > 0 (Pa), got -100", NULL);
  expect_error(MAT1("von_mises", ", 'yield_stress': 1e999"), MPM_ERR_INVALID,
               "materials[1].yield_stress: expected a number > 0 (Pa), got a number too large",
               NULL);
  expect_error(MAT1("snow", ", 'theta_c': 0"), MPM_ERR_INVALID,
               "scenes/x.json: materials[1].theta_c: expected a number in (0, 1) (critical "
               "compression), got 0",
               NULL);
  expect_error(MAT1("snow", ", 'theta_c': 1"), MPM_ERR_INVALID,
               "materials[1].theta_c: expected a number in (0, 1) (critical compression), got 1",
               NULL);
  expect_error(MAT1("snow", ", 'theta_s': 0"), MPM_ERR_INVALID,
               "scenes/x.json: materials[1].theta_s: expected a number > 0 (critical stretch), "
               "got 0",
               NULL);
  expect_error(MAT1("snow", ", 'hardening': -2"), MPM_ERR_INVALID,
               "scenes/x.json: materials[1].hardening: expected a number >= 0 (hardening "
               "coefficient), got -2",
               NULL);
  expect_error(MAT1("neo_hookean", ", 'min_stretch': 0"), MPM_ERR_INVALID,
               "materials[1].min_stretch: expected a number in (0, 1], got 0", NULL);
  /* in an inline material: the body's key path */
  expect_error("{" DOMAIN ", " TIME ", " MATS ", 'bodies': [{'shape': " SPHERE ", 'material': "
               "{'model': 'snow', 'E': 1e5, 'nu': 0.2, 'density': 400, 'theta_s': -1}}]}",
               MPM_ERR_INVALID,
               "scenes/x.json: bodies[0].material.theta_s: expected a number > 0 (critical "
               "stretch), got -1",
               NULL);
}

static void test_yield_stress_required(void **state) {
  (void)state;
  expect_error(MAT1("von_mises", ""), MPM_ERR_INVALID,
               "scenes/x.json: materials[1].yield_stress: required for model 'von_mises'",
               "expected a number > 0 (Pa)", NULL);
  expect_error("{" DOMAIN ", " TIME ", 'materials': [], 'bodies': [{'shape': " SPHERE
               ", 'material': {'model': 'von_mises', 'E': 1e4, 'nu': 0.3, 'density': 1000}}]}",
               MPM_ERR_INVALID,
               "scenes/x.json: bodies[0].material.yield_stress: required for model 'von_mises'",
               NULL);
  /* a typo of it is caught as an unknown key first */
  expect_error(MAT1("von_mises", ", 'yeild_stress': 100"), MPM_ERR_INVALID,
               "materials[1].yeild_stress: unknown key; did you mean 'yield_stress'?", NULL);
}

/* A parameter of another model would be ignored: an error naming the key and its models. */
static void test_material_key_not_for_model(void **state) {
  (void)state;
  expect_error(MAT1("neo_hookean", ", 'friction_angle': 30"), MPM_ERR_INVALID,
               "scenes/x.json: materials[1].friction_angle: applies only to model "
               "drucker_prager, not to 'neo_hookean' (it would have no effect)",
               NULL);
  expect_error(MAT1("snow", ", 'yield_stress': 100"), MPM_ERR_INVALID,
               "scenes/x.json: materials[1].yield_stress: applies only to model von_mises, not "
               "to 'snow'",
               NULL);
  expect_error(MAT1("fixed_corotated", ", 'min_stretch': 0.3"), MPM_ERR_INVALID,
               "scenes/x.json: materials[1].min_stretch: applies only to model neo_hookean, not "
               "to 'fixed_corotated'",
               NULL);
  expect_error(MAT1("drucker_prager", ", 'min_stretch': 0.3"), MPM_ERR_INVALID,
               "materials[1].min_stretch: applies only to model neo_hookean, not to "
               "'drucker_prager'",
               NULL);
  expect_error(MAT1("von_mises", ", 'yield_stress': 100, 'cohesion': 5"), MPM_ERR_INVALID,
               "materials[1].cohesion: applies only to model drucker_prager, not to 'von_mises'",
               NULL);
  expect_error(MAT1("drucker_prager", ", 'theta_c': 0.02"), MPM_ERR_INVALID,
               "materials[1].theta_c: applies only to model snow, not to 'drucker_prager'", NULL);
  expect_error(MAT1("hencky_stvk", ", 'theta_s': 0.01"), MPM_ERR_INVALID,
               "materials[1].theta_s: applies only to model snow, not to 'hencky_stvk'", NULL);
  expect_error(MAT1("fixed_corotated", ", 'hardening': 10"), MPM_ERR_INVALID,
               "materials[1].hardening: applies only to model snow, not to 'fixed_corotated'",
               NULL);
  /* even with a valid value, and even when the value is out of range (the key is the
     mistake), and in an inline material */
  expect_error(MAT1("snow", ", 'friction_angle': 95"), MPM_ERR_INVALID,
               "materials[1].friction_angle: applies only to model drucker_prager, not to 'snow'",
               NULL);
  expect_error("{" DOMAIN ", " TIME ", " MATS ", 'bodies': [{'shape': " SPHERE ", 'material': "
               "{'model': 'von_mises', 'E': 1e5, 'nu': 0.3, 'density': 1, 'yield_stress': 10, "
               "'hardening': 1}}]}",
               MPM_ERR_INVALID,
               "scenes/x.json: bodies[0].material.hardening: applies only to model snow, not to "
               "'von_mises'",
               NULL);
}

static void test_model_names(void **state) {
  (void)state;
  expect_error(MAT1("drucker-prager", ""), MPM_ERR_INVALID,
               "scenes/x.json: materials[1].model: expected one of fixed_corotated, neo_hookean, "
               "hencky_stvk, drucker_prager, von_mises, snow, got 'drucker-prager'; did you mean "
               "'drucker_prager'?",
               NULL);
  expect_error(MAT1("vonmises", ""), MPM_ERR_INVALID, "materials[1].model: expected one of ",
               "got 'vonmises'; did you mean 'von_mises'?", NULL);
  expect_error(MAT1("hencky_stvc", ""), MPM_ERR_INVALID, "did you mean 'hencky_stvk'?", NULL);
  expect_error(MAT1("Snow", ""), MPM_ERR_INVALID, "got 'Snow'; did you mean 'snow'?", NULL);
  /* nothing close: no suggestion */
  mpm_scene s;
  mpm_error err;
  mpm_error_clear(&err);
  assert_int_equal(mpm_scene_parse(q(MAT1("plasticine", "")), FILE_NAME, &s, &err),
                   MPM_ERR_INVALID);
  assert_non_null(strstr(err.message, "materials[1].model: expected one of fixed_corotated"));
  assert_null(strstr(err.message, "did you mean"));
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
               "halfspace, got 'mesh'",
               NULL);
}

static void test_unknown_material(void **state) {
  (void)state;
  expect_error("{" DOMAIN ", " TIME ", " MATS ", 'bodies': [{'shape': " SPHERE
               ", 'material': 'jelly'}]}",
               MPM_ERR_INVALID,
               "scenes/x.json: bodies[0].material: no material named 'jelly'; known: jello, steel",
               "did you mean 'jello'?", NULL);
  expect_error("{" DOMAIN ", " TIME ", 'materials': [], 'bodies': [{'shape': " SPHERE
               ", 'material': 'jello'}]}",
               MPM_ERR_INVALID, "bodies[0].material: no material named 'jello'",
               "'materials' array is empty", NULL);
  /* an inline material is not referable by name from other bodies */
  expect_error("{" DOMAIN ", " TIME ", 'materials': [], 'bodies': [{'shape': " SPHERE
               ", 'material': " JELLO "}, {'shape': " SPHERE ", 'material': 'jello'}]}",
               MPM_ERR_INVALID, "bodies[1].material: no material named 'jello'", NULL);
}

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
  assert_non_null(strstr(err.message, "cannot read the scene file"));

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
      cmocka_unit_test(test_full_scene),
      cmocka_unit_test(test_minimal_scene_defaults),
      cmocka_unit_test(test_resolution_sets_dx),
      cmocka_unit_test(test_plastic_models),
      cmocka_unit_test(test_lame),
      cmocka_unit_test(test_syntax_errors),
      cmocka_unit_test(test_unknown_keys),
      cmocka_unit_test(test_missing_keys),
      cmocka_unit_test(test_wrong_types),
      cmocka_unit_test(test_out_of_range),
      cmocka_unit_test(test_material_parameter_ranges),
      cmocka_unit_test(test_yield_stress_required),
      cmocka_unit_test(test_material_key_not_for_model),
      cmocka_unit_test(test_model_names),
      cmocka_unit_test(test_domain_errors),
      cmocka_unit_test(test_non_finite),
      cmocka_unit_test(test_duplicate_keys),
      cmocka_unit_test(test_enum_errors),
      cmocka_unit_test(test_unknown_material),
      cmocka_unit_test(test_body_outside_domain),
      cmocka_unit_test(test_motion_errors),
      cmocka_unit_test(test_error_after_allocation),
      cmocka_unit_test(test_did_you_mean),
      cmocka_unit_test(test_load_files),
      cmocka_unit_test(test_mesh_bodies),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
