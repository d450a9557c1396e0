/* ghost_apic_lanes.h - the lane kernels' share of APIC across the levels of the multi-level grid
 * (adaptive/apic.c has the method; transfer.h, mpm_ghost_apic, the data).
 *
 * A boundary particle's stencil reaches ghosts whose rows have several real nodes. For it:
 *   P2G  the real nodes need C_p = B_p D_p^-1 with D_p = D~_p + sum_g w_gp S_g (D~_p the ghost
 *        level's diagonal, which the lanes divide by; S_g the ghost's spread). The lanes add
 *        m B D~^-1 (x_g - x_p) w_gp, so the batch's m B is replaced by m C D~: the lanes then add
 *        exactly m C (x_g - x_p) w_gp; each entry (a ghost of the cell's stencil) sums
 *        w_gp m_p C_p over the cell's particles, the ghosts' affine moments' terms;
 *   G2P  the lanes give sum_g w_gp v_g (x_g - x_p)^T, and B_p needs sum_g w_gp M_g besides (the
 *        ghosts' velocity moments).
 * The particles of one cell share its entries (stencil node, ghost), so both are lane-wise sums
 * over the cell's entries, from the weights the lanes computed for the transfer itself. D, its
 * inverse and C are in double lanes. */
#ifndef MPM_TRANSFER_GHOST_APIC_LANES_H
#define MPM_TRANSFER_GHOST_APIC_LANES_H

#include "transfer/transfer.h"
#include "transfer/transfer_lanes.h"

typedef double mpm_vd __attribute__((vector_size(MPM_LANES * sizeof(double))));

/* Stencil node (i, j, k) packed 4 bits each: its weight in double lanes from 1D weights w. */
MPM_ALWAYS_INLINE mpm_vd mpm_ghost_apic_weight(const mpm_vd w[3][MPM_STENCIL_MAX], uint32_t n) {
  return w[0][n & 15] * w[1][n >> 4 & 15] * w[2][n >> 8 & 15];
}

/* P2G of a batch of n boundary particles of cell c (lane stencil s, lane inputs mB = m B): mB
 * becomes m C D~, and sum_p w_ep m_p C_p is added to each entry's affine moment. The ghost
 * level's D~ per axis is the divisor of the lanes' APIC factors (transfer_lanes.h): dx^2 / 4 for
 * the quadratic B-spline, dx^2 / 3 for the cubic, sum_q w_q (q - f)^2 dx^2 for the others. A lane
 * whose D is singular (not met with uGIMP) brings no affine part. */
