/* corner_pads.c - the corners' transfers to and from the sparse grid through pads of nodes
 * (see corner_pads.h). */
#include "domain/corner_pads.h"
#include "core/parallel.h"
#include "domain/corner_motion.h"
#include "domain/domain.h"
#include "grid/sparse_grid.h"
#include "transfer/transfer_lanes.h"

#include <stdlib.h>
#include <string.h>

#define ALWAYS_INLINE static inline __attribute__((always_inline))
#define SIDE_MAX (MPM_BLOCK + MPM_STENCIL_MAX - 1) /* a pad's nodes per axis */
#define SCATTER_FIELDS 7                           /* mass, momentum, force */
#define SCATTER_STRIDE 8
#define GATHER_STRIDE 6 /* v, v0 */
#define PAD_NODES (SIDE_MAX * SIDE_MAX * SIDE_MAX)

void mpm_corner_pads_free(mpm_corner_pads *P) {
  mpm_scatter_schedule_free(&P->schedule);
  memset(P, 0, sizeof *P);
}

/* A group and the place of its block in space. */
typedef struct group_place {
  uint64_t key;
  uint32_t group;
} group_place;

static int compare_place(const void *a, const void *b) {
  const group_place *x = a, *y = b;
  return x->key < y->key ? -1 : x->key > y->key;
}

mpm_status mpm_corner_pads_plan(mpm_corner_pads *P, const mpm_domain_set *s, const mpm_grid *g,
                                const mpm_kernel *k, mpm_arena *scratch) {
  P->on = 0;
  const mpm_sparse_grid *sg = &g->impl.sparse;
  const size_t nc = s->corner_count, nk = sg->block_count;
  P->block = mpm_arena_alloc(scratch, (nc + 1) * sizeof *P->block);
  P->cell = mpm_arena_alloc(scratch, nc + 1);
  uint8_t *key_colour = mpm_arena_alloc(scratch, nk + 1);
  if (!P->block || !P->cell || !key_colour) return MPM_ERR_NOMEM;
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
      int base[3];
      mpm_kernel_base(k, xr, base);
      const int32_t bb[3] = {base[0] >> MPM_BLOCK_BITS, base[1] >> MPM_BLOCK_BITS,
                             base[2] >> MPM_BLOCK_BITS};
      if (bb[0] != last[0] || bb[1] != last[1] || bb[2] != last[2]) {
        last_block = mpm_sparse_grid_find(sg, bb);
        memcpy(last, bb, sizeof last);
      }
      if (last_block < 0) {
        missing = 1;
        continue;
      }
      P->block[c] = last_block;
      /* x fastest, as the samplers lay bodies out and so number the corners */
      P->cell[c] = (uint8_t)((base[2] & 3) << 4 | (base[1] & 3) << 2 | (base[0] & 3));
    }
  }
  if (missing) return MPM_ERR_INVALID;
  /* the colour of a block is the parity of its coordinates (grid.c, stencil_nodes) */
  for (size_t b = 0; b < nk; ++b) {
    const int32_t *bc = sg->coord[b];
    key_colour[b] = (uint8_t)((bc[0] & 1) << 2 | (bc[1] & 1) << 1 | (bc[2] & 1));
  }
  mpm_scatter_schedule *S = &P->schedule;
  if (mpm_scatter_schedule_build(S, nc, P->block, nk, key_colour)) return MPM_ERR_NOMEM;
  const size_t groups = S->colour_start[MPM_SCHEDULE_COLOURS];
  P->pad = mpm_arena_alloc(scratch, (groups + 1) * sizeof *P->pad);
  P->org = mpm_arena_alloc(scratch, (groups + 1) * sizeof *P->org);
  P->cell_start = mpm_arena_alloc(scratch, (groups + 1) * sizeof *P->cell_start);
  P->grid_positions = S->group_start[groups];
  P->positions = P->grid_positions + S->own_rows;
  P->row = mpm_arena_alloc(scratch, (P->positions + 1) * sizeof *P->row);
  P->pos = mpm_arena_alloc(scratch, (nc + 1) * sizeof *P->pos);
  if (!P->pad || !P->org || !P->cell_start || !P->row || !P->pos) return MPM_ERR_NOMEM;
