/* test_scene_def_more.c - the scene def's later fields (include/mpm/scene_def.h, issue 17)
 * against the same scenes written as JSON by hand: keyframed motion and `active` windows,
 * body-force regions, materials' strength schedules, revolve colliders, the multi-level grid
 * (levels, refinement rules, resampling, rebuilds), output.surface and the .vdb switches, the
 * camera, the rest of the solver's keys, domain.resolution and particle domains' own keys.
 *
 * As in test_scene_def.c (helpers: scene_def_support.h): (a) each new struct's _default() against
 * JSON that leaves its keys out, (b) every new field changed against JSON that gives it, bit for
 * bit over the parsed scene and the particles after one frame, (c) each refusal naming its
 * field, by the def itself or by the format's check under the def's name. */
#include "scene_def_support.h"

#include <math.h>

/* ---- (a) the defaults ------------------------------------------------------------------- */

static const double cup_profile[4][2] = {{0, 0}, {0.3, 0}, {0.3, 0.04}, {0, 0.04}};

/* The multi-level grid's, the surface's, the camera's, a force region's, a revolve's and a
 * keyframed motion's defaults. */
static void test_defaults_grid(void **state) {
  (void)state;
  mpm_material_def m = mpm_material_def_default();
  m.name = "m";
  mpm_body_def b = mpm_body_def_default();
  for (int k = 0; k < 3; ++k) b.shape.center[k] = 0.4, b.shape.half_extent[k] = 0.06;
  static const mpm_keyframe_def keys[2] = {{0, {0, 0, 0}, 0}, {0.1, {0, 0, 0}, 0}};
  mpm_keyframe_def k0 = mpm_keyframe_def_default(), k1 = mpm_keyframe_def_default();
  k1.time = 0.1;
  assert_memory_equal(&k0, &keys[0], sizeof k0);
  assert_memory_equal(&k1, &keys[1], sizeof k1);
  mpm_collider_def cols[2] = {mpm_collider_def_default(), mpm_collider_def_default()};
  cols[0].shape = mpm_shape_def_default(MPM_DEF_REVOLVE);
  cols[0].shape.center[0] = cols[0].shape.center[2] = 0.4, cols[0].shape.center[1] = 0.2;
  cols[0].shape.profile = cup_profile, cols[0].shape.profile_count = 4;
  cols[1].shape.point[1] = 0.1;
  cols[1].motion.keyframes = keys, cols[1].motion.keyframe_count = 2;
  mpm_force_def f = mpm_force_def_default();
  for (int k = 0; k < 3; ++k) f.shape.center[k] = 0.4, f.shape.half_extent[k] = 0.1;
  f.acceleration[1] = 5;
  mpm_refine_def r = mpm_refine_def_default();
  for (int k = 0; k < 3; ++k) r.box.min[k] = 0.3, r.box.max[k] = 0.5;
  mpm_scene_def def = mpm_scene_def_default();
  def.domain.max[0] = def.domain.max[1] = def.domain.max[2] = 0.8;
  def.domain.dx = 0.05;
  def.domain.levels = 2;
  def.domain.refine = &r, def.domain.refine_count = 1;
  def.domain.resample.enabled = 1;
  def.solver.kernel = MPM_DEF_KERNEL_UGIMP; /* the format's default on levels */
  def.time.end = 0.02, def.time.fps = 50;
  def.materials = &m, def.material_count = 1;
  def.bodies = &b, def.body_count = 1;
  def.colliders = cols, def.collider_count = 2;
  def.forces = &f, def.force_count = 1;
  def.output.surface.enabled = 1;
  def.camera.enabled = 1;
  def.camera.eye[2] = 2, def.camera.target[1] = 0.3;
  assert_def_is_json(
      &def,
      "{\"domain\": {\"min\": [0, 0, 0], \"max\": [0.8, 0.8, 0.8], \"dx\": 0.05, \"levels\": 2,"
      "   \"refine\": [{\"level\": 1, \"box\": {\"min\": [0.3, 0.3, 0.3],"
      "     \"max\": [0.5, 0.5, 0.5]}}], \"resample\": {}},"
      " \"time\": {\"end\": 0.02, \"fps\": 50},"
      " \"materials\": [{\"name\": \"m\", \"model\": \"fixed_corotated\", \"E\": 1e5,"
      "   \"nu\": 0.3, \"density\": 1000}],"
      " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.4, 0.4, 0.4],"
      "   \"half_extent\": [0.06, 0.06, 0.06]}, \"material\": \"m\"}],"
      " \"colliders\": [{\"shape\": {\"type\": \"revolve\", \"center\": [0.4, 0.2, 0.4],"
      "   \"profile\": [[0, 0], [0.3, 0], [0.3, 0.04], [0, 0.04]]}},"
      "  {\"shape\": {\"type\": \"halfspace\", \"point\": [0, 0.1, 0], \"normal\": [0, 1, 0]},"
      "   \"motion\": {\"keyframes\": [{\"time\": 0}, {\"time\": 0.1}]}}],"
      " \"forces\": [{\"shape\": {\"type\": \"box\", \"center\": [0.4, 0.4, 0.4],"
      "   \"half_extent\": [0.1, 0.1, 0.1]}, \"acceleration\": [0, 5, 0]}],"
      " \"output\": {\"surface\": true},"
      " \"camera\": {\"eye\": [0, 0, 2], \"target\": [0, 0.3, 0]}}",
      NULL);
  /* the defaults the structs say, spelled out */
  assert_true(isinf(cols[0].active[1]) && cols[0].active[0] == 0 && f.active[1] > 1e300);
  assert_true(f.shape.type == MPM_DEF_BOX && f.motion.axis[2] == 1 && r.collider == -1);
  assert_true(def.camera.fov == 35 && def.output.surface.smoothing == 1 && r.level == 1);
  assert_true(def.domain.resample.split && def.domain.resample.merge &&
              def.domain.resample.every == 1 && def.domain.resample.merge_margin == 1);
}

