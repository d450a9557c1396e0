/* implicit_support.h - shared by the implicit tests: a small block as a simulation, its
 * implicit system, and random DOF vectors. */
#ifndef MPM_TEST_IMPLICIT_SUPPORT_H
#define MPM_TEST_IMPLICIT_SUPPORT_H

#include "support.h"
#include "solver/implicit.h"
#include "solver/sim.h"

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

#endif