#pragma omp parallel for schedule(static) if (nc > MPM_PARALLEL_MIN)
  for (long c = 0; c < (long)nc; ++c) P->pos[c] = MPM_CORNER_PADS_NONE;
  /* the groups' ranges of positions in the order of their blocks in space (z, y, x; x fastest),
   * not in the schedule's colour order: the corners, numbered as the samplers lay bodies out,
   * then write their P2G values close to one another (measured: 10% of the domain step) */
  uint32_t *first = mpm_arena_alloc(scratch, (groups + 1) * sizeof *first);
  group_place *place = mpm_arena_alloc(scratch, (groups + 1) * sizeof *place);
  P->in_space = mpm_arena_alloc(scratch, (groups + 1) * sizeof *P->in_space);
  if (!first || !place || !P->in_space) return MPM_ERR_NOMEM;
  for (size_t q = 0; q < groups; ++q) {
    const int32_t *bc = sg->coord[mpm_scatter_schedule_group_key(S, P->block, q)];
    place[q].key = (uint64_t)(uint32_t)(bc[2] + (1 << 20)) << 42 |
                   (uint64_t)(uint32_t)(bc[1] + (1 << 20)) << 21 |
                   (uint64_t)(uint32_t)(bc[0] + (1 << 20));
    place[q].group = (uint32_t)q;
  }
  qsort(place, groups, sizeof *place, compare_place);
  uint32_t next = 0;
  for (size_t j = 0; j < groups; ++j) {
    const uint32_t q = place[j].group;
    P->in_space[j] = q;
    first[q] = next;
    next += S->group_start[q + 1] - S->group_start[q];
  }
  /* each group's corners by the cell of their base node (stable): the corners of one cell
   * share every node they touch and are taken as SIMD lanes */
#pragma omp parallel for schedule(dynamic, 16)
  for (long q = 0; q < (long)groups; ++q) {
    uint32_t *cs = P->cell_start[q];
    memset(cs, 0, sizeof P->cell_start[q]);
    const uint32_t r0 = S->group_start[q], r1 = S->group_start[q + 1];
    for (uint32_t r = r0; r < r1; ++r) cs[P->cell[S->group_row[r]] + 1]++;
    cs[0] = first[q];
    for (int c = 0; c < MPM_BLOCK_NODES; ++c) cs[c + 1] += cs[c];
    uint32_t at[MPM_BLOCK_NODES];
    memcpy(at, cs, sizeof at);
    for (uint32_t r = r0; r < r1; ++r) {
      const uint32_t c = S->group_row[r];
      const uint32_t at_k = at[P->cell[c]]++;
      P->row[at_k] = c;
      P->pos[c] = at_k;
    }
  }
  for (size_t j = 0; j < S->own_rows; ++j) { /* the enriched corners follow, in corner order */
    P->row[P->grid_positions + j] = S->own_row[j];
    P->pos[S->own_row[j]] = (uint32_t)(P->grid_positions + j);
  }
  for (size_t q = 0; q < groups; ++q) {
    const int32_t *bc = sg->coord[mpm_scatter_schedule_group_key(S, P->block, q)];
    for (int o = 0; o < 8; ++o) {
      const int32_t nb[3] = {bc[0] + ((o >> 2) & 1), bc[1] + ((o >> 1) & 1), bc[2] + (o & 1)};
      if ((P->pad[q][o] = mpm_sparse_grid_find(sg, nb)) < 0) return MPM_ERR_INVALID;
    }
    for (int d = 0; d < 3; ++d) P->org[q][d] = bc[d] * MPM_BLOCK;
  }
  long breaks = 0;
  const long gp = (long)P->grid_positions;
