/* test_body_force.c - body-force regions (`forces`, Zhu Fig. 9's suction): an acceleration on
 * top of gravity inside a region, scaled by a schedule, over an `active` window.
 *
 * Two elastic blocks float without gravity; a region holds the first and not the second. The
 * first translates rigidly with the region's acceleration integrated over the schedule
 * (v = integral of a f(t) dt, against the closed form), the second stays at rest exactly.
 * Explicit and implicit integrators, material points and enriched domains (whose corners are
 * DOFs of their own). A region's drag slows the first block by 1 / (1 + drag dt) per step and
 * leaves the second's velocity alone. Bad keys are refused with their key paths. */
#include "support.h"
#include "sim/sim.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* %s: solver, body extras, force extras */
static const char *SCENE =
    "{\"domain\": {\"min\": [0,0,0], \"max\": [1.2,1.2,0.6], \"dx\": 0.04},"
    " \"gravity\": [0, 0, 0], \"time\": {\"end\": 0.2, \"fps\": 20}, \"solver\": {%s},"
    " \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\", \"E\": 1e5, \"nu\": 0.3,"
    " \"density\": 1000}],"
    " \"bodies\": [{\"name\": \"in\", \"shape\": {\"type\": \"box\", \"center\": [0.3,0.4,0.3],"
    " \"half_extent\": [0.06,0.06,0.06]}, \"material\": \"m\", \"jitter\": 0%s},"
    " {\"name\": \"out\", \"shape\": {\"type\": \"box\", \"center\": [0.9,0.4,0.3],"
    " \"half_extent\": [0.06,0.06,0.06]}, \"material\": \"m\", \"jitter\": 0%s}],"
    " \"forces\": [{\"name\": \"straw\", \"shape\": {\"type\": \"cylinder\", \"center\": "
    "[0.3,0.6,0.3], \"radius\": 0.2, \"axis\": [0,1,0], \"half_height\": 0.45}%s}]}";
static const char *ACCELERATION = ", \"acceleration\": [0, 2, 0]";

/* mean velocity and centre of mass of the particles of one body */
static void body_motion(const mpm_sim *sim, int body, double v[3], double x[3]) {
  const mpm_particles *p = sim->domains.particles.count ? &sim->domains.particles : &sim->particles;
  double m = 0;
  for (int d = 0; d < 3; ++d) v[d] = x[d] = 0;
  for (size_t i = 0; i < p->count; ++i) {
    if ((int)p->body[i] != body) continue;
    m += p->mass[i];
    for (int d = 0; d < 3; ++d) {
      v[d] += (double)p->mass[i] * p->v[d][i];
      x[d] += (double)p->mass[i] * p->x[d][i];
    }
  }
  for (int d = 0; d < 3; ++d) v[d] /= m, x[d] /= m;
}

/* Runs the scene to its end; expects body 0's velocity vy (within rel) and body 1 at rest. */
static void run_case(const char *solver, const char *body, const char *force, double vy, double rel,
                     const char *what) {
  char text[4096], f[512];
  snprintf(f, sizeof f, "%s%s", ACCELERATION, force);
  snprintf(text, sizeof text, SCENE, solver, body, body, f);
  mpm_sim *sim = test_sim_from_json(text, "suction.json");
  double v0[3], x0[3], v1[3], x1[3];
  body_motion(sim, 0, v0, x0);
  body_motion(sim, 1, v1, x1);
  const double y0 = x0[1], y1 = x1[1];
  while (sim->frame < sim->frame_count) assert_int_equal(mpm_sim_advance_frame(sim), MPM_OK);
  body_motion(sim, 0, v0, x0);
  body_motion(sim, 1, v1, x1);
  print_message("%s: inside v_y %.6f (expected %.6f), moved %.5f m; outside |v| %.2e, moved "
                "%.2e m\n",
                what, v0[1], vy, x0[1] - y0, fabs(v1[0]) + fabs(v1[1]) + fabs(v1[2]),
                fabs(x1[1] - y1));
  assert_true(fabs(v0[1] - vy) <= rel * vy);
  assert_true(fabs(v0[0]) < 1e-4 * vy && fabs(v0[2]) < 1e-4 * vy);
  /* at rest to round-off (exactly 0 for material points; enriched domains' elastic and
   * hourglass forces of a rest state at round-off, and the implicit solve's tolerance, leave
   * ~1e-11 m/s) */
  assert_true(fabs(v1[0]) + fabs(v1[1]) + fabs(v1[2]) < 1e-9);
  assert_true(fabs(x1[1] - y1) < 1e-6);
  mpm_sim_destroy(sim);
}

static const char *EXPLICIT = "\"kernel\": \"quadratic\"";
static const char *IMPLICIT = "\"kernel\": \"quadratic\", \"integrator\": \"implicit\", "
                              "\"dt\": 0.005";

/* a = 2 m/s^2 for 0.2 s: v = 0.4 m/s (a rigid translation: the elastic forces stay zero) */
static void test_constant_region(void **state) {
  (void)state;
  run_case(EXPLICIT, "", "", 0.4, 1e-4, "explicit, constant");
  run_case(IMPLICIT, "", "", 0.4, 1e-4, "implicit, constant");
}

