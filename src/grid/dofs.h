/* dofs.h - the DOF set: one flat vector of velocity unknowns over every grid level and every
 * domain corner that is its own unknown (DESIGN.md, "DOF set").
 *
 * The solver never asks "grid node or domain corner?". Gao et al.'s multi-level grid (sec. 6)
 * makes the real nodes of every level unknowns; Zhu et al.'s enrichment (sec. 5, eq. 12: the
 * set {i, alpha-hat}) adds enriched corners beside them. Both are DOFs here: the explicit
 * update, the implicit solve (matrix-free CG with the Jacobi preconditioner, Zhu eqs. 12-19)
 * and the boundary rules run over indices 0 .. count.
 *
 * Storage is a structure of arrays over DOF indices, one array per field (see mpm_grid_values
 * in grid/grid.h for what each holds during a step):
 *   mass      m_i
 *   v0[3]     P2G: the momentum; after the update: the velocity at the start of the step v^n
 *   v[3]      the velocity at the end of the step v^{n+1} (CG's unknown)
 *   f[3]      the force
 *   vm[3]     after an update that sets it, the velocity the particles move and deform by
 *             (the implicit step's Newmark scheme: a solver vector); NULL: v
 * Only the fields a step uses are allocated (explicit APIC folds the force into the momentum
 * and needs no f).
 *
 * Indices come in segments, laid out anew every step: the nodes of each grid level in the
 * order of that level's boxes, then corner DOFs. A DOF's kind, level and position follow from
 * its segment: a grid node sits at the level's origin + dx times its node coordinate, a corner
 * where its position array says, so positions are not stored twice.
 *
 * Solver vectors (CG's r, p, A p, the Jacobi diagonal) are attached by name, as 3-component
 * vectors over the DOFs, without new grid channels; they are resized with every layout.
 *
 * Reductions (dot products, norms) sum fixed chunks of MPM_DOF_CHUNK DOFs in double, then the
 * chunk sums in chunk order: the result does not depend on the number of threads. */
#ifndef MPM_GRID_DOFS_H
#define MPM_GRID_DOFS_H

#include "mpm/mpm.h"
#include "core/reduce.h"
#include "grid/grid.h"

#include <stddef.h>

/* Fields, as a bit mask. */
enum { MPM_DOF_MASS = 1, MPM_DOF_V0 = 2, MPM_DOF_V = 4, MPM_DOF_F = 8, MPM_DOF_ALL = 15 };

typedef enum mpm_dof_kind {
  MPM_DOF_GRID_NODE, /* a real node of a grid level */
  MPM_DOF_CORNER     /* a domain corner that is its own unknown (Zhu sec. 5: enriched) */
} mpm_dof_kind;

typedef struct mpm_dof_segment {
  mpm_dof_kind kind;
  int level;               /* grid level, -1 for corners */
  size_t begin, count;     /* DOFs begin .. begin + count */
  const mpm_grid *grid;    /* grid nodes: the level (its boxes give the positions) */
  const mpm_real *x[3];    /* corners: position of corner k at x[d][k], m */
  mpm_real boundary_depth; /* how far past a wall plane a DOF must lie to be in the wall band:
                              half a cell for grid nodes (they sit on the lattice), 0 for
                              corners */
} mpm_dof_segment;

#define MPM_DOF_MAX_SEGMENTS 72 /* the multi-level grid's transfer grids, and corners */
/* the named vectors a DOF set carries: the implicit step's (its Newton state, CG's, the
   multigrid's start) and heat's are 20 together; 16 made a melting scene's implicit step fail
   at its first heat transfer */
#define MPM_DOF_MAX_VECTORS 32
#define MPM_DOF_VECTOR_NAME 16
#define MPM_DOF_CHUNK 4096

typedef struct mpm_dof_vector {
  char name[MPM_DOF_VECTOR_NAME];
  mpm_real *c[3];
} mpm_dof_vector;

typedef struct mpm_dofs {
  size_t count, capacity;
  unsigned fields; /* the fields allocated, MPM_DOF_* */
  mpm_real *mass, *v0[3], *v[3], *f[3];
  mpm_real *vm[3]; /* set by the update, reset by a layout (see above) */
  int segment_count;
  mpm_dof_segment segment[MPM_DOF_MAX_SEGMENTS];
  int vector_count;
  mpm_dof_vector vector[MPM_DOF_MAX_VECTORS];
  double *partial; /* chunk sums of the reductions, capacity / MPM_DOF_CHUNK + 1 */
  /* the reductions over every process of the run (core/reduce.h); NULL: this process alone */
  const mpm_reduction *reduction;
} mpm_dofs;

void mpm_dofs_init(mpm_dofs *d);
void mpm_dofs_free(mpm_dofs *d);

/* A new layout: no segments, count 0 (the arrays are kept for reuse). */
void mpm_dofs_begin_layout(mpm_dofs *d);
/* Append the nodes of grid level g as a segment (g->dof_begin is set). MPM_OK, or MPM_ERR_INVALID
 * when there are already MPM_DOF_MAX_SEGMENTS segments. */
mpm_status mpm_dofs_add_grid(mpm_dofs *d, mpm_grid *g);
/* Append `count` corner DOFs whose positions are x[d][0 .. count). MPM_OK or MPM_ERR_INVALID as
 * above. */
mpm_status mpm_dofs_add_corners(mpm_dofs *d, size_t count, const mpm_real *const x[3]);
/* Make room for the layout's count DOFs in the fields of the mask (others are freed) and in
 * every attached vector. Values are not kept: a layout is made anew each step. MPM_OK, or
 * MPM_ERR_NOMEM when out of memory. */
mpm_status mpm_dofs_end_layout(mpm_dofs *d, unsigned fields);

/* Zero the fields of the mask over all DOFs (parallel). */
void mpm_dofs_clear(mpm_dofs *d, unsigned fields);

/* The values of all DOFs (DOF i at index i), and those at grid level g's nodes (node n at
 * index n; g must be a segment of the layout). */
mpm_grid_values mpm_dofs_values(const mpm_dofs *d);
mpm_grid_values mpm_dofs_grid_values(const mpm_dofs *d, const mpm_grid *g);

/* The segment holding DOF i (binary search), and DOF i's position, m. */
const mpm_dof_segment *mpm_dofs_segment_of(const mpm_dofs *d, size_t i);
void mpm_dofs_position(const mpm_dofs *d, size_t i, mpm_real x[3]);

/* The solver vector called `name`, created (zero) on first use: its 3 component arrays over
 * the DOFs. NULL when out of memory or when MPM_DOF_MAX_VECTORS are attached. The pointers
 * are valid until the next mpm_dofs_end_layout. */
mpm_real **mpm_dofs_vector(mpm_dofs *d, const char *name);

/* Deterministic reductions over all DOFs (see the file comment), then over every process of
 * the run (d->reduction). w: per-DOF weights (such as the mass) or NULL for 1. */
double mpm_dofs_dot(const mpm_dofs *d, const mpm_real *w, mpm_real *const a[3],
                    mpm_real *const b[3]);
double mpm_dofs_max_abs(const mpm_dofs *d, mpm_real *const a[3]);

/* y += alpha x, and y = x + beta y (CG's search direction update), component-wise. */
void mpm_dofs_axpy(const mpm_dofs *d, mpm_real alpha, mpm_real *const x[3], mpm_real *const y[3]);
void mpm_dofs_xpby(const mpm_dofs *d, mpm_real *const x[3], mpm_real beta, mpm_real *const y[3]);
/* y = x */
void mpm_dofs_copy(const mpm_dofs *d, mpm_real *const x[3], mpm_real *const y[3]);

#endif
