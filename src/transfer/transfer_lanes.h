/* transfer_lanes.h - P2G and G2P for the sparse grid with particles as SIMD lanes.
 *
 * Particles are sorted by the cell of their stencil's base node (sparse_grid.h), so the up to
 * 8 particles of one cell share every grid node they touch. A batch of them (MPM_LANES: 8 in
 * float, 4 in double) becomes the lanes of one vector: a node's value is broadcast to all lanes
 * (G2P) or the lanes' contributions are summed once per node (P2G), and every weight is computed
 * lane-wise. The tensor-product structure of the kernels (Gao et al. 2017, sec. 6.2) is used to
 * contract one axis at a time:
 *
 *   P2G (APIC, force fused in):  p_d(i,j,k) = wz_k (wy_j X_di + wx_i Y_dj) + wx_i wy_j Z_dk,
 *     X_d = m v_d wx + (mB)_d0 ax + dt K_d0 dwx,  Y_d = (mB)_d1 ay + dt K_d1 dwy,
 *     Z_d = (mB)_d2 az + dt K_d2 dwz   (K = -V0 tau; a = D^{-1}(x_i - x_p) w per axis)
 *   G2P: sum over k, then j, then i, of the node velocity against w, dw and w r per axis.
 *
 * Lanes are core/lanes.h vectors (GCC vector extensions, no intrinsics). The dense reference
 * grid keeps the plain scalar bodies of transfer_core.h, and the tests compare the two. */
#ifndef MPM_TRANSFER_TRANSFER_LANES_H
#define MPM_TRANSFER_TRANSFER_LANES_H

#include "core/lanes.h"
#include "transfer/transfer_core.h"
#include "core/particles.h"

#include <stdint.h>

typedef mpm_real mpm_vq __attribute__((vector_size(4 * sizeof(mpm_real))));

/* Reals per node in the AoS pads: APIC needs 4 (mass, momentum / velocity), PIC/FLIP 8 (mass,
 * momentum, force / new and old velocity). */
#define MPM_PAD_STRIDE(apic) ((apic) ? 4 : 8)

/* Pairwise lane sums of two vectors: (a0+a1, a2+a3, ..., b0+b1, b2+b3, ...). */
MPM_ALWAYS_INLINE mpm_vl mpm_vl_pair(mpm_vl a, mpm_vl b) {
#if MPM_LANES == 4
  return __builtin_shufflevector(a, b, 0, 2, 4, 6) + __builtin_shufflevector(a, b, 1, 3, 5, 7);
#elif defined(__clang__) /* clang has no __builtin_shuffle (the fuzz build, fuzz/, uses clang) */
  return __builtin_shufflevector(a, b, 0, 2, 4, 6, 8, 10, 12, 14) +
         __builtin_shufflevector(a, b, 1, 3, 5, 7, 9, 11, 13, 15);
#else
  const mpm_vl_index even = {0, 2, 4, 6, 8, 10, 12, 14}, odd = {1, 3, 5, 7, 9, 11, 13, 15};
  return __builtin_shuffle(a, b, even) + __builtin_shuffle(a, b, odd);
#endif
}

/* Lane sums of 8 vectors: (sum v0, sum v1, ..., sum v7). */
MPM_ALWAYS_INLINE mpm_v8 mpm_vl_sum8(const mpm_vl v[8]) {
  const mpm_vl a = mpm_vl_pair(v[0], v[1]), b = mpm_vl_pair(v[2], v[3]);
  const mpm_vl c = mpm_vl_pair(v[4], v[5]), d = mpm_vl_pair(v[6], v[7]);
#if MPM_LANES == 8
  return mpm_vl_pair(mpm_vl_pair(a, b), mpm_vl_pair(c, d));
#else
  return __builtin_shufflevector(mpm_vl_pair(a, b), mpm_vl_pair(c, d), 0, 1, 2, 3, 4, 5, 6, 7);
#endif
}

