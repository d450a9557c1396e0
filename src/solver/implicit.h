/* implicit.h - the implicit velocity update on the DOF set (Zhu et al. 2017 sec. 6; Stomakhin
 * et al. 2013 sec. 4 for material points; Gast et al. 2015 for the Newton iterations).
 *
 * Backward Euler on the grid is the minimization of the incremental potential
 *   E(v) = sum_i 1/2 m_i |v_i - v_i^n|^2 - dt sum_i m_i g . v_i + Phi(x + dt v),
 * Phi the elastic energy of every material point and particle domain at the grid displaced by
 * u = dt v. Its gradient is m (v - v^n) - dt m g - dt f(u), its Hessian M + dt^2 K(u) with
 * K = -df/du. One Newton step from u = 0 is Zhu's eq. 12,
 *   (M + dt^2 K) v = M v*,  v* = v^n + dt (g + f^n / m)          (eqs. 12-13, times M)
 * (the mass-weighted form of (I + dt^2 M^-1 K) v = v*: symmetric, so CG applies). More
 * iterations (newton_iterations > 1) solve (M + dt^2 K(u_k)) dv = -grad E(v_k) and take the
 * longest step of a backtracking line search that lowers E (Armijo, halving).
 *
 * Newmark's scheme with beta = 1/2, gamma = 1 (solver.scheme "newmark", theta = 1/2 below) moves
 * the grid by the mean of the step's velocities, u = dt (v^n + v) / 2, and balances the forces
 * there: m (v - v^n) = dt m g + dt f(u). It is the minimization of
 *   E(v) = sum_i 1/2 m_i |v_i - v_i^n - dt g|^2 + Phi(x + u(v)) / theta,
 * Hessian M + theta dt^2 K, and everything above holds with u(0) = dt (1 - theta) v^n for 0 and
 * f at it for f^n. Backward Euler's positions lag a free fall by g dt^2 / 2 a step (at 1/60 s,
 * 1.4 mm: a rubber bunny thrown onto a floor landed 9 mm off the explicit run's path); Newmark's
 * are exact in free fall, and a mode of frequency omega keeps (1 + (omega dt)^2 / 2)^(-1/2) of
 * its amplitude a step where backward Euler keeps (1 + (omega dt)^2)^(-1/2): stable for any dt,
 * and it still damps what the step cannot resolve. G2P moves and deforms the particles by
 * v_m = u / dt (the DOF set's vm) and gives them v. Only in steps where no obstacle or wall acts
 * at a DOF with mass (implicit.c, touches()); a step in contact is backward Euler: with
 * Newmark's weaker damping a rubber bunny landing at the CFL rate rebounded faster than the
 * step allowed (the guard stopped it), and resting on a floor with friction it gained strain.
 *
 * K is matrix-free (implicit_hessian.c):
 *   material points  K du = sum_p V_p^0 (C_p : G_p F_p) F_p^T grad w_ip, G_p = sum_j du_j grad
 * w_jp^T (gather_gradients -> stress differential -> scatter_matrices) particle domains the
 * reference-configuration form, eqs. 14-15 (domain/domain_hessian.h) with C_p = dP/dF at the
 * displaced F, made positive semi-definite per particle in the SVD space (eq. 16, the models'
 * hessian_definite), factored once per Newton iteration. The Jacobi preconditioner is the diagonal
 * of M + dt^2 K with the same definite C (eqs. 17-19).
 *
 * Boundary conditions (collide/boundary.h) act inside the solve: a DOF in a sticky obstacle
 * has its velocity fixed to the obstacle's; in a slip obstacle, or in a separating one that the
 * predicted velocity v* moves into, the normal component is fixed and projected out of CG's
 * residual and search directions; where an obstacle with friction stops the step's motion
 * v^n + dt g, the whole velocity is fixed to what Coulomb's rule makes of that motion (held by
 * static friction, slowed by kinetic), so that the elastic solve sees the contact as it will
 * be. After the solve the full boundary rule runs on every DOF with the normal velocity of v*
 * restored first on the other constrained ones: that is where separation acts.
 *
 * On Gao et al.'s multi-level grid (adaptive/adaptive.h) the material points transfer in parts, one
 * per transfer grid, and every slot of a transfer grid is a real node (a DOF of the system) or a
 * ghost whose row E_g ties it to real nodes (adaptive/grid.h). The unknowns are the real
 * nodes of every level; the system is the slots' one pulled back through the rows,
 *   K = E^T K_slots E,  f = E^T f_slots,
 * so that displacements are gathered to the ghosts before the gradients and the scattered forces
 * go from the ghosts to their parents after (Gao eq. 15, as in the explicit step's P2G): K stays
 * symmetric, and definite where K_slots is. The Jacobi diagonal takes diag(E^T diag(K_slots) E).
 * Ghosts hold no mass, so CG leaves them at zero.
 *
 * Plasticity: the particles' F is the elastic part; the Hessian is that of the elastic energy
 * at the elastic F, and the return map runs after the F update in G2P, as in the explicit step. */
#ifndef MPM_SOLVER_IMPLICIT_H
#define MPM_SOLVER_IMPLICIT_H

