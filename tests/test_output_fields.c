/* test_output_fields.c - output.fields (issue 17, "outputs people expect"): the point arrays of
 * frame_NNNN.vtu chosen by the scene, read back with the engine's reader (src/io/vtu_read.c).
 *
 * A block held at the uniform stretch F = diag(a, 1, 1) has, for the two invertible models,
 * the Cauchy stress sigma = P F^T / J in closed form (J = a):
 *   neo-Hookean      sigma = (mu (F F^T - I) + lambda ln J I) / J    (neo_hookean.c)
 *     sigma_xx = (mu (a^2 - 1) + lambda ln a) / a,  sigma_yy = sigma_zz = lambda ln a / a;
 *   fixed-corotated  sigma = (2 mu (F - R) F^T + lambda (J - 1) J I) / J, R = I
 *     sigma_xx = (2 mu + lambda) (a - 1),  sigma_yy = sigma_zz = lambda (a - 1).
 * The written tensor, pressure -tr(sigma)/3 and F equal these to the round-off of the build's
 * real (the reader converts to float). Domain particles are written with the others, and a
 * melting material's stress has the softened moduli the step uses. Bad lists are refused with
 * the key path; without the key the arrays are today's. */
#include "support.h"
#include "io/io.h"
#include "scene/scene.h"
#include "sim/sim.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define STRETCH 1.1
#define E_MOD 1e5
#define NU 0.3

typedef struct analytic {
  double xx, yy; /* sigma_xx, sigma_yy = sigma_zz, Pa; no shear */
} analytic;

static analytic cauchy_of(const char *model, double scale) {
  const double mu = scale * E_MOD / (2 * (1 + NU));
  const double lambda = scale * E_MOD * NU / ((1 + NU) * (1 - 2 * NU)), a = STRETCH;
  analytic s;
  if (!strcmp(model, "neo_hookean")) {
    s.xx = (mu * (a * a - 1) + lambda * log(a)) / a;
    s.yy = lambda * log(a) / a;
  } else {
    s.xx = (2 * mu + lambda) * (a - 1);
    s.yy = lambda * (a - 1);
  }
  return s;
}

/* A scene of one block of `model` (with particle domains when `domains`) writing `fields`
 * (a JSON array text), melting at once above 0 degrees to half its moduli when `melted`. */
static struct mpm_sim *block_sim(const char *model, int domains, int melted, const char *fields) {
  char text[2048];
  snprintf(text, sizeof text,
           "{\"domain\": {\"min\": [0,0,0], \"max\": [1,1,1], \"dx\": 0.1}, \"gravity\": [0,0,0],"
           " \"time\": {\"end\": 0.1, \"fps\": 10},"
           " \"materials\": [{\"name\": \"m\", \"model\": \"%s\", \"E\": %g, \"nu\": %g,"
           " \"density\": 1000%s}],"
           " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.5,0.5,0.5],"
           " \"half_extent\": [0.15,0.15,0.15]}, \"material\": \"m\"%s}]%s,"
           " \"output\": {\"fields\": %s}}",
           model, E_MOD, NU,
           melted ? ", \"melting\": {\"point\": 0, \"shear\": 0.5, \"bulk\": 0.5}" : "",
           domains ? ", \"domains\": true" : "", melted ? ", \"heat\": {\"temperature\": 10}" : "",
           fields);
  return test_sim_from_json(text, model);
}

static void stretch(mpm_particles *p) {
  for (size_t i = 0; i < p->count; ++i)
    for (int c = 0; c < 9; ++c) p->F[c][i] = c == 0 ? (mpm_real)STRETCH : c % 4 == 0 ? 1 : 0;
}

/* Write frame 0 of sim into a fresh folder and read it back. */
static void write_and_read(struct mpm_sim *sim, const char *name, mpm_vtu_frame *frame) {
  const char *dir = test_temp_dir(name);
  assert_int_equal(mpm_sim_enable_output(sim, dir), MPM_OK);
  char path[700];
  snprintf(path, sizeof path, "%s/frame_0000.vtu", dir);
  mpm_error err;
  mpm_error_clear(&err);
  if (mpm_read_vtu(path, frame, &err) != MPM_OK) fail_msg("%s", err.message);
}

static const mpm_vtu_array *array(const mpm_vtu_frame *f, const char *name, int comps) {
  const mpm_vtu_array *a = mpm_vtu_frame_array(f, name);
  if (!a) fail_msg("no array '%s'", name);
  assert_int_equal(a->components, comps);
  return a;
}