/* Lane sums of 4 vectors in lanes 0..3 (and zeros in 4..7 of 8 lanes). */
MPM_ALWAYS_INLINE mpm_vl mpm_vl_sum4(const mpm_vl v[4]) {
#if MPM_LANES == 4
  return mpm_vl_pair(mpm_vl_pair(v[0], v[1]), mpm_vl_pair(v[2], v[3]));
#else
  const mpm_vl zero = {0};
  return mpm_vl_pair(mpm_vl_pair(mpm_vl_pair(v[0], v[1]), mpm_vl_pair(v[2], v[3])), zero);
#endif
}

/* A batch is contiguous when its n = MPM_LANES particles are consecutive in memory, which is
 * the common case right after the particles were reordered into block order; then lanes move
 * with single vector loads and stores instead of gathers and scatters. */
MPM_ALWAYS_INLINE int mpm_batch_contiguous(const uint32_t *idx, int n) {
  return n == MPM_LANES && idx[MPM_LANES - 1] == idx[0] + (MPM_LANES - 1);
}

/* Lanes of array a at the batch's particles (lanes >= n repeat lane 0). */
MPM_ALWAYS_INLINE mpm_vl mpm_lanes_load(const mpm_real *a, const uint32_t *idx, int n,
                                        int contiguous) {
  mpm_vl v;
  if (contiguous) {
    __builtin_memcpy(&v, a + idx[0], sizeof v);
  } else {
    for (int l = 0; l < MPM_LANES; ++l) v[l] = a[idx[l < n ? l : 0]];
  }
  return v;
}

/* Store the first n lanes of v to array a at the batch's particles. */
MPM_ALWAYS_INLINE void mpm_lanes_store(mpm_real *a, const uint32_t *idx, int n, int contiguous,
                                       mpm_vl v) {
  if (contiguous) {
    __builtin_memcpy(a + idx[0], &v, sizeof v);
  } else {
    for (int l = 0; l < n; ++l) a[idx[l]] = v[l];
  }
}

/* Prefetch particle i's entries of every per-particle array. Transfers touch ~27 arrays per
 * particle; that many concurrent streams is more than the hardware prefetchers follow, so the
 * batch loops ask for the particles two batches ahead. RW is 0 (read) or 1 (write): a macro,
 * because __builtin_prefetch needs a constant even in unoptimized builds. */
#define MPM_PREFETCH_PARTICLE(p, i, RW)                                                            \
  do {                                                                                             \
    for (int d_ = 0; d_ < 3; ++d_) {                                                               \
      __builtin_prefetch((p)->x[d_] + (i), RW);                                                    \
      __builtin_prefetch((p)->v[d_] + (i), RW);                                                    \
    }                                                                                              \
    for (int c_ = 0; c_ < 9; ++c_) {                                                               \
      __builtin_prefetch((p)->F[c_] + (i), RW);                                                    \
      __builtin_prefetch((p)->B[c_] + (i), RW);                                                    \
    }                                                                                              \
    __builtin_prefetch((p)->plastic + (i), RW);                                                    \
    __builtin_prefetch((p)->mass + (i), 0);                                                        \
    __builtin_prefetch((p)->vol0 + (i), 0);                                                        \
  } while (0)

/* Per-lane stencil factors of a batch: [axis][node][lane]. */
typedef struct mpm_lane_stencil {
  mpm_vl w[3][MPM_STENCIL_MAX], dw[3][MPM_STENCIL_MAX], a[3][MPM_STENCIL_MAX];
  mpm_vl f[3]; /* distance from the base node, cells */
} mpm_lane_stencil;

/* uGIMP's 3 nodes per lane at distances f in [1/2, 3/2) cells from the first (box half width
 * h <= 1/2); see mpm_ugimp_outer in kernel.h: outer nodes in closed form, the middle one by
 * partition of unity. The APIC factors a only if need_a. */
