/* p2g.c - particle-to-grid transfer (Gao sec. 3.2 steps 1-2) on the sparse and dense grids.
 *
 * Stresses are evaluated in chunks of one material (particles are sorted by block and then by
 * material), through the model's batch entry, a window ahead of the batches that scatter them
 * (stress_window). The sparse
 * grid takes the particles of one cell as SIMD lanes (transfer_lanes.h); the dense reference
 * uses the plain scalar bodies of transfer_core.h. Sparse P2G
 * runs owner blocks of one colour in parallel; each block scatters into a private 8x8x8 pad
 * that is then added to the 8 blocks it covers. No atomics; deterministic for any thread count
 * (see sparse_grid.h). */
#include "transfer/transfer.h"
#include "transfer/batches.h"
#include "transfer/ghost_apic_lanes.h"
#include "transfer/operators.h"
#include "transfer/stress_window.h"
#include "transfer/transfer_lanes.h"
#include "core/parallel.h"

#include <string.h>

#define ALWAYS_INLINE static inline __attribute__((always_inline))

/* Scatter particles idx[0..n) with stresses tau into channel arrays viewed from node `org`
 * (global node index of ch[..][0]) with strides sx, sy. */
ALWAYS_INLINE void scatter_chunk(const int W, const int apic, const mpm_transfer_ctx *ctx,
                                 const mpm_particles *p, const uint32_t *idx, int n,
                                 mpm_real tau[9][MPM_STRESS_CHUNK],
                                 mpm_real *const ch[MPM_P2G_CHANNELS], const int org[3], long sx,
                                 long sy) {
  const mpm_kernel *k = &ctx->kernel;
  for (int q = 0; q < n; ++q) {
    const uint32_t i = idx[q];
    const mpm_real xr[3] = {p->x[0][i] - ctx->origin[0], p->x[1][i] - ctx->origin[1],
                            p->x[2][i] - ctx->origin[2]};
    mpm_stencil s;
    mpm_kernel_stencil(k, xr, &s);
    const mpm_real m = p->mass[i], mv[3] = {m * p->v[0][i], m * p->v[1][i], m * p->v[2][i]};
    mpm_real mB[9], K[9];
    const mpm_real nv = -p->vol0[i];
    for (int c = 0; c < 9; ++c) {
      mB[c] = m * p->B[c][i];
      K[c] = nv * tau[c][q];
    }
    const long off = (long)(s.base[0] - org[0]) * sx + (long)(s.base[1] - org[1]) * sy +
                     (long)(s.base[2] - org[2]);
    mpm_real *at[MPM_P2G_CHANNELS];
    for (int c = 0; c < MPM_P2G_CHANNELS; ++c) at[c] = ch[c] + off;
    mpm_p2g_particle(W, &s, m, mv, apic ? mB : NULL, K, at, sx, sy);
  }
}

/* Gather the lane inputs of a batch of n particles (lanes >= n contribute nothing). */
ALWAYS_INLINE void batch_inputs(const mpm_particles *p, const uint32_t *idx, int n, int contiguous,
                                mpm_real dt, const int apic, const mpm_real *const tau[9],
                                mpm_vl *m, mpm_vl mv[3], mpm_vl mB[9], mpm_vl K[9]) {
  mpm_vl live = {0}; /* 1 for the batch's lanes, 0 for padding */
  for (int l = 0; l < n; ++l) live[l] = 1;
  *m = mpm_lanes_load(p->mass, idx, n, contiguous) * live;
  /* APIC folds dt * force into the momentum; PIC/FLIP keeps the force apart */
  const mpm_vl nv = mpm_lanes_load(p->vol0, idx, n, contiguous) * live * (apic ? -dt : R_(-1.0));
  for (int d = 0; d < 3; ++d) mv[d] = *m * mpm_lanes_load(p->v[d], idx, n, contiguous);
  for (int c = 0; c < 9; ++c) {
    mB[c] = apic ? *m * mpm_lanes_load(p->B[c], idx, n, contiguous) : (mpm_vl){0};
    mpm_vl t = {0};
    if (n == MPM_LANES)
      __builtin_memcpy(&t, tau[c], sizeof t);
    else /* lanes >= n of tau were never written: they may hold NaN, and 0 * NaN is NaN */
      for (int l = 0; l < n; ++l) t[l] = tau[c][l];
    K[c] = nv * t;
  }
}

