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

mpm_status mpm_implicit_constraints(mpm_implicit *s, mpm_real *const v[3]) {
  mpm_dofs *d = s->dofs;
  if (!s->px[0] && dof_positions(s, s->px, &s->depth)) return MPM_ERR_NOMEM;
  const size_t nd = d->count;
  uint8_t *flag = mpm_arena_alloc(s->arena, nd + 1);
  mpm_real(*P)[6] = mpm_arena_alloc(s->arena, (nd + 1) * sizeof *P);
  if (!flag || !P) return MPM_ERR_NOMEM;
  const long n = (long)nd;
#pragma omp parallel for schedule(static)
  for (long i = 0; i < n; ++i) {
    flag[i] = 0;
    if (!(d->mass[i] > 0)) continue;
    mpm_real vi[3] = {v[0][i], v[1][i], v[2][i]}, nn[4][3], vo[4][3];
    mpm_real vm[3]; /* the motion the step brings without the elastic forces: for friction */
    for (int c = 0; c < 3; ++c)
      vm[c] = d->v0[c][i] + s->dt * (s->accel[c] ? s->accel[c][i] : s->gravity[c]);
    const mpm_real x[3] = {s->px[0][i], s->px[1][i], s->px[2][i]};
    const int corner = (size_t)i >= s->corner_begin;
    int count = mpm_boundary_constraints(s->boundary, x, s->depth[i], corner, vi, vm, nn, vo);
    if (count == 0 && corner) {
      /* a corner DOF free where it is: constrained where the predicted step takes it
       * (explicit_update.c) */
      const mpm_real y[3] = {x[0] + s->dt * vi[0], x[1] + s->dt * vi[1], x[2] + s->dt * vi[2]};
      count = mpm_boundary_constraints(s->boundary, y, s->depth[i], corner, vi, vm, nn, vo);
    }
    /* 1: constrained; 2: held by friction (its velocity is the rule's already: boundary_after
       leaves it) */
    flag[i] = (uint8_t)(constrain_dof(count, nn, vo, vi, P[i]) ? (count == -2 ? 2 : 1) : 0);
    for (int c = 0; c < 3; ++c) v[c][i] = vi[c];
  }
  size_t count = 0;
  for (size_t i = 0; i < nd; ++i) count += flag[i] != 0;
  s->constraint_dof = mpm_arena_alloc(s->arena, (count + 1) * sizeof *s->constraint_dof);
  s->constraint_P = mpm_arena_alloc(s->arena, (count + 1) * sizeof *s->constraint_P);
  s->constraint_friction = mpm_arena_alloc(s->arena, count + 1);
  if (!s->constraint_dof || !s->constraint_P || !s->constraint_friction) return MPM_ERR_NOMEM;
  size_t k = 0;
  for (size_t i = 0; i < nd; ++i)
    if (flag[i]) {
      s->constraint_dof[k] = (uint32_t)i;
      memcpy(s->constraint_P[k], P[i], sizeof P[i]);
      s->constraint_friction[k] = flag[i] == 2;
      ++k;
    }
  s->constraint_count = count;
  return MPM_OK;
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

/* v0 <- v^n = momentum / m; massless DOFs get 0. */
static void start_velocity(mpm_implicit *s) {
  mpm_dofs *d = s->dofs;
  const long n = (long)d->count;
#pragma omp parallel for schedule(static)
  for (long i = 0; i < n; ++i) {
    const mpm_real m = d->mass[i];
    for (int c = 0; c < 3; ++c) d->v0[c][i] = m > 0 ? d->v0[c][i] / m : 0;
  }
}

/* Whether an obstacle or a wall acts at a DOF with mass in this step: its rule changes the
 * step's motion without elastic forces, v^n + dt g (collide/boundary.h). Newmark's positions are
 * taken only in steps where none does (implicit.h says why). 0 or 1; -1 when out of memory. */
static int touches(mpm_implicit *s) {
  mpm_dofs *d = s->dofs;
  if (!s->px[0] && dof_positions(s, s->px, &s->depth)) return -1;
  const long n = (long)d->count;
  int any = 0;
#pragma omp parallel for schedule(static) reduction(| : any)
  for (long i = 0; i < n; ++i) {
    if (!(d->mass[i] > 0)) continue;
    mpm_real v[3], w[3];
    for (int c = 0; c < 3; ++c) v[c] = w[c] = d->v0[c][i] + s->dt * s->gravity[c];
    const mpm_real x[3] = {s->px[0][i], s->px[1][i], s->px[2][i]};
    mpm_boundary_apply(s->boundary, x, s->depth[i], (size_t)i >= s->corner_begin, v);
    any |= v[0] != w[0] || v[1] != w[1] || v[2] != w[2];
  }
  return any;
}

/* v <- v* = v^n + dt (f / m + g) (f at the step's base displacement); massless DOFs get 0. g is
 * gravity, or with body-force regions each DOF's own acceleration. 0, or -1 when out of
 * memory. */
static int predictor(mpm_implicit *s) {
  mpm_dofs *d = s->dofs;
  if (s->region_count > 0 && dof_accelerations(s)) return -1;
  const long n = (long)d->count;
#pragma omp parallel for schedule(static)
  for (long i = 0; i < n; ++i) {
    const mpm_real m = d->mass[i];
    for (int c = 0; c < 3; ++c) {
      const mpm_real g = s->accel[c] ? s->accel[c][i] : s->gravity[c];
      d->v[c][i] = m > 0 ? d->v0[c][i] + s->dt * (d->f[c][i] / m + g) : 0;
    }
  }
  return 0;
}

/* E(v) up to a constant: 1/2 sum m |v - v^n - dt g|^2 + Phi(x + u(v)) / theta, with F^ already
 * displaced to u(v) (displacement()). t: work vector. */
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
  const double phi = mpm_implicit_energy(s);
  return 0.5 * mpm_dofs_dot(d, d->mass, t, t) + (s->theta < 1 ? phi / s->theta : phi);
}

