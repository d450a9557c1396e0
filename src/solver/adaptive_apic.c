/* adaptive_apic.c - APIC with exact angular momentum across the levels of the multi-level grid
 * (docs/adaptive-grid.md, "APIC with exact angular momentum across levels"; Gao et al. list it
 * as future work).
 *
 * A particle whose stencil reaches a ghost with a row of several real nodes (a T-junction or a
 * refined node inside a coarser leaf) is a *boundary particle*. For it the lane kernels are not
 * the real-node APIC transfer:
 *   P2G  the lanes add m B_p D~^-1 (x_g - x_p) w_gp with D~ the ghost-level D_p, while the real
 *        nodes need C_p = B_p D_p^-1 with D_p = sum_g w_gp ((x_g - x_p)(x_g - x_p)^T + S_g) and,
 *        at each ghost, the affine moment A_g = sum_p w_gp m_p C_p, which
 *        mpm_adaptive_grid_scatter_apic carries to the real nodes as m_p C_p (x_i - x_g);
 *   G2P  the lanes give sum_g w_gp v_g (x_g - x_p)^T, and B_p needs sum_g w_gp M_g besides, the
 *        ghosts' velocity moments (mpm_adaptive_grid_gather_moments).
 * This scalar pass makes both corrections for the boundary particles only, so the lane kernels
 * stay as they are. It runs serially in a fixed order (the boundary particles' writes overlap),
 * so results do not depend on the thread count. */
#include "solver/adaptive.h"

#include "core/alloc.h"
#include "solver/sim.h"

#include <string.h>

static int grow(void **buf, size_t *cap, size_t n, size_t size) {
  if (n <= *cap) return 0;
  size_t c = *cap ? *cap : 1024;
  while (c < n) c *= 2;
  void *b = mpm_alloc(c * size);
  if (!b) return -1;
  if (*buf) memcpy(b, *buf, *cap * size);
  mpm_free(*buf);
  *buf = b;
  *cap = c;
  return 0;
}

/* The DOF slots of the W^3 stencil at `base` (node coordinates of the grid) of a particle in
 * owner block b, through the block's pad. */
static void stencil_slots(const mpm_grid *g, size_t b, const int32_t base[3], int W,
                          uint32_t *slot) {
  const mpm_sparse_grid *sg = &g->impl.sparse;
  int n = 0;
  for (int i = 0; i < W; ++i)
    for (int j = 0; j < W; ++j)
      for (int k = 0; k < W; ++k, ++n) {
        const int32_t p[3] = {base[0] - sg->coord[b][0] * MPM_BLOCK + i,
                              base[1] - sg->coord[b][1] * MPM_BLOCK + j,
                              base[2] - sg->coord[b][2] * MPM_BLOCK + k}; /* 0 .. 6 in the pad */
        const int o = (p[0] >> 2) << 2 | (p[1] >> 2) << 1 | (p[2] >> 2);
        const int local = (p[0] & 3) << 4 | (p[1] & 3) << 2 | (p[2] & 3);
        slot[n] =
            (uint32_t)(g->dof_begin + (size_t)sg->neighbor[b][o] * MPM_BLOCK_NODES + (size_t)local);
      }
}