/* factor ramps 0 -> 1 over [0, 0.1], then holds: v = a (0.05 + 0.1) = 0.3 m/s; the factor is
 * taken at each step's end, so the ramp integrates to first order in dt */
static void test_schedule(void **state) {
  (void)state;
  const char *ramp = ", \"schedule\": [[0, 0], [0.1, 1]]";
  run_case(EXPLICIT, "", ramp, 0.3, 2e-2, "explicit, ramp");
  run_case(IMPLICIT, "", ramp, 0.3, 5e-2, "implicit, ramp");
  /* the window: the region acts for the first 0.1 s only: v = 0.2 m/s */
  run_case(EXPLICIT, "", ", \"active\": [0, 0.1]", 0.2, 2e-2, "explicit, window");
}

/* enriched domains: every corner is a DOF of its own, off the grid, and gets the region's
 * acceleration at its own position */
static void test_enriched_domains(void **state) {
  (void)state;
  const char *dom = ", \"domains\": true, \"particles_per_cell\": 1, \"enrichment\": 1";
  run_case(EXPLICIT, dom, "", 0.4, 1e-4, "explicit, enriched domains");
  run_case(IMPLICIT, dom, "", 0.4, 1e-4, "implicit, enriched domains");
  run_case(IMPLICIT, ", \"domains\": true, \"particles_per_cell\": 1", "", 0.4, 1e-4,
           "implicit, domains on the grid");
}

/* drag = 5 /s (no acceleration): both blocks start at 0.5 m/s along y; the one inside keeps
 * 1 / (1 + 5 dt) of its velocity per step (collide/body_force.h; a rigid translation, so no
 * elastic force mixes in), the one outside all of it. */
static void drag_case(const char *solver, const char *body, const char *what) {
  char text[4096], b[512];
  snprintf(b, sizeof b, ", \"velocity\": [0, 0.5, 0]%s", body);
  snprintf(text, sizeof text, SCENE, solver, b, b, ", \"drag\": 5");
  mpm_sim *sim = test_sim_from_json(text, "drag.json");
  double expect = 0.5, v0[3], x0[3], v1[3], x1[3];
  while (sim->time < 0.2 - 1e-9) {
    assert_int_equal(mpm_sim_step(sim, 0), MPM_OK);
    expect /= 1 + 5 * sim->last_dt;
  }
  body_motion(sim, 0, v0, x0);
  body_motion(sim, 1, v1, x1);
  print_message("%s, drag: inside v_y %.6f (expected %.6f), outside %.6f (0.5)\n", what, v0[1],
                expect, v1[1]);
  assert_true(fabs(v0[1] - expect) <= 1e-4 * expect);
  assert_true(fabs(v1[1] - 0.5) <= 1e-5);
  assert_true(fabs(v0[0]) + fabs(v0[2]) < 1e-6 && fabs(v1[0]) + fabs(v1[2]) < 1e-6);
  mpm_sim_destroy(sim);
}

static void test_drag(void **state) {
  (void)state;
  drag_case(EXPLICIT, "", "explicit");
  drag_case(IMPLICIT, "", "implicit");
  drag_case(IMPLICIT, ", \"domains\": true, \"particles_per_cell\": 1, \"enrichment\": 1",
            "implicit, enriched domains");
}

static void expect_error(const char *force, const char *needle) {
  char text[4096];
  snprintf(text, sizeof text, SCENE, EXPLICIT, "", "", force);
  if (strstr(force, "acceleration") == NULL) {
    char f[512];
    snprintf(f, sizeof f, "%s%s", ACCELERATION, force);
    snprintf(text, sizeof text, SCENE, EXPLICIT, "", "", f);
  }
  mpm_scene scene;
  mpm_error err;
  assert_int_not_equal(mpm_scene_parse(text, "suction.json", &scene, &err), MPM_OK);
  if (!strstr(err.message, needle)) fail_msg("expected '%s' in: %s", needle, err.message);
}

static void test_bad_keys(void **state) {
  (void)state;
  expect_error(", \"schedule\": [[0, 1], [0, 2]]", "forces[0].schedule[1]");
  expect_error(", \"schedule\": [[0, -1]]", "forces[0].schedule[0]");
  expect_error(", \"schedule\": 3", "forces[0].schedule");
  expect_error(", \"active\": [1, 0]", "forces[0].active");
  expect_error(", \"strength\": 1", "forces[0].strength: unknown key");
  expect_error(", \"acceleration\": [0, 1]", "forces[0].acceleration");
  expect_error(", \"drag\": -1", "forces[0].drag");
  /* a region needs its acceleration or a drag */
  expect_error(", \"acceleration\": null, \"inside_out\": false", "forces[0].acceleration");
  char text[4096];
  snprintf(text, sizeof text, SCENE, EXPLICIT, "", "", "");
  mpm_scene scene;
  mpm_error err;
  assert_int_not_equal(mpm_scene_parse(text, "suction.json", &scene, &err), MPM_OK);
  if (!strstr(err.message, "forces[0]") || !strstr(err.message, "\"acceleration\" or \"drag\""))
    fail_msg("expected forces[0] and acceleration or drag in: %s", err.message);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_constant_region),  cmocka_unit_test(test_schedule),
      cmocka_unit_test(test_enriched_domains), cmocka_unit_test(test_drag),
      cmocka_unit_test(test_bad_keys),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