/* The solver's remaining keys (explicit and implicit), particle domains' own keys and a
 * release's defaults. */
static void test_defaults_solver_domains(void **state) {
  (void)state;
  mpm_material_def m = mpm_material_def_default();
  m.name = "m";
  mpm_release_def rel = mpm_release_def_default();
  for (int k = 0; k < 3; ++k) rel.max[k] = 0.5;
  mpm_body_def b = mpm_body_def_default();
  for (int k = 0; k < 3; ++k) b.shape.center[k] = 0.4, b.shape.half_extent[k] = 0.06;
  b.domains = 1;
  b.domain_release = &rel, b.domain_release_count = 1;
  mpm_scene_def def = mpm_scene_def_default();
  def.domain.max[0] = def.domain.max[1] = def.domain.max[2] = 0.8;
  def.domain.dx = 0.05;
  def.solver.integrator = MPM_DEF_IMPLICIT;
  def.time.end = 0.02, def.time.fps = 50;
  def.materials = &m, def.material_count = 1;
  def.bodies = &b, def.body_count = 1;
  assert_def_is_json(
      &def,
      "{\"domain\": {\"min\": [0, 0, 0], \"max\": [0.8, 0.8, 0.8], \"dx\": 0.05},"
      " \"time\": {\"end\": 0.02, \"fps\": 50}, \"solver\": {\"integrator\": \"implicit\"},"
      " \"materials\": [{\"name\": \"m\", \"model\": \"fixed_corotated\", \"E\": 1e5,"
      "   \"nu\": 0.3, \"density\": 1000}],"
      " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.4, 0.4, 0.4],"
      "   \"half_extent\": [0.06, 0.06, 0.06]}, \"material\": \"m\", \"domains\": true,"
      "   \"domain_release\": [{\"time\": 0, \"min\": [0, 0, 0], \"max\": [0.5, 0.5, 0.5]}]}]}",
      NULL);
  assert_true(def.solver.max_retries == 8 && def.solver.cg_max_iterations == 500);
  assert_true(def.solver.grid == MPM_DEF_GRID_SPARSE && def.solver.cg_tolerance == 0);
  assert_true(b.enrichment == 0 && b.enrichment_metric == MPM_DEF_METRIC_CONDITION);
}

/* ---- (b) every field -------------------------------------------------------------------- */

static mpm_material_def grid_materials[2];
static mpm_body_def grid_bodies[2];
static mpm_collider_def grid_colliders[2];
static mpm_force_def grid_forces[2];
static mpm_refine_def grid_rules[6];
static const double jelly_strength[2][2] = {{0, 1}, {0.01, 0.5}};
static const double lift_schedule[2][2] = {{0, 0}, {0.02, 1}};
static const mpm_keyframe_def paddle_keys[2] = {{0, {0, 0, 0}, 0}, {0.05, {0.02, 0, 0}, 0.1}};
static const int surface_bodies[2] = {1, 0};
static const int resample_bodies[1] = {1};

/* A multi-level grid with every rule kind and resampling; a keyframed paddle with a window and a
 * revolve plate; two force regions; a strength schedule; a surface with .vdb grids; a camera. */
