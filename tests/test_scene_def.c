/* test_scene_def.c - a scene built in code (include/mpm/scene_def.h, issue 17) against the same
 * scene written as JSON by hand.
 *
 * The truth is the JSON parser: a def and the hand-written text must give the same scene
 * structs (every field the def mirrors, compared bit for bit through mpm_scene_parse, which sees
 * the defaults no particle shows: output switches, FLIP ratio under APIC, ...) and the same
 * simulation (count, positions, velocities and masses, bit for bit, after creation and after
 * one frame). The default test writes only the keys the format requires, so a _default() that
 * differs from the parser's default in any mirrored field fails it. Then the def's own checks
 * (NULLs, counts, enums, names: MPM_ERR_INVALID naming the field), the parser's messages under
 * the def's name, and mpm_scene_def_to_json read back. The comparisons are scene_def_support.h's;
 * the later fields (motion keyframes, forces, the multi-level grid, surfaces, the camera, ...)
 * are test_scene_def_more.c's. */
#include "scene_def_support.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- (a) the defaults ------------------------------------------------------------------ */

/* Only what the format requires; everything else is each _default()'s. */
static const char *const defaults_json =
    "{\"domain\": {\"min\": [0, 0, 0], \"max\": [1, 1, 1], \"dx\": 0.015625},"
    " \"time\": {\"end\": 1},"
    " \"materials\": [{\"name\": \"jelly\", \"model\": \"fixed_corotated\", \"E\": 1e5,"
    "   \"nu\": 0.3, \"density\": 1000},"
    "  {\"name\": \"m1\", \"model\": \"neo_hookean\", \"E\": 1e5, \"nu\": 0.3, \"density\": 1000},"
    "  {\"name\": \"m2\", \"model\": \"hencky_stvk\", \"E\": 1e5, \"nu\": 0.3, \"density\": 1000},"
    "  {\"name\": \"m3\", \"model\": \"drucker_prager\", \"E\": 1e5, \"nu\": 0.3,"
    "   \"density\": 1000},"
    "  {\"name\": \"m4\", \"model\": \"von_mises\", \"E\": 1e5, \"nu\": 0.3, \"density\": 1000,"
    "   \"yield_stress\": 1e4},"
    "  {\"name\": \"m5\", \"model\": \"snow\", \"E\": 1e5, \"nu\": 0.3, \"density\": 1000}],"
    " \"bodies\": [{\"shape\": {\"type\": \"sphere\", \"center\": [0.5, 0.3, 0.5],"
    "   \"radius\": 0.06}, \"material\": \"jelly\"}],"
    " \"colliders\": [{\"shape\": {\"type\": \"halfspace\", \"point\": [0, 0.2, 0],"
    "   \"normal\": [0, 1, 0]}},"
    "  {\"shape\": {\"type\": \"cylinder\", \"center\": [0.1, 0.5, 0.1], \"radius\": 0.02}}]}";

static void test_defaults(void **state) {
  (void)state;
  /* one material of each model, so that the defaults of every model's own keys are compared
     (the required yield_stress of von_mises aside); the body uses the first */
  static const char *const names[6] = {"jelly", "m1", "m2", "m3", "m4", "m5"};
  mpm_material_def mats[6];
  for (int i = 0; i < 6; ++i) {
    mats[i] = mpm_material_def_default();
    mats[i].name = names[i];
    mats[i].model = (mpm_def_model)i;
  }
  mats[MPM_DEF_VON_MISES].yield_stress = 1e4;
  const mpm_material_def jelly = mats[0];
  mpm_body_def ball = mpm_body_def_default();
  ball.shape = mpm_shape_def_default(MPM_DEF_SPHERE);
  ball.shape.center[0] = 0.5, ball.shape.center[1] = 0.3, ball.shape.center[2] = 0.5;
  ball.shape.radius = 0.06;
  mpm_collider_def col[2] = {mpm_collider_def_default(), mpm_collider_def_default()};
  col[0].shape.point[1] = 0.2; /* the normal's default, +y, is the JSON's */
  col[1].shape = mpm_shape_def_default(MPM_DEF_CYLINDER);
  col[1].shape.center[0] = 0.1, col[1].shape.center[1] = 0.5, col[1].shape.center[2] = 0.1;
  col[1].shape.radius = 0.02;
  mpm_scene_def def = mpm_scene_def_default();
  def.materials = mats, def.material_count = 6;
  def.bodies = &ball, def.body_count = 1;
  def.colliders = col, def.collider_count = 2;
  assert_def_is_json(&def, defaults_json, NULL);

  /* the defaults the struct says, spelled out (a change to them is a change of the API) */
  assert_int_equal(def.solver.kernel, MPM_DEF_KERNEL_QUADRATIC);
  assert_int_equal(def.domain.walls.rule, MPM_DEF_SLIP);
  assert_true(def.gravity[1] == -9.81 && def.time.fps == 24 && def.output.vtu == 1);
  assert_true(ball.particles_per_cell == 8 && ball.seed == 1 && jelly.min_stretch == 0.2);
  assert_true(col[0].shape.type == MPM_DEF_HALFSPACE && col[0].rule == MPM_DEF_SLIP);
}