mpm_status mpm_adaptive_apic_prepare(mpm_sim *sim) {
  mpm_adaptive *a = sim->adaptive;
  mpm_adaptive_grid *ag = &a->grid;
  a->boundary_count = 0;
  const size_t dofs = sim->dofs.count;
  if (grow((void **)&a->ghost_of, &a->ghost_of_capacity, dofs + 1, sizeof *a->ghost_of)) goto nomem;
  memset(a->ghost_of, 0xff, dofs * sizeof *a->ghost_of);
  size_t multi = 0;
  for (size_t g = 0; g < ag->ghost_count; ++g)
    if (ag->ghosts.row_len[g] > 1) {
      a->ghost_of[ag->ghost_slot[g]] = (int32_t)g;
      ++multi;
    }
  /* the ghosts' affine moments (P2G) and velocity moments (G2P), zero at ghosts no boundary
   * particle reaches */
  if (grow((void **)&a->moment, &a->moment_capacity, 9 * ag->ghost_count + 1, sizeof *a->moment))
    goto nomem;
  memset(a->moment, 0, 9 * ag->ghost_count * sizeof *a->moment);
  if (!multi) return MPM_OK;
  uint32_t slot[MPM_STENCIL_MAX * MPM_STENCIL_MAX * MPM_STENCIL_MAX];
  for (int t = 0; t < a->tgrid_count; ++t) {
    const mpm_transfer_grid *tg = &a->tgrid[t];
    const mpm_grid *g = mpm_adaptive_grid_at(ag, tg->G);
    const mpm_sparse_grid *sg = &g->impl.sparse;
    const int W = tg->kernel.width, nodes = W * W * W;
    const size_t nmat = (size_t)sg->material_count;
    for (size_t b = 0; b < sg->owner_count; ++b)
      for (int c = 0; c < MPM_BLOCK_NODES; ++c) {
        const size_t q0 = (b * nmat) * MPM_BLOCK_NODES + (size_t)c;
        int any = 0;
        for (size_t m = 0; m < nmat && !any; ++m)
          any = sg->cell_start[q0 + m * MPM_BLOCK_NODES + 1] >
                sg->cell_start[q0 + m * MPM_BLOCK_NODES];
        if (!any) continue;
        const int32_t base[3] = {sg->coord[b][0] * MPM_BLOCK + ((c >> 4) & 3),
                                 sg->coord[b][1] * MPM_BLOCK + ((c >> 2) & 3),
                                 sg->coord[b][2] * MPM_BLOCK + (c & 3)};
        stencil_slots(g, b, base, W, slot);
        int reaches = 0;
        for (int n = 0; n < nodes && !reaches; ++n) reaches = a->ghost_of[slot[n]] >= 0;
        if (!reaches) continue;
        for (size_t m = 0; m < nmat; ++m) {
          const size_t q = q0 + m * MPM_BLOCK_NODES;
          for (uint32_t j = sg->cell_start[q]; j < sg->cell_start[q + 1]; ++j) {
            if (grow((void **)&a->boundary, &a->boundary_capacity, a->boundary_count + 1,
                     sizeof *a->boundary))
              goto nomem;
            a->boundary[a->boundary_count].particle = (uint32_t)a->range[t] + sg->perm[j];
            a->boundary[a->boundary_count].tgrid = (uint16_t)t;
            a->boundary[a->boundary_count].block = (uint32_t)b;
            a->boundary_count++;
          }
        }
      }
  }
  /* per boundary particle its B correction */
  if (grow((void **)&a->dB, &a->dB_capacity, 9 * a->boundary_count + 1, sizeof *a->dB)) goto nomem;
  return MPM_OK;
nomem:
  return mpm_error_set(&sim->error, MPM_ERR_NOMEM,
                       "step %lld: out of memory for the APIC moments of the ghost nodes",
                       (long long)sim->steps);
}

/* A boundary particle's stencil on its transfer grid: weights, offsets x_g - x_p and slots. */
typedef struct boundary_stencil {
  int W;
  mpm_stencil s;
  double f[3]; /* distance from the base node, cells */
  uint32_t slot[MPM_STENCIL_MAX * MPM_STENCIL_MAX * MPM_STENCIL_MAX];
} boundary_stencil;

static void boundary_stencil_of(const mpm_adaptive *a, const mpm_sim *sim, size_t k,
                                boundary_stencil *bs) {
  const mpm_particles *p = &sim->particles;
  const mpm_transfer_grid *tg = &a->tgrid[a->boundary[k].tgrid];
  const mpm_grid *g = mpm_adaptive_grid_at((mpm_adaptive_grid *)&a->grid, tg->G);
  const size_t i = a->boundary[k].particle;
  mpm_real x[3];
  for (int d = 0; d < 3; ++d) x[d] = p->x[d][i] - g->origin[d];
  mpm_kernel_stencil(&tg->kernel, x, &bs->s);
  for (int d = 0; d < 3; ++d) bs->f[d] = (double)(x[d] * tg->kernel.inv_dx) - bs->s.base[d];
  bs->W = tg->kernel.width;
  const int32_t base[3] = {bs->s.base[0], bs->s.base[1], bs->s.base[2]};
  stencil_slots(g, a->boundary[k].block, base, bs->W, bs->slot);
}