static mpm_scene_def grid_def(void) {
  mpm_material_def *m = grid_materials;
  m[0] = m[1] = mpm_material_def_default();
  m[0].name = "jelly", m[0].strength = jelly_strength, m[0].strength_count = 2;
  m[1].name = "goo", m[1].model = MPM_DEF_NEO_HOOKEAN, m[1].E = 5e4;
  mpm_body_def *b = grid_bodies;
  b[0] = b[1] = mpm_body_def_default();
  b[0].name = "cube";
  b[0].shape.center[0] = 0.3, b[0].shape.center[1] = 0.35, b[0].shape.center[2] = 0.4;
  for (int k = 0; k < 3; ++k) b[0].shape.half_extent[k] = 0.06;
  b[1].name = "ball", b[1].material = 1;
  b[1].shape = mpm_shape_def_default(MPM_DEF_SPHERE);
  b[1].shape.center[0] = 0.52, b[1].shape.center[1] = 0.35, b[1].shape.center[2] = 0.4;
  b[1].shape.radius = 0.06;
  mpm_collider_def *c = grid_colliders;
  c[0] = c[1] = mpm_collider_def_default();
  c[0].name = "paddle", c[0].rule = MPM_DEF_STICKY;
  c[0].shape = mpm_shape_def_default(MPM_DEF_BOX);
  c[0].shape.center[0] = 0.2, c[0].shape.center[1] = 0.35, c[0].shape.center[2] = 0.4;
  c[0].shape.half_extent[0] = 0.02, c[0].shape.half_extent[1] = c[0].shape.half_extent[2] = 0.08;
  c[0].motion.axis[0] = 0, c[0].motion.axis[1] = 1, c[0].motion.axis[2] = 0;
  c[0].motion.keyframes = paddle_keys, c[0].motion.keyframe_count = 2;
  c[0].active[0] = 0.005, c[0].active[1] = 0.5;
  c[1].name = "plate";
  c[1].shape = mpm_shape_def_default(MPM_DEF_REVOLVE);
  c[1].shape.center[0] = c[1].shape.center[2] = 0.4, c[1].shape.center[1] = 0.22;
  c[1].shape.axis[0] = 0.05;
  c[1].shape.profile = cup_profile, c[1].shape.profile_count = 4;
  mpm_force_def *f = grid_forces;
  f[0] = f[1] = mpm_force_def_default();
  f[0].name = "lift";
  f[0].shape = mpm_shape_def_default(MPM_DEF_SPHERE);
  f[0].shape.center[0] = 0.52, f[0].shape.center[1] = 0.35, f[0].shape.center[2] = 0.4;
  f[0].shape.radius = 0.1;
  f[0].acceleration[1] = 12;
  f[0].schedule = lift_schedule, f[0].schedule_count = 2;
  f[0].active[1] = 0.04;
  f[1].name = "wind", f[1].inside_out = 1;
  f[1].shape = mpm_shape_def_default(MPM_DEF_HALFSPACE);
  f[1].shape.point[0] = 0.25, f[1].shape.normal[0] = -1, f[1].shape.normal[1] = 0;
  f[1].motion.velocity[0] = 0.1, f[1].motion.angular_speed = 0.5;
  f[1].acceleration[0] = 1;
  mpm_refine_def *r = grid_rules;
  for (int i = 0; i < 6; ++i) r[i] = mpm_refine_def_default();
  for (int k = 0; k < 3; ++k) r[0].box.min[k] = 0.25, r[0].box.max[k] = 0.45;
  r[1].kind = MPM_DEF_REFINE_COLLIDER, r[1].collider_name = "paddle", r[1].distance = 0.05;
  r[2].kind = MPM_DEF_REFINE_BODY, r[2].body = 1, r[2].distance = 0.03;
  r[2].box.min[0] = 0.5, r[2].box.max[0] = r[2].box.max[1] = r[2].box.max[2] = 0.8; /* within */
  r[3].kind = MPM_DEF_REFINE_SURFACE, r[3].surface = 0.04, r[3].body_name = "cube";
  r[4].kind = MPM_DEF_REFINE_TYPES, r[4].distance = 0.02;
  r[5].kind = MPM_DEF_REFINE_STRAIN, r[5].strain = 0.1, r[5].distance = 0.01;

  mpm_scene_def d = mpm_scene_def_default();
  d.name = "grid";
  d.domain.max[0] = d.domain.max[1] = d.domain.max[2] = 0.8;
  d.domain.dx = 0.05;
  d.domain.levels = 2;
  d.domain.refine = r, d.domain.refine_count = 6;
  d.domain.refine_every = 4;
  mpm_resample_def *rs = &d.domain.resample;
  rs->enabled = 1, rs->merge = 0, rs->every = 2, rs->merge_margin = 0.5;
  rs->max_per_cell = 20, rs->min_per_cell = 40, rs->seed = 7;
  rs->bodies = resample_bodies, rs->body_count = 1;
  d.solver.kernel = MPM_DEF_KERNEL_UGIMP, d.solver.cfl = 0.3;
  d.solver.on_instability = MPM_DEF_INSTABILITY_RETRY, d.solver.max_retries = 5;
  d.solver.domain_kernel = MPM_DEF_KERNEL_QUADRATIC;
  d.time.end = 0.02, d.time.fps = 50;
  d.materials = m, d.material_count = 2;
  d.bodies = b, d.body_count = 2;
  d.colliders = c, d.collider_count = 2;
  d.forces = f, d.force_count = 2;
  mpm_surface_def *s = &d.output.surface;
  s->enabled = 1, s->bodies = surface_bodies, s->body_count = 2;
  s->voxel = 0.5, s->radius = 0.6, s->smoothing = 2, s->filter = MPM_DEF_FILTER_GAUSSIAN;
  s->per_body = 1;
  d.output.vdb = d.output.vdb_density = d.output.vdb_velocity = 1;
  d.camera.enabled = 1, d.camera.fov = 40;
  d.camera.eye[0] = 1.5, d.camera.eye[1] = 1, d.camera.eye[2] = 2;
  d.camera.target[0] = d.camera.target[2] = 0.4, d.camera.target[1] = 0.3;
  return d;
}

