/* diagnostics.c - conserved and monitored quantities over the particles: mass, kinetic,
 * elastic and gravitational energy, linear and angular momentum. Accumulated in double, in
 * particle-id order independent chunks summed in a fixed order, so the result does not depend
 * on threads.
 *
 * With APIC a particle carries angular momentum in its affine field too (Jiang et al. 2015):
 * L_p = x_p x m_p v_p + m_p eps : B_p^T with the particle's affine moment B_p = C_p D_p. Domain
 * particles (Zhu et al.) count with their position and velocity. */
#include "sim/sim.h"
#include "core/mat3.h"

#include <string.h>

/* Add the particles of p (those with active[i] != 0 when active is given) to out. */
static void accumulate(const mpm_sim *sim, const mpm_particles *p, const uint8_t *active, int apic,
                       mpm_diagnostics *out) {
  for (size_t i = 0; i < p->count; ++i) {
    if (active && !active[i]) continue;
    const double m = p->mass[i];
    const double x[3] = {p->x[0][i], p->x[1][i], p->x[2][i]};
    const double v[3] = {p->v[0][i], p->v[1][i], p->v[2][i]};
    out->mass += m;
    out->kinetic += 0.5 * m * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    /* the potential of the uniform gravity field, zero at the origin: only its changes mean
     * anything, and the origin is a reference every run of the scene shares */
    const double *g = sim->scene.gravity;
    out->gravitational -= m * (g[0] * x[0] + g[1] * x[1] + g[2] * x[2]);
    for (int d = 0; d < 3; ++d) out->momentum[d] += m * v[d];
    out->angular_momentum[0] += m * (x[1] * v[2] - x[2] * v[1]);
    out->angular_momentum[1] += m * (x[2] * v[0] - x[0] * v[2]);
    out->angular_momentum[2] += m * (x[0] * v[1] - x[1] * v[0]);
    if (apic) {
      double B[9];
      for (int c = 0; c < 9; ++c) B[c] = p->B[c][i];
      out->angular_momentum[0] += m * (B[7] - B[5]);
      out->angular_momentum[1] += m * (B[2] - B[6]);
      out->angular_momentum[2] += m * (B[3] - B[1]);
    }
    const mpm_material at = mpm_material_at_temperature(&sim->materials[p->material[i]],
                                                        p->plastic[i], p->temperature[i]);
    const mpm_material *mat = &at;
    mpm_real F[9];
    for (int c = 0; c < 9; ++c) F[c] = p->F[c][i];
    out->elastic += (double)p->vol0[i] * (double)mat->model->energy(mat, F);
  }
}

mpm_diagnostics mpm_sim_diagnostics(const mpm_sim *sim) {
  mpm_diagnostics out;
  memset(&out, 0, sizeof out);
  accumulate(sim, &sim->particles, NULL, sim->scene.solver.transfer == MPM_TRANSFER_APIC, &out);
  /* domain particles carry no affine moment: their velocity field lives on the corners */
  accumulate(sim, &sim->domains.particles, sim->domains.active, 0, &out);
  /* over every process of the run */
  double all[10] = {out.mass, out.kinetic, out.elastic, out.gravitational};
  for (int d = 0; d < 3; ++d) {
    all[4 + d] = out.momentum[d];
    all[7 + d] = out.angular_momentum[d];
  }
  mpm_reduce_all(sim->reduction, MPM_REDUCE_SUM, all, 10);
  out.mass = all[0];
  out.kinetic = all[1];
  out.elastic = all[2];
  out.gravitational = all[3];
  for (int d = 0; d < 3; ++d) {
    out.momentum[d] = all[4 + d];
    out.angular_momentum[d] = all[7 + d];
  }
  return out;
}
