/* test_implicit.c - the implicit step (solver/implicit.h) against independent truth:
 *   - K du equals central finite differences of the grid forces, -(f(u + e du) - f(u - e du)) /
 *     (2 e), for every model, for material points and particle domains, for each kernel, at
 *     random, strongly compressed and inverted deformation gradients (where the model takes
 *     them);
 *   - the operator is symmetric, and with the definiteness fix <a, K a> >= 0 at a compressed
 *     state where the model's own Hessian is indefinite (shown along a linearized rotation);
 *   - with no gravity and no colliders, an implicit step conserves linear momentum to the CG
 *     tolerance; free fall matches the exact discrete answer;
 *   - a stiff block (E = 1e8 Pa) dropped on a floor at 50x the explicit CFL step stays stable
 *     and its total energy never grows;
 *   - 1 and 2 threads give bitwise-identical states; Newton iterations lower the incremental
 *     potential's gradient;
 *   - the scene keys are validated with key paths. */
#include "implicit_support.h"
#include "core/parallel.h"

#include <stdlib.h>

typedef enum state_kind { STATE_RANDOM, STATE_COMPRESSED, STATE_INVERTED } state_kind;
static const char *const STATE_NAMES[] = {"random", "compressed", "inverted"};

/* Every particle's F set to a state of the kind, with per-particle noise. */
static void set_states(mpm_particles *p, state_kind kind, uint64_t *rng) {
  for (size_t i = 0; i < p->count; ++i) {
    mpm_real F[9];
    for (int c = 0; c < 9; ++c) F[c] = (c % 4 == 0 ? 1 : 0) + (mpm_real)test_rand(rng, -0.25, 0.25);
    if (kind == STATE_COMPRESSED)
      for (int c = 0; c < 9; ++c) F[c] *= (mpm_real)0.45;
    if (kind == STATE_INVERTED)
      for (int c = 0; c < 3; ++c) F[c] = -F[c]; /* the first row flipped: det F < 0 */
    for (int c = 0; c < 9; ++c) p->F[c][i] = F[c];
  }
}

static double norm(const mpm_dofs *d, mpm_real *const a[3]) {
  return sqrt(mpm_dofs_dot(d, NULL, a, a));
}

/* max over the test's vectors of |K du + (f+ - f-) / 2e| / |K du| */
static double fd_error(mpm_sim *sim, uint64_t *rng) {
  mpm_implicit s;
  assert_int_equal(mpm_sim_implicit_system(sim, 1e-3, &s), MPM_OK);
  s.exact = 1;
  mpm_dofs *d = s.dofs;
  mpm_real **du = mpm_dofs_vector(d, "t.du"), **u = mpm_dofs_vector(d, "t.u");
  mpm_real **fp = mpm_dofs_vector(d, "t.fp"), **fm = mpm_dofs_vector(d, "t.fm");
  mpm_real **Kdu = mpm_dofs_vector(d, "t.Kdu");
  assert_non_null(du && u && fp && fm && Kdu);
  /* displacements of a tenth of a cell: the stencils' gradients are 1/dx, so |dF| ~ 0.1 */
  implicit_random(d, rng, du);
  for (int c = 0; c < 3; ++c)
    for (size_t i = 0; i < d->count; ++i) du[c][i] *= (mpm_real)(0.1 * sim->scene.dx);
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
  for (int c = 0; c < 3; ++c) /* fp <- K du + (f+ - f-) / 2e */
    for (size_t i = 0; i < d->count; ++i) fp[c][i] = Kdu[c][i] + (fp[c][i] - fm[c][i]) / (2 * e);
  const double k = norm(d, Kdu);
  assert_true(k > 0);
  return norm(d, fp) / k;
}

typedef struct model_case {
  const char *model, *extra;
  int inverts; /* takes inverted F */
} model_case;

static const model_case MODELS[] = {
    {"fixed_corotated", "", 1},
    {"neo_hookean", "", 0},
    {"hencky_stvk", "", 1},
    {"drucker_prager", ", \"friction_angle\": 30", 1},
    {"von_mises", ", \"yield_stress\": 1e9", 1},
    {"snow", "", 1},
};