MPM_ALWAYS_INLINE void mpm_lane_ugimp(const mpm_real h, const mpm_real inv_dx, const mpm_vl f,
                                      const int need_a, mpm_vl *w, mpm_vl *dw, mpm_vl *a) {
  const mpm_real inv_4h = 1 / (4 * h), inv_2h = 1 / (2 * h);
  const mpm_vl zero = {0}, hv = mpm_vl_splat(h);
  const mpm_vl x0 = 1 - f, x2 = f - 1; /* 1 - distance to nodes 0 and 2 */
  const mpm_vl q0 = mpm_vl_max(x0 + h, zero), q2 = mpm_vl_max(x2 + h, zero);
  w[0] = mpm_vl_select(x0 >= hv, x0, q0 * q0 * inv_4h);
  w[2] = mpm_vl_select(x2 >= hv, x2, q2 * q2 * inv_4h);
  w[1] = 1 - w[0] - w[2];
  dw[0] = mpm_vl_select(x0 >= hv, mpm_vl_splat(-inv_dx), q0 * (-inv_2h * inv_dx));
  dw[2] = mpm_vl_select(x2 >= hv, mpm_vl_splat(inv_dx), q2 * (inv_2h * inv_dx));
  dw[1] = -dw[0] - dw[2];
  mpm_vl dsum = {0};
  for (int q = 0; q < 3; ++q) {
    const mpm_vl r = (mpm_real)q - f;
    dsum += w[q] * r * r;
  }
  if (need_a) {
    const mpm_vl sc = inv_dx / dsum;
    for (int q = 0; q < 3; ++q) a[q] = w[q] * ((mpm_real)q - f) * sc;
  }
}

/* Stencils of n particles that share their base node (the APIC factors a only if need_a) (lanes >=
 * n copy lane 0 so that every value stays finite). Because the base is common, the weights are
 * polynomials of the lane's offset f from it and vectorize without branches (uGIMP's piecewise
 * integrals become selects). */
