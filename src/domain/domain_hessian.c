/* domain_hessian.c - the particle domains' forces, energy, Hessian action and Jacobi diagonal
 * for the implicit solve (see domain_hessian.h). */
#include "domain/domain_hessian.h"
#include "core/ordered_sum.h"
#include "domain/enrich.h"

#include <string.h>

mpm_status mpm_domain_hessian_init(mpm_domain_hessian *h, mpm_domain_set *s,
                                   const mpm_material *materials, mpm_arena *arena) {
  memset(h, 0, sizeof *h);
  h->s = s;
  h->materials = materials;
  const size_t np = s->particles.count + 1, nc = s->corner_count + 1;
  h->H = mpm_arena_alloc(arena, np * sizeof *h->H);
  h->Fh = mpm_arena_alloc(arena, np * sizeof *h->Fh);
  h->dP = mpm_arena_alloc(arena, np * sizeof *h->dP);
  int ok = h->H && h->Fh && h->dP;
  for (int d = 0; d < 3; ++d) {
    h->cu[d] = mpm_arena_alloc(arena, nc * sizeof(mpm_real));
    h->cy[d] = mpm_arena_alloc(arena, nc * sizeof(mpm_real));
    ok = ok && h->cu[d] && h->cy[d];
  }
  if (ok && mpm_hourglass_on(s)) {
    h->kappa = mpm_arena_alloc(arena, np * sizeof *h->kappa);
    h->qh = mpm_arena_alloc(arena, np * sizeof *h->qh);
    h->Q = mpm_arena_alloc(arena, np * sizeof *h->Q);
    ok = h->kappa && h->qh && h->Q;
    for (size_t q = 0; ok && q + 1 < np; ++q) {
      h->kappa[q] = mpm_hourglass_kappa(s, materials, q);
      memset(h->qh[q], 0, sizeof h->qh[q]);
    }
  }
  return ok ? MPM_OK : MPM_ERR_NOMEM;
}

/* cu = E u (0 for unused corners: their rows are empty). */
static void corners_from_dofs(mpm_domain_hessian *h, mpm_real *const u[3]) {
  const mpm_real *const uc[3] = {u[0], u[1], u[2]};
  mpm_embedding_gather(&h->s->corner_grid, 3, uc, h->cu);
}

/* sum_a (cu_a - cu_0) g_qa^T: sum_a g_qa = 0, so the reference corner changes nothing in exact
 * arithmetic but makes a uniform displacement give exactly 0 (see transfer/operators.c). */
static void corner_gradient(const mpm_domain_hessian *h, long q, mpm_real dF[9]) {
  const mpm_domain_set *s = h->s;
  const uint32_t c0 = s->corner[q][0];
  const mpm_real ref[3] = {h->cu[0][c0], h->cu[1][c0], h->cu[2][c0]};
  for (int e = 0; e < 9; ++e) dF[e] = 0;
  for (int a = 1; a < MPM_HEX_CORNERS; ++a) {
    const uint32_t c = s->corner[q][a];
    mpm_real gc[3];
    const mpm_real *g = mpm_domain_gradient(s, (uint32_t)q, (uint32_t)a, gc);
    for (int r = 0; r < 3; ++r) {
      const mpm_real du = h->cu[r][c] - ref[r];
      for (int t = 0; t < 3; ++t) dF[3 * r + t] += du * g[t];
    }
  }
}

void mpm_domain_hessian_displace(mpm_domain_hessian *h, mpm_real *const u[3]) {
  mpm_domain_set *s = h->s;
  const mpm_particles *p = &s->particles;
  if (u) corners_from_dofs(h, u);
  const long n = (long)p->count;
#pragma omp parallel for schedule(static)
  for (long q = 0; q < n; ++q) {
    for (int e = 0; e < 9; ++e) h->Fh[q][e] = p->F[e][q];
    if (h->kappa && h->kappa[q] > 0) { /* q_alpha at x + u */
      mpm_hourglass_q(s, (size_t)q, s->cx, h->qh[q]);
      if (u) {
        mpm_real du[4][3];
        mpm_hourglass_q(s, (size_t)q, h->cu, du);
        for (int al = 0; al < 4; ++al)
          for (int d = 0; d < 3; ++d) h->qh[q][al][d] += du[al][d];
      }
    }
    if (!s->active[q] || !u) continue;
    mpm_real dF[9];
    corner_gradient(h, q, dF);
    for (int e = 0; e < 9; ++e) h->Fh[q][e] += dF[e];
  }
}