static void test_hessian_matches_finite_differences(void **state) {
  (void)state;
  static const char *const kernels[] = {"linear", "quadratic", "cubic", "ugimp"};
  uint64_t rng = 7;
  for (size_t m = 0; m < sizeof MODELS / sizeof MODELS[0]; ++m)
    for (int domains = 0; domains <= 1; ++domains)
      for (int k = 0; k < 4; ++k) {
        if (domains && k > 2) continue; /* corner weights: linear, quadratic, cubic */
        for (int st = 0; st < 3; ++st) {
          if (st == STATE_INVERTED && !MODELS[m].inverts) continue;
          char solver[128];
          solver[0] = '\0';
          if (domains) snprintf(solver, sizeof solver, ", \"domain_kernel\": \"%s\"", kernels[k]);
          mpm_sim *sim =
              implicit_block(MODELS[m].model, MODELS[m].extra, domains ? "quadratic" : kernels[k],
                             domains, solver, 0.12, 8);
          set_states(implicit_particles(sim), (state_kind)st, &rng);
          const double err = fd_error(sim, &rng);
          print_message("K du vs central differences: %-16s %-9s %-10s %-11s rel. error %.2e\n",
                        MODELS[m].model, domains ? "domains" : "points", kernels[k],
                        STATE_NAMES[st], err);
          assert_true(err < TOL(3e-2, 1e-6));
          mpm_sim_destroy(sim);
        }
      }
}

/* With enriched corners (Zhu sec. 5: identity rows of the corner embedding, corner DOFs) and
 * their hourglass control (domain/enrich.h) K matches central differences of the forces. */
static void test_enriched_finite_differences(void **state) {
  (void)state;
  static const char *const kernels[] = {"linear", "quadratic"};
  uint64_t rng = 17;
  for (int m = 0; m < 2; ++m)
    for (int k = 0; k < 2; ++k) {
      char solver[128];
      snprintf(solver, sizeof solver, ", \"domain_kernel\": \"%s\"", kernels[k]);
      mpm_sim *sim = implicit_block(MODELS[m].model, "", "quadratic", 2, solver, 0.12, 8);
      set_states(implicit_particles(sim), STATE_RANDOM, &rng);
      const double err = fd_error(sim, &rng);
      const mpm_domain_enrichment *e = &sim->domains.enrich;
      print_message("K du vs central differences, enriched: %-16s %-9s %zu / %zu / %zu "
                    "particles unenriched / transitional / enriched, %zu corner DOFs: rel. error "
                    "%.2e\n",
                    MODELS[m].model, kernels[k], e->particles[0], e->particles[1], e->particles[2],
                    e->count, err);
      assert_true(e->particles[1] > 0 && e->particles[2] > 0);
      assert_true(err < TOL(3e-2, 1e-6));
      mpm_sim_destroy(sim);
    }
}

/* On the dense reference grid (the operators' scalar paths) K matches central differences of
 * the forces too. */
static void test_dense_grid(void **state) {
  (void)state;
  uint64_t rng = 21;
  for (int domains = 0; domains <= 1; ++domains) {
    mpm_sim *sim = implicit_block("fixed_corotated", "", "quadratic", domains,
                                  ", \"grid\": \"dense\"", 0.12, 8);
    set_states(implicit_particles(sim), STATE_COMPRESSED, &rng);
    const double err = fd_error(sim, &rng);
    print_message("dense grid, %s: K du vs central differences, rel. error %.2e\n",
                  domains ? "domains" : "points", err);
    assert_true(err < TOL(3e-2, 1e-6));
    mpm_sim_destroy(sim);
  }
}

