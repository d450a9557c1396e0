/* test_implicit_levels.c - the implicit step on Gao et al.'s multi-level grid (solver/implicit.h,
 * "On Gao et al.'s multi-level grid"; Gao list it as future work), against independent truth:
 *   - K du equals central finite differences of the forces of a block that straddles the level
 *     change (its particles on three transfer grids, their stencils through ghost nodes), for
 *     three models at random and compressed states;
 *   - the operator E^T K E is symmetric, and definite with the definiteness fix; its Jacobi
 *     diagonal is positive wherever there is mass;
 *   - one level through the multi-level path gives bitwise the uniform grid's implicit step;
 *   - a spinning block flying across the level change without gravity keeps its mass exactly,
 *     its linear momentum to the CG tolerance and (APIC, the ghosts' moments) its angular
 *     momentum;
 *   - a stiff block dropped across the level change onto a floor at 25 times the explicit step
 *     stays stable and its energy never grows;
 *   - 1 and 2 threads give bitwise-identical states; with the grid rebuilt every 2 steps, a run
 *     stopped between rebuilds resumes bit-identically. */
#include "implicit_support.h"
#include "resume_support.h"
#include "core/parallel.h"
#include "adaptive/adaptive.h"

#include <stdlib.h>

/* A block of `model` centred on the level change at x = 0.6 (fine to the right) of a domain
 * 1.2 m wide with dx = 0.1 on level 0; `levels` spliced into the domain object, `solver` into
 * the solver's. */
static mpm_sim *levels_block(const char *model, const char *levels, const char *solver,
                             const char *extra_bodies) {
  char text[4096];
  snprintf(text, sizeof text,
           "{\"domain\": {\"min\": [0, 0, 0], \"max\": [1.2, 1.2, 1.2], \"dx\": 0.1%s},"
           " \"gravity\": [0, 0, 0], \"time\": {\"end\": 1, \"fps\": 10},"
           " \"solver\": {\"kernel\": \"ugimp\", \"integrator\": \"implicit\"%s},"
           " \"materials\": [{\"name\": \"m\", \"model\": \"%s\", \"E\": 1e5, \"nu\": 0.3,"
           " \"density\": 1000}],"
           " \"bodies\": [{\"name\": \"b\", \"shape\": {\"type\": \"box\", \"center\": [0.6, "
           "0.59, 0.61], \"half_extent\": [0.2, 0.15, 0.16]}, \"material\": \"m\", "
           "\"jitter\": 0}]%s}",
           levels, solver, model, extra_bodies);
  return test_sim_from_json(text, "levels_block.json");
}

#define TWO_LEVELS                                                                                 \
  ", \"levels\": 2, \"refine\": [{\"level\": 1, \"box\": {\"min\": [0.6, 0, 0], \"max\": [1.2, "   \
  "1.2, 1.2]}}]"

static double norm(const mpm_dofs *d, mpm_real *const a[3]) {
  return sqrt(mpm_dofs_dot(d, NULL, a, a));
}

/* The system of one step of dt, with the multi-level grid's parts and ghosts checked. */
static void system_of(mpm_sim *sim, mpm_implicit *s) {
  assert_int_equal(mpm_sim_implicit_system(sim, 1e-3, s), MPM_OK);
  assert_non_null(s->levels);
  assert_true(s->levels->ghost_count > 0);
  int used = 0; /* coarse and fine particles, and coarse ones transferring on the fine level */
  for (int k = 0; k < s->part_count; ++k) used += s->part[k].count > 0;
  assert_true(used >= 3);
}

/* The particles moved by 0.013 m along x: sampled leaf by leaf, the coarse ones' boxes end where
 * the fine leaves begin; moved, those next to the level change transfer on the fine level (an
 * extra transfer grid whose slots are all ghosts). */
static void shift(mpm_particles *p) {
  for (size_t i = 0; i < p->count; ++i) p->x[0][i] += (mpm_real)0.013;
}

/* Every particle's F near a state: random (F ~ I + 0.2), or compressed (that times 0.5). */
static void set_states(mpm_particles *p, int compressed, uint64_t *rng) {
  for (size_t i = 0; i < p->count; ++i)
    for (int c = 0; c < 9; ++c) {
      const mpm_real f = (c % 4 == 0 ? 1 : 0) + (mpm_real)test_rand(rng, -0.2, 0.2);
      p->F[c][i] = compressed ? (mpm_real)0.5 * f : f;
    }
}

