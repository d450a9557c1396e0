/* operators.c - the separate transfer operators (see operators.h): the sparse grid's SIMD
 * versions on the batch walk, and the dense grid's scalar reference versions. */
#include "transfer/operators.h"
#include "core/parallel.h"
#include "transfer/batches.h"
#include "transfer/stress_window.h"
#include "transfer/transfer_lanes.h"

#include <string.h>

#define ALWAYS_INLINE static inline __attribute__((always_inline))
#define STRIDE 4 /* reals per node in the operators' pads: 3 components and one unused */

/* ---- sparse grid ---- */

/* The lanes' matrices: M_p from the arrays, or -V0 tau_p from the stress window. Lanes >= n
 * are zero. */
ALWAYS_INLINE void batch_matrices(const int stress, const mpm_particles *p, const uint32_t *idx,
                                  uint32_t j, int n, int contiguous, const mpm_real *const M[9],
                                  const stress_window *w, mpm_vl out[9]) {
  mpm_vl live = {0};
  for (int l = 0; l < n; ++l) live[l] = 1;
  if (!stress) {
    for (int c = 0; c < 9; ++c) out[c] = mpm_lanes_load(M[c], idx, n, contiguous) * live;
    return;
  }
  const mpm_vl nv = -mpm_lanes_load(p->vol0, idx, n, contiguous) * live;
  for (int c = 0; c < 9; ++c) {
    mpm_vl t = {0}; /* lanes >= n of the window may hold anything */
    for (int l = 0; l < n; ++l) t[l] = w->tau[c][j - w->begin + (uint32_t)l];
    out[c] = nv * t;
  }
}

ALWAYS_INLINE void scatter_block(const int W, const int stress, const mpm_transfer_ctx *ctx,
                                 const mpm_sparse_grid *g, mpm_real *const f[3],
                                 const mpm_real *const M[9], const mpm_particles *p, int32_t b) {
  mpm_real pad[MPM_PAD_NODES * STRIDE] __attribute__((aligned(MPM_ALIGN)));
  memset(pad, 0, sizeof pad);
  const int org[3] = {g->coord[b][0] * MPM_BLOCK, g->coord[b][1] * MPM_BLOCK,
                      g->coord[b][2] * MPM_BLOCK};
  const mpm_real *const x[3] = {p->x[0], p->x[1], p->x[2]};
  stress_window w;
  w.begin = w.count = 0;
  size_t q1;
  const size_t q0 = mpm_block_cells(g, (size_t)b, &q1);
  uint32_t range_end = 0;
  for (size_t q = q0; q < q1; ++q) {
    const int m = mpm_cell_material(q, q0);
    if (mpm_cell_first_of_material(q, q0)) {
      uint32_t range_begin;
      mpm_material_range(g, q0, m, &range_begin, &range_end);
      w.begin = w.count = 0;
    }
    const uint32_t end = g->cell_start[q + 1];
    for (uint32_t j = g->cell_start[q]; j < end; j += MPM_LANES) {
      const int n = mpm_batch_size(j, end);
      const uint32_t *idx = g->perm + j;
      if (stress) stress_window_need(&w, &ctx->materials[m], p, g->perm, j, n, range_end);
      const int contiguous = mpm_batch_contiguous(idx, n);
      int base[3];
      mpm_lane_stencil s;
      mpm_lane_stencil_eval(W, &ctx->kernel, x, ctx->origin, idx, n, contiguous, 0, base, &s);
      mpm_vl Mv[9];
      batch_matrices(stress, p, idx, j, n, contiguous, M, &w, Mv);
      mpm_scatter_lanes(W, &s, Mv, pad, STRIDE, mpm_pad_offset(base, org), MPM_PAD * MPM_PAD,
                        MPM_PAD);
    }
  }
  mpm_pad_add(W, g, b, 3, pad, STRIDE, f);
}

/* One owner block's scatter specialized by stencil width and source (matrices or stresses): a
 * table, chosen once per call. */