/* <a, K b> - <K a, b>, <a, K a> at a compressed state, definite and exact. */
static void test_symmetric_and_definite(void **state) {
  (void)state;
  uint64_t rng = 11;
  for (int domains = 0; domains <= 1; ++domains) {
    mpm_sim *sim = implicit_block("fixed_corotated", "", "quadratic", domains, "", 0.2, 8);
    set_states(implicit_particles(sim), STATE_COMPRESSED, &rng);
    mpm_implicit s;
    assert_int_equal(mpm_sim_implicit_system(sim, 1e-3, &s), MPM_OK);
    mpm_dofs *d = s.dofs;
    mpm_real **a = mpm_dofs_vector(d, "t.a"), **b = mpm_dofs_vector(d, "t.b");
    mpm_real **Ka = mpm_dofs_vector(d, "t.Ka"), **Kb = mpm_dofs_vector(d, "t.Kb");
    assert_non_null(a && b && Ka && Kb);
    mpm_implicit_displace(&s, NULL);
    mpm_implicit_build(&s);
    for (int trial = 0; trial < 10; ++trial) {
      implicit_random(d, &rng, a);
      implicit_random(d, &rng, b);
      mpm_implicit_apply(&s, 0, 1, a, Ka);
      mpm_implicit_apply(&s, 0, 1, b, Kb);
      const double aKb = mpm_dofs_dot(d, NULL, a, Kb), Kab = mpm_dofs_dot(d, NULL, Ka, b);
      const double scale = norm(d, a) * norm(d, Kb);
      assert_true(fabs(aKb - Kab) <= TOL(1e-5, 1e-12) * scale);
      assert_true(mpm_dofs_dot(d, NULL, a, Ka) >= -TOL(1e-6, 1e-13) * norm(d, a) * norm(d, Ka));
    }
    /* a linearized rotation about z through the block's centre: the model's own Hessian has
     * negative curvature along it in compression, the definite one does not */
    for (size_t i = 0; i < d->count; ++i) {
      mpm_real x[3];
      mpm_dofs_position(d, i, x);
      const int live = d->mass[i] > 0;
      a[0][i] = live ? -(x[1] - (mpm_real)0.6) : 0;
      a[1][i] = live ? (x[0] - (mpm_real)0.6) : 0;
      a[2][i] = 0;
    }
    mpm_implicit_apply(&s, 0, 1, a, Ka);
    const double definite = mpm_dofs_dot(d, NULL, a, Ka);
    s.exact = 1;
    mpm_implicit_displace(&s, NULL);
    mpm_implicit_apply(&s, 0, 1, a, Ka);
    const double exact = mpm_dofs_dot(d, NULL, a, Ka);
    print_message("%s, F ~ 0.45 I: <a, K a> along a rotation: exact %.4g, definite %.4g\n",
                  domains ? "domains" : "points", exact, definite);
    assert_true(exact < 0);
    assert_true(definite >= 0);
    mpm_sim_destroy(sim);
  }
}

/* Diagnostics' momentum of an implicit run of a spinning, stretched block, no gravity. */
static void test_momentum_conserved(void **state) {
  (void)state;
  for (int domains = 0; domains <= 1; ++domains) {
    mpm_sim *sim = implicit_block("neo_hookean", "", "quadratic", domains,
                                  ", \"dt\": 0.01, \"cg_tolerance\": 1e-7", 0.2, 1);
    mpm_particles *p = implicit_particles(sim);
    for (size_t i = 0; i < p->count; ++i) {
      p->v[0][i] = 1 - 2 * (p->x[1][i] - (mpm_real)0.6);
      p->v[1][i] = 2 * (p->x[0][i] - (mpm_real)0.6);
      p->v[2][i] = (mpm_real)0.3;
      p->F[0][i] = (mpm_real)1.3;
    }
    mpm_domain_set *ds = &sim->domains; /* the corners carry their own velocities */
    for (size_t c = 0; c < ds->corner_count; ++c) {
      ds->cv[0][c] = 1 - 2 * (ds->cx[1][c] - (mpm_real)0.6);
      ds->cv[1][c] = 2 * (ds->cx[0][c] - (mpm_real)0.6);
      ds->cv[2][c] = (mpm_real)0.3;
    }
    const mpm_diagnostics d0 = mpm_sim_diagnostics(sim);
    for (int k = 0; k < 5; ++k) assert_int_equal(mpm_sim_step(sim, 1), MPM_OK);
    const mpm_diagnostics d1 = mpm_sim_diagnostics(sim);
    const double scale = d0.mass * 1.0;
    for (int c = 0; c < 3; ++c) {
      print_message("%s: momentum %c %.9g -> %.9g\n", domains ? "domains" : "points", "xyz"[c],
                    d0.momentum[c], d1.momentum[c]);
      assert_true(fabs(d1.momentum[c] - d0.momentum[c]) <= TOL(1e-4, 1e-6) * scale);
    }
    mpm_sim_destroy(sim);
  }
}