static const char *const grid_json =
    "{\"name\": \"grid\","
    " \"domain\": {\"min\": [0, 0, 0], \"max\": [0.8, 0.8, 0.8], \"dx\": 0.05, \"levels\": 2,"
    "   \"refine_every\": 4,"
    "   \"refine\": [{\"level\": 1, \"box\": {\"min\": [0.25, 0.25, 0.25],"
    "       \"max\": [0.45, 0.45, 0.45]}},"
    "     {\"level\": 1, \"collider\": \"paddle\", \"distance\": 0.05},"
    "     {\"level\": 1, \"body\": 1, \"distance\": 0.03, \"within\": {\"min\": [0.5, 0, 0],"
    "       \"max\": [0.8, 0.8, 0.8]}},"
    "     {\"level\": 1, \"surface\": 0.04, \"body\": \"cube\"},"
    "     {\"level\": 1, \"types\": true, \"distance\": 0.02},"
    "     {\"level\": 1, \"strain\": 0.1, \"distance\": 0.01}],"
    "   \"resample\": {\"merge\": false, \"every\": 2, \"merge_margin\": 0.5,"
    "     \"max_per_cell\": 20, \"min_per_cell\": 40, \"bodies\": [\"ball\"], \"seed\": 7}},"
    " \"time\": {\"end\": 0.02, \"fps\": 50},"
    " \"solver\": {\"cfl\": 0.3, \"on_instability\": \"retry\", \"max_retries\": 5,"
    "   \"domain_kernel\": \"quadratic\"},"
    " \"materials\": [{\"name\": \"jelly\", \"model\": \"fixed_corotated\", \"E\": 1e5,"
    "   \"nu\": 0.3, \"density\": 1000, \"strength\": [[0, 1], [0.01, 0.5]]},"
    "  {\"name\": \"goo\", \"model\": \"neo_hookean\", \"E\": 5e4, \"nu\": 0.3,"
    "   \"density\": 1000}],"
    " \"bodies\": [{\"name\": \"cube\", \"shape\": {\"type\": \"box\","
    "   \"center\": [0.3, 0.35, 0.4], \"half_extent\": [0.06, 0.06, 0.06]}, \"material\": "
    "\"jelly\"},"
    "  {\"name\": \"ball\", \"shape\": {\"type\": \"sphere\", \"center\": [0.52, 0.35, 0.4],"
    "   \"radius\": 0.06}, \"material\": \"goo\"}],"
    " \"colliders\": [{\"name\": \"paddle\", \"shape\": {\"type\": \"box\","
    "   \"center\": [0.2, 0.35, 0.4], \"half_extent\": [0.02, 0.08, 0.08]}, \"rule\": \"sticky\","
    "   \"motion\": {\"axis\": [0, 1, 0], \"keyframes\": [{\"time\": 0},"
    "     {\"time\": 0.05, \"translation\": [0.02, 0, 0], \"angle\": 0.1}]},"
    "   \"active\": [0.005, 0.5]},"
    "  {\"name\": \"plate\", \"shape\": {\"type\": \"revolve\", \"center\": [0.4, 0.22, 0.4],"
    "   \"axis\": [0.05, 1, 0], \"profile\": [[0, 0], [0.3, 0], [0.3, 0.04], [0, 0.04]]}}],"
    " \"forces\": [{\"name\": \"lift\", \"shape\": {\"type\": \"sphere\","
    "   \"center\": [0.52, 0.35, 0.4], \"radius\": 0.1}, \"acceleration\": [0, 12, 0],"
    "   \"schedule\": [[0, 0], [0.02, 1]], \"active\": [0, 0.04]},"
    "  {\"name\": \"wind\", \"shape\": {\"type\": \"halfspace\", \"point\": [0.25, 0, 0],"
    "   \"normal\": [-1, 0, 0]}, \"inside_out\": true,"
    "   \"motion\": {\"velocity\": [0.1, 0, 0], \"angular_speed\": 0.5},"
    "   \"acceleration\": [1, 0, 0]}],"
    " \"output\": {\"surface\": {\"bodies\": [\"ball\", 0], \"voxel\": 0.5, \"radius\": 0.6,"
    "   \"smoothing\": 2, \"filter\": \"gaussian\", \"per_body\": true},"
    "   \"vdb_density\": true, \"vdb_velocity\": true},"
    " \"camera\": {\"eye\": [1.5, 1, 2], \"target\": [0.4, 0.3, 0.4], \"fov\": 40}}";

