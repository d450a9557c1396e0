/* enrich_contact.c - enriched corners meet other material on the grid (see enrich_contact.h). */
#include "domain/enrich_contact.h"
#include "core/intmath.h"
#include "core/parallel.h"
#include "core/tile_batches.h"
#include "domain/enrich.h"
#include "grid/embedding.h"

#include <math.h>
#include <string.h>

int mpm_enrich_contact_on(const mpm_domain_set *s) {
  const mpm_domain_enrichment *e = &s->enrich;
  if (!e->count) return 0;
  for (int b = 0; b < e->body_count; ++b)
    if (e->body[b].contact) return 1;
  return 0;
}

/* The contact of enriched corner j (its corner c, DOF own) with the grid (enrich_contact.h); 1
 * when it took an impulse. corner_mass: the body's own corners' mass on each DOF. */
static int contact_corner(const mpm_domain_set *s, const mpm_grid *g, const mpm_kernel *k,
                          const mpm_grid_values *dofs, const mpm_real *corner_mass, uint32_t c,
                          size_t own, mpm_grid_cursor *cursor) {
  const double mc = (double)dofs->mass[own];
  const mpm_real xr[3] = {s->cx[0][c] - g->origin[0], s->cx[1][c] - g->origin[1],
                          s->cx[2][c] - g->origin[2]};
  mpm_stencil st;
  mpm_kernel_stencil(k, xr, &st);
  const int W = k->width;
  const uint32_t dof_begin = (uint32_t)g->dof_begin;
  uint32_t nodes[MPM_STENCIL_MAX * MPM_STENCIL_MAX * MPM_STENCIL_MAX];
  int32_t key;
  uint8_t colour;
  if (g->ops->stencil_nodes(g, st.base, W, cursor, nodes, &key, &colour)) return 0;
  /* other material's mass about the corner, its gradient, and the grid's mass and momentum
   * there */
  double mo = 0, grad[3] = {0, 0, 0}, M = 0, P[3] = {0, 0, 0};
  double w[MPM_STENCIL_MAX * MPM_STENCIL_MAX * MPM_STENCIL_MAX];
  int n = 0;
  for (int a = 0; a < W; ++a)
    for (int bb = 0; bb < W; ++bb)
      for (int l = 0; l < W; ++l, ++n) {
        const uint32_t i = dof_begin + nodes[n];
        const double wi = (double)st.w[0][a] * st.w[1][bb] * st.w[2][l];
        const double gi[3] = {(double)st.dw[0][a] * st.w[1][bb] * st.w[2][l],
                              (double)st.w[0][a] * st.dw[1][bb] * st.w[2][l],
                              (double)st.w[0][a] * st.w[1][bb] * st.dw[2][l]};
        w[n] = wi;
        const double m = (double)dofs->mass[i];
        /* what other material gave (rounding leaves a trace where it gave none) */
        double m_o = m - (double)corner_mass[i];
        if (!(m_o > 1e-4 * m)) m_o = 0;
        mo += wi * m_o;
        M += wi * m;
        for (int d = 0; d < 3; ++d) {
          grad[d] += gi[d] * m_o;
          P[d] += wi * m * (double)dofs->v[d][i];
        }
      }
  const double gn = sqrt(grad[0] * grad[0] + grad[1] * grad[1] + grad[2] * grad[2]);
  if (!(mo > 0) || !(M > 0) || !(gn > 0)) return 0;
  double vn = 0;
  for (int d = 0; d < 3; ++d) vn += ((double)dofs->v[d][own] - P[d] / M) * (grad[d] / gn);
  if (!(vn > 0)) return 0; /* separating, or sliding */
  const double jn = mc * M / (mc + M) * vn;
  for (int d = 0; d < 3; ++d) {
    const double nd = grad[d] / gn;
    dofs->v[d][own] = (mpm_real)((double)dofs->v[d][own] - jn / mc * nd);
    for (int q = 0; q < n; ++q) {
      const uint32_t i = dof_begin + nodes[q];
      if (w[q] == 0 || !(dofs->mass[i] > 0)) continue;
      dofs->v[d][i] = (mpm_real)((double)dofs->v[d][i] + jn * w[q] / M * nd);
    }
  }
  return 1;
}

/* The contacts of body b's enriched corners (body: each corner's body; own_mass, corner_mass:
 * scratch of nc and count values). */
