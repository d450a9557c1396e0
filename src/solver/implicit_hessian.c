/* implicit_hessian.c - the pieces of the implicit system (see implicit.h): the displaced
 * deformation gradients, the factored stress derivatives, the matrix-free action of
 * M + dt^2 K, the elastic forces and energy, and the Jacobi diagonal, for the material points
 * (spatial form, Stomakhin et al. 2013 eq. 6 and sec. 4) and the particle domains (Zhu eqs.
 * 14-19, domain/domain_hessian.c). */
#include "solver/implicit.h"
#include "core/lanes.h"
#include "core/parallel.h"
#include "core/mat3.h"
#include "core/ordered_sum.h"
#include "core/particles.h"
#include "core/svd3.h"
#include "transfer/operators.h"

#include <string.h>

static void *arena_reals(mpm_arena *a, size_t n) {
  return mpm_arena_alloc(a, (n + 1) * sizeof(mpm_real));
}

/* The per-particle arrays live in the step's arena, allocated once per step so that Newton
 * iterations do not grow it; G is twice as long so that the diagonal's 18 quadratic-form
 * entries fit in it. */
mpm_status mpm_implicit_init(mpm_implicit *s) {
  const size_t n = s->p ? s->p->count : 0;
  int ok = 1;
  mpm_real **h[5] = {s->hU, s->hW, s->hA, s->hs, s->hk};
  const int hn[5] = {9, 9, 6, 3, 3};
  for (int k = 0; k < 5; ++k)
    for (int c = 0; c < hn[k]; ++c) ok = ok && (h[k][c] = arena_reals(s->arena, n)) != NULL;
  for (int c = 0; c < 9; ++c) {
    s->Fh[c] = arena_reals(s->arena, n);
    s->G[c] = arena_reals(s->arena, 2 * n); /* G, then the second half: Q's overflow below */
    ok = ok && s->Fh[c] && s->G[c];
  }
  s->constraint_count = 0;
  s->constraint_dof = NULL;
  s->constraint_P = NULL;
  if (!(s->theta > 0 && s->theta <= 1)) s->theta = 1; /* unset: backward Euler */
  s->apply_scale = s->theta * s->dt * s->dt;
  for (int c = 0; c < 3; ++c) s->px[c] = NULL;
  s->depth = NULL;
  if (s->part_count == 0 && s->p) { /* one grid, one kernel: one part */
    s->part[0] = (mpm_implicit_part){s->grid, s->tc->kernel, 0, n};
    s->part_count = 1;
  }
  s->ghosted = NULL;
  s->mg = NULL;
  s->mg_row_of = NULL;
  s->mg_cycle_seconds = 0;
  s->mg_dof = NULL;
  if (ok && s->levels) ok = (s->ghosted = mpm_dofs_vector(s->dofs, "imp.ghosted")) != NULL;
  if (ok && s->domains)
    ok = mpm_domain_hessian_init(&s->dh, s->domains, s->tc->materials, s->arena) == MPM_OK;
  if (ok && s->domains) s->dh.exact = s->exact;
  return ok ? MPM_OK : MPM_ERR_NOMEM;
}

/* Particle i's material: the scene's own where its moduli do not vary per particle, else its
 * moduli at the particle's plastic state and temperature, in *own (the copy per particle cost
 * the implicit step's force and energy loops more than their stresses). */
static const mpm_material *material_at(const mpm_implicit *s, size_t i, mpm_material *own) {
  const mpm_material *m = &s->tc->materials[s->p->material[i]];
  if (!mpm_material_varies(m)) return m;
  *own = mpm_material_at_temperature(m, s->p->plastic[i], s->p->temperature[i]);
  return own;
}

/* ---- the material points' transfers, part by part ------------------------------------------ */

/* Part k's transfer context, particles and the per-particle arrays a[0 .. n) from its first
 * particle. */