/* ---- (b) every field ------------------------------------------------------------------- */

static mpm_material_def full_materials[4];
static mpm_body_def full_bodies[4];
static mpm_collider_def full_colliders[3];

static mpm_scene_def full_def(void) {
  mpm_material_def *m = full_materials;
  for (int i = 0; i < 4; ++i) m[i] = mpm_material_def_default();
  m[0].name = "rubber", m[0].model = MPM_DEF_NEO_HOOKEAN;
  m[0].E = 3e4, m[0].nu = 0.35, m[0].density = 1100, m[0].min_stretch = 0.3;
  m[1].name = "snow", m[1].model = MPM_DEF_SNOW;
  m[1].E = 1.4e5, m[1].nu = 0.2, m[1].density = 400;
  m[1].theta_c = 0.02, m[1].theta_s = 0.005, m[1].hardening = 7;
  m[2].name = "sand", m[2].model = MPM_DEF_DRUCKER_PRAGER;
  m[2].E = 3.5e5, m[2].nu = 0.29, m[2].density = 1600, m[2].friction_angle = 35, m[2].cohesion = 10;
  m[3].name = NULL, m[3].model = MPM_DEF_VON_MISES; /* named material3 */
  m[3].E = 2e5, m[3].nu = 0.33, m[3].density = 2700, m[3].yield_stress = 5e3;

  mpm_body_def *b = full_bodies;
  for (int i = 0; i < 4; ++i) b[i] = mpm_body_def_default();
  b[0].name = "block", b[0].material = 0;
  b[0].shape.center[0] = 0.1, b[0].shape.center[1] = 0.25, b[0].shape.center[2] = 0.15;
  for (int k = 0; k < 3; ++k) b[0].shape.half_extent[k] = 0.04 + 0.01 * k;
  b[0].velocity[0] = 0.5, b[0].velocity[1] = -0.25, b[0].angular_velocity[2] = 2;
  b[0].particles_per_cell = 4, b[0].jitter = 0.3, b[0].seed = 4000000000u;
  b[1].name = "snowball", b[1].material_name = "snow", b[1].material = 3;
  b[1].shape = mpm_shape_def_default(MPM_DEF_SPHERE);
  b[1].shape.center[0] = 0.3, b[1].shape.center[1] = 0.35, b[1].shape.center[2] = 0.2;
  b[1].shape.radius = 0.05, b[1].angular_velocity[0] = -1;
  b[2].material = 2; /* named body2 */
  b[2].shape = mpm_shape_def_default(MPM_DEF_CYLINDER);
  b[2].shape.center[0] = 0.3, b[2].shape.center[1] = 0.15, b[2].shape.center[2] = 0.2;
  b[2].shape.radius = 0.04, b[2].shape.half_height = 0.03;
  b[2].shape.axis[0] = 1, b[2].shape.axis[1] = 0, b[2].shape.axis[2] = 1;
  b[3].name = "torus", b[3].material = 3, b[3].domains = 1;
  b[3].shape = mpm_shape_def_default(MPM_DEF_MESH);
  b[3].shape.file = "meshes/torus.obj", b[3].shape.scale = 0.03, b[3].shape.max_file_mb = 8;
  b[3].shape.center[0] = 0.1, b[3].shape.center[1] = 0.45, b[3].shape.center[2] = 0.2;

  mpm_collider_def *c = full_colliders;
  for (int i = 0; i < 3; ++i) c[i] = mpm_collider_def_default();
  c[0].name = "floor", c[0].rule = MPM_DEF_STICKY, c[0].friction = 0.2;
  c[0].shape.point[1] = 0.12, c[0].shape.normal[0] = 0.1;
  c[1].name = "pusher", c[1].rule = MPM_DEF_SEPARATE, c[1].friction = 0.4;
  c[1].shape = mpm_shape_def_default(MPM_DEF_BOX);
  c[1].shape.center[0] = 0.45, c[1].shape.center[1] = 0.3, c[1].shape.center[2] = 0.2;
  c[1].shape.half_extent[0] = 0.02, c[1].shape.half_extent[1] = 0.1;
  c[1].shape.half_extent[2] = 0.1;
  c[1].motion.velocity[0] = -0.3;
  c[2].name = "jar", c[2].inside_out = 1;
  c[2].shape = mpm_shape_def_default(MPM_DEF_CYLINDER);
  c[2].shape.center[0] = 0.25, c[2].shape.center[1] = 0.3, c[2].shape.center[2] = 0.2;
  c[2].shape.radius = 0.3, c[2].shape.half_height = 0;
  c[2].motion.axis[0] = 0, c[2].motion.axis[1] = 1, c[2].motion.axis[2] = 0;
  c[2].motion.angular_speed = 1.5;

  mpm_scene_def d = mpm_scene_def_default();
  d.name = "full";
  d.domain.min[0] = -0.1, d.domain.max[0] = 0.6, d.domain.max[1] = 0.6, d.domain.max[2] = 0.4;
  d.domain.dx = 0.02;
  d.domain.walls.rule = MPM_DEF_SEPARATE, d.domain.walls.friction = 0.3;
  d.domain.walls.cells = 4;
  d.gravity[0] = 0.5, d.gravity[1] = -9, d.gravity[2] = 0.1;
  d.time.end = 0.2, d.time.fps = 30;
  d.solver.kernel = MPM_DEF_KERNEL_CUBIC, d.solver.transfer = MPM_DEF_FLIP;
  d.solver.flip_alpha = 0.9, d.solver.cfl = 0.3, d.solver.max_dt = 2e-3;
  d.materials = m, d.material_count = 4;
  d.bodies = b, d.body_count = 4;
  d.colliders = c, d.collider_count = 3;
  d.output.directory = "/tmp/full_out", d.output.vtu = 0, d.output.ply = 1, d.output.stats = 0;
  d.output.checkpoint_every = 3;
  return d;
}