static mpm_status contact_body(const mpm_domain_set *s, const mpm_grid *g, const mpm_kernel *k,
                               const mpm_grid_values *dofs, size_t count, int b,
                               const int32_t *body, mpm_real *own_mass, mpm_real *corner_mass,
                               mpm_arena *scratch, size_t *contacts) {
  const mpm_domain_enrichment *e = &s->enrich;
  /* the body's own corners' mass on the grid, through the embedding's rows (P2G's sums again,
   * in the same order): the rest of the nodes' mass is other material's */
  for (size_t c = 0; c < s->corner_count; ++c) own_mass[c] = body[c] == b ? s->cm[c] : 0;
  memset(corner_mass, 0, (count + 1) * sizeof *corner_mass);
  const mpm_real *carrier[1] = {own_mass};
  mpm_real *const values[1] = {corner_mass};
  mpm_embedding_scatter(&s->corner_grid, 1, carrier, values);
  /* the body's corners with mass, tiled by their stencils' base cells: a corner touches the
     nodes base .. base + W - 1, so tiles of W cells keep one colour's tiles' stencils apart
     (core/tile_batches.h) */
  uint32_t *which = mpm_arena_alloc(scratch, (e->count + 1) * sizeof *which);
  int32_t(*tile)[3] = mpm_arena_alloc(scratch, (e->count + 1) * sizeof *tile);
  uint8_t *took = mpm_arena_alloc(scratch, e->count + 1);
  if (!which || !tile || !took) return MPM_ERR_NOMEM;
  size_t n = 0;
  for (size_t j = 0; j < e->count; ++j)
    if (body[e->corner[j]] == b && dofs->mass[e->dof_begin + j] > 0) which[n++] = (uint32_t)j;
  const long nl = (long)n;
#pragma omp parallel for schedule(static) if (nl > MPM_PARALLEL_MIN)
  for (long i = 0; i < nl; ++i) {
    const uint32_t c = e->corner[which[i]];
    const mpm_real xr[3] = {s->cx[0][c] - g->origin[0], s->cx[1][c] - g->origin[1],
                            s->cx[2][c] - g->origin[2]};
    mpm_stencil st;
    mpm_kernel_stencil(k, xr, &st);
    for (int d = 0; d < 3; ++d) tile[i][d] = (int32_t)mpm_floor_div(st.base[d], k->width);
    took[i] = 0;
  }
  mpm_tile_batches batch;
  if (mpm_tile_batches_build(n, (const int32_t(*)[3])tile, scratch, &batch)) return MPM_ERR_NOMEM;
  for (int colour = 0; colour < MPM_TILE_COLOURS; ++colour) {
    const long t0 = (long)batch.colour_start[colour], t1 = (long)batch.colour_start[colour + 1];
#pragma omp parallel if (t1 - t0 > 1)
    {
      mpm_grid_cursor cursor;
      mpm_grid_cursor_init(&cursor);
#pragma omp for schedule(dynamic, 4)
      for (long t = t0; t < t1; ++t)
        for (size_t i = batch.tile_start[t]; i < batch.tile_start[t + 1]; ++i) {
          const uint32_t j = which[batch.item[i]];
          took[batch.item[i]] = (uint8_t)contact_corner(s, g, k, dofs, corner_mass, e->corner[j],
                                                        e->dof_begin + j, &cursor);
        }
    }
  }
  for (size_t i = 0; i < n; ++i) *contacts += took[i];
  return MPM_OK;
}

mpm_status mpm_enrich_contact(const mpm_domain_set *s, const mpm_grid *g, const mpm_kernel *k,
                              const mpm_grid_values *dofs, size_t count, mpm_arena *scratch,
                              size_t *contacts) {
  *contacts = 0;
  const mpm_domain_enrichment *e = &s->enrich;
  if (!mpm_enrich_contact_on(s) || !s->corner_grid.rows) return MPM_OK;
  const size_t nc = s->corner_count;
  mpm_real *corner_mass = mpm_arena_alloc(scratch, (count + 1) * sizeof *corner_mass);
  mpm_real *own_mass = mpm_arena_alloc(scratch, (nc + 1) * sizeof *own_mass);
  int32_t *body = mpm_arena_alloc(scratch, (nc + 1) * sizeof *body);
  if (!corner_mass || !own_mass || !body) return MPM_ERR_NOMEM;
  for (size_t c = 0; c < nc; ++c) body[c] = mpm_domain_corner_body(s, c);
  for (int b = 0; b < e->body_count; ++b)
    if (e->body[b].contact) {
      const mpm_status st =
          contact_body(s, g, k, dofs, count, b, body, own_mass, corner_mass, scratch, contacts);
      if (st) return st;
    }
  return MPM_OK;
}
