/* domain_hessian.h - the particle domains' part of the implicit system (Zhu et al. 2017 sec. 6,
 * eqs. 14-19), in the reference configuration, through the corners' embedding.
 *
 * A grid displacement u (over the DOF set) moves each corner by u_a = sum_i E_ai u_i (the
 * embedding of domain_transfer.h) and each domain particle's deformation gradient to
 *   F^_p = F_p + sum_a u_a g_pa^T,           (Zhu eq. 7 with dt v = u; F = sum_a x_a g_pa^T)
 * with g_pa = grad_X omega_ap averaged over the domain (Zhu eq. 5). Then, with C_p = dP/dF at
 * F^_p (made definite, eq. 16, when the Hessian is built definite):
 *   forces      f_i = -E^T (sum_p V_p^0 P(F^_p) g_pa)                     (eq. 8)
 *   Hessian     K u = E^T (sum_p V_p^0 (C_p : sum_b u_b g_pb^T) g_pa)      (eqs. 14-15)
 *   diagonal    K_ii,cc = sum_p V_p^0 b_ip^T S_p^c b_ip,  b_ip = sum_a E_ai g_pa = grad_X w_ip,
 *               S^c_jl = C_cj,cl                                           (eqs. 17-19)
 * Particles touching enriched corners add the hourglass energy 1/2 kappa sum |q_alpha|^2
 * (domain/enrich.h), quadratic in the corner positions: its forces, its constant Hessian
 * kappa sum_alpha h_alpha h_alpha^T and its diagonal go with the terms above.
 * The corner sums go through the corner adjacency (race-free, deterministic); E^T through the
 * embedding's coloured schedule. The diagonal's cross-corner terms are summed particle by
 * particle, serially (it is built once per Newton iteration). */
#ifndef MPM_DOMAIN_DOMAIN_HESSIAN_H
#define MPM_DOMAIN_DOMAIN_HESSIAN_H

#include "mpm/mpm.h"
#include "core/arena.h"
#include "domain/domain.h"
#include "material/material.h"

typedef struct mpm_domain_hessian {
  mpm_domain_set *s;
  const mpm_material *materials;
  mpm_stress_hessian *H; /* per domain particle */
  mpm_real (*Fh)[9];     /* F^_p, the deformation gradient at the displacement */
  mpm_real (*dP)[9];     /* per particle scratch of the actions */
  mpm_real *cu[3];       /* per corner: displacement */
  mpm_real *cy[3];       /* per corner: force */
  int exact;             /* 1: the model's own dP/dF at F^ (tests), not the definite one */
  /* hourglass control of particles touching enriched corners (domain/enrich.h; NULL without
   * enriched corners): kappa, q_alpha at the displacement, and per-action scratch kappa q */
  mpm_real *kappa;
  mpm_real (*qh)[4][3];
  mpm_real (*Q)[4][3];
} mpm_domain_hessian;

/* Scratch from the step's arena for the set's particles and corners (after mpm_domain_p2g has
 * built the embedding). MPM_OK, or MPM_ERR_NOMEM when out of memory. */
mpm_status mpm_domain_hessian_init(mpm_domain_hessian *h, mpm_domain_set *s,
                                   const mpm_material *materials, mpm_arena *arena);
/* F^ at the DOF displacement u (NULL: u = 0, F^ = F). */
void mpm_domain_hessian_displace(mpm_domain_hessian *h, mpm_real *const u[3]);
/* The per-particle factored stress derivative at F^ (definite unless h->exact). */
void mpm_domain_hessian_build(mpm_domain_hessian *h);
/* y += scale K x (x, y over the DOF set). */
void mpm_domain_hessian_apply(mpm_domain_hessian *h, mpm_real scale, mpm_real *const x[3],
                              mpm_real *const y[3]);
/* f += the elastic forces at F^. */
void mpm_domain_hessian_forces(mpm_domain_hessian *h, mpm_real *const f[3]);
/* sum_p V_p^0 Psi(F^_p), J. */
double mpm_domain_hessian_energy(const mpm_domain_hessian *h);
/* d += scale diag(K). */
void mpm_domain_hessian_diagonal(mpm_domain_hessian *h, mpm_real scale, mpm_real *const d[3]);

#endif
