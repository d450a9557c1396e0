/* transfer_simd.h - the sparse grid's P2G and G2P bodies, vectorized along z rows.
 *
 * Every kernel is a tensor product, so what a particle adds to node (i,j,k) of a channel is
 *     val(i,j,k) = wz_k (wy_j X_i + wx_i Y_j) + wx_i wy_j Z_k
 * for per-axis coefficient arrays X, Y, Z (for the force f_d = sum_e K_de grad_e w:
 * X = K_d0 dwx, Y = K_d1 dwy, Z = K_d2 dwz; for the APIC momentum w m v + m B D^{-1}(x_i - x_p) w
 * the same shape with the a factors; the mass has only X). A z row of the 8x8x8 pad is
 * contiguous, so each (i,j) row is one 4-wide vector operation (the stencil is at most 4 wide;
 * unused lanes carry zero weight and land inside the pad). G2P contracts rows the same way and
 * sums lanes once per output. This is the regularity Gao et al. 2017 (sec. 6.2) exploit.
 *
 * Written with GCC/Clang vector extensions, not intrinsics: the compiler maps them to SSE/AVX
 * (or splits them), and the plain scalar bodies in transfer_core.h - used by the dense
 * reference grid - are what the tests compare against. */
#ifndef MPM_TRANSFER_TRANSFER_SIMD_H
#define MPM_TRANSFER_TRANSFER_SIMD_H

#include "transfer/transfer_core.h"

typedef mpm_real mpm_v4 __attribute__((vector_size(4 * sizeof(mpm_real))));

MPM_ALWAYS_INLINE mpm_v4 mpm_v4_load(const mpm_real *p) {
  mpm_v4 v;
  __builtin_memcpy(&v, p, sizeof v);
  return v;
}
MPM_ALWAYS_INLINE void mpm_v4_store(mpm_real *p, mpm_v4 v) { __builtin_memcpy(p, &v, sizeof v); }
MPM_ALWAYS_INLINE mpm_real mpm_v4_sum(mpm_v4 v) { return (v[0] + v[1]) + (v[2] + v[3]); }

/* The z factors of a stencil as 4-lane vectors (zero beyond the width). */
MPM_ALWAYS_INLINE mpm_v4 mpm_v4_from(const int W, const mpm_real *a) {
  mpm_v4 v = {0, 0, 0, 0};
  for (int k = 0; k < W; ++k) v[k] = a[k];
  return v;
}

/* P2G of one particle. ch[] point at the particle's base node in the pad (z contiguous);
 * sx, sy the x and y strides. fused = 1 (APIC): momentum and dt * force go into the momentum
 * channel together (the grid update only needs their sum), mB = m B; fused = 0 (PIC/FLIP):
 * momentum m v and force K grad w in their own channels. dtK = dt K when fused, else K. */
MPM_ALWAYS_INLINE void mpm_p2g_particle_v4(const int W, const mpm_stencil *s, mpm_real m,
                                           const mpm_real mv[3], const mpm_real mB[9],
                                           const mpm_real dtK[9], const int fused,
                                           mpm_real *const ch[MPM_GRID_CHANNELS], long sx,
                                           long sy) {
  const mpm_v4 WZ = mpm_v4_from(W, s->w[2]), DZ = mpm_v4_from(W, s->dw[2]);
  const mpm_v4 AZ = mpm_v4_from(W, s->a[2]);
  /* coefficient arrays: channel c of the momentum (or p = m v + dt f when fused) and force */
  mpm_real PX[3][MPM_STENCIL_MAX], PY[3][MPM_STENCIL_MAX];
  mpm_real FX[3][MPM_STENCIL_MAX], FY[3][MPM_STENCIL_MAX];
  mpm_v4 PZ[3], FZ[3];
  for (int d = 0; d < 3; ++d) {
    const mpm_real *B = mB + 3 * d, *K = dtK + 3 * d;
    for (int i = 0; i < W; ++i) {
      if (fused) {
        PX[d][i] = mv[d] * s->w[0][i] + B[0] * s->a[0][i] + K[0] * s->dw[0][i];
        PY[d][i] = B[1] * s->a[1][i] + K[1] * s->dw[1][i];
      } else {
        PX[d][i] = mv[d] * s->w[0][i];
        FX[d][i] = K[0] * s->dw[0][i];
        FY[d][i] = K[1] * s->dw[1][i];
      }
    }
    if (fused) {
      PZ[d] = B[2] * AZ + K[2] * DZ;
    } else {
      FZ[d] = K[2] * DZ;
    }
  }
  for (int i = 0; i < W; ++i) {
    const mpm_real wx = s->w[0][i];
    const mpm_real mwx = m * wx;
    for (int j = 0; j < W; ++j) {
      const mpm_real wy = s->w[1][j], wxy = wx * wy;
      const long off = i * sx + j * sy;
      mpm_real *row = ch[MPM_CH_MASS] + off;
      mpm_v4_store(row, mpm_v4_load(row) + (mwx * wy) * WZ);
      for (int d = 0; d < 3; ++d) {
        mpm_real *prow = ch[MPM_CH_MV + d] + off;
        const mpm_real py = fused ? PY[d][j] : 0;
        mpm_v4 pv = (wy * PX[d][i] + wx * py) * WZ;
        if (fused) pv += wxy * PZ[d];
        mpm_v4_store(prow, mpm_v4_load(prow) + pv);
        if (!fused) {
          mpm_real *frow = ch[MPM_CH_F + d] + off;
          mpm_v4 fv = (wy * FX[d][i] + wx * FY[d][j]) * WZ + wxy * FZ[d];
          mpm_v4_store(frow, mpm_v4_load(frow) + fv);
        }
      }
    }
  }
}

