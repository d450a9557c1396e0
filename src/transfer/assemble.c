/* assemble.c - the stiffness of the implicit system as a matrix of 3x3 node blocks
 * (operators.h, mpm_assemble_stiffness), the finest level of the multigrid preconditioner
 * (solver/multigrid.h).
 *
 * The matrix-free action (implicit_hessian.c) scatters M_p = T_p(G_p) grad w_ip with
 * G_p = sum_j u_j grad w_jp^T and T_p the particle's linear map of velocity gradients (its
 * stress derivative with F folded in). Written in components, with T_p as the 9 x 9 matrix
 * C_p[(a, c), (b, d)] (M_ac = sum_bd C_ac,bd G_bd), the block that couples node j's velocity to
 * node i's force is
 *   K_ij[a][b] = sum_p sum_cd C_p[(a, c), (b, d)] grad w_ip^c grad w_jp^d.
 * The particles of one cell share their 3 x 3 x 3 (W^3) stencil nodes, so a cell's pairs are
 * summed in a local W^3 x W^3 table of blocks and added to the matrix once per cell; per particle
 * the product is taken in two stages, T_j[(a, c), b] = sum_d C[(a, c), (b, d)] grad w_j^d for each
 * node, then K_ij[a][b] += sum_c grad w_i^c T_j[(a, c), b], over the pairs i <= j only (the
 * definite stress derivative is symmetric, so K_ji = K_ij^T), written to row i alone: the
 * transposed write to row j doubled the scattered traffic into the matrix, and the caller fills
 * the lower half afterwards in one pass over rows. Blocks run colour by colour as in
 * the scatters (operators.c): a colour's blocks write disjoint rows, and every row receives its
 * sums in a fixed order, whatever the number of threads. */
#include "core/parallel.h"
#include "transfer/batches.h"
#include "transfer/operators.h"
#include "transfer/transfer_lanes.h"

#include <string.h>

#define KMAX (MPM_STENCIL_MAX * MPM_STENCIL_MAX * MPM_STENCIL_MAX)

/* The table of one stencil's pairs (cell) into the matrix rows of its nodes, base node `base`
 * in owner block b (origin org): K_in at row i, n >= i in the stencil's order, so its offset
 * x_n - x_i is at or after the centre in the slots' order (the upper half; the caller mirrors
 * it, operators.h). */
static void flush_pairs(const int W, const mpm_sparse_grid *g, int32_t b, const int org[3],
                        const int base[3], const int32_t *row_of, int radius, mpm_real *val,
                        const mpm_real *cell) {
  const int K = W * W * W, span = 2 * radius + 1;
  const size_t S = (size_t)span * (size_t)span * (size_t)span;
  int32_t rows[KMAX];
  int off[KMAX][3];
  for (int a = 0, n = 0; a < W; ++a)
    for (int e = 0; e < W; ++e)
      for (int c = 0; c < W; ++c, ++n) {
        const int pad[3] = {base[0] - org[0] + a, base[1] - org[1] + e, base[2] - org[2] + c};
        const int o =
            ((pad[0] >= MPM_BLOCK) << 2) | ((pad[1] >= MPM_BLOCK) << 1) | (pad[2] >= MPM_BLOCK);
        const size_t node =
            (size_t)g->neighbor[b][o] * MPM_BLOCK_NODES +
            (size_t)(((pad[0] & 3) * MPM_BLOCK + (pad[1] & 3)) * MPM_BLOCK + (pad[2] & 3));
        rows[n] = row_of[node];
        off[n][0] = a, off[n][1] = e, off[n][2] = c;
      }
  for (int i = 0; i < K; ++i)
    for (int n = i; n < K; ++n) {
      const mpm_real *blk = cell + ((size_t)i * (size_t)K + (size_t)n) * 9;
      const size_t slot =
          (size_t)(((off[n][0] - off[i][0] + radius) * span + (off[n][1] - off[i][1] + radius)) *
                       span +
                   (off[n][2] - off[i][2] + radius));
      if (rows[i] >= 0) {
        mpm_real *dst = val + ((size_t)rows[i] * S + slot) * 9;
        for (int k = 0; k < 9; ++k) dst[k] += blk[k];
      }
    }
}

/* The pairs of a batch of up to MPM_LANES particles that share a stencil (the lanes past the
 * batch hold zero weight gradients, so whatever their C they add zeros), summed over the lanes into
 * the cell table: per pair (i, n) the 9 entries are vectors over the particles, reduced 8 at a time
 * (mpm_vl_sum8) and the 9th alone. */