static void part_view(const mpm_implicit *s, int k, mpm_transfer_ctx *tc, mpm_particles *v,
                      mpm_real *const *a, int n, mpm_real **out) {
  const mpm_implicit_part *pt = &s->part[k];
  *tc = *s->tc;
  tc->kernel = pt->kernel;
  *v = mpm_particles_range(s->p, pt->begin, pt->count);
  for (int c = 0; c < n; ++c) out[c] = a[c] + pt->begin;
}

/* A DOF-set vector as part k's grid's node arrays. */
static void grid_view(const mpm_implicit *s, int k, mpm_real *const u[3], mpm_real *v[3]) {
  for (int c = 0; c < 3; ++c) v[c] = u[c] + s->part[k].grid->dof_begin;
}

/* s->G = sum_j u_j grad w_jp^T for every material point; on levels from E u (the ghosts
 * gathered from their parents). */
static void gather_gradients(mpm_implicit *s, mpm_real *const u[3]) {
  mpm_real *const *src = u;
  if (s->levels) {
    mpm_dofs_copy(s->dofs, u, s->ghosted);
    mpm_adaptive_grid_gather(s->levels, 3, s->ghosted);
    src = s->ghosted;
  }
  for (int k = 0; k < s->part_count; ++k) {
    if (!s->part[k].count) continue;
    mpm_transfer_ctx tc;
    mpm_particles v;
    mpm_real *G[9], *ul[3];
    part_view(s, k, &tc, &v, s->G, 9, G);
    grid_view(s, k, src, ul);
    mpm_gather_gradients(&tc, s->part[k].grid, (const mpm_real *const *)ul, &v, G);
  }
}

/* y += sum_p M_p grad w_ip over every part (M = s->G), then on levels the ghosts' sums to
 * their parents (E^T). */
static void scatter_matrices(mpm_implicit *s, mpm_real *const y[3]) {
  for (int k = 0; k < s->part_count; ++k) {
    if (!s->part[k].count) continue;
    mpm_transfer_ctx tc;
    mpm_particles v;
    mpm_real *M[9], *yl[3];
    part_view(s, k, &tc, &v, s->G, 9, M);
    grid_view(s, k, y, yl);
    mpm_scatter_matrices(&tc, s->part[k].grid, yl, (const mpm_real *const *)M, &v);
  }
  if (s->levels) mpm_adaptive_grid_scatter(s->levels, 3, y);
}

/* d += the quadratic forms Q (18 arrays) over every part, then on levels diag(E^T D E) of the
 * ghosts' sums D. */
static void scatter_quadratic_forms(mpm_implicit *s, mpm_real *const d[3], mpm_real *const Q[18]) {
  for (int k = 0; k < s->part_count; ++k) {
    if (!s->part[k].count) continue;
    mpm_transfer_ctx tc;
    mpm_particles v;
    mpm_real *Qk[18], *dl[3];
    part_view(s, k, &tc, &v, Q, 18, Qk);
    grid_view(s, k, d, dl);
    mpm_scatter_quadratic_forms(&tc, s->part[k].grid, dl, (const mpm_real *const *)Qk, &v);
  }
  if (s->levels) mpm_adaptive_grid_scatter_squared(s->levels, 3, d);
}

void mpm_implicit_displace(mpm_implicit *s, mpm_real *const u[3]) {
  s->dh.exact = s->exact;
  const mpm_particles *p = s->p;
  const long n = p ? (long)p->count : 0;
  if (n > 0) {
    if (u) gather_gradients(s, u);
#pragma omp parallel for schedule(static)
    for (long i = 0; i < n; ++i) {
      mpm_real F[9], Fh[9];
      for (int c = 0; c < 9; ++c) F[c] = p->F[c][i];
      if (u) {
        mpm_real A[9]; /* I + G */
        for (int c = 0; c < 9; ++c) A[c] = s->G[c][i] + (c % 4 == 0 ? 1 : 0);
        mpm_m3_mul(A, F, Fh);
      } else {
        memcpy(Fh, F, sizeof Fh);
      }
      for (int c = 0; c < 9; ++c) s->Fh[c][i] = Fh[c];
    }
  }
  if (s->domains) mpm_domain_hessian_displace(&s->dh, u);
}

