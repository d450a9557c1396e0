/* heat.h - heat transfer on the DOF set: per-particle temperature carried to the grid, an
 * explicit conduction step on the grid nodes, and the change carried back (Stomakhin et al.
 * 2014 sec. 4 simplified: one phase-independent heat capacity and conductivity per material,
 * no latent heat; Zhu et al. 2017 Fig. 11 melts a bunny this way).
 *
 * With heat capacity C_p = m_p c_p and the B-spline weights w_ip of the standard particles'
 * kernel (every particle carries heat through the grid at its position, domain particles
 * too: heat does not need the corners):
 *   P2G        C_i = sum_p w_ip C_p,   T_i = sum_p w_ip C_p T_p / C_i
 *   sources    nodes inside a heat-source collider's solid are held at its temperature
 *   conduction C_i dT_i/dt = -sum_p V_p k_p grad w_ip . grad T_p,  grad T_p = sum_j T_j grad w_jp
 *              (the weak form of C dT/dt = div(k grad T); V_p = J_p V_p^0), explicit in
 *              substeps of at most 1/4 dx^2 / alpha, alpha = k / (rho c) the largest diffusivity
 *   G2P        T_p += sum_i w_ip (T_i^end - T_i^P2G)   (FLIP: no numerical diffusion), blended
 *              with the fraction `pic` of T_p = sum_i w_ip T_i^end (PIC: damps the
 *              overshoot of FLIP where material moves past a source); a particle touching a
 *              held node takes the PIC value (see heat.c). Both conserve the total heat:
 *              sum_p C_p sum_i w_ip T_i = sum_i C_i T_i.
 * The total heat sum_p C_p T_p changes only through the sources: sum_i grad w_ip = 0 for
 * every particle, so the conduction fluxes cancel, and the G2P increment returns exactly what
 * the nodes gained (tests/test_heat.c). Without sources the boundary is insulated.
 *
 * Carriers (one per particle of each set) and their weights are an embedding (grid/
 * embedding.h) from particles to DOFs, scheduled by the grid's stencil keys, so the scatters
 * are parallel and the same for any number of threads. */
#ifndef MPM_HEAT_HEAT_H
#define MPM_HEAT_HEAT_H

#include "collide/collider.h"
#include "grid/embedding.h"
#include "interp/kernel.h"
#include "material/material.h"
#include "solver/dofs.h"

#include <stddef.h>
#include <stdint.h>

/* A set of particles that carries heat: all of them, or those with active[i] != 0. */
typedef struct mpm_heat_set {
  mpm_particles *p;
  const uint8_t *active; /* NULL: every particle */
} mpm_heat_set;

typedef struct mpm_heat_step_desc {
  double dt;            /* s */
  mpm_real pic;         /* the PIC fraction of the G2P temperature, [0, 1] (heat.pic) */
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
  mpm_real *capacity, *heat, *vk, *flux[3], *zero;
  int32_t *key;
  uint8_t *colour;
  size_t row_capacity;
  uint8_t *key_colour;
  size_t key_capacity;
  uint8_t *held; /* per DOF: held at a source */
  size_t held_capacity;
  mpm_heat_figures figures;
} mpm_heat;

void mpm_heat_init(mpm_heat *h);
void mpm_heat_free(mpm_heat *h);

/* One heat step: the particles' temperatures advance by dt. 0; -1 when out of memory; -2 when
 * a particle's stencil reaches a node the grid does not have (the caller activates them). */
int mpm_heat_step(mpm_heat *h, const mpm_heat_step_desc *s);

/* The conduction substeps a step of dt needs: ceil(dt / (dx^2 / (4 alpha_max))), alpha_max the
 * largest k / (rho c) over the materials that conduct (1 when none does). */
int mpm_heat_substeps(double dt, double dx, const mpm_material *materials, int material_count);

/* The total heat sum_p m_p c_p T_p of the particles of a set (double sums, in particle
 * order), J in the scene's temperature unit times J/K. */
double mpm_heat_total(const mpm_heat_set *set, const mpm_material *materials);

#endif
