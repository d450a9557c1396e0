/* g2p.c - grid-to-particle transfer (Gao sec. 3.2 steps 5-6) on the sparse and dense grids.
 *
 * Each particle reads the new (and, for FLIP, old) grid velocity of its stencil and updates
 * v_p (APIC, or alpha FLIP + (1 - alpha) PIC), APIC's B_p, F_p <- (I + dt grad v) F_p and x_p.
 * Particles are independent, so the loop is parallel and deterministic; the reductions (max speed,
 * first bad particle) are order-independent. The sparse version first copies the 8 blocks around an
 * owner block into a pad and then takes the particles of one cell as SIMD lanes
 * (transfer_lanes.h); the dense reference uses the scalar bodies of transfer_core.h. */
#include "transfer/transfer.h"
#include "core/compensated.h"
#include "transfer/batches.h"
#include "transfer/ghost_apic_lanes.h"
#include "transfer/transfer_lanes.h"
#include "core/parallel.h"

#include <math.h>
#include <string.h>

#define ALWAYS_INLINE static inline __attribute__((always_inline))

/* Update particle i from grid channels viewed from node org with strides sx, sy.
 * Returns |v|^2, or -1 when a value is not finite. */
ALWAYS_INLINE mpm_real update_particle(const int W, const int apic, const mpm_transfer_ctx *ctx,
                                       mpm_particles *p, uint32_t i, const mpm_grid_values *val,
                                       const int org[3], long sx, long sy) {
  const mpm_kernel *k = &ctx->kernel;
  const int flip = !apic;
  mpm_real xr[3] = {p->x[0][i] - ctx->origin[0], p->x[1][i] - ctx->origin[1],
                    p->x[2][i] - ctx->origin[2]};
  mpm_stencil s;
  mpm_kernel_stencil(k, xr, &s);
  const long off = (long)(s.base[0] - org[0]) * sx + (long)(s.base[1] - org[1]) * sy +
                   (long)(s.base[2] - org[2]);
  const mpm_real *vn[3], *vo[3], *vm[3];
  for (int d = 0; d < 3; ++d) {
    vn[d] = val->v[d] + off;
    vo[d] = val->v0[d] ? val->v0[d] + off : NULL;
    vm[d] = val->vm[d] ? val->vm[d] + off : NULL;
  }
  mpm_real f[3];
  for (int d = 0; d < 3; ++d) f[d] = xr[d] * k->inv_dx - (mpm_real)s.base[d];
  mpm_g2p_gather o;
  mpm_g2p_particle(W, &s, f, k->dx, flip, apic, vn, vo, vm[0] ? vm : NULL, sx, sy, &o);

  const mpm_real dt = ctx->dt;
  mpm_real v[3];
  if (apic) {
    for (int d = 0; d < 3; ++d) v[d] = o.v[d];
    for (int c = 0; c < 9; ++c) p->B[c][i] = o.B[c];
  } else {
    const mpm_real a = ctx->flip_alpha;
    for (int d = 0; d < 3; ++d) v[d] = a * (p->v[d][i] + o.dv[d]) + (1 - a) * o.v[d];
  }
  /* F^{n+1} = (I + dt grad v) F^n  (Gao sec. 3.2 step 5) */
  mpm_real F[9], Fn[9];
  for (int c = 0; c < 9; ++c) F[c] = p->F[c][i];
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      Fn[3 * r + c] = F[3 * r + c] + dt * (o.grad[3 * r] * F[c] + o.grad[3 * r + 1] * F[3 + c] +
                                           o.grad[3 * r + 2] * F[6 + c]);
  mpm_real check = 0;
  for (int c = 0; c < 9; ++c) {
    p->F[c][i] = Fn[c];
    check += Fn[c];
  }
  for (int d = 0; d < 3; ++d) {
    /* x += dt v with compensation (particles.h, xc; core/compensated.h) */
    const mpm_real xn = mpm_compensated_move(p->x[d][i], dt * o.xv[d], ctx->clamp_lo[d],
                                             ctx->clamp_hi[d], &p->xc[d][i]);
    p->x[d][i] = xn;
    p->v[d][i] = v[d];
    check += xn + v[d];
  }
  const mpm_real v2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
  if (!isfinite(check + v2)) return -1; /* includes a speed whose square overflows */
  return v2;
}

/* Write back a batch's lane results to its n particles: v (APIC or FLIP blend), B, F, x; the
 * largest |v|^2 and the first particle with a non-finite value go to max_v2 and bad. */