/* A body at rest with F = I falls freely: after n steps of dt, v = -g n dt exactly as the
 * discrete update gives it (K acts on nothing: the stress is zero and uniform motion does not
 * deform), x = x0 - g dt^2 n (n + 1) / 2. */
static void test_free_fall(void **state) {
  (void)state;
  char text[2048];
  snprintf(
      text, sizeof text,
      "{\"domain\": {\"min\": [0, 0, 0], \"max\": [1.2, 1.4, 1.2], \"dx\": 0.1},"
      " \"gravity\": [0, -10, 0], \"time\": {\"end\": 1, \"fps\": 10},"
      " \"solver\": {\"integrator\": \"implicit\", \"dt\": 0.01, \"transfer\": \"apic\","
      " \"cg_tolerance\": %g},"
      " \"materials\": [{\"name\": \"m\", \"model\": \"fixed_corotated\", \"E\": 1e6, \"nu\": 0.3,"
      " \"density\": 1000}],"
      " \"bodies\": [{\"name\": \"b\", \"shape\": {\"type\": \"box\", \"center\": [0.6, 0.75,"
      " 0.6], \"half_extent\": [0.1, 0.1, 0.1]}, \"material\": \"m\", \"jitter\": 0}]}",
      TOL(1e-6, 1e-12));
  mpm_sim *sim = test_sim_from_json(text, "fall.json");
  const mpm_particles *p = &sim->particles;
  const double y0 = p->x[1][0];
  const int n = 10;
  for (int k = 0; k < n; ++k) assert_int_equal(mpm_sim_step(sim, 1), MPM_OK);
  const double v = -10 * 0.01 * n, y = y0 - 10 * 0.01 * 0.01 * n * (n + 1) / 2.0;
  for (size_t i = 0; i < p->count; i += 7) {
    assert_close(p->v[1][i], v, TOL(1e-4, 1e-10));
    assert_close(p->v[0][i], 0, TOL(1e-5, 1e-12));
  }
  assert_close(p->x[1][0], y, TOL(1e-5, 1e-10));
  print_message("free fall after %d steps: v = %.9g (exact %.9g), y = %.9g (exact %.9g)\n", n,
                (double)p->v[1][0], v, (double)p->x[1][0], y);
  mpm_sim_destroy(sim);
}

static void test_stiff_block_on_floor(void **state) {
  (void)state;
  const char *text =
      "{\"domain\": {\"min\": [0, 0, 0], \"max\": [0.6, 0.6, 0.6], \"dx\": 0.04},"
      " \"gravity\": [0, -9.81, 0], \"time\": {\"end\": 0.2, \"fps\": 20},"
      " \"solver\": {\"integrator\": \"implicit\", \"dt\": 0.002,"
      " \"on_cg_failure\": \"stop\"},"
      " \"materials\": [{\"name\": \"steel\", \"model\": \"fixed_corotated\", \"E\": 1e8,"
      " \"nu\": 0.3, \"density\": 1000}],"
      " \"bodies\": [{\"name\": \"b\", \"shape\": {\"type\": \"box\", \"center\": [0.3, 0.25,"
      " 0.3], \"half_extent\": [0.1, 0.06, 0.1]}, \"material\": \"steel\", \"jitter\": 0}],"
      " \"colliders\": [{\"shape\": {\"type\": \"halfspace\", \"point\": [0, 0.15, 0],"
      " \"normal\": [0, 1, 0]}, \"rule\": \"slip\"}]}";
  mpm_sim *sim = test_sim_from_json(text, "stiff.json");
  const implicit_drop r = implicit_drop_run(sim, sim->scene.dx);
  print_message("stiff block: dt = %.3g s = %.0fx the explicit CFL step, %lld steps, energy "
                "%.6g -> %.6g J, lowest particle %.4f m (floor 0.15)\n",
                sim->last_dt, r.dt_ratio, (long long)sim->steps, r.e0, r.e1, r.lowest);
  assert_true(r.dt_ratio >= 20);
  assert_true(r.lowest > 0.15 - 0.5 * sim->scene.dx); /* it rests on the floor */
  assert_true(r.e1 < r.e0);
  mpm_sim_destroy(sim);
}