static mpm_material material_of(const mpm_domain_hessian *h, long q) {
  const mpm_particles *p = &h->s->particles;
  return mpm_material_at_temperature(&h->materials[p->material[q]], p->plastic[q],
                                     p->temperature[q]);
}

void mpm_domain_hessian_build(mpm_domain_hessian *h) {
  const long n = (long)h->s->particles.count;
  if (h->exact) return; /* the exact action evaluates dP/dF at F^ itself */
#pragma omp parallel for schedule(static)
  for (long q = 0; q < n; ++q) {
    if (!h->s->active[q]) continue;
    const mpm_material m = material_of(h, q);
    m.model->hessian_definite(&m, h->Fh[q], &h->H[q]);
  }
}

static void action(const mpm_domain_hessian *h, long q, const mpm_real dF[9], mpm_real dP[9]) {
  if (h->exact) {
    const mpm_material m = material_of(h, q);
    m.model->dpdf_action(&m, h->Fh[q], dF, dP);
  } else {
    mpm_stress_hessian_action(&h->H[q], dF, dP);
  }
}

/* cy_a = scale sum_p (per-particle matrix)_p g_pa, through the adjacency; then y += E^T cy. */
static void corners_to_dofs(mpm_domain_hessian *h, mpm_real scale, mpm_real *const y[3]) {
  mpm_domain_set *s = h->s;
  const long nc = (long)s->corner_count;
#pragma omp parallel for schedule(static)
  for (long c = 0; c < nc; ++c) {
    double f[3] = {0, 0, 0};
    for (uint32_t j = s->adj_start[c]; j < s->adj_start[c + 1]; ++j) {
      const uint32_t q = s->adj[j] / MPM_HEX_CORNERS, a = s->adj[j] % MPM_HEX_CORNERS;
      mpm_real gc[3];
      const mpm_real *g = mpm_domain_gradient(s, q, a, gc), *M = h->dP[q];
      for (int d = 0; d < 3; ++d)
        f[d] += M[3 * d] * g[0] + M[3 * d + 1] * g[1] + M[3 * d + 2] * g[2];
      if (h->kappa) /* + sum_alpha h_alpha,a kappa q_alpha */
        for (int al = 0; al < 4; ++al)
          for (int d = 0; d < 3; ++d) f[d] += mpm_hourglass_modes[al][a] * h->Q[q][al][d];
    }
    for (int d = 0; d < 3; ++d) h->cy[d][c] = (mpm_real)(scale * f[d]);
  }
  const mpm_real *const cy[3] = {h->cy[0], h->cy[1], h->cy[2]};
  mpm_embedding_scatter(&s->corner_grid, 3, cy, y);
}

void mpm_domain_hessian_apply(mpm_domain_hessian *h, mpm_real scale, mpm_real *const x[3],
                              mpm_real *const y[3]) {
  mpm_domain_set *s = h->s;
  const mpm_particles *p = &s->particles;
  corners_from_dofs(h, x);
  const long n = (long)p->count;
#pragma omp parallel for schedule(static)
  for (long q = 0; q < n; ++q) {
    if (!s->active[q]) {
      memset(h->dP[q], 0, sizeof h->dP[q]);
      continue;
    }
    mpm_real dF[9], dP[9];
    corner_gradient(h, q, dF);
    action(h, q, dF, dP);
    for (int e = 0; e < 9; ++e) h->dP[q][e] = p->vol0[q] * dP[e];
    if (h->kappa && h->kappa[q] > 0) { /* the hourglass Hessian kappa sum h_alpha h_alpha^T */
      mpm_hourglass_q(s, (size_t)q, h->cu, h->Q[q]);
      for (int al = 0; al < 4; ++al)
        for (int d = 0; d < 3; ++d) h->Q[q][al][d] *= h->kappa[q];
    } else if (h->kappa) {
      memset(h->Q[q], 0, sizeof h->Q[q]);
    }
  }
  corners_to_dofs(h, scale, y);
}

