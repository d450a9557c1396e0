/* test_domain_apic.c - domain bodies honour solver.transfer (issue 13): APIC through the corners
 * (domain/domain_transfer.h) against the PIC/FLIP blend.
 *
 * A soft cube with particle domains spins freely (no gravity, no walls in reach). Under APIC
 * the corners carry their velocity and an affine moment across the grid, so the spin's
 * angular momentum stays what it was and its kinetic energy is kept; PIC (flip_alpha 0) damps
 * the spin on the grid every step (on this coarse a body nearly all of it in 150 steps: the
 * material-point PIC does the same), and FLIP sits between. The affine moment is the state of
 * the corners: a run checkpointed under APIC resumes bit-identically (test_checkpoint), and
 * one and two threads agree bitwise here. */
#include "support.h"
#include "core/parallel.h"
#include "sim/sim.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

static mpm_sim *spinning_cube(const char *solver, const char *body) {
  char text[2048];
  snprintf(text, sizeof text,
           "{\"domain\": {\"min\": [0,0,0], \"max\": [1,1,1], \"dx\": 0.05},"
           " \"gravity\": [0, 0, 0], \"time\": {\"end\": 1, \"fps\": 10}, \"solver\": {%s},"
           " \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\", \"E\": 1e5, \"nu\": "
           "0.3, \"density\": 1000}],"
           " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.5,0.5,0.5], "
           "\"half_extent\": [0.12,0.12,0.12]}, \"material\": \"m\", \"domains\": true, "
           "\"angular_velocity\": [0.6, 1.2, 2]%s}]}",
           solver, body);
  return test_sim_from_json(text, "spin.json");
}

/* The corners' angular momentum about the centre of mass and kinetic energy, with the lumped
 * corner masses m_a = sum_p omega_ap m_p (what P2G gives them). The angular momentum is APIC's
 * (Jiang et al. 2015), what P2G hands the grid: m_a (r_a x v_a + eps : B_a^T), the second term
 * the spin of the corner's affine field, m_a eps_ijk B_a[k][j]. */
static void corner_motion(const mpm_sim *sim, double L[3], double *kinetic) {
  const mpm_domain_set *s = &sim->domains;
  const mpm_particles *p = &s->particles;
  double m = 0, c[3] = {0, 0, 0};
  static double mc[4096];
  assert_true(s->corner_count <= 4096);
  memset(mc, 0, sizeof mc);
  for (size_t q = 0; q < p->count; ++q)
    for (int a = 0; a < MPM_HEX_CORNERS; ++a) mc[s->corner[q][a]] += s->w[q][a] * p->mass[q];
  for (size_t k = 0; k < s->corner_count; ++k) {
    m += mc[k];
    for (int d = 0; d < 3; ++d) c[d] += mc[k] * s->cx[d][k];
  }
  for (int d = 0; d < 3; ++d) c[d] /= m, L[d] = 0;
  *kinetic = 0;
  for (size_t k = 0; k < s->corner_count; ++k) {
    const double r[3] = {s->cx[0][k] - c[0], s->cx[1][k] - c[1], s->cx[2][k] - c[2]};
    const double v[3] = {s->cv[0][k], s->cv[1][k], s->cv[2][k]};
    const mpm_real *const B[9] = {s->cB[0], s->cB[1], s->cB[2], s->cB[3], s->cB[4],
                                  s->cB[5], s->cB[6], s->cB[7], s->cB[8]};
    L[0] += mc[k] * (r[1] * v[2] - r[2] * v[1] + B[7][k] - B[5][k]);
    L[1] += mc[k] * (r[2] * v[0] - r[0] * v[2] + B[2][k] - B[6][k]);
    L[2] += mc[k] * (r[0] * v[1] - r[1] * v[0] + B[3][k] - B[1][k]);
    *kinetic += 0.5 * mc[k] * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  }
}