/* G2P of one particle; same view of the grid as mpm_p2g_particle_v4 (read-only). */
MPM_ALWAYS_INLINE void mpm_g2p_particle_v4(const int W, const mpm_stencil *s, const mpm_real f[3],
                                           mpm_real dx, const int flip, const int apic,
                                           const mpm_real *const ch[MPM_GRID_CHANNELS], long sx,
                                           long sy, mpm_g2p_gather *o) {
  const mpm_v4 WZ = mpm_v4_from(W, s->w[2]), DZ = mpm_v4_from(W, s->dw[2]);
  mpm_v4 RZ = {0, 0, 0, 0};
  mpm_real rwx[MPM_STENCIL_MAX], rwy[MPM_STENCIL_MAX];
  for (int k = 0; k < W; ++k) {
    RZ[k] = s->w[2][k] * ((mpm_real)k - f[2]) * dx;
    rwx[k] = s->w[0][k] * ((mpm_real)k - f[0]) * dx;
    rwy[k] = s->w[1][k] * ((mpm_real)k - f[1]) * dx;
  }
  for (int d = 0; d < 3; ++d) {
    const mpm_real *vn = ch[MPM_CH_VNEW + d];
    const mpm_real *vo = flip ? ch[MPM_CH_VOLD + d] : NULL;
    mpm_v4 S1 = {0, 0, 0, 0}, S2 = S1, S3 = S1, S4 = S1, S5 = S1, SD = S1;
    for (int i = 0; i < W; ++i) {
      mpm_v4 T1 = {0, 0, 0, 0}, T2 = T1, T3 = T1, TD = T1;
      for (int j = 0; j < W; ++j) {
        const long off = i * sx + j * sy;
        const mpm_v4 R = mpm_v4_load(vn + off);
        T1 += s->w[1][j] * R;
        T2 += s->dw[1][j] * R;
        if (apic) T3 += rwy[j] * R;
        if (flip) TD += s->w[1][j] * (R - mpm_v4_load(vo + off));
      }
      S1 += s->w[0][i] * T1;
      S2 += s->dw[0][i] * T1;
      S3 += s->w[0][i] * T2;
      if (apic) {
        S4 += rwx[i] * T1;
        S5 += s->w[0][i] * T3;
      }
      if (flip) SD += s->w[0][i] * TD;
    }
    o->v[d] = mpm_v4_sum(S1 * WZ);
    o->grad[3 * d + 0] = mpm_v4_sum(S2 * WZ);
    o->grad[3 * d + 1] = mpm_v4_sum(S3 * WZ);
    o->grad[3 * d + 2] = mpm_v4_sum(S1 * DZ);
    if (apic) {
      o->B[3 * d + 0] = mpm_v4_sum(S4 * WZ);
      o->B[3 * d + 1] = mpm_v4_sum(S5 * WZ);
      o->B[3 * d + 2] = mpm_v4_sum(S1 * RZ);
    } else {
      o->B[3 * d + 0] = o->B[3 * d + 1] = o->B[3 * d + 2] = 0;
    }
    o->dv[d] = flip ? mpm_v4_sum(SD * WZ) : 0;
  }
}

#endif