ALWAYS_INLINE void batch_update(const int apic, const mpm_transfer_ctx *ctx, mpm_particles *p,
                                const uint32_t *idx, int n, int contiguous,
                                const mpm_g2p_lanes_out *o, mpm_real *max_v2, long *bad) {
  const mpm_real dt = ctx->dt, a = ctx->flip_alpha;
  /* F^{n+1} = (I + dt grad v) F^n (Gao sec. 3.2 step 5), lane-wise */
  mpm_vl F[9], Fn[9];
  for (int c = 0; c < 9; ++c) F[c] = mpm_lanes_load(p->F[c], idx, n, contiguous);
  mpm_vl check = {0};
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) {
      Fn[3 * r + c] = F[3 * r + c] + dt * (o->grad[3 * r] * F[c] + o->grad[3 * r + 1] * F[3 + c] +
                                           o->grad[3 * r + 2] * F[6 + c]);
      check += Fn[3 * r + c];
    }
  for (int c = 0; c < 9; ++c) mpm_lanes_store(p->F[c], idx, n, contiguous, Fn[c]);
  mpm_vl v2 = {0};
  for (int d = 0; d < 3; ++d) {
    mpm_vl v = o->v[d];
    if (!apic) v = a * (mpm_lanes_load(p->v[d], idx, n, contiguous) + o->dv[d]) + (1 - a) * o->v[d];
    /* x += dt v with compensation (particles.h, xc; core/compensated.h) */
    mpm_vl rem = mpm_lanes_load(p->xc[d], idx, n, contiguous);
    const mpm_vl xn =
        mpm_compensated_move_lanes(mpm_lanes_load(p->x[d], idx, n, contiguous), dt * o->xv[d],
                                   ctx->clamp_lo[d], ctx->clamp_hi[d], &rem);
    mpm_lanes_store(p->x[d], idx, n, contiguous, xn);
    mpm_lanes_store(p->xc[d], idx, n, contiguous, rem);
    mpm_lanes_store(p->v[d], idx, n, contiguous, v);
    check += xn;
    v2 += v * v;
  }
  if (apic)
    for (int c = 0; c < 9; ++c) mpm_lanes_store(p->B[c], idx, n, contiguous, o->B[c]);
  check += v2;
  for (int l = 0; l < n; ++l) {
    if (!isfinite(check[l])) {
      if (*bad < 0 || (long)idx[l] < *bad) *bad = (long)idx[l];
    } else if (v2[l] > *max_v2) {
      *max_v2 = v2[l];
    }
  }
}

/* Plasticity (Gao sec. 4.2): project the new F of n <= MPM_STRESS_CHUNK particles of one
 * material back onto its yield surface, in place when they are consecutive in memory, through
 * a small buffer otherwise. */
static void chunk_return_map(const mpm_material *mat, mpm_particles *p, const uint32_t *idx,
                             int n) {
  int contiguous = 1;
  for (int q = 1; q < n; ++q) contiguous &= idx[q] == idx[0] + (uint32_t)q;
  if (contiguous) {
    mpm_real *F[9];
    for (int c = 0; c < 9; ++c) F[c] = p->F[c] + idx[0];
    mat->model->return_map(mat, n, F, p->plastic + idx[0]);
    return;
  }
  mpm_real Fbuf[9][MPM_STRESS_CHUNK], plastic[MPM_STRESS_CHUNK];
  mpm_real *F[9];
  for (int c = 0; c < 9; ++c) {
    for (int l = 0; l < n; ++l) Fbuf[c][l] = p->F[c][idx[l]];
    F[c] = Fbuf[c];
  }
  for (int l = 0; l < n; ++l) plastic[l] = p->plastic[idx[l]];
  mat->model->return_map(mat, n, F, plastic);
  for (int c = 0; c < 9; ++c)
    for (int l = 0; l < n; ++l) p->F[c][idx[l]] = Fbuf[c][l];
  for (int l = 0; l < n; ++l) p->plastic[idx[l]] = plastic[l];
}

/* The return map of the particles at perm positions [begin, end) (one block and material),
 * after all of their F are updated, in chunks of MPM_STRESS_CHUNK: the model's SIMD SVD needs
 * more particles than the up to MPM_LANES of one cell. */
static void range_return_map(const mpm_material *mat, mpm_particles *p, const uint32_t *perm,
                             uint32_t begin, uint32_t end) {
  for (uint32_t j = begin; j < end; j += MPM_STRESS_CHUNK) {
    const int n = (int)(end - j < MPM_STRESS_CHUNK ? end - j : MPM_STRESS_CHUNK);
    chunk_return_map(mat, p, perm + j, n);
  }
}