/* u(v) = dt ((1 - theta) v^n + theta v): dt v for backward Euler (theta 1); v NULL: v = 0 (the
 * step's base u(0), theta < 1) */
static void displacement(mpm_implicit *s, mpm_real *const v[3], mpm_real *const u[3]) {
  const long n = (long)s->dofs->count;
  const mpm_real dt = s->dt, a = s->theta * dt, b = dt - a;
  for (int c = 0; c < 3; ++c) {
    mpm_real *restrict uc = u[c];
    if (!v) {
      const mpm_real *restrict v0 = s->dofs->v0[c];
#pragma omp parallel for simd schedule(static) if (n > MPM_PARALLEL_MIN)
      for (long i = 0; i < n; ++i) uc[i] = b * v0[i];
      continue;
    }
    const mpm_real *restrict vc = v[c];
    if (s->theta < 1) {
      const mpm_real *restrict v0 = s->dofs->v0[c];
#pragma omp parallel for simd schedule(static) if (n > MPM_PARALLEL_MIN)
      for (long i = 0; i < n; ++i) uc[i] = a * vc[i] + b * v0[i];
    } else {
#pragma omp parallel for simd schedule(static) if (n > MPM_PARALLEL_MIN)
      for (long i = 0; i < n; ++i) uc[i] = dt * vc[i];
    }
  }
}

/* The floor of the residuals' norm, as a fraction of the Jacobi diagonal's mean over the DOFs
 * with mass (see jacobi()). */
#define JACOBI_FLOOR 1e-2

/* The Jacobi diagonal D of M + dt^2 K (DOFs without mass, and without stiffness, get 1), the
 * preconditioner, and the diagonal W of the norm every residual is measured in, |r|_W (cg.h):
 * D floored at JACOBI_FLOOR of its mean over the DOFs with mass. D itself as the norm counted
 * the nodes at the edge of a particle's stencil as much as full ones: a particle s cells inside
 * the edge of the quadratic B-spline's support gives its node a mass and a stiffness of order
 * s^2 and a force of order s, so the node's r^2 / D is of order one (about that particle's
 * strain energy) however small s is. Such nodes come and go as particles move by microns: the
 * rubber bunny at rest on a floor began every step 20-25 tolerances out of balance through
 * some 30 nodes of 1e-12 kg each (a particle 1e-6 m inside a support's edge) and paid 2 Newton
 * iterations and 40 CG iterations a step for a state that did not change. In W, a node lighter
 * than a hundredth of the mean counts as momentum on one of that weight: its residual vanishes
 * with its share of a particle, and a full node's is measured as before. D is not floored: as
 * the preconditioner, floored, it slowed a stiff block on a floor past 664 iterations. The sum
 * runs in one order (one thread), so W is the same for any thread count. W is made once a step
 * (norm NULL leaves it): the scale and every residual of the step are measured in it. */
