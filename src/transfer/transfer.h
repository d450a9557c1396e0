/* transfer.h - particle-to-grid (P2G) and grid-to-particle (G2P) transfers on the sparse and
 * dense grids, with APIC or the PIC/FLIP blend (Gao sec. 3.2 steps 1, 2, 5, 6).
 *
 * P2G accumulates per node: mass m_i = sum m_p w_ip, momentum sum w_ip m_p (v_p + C_p (x_i -
 * x_p)) (the affine term only with APIC; C_p = B_p D_p^{-1}) and force f_i = -sum V_p^0 tau_p grad
 * w_ip with the Kirchhoff stress tau = P F^T, which equals Gao's -sum V^0 J sigma grad w (step 2).
 * G2P gathers the new grid velocity: the PIC velocity, the FLIP increment, the velocity
 * gradient for F^{n+1} = (I + dt grad v) F^n (step 5), APIC's B_p, and advects x_p (step 6). */
#ifndef MPM_TRANSFER_TRANSFER_H
#define MPM_TRANSFER_TRANSFER_H

#include "core/lanes.h"
#include "core/particles.h"
#include "grid/grid.h"
#include "interp/kernel.h"
#include "material/material.h"

/* APIC across the levels of the multi-level grid (adaptive/apic.c), for one transfer grid:
 * its cells whose stencils reach ghost nodes of several real nodes (boundary cells) and what their
 * particles need beyond the lanes' transfer (transfer/ghost_apic_lanes.h). */
typedef struct mpm_stencil_ghost {
  uint32_t node;  /* the stencil node (i, j, k), 4 bits each */
  uint32_t ghost; /* its ghost */
} mpm_stencil_ghost;

typedef enum mpm_transfer_kind {
  MPM_TRANSFER_APIC = 0, /* affine PIC (Jiang et al. 2015) */
  MPM_TRANSFER_FLIP = 1, /* PIC/FLIP blend with ratio flip_alpha (Gao sec. 3.2 step 6) */
} mpm_transfer_kind;

#define MPM_NOT_BOUNDARY UINT32_MAX

typedef struct mpm_ghost_apic {
  const uint32_t *cell_of;     /* per cell q of the grid (cell_start's numbering): its boundary
                                  cell c, or MPM_NOT_BOUNDARY */
  const uint32_t *entry_start; /* cell c's entries: entry[entry_start[c] .. entry_start[c + 1]) */
  const mpm_stencil_ghost *entry;
  const mpm_real *spread; /* P2G: per ghost sum_i r_gi (x_i - x_g)(x_i - x_g)^T, 6 (xx yy zz xy
                             xz yz), m^2 */
  mpm_real *affine;       /* P2G adds per entry e sum_p w_ep m_p C_p (9, row-major), kg/s */
  const mpm_real *moment; /* G2P: per ghost sum_i r_gi v_i (x_i - x_g)^T, 9 interleaved */
} mpm_ghost_apic;

typedef struct mpm_transfer_ctx {
  mpm_kernel kernel;
  mpm_real origin[3]; /* grid node (0,0,0), m */
  mpm_real dt;        /* s */
  mpm_transfer_kind transfer;
  mpm_real flip_alpha;
  const mpm_material *materials;
  int material_count;
  mpm_real clamp_lo[3], clamp_hi[3]; /* particles are kept inside this box, m */
  /* P2G on the sparse grid with APIC folds dt f into the momentum (Gao sec. 6.2's fused
   * kernel); the force is then not accumulated (mpm_p2g_output in solver/explicit_update.h) */
  const mpm_ghost_apic *ghost_apic; /* APIC across levels on this grid, or NULL (sparse only) */
} mpm_transfer_ctx;

/* What G2P reports back for the next step and for blow-up detection. */
typedef struct mpm_g2p_result {
  mpm_real max_speed; /* max |v_p|, m/s */
  long bad_particle;  /* index of a particle with a non-finite value, or -1 */
} mpm_g2p_result;