/* Everything P2G needs of the walk's current batch: lane stencils (with APIC factors when apic)
 * and lane inputs (see batch_inputs), with the stresses from the window, which is filled ahead as
 * the batches need it (the caller restarts it at every material); without force, no stresses
 * (K = 0). The particles two batches ahead are asked for meanwhile. */
ALWAYS_INLINE void batch_prepare(const int W, const int apic, const int force,
                                 const mpm_transfer_ctx *ctx, const mpm_sparse_grid *g,
                                 const mpm_particles *p, stress_window *w, int material,
                                 uint32_t range_end, uint32_t j, uint32_t end, int base[3],
                                 mpm_lane_stencil *s, mpm_vl *mass, mpm_vl mv[3], mpm_vl mB[9],
                                 mpm_vl K[9]) {
  const uint32_t *idx = g->perm + j;
  const int n = mpm_batch_size(j, end);
  if (j + 2 * MPM_LANES < g->particle_count) MPM_PREFETCH_PARTICLE(p, idx[2 * MPM_LANES], 0);
  if (force) stress_window_need(w, &ctx->materials[material], p, g->perm, j, n, range_end);
  const int contiguous = mpm_batch_contiguous(idx, n);
  static const mpm_real zero[MPM_LANES] = {0};
  const mpm_real *tau[9];
  for (int c = 0; c < 9; ++c) tau[c] = force ? w->tau[c] + (j - w->begin) : zero;
  const mpm_real *const x[3] = {p->x[0], p->x[1], p->x[2]};
  mpm_lane_stencil_eval(W, &ctx->kernel, x, ctx->origin, idx, n, contiguous, apic, base, s);
  batch_inputs(p, idx, n, contiguous, ctx->dt, apic, tau, mass, mv, mB, K);
}

/* The P2G channels (mass, momentum, force) of a level's values. */
static void p2g_channels(const mpm_grid_values *val, mpm_real *ch[MPM_P2G_CHANNELS]) {
  ch[MPM_P2G_MASS] = val->mass;
  for (int d = 0; d < 3; ++d) {
    ch[MPM_P2G_MOMENTUM + d] = val->v0[d];
    ch[MPM_P2G_FORCE + d] = val->f[d];
  }
}

/* P2G of owner block b into a pad of 8 (PIC/FLIP) or 4 (APIC, force fused) reals per node,
 * then added to the level's values; without force (force = 0) only mass and momentum. */