ALWAYS_INLINE void g2p_block(const int W, const int apic, const int motion,
                             const mpm_transfer_ctx *ctx, const mpm_sparse_grid *g,
                             const mpm_grid_values *val, mpm_particles *p, int32_t b,
                             mpm_real *max_v2, long *bad) {
  /* the 8 blocks around the owner block as an AoS pad: v_new xyz, (FLIP) v_old xyz, (motion)
     v_m xyz per node (mpm_g2p_pad_stride); and the blocks of the next owner block are requested
     while this one is processed */
  const mpm_real *vel[9] = {val->v[0], val->v[1], val->v[2]};
  int count = 3;
  if (!apic)
    for (int d = 0; d < 3; ++d) vel[count++] = val->v0[d];
  if (motion)
    for (int d = 0; d < 3; ++d) vel[count++] = val->vm[d];
  if ((size_t)b + 1 < g->owner_count) MPM_PAD_PREFETCH(g, b + 1, count, vel, 0);
  mpm_real pad[MPM_PAD_NODES * 12] __attribute__((aligned(MPM_ALIGN)));
  mpm_pad_gather(W, g, b, count, vel, mpm_g2p_pad_stride(apic, motion), pad);
  const int org[3] = {g->coord[b][0] * MPM_BLOCK, g->coord[b][1] * MPM_BLOCK,
                      g->coord[b][2] * MPM_BLOCK};
  const mpm_real *const x[3] = {p->x[0], p->x[1], p->x[2]};
  size_t q1;
  const size_t q0 = mpm_block_cells(g, (size_t)b, &q1);
  for (size_t q = q0; q < q1; ++q) {
    const uint32_t end = g->cell_start[q + 1];
    const mpm_ghost_apic *ga = ctx->ghost_apic; /* APIC across levels */
    const uint32_t bc = apic && ga ? ga->cell_of[q] : MPM_NOT_BOUNDARY;
    for (uint32_t j = g->cell_start[q]; j < end; j += MPM_LANES) {
      const int n = mpm_batch_size(j, end);
      const uint32_t *idx = g->perm + j;
      if (j + 2 * MPM_LANES < g->particle_count) MPM_PREFETCH_PARTICLE(p, idx[2 * MPM_LANES], 1);
      const int contiguous = mpm_batch_contiguous(idx, n);
      int base[3];
      mpm_lane_stencil s;
      mpm_lane_stencil_eval(W, &ctx->kernel, x, ctx->origin, idx, n, contiguous, 0, base, &s);
      mpm_g2p_lanes_out o;
      mpm_g2p_lanes(W, apic, motion, &s, ctx->kernel.dx, pad, mpm_pad_offset(base, org),
                    MPM_PAD * MPM_PAD, MPM_PAD, &o);
      if (bc != MPM_NOT_BOUNDARY) mpm_ghost_apic_g2p(W, ga, bc, &s, o.B);
      batch_update(apic, ctx, p, idx, n, contiguous, &o, max_v2, bad);
    }
    const int m = mpm_cell_material(q, q0);
    if (mpm_cell_last_of_material(q, q0) && ctx->materials[m].model->return_map) {
      uint32_t begin, range_end; /* all of the material's F are new */
      mpm_material_range(g, q0, m, &begin, &range_end);
      range_return_map(&ctx->materials[m], p, g->perm, begin, range_end);
    }
  }
}

/* One owner block's G2P specialized by stencil width and APIC: a table, chosen once per call. */
typedef void (*g2p_block_fn)(const mpm_transfer_ctx *ctx, const mpm_sparse_grid *g,
                             const mpm_grid_values *val, mpm_particles *p, int32_t b,
                             mpm_real *max_v2, long *bad);
#define G2P_BLOCK(W, A, M)                                                                         \
  static void g2p_block_w##W##_a##A##_m##M(const mpm_transfer_ctx *ctx, const mpm_sparse_grid *g,  \
                                           const mpm_grid_values *val, mpm_particles *p,           \
                                           int32_t b, mpm_real *max_v2, long *bad) {               \
    g2p_block(W, A, M, ctx, g, val, p, b, max_v2, bad);                                            \
  }
G2P_BLOCK(2, 0, 0)
G2P_BLOCK(2, 1, 0)
G2P_BLOCK(3, 0, 0)
G2P_BLOCK(3, 1, 0)
G2P_BLOCK(4, 0, 0)
G2P_BLOCK(4, 1, 0)
G2P_BLOCK(2, 0, 1)
G2P_BLOCK(2, 1, 1)
G2P_BLOCK(3, 0, 1)
G2P_BLOCK(3, 1, 1)
G2P_BLOCK(4, 0, 1)
G2P_BLOCK(4, 1, 1)
#undef G2P_BLOCK

/* [motion field][width: 2, 3, 4][apic] */
static const g2p_block_fn g2p_block_variants[2][3][2] = {
    {{g2p_block_w2_a0_m0, g2p_block_w2_a1_m0},
     {g2p_block_w3_a0_m0, g2p_block_w3_a1_m0},
     {g2p_block_w4_a0_m0, g2p_block_w4_a1_m0}},
    {{g2p_block_w2_a0_m1, g2p_block_w2_a1_m1},
     {g2p_block_w3_a0_m1, g2p_block_w3_a1_m1},
     {g2p_block_w4_a0_m1, g2p_block_w4_a1_m1}},
};