typedef void (*scatter_block_fn)(const mpm_transfer_ctx *ctx, const mpm_sparse_grid *g,
                                 mpm_real *const f[3], const mpm_real *const M[9],
                                 const mpm_particles *p, int32_t b);
#define SCATTER_BLOCK(W, S)                                                                        \
  static void scatter_block_w##W##_s##S(const mpm_transfer_ctx *ctx, const mpm_sparse_grid *g,     \
                                        mpm_real *const f[3], const mpm_real *const M[9],          \
                                        const mpm_particles *p, int32_t b) {                       \
    scatter_block(W, S, ctx, g, f, M, p, b);                                                       \
  }
SCATTER_BLOCK(2, 0)
SCATTER_BLOCK(2, 1)
SCATTER_BLOCK(3, 0)
SCATTER_BLOCK(3, 1)
SCATTER_BLOCK(4, 0)
SCATTER_BLOCK(4, 1)
#undef SCATTER_BLOCK

/* [width: 2, 3, 4][stress] */
static const scatter_block_fn scatter_block_variants[3][2] = {
    {scatter_block_w2_s0, scatter_block_w2_s1},
    {scatter_block_w3_s0, scatter_block_w3_s1},
    {scatter_block_w4_s0, scatter_block_w4_s1},
};

static void scatter_sparse(const int stress, const mpm_transfer_ctx *ctx, const mpm_sparse_grid *g,
                           mpm_real *const f[3], const mpm_real *const M[9],
                           const mpm_particles *p) {
  const scatter_block_fn block =
      scatter_block_variants[mpm_width_index(ctx->kernel.width)][stress != 0];
  for (int colour = 0; colour < 8; ++colour) {
    const long begin = (long)g->color_start[colour], end = (long)g->color_start[colour + 1];
#pragma omp parallel for schedule(dynamic, 4) if (end - begin > 1)
    for (long q = begin; q < end; ++q) {
      const int32_t b = g->color_blocks[q];
      block(ctx, g, f, M, p, b);
    }
  }
}

ALWAYS_INLINE void gather_block(const int W, const mpm_transfer_ctx *ctx, const mpm_sparse_grid *g,
                                const mpm_real *const u[3], const mpm_particles *p,
                                mpm_real *const G[9], int32_t b) {
  mpm_real pad[MPM_PAD_NODES * STRIDE] __attribute__((aligned(MPM_ALIGN)));
  mpm_pad_gather(W, g, b, 3, u, STRIDE, pad);
  /* G = sum_i (u_i - u_ref) grad w_i^T, u_ref the block's first node: the same in exact
   * arithmetic (sum_i grad w_i = 0), but a uniform field gives exactly 0 and a smooth one loses
   * no digits to the cancellation. The implicit solve applies K to velocities of ~1 m/s whose
   * gradient is all that matters; without the reference the round-off of sum_i grad w_i (1e-7
   * in float) times dt^2 K is a few percent of M v for a stiff body at a large step. */
  const mpm_real ref[3] = {pad[0], pad[1], pad[2]};
  const int span = MPM_BLOCK + W - 1;
  for (int i = 0; i < span; ++i)
    for (int j = 0; j < span; ++j)
      for (int k = 0; k < span; ++k) {
        mpm_real *node = &pad[(i * MPM_PAD * MPM_PAD + j * MPM_PAD + k) * STRIDE];
        for (int c = 0; c < 3; ++c) node[c] -= ref[c];
      }
  const int org[3] = {g->coord[b][0] * MPM_BLOCK, g->coord[b][1] * MPM_BLOCK,
                      g->coord[b][2] * MPM_BLOCK};
  const mpm_real *const x[3] = {p->x[0], p->x[1], p->x[2]};
  size_t q1;
  const size_t q0 = mpm_block_cells(g, (size_t)b, &q1);
  for (size_t q = q0; q < q1; ++q)
    for (uint32_t j = g->cell_start[q]; j < g->cell_start[q + 1]; j += MPM_LANES) {
      const int n = mpm_batch_size(j, g->cell_start[q + 1]);
      const uint32_t *idx = g->perm + j;
      const int contiguous = mpm_batch_contiguous(idx, n);
      int base[3];
      mpm_lane_stencil s;
      mpm_lane_stencil_eval(W, &ctx->kernel, x, ctx->origin, idx, n, contiguous, 0, base, &s);
      mpm_vl Gv[9];
      mpm_gradient_lanes(W, &s, pad, STRIDE, mpm_pad_offset(base, org), MPM_PAD * MPM_PAD, MPM_PAD,
                         Gv);
      for (int c = 0; c < 9; ++c) mpm_lanes_store(G[c], idx, n, contiguous, Gv[c]);
    }
}

