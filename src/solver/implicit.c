/* implicit.c - the implicit update: predictor, boundary constraints, Zhu's linearized step,
 * the Newton iterations with a backtracking line search, and the boundary rule after the solve
 * (see implicit.h). */
#include "solver/implicit.h"
#include "core/parallel.h"

#include <math.h>
#include <string.h>

/* ---- DOF positions ------------------------------------------------------------------- */

/* Every DOF's position and its wall-band depth, into arena arrays. */
static int dof_positions(mpm_implicit *s, mpm_real *x[3], mpm_real **depth) {
  mpm_dofs *d = s->dofs;
  for (int c = 0; c < 3; ++c) {
    x[c] = mpm_arena_alloc(s->arena, (d->count + 1) * sizeof(mpm_real));
    if (!x[c]) return -1;
  }
  *depth = mpm_arena_alloc(s->arena, (d->count + 1) * sizeof(mpm_real));
  if (!*depth) return -1;
  s->corner_begin = d->count;
  for (int k = 0; k < d->segment_count; ++k) {
    const mpm_dof_segment *sg = &d->segment[k];
    if (sg->kind == MPM_DOF_GRID_NODE) {
      const mpm_grid *g = sg->grid;
      const long boxes = (long)g->ops->box_count(g);
#pragma omp parallel for schedule(dynamic, 16)
      for (long b = 0; b < boxes; ++b) {
        const mpm_node_box box = g->ops->box(g, (size_t)b);
        size_t i = sg->begin + box.first;
        for (int a = 0; a < box.n[0]; ++a)
          for (int e = 0; e < box.n[1]; ++e)
            for (int c = 0; c < box.n[2]; ++c, ++i) {
              const int32_t idx[3] = {box.lo[0] + a, box.lo[1] + e, box.lo[2] + c};
              mpm_real p[3];
              mpm_grid_node_position(g, idx, p);
              for (int t = 0; t < 3; ++t) x[t][i] = p[t];
              (*depth)[i] = sg->boundary_depth;
            }
      }
    } else {
      if (sg->begin < s->corner_begin) s->corner_begin = sg->begin;
      for (size_t j = 0; j < sg->count; ++j) {
        for (int t = 0; t < 3; ++t) x[t][sg->begin + j] = sg->x[t][j];
        (*depth)[sg->begin + j] = sg->boundary_depth;
      }
    }
  }
  return 0;
}

/* ---- constraints ------------------------------------------------------------------------ */

/* Orthonormalize the constraint normals (Gram-Schmidt; near-dependent ones dropped) and write
 * the projector I - sum q q^T; the velocity v is moved onto the constraints one after the
 * other (v <- v - n (n . (v - vo))). Returns 1 if the DOF is constrained. */
static int constrain_dof(int count, mpm_real n[4][3], mpm_real vo[4][3], mpm_real v[3],
                         mpm_real P[6]) {
  if (count == 0) return 0;
  if (count < 0) { /* sticky: fixed */
    for (int e = 0; e < 3; ++e) v[e] = vo[0][e];
    memset(P, 0, 6 * sizeof(mpm_real));
    return 1;
  }
  for (int k = 0; k < count; ++k) {
    const mpm_real vn =
        (v[0] - vo[k][0]) * n[k][0] + (v[1] - vo[k][1]) * n[k][1] + (v[2] - vo[k][2]) * n[k][2];
    for (int e = 0; e < 3; ++e) v[e] -= vn * n[k][e];
  }
  mpm_real q[3][3];
  int m = 0;
  for (int k = 0; k < count && m < 3; ++k) {
    mpm_real a[3] = {n[k][0], n[k][1], n[k][2]};
    for (int j = 0; j < m; ++j) {
      const mpm_real dot = a[0] * q[j][0] + a[1] * q[j][1] + a[2] * q[j][2];
      for (int e = 0; e < 3; ++e) a[e] -= dot * q[j][e];
    }
    const mpm_real len = mpm_sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    if (len < R_(1e-3)) continue;
    for (int e = 0; e < 3; ++e) q[m][e] = a[e] / len;
    ++m;
  }
  mpm_real M[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  for (int j = 0; j < m; ++j)
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) M[3 * r + c] -= q[j][r] * q[j][c];
  if (m == 3) memset(M, 0, sizeof M);
  P[0] = M[0], P[1] = M[1], P[2] = M[2], P[3] = M[4], P[4] = M[5], P[5] = M[8];
  return 1;
}