#pragma omp parallel for schedule(static) reduction(+ : breaks) if (gp > MPM_PARALLEL_MIN)
  for (long j = 1; j < gp; ++j) breaks += P->row[j] != P->row[j - 1] + 1;
  P->breaks = (size_t)breaks;
  for (int d = 0; d < 3; ++d) P->origin[d] = g->origin[d];
  P->on = 1;
  return MPM_OK;
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

/* The positions k .. k + n - 1 of a batch, as lane indices (lanes >= n repeat lane 0). */
ALWAYS_INLINE void batch_positions(uint32_t k, int n, uint32_t pos[MPM_LANES]) {
  for (int l = 0; l < MPM_LANES; ++l) pos[l] = k + (uint32_t)(l < n ? l : 0);
}

/* The lanes of a batch of n corners' values laid out by position (lanes >= n: 0). */
ALWAYS_INLINE mpm_vl corner_lanes(const mpm_real *a, const uint32_t pos[MPM_LANES], int n,
                                  mpm_vl live) {
  return mpm_lanes_load(a, pos, n, n == MPM_LANES) * live;
}

/* The weight and (apic) APIC factors of node (i, j, l) of a lane stencil. */
ALWAYS_INLINE mpm_vl node_weight(const mpm_lane_stencil *st, int i, int j, int l) {
  return st->w[0][i] * (st->w[1][j] * st->w[2][l]);
}
ALWAYS_INLINE void node_apic(const mpm_lane_stencil *st, int i, int j, int l, mpm_vl A[3]) {
  A[0] = st->a[0][i] * (st->w[1][j] * st->w[2][l]);
  A[1] = st->w[0][i] * (st->a[1][j] * st->w[2][l]);
  A[2] = st->w[0][i] * (st->w[1][j] * st->a[2][l]);
}

/* Group q's scatter: each batch's terms are added to the pad lane by lane (acc[node][field], 8
 * lanes each), and the lanes are summed once per node when the group is done, instead of once
 * per node per batch (the material points' P2G does the same, transfer_lanes.h). With APIC the
 * corners' m_a B_a are made here from their masses and B_a (read through P->row). */
ALWAYS_INLINE void scatter_group(const int W, const int apic, const mpm_corner_pads *P,
                                 const mpm_domain_set *s, const mpm_kernel *k, size_t q,
                                 const mpm_real *const carrier[7], mpm_real *const values[7],
                                 mpm_vl (*acc)[SCATTER_STRIDE]) {
  const int S = MPM_BLOCK + W - 1;
  const mpm_vl zero = {0};
  for (int n = 0; n < S * S * S; ++n)
    for (int f = 0; f < SCATTER_FIELDS; ++f) acc[n][f] = zero;
  const mpm_real *const x[3] = {s->cx[0], s->cx[1], s->cx[2]}; /* by corner */
  for (int cell = 0; cell < MPM_BLOCK_NODES; ++cell) {
    const uint32_t end = P->cell_start[q][cell + 1];
    for (uint32_t r = P->cell_start[q][cell]; r < end; r += MPM_LANES) {
      const int n = end - r < MPM_LANES ? (int)(end - r) : MPM_LANES;
      uint32_t pos[MPM_LANES];
      batch_positions(r, n, pos);
      mpm_vl live = {0};
      for (int l = 0; l < n; ++l) live[l] = 1;
      const uint32_t *idx = P->row + r;
      const int run = mpm_batch_contiguous(idx, n); /* corners numbered in the pads' order */
      mpm_lane_stencil st;
      int base[3];
      mpm_lane_stencil_eval(W, k, x, P->origin, idx, n, run, apic, base, &st);
      mpm_vl in[SCATTER_FIELDS], cm[9];
      for (int f = 0; f < SCATTER_FIELDS; ++f) in[f] = corner_lanes(carrier[f], pos, n, live);
      if (apic) /* m_a B_a, B_a by corner */
        for (int e = 0; e < 9; ++e) cm[e] = in[0] * mpm_lanes_load(s->cB[e], idx, n, run);
      const int off =
          ((base[0] - P->org[q][0]) * S + (base[1] - P->org[q][1])) * S + (base[2] - P->org[q][2]);
      for (int i = 0; i < W; ++i)
        for (int j = 0; j < W; ++j)
          for (int l = 0; l < W; ++l) {
            const mpm_vl w = node_weight(&st, i, j, l);
            mpm_vl *a = acc[off + (i * S + j) * S + l];
            a[0] += w * in[0];
            for (int d = 0; d < 3; ++d) {
              mpm_vl mom = w * in[1 + d];
              if (apic) { /* the affine moment m_a B_a D^-1 (x_i - x_a) w */
                mpm_vl A[3];
                node_apic(&st, i, j, l, A);
                mom += A[0] * cm[3 * d] + A[1] * cm[3 * d + 1] + A[2] * cm[3 * d + 2];
              }
              a[1 + d] += mom;
              a[4 + d] += w * in[4 + d];
            }
          }
    }
  }
  uint32_t dof[SIDE_MAX * SIDE_MAX * SIDE_MAX];
  pad_dofs(P, q, S, dof);
  for (int n = 0; n < S * S * S; ++n) {
    acc[n][SCATTER_FIELDS] = zero;
    const mpm_v8 sum = mpm_vl_sum8(acc[n]);
    for (int f = 0; f < SCATTER_FIELDS; ++f) values[f][dof[n]] += sum[f];
  }
}

