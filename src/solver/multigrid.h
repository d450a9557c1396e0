/* multigrid.h - a Galerkin multigrid V-cycle on a grid's nodes, the preconditioner of the
 * implicit step's CG (solver.preconditioner "multigrid"; after HOT, Wang et al. 2020, sec. 4).
 *
 * The finest level is the assembled system matrix of 3x3 node blocks (transfer/operators.h,
 * mpm_assemble_stiffness, plus the lumped mass), stored per row as a dense stencil: the block
 * for every offset in [-radius, radius]^3 (absent neighbours have no row). Each coarser level
 * has half as many nodes per axis; its nodes' functions are combinations of the finer ones,
 * with the prolongation P from the kernel's own refinement relation:
 *   quadratic B-spline  the coarse B-spline of spacing 2 dx is, per axis, 1/4, 3/4, 3/4, 1/4 of
 *                       the fine B-splines at nodes 2I - 1 .. 2I + 2 (the B-splines' two-scale
 *                       relation; the coarse nodes sit between fine ones, at (2I + 1/2) dx), so
 *                       the Galerkin product R A P with R = P^T is exactly the system the
 *                       particles would make on the coarse grid (HOT sec. 4.2): nothing is lost
 *                       to a rediscretization;
 *   other kernels       linear interpolation: 1/2, 1, 1/2 at fine nodes 2I - 1 .. 2I + 1.
 * The coarse operators are Galerkin, A_{l+1} = P^T A_l P, taken in two passes (A P by fine
 * rows, each row's dense stencil contracted with P's tensor-product rows one axis at a time, then
 * P^T (A P) by coarse rows through each coarse node's children), so they stay
 * symmetric and positive (semi-)definite whatever the particles do.
 *
 * Boundary conditions: the finest level's constrained nodes carry a projector Pi_i (sticky: 0;
 * slip: I - n n^T; the implicit step's constraints); the finest matrix is taken as Pi A Pi, so
 * the coarse levels are Galerkin for the projected system and see the obstacles as the fine
 * level does. The smoother is a symmetric block Gauss-Seidel: nodes coloured by their
 * coordinates modulo radius + 1 (a colour's nodes never share a block, so each colour runs in
 * parallel and the result does not depend on the thread count), each node's 3x3 diagonal block
 * inverted (pseudo-inverted where the projection leaves it singular). Two cycles:
 *   symmetric  a forward sweep over the colours before the coarse correction and a backward one
 *              after it, the forward sweep's adjoint: a symmetric operator, for plain CG; it
 *              reads each level's matrix three times (sweep, residual, sweep);
 *   one-pass   (`cheap`, the implicit step's) the coarse correction of b itself, then the
 *              backward sweep: one read of each level's matrix, not symmetric, so CG runs
 *              flexible (cg.h). Measured on a spinning block (mpm bench implicit --only
 *              resolution) it needed fewer iterations than the symmetric cycle, not more
 *              (3.5-16 per Newton iteration against 12-15), in a third of the time each.
 * The coarsest level
 * (at most `coarsest` nodes) is solved directly: a dense Cholesky factor in double, with the
 * pivots of null directions (a node held by obstacles) left out.
 *
 * Memory: every level is allocated from the caller's arena; the finest matrix is 9 (2 radius +
 * 1)^3 reals per node (4.5 KiB in float for the quadratic kernel), the coarse ones an eighth
 * of it each. */
#ifndef MPM_SOLVER_MULTIGRID_H
#define MPM_SOLVER_MULTIGRID_H

#include "mpm/mpm.h"
#include "core/arena.h"
#include "core/real.h"

#include <stddef.h>
#include <stdint.h>

#define MPM_MG_LEVELS_MAX 12

typedef enum mpm_mg_prolongation {
  MPM_MG_LINEAR = 0,   /* 1/2, 1, 1/2 */
  MPM_MG_QUADRATIC = 1 /* the quadratic B-spline's two-scale relation, 1/4, 3/4, 3/4, 1/4 */
} mpm_mg_prolongation;