/* |K du + (f(e du) - f(-e du)) / 2e| / |K du|, the model's own derivative */
static double fd_error(mpm_sim *sim, uint64_t *rng) {
  mpm_implicit s;
  system_of(sim, &s);
  s.exact = 1;
  mpm_dofs *d = s.dofs;
  mpm_real **du = mpm_dofs_vector(d, "t.du"), **u = mpm_dofs_vector(d, "t.u");
  mpm_real **fp = mpm_dofs_vector(d, "t.fp"), **fm = mpm_dofs_vector(d, "t.fm");
  mpm_real **Kdu = mpm_dofs_vector(d, "t.Kdu");
  assert_non_null(du && u && fp && fm && Kdu);
  implicit_random(d, rng, du); /* zero at the ghosts, which hold no mass */
  for (int c = 0; c < 3; ++c)
    for (size_t i = 0; i < d->count; ++i) du[c][i] *= (mpm_real)(0.05 * sim->scene.dx);
  const mpm_real e = (mpm_real)TOL(2e-3, 1e-5);
  mpm_implicit_displace(&s, NULL);
  mpm_implicit_build(&s);
  mpm_implicit_apply(&s, 0, 1, du, Kdu);
  for (int sign = 1; sign >= -1; sign -= 2) {
    mpm_dofs_copy(d, du, u);
    for (int c = 0; c < 3; ++c)
      for (size_t i = 0; i < d->count; ++i) u[c][i] *= sign * e;
    mpm_implicit_displace(&s, u);
    mpm_implicit_forces(&s, sign > 0 ? fp : fm);
  }
  for (int c = 0; c < 3; ++c)
    for (size_t i = 0; i < d->count; ++i) fp[c][i] = Kdu[c][i] + (fp[c][i] - fm[c][i]) / (2 * e);
  const double k = norm(d, Kdu);
  assert_true(k > 0);
  return norm(d, fp) / k;
}

static void test_hessian_matches_finite_differences(void **state) {
  (void)state;
  static const char *const models[] = {"fixed_corotated", "neo_hookean", "hencky_stvk"};
  uint64_t rng = 5;
  for (int m = 0; m < 3; ++m)
    for (int compressed = 0; compressed <= 1; ++compressed) {
      mpm_sim *sim = levels_block(models[m], TWO_LEVELS, "", "");
      shift(&sim->particles);
      set_states(&sim->particles, compressed, &rng);
      const double err = fd_error(sim, &rng);
      print_message("2 levels, K du vs central differences: %-16s %-10s rel. error %.2e\n",
                    models[m], compressed ? "compressed" : "random", err);
      assert_true(err < TOL(3e-2, 1e-6));
      mpm_sim_destroy(sim);
    }
}