int mpm_implicit_constraints(mpm_implicit *s, mpm_real *const v[3]) {
  mpm_dofs *d = s->dofs;
  if (!s->px[0] && dof_positions(s, s->px, &s->depth)) return -1;
  const size_t nd = d->count;
  uint8_t *flag = mpm_arena_alloc(s->arena, nd + 1);
  mpm_real(*P)[6] = mpm_arena_alloc(s->arena, (nd + 1) * sizeof *P);
  if (!flag || !P) return -1;
  const long n = (long)nd;
#pragma omp parallel for schedule(static)
  for (long i = 0; i < n; ++i) {
    flag[i] = 0;
    if (!(d->mass[i] > 0)) continue;
    mpm_real vi[3] = {v[0][i], v[1][i], v[2][i]}, nn[4][3], vo[4][3];
    const mpm_real x[3] = {s->px[0][i], s->px[1][i], s->px[2][i]};
    const int corner = (size_t)i >= s->corner_begin;
    int count = mpm_boundary_constraints(s->boundary, x, s->depth[i], corner, vi, nn, vo);
    if (count == 0 && corner) {
      /* a corner DOF free where it is: constrained where the predicted step takes it
       * (explicit_update.c) */
      const mpm_real y[3] = {x[0] + s->dt * vi[0], x[1] + s->dt * vi[1], x[2] + s->dt * vi[2]};
      count = mpm_boundary_constraints(s->boundary, y, s->depth[i], corner, vi, nn, vo);
    }
    flag[i] = (uint8_t)constrain_dof(count, nn, vo, vi, P[i]);
    for (int c = 0; c < 3; ++c) v[c][i] = vi[c];
  }
  size_t count = 0;
  for (size_t i = 0; i < nd; ++i) count += flag[i];
  s->constraint_dof = mpm_arena_alloc(s->arena, (count + 1) * sizeof *s->constraint_dof);
  s->constraint_P = mpm_arena_alloc(s->arena, (count + 1) * sizeof *s->constraint_P);
  if (!s->constraint_dof || !s->constraint_P) return -1;
  size_t k = 0;
  for (size_t i = 0; i < nd; ++i)
    if (flag[i]) {
      s->constraint_dof[k] = (uint32_t)i;
      memcpy(s->constraint_P[k], P[i], sizeof P[i]);
      ++k;
    }
  s->constraint_count = count;
  return 0;
}

void mpm_implicit_project(mpm_implicit *s, mpm_real *const v[3]) {
  const long n = (long)s->constraint_count;
#pragma omp parallel for schedule(static) if (n > MPM_PARALLEL_MIN)
  for (long k = 0; k < n; ++k) {
    const uint32_t i = s->constraint_dof[k];
    const mpm_real *P = s->constraint_P[k];
    const mpm_real a = v[0][i], b = v[1][i], c = v[2][i];
    v[0][i] = P[0] * a + P[1] * b + P[2] * c;
    v[1][i] = P[1] * a + P[3] * b + P[4] * c;
    v[2][i] = P[2] * a + P[4] * b + P[5] * c;
  }
}

/* ---- the solve ------------------------------------------------------------------------- */

static void cg_apply(void *user, mpm_real *const x[3], mpm_real *const y[3]) {
  mpm_implicit *s = user;
  mpm_implicit_apply(s, 1, s->apply_scale, x, y);
}

static void cg_project(void *user, mpm_real *const v[3]) {
  mpm_implicit_project(user, v);
}

/* With body-force regions, each DOF's acceleration (gravity plus the regions at its
 * position) into s->accel, and where a region drags each DOF's drag rate into s->drag. 0, or
 * -1 when out of memory. */
