/* implicit_hessian.c - the pieces of the implicit system (see implicit.h): the displaced
 * deformation gradients, the factored stress derivatives, the matrix-free action of
 * M + dt^2 K, the elastic forces and energy, and the Jacobi diagonal, for the material points
 * (spatial form, Stomakhin et al. 2013 eq. 6 and sec. 4) and the particle domains (Zhu eqs.
 * 14-19, domain/domain_hessian.c). */
#include "solver/implicit.h"
#include "core/mat3.h"
#include "transfer/operators.h"

#include <string.h>

static void *arena_reals(mpm_arena *a, size_t n) {
  return mpm_arena_alloc(a, (n + 1) * sizeof(mpm_real));
}

/* The per-particle arrays live in the step's arena, allocated once per step so that Newton
 * iterations do not grow it; G is twice as long so that the diagonal's 18 quadratic-form
 * entries fit in it. */
int mpm_implicit_init(mpm_implicit *s) {
  const size_t n = s->p ? s->p->count : 0;
  s->H = mpm_arena_alloc(s->arena, (n + 1) * sizeof *s->H);
  int ok = s->H != NULL;
  for (int c = 0; c < 9; ++c) {
    s->Fh[c] = arena_reals(s->arena, n);
    s->G[c] = arena_reals(s->arena, 2 * n); /* G, then the second half: Q's overflow below */
    ok = ok && s->Fh[c] && s->G[c];
  }
  s->constraint_count = 0;
  s->constraint_dof = NULL;
  s->constraint_P = NULL;
  s->apply_scale = s->dt * s->dt;
  for (int c = 0; c < 3; ++c) s->px[c] = NULL;
  s->depth = NULL;
  if (ok && s->domains)
    ok = mpm_domain_hessian_init(&s->dh, s->domains, s->tc->materials, s->arena) == 0;
  if (ok && s->domains) s->dh.exact = s->exact;
  return ok ? 0 : -1;
}

static mpm_material material_at(const mpm_implicit *s, size_t i) {
  return mpm_material_at(&s->tc->materials[s->p->material[i]], s->p->plastic[i]);
}

/* A DOF-set vector as the grid level's node arrays. */
static void level_view(const mpm_implicit *s, mpm_real *const u[3], mpm_real *v[3]) {
  for (int c = 0; c < 3; ++c) v[c] = u[c] + s->grid->dof_begin;
}