static void check_stretched(const char *model, int domains, int melted) {
  struct mpm_sim *sim =
      block_sim(model, domains, melted, "[\"cauchy_stress\", \"pressure\", \"F\", \"J\"]");
  stretch(&sim->particles);
  stretch(&sim->domains.particles);
  mpm_vtu_frame f;
  write_and_read(sim, model, &f);
  const size_t n = sim->particles.count + sim->domains.active_count;
  assert_true(n > 0);
  assert_int_equal(f.point_count, (long)n);
  if (domains) assert_true(sim->domains.active_count > 0 && sim->particles.count == 0);
  /* exactly what was asked, Points aside */
  assert_int_equal(f.array_count, 5);
  assert_null(mpm_vtu_frame_array(&f, "stress"));
  assert_null(mpm_vtu_frame_array(&f, "velocity"));
  const analytic s = cauchy_of(model, melted ? 0.5 : 1);
  const double want[9] = {s.xx, 0, 0, 0, s.yy, 0, 0, 0, s.yy};
  const double pressure = -(s.xx + 2 * s.yy) / 3;
  /* the round-off of the real type and of the float the reader converts to */
  const double tol = TOL(4e-6, 4e-7) * fabs(s.xx);
  const mpm_vtu_array *sigma = array(&f, "cauchy_stress", 9), *p = array(&f, "pressure", 1);
  const mpm_vtu_array *F = array(&f, "F", 9), *J = array(&f, "J", 1);
  for (size_t i = 0; i < n; ++i) {
    for (int c = 0; c < 9; ++c) {
      assert_close(sigma->data[9 * i + c], want[c], tol);
      assert_true(F->data[9 * i + c] == (float)(c == 0 ? STRETCH : c % 4 == 0 ? 1 : 0));
    }
    assert_close(p->data[i], pressure, tol);
    assert_close(J->data[i], STRETCH, TOL(1e-6, 1e-7));
  }
  mpm_vtu_frame_free(&f);
  mpm_sim_destroy(sim);
}

static void test_stretch_neo_hookean(void **state) {
  (void)state;
  check_stretched("neo_hookean", 0, 0);
}

static void test_stretch_fixed_corotated(void **state) {
  (void)state;
  check_stretched("fixed_corotated", 0, 0);
}

/* Domain particles are in frame_NNNN.vtu with the material points (sim_output.c). */
static void test_stretch_domains(void **state) {
  (void)state;
  check_stretched("neo_hookean", 1, 0);
}

/* Melted at once to half of mu and lambda (heat/heat.h, material.h): half the stress. */
static void test_stretch_melted(void **state) {
  (void)state;
  check_stretched("fixed_corotated", 0, 1);
}

/* The list's order does not matter; plastic and the default arrays can be picked too. */
static void test_order_and_plastic(void **state) {
  (void)state;
  struct mpm_sim *sim = block_sim("neo_hookean", 0, 0, "[\"plastic\", \"velocity\", \"id\"]");
  mpm_vtu_frame f;
  write_and_read(sim, "order", &f);
  assert_int_equal(f.array_count, 4);
  const char *order[4] = {"id", "velocity", "plastic", "Points"}; /* as the header lists them */
  for (int k = 0; k < 4; ++k) assert_string_equal(f.arrays[k].name, order[k]);
  for (long i = 0; i < f.point_count; ++i) assert_true(f.arrays[2].data[i] == 1); /* at rest */
  mpm_vtu_frame_free(&f);
  mpm_sim_destroy(sim);
}

/* ---- the scene key ------------------------------------------------------------------ */

static void expect_fields_error(const char *fields, const char *heat, const char *where,
                                const char *what) {
  char text[1024];
  snprintf(
      text, sizeof text,
      "{\"domain\": {\"min\": [0,0,0], \"max\": [1,1,1], \"dx\": 0.1}, \"time\": {\"end\": 1},"
      " \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\", \"E\": 1e5, \"nu\": 0.3,"
      " \"density\": 1000}], \"bodies\": [{\"shape\": {\"type\": \"sphere\", \"center\":"
      " [0.5,0.5,0.5], \"radius\": 0.1}, \"material\": \"m\"}]%s, \"output\": {\"fields\": %s}}",
      heat, fields);
  mpm_scene s;
  mpm_error err;
  mpm_error_clear(&err);
  assert_int_equal(mpm_scene_parse(text, "x.json", &s, &err), MPM_ERR_INVALID);
  char at[128];
  snprintf(at, sizeof at, "x.json: %s: ", where);
  if (strncmp(err.message, at, strlen(at)) || !strstr(err.message, what))
    fail_msg("expected '%s...%s', got: %s", at, what, err.message);
}