/* Runs `steps` steps after a first one; the relative change of L from the state after that
 * first step (largest over the run) and the kinetic energy kept at the end. The first step
 * starts without the corners' affine moments (B_a = 0, as for material points), and on a body
 * this coarse (5 cells across) the grid's velocity without them is the PIC one, which loses a
 * part of the spin; from then on APIC carries it. */
static void spin(const char *solver, const char *body, int steps, double *dL, double *kept) {
  mpm_sim *sim = spinning_cube(solver, body);
  double L0[3], K0, L[3], K;
  if (mpm_sim_step(sim, 0) != MPM_OK) fail_msg("%s", mpm_sim_last_error(sim));
  corner_motion(sim, L0, &K0);
  const double l0 = sqrt(L0[0] * L0[0] + L0[1] * L0[1] + L0[2] * L0[2]);
  *dL = 0;
  for (int k = 0; k < steps; ++k) {
    if (mpm_sim_step(sim, 0) != MPM_OK) fail_msg("%s", mpm_sim_last_error(sim));
    corner_motion(sim, L, &K);
    const double e[3] = {L[0] - L0[0], L[1] - L0[1], L[2] - L0[2]};
    *dL = fmax(*dL, sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]) / l0);
  }
  *kept = K / K0;
  print_message("%-45s %d steps (%.3f s): |L - L0| / |L0| up to %.2e, kinetic energy kept %.5f\n",
                solver, steps, sim->time, *dL, *kept);
  mpm_sim_destroy(sim);
}

static void test_spin_kept_by_apic(void **state) {
  (void)state;
  double dL_apic, K_apic, dL_pic, K_pic, dL_flip, K_flip;
  spin("\"transfer\": \"apic\"", "", 150, &dL_apic, &K_apic);
  spin("\"transfer\": \"flip\", \"flip_alpha\": 0", "", 150, &dL_pic, &K_pic);
  spin("\"transfer\": \"flip\", \"flip_alpha\": 0.95", "", 150, &dL_flip, &K_flip);
  /* APIC: the spin passes the grid intact */
  assert_true(dL_apic < TOL(2e-5, 1e-10));
  assert_true(K_apic > 0.9); /* (some of it goes into the centrifugal stretch and back) */
  /* PIC damps it: the scene's transfer is what the domains get */
  assert_true(K_pic < K_apic - 0.02);
  assert_true(dL_pic > 10 * dL_apic);
  assert_true(K_flip > K_pic);
  /* the quadratic corner kernel too */
  spin("\"transfer\": \"apic\", \"domain_kernel\": \"quadratic\"", "", 150, &dL_apic, &K_apic);
  assert_true(dL_apic < TOL(2e-5, 1e-10));
  assert_true(K_apic > 0.9);
}

static void test_threads_bitwise(void **state) {
  (void)state;
  mpm_sim *run[2];
  for (int t = 0; t < 2; ++t) {
    mpm_set_threads(t + 1);
    run[t] = spinning_cube("\"transfer\": \"apic\"", ", \"enrichment\": 0.999");
    for (int k = 0; k < 30; ++k)
      if (mpm_sim_step(run[t], 0) != MPM_OK) fail_msg("%s", mpm_sim_last_error(run[t]));
  }
  mpm_set_threads(2);
  const mpm_domain_set *a = &run[0]->domains, *b = &run[1]->domains;
  for (int d = 0; d < 3; ++d) {
    assert_memory_equal(a->cx[d], b->cx[d], a->corner_count * sizeof(mpm_real));
    assert_memory_equal(a->cv[d], b->cv[d], a->corner_count * sizeof(mpm_real));
  }
  for (int e = 0; e < 9; ++e)
    assert_memory_equal(a->cB[e], b->cB[e], a->corner_count * sizeof(mpm_real));
  mpm_sim_destroy(run[0]);
  mpm_sim_destroy(run[1]);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_spin_kept_by_apic),
      cmocka_unit_test(test_threads_bitwise),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