MPM_ALWAYS_INLINE void mpm_lane_stencil_eval(const int W, const mpm_kernel *k,
                                             const mpm_real *const x[3], const mpm_real origin[3],
                                             const uint32_t *idx, int n, int contiguous,
                                             const int need_a, int base[3], mpm_lane_stencil *s) {
  const mpm_real inv_dx = k->inv_dx;
  for (int d = 0; d < 3; ++d) {
    const mpm_vl xg = (mpm_lanes_load(x[d], idx, n, contiguous) - origin[d]) * inv_dx;
    base[d] = (int)mpm_floor(xg[0] - k->shift);
    if (W == 4) base[d] &= mpm_kernel_base_mask(k); /* paired: the even node below */
    const mpm_vl f = xg - (mpm_real)base[d];
    s->f[d] = f;
    mpm_vl *w = s->w[d], *dw = s->dw[d], *a = s->a[d];
    if (W == 4 && k->kind == MPM_KERNEL_UGIMP_PAIRED) {
      /* a lane whose own base is odd (f >= 3/2) has its 3 nodes one node up */
      const mpm_vl_index odd = f >= mpm_vl_splat(R_(1.5));
      const mpm_vl zero = {0}, one = mpm_vl_splat(1);
      mpm_vl w3[3], dw3[3], a3[3] = {zero, zero, zero};
      mpm_lane_ugimp(k->half_len, inv_dx, f - mpm_vl_select(odd, one, zero), need_a, w3, dw3, a3);
      mpm_vl *out[3] = {w, dw, a}, *in[3] = {w3, dw3, a3};
      for (int c = 0; c < 3; ++c) {
        out[c][0] = mpm_vl_select(odd, zero, in[c][0]);
        out[c][1] = mpm_vl_select(odd, in[c][0], in[c][1]);
        out[c][2] = mpm_vl_select(odd, in[c][1], in[c][2]);
        out[c][3] = mpm_vl_select(odd, in[c][2], zero);
      }
      continue;
    }
    if (W == 4 && k->kind == MPM_KERNEL_UGIMP_WIDE) {
      /* the wide box (mpm_ugimp_wide_outer and _inner in kernel.h), the three pieces of the
         inner node as selects, node 2 by partition of unity; outside the switch and behind the
         compile-time width, so that the code of the 3-wide kernels is what it was without it */
      const mpm_real h = k->half_len, inv_4h = 1 / (4 * h), inv_2h = 1 / (2 * h);
      const mpm_vl zero = {0}, hv = mpm_vl_splat(h);
      const mpm_vl x0 = (1 + h) - f, x3 = f + (h - 2);
      const mpm_vl q0 = mpm_vl_max(x0, zero), q3 = mpm_vl_max(x3, zero);
      w[0] = q0 * q0 * inv_4h;
      w[3] = q3 * q3 * inv_4h;
      dw[0] = q0 * (-inv_2h * inv_dx);
      dw[3] = q3 * (inv_2h * inv_dx);
      const mpm_vl d1 = f - 1, a1 = d1 - h, x1 = (1 + h) - d1;
      const mpm_vl wA = x1 * x1 * inv_4h, dA = x1 * (-inv_2h);
      const mpm_vl wB = 1 - (d1 * d1 + h * h) * inv_2h, dB = d1 * (-1 / h);
      const mpm_vl wC = (R_(0.5) - a1 - R_(0.5) * a1 * a1) * inv_2h, dC = (1 + a1) * (-inv_2h);
      const mpm_vl_index peak = d1 < hv, foot = d1 + h <= mpm_vl_splat(1);
      w[1] = mpm_vl_select(peak, mpm_vl_select(foot, wB, wC), wA);
      dw[1] = mpm_vl_select(peak, mpm_vl_select(foot, dB, dC), dA) * inv_dx;
      w[2] = 1 - w[0] - w[1] - w[3];
      dw[2] = -dw[0] - dw[1] - dw[3];
      if (need_a) {
        mpm_vl dsum = {0};
        for (int q = 0; q < 4; ++q) {
          const mpm_vl r = (mpm_real)q - f;
          dsum += w[q] * r * r;
        }
        const mpm_vl sc = inv_dx / dsum;
        for (int q = 0; q < 4; ++q) a[q] = w[q] * ((mpm_real)q - f) * sc;
      }
      continue;
    }
    switch (k->kind) {
    default: /* MPM_KERNEL_LINEAR */
      w[0] = 1 - f;
      w[1] = f;
      dw[0] = a[0] = mpm_vl_splat(-inv_dx);
      dw[1] = a[1] = mpm_vl_splat(inv_dx);
      (void)need_a;
      break;
    case MPM_KERNEL_QUADRATIC: {
      const mpm_vl t0 = R_(1.5) - f, t1 = f - 1, t2 = f - R_(0.5);
      w[0] = R_(0.5) * t0 * t0;
      w[1] = R_(0.75) - t1 * t1;
      w[2] = R_(0.5) * t2 * t2;
      dw[0] = -inv_dx * t0;
      dw[1] = (-2 * inv_dx) * t1;
      dw[2] = inv_dx * t2;
      if (need_a)
        for (int q = 0; q < 3; ++q) a[q] = (4 * inv_dx) * w[q] * ((mpm_real)q - f); /* D = dx^2/4 */
      break;
    }
    case MPM_KERNEL_CUBIC: {
      const mpm_vl d1 = f - 1, d2 = 2 - f, u0 = 2 - f, u3 = f - 1;
      w[0] = u0 * u0 * u0 * (R_(1.0) / 6);
      w[1] = R_(0.5) * d1 * d1 * d1 - d1 * d1 + R_(2.0) / 3;
      w[2] = R_(0.5) * d2 * d2 * d2 - d2 * d2 + R_(2.0) / 3;
      w[3] = u3 * u3 * u3 * (R_(1.0) / 6);
      dw[0] = (-R_(0.5) * inv_dx) * u0 * u0;
      dw[1] = inv_dx * (R_(1.5) * d1 * d1 - 2 * d1);
      dw[2] = -inv_dx * (R_(1.5) * d2 * d2 - 2 * d2);
      dw[3] = (R_(0.5) * inv_dx) * u3 * u3;
      if (need_a)
        for (int q = 0; q < 4; ++q) a[q] = (3 * inv_dx) * w[q] * ((mpm_real)q - f); /* D = dx^2/3 */
      break;
    }
    case MPM_KERNEL_UGIMP:
      mpm_lane_ugimp(k->half_len, inv_dx, f, need_a, w, dw, a);
      break;
    }
  }
}