static void jacobi(mpm_implicit *s, mpm_real *const diag[3], mpm_real *const norm[3]) {
  mpm_implicit_diagonal(s, 1, s->apply_scale, diag);
  const mpm_dofs *d = s->dofs;
  const long n = (long)d->count;
  for (int c = 0; c < 3; ++c) {
    mpm_real *restrict dc = diag[c];
#pragma omp parallel for simd schedule(static) if (n > MPM_PARALLEL_MIN)
    for (long i = 0; i < n; ++i) dc[i] = dc[i] > 0 ? dc[i] : 1;
  }
  if (!norm) return;
  double sum = 0;
  long with_mass = 0;
  for (int c = 0; c < 3; ++c)
    for (long i = 0; i < n; ++i)
      if (d->mass[i] > 0) sum += diag[c][i], ++with_mass;
  const mpm_real least = with_mass ? (mpm_real)(JACOBI_FLOOR * sum / (double)with_mass) : 0;
  for (int c = 0; c < 3; ++c) {
    const mpm_real *restrict dc = diag[c];
    mpm_real *restrict wc = norm[c];
#pragma omp parallel for simd schedule(static) if (n > MPM_PARALLEL_MIN)
    for (long i = 0; i < n; ++i) wc[i] = dc[i] < least ? least : dc[i];
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
    if (s->constraint_friction[k]) continue; /* held at the friction rule's velocity */
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

/* sqrt(<P v, D^-1 P v>) with v projected in place (D the Jacobi diagonal, I without one); w:
 * work. */
static double free_norm(mpm_implicit *s, mpm_real *const diag[3], mpm_real *const v[3],
                        mpm_real *const w[3]) {
  mpm_dofs *d = s->dofs;
  mpm_implicit_project(s, v);
  if (!diag) return sqrt(mpm_dofs_dot(d, NULL, v, v));
  const long n = (long)d->count;
  for (int c = 0; c < 3; ++c) {
    const mpm_real *restrict vc = v[c], *restrict dc = diag[c];
    mpm_real *restrict wc = w[c];
#pragma omp parallel for simd schedule(static) if (n > MPM_PARALLEL_MIN)
    for (long i = 0; i < n; ++i) wc[i] = vc[i] / dc[i];
  }
  return sqrt(mpm_dofs_dot(d, NULL, v, w));
}

/* The scale the step's residuals are measured against: the larger of the impulses over the step
 * of the elastic forces at its start and of gravity (with the regions), dt f^n and dt m g, on
 * the free DOFs, in the preconditioner's norm. A residual is a momentum out of balance; this
 * scale does not grow with the body's own momentum (|M v*| of a body falling fast let CG stop
 * with an error that strained it: elastic energy out of nothing), does not count the reactions
 * of the DOFs that obstacles hold (a clamped beam's support force let the test pass with the
 * free part out of balance: the beam froze short of its deflection), and does not vanish for a
 * body at rest (a relative drop of a tiny residual cost a resting body full price every step).
 * t, w: work. */
static double impulse_scale(mpm_implicit *s, mpm_real *const diag[3], mpm_real *const t[3],
                            mpm_real *const w[3]) {
  mpm_dofs *d = s->dofs;
  const long n = (long)d->count;
  for (int c = 0; c < 3; ++c) {
    const mpm_real *restrict fc = d->f[c];
    mpm_real *restrict tc = t[c];
    const mpm_real dt = s->dt;
#pragma omp parallel for simd schedule(static) if (n > MPM_PARALLEL_MIN)
    for (long i = 0; i < n; ++i) tc[i] = dt * fc[i];
  }
  const double elastic = free_norm(s, diag, t, w);
  for (int c = 0; c < 3; ++c) {
    const mpm_real *restrict m = d->mass, *restrict a = s->accel[c];
    mpm_real *restrict tc = t[c];
    const mpm_real dt = s->dt, g = s->gravity[c];
#pragma omp parallel for simd schedule(static) if (n > MPM_PARALLEL_MIN)
    for (long i = 0; i < n; ++i) tc[i] = dt * m[i] * (a ? a[i] : g);
  }
  const double weight = free_norm(s, diag, t, w);
  return elastic > weight ? elastic : weight;
}

/* The impulse below which the real type cannot tell a force apart, on the free DOFs in the
 * preconditioner's norm: a stress is resolved to eps E (the rounding of F near I, eps of the
 * real type), a DOF's force to about eps K_ii dx / sqrt(27) (K_ii = (D_ii - m_i) / dt^2 the
 * DOF's stiffness, about E dx; the roundings of the particles it sums add in quadrature), so
 * its impulse over the step to 0.2 eps dx (D_ii - m_i) / dt. A 1e9 Pa block at
 * rest at dx = 2 cm holds its weight as a strain of 13 ulps of F in float: its forces are
 * resolved to about its weight, and a tolerance below that cannot be met. 0 without a
 * preconditioner. t, w: work. */
static double resolution_scale(mpm_implicit *s, mpm_real *const diag[3], mpm_real *const t[3],
                               mpm_real *const w[3]) {
  if (!diag) return 0;
  mpm_dofs *d = s->dofs;
  const long n = (long)d->count;
  /* the roundings of the stencil's some 27 particles add in quadrature: sqrt(27) / 27 */
  const mpm_real k = R_(0.2) * MPM_REAL_EPS * s->tc->kernel.dx / (s->theta * s->dt);
  for (int c = 0; c < 3; ++c) {
    const mpm_real *restrict m = d->mass, *restrict dc = diag[c];
    mpm_real *restrict tc = t[c];
#pragma omp parallel for simd schedule(static) if (n > MPM_PARALLEL_MIN)
    for (long i = 0; i < n; ++i) tc[i] = m[i] > 0 && dc[i] > m[i] ? k * (dc[i] - m[i]) : 0;
  }
  return free_norm(s, diag, t, w);
}

/* The rounding of an incremental potential of size |E| in the real type: differences below it
 * are not a change of E. */
static double energy_noise(double E) {
  return 16 * (double)MPM_REAL_EPS * fabs(E);
}

/* With Newton iterations, Zhu's step v_1 is searched too: from v_0 (the constrained components
 * of v_1, zero elsewhere: no motion but what the obstacles impose) along v_1 - v_0, the
 * longest of 1, 1/2, ... whose incremental potential is below E(v_0) beyond rounding (the whole
 * step also when E cannot tell them apart: near rest v_1 and v_0 differ by less than E
 * resolves, and v_1 is kept). A linearized step across an
 * impact or a large rotation can overshoot badly; this keeps every iterate a descent. Returns
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
  const double noise = energy_noise(E0);
  double alpha = 1;
  for (int h = 0; h < 12; ++h, alpha *= 0.5) {
    mpm_dofs_copy(d, d->v, t);
    mpm_dofs_axpy(d, (mpm_real)alpha, d0, t);
    displacement(s, t, u);
    mpm_implicit_displace(s, u);
    /* the whole step where E cannot tell it from no motion; a part of it only where E is
       lower beyond rounding (a sliver of a step is not a descent E can see) */
    const double E = incremental_potential(s, t, u);
    if (h == 0 ? E <= E0 + noise : E < E0 - noise) {
      mpm_dofs_axpy(d, (mpm_real)alpha, d0, d->v);
      return 0;
    }
  }
  return 1;
}