typedef struct mpm_mg_level {
  size_t n;         /* nodes (rows) */
  int radius, span; /* the stencil: offsets in [-radius, radius]^3, span = 2 radius + 1 */
  size_t slots;     /* span^3 */
  int32_t (*coord)[3];
  int32_t *nbr;   /* n * slots: the row of the node at each offset, -1 where none */
  mpm_real *val;  /* n * slots * 9: the blocks, row-major */
  mpm_real *dinv; /* n * 9: the diagonal blocks' (pseudo-)inverses */
  int colours;
  uint32_t *colour_start; /* colours + 1 */
  uint32_t *colour_row;   /* n: the rows colour by colour */
  /* to the next coarser level: each row's parents there and their weights (P's row) */
  int32_t *parent; /* n * 8, -1 unused */
  mpm_real *pw;    /* n * 8 */
  /* from the next finer level: each row's children there (P's column), for R = P^T */
  uint32_t *child_start; /* n + 1 */
  uint32_t *child;
  mpm_real *cw;
  mpm_real *x, *b, *r; /* 3 n each, node by node (x y z) */
} mpm_mg_level;

typedef struct mpm_multigrid {
  int level_count;
  mpm_mg_level level[MPM_MG_LEVELS_MAX];
  mpm_mg_prolongation prolongation;
  int sweeps; /* Gauss-Seidel sweeps before (forward) and after (backward) the coarse correction */
  int cheap;  /* 1: the coarse correction of b then the backward sweeps only (not symmetric: for
                 flexible CG), one pass over each level's matrix instead of three */
  /* the finest level's constraints: projector proj[k] (xx, xy, xz, yy, yz, zz) of row
     proj_row[k] */
  size_t constrained;
  const uint32_t *proj_row;
  const mpm_real (*proj)[6];
  int32_t *proj_of_row; /* n: k, or -1 */
  /* the coarsest level's dense factor (3 n x 3 n, double, lower triangle) */
  size_t dense_n;
  double *chol;
  uint8_t *null;
  double *dense_x;
  mpm_real *ap; /* the Galerkin products' scratch, A P of one level at a time */
  mpm_arena *arena;
  size_t bytes; /* what the levels and the Galerkin products' scratch took from the arena */
} mpm_multigrid;

/* The hierarchy over the finest level's n nodes at integer coordinates coord (distinct), for a
 * matrix of the given stencil radius: levels coarsened until one has at most `coarsest` nodes
 * (or MPM_MG_LEVELS_MAX). Everything from `arena` (valid until its reset). The finest level's
 * values are left zero for the caller to fill (level[0].val). MPM_OK; MPM_ERR_INVALID for a
 * radius outside 1 .. 3 (the kernels' stencils); MPM_ERR_NOMEM when out of memory. */
mpm_status mpm_multigrid_setup(mpm_multigrid *mg, mpm_arena *arena, size_t n,
                               const int32_t (*coord)[3], int radius,
                               mpm_mg_prolongation prolongation, size_t coarsest);

/* Zero the finest level's values (before assembling them again). */
void mpm_multigrid_clear(mpm_multigrid *mg);

/* The finest level's blocks before the centre slot from the symmetric ones after it,
 * A_ij = A_ji^T (for a caller that assembled the upper half of each row). */
void mpm_multigrid_mirror_lower(mpm_multigrid *mg);

/* After the finest values are filled: project them with the constraints (count of them: rows
 * row[k] with projector P[k]; the arrays are kept and must outlive the V-cycles), form the
 * coarse levels' values (Galerkin, in the scratch allocated at setup), the smoother's inverses
 * and the coarsest factor. */
void mpm_multigrid_factor(mpm_multigrid *mg, size_t count, const uint32_t *row,
                          const mpm_real (*P)[6]);

/* x = B b on the finest level (level[0].b in, level[0].x out): one V-cycle from x = 0. B is
 * symmetric and, where A is positive definite on the unconstrained subspace, positive
 * definite there; B b is projected. */
void mpm_multigrid_vcycle(mpm_multigrid *mg);

/* y = A x with level l's matrix (3 n vectors, node by node). */
void mpm_multigrid_apply(const mpm_multigrid *mg, int l, const mpm_real *x, mpm_real *y);

#endif