/* Positions and velocities after a few steps, as bytes. */
static void run_bytes(int threads, int newton, int domains, mpm_real *out, size_t n) {
  mpm_set_threads(threads);
  char solver[160];
  snprintf(solver, sizeof solver, ", \"dt\": 0.01, \"newton_iterations\": %d", newton);
  mpm_sim *sim = implicit_block("neo_hookean", "", "quadratic", domains, solver, 0.2, 1);
  mpm_particles *p = implicit_particles(sim);
  for (size_t i = 0; i < p->count; ++i) p->v[1][i] = (mpm_real)(p->x[0][i] - 0.6);
  for (int k = 0; k < 4; ++k) assert_int_equal(mpm_sim_step(sim, 1), MPM_OK);
  assert_true(3 * p->count <= n);
  for (size_t i = 0; i < p->count; ++i)
    for (int c = 0; c < 3; ++c) out[3 * i + c] = p->x[c][i] + p->v[c][i];
  mpm_sim_destroy(sim);
}

static void test_threads_bitwise(void **state) {
  (void)state;
  enum { N = 3 * 4096 };
  mpm_real *a = calloc(N, sizeof *a), *b = calloc(N, sizeof *b);
  assert_non_null(a && b);
  for (int domains = 0; domains <= 1; ++domains)
    for (int newton = 1; newton <= 3; newton += 2) {
      run_bytes(1, newton, domains, a, N);
      run_bytes(2, newton, domains, b, N);
      assert_memory_equal(a, b, N * sizeof *a);
    }
  mpm_set_threads(0);
  free(a);
  free(b);
}

/* Newton iterations reach a smaller incremental-potential gradient than the single step. */
static void test_newton_iterations(void **state) {
  (void)state;
  int iters[2];
  for (int k = 0; k < 2; ++k) {
    char solver[160];
    snprintf(solver, sizeof solver, ", \"dt\": 0.02, \"newton_iterations\": %d", k ? 8 : 1);
    mpm_sim *sim = implicit_block("neo_hookean", "", "quadratic", 0, solver, 0.2, 1);
    mpm_particles *p = &sim->particles;
    for (size_t i = 0; i < p->count; ++i) p->v[1][i] = (mpm_real)(8 * (p->x[0][i] - 0.6));
    assert_int_equal(mpm_sim_step(sim, 1), MPM_OK);
    iters[k] = sim->solver_figures.last_newton;
    mpm_sim_destroy(sim);
  }
  print_message("Newton iterations taken: %d (newton_iterations 1), %d (8)\n", iters[0], iters[1]);
  assert_int_equal(iters[0], 1);
  assert_true(iters[1] >= 2);
}

/* Plasticity keeps working: a Drucker-Prager block squeezed implicitly (the return map runs
 * after the F update, the Hessian is the elastic part's): its plastic state moves and every
 * particle's elastic F stays on or inside the yield surface (no tension beyond the cone's tip:
 * the Hencky strain's trace is at most 0). */
static void test_plasticity(void **state) {
  (void)state;
  mpm_sim *sim = implicit_block("drucker_prager", ", \"friction_angle\": 30", "quadratic", 0,
                                ", \"dt\": 0.005", 0.2, 8);
  mpm_particles *p = &sim->particles;
  for (size_t i = 0; i < p->count; ++i) { /* stretched sideways, squeezed vertically */
    p->v[0][i] = (mpm_real)(2 * (p->x[0][i] - 0.62));
    p->v[1][i] = (mpm_real)(-3 * (p->x[1][i] - 0.59));
  }
  for (int k = 0; k < 6; ++k) assert_int_equal(mpm_sim_step(sim, 1), MPM_OK);
  double moved = 0;
  for (size_t i = 0; i < p->count; ++i) {
    moved = fmax(moved, fabs((double)p->plastic[i] - sim->materials[0].model->plastic_initial));
    double F[9];
    for (int c = 0; c < 9; ++c) F[c] = p->F[c][i];
    const double J = F[0] * (F[4] * F[8] - F[5] * F[7]) - F[1] * (F[3] * F[8] - F[5] * F[6]) +
                     F[2] * (F[3] * F[7] - F[4] * F[6]);
    assert_true(log(J) <= TOL(1e-4, 1e-9)); /* tr(log sigma) = log J <= 0: no tension */
  }
  print_message("Drucker-Prager, implicit: largest change of the plastic state %.3g\n", moved);
  assert_true(moved > 0);
  mpm_sim_destroy(sim);
}