static const char *const full_json =
    "{\"name\": \"full\","
    " \"domain\": {\"min\": [-0.1, 0, 0], \"max\": [0.6, 0.6, 0.4], \"dx\": 0.02,"
    "   \"walls\": {\"rule\": \"separate\", \"friction\": 0.3, \"cells\": 4}},"
    " \"gravity\": [0.5, -9, 0.1], \"time\": {\"end\": 0.2, \"fps\": 30},"
    " \"solver\": {\"integrator\": \"explicit\", \"kernel\": \"cubic\", \"transfer\": \"flip\","
    "   \"flip_alpha\": 0.9, \"cfl\": 0.3, \"max_dt\": 2e-3},"
    " \"materials\": ["
    "  {\"name\": \"rubber\", \"model\": \"neo_hookean\", \"E\": 3e4, \"nu\": 0.35,"
    "   \"density\": 1100, \"min_stretch\": 0.3},"
    "  {\"name\": \"snow\", \"model\": \"snow\", \"E\": 1.4e5, \"nu\": 0.2, \"density\": 400,"
    "   \"theta_c\": 0.02, \"theta_s\": 0.005, \"hardening\": 7},"
    "  {\"name\": \"sand\", \"model\": \"drucker_prager\", \"E\": 3.5e5, \"nu\": 0.29,"
    "   \"density\": 1600, \"friction_angle\": 35, \"cohesion\": 10},"
    "  {\"name\": \"material3\", \"model\": \"von_mises\", \"E\": 2e5, \"nu\": 0.33,"
    "   \"density\": 2700, \"yield_stress\": 5e3}],"
    " \"bodies\": ["
    "  {\"name\": \"block\", \"shape\": {\"type\": \"box\", \"center\": [0.1, 0.25, 0.15],"
    "   \"half_extent\": [0.04, 0.05, 0.06]}, \"material\": \"rubber\","
    "   \"velocity\": [0.5, -0.25, 0], \"angular_velocity\": [0, 0, 2],"
    "   \"particles_per_cell\": 4, \"jitter\": 0.3, \"seed\": 4000000000},"
    "  {\"name\": \"snowball\", \"shape\": {\"type\": \"sphere\", \"center\": [0.3, 0.35, 0.2],"
    "   \"radius\": 0.05}, \"material\": \"snow\", \"angular_velocity\": [-1, 0, 0]},"
    "  {\"shape\": {\"type\": \"cylinder\", \"center\": [0.3, 0.15, 0.2], \"radius\": 0.04,"
    "   \"half_height\": 0.03, \"axis\": [1, 0, 1]}, \"material\": \"sand\"},"
    "  {\"name\": \"torus\", \"shape\": {\"type\": \"mesh\", \"file\": \"meshes/torus.obj\","
    "   \"center\": [0.1, 0.45, 0.2], \"scale\": 0.03, \"max_file_mb\": 8},"
    "   \"material\": \"material3\","
    "   \"domains\": true}],"
    " \"colliders\": ["
    "  {\"name\": \"floor\", \"shape\": {\"type\": \"halfspace\", \"point\": [0, 0.12, 0],"
    "   \"normal\": [0.1, 1, 0]}, \"rule\": \"sticky\", \"friction\": 0.2},"
    "  {\"name\": \"pusher\", \"shape\": {\"type\": \"box\", \"center\": [0.45, 0.3, 0.2],"
    "   \"half_extent\": [0.02, 0.1, 0.1]}, \"rule\": \"separate\", \"friction\": 0.4,"
    "   \"motion\": {\"velocity\": [-0.3, 0, 0]}},"
    "  {\"name\": \"jar\", \"shape\": {\"type\": \"cylinder\", \"center\": [0.25, 0.3, 0.2],"
    "   \"radius\": 0.3}, \"inside_out\": true,"
    "   \"motion\": {\"axis\": [0, 1, 0], \"angular_speed\": 1.5}}],"
    " \"output\": {\"directory\": \"/tmp/full_out\", \"vtu\": false, \"ply\": true,"
    "   \"stats\": false, \"checkpoint_every\": 3}}";

