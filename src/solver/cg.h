/* cg.h - preconditioned conjugate gradients on the DOF set (Hestenes and Stiefel 1952), the
 * linear solver of the implicit step (Zhu et al. 2017 sec. 6: eq. 12 solved matrix-free with
 * the Jacobi preconditioner of eqs. 17-19).
 *
 * Solves A x = b for a symmetric positive (semi-)definite A that the caller applies
 * (matrix-free: for MPM, gather -> per-particle stress differential -> scatter, see
 * transfer/operators.h), on 3-component vectors over the DOFs of a mpm_dofs. Boundary
 * conditions act inside the solve through a projection P that the caller applies (sticky DOFs:
 * their components zeroed; slip DOFs: the normal component removed): the residual and every
 * search direction are projected, so the iterates stay in the admissible subspace and CG solves
 * P A P x = P b there. The preconditioner is a diagonal D (Jacobi). Residuals are measured in
 * the preconditioner's norm, |r|_D = sqrt(<r, P D^-1 P r>) (the <r, z> CG computes anyway;
 * for MPM it weighs each DOF's residual by 1/(m + dt^2 K_ii), i.e. in velocity units, so the
 * stiff modes that a large step resolves to round-off do not set the pace), and the solve stops
 * when |r|_D <= rel_tol max(|P b|_D, |r0|_D) or after max_iterations (D, or the diagonal W a
 * caller gives for the norm alone: options.norm). Both scales are the
 * problem's own: |b| (for MPM the momentum M v*) credits a good initial guess, |r0| (the
 * elastic correction dt^2 K v* a stiff body needs) asks for that correction to rel_tol, not for
 * the momentum of a body at rest to it. A caller may give its own scale instead (the implicit
 * step does: |M v*| of a falling body let CG stop with an error that strained it). Without a
 * preconditioner D = I.
 *
 * Every reduction is mpm_dofs_dot's (fixed chunks, fixed order), so the iterates, the
 * iteration count and the answer are bitwise the same for any number of threads. The work
 * vectors are the DOF set's named vectors "cg.r", "cg.z", "cg.p", "cg.Ap" (and "cg.w" with a
 * preconditioner of the caller's). */
#ifndef MPM_SOLVER_CG_H
#define MPM_SOLVER_CG_H

#include "mpm/mpm.h"
#include "grid/dofs.h"

/* y = A x, for vectors over the DOFs of the set. */
typedef void (*mpm_cg_apply_fn)(void *user, mpm_real *const x[3], mpm_real *const y[3]);
/* v = P v in place. */
typedef void (*mpm_cg_project_fn)(void *user, mpm_real *const v[3]);

typedef struct mpm_cg_options {
  double rel_tol;     /* relative residual to reach, > 0 */
  int max_iterations; /* >= 1 */
  /* > 0: the scale of the caller's that rel_tol is relative to (|r|_D <= rel_tol scale), in
   * place of max(|P b|_D, |r0|_D); the implicit step gives the impulse of the step's forces,
   * which a body's momentum does not inflate (implicit.c). 0: the problem's own scales */
  double scale;
  /* with `scale`: the least drop asked of |r0|_D, so that a scale below what the real type can
   * resolve does not run CG to max_iterations (|r|_D <= floor_drop |r0|_D also converges) */
  double floor_drop;
  /* NULL, or a preconditioner z = B r used in place of the diagonal (B symmetric and positive
     definite on the projected subspace, as a multigrid V-cycle is: solver/multigrid.h), its
     output projected after; the residual is still measured in the diagonal's norm |r|_D, so
     the stopping test means the same whatever preconditions the iterations */
  void (*precondition)(void *user, mpm_real *const r[3], mpm_real *const z[3]);
  void *precondition_user;
  /* with `precondition`: 1 when it is not symmetric (flexible CG: Polak-Ribiere's beta, one
     more vector "cg.rold" and one more dot product an iteration) */
  int flexible;
  /* NULL, or the diagonal the residuals are measured in, |r|_W = sqrt(<r, P W^-1 P r>), in place
     of the preconditioner's D (the implicit step floors D for its norm: implicit.c, jacobi());
     one more pass over the residual an iteration with the Jacobi preconditioner */
  mpm_real *const *norm;
} mpm_cg_options;

typedef struct mpm_cg_result {
  int iterations;
  double residual0, residual; /* |r|_D at the start and at the end */
  double rhs;                 /* |P b|_D */
  double scale;               /* what the tolerance was relative to */
  int converged;              /* residual <= rel_tol scale */
} mpm_cg_result;

/* Solve A x = b: x holds the initial guess and receives the solution. diag: the Jacobi
 * diagonal (positive), or NULL for none; project: NULL for none. MPM_OK, or MPM_ERR_NOMEM when
 * the work vectors cannot be allocated (x is then unchanged). A breakdown (<p, A p> <= 0: A is
 * not positive on the subspace) ends the solve, not converged. */
mpm_status mpm_cg_solve(mpm_dofs *d, mpm_cg_apply_fn apply, mpm_cg_project_fn project, void *user,
                        mpm_real *const diag[3], mpm_real *const b[3], mpm_real *const x[3],
                        const mpm_cg_options *options, mpm_cg_result *result);

#endif