/* One owner block's gradients specialized by stencil width: a table, chosen once per call. */
typedef void (*gather_block_fn)(const mpm_transfer_ctx *ctx, const mpm_sparse_grid *g,
                                const mpm_real *const u[3], const mpm_particles *p,
                                mpm_real *const G[9], int32_t b);
#define GATHER_BLOCK(W)                                                                            \
  static void gather_block_w##W(const mpm_transfer_ctx *ctx, const mpm_sparse_grid *g,             \
                                const mpm_real *const u[3], const mpm_particles *p,                \
                                mpm_real *const G[9], int32_t b) {                                 \
    gather_block(W, ctx, g, u, p, G, b);                                                           \
  }
GATHER_BLOCK(2)
GATHER_BLOCK(3)
GATHER_BLOCK(4)
#undef GATHER_BLOCK

static const gather_block_fn gather_block_variants[3] = {gather_block_w2, gather_block_w3,
                                                         gather_block_w4};

static void gather_sparse(const mpm_transfer_ctx *ctx, const mpm_sparse_grid *g,
                          const mpm_real *const u[3], const mpm_particles *p,
                          mpm_real *const G[9]) {
  const gather_block_fn block = gather_block_variants[mpm_width_index(ctx->kernel.width)];
  const long nb = (long)g->owner_count;
#pragma omp parallel for schedule(dynamic, 8) if (nb > 1)
  for (long b = 0; b < nb; ++b) {
    block(ctx, g, u, p, G, (int32_t)b);
  }
}

/* d_a += grad w^T Q^a grad w over particle i's stencil, into a pad (scalar: the Jacobi
 * diagonal is built once per Newton iteration, not per CG iteration). Q: 6 symmetric entries
 * (xx, xy, xz, yy, yz, zz) for each of the 3 components. */
ALWAYS_INLINE void quadratic_particle(const int W, const mpm_stencil *s, const mpm_real Q[18],
                                      mpm_real *pad, int stride, long off, long sx, long sy) {
  for (int a = 0; a < W; ++a)
    for (int b = 0; b < W; ++b)
      for (int c = 0; c < W; ++c) {
        const mpm_real gx = s->dw[0][a] * s->w[1][b] * s->w[2][c];
        const mpm_real gy = s->w[0][a] * s->dw[1][b] * s->w[2][c];
        const mpm_real gz = s->w[0][a] * s->w[1][b] * s->dw[2][c];
        mpm_real *node = pad + (off + a * sx + b * sy + c) * stride;
        for (int d = 0; d < 3; ++d) {
          const mpm_real *q = Q + 6 * d;
          node[d] += q[0] * gx * gx + q[3] * gy * gy + q[5] * gz * gz +
                     2 * (q[1] * gx * gy + q[2] * gx * gz + q[4] * gy * gz);
        }
      }
}