/* 3x3 inverse (row-major, double); 0 when singular. */
static int invert3(const double A[9], double R[9]) {
  const double c0 = A[4] * A[8] - A[5] * A[7], c1 = A[5] * A[6] - A[3] * A[8],
               c2 = A[3] * A[7] - A[4] * A[6];
  const double det = A[0] * c0 + A[1] * c1 + A[2] * c2;
  if (!(det != 0)) return 0;
  const double s = 1 / det;
  R[0] = c0 * s;
  R[1] = (A[2] * A[7] - A[1] * A[8]) * s;
  R[2] = (A[1] * A[5] - A[2] * A[4]) * s;
  R[3] = c1 * s;
  R[4] = (A[0] * A[8] - A[2] * A[6]) * s;
  R[5] = (A[2] * A[3] - A[0] * A[5]) * s;
  R[6] = c2 * s;
  R[7] = (A[1] * A[6] - A[0] * A[7]) * s;
  R[8] = (A[0] * A[4] - A[1] * A[3]) * s;
  return 1;
}

void mpm_adaptive_apic_p2g(mpm_sim *sim) {
  mpm_adaptive *a = sim->adaptive;
  const mpm_adaptive_grid *ag = &a->grid;
  mpm_dofs *dofs = &sim->dofs;
  const mpm_particles *p = &sim->particles;
  boundary_stencil bs;
  for (size_t k = 0; k < a->boundary_count; ++k) {
    boundary_stencil_of(a, sim, k, &bs);
    const size_t i = a->boundary[k].particle;
    const double dx = (double)a->tgrid[a->boundary[k].tgrid].kernel.dx, m = (double)p->mass[i];
    const int W = bs.W;
    double B[9], D[9] = {0}, Dinv[9], C[9];
    for (int c = 0; c < 9; ++c) B[c] = (double)p->B[c][i];
    /* the real-node D_p: the ghost level's plus the ghosts' spreads */
    int n = 0;
    for (int ii = 0; ii < W; ++ii)
      for (int jj = 0; jj < W; ++jj)
        for (int kk = 0; kk < W; ++kk, ++n) {
          const double w = (double)bs.s.w[0][ii] * bs.s.w[1][jj] * bs.s.w[2][kk];
          const double r[3] = {(ii - bs.f[0]) * dx, (jj - bs.f[1]) * dx, (kk - bs.f[2]) * dx};
          for (int u = 0; u < 3; ++u)
            for (int v = 0; v < 3; ++v) D[3 * u + v] += w * r[u] * r[v];
          const int32_t gh = a->ghost_of[bs.slot[n]];
          if (gh < 0) continue;
          const mpm_real *const *S = (const mpm_real *const *)ag->spread;
          const double s6[6] = {S[0][gh], S[1][gh], S[2][gh], S[3][gh], S[4][gh], S[5][gh]};
          const double Sg[9] = {s6[0], s6[3], s6[4], s6[3], s6[1], s6[5], s6[4], s6[5], s6[2]};
          for (int c = 0; c < 9; ++c) D[c] += w * Sg[c];
        }
    if (!invert3(D, Dinv)) continue;
    for (int u = 0; u < 3; ++u)
      for (int v = 0; v < 3; ++v)
        C[3 * u + v] = B[3 * u] * Dinv[v] + B[3 * u + 1] * Dinv[3 + v] + B[3 * u + 2] * Dinv[6 + v];
    /* at every stencil node: the real-node affine momentum minus what the lanes added; at the
     * ghosts the affine moment */
    n = 0;
    for (int ii = 0; ii < W; ++ii)
      for (int jj = 0; jj < W; ++jj)
        for (int kk = 0; kk < W; ++kk, ++n) {
          const double wx = bs.s.w[0][ii], wy = bs.s.w[1][jj], wz = bs.s.w[2][kk];
          const double w = wx * wy * wz;
          const double r[3] = {(ii - bs.f[0]) * dx, (jj - bs.f[1]) * dx, (kk - bs.f[2]) * dx};
          const double lane[3] = {bs.s.a[0][ii] * wy * wz, wx * bs.s.a[1][jj] * wz,
                                  wx * wy * bs.s.a[2][kk]};
          const uint32_t s = bs.slot[n];
          for (int u = 0; u < 3; ++u) {
            double want = 0, had = 0;
            for (int v = 0; v < 3; ++v) {
              want += C[3 * u + v] * r[v];
              had += B[3 * u + v] * lane[v];
            }
            dofs->v0[u][s] += (mpm_real)(m * (w * want - had));
          }
          const int32_t gh = a->ghost_of[s];
          if (gh < 0) continue;
          for (int c = 0; c < 9; ++c)
            a->moment[(size_t)c * ag->ghost_count + (size_t)gh] += (mpm_real)(w * m * C[c]);
        }
  }
}