static void test_symmetric_definite_and_diagonal(void **state) {
  (void)state;
  uint64_t rng = 9;
  mpm_sim *sim = levels_block("fixed_corotated", TWO_LEVELS, "", "");
  shift(&sim->particles);
  set_states(&sim->particles, 1, &rng);
  mpm_implicit s;
  system_of(sim, &s);
  mpm_dofs *d = s.dofs;
  mpm_real **a = mpm_dofs_vector(d, "t.a"), **b = mpm_dofs_vector(d, "t.b");
  mpm_real **Ka = mpm_dofs_vector(d, "t.Ka"), **Kb = mpm_dofs_vector(d, "t.Kb");
  assert_non_null(a && b && Ka && Kb);
  mpm_implicit_displace(&s, NULL);
  mpm_implicit_build(&s);
  double worst = 0;
  for (int trial = 0; trial < 8; ++trial) {
    implicit_random(d, &rng, a);
    implicit_random(d, &rng, b);
    mpm_implicit_apply(&s, 0, 1, a, Ka);
    mpm_implicit_apply(&s, 0, 1, b, Kb);
    const double aKb = mpm_dofs_dot(d, NULL, a, Kb), Kab = mpm_dofs_dot(d, NULL, Ka, b);
    const double scale = norm(d, a) * norm(d, Kb);
    worst = fmax(worst, fabs(aKb - Kab) / scale);
    assert_true(fabs(aKb - Kab) <= TOL(1e-5, 1e-12) * scale);
    assert_true(mpm_dofs_dot(d, NULL, a, Ka) >= -TOL(1e-6, 1e-13) * norm(d, a) * norm(d, Ka));
    /* K a is zero at every ghost: its sums went to the parents */
    for (size_t g = 0; g < s.levels->ghost_count; ++g)
      for (int c = 0; c < 3; ++c) assert_true(Ka[c][s.levels->ghost_slot[g]] == 0);
  }
  /* the Jacobi diagonal: positive at every DOF with mass, zero at the ghosts */
  mpm_implicit_diagonal(&s, 1, (mpm_real)1e-3, a);
  size_t live = 0, stiff = 0;
  for (size_t i = 0; i < d->count; ++i)
    for (int c = 0; c < 3; ++c)
      if (d->mass[i] > 0) {
        assert_true(a[c][i] >= d->mass[i]); /* a node's gradients can all vanish */
        stiff += a[c][i] > d->mass[i];
        live++;
      }
  assert_true(stiff > live / 2);
  for (size_t g = 0; g < s.levels->ghost_count; ++g)
    for (int c = 0; c < 3; ++c) assert_true(a[c][s.levels->ghost_slot[g]] == 0);
  print_message("2 levels: |<a, K b> - <K a, b>| / (|a| |K b|) at most %.2e over %zu DOF "
                "components with mass (%zu with stiffness on the diagonal), %zu ghosts\n",
                worst, live, stiff, s.levels->ghost_count);
  mpm_sim_destroy(sim);
}

static void run_steps(mpm_sim *sim, int n) {
  for (int k = 0; k < n; ++k)
    if (mpm_sim_step(sim, 1) != MPM_OK) fail_msg("step %d: %s", k, mpm_sim_last_error(sim));
}

static void spin(mpm_particles *p) {
  for (size_t i = 0; i < p->count; ++i) {
    p->v[0][i] = (mpm_real)(0.5 - 2 * (p->x[1][i] - 0.59));
    p->v[1][i] = (mpm_real)(2 * (p->x[0][i] - 0.6));
    p->v[2][i] = (mpm_real)0.3;
    p->F[0][i] = (mpm_real)1.2;
  }
}

static void assert_same(const mpm_particles *a, const mpm_particles *b) {
  assert_int_equal(a->count, b->count);
  for (int c = 0; c < 3; ++c) {
    assert_memory_equal(a->x[c], b->x[c], a->count * sizeof(mpm_real));
    assert_memory_equal(a->v[c], b->v[c], a->count * sizeof(mpm_real));
  }
  for (int c = 0; c < 9; ++c) {
    assert_memory_equal(a->F[c], b->F[c], a->count * sizeof(mpm_real));
    assert_memory_equal(a->B[c], b->B[c], a->count * sizeof(mpm_real));
  }
}

static void test_single_level_is_uniform_bitwise(void **state) {
  (void)state;
  static const char *const transfers[] = {", \"transfer\": \"apic\"", ", \"transfer\": \"flip\""};
  for (int t = 0; t < 2; ++t) {
    char solver[160];
    snprintf(solver, sizeof solver, ", \"dt\": 0.01, \"newton_iterations\": 2%s", transfers[t]);
    mpm_sim *u = levels_block("neo_hookean", "", solver, "");
    mpm_sim *a = levels_block("neo_hookean", ", \"levels\": 1", solver, "");
    assert_null(u->adaptive);
    assert_non_null(a->adaptive);
    spin(&u->particles);
    spin(&a->particles);
    run_steps(u, 6);
    run_steps(a, 6);
    assert_true(u->implicit_steps == 6 && a->implicit_steps == 6);
    assert_same(&a->particles, &u->particles);
    mpm_sim_destroy(u);
    mpm_sim_destroy(a);
  }
}

typedef struct sums {
  double mass, p[3], L[3];
} sums;