/* Particle i's factored derivative from its definite Hessian H at F^: U, W = F V, the diagonal
 * block's six entries and the pairs' eigenvalues. */
static void store_hessian(mpm_implicit *s, long i, const mpm_stress_hessian *H) {
  mpm_real F[9], W[9];
  for (int c = 0; c < 9; ++c) F[c] = s->p->F[c][i];
  mpm_m3_mul(F, H->V, W);
  for (int c = 0; c < 9; ++c) s->hU[c][i] = H->U[c], s->hW[c][i] = W[c];
  static const int sym[6] = {0, 1, 2, 4, 5, 8};
  for (int c = 0; c < 6; ++c) s->hA[c][i] = H->A[sym[c]];
  for (int c = 0; c < 3; ++c) s->hs[c][i] = H->lsym[c], s->hk[c][i] = H->lskew[c];
}

void mpm_implicit_build(mpm_implicit *s) {
  s->dh.exact = s->exact;
  const long n = s->p ? (long)s->p->count : 0;
  if (!s->exact) {
    /* in chunks of MPM_STRESS_CHUNK: a run of particles of one material whose moduli do not
       vary per particle takes its SVDs in one SIMD batch (mpm_svd3_batch) where the model
       builds its Hessian from a given SVD; the others one at a time */
#pragma omp parallel for schedule(dynamic, 4)
    for (long c0 = 0; c0 < n; c0 += MPM_STRESS_CHUNK) {
      const long c1 = c0 + MPM_STRESS_CHUNK < n ? c0 + MPM_STRESS_CHUNK : n;
      for (long a = c0, b; a < c1; a = b) {
        const int32_t mi = s->p->material[a];
        for (b = a + 1; b < c1 && s->p->material[b] == mi;) ++b;
        const mpm_material *mat = &s->tc->materials[mi];
        if (mat->model->hessian_definite_svd && !mpm_material_varies(mat)) {
          _Alignas(MPM_ALIGN) mpm_real U[9][MPM_STRESS_CHUNK], V[9][MPM_STRESS_CHUNK],
              sg[3][MPM_STRESS_CHUNK];
          const mpm_real *F[9];
          mpm_real *Up[9], *Vp[9], *sp[3];
          for (int c = 0; c < 9; ++c) F[c] = s->Fh[c] + a, Up[c] = U[c], Vp[c] = V[c];
          for (int c = 0; c < 3; ++c) sp[c] = sg[c];
          mpm_svd3_batch((int)(b - a), F, Up, sp, Vp);
          for (long i = a; i < b; ++i) {
            const long q = i - a;
            mpm_real Ui[9], si[3], Vi[9];
            for (int c = 0; c < 9; ++c) Ui[c] = U[c][q], Vi[c] = V[c][q];
            for (int c = 0; c < 3; ++c) si[c] = sg[c][q];
            mpm_stress_hessian H;
            mat->model->hessian_definite_svd(mat, Ui, si, Vi, &H);
            store_hessian(s, i, &H);
          }
        } else {
          for (long i = a; i < b; ++i) {
            mpm_material own;
            const mpm_material *m = material_at(s, (size_t)i, &own);
            mpm_real Fh[9];
            for (int c = 0; c < 9; ++c) Fh[c] = s->Fh[c][i];
            mpm_stress_hessian H;
            m->model->hessian_definite(m, Fh, &H);
            store_hessian(s, i, &H);
          }
        }
      }
    }
  }
  if (s->domains) mpm_domain_hessian_build(&s->dh);
}

