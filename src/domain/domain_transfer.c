/* domain_transfer.c - two-step particle -> corner -> grid transfers and back (see
 * domain_transfer.h). */
#include "domain/domain_transfer.h"
#include "core/alloc.h"
#include "core/mat3.h"
#include "domain/corner_motion.h"
#include "domain/corner_pads.h"
#include "domain/enrich.h"

#include <math.h>
#include <string.h>

/* Four reals (an SSE register in float, AVX in double) and four doubles: the corner loops below
 * keep a corner's or a particle's three components in the first three lanes (the fourth is 0),
 * so that one vector operation does the work of three scalar ones with the same roundings. */
typedef mpm_real real4 __attribute__((vector_size(4 * sizeof(mpm_real))));
typedef double double4 __attribute__((vector_size(4 * sizeof(double))));

static inline real4 load4(const mpm_real *a) {
  real4 v;
  memcpy(&v, a, sizeof v);
  return v;
}

/* What a particle gives its corners' forces, 9 reals (mpm_domain_p2g): the force on corner a is
 * -V0 P g_a (Zhu eq. 8 with eq. 5), per component (V0 P)_d0 g_0 + (V0 P)_d1 g_1 + (V0 P)_d2 g_2
 * in that order. For a cube's pattern (mpm_domain_gradient: g_at = s_at m, s = +-1) the
 * products are +-r_t, r_t the column t of V0 P times m, which is what is kept (the signs are
 * exact); otherwise the columns of V0 P. Column t at [3t, 3t + 3), read as 4 lanes, the fourth
 * the next one's first (or the row after the last, which P2G zeroes), which no sum uses: 36
 * bytes a particle, written once and read by 8 corners (their traffic sets the cost). */
#define VP_STRIDE 9
static inline void store_vp(mpm_real *vp, const mpm_real v0, const mpm_real P[9],
                            const mpm_real m) {
  for (int t = 0; t < 3; ++t)
    for (int d = 0; d < 3; ++d) {
      const mpm_real col = v0 * P[3 * d + t];
      vp[3 * t + d] = m == 0 ? col : col * m;
    }
}

/* The cube's signs s_at of corner a (mpm_hex_sign: +1 where bit t of a is set) as sign-bit
 * masks, 0 where s_at = +1: the corners' force sums flip sign bits instead of branching on
 * the corner, exactly (-r is r with its sign bit flipped). */
#ifdef MPM_USE_DOUBLE
typedef int64_t mask4 __attribute__((vector_size(4 * sizeof(int64_t))));
#define SIGN INT64_MIN
#else
typedef int32_t mask4 __attribute__((vector_size(4 * sizeof(int32_t))));
#define SIGN INT32_MIN
#endif
#define SIGN_OF(a, t) (((a) >> (t)) & 1 ? 0 : SIGN)
#define CORNER_SIGN(a, t)                                                                          \
  { SIGN_OF(a, t), SIGN_OF(a, t), SIGN_OF(a, t), SIGN_OF(a, t) }
#define CORNER_SIGNS(a)                                                                            \
  { CORNER_SIGN(a, 0), CORNER_SIGN(a, 1), CORNER_SIGN(a, 2) }
static const mask4 corner_sign[MPM_HEX_CORNERS][3] = {
    CORNER_SIGNS(0), CORNER_SIGNS(1), CORNER_SIGNS(2), CORNER_SIGNS(3),
    CORNER_SIGNS(4), CORNER_SIGNS(5), CORNER_SIGNS(6), CORNER_SIGNS(7)};
static inline real4 flip_sign(real4 r, mask4 sign) {
  return (real4)((mask4)r ^ sign);
}

/* P2G's corner loop fetches the particles of the corner this many on, and G2P's particle loop
 * the corners of the particle this many on (measured at 1M particles: 8, 16 and 32 alike; a
 * twentieth off the one, a fifth off the other) */
#define PREFETCH_AHEAD 16

mpm_status mpm_domain_activate(mpm_domain_set *s, mpm_grid *g, const mpm_kernel *k) {
  const mpm_real *const x[3] = {s->cx[0], s->cx[1], s->cx[2]};
  /* enriched corners (domain/enrich.h) do not touch the grid */
  const uint8_t *use = s->enrich.count ? s->enrich.on_grid : s->corner_use;
  return g->ops->activate_points(g, k, s->corner_count, x, use);
}