/* |P (b - A x)|_D (D = diag, or I); r, w: work. */
static double residual_norm(mpm_implicit *s, mpm_real *const diag[3], mpm_real *const b[3],
                            mpm_real *const x[3], mpm_real *const r[3], mpm_real *const w[3]) {
  mpm_implicit_apply(s, 1, s->apply_scale, x, r);
  mpm_dofs_xpby(s->dofs, b, -1, r); /* r = b - A x */
  return free_norm(s, diag, r, w);
}

/* The first solve's initial guess: the one of v^n + dt g (exact for a body in free fall),
 * v^n (a body in steady motion) and rest (a stiff body at rest) whose residual is smallest,
 * each with the constrained components of v (which holds v* moved onto the constraints) and
 * their free part its own. Not v* = v^n + dt (g + f^n / m): it is the explicit step, which at
 * an implicit step's length multiplies a stiff mode's error by about (omega dt)^2 (10^4 for a
 * 1e9 Pa block at dt = 1 ms); a residual below the tolerance ends the solve at once, so from v*
 * errors of the rounding's size grew step after step up to the tolerance, and stayed there as
 * elastic energy out of nothing. Returns the kept guess's residual. g, r, w, keep: work. */
static double initial_guess(mpm_implicit *s, mpm_real *const diag[3], mpm_real *const b[3],
                            mpm_real *const g[3], mpm_real *const r[3], mpm_real *const w[3],
                            mpm_real *const keep[3]) {
  mpm_dofs *d = s->dofs;
  const long n = (long)d->count;
  double best = INFINITY;
  for (int k = 0; k < 3; ++k) {
    /* g = v + P (candidate - v): the candidate's free part, v's constrained one */
    for (int c = 0; c < 3; ++c) {
      const mpm_real *restrict vc = d->v[c], *restrict v0 = d->v0[c], *restrict a = s->accel[c];
      mpm_real *restrict gc = g[c];
      const mpm_real dt = s->dt, gr = s->gravity[c];
      if (k == 0) {
#pragma omp parallel for simd schedule(static) if (n > MPM_PARALLEL_MIN)
        for (long i = 0; i < n; ++i)
          gc[i] = d->mass[i] > 0 ? v0[i] + dt * (a ? a[i] : gr) - vc[i] : 0;
      } else if (k == 1) {
#pragma omp parallel for simd schedule(static) if (n > MPM_PARALLEL_MIN)
        for (long i = 0; i < n; ++i) gc[i] = v0[i] - vc[i];
      } else {
#pragma omp parallel for simd schedule(static) if (n > MPM_PARALLEL_MIN)
        for (long i = 0; i < n; ++i) gc[i] = -vc[i];
      }
    }
    mpm_implicit_project(s, g);
    mpm_dofs_axpy(d, 1, d->v, g);
    const double norm = residual_norm(s, diag, b, g, r, w);
    if (norm < best) {
      best = norm;
      mpm_dofs_copy(d, g, keep);
    }
  }
  mpm_dofs_copy(d, keep, d->v);
  return best;
}