/* P2G of one batch into an AoS pad (8 reals per node: mass, momentum or p, force, unused).
 * node(i,j,k) is at pad[(off + i*sx + j*sy + k) * MPM_PAD_STRIDE(fused)]. Lane inputs: m, mv[3],
 * mB[9] (APIC), K[9] (dt K when fused). fused = APIC: force folded into the momentum channel. */
MPM_ALWAYS_INLINE void mpm_p2g_lanes(const int W, const int fused, const mpm_lane_stencil *s,
                                     mpm_vl m, const mpm_vl mv[3], const mpm_vl mB[9],
                                     const mpm_vl K[9], mpm_real *pad, long off, long sx, long sy) {
  mpm_vl X[3][MPM_STENCIL_MAX], Y[3][MPM_STENCIL_MAX], Z[3][MPM_STENCIL_MAX];
  mpm_vl FX[3][MPM_STENCIL_MAX], FY[3][MPM_STENCIL_MAX], FZ[3][MPM_STENCIL_MAX];
  for (int d = 0; d < 3; ++d)
    for (int q = 0; q < W; ++q) {
      if (fused) {
        X[d][q] = mv[d] * s->w[0][q] + mB[3 * d] * s->a[0][q] + K[3 * d] * s->dw[0][q];
        Y[d][q] = mB[3 * d + 1] * s->a[1][q] + K[3 * d + 1] * s->dw[1][q];
        Z[d][q] = mB[3 * d + 2] * s->a[2][q] + K[3 * d + 2] * s->dw[2][q];
      } else {
        X[d][q] = mv[d] * s->w[0][q];
        FX[d][q] = K[3 * d] * s->dw[0][q];
        FY[d][q] = K[3 * d + 1] * s->dw[1][q];
        FZ[d][q] = K[3 * d + 2] * s->dw[2][q];
      }
    }
  for (int i = 0; i < W; ++i) {
    const mpm_vl wx = s->w[0][i], mwx = m * wx;
    for (int j = 0; j < W; ++j) {
      const mpm_vl wy = s->w[1][j], wxy = wx * wy, mwxy = mwx * wy;
      mpm_vl U[3], UF[3];
      for (int d = 0; d < 3; ++d) {
        U[d] = fused ? wy * X[d][i] + wx * Y[d][j] : wy * X[d][i];
        if (!fused) UF[d] = wy * FX[d][i] + wx * FY[d][j];
      }
      for (int k = 0; k < W; ++k) {
        const mpm_vl wz = s->w[2][k];
        mpm_real *node = pad + (off + i * sx + j * sy + k) * MPM_PAD_STRIDE(fused);
        if (fused) {
          mpm_vl c[4] = {mwxy * wz, wz * U[0] + wxy * Z[0][k], wz * U[1] + wxy * Z[1][k],
                         wz * U[2] + wxy * Z[2][k]};
          const mpm_vl sum = mpm_vl_sum4(c);
          mpm_vq node_q, sum_q;
          __builtin_memcpy(&node_q, node, sizeof node_q);
          __builtin_memcpy(&sum_q, &sum, sizeof sum_q); /* lanes 0..3 */
          node_q += sum_q;
          __builtin_memcpy(node, &node_q, sizeof node_q);
        } else {
          mpm_v8 node_v;
          __builtin_memcpy(&node_v, node, sizeof node_v);
          const mpm_vl zero = {0};
          mpm_vl c[8] = {mwxy * wz,
                         wz * U[0],
                         wz * U[1],
                         wz * U[2],
                         wz * UF[0] + wxy * FZ[0][k],
                         wz * UF[1] + wxy * FZ[1][k],
                         wz * UF[2] + wxy * FZ[2][k],
                         zero};
          node_v += mpm_vl_sum8(c);
          __builtin_memcpy(node, &node_v, sizeof node_v);
        }
      }
    }
  }
}