static int dof_accelerations(mpm_implicit *s) {
  mpm_dofs *d = s->dofs;
  if (!s->px[0] && dof_positions(s, s->px, &s->depth)) return -1;
  for (int c = 0; c < 3; ++c) {
    s->accel[c] = mpm_arena_alloc(s->arena, (d->count + 1) * sizeof(mpm_real));
    if (!s->accel[c]) return -1;
  }
  int drags = 0;
  for (int k = 0; k < s->region_count; ++k) drags |= s->regions[k].drag > 0;
  s->drag = drags ? mpm_arena_alloc(s->arena, (d->count + 1) * sizeof(mpm_real)) : NULL;
  if (drags && !s->drag) return -1;
  const long n = (long)d->count;
#pragma omp parallel for schedule(static)
  for (long i = 0; i < n; ++i) {
    const mpm_real x[3] = {s->px[0][i], s->px[1][i], s->px[2][i]};
    mpm_real g[3] = {s->gravity[0], s->gravity[1], s->gravity[2]};
    const mpm_real drag = mpm_force_regions_add(s->regions, s->region_count, x, g);
    for (int c = 0; c < 3; ++c) s->accel[c][i] = g[c];
    if (s->drag) s->drag[i] = drag;
  }
  return 0;
}

/* v0 <- v^n = momentum / m, v <- v* = v^n + dt (f / m + g); massless DOFs get 0. g is gravity,
 * or with body-force regions each DOF's own acceleration. 0, or -1 when out of memory. */
static int predictor(mpm_implicit *s) {
  mpm_dofs *d = s->dofs;
  if (s->region_count > 0 && dof_accelerations(s)) return -1;
  const long n = (long)d->count;
#pragma omp parallel for schedule(static)
  for (long i = 0; i < n; ++i) {
    const mpm_real m = d->mass[i];
    for (int c = 0; c < 3; ++c) {
      if (!(m > 0)) {
        d->v0[c][i] = d->v[c][i] = 0;
        continue;
      }
      const mpm_real vn = d->v0[c][i] / m;
      const mpm_real g = s->accel[c] ? s->accel[c][i] : s->gravity[c];
      d->v0[c][i] = vn;
      d->v[c][i] = vn + s->dt * (d->f[c][i] / m + g);
    }
  }
  return 0;
}

/* E(v) up to a constant: 1/2 sum m |v - v^n - dt g|^2 + Phi(x + dt v), with F^ already
 * displaced to u = dt v. t: work vector. */
static double incremental_potential(mpm_implicit *s, mpm_real *const v[3], mpm_real *const t[3]) {
  mpm_dofs *d = s->dofs;
  const long n = (long)d->count;
  for (int c = 0; c < 3; ++c) {
    const mpm_real dg = s->dt * s->gravity[c], dt = s->dt;
    const mpm_real *restrict a = s->accel[c];
    if (a) {
#pragma omp parallel for simd schedule(static) if (n > MPM_PARALLEL_MIN)
      for (long i = 0; i < n; ++i) t[c][i] = v[c][i] - d->v0[c][i] - dt * a[i];
    } else {
#pragma omp parallel for simd schedule(static) if (n > MPM_PARALLEL_MIN)
      for (long i = 0; i < n; ++i) t[c][i] = v[c][i] - d->v0[c][i] - dg;
    }
  }
  return 0.5 * mpm_dofs_dot(d, d->mass, t, t) + mpm_implicit_energy(s);
}

/* u = dt v */
static void displacement(mpm_implicit *s, mpm_real *const v[3], mpm_real *const u[3]) {
  mpm_dofs_copy(s->dofs, v, u);
  const long n = (long)s->dofs->count;
  for (int c = 0; c < 3; ++c) {
    mpm_real *restrict uc = u[c];
#pragma omp parallel for simd schedule(static) if (n > MPM_PARALLEL_MIN)
    for (long i = 0; i < n; ++i) uc[i] *= s->dt;
  }
}

/* The Jacobi diagonal of M + dt^2 K; DOFs without mass (and without stiffness) get 1. */
static void jacobi(mpm_implicit *s, mpm_real *const diag[3]) {
  mpm_implicit_diagonal(s, 1, s->apply_scale, diag);
  const long n = (long)s->dofs->count;
  for (int c = 0; c < 3; ++c) {
    mpm_real *restrict dc = diag[c];
#pragma omp parallel for simd schedule(static) if (n > MPM_PARALLEL_MIN)
    for (long i = 0; i < n; ++i) dc[i] = dc[i] > 0 ? dc[i] : 1;
  }
}

