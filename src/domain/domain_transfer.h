/* domain_transfer.h - the two-step transfers of particle domains (Zhu et al. 2017, sec. 4 and
 * Algorithm 1 without enrichment) on a grid level, through the grid interface (grid/grid.h):
 *   P2G  particle -> corner:  m_a = sum_p omega_ap m_p,  p_a = sum_p omega_ap m_p v_p,
 *                             f_a = -sum_p V_p^0 P_p g_ap        (Zhu eq. 8 through eq. 5)
 *        corner -> grid:      m_i += omega_i(x_a) m_a, and so on
 *   G2P  grid -> corner:      v^g_a = sum_i omega_i(x_a) v_i^{n+1}, and the hybrid PIC/FLIP
 *                             corner velocity; colliders on the corners (Zhu sec. 7)
 *        particle:            F_p += dt sum_a v^g_a g_ap^T           (Zhu eq. 7)
 *        corner:              x_a += dt v^g_a                        (Zhu eq. 9)
 *        particle:            x_p = sum_a omega_ap x_a, v_p = sum_a omega_ap v_a
 * With solver.transfer "flip" the corner velocity is the scene's PIC/FLIP blend (flip_alpha 0:
 * PIC). With "apic" (Jiang et al. 2015) the corners are the carriers of the grid transfer: a
 * corner keeps its own velocity v_a and an affine moment B_a = sum_i omega_i(x_a) v_i (x_i -
 * x_a)^T from the grid, P2G gives it the momentum m_a v_a (= sum_p omega_ap m_p v_p, as v_p
 * interpolates the corners: no average over its particles) and spreads m_a (v_a + C_a (x_i -
 * x_a)) to the grid, C_a = B_a D_a^-1; G2P gives it the grid's velocity and B_a. Linear and
 * angular momentum then pass corner -> grid -> corner as through APIC's particles; an
 * enriched corner, its own DOF, keeps its velocity exactly (B_a = 0).
 * omega_i is the engine's kernel given (Zhu's linear hat by default). The particle -> corner
 * gathers go through the corner adjacency (race-free, deterministic); corner -> grid and grid
 * -> corner are the embedding operator E (grid/embedding.h) with rows omega_i(x_a), applied as
 * E^T (a coloured, deterministic parallel scatter) and as E. */
#ifndef MPM_DOMAIN_DOMAIN_TRANSFER_H
#define MPM_DOMAIN_DOMAIN_TRANSFER_H

#include "mpm/mpm.h"
#include "collide/boundary.h"
#include "domain/domain.h"
#include "grid/grid.h"
#include "transfer/transfer.h"

/* Activate the grid level's nodes around every used corner's stencil (after the activation from
 * the standard particles, before the DOF layout). MPM_OK, or MPM_ERR_NOMEM when out of memory. */
mpm_status mpm_domain_activate(mpm_domain_set *s, mpm_grid *g, const mpm_kernel *k);

/* The corner -> grid transfers' plan for this step, from the corners' positions (after
 * mpm_domain_activate): on a sparse level, unless the step applies the embedding as a matrix
 * (s->corner_rows: the implicit Hessian), the corners go to the grid through pads of nodes
 * (domain/corner_pads.h, s->pads.on); otherwise P2G builds the embedding's rows. MPM_OK;
 * MPM_ERR_NOMEM when out of memory; MPM_ERR_INVALID when a corner's block is missing (not after
 * mpm_domain_activate). */
mpm_status mpm_domain_plan(mpm_domain_set *s, const mpm_grid *g, const mpm_kernel *k,
                           mpm_arena *scratch);

/* After mpm_domain_plan: when the corners' numbers have come apart from the pads' order,
 * renumber the corners into it (mpm_domain_set_permute_corners) and plan again; *order is then
 * the permutation (new -> old, step scratch) for copies of corner arrays held elsewhere, else
 * NULL. The decision follows from the state alone (a resumed run takes the same). MPM_OK, or
 * mpm_domain_plan's failure (MPM_ERR_NOMEM when out of memory). */
mpm_status mpm_domain_order_corners(mpm_domain_set *s, const mpm_grid *g, const mpm_kernel *k,
                                    mpm_arena *scratch, uint32_t **order);

/* Rasterize the domain particles to their corners, and the corners to grid level g (its
 * DOFs from g->dof_begin) through the corners' embedding (s->corner_grid, built here): the DOF
 * set's mass, momentum (v0) and force (dof: the values of all DOFs, DOF 0 at index 0); the
 * particles' stresses and the scatter schedule's keys are step scratch (ctx: kernel,
 * origin, materials). MPM_OK; MPM_ERR_NOMEM when out of memory (nothing added to the grid then);
 * MPM_ERR_INVALID when a corner's stencil meets a node that is not active (not after
 * mpm_domain_activate). */
mpm_status mpm_domain_p2g(const mpm_transfer_ctx *ctx, mpm_domain_set *s, const mpm_grid *g,
                          const mpm_grid_values *dof, mpm_arena *scratch);

/* After the grid update (the DOF set holds v^n in v0 and v^{n+1} in v; dof as for P2G): the
 * corners' velocities through their embedding, the boundary rules (colliders at the end of
 * the step, walls) at the corners, then corners and particles. */
mpm_g2p_result mpm_domain_g2p(const mpm_transfer_ctx *ctx, mpm_domain_set *s,
                              const mpm_grid_values *dof, const mpm_boundary *boundary);

/* F_p^{n+1} = F_p^n + dt grad_X v (Zhu eq. 7) of particle q from the grid velocities vg at its
 * corners (by corner), as mpm_domain_g2p does it; exposed for tests. */
void mpm_domain_update_F(mpm_domain_set *s, size_t q, mpm_real dt, const mpm_real *const vg[3]);

#endif