/* -grad E at v = d->v into b, projected, and its free norm (E into *E):
 *   grad E = m (v - v^n - dt g) - dt f(u(v))
 * with F^ displaced to u(v) (left so for the Hessian). t, u, w: work. */
static double neg_gradient(mpm_implicit *s, mpm_real *const diag[3], mpm_real *const b[3],
                           mpm_real *const t[3], mpm_real *const u[3], mpm_real *const w[3],
                           double *E) {
  mpm_dofs *d = s->dofs;
  displacement(s, d->v, u);
  mpm_implicit_displace(s, u);
  *E = incremental_potential(s, d->v, t); /* t = v - v^n - dt g */
  mpm_implicit_forces(s, b);
  const long n = (long)d->count;
  for (int c = 0; c < 3; ++c) {
    const mpm_real *restrict m = d->mass, *restrict tc = t[c];
    mpm_real *restrict bc = b[c];
    const mpm_real dt = s->dt;
#pragma omp parallel for simd schedule(static) if (n > MPM_PARALLEL_MIN)
    for (long i = 0; i < n; ++i) bc[i] = -(m[i] * tc[i] - dt * bc[i]);
  }
  return free_norm(s, diag, b, w);
}

/* With theta < 1: the velocity the particles move and deform by, v_m = u(v) / dt =
 * (1 - theta) v^n + theta v^{n+1}, as the DOF set's vm (grid/dofs.h: G2P reads it). MPM_OK, or
 * MPM_ERR_NOMEM when out of memory. */
static mpm_status motion(mpm_implicit *s) {
  mpm_dofs *d = s->dofs;
  mpm_real **vm = mpm_dofs_vector(d, "imp.motion");
  if (!vm) return MPM_ERR_NOMEM;
  const long n = (long)d->count;
  const mpm_real a = s->theta, b = 1 - s->theta;
#pragma omp parallel for schedule(static)
  for (long i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) vm[c][i] = a * d->v[c][i] + b * d->v0[c][i];
  for (int c = 0; c < 3; ++c) d->vm[c] = vm[c];
  return MPM_OK;
}

/* A step whose first residual is within this many tolerances of the scale is near balance:
 * no line search (E is no guide there). */
#define NEAR_BALANCE 10

/* The precision a solve can reach from its first residual in the real type: CG asks no more
 * of |r0| than this drop (cg.h, floor_drop). */
#define REACHABLE_DROP (sizeof(mpm_real) == 4 ? 1e-5 : 1e-10)