/* After the solve: the constrained components take v*'s values back, then the regions' drag
 * (collide/body_force.h: split from the solve) and the full boundary rule (colliders, walls)
 * act on every DOF, as in the explicit update. */
static void boundary_after(mpm_implicit *s, mpm_real *const vstar[3]) {
  mpm_dofs *d = s->dofs;
  const long nk = (long)s->constraint_count;
#pragma omp parallel for schedule(static)
  for (long k = 0; k < nk; ++k) {
    const uint32_t i = s->constraint_dof[k];
    const mpm_real *P = s->constraint_P[k];
    mpm_real w[3]; /* (I - P)(v* - v) */
    for (int c = 0; c < 3; ++c) w[c] = vstar[c][i] - d->v[c][i];
    const mpm_real Pw[3] = {P[0] * w[0] + P[1] * w[1] + P[2] * w[2],
                            P[1] * w[0] + P[3] * w[1] + P[4] * w[2],
                            P[2] * w[0] + P[4] * w[1] + P[5] * w[2]};
    for (int c = 0; c < 3; ++c) d->v[c][i] += w[c] - Pw[c];
  }
  const long n = (long)d->count;
#pragma omp parallel for schedule(static)
  for (long i = 0; i < n; ++i) {
    if (!(d->mass[i] > 0)) continue;
    mpm_real v[3] = {d->v[0][i], d->v[1][i], d->v[2][i]};
    if (s->drag) mpm_force_drag(s->drag[i], s->dt, v);
    const mpm_real x[3] = {s->px[0][i], s->px[1][i], s->px[2][i]};
    const int corner = (size_t)i >= s->corner_begin;
    mpm_boundary_apply(s->boundary, x, s->depth[i], corner, v);
    if (corner) { /* corners: and where the step takes them */
      const mpm_real y[3] = {x[0] + s->dt * v[0], x[1] + s->dt * v[1], x[2] + s->dt * v[2]};
      mpm_boundary_apply(s->boundary, y, s->depth[i], 1, v);
    }
    for (int c = 0; c < 3; ++c) d->v[c][i] = v[c];
  }
}

static void cg_record(mpm_implicit_result *r, const mpm_cg_result *cg) {
  r->cg_iterations += cg->iterations;
  const double scale = cg->rhs > cg->residual0 ? cg->rhs : cg->residual0;
  const double rel = scale > 0 ? cg->residual / scale : 0;
  if (rel > r->cg_residual) r->cg_residual = rel;
  if (!cg->converged) r->cg_converged = 0;
}

/* With Newton iterations, Zhu's step v_1 is searched too: from v_0 (the constrained components
 * of v_1, zero elsewhere: no motion but what the obstacles impose) along v_1 - v_0, the
 * longest of 1, 1/2, ... whose incremental potential is below E(v_0). A linearized step across
 * an impact or a large rotation can overshoot badly; this keeps every iterate a descent. Returns
 * 1 when no step lowers E (v is then v_0). */
static int first_step_search(mpm_implicit *s, mpm_real *const u[3], mpm_real *const d0[3],
                             mpm_real *const t[3]) {
  mpm_dofs *d = s->dofs;
  mpm_dofs_copy(d, d->v, d0); /* d0 = P v_1 (the free part), v <- v_0 = v_1 - P v_1 */
  mpm_implicit_project(s, d0);
  mpm_dofs_axpy(d, -1, d0, d->v);
  displacement(s, d->v, u);
  mpm_implicit_displace(s, u);
  const double E0 = incremental_potential(s, d->v, t);
  double alpha = 1;
  for (int h = 0; h < 12; ++h, alpha *= 0.5) {
    mpm_dofs_copy(d, d->v, t);
    mpm_dofs_axpy(d, (mpm_real)alpha, d0, t);
    displacement(s, t, u);
    mpm_implicit_displace(s, u);
    if (incremental_potential(s, t, u) < E0) {
      mpm_dofs_axpy(d, (mpm_real)alpha, d0, d->v);
      return 0;
    }
  }
  return 1;
}