static void test_grid_fields(void **state) {
  (void)state;
  const mpm_scene_def def = grid_def();
  assert_def_is_json(&def, grid_json, NULL);
}

static mpm_material_def implicit_material;
static mpm_body_def implicit_bodies[2];
static mpm_collider_def implicit_floor;
static mpm_force_def implicit_force;
static const mpm_release_def releases[2] = {{0.004, {0, 0, 0}, {0.4, 0.8, 0.8}},
                                            {0.008, {0.4, 0, 0}, {0.8, 0.8, 0.8}}};
static const mpm_keyframe_def push_keys[3] = {
    {0, {0, 0, 0}, 0}, {0.005, {0, 0.01, 0}, 0}, {0.01, {0.01, 0.01, 0}, 0.2}};
static const int surface_materials[1] = {0};

/* The implicit integrator's CG keys on a dense grid, a body with particle domains and releases
 * beside one of material points, a keyframed force region, a collider with a window, the
 * domain by resolution and a surface of a material. */
static mpm_scene_def implicit_def(void) {
  implicit_material = mpm_material_def_default();
  implicit_material.name = "rubber";
  mpm_body_def *b = implicit_bodies;
  b[0] = b[1] = mpm_body_def_default();
  b[0].name = "domains", b[0].domains = 1;
  b[0].shape.center[0] = 0.3, b[0].shape.center[1] = b[0].shape.center[2] = 0.4;
  for (int k = 0; k < 3; ++k) b[0].shape.half_extent[k] = 0.08;
  b[0].enrichment = 0.6, b[0].enrichment_exit = 0.9, b[0].enrichment_hourglass = 0.05;
  b[0].enrichment_contact = 1;
  b[0].enrichment_surface_contact = 0;
  b[0].enrichment_self_contact = 0;
  b[0].enrichment_exit_wait = 0.2;
  b[0].enrichment_metric = MPM_DEF_METRIC_FROBENIUS;
  b[0].hourglass = MPM_DEF_HOURGLASS_ALL;
  b[0].domain_release = releases, b[0].domain_release_count = 2;
  b[1].name = "points";
  b[1].shape.center[0] = 0.55, b[1].shape.center[1] = b[1].shape.center[2] = 0.4;
  for (int k = 0; k < 3; ++k) b[1].shape.half_extent[k] = 0.06;
  implicit_floor = mpm_collider_def_default();
  implicit_floor.shape.point[1] = 0.3;
  implicit_floor.active[0] = 0, implicit_floor.active[1] = 0.006;
  implicit_force = mpm_force_def_default();
  implicit_force.shape.center[0] = 0.55, implicit_force.shape.center[1] = 0.4;
  implicit_force.shape.center[2] = 0.4;
  for (int k = 0; k < 3; ++k) implicit_force.shape.half_extent[k] = 0.1;
  implicit_force.motion.keyframes = push_keys, implicit_force.motion.keyframe_count = 3;
  implicit_force.acceleration[0] = -3;
  implicit_force.drag = 2;
  mpm_scene_def d = mpm_scene_def_default();
  d.domain.max[0] = d.domain.max[1] = d.domain.max[2] = 0.8;
  d.domain.resolution = 16;
  d.solver.integrator = MPM_DEF_IMPLICIT, d.solver.dt = 2e-3, d.solver.newton_iterations = 1;
  d.solver.cg_tolerance = 1e-5, d.solver.cg_max_iterations = 300;
  d.solver.on_cg_failure = MPM_DEF_CG_STOP;
  d.solver.grid = MPM_DEF_GRID_DENSE, d.solver.gimp_length = 0.02;
  d.time.end = 0.01, d.time.fps = 100;
  d.materials = &implicit_material, d.material_count = 1;
  d.bodies = b, d.body_count = 2;
  d.colliders = &implicit_floor, d.collider_count = 1;
  d.forces = &implicit_force, d.force_count = 1;
  d.output.surface.enabled = 1;
  d.output.surface.materials = surface_materials, d.output.surface.material_count = 1;
  d.output.surface.filter = MPM_DEF_FILTER_LAPLACIAN, d.output.surface.smoothing = 0;
  d.output.vdb = 1;
  return d;
}