static void test_every_field(void **state) {
  (void)state;
  const mpm_scene_def def = full_def();
  assert_def_is_json(&def, full_json, "examples");
}

/* The implicit integrator's fields, written only for it. */
static void test_implicit_fields(void **state) {
  (void)state;
  mpm_material_def m = mpm_material_def_default();
  m.name = "m";
  mpm_body_def b = mpm_body_def_default();
  for (int k = 0; k < 3; ++k) b.shape.center[k] = 0.5, b.shape.half_extent[k] = 0.05;
  mpm_scene_def def = mpm_scene_def_default();
  def.materials = &m, def.material_count = 1, def.bodies = &b, def.body_count = 1;
  def.domain.dx = 0.05, def.time.end = 0.05, def.time.fps = 40;
  def.solver.integrator = MPM_DEF_IMPLICIT, def.solver.dt = 2.5e-3;
  def.solver.newton_iterations = 1;
  assert_def_is_json(&def,
                     "{\"domain\": {\"min\": [0, 0, 0], \"max\": [1, 1, 1], \"dx\": 0.05},"
                     " \"time\": {\"end\": 0.05, \"fps\": 40},"
                     " \"solver\": {\"integrator\": \"implicit\", \"dt\": 2.5e-3,"
                     "   \"newton_iterations\": 1},"
                     " \"materials\": [{\"name\": \"m\", \"model\": \"fixed_corotated\","
                     "   \"E\": 1e5, \"nu\": 0.3, \"density\": 1000}],"
                     " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.5, 0.5, 0.5],"
                     "   \"half_extent\": [0.05, 0.05, 0.05]}, \"material\": \"m\"}]}",
                     NULL);
}

