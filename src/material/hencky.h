/* hencky.h - private to src/material/: the St. Venant-Kirchhoff energy in Hencky strain
 * (Gao et al. 2017 eq. 7), shared by hencky_stvk.c, drucker_prager.c and von_mises.c.
 *
 *   Psi = mu tr(eps^2) + lambda/2 (tr eps)^2,  eps = log(sigma) (principal Hencky strain).
 *
 * Inverted and degenerate F: with signed singular values (core/svd3.h) sigma_3 < 0 when
 * det F < 0. The energy is evaluated on c_i = max(|sigma_i|, MPM_HENCKY_FLOOR), i.e. the
 * mirror image of the inverted particle (the Hencky energy is +inf at sigma = 0, so a smooth
 * motion never crosses it; a particle that arrives inverted behaves like its reflection and is
 * returned to det > 0 by the next plastic projection of drucker_prager.c / von_mises.c).
 * Below the floor the stress is frozen at its value at the floor (P continuous) and the energy
 * is extended to first order: Psi = psi(c) + sum_i h_i (|sigma_i| - c_i), h_i = dpsi/dc_i.
 *
 *   P   = U diag(g) V^T,  g_i = sign(sigma_i) h_i,  h_i = (2 mu eps_i + lambda tr eps) / c_i,
 *   tau = P F^T = U diag(h_i |sigma_i|) U^T  (= U diag(2 mu eps + lambda tr eps) U^T).
 *
 * dP/dF (isotropic.h): A_ij = s_i s_j H_ij with s_i = sign(sigma_i),
 *   H_ii = (2 mu + lambda - 2 mu eps_i - lambda tr eps) / c_i^2,  H_ij = lambda / (c_i c_j);
 * the pair quotients in terms of c: D- = (h_i - h_j) / (c_i - c_j) =
 *   2 mu (c_j L(c_i, c_j) - eps_j) / (c_i c_j) - lambda tr eps / (c_i c_j),  L = divided
 * difference of log (isotropic.h), and D+ = (h_i + h_j) / (c_i + c_j) (c_i + c_j > 0); for
 * equal signs l_sym = D-, l_skew = D+, for opposite signs the two swap. All are evaluated at c
 * (in the clamped region this is the Hessian at the floor, as Zhu eq. 16 does for clamps). */
#ifndef MPM_MATERIAL_HENCKY_H
#define MPM_MATERIAL_HENCKY_H

#include "material/isotropic.h"
#include "material/material.h"

/* Smallest |sigma| the Hencky strain is evaluated at (log(1e-6) = -13.8). */
#define MPM_HENCKY_FLOOR R_(1e-6)

mpm_real mpm_hencky_energy(const mpm_material *m, const mpm_real F[9]);
void mpm_hencky_pk1(const mpm_material *m, const mpm_real F[9], mpm_real P[9]);
void mpm_hencky_dpdf_action(const mpm_material *m, const mpm_real F[9], const mpm_real dF[9],
                            mpm_real dP[9]);
void mpm_hencky_dpdf_action_definite(const mpm_material *m, const mpm_real F[9],
                                     const mpm_real dF[9], mpm_real dP[9]);
void mpm_hencky_hessian_definite(const mpm_material *m, const mpm_real F[9], mpm_stress_hessian *H);
/* P for n <= MPM_STRESS_CHUNK particles (the model's pk1_batch). */
void mpm_hencky_pk1_batch(const mpm_material *m, int n, const mpm_real *const F[9],
                          mpm_real P[9][MPM_STRESS_CHUNK]);
/* tau for n <= MPM_STRESS_CHUNK particles; the plastic state plays no role in the elasticity. */
void mpm_hencky_kirchhoff_batch(const mpm_material *m, int n, const mpm_real *const F[9],
                                const mpm_real *plastic, mpm_real tau[9][MPM_STRESS_CHUNK]);

#endif