static void test_implicit_and_domain_fields(void **state) {
  (void)state;
  const mpm_scene_def def = implicit_def();
  assert_def_is_json(
      &def,
      "{\"domain\": {\"min\": [0, 0, 0], \"max\": [0.8, 0.8, 0.8], \"resolution\": 16},"
      " \"time\": {\"end\": 0.01, \"fps\": 100},"
      " \"solver\": {\"integrator\": \"implicit\", \"dt\": 2e-3, \"newton_iterations\": 1,"
      "   \"cg_tolerance\": 1e-5, \"cg_max_iterations\": 300, \"on_cg_failure\": \"stop\","
      "   \"grid\": \"dense\", \"gimp_length\": 0.02},"
      " \"materials\": [{\"name\": \"rubber\", \"model\": \"fixed_corotated\", \"E\": 1e5,"
      "   \"nu\": 0.3, \"density\": 1000}],"
      " \"bodies\": [{\"name\": \"domains\", \"shape\": {\"type\": \"box\","
      "   \"center\": [0.3, 0.4, 0.4], \"half_extent\": [0.08, 0.08, 0.08]},"
      "   \"material\": \"rubber\", \"domains\": true, \"enrichment\": 0.6,"
      "   \"enrichment_exit\": 0.9, \"enrichment_hourglass\": 0.05, \"enrichment_contact\": true,"
      "   \"enrichment_surface_contact\": false, \"enrichment_self_contact\": false,"
      "   \"enrichment_exit_wait\": 0.2,"
      "   \"enrichment_metric\": \"frobenius\", "
      "\"hourglass\": \"all\","
      "   \"domain_release\": [{\"time\": 0.004, \"min\": [0, 0, 0], \"max\": [0.4, 0.8, 0.8]},"
      "     {\"time\": 0.008, \"min\": [0.4, 0, 0], \"max\": [0.8, 0.8, 0.8]}]},"
      "  {\"name\": \"points\", \"shape\": {\"type\": \"box\", \"center\": [0.55, 0.4, 0.4],"
      "   \"half_extent\": [0.06, 0.06, 0.06]}, \"material\": \"rubber\"}],"
      " \"colliders\": [{\"shape\": {\"type\": \"halfspace\", \"point\": [0, 0.3, 0],"
      "   \"normal\": [0, 1, 0]}, \"active\": [0, 0.006]}],"
      " \"forces\": [{\"shape\": {\"type\": \"box\", \"center\": [0.55, 0.4, 0.4],"
      "   \"half_extent\": [0.1, 0.1, 0.1]}, \"acceleration\": [-3, 0, 0], \"drag\": 2,"
      "   \"motion\": {\"keyframes\": [{\"time\": 0}, {\"time\": 0.005, \"translation\": [0, 0.01, "
      "0]},"
      "     {\"time\": 0.01, \"translation\": [0.01, 0.01, 0], \"angle\": 0.2}]}}],"
      " \"output\": {\"surface\": {\"materials\": [\"rubber\"], \"smoothing\": 0,"
      "   \"filter\": \"laplacian\"}, \"vdb\": true}}",
      NULL);
}

/* ---- (c) what the def refuses ------------------------------------------------------------ */