MPM_ALWAYS_INLINE void mpm_ghost_apic_p2g(const int W, const mpm_ghost_apic *ga,
                                          const mpm_kernel *k, uint32_t c, int n,
                                          const mpm_lane_stencil *s, mpm_vl mB[9]) {
  mpm_vd w[3][MPM_STENCIL_MAX], Dt[3];
  const double dx2 = (double)k->dx * (double)k->dx;
  for (int d = 0; d < 3; ++d) {
    mpm_vl sum = {0};
    for (int q = 0; q < W; ++q) {
      const mpm_vl r = (mpm_real)q - s->f[d];
      sum += s->w[d][q] * r * r;
    }
    if (k->kind == MPM_KERNEL_QUADRATIC) sum = mpm_vl_splat(R_(0.25));
    if (k->kind == MPM_KERNEL_CUBIC) sum = mpm_vl_splat(R_(1.0) / 3);
    Dt[d] = __builtin_convertvector(sum, mpm_vd) * dx2;
    for (int l = 0; l < MPM_LANES; ++l)
      for (int q = 0; q < MPM_STENCIL_MAX; ++q) w[d][q][l] = q < W ? (double)s->w[d][q][l] : 0;
  }
  /* D = D~ + sum_e w_e S_e (xx yy zz xy xz yz) */
  const mpm_vd zero = {0};
  mpm_vd D[6] = {Dt[0], Dt[1], Dt[2], zero, zero, zero};
  for (uint32_t e = ga->entry_start[c]; e < ga->entry_start[c + 1]; ++e) {
    const mpm_vd we = mpm_ghost_apic_weight(w, ga->entry[e].node);
    const mpm_real *S = ga->spread + 6 * (size_t)ga->entry[e].ghost;
    for (int u = 0; u < 6; ++u) D[u] += we * (double)S[u];
  }
  const mpm_vd xx = D[0], yy = D[1], zz = D[2], xy = D[3], xz = D[4], yz = D[5];
  /* the symmetric inverse by cofactors */
  const mpm_vd c00 = yy * zz - yz * yz, c01 = xz * yz - xy * zz, c02 = xy * yz - xz * yy,
               c11 = xx * zz - xz * xz, c12 = xy * xz - xx * yz, c22 = xx * yy - xy * xy;
  const mpm_vd det = xx * c00 + xy * c01 + xz * c02;
  mpm_vd inv_det;
  for (int l = 0; l < MPM_LANES; ++l) inv_det[l] = det[l] != 0 ? 1 / det[l] : 0;
  const mpm_vd Di[9] = {c00 * inv_det, c01 * inv_det, c02 * inv_det, c01 * inv_det, c11 * inv_det,
                        c12 * inv_det, c02 * inv_det, c12 * inv_det, c22 * inv_det};
  mpm_vd mb[9], mC[9], live = {0}; /* lanes >= n (padding) bring nothing, whatever their D */
  for (int l = 0; l < n; ++l) live[l] = 1;
  for (int q = 0; q < 9; ++q)
    for (int l = 0; l < MPM_LANES; ++l) mb[q][l] = (double)mB[q][l];
  for (int u = 0; u < 3; ++u)
    for (int v = 0; v < 3; ++v) {
      mC[3 * u + v] =
          (mb[3 * u] * Di[v] + mb[3 * u + 1] * Di[3 + v] + mb[3 * u + 2] * Di[6 + v]) * live;
      const mpm_vd scaled = mC[3 * u + v] * Dt[v]; /* the lanes divide by D~ */
      for (int l = 0; l < MPM_LANES; ++l) mB[3 * u + v][l] = (mpm_real)scaled[l];
    }
  /* the ghosts' affine moments: per entry the batch's sum_p w_ep m_p C_p, particle by particle
   * (9 components as 8 lanes and one) */
  typedef mpm_real sum8 __attribute__((vector_size(8 * sizeof(mpm_real))));
  sum8 c8[MPM_LANES];
  mpm_real c9[MPM_LANES];
  for (int l = 0; l < n; ++l) {
    for (int q = 0; q < 8; ++q) c8[l][q] = (mpm_real)mC[q][l];
    c9[l] = (mpm_real)mC[8][l];
  }
  for (uint32_t e = ga->entry_start[c]; e < ga->entry_start[c + 1]; ++e) {
    const mpm_vd we = mpm_ghost_apic_weight(w, ga->entry[e].node);
    mpm_real *A = ga->affine + 9 * (size_t)e;
    sum8 A8;
    __builtin_memcpy(&A8, A, sizeof A8);
    mpm_real A_8 = A[8];
    for (int l = 0; l < n; ++l) {
      const mpm_real wl = (mpm_real)we[l];
      A8 += wl * c8[l];
      A_8 += wl * c9[l];
    }
    __builtin_memcpy(A, &A8, sizeof A8);
    A[8] = A_8;
  }
}

/* G2P of a batch of cell c's boundary particles (lane stencil s): B += sum_e w_e M_e. */
MPM_ALWAYS_INLINE void mpm_ghost_apic_g2p(const int W, const mpm_ghost_apic *ga, uint32_t c,
                                          const mpm_lane_stencil *s, mpm_vl B[9]) {
  mpm_vd w[3][MPM_STENCIL_MAX], dB[9] = {{0}};
  for (int d = 0; d < 3; ++d)
    for (int l = 0; l < MPM_LANES; ++l)
      for (int q = 0; q < MPM_STENCIL_MAX; ++q) w[d][q][l] = q < W ? (double)s->w[d][q][l] : 0;
  for (uint32_t e = ga->entry_start[c]; e < ga->entry_start[c + 1]; ++e) {
    const mpm_vd we = mpm_ghost_apic_weight(w, ga->entry[e].node);
    const mpm_real *M = ga->moment + 9 * (size_t)ga->entry[e].ghost;
    for (int q = 0; q < 9; ++q) dB[q] += we * (double)M[q];
  }
  for (int q = 0; q < 9; ++q)
    for (int l = 0; l < MPM_LANES; ++l) B[q][l] += (mpm_real)dB[q][l];
}

#endif
