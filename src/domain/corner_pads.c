/* corner_pads.c - the corners' transfers to and from the sparse grid through pads of nodes
 * (see corner_pads.h). */
#include "domain/corner_pads.h"
#include "core/parallel.h"
#include "domain/domain.h"
#include "grid/sparse_grid.h"

#include <string.h>

#define ALWAYS_INLINE static inline __attribute__((always_inline))
#define SIDE_MAX (MPM_BLOCK + MPM_STENCIL_MAX - 1) /* a pad's nodes per axis */
#define SCATTER_FIELDS 7                           /* mass, momentum, force */
#define SCATTER_STRIDE 8
#define GATHER_STRIDE 6 /* v, v0 */

void mpm_corner_pads_free(mpm_corner_pads *P) {
  mpm_scatter_schedule_free(&P->schedule);
  memset(P, 0, sizeof *P);
}

int mpm_corner_pads_plan(mpm_corner_pads *P, const mpm_domain_set *s, const mpm_grid *g,
                         const mpm_kernel *k, mpm_arena *scratch) {
  P->on = 0;
  const mpm_sparse_grid *sg = &g->impl.sparse;
  const size_t nc = s->corner_count, nk = sg->block_count;
  P->block = mpm_arena_alloc(scratch, (nc + 1) * sizeof *P->block);
  uint8_t *key_colour = mpm_arena_alloc(scratch, nk + 1);
  for (int d = 0; d < 3; ++d) P->dv[d] = mpm_arena_alloc(scratch, (nc + 1) * sizeof(mpm_real));
  if (!P->block || !key_colour || !P->dv[0] || !P->dv[1] || !P->dv[2]) return -1;
  const mpm_domain_enrichment *en = &s->enrich;
  const int enriched = en->count > 0;
  int missing = 0;
#pragma omp parallel reduction(| : missing)
  {
    int32_t last[3] = {INT32_MIN, INT32_MIN, INT32_MIN}, last_block = -1;
#pragma omp for schedule(static)
    for (long c = 0; c < (long)nc; ++c) {
      P->block[c] = -1;
      if (!s->corner_use[c]) continue;
      if (enriched && en->enriched[c]) { /* its own DOF (Zhu sec. 5.2) */
        P->block[c] = MPM_SCHEDULE_OWN_COLUMNS;
        continue;
      }
      const mpm_real xr[3] = {s->cx[0][c] - g->origin[0], s->cx[1][c] - g->origin[1],
                              s->cx[2][c] - g->origin[2]};
      mpm_stencil st;
      mpm_kernel_stencil(k, xr, &st);
      const int32_t bb[3] = {st.base[0] >> MPM_BLOCK_BITS, st.base[1] >> MPM_BLOCK_BITS,
                             st.base[2] >> MPM_BLOCK_BITS};
      if (bb[0] != last[0] || bb[1] != last[1] || bb[2] != last[2]) {
        last_block = mpm_sparse_grid_find(sg, bb);
        memcpy(last, bb, sizeof last);
      }
      if (last_block < 0) {
        missing = 1;
        continue;
      }
      P->block[c] = last_block;
    }
  }
  if (missing) return -1;
  /* the colour of a block is the parity of its coordinates (grid.c, stencil_nodes) */
  for (size_t c = 0; c < nc; ++c)
    if (P->block[c] >= 0) {
      const int32_t *bc = sg->coord[P->block[c]];
      key_colour[P->block[c]] = (uint8_t)((bc[0] & 1) << 2 | (bc[1] & 1) << 1 | (bc[2] & 1));
    }
  mpm_scatter_schedule *S = &P->schedule;
  if (mpm_scatter_schedule_build(S, nc, P->block, nk, key_colour)) return -1;
  const size_t groups = S->colour_start[MPM_SCHEDULE_COLOURS];
  P->pad = mpm_arena_alloc(scratch, (groups + 1) * sizeof *P->pad);
  P->org = mpm_arena_alloc(scratch, (groups + 1) * sizeof *P->org);
  if (!P->pad || !P->org) return -1;
  for (size_t q = 0; q < groups; ++q) {
    const int32_t *bc = sg->coord[mpm_scatter_schedule_group_key(S, P->block, q)];
    for (int o = 0; o < 8; ++o) {
      const int32_t nb[3] = {bc[0] + ((o >> 2) & 1), bc[1] + ((o >> 1) & 1), bc[2] + (o & 1)};
      if ((P->pad[q][o] = mpm_sparse_grid_find(sg, nb)) < 0) return -1;
    }
    for (int d = 0; d < 3; ++d) P->org[q][d] = bc[d] * MPM_BLOCK;
  }
  P->grid_dofs = (uint32_t)g->dof_begin;
  P->corner_dofs = (uint32_t)en->dof_begin;
  for (int d = 0; d < 3; ++d) P->origin[d] = g->origin[d];
  P->on = 1;
  return 0;
}

