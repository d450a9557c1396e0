/* operators.h - the transfers as separate, reusable operators (DESIGN.md, "Transfers as
 * operators").
 *
 * An explicit step uses the fused fast path (transfer.h: stress + scatter in one pass;
 * velocity, F, return map and advection in one pass). The implicit solve (Zhu et al. sec. 6,
 * eqs. 12-15; Stomakhin et al. 2013 sec. 4 for material points) needs the pieces alone, many
 * times per step, without moving particles:
 *   mass and momentum   m_i += sum_p w_ip m_p,
 *                       p_i += sum_p w_ip m_p (v_p + B_p D_p^{-1} (x_i - x_p))  (APIC part
 *                       with APIC; Gao sec. 3.2 step 1)
 *   stress divergence   f_i += -sum_p V_p^0 tau_p grad w_ip      (Gao sec. 3.2 step 2)
 *   matrix scatter      f_i += sum_p M_p grad w_ip               (the force differential of
 *                       Stomakhin eq. 6 with M_p = -V0 A_p F_p^T, A_p = dP/dF : dF_p)
 *   gradient gather     G_p = sum_i (u_i - u_ref) grad w_ip^T    (dF_p = dt G_p F_p; u_ref a
 *                       nearby node's value: exact for uniform fields, see operators.c)
 *   quadratic forms     d_i,a += sum_p grad w_ip^T Q_p^a grad w_ip   (the Jacobi diagonal,
 *                       Zhu eqs. 17-19, with Q^a = V0 F S^a F^T; scalar stencils)
 * The matrix scatter and the gradient gather are adjoint, sum_p <G_p(u), M_p> =
 * sum_i <u_i, f_i(M)>, which is what makes the implicit system's matrix symmetric
 * (tests/test_transfer_operators.c).
 *
 * Node arrays are those of one grid level (node n at index n: the level's view of the DOF set,
 * mpm_grid_values, or a solver vector offset by the level's dof_begin); per-particle matrices
 * are 9 arrays (row-major components) indexed like the particles. On the sparse grid the
 * particles must be sorted by the level's activation; the operators walk them with the batch
 * walk of batches.h as SIMD lanes, the scatters colour by colour (deterministic for any
 * number of threads). The dense reference grid uses plain scalar loops. */
#ifndef MPM_TRANSFER_OPERATORS_H
#define MPM_TRANSFER_OPERATORS_H

#include "mpm/mpm.h"
#include "transfer/transfer.h"

void mpm_p2g_mass_momentum(const mpm_transfer_ctx *ctx, const mpm_grid *g,
                           const mpm_grid_values *val, const mpm_particles *p);
void mpm_p2g_stress_force(const mpm_transfer_ctx *ctx, const mpm_grid *g, mpm_real *const f[3],
                          const mpm_particles *p);
void mpm_scatter_matrices(const mpm_transfer_ctx *ctx, const mpm_grid *g, mpm_real *const f[3],
                          const mpm_real *const M[9], const mpm_particles *p);
void mpm_gather_gradients(const mpm_transfer_ctx *ctx, const mpm_grid *g,
                          const mpm_real *const u[3], const mpm_particles *p, mpm_real *const G[9]);
/* Q: 18 arrays, the symmetric Q^a of component a in entries 6a .. 6a + 5 (xx, xy, xz, yy,
 * yz, zz). */
void mpm_scatter_quadratic_forms(const mpm_transfer_ctx *ctx, const mpm_grid *g,
                                 mpm_real *const d[3], const mpm_real *const Q[18],
                                 const mpm_particles *p);

/* The stiffness as a matrix of 3x3 node blocks (assemble.c): for every particle its linear map
 * of velocity gradients C[(a, c), (b, d)] (81 reals, row-major: M_ac = sum_bd C_ac,bd G_bd, as the
 * matrix scatter applies it) from `tangent`, and
 *   K_ij[a][b] += sum_p sum_cd C_p[(a, c), (b, d)] grad w_ip^c grad w_jp^d
 * added to the rows of the nodes the particles touch: node n of the grid (its own index, the
 * level's dof_begin not added) is row row_of[n] (-1: not stored), and the block of row r for the
 * node at offset o = x_j - x_i in [-radius, radius]^3 (radius >= kernel width - 1) is at
 * val + 9 ((r S) + ((o_x + radius) span + o_y + radius) span + o_z + radius), span = 2 radius + 1,
 * S = span^3, row-major. C must be symmetric (C_ac,bd = C_bd,ac): only pairs i <= j are formed,
 * and only the upper half of each row is added to: the blocks at the centre slot and after it
 * (offsets lexicographically >= 0); the caller fills the rest as K_ij = K_ji^T.
 * MPM_OK; MPM_ERR_INVALID on the dense grid (sparse grid only) or for a radius below the kernel
 * width - 1. */
mpm_status mpm_assemble_stiffness(const mpm_transfer_ctx *ctx, const mpm_grid *g,
                                  const mpm_particles *p, mpm_tangent_fn tangent, void *user,
                                  const int32_t *row_of, int radius, mpm_real *val);

/* The grid variants' own (operators.c holds the table, mpm_transfer_variant_of): the sparse
 * grid's mass and momentum P2G (p2g.c, the fused kernels without the force) and its assembly
 * (assemble.c). */
mpm_status mpm_assemble_stiffness_sparse(const mpm_transfer_ctx *ctx, const mpm_grid *g,
                                         const mpm_particles *p, mpm_tangent_fn tangent, void *user,
                                         const int32_t *row_of, int radius, mpm_real *val);
void mpm_p2g_mass_momentum_sparse(const mpm_transfer_ctx *ctx, const mpm_sparse_grid *g,
                                  const mpm_grid_values *val, const mpm_particles *p);

#endif