/* Heat and melting, and output.fields: a hot plate under a melting block with its own starting
 * temperature, beside a ball at the scene's, writing the stress tensor and the temperature. */
static const mpm_def_field heat_fields[] = {MPM_DEF_FIELD_ID, MPM_DEF_FIELD_TEMPERATURE,
                                            MPM_DEF_FIELD_MELT, MPM_DEF_FIELD_CAUCHY_STRESS};

static mpm_scene_def heat_def(mpm_material_def *wax, mpm_body_def bodies[2],
                              mpm_collider_def *plate) {
  *wax = mpm_material_def_default();
  wax->name = "wax";
  wax->model = MPM_DEF_NEO_HOOKEAN;
  wax->specific_heat = 2000;
  wax->conductivity = 5;
  wax->melting = 1;
  wax->melt_point = 40;
  wax->melt_range = 5;
  wax->melt_shear = 0.1;
  wax->melt_bulk = 0.5;
  bodies[0] = mpm_body_def_default();
  bodies[0].shape.center[0] = 0.3, bodies[0].shape.center[1] = 0.3, bodies[0].shape.center[2] = 0.5;
  bodies[0].shape.half_extent[0] = bodies[0].shape.half_extent[1] = 0.08;
  bodies[0].shape.half_extent[2] = 0.08;
  bodies[0].has_temperature = 1;
  bodies[0].temperature = 35;
  bodies[1] = mpm_body_def_default();
  bodies[1].shape = mpm_shape_def_default(MPM_DEF_SPHERE);
  bodies[1].shape.center[0] = 0.7, bodies[1].shape.center[1] = 0.3, bodies[1].shape.center[2] = 0.5;
  bodies[1].shape.radius = 0.07;
  *plate = mpm_collider_def_default();
  plate->shape = mpm_shape_def_default(MPM_DEF_BOX);
  plate->shape.center[0] = 0.5, plate->shape.center[1] = 0.15, plate->shape.center[2] = 0.5;
  plate->shape.half_extent[0] = 0.4, plate->shape.half_extent[1] = 0.05;
  plate->shape.half_extent[2] = 0.4;
  plate->rule = MPM_DEF_STICKY;
  plate->heat_source = 1;
  plate->temperature = 90;
  mpm_scene_def def = mpm_scene_def_default();
  def.domain.dx = 0.04;
  def.time.end = 0.05, def.time.fps = 40;
  def.materials = wax, def.material_count = 1;
  def.bodies = bodies, def.body_count = 2;
  def.colliders = plate, def.collider_count = 1;
  def.heat.enabled = 1;
  def.heat.temperature = 20;
  def.heat.pic = 0.25;
  for (size_t k = 0; k < sizeof heat_fields / sizeof heat_fields[0]; ++k)
    def.output.fields |= 1u << heat_fields[k];
  return def;
}