/* M = U P^(U^T X W) W^T: the factored definite stress derivative of particle i applied to the
 * velocity gradient X, M = (C : X F) F^T (isotropic.h's blocks: A on the diagonal, each pair
 * (a, b) by lsym on its symmetric and lskew on its skew part). Written on scalars so that the
 * caller's loop over particles vectorizes. */
typedef struct factored_view {
  const mpm_real *U[9], *W[9], *A[6], *ls[3], *lk[3];
} factored_view;

static factored_view view_of(const mpm_implicit *s) {
  factored_view v;
  for (int c = 0; c < 9; ++c) v.U[c] = s->hU[c], v.W[c] = s->hW[c];
  for (int c = 0; c < 6; ++c) v.A[c] = s->hA[c];
  for (int c = 0; c < 3; ++c) v.ls[c] = s->hs[c], v.lk[c] = s->hk[c];
  return v;
}

/* The operator on one particle (T = mpm_real), on MPM_NLANES consecutive particles
 * (T = mpm_vn) or on MPM_NLANES particles anywhere (T = mpm_vn, I their indices), from the
 * structure of arrays. */
#define LOAD_REAL(a, i) ((a)[i])
#define LOAD_VN(a, i) load_vn((a) + (i))
#define GATHER_VN(a, idx) gather_vn((a), (idx))
static inline mpm_vn load_vn(const mpm_real *a) {
  mpm_vn v;
  memcpy(&v, a, sizeof v);
  return v;
}
static inline mpm_vn gather_vn(const mpm_real *a, const uint32_t *idx) {
  mpm_vn v;
  for (int l = 0; l < MPM_NLANES; ++l) v[l] = a[idx[l]];
  return v;
}
#define DEFINE_FACTORED_OP(NAME, T, I, LOAD)                                                       \
  MPM_ALWAYS_INLINE void NAME(const factored_view *s, I i, const T X[9], T M[9]) {                 \
    T U[9], W[9], Tm[9], d[9], q[9];                                                               \
    for (int c = 0; c < 9; ++c) U[c] = LOAD(s->U[c], i), W[c] = LOAD(s->W[c], i);                  \
    for (int r = 0; r < 3; ++r) /* d = U^T X W */                                                  \
      for (int c = 0; c < 3; ++c)                                                                  \
        Tm[3 * r + c] = U[r] * X[c] + U[3 + r] * X[3 + c] + U[6 + r] * X[6 + c];                   \
    for (int r = 0; r < 3; ++r)                                                                    \
      for (int c = 0; c < 3; ++c)                                                                  \
        d[3 * r + c] = Tm[3 * r] * W[c] + Tm[3 * r + 1] * W[3 + c] + Tm[3 * r + 2] * W[6 + c];     \
    const T a00 = LOAD(s->A[0], i), a01 = LOAD(s->A[1], i), a02 = LOAD(s->A[2], i);                \
    const T a11 = LOAD(s->A[3], i), a12 = LOAD(s->A[4], i), a22 = LOAD(s->A[5], i);                \
    q[0] = a00 * d[0] + a01 * d[4] + a02 * d[8];                                                   \
    q[4] = a01 * d[0] + a11 * d[4] + a12 * d[8];                                                   \
    q[8] = a02 * d[0] + a12 * d[4] + a22 * d[8];                                                   \
    static const int pi[3] = {0, 0, 1}, pj[3] = {1, 2, 2};                                         \
    for (int k = 0; k < 3; ++k) {                                                                  \
      const int a = pi[k], b = pj[k];                                                              \
      const T sy = R_(0.5) * (d[3 * a + b] + d[3 * b + a]);                                        \
      const T sk = R_(0.5) * (d[3 * a + b] - d[3 * b + a]);                                        \
      const T ls = LOAD(s->ls[k], i), lk = LOAD(s->lk[k], i);                                      \
      q[3 * a + b] = ls * sy + lk * sk;                                                            \
      q[3 * b + a] = ls * sy - lk * sk;                                                            \
    }                                                                                              \
    for (int r = 0; r < 3; ++r) /* M = U q W^T */                                                  \
      for (int c = 0; c < 3; ++c)                                                                  \
        Tm[3 * r + c] = U[3 * r] * q[c] + U[3 * r + 1] * q[3 + c] + U[3 * r + 2] * q[6 + c];       \
    for (int r = 0; r < 3; ++r)                                                                    \
      for (int c = 0; c < 3; ++c)                                                                  \
        M[3 * r + c] =                                                                             \
            Tm[3 * r] * W[3 * c] + Tm[3 * r + 1] * W[3 * c + 1] + Tm[3 * r + 2] * W[3 * c + 2];    \
  }