static void test_refused_by_def(void **state) {
  (void)state;
  const mpm_scene_def good = grid_def();
  mpm_scene_def d = good;
  mpm_collider_def cols[2];
  mpm_force_def forces[2];
  mpm_material_def mats[2];
  mpm_refine_def rules[6];

  /* arrays: NULL with a count, negative counts */
  d.forces = NULL;
  assert_refused(&d, "forces: NULL with force_count 2");
  d = good, d.force_count = -1;
  assert_refused(&d, "forces: expected force_count >= 0, got -1");
  memcpy(cols, grid_colliders, sizeof cols);
  d = good, d.colliders = cols, cols[1].shape.profile = NULL;
  assert_refused(&d, "colliders[1].shape.profile: NULL with profile_count 4");
  memcpy(cols, grid_colliders, sizeof cols);
  d = good, d.colliders = cols, cols[0].motion.keyframe_count = -2;
  assert_refused(&d, "colliders[0].motion.keyframes: expected keyframe_count >= 0");
  memcpy(mats, grid_materials, sizeof mats);
  d = good, d.materials = mats, mats[0].strength = NULL;
  assert_refused(&d, "materials[0].strength: NULL with strength_count 2");
  memcpy(forces, grid_forces, sizeof forces);
  d = good, d.forces = forces, forces[0].schedule_count = -1;
  assert_refused(&d, "forces[0].schedule: expected schedule_count >= 0");
  d = good, d.domain.refine = NULL;
  assert_refused(&d, "domain.refine: NULL with refine_count 6");
  d = good, d.domain.resample.bodies = NULL;
  assert_refused(&d, "domain.resample.bodies: NULL with body_count 1");
  d = good, d.output.surface.body_count = -1;
  assert_refused(&d, "output.surface.bodies: expected body_count >= 0");

  /* enums out of range, long names */
  d = good, d.solver.grid = (mpm_def_grid)2;
  assert_refused(&d, "solver.grid: expected an mpm_def_grid");
  d = good, d.solver.on_instability = (mpm_def_instability)-1;
  assert_refused(&d, "solver.on_instability: expected an mpm_def_instability");
  d = good, d.solver.domain_kernel = (mpm_def_kernel)9;
  assert_refused(&d, "solver.domain_kernel: expected an mpm_def_kernel");
  d = good, d.output.surface.filter = (mpm_def_surface_filter)3;
  assert_refused(&d, "output.surface.filter: expected an mpm_def_surface_filter");
  memcpy(rules, grid_rules, sizeof rules);
  d = good, d.domain.refine = rules, rules[4].kind = (mpm_def_refine_kind)6;
  assert_refused(&d, "domain.refine[4].kind: expected an mpm_def_refine_kind");
  memcpy(forces, grid_forces, sizeof forces);
  d = good, d.forces = forces, forces[1].shape.type = (mpm_def_shape_type)6;
  assert_refused(&d, "forces[1].shape.type: expected an mpm_def_shape_type");
  memcpy(forces, grid_forces, sizeof forces);
  d = good, d.forces = forces;
  forces[1].name = "a_name_of_sixty_four_bytes_which_is_one_more_than_the_format_has";
  assert_refused(&d, "forces[1].name: expected a name of at most 63 bytes");

  /* fields that would have no effect */
  memcpy(cols, grid_colliders, sizeof cols);
  d = good, d.colliders = cols, cols[0].shape.profile = cup_profile;
  assert_refused(&d, "colliders[0].shape.profile: not a field of a box shape");
  memcpy(cols, grid_colliders, sizeof cols);
  d = good, d.colliders = cols, cols[1].shape.radius = 0.1;
  assert_refused(&d, "colliders[1].shape.radius: not a field of a revolve shape");
  memcpy(cols, grid_colliders, sizeof cols);
  d = good, d.colliders = cols, cols[0].motion.velocity[1] = 0.1;
  assert_refused(&d, "colliders[0].motion.velocity: given with keyframes");
  memcpy(forces, grid_forces, sizeof forces);
  d = good, d.forces = forces, forces[1].motion.keyframes = paddle_keys;
  forces[1].motion.keyframe_count = 2;
  assert_refused(&d, "forces[1].motion.angular_speed: given with keyframes");
  memcpy(cols, grid_colliders, sizeof cols);
  d = good, d.colliders = cols, cols[0].active[1] = HUGE_VAL;
  assert_refused(&d, "colliders[0].active[1]: expected a finite end");
  memcpy(rules, grid_rules, sizeof rules);
  d = good, d.domain.refine = rules, rules[0].distance = 0.1;
  assert_refused(&d, "domain.refine[0].distance: not a field of a box rule");
  memcpy(rules, grid_rules, sizeof rules);
  d = good, d.domain.refine = rules, rules[3].strain = 0.2;
  assert_refused(&d, "domain.refine[3].strain: not a field of a surface rule");
  memcpy(rules, grid_rules, sizeof rules);
  d = good, d.domain.refine = rules, rules[4].body = 0;
  assert_refused(&d, "domain.refine[4].body: not a field of a types rule");
  memcpy(rules, grid_rules, sizeof rules);
  d = good, d.domain.refine = rules, rules[1].collider_name = NULL;
  assert_refused(&d, "domain.refine[1].collider: a collider rule needs its collider");
  memcpy(rules, grid_rules, sizeof rules);
  d = good, d.domain.refine = rules, rules[2].body = -1;
  assert_refused(&d, "domain.refine[2].body: a body rule needs its body");
  d = good, d.domain.resample.enabled = 0;
  assert_refused(&d, "domain.resample.merge: given with domain.resample.enabled 0");
  d = good, d.domain.resolution = 16;
  assert_refused(&d, "domain.dx: given with domain.resolution 16");
  d = good, d.output.surface.enabled = 0;
  assert_refused(&d, "output.surface.bodies: given with output.surface.enabled 0");
  d = good, d.camera.enabled = 0;
  assert_refused(&d, "camera.eye: given with camera.enabled 0");
  d = good, d.solver.cg_max_iterations = 100;
  assert_refused(&d, "solver.cg_max_iterations: a field of the implicit integrator only");
  d = good, d.solver.on_cg_failure = MPM_DEF_CG_STOP;
  assert_refused(&d, "solver.on_cg_failure: a field of the implicit integrator only");
  {
    const mpm_scene_def imp = implicit_def();
    mpm_body_def bodies[2];
    memcpy(bodies, implicit_bodies, sizeof bodies);
    d = imp, d.bodies = bodies, bodies[0].domains = 0;
    assert_refused(&d, "bodies[0].enrichment: a field of particle domains, and bodies[0].domains");
    bodies[0].enrichment = 0, bodies[0].enrichment_exit = 0;
    bodies[0].enrichment_metric = MPM_DEF_METRIC_CONDITION;
    assert_refused(&d, "bodies[0].enrichment_hourglass: a field of particle domains");
    bodies[0].enrichment_hourglass = 0;
    assert_refused(&d, "bodies[0].enrichment_contact: a field of particle domains");
    bodies[0].enrichment_contact = 0;
    assert_refused(&d, "bodies[0].enrichment_surface_contact: a field of particle domains");
    bodies[0].enrichment_surface_contact = 1;
    assert_refused(&d, "bodies[0].enrichment_self_contact: a field of particle domains");
    bodies[0].enrichment_self_contact = 1;
    assert_refused(&d, "bodies[0].enrichment_exit_wait: a field of particle domains");
    bodies[0].enrichment_exit_wait = 0;
    assert_refused(&d, "bodies[0].hourglass: a field of particle domains");
    bodies[0].hourglass = MPM_DEF_HOURGLASS_ENRICHED;
    assert_refused(&d, "bodies[0].domain_release: a field of particle domains");
    memcpy(bodies, implicit_bodies, sizeof bodies);
    d = imp, d.bodies = bodies, bodies[0].enrichment_metric = (mpm_def_enrichment_metric)2;
    assert_refused(&d, "bodies[0].enrichment_metric: expected an mpm_def_enrichment_metric");
    memcpy(bodies, implicit_bodies, sizeof bodies);
    d = imp, d.bodies = bodies, bodies[0].hourglass = (mpm_def_hourglass)2;
    assert_refused(&d, "bodies[0].hourglass: expected an mpm_def_hourglass");
  }
}