static void test_heat_and_fields(void **state) {
  (void)state;
  mpm_material_def wax;
  mpm_body_def bodies[2];
  mpm_collider_def plate;
  const mpm_scene_def def = heat_def(&wax, bodies, &plate);
  assert_def_is_json(
      &def,
      "{\"domain\": {\"min\": [0, 0, 0], \"max\": [1, 1, 1], \"dx\": 0.04},"
      " \"time\": {\"end\": 0.05, \"fps\": 40},"
      " \"heat\": {\"temperature\": 20, \"pic\": 0.25},"
      " \"materials\": [{\"name\": \"wax\", \"model\": \"neo_hookean\", \"E\": 1e5,"
      "   \"nu\": 0.3, \"density\": 1000, \"specific_heat\": 2000, \"conductivity\": 5,"
      "   \"melting\": {\"point\": 40, \"range\": 5, \"shear\": 0.1, \"bulk\": 0.5}}],"
      " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.3, 0.3, 0.5],"
      "   \"half_extent\": [0.08, 0.08, 0.08]}, \"material\": \"wax\", \"temperature\": 35},"
      "  {\"shape\": {\"type\": \"sphere\", \"center\": [0.7, 0.3, 0.5], \"radius\": 0.07},"
      "   \"material\": \"wax\"}],"
      " \"colliders\": [{\"shape\": {\"type\": \"box\", \"center\": [0.5, 0.15, 0.5],"
      "   \"half_extent\": [0.4, 0.05, 0.4]}, \"rule\": \"sticky\", \"temperature\": 90}],"
      " \"output\": {\"fields\": [\"cauchy_stress\", \"id\", \"melt\", \"temperature\"]}}",
      NULL);
  /* the temperatures reach the particles: the block's own, the ball the scene's */
  mpm_sim *sim = NULL;
  char err[1024];
  if (mpm_sim_create_from_def(&def, NULL, &sim, err, sizeof err) != MPM_OK) fail_msg("%s", err);
  const mpm_particle_view v = mpm_sim_particles(sim);
  assert_non_null(v.temperature);
  size_t n[2] = {0, 0};
  for (size_t i = 0; i < v.count; ++i) {
    const double T =
        v.real_size == 4 ? ((const float *)v.temperature)[i] : ((const double *)v.temperature)[i];
    assert_true(v.body[i] == 0 ? T == 35 : T == 20);
    ++n[v.body[i]];
  }
  assert_true(n[0] > 0 && n[1] > 0);
  mpm_sim_destroy(sim);
}

/* ---- (c) what the def refuses ---------------------------------------------------------- */

