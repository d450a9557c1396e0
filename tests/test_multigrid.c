/* test_multigrid.c - the multigrid preconditioner of the implicit step (solver/multigrid.h,
 * solver/implicit_multigrid.c, transfer/assemble.c) against independent truth:
 *   - the assembled finest matrix M + dt^2 K applies as the matrix-free action does, for the
 *     linear, quadratic and cubic kernels (stencil radii 1, 2, 3) at compressed states;
 *   - every coarse matrix is the Galerkin product: <P x, A P y> = <x, A_c y> for random coarse
 *     x, y, with P the prolongation the cycle applies and R = P^T its restriction;
 *   - the prolongation reproduces linear fields exactly (the quadratic B-spline's two-scale
 *     relation with its staggered coarse nodes, and linear interpolation);
 *   - the V-cycle is symmetric and positive definite on the constrained subspace (a slip floor
 *     and a sticky wall hold nodes): x . B y = y . B x, x . B x > 0, B x projected;
 *   - a step solved with Jacobi and with multigrid to a tight tolerance ends in the same state,
 *     in far fewer iterations; 1 and 2 threads give bitwise the same run, and so does a run
 *     resumed from a checkpoint;
 *   - the multigrid's iterations per Newton iteration do not grow when dx halves (a stiff block
 *     spinning onto a floor), where Jacobi's grow. */
#include "implicit_support.h"
#include "resume_support.h"
#include "core/parallel.h"

#include <stdlib.h>

static void compress(mpm_particles *p, uint64_t *rng) {
  for (size_t i = 0; i < p->count; ++i)
    for (int c = 0; c < 9; ++c)
      p->F[c][i] = (mpm_real)((c % 4 == 0 ? 0.8 : 0) + test_rand(rng, -0.1, 0.1));
}

/* The system of sim's next step at dt with its hierarchy prepared and built (constraints from
 * v*: none without colliders). */
static void multigrid_system(mpm_sim *sim, double dt, mpm_implicit *s) {
  assert_int_equal(mpm_sim_implicit_system(sim, dt, s), MPM_OK);
  assert_true(mpm_implicit_multigrid_supported(s));
  mpm_implicit_displace(s, NULL);
  mpm_implicit_build(s);
  mpm_dofs *d = s->dofs;
  mpm_real **v = mpm_dofs_vector(d, "t.v");
  assert_non_null(v);
  for (size_t i = 0; i < d->count; ++i) /* falling at 1 m/s into whatever holds it */
    for (int c = 0; c < 3; ++c) v[c][i] = c == 1 ? -1 : 0;
  assert_int_equal(mpm_implicit_constraints(s, v), MPM_OK);
  assert_int_equal(mpm_implicit_multigrid_prepare(s), MPM_OK);
  assert_int_equal(mpm_implicit_multigrid_build(s), MPM_OK);
}

/* The finest level's rows as a DOF vector and back. */
static void to_rows(const mpm_implicit *s, mpm_real *const a[3], mpm_real *out) {
  for (size_t i = 0; i < s->mg->level[0].n; ++i)
    for (int c = 0; c < 3; ++c) out[3 * i + c] = a[c][s->mg_dof[i]];
}

static void test_assembled_equals_action(void **state) {
  (void)state;
  static const char *const kernels[] = {"linear", "quadratic", "cubic"};
  uint64_t rng = 7;
  for (int k = 0; k < 3; ++k) {
    mpm_sim *sim = implicit_block("neo_hookean", "", kernels[k], 0, "", 0.25, 8);
    compress(&sim->particles, &rng);
    mpm_implicit s;
    multigrid_system(sim, 1e-2, &s);
    assert_int_equal(s.mg->level[0].radius, k + 1);
    mpm_dofs *d = s.dofs;
    mpm_real **x = mpm_dofs_vector(d, "t.x"), **y = mpm_dofs_vector(d, "t.y");
    const size_t n = s.mg->level[0].n;
    mpm_real *xr = malloc(3 * n * sizeof *xr), *yr = malloc(3 * n * sizeof *yr);
    assert_non_null(x && y && xr && yr);
    double worst = 0;
    for (int trial = 0; trial < 4; ++trial) {
      /* nodes in the walls' band are constrained: the assembled matrix is P A P there */
      implicit_random(d, &rng, x);
      mpm_implicit_project(&s, x);
      mpm_implicit_apply(&s, 1, s.apply_scale, x, y);
      mpm_implicit_project(&s, y);
      to_rows(&s, x, xr);
      mpm_multigrid_apply(s.mg, 0, xr, yr);
      double num = 0, den = 0;
      for (size_t i = 0; i < n; ++i)
        for (int c = 0; c < 3; ++c) {
          const double e = (double)yr[3 * i + c] - (double)y[c][s.mg_dof[i]];
          num += e * e;
          den += (double)y[c][s.mg_dof[i]] * y[c][s.mg_dof[i]];
        }
      worst = fmax(worst, sqrt(num / den));
    }
    printf("  %s: %zu rows, radius %d, %d levels: |A x - action(x)| / |action(x)| = %.2e\n",
           kernels[k], n, s.mg->level[0].radius, s.mg->level_count, worst);
    assert_true(worst < TOL(2e-5, 1e-12));
    free(xr);
    free(yr);
    mpm_sim_destroy(sim);
  }
}