/* The embedding of the corners in the grid level (Zhu eqs. 2-3): row c holds the nodes of
 * corner c's stencil with their nonzero weights omega_i(x_c), as DOF indices (the level's
 * dof_begin + its node index); rows of unused corners stay empty. Its scatter schedule groups
 * the used corners by the grid's scatter key of their stencils and colours the keys as the grid
 * says (grid.h, stencil_nodes: for the sparse grid the base block and its parity, as the
 * standard P2G colours blocks), so that the groups of one colour never touch the same node.
 * MPM_OK; MPM_ERR_NOMEM when out of memory; MPM_ERR_INVALID when a node of a stencil is not
 * active. */
static mpm_status build_corner_embedding(const mpm_kernel *k, mpm_domain_set *s, const mpm_grid *g,
                                         int apic, mpm_arena *scratch) {
  const size_t nc = s->corner_count, nk = g->ops->scatter_key_count(g);
  const int W = k->width;
  mpm_embedding *E = &s->corner_grid;
  const mpm_status laid = mpm_embedding_layout(E, nc, NULL, (uint32_t)(W * W * W));
  if (laid != MPM_OK) return laid;
  /* APIC: the factors of every entry and D of every corner (step scratch) */
  for (int d = 0; d < 3; ++d) {
    s->apic_a[d] =
        apic ? mpm_arena_alloc(scratch, (E->entry_capacity + 1) * sizeof(mpm_real)) : NULL;
    s->apic_d[d] = apic ? mpm_arena_alloc(scratch, (nc + 1) * sizeof(mpm_real)) : NULL;
    if (apic && (!s->apic_a[d] || !s->apic_d[d])) return MPM_ERR_NOMEM;
  }
  int32_t *key = mpm_arena_alloc(scratch, (nc + 1) * sizeof *key);
  uint8_t *colour = mpm_arena_alloc(scratch, nc + 1),
          *key_colour = mpm_arena_alloc(scratch, nk + 1);
  if (!key || !colour || !key_colour) return MPM_ERR_NOMEM;
  const uint32_t dof_begin = (uint32_t)g->dof_begin;
  const mpm_domain_enrichment *en = &s->enrich;
  const int enriched = en->count > 0;
  const uint32_t corner_dofs = (uint32_t)en->dof_begin;
  int missing = 0; /* a node not activated: cannot happen after mpm_domain_activate */
#pragma omp parallel reduction(| : missing)
  {
    mpm_grid_cursor cursor;
    mpm_grid_cursor_init(&cursor);
#pragma omp for schedule(static)
    for (long c = 0; c < (long)nc; ++c) {
      key[c] = -1;
      if (!s->corner_use[c]) continue;
      if (enriched && en->enriched[c]) { /* its own DOF: an identity row (Zhu sec. 5.2) */
        if (apic)                        /* no offset to its node: no affine part, and B_a = 0 */
          for (int d = 0; d < 3; ++d) s->apic_a[d][E->row_start[c]] = s->apic_d[d][c] = 0;
        mpm_embedding_push(E, (size_t)c, corner_dofs + en->slot[c], 1);
        key[c] = MPM_EMBEDDING_OWN_COLUMNS;
        continue;
      }
      const mpm_real xr[3] = {s->cx[0][c] - g->origin[0], s->cx[1][c] - g->origin[1],
                              s->cx[2][c] - g->origin[2]};
      mpm_stencil st;
      mpm_kernel_stencil(k, xr, &st);
      uint32_t nodes[MPM_STENCIL_MAX * MPM_STENCIL_MAX * MPM_STENCIL_MAX];
      if (g->ops->stencil_nodes(g, st.base, W, &cursor, nodes, &key[c], &colour[c])) {
        missing = 1;
        key[c] = -1;
        continue;
      }
      if (apic) /* D's diagonal: sum_i w_i (x_i - x_a)^2 per axis (interp/kernel.h) */
        for (int d = 0; d < 3; ++d) {
          mpm_real D = 0;
          for (int i = 0; i < W; ++i) {
            const mpm_real r = (mpm_real)(st.base[d] + i) * k->dx - xr[d];
            D += st.w[d][i] * r * r;
          }
          s->apic_d[d][c] = D;
        }
      int e = 0;
      for (int i = 0; i < W; ++i)
        for (int j = 0; j < W; ++j)
          for (int l = 0; l < W; ++l, ++e) {
            const mpm_real w = st.w[0][i] * st.w[1][j] * st.w[2][l];
            if (w == 0) continue;
            if (apic) {
              const uint32_t at = E->row_start[c] + E->row_len[c];
              s->apic_a[0][at] = st.a[0][i] * st.w[1][j] * st.w[2][l];
              s->apic_a[1][at] = st.w[0][i] * st.a[1][j] * st.w[2][l];
              s->apic_a[2][at] = st.w[0][i] * st.w[1][j] * st.a[2][l];
            }
            mpm_embedding_push(E, (size_t)c, dof_begin + nodes[e], w);
          }
    }
  }
  if (missing) return MPM_ERR_INVALID;
  for (size_t c = 0; c < nc; ++c) /* every corner of one key has the key's colour */
    if (key[c] >= 0) key_colour[key[c]] = colour[c];
  return mpm_embedding_schedule(E, key, nk, key_colour);
}