#include "mpm/mpm.h"
#include "collide/body_force.h"
#include "collide/boundary.h"
#include "core/arena.h"
#include "domain/domain_hessian.h"
#include "adaptive/grid.h"
#include "solver/cg.h"
#include "grid/dofs.h"
#include "solver/multigrid.h"
#include "transfer/transfer.h"

typedef struct mpm_implicit_options {
  int newton_iterations; /* >= 1; 1 = Zhu's single linearized step */
  double cg_tolerance;   /* relative residual */
  int cg_max_iterations;
  /* 1: Jacobi (eqs. 17-19); 2: multigrid (solver/multigrid.h) where it is built
     (mpm_implicit_multigrid_supported), else Jacobi; 0: none (benchmarks) */
  int precondition;
} mpm_implicit_options;

typedef struct mpm_implicit_result {
  int newton_iterations; /* taken */
  int cg_iterations;     /* over all Newton iterations */
  double cg_residual;    /* the largest final relative residual of the Newton iterations */
  int cg_converged;      /* every CG solve reached the tolerance */
  int line_search_failed;
  double mg_setup_seconds, mg_cycle_seconds; /* multigrid: the hierarchy's build, the V-cycles */
  size_t mg_bytes;                           /* multigrid: the hierarchy's memory */
} mpm_implicit_result;

/* Material points of p in begin .. begin + count (sorted into `grid` by its activation) that
 * transfer on `grid` with `kernel`. */
typedef struct mpm_implicit_part {
  const mpm_grid *grid;
  mpm_kernel kernel;
  size_t begin, count;
} mpm_implicit_part;

/* The system of one step. The caller fills the inputs; mpm_implicit_init allocates scratch. */
typedef struct mpm_implicit {
  /* inputs */
  mpm_real dt;
  /* the positions' weight of the step's end (0 or unset: 1): the grid moves by
   * u = dt ((1 - theta) v^n + theta v), backward Euler at 1, at 1/2 Newmark's scheme with
   * beta = 1/2, gamma = 1 (see above; the solve sets it to 1 in a step with contact) */
  mpm_real theta;
  mpm_real gravity[3];
  int region_count; /* body-force regions on top of gravity (collide/body_force.h) */
  const mpm_force_region *regions;
  mpm_dofs *dofs; /* after P2G: mass, momentum (v0), force at u = 0 (f) */
  const mpm_transfer_ctx *tc;
  const mpm_grid *grid; /* material points: one level, its DOFs from grid->dof_begin */
  const mpm_particles *p;
  /* or, on the multi-level grid, parts (in place of grid: part_count 0 is one part, grid with
   * tc->kernel over all of p) and the ghost rows (NULL: no ghosts) */
  int part_count;
  mpm_implicit_part part[MPM_TRANSFER_GRIDS_MAX];
  mpm_adaptive_grid *levels;
  mpm_domain_set *domains; /* NULL or a set with active particles (its embedding built) */
  const mpm_boundary *boundary;
  int exact; /* 1: K is the model's own dP/dF (finite-difference tests), not the definite one */
  /* scratch */
  mpm_arena *arena;
  /* per material point, structure of arrays: the factored definite dP/dF at F^ with the
   * particle's F folded in, U, W = F V, A (xx, xy, xz, yy, yz, zz), lsym, lskew, so that the
   * action's matrix M = V0 (C : G F) F^T is U P^(U^T G W) W^T: four 3x3 products, vectorized
   * across particles */
  mpm_real *hU[9], *hW[9], *hA[6], *hs[3], *hk[3];
  mpm_real *Fh[9]; /* per material point: F at the displacement */
  mpm_real *G[9];  /* per material point: gathered gradients, then scattered matrices */
  mpm_domain_hessian dh;
  /* the constraints: DOF index, the projector I - sum n n^T (xx, xy, xz, yy, yz, zz), and
     whether friction holds the DOF (boundary.h: its velocity is the friction rule's) */
  size_t constraint_count;
  uint32_t *constraint_dof;
  mpm_real (*constraint_P)[6];
  uint8_t *constraint_friction;
  mpm_real apply_scale; /* theta dt^2 in CG's operator */
  mpm_real *px[3];      /* DOF positions (built with the constraints), m */
  size_t corner_begin;  /* the first corner DOF (DOFs from here are constrained ahead) */
  mpm_real *depth;      /* DOF wall-band depths (grid/dofs.h) */
  mpm_real *accel[3];   /* with body-force regions: each DOF's gravity plus regions, m/s^2 */
  mpm_real *drag;       /* with regions that drag: each DOF's drag rate, 1/s (else NULL) */
  mpm_real **ghosted;   /* on levels: a DOF vector with its ghosts gathered (E u) */
  /* the multigrid preconditioner (implicit_multigrid.c): the hierarchy, each grid node's row on
     its finest level (-1: no mass) and each row's DOF */
  struct mpm_multigrid *mg;
  int32_t *mg_row_of;
  uint32_t *mg_dof;
  double mg_cycle_seconds; /* the V-cycles' wall time in this step */
  int mg_wanted, mg_built; /* this step: the multigrid preconditions its solves; it is built */
  int mg_prepared;         /* this step: its hierarchy (rows, levels) is laid out */
  int mg_stale;            /* its values are to be rebuilt at the current iterate */
  int newmark;             /* the step was asked for Newmark's positions (theta < 1 at its start) */
} mpm_implicit;