/* A block resting on a slip floor against a sticky wall: constrained nodes of both kinds. */
static mpm_sim *held_block(const char *extra) {
  char text[2048];
  snprintf(text, sizeof text,
           "{\"domain\": {\"min\": [0, 0, 0], \"max\": [1.2, 1.2, 1.2], \"dx\": 0.05},"
           " \"time\": {\"end\": 0.1, \"fps\": 20},"
           " \"solver\": {\"integrator\": \"implicit\", \"dt\": 0.01%s},"
           " \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\", \"E\": 1e7, \"nu\": 0.3,"
           " \"density\": 1000}],"
           " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.5, 0.31, 0.6],"
           " \"half_extent\": [0.2, 0.1, 0.15]}, \"material\": \"m\", \"particles_per_cell\": 8,"
           " \"jitter\": 0, \"velocity\": [-0.3, -0.5, 0.1]}],"
           " \"colliders\": [{\"shape\": {\"type\": \"halfspace\", \"point\": [0, 0.2, 0],"
           " \"normal\": [0, 1, 0.2]}, \"rule\": \"slip\"},"
           " {\"shape\": {\"type\": \"halfspace\", \"point\": [0.3, 0, 0],"
           " \"normal\": [1, 0, 0]}, \"rule\": \"sticky\"}]}",
           extra);
  return test_sim_from_json(text, "held.json");
}

/* x_f = P x_c between levels l + 1 and l, as the cycle prolongs. */
static void prolong(const mpm_multigrid *mg, int l, const mpm_real *xc, mpm_real *xf) {
  const mpm_mg_level *L = &mg->level[l];
  for (size_t i = 0; i < L->n; ++i)
    for (int e = 0; e < 3; ++e) {
      double acc = 0;
      for (int k = 0; k < 8 && L->parent[8 * i + (size_t)k] >= 0; ++k)
        acc += L->pw[8 * i + (size_t)k] * xc[3 * (size_t)L->parent[8 * i + (size_t)k] + (size_t)e];
      xf[3 * i + (size_t)e] = (mpm_real)acc;
    }
}

static double dot(const mpm_real *a, const mpm_real *b, size_t n) {
  double s = 0;
  for (size_t i = 0; i < n; ++i) s += (double)a[i] * b[i];
  return s;
}

static void test_galerkin_coarse_levels(void **state) {
  (void)state;
  uint64_t rng = 11;
  static const char *const kernels[] = {", \"kernel\": \"quadratic\"", ", \"kernel\": \"linear\""};
  static const char *const names[] = {"quadratic", "linear"};
  for (int k = 0; k < 2; ++k) {
    mpm_sim *sim = held_block(kernels[k]);
    compress(&sim->particles, &rng);
    mpm_implicit s;
    multigrid_system(sim, 1e-2, &s);
    const mpm_multigrid *mg = s.mg;
    assert_true(mg->level_count >= 2);
    for (int l = 0; l + 1 < mg->level_count; ++l) {
      const size_t nf = mg->level[l].n, nc = mg->level[l + 1].n;
      mpm_real *xc = malloc(3 * nc * sizeof *xc), *yc = malloc(3 * nc * sizeof *yc);
      mpm_real *Ayc = malloc(3 * nc * sizeof *Ayc), *xf = malloc(3 * nf * sizeof *xf);
      mpm_real *yf = malloc(3 * nf * sizeof *yf), *Ayf = malloc(3 * nf * sizeof *Ayf);
      assert_non_null(xc && yc && Ayc && xf && yf && Ayf);
      for (size_t i = 0; i < 3 * nc; ++i) {
        xc[i] = (mpm_real)test_rand(&rng, -1, 1);
        yc[i] = (mpm_real)test_rand(&rng, -1, 1);
      }
      prolong(mg, l, xc, xf);
      prolong(mg, l, yc, yf);
      mpm_multigrid_apply(mg, l, yf, Ayf);
      mpm_multigrid_apply(mg, l + 1, yc, Ayc);
      const double fine = dot(xf, Ayf, 3 * nf), coarse = dot(xc, Ayc, 3 * nc);
      /* and R = P^T: the restriction the cycle takes is P's transpose, row by row */
      const mpm_mg_level *C = &mg->level[l + 1];
      double rp = 0;
      for (size_t I = 0; I < nc; ++I)
        for (uint32_t q = C->child_start[I]; q < C->child_start[I + 1]; ++q)
          for (int e = 0; e < 3; ++e)
            rp += xc[3 * I + (size_t)e] * C->cw[q] * Ayf[3 * C->child[q] + (size_t)e];
      printf("  %s level %d -> %d (%zu -> %zu nodes): <Px, A Py> = %.9g, <x, A_c y> = %.9g, "
             "<x, R A P y> = %.9g\n",
             names[k], l, l + 1, nf, nc, fine, coarse, rp);
      const double scale = sqrt(dot(xf, xf, 3 * nf) * dot(Ayf, Ayf, 3 * nf));
      assert_true(fabs(fine - coarse) <= TOL(1e-4, 1e-11) * scale);
      assert_true(fabs(fine - rp) <= TOL(1e-4, 1e-11) * scale);
      free(xc), free(yc), free(Ayc), free(xf), free(yf), free(Ayf);
    }
    mpm_sim_destroy(sim);
  }
}