/* The scatter of the groups of one colour with a kernel of width W (each thread's pad in acc). */
ALWAYS_INLINE void scatter_colour(const int W, const int apic, const mpm_corner_pads *P,
                                  const mpm_domain_set *s, const mpm_kernel *k, long g0, long g1,
                                  const mpm_real *const carrier[7], mpm_real *const values[7],
                                  mpm_vl (*acc)[SCATTER_STRIDE]) {
#pragma omp parallel
  {
    mpm_vl(*pad)[SCATTER_STRIDE] = acc + (size_t)mpm_thread_id() * PAD_NODES;
#pragma omp for schedule(dynamic, 4)
    for (long q = g0; q < g1; ++q) scatter_group(W, apic, P, s, k, (size_t)q, carrier, values, pad);
  }
}

mpm_status mpm_corner_pads_scatter(const mpm_corner_pads *P, const mpm_domain_set *s,
                                   const mpm_kernel *k, const mpm_real *const carrier[7], int apic,
                                   mpm_real *const values[7], mpm_arena *scratch) {
  const mpm_scatter_schedule *sch = &P->schedule;
  mpm_vl(*acc)[SCATTER_STRIDE] =
      mpm_arena_alloc(scratch, (size_t)mpm_thread_count() * PAD_NODES * sizeof *acc);
  if (!acc) return MPM_ERR_NOMEM;
  for (int colour = 0; colour < MPM_SCHEDULE_COLOURS; ++colour) {
    const long g0 = (long)sch->colour_start[colour], g1 = (long)sch->colour_start[colour + 1];
    /* the width and APIC constants in each copy: the stencil loops unroll */
    const int w = k->width;
    if (w == 2 && apic)
      scatter_colour(2, 1, P, s, k, g0, g1, carrier, values, acc);
    else if (w == 2)
      scatter_colour(2, 0, P, s, k, g0, g1, carrier, values, acc);
    else if (w == 3 && apic)
      scatter_colour(3, 1, P, s, k, g0, g1, carrier, values, acc);
    else if (w == 3)
      scatter_colour(3, 0, P, s, k, g0, g1, carrier, values, acc);
    else if (apic)
      scatter_colour(4, 1, P, s, k, g0, g1, carrier, values, acc);
    else
      scatter_colour(4, 0, P, s, k, g0, g1, carrier, values, acc);
  }
  /* enriched corners: identity rows into their DOFs (weight 1, APIC factors 0) */
  const long own = (long)sch->own_rows;
  const mpm_real one = 1, zero = 0;
#pragma omp parallel for schedule(static) if (own >= MPM_PARALLEL_MIN)
  for (long j = 0; j < own; ++j) {
    const size_t at = P->grid_positions + (size_t)j;
    const uint32_t c = P->row[at], i = P->corner_dofs + s->enrich.slot[c];
    for (int f = 0; f < SCATTER_FIELDS; ++f) values[f][i] += one * carrier[f][at];
    if (apic)
      for (int kk = 0; kk < 3; ++kk) {
        const mpm_real cm = carrier[0][at];
        values[1 + kk][i] += zero * (cm * s->cB[3 * kk][c]) + zero * (cm * s->cB[3 * kk + 1][c]) +
                             zero * (cm * s->cB[3 * kk + 2][c]);
      }
  }
  return MPM_OK;
}

