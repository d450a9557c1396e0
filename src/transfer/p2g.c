/* p2g.c - particle-to-grid transfer (Gao sec. 3.2 steps 1-2) on the sparse and dense grids.
 *
 * Stresses are evaluated in chunks of one material (particles are sorted by block and then by
 * material), through the model's batch entry, just before the chunk is scattered. The sparse
 * grid uses the row-vectorized bodies of transfer_simd.h, the dense reference the plain scalar
 * ones of transfer_core.h. Sparse P2G
 * runs owner blocks of one colour in parallel; each block scatters into a private 8x8x8 pad
 * that is then added to the 8 blocks it covers. No atomics; deterministic for any thread count
 * (see sparse_grid.h). */
#include "transfer/transfer.h"
#include "transfer/transfer_simd.h"
#include "core/parallel.h"

#include <string.h>

#define ALWAYS_INLINE static inline __attribute__((always_inline))

/* Kirchhoff stresses of particles idx[0..n) (all of material `mat`) into tau. */
ALWAYS_INLINE void chunk_stress(const mpm_material *mat, const mpm_particles *p,
                                const uint32_t *idx, int n, mpm_real tau[9][MPM_STRESS_CHUNK]) {
  mpm_real Fbuf[9][MPM_STRESS_CHUNK];
  const mpm_real *Fp[9];
  for (int c = 0; c < 9; ++c) {
    const mpm_real *src = p->F[c];
    for (int q = 0; q < n; ++q) Fbuf[c][q] = src[idx[q]];
    Fp[c] = Fbuf[c];
  }
  mat->model->kirchhoff_batch(mat, n, Fp, tau);
}

/* Scatter particles idx[0..n) with stresses tau into channel arrays viewed from node `org`
 * (global node index of ch[..][0]) with strides sx, sy. */
ALWAYS_INLINE void scatter_chunk(const int W, const int simd, const int apic,
                                 const mpm_transfer_ctx *ctx, const mpm_particles *p,
                                 const uint32_t *idx, int n, mpm_real tau[9][MPM_STRESS_CHUNK],
                                 mpm_real *const ch[MPM_GRID_CHANNELS], const int org[3], long sx,
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
    mpm_real *at[MPM_GRID_CHANNELS];
    for (int c = 0; c < MPM_GRID_CHANNELS; ++c) at[c] = ch[c] + off;
    if (simd) {
      /* APIC fuses dt * force into the momentum channel (the grid update needs only the sum) */
      if (apic)
        for (int c = 0; c < 9; ++c) K[c] *= ctx->dt;
      else
        for (int c = 0; c < 9; ++c) mB[c] = 0;
      mpm_p2g_particle_v4(W, &s, m, mv, mB, K, apic, at, sx, sy);
    } else {
      mpm_p2g_particle(W, &s, m, mv, apic ? mB : NULL, K, at, sx, sy);
    }
  }
}

ALWAYS_INLINE void p2g_block(const int W, const int apic, const mpm_transfer_ctx *ctx,
                             mpm_sparse_grid *g, const mpm_particles *p, int32_t b) {
  /* with APIC the force is fused into the momentum: only mass and momentum are used */
  const int used = apic ? MPM_CH_F : MPM_GRID_CHANNELS;
  mpm_real pad[MPM_GRID_CHANNELS][MPM_PAD_NODES] __attribute__((aligned(MPM_ALIGN)));
  memset(pad, 0, (size_t)used * sizeof pad[0]);
  mpm_real *ch[MPM_GRID_CHANNELS];
  for (int c = 0; c < MPM_GRID_CHANNELS; ++c) ch[c] = pad[c];
  const int org[3] = {g->coord[b][0] * MPM_BLOCK, g->coord[b][1] * MPM_BLOCK,
                      g->coord[b][2] * MPM_BLOCK};
  const int nm = g->material_count;
  mpm_real tau[9][MPM_STRESS_CHUNK];
  for (int m = 0; m < nm; ++m) {
    const uint32_t begin = g->run_start[(size_t)b * nm + m], end = g->run_start[(size_t)b * nm + m + 1];
    for (uint32_t j = begin; j < end; j += MPM_STRESS_CHUNK) {
      const int n = (int)(end - j < MPM_STRESS_CHUNK ? end - j : MPM_STRESS_CHUNK);
      chunk_stress(&ctx->materials[m], p, g->perm + j, n, tau);
      scatter_chunk(W, 1, apic, ctx, p, g->perm + j, n, tau, ch, org, MPM_PAD * MPM_PAD, MPM_PAD);
    }
  }
  /* add the pad to the 8 blocks it covers */
  for (int o = 0; o < 8; ++o) {
    mpm_grid_block *blk = &g->blocks[g->neighbor[b][o]];
    const int ox = ((o >> 2) & 1) * MPM_BLOCK, oy = ((o >> 1) & 1) * MPM_BLOCK,
              oz = (o & 1) * MPM_BLOCK;
    for (int c = 0; c < used; ++c)
      for (int i = 0; i < MPM_BLOCK; ++i)
        for (int j = 0; j < MPM_BLOCK; ++j) {
          const mpm_real *src = &pad[c][(ox + i) * MPM_PAD * MPM_PAD + (oy + j) * MPM_PAD + oz];
          mpm_real *dst = &blk->ch[c][(i * MPM_BLOCK + j) * MPM_BLOCK];
          for (int k = 0; k < MPM_BLOCK; ++k) dst[k] += src[k];
        }
  }
}

void mpm_p2g_sparse(const mpm_transfer_ctx *ctx, mpm_sparse_grid *g, const mpm_particles *p) {
  const int W = ctx->kernel.width, apic = ctx->transfer == MPM_TRANSFER_APIC;
  for (int color = 0; color < 8; ++color) {
    const long begin = (long)g->color_start[color], end = (long)g->color_start[color + 1];
#pragma omp parallel for schedule(dynamic, 4)
    for (long q = begin; q < end; ++q) {
      const int32_t b = g->color_blocks[q];
      switch (W * 2 + apic) {
      case 4: p2g_block(2, 0, ctx, g, p, b); break;
      case 5: p2g_block(2, 1, ctx, g, p, b); break;
      case 6: p2g_block(3, 0, ctx, g, p, b); break;
      case 7: p2g_block(3, 1, ctx, g, p, b); break;
      case 8: p2g_block(4, 0, ctx, g, p, b); break;
      default: p2g_block(4, 1, ctx, g, p, b); break;
      }
    }
  }
}

void mpm_p2g_dense(const mpm_transfer_ctx *ctx, mpm_dense_grid *g, const mpm_particles *p) {
  const int W = ctx->kernel.width, apic = ctx->transfer == MPM_TRANSFER_APIC;
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
    switch (W) {
    case 2: scatter_chunk(2, 0, apic, ctx, p, idx, n, tau, g->ch, org, sx, sy); break;
    case 3: scatter_chunk(3, 0, apic, ctx, p, idx, n, tau, g->ch, org, sx, sy); break;
    default: scatter_chunk(4, 0, apic, ctx, p, idx, n, tau, g->ch, org, sx, sy); break;
    }
    i += (size_t)n;
  }
}