/* V0 P of particles [a, b) (< MPM_STRESS_CHUNK, all of material mat) one by one, with the
 * moduli of each particle's state where they vary. */
static void stresses_one_by_one(const mpm_material *mat, const mpm_domain_set *s, long a, long b,
                                mpm_real (*vP)[VP_STRIDE]) {
  const mpm_particles *p = &s->particles;
  for (long q = a; q < b; ++q) {
    if (!s->active[q]) continue;
    mpm_real F[9], P[9];
    for (int e = 0; e < 9; ++e) F[e] = p->F[e][q];
    if (mpm_material_varies(mat)) {
      const mpm_material at = mpm_material_at_temperature(mat, p->plastic[q], p->temperature[q]);
      at.model->pk1(&at, F, P);
    } else {
      mat->model->pk1(mat, F, P);
    }
    store_vp(vP[q], p->vol0[q], P, s->cube_g[q]);
  }
}

/* V0 P of every active domain particle, once (each is gathered by its 8 corners): in chunks of
 * consecutive particles of one material through the model's pk1_batch (its SIMD SVD: 23 against
 * 402 ns a particle for fixed corotated, `mpm bench stress`), one by one where the moduli vary
 * per particle or the model has no batch entry. */
static void domain_stresses(const mpm_transfer_ctx *ctx, const mpm_domain_set *s,
                            mpm_real (*vP)[VP_STRIDE]) {
  const mpm_particles *p = &s->particles;
  const long np = (long)p->count;
#pragma omp parallel for schedule(dynamic, 4)
  for (long c0 = 0; c0 < np; c0 += MPM_STRESS_CHUNK) {
    const long c1 = c0 + MPM_STRESS_CHUNK < np ? c0 + MPM_STRESS_CHUNK : np;
    for (long a = c0, b; a < c1; a = b) {
      const int32_t m = p->material[a];
      for (b = a + 1; b < c1 && p->material[b] == m;) ++b;
      const mpm_material *mat = &ctx->materials[m];
      if (!mat->model->pk1_batch || mpm_material_varies(mat)) {
        stresses_one_by_one(mat, s, a, b, vP);
        continue;
      }
      const mpm_real *F[9];
      for (int e = 0; e < 9; ++e) F[e] = p->F[e] + a;
      mpm_real P[9][MPM_STRESS_CHUNK];
      mat->model->pk1_batch(mat, (int)(b - a), F, P);
      for (long q = a; q < b; ++q) { /* inactive particles' P is not used */
        mpm_real Pq[9];
        for (int e = 0; e < 9; ++e) Pq[e] = P[e][q - a];
        store_vp(vP[q], p->vol0[q], Pq, s->cube_g[q]);
      }
    }
  }
}

mpm_status mpm_domain_plan(mpm_domain_set *s, const mpm_grid *g, const mpm_kernel *k,
                           mpm_arena *scratch) {
  s->pads.on = 0;
  if (!mpm_grid_paged(g) || s->corner_rows) return MPM_OK;
  for (int d = 0; d < 3; ++d) s->apic_a[d] = s->apic_d[d] = NULL;
  s->corner_grid.rows = 0; /* not this step's */
  s->corner_grid.schedule.built = 0;
  return mpm_corner_pads_plan(&s->pads, s, g, k, scratch);
}