static void test_prolongation_reproduces_linear_fields(void **state) {
  (void)state;
  static const char *const kernels[] = {", \"kernel\": \"quadratic\"", ", \"kernel\": \"linear\""};
  for (int k = 0; k < 2; ++k) {
    mpm_sim *sim = held_block(kernels[k]);
    mpm_implicit s;
    multigrid_system(sim, 1e-2, &s);
    const mpm_multigrid *mg = s.mg;
    /* coarse node I of level l + 1 sits at fine coordinate 2 I + 1/2 (quadratic: between fine
       nodes) or 2 I (linear) of level l */
    const double shift = k == 0 ? 0.5 : 0;
    const double a[3] = {0.3, -1.7, 0.9}, b = 2.5;
    for (int l = 0; l + 1 < mg->level_count; ++l) {
      const mpm_mg_level *F = &mg->level[l], *C = &mg->level[l + 1];
      mpm_real *xc = malloc(3 * C->n * sizeof *xc), *xf = malloc(3 * F->n * sizeof *xf);
      assert_non_null(xc && xf);
      for (size_t I = 0; I < C->n; ++I)
        for (int e = 0; e < 3; ++e) {
          double f = b;
          for (int t = 0; t < 3; ++t) f += a[t] * (2 * C->coord[I][t] + shift);
          xc[3 * I + (size_t)e] = (mpm_real)(f * (e + 1));
        }
      prolong(mg, l, xc, xf);
      double worst = 0;
      for (size_t i = 0; i < F->n; ++i)
        for (int e = 0; e < 3; ++e) {
          double f = b;
          for (int t = 0; t < 3; ++t) f += a[t] * F->coord[i][t];
          worst = fmax(worst, fabs(xf[3 * i + (size_t)e] - f * (e + 1)));
        }
      assert_true(worst < TOL(1e-4, 1e-10) * 40);
      free(xc), free(xf);
    }
    mpm_sim_destroy(sim);
  }
}

static void test_vcycle_symmetric_positive(void **state) {
  (void)state;
  mpm_sim *sim = held_block("");
  uint64_t rng = 3;
  mpm_implicit s;
  multigrid_system(sim, 1e-2, &s);
  s.mg->cheap = 0; /* the symmetric cycle (the one-pass cycle is for flexible CG) */
  assert_true(s.constraint_count > 0);
  mpm_dofs *d = s.dofs;
  mpm_real **x = mpm_dofs_vector(d, "t.x"), **y = mpm_dofs_vector(d, "t.y");
  mpm_real **Bx = mpm_dofs_vector(d, "t.Bx"), **By = mpm_dofs_vector(d, "t.By");
  mpm_real **t = mpm_dofs_vector(d, "t.t");
  assert_non_null(x && y && Bx && By && t);
  for (int trial = 0; trial < 5; ++trial) {
    implicit_random(d, &rng, x);
    implicit_random(d, &rng, y);
    mpm_implicit_project(&s, x);
    mpm_implicit_project(&s, y);
    mpm_implicit_multigrid_precondition(&s, x, Bx);
    mpm_implicit_multigrid_precondition(&s, y, By);
    const double xBy = mpm_dofs_dot(d, NULL, x, By), yBx = mpm_dofs_dot(d, NULL, y, Bx);
    const double xBx = mpm_dofs_dot(d, NULL, x, Bx);
    const double scale = sqrt(mpm_dofs_dot(d, NULL, x, x) * mpm_dofs_dot(d, NULL, By, By));
    assert_true(fabs(xBy - yBx) <= TOL(2e-4, 1e-10) * scale);
    assert_true(xBx > 0);
    /* B x is projected: P B x = B x */
    mpm_dofs_copy(d, Bx, t);
    mpm_implicit_project(&s, t);
    mpm_dofs_axpy(d, -1, Bx, t);
    assert_true(sqrt(mpm_dofs_dot(d, NULL, t, t)) <=
                TOL(1e-6, 1e-13) * sqrt(mpm_dofs_dot(d, NULL, Bx, Bx)));
  }
  mpm_sim_destroy(sim);
}