mpm_status mpm_implicit_solve(mpm_implicit *s, const mpm_implicit_options *o,
                              mpm_implicit_result *r) {
  memset(r, 0, sizeof *r);
  r->cg_converged = 1;
  mpm_dofs *d = s->dofs;
  mpm_real **vstar = mpm_dofs_vector(d, "imp.vstar"), **b = mpm_dofs_vector(d, "imp.b");
  mpm_real **diag = mpm_dofs_vector(d, "imp.diag"), **t = mpm_dofs_vector(d, "imp.t");
  mpm_real **u = mpm_dofs_vector(d, "imp.u"), **dv = mpm_dofs_vector(d, "imp.dv");
  mpm_real **v1 = mpm_dofs_vector(d, "imp.v1"), **norm = mpm_dofs_vector(d, "imp.norm");
  if (!vstar || !b || !diag || !t || !u || !dv || !v1 || !norm) return MPM_ERR_NOMEM;
  /* f^n as the incremental potential's own gradient has it at u = 0, in place of P2G's: the
     batched stresses of P2G differ from it by a few ulps of a stress that mostly balances the
     weight, which made a body at rest look 5% of its weight out of balance to the Newton test
     (and Zhu's step aim at another v* than the potential's) */
  start_velocity(s);
  s->newmark = s->theta < 1;
  if (s->theta < 1) { /* Newmark's positions where nothing touches an obstacle */
    const int touching = touches(s);
    if (touching < 0) return MPM_ERR_NOMEM;
    if (touching) s->theta = 1;
    s->apply_scale = s->theta * s->dt * s->dt;
  }
  if (s->theta < 1) { /* the base u(0) = dt (1 - theta) v^n */
    displacement(s, NULL, u);
    mpm_implicit_displace(s, u);
  } else {
    mpm_implicit_displace(s, NULL);
  }
  mpm_implicit_forces(s, d->f);
  if (predictor(s)) return MPM_ERR_NOMEM;
  mpm_dofs_copy(d, d->v, vstar);
  if (mpm_implicit_constraints(s, d->v)) return MPM_ERR_NOMEM; /* the initial guess obeys them */
  /* Newton iteration 1 (Zhu eq. 12): (M + dt^2 K(0)) v = M v* */
  const long n = (long)d->count;
  for (int c = 0; c < 3; ++c) {
    const mpm_real *restrict m = d->mass, *restrict vs = vstar[c];
    mpm_real *restrict bc = b[c];
#pragma omp parallel for simd schedule(static) if (n > MPM_PARALLEL_MIN)
    for (long i = 0; i < n; ++i) bc[i] = m[i] * vs[i];
  }
  mpm_implicit_build(s); /* at u(0) (displaced above) */
  if (o->precondition) jacobi(s, diag, norm);
  /* the preconditioner, and the norm of the residuals */
  mpm_real *const *D = o->precondition ? diag : NULL, *const *N = o->precondition ? norm : NULL;
  /* the tolerance is relative to the step's impulses, and never below what the real type
     resolves */
  const double resolved = resolution_scale(s, N, t, u) / o->cg_tolerance;
  double scale = impulse_scale(s, N, t, u);
  if (resolved > scale) scale = resolved;
  /* the first solve to the tolerance (or as far as the real type reaches); the Newton
     directions after it as inexact Newton does, to the tolerance of their own residual */
  mpm_cg_options first = {
      o->cg_tolerance, o->cg_max_iterations, scale, REACHABLE_DROP, NULL, s, 0, N};
  mpm_cg_options direction = {
      o->cg_tolerance, o->cg_max_iterations, scale, o->cg_tolerance, NULL, s, 0, N};
  const double guess = initial_guess(s, N, b, dv, t, u, v1);
  /* the multigrid V-cycle preconditions CG where it is built, from the first solve that Jacobi
     does not end in a few iterations (solve()); the residuals are measured in the Jacobi norm D
     either way (cg.h), so the tolerance means the same */
  s->mg_wanted = o->precondition == 2 && mpm_implicit_multigrid_supported(s);
  s->mg_built = s->mg_prepared = s->mg_stale = 0;
  mpm_cg_result cg;
  if (mpm_implicit_pcg(s, D, b, d->v, guess <= NEAR_BALANCE * o->cg_tolerance * scale, &first, r,
                       &cg))
    return MPM_ERR_NOMEM;
  r->newton_iterations = 1;
  /* Newton iterations 2.. on E (Gast et al. 2015): the gradient in b, the step in dv; the step
     is done when the free DOFs' momentum out of balance is within the tolerance of the scale */
  int searched = 0;
  const int near = cg.residual0 <= NEAR_BALANCE * o->cg_tolerance * scale;
  for (int k = 1; k < o->newton_iterations;) {
    double E0;
    const double gn = neg_gradient(s, N, b, t, u, dv, &E0);
    if (!(gn > o->cg_tolerance * scale)) break; /* converged */
    /* Near balance (Zhu's step began within 10 tolerances of it) the step cannot overshoot,
       and E is no guide: its differences are below its rounding (a 1e9 Pa block at rest in
       float: E(v_0 + a (v_1 - v_0)) scattered by 20% over a, and a sliver of the step "won",
       which stopped the body). There, a step that did not halve the imbalance its linear
       model removed is final: the model predicts nothing below this level (in float, the
       rounding of F at the small displacements of a body nearly at rest), and more Newton
       iterations would only chase it, every step. */
    if (!searched && near && gn >= 0.5 * cg.residual0) break;
    const int search = !searched && !near;
    searched = 1;
    if (search) { /* Zhu's step checked against no motion first, once */
      mpm_dofs_copy(d, d->v, v1);
      if (first_step_search(s, u, dv, t)) {
        /* no step along it lowers E: the one out of balance the less is kept, not rest by
           default (which froze a beam short of its deflection) */
        double E;
        if (neg_gradient(s, N, b, t, u, dv, &E) >= gn)
          mpm_dofs_copy(d, v1, d->v);
        else
          r->line_search_failed = 1;
      }
      continue; /* the gradient where the search left v */
    }
    mpm_implicit_build(s);
    /* a solve the hierarchy took long for has its values rebuilt at the new iterate (the matrix
       moved far from the one it was built for) */
    mpm_implicit_multigrid_mark(s, cg.iterations);
    /* Jacobi's diagonal at the new iterate where Jacobi preconditions (the multigrid once
       built preconditions the rest of the step); the norm stays the step's */
    if (o->precondition && !s->mg_built) jacobi(s, diag, NULL);
    /* otherwise the multigrid of the first iteration preconditions the later ones: a
       preconditioner need only be near the matrix, and building it (assembly and Galerkin
       products, 65 ms a step of the rubber bunny at 2 threads) costs some 20 Jacobi-CG
       iterations (the matrix-free action: 2.5 ms) */
    for (int c = 0; c < 3; ++c) memset(dv[c], 0, (size_t)n * sizeof(mpm_real));
    if (mpm_implicit_pcg(s, D, b, dv, 1, &direction, r, &cg)) return MPM_ERR_NOMEM;
    r->newton_iterations = ++k;
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
      if (E <= E0 + 1e-4 * alpha * slope + energy_noise(E0)) {
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
  r->mg_cycle_seconds = s->mg_cycle_seconds;
  return s->theta < 1 ? motion(s) : MPM_OK;
}

/* The momentum the colliders took in the solved step (stats.csv): the part of a DOF's momentum
 * change that neither gravity nor the elastic forces at the end of the step explain, the
 * obstacle's impulse on it (backward Euler, m (v - v^n) = dt m g + dt f(u) + J):
 *   J_i = m_i (v_i - v*_i) + dt f_i^n - dt f_i(u(v)),  v* = v^n + dt (g + f^n / m),
 * zero at free DOFs (there it is the Newton residual, to the solver's tolerance). The DOFs
 * inside collider (pose) c where the step began (or, for corners, where it takes them) count
 * for c, the first one when several hold a DOF; the collider took -J_i. One more evaluation of
 * the forces, only when the caller measures. Sums per chunk of DOFs, then in chunk order, so
 * they do not depend on the thread count. */
#define TAKEN_CHUNK 1024
mpm_status mpm_implicit_collider_taken(mpm_implicit *s, double *taken) {
  mpm_dofs *d = s->dofs;
  const mpm_boundary *bd = s->boundary;
  const int nc = bd->collider_count;
  mpm_real **vstar = mpm_dofs_vector(d, "imp.vstar"), **u = mpm_dofs_vector(d, "imp.u");
  mpm_real **f = mpm_dofs_vector(d, "imp.b");
  const long n = (long)d->count, chunks = (n + TAKEN_CHUNK - 1) / TAKEN_CHUNK;
  double *slots = mpm_arena_alloc(s->arena, ((size_t)chunks * 3 * (size_t)nc + 1) * sizeof *slots);
  if (!vstar || !u || !f || !slots) return MPM_ERR_NOMEM;
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
  return MPM_OK;
}