ALWAYS_INLINE mpm_real gather_group(const int W, const int apic, const mpm_corner_pads *P,
                                    mpm_domain_set *s, const mpm_kernel *k, size_t q,
                                    const mpm_real *const v[3], const mpm_real *const v0[3],
                                    const mpm_corner_motion *motion) {
  const int S = MPM_BLOCK + W - 1;
  uint32_t dof[SIDE_MAX * SIDE_MAX * SIDE_MAX];
  mpm_real pad[SIDE_MAX * SIDE_MAX * SIDE_MAX * GATHER_STRIDE];
  pad_dofs(P, q, S, dof);
  for (int n = 0; n < S * S * S; ++n)
    for (int d = 0; d < 3; ++d) {
      pad[n * GATHER_STRIDE + d] = v[d][dof[n]];
      pad[n * GATHER_STRIDE + 3 + d] = apic ? 0 : v0[d][dof[n]]; /* v0: FLIP's increment only */
    }
  const mpm_real *const x[3] = {s->cx[0], s->cx[1], s->cx[2]}; /* by corner */
  const mpm_real dx = k->dx;
  mpm_real max_v2 = 0;
  for (int cell = 0; cell < MPM_BLOCK_NODES; ++cell) {
    const uint32_t end = P->cell_start[q][cell + 1];
    for (uint32_t r = P->cell_start[q][cell]; r < end; r += MPM_LANES) {
      const int n = end - r < MPM_LANES ? (int)(end - r) : MPM_LANES;
      const uint32_t *idx = P->row + r;
      const int run = mpm_batch_contiguous(idx, n); /* corners numbered in the pads' order */
      mpm_lane_stencil st;
      int base[3];
      mpm_lane_stencil_eval(W, k, x, P->origin, idx, n, run, apic, base, &st);
      const int off =
          ((base[0] - P->org[q][0]) * S + (base[1] - P->org[q][1])) * S + (base[2] - P->org[q][2]);
      /* v^g_a = sum_i omega_i(x_a) v_i^{n+1}, the FLIP increment sum_i omega_i(x_a) (v_i^{n+1}
       * - v_i^n), and sum_i v_i a_i^T for B_a */
      const mpm_vl zero = {0};
      mpm_vl vg[3] = {zero, zero, zero}, dv[3] = {zero, zero, zero}, B[9];
      for (int e = 0; e < 9; ++e) B[e] = zero;
      for (int i = 0; i < W; ++i)
        for (int j = 0; j < W; ++j)
          for (int l = 0; l < W; ++l) {
            const mpm_vl w = node_weight(&st, i, j, l);
            const mpm_real *node = pad + (off + (i * S + j) * S + l) * GATHER_STRIDE;
            mpm_vl A[3];
            if (apic) node_apic(&st, i, j, l, A);
            for (int d = 0; d < 3; ++d) {
              const mpm_vl u = mpm_vl_splat(node[d]);
              vg[d] += w * u;
              if (!apic) dv[d] += w * (u - node[3 + d]); /* APIC takes v^g alone */
              if (apic)
                for (int t = 0; t < 3; ++t) B[3 * d + t] += u * A[t];
            }
          }
      /* each corner moved now (corner_motion.h) */
      if (!(run && mpm_corner_move_lanes(s, motion, idx[0], vg, dv, &max_v2)))
        for (int l = 0; l < n; ++l) {
          const mpm_real vn[3] = {vg[0][l], vg[1][l], vg[2][l]};
          const mpm_real inc[3] = {dv[0][l], dv[1][l], dv[2][l]}; /* (APIC: unused) */
          const mpm_real vg2 = mpm_corner_move(s, motion, idx[l], vn, inc);
          if (vg2 > max_v2) max_v2 = vg2;
        }
      if (!apic) continue;
      /* B_a = (sum_i v_i a_i^T) D_a, D_a's diagonal sum_i w_i (x_i - x_a)^2 per axis */
      for (int t = 0; t < 3; ++t) {
        mpm_vl D = zero;
        for (int i = 0; i < W; ++i) {
          const mpm_vl rr = ((mpm_real)i - st.f[t]) * dx;
          D += st.w[t][i] * rr * rr;
        }
        for (int d = 0; d < 3; ++d)
          mpm_lanes_store(s->cB[3 * d + t], idx, n, run, B[3 * d + t] * D);
      }
    }
  }
  return max_v2;
}