mpm_status mpm_domain_order_corners(mpm_domain_set *s, const mpm_grid *g, const mpm_kernel *k,
                                    mpm_arena *scratch, uint32_t **order) {
  *order = NULL;
  const mpm_corner_pads *P = &s->pads;
  /* the pads read and write the corners' values in the order of their positions, lane by lane
   * where the corner numbers of a batch are not consecutive: renumbered once a tenth of the
   * positions break the run (the material points' rule, sim/step.c), so that batches move
   * with vector loads and stores */
  if (!P->on || (double)P->breaks <= 0.1 * (double)P->grid_positions) return MPM_OK;
  const size_t nc = s->corner_count;
  uint32_t *o = mpm_arena_alloc(scratch, (nc + 1) * sizeof *o);
  if (!o) return MPM_ERR_NOMEM;
  memcpy(o, P->row, P->positions * sizeof *o); /* the used corners, then the others */
  size_t next = P->positions;
  for (size_t c = 0; c < nc; ++c)
    if (P->pos[c] == MPM_CORNER_PADS_NONE) o[next++] = (uint32_t)c;
  if (mpm_domain_set_permute_corners(s, o, scratch)) return MPM_ERR_NOMEM;
  *order = o;
  return mpm_domain_plan(s, g, k, scratch);
}