/* The factored definite derivative is the models' dpdf_action_definite, bitwise. */
static void test_factored_hessian(void **state) {
  (void)state;
  static const mpm_model_kind kinds[] = {MPM_MODEL_FIXED_COROTATED, MPM_MODEL_NEO_HOOKEAN,
                                         MPM_MODEL_HENCKY_STVK,     MPM_MODEL_DRUCKER_PRAGER,
                                         MPM_MODEL_VON_MISES,       MPM_MODEL_SNOW};
  uint64_t rng = 3;
  for (size_t k = 0; k < sizeof kinds / sizeof kinds[0]; ++k) {
    mpm_material_desc md = mpm_material_desc_default();
    md.model = kinds[k];
    mpm_material m;
    mpm_material_init(&m, &md);
    assert_non_null(m.model->hessian_definite);
    for (int t = 0; t < 50; ++t) {
      mpm_real F[9], dF[9], a[9], b[9];
      for (int c = 0; c < 9; ++c) {
        F[c] = (c % 4 == 0 ? 1 : 0) + (mpm_real)test_rand(&rng, -0.6, 0.6);
        dF[c] = (mpm_real)test_rand(&rng, -1, 1);
      }
      mpm_stress_hessian H;
      m.model->hessian_definite(&m, F, &H);
      mpm_stress_hessian_action(&H, dF, a);
      m.model->dpdf_action_definite(&m, F, dF, b);
      assert_memory_equal(a, b, sizeof a);
    }
  }
}

static void expect_scene_error(const char *solver, const char *needle) {
  char text[1024];
  snprintf(text, sizeof text,
           "{\"domain\": {\"min\": [0, 0, 0], \"max\": [1, 1, 1], \"dx\": 0.1},"
           " \"time\": {\"end\": 1}, \"solver\": {%s}, \"materials\": [{\"name\": \"m\"}],"
           " \"bodies\": [{\"name\": \"b\", \"shape\": {\"type\": \"sphere\", \"center\": [0.5,"
           " 0.5, 0.5], \"radius\": 0.1}, \"material\": \"m\"}]}",
           solver);
  mpm_scene scene;
  mpm_error err;
  assert_int_not_equal(mpm_scene_parse(text, "keys.json", &scene, &err), MPM_OK);
  if (!strstr(err.message, needle)) fail_msg("expected '%s' in: %s", needle, err.message);
}

static void test_scene_keys(void **state) {
  (void)state;
  expect_scene_error("\"integrator\": \"implicitt\"", "solver.integrator");
  expect_scene_error("\"dt\": 0.01", "solver.dt: a key of the implicit integrator only");
  expect_scene_error("\"integrator\": \"implicit\", \"newton_iterations\": 0",
                     "solver.newton_iterations");
  expect_scene_error("\"integrator\": \"implicit\", \"cg_tolerance\": 2", "solver.cg_tolerance");
  expect_scene_error("\"integrator\": \"implicit\", \"on_cg_failure\": \"maybe\"",
                     "solver.on_cg_failure");
  expect_scene_error("\"integrator\": \"implicit\", \"dt\": -1", "solver.dt");
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_hessian_matches_finite_differences),
      cmocka_unit_test(test_enriched_finite_differences),
      cmocka_unit_test(test_dense_grid),
      cmocka_unit_test(test_symmetric_and_definite),
      cmocka_unit_test(test_momentum_conserved),
      cmocka_unit_test(test_free_fall),
      cmocka_unit_test(test_stiff_block_on_floor),
      cmocka_unit_test(test_threads_bitwise),
      cmocka_unit_test(test_newton_iterations),
      cmocka_unit_test(test_scene_keys),
      cmocka_unit_test(test_factored_hessian),
      cmocka_unit_test(test_plasticity),
  };
  if (getenv("MPM_TEST_FILTER")) cmocka_set_test_filter(getenv("MPM_TEST_FILTER"));
  return cmocka_run_group_tests(tests, NULL, NULL);
}