void mpm_adaptive_apic_scatter(mpm_sim *sim, int impulse) {
  mpm_adaptive *a = sim->adaptive;
  mpm_adaptive_grid *ag = &a->grid;
  mpm_dofs *d = &sim->dofs;
  mpm_real *u[7] = {d->mass, d->v0[0], d->v0[1], d->v0[2], d->f[0], d->f[1], d->f[2]};
  const mpm_real *A[9]; /* the ghosts' affine moments, one plane per component */
  for (int c = 0; c < 9; ++c) A[c] = a->moment + (size_t)c * ag->ghost_count;
  mpm_adaptive_grid_scatter_apic(ag, impulse ? 4 : 7, u, A);
}

void mpm_adaptive_apic_g2p_before(mpm_sim *sim) {
  mpm_adaptive *a = sim->adaptive;
  const mpm_adaptive_grid *ag = &a->grid;
  if (!a->boundary_count) return;
  const size_t n = ag->ghost_count;
  mpm_real *M[9];
  for (int c = 0; c < 9; ++c) M[c] = a->moment + (size_t)c * n; /* P2G's are spent */
  const mpm_real *const v[3] = {sim->dofs.v[0], sim->dofs.v[1], sim->dofs.v[2]};
  mpm_adaptive_grid_gather_moments(ag, v, M);
  boundary_stencil bs;
  for (size_t k = 0; k < a->boundary_count; ++k) {
    boundary_stencil_of(a, sim, k, &bs);
    double dB[9] = {0};
    const int W = bs.W;
    int q = 0;
    for (int ii = 0; ii < W; ++ii)
      for (int jj = 0; jj < W; ++jj)
        for (int kk = 0; kk < W; ++kk, ++q) {
          const int32_t gh = a->ghost_of[bs.slot[q]];
          if (gh < 0) continue;
          const double w = (double)bs.s.w[0][ii] * bs.s.w[1][jj] * bs.s.w[2][kk];
          for (int c = 0; c < 9; ++c) dB[c] += w * (double)M[c][gh];
        }
    for (int c = 0; c < 9; ++c) a->dB[9 * k + (size_t)c] = (mpm_real)dB[c];
  }
}

void mpm_adaptive_apic_g2p_after(mpm_sim *sim) {
  mpm_adaptive *a = sim->adaptive;
  mpm_particles *p = &sim->particles;
  for (size_t k = 0; k < a->boundary_count; ++k) {
    const size_t i = a->boundary[k].particle;
    for (int c = 0; c < 9; ++c) p->B[c][i] += a->dB[9 * k + (size_t)c];
  }
}