DEFINE_FACTORED_OP(factored_op, mpm_real, long, LOAD_REAL)
DEFINE_FACTORED_OP(factored_op_lanes, mpm_vn, long, LOAD_VN)
DEFINE_FACTORED_OP(factored_op_gather, mpm_vn, const uint32_t *, GATHER_VN)

/* M = (C_i : X F) F^T at particle i's F^ (the model's own derivative in exact mode). */
static void stress_op(const mpm_implicit *s, long i, const mpm_real X[9], mpm_real M[9]) {
  if (!s->exact) {
    const factored_view v = view_of(s);
    factored_op(&v, i, X, M);
    return;
  }
  mpm_material own;
  const mpm_material *m = material_at(s, (size_t)i, &own);
  mpm_real Fh[9], F[9], dF[9], dP[9];
  for (int c = 0; c < 9; ++c) Fh[c] = s->Fh[c][i], F[c] = s->p->F[c][i];
  mpm_m3_mul(X, F, dF);
  m->model->dpdf_action(m, Fh, dF, dP);
  mpm_m3_mul_bt(dP, F, M);
}

void mpm_implicit_tangent(const mpm_implicit *s, const uint32_t idx[MPM_NLANES], int count,
                          mpm_vn C[81]) {
  uint32_t at[MPM_NLANES]; /* the lanes past count repeat the first particle */
  for (int l = 0; l < MPM_NLANES; ++l) at[l] = idx[l < count ? l : 0];
  const mpm_vn v = s->apply_scale * gather_vn(s->p->vol0, at);
  if (s->exact) { /* the model's own derivative, one particle at a time */
    for (int l = 0; l < MPM_NLANES; ++l)
      for (int bd = 0; bd < 9; ++bd) {
        mpm_real X[9] = {0}, M[9];
        X[bd] = 1;
        stress_op(s, (long)at[l], X, M);
        for (int ac = 0; ac < 9; ++ac) C[9 * ac + bd][l] = v[l] * M[ac];
      }
    return;
  }
  /* the factored form, the lanes' particles at once: column (b, d) of C is the operator on the
     unit gradient e_b e_d^T */
  const factored_view fv = view_of(s);
  const mpm_vn zero = {0}, one = zero + 1;
  for (int bd = 0; bd < 9; ++bd) {
    mpm_vn X[9], M[9];
    for (int c = 0; c < 9; ++c) X[c] = c == bd ? one : zero;
    factored_op_gather(&fv, at, X, M);
    for (int ac = 0; ac < 9; ++ac) C[9 * ac + bd] = v * M[ac];
  }
}

