/* heat.h - heat transfer on the DOF set: per-particle temperature carried to the grid, an
 * explicit conduction step on the grid nodes with the heat sources as boundaries, and the
 * result carried back (Stomakhin et al. 2014 sec. 4 simplified: one phase-independent heat
 * capacity and conductivity per material, no latent heat; Zhu et al. 2017 Fig. 11 melts a bunny
 * this way).
 *
 * With heat capacity C_p = m_p c_p, volume V_p = J_p V_p^0 and the B-spline weights w_ip of the
 * standard particles' kernel (every particle carries heat through the grid at its position,
 * domain particles too: heat does not need the corners):
 *   P2G        C_i = sum_p w_ip C_p, V_i = sum_p w_ip V_p, (V k)_i = sum_p w_ip V_p k_p, and
 *              C_i T_i = sum_p w_ip C_p (T_p + g_p . (x_i - x_p)): APIC's affine P2G for a
 *              scalar (Jiang et al. 2015), g_p the gradient of a first plain P2G's field, so that
 *              a node beside a face or a source carries the temperature at its own place
 *   sources    nodes inside a heat-source collider's solid are held: ghosts whose value continues
 *              the material's temperature linearly through the surface, where it is the
 *              source's (ghost fluid, Fedkiw et al. 1999), for the transfers back
 *   conduction C_i dT_i/dt = sum_j G_ij (T_j - T_i) + sum_s G_is (T_s - T_i) over the 6 axis
 *              neighbours: G_ij = dx min(f_i, f_j) k_ij with f = V_i / dx^3 the material's
 *              volume fraction at the node and k_ij the harmonic mean of the nodes' (V k) / V
 *              (the 7-point Laplacian in the bulk; a free surface insulated); a neighbour inside
 *              a source is its surface at theta = phi_i / (phi_i - phi_j) of the link (Gibou et
 *              al. 2002), conductance dx a k_i / theta, a the material's share of the link's
 *              face. Explicit, in substeps within the operator's own bound (sum_j G_ij / C_i),
 *              so each substep is a convex combination: no new extremes
 *   G2P        PIC, T_p = sum_i w_ip T_i, blended with FLIP, T_p + sum_i w_ip (T_i - T_i^P2G),
 *              by the share exp(-4 pic alpha dt / dx^2) (alpha = k / (rho c) of the particle's
 *              material): the particles relax to the grid's field at a rate per second, so the
 *              PIC share's smoothing does not grow as the step shrinks; with the affine P2G the
 *              two transfers' smoothing of a smooth profile cancels to leading order.
 * The total heat sum_p C_p T_p changes only through the sources: the links are antisymmetric,
 * the affine part of P2G sums to zero over the nodes (sum_i w_ip (x_i - x_p) = 0) and both G2P
 * transfers return what the nodes hold (tests/test_heat.c). Without sources the boundary is
 * insulated. tests/test_heat_boundary.c checks a slab against the semi-infinite solution: a
 * monotone, bounded profile, the same whether the surface lies on a node or between two.
 *
 * Carriers (one per particle of each set) and their weights are an embedding (grid/
 * embedding.h) from particles to DOFs, scheduled by the grid's stencil keys, so the scatters
 * are parallel and the same for any number of threads; the nodes' links find their neighbours
 * through the level's node boxes. */
#ifndef MPM_HEAT_HEAT_H
#define MPM_HEAT_HEAT_H

#include "mpm/mpm.h"
#include "collide/collider.h"
#include "grid/embedding.h"
#include "interp/kernel.h"
#include "material/material.h"
#include "grid/dofs.h"

#include <stddef.h>
#include <stdint.h>

/* A set of particles that carries heat: all of them, or those with active[i] != 0. */
typedef struct mpm_heat_set {
  mpm_particles *p;
  const uint8_t *active; /* NULL: every particle */
} mpm_heat_set;

typedef struct mpm_heat_step_desc {
  double dt;            /* s */
  mpm_real pic;         /* the PIC share's rate, in units of 4 alpha / dx^2 (heat.pic) */
  const mpm_grid *grid; /* the uniform level; its nodes must cover every particle's stencil */
  mpm_dofs *dofs;       /* laid out over the level */
  mpm_kernel kernel;
  mpm_real clamp_lo[3], clamp_hi[3]; /* particle positions clamped into these for stencils */
  const mpm_material *materials;
  int set_count;
  mpm_heat_set sets[2];
  /* the colliders acting this step: those with desc.heat_source hold their nodes */
  int pose_count;
  const mpm_collider_pose *poses;
} mpm_heat_step_desc;

/* What the last heat step did. */
typedef struct mpm_heat_figures {
  int substeps;      /* conduction substeps */
  size_t held_nodes; /* nodes held at a source's temperature */
  double seconds;    /* wall time */
} mpm_heat_figures;

/* Scratch kept between steps. */
typedef struct mpm_heat {
  mpm_embedding E;
  mpm_real *g[3]; /* per entry: grad w_ip, 1/m */
  size_t entry_capacity;
  /* per carrier */
  mpm_real *capacity, *heat, *vol, *vk, *cg[3], *cgx;
  int32_t *key;
  uint8_t *colour;
  size_t row_capacity;
  uint8_t *key_colour;
  size_t key_capacity;
  uint8_t *held; /* per DOF: held at a source */
  size_t held_capacity;
  /* the held nodes as ghosts (heat.c): each node, its depth in the source over dx, the
   * source's temperature and the stencil of its probe point (a free node's weight, or 0) */
  struct mpm_heat_ghost *ghosts;
  size_t ghost_count, ghost_capacity;
  /* per node of the level: its conduction links (heat.c) */
  struct mpm_heat_links *links;
  size_t link_capacity;
  size_t *box_slot; /* the level's node boxes by coordinate (heat.c: node_at) */
  size_t box_slots, box_slot_capacity;
  int32_t box_size[3];
  mpm_heat_figures figures;
} mpm_heat;

void mpm_heat_init(mpm_heat *h);
void mpm_heat_free(mpm_heat *h);

/* One heat step: the particles' temperatures advance by dt. MPM_OK; MPM_ERR_NOMEM when out of
 * memory; MPM_ERR_INVALID when a particle's stencil reaches a node the grid does not have (the
 * caller activates them). */
mpm_status mpm_heat_step(mpm_heat *h, const mpm_heat_step_desc *s);

/* The conduction substeps a step of dt needs in the bulk of the material: ceil(dt / (0.9 dx^2 /
 * (6 alpha_max))), alpha_max the largest k / (rho c) over the materials that conduct (1 when
 * none does); links to a source close to a node may take more (mpm_heat_figures.substeps). */
int mpm_heat_substeps(double dt, double dx, const mpm_material *materials, int material_count);

/* The total heat sum_p m_p c_p T_p of the particles of a set (double sums, in particle
 * order), J in the scene's temperature unit times J/K. */
double mpm_heat_total(const mpm_heat_set *set, const mpm_material *materials);

#endif