static void test_refused(void **state) {
  (void)state;
  char err[256];
  mpm_sim *sim = NULL;
  assert_int_equal(mpm_sim_create_from_def(NULL, NULL, &sim, err, sizeof err), MPM_ERR_INVALID);
  assert_null(sim);
  assert_non_null(strstr(err, "NULL"));
  char *text = NULL;
  assert_int_equal(mpm_scene_def_to_json(NULL, &text, err, sizeof err), MPM_ERR_INVALID);
  assert_null(text);

  const mpm_scene_def good = full_def();
  mpm_scene_def d = good;
  d.materials = NULL;
  assert_refused(&d, "materials: NULL with material_count 4");
  d = good, d.bodies = NULL;
  assert_refused(&d, "bodies: NULL with body_count 4");
  d = good, d.colliders = NULL;
  assert_refused(&d, "colliders: NULL");
  d = good, d.body_count = -1;
  assert_refused(&d, "bodies: expected body_count >= 0, got -1");
  d = good, d.material_count = -2;
  assert_refused(&d, "material_count");
  d = good, d.collider_count = -3;
  assert_refused(&d, "collider_count");

  /* enum values out of range */
  d = good, d.solver.kernel = (mpm_def_kernel)7;
  assert_refused(&d, "solver.kernel: expected an mpm_def_kernel");
  d = good, d.solver.transfer = (mpm_def_transfer)-1;
  assert_refused(&d, "solver.transfer");
  d = good, d.solver.integrator = (mpm_def_integrator)2;
  assert_refused(&d, "solver.integrator");
  d = good, d.domain.walls.rule = (mpm_def_rule)3;
  assert_refused(&d, "domain.walls.rule");
  mpm_material_def mats[4];
  memcpy(mats, full_materials, sizeof mats);
  d = good, d.materials = mats, mats[2].model = (mpm_def_model)6;
  assert_refused(&d, "materials[2].model: expected an mpm_def_model");
  mpm_body_def bodies[4];
  memcpy(bodies, full_bodies, sizeof bodies);
  d = good, d.bodies = bodies, bodies[1].shape.type = (mpm_def_shape_type)9;
  assert_refused(&d, "bodies[1].shape.type");
  mpm_collider_def cols[3];
  memcpy(cols, full_colliders, sizeof cols);
  d = good, d.colliders = cols, cols[2].rule = (mpm_def_rule)-4;
  assert_refused(&d, "colliders[2].rule");

  /* names over 63 bytes, at every level */
  static const char long_name[] =
      "a_name_of_sixty_four_bytes_which_is_one_more_than_the_format_has";
  assert_int_equal(strlen(long_name), 64);
  d = good, d.name = long_name;
  assert_refused(&d, "name: expected a name of at most 63 bytes, got 64");
  memcpy(mats, full_materials, sizeof mats);
  d = good, d.materials = mats, mats[1].name = long_name;
  assert_refused(&d, "materials[1].name");
  memcpy(bodies, full_bodies, sizeof bodies);
  d = good, d.bodies = bodies, bodies[0].name = long_name;
  assert_refused(&d, "bodies[0].name");
  memcpy(bodies, full_bodies, sizeof bodies);
  d = good, d.bodies = bodies, bodies[1].material_name = long_name;
  assert_refused(&d, "bodies[1].material_name");
  memcpy(cols, full_colliders, sizeof cols);
  d = good, d.colliders = cols, cols[0].name = long_name;
  assert_refused(&d, "colliders[0].name");

  /* a material index out of range; fields that would have no effect */
  memcpy(bodies, full_bodies, sizeof bodies);
  d = good, d.bodies = bodies, bodies[2].material = 4;
  assert_refused(&d, "bodies[2].material: expected an index into the def's materials (0 .. 3)");
  d = good, d.material_count = 0, d.body_count = 1;
  assert_refused(&d, "bodies[0].material: the def has no materials");
  memcpy(mats, full_materials, sizeof mats);
  d = good, d.materials = mats, mats[0].friction_angle = 40;
  assert_refused(&d, "materials[0].friction_angle: applies only to model drucker_prager");
  memcpy(bodies, full_bodies, sizeof bodies);
  d = good, d.bodies = bodies, bodies[0].shape.radius = 0.1;
  assert_refused(&d, "bodies[0].shape.radius: not a field of a box shape");
  d = good, d.solver.newton_iterations = 3;
  assert_refused(&d, "solver.newton_iterations: a field of the implicit integrator only");

  /* heat fields without heat, and values that their switch leaves unused */
  {
    mpm_material_def wax;
    mpm_body_def hb[2];
    mpm_collider_def plate;
    const mpm_scene_def hot = heat_def(&wax, hb, &plate);
    d = hot, d.heat.enabled = 0;
    assert_refused(&d, "materials[0].specific_heat: a heat field, and the def's heat is off");
    mpm_material_def cold = wax;
    cold.specific_heat = mpm_material_def_default().specific_heat;
    cold.conductivity = mpm_material_def_default().conductivity;
    d = hot, d.heat.enabled = 0, d.materials = &cold;
    assert_refused(&d, "materials[0].melting: a heat field");
    cold.melting = 0;
    assert_refused(&d, "materials[0].melt_*: melting values with melting 0");
    cold = mpm_material_def_default(), cold.model = MPM_DEF_NEO_HOOKEAN;
    assert_refused(&d, "bodies[0].temperature: a heat field");
    mpm_body_def plain[2] = {hb[0], hb[1]};
    plain[0].has_temperature = 0;
    d.bodies = plain;
    assert_refused(&d, "bodies[0].temperature: given with has_temperature 0");
    plain[0].temperature = 0;
    assert_refused(&d, "colliders[0].temperature: a heat field");
    mpm_collider_def unheated = plate;
    unheated.heat_source = 0;
    d.colliders = &unheated;
    assert_refused(&d, "colliders[0].temperature: given with heat_source 0");
    unheated.temperature = 0;
    assert_refused(&d, "heat.temperature: given with heat.enabled 0");
    d.heat.temperature = 0;
    d.heat.pic = mpm_scene_def_default().heat.pic;
    /* temperature among the fields without heat: the parser's check (to_json writes it) */
    assert_int_equal(mpm_sim_create_from_def(&d, NULL, &sim, err, sizeof err), MPM_ERR_INVALID);
    assert_null(sim);
    assert_non_null(strstr(err, "<def>: output.fields[1]: 'temperature' needs heat"));
    d.output.fields = 1u << 16;
    assert_refused(&d, "output.fields: bits above");
  }

  /* the parser's checks, under the def's name and its field paths */
  memcpy(bodies, full_bodies, sizeof bodies);
  d = good, d.bodies = bodies, bodies[1].shape.radius = 0;
  assert_refused(&d, "<def>: bodies[1].shape.radius: expected a number > 0");
  memcpy(mats, full_materials, sizeof mats);
  d = good, d.materials = mats, mats[3].yield_stress = 0;
  assert_refused(&d, "materials[3].yield_stress: expected");
  d = good, d.domain.dx = HUGE_VAL;
  assert_refused(&d, "domain.dx: expected");
  d = good, d.body_count = 0;
  assert_refused(&d, "bodies: expected at least one body");
  /* relative to base_dir: "BASE/<def>", and a mesh that is not there */
  memcpy(bodies, full_bodies, sizeof bodies);
  d = good, d.bodies = bodies, bodies[3].shape.file = "meshes/none.obj";
  assert_int_equal(mpm_sim_create_from_def(&d, "examples", &sim, err, sizeof err), MPM_ERR_IO);
  print_message("%s\n", err);
  assert_non_null(strstr(err, "examples/<def>: bodies[3].shape.file: cannot open mesh file"));
}

