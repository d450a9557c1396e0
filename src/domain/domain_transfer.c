/* domain_transfer.c - two-step particle -> corner -> grid transfers and back (see
 * domain_transfer.h). */
#include "domain/domain_transfer.h"
#include "core/mat3.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int mpm_domain_activate(mpm_domain_set *s, mpm_sparse_grid *g, const mpm_kernel *k,
                        const mpm_real origin[3]) {
  /* corners come in lattice order: neighbours mostly share their base block, whose 8 block
   * indices are then reused instead of looked up again */
  int32_t last[3] = {INT32_MIN, INT32_MIN, INT32_MIN};
  int32_t last_blocks[8] = {0};
  for (size_t c = 0; c < s->corner_count; ++c) {
    if (s->adj_start[c] == s->adj_start[c + 1]) continue; /* no active particle uses it */
    const mpm_real xr[3] = {s->cx[0][c] - origin[0], s->cx[1][c] - origin[1],
                            s->cx[2][c] - origin[2]};
    mpm_stencil st;
    mpm_kernel_stencil(k, xr, &st);
    int32_t *blocks = s->cblock[c];
    for (int d = 0; d < 3; ++d) s->cbase[c][d] = st.base[d];
    const int32_t bb[3] = {st.base[0] >> MPM_BLOCK_BITS, st.base[1] >> MPM_BLOCK_BITS,
                           st.base[2] >> MPM_BLOCK_BITS};
    if (bb[0] == last[0] && bb[1] == last[1] && bb[2] == last[2]) {
      memcpy(blocks, last_blocks, sizeof last_blocks);
      continue;
    }
    for (int o = 0; o < 8; ++o) {
      const int32_t bc[3] = {bb[0] + ((o >> 2) & 1), bb[1] + ((o >> 1) & 1), bb[2] + (o & 1)};
      blocks[o] = mpm_sparse_grid_touch(g, bc);
      if (blocks[o] < 0) return -1;
    }
    memcpy(last, bb, sizeof last);
    memcpy(last_blocks, blocks, sizeof last_blocks);
  }
  return 0;
}

/* The level's node index of node base + (i, j, k) of a corner's stencil. */
static inline size_t node_at(const int32_t cblock[8], const int32_t base[3], int i, int j, int k) {
  const int n[3] = {base[0] + i, base[1] + j, base[2] + k};
  const int o = (((n[0] >> MPM_BLOCK_BITS) - (base[0] >> MPM_BLOCK_BITS)) << 2) |
                (((n[1] >> MPM_BLOCK_BITS) - (base[1] >> MPM_BLOCK_BITS)) << 1) |
                ((n[2] >> MPM_BLOCK_BITS) - (base[2] >> MPM_BLOCK_BITS));
  const int local = ((n[0] & 3) << 4) | ((n[1] & 3) << 2) | (n[2] & 3);
  return (size_t)cblock[o] * MPM_BLOCK_NODES + (size_t)local;
}

/* Group the used corners by base block (counting sort on the block index, stable in corner
 * order) and the groups by colour; fills group_corner, group_start and colour_start. */