static void quadratic_sparse(const mpm_transfer_ctx *ctx, const mpm_sparse_grid *g,
                             mpm_real *const d[3], const mpm_real *const Q[18],
                             const mpm_particles *p) {
  const int W = ctx->kernel.width;
  for (int colour = 0; colour < 8; ++colour) {
    const long begin = (long)g->color_start[colour], end = (long)g->color_start[colour + 1];
#pragma omp parallel for schedule(dynamic, 4) if (end - begin > 1)
    for (long k = begin; k < end; ++k) {
      const int32_t b = g->color_blocks[k];
      mpm_real pad[MPM_PAD_NODES * STRIDE] __attribute__((aligned(MPM_ALIGN)));
      memset(pad, 0, sizeof pad);
      const int org[3] = {g->coord[b][0] * MPM_BLOCK, g->coord[b][1] * MPM_BLOCK,
                          g->coord[b][2] * MPM_BLOCK};
      size_t q1;
      const size_t q0 = mpm_block_cells(g, (size_t)b, &q1);
      for (uint32_t j = g->cell_start[q0]; j < g->cell_start[q1]; ++j) {
        const uint32_t i = g->perm[j];
        const mpm_real xr[3] = {p->x[0][i] - ctx->origin[0], p->x[1][i] - ctx->origin[1],
                                p->x[2][i] - ctx->origin[2]};
        mpm_stencil s;
        mpm_kernel_stencil(&ctx->kernel, xr, &s);
        mpm_real Qi[18];
        for (int c = 0; c < 18; ++c) Qi[c] = Q[c][i];
        quadratic_particle(W, &s, Qi, pad, STRIDE, mpm_pad_offset(s.base, org), MPM_PAD * MPM_PAD,
                           MPM_PAD);
      }
      mpm_pad_add(W, g, b, 3, pad, STRIDE, d);
    }
  }
}

/* ---- dense grid: scalar reference loops ---- */

/* Stencil of particle i and the dense index of its base node. */
static long dense_stencil(const mpm_transfer_ctx *ctx, const mpm_dense_grid *g,
                          const mpm_particles *p, size_t i, mpm_stencil *s) {
  const mpm_real xr[3] = {p->x[0][i] - ctx->origin[0], p->x[1][i] - ctx->origin[1],
                          p->x[2][i] - ctx->origin[2]};
  mpm_kernel_stencil(&ctx->kernel, xr, s);
  return ((long)s->base[0] * g->n[1] + s->base[1]) * g->n[2] + s->base[2];
}

/* f += M grad w over particle i's stencil (M row-major). */
static void dense_scatter_particle(const mpm_transfer_ctx *ctx, const mpm_dense_grid *g,
                                   const mpm_particles *p, size_t i, const mpm_real M[9],
                                   mpm_real *const f[3]) {
  mpm_stencil s;
  const long n0 = dense_stencil(ctx, g, p, i, &s);
  const int W = ctx->kernel.width;
  const long sy = g->n[2], sx = (long)g->n[1] * g->n[2];
  for (int a = 0; a < W; ++a)
    for (int b = 0; b < W; ++b)
      for (int c = 0; c < W; ++c) {
        const mpm_real gw[3] = {s.dw[0][a] * s.w[1][b] * s.w[2][c],
                                s.w[0][a] * s.dw[1][b] * s.w[2][c],
                                s.w[0][a] * s.w[1][b] * s.dw[2][c]};
        const long n = n0 + a * sx + b * sy + c;
        for (int d = 0; d < 3; ++d)
          f[d][n] += M[3 * d] * gw[0] + M[3 * d + 1] * gw[1] + M[3 * d + 2] * gw[2];
      }
}