void mpm_implicit_apply(mpm_implicit *s, mpm_real mass_scale, mpm_real scale, mpm_real *const x[3],
                        mpm_real *const y[3]) {
  s->dh.exact = s->exact;
  const mpm_dofs *d = s->dofs;
  const long nd = (long)d->count;
#pragma omp parallel if (nd > MPM_PARALLEL_MIN)
  for (int c = 0; c < 3; ++c) {
    const mpm_real *restrict xc = x[c], *restrict m = d->mass;
    mpm_real *restrict yc = y[c];
#pragma omp for simd schedule(static) nowait
    for (long i = 0; i < nd; ++i) yc[i] = mass_scale * m[i] * xc[i];
  }
  const mpm_particles *p = s->p;
  const long n = p ? (long)p->count : 0;
  if (n > 0) {
    /* G_p = sum_j x_j grad w_jp^T, then M_p = scale V0 (C : G F) F^T in place of G */
    gather_gradients(s, x);
    if (s->exact) {
#pragma omp parallel for schedule(static)
      for (long i = 0; i < n; ++i) {
        mpm_real G[9], M[9];
        for (int c = 0; c < 9; ++c) G[c] = s->G[c][i];
        stress_op(s, i, G, M);
        const mpm_real v = scale * p->vol0[i];
        for (int c = 0; c < 9; ++c) s->G[c][i] = v * M[c];
      }
    } else {
      const factored_view fv = view_of(s);
      mpm_real *Gp[9];
      for (int c = 0; c < 9; ++c) Gp[c] = s->G[c];
      const mpm_real *restrict vol0 = p->vol0;
      const long nv = n / MPM_NLANES;
#pragma omp parallel for schedule(static)
      for (long k = 0; k < nv; ++k) {
        const long i = k * MPM_NLANES;
        mpm_vn G[9], M[9];
        for (int c = 0; c < 9; ++c) G[c] = load_vn(Gp[c] + i);
        factored_op_lanes(&fv, i, G, M);
        const mpm_vn v = scale * load_vn(vol0 + i);
        for (int c = 0; c < 9; ++c) {
          const mpm_vn out = v * M[c];
          memcpy(Gp[c] + i, &out, sizeof out);
        }
      }
      for (long i = nv * MPM_NLANES; i < n; ++i) { /* the remainder, one at a time */
        mpm_real G[9], M[9];
        for (int c = 0; c < 9; ++c) G[c] = Gp[c][i];
        factored_op(&fv, i, G, M);
        const mpm_real v = scale * vol0[i];
        for (int c = 0; c < 9; ++c) Gp[c][i] = v * M[c];
      }
    }
    scatter_matrices(s, y);
  }
  if (s->domains) mpm_domain_hessian_apply(&s->dh, scale, x, y);
}

void mpm_implicit_forces(mpm_implicit *s, mpm_real *const f[3]) {
  const mpm_dofs *d = s->dofs;
  const long nd = (long)d->count;
  for (int c = 0; c < 3; ++c) memset(f[c], 0, (size_t)nd * sizeof(mpm_real));
  const mpm_particles *p = s->p;
  const long n = p ? (long)p->count : 0;
  if (n > 0) {
    /* f_i = -sum_p V0 P(F^_p) F_p^T grad w_ip */
#pragma omp parallel for schedule(static)
    for (long i = 0; i < n; ++i) {
      mpm_material own;
      const mpm_material *m = material_at(s, (size_t)i, &own);
      mpm_real Fh[9], F[9], P[9], M[9];
      for (int c = 0; c < 9; ++c) Fh[c] = s->Fh[c][i], F[c] = p->F[c][i];
      m->model->pk1(m, Fh, P);
      mpm_m3_mul_bt(P, F, M);
      const mpm_real v = -p->vol0[i];
      for (int c = 0; c < 9; ++c) s->G[c][i] = v * M[c];
    }
    scatter_matrices(s, f);
  }
  if (s->domains) mpm_domain_hessian_forces(&s->dh, f);
}

static double point_energy(const void *ctx, size_t i) {
  const mpm_implicit *s = ctx;
  mpm_material own;
  const mpm_material *m = material_at(s, i, &own);
  mpm_real Fh[9];
  for (int c = 0; c < 9; ++c) Fh[c] = s->Fh[c][i];
  return (double)s->p->vol0[i] * (double)m->model->energy(m, Fh);
}