/* mass, linear and angular momentum (with APIC's affine part: mpm_sim_diagnostics) */
static sums sums_of(const mpm_sim *sim) {
  const mpm_diagnostics d = mpm_sim_diagnostics(sim);
  sums s = {d.mass, {0}, {0}};
  for (int c = 0; c < 3; ++c) s.p[c] = d.momentum[c], s.L[c] = d.angular_momentum[c];
  return s;
}

/* |L1 - L0| / |L0| of a spinning block over 10 implicit steps; mass and linear momentum checked
 * on the way */
static double angular_change(const char *levels, const char *transfer) {
  char solver[160];
  snprintf(solver, sizeof solver, ", \"dt\": 0.01, \"transfer\": \"%s\", \"cg_tolerance\": %g",
           transfer, TOL(1e-6, 1e-10));
  mpm_sim *sim = levels_block("neo_hookean", levels, solver, "");
  spin(&sim->particles);
  const sums s0 = sums_of(sim);
  run_steps(sim, 10);
  const sums s1 = sums_of(sim);
  const double P = sqrt(s0.p[0] * s0.p[0] + s0.p[1] * s0.p[1] + s0.p[2] * s0.p[2]);
  const double L = sqrt(s0.L[0] * s0.L[0] + s0.L[1] * s0.L[1] + s0.L[2] * s0.L[2]);
  double dL = 0;
  for (int c = 0; c < 3; ++c) dL += (s1.L[c] - s0.L[c]) * (s1.L[c] - s0.L[c]);
  dL = sqrt(dL) / L;
  print_message("%s, implicit, %s: mass %.9g -> %.9g; momentum (%.7g, %.7g, %.7g) -> (%.7g, "
                "%.7g, %.7g); angular momentum changed by %.3g of %.7g; %lld CG iterations\n",
                levels[0] ? "2 levels" : "uniform", transfer, s0.mass, s1.mass, s0.p[0], s0.p[1],
                s0.p[2], s1.p[0], s1.p[1], s1.p[2], dL, L, sim->cg_iterations);
  assert_true(s1.mass == s0.mass);
  for (int c = 0; c < 3; ++c) assert_true(fabs(s1.p[c] - s0.p[c]) <= TOL(1e-4, 1e-7) * P);
  mpm_sim_destroy(sim);
  return dL;
}

/* Mass exactly and linear momentum to the CG tolerance. Backward Euler changes the angular
 * momentum by O(dt^2) on any grid (the forces balance moments about the displaced nodes, not the
 * nodes): with APIC (the ghosts' moments across the level change) two levels change it no more
 * than the uniform grid does. */
static void test_conserves_across_the_level_change(void **state) {
  (void)state;
  const double uniform = angular_change("", "apic");
  const double levels = angular_change(TWO_LEVELS, "apic");
  assert_true(levels <= 1.5 * uniform + TOL(1e-5, 1e-8));
  angular_change(TWO_LEVELS, "flip");
}

static void test_stiff_block_on_floor(void **state) {
  (void)state;
  const char *text =
      "{\"domain\": {\"min\": [0, 0, 0], \"max\": [0.96, 0.96, 0.96], \"dx\": 0.08,"
      " \"levels\": 2, \"refine\": [{\"level\": 1, \"box\": {\"min\": [0.48, 0, 0], "
      "\"max\": [0.96, 0.96, 0.96]}}]},"
      " \"gravity\": [0, -9.81, 0], \"time\": {\"end\": 0.2, \"fps\": 20},"
      " \"solver\": {\"integrator\": \"implicit\", \"dt\": 0.002,"
      " \"on_cg_failure\": \"stop\"},"
      " \"materials\": [{\"name\": \"steel\", \"model\": \"fixed_corotated\", \"E\": 1e8,"
      " \"nu\": 0.3, \"density\": 1000}],"
      " \"bodies\": [{\"name\": \"b\", \"shape\": {\"type\": \"box\", \"center\": [0.48, 0.5,"
      " 0.48], \"half_extent\": [0.12, 0.06, 0.1]}, \"material\": \"steel\", \"jitter\": 0}],"
      " \"colliders\": [{\"shape\": {\"type\": \"halfspace\", \"point\": [0, 0.32, 0],"
      " \"normal\": [0, 1, 0]}, \"rule\": \"slip\"}]}";
  mpm_sim *sim = test_sim_from_json(text, "stiff_levels.json");
  assert_non_null(sim->adaptive);
  const double dx = mpm_adaptive_finest_dx(sim->adaptive);
  const implicit_drop r = implicit_drop_run(sim, dx);
  print_message("2 levels, stiff block: dt = %.3g s = %.0fx the explicit CFL step at the finest "
                "dx, %lld steps, energy %.6g -> %.6g J, lowest particle %.4f m (floor 0.32)\n",
                sim->last_dt, r.dt_ratio, (long long)sim->steps, r.e0, r.e1, r.lowest);
  assert_true(r.dt_ratio >= 20);
  assert_true(r.lowest > 0.32 - 0.5 * dx); /* on the floor, */
  assert_true(r.lowest < 0.40);            /* having fallen from 0.45 */
  assert_true(r.e1 < r.e0);
  mpm_sim_destroy(sim);
}

