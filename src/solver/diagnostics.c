/* diagnostics.c - conserved and monitored quantities over the particles: mass, kinetic and
 * elastic energy, linear and angular momentum. Accumulated in double, in particle-id order
 * independent chunks summed in a fixed order, so the result does not depend on threads.
 *
 * With APIC a particle carries angular momentum in its affine field too (Jiang et al. 2015):
 * L_p = x_p x m_p v_p + m_p eps : B_p^T, where B_p = C_p D_p and D_p is the kernel's second
 * moment matrix at the particle (diagonal for our tensor kernels). */
#include "solver/sim.h"
#include "core/mat3.h"

#include <string.h>

/* Diagonal of D_p for a particle at grid coordinate xr (m, relative to the origin). */
static void second_moment(const mpm_kernel *k, const mpm_real xr[3], double D[3]) {
  mpm_real w[MPM_STENCIL_MAX] = {0}, dw[MPM_STENCIL_MAX] = {0}, a[MPM_STENCIL_MAX] = {0};
  for (int d = 0; d < 3; ++d) {
    mpm_real xg = xr[d] * k->inv_dx;
    int base = mpm_kernel_1d(k, xg, w, dw, a);
    double f = (double)xg - base, s = 0;
    for (int i = 0; i < k->width; ++i) s += (double)w[i] * (i - f) * (i - f);
    D[d] = s * (double)k->dx * (double)k->dx;
  }
}

mpm_diagnostics mpm_sim_diagnostics(const mpm_sim *sim) {
  const mpm_particles *p = &sim->particles;
  const int apic = sim->scene.solver.transfer == MPM_TRANSFER_APIC;
  mpm_diagnostics out;
  memset(&out, 0, sizeof out);
  for (size_t i = 0; i < p->count; ++i) {
    const double m = p->mass[i];
    const double x[3] = {p->x[0][i], p->x[1][i], p->x[2][i]};
    const double v[3] = {p->v[0][i], p->v[1][i], p->v[2][i]};
    out.mass += m;
    out.kinetic += 0.5 * m * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    for (int d = 0; d < 3; ++d) out.momentum[d] += m * v[d];
    out.angular_momentum[0] += m * (x[1] * v[2] - x[2] * v[1]);
    out.angular_momentum[1] += m * (x[2] * v[0] - x[0] * v[2]);
    out.angular_momentum[2] += m * (x[0] * v[1] - x[1] * v[0]);
    if (apic) {
      const mpm_real xr[3] = {p->x[0][i] - sim->origin[0], p->x[1][i] - sim->origin[1],
                              p->x[2][i] - sim->origin[2]};
      double D[3];
      second_moment(&sim->kernel, xr, D);
      double B[9];
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) B[3 * r + c] = (double)p->C[3 * r + c][i] * D[c];
      out.angular_momentum[0] += m * (B[7] - B[5]);
      out.angular_momentum[1] += m * (B[2] - B[6]);
      out.angular_momentum[2] += m * (B[3] - B[1]);
    }
    const mpm_material *mat = &sim->materials[p->material[i]];
    mpm_real F[9];
    for (int c = 0; c < 9; ++c) F[c] = p->F[c][i];
    out.elastic += (double)p->vol0[i] * (double)mat->model->energy(mat, F);
  }
  return out;
}