static void dense_mass_momentum(const mpm_transfer_ctx *ctx, const mpm_dense_grid *g,
                                const mpm_grid_values *val, const mpm_particles *p) {
  const int W = ctx->kernel.width, apic = ctx->transfer == MPM_TRANSFER_APIC;
  const long sy = g->n[2], sx = (long)g->n[1] * g->n[2];
  for (size_t i = 0; i < p->count; ++i) {
    mpm_stencil s;
    const long n0 = dense_stencil(ctx, g, p, i, &s);
    const mpm_real m = p->mass[i];
    for (int a = 0; a < W; ++a)
      for (int b = 0; b < W; ++b)
        for (int c = 0; c < W; ++c) {
          const mpm_real w = s.w[0][a] * s.w[1][b] * s.w[2][c];
          const long n = n0 + a * sx + b * sy + c;
          val->mass[n] += w * m;
          const mpm_real av[3] = {s.a[0][a] * s.w[1][b] * s.w[2][c],
                                  s.w[0][a] * s.a[1][b] * s.w[2][c],
                                  s.w[0][a] * s.w[1][b] * s.a[2][c]};
          for (int d = 0; d < 3; ++d) {
            mpm_real q = w * m * p->v[d][i];
            if (apic)
              q += m * (p->B[3 * d][i] * av[0] + p->B[3 * d + 1][i] * av[1] +
                        p->B[3 * d + 2][i] * av[2]);
            val->v0[d][n] += q;
          }
        }
  }
}

static void dense_stress_force(const mpm_transfer_ctx *ctx, const mpm_dense_grid *g,
                               mpm_real *const f[3], const mpm_particles *p) {
  mpm_real tau[9][MPM_STRESS_CHUNK];
  uint32_t idx[MPM_STRESS_CHUNK];
  size_t i = 0;
  while (i < p->count) { /* chunks of consecutive particles of one material */
    const int32_t m = p->material[i];
    int n = 0;
    while (i + (size_t)n < p->count && n < MPM_STRESS_CHUNK && p->material[i + (size_t)n] == m) {
      idx[n] = (uint32_t)(i + (size_t)n);
      ++n;
    }
    chunk_stress(&ctx->materials[m], p, idx, n, tau);
    for (int q = 0; q < n; ++q) {
      mpm_real K[9];
      for (int c = 0; c < 9; ++c) K[c] = -p->vol0[idx[q]] * tau[c][q];
      dense_scatter_particle(ctx, g, p, idx[q], K, f);
    }
    i += (size_t)n;
  }
}

static void dense_gather(const mpm_transfer_ctx *ctx, const mpm_dense_grid *g,
                         const mpm_real *const u[3], const mpm_particles *p, mpm_real *const G[9]) {
  const int W = ctx->kernel.width;
  const long sy = g->n[2], sx = (long)g->n[1] * g->n[2];
  const long count = (long)p->count;
#pragma omp parallel for schedule(static)
  for (long i = 0; i < count; ++i) {
    mpm_stencil s;
    const long n0 = dense_stencil(ctx, g, p, (size_t)i, &s);
    mpm_real acc[9] = {0};
    const mpm_real ref[3] = {u[0][n0], u[1][n0], u[2][n0]}; /* as in gather_block */
    for (int a = 0; a < W; ++a)
      for (int b = 0; b < W; ++b)
        for (int c = 0; c < W; ++c) {
          const mpm_real gw[3] = {s.dw[0][a] * s.w[1][b] * s.w[2][c],
                                  s.w[0][a] * s.dw[1][b] * s.w[2][c],
                                  s.w[0][a] * s.w[1][b] * s.dw[2][c]};
          const long n = n0 + a * sx + b * sy + c;
          for (int d = 0; d < 3; ++d)
            for (int e = 0; e < 3; ++e) acc[3 * d + e] += (u[d][n] - ref[d]) * gw[e];
        }
    for (int k = 0; k < 9; ++k) G[k][i] = acc[k];
  }
}

/* ---- the operators of each grid variant ---- */

static void sparse_mass_momentum(const mpm_transfer_ctx *ctx, const mpm_grid *g,
                                 const mpm_grid_values *val, const mpm_particles *p) {
  mpm_p2g_mass_momentum_sparse(ctx, &g->impl.sparse, val, p);
}

static void sparse_stress_force(const mpm_transfer_ctx *ctx, const mpm_grid *g,
                                mpm_real *const f[3], const mpm_particles *p) {
  scatter_sparse(1, ctx, &g->impl.sparse, f, NULL, p);
}