static int group_corners(mpm_domain_set *s, const mpm_sparse_grid *g) {
  const size_t nc = s->corner_count, nb = g->block_count;
  if (s->group_capacity < nc + 1 || s->block_capacity < nb + 1) {
    free(s->group_corner);
    free(s->group_start);
    free(s->block_group);
    s->group_corner = malloc((nc + 1) * sizeof *s->group_corner);
    s->group_start = malloc((nb + 2) * sizeof *s->group_start);
    s->block_group = malloc((nb + 1) * sizeof *s->block_group);
    if (!s->group_corner || !s->group_start || !s->block_group) {
      s->group_capacity = s->block_capacity = 0;
      return -1;
    }
    s->group_capacity = nc + 1;
    s->block_capacity = nb + 1;
  }
  /* the base blocks in use, numbered as groups in colour order, then block order */
  int32_t *bg = s->block_group;
  for (size_t b = 0; b < nb; ++b) bg[b] = -1;
  for (size_t c = 0; c < nc; ++c)
    if (s->adj_start[c] != s->adj_start[c + 1]) bg[s->cblock[c][0]] = 0;
  size_t groups = 0;
  for (int colour = 0; colour < 8; ++colour) {
    s->colour_start[colour] = groups;
    for (size_t b = 0; b < nb; ++b) {
      if (bg[b] < 0) continue;
      const int32_t *bc = g->coord[b];
      if (((bc[0] & 1) << 2 | (bc[1] & 1) << 1 | (bc[2] & 1)) == colour) bg[b] = (int32_t)groups++;
    }
  }
  s->colour_start[8] = groups;
  /* counting sort of the corners by group */
  uint32_t *start = s->group_start;
  memset(start, 0, (groups + 1) * sizeof *start);
  for (size_t c = 0; c < nc; ++c)
    if (s->adj_start[c] != s->adj_start[c + 1]) start[bg[s->cblock[c][0]] + 1]++;
  for (size_t q = 0; q < groups; ++q) start[q + 1] += start[q];
  for (size_t c = 0; c < nc; ++c)
    if (s->adj_start[c] != s->adj_start[c + 1]) {
      const int32_t q = bg[s->cblock[c][0]];
      s->group_corner[start[q]++] = (uint32_t)c;
    }
  for (size_t q = groups; q > 0; --q) start[q] = start[q - 1]; /* back to the starts */
  start[0] = 0;
  return 0;
}

int mpm_domain_p2g(const mpm_transfer_ctx *ctx, mpm_domain_set *s, const mpm_sparse_grid *g,
                   const mpm_grid_values *val) {
  const mpm_particles *p = &s->particles;
  const long nc = (long)s->corner_count, np = (long)p->count;
  /* 0. V0 P of every active particle, once (each is gathered by its 8 corners) */
  if (s->vP_capacity < p->count) {
    mpm_real(*grown)[9] = realloc(s->vP, (p->count + 1) * sizeof *grown);
    if (!grown) return -1;
    s->vP = grown;
    s->vP_capacity = p->count;
  }
#pragma omp parallel for schedule(static)
  for (long q = 0; q < np; ++q) {
    if (!s->active[q]) continue;
    mpm_real F[9], P[9];
    for (int e = 0; e < 9; ++e) F[e] = p->F[e][q];
    const mpm_material mat = mpm_material_at(&ctx->materials[p->material[q]], p->plastic[q]);
    mat.model->pk1(&mat, F, P);
    for (int e = 0; e < 9; ++e) s->vP[q][e] = p->vol0[q] * P[e];
  }
  /* 1. particle -> corner, gathered per corner (each corner sums its <= 8 particle slots in
   *    slot order: no races, the same sums for any thread count) */
#pragma omp parallel for schedule(static)
  for (long c = 0; c < nc; ++c) {
    double m = 0, mv[3] = {0, 0, 0}, f[3] = {0, 0, 0};
    for (uint32_t j = s->adj_start[c]; j < s->adj_start[c + 1]; ++j) {
      const uint32_t q = s->adj[j] / MPM_HEX_CORNERS, a = s->adj[j] % MPM_HEX_CORNERS;
      const double w = s->w[q][a];
      const double mq = p->mass[q];
      m += w * mq;
      for (int d = 0; d < 3; ++d) mv[d] += w * mq * p->v[d][q];
      /* f_a = -V0 P g_ap (Zhu eq. 8 with eq. 5) */
      const mpm_real *gq = s->g[q][a], *vP = s->vP[q];
      for (int d = 0; d < 3; ++d)
        f[d] -= vP[3 * d] * gq[0] + vP[3 * d + 1] * gq[1] + vP[3 * d + 2] * gq[2];
    }
    s->cm[c] = (mpm_real)m;
    for (int d = 0; d < 3; ++d) {
      s->cp[d][c] = (mpm_real)mv[d];
      s->cf[d][c] = (mpm_real)f[d];
    }
  }
  /* 2. corner -> grid. Corners are grouped by their base block and the groups coloured by the
   *    parity of the block's coordinates, as the standard P2G does (sparse_grid.h): a stencil
   *    reaches only its base block and the forward neighbours, so the groups of one colour
   *    never touch the same node and run in parallel, and a node receives the colours in a
   *    fixed order and each group's corners in corner order: the same sums for any number
   *    of threads. */
  if (group_corners(s, g)) return -1;
  const mpm_kernel *k = &ctx->kernel;
  const int W = k->width;
  for (int colour = 0; colour < 8; ++colour) {
    const long g0 = (long)s->colour_start[colour], g1 = (long)s->colour_start[colour + 1];
#pragma omp parallel for schedule(dynamic, 4)
    for (long grp = g0; grp < g1; ++grp)
      for (uint32_t j = s->group_start[grp]; j < s->group_start[grp + 1]; ++j) {
        const uint32_t c = s->group_corner[j];
        const mpm_real xr[3] = {s->cx[0][c] - ctx->origin[0], s->cx[1][c] - ctx->origin[1],
                                s->cx[2][c] - ctx->origin[2]};
        mpm_stencil st;
        mpm_kernel_stencil(k, xr, &st);
        for (int i = 0; i < W; ++i)
          for (int jj = 0; jj < W; ++jj)
            for (int l = 0; l < W; ++l) {
              const mpm_real w = st.w[0][i] * st.w[1][jj] * st.w[2][l];
              if (w == 0) continue;
              const size_t n = node_at(s->cblock[c], s->cbase[c], i, jj, l);
              val->mass[n] += w * s->cm[c];
              for (int d = 0; d < 3; ++d) {
                val->v0[d][n] += w * s->cp[d][c];
                val->f[d][n] += w * s->cf[d][c];
              }
            }
      }
  }
  return 0;
}