/* Steps of the held block with a preconditioner at tolerance tol; CG iterations per step. */
static double held_run(const char *pre, double tol, int newton, int steps, mpm_sim **out) {
  char extra[256];
  snprintf(extra, sizeof extra,
           ", \"preconditioner\": \"%s\", \"cg_tolerance\": %g, \"cg_max_iterations\": 5000,"
           " \"newton_iterations\": %d",
           pre, tol, newton);
  mpm_sim *sim = held_block(extra);
  for (int k = 0; k < steps; ++k)
    if (mpm_sim_step(sim, 0.01) != MPM_OK) fail_msg("%s", sim->error.message);
  *out = sim;
  return (double)sim->cg_iterations / (double)sim->implicit_steps;
}

static void test_jacobi_and_multigrid_agree(void **state) {
  (void)state;
  mpm_sim *a, *b;
  const double tol = TOL(1e-5, 1e-9);
  const double ja = held_run("jacobi", tol, 20, 4, &a), mg = held_run("multigrid", tol, 20, 4, &b);
  double worst = 0, vmax = 0;
  for (size_t i = 0; i < a->particles.count; ++i)
    for (int c = 0; c < 3; ++c) {
      worst = fmax(worst, fabs((double)a->particles.v[c][i] - b->particles.v[c][i]));
      vmax = fmax(vmax, fabs((double)a->particles.v[c][i]));
    }
  printf("  4 steps: Jacobi %.1f CG iterations per step (%lld Newton, %lld unconverged), "
         "multigrid %.1f (%lld, %lld); largest velocity difference %.2e m/s of %.3f\n",
         ja, a->solver_figures.newton_iterations, a->solver_figures.cg_unconverged, mg,
         b->solver_figures.newton_iterations, b->solver_figures.cg_unconverged, worst, vmax);
  assert_true(worst <= TOL(1e-3, 1e-6) * vmax);
  assert_true(mg * 3 < ja);
  mpm_sim_destroy(a);
  mpm_sim_destroy(b);
}

static void test_threads_bitwise(void **state) {
  (void)state;
  mpm_sim *r[2];
  for (int t = 0; t < 2; ++t) {
    mpm_set_threads(t + 1);
    held_run("multigrid", 1e-3, 3, 3, &r[t]);
  }
  mpm_set_threads(0);
  test_assert_same_particles(r[0], r[1]);
  assert_int_equal(r[0]->cg_iterations, r[1]->cg_iterations);
  mpm_sim_destroy(r[0]);
  mpm_sim_destroy(r[1]);
}

/* CG iterations per Newton iteration of one step of a stiff block spinning onto a slip floor
 * at grid spacing dx, with the preconditioner. */