int mpm_implicit_solve(mpm_implicit *s, const mpm_implicit_options *o, mpm_implicit_result *r) {
  memset(r, 0, sizeof *r);
  r->cg_converged = 1;
  mpm_dofs *d = s->dofs;
  mpm_real **vstar = mpm_dofs_vector(d, "imp.vstar"), **b = mpm_dofs_vector(d, "imp.b");
  mpm_real **diag = mpm_dofs_vector(d, "imp.diag"), **t = mpm_dofs_vector(d, "imp.t");
  if (!vstar || !b || !diag || !t) return -1;
  if (predictor(s)) return -1;
  mpm_dofs_copy(d, d->v, vstar);
  if (mpm_implicit_constraints(s, d->v)) return -1; /* the initial guess obeys them */
  const mpm_cg_options cg_opt = {o->cg_tolerance, o->cg_max_iterations};
  /* Newton iteration 1 (Zhu eq. 12): (M + dt^2 K(0)) v = M v* */
  const long n = (long)d->count;
  for (int c = 0; c < 3; ++c) {
    const mpm_real *restrict m = d->mass, *restrict vs = vstar[c];
    mpm_real *restrict bc = b[c];
#pragma omp parallel for simd schedule(static) if (n > MPM_PARALLEL_MIN)
    for (long i = 0; i < n; ++i) bc[i] = m[i] * vs[i];
  }
  mpm_implicit_displace(s, NULL);
  mpm_implicit_build(s);
  if (o->precondition) jacobi(s, diag);
  mpm_cg_result cg;
  if (mpm_cg_solve(d, cg_apply, cg_project, s, o->precondition ? diag : NULL, b, d->v, &cg_opt,
                   &cg))
    return -1;
  cg_record(r, &cg);
  r->newton_iterations = 1;
  /* Newton iterations 2.. on E (Gast et al. 2015): the gradient in b, the step in t */
  mpm_real **u = mpm_dofs_vector(d, "imp.u"), **dv = mpm_dofs_vector(d, "imp.dv");
  if (o->newton_iterations > 1 && (!u || !dv)) return -1;
  const double b_norm = sqrt(mpm_dofs_dot(d, NULL, b, b));
  if (o->newton_iterations > 1 && first_step_search(s, u, dv, t)) r->line_search_failed = 1;
  for (int k = 1; k < o->newton_iterations; ++k) {
    displacement(s, d->v, u);
    mpm_implicit_displace(s, u);
    const double E0 = incremental_potential(s, d->v, t);
    /* grad E = m (v - v^n - dt g) - dt f(u): t holds v - v^n - dt g */
    mpm_implicit_forces(s, b);
    for (int c = 0; c < 3; ++c) {
      const mpm_real *restrict m = d->mass, *restrict tc = t[c];
      mpm_real *restrict bc = b[c];
#pragma omp parallel for simd schedule(static) if (n > MPM_PARALLEL_MIN)
      for (long i = 0; i < n; ++i) bc[i] = -(m[i] * tc[i] - s->dt * bc[i]); /* -grad E */
    }
    mpm_implicit_project(s, b);
    const double g_norm = sqrt(mpm_dofs_dot(d, NULL, b, b));
    if (!(g_norm > o->cg_tolerance * b_norm)) break; /* converged: the step is stationary */
    mpm_implicit_build(s);
    if (o->precondition) jacobi(s, diag);
    for (int c = 0; c < 3; ++c) memset(dv[c], 0, (size_t)n * sizeof(mpm_real));
    if (mpm_cg_solve(d, cg_apply, cg_project, s, o->precondition ? diag : NULL, b, dv, &cg_opt,
                     &cg))
      return -1;
    cg_record(r, &cg);
    r->newton_iterations = k + 1;
    /* backtracking: the longest of 1, 1/2, 1/4, ... that lowers E enough (Armijo) */
    const double slope = -mpm_dofs_dot(d, NULL, b, dv); /* <grad E, dv> */
    double alpha = 1;
    int accepted = 0;
    for (int h = 0; h < 12 && !accepted; ++h, alpha *= 0.5) {
      mpm_dofs_copy(d, d->v, t);
      mpm_dofs_axpy(d, (mpm_real)alpha, dv, t); /* t = v + alpha dv */
      displacement(s, t, u);
      mpm_implicit_displace(s, u);
      const double E = incremental_potential(s, t, u); /* u reused as work */
      if (E <= E0 + 1e-4 * alpha * slope) {
        accepted = 1;
        mpm_dofs_axpy(d, (mpm_real)alpha, dv, d->v);
      }
    }
    if (!accepted) {
      r->line_search_failed = 1;
      break;
    }
  }
  boundary_after(s, vstar);
  return 0;
}