/* Scratch for the step (from s->arena). MPM_OK, or MPM_ERR_NOMEM when out of memory. */
mpm_status mpm_implicit_init(mpm_implicit *s);

/* The whole implicit update: v0 <- v^n, v <- v^{n+1} on every DOF (like the explicit update),
 * boundary rules applied. MPM_OK, or MPM_ERR_NOMEM when out of memory. */
mpm_status mpm_implicit_solve(mpm_implicit *s, const mpm_implicit_options *o,
                              mpm_implicit_result *r);

/* The pieces, for tests and benchmarks (u: a displacement over the DOF set):
 * displace   F^ = (I + G(u)) F (material points), F + sum u_a g^T (domains); u NULL: u = 0
 * build      the factored (definite) stress derivatives at F^
 * apply      y = mass_scale m x + scale K x, projected when project is set
 * forces     f = the elastic forces at F^
 * energy     the elastic energy at F^
 * diagonal   d = mass_scale m + scale diag(K) */
void mpm_implicit_displace(mpm_implicit *s, mpm_real *const u[3]);
void mpm_implicit_build(mpm_implicit *s);
void mpm_implicit_apply(mpm_implicit *s, mpm_real mass_scale, mpm_real scale, mpm_real *const x[3],
                        mpm_real *const y[3]);
void mpm_implicit_forces(mpm_implicit *s, mpm_real *const f[3]);
double mpm_implicit_energy(mpm_implicit *s);
void mpm_implicit_diagonal(mpm_implicit *s, mpm_real mass_scale, mpm_real scale,
                           mpm_real *const d[3]);
/* The linear maps of velocity gradients in the action of dt^2 K (apply_scale) of the particles
 * idx[0 .. count), one per lane (lanes past count: the first particle's): C with
 * M_ac = sum_bd C[9 (3 a + c) + 3 b + d] G_bd, M = apply_scale V0 (C_i : G F) F^T, the factored
 * definite derivative (or the model's own in exact mode) after mpm_implicit_build. */
void mpm_implicit_tangent(const mpm_implicit *s, const uint32_t idx[MPM_NLANES], int count,
                          mpm_vn C[81]);

/* The multigrid preconditioner (implicit_multigrid.c): whether it is built for this system (one
 * sparse grid of material points: not yet on the multi-level grid nor with particle domains);
 * its hierarchy for the step's nodes with mass (after mpm_implicit_init); its matrices at the
 * displacement of the last mpm_implicit_build, with the constraints of the last
 * mpm_implicit_constraints; and z = B r, CG's preconditioner (user: the mpm_implicit). The
 * preparation and the build: MPM_OK, or MPM_ERR_NOMEM when out of memory (the build also
 * MPM_ERR_INVALID where it is not supported: mpm_assemble_stiffness). */
int mpm_implicit_multigrid_supported(const mpm_implicit *s);
mpm_status mpm_implicit_multigrid_prepare(mpm_implicit *s);
mpm_status mpm_implicit_multigrid_build(mpm_implicit *s);
void mpm_implicit_multigrid_precondition(void *user, mpm_real *const r[3], mpm_real *const z[3]);

/* CG on (M + dt^2 K) x = b from x, its figures added to r (the last part's in cg), with Jacobi
 * (diagonal D) or, where s->mg_wanted, the multigrid built here when first needed (`near`: the
 * solve starts near balance, and a few Jacobi iterations may end it first). implicit_multigrid.c
 * says the policy. MPM_OK, or MPM_ERR_NOMEM when out of memory. */
mpm_status mpm_implicit_pcg(mpm_implicit *s, mpm_real *const D[3], mpm_real *const b[3],
                            mpm_real *const x[3], int near, const mpm_cg_options *o,
                            mpm_implicit_result *r, mpm_cg_result *cg);
/* After a Newton iteration's solve of `iterations`: marks the multigrid's values stale where
 * the solve took long enough that the matrix has moved far from the one they were built for. */
void mpm_implicit_multigrid_mark(mpm_implicit *s, int iterations);

/* Build the constraints from the predicted velocity v (over the DOF set). MPM_OK, or
 * MPM_ERR_NOMEM when out of memory. */
mpm_status mpm_implicit_constraints(mpm_implicit *s, mpm_real *const v[3]);
/* v = P v at the constrained DOFs. */
void mpm_implicit_project(mpm_implicit *s, mpm_real *const v[3]);
/* After mpm_implicit_solve: add to taken[3 c + e] (pose c of s->boundary, component e) the
 * momentum collider c took from the DOFs in the step, kg m/s (implicit.c says how). Evaluates
 * the forces at the end of the step once more (the scratch of the solve is overwritten). MPM_OK,
 * or MPM_ERR_NOMEM when out of memory. */
mpm_status mpm_implicit_collider_taken(mpm_implicit *s, double *taken);

#endif
