/* grid_update.c - grid velocity update, colliders and domain walls (Gao sec. 3.2 steps 3-4). */
#include "solver/grid_update.h"
#include "core/parallel.h"

void mpm_grid_update_node(const mpm_grid_update_ctx *u, const int idx[3], mpm_real *m,
                          mpm_real mv[3], mpm_real f[3]) {
  const mpm_real mass = *m;
  if (!(mass > 0)) {
    for (int d = 0; d < 3; ++d) mv[d] = f[d] = 0;
    return;
  }
  const mpm_real inv_m = 1 / mass;
  mpm_real v_old[3], v[3];
  for (int d = 0; d < 3; ++d) {
    v_old[d] = mv[d] * inv_m;
    v[d] = v_old[d] + u->dt * (f[d] * inv_m + u->gravity[d]);
  }
  if (u->collider_count) {
    const mpm_real x[3] = {u->origin[0] + idx[0] * u->dx, u->origin[1] + idx[1] * u->dx,
                           u->origin[2] + idx[2] * u->dx};
    for (int c = 0; c < u->collider_count; ++c) mpm_collider_apply(&u->poses[c], x, v);
  }
  static const mpm_real zero[3] = {0, 0, 0};
  for (int d = 0; d < 3; ++d) {
    if (idx[d] < u->wall_lo[d] || idx[d] > u->wall_hi[d]) {
      mpm_real n[3] = {0, 0, 0};
      n[d] = idx[d] < u->wall_lo[d] ? 1 : -1;
      mpm_boundary_project(u->wall_rule, u->wall_friction, n, zero, v);
    }
  }
  for (int d = 0; d < 3; ++d) {
    mv[d] = v_old[d]; /* MPM_CH_VOLD */
    f[d] = v[d];      /* MPM_CH_VNEW */
  }
}

void mpm_grid_update_sparse(const mpm_grid_update_ctx *u, mpm_sparse_grid *g) {
  const long nb = (long)g->block_count;
#pragma omp parallel for schedule(dynamic, 16)
  for (long b = 0; b < nb; ++b) {
    mpm_grid_block *blk = &g->blocks[b];
    const int *c = g->coord[b];
    for (int n = 0; n < MPM_BLOCK_NODES; ++n) {
      const int idx[3] = {c[0] * MPM_BLOCK + (n >> 4), c[1] * MPM_BLOCK + ((n >> 2) & 3),
                          c[2] * MPM_BLOCK + (n & 3)};
      mpm_real mv[3] = {blk->ch[MPM_CH_MV][n], blk->ch[MPM_CH_MV + 1][n],
                        blk->ch[MPM_CH_MV + 2][n]};
      mpm_real f[3] = {0, 0, 0};
      if (!u->force_in_momentum)
        for (int d = 0; d < 3; ++d) f[d] = blk->ch[MPM_CH_F + d][n];
      mpm_grid_update_node(u, idx, &blk->ch[MPM_CH_MASS][n], mv, f);
      for (int d = 0; d < 3; ++d) {
        blk->ch[MPM_CH_MV + d][n] = mv[d];
        blk->ch[MPM_CH_F + d][n] = f[d];
      }
    }
  }
}

void mpm_grid_update_dense(const mpm_grid_update_ctx *u, mpm_dense_grid *g) {
  const int nx = g->n[0], ny = g->n[1], nz = g->n[2];
#pragma omp parallel for schedule(static)
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < ny; ++j)
      for (int k = 0; k < nz; ++k) {
        const size_t n = ((size_t)i * ny + j) * nz + k;
        const int idx[3] = {i, j, k};
        mpm_real mv[3] = {g->ch[MPM_CH_MV][n], g->ch[MPM_CH_MV + 1][n], g->ch[MPM_CH_MV + 2][n]};
        mpm_real f[3] = {g->ch[MPM_CH_F][n], g->ch[MPM_CH_F + 1][n], g->ch[MPM_CH_F + 2][n]};
        mpm_grid_update_node(u, idx, &g->ch[MPM_CH_MASS][n], mv, f);
        for (int d = 0; d < 3; ++d) {
          g->ch[MPM_CH_MV + d][n] = mv[d];
          g->ch[MPM_CH_F + d][n] = f[d];
        }
      }
}