void mpm_domain_hessian_forces(mpm_domain_hessian *h, mpm_real *const f[3]) {
  mpm_domain_set *s = h->s;
  const mpm_particles *p = &s->particles;
  const long n = (long)p->count;
#pragma omp parallel for schedule(static)
  for (long q = 0; q < n; ++q) {
    if (!s->active[q]) {
      memset(h->dP[q], 0, sizeof h->dP[q]);
      continue;
    }
    const mpm_material m = material_of(h, q);
    mpm_real P[9];
    m.model->pk1(&m, h->Fh[q], P);
    for (int e = 0; e < 9; ++e) h->dP[q][e] = p->vol0[q] * P[e];
    if (h->kappa) /* the hourglass forces -kappa sum_alpha h_alpha q_alpha */
      for (int al = 0; al < 4; ++al)
        for (int d = 0; d < 3; ++d) h->Q[q][al][d] = h->kappa[q] * h->qh[q][al][d];
  }
  corners_to_dofs(h, -1, f);
}

static double particle_energy(const void *ctx, size_t q) {
  const mpm_domain_hessian *h = ctx;
  const mpm_domain_set *s = h->s;
  if (!s->active[q]) return 0;
  const mpm_material m = material_of(h, (long)q);
  double e = (double)s->particles.vol0[q] * (double)m.model->energy(&m, h->Fh[q]);
  if (h->kappa && h->kappa[q] > 0) {
    double q2 = 0;
    for (int al = 0; al < 4; ++al)
      for (int d = 0; d < 3; ++d) q2 += (double)h->qh[q][al][d] * (double)h->qh[q][al][d];
    e += 0.5 * (double)h->kappa[q] * q2;
  }
  return e;
}

double mpm_domain_hessian_energy(const mpm_domain_hessian *h) {
  /* in ordered chunks: the same sum for any thread count */
  return mpm_ordered_sum(h->s->particles.count, particle_energy, h);
}

/* S^c_jl = C_cj,cl for c = 0..2 (each symmetric): nine actions on e_c e_l^T. */
static void diagonal_blocks(const mpm_domain_hessian *h, long q, mpm_real S[3][9]) {
  for (int c = 0; c < 3; ++c)
    for (int l = 0; l < 3; ++l) {
      mpm_real dF[9] = {0}, dP[9];
      dF[3 * c + l] = 1;
      action(h, q, dF, dP);
      for (int j = 0; j < 3; ++j) S[c][3 * j + l] = dP[3 * c + j];
    }
}

#define MAX_NODES (MPM_HEX_CORNERS * 64)

void mpm_domain_hessian_diagonal(mpm_domain_hessian *h, mpm_real scale, mpm_real *const d[3]) {
  const mpm_domain_set *s = h->s;
  const mpm_particles *p = &s->particles;
  const mpm_embedding *E = &s->corner_grid;
  uint32_t col[MAX_NODES];
  mpm_real b[MAX_NODES][3], hs[MAX_NODES][4];
  for (size_t q = 0; q < p->count; ++q) {
    if (!s->active[q]) continue;
    /* b_i = sum_a E_ai g_qa over the union of the corners' stencils */
    int count = 0;
    for (int a = 0; a < MPM_HEX_CORNERS; ++a) {
      const uint32_t c = s->corner[q][a];
      const mpm_real *g = s->g[q][a];
      for (uint32_t e = E->row_start[c]; e < E->row_start[c] + E->row_len[c]; ++e) {
        int k = 0;
        while (k < count && col[k] != E->col[e]) ++k;
        if (k == count) {
          if (count == MAX_NODES) continue;
          col[count] = E->col[e];
          b[count][0] = b[count][1] = b[count][2] = 0;
          hs[count][0] = hs[count][1] = hs[count][2] = hs[count][3] = 0;
          ++count;
        }
        for (int t = 0; t < 3; ++t) b[k][t] += E->w[e] * g[t];
        /* the hourglass vectors seen by the DOF: sum_a E_ai h_alpha,a */
        for (int al = 0; al < 4; ++al) hs[k][al] += E->w[e] * mpm_hourglass_modes[al][a];
      }
    }
    mpm_real S[3][9];
    diagonal_blocks(h, (long)q, S);
    const mpm_real v = scale * p->vol0[q];
    const mpm_real kap = h->kappa ? scale * h->kappa[q] : 0;
    for (int k = 0; k < count; ++k) {
      mpm_real hg = 0; /* kappa sum_alpha (sum_a E_ai h_alpha,a)^2, the same for every component */
      for (int al = 0; al < 4; ++al) hg += hs[k][al] * hs[k][al];
      for (int c = 0; c < 3; ++c) {
        mpm_real sum = 0;
        for (int j = 0; j < 3; ++j)
          for (int l = 0; l < 3; ++l) sum += b[k][j] * S[c][3 * j + l] * b[k][l];
        d[c][col[k]] += v * sum + kap * hg;
      }
    }
  }
}