static void batch_pairs(const int W, const mpm_vl gw[KMAX][3], const mpm_vl C[81], mpm_real *cell) {
  const int K = W * W * W;
  /* T_n[(a, c), b] = sum_d C[(a, c), (b, d)] grad w_n^d */
  mpm_vl T[KMAX][27];
  for (int n = 0; n < K; ++n)
    for (int ac = 0; ac < 9; ++ac)
      for (int bb = 0; bb < 3; ++bb) {
        const mpm_vl *c = C + 9 * ac + 3 * bb;
        T[n][3 * ac + bb] = c[0] * gw[n][0] + c[1] * gw[n][1] + c[2] * gw[n][2];
      }
  for (int i = 0; i < K; ++i)
    for (int n = i; n < K; ++n) {
      mpm_real *blk = cell + ((size_t)i * (size_t)K + (size_t)n) * 9;
      const mpm_vl *t = T[n];
      mpm_vl acc[9];
      for (int a = 0; a < 3; ++a)
        for (int bb = 0; bb < 3; ++bb)
          acc[3 * a + bb] = gw[i][0] * t[3 * (3 * a) + bb] + gw[i][1] * t[3 * (3 * a + 1) + bb] +
                            gw[i][2] * t[3 * (3 * a + 2) + bb];
      const mpm_v8 s8 = mpm_vl_sum8(acc);
      for (int k = 0; k < 8; ++k) blk[k] += s8[k];
      mpm_real last = 0;
      for (int l = 0; l < MPM_LANES; ++l) last += acc[8][l];
      blk[8] += last;
    }
}

/* One owner block's particles into the matrix rows of its pad's nodes. The particles of a cell
 * run share their base node (the sort's); they are taken MPM_LANES at a time as SIMD lanes, and
 * their pairs summed in `cell` until the base changes (a kernel whose base the sort did not
 * use starts a new batch and a new table). */
static void assemble_block(const mpm_transfer_ctx *ctx, const mpm_sparse_grid *g,
                           const mpm_particles *p, mpm_tangent_fn tangent, void *user,
                           const int32_t *row_of, int radius, mpm_real *val, int32_t b,
                           mpm_real *cell /* KMAX * KMAX * 9 */) {
  const int W = ctx->kernel.width, K = W * W * W;
  const size_t table = (size_t)K * (size_t)K * 9 * sizeof(mpm_real);
  const int org[3] = {g->coord[b][0] * MPM_BLOCK, g->coord[b][1] * MPM_BLOCK,
                      g->coord[b][2] * MPM_BLOCK};
  size_t q1;
  const size_t q0 = mpm_block_cells(g, (size_t)b, &q1);
  int base[3] = {0, 0, 0}, filled = 0, lanes = 0;
  uint32_t batch[MPM_LANES];
  mpm_vl gw[KMAX][3], C[81];
  const mpm_vl zero = {0};
  for (size_t q = q0; q < q1; ++q)
    for (uint32_t j = g->cell_start[q]; j < g->cell_start[q + 1]; ++j) {
      const uint32_t pi = g->perm[j];
      const mpm_real xr[3] = {p->x[0][pi] - ctx->origin[0], p->x[1][pi] - ctx->origin[1],
                              p->x[2][pi] - ctx->origin[2]};
      mpm_stencil s;
      mpm_kernel_stencil(&ctx->kernel, xr, &s);
      const int same =
          filled && s.base[0] == base[0] && s.base[1] == base[1] && s.base[2] == base[2];
      if (lanes && (!same || lanes == MPM_LANES)) { /* the batch is full or ends here */
        tangent(user, batch, lanes, C);
        batch_pairs(W, (const mpm_vl(*)[3])gw, C, cell);
        lanes = 0;
      }
      if (!same) {
        if (filled) flush_pairs(W, g, b, org, base, row_of, radius, val, cell);
        memcpy(base, s.base, sizeof base);
        memset(cell, 0, table);
        filled = 1;
      }
      if (lanes == 0)
        for (int n = 0; n < K; ++n) gw[n][0] = gw[n][1] = gw[n][2] = zero;
      for (int a = 0, n = 0; a < W; ++a)
        for (int e = 0; e < W; ++e)
          for (int c = 0; c < W; ++c, ++n) {
            gw[n][0][lanes] = s.dw[0][a] * s.w[1][e] * s.w[2][c];
            gw[n][1][lanes] = s.w[0][a] * s.dw[1][e] * s.w[2][c];
            gw[n][2][lanes] = s.w[0][a] * s.w[1][e] * s.dw[2][c];
          }
      batch[lanes++] = pi;
    }
  if (lanes) {
    tangent(user, batch, lanes, C);
    batch_pairs(W, (const mpm_vl(*)[3])gw, C, cell);
  }
  if (filled) flush_pairs(W, g, b, org, base, row_of, radius, val, cell);
}

mpm_status mpm_assemble_stiffness_sparse(const mpm_transfer_ctx *ctx, const mpm_grid *g,
                                         const mpm_particles *p, mpm_tangent_fn tangent, void *user,
                                         const int32_t *row_of, int radius, mpm_real *val) {
  if (radius < ctx->kernel.width - 1) return MPM_ERR_INVALID;
  const mpm_sparse_grid *sg = &g->impl.sparse;
  for (int colour = 0; colour < 8; ++colour) {
    const long begin = (long)sg->color_start[colour], end = (long)sg->color_start[colour + 1];
#pragma omp parallel if (end - begin > 1)
    {
      mpm_real local[KMAX * KMAX * 9]; /* the cell's table of pairs, per thread */
#pragma omp for schedule(dynamic, 2)
      for (long q = begin; q < end; ++q)
        assemble_block(ctx, sg, p, tangent, user, row_of, radius, val, sg->color_blocks[q], local);
    }
  }
  return MPM_OK;
}