ALWAYS_INLINE mpm_real gather_groups(const int W, const int apic, const mpm_corner_pads *P,
                                     mpm_domain_set *s, const mpm_kernel *k,
                                     const mpm_real *const v[3], const mpm_real *const v0[3],
                                     const mpm_corner_motion *motion) {
  const long groups = (long)P->schedule.colour_start[MPM_SCHEDULE_COLOURS];
  mpm_real max_v2 = 0;
  /* in the order of the positions: the corners' positions stream through memory */
#pragma omp parallel for schedule(dynamic, 4) reduction(max : max_v2)
  for (long j = 0; j < groups; ++j) {
    const mpm_real m = gather_group(W, apic, P, s, k, P->in_space[j], v, v0, motion);
    if (m > max_v2) max_v2 = m;
  }
  return max_v2;
}

mpm_real mpm_corner_pads_gather(const mpm_corner_pads *P, mpm_domain_set *s, const mpm_kernel *k,
                                const mpm_real *const v[3], const mpm_real *const v0[3],
                                const mpm_corner_motion *motion) {
  /* reads of the grid only, and each corner's own values: every group at once, in parallel */
  const int w = k->width, apic = motion->apic;
  mpm_real max_v2;
  if (w == 2 && apic)
    max_v2 = gather_groups(2, 1, P, s, k, v, v0, motion);
  else if (w == 2)
    max_v2 = gather_groups(2, 0, P, s, k, v, v0, motion);
  else if (w == 3 && apic)
    max_v2 = gather_groups(3, 1, P, s, k, v, v0, motion);
  else if (w == 3)
    max_v2 = gather_groups(3, 0, P, s, k, v, v0, motion);
  else if (apic)
    max_v2 = gather_groups(4, 1, P, s, k, v, v0, motion);
  else
    max_v2 = gather_groups(4, 0, P, s, k, v, v0, motion);
  const mpm_scatter_schedule *sch = &P->schedule;
  const long own = (long)sch->own_rows;
  const mpm_real one = 1;
#pragma omp parallel for schedule(static) reduction(max : max_v2) if (own >= MPM_PARALLEL_MIN)
  for (long j = 0; j < own; ++j) { /* an enriched corner: its own DOF's velocity, B_a = 0 */
    const uint32_t c = sch->own_row[j];
    const uint32_t i = P->corner_dofs + s->enrich.slot[c];
    mpm_real vnew[3], dv[3];
    for (int d = 0; d < 3; ++d) {
      vnew[d] = 0;
      dv[d] = 0;
      vnew[d] += one * v[d][i];
      dv[d] += one * (v[d][i] - v0[d][i]);
    }
    if (apic)
      for (int e = 0; e < 9; ++e) s->cB[e][c] = 0;
    const mpm_real vg2 = mpm_corner_move(s, motion, c, vnew, dv);
    if (vg2 > max_v2) max_v2 = vg2;
  }
  return max_v2;
}