/* APIC P2G of one batch accumulated lane by lane: acc[node][0] gathers mass, acc[node][1..3]
 * the momentum p = m v + dt f, each still as 8 lanes; node(i,j,k) = off + i*sx + j*sy + k. The
 * lanes are summed once per node when the block is done, instead of once per node per batch.
 * mB = m B, K = dt (-V0 tau). */
MPM_ALWAYS_INLINE void mpm_p2g_lanes_acc(const int W, const mpm_lane_stencil *s, mpm_vl m,
                                         const mpm_vl mv[3], const mpm_vl mB[9], const mpm_vl K[9],
                                         mpm_vl (*acc)[4], long off, long sx, long sy) {
  mpm_vl X[3][MPM_STENCIL_MAX], Y[3][MPM_STENCIL_MAX], Z[3][MPM_STENCIL_MAX];
  for (int d = 0; d < 3; ++d)
    for (int q = 0; q < W; ++q) {
      X[d][q] = mv[d] * s->w[0][q] + mB[3 * d] * s->a[0][q] + K[3 * d] * s->dw[0][q];
      Y[d][q] = mB[3 * d + 1] * s->a[1][q] + K[3 * d + 1] * s->dw[1][q];
      Z[d][q] = mB[3 * d + 2] * s->a[2][q] + K[3 * d + 2] * s->dw[2][q];
    }
  for (int i = 0; i < W; ++i) {
    const mpm_vl wx = s->w[0][i], mwx = m * wx;
    for (int j = 0; j < W; ++j) {
      const mpm_vl wy = s->w[1][j], wxy = wx * wy, mwxy = mwx * wy;
      mpm_vl U[3];
      for (int d = 0; d < 3; ++d) U[d] = wy * X[d][i] + wx * Y[d][j];
      for (int k = 0; k < W; ++k) {
        const mpm_vl wz = s->w[2][k];
        mpm_vl *node = acc[off + i * sx + j * sy + k];
        node[0] += mwxy * wz;
        for (int d = 0; d < 3; ++d) node[1 + d] += wz * U[d] + wxy * Z[d][k];
      }
    }
  }
}

/* Lane results of G2P. */
typedef struct mpm_g2p_lanes_out {
  mpm_vl v[3], dv[3], grad[9], B[9];
  mpm_vl xv[3]; /* the velocity the particle moves by: v, or with a motion channel sum w v_m */
} mpm_g2p_lanes_out;

/* The G2P pads' layout: per node v_new xyz, then for FLIP v_old xyz, then with a motion field
 * (grid.h, vm) its xyz, in `stride` reals. */
MPM_ALWAYS_INLINE int mpm_g2p_pad_stride(int apic, int motion) {
  return motion ? (apic ? 8 : 12) : MPM_PAD_STRIDE(apic);
}

/* G2P of one batch from an AoS pad (mpm_g2p_pad_stride). With `motion`, grad v and the
 * particle's motion xv are taken from the motion channel, v, B and the FLIP increment from
 * v_new; without, all from v_new (xv = v). */