/* The momentum the colliders took in the solved step (stats.csv): the part of a DOF's momentum
 * change that neither gravity nor the elastic forces at the end of the step explain, the
 * obstacle's impulse on it (backward Euler, m (v - v^n) = dt m g + dt f(u) + J):
 *   J_i = m_i (v_i - v*_i) + dt f_i^n - dt f_i(dt v),  v* = v^n + dt (g + f^n / m),
 * zero at free DOFs (there it is the Newton residual, to the solver's tolerance). The DOFs
 * inside collider (pose) c where the step began (or, for corners, where it takes them) count
 * for c, the first one when several hold a DOF; the collider took -J_i. One more evaluation of
 * the forces, only when the caller measures. Sums per chunk of DOFs, then in chunk order, so
 * they do not depend on the thread count. */
#define TAKEN_CHUNK 1024
int mpm_implicit_collider_taken(mpm_implicit *s, double *taken) {
  mpm_dofs *d = s->dofs;
  const mpm_boundary *bd = s->boundary;
  const int nc = bd->collider_count;
  mpm_real **vstar = mpm_dofs_vector(d, "imp.vstar"), **u = mpm_dofs_vector(d, "imp.u");
  mpm_real **f = mpm_dofs_vector(d, "imp.b");
  const long n = (long)d->count, chunks = (n + TAKEN_CHUNK - 1) / TAKEN_CHUNK;
  double *slots = mpm_arena_alloc(s->arena, ((size_t)chunks * 3 * (size_t)nc + 1) * sizeof *slots);
  if (!vstar || !u || !f || !slots) return -1;
  displacement(s, d->v, u);
  mpm_implicit_displace(s, u);
  mpm_implicit_forces(s, f);
#pragma omp parallel for schedule(static)
  for (long h = 0; h < chunks; ++h) {
    double *t = slots + (size_t)h * 3 * (size_t)nc;
    for (int k = 0; k < 3 * nc; ++k) t[k] = 0;
    const long end = (h + 1) * TAKEN_CHUNK < n ? (h + 1) * TAKEN_CHUNK : n;
    for (long i = h * TAKEN_CHUNK; i < end; ++i) {
      const mpm_real m = d->mass[i];
      if (!(m > 0)) continue;
      const mpm_real x[3] = {s->px[0][i], s->px[1][i], s->px[2][i]};
      const mpm_real vs[3] = {vstar[0][i], vstar[1][i], vstar[2][i]};
      const mpm_real y[3] = {x[0] + s->dt * vs[0], x[1] + s->dt * vs[1], x[2] + s->dt * vs[2]};
      int c = 0;
      for (mpm_real nrm[3]; c < nc; ++c)
        if (mpm_collider_phi(&bd->poses[c], x, nrm) <= 0 ||
            ((size_t)i >= s->corner_begin && mpm_collider_phi(&bd->poses[c], y, nrm) <= 0))
          break;
      if (c == nc) continue;
      /* f^n: v* - v^n = dt (g + f^n / m) */
      for (int e = 0; e < 3; ++e) {
        const double fn_dt =
            (double)m * ((double)vs[e] - (double)d->v0[e][i]) -
            (double)m * (double)s->dt * (double)(s->accel[e] ? s->accel[e][i] : s->gravity[e]);
        const double J = (double)m * ((double)d->v[e][i] - (double)vs[e]) + fn_dt -
                         (double)s->dt * (double)f[e][i];
        t[3 * c + e] -= J;
      }
    }
  }
  for (long h = 0; h < chunks; ++h)
    for (int k = 0; k < 3 * nc; ++k) taken[k] += slots[(size_t)h * 3 * (size_t)nc + (size_t)k];
  return 0;
}