static void sparse_matrices(const mpm_transfer_ctx *ctx, const mpm_grid *g, mpm_real *const f[3],
                            const mpm_real *const M[9], const mpm_particles *p) {
  scatter_sparse(0, ctx, &g->impl.sparse, f, M, p);
}

static void sparse_quadratic_forms(const mpm_transfer_ctx *ctx, const mpm_grid *g,
                                   mpm_real *const d[3], const mpm_real *const Q[18],
                                   const mpm_particles *p) {
  quadratic_sparse(ctx, &g->impl.sparse, d, Q, p);
}

static void sparse_gradients(const mpm_transfer_ctx *ctx, const mpm_grid *g,
                             const mpm_real *const u[3], const mpm_particles *p,
                             mpm_real *const G[9]) {
  gather_sparse(ctx, &g->impl.sparse, u, p, G);
}

static void sparse_p2g(const mpm_transfer_ctx *ctx, const mpm_grid *g, const mpm_grid_values *val,
                       const mpm_particles *p) {
  mpm_p2g_sparse(ctx, &g->impl.sparse, val, p);
}

static mpm_g2p_result sparse_g2p(const mpm_transfer_ctx *ctx, const mpm_grid *g,
                                 const mpm_grid_values *val, mpm_particles *p) {
  return mpm_g2p_sparse(ctx, &g->impl.sparse, val, p);
}

static void dense_mass_momentum_of(const mpm_transfer_ctx *ctx, const mpm_grid *g,
                                   const mpm_grid_values *val, const mpm_particles *p) {
  dense_mass_momentum(ctx, &g->impl.dense, val, p);
}

static void dense_stress_force_of(const mpm_transfer_ctx *ctx, const mpm_grid *g,
                                  mpm_real *const f[3], const mpm_particles *p) {
  dense_stress_force(ctx, &g->impl.dense, f, p);
}

static void dense_matrices(const mpm_transfer_ctx *ctx, const mpm_grid *g, mpm_real *const f[3],
                           const mpm_real *const M[9], const mpm_particles *p) {
  for (size_t i = 0; i < p->count; ++i) {
    mpm_real Mi[9];
    for (int c = 0; c < 9; ++c) Mi[c] = M[c][i];
    dense_scatter_particle(ctx, &g->impl.dense, p, i, Mi, f);
  }
}

static void dense_quadratic_forms(const mpm_transfer_ctx *ctx, const mpm_grid *g,
                                  mpm_real *const d[3], const mpm_real *const Q[18],
                                  const mpm_particles *p) {
  const mpm_dense_grid *dg = &g->impl.dense;
  const long sy = dg->n[2], sx = (long)dg->n[1] * dg->n[2];
  for (size_t i = 0; i < p->count; ++i) {
    mpm_stencil s;
    const long n0 = dense_stencil(ctx, dg, p, i, &s);
    mpm_real Qi[18], node[MPM_STENCIL_MAX * MPM_STENCIL_MAX * MPM_STENCIL_MAX * 3];
    for (int c = 0; c < 18; ++c) Qi[c] = Q[c][i];
    const int W = ctx->kernel.width;
    memset(node, 0, sizeof node);
    quadratic_particle(W, &s, Qi, node, 3, 0, W * W, W);
    for (int a = 0; a < W; ++a)
      for (int b = 0; b < W; ++b)
        for (int c = 0; c < W; ++c)
          for (int e = 0; e < 3; ++e)
            d[e][n0 + a * sx + b * sy + c] += node[((a * W + b) * W + c) * 3 + e];
  }
}

static void dense_gradients(const mpm_transfer_ctx *ctx, const mpm_grid *g,
                            const mpm_real *const u[3], const mpm_particles *p,
                            mpm_real *const G[9]) {
  dense_gather(ctx, &g->impl.dense, u, p, G);
}

static void dense_p2g(const mpm_transfer_ctx *ctx, const mpm_grid *g, const mpm_grid_values *val,
                      const mpm_particles *p) {
  mpm_p2g_dense(ctx, &g->impl.dense, val, p);
}