/* Written as given, refused by the format's check, which names the def's field. */
static void test_refused_by_format(void **state) {
  (void)state;
  const mpm_scene_def good = grid_def();
  mpm_scene_def d = good;
  mpm_collider_def cols[2];
  mpm_body_def bodies[2];
  d.solver.kernel = MPM_DEF_KERNEL_QUADRATIC;
  assert_format_refuses(&d, "<def>: solver.kernel: expected \"ugimp\" with domain.levels");
  d = good, d.domain.levels = 0;
  assert_format_refuses(&d, "<def>: domain.refine: refinement needs a multi-level grid");
  d = good, d.domain.levels = 7;
  assert_format_refuses(&d, "<def>: domain.levels: expected");
  d = good, d.output.surface.enabled = 0, d.output.surface.bodies = NULL;
  d.output.surface.body_count = 0, d.output.surface.voxel = 0, d.output.surface.radius = 0;
  d.output.surface.smoothing = 1, d.output.surface.filter = MPM_DEF_FILTER_MEAN_CURVATURE;
  d.output.surface.per_body = 0;
  assert_format_refuses(&d, "<def>: output.vdb: expected output.surface too");
  d = good, d.output.surface.bodies = (const int[]){3}, d.output.surface.body_count = 1;
  assert_format_refuses(&d, "<def>: output.surface.bodies[0]: expected the index of one of the 2");
  d = good, d.domain.resample.bodies = (const int[]){-1};
  assert_format_refuses(&d, "<def>: domain.resample.bodies[0]: expected the name or index");
  d = good, d.camera.target[0] = 1.5, d.camera.target[1] = 1, d.camera.target[2] = 2;
  assert_format_refuses(&d, "<def>: camera.target: expected a point other than the eye");
  memcpy(cols, grid_colliders, sizeof cols);
  d = good, d.colliders = cols, cols[1].shape.profile_count = 2;
  assert_format_refuses(&d, "<def>: colliders[1].shape.profile: expected 3 to 32 points, got 2");
  static const mpm_keyframe_def backwards[2] = {{0.1, {0, 0, 0}, 0}, {0.05, {0, 0, 0}, 0}};
  memcpy(cols, grid_colliders, sizeof cols);
  d = good, d.colliders = cols, cols[0].motion.keyframes = backwards;
  assert_format_refuses(&d, "<def>: colliders[0].motion.keyframes[1].time: expected");
  memcpy(cols, grid_colliders, sizeof cols);
  d = good, d.colliders = cols, cols[0].active[0] = 0.6;
  assert_format_refuses(&d, "<def>: colliders[0].active: expected 0 <= start < end");
  memcpy(bodies, grid_bodies, sizeof bodies);
  d = good, d.bodies = bodies, bodies[1].shape = grid_colliders[1].shape;
  assert_format_refuses(&d, "<def>: bodies[1].shape.type: expected one of box, sphere, cylinder, "
                            "mesh, got 'revolve'");
  static const double too_strong[1][2] = {{0, 2e6}};
  mpm_material_def mats[2];
  memcpy(mats, grid_materials, sizeof mats);
  d = good, d.materials = mats, mats[1].strength = too_strong, mats[1].strength_count = 1;
  assert_format_refuses(&d, "<def>: materials[1].strength[0]: expected a factor from 0 to 1e6");
  d = good, d.domain.refine_every = 0;
  assert_format_refuses(&d, "<def>: domain.refine[3].surface: a rule on the moving material");
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_defaults_grid),  cmocka_unit_test(test_defaults_solver_domains),
      cmocka_unit_test(test_grid_fields),    cmocka_unit_test(test_implicit_and_domain_fields),
      cmocka_unit_test(test_refused_by_def), cmocka_unit_test(test_refused_by_format),
  };
  return test_cleanup(cmocka_run_group_tests(tests, NULL, NULL));
}