double mpm_implicit_energy(mpm_implicit *s) {
  /* in ordered chunks: the same sum for any thread count (the line search compares them) */
  double e = s->p ? mpm_ordered_sum(s->p->count, point_energy, s) : 0;
  if (s->domains) e += mpm_domain_hessian_energy(&s->dh);
  mpm_reduce_all(s->dofs->reduction, MPM_REDUCE_SUM, &e, 1); /* over every process */
  return e;
}

void mpm_implicit_diagonal(mpm_implicit *s, mpm_real mass_scale, mpm_real scale,
                           mpm_real *const d[3]) {
  s->dh.exact = s->exact;
  const mpm_dofs *dofs = s->dofs;
  const long nd = (long)dofs->count;
  for (int c = 0; c < 3; ++c) {
    mpm_real *restrict dc = d[c];
    const mpm_real *restrict m = dofs->mass;
#pragma omp parallel for simd schedule(static)
    for (long i = 0; i < nd; ++i) dc[i] = mass_scale * m[i];
  }
  const mpm_particles *p = s->p;
  const long n = p ? (long)p->count : 0;
  if (n > 0) {
    /* The diagonal entry of component a at node i is V0 b^T S^a b with b = F^T grad w_ip and
     * S^a_jl = C_aj,al (eqs. 18-19 in the spatial form), i.e. grad w^T Q^a grad w with
     * Q^a = V0 F S^a F^T. The 18 entries of Q live in G's two halves (G was sized 2n). */
    mpm_real *Q[18];
    for (int c = 0; c < 9; ++c) {
      Q[c] = s->G[c];
      Q[9 + c] = s->G[c] + n + 1;
    }
    /* Q^a_nm = V0 [(C : e_a e_n^T F) F^T]_am: grad w^T Q^a grad w is the diagonal entry; the
       factored form MPM_NLANES consecutive particles at once, the rest (and the exact mode's
       derivative) one at a time */
    static const int e6[6] = {0, 1, 2, 4, 5, 8};
    const long nv = s->exact ? 0 : n / MPM_NLANES;
    if (nv > 0) {
      const factored_view fv = view_of(s);
      const mpm_vn zero = {0}, one = zero + 1;
#pragma omp parallel for schedule(static)
      for (long k = 0; k < nv; ++k) {
        const long i = k * MPM_NLANES;
        const mpm_vn v = scale * load_vn(p->vol0 + i);
        for (int a = 0; a < 3; ++a) {
          mpm_vn Qa[9];
          for (int e = 0; e < 3; ++e) {
            mpm_vn X[9], M[9];
            for (int c = 0; c < 9; ++c) X[c] = c == 3 * a + e ? one : zero;
            factored_op_lanes(&fv, i, X, M);
            for (int m = 0; m < 3; ++m) Qa[3 * e + m] = M[3 * a + m];
          }
          for (int q = 0; q < 6; ++q) {
            const mpm_vn out = v * Qa[e6[q]];
            memcpy(Q[6 * a + q] + i, &out, sizeof out);
          }
        }
      }
    }
#pragma omp parallel for schedule(static)
    for (long i = nv * MPM_NLANES; i < n; ++i) {
      const mpm_real v = scale * p->vol0[i];
      for (int a = 0; a < 3; ++a) {
        mpm_real Qa[9];
        for (int e = 0; e < 3; ++e) {
          mpm_real X[9] = {0}, M[9];
          X[3 * a + e] = 1;
          stress_op(s, i, X, M);
          for (int m = 0; m < 3; ++m) Qa[3 * e + m] = M[3 * a + m];
        }
        for (int q = 0; q < 6; ++q) Q[6 * a + q][i] = v * Qa[e6[q]];
      }
    }
    scatter_quadratic_forms(s, d, Q);
  }
  if (s->domains) mpm_domain_hessian_diagonal(&s->dh, scale, d);
}