/* ---- (d) the def saved as a scene ------------------------------------------------------- */

static void test_to_json(void **state) {
  (void)state;
  const mpm_scene_def def = full_def();
  char err[2048], *text = NULL;
  assert_int_equal(mpm_scene_def_to_json(&def, &text, err, sizeof err), MPM_OK);
  assert_non_null(text);
  /* written as a scene file and loaded as one (mesh paths relative to the file) */
  char path[1100];
  snprintf(path, sizeof path, "%s/full.json", test_temp_dir("scene_def"));
  FILE *f = fopen(path, "w");
  assert_non_null(f);
  fputs(text, f);
  fclose(f);
  mpm_sim *a = NULL, *b = NULL, *c = NULL;
  assert_int_equal(mpm_sim_create_from_def(&def, "examples", &a, err, sizeof err), MPM_OK);
  assert_int_equal(mpm_sim_create_from_json(text, "examples", &b, err, sizeof err), MPM_OK);
  mpm_free_string(text);
  mpm_free_string(NULL);
  assert_same_view(a, b);
  /* as a file the mesh must be found from the file's folder: give the absolute path */
  mpm_body_def bodies[4];
  memcpy(bodies, full_bodies, sizeof bodies);
  char mesh[1100];
  snprintf(mesh, sizeof mesh, "%s/examples/meshes/torus.obj", MPM_SOURCE_DIR);
  bodies[3].shape.file = mesh;
  mpm_scene_def abs_def = def;
  abs_def.bodies = bodies;
  assert_int_equal(mpm_scene_def_to_json(&abs_def, &text, err, sizeof err), MPM_OK);
  f = fopen(path, "w");
  assert_non_null(f);
  fputs(text, f);
  fclose(f);
  mpm_free_string(text);
  if (mpm_sim_create_from_file(path, &c, err, sizeof err) != MPM_OK) fail_msg("%s", err);
  assert_same_view(a, c);
  assert_int_equal(mpm_sim_advance_frame(a), MPM_OK);
  assert_int_equal(mpm_sim_advance_frame(b), MPM_OK);
  assert_int_equal(mpm_sim_advance_frame(c), MPM_OK);
  assert_same_view(a, b);
  assert_same_view(a, c);
  mpm_sim_destroy(a);
  mpm_sim_destroy(b);
  mpm_sim_destroy(c);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_defaults),        cmocka_unit_test(test_every_field),
      cmocka_unit_test(test_implicit_fields), cmocka_unit_test(test_refused),
      cmocka_unit_test(test_to_json),         cmocka_unit_test(test_heat_and_fields),
  };
  return test_cleanup(cmocka_run_group_tests(tests, NULL, NULL));
}