/* The DOFs of group q's pad of S^3 nodes, (i, j, k) at (i S + j) S + k. */
ALWAYS_INLINE void pad_dofs(const mpm_corner_pads *P, size_t q, const int S, uint32_t *dof) {
  for (int i = 0; i < S; ++i)
    for (int j = 0; j < S; ++j)
      for (int k = 0; k < S; ++k) {
        const int o = (i >= MPM_BLOCK) << 2 | (j >= MPM_BLOCK) << 1 | (k >= MPM_BLOCK);
        const uint32_t local = (uint32_t)((((i & 3) << 2) | (j & 3)) << 2 | (k & 3));
        dof[(i * S + j) * S + k] = P->grid_dofs + (uint32_t)P->pad[q][o] * MPM_BLOCK_NODES + local;
      }
}

/* Corner c's stencil and the pad index of its base node in group q's pad. */
ALWAYS_INLINE int corner_stencil(const mpm_corner_pads *P, const mpm_domain_set *s,
                                 const mpm_kernel *k, size_t q, const int S, uint32_t c,
                                 mpm_stencil *st, mpm_real xr[3]) {
  for (int d = 0; d < 3; ++d) xr[d] = s->cx[d][c] - P->origin[d];
  mpm_kernel_stencil(k, xr, st);
  return ((st->base[0] - P->org[q][0]) * S + (st->base[1] - P->org[q][1])) * S +
         (st->base[2] - P->org[q][2]);
}

ALWAYS_INLINE void scatter_group(const int W, const mpm_corner_pads *P, const mpm_domain_set *s,
                                 const mpm_kernel *k, size_t q, const mpm_real *const carrier[7],
                                 const mpm_real *const mB[9], mpm_real *const values[7]) {
  const int S = MPM_BLOCK + W - 1;
  uint32_t dof[SIDE_MAX * SIDE_MAX * SIDE_MAX];
  mpm_real pad[SIDE_MAX * SIDE_MAX * SIDE_MAX * SCATTER_STRIDE];
  pad_dofs(P, q, S, dof);
  /* the pad starts from the values: each node then sums in the order of the rows' scatter */
  for (int n = 0; n < S * S * S; ++n)
    for (int f = 0; f < SCATTER_FIELDS; ++f) pad[n * SCATTER_STRIDE + f] = values[f][dof[n]];
  const mpm_scatter_schedule *sch = &P->schedule;
  for (uint32_t r = sch->group_start[q]; r < sch->group_start[q + 1]; ++r) {
    const uint32_t c = sch->group_row[r];
    mpm_stencil st;
    mpm_real xr[3];
    const int base = corner_stencil(P, s, k, q, S, c, &st, xr);
    mpm_real ca[SCATTER_FIELDS];
    for (int f = 0; f < SCATTER_FIELDS; ++f) ca[f] = carrier[f][c];
    for (int i = 0; i < W; ++i)
      for (int j = 0; j < W; ++j)
        for (int l = 0; l < W; ++l) {
          const mpm_real w = st.w[0][i] * st.w[1][j] * st.w[2][l];
          if (w == 0) continue; /* the rows hold no such entry */
          mpm_real *at = pad + (base + (i * S + j) * S + l) * SCATTER_STRIDE;
          for (int f = 0; f < SCATTER_FIELDS; ++f) at[f] += w * ca[f];
        }
    if (!mB) continue;
    /* APIC: the affine moment, after the row's weights as in mpm_embedding_scatter_moments */
    mpm_real cm[9];
    for (int e = 0; e < 9; ++e) cm[e] = mB[e][c];
    for (int i = 0; i < W; ++i)
      for (int j = 0; j < W; ++j)
        for (int l = 0; l < W; ++l) {
          if (st.w[0][i] * st.w[1][j] * st.w[2][l] == 0) continue;
          const mpm_real a0 = st.a[0][i] * st.w[1][j] * st.w[2][l];
          const mpm_real a1 = st.w[0][i] * st.a[1][j] * st.w[2][l];
          const mpm_real a2 = st.w[0][i] * st.w[1][j] * st.a[2][l];
          mpm_real *at = pad + (base + (i * S + j) * S + l) * SCATTER_STRIDE + 1;
          for (int kk = 0; kk < 3; ++kk)
            at[kk] += a0 * cm[3 * kk] + a1 * cm[3 * kk + 1] + a2 * cm[3 * kk + 2];
        }
  }
  for (int n = 0; n < S * S * S; ++n)
    for (int f = 0; f < SCATTER_FIELDS; ++f) values[f][dof[n]] = pad[n * SCATTER_STRIDE + f];
}