static mpm_g2p_result dense_g2p(const mpm_transfer_ctx *ctx, const mpm_grid *g,
                                const mpm_grid_values *val, mpm_particles *p) {
  return mpm_g2p_dense(ctx, &g->impl.dense, val, p);
}

/* The dense reference assembles nothing (the multigrid runs on the sparse grid). */
static mpm_status dense_assemble(const mpm_transfer_ctx *ctx, const mpm_grid *g,
                                 const mpm_particles *p, mpm_tangent_fn tangent, void *user,
                                 const int32_t *row_of, int radius, mpm_real *val) {
  (void)ctx, (void)g, (void)p, (void)tangent, (void)user, (void)row_of, (void)radius, (void)val;
  return MPM_ERR_INVALID;
}

/* Indexed by the grid's kind: the one place the transfers ask which grid they run on. */
static const mpm_transfer_variant variants[] = {
    [MPM_GRID_SPARSE] = {.fuses_force = 1,
                         .p2g = sparse_p2g,
                         .g2p = sparse_g2p,
                         .mass_momentum = sparse_mass_momentum,
                         .stress_force = sparse_stress_force,
                         .scatter_matrices = sparse_matrices,
                         .scatter_quadratic_forms = sparse_quadratic_forms,
                         .gather_gradients = sparse_gradients,
                         .assemble_stiffness = mpm_assemble_stiffness_sparse},
    [MPM_GRID_DENSE] = {.fuses_force = 0,
                        .p2g = dense_p2g,
                        .g2p = dense_g2p,
                        .mass_momentum = dense_mass_momentum_of,
                        .stress_force = dense_stress_force_of,
                        .scatter_matrices = dense_matrices,
                        .scatter_quadratic_forms = dense_quadratic_forms,
                        .gather_gradients = dense_gradients,
                        .assemble_stiffness = dense_assemble},
};

const mpm_transfer_variant *mpm_transfer_variant_of(const mpm_grid *g) {
  return &variants[g->kind];
}

/* ---- the operators ---- */

void mpm_p2g_mass_momentum(const mpm_transfer_ctx *ctx, const mpm_grid *g,
                           const mpm_grid_values *val, const mpm_particles *p) {
  mpm_transfer_variant_of(g)->mass_momentum(ctx, g, val, p);
}

void mpm_p2g_stress_force(const mpm_transfer_ctx *ctx, const mpm_grid *g, mpm_real *const f[3],
                          const mpm_particles *p) {
  mpm_transfer_variant_of(g)->stress_force(ctx, g, f, p);
}

void mpm_scatter_matrices(const mpm_transfer_ctx *ctx, const mpm_grid *g, mpm_real *const f[3],
                          const mpm_real *const M[9], const mpm_particles *p) {
  mpm_transfer_variant_of(g)->scatter_matrices(ctx, g, f, M, p);
}

void mpm_scatter_quadratic_forms(const mpm_transfer_ctx *ctx, const mpm_grid *g,
                                 mpm_real *const d[3], const mpm_real *const Q[18],
                                 const mpm_particles *p) {
  mpm_transfer_variant_of(g)->scatter_quadratic_forms(ctx, g, d, Q, p);
}

void mpm_gather_gradients(const mpm_transfer_ctx *ctx, const mpm_grid *g,
                          const mpm_real *const u[3], const mpm_particles *p,
                          mpm_real *const G[9]) {
  mpm_transfer_variant_of(g)->gather_gradients(ctx, g, u, p, G);
}

mpm_status mpm_assemble_stiffness(const mpm_transfer_ctx *ctx, const mpm_grid *g,
                                  const mpm_particles *p, mpm_tangent_fn tangent, void *user,
                                  const int32_t *row_of, int radius, mpm_real *val) {
  return mpm_transfer_variant_of(g)->assemble_stiffness(ctx, g, p, tangent, user, row_of, radius,
                                                        val);
}