ALWAYS_INLINE void p2g_block(const int W, const int apic, const int force,
                             const mpm_transfer_ctx *ctx, const mpm_sparse_grid *g,
                             mpm_real *const ch[MPM_P2G_CHANNELS], const mpm_particles *p,
                             int32_t b) {
  /* with APIC the force is fused into the momentum: only mass and momentum are used */
  const int used = apic || !force ? MPM_P2G_FORCE : MPM_P2G_CHANNELS;
  const int stride = MPM_PAD_STRIDE(apic);
  mpm_real pad[MPM_PAD_NODES * 8] __attribute__((aligned(MPM_ALIGN)));
  memset(pad, 0, (size_t)MPM_PAD_NODES * (size_t)stride * sizeof(mpm_real));
  MPM_PAD_PREFETCH(g, b, used, ch, 1); /* the 8 blocks are written at the end: ask for them now */
  const int org[3] = {g->coord[b][0] * MPM_BLOCK, g->coord[b][1] * MPM_BLOCK,
                      g->coord[b][2] * MPM_BLOCK};
  stress_window w;
  size_t q1;
  const size_t q0 = mpm_block_cells(g, (size_t)b, &q1);
  uint32_t range_end = 0;
  for (size_t q = q0; q < q1; ++q) {
    const int m = mpm_cell_material(q, q0);
    if (mpm_cell_first_of_material(q, q0)) { /* the material's stresses start */
      uint32_t range_begin;
      mpm_material_range(g, q0, m, &range_begin, &range_end);
      w.begin = w.count = 0;
    }
    const uint32_t end = g->cell_start[q + 1];
    for (uint32_t j = g->cell_start[q]; j < end; j += MPM_LANES) {
      int base[3];
      mpm_lane_stencil s;
      mpm_vl mass, mv[3], mB[9], K[9];
      batch_prepare(W, apic, force, ctx, g, p, &w, m, range_end, j, end, base, &s, &mass, mv, mB,
                    K);
      mpm_p2g_lanes(W, apic, &s, mass, mv, mB, K, pad, mpm_pad_offset(base, org), MPM_PAD * MPM_PAD,
                    MPM_PAD);
    }
  }
  /* add the pad (nodes x 8 channels) to the 8 blocks it covers */
  mpm_pad_add(W, g, b, used, pad, stride, ch);
}

/* APIC P2G of one owner block: lanes are accumulated per node over the whole block (a compact
 * (W+3)^3 region of nodes, the base cells plus the stencil reach) and summed once at the end. */
#define LANE_PAD_SIDE_MAX (MPM_BLOCK + MPM_STENCIL_MAX - 1)
ALWAYS_INLINE void p2g_block_apic(const int W, const int force, const mpm_transfer_ctx *ctx,
                                  const mpm_sparse_grid *g, mpm_real *const ch[MPM_P2G_CHANNELS],
                                  const mpm_particles *p, int32_t b) {
  const int S = MPM_BLOCK + W - 1;
  mpm_vl acc[LANE_PAD_SIDE_MAX * LANE_PAD_SIDE_MAX * LANE_PAD_SIDE_MAX][4]
      __attribute__((aligned(MPM_ALIGN)));
  memset(acc, 0, (size_t)(S * S * S) * sizeof acc[0]);
  MPM_PAD_PREFETCH(g, b, MPM_P2G_FORCE, ch, 1);
  const int org[3] = {g->coord[b][0] * MPM_BLOCK, g->coord[b][1] * MPM_BLOCK,
                      g->coord[b][2] * MPM_BLOCK};
  stress_window w;
  size_t q1;
  const size_t q0 = mpm_block_cells(g, (size_t)b, &q1);
  uint32_t range_end = 0;
  for (size_t q = q0; q < q1; ++q) {
    const int m = mpm_cell_material(q, q0);
    if (mpm_cell_first_of_material(q, q0)) { /* the material's stresses start */
      uint32_t range_begin;
      mpm_material_range(g, q0, m, &range_begin, &range_end);
      w.begin = w.count = 0;
    }
    const uint32_t end = g->cell_start[q + 1];
    /* a cell whose stencil reaches ghosts of several real nodes (APIC across levels) */
    const mpm_ghost_apic *ga = ctx->ghost_apic;
    const uint32_t bc = ga ? ga->cell_of[q] : MPM_NOT_BOUNDARY;
    for (uint32_t j = g->cell_start[q]; j < end; j += MPM_LANES) {
      int base[3];
      mpm_lane_stencil s;
      mpm_vl mass, mv[3], mB[9], K[9];
      batch_prepare(W, 1, force, ctx, g, p, &w, m, range_end, j, end, base, &s, &mass, mv, mB, K);
      if (bc != MPM_NOT_BOUNDARY)
        mpm_ghost_apic_p2g(W, ga, &ctx->kernel, bc, mpm_batch_size(j, end), &s, mB);
      const long off = ((long)(base[0] - org[0]) * S + (base[1] - org[1])) * S + (base[2] - org[2]);
      mpm_p2g_lanes_acc(W, &s, mass, mv, mB, K, acc, off, (long)S * S, S);
    }
  }
  /* sum the lanes of every node once and add mass and momentum to the 8 blocks */
  for (int i = 0; i < S; ++i)
    for (int j = 0; j < S; ++j)
      for (int k = 0; k < S; ++k) {
        const mpm_vl sum = mpm_vl_sum4(acc[(i * S + j) * S + k]);
        const int o = (i >= MPM_BLOCK) << 2 | (j >= MPM_BLOCK) << 1 | (k >= MPM_BLOCK);
        const size_t n = (size_t)g->neighbor[b][o] * MPM_BLOCK_NODES +
                         (size_t)(((i & 3) * MPM_BLOCK + (j & 3)) * MPM_BLOCK + (k & 3));
        for (int c = 0; c < MPM_P2G_FORCE; ++c) ch[c][n] += sum[c];
      }
}

