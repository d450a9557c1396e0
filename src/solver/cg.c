/* cg.c - preconditioned, projected conjugate gradients on the DOF set (see cg.h).
 *
 *   r = P (b - A x),  z = P M^-1 r,  p = z
 *   repeat:  q = P A p,  alpha = <r, z> / <p, q>,  x += alpha p,  r -= alpha q,
 *            stop when |r| <= tol |r0|;  z = P M^-1 r,  beta = <r, z>_new / <r, z>,  p = z + beta p
 * (Hestenes and Stiefel 1952; Shewchuk 1994, "An Introduction to the Conjugate Gradient Method
 * Without the Agonizing Pain", B3). */
#include "solver/cg.h"
#include "core/parallel.h"

#include <math.h>

/* z = r / diag (or z = r), component-wise, in parallel. */
static void precondition(const mpm_dofs *d, mpm_real *const diag[3], mpm_real *const r[3],
                         mpm_real *const z[3]) {
  if (!diag) {
    mpm_dofs_copy(d, r, z);
    return;
  }
  const long n = (long)d->count;
#pragma omp parallel if (n > MPM_PARALLEL_MIN)
  for (int c = 0; c < 3; ++c) {
    const mpm_real *restrict rc = r[c], *restrict dc = diag[c];
    mpm_real *restrict zc = z[c];
#pragma omp for simd schedule(static) nowait
    for (long i = 0; i < n; ++i) zc[i] = rc[i] / dc[i];
  }
}

/* |r|_D = sqrt(<r, P D^-1 P r>) for a projected r; w: work. */
static double diag_norm(const mpm_dofs *d, mpm_real *const diag[3], mpm_cg_project_fn project,
                        void *user, mpm_real *const r[3], mpm_real *const w[3]) {
  precondition(d, diag, r, w);
  if (project) project(user, w);
  const double rr = mpm_dofs_dot(d, NULL, r, w);
  return sqrt(rr > 0 ? rr : 0);
}

mpm_status mpm_cg_solve(mpm_dofs *d, mpm_cg_apply_fn apply, mpm_cg_project_fn project, void *user,
                        mpm_real *const diag[3], mpm_real *const b[3], mpm_real *const x[3],
                        const mpm_cg_options *options, mpm_cg_result *result) {
  mpm_real **r = mpm_dofs_vector(d, "cg.r"), **z = mpm_dofs_vector(d, "cg.z");
  mpm_real **p = mpm_dofs_vector(d, "cg.p"), **q = mpm_dofs_vector(d, "cg.Ap");
  if (!r || !z || !p || !q) return MPM_ERR_NOMEM;
  const int own = options->precondition != NULL; /* the caller's preconditioner */
  /* the diagonal of the residuals' norm, and whether it is not the one that preconditions */
  mpm_real *const *W = options->norm ? options->norm : diag;
  const int apart = own || options->norm != NULL;
  mpm_real **w = apart ? mpm_dofs_vector(d, "cg.w") : NULL;
  /* flexible: the residual before the step, for Polak-Ribiere's beta */
  mpm_real **rold = own && options->flexible ? mpm_dofs_vector(d, "cg.rold") : NULL;
  if ((apart && !w) || (own && options->flexible && !rold)) return MPM_ERR_NOMEM;
  result->iterations = 0;
  /* the scale: |P b| in the preconditioner's norm, sqrt(<P b, P D^-1 P b>) */
  mpm_dofs_copy(d, b, p);
  if (project) project(user, p);
  precondition(d, W, p, z);
  if (project) project(user, z);
  result->rhs = sqrt(mpm_dofs_dot(d, NULL, p, z));
  /* r = P (b - A x), z = P D^-1 r */
  apply(user, x, q);
  mpm_dofs_copy(d, b, r);
  mpm_dofs_axpy(d, -1, q, r);
  if (project) project(user, r);
  double rz;
  if (own) {
    result->residual0 = result->residual = diag_norm(d, W, project, user, r, w);
    options->precondition(options->precondition_user, r, z);
    if (project) project(user, z);
    rz = mpm_dofs_dot(d, NULL, r, z);
  } else {
    precondition(d, diag, r, z);
    if (project)
      project(user, z); /* P M^-1 P: a diagonal need not commute with a slip projection */
    rz = mpm_dofs_dot(d, NULL, r, z);
    result->residual0 = result->residual = w ? diag_norm(d, W, project, user, r, w) : sqrt(rz);
  }
  result->scale = options->scale > 0                ? options->scale
                  : result->rhs > result->residual0 ? result->rhs
                                                    : result->residual0;
  double target = options->rel_tol * result->scale;
  if (options->scale > 0 && options->floor_drop * result->residual0 > target) {
    target = options->floor_drop * result->residual0;
    result->scale = target / options->rel_tol; /* the scale the answer is good to */
  }
  result->converged = result->residual <= target;
  if (result->converged) return MPM_OK;
  mpm_dofs_copy(d, z, p);
  for (int k = 0; k < options->max_iterations; ++k) {
    apply(user, p, q);
    if (project) project(user, q);
    const double pq = mpm_dofs_dot(d, NULL, p, q);
    if (!(pq > 0)) break; /* A is not positive on the search direction: breakdown */
    const mpm_real alpha = (mpm_real)(rz / pq);
    mpm_dofs_axpy(d, alpha, p, x);
    if (rold) mpm_dofs_copy(d, r, rold);
    mpm_dofs_axpy(d, -alpha, q, r);
    result->iterations = k + 1;
    double rz_new;
    if (own) {
      result->residual = diag_norm(d, W, project, user, r, w);
      if (result->residual <= target) {
        result->converged = 1;
        break;
      }
      options->precondition(options->precondition_user, r, z);
      if (project) project(user, z);
      rz_new = mpm_dofs_dot(d, NULL, r, z);
    } else {
      precondition(d, diag, r, z);
      if (project) project(user, z);
      rz_new = mpm_dofs_dot(d, NULL, r, z);
      result->residual = w ? diag_norm(d, W, project, user, r, w) : sqrt(rz_new > 0 ? rz_new : 0);
    }
    if (result->residual <= target) {
      result->converged = 1;
      break;
    }
    /* flexible (a preconditioner that is not symmetric): beta = <z, r - r_old> / <z_old, r_old>
       (Polak-Ribiere; Notay 2000), which keeps the directions conjugate as far as it can */
    const double num = rold ? rz_new - mpm_dofs_dot(d, NULL, rold, z) : rz_new;
    const mpm_real beta = (mpm_real)(num / rz);
    rz = rz_new;
    mpm_dofs_xpby(d, z, beta, p); /* p = z + beta p */
  }
  return MPM_OK;
}