static void test_bad_fields(void **state) {
  (void)state;
  const char *names = "id, velocity, mass, volume, J, stress, plastic, material, body, level, "
                      "enrichment, temperature, melt, cauchy_stress, pressure, F";
  expect_fields_error("[\"velocity\", \"J\", \"presure\"]", "", "output.fields[2]",
                      "did you mean 'pressure'?");
  expect_fields_error("[\"velocity\", \"J\", \"presure\"]", "", "output.fields[2]", names);
  expect_fields_error("[\"J\", 3]", "", "output.fields[1]", "got a number (3)");
  expect_fields_error("[\"J\", \"F\", \"J\"]", "", "output.fields[2]", "'J' is listed twice");
  expect_fields_error("[]", "", "output.fields", "expected a non-empty array of field names");
  expect_fields_error("\"F\"", "", "output.fields", names);
  expect_fields_error("[\"F\", \"melt\"]", "", "output.fields[1]", "'melt' needs heat");
  /* with heat, temperature and melt are fine */
  char text[1024];
  snprintf(text, sizeof text,
           "{\"domain\": {\"min\": [0,0,0], \"max\": [1,1,1], \"dx\": 0.1}, \"time\": {\"end\": 1},"
           " \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\", \"E\": 1e5, \"nu\": 0.3,"
           " \"density\": 1000}], \"bodies\": [{\"shape\": {\"type\": \"sphere\", \"center\":"
           " [0.5,0.5,0.5], \"radius\": 0.1}, \"material\": \"m\"}], \"heat\": {},"
           " \"output\": {\"fields\": [\"melt\", \"temperature\", \"F\"]}}");
  mpm_scene s;
  mpm_error err;
  mpm_error_clear(&err);
  if (mpm_scene_parse(text, "x.json", &s, &err) != MPM_OK) fail_msg("%s", err.message);
  assert_true(s.output.fields ==
              (1u << MPM_FIELD_MELT | 1u << MPM_FIELD_TEMPERATURE | 1u << MPM_FIELD_F));
  mpm_scene_free(&s);
}

/* Without output.fields a frame holds the arrays it held before the key (the regression
 * digests and tests/vtk/check_output.py hold the bytes); the default set named explicitly
 * writes the same file, byte for byte. */
static void test_default_unchanged(void **state) {
  (void)state;
  const char *base =
      "{\"domain\": {\"min\": [0,0,0], \"max\": [1,1,1], \"dx\": 0.1}, \"time\": {\"end\": 0.1,"
      " \"fps\": 10}, \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\", \"E\": 1e5,"
      " \"nu\": 0.3, \"density\": 1000}], \"bodies\": [{\"shape\": {\"type\": \"sphere\","
      " \"center\": [0.5,0.5,0.5], \"radius\": 0.2}, \"material\": \"m\"}]%s}";
  char plain[1024], named[1024];
  snprintf(plain, sizeof plain, base, "");
  snprintf(named, sizeof named, base,
           ", \"output\": {\"fields\": [\"id\", \"velocity\", \"mass\", \"volume\", \"J\","
           " \"stress\", \"plastic\", \"material\", \"body\", \"level\", \"enrichment\"]}");
  char file[2][700];
  const char *texts[2] = {plain, named};
  for (int k = 0; k < 2; ++k) {
    struct mpm_sim *sim = test_sim_from_json(texts[k], "default");
    assert_int_equal(sim->scene.output.fields, k ? mpm_output_fields_default(0) : 0u);
    const char *dir = test_temp_dir(k ? "default-named" : "default-plain");
    assert_int_equal(mpm_sim_enable_output(sim, dir), MPM_OK);
    assert_int_equal(mpm_sim_advance_frame(sim), MPM_OK);
    snprintf(file[k], sizeof file[k], "%s/frame_0001.vtu", dir);
    mpm_sim_destroy(sim);
  }
  FILE *a = fopen(file[0], "rb"), *b = fopen(file[1], "rb");
  assert_non_null(a);
  assert_non_null(b);
  long bytes = 0;
  for (int ca = fgetc(a), cb = fgetc(b);; ca = fgetc(a), cb = fgetc(b), ++bytes) {
    assert_int_equal(ca, cb);
    if (ca == EOF) break;
  }
  assert_true(bytes > 1000);
  fclose(a);
  fclose(b);
  /* and the header names the arrays of before, with the active attributes of before */
  mpm_vtu_frame f;
  mpm_error err;
  mpm_error_clear(&err);
  assert_int_equal(mpm_read_vtu(file[0], &f, &err), MPM_OK);
  assert_int_equal(f.array_count, 12);
  assert_null(mpm_vtu_frame_array(&f, "cauchy_stress"));
  mpm_vtu_frame_free(&f);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_stretch_neo_hookean), cmocka_unit_test(test_stretch_fixed_corotated),
      cmocka_unit_test(test_stretch_domains),     cmocka_unit_test(test_stretch_melted),
      cmocka_unit_test(test_order_and_plastic),   cmocka_unit_test(test_bad_fields),
      cmocka_unit_test(test_default_unchanged),
  };
  return test_cleanup(cmocka_run_group_tests(tests, NULL, NULL));
}