/* One owner block's P2G specialized by stencil width, APIC and force (the lanes' loops are
 * unrolled for each): a table of the twelve, chosen once per call. */
typedef void (*p2g_block_fn)(const mpm_transfer_ctx *ctx, const mpm_sparse_grid *g,
                             mpm_real *const ch[MPM_P2G_CHANNELS], const mpm_particles *p,
                             int32_t b);
#define P2G_BLOCK(W, F)                                                                            \
  static void p2g_block_w##W##_f##F(const mpm_transfer_ctx *ctx, const mpm_sparse_grid *g,         \
                                    mpm_real *const ch[MPM_P2G_CHANNELS], const mpm_particles *p,  \
                                    int32_t b) {                                                   \
    p2g_block(W, 0, F, ctx, g, ch, p, b);                                                          \
  }                                                                                                \
  static void p2g_block_apic_w##W##_f##F(const mpm_transfer_ctx *ctx, const mpm_sparse_grid *g,    \
                                         mpm_real *const ch[MPM_P2G_CHANNELS],                     \
                                         const mpm_particles *p, int32_t b) {                      \
    p2g_block_apic(W, F, ctx, g, ch, p, b);                                                        \
  }
P2G_BLOCK(2, 0)
P2G_BLOCK(2, 1)
P2G_BLOCK(3, 0)
P2G_BLOCK(3, 1)
P2G_BLOCK(4, 0)
P2G_BLOCK(4, 1)
#undef P2G_BLOCK

/* [width: 2, 3, 4][apic][force] */
static const p2g_block_fn p2g_block_variants[3][2][2] = {
    {{p2g_block_w2_f0, p2g_block_w2_f1}, {p2g_block_apic_w2_f0, p2g_block_apic_w2_f1}},
    {{p2g_block_w3_f0, p2g_block_w3_f1}, {p2g_block_apic_w3_f0, p2g_block_apic_w3_f1}},
    {{p2g_block_w4_f0, p2g_block_w4_f1}, {p2g_block_apic_w4_f0, p2g_block_apic_w4_f1}},
};

/* The P2G of every owner block, colour by colour (blocks of one colour in parallel). */
static void p2g_blocks(const mpm_transfer_ctx *ctx, const mpm_sparse_grid *g,
                       mpm_real *const ch[MPM_P2G_CHANNELS], const mpm_particles *p,
                       const int force) {
  const int apic = ctx->transfer == MPM_TRANSFER_APIC;
  const p2g_block_fn block =
      p2g_block_variants[mpm_width_index(ctx->kernel.width)][apic][force != 0];
  for (int color = 0; color < 8; ++color) {
    const long begin = (long)g->color_start[color], end = (long)g->color_start[color + 1];
#pragma omp parallel for schedule(dynamic, 4)
    for (long q = begin; q < end; ++q) {
      const int32_t b = g->color_blocks[q];
      block(ctx, g, ch, p, b);
    }
  }
}

