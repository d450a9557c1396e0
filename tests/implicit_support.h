/* implicit_support.h - shared by the implicit tests: a small block as a simulation, its
 * implicit system, and random DOF vectors. */
#ifndef MPM_TEST_IMPLICIT_SUPPORT_H
#define MPM_TEST_IMPLICIT_SUPPORT_H

#include "support.h"
#include "solver/implicit.h"
#include "sim/sim.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* A block of `model` (extra material keys in material_extra) of half size `half` with `ppc`
 * particles per cell (on the lattice, no jitter), as
 * domains or not, on `kernel`; solver_extra is added to the solver section. */
/* domains: 0 material points, 1 particle domains, 2 domains enriched where K(F) <= 0.85. */
static inline mpm_sim *implicit_block(const char *model, const char *material_extra,
                                      const char *kernel, int domains, const char *solver_extra,
                                      double half, int ppc) {
  char text[4096];
  snprintf(text, sizeof text,
           "{\"domain\": {\"min\": [0, 0, 0], \"max\": [1.2, 1.2, 1.2], \"dx\": 0.1},"
           " \"gravity\": [0, 0, 0], \"time\": {\"end\": 1, \"fps\": 10},"
           " \"solver\": {\"kernel\": \"%s\", \"integrator\": \"implicit\"%s},"
           " \"materials\": [{\"name\": \"m\", \"model\": \"%s\", \"E\": 1e5, \"nu\": 0.3,"
           " \"density\": 1000%s}],"
           " \"bodies\": [{\"name\": \"b\", \"shape\": {\"type\": \"box\", \"center\": [0.62, "
           "0.59, 0.61], \"half_extent\": [%g, %g, %g]}, \"material\": \"m\", "
           "\"particles_per_cell\": %d, \"jitter\": 0, \"domains\": %s}]}",
           kernel, solver_extra, model, material_extra, half, half * 0.8, half * 0.9, ppc,
           domains == 2 ? "true, \"enrichment\": 0.92, \"enrichment_metric\": \"frobenius\""
           : domains    ? "true"
                        : "false");
  return test_sim_from_json(text, "block.json");
}

/* The particles of the system, standard or domain. */
static inline mpm_particles *implicit_particles(mpm_sim *sim) {
  return sim->domains.particles.count ? &sim->domains.particles : &sim->particles;
}

/* Random vector over the DOFs with mass (0 elsewhere), components in [-1, 1). */
static inline void implicit_random(const mpm_dofs *d, uint64_t *rng, mpm_real *const a[3]) {
  for (size_t i = 0; i < d->count; ++i)
    for (int c = 0; c < 3; ++c) a[c][i] = d->mass[i] > 0 ? (mpm_real)test_rand(rng, -1, 1) : 0;
}

/* kinetic + elastic + gravitational (9.81 m/s^2 along -y) energy of the particles, J */
static inline double implicit_total_energy(const mpm_sim *sim) {
  const mpm_diagnostics d = mpm_sim_diagnostics(sim);
  double pot = 0;
  const mpm_particles *p = &sim->particles;
  for (size_t i = 0; i < p->count; ++i) pot += (double)p->mass[i] * 9.81 * (double)p->x[1][i];
  return d.kinetic + d.elastic + pot;
}

/* A stiff block's drop onto a floor: the step against the explicit CFL step at spacing dx, the
 * energy at the start and the end, and the lowest any particle came, m. */
typedef struct implicit_drop {
  double dt_ratio, e0, e1, lowest;
} implicit_drop;

/* Every frame of sim (material 0 the block's), asserting that the energy never grows (a slack
 * for the float sums of a body at rest). */
static inline implicit_drop implicit_drop_run(mpm_sim *sim, double dx) {
  implicit_drop r;
  const double c = sqrt((double)(sim->materials[0].lambda + 2 * sim->materials[0].mu) / 1000);
  r.e0 = r.e1 = implicit_total_energy(sim);
  r.lowest = 1e30;
  while (sim->frame < sim->frame_count) {
    if (mpm_sim_advance_frame(sim) != MPM_OK) fail_msg("%s", sim->error.message);
    const double e = implicit_total_energy(sim);
    assert_true(e <= r.e1 + TOL(1e-4, 1e-9) * fabs(r.e0));
    r.e1 = e;
    const mpm_particles *p = &sim->particles;
    for (size_t i = 0; i < p->count; ++i) r.lowest = fmin(r.lowest, (double)p->x[1][i]);
  }
  r.dt_ratio = sim->last_dt / (sim->scene.solver.cfl * dx / c);
  return r;
}

#endif