/* P2G adds the particles' mass, momentum and (unless fused) force to the level's values
 * (mass, v0, f of mpm_grid_values); G2P reads v (and v0 for FLIP) and updates the particles.
 * Both dispatch on the grid's variant. The sparse versions visit particles in the order
 * g->perm of the last activation; the dense reference is serial in particle order for P2G. */
void mpm_p2g(const mpm_transfer_ctx *ctx, const mpm_grid *g, const mpm_grid_values *val,
             const mpm_particles *p);
mpm_g2p_result mpm_g2p(const mpm_transfer_ctx *ctx, const mpm_grid *g, const mpm_grid_values *val,
                       mpm_particles *p);

/* 1 when P2G on grid g with ctx folds the force into the momentum (sparse grid, APIC). */
int mpm_p2g_fuses_force(const mpm_transfer_ctx *ctx, const mpm_grid *g);

/* The transfers of one grid variant (the sparse paged grid, the dense reference), one table
 * each, chosen by mpm_transfer_variant_of (operators.c) once per call: P2G and G2P here, the
 * operators of operators.h, the assembly. */
/* The stiffness assembly's particle tangents, a batch of MPM_LANES at once: C[k] lane l is
   entry k of particle[l]'s 9 x 9 map (operators.h); lanes from count on are ignored. */
typedef void (*mpm_tangent_fn)(void *user, const uint32_t particle[MPM_LANES], int count,
                               mpm_vl C[81]);
typedef struct mpm_transfer_variant {
  int fuses_force; /* its APIC P2G folds dt f into the momentum */
  void (*p2g)(const mpm_transfer_ctx *ctx, const mpm_grid *g, const mpm_grid_values *val,
              const mpm_particles *p);
  mpm_g2p_result (*g2p)(const mpm_transfer_ctx *ctx, const mpm_grid *g, const mpm_grid_values *val,
                        mpm_particles *p);
  void (*mass_momentum)(const mpm_transfer_ctx *ctx, const mpm_grid *g, const mpm_grid_values *val,
                        const mpm_particles *p);
  void (*stress_force)(const mpm_transfer_ctx *ctx, const mpm_grid *g, mpm_real *const f[3],
                       const mpm_particles *p);
  void (*scatter_matrices)(const mpm_transfer_ctx *ctx, const mpm_grid *g, mpm_real *const f[3],
                           const mpm_real *const M[9], const mpm_particles *p);
  void (*scatter_quadratic_forms)(const mpm_transfer_ctx *ctx, const mpm_grid *g,
                                  mpm_real *const d[3], const mpm_real *const Q[18],
                                  const mpm_particles *p);
  void (*gather_gradients)(const mpm_transfer_ctx *ctx, const mpm_grid *g,
                           const mpm_real *const u[3], const mpm_particles *p,
                           mpm_real *const G[9]);
  mpm_status (*assemble_stiffness)(const mpm_transfer_ctx *ctx, const mpm_grid *g,
                                   const mpm_particles *p, mpm_tangent_fn tangent, void *user,
                                   const int32_t *row_of, int radius, mpm_real *val);
} mpm_transfer_variant;
const mpm_transfer_variant *mpm_transfer_variant_of(const mpm_grid *g);

void mpm_p2g_sparse(const mpm_transfer_ctx *ctx, const mpm_sparse_grid *g,
                    const mpm_grid_values *val, const mpm_particles *p);
mpm_g2p_result mpm_g2p_sparse(const mpm_transfer_ctx *ctx, const mpm_sparse_grid *g,
                              const mpm_grid_values *val, mpm_particles *p);
void mpm_p2g_dense(const mpm_transfer_ctx *ctx, const mpm_dense_grid *g, const mpm_grid_values *val,
                   const mpm_particles *p);
mpm_g2p_result mpm_g2p_dense(const mpm_transfer_ctx *ctx, const mpm_dense_grid *g,
                             const mpm_grid_values *val, mpm_particles *p);

#endif