mpm_status mpm_domain_p2g(const mpm_transfer_ctx *ctx, mpm_domain_set *s, const mpm_grid *g,
                          const mpm_grid_values *dof, mpm_arena *scratch) {
  const mpm_particles *p = &s->particles;
  const long nc = (long)s->corner_count, np = (long)p->count;
  /* 0. V0 P of every active particle (domain_stresses), by columns */
  mpm_real(*vP)[VP_STRIDE] = mpm_arena_alloc(scratch, (p->count + 1) * sizeof *vP);
  if (!vP) return MPM_ERR_NOMEM;
  memset(vP[p->count], 0, sizeof *vP); /* the last particle's fourth lane (store_vp) */
  /* hourglass control of particles touching enriched corners, or of every particle of a body
   * with hourglass "all" (domain/enrich.h): kappa q */
  const int hourglass = mpm_hourglass_on(s);
  mpm_real(*Q)[4][3] = hourglass ? mpm_arena_alloc(scratch, (p->count + 1) * sizeof *Q) : NULL;
  if (hourglass && !Q) return MPM_ERR_NOMEM;
  const int apic = ctx->transfer == MPM_TRANSFER_APIC;
  if (hourglass) {
#pragma omp parallel for schedule(static)
    for (long q = 0; q < np; ++q) { /* kappa 0: no control */
      const mpm_real kappa = mpm_hourglass_kappa(s, ctx->materials, (size_t)q);
      if (kappa > 0) {
        mpm_hourglass_q(s, (size_t)q, s->cx, Q[q]);
        for (int al = 0; al < 4; ++al)
          for (int d = 0; d < 3; ++d) Q[q][al][d] *= kappa;
      } else {
        memset(Q[q], 0, sizeof Q[q]);
      }
    }
  }
  domain_stresses(ctx, s, vP);
  /* the corner -> grid step's plan (mpm_domain_plan): through pads, the corners' values are
   * laid out in the pads' order; the DOFs are those of this step's layout, which follows the
   * plan */
  const int pads = s->pads.on;
  if (pads) {
    s->pads.grid_dofs = (uint32_t)g->dof_begin;
    s->pads.corner_dofs = (uint32_t)s->enrich.dof_begin;
  }
  /* 1. particle -> corner, gathered per corner (each corner sums its <= 8 particle slots in
   *    slot order: no races, the same sums for any thread count), in corner order (the
   *    particles' values are read in their order); with pads, corner c's values are written
   *    at its position s->pads.pos[c] */
  const uint32_t *pos = pads ? s->pads.pos : NULL;
  /* G2P's packed copy of the corners (step scratch) */
  s->corner_pack = mpm_arena_alloc(scratch, (s->corner_count + 1) * sizeof *s->corner_pack);
  if (!s->corner_pack) return MPM_ERR_NOMEM;
  memset(s->corner_pack[s->corner_count], 0, sizeof *s->corner_pack); /* the last one's lane 4 */
  mpm_real *mB[9] = {NULL}; /* APIC on the rows: m_a B_a (the pads make it themselves) */
  for (int e = 0; e < 9 && apic && !pads; ++e) {
    mB[e] = mpm_arena_alloc(scratch, (s->corner_count + 1) * sizeof(mpm_real));
    if (!mB[e]) return MPM_ERR_NOMEM;
  }
#pragma omp parallel for schedule(static)
  for (long c = 0; c < nc; ++c) {
    /* the particles are read in the corners' order (block order), not theirs: the V0 P rows
     * of the first and last particle of the corner PREFETCH_AHEAD on are fetched now (of the
     * 8, measured: every one's costs more than it saves) */
    if (c + PREFETCH_AHEAD < nc) {
      const uint32_t j0 = s->adj_start[c + PREFETCH_AHEAD];
      const uint32_t j1 = s->adj_start[c + PREFETCH_AHEAD + 1];
      if (j1 > j0) {
        __builtin_prefetch(vP[s->adj[j0] / MPM_HEX_CORNERS], 0);
        __builtin_prefetch(vP[s->adj[j1 - 1] / MPM_HEX_CORNERS], 0);
        __builtin_prefetch(vP[s->adj[j1 - 1] / MPM_HEX_CORNERS] + VP_STRIDE - 1, 0);
      }
    }
    const uint32_t k = pos ? pos[c] : (uint32_t)c;
    if (k == MPM_CORNER_PADS_NONE) continue; /* unused */
    const double m = s->cmass[c];            /* sum_p omega_ap m_p, made with the adjacency */
    double mv[3] = {0, 0, 0};
    double4 f = {0, 0, 0, 0};
    for (uint32_t j = s->adj_start[c]; j < s->adj_start[c + 1]; ++j) {
      const uint32_t q = s->adj[j] / MPM_HEX_CORNERS, a = s->adj[j] % MPM_HEX_CORNERS;
      const mpm_real *vPq = vP[q];
      const int cube = s->cube_g[q] != 0;
      if (!apic) {
        const double w = cube ? 0.125 : s->w[q][a], mq = p->mass[q];
        for (int d = 0; d < 3; ++d) mv[d] += w * mq * p->v[d][q];
      }
      /* f_a = -V0 P g_ap (store_vp: the cube's sums by corner, or the columns) */
      real4 term;
      if (cube) { /* (s_0 r_0 + s_1 r_1) + s_2 r_2, the signs by flipping sign bits */
        const real4 r0 = load4(vPq), r1 = load4(vPq + 3), r2 = load4(vPq + 6);
        term = (flip_sign(r0, corner_sign[a][0]) + flip_sign(r1, corner_sign[a][1])) +
               flip_sign(r2, corner_sign[a][2]);
      } else {
        const mpm_real *gq = s->g[q][a];
        term = load4(vPq) * gq[0] + load4(vPq + 3) * gq[1] + load4(vPq + 6) * gq[2];
      }
      f -= __builtin_convertvector(term, double4);
      if (hourglass) /* f_a -= kappa sum_alpha h_alpha,a q_alpha */
        for (int al = 0; al < 4; ++al)
          for (int d = 0; d < 3; ++d) f[d] -= mpm_hourglass_modes[al][a] * Q[q][al][d];
    }
    /* APIC: the corner carries its own velocity (and its affine moment to the grid below); its
     * particles' velocities are its interpolants (v_p = sum_a omega_ap v_a), so the momentum is
     * the same, sum_a m_a v_a = sum_p m_p v_p, and nothing is averaged away */
    if (apic)
      for (int d = 0; d < 3; ++d) mv[d] = m * s->cv[d][c];
    s->cm[k] = (mpm_real)m;
    for (int d = 0; d < 3; ++d) {
      s->cp[d][k] = (mpm_real)mv[d];
      s->cf[d][k] = (mpm_real)f[d];
    }
  }
  /* APIC on the rows: m_a B_a (apart from the loop above, whose scattered writes would double:
   * measured) */
  if (apic && !pads) {
#pragma omp parallel for schedule(static)
    for (long c = 0; c < nc; ++c)
      if (s->corner_use[c])
        for (int e = 0; e < 9; ++e) mB[e][c] = s->cm[c] * s->cB[e][c];
  }
  /* 2. corner -> grid: the transpose of the corners' embedding (grid/embedding.h), scheduled
   *    so that a node receives the colours in a fixed order and each group's corners in corner
   *    order: the same sums for any number of threads (through the pads: the same terms) */
  if (!pads) {
    const mpm_status built = build_corner_embedding(&ctx->kernel, s, g, apic, scratch);
    if (built != MPM_OK) return built;
  }
  const mpm_real *carrier[7] = {s->cm, s->cp[0], s->cp[1], s->cp[2], s->cf[0], s->cf[1], s->cf[2]};
  mpm_real *const values[7] = {dof->mass, dof->v0[0], dof->v0[1], dof->v0[2],
                               dof->f[0], dof->f[1],  dof->f[2]};
  /* APIC at the corner -> grid step: the corner's affine moment m_a B_a (B_a from the last
   * G2P) spread with the entries' APIC factors */
  if (pads)
    return mpm_corner_pads_scatter(&s->pads, s, &ctx->kernel, carrier, apic, values, scratch);
  if (!apic) {
    mpm_embedding_scatter(&s->corner_grid, 7, carrier, values);
    return MPM_OK;
  }
  const mpm_real *const a[3] = {s->apic_a[0], s->apic_a[1], s->apic_a[2]};
  const mpm_real *const cm[9] = {mB[0], mB[1], mB[2], mB[3], mB[4], mB[5], mB[6], mB[7], mB[8]};
  mpm_real *const um[3] = {dof->v0[0], dof->v0[1], dof->v0[2]};
  mpm_embedding_scatter_moments(&s->corner_grid, 7, carrier, values, a, cm, um);
  return MPM_OK;
}