static double spin_iterations(double dx, const char *pre) {
  char text[2048];
  const double side = 0.24, floor_y = 4 * dx + 0.05, pad = 6 * dx;
  snprintf(text, sizeof text,
           "{\"domain\": {\"min\": [0,0,0], \"max\": [%.6g,%.6g,%.6g], \"dx\": %g},"
           " \"time\": {\"end\": 1, \"fps\": 120}, \"solver\": {\"integrator\": \"implicit\","
           " \"dt\": %.9g, \"cg_tolerance\": 1e-3, \"cg_max_iterations\": 20000,"
           " \"preconditioner\": \"%s\"},"
           " \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\", \"E\": 1e9,"
           " \"nu\": 0.4, \"density\": 1100}],"
           " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [%.6g,%.6g,%.6g],"
           " \"half_extent\": [%.6g,%.6g,%.6g]}, \"material\": \"m\", \"particles_per_cell\": 8,"
           " \"jitter\": 0, \"velocity\": [0,-0.5,0], \"angular_velocity\": [0,2,0]}],"
           " \"colliders\": [{\"shape\": {\"type\": \"halfspace\", \"point\": [0, %g, 0],"
           " \"normal\": [0, 1, 0]}, \"rule\": \"slip\"}]}",
           side * 1.5 + 2 * pad, side + floor_y + 2 * pad, side * 1.5 + 2 * pad, dx, 1.0 / 120, pre,
           pad + side * 0.75, floor_y + side / 2 + 0.25 * dx, pad + side * 0.75, side / 2, side / 2,
           side / 2, floor_y);
  mpm_sim *sim = test_sim_from_json(text, "spin.json");
  if (mpm_sim_step(sim, 1.0 / 120) != MPM_OK) fail_msg("%s", sim->error.message);
  const mpm_solver_figures *f = &sim->last_frame_solver;
  const double it = (double)f->cg_iterations / (double)f->newton_iterations;
  mpm_sim_destroy(sim);
  return it;
}

/* The multigrid's iterations do not grow as the grid refines (HOT's and any multigrid's point);
 * Jacobi's do, which shows the scene can tell them apart. */
static void test_iterations_independent_of_resolution(void **state) {
  (void)state;
  double it[2][2];
  static const char *const pre[] = {"jacobi", "multigrid"};
  for (int m = 0; m < 2; ++m)
    for (int k = 0; k < 2; ++k) it[m][k] = spin_iterations(k == 0 ? 0.04 : 0.02, pre[m]);
  printf("  CG iterations per Newton iteration at dx = 4 cm and 2 cm: Jacobi %.1f, %.1f; "
         "multigrid %.1f, %.1f\n",
         it[0][0], it[0][1], it[1][0], it[1][1]);
  assert_true(it[1][1] <= 1.5 * it[1][0]);
  assert_true(it[0][1] > 1.25 * it[0][0]);
  assert_true(it[1][1] * 5 < it[0][1]);
}

/* Implicit steps with the multigrid, checkpointed one step after a frame and resumed: bit for
 * bit the run that went through (the hierarchy is built from each step's state alone). */
static void test_resume_bitwise(void **state) {
  (void)state;
  const char *text =
      "{\"domain\": {\"min\": [0, 0, 0], \"max\": [1.2, 1.2, 1.2], \"dx\": 0.05},"
      " \"time\": {\"end\": 0.06, \"fps\": 50},"
      " \"solver\": {\"integrator\": \"implicit\", \"dt\": 0.005, \"preconditioner\": "
      "\"multigrid\"},"
      " \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\", \"E\": 1e6, \"nu\": 0.3,"
      " \"density\": 1000}],"
      " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.5, 0.3, 0.6],"
      " \"half_extent\": [0.15, 0.1, 0.12]}, \"material\": \"m\", \"velocity\": [0.3, -1, 0],"
      " \"angular_velocity\": [0, 0, 3]}],"
      " \"colliders\": [{\"shape\": {\"type\": \"halfspace\", \"point\": [0, 0.18, 0],"
      " \"normal\": [0, 1, 0]}, \"rule\": \"slip\"}],"
      " \"output\": {\"checkpoint_every\": 1}}";
  mpm_sim *a, *c;
  resume_pair("multigrid_resume", text, 1, 1, NULL, &a, &c);
  assert_true(a->implicit_steps > 0);
  assert_int_equal(a->particles.count, c->particles.count);
  for (int k = 0; k < 3; ++k) {
    assert_memory_equal(a->particles.x[k], c->particles.x[k],
                        a->particles.count * sizeof(mpm_real));
    assert_memory_equal(a->particles.v[k], c->particles.v[k],
                        a->particles.count * sizeof(mpm_real));
  }
  for (int k = 0; k < 9; ++k)
    assert_memory_equal(a->particles.F[k], c->particles.F[k],
                        a->particles.count * sizeof(mpm_real));
  mpm_sim_destroy(a);
  mpm_sim_destroy(c);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_assembled_equals_action),
      cmocka_unit_test(test_galerkin_coarse_levels),
      cmocka_unit_test(test_prolongation_reproduces_linear_fields),
      cmocka_unit_test(test_vcycle_symmetric_positive),
      cmocka_unit_test(test_jacobi_and_multigrid_agree),
      cmocka_unit_test(test_threads_bitwise),
      cmocka_unit_test(test_iterations_independent_of_resolution),
      cmocka_unit_test(test_resume_bitwise),
  };
  return test_cleanup(cmocka_run_group_tests_name("multigrid", tests, NULL, NULL));
}