void mpm_domain_update_F(mpm_domain_set *s, size_t q, mpm_real dt) {
  mpm_real gradv[9] = {0}; /* grad_X v = sum_i v_i grad_X omega_ip^T = sum_a v^g_a g_ap^T */
  for (int a = 0; a < MPM_HEX_CORNERS; ++a) {
    const uint32_t c = s->corner[q][a];
    const mpm_real *ga = s->g[q][a];
    for (int r = 0; r < 3; ++r)
      for (int t = 0; t < 3; ++t) gradv[3 * r + t] += s->cvg[r][c] * ga[t];
  }
  for (int e = 0; e < 9; ++e) s->particles.F[e][q] += dt * gradv[e];
}

mpm_g2p_result mpm_domain_g2p(const mpm_transfer_ctx *ctx, mpm_domain_set *s,
                              const mpm_grid_values *val, const mpm_collider_pose *poses,
                              int collider_count) {
  const mpm_kernel *k = &ctx->kernel;
  const int W = k->width;
  const long nc = (long)s->corner_count;
  const mpm_real dt = ctx->dt, alpha = ctx->flip_alpha;
  /* 1. grid -> corner: the grid velocity (PIC) and the hybrid PIC/FLIP corner velocity */
  mpm_real max_v2 = 0; /* corners move at their grid velocity: it bounds the next dt too */
#pragma omp parallel for schedule(static) reduction(max : max_v2)
  for (long c = 0; c < nc; ++c) {
    if (s->adj_start[c] == s->adj_start[c + 1]) continue;
    const mpm_real xr[3] = {s->cx[0][c] - ctx->origin[0], s->cx[1][c] - ctx->origin[1],
                            s->cx[2][c] - ctx->origin[2]};
    mpm_stencil st;
    mpm_kernel_stencil(k, xr, &st);
    mpm_real vnew[3] = {0, 0, 0}, dv[3] = {0, 0, 0};
    for (int i = 0; i < W; ++i)
      for (int j = 0; j < W; ++j)
        for (int l = 0; l < W; ++l) {
          const mpm_real w = st.w[0][i] * st.w[1][j] * st.w[2][l];
          if (w == 0) continue;
          const size_t n = node_at(s->cblock[c], s->cbase[c], i, j, l);
          for (int d = 0; d < 3; ++d) {
            const mpm_real vn = val->v[d][n];
            const mpm_real vo = val->v0[d][n];
            vnew[d] += w * vn;
            dv[d] += w * (vn - vo);
          }
        }
    mpm_real v[3];
    for (int d = 0; d < 3; ++d) {
      s->cvg[d][c] = vnew[d];
      v[d] = alpha * (s->cv[d][c] + dv[d]) + (1 - alpha) * vnew[d];
    }
    /* colliders on the corners (Zhu sec. 7, Algorithm 1 line 24): the corner velocity obeys
     * the boundary rule, and the particles take their velocities from the corners, which
     * applies the collision impulse to them. The corner moves with the grid velocity (which
     * the grid update already made obey the colliders), as F does: F stays the gradient of
     * the corner positions (F = sum_a x_a g_ap^T) */
    const mpm_real vg[3] = {vnew[0], vnew[1], vnew[2]};
    const mpm_real xn[3] = {s->cx[0][c], s->cx[1][c], s->cx[2][c]};
    for (int q = 0; q < collider_count; ++q) mpm_collider_apply(&poses[q], xn, v);
    const mpm_real vg2 = vg[0] * vg[0] + vg[1] * vg[1] + vg[2] * vg[2];
    if (vg2 > max_v2) max_v2 = vg2;
    for (int d = 0; d < 3; ++d) {
      s->cv[d][c] = v[d];
      mpm_real x = s->cx[d][c] + dt * vg[d]; /* Zhu eq. 9 */
      x = x < ctx->clamp_lo[d] ? ctx->clamp_lo[d] : x;
      s->cx[d][c] = x > ctx->clamp_hi[d] ? ctx->clamp_hi[d] : x;
    }
  }
  /* 2. particles: F from the grid velocities at the corners (Zhu eq. 7), the return map of
   *    plastic models, then position and velocity from the corners */
  mpm_particles *p = &s->particles;
  const long n = (long)p->count;
  long bad = -1;
#pragma omp parallel for schedule(static) reduction(max : max_v2)
  for (long q = 0; q < n; ++q) {
    if (!s->active[q]) continue;
    mpm_domain_update_F(s, (size_t)q, dt);
    mpm_real *F[9];
    for (int e = 0; e < 9; ++e) F[e] = p->F[e] + q;
    const mpm_material *mat = &ctx->materials[p->material[q]];
    if (mat->model->return_map) mat->model->return_map(mat, 1, F, p->plastic + q);
    mpm_real x[3] = {0, 0, 0}, v[3] = {0, 0, 0};
    for (int a = 0; a < MPM_HEX_CORNERS; ++a) {
      const uint32_t c = s->corner[q][a];
      const mpm_real w = s->w[q][a];
      for (int d = 0; d < 3; ++d) {
        x[d] += w * s->cx[d][c];
        v[d] += w * s->cv[d][c];
      }
    }
    mpm_real check = 0, v2 = 0;
    for (int d = 0; d < 3; ++d) {
      p->x[d][q] = x[d];
      p->v[d][q] = v[d];
      check += x[d];
      v2 += v[d] * v[d];
    }
    for (int e = 0; e < 9; ++e) check += *F[e];
    if (!isfinite(check + v2)) {
#pragma omp critical(mpm_domain_bad)
      if (bad < 0 || q < bad) bad = q;
    } else if (v2 > max_v2) {
      max_v2 = v2;
    }
  }
  mpm_g2p_result r = {mpm_sqrt(max_v2), bad};
  return r;
}