static void run_bytes(int threads, mpm_real *out, size_t n) {
  mpm_set_threads(threads);
  mpm_sim *sim =
      levels_block("neo_hookean", TWO_LEVELS, ", \"dt\": 0.01, \"newton_iterations\": 3", "");
  spin(&sim->particles);
  run_steps(sim, 4);
  const mpm_particles *p = &sim->particles;
  assert_true(3 * p->count <= n);
  for (size_t i = 0; i < p->count; ++i)
    for (int c = 0; c < 3; ++c) out[3 * i + c] = p->x[c][i] + p->v[c][i];
  mpm_sim_destroy(sim);
}

static void test_threads_bitwise(void **state) {
  (void)state;
  enum { N = 3 * 16384 };
  mpm_real *a = calloc(N, sizeof *a), *b = calloc(N, sizeof *b);
  assert_non_null(a && b);
  run_bytes(1, a, N);
  run_bytes(2, b, N);
  assert_memory_equal(a, b, N * sizeof *a);
  mpm_set_threads(0);
  free(a);
  free(b);
}

/* Implicit steps with the tree rebuilt from the rules every 2 steps (the body rule follows the
 * spinning block), checkpointed one step after a frame and resumed: bit for bit the run that went
 * through. */
static void test_resume_with_rebuilds(void **state) {
  (void)state;
  const char *text =
      "{\"domain\": {\"min\": [0, 0, 0], \"max\": [1.2, 1.2, 1.2], \"dx\": 0.1, \"levels\": 2,"
      " \"refine_every\": 2, \"refine\": [{\"level\": 1, \"body\": \"b\", \"distance\": 0.1}]},"
      " \"gravity\": [0, -9.81, 0], \"time\": {\"end\": 0.1, \"fps\": 20},"
      " \"solver\": {\"integrator\": \"implicit\", \"dt\": 0.01, \"transfer\": \"apic\"},"
      " \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\", \"E\": 1e5, \"nu\": 0.3,"
      " \"density\": 1000}],"
      " \"bodies\": [{\"name\": \"b\", \"shape\": {\"type\": \"box\", \"center\": [0.6, 0.6, 0.6],"
      " \"half_extent\": [0.15, 0.12, 0.13]}, \"material\": \"m\", \"velocity\": [0.5, 0, 0],"
      " \"angular_velocity\": [0, 0, 3]}],"
      " \"output\": {\"checkpoint_every\": 1}}";
  mpm_sim *a, *c;
  resume_pair("implicit_levels_resume", text, 1, 1, NULL, &a, &c);
  assert_true(a->implicit_steps > 0 && a->adaptive->rebuilds > 0);
  assert_same(&a->particles, &c->particles);
  mpm_sim_destroy(a);
  mpm_sim_destroy(c);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_hessian_matches_finite_differences),
      cmocka_unit_test(test_symmetric_definite_and_diagonal),
      cmocka_unit_test(test_single_level_is_uniform_bitwise),
      cmocka_unit_test(test_conserves_across_the_level_change),
      cmocka_unit_test(test_stiff_block_on_floor),
      cmocka_unit_test(test_threads_bitwise),
      cmocka_unit_test(test_resume_with_rebuilds),
  };
  return test_cleanup(cmocka_run_group_tests_name("implicit_levels", tests, NULL, NULL));
}
