/* transfer_core.h - the per-particle bodies of P2G and G2P, shared by the sparse and the dense
 * grid. A grid is seen through channel pointers already offset to the particle's base node and
 * the strides of its x and y axes (z is contiguous); the stencil width W is a compile-time
 * constant at every call site so the node loops unroll. Private to src/transfer. */
#ifndef MPM_TRANSFER_TRANSFER_CORE_H
#define MPM_TRANSFER_TRANSFER_CORE_H

#include "grid/block.h"
#include "interp/kernel.h"

/* The seven quantities P2G accumulates per node, as channel arrays: mass, momentum (the DOF
 * set's v0 field) and force. */
enum { MPM_P2G_MASS = 0, MPM_P2G_MOMENTUM = 1, MPM_P2G_FORCE = 4, MPM_P2G_CHANNELS = 7 };

/* One particle's contribution: mass, momentum m v w + (m B) D^{-1} (x_i - x_p) w (APIC, the
 * D^{-1}(x_i - x_p) w factor is the stencil's `a` vector), and force K grad w with
 * K = -V0 tau. mB = m B (row-major) or NULL for PIC/FLIP. */
MPM_ALWAYS_INLINE void mpm_p2g_particle(const int W, const mpm_stencil *s, mpm_real m,
                                        const mpm_real mv[3], const mpm_real *mB,
                                        const mpm_real K[9], mpm_real *const ch[MPM_P2G_CHANNELS],
                                        long sx, long sy) {
  for (int i = 0; i < W; ++i)
    for (int j = 0; j < W; ++j) {
      const mpm_real wij = s->w[0][i] * s->w[1][j];
      const mpm_real gx_ij = s->dw[0][i] * s->w[1][j], gy_ij = s->w[0][i] * s->dw[1][j];
      const mpm_real ax_ij = s->a[0][i] * s->w[1][j], ay_ij = s->w[0][i] * s->a[1][j];
      const long off = i * sx + j * sy;
      for (int k = 0; k < W; ++k) {
        const mpm_real wz = s->w[2][k];
        const mpm_real w = wij * wz;
        const mpm_real gx = gx_ij * wz, gy = gy_ij * wz, gz = wij * s->dw[2][k];
        mpm_real qx = w * mv[0], qy = w * mv[1], qz = w * mv[2];
        if (mB) {
          const mpm_real ax = ax_ij * wz, ay = ay_ij * wz, az = wij * s->a[2][k];
          qx += mB[0] * ax + mB[1] * ay + mB[2] * az;
          qy += mB[3] * ax + mB[4] * ay + mB[5] * az;
          qz += mB[6] * ax + mB[7] * ay + mB[8] * az;
        }
        const long n = off + k;
        ch[MPM_P2G_MASS][n] += w * m;
        ch[MPM_P2G_MOMENTUM + 0][n] += qx;
        ch[MPM_P2G_MOMENTUM + 1][n] += qy;
        ch[MPM_P2G_MOMENTUM + 2][n] += qz;
        ch[MPM_P2G_FORCE + 0][n] += K[0] * gx + K[1] * gy + K[2] * gz;
        ch[MPM_P2G_FORCE + 1][n] += K[3] * gx + K[4] * gy + K[5] * gz;
        ch[MPM_P2G_FORCE + 2][n] += K[6] * gx + K[7] * gy + K[8] * gz;
      }
    }
}

/* Gathered grid quantities at one particle. */
typedef struct mpm_g2p_gather {
  mpm_real v[3];    /* PIC velocity sum w v^{n+1} */
  mpm_real dv[3];   /* FLIP increment sum w (v^{n+1} - v^n) */
  mpm_real grad[9]; /* sum v^{n+1} grad w^T (with a motion field: sum v_m grad w^T) */
  mpm_real B[9];    /* APIC: B_p = sum w v^{n+1} (x_i - x_p)^T */
  mpm_real xv[3];   /* the velocity the particle moves by: v, or sum w v_m */
} mpm_g2p_gather;

/* f = distance of the particle from its base node in cells; dx the cell size. vn: the new
 * velocity v^{n+1} per axis, vo: the old one v^n (read for FLIP only), vm: NULL, or the motion
 * field (grid.h) that grad and xv are taken from, all offset to the base node. */
MPM_ALWAYS_INLINE void mpm_g2p_particle(const int W, const mpm_stencil *s, const mpm_real f[3],
                                        mpm_real dx, int flip, int apic,
                                        const mpm_real *const vn[3], const mpm_real *const vo[3],
                                        const mpm_real *const vm[3], long sx, long sy,
                                        mpm_g2p_gather *o) {
  mpm_real v0 = 0, v1 = 0, v2 = 0, d0 = 0, d1 = 0, d2 = 0;
  mpm_real G[9] = {0}, B[9] = {0}, X[3] = {0, 0, 0};
  const mpm_real *const *vg = vm ? vm : vn; /* what grad and xv read */
  for (int i = 0; i < W; ++i)
    for (int j = 0; j < W; ++j) {
      const mpm_real wij = s->w[0][i] * s->w[1][j];
      const mpm_real gx_ij = s->dw[0][i] * s->w[1][j], gy_ij = s->w[0][i] * s->dw[1][j];
      const mpm_real rx = ((mpm_real)i - f[0]) * dx, ry = ((mpm_real)j - f[1]) * dx;
      const long off = i * sx + j * sy;
      for (int k = 0; k < W; ++k) {
        const long n = off + k;
        const mpm_real wz = s->w[2][k];
        const mpm_real w = wij * wz;
        const mpm_real ux = vn[0][n], uy = vn[1][n], uz = vn[2][n];
        v0 += w * ux;
        v1 += w * uy;
        v2 += w * uz;
        if (flip) {
          d0 += w * (ux - vo[0][n]);
          d1 += w * (uy - vo[1][n]);
          d2 += w * (uz - vo[2][n]);
        }
        const mpm_real gx = gx_ij * wz, gy = gy_ij * wz, gz = wij * s->dw[2][k];
        const mpm_real mx = vg[0][n], my = vg[1][n], mz = vg[2][n];
        if (vm) {
          X[0] += w * mx;
          X[1] += w * my;
          X[2] += w * mz;
        }
        G[0] += mx * gx;
        G[1] += mx * gy;
        G[2] += mx * gz;
        G[3] += my * gx;
        G[4] += my * gy;
        G[5] += my * gz;
        G[6] += mz * gx;
        G[7] += mz * gy;
        G[8] += mz * gz;
        if (apic) {
          const mpm_real rz = ((mpm_real)k - f[2]) * dx;
          const mpm_real ax = w * rx, ay = w * ry, az = w * rz;
          B[0] += ux * ax;
          B[1] += ux * ay;
          B[2] += ux * az;
          B[3] += uy * ax;
          B[4] += uy * ay;
          B[5] += uy * az;
          B[6] += uz * ax;
          B[7] += uz * ay;
          B[8] += uz * az;
        }
      }
    }
  o->v[0] = v0;
  o->v[1] = v1;
  o->v[2] = v2;
  o->dv[0] = d0;
  o->dv[1] = d1;
  o->dv[2] = d2;
  for (int d = 0; d < 3; ++d) o->xv[d] = vm ? X[d] : o->v[d];
  for (int c = 0; c < 9; ++c) {
    o->grad[c] = G[c];
    o->B[c] = B[c];
  }
}

#endif