mpm_g2p_result mpm_g2p_sparse(const mpm_transfer_ctx *ctx, const mpm_sparse_grid *g,
                              const mpm_grid_values *val, mpm_particles *p) {
  const int apic = ctx->transfer == MPM_TRANSFER_APIC;
  const g2p_block_fn block =
      g2p_block_variants[val->vm[0] != NULL][mpm_width_index(ctx->kernel.width)][apic];
  const long nb = (long)g->owner_count;
  mpm_real max_v2 = 0;
  long bad = -1;
#pragma omp parallel
  {
    mpm_real my_v2 = 0;
    long my_bad = -1;
#pragma omp for schedule(dynamic, 8)
    for (long b = 0; b < nb; ++b) {
      block(ctx, g, val, p, (int32_t)b, &my_v2, &my_bad);
    }
#pragma omp critical(mpm_g2p_reduce)
    {
      if (my_v2 > max_v2) max_v2 = my_v2;
      if (my_bad >= 0 && (bad < 0 || my_bad < bad)) bad = my_bad;
    }
  }
  mpm_g2p_result r = {mpm_sqrt(max_v2), bad};
  return r;
}

/* One particle's G2P on the dense grid specialized by stencil width (the reference grid: a
 * call per particle). */
typedef mpm_real (*update_particle_fn)(int apic, const mpm_transfer_ctx *ctx, mpm_particles *p,
                                       uint32_t i, const mpm_grid_values *val, const int org[3],
                                       long sx, long sy);
#define UPDATE_PARTICLE(W)                                                                         \
  static mpm_real update_particle_w##W(int apic, const mpm_transfer_ctx *ctx, mpm_particles *p,    \
                                       uint32_t i, const mpm_grid_values *val, const int org[3],   \
                                       long sx, long sy) {                                         \
    return update_particle(W, apic, ctx, p, i, val, org, sx, sy);                                  \
  }
UPDATE_PARTICLE(2)
UPDATE_PARTICLE(3)
UPDATE_PARTICLE(4)
#undef UPDATE_PARTICLE

static const update_particle_fn update_particle_variants[3] = {
    update_particle_w2, update_particle_w3, update_particle_w4};

mpm_g2p_result mpm_g2p_dense(const mpm_transfer_ctx *ctx, const mpm_dense_grid *g,
                             const mpm_grid_values *val, mpm_particles *p) {
  const int apic = ctx->transfer == MPM_TRANSFER_APIC;
  const update_particle_fn update = update_particle_variants[mpm_width_index(ctx->kernel.width)];
  const long sy = g->n[2], sx = (long)g->n[1] * g->n[2];
  const int org[3] = {0, 0, 0};
  const long n = (long)p->count;
  mpm_real max_v2 = 0;
  long bad = -1;
#pragma omp parallel
  {
    mpm_real my_v2 = 0;
    long my_bad = -1;
#pragma omp for schedule(static)
    for (long i = 0; i < n; ++i) {
      const mpm_real v2 = update(apic, ctx, p, (uint32_t)i, val, org, sx, sy);
      if (v2 < 0) {
        if (my_bad < 0 || i < my_bad) my_bad = i;
      } else if (v2 > my_v2) {
        my_v2 = v2;
      }
    }
#pragma omp critical(mpm_g2p_reduce_dense)
    {
      if (my_v2 > max_v2) max_v2 = my_v2;
      if (my_bad >= 0 && (bad < 0 || my_bad < bad)) bad = my_bad;
    }
  }
  /* plasticity on chunks of consecutive particles of one material */
  const long chunks = (n + MPM_STRESS_CHUNK - 1) / MPM_STRESS_CHUNK;
#pragma omp parallel for schedule(static)
  for (long c = 0; c < chunks; ++c) {
    const long begin = c * MPM_STRESS_CHUNK;
    const long end = begin + MPM_STRESS_CHUNK < n ? begin + MPM_STRESS_CHUNK : n;
    long i = begin;
    while (i < end) {
      const int32_t m = p->material[i];
      uint32_t idx[MPM_STRESS_CHUNK];
      int k = 0;
      while (i < end && p->material[i] == m) idx[k++] = (uint32_t)i++;
      const mpm_material *mat = &ctx->materials[m];
      if (mat->model->return_map) chunk_return_map(mat, p, idx, k);
    }
  }
  mpm_g2p_result r = {mpm_sqrt(max_v2), bad};
  return r;
}

mpm_g2p_result mpm_g2p(const mpm_transfer_ctx *ctx, const mpm_grid *g, const mpm_grid_values *val,
                       mpm_particles *p) {
  return mpm_transfer_variant_of(g)->g2p(ctx, g, val, p);
}