void mpm_implicit_displace(mpm_implicit *s, mpm_real *const u[3]) {
  s->dh.exact = s->exact;
  const mpm_particles *p = s->p;
  const long n = p ? (long)p->count : 0;
  if (n > 0) {
    if (u) {
      mpm_real *ul[3];
      level_view(s, u, ul);
      mpm_gather_gradients(s->tc, s->grid, (const mpm_real *const *)ul, p, s->G);
    }
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

void mpm_implicit_build(mpm_implicit *s) {
  s->dh.exact = s->exact;
  const long n = s->p ? (long)s->p->count : 0;
  if (!s->exact) {
#pragma omp parallel for schedule(static)
    for (long i = 0; i < n; ++i) {
      const mpm_material m = material_at(s, (size_t)i);
      mpm_real Fh[9];
      for (int c = 0; c < 9; ++c) Fh[c] = s->Fh[c][i];
      m.model->hessian_definite(&m, Fh, &s->H[i]);
    }
  }
  if (s->domains) mpm_domain_hessian_build(&s->dh);
}

/* dP = C_i : dF at particle i's F^. */
static void stress_action(const mpm_implicit *s, size_t i, const mpm_real dF[9], mpm_real dP[9]) {
  if (s->exact) {
    const mpm_material m = material_at(s, i);
    mpm_real Fh[9];
    for (int c = 0; c < 9; ++c) Fh[c] = s->Fh[c][i];
    m.model->dpdf_action(&m, Fh, dF, dP);
  } else {
    mpm_stress_hessian_action(&s->H[i], dF, dP);
  }
}

void mpm_implicit_apply(mpm_implicit *s, mpm_real mass_scale, mpm_real scale, mpm_real *const x[3],
                        mpm_real *const y[3]) {
  s->dh.exact = s->exact;
  const mpm_dofs *d = s->dofs;
  const long nd = (long)d->count;
  for (int c = 0; c < 3; ++c) {
    const mpm_real *restrict xc = x[c], *restrict m = d->mass;
    mpm_real *restrict yc = y[c];
#pragma omp parallel for simd schedule(static)
    for (long i = 0; i < nd; ++i) yc[i] = mass_scale * m[i] * xc[i];
  }
  const mpm_particles *p = s->p;
  const long n = p ? (long)p->count : 0;
  if (n > 0) {
    mpm_real *xl[3], *yl[3];
    level_view(s, x, xl);
    level_view(s, y, yl);
    /* G_p = sum_j x_j grad w_jp^T, dF = G F, then M_p = scale V0 (C : dF) F^T in place of G */
    mpm_gather_gradients(s->tc, s->grid, (const mpm_real *const *)xl, p, s->G);
#pragma omp parallel for schedule(static)
    for (long i = 0; i < n; ++i) {
      mpm_real G[9], F[9], dF[9], dP[9], M[9];
      for (int c = 0; c < 9; ++c) G[c] = s->G[c][i], F[c] = p->F[c][i];
      mpm_m3_mul(G, F, dF);
      stress_action(s, (size_t)i, dF, dP);
      mpm_m3_mul_bt(dP, F, M);
      const mpm_real v = scale * p->vol0[i];
      for (int c = 0; c < 9; ++c) s->G[c][i] = v * M[c];
    }
    mpm_scatter_matrices(s->tc, s->grid, yl, (const mpm_real *const *)s->G, p);
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
      const mpm_material m = material_at(s, (size_t)i);
      mpm_real Fh[9], F[9], P[9], M[9];
      for (int c = 0; c < 9; ++c) Fh[c] = s->Fh[c][i], F[c] = p->F[c][i];
      m.model->pk1(&m, Fh, P);
      mpm_m3_mul_bt(P, F, M);
      const mpm_real v = -p->vol0[i];
      for (int c = 0; c < 9; ++c) s->G[c][i] = v * M[c];
    }
    mpm_real *fl[3];
    level_view(s, f, fl);
    mpm_scatter_matrices(s->tc, s->grid, fl, (const mpm_real *const *)s->G, p);
  }
  if (s->domains) mpm_domain_hessian_forces(&s->dh, f);
}

double mpm_implicit_energy(mpm_implicit *s) {
  const mpm_particles *p = s->p;
  double e = 0; /* serial, in particle order: the same sum for any thread count */
  for (size_t i = 0; p && i < p->count; ++i) {
    const mpm_material m = material_at(s, i);
    mpm_real Fh[9];
    for (int c = 0; c < 9; ++c) Fh[c] = s->Fh[c][i];
    e += (double)p->vol0[i] * (double)m.model->energy(&m, Fh);
  }
  if (s->domains) e += mpm_domain_hessian_energy(&s->dh);
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
     * S^a_jl = C_aj,al (eqs. 18-19 in the spatial form): grad w^T Q^a grad w with
     * Q^a = V0 F S^a F^T. The 18 entries of Q live in G's two halves (G was sized 2n). */
    mpm_real *Q[18];
    for (int c = 0; c < 9; ++c) {
      Q[c] = s->G[c];
      Q[9 + c] = s->G[c] + n + 1;
    }
#pragma omp parallel for schedule(static)
    for (long i = 0; i < n; ++i) {
      mpm_real F[9];
      for (int c = 0; c < 9; ++c) F[c] = p->F[c][i];
      const mpm_real v = scale * p->vol0[i];
      for (int a = 0; a < 3; ++a) {
        mpm_real S[9], T[9], Qa[9];
        for (int l = 0; l < 3; ++l) {
          mpm_real dF[9] = {0}, dP[9];
          dF[3 * a + l] = 1;
          stress_action(s, (size_t)i, dF, dP);
          for (int j = 0; j < 3; ++j) S[3 * j + l] = dP[3 * a + j];
        }
        mpm_m3_mul(F, S, T);
        mpm_m3_mul_bt(T, F, Qa);
        const int e[6] = {0, 1, 2, 4, 5, 8};
        for (int k = 0; k < 6; ++k) Q[6 * a + k][i] = v * Qa[e[k]];
      }
    }
    mpm_real *dl[3];
    level_view(s, d, dl);
    mpm_scatter_quadratic_forms(s->tc, s->grid, dl, (const mpm_real *const *)Q, p);
  }
  if (s->domains) mpm_domain_hessian_diagonal(&s->dh, scale, d);
}