/* The scatter of the groups of one colour with a kernel of width W. */
ALWAYS_INLINE void scatter_colour(const int W, const mpm_corner_pads *P, const mpm_domain_set *s,
                                  const mpm_kernel *k, long g0, long g1,
                                  const mpm_real *const carrier[7], const mpm_real *const mB[9],
                                  mpm_real *const values[7]) {
#pragma omp parallel for schedule(dynamic, 4)
  for (long q = g0; q < g1; ++q) scatter_group(W, P, s, k, (size_t)q, carrier, mB, values);
}

void mpm_corner_pads_scatter(const mpm_corner_pads *P, const mpm_domain_set *s, const mpm_kernel *k,
                             const mpm_real *const carrier[7], const mpm_real *const mB[9],
                             mpm_real *const values[7]) {
  const mpm_scatter_schedule *sch = &P->schedule;
  for (int colour = 0; colour < MPM_SCHEDULE_COLOURS; ++colour) {
    const long g0 = (long)sch->colour_start[colour], g1 = (long)sch->colour_start[colour + 1];
    switch (k->width) { /* the width a constant in each copy: the stencil loops unroll */
    case 2:
      scatter_colour(2, P, s, k, g0, g1, carrier, mB, values);
      break;
    case 3:
      scatter_colour(3, P, s, k, g0, g1, carrier, mB, values);
      break;
    default:
      scatter_colour(4, P, s, k, g0, g1, carrier, mB, values);
      break;
    }
  }
  /* enriched corners: identity rows into their DOFs (weight 1, APIC factors 0) */
  const long own = (long)sch->own_rows;
  const mpm_real one = 1, zero = 0;
#pragma omp parallel for schedule(static) if (own >= MPM_PARALLEL_MIN)
  for (long j = 0; j < own; ++j) {
    const uint32_t c = sch->own_row[j];
    const uint32_t i = P->corner_dofs + s->enrich.slot[c];
    for (int f = 0; f < SCATTER_FIELDS; ++f) values[f][i] += one * carrier[f][c];
    if (mB)
      for (int kk = 0; kk < 3; ++kk)
        values[1 + kk][i] +=
            zero * mB[3 * kk][c] + zero * mB[3 * kk + 1][c] + zero * mB[3 * kk + 2][c];
  }
}