MPM_ALWAYS_INLINE void mpm_g2p_lanes(const int W, const int apic, const int motion,
                                     const mpm_lane_stencil *s, mpm_real dx, const mpm_real *pad,
                                     long off, long sx, long sy, mpm_g2p_lanes_out *o) {
  const int stride = mpm_g2p_pad_stride(apic, motion), mo = apic ? 3 : 6;
  mpm_vl rw[3][MPM_STENCIL_MAX]; /* w (x_i - x_p) per axis, m */
  for (int d = 0; d < 3; ++d)
    for (int q = 0; q < W; ++q) rw[d][q] = s->w[d][q] * (((mpm_real)q - s->f[d]) * dx);
  const mpm_vl zero = {0};
  mpm_vl v[3], gx[3], gy[3], gz[3], bx[3], by[3], bz[3], dv[3], xv[3];
  for (int d = 0; d < 3; ++d)
    v[d] = gx[d] = gy[d] = gz[d] = bx[d] = by[d] = bz[d] = dv[d] = xv[d] = zero;
  for (int i = 0; i < W; ++i) {
    mpm_vl Y0[3], Y1[3], Y2[3], Y3[3], Y4[3], YD[3], YM[3];
    for (int d = 0; d < 3; ++d) Y0[d] = Y1[d] = Y2[d] = Y3[d] = Y4[d] = YD[d] = YM[d] = zero;
    for (int j = 0; j < W; ++j) {
      mpm_vl Z0[3], Z1[3], Z2[3], ZD[3], ZM[3];
      for (int d = 0; d < 3; ++d) Z0[d] = Z1[d] = Z2[d] = ZD[d] = ZM[d] = zero;
      for (int k = 0; k < W; ++k) {
        const mpm_real *node = pad + (off + i * sx + j * sy + k) * stride;
        for (int d = 0; d < 3; ++d) {
          const mpm_vl u = mpm_vl_splat(node[d]);
          Z0[d] += s->w[2][k] * u;
          if (motion) {
            const mpm_vl um = mpm_vl_splat(node[mo + d]);
            ZM[d] += s->w[2][k] * um;
            Z1[d] += s->dw[2][k] * um;
          } else {
            Z1[d] += s->dw[2][k] * u;
          }
          if (apic)
            Z2[d] += rw[2][k] * u;
          else
            ZD[d] += s->w[2][k] * (u - node[3 + d]);
        }
      }
      for (int d = 0; d < 3; ++d) {
        /* the motion's w sums (ZM; Z0 without a motion channel) make the gradient's */
        const mpm_vl zm = motion ? ZM[d] : Z0[d];
        Y0[d] += s->w[1][j] * Z0[d];
        Y1[d] += s->dw[1][j] * zm;
        Y2[d] += s->w[1][j] * Z1[d];
        if (motion) YM[d] += s->w[1][j] * ZM[d];
        if (apic) {
          Y3[d] += rw[1][j] * Z0[d];
          Y4[d] += s->w[1][j] * Z2[d];
        } else {
          YD[d] += s->w[1][j] * ZD[d];
        }
      }
    }
    for (int d = 0; d < 3; ++d) {
      const mpm_vl ym = motion ? YM[d] : Y0[d];
      v[d] += s->w[0][i] * Y0[d];
      gx[d] += s->dw[0][i] * ym;
      gy[d] += s->w[0][i] * Y1[d];
      gz[d] += s->w[0][i] * Y2[d];
      if (motion) xv[d] += s->w[0][i] * YM[d];
      if (apic) {
        bx[d] += rw[0][i] * Y0[d];
        by[d] += s->w[0][i] * Y3[d];
        bz[d] += s->w[0][i] * Y4[d];
      } else {
        dv[d] += s->w[0][i] * YD[d];
      }
    }
  }
  for (int d = 0; d < 3; ++d) {
    o->v[d] = v[d];
    o->xv[d] = motion ? xv[d] : v[d];
    o->dv[d] = dv[d];
    o->grad[3 * d] = gx[d];
    o->grad[3 * d + 1] = gy[d];
    o->grad[3 * d + 2] = gz[d];
    o->B[3 * d] = bx[d];
    o->B[3 * d + 1] = by[d];
    o->B[3 * d + 2] = bz[d];
  }
}