void mpm_domain_update_F(mpm_domain_set *s, size_t q, mpm_real dt, const mpm_real *const vg[3]) {
  /* grad_X v = sum_i v_i grad_X omega_ip^T = sum_a v^g_a g_ap^T (mpm_domain_g2p has the same
   * sums in its loop over the particles) */
  mpm_real gradv[9] = {0};
  for (int a = 0; a < MPM_HEX_CORNERS; ++a) {
    const uint32_t c = s->corner[q][a];
    const mpm_real *ga = s->g[q][a];
    for (int r = 0; r < 3; ++r)
      for (int t = 0; t < 3; ++t) gradv[3 * r + t] += vg[r][c] * ga[t];
  }
  for (int e = 0; e < 9; ++e) s->particles.F[e][q] += dt * gradv[e];
}

/* v^g_a, the FLIP increment and (apic) B_a of corner c through the embedding's rows. */
static void corner_velocity(mpm_domain_set *s, const mpm_grid_values *dof, int apic, size_t c,
                            mpm_real vnew[3], mpm_real dv[3]) {
  const mpm_embedding *E = &s->corner_grid;
  const uint32_t e0 = E->row_start[c], e1 = e0 + E->row_len[c];
  for (uint32_t e = e0; e < e1; ++e) {
    const uint32_t n = E->col[e];
    const mpm_real w = E->w[e];
    for (int d = 0; d < 3; ++d) {
      const mpm_real vn = dof->v[d][n];
      const mpm_real vo = dof->v0[d][n];
      vnew[d] += w * vn;
      dv[d] += w * (vn - vo);
    }
  }
  if (apic) { /* B_a = sum_i w_i v_i (x_i - x_a)^T = (sum_i v_i a_i^T) D_a */
    mpm_real S[9] = {0};
    for (uint32_t e = e0; e < e1; ++e) {
      const uint32_t n = E->col[e];
      const mpm_real a[3] = {s->apic_a[0][e], s->apic_a[1][e], s->apic_a[2][e]};
      for (int r = 0; r < 3; ++r)
        for (int t = 0; t < 3; ++t) S[3 * r + t] += dof->v[r][n] * a[t];
    }
    for (int r = 0; r < 3; ++r)
      for (int t = 0; t < 3; ++t) s->cB[3 * r + t][c] = S[3 * r + t] * s->apic_d[t][c];
  }
}

