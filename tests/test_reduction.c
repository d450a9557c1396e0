/* test_reduction.c - every global reduction of a step goes through the simulation's reduction
 * (core/reduce.h), the seam a distributed run fills with its all-reduce:
 *   - an explicit step hands its largest speed and its blow-up flag (a maximum), the guard its
 *     verdict (a maximum), stats' energies and momenta their ten sums; a reduction that
 *     changes nothing leaves the run bitwise as without one;
 *   - an implicit step's CG hands each dot product over: at least one sum per CG iteration,
 *     again bitwise as without a reduction;
 *   - the processes agree: when another process's particle blew up or broke the guard (the
 *     reduction says so), this process's step fails too, naming the other process; and when a
 *     stage failed in another process (the verdict after each stage), this one stops with its
 *     status instead of waiting in the next stage's exchange. */
#include "support.h"
#include "core/reduce.h"
#include "sim/sim.h"

#include <string.h>

typedef struct counting {
  long calls[3];  /* per op */
  long values[3]; /* values reduced, per op */
  int poison;     /* 1: report a blow-up elsewhere; 2: a guard hit elsewhere; 3: a stage failed
                     elsewhere (out of memory) */
  int stepped;    /* the step's (speed, blow-up) maximum came: the guard's verdict is next */
} counting;

static void count_all(void *ctx, mpm_reduce_op op, double *values, int count) {
  counting *c = ctx;
  c->calls[op]++;
  c->values[op] += count;
  /* the step's maximum of (speed, blow-up flag), then the guard's maximum of one flag (the
     stages' verdicts, maxima of one status each, come before the step's) */
  if (op == MPM_REDUCE_MAX && count == 2) {
    if (c->poison == 1) values[1] = 1;
    c->stepped = 1;
  } else if (op == MPM_REDUCE_MAX && count == 1 && c->stepped) {
    if (c->poison == 2) values[0] = 1;
    c->stepped = 0;
  } else if (op == MPM_REDUCE_MAX && count == 1 && c->poison == 3) {
    values[0] = MPM_ERR_NOMEM;
  }
}

static const char *scene(const char *integrator) {
  static char text[1024];
  snprintf(text, sizeof text,
           "{\"domain\": {\"min\": [0,0,0], \"max\": [0.4,0.4,0.4], \"dx\": 0.025},"
           " \"gravity\": [0,-9.81,0], \"time\": {\"end\": 0.02, \"fps\": 100},"
           " \"solver\": {\"integrator\": \"%s\"%s},"
           " \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\", \"E\": 1e5, \"nu\": 0.3,"
           " \"density\": 1000}],"
           " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.2,0.15,0.2],"
           " \"half_extent\": [0.05,0.05,0.05]}, \"material\": \"m\","
           " \"velocity\": [0.3,0,0.1], \"angular_velocity\": [0,2,0]}]}",
           integrator, strcmp(integrator, "implicit") ? "" : ", \"dt\": 0.004");
  return text;
}

static void run_steps(mpm_sim *sim, int steps) {
  for (int k = 0; k < steps; ++k)
    if (mpm_sim_step(sim, 1) != MPM_OK) fail_msg("%s", mpm_sim_last_error(sim));
}

static void assert_same_state(const mpm_sim *a, const mpm_sim *b) {
  const mpm_particles *p = &a->particles, *q = &b->particles;
  assert_int_equal(p->count, q->count);
  for (int d = 0; d < 3; ++d) {
    assert_memory_equal(p->x[d], q->x[d], p->count * sizeof(mpm_real));
    assert_memory_equal(p->v[d], q->v[d], p->count * sizeof(mpm_real));
  }
  assert_true(a->time == b->time);
}

static void test_explicit_step_reduces(void **state) {
  (void)state;
  mpm_sim *plain = test_sim_from_json(scene("explicit"), "reduce_explicit.json");
  mpm_sim *sim = test_sim_from_json(scene("explicit"), "reduce_explicit.json");
  counting c = {0};
  const mpm_reduction r = {count_all, &c};
  mpm_sim_set_reduction(sim, &r);
  const int steps = 6;
  run_steps(plain, steps);
  run_steps(sim, steps);
  assert_same_state(plain, sim);
  /* per step: the verdicts on the scratch and on each of the 7 stages, the speed and blow-up
     flag, the guard's verdict (all maxima) */
  assert_true(c.calls[MPM_REDUCE_MAX] >= (8 + 2) * steps);
  assert_int_equal(c.calls[MPM_REDUCE_SUM], 0);
  const mpm_diagnostics d0 = mpm_sim_diagnostics(plain), d1 = mpm_sim_diagnostics(sim);
  assert_int_equal(c.calls[MPM_REDUCE_SUM], 1);
  assert_int_equal(c.values[MPM_REDUCE_SUM], 10);
  assert_memory_equal(&d0, &d1, sizeof d0);
  mpm_sim_destroy(plain);
  mpm_sim_destroy(sim);
}

static void test_implicit_dots_reduce(void **state) {
  (void)state;
  mpm_sim *plain = test_sim_from_json(scene("implicit"), "reduce_implicit.json");
  mpm_sim *sim = test_sim_from_json(scene("implicit"), "reduce_implicit.json");
  counting c = {0};
  const mpm_reduction r = {count_all, &c};
  mpm_sim_set_reduction(sim, &r);
  run_steps(plain, 3);
  run_steps(sim, 3);
  assert_same_state(plain, sim);
  assert_true(sim->cg_iterations > 0);
  assert_true(c.calls[MPM_REDUCE_SUM] >= sim->cg_iterations);
  mpm_sim_destroy(plain);
  mpm_sim_destroy(sim);
}

static void test_processes_agree(void **state) {
  (void)state;
  for (int poison = 1; poison <= 2; ++poison) {
    mpm_sim *sim = test_sim_from_json(scene("explicit"), "reduce_agree.json");
    counting c = {.poison = poison};
    const mpm_reduction r = {count_all, &c};
    mpm_sim_set_reduction(sim, &r);
    assert_int_equal(mpm_sim_step(sim, 1), MPM_ERR_UNSTABLE);
    const char *msg = mpm_sim_last_error(sim);
    assert_non_null(strstr(msg, "another process"));
    assert_non_null(strstr(msg, poison == 1 ? "blew up" : "unstable"));
    mpm_sim_destroy(sim);
  }
}

/* A stage that failed in another process (out of memory there) stops this one's step too, with
 * that status, where it would otherwise wait in the next stage's exchange. */
static void test_stage_failure_elsewhere(void **state) {
  (void)state;
  mpm_sim *sim = test_sim_from_json(scene("explicit"), "reduce_stage.json");
  counting c = {.poison = 3};
  const mpm_reduction r = {count_all, &c};
  mpm_sim_set_reduction(sim, &r);
  assert_int_equal(mpm_sim_step(sim, 1), MPM_ERR_NOMEM);
  assert_non_null(strstr(mpm_sim_last_error(sim), "another process"));
  mpm_sim_destroy(sim);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_explicit_step_reduces),
      cmocka_unit_test(test_implicit_dots_reduce),
      cmocka_unit_test(test_processes_agree),
      cmocka_unit_test(test_stage_failure_elsewhere),
  };
  return test_cleanup(cmocka_run_group_tests(tests, NULL, NULL));
}