/* The scatter of per-particle matrices M (the lanes' M_p) to a pad of `stride` >= 4 reals per
 * node: f_d(node) += sum_e M_de dw_e(node), grad w = (dwx wy wz, wx dwy wz, wx wy dwz), lanes
 * summed once per node. The force of P2G is this with M = -V0 tau. */
MPM_ALWAYS_INLINE void mpm_scatter_lanes(const int W, const mpm_lane_stencil *s, const mpm_vl M[9],
                                         mpm_real *pad, int stride, long off, long sx, long sy) {
  mpm_vl FX[3][MPM_STENCIL_MAX], FY[3][MPM_STENCIL_MAX], FZ[3][MPM_STENCIL_MAX];
  for (int d = 0; d < 3; ++d)
    for (int q = 0; q < W; ++q) {
      FX[d][q] = M[3 * d] * s->dw[0][q];
      FY[d][q] = M[3 * d + 1] * s->dw[1][q];
      FZ[d][q] = M[3 * d + 2] * s->dw[2][q];
    }
  const mpm_vl zero = {0};
  for (int i = 0; i < W; ++i) {
    const mpm_vl wx = s->w[0][i];
    for (int j = 0; j < W; ++j) {
      const mpm_vl wy = s->w[1][j], wxy = wx * wy;
      mpm_vl UF[3];
      for (int d = 0; d < 3; ++d) UF[d] = wy * FX[d][i] + wx * FY[d][j];
      for (int k = 0; k < W; ++k) {
        const mpm_vl wz = s->w[2][k];
        mpm_real *node = pad + (off + i * sx + j * sy + k) * stride;
        mpm_vl c[4] = {wz * UF[0] + wxy * FZ[0][k], wz * UF[1] + wxy * FZ[1][k],
                       wz * UF[2] + wxy * FZ[2][k], zero};
        const mpm_vl sum = mpm_vl_sum4(c);
        for (int d = 0; d < 3; ++d) node[d] += sum[d];
      }
    }
  }
}

/* The gradient of a node field u at the lanes' particles: G_de = sum_nodes u_d dw_e, from a
 * pad of `stride` reals per node (u in the first 3). */
MPM_ALWAYS_INLINE void mpm_gradient_lanes(const int W, const mpm_lane_stencil *s,
                                          const mpm_real *pad, int stride, long off, long sx,
                                          long sy, mpm_vl G[9]) {
  const mpm_vl zero = {0};
  mpm_vl gx[3], gy[3], gz[3];
  for (int d = 0; d < 3; ++d) gx[d] = gy[d] = gz[d] = zero;
  for (int i = 0; i < W; ++i) {
    mpm_vl Y0[3], Y1[3], Y2[3];
    for (int d = 0; d < 3; ++d) Y0[d] = Y1[d] = Y2[d] = zero;
    for (int j = 0; j < W; ++j) {
      mpm_vl Z0[3], Z1[3];
      for (int d = 0; d < 3; ++d) Z0[d] = Z1[d] = zero;
      for (int k = 0; k < W; ++k) {
        const mpm_real *node = pad + (off + i * sx + j * sy + k) * stride;
        for (int d = 0; d < 3; ++d) {
          const mpm_vl u = mpm_vl_splat(node[d]);
          Z0[d] += s->w[2][k] * u;
          Z1[d] += s->dw[2][k] * u;
        }
      }
      for (int d = 0; d < 3; ++d) {
        Y0[d] += s->dw[1][j] * Z0[d];
        Y1[d] += s->w[1][j] * Z0[d];
        Y2[d] += s->w[1][j] * Z1[d];
      }
    }
    for (int d = 0; d < 3; ++d) {
      gx[d] += s->dw[0][i] * Y1[d];
      gy[d] += s->w[0][i] * Y0[d];
      gz[d] += s->w[0][i] * Y2[d];
    }
  }
  for (int d = 0; d < 3; ++d) {
    G[3 * d] = gx[d];
    G[3 * d + 1] = gy[d];
    G[3 * d + 2] = gz[d];
  }
}

#endif