void mpm_p2g_sparse(const mpm_transfer_ctx *ctx, const mpm_sparse_grid *g,
                    const mpm_grid_values *val, const mpm_particles *p) {
  mpm_real *ch[MPM_P2G_CHANNELS];
  p2g_channels(val, ch);
  p2g_blocks(ctx, g, ch, p, 1);
}

void mpm_p2g_mass_momentum_sparse(const mpm_transfer_ctx *ctx, const mpm_sparse_grid *g,
                                  const mpm_grid_values *val, const mpm_particles *p) {
  mpm_real *ch[MPM_P2G_CHANNELS];
  p2g_channels(val, ch);
  p2g_blocks(ctx, g, ch, p, 0);
}

/* A chunk's scatter on the dense grid specialized by stencil width and APIC. */
typedef void (*scatter_chunk_fn)(const mpm_transfer_ctx *ctx, const mpm_particles *p,
                                 const uint32_t *idx, int n, mpm_real tau[9][MPM_STRESS_CHUNK],
                                 mpm_real *const ch[MPM_P2G_CHANNELS], const int org[3], long sx,
                                 long sy);
#define SCATTER_CHUNK(W, A)                                                                        \
  static void scatter_chunk_w##W##_a##A(                                                           \
      const mpm_transfer_ctx *ctx, const mpm_particles *p, const uint32_t *idx, int n,             \
      mpm_real tau[9][MPM_STRESS_CHUNK], mpm_real *const ch[MPM_P2G_CHANNELS], const int org[3],   \
      long sx, long sy) {                                                                          \
    scatter_chunk(W, A, ctx, p, idx, n, tau, ch, org, sx, sy);                                     \
  }
SCATTER_CHUNK(2, 0)
SCATTER_CHUNK(2, 1)
SCATTER_CHUNK(3, 0)
SCATTER_CHUNK(3, 1)
SCATTER_CHUNK(4, 0)
SCATTER_CHUNK(4, 1)
#undef SCATTER_CHUNK

/* [width: 2, 3, 4][apic] */
static const scatter_chunk_fn scatter_chunk_variants[3][2] = {
    {scatter_chunk_w2_a0, scatter_chunk_w2_a1},
    {scatter_chunk_w3_a0, scatter_chunk_w3_a1},
    {scatter_chunk_w4_a0, scatter_chunk_w4_a1},
};

void mpm_p2g_dense(const mpm_transfer_ctx *ctx, const mpm_dense_grid *g, const mpm_grid_values *val,
                   const mpm_particles *p) {
  const int apic = ctx->transfer == MPM_TRANSFER_APIC;
  const scatter_chunk_fn scatter = scatter_chunk_variants[mpm_width_index(ctx->kernel.width)][apic];
  mpm_real *ch[MPM_P2G_CHANNELS];
  p2g_channels(val, ch);
  const long sy = g->n[2], sx = (long)g->n[1] * g->n[2];
  const int org[3] = {0, 0, 0};
  mpm_real tau[9][MPM_STRESS_CHUNK];
  uint32_t idx[MPM_STRESS_CHUNK];
  size_t i = 0;
  while (i < p->count) {
    /* a chunk of consecutive particles of one material */
    const int32_t m = p->material[i];
    int n = 0;
    while (i + n < p->count && n < MPM_STRESS_CHUNK && p->material[i + n] == m) {
      idx[n] = (uint32_t)(i + n);
      ++n;
    }
    chunk_stress(&ctx->materials[m], p, idx, n, tau);
    scatter(ctx, p, idx, n, tau, ch, org, sx, sy);
    i += (size_t)n;
  }
}

int mpm_p2g_fuses_force(const mpm_transfer_ctx *ctx, const mpm_grid *g) {
  return mpm_transfer_variant_of(g)->fuses_force && ctx->transfer == MPM_TRANSFER_APIC;
}

void mpm_p2g(const mpm_transfer_ctx *ctx, const mpm_grid *g, const mpm_grid_values *val,
             const mpm_particles *p) {
  mpm_transfer_variant_of(g)->p2g(ctx, g, val, p);
}