mpm_g2p_result mpm_domain_g2p(const mpm_transfer_ctx *ctx, mpm_domain_set *s,
                              const mpm_grid_values *dof, const mpm_boundary *boundary) {
  const long nc = (long)s->corner_count;
  const mpm_corner_pads *P = &s->pads;
  const int apic = ctx->transfer == MPM_TRANSFER_APIC && (P->on || s->apic_a[0]);
  /* APIC: the corner takes the grid's velocity (PIC) and its affine moment; otherwise the
   * scene's PIC/FLIP blend */
  const mpm_real dt = ctx->dt, alpha = ctx->flip_alpha;
  /* 1. grid -> corner: the grid velocity (PIC) and the hybrid PIC/FLIP corner velocity, and
   *    the corners moved (domain/corner_motion.h) */
  const mpm_corner_motion motion = {boundary, dt, alpha, apic, ctx->clamp_lo, ctx->clamp_hi};
  mpm_real max_v2 = 0; /* corners move at their grid velocity: it bounds the next dt too */
  if (P->on) {         /* the same sums from the corners' positions (domain/corner_pads.h) */
    const mpm_real *const v[3] = {dof->v[0], dof->v[1], dof->v[2]};
    const mpm_real *const v0[3] = {dof->v0[0], dof->v0[1], dof->v0[2]};
    max_v2 = mpm_corner_pads_gather(P, s, &ctx->kernel, v, v0, &motion);
  } else {
#pragma omp parallel for schedule(static) reduction(max : max_v2)
    for (long c = 0; c < nc; ++c) {
      if (!s->corner_use[c]) continue;
      /* the embedding applied to the grid's velocities: v^g_a = sum_i E_ai v_i^{n+1}, and the
       * FLIP increment sum_i E_ai (v_i^{n+1} - v_i^n) */
      mpm_real vnew[3] = {0, 0, 0}, dv[3] = {0, 0, 0};
      corner_velocity(s, dof, apic, (size_t)c, vnew, dv);
      const mpm_real vg2 = mpm_corner_move(s, &motion, (size_t)c, vnew, dv);
      if (vg2 > max_v2) max_v2 = vg2;
    }
  }
  /* 2. particles: F from the grid velocities at the corners (Zhu eq. 7), the return map of
   *    plastic models, then position and velocity from the corners */
  mpm_particles *p = &s->particles;
  const long n = (long)p->count;
  long bad = -1;
#pragma omp parallel for schedule(static) reduction(max : max_v2)
  for (long q = 0; q < n; ++q) {
    /* the corners' packed rows are read in the particles' order, not theirs (block order):
     * the new corners (+x side) of a particle PREFETCH_AHEAD on are fetched now */
    if (q + PREFETCH_AHEAD < n) {
      const uint32_t *ahead = s->corner[q + PREFETCH_AHEAD];
      for (int a = 1; a < MPM_HEX_CORNERS; a += 2) {
        __builtin_prefetch(s->corner_pack[ahead[a]], 0); /* 36 bytes: one or two lines */
        __builtin_prefetch(s->corner_pack[ahead[a]] + 8, 0);
      }
    }
    if (!s->active[q]) continue;
    /* one pass over the 8 corners for grad_X v (F, Zhu eq. 7) and for x and v (the corners
     * have moved already: they do not depend on F) */
    /* G[t]'s lane r: (grad_X v)_rt; the lanes of x and v their components (the same sums, in
     * the same order, as one scalar per component) */
    real4 G[3] = {{0}, {0}, {0}}, X = {0}, V = {0};
    for (int a = 0; a < MPM_HEX_CORNERS; ++a) {
      const mpm_real *pk = s->corner_pack[s->corner[q][a]]; /* x, v, v^g */
      mpm_real gc[3];
      const mpm_real *ga = mpm_domain_gradient(s, q, a, gc);
      const mpm_real w = ga == gc ? (mpm_real)0.125 : s->w[q][a];
      const real4 vg = load4(pk + 6); /* lane 3: the next corner's (unused) */
      for (int t = 0; t < 3; ++t) G[t] += vg * ga[t];
      X += w * load4(pk);
      V += w * load4(pk + 3);
    }
    const mpm_real x[3] = {X[0], X[1], X[2]}, v[3] = {V[0], V[1], V[2]};
    mpm_real *F[9];
    for (int e = 0; e < 9; ++e) {
      F[e] = p->F[e] + q;
      *F[e] += dt * G[e % 3][e / 3];
    }
    const mpm_material *mat = &ctx->materials[p->material[q]];
    if (mat->model->return_map) mat->model->return_map(mat, 1, F, p->plastic + q);
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