ALWAYS_INLINE void gather_group(const int W, const mpm_corner_pads *P, mpm_domain_set *s,
                                const mpm_kernel *k, size_t q, const int apic,
                                const mpm_real *const v[3], const mpm_real *const v0[3]) {
  const int S = MPM_BLOCK + W - 1;
  uint32_t dof[SIDE_MAX * SIDE_MAX * SIDE_MAX];
  mpm_real pad[SIDE_MAX * SIDE_MAX * SIDE_MAX * GATHER_STRIDE];
  pad_dofs(P, q, S, dof);
  for (int n = 0; n < S * S * S; ++n)
    for (int d = 0; d < 3; ++d) {
      pad[n * GATHER_STRIDE + d] = v[d][dof[n]];
      pad[n * GATHER_STRIDE + 3 + d] = v0[d][dof[n]];
    }
  const mpm_scatter_schedule *sch = &P->schedule;
  for (uint32_t r = sch->group_start[q]; r < sch->group_start[q + 1]; ++r) {
    const uint32_t c = sch->group_row[r];
    mpm_stencil st;
    mpm_real xr[3];
    const int base = corner_stencil(P, s, k, q, S, c, &st, xr);
    /* v^g_a = sum_i E_ai v_i^{n+1} and the FLIP increment sum_i E_ai (v_i^{n+1} - v_i^n) */
    mpm_real vnew[3] = {0, 0, 0}, dv[3] = {0, 0, 0};
    for (int i = 0; i < W; ++i)
      for (int j = 0; j < W; ++j)
        for (int l = 0; l < W; ++l) {
          const mpm_real w = st.w[0][i] * st.w[1][j] * st.w[2][l];
          if (w == 0) continue;
          const mpm_real *at = pad + (base + (i * S + j) * S + l) * GATHER_STRIDE;
          for (int d = 0; d < 3; ++d) {
            const mpm_real vn = at[d], vo = at[3 + d];
            vnew[d] += w * vn;
            dv[d] += w * (vn - vo);
          }
        }
    for (int d = 0; d < 3; ++d) {
      s->cvg[d][c] = vnew[d];
      P->dv[d][c] = dv[d];
    }
    if (!apic) continue;
    /* B_a = sum_i w_i v_i (x_i - x_a)^T = (sum_i v_i a_i^T) D_a */
    mpm_real B[9] = {0}, D[3];
    for (int i = 0; i < W; ++i)
      for (int j = 0; j < W; ++j)
        for (int l = 0; l < W; ++l) {
          if (st.w[0][i] * st.w[1][j] * st.w[2][l] == 0) continue;
          const mpm_real a[3] = {st.a[0][i] * st.w[1][j] * st.w[2][l],
                                 st.w[0][i] * st.a[1][j] * st.w[2][l],
                                 st.w[0][i] * st.w[1][j] * st.a[2][l]};
          const mpm_real *at = pad + (base + (i * S + j) * S + l) * GATHER_STRIDE;
          for (int rr = 0; rr < 3; ++rr)
            for (int t = 0; t < 3; ++t) B[3 * rr + t] += at[rr] * a[t];
        }
    mpm_corner_apic_d(k, &st, xr, D);
    for (int rr = 0; rr < 3; ++rr)
      for (int t = 0; t < 3; ++t) s->cB[3 * rr + t][c] = B[3 * rr + t] * D[t];
  }
}

ALWAYS_INLINE void gather_groups(const int W, const mpm_corner_pads *P, mpm_domain_set *s,
                                 const mpm_kernel *k, const int apic, const mpm_real *const v[3],
                                 const mpm_real *const v0[3]) {
  const long groups = (long)P->schedule.colour_start[MPM_SCHEDULE_COLOURS];
#pragma omp parallel for schedule(dynamic, 4)
  for (long q = 0; q < groups; ++q) gather_group(W, P, s, k, (size_t)q, apic, v, v0);
}

void mpm_corner_pads_gather(const mpm_corner_pads *P, mpm_domain_set *s, const mpm_kernel *k,
                            int apic, const mpm_real *const v[3], const mpm_real *const v0[3]) {
  switch (k->width) { /* reads only: every group at once, in parallel */
  case 2:
    gather_groups(2, P, s, k, apic, v, v0);
    break;
  case 3:
    gather_groups(3, P, s, k, apic, v, v0);
    break;
  default:
    gather_groups(4, P, s, k, apic, v, v0);
    break;
  }
  const mpm_scatter_schedule *sch = &P->schedule;
  const long own = (long)sch->own_rows;
  const mpm_real one = 1;
#pragma omp parallel for schedule(static) if (own >= MPM_PARALLEL_MIN)
  for (long j = 0; j < own; ++j) { /* an enriched corner: its own DOF's velocity, B_a = 0 */
    const uint32_t c = sch->own_row[j];
    const uint32_t i = P->corner_dofs + s->enrich.slot[c];
    for (int d = 0; d < 3; ++d) {
      mpm_real vnew = 0, dv = 0;
      vnew += one * v[d][i];
      dv += one * (v[d][i] - v0[d][i]);
      s->cvg[d][c] = vnew;
      P->dv[d][c] = dv;
    }
    if (apic)
      for (int e = 0; e < 9; ++e) s->cB[e][c] = 0;
  }
}
