/* test_scene_json_material.c - materials in the JSON scene loader: every model name parses
 * into its kind with its own keys and defaults, the Lame parameters, and each mistake (a
 * parameter out of range, yield_stress missing for von_mises, a key of another model, a
 * misspelt model, a body naming an unknown material) is reported with the key path and what
 * was expected. */
#include "support.h"
#include "scene_json_support.h"
#include "scene/scene.h"

#include <string.h>

/* ---- valid scenes ---------------------------------------------------------------------- */

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

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_plastic_models),
      cmocka_unit_test(test_lame),
      cmocka_unit_test(test_material_parameter_ranges),
      cmocka_unit_test(test_yield_stress_required),
      cmocka_unit_test(test_material_key_not_for_model),
      cmocka_unit_test(test_model_names),
      cmocka_unit_test(test_unknown_material),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
