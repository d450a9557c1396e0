/* kernel.h - particle-grid weight kernels with gradients, as 1D factors of a tensor stencil.
 *
 * Every kernel here is a tensor product of 1D weights, so a particle's stencil is described by
 * its base node and, per axis, up to 4 weights w, derivatives dw and APIC factors a:
 *   w_ip = wx[i] wy[j] wz[k],  grad w_ip = (dwx wy wz, wx dwy wz, wx wy dwz).
 *
 *  linear     trilinear hat N_i(x_p) (Gao eq. 2), 2 nodes per axis
 *  quadratic  quadratic B-spline, 3 nodes per axis
 *  cubic      cubic B-spline, 4 nodes per axis
 *  ugimp      undeformed GIMP (Gao eqs. 5-6): the hat averaged over the particle's box of side
 *             L_p <= 2 dx, in closed form. In 1D the average of a hat over [x - L/2, x + L/2] is
 *             a difference of the hat's antiderivative; the 3D weight of Gao sec. 6.2 is the
 *             product of three such factors (the box integral of a separable N_i is separable),
 *             so we never form the per-cell W(a..f) expression of sec. 6.2 explicitly.
 *             3 nodes per axis for L_p <= dx (with L_p = dx it equals the quadratic B-spline,
 *             Gao sec. 3.3); 4 for dx < L_p <= 2 dx, the box of a particle one level coarser
 *             than the level it transfers on (Gao sec. 6.1 on the multi-level grid).
 *
 * APIC (Jiang et al. 2015) needs D_p = sum_i w_ip (x_i - x_p)(x_i - x_p)^T. For tensor kernels
 * D_p is diagonal with 1D entries d = sum_i w_i (x_i - x_p)^2, so the APIC factor per node is
 * a_i = w_i (x_i - x_p) / d (exact for every kernel, which keeps angular momentum exact). The
 * B-splines have constant d (dx^2/4 quadratic, dx^2/3 cubic); uGIMP's varies and is summed. For
 * the linear kernel d = f(1-f) dx^2 vanishes on nodes, and a_i equals dw_i exactly, so dw is used.
 */
#ifndef MPM_INTERP_KERNEL_H
#define MPM_INTERP_KERNEL_H

#include "core/real.h"

typedef enum mpm_kernel_kind {
  MPM_KERNEL_LINEAR = 0,      /* trilinear hat (Gao eq. 2) */
  MPM_KERNEL_QUADRATIC = 1,   /* quadratic B-spline (Stomakhin et al. 2013) */
  MPM_KERNEL_CUBIC = 2,       /* cubic B-spline */
  MPM_KERNEL_UGIMP = 3,       /* undeformed GIMP, closed form (Gao eqs. 5-6, sec. 6.2) */
  MPM_KERNEL_UGIMP_WIDE = 4,  /* internal, no scene name: the uGIMP kernel mpm_kernel_make builds
                                for boxes wider than dx (4 nodes per axis) */
  MPM_KERNEL_UGIMP_PAIRED = 5 /* internal: uGIMP (box <= dx) from the even node at or below the
                                 base, 4 nodes per axis (mpm_kernel_paired) */
} mpm_kernel_kind;

#define MPM_STENCIL_MAX 4

typedef struct mpm_kernel {
  mpm_kernel_kind kind;
  int width;      /* nodes per axis: 2, 3 or 4 (mpm_width_index) */
  mpm_real shift; /* base = floor(x/dx - shift) */
  mpm_real dx, inv_dx;
  mpm_real half_len; /* uGIMP: L_p / (2 dx), in (0, 1]; above 1/2 the stencil is 4 wide */
} mpm_kernel;

/* 1D factors of one particle's stencil. */
typedef struct mpm_stencil {
  int base[3];
  mpm_real w[3][MPM_STENCIL_MAX];
  mpm_real dw[3][MPM_STENCIL_MAX]; /* d w / d x, 1/m */
  mpm_real a[3][MPM_STENCIL_MAX];  /* APIC factor w (x_i - x_p) / d, 1/m */
} mpm_stencil;

/* gimp_length: L_p for uGIMP (ignored otherwise), in (0, 2 dx]. */
mpm_kernel mpm_kernel_make(mpm_kernel_kind kind, mpm_real dx, mpm_real gimp_length);

/* The uGIMP kernel k (box <= dx) with its stencils taken from the even node at or below the
 * base, 4 nodes per axis: the same weights, the 4th node's zero. On the multi-level grid the
 * particles one level coarser than the grid they transfer on (Gao sec. 6.1) lie one per cell;
 * with bases paired, the 8 of a 2 x 2 x 2 block of cells share a stencil and fill the SIMD
 * lanes of one batch (transfer_lanes.h) instead of 8 batches of one lane each. Other kernels
 * are returned as they are. */
mpm_kernel mpm_kernel_paired(mpm_kernel k);

const char *mpm_kernel_name(mpm_kernel_kind kind);

/* ---- implementation (inline so that the transfer loops see through it) ---- */

/* uGIMP weight of an outer stencil node and its derivative with respect to the node distance
 * d in [1/2, 3/2] (cells), for a particle box of half width h <= 1/2 (Gao eq. 5 in 1D):
 * the hat 1 - d integrated over [d - h, d + h] / 2h. With x = 1 - d: w = x while the whole box
 * lies inside the hat's support (x >= h), else w = (x + h)^2 / 4h. Written so that a weight
 * near the edge of the support is the square of a small number, never a difference of
 * numbers near 1: the latter loses every digit in float and can turn a tiny weight negative,
 * which gives a node a tiny negative mass and an enormous velocity. */
static inline mpm_real mpm_ugimp_outer(mpm_real d, mpm_real h, mpm_real *dw_dd) {
  const mpm_real x = 1 - d;
  if (x >= h) {
    *dw_dd = -1;
    return x;
  }
  const mpm_real q = x + h > 0 ? x + h : 0;
  *dw_dd = -q / (2 * h);
  return q * q / (4 * h);
}

/* The wide uGIMP box, half width h in (1/2, 1] (cells): the weight of a node at distance d
 * in [1, 2) (an outer node) is (1 + h - d)^2 / 4h, or 0 past 1 + h; derivative in *dw_dd. */
static inline mpm_real mpm_ugimp_wide_outer(mpm_real d, mpm_real h, mpm_real *dw_dd) {
  const mpm_real x = 1 + h - d, q = x > 0 ? x : 0;
  *dw_dd = -q / (2 * h);
  return q * q / (4 * h);
}

/* ... and of a node at distance d in [0, 1] (an inner node): three pieces, by whether the box
 * holds the hat's peak (d < h) and reaches past its foot (d + h > 1):
 *   d >= h             (1 + h - d)^2 / 4h
 *   d < h, d + h <= 1  1 - (d^2 + h^2) / 2h
 *   d < h, d + h > 1   (1/2 - a - a^2/2) / 2h with a = d - h
 * (continuous where they meet: 1/4h at d = h). */
static inline mpm_real mpm_ugimp_wide_inner(mpm_real d, mpm_real h, mpm_real *dw_dd) {
  if (d >= h) return mpm_ugimp_wide_outer(d, h, dw_dd);
  if (d + h <= 1) {
    *dw_dd = -d / h;
    return 1 - (d * d + h * h) / (2 * h);
  }
  const mpm_real a = d - h;
  *dw_dd = -(1 + a) / (2 * h);
  return (R_(0.5) - a - R_(0.5) * a * a) / (2 * h);
}

/* APIC factor a_i = w_i (x_i - x_p) / sum_j w_j (x_j - x_p)^2 (see the header comment). */
static inline void mpm_apic_factors(const int n, const mpm_real *w, mpm_real f, mpm_real inv_dx,
                                    mpm_real *a) {
  mpm_real d = 0;
  for (int i = 0; i < n; ++i) {
    mpm_real r = (mpm_real)i - f;
    d += w[i] * r * r;
  }
  const mpm_real s = inv_dx / d;
  for (int i = 0; i < n; ++i) a[i] = w[i] * ((mpm_real)i - f) * s;
}

/* uGIMP's 3 nodes (Gao eqs. 5-6 in 1D) at distance f in [1/2, 3/2) cells from the first, box
 * half width h <= 1/2. The support |x_i - x_p| < dx + L_p/2 <= 1.5 dx covers three nodes; the
 * outer two in closed form, the middle one by partition of unity. */
static inline __attribute__((always_inline)) void
mpm_ugimp_1d(mpm_real h, mpm_real f, mpm_real inv_dx, mpm_real *w, mpm_real *dw, mpm_real *a) {
  mpm_real g0, g2;
  w[0] = mpm_ugimp_outer(f, h, &g0);
  w[2] = mpm_ugimp_outer(2 - f, h, &g2);
  w[1] = 1 - w[0] - w[2];
  dw[0] = g0 * inv_dx;  /* d(distance)/dx = +1 for node 0 */
  dw[2] = -g2 * inv_dx; /* and -1 for node 2 */
  dw[1] = -dw[0] - dw[2];
  mpm_apic_factors(3, w, f, inv_dx, a);
}

/* 1D weights for grid coordinate xg = (x - origin) / dx: base node, weights, d/dx and APIC
 * factors (arrays of kernel width). Inlined into the transfer loops. */
static inline __attribute__((always_inline)) int
mpm_kernel_1d(const mpm_kernel *k, mpm_real xg, mpm_real *w, mpm_real *dw, mpm_real *a) {
  const mpm_real inv_dx = k->inv_dx;
  const int base = (int)mpm_floor(xg - k->shift);
  const mpm_real f = xg - (mpm_real)base; /* distance from the base node, in cells */
  switch (k->kind) {
  default: /* MPM_KERNEL_LINEAR */
    w[0] = 1 - f;
    w[1] = f;
    dw[0] = -inv_dx;
    dw[1] = inv_dx;
    a[0] = dw[0];
    a[1] = dw[1];
    return base;
  case MPM_KERNEL_QUADRATIC: {
    /* f in [0.5, 1.5) */
    mpm_real t0 = R_(1.5) - f, t1 = f - 1, t2 = f - R_(0.5);
    w[0] = R_(0.5) * t0 * t0;
    w[1] = R_(0.75) - t1 * t1;
    w[2] = R_(0.5) * t2 * t2;
    dw[0] = -t0 * inv_dx;
    dw[1] = -2 * t1 * inv_dx;
    dw[2] = t2 * inv_dx;
    for (int i = 0; i < 3; ++i) a[i] = 4 * inv_dx * w[i] * ((mpm_real)i - f); /* D = dx^2/4 */
    break;
  }
  case MPM_KERNEL_CUBIC: {
    /* f in [1, 2): distances to nodes 0..3 are f, f-1, 2-f, 3-f */
    mpm_real d0 = f, d1 = f - 1, d2 = 2 - f, d3 = 3 - f;
    mpm_real u0 = 2 - d0, u3 = 2 - d3;
    w[0] = u0 * u0 * u0 / 6;
    w[1] = R_(0.5) * d1 * d1 * d1 - d1 * d1 + R_(2.0) / 3;
    w[2] = R_(0.5) * d2 * d2 * d2 - d2 * d2 + R_(2.0) / 3;
    w[3] = u3 * u3 * u3 / 6;
    dw[0] = -R_(0.5) * u0 * u0 * inv_dx;
    dw[1] = (R_(1.5) * d1 * d1 - 2 * d1) * inv_dx;
    dw[2] = -(R_(1.5) * d2 * d2 - 2 * d2) * inv_dx;
    dw[3] = R_(0.5) * u3 * u3 * inv_dx;
    for (int i = 0; i < 4; ++i) a[i] = 3 * inv_dx * w[i] * ((mpm_real)i - f); /* D = dx^2/3 */
    break;
  }
  case MPM_KERNEL_UGIMP_WIDE: {
    /* the wide box: f in [1, 2), nodes at distances f, f - 1, 2 - f, 3 - f; node 2 by
       partition of unity */
    const mpm_real h = k->half_len;
    mpm_real g0, g1, g3;
    w[0] = mpm_ugimp_wide_outer(f, h, &g0);
    w[1] = mpm_ugimp_wide_inner(f - 1, h, &g1);
    w[3] = mpm_ugimp_wide_outer(3 - f, h, &g3);
    w[2] = 1 - w[0] - w[1] - w[3];
    dw[0] = g0 * inv_dx; /* distance grows with x for nodes 0 and 1 */
    dw[1] = g1 * inv_dx;
    dw[3] = -g3 * inv_dx;
    dw[2] = -dw[0] - dw[1] - dw[3];
    mpm_apic_factors(4, w, f, inv_dx, a);
    break;
  }
  case MPM_KERNEL_UGIMP:
    mpm_ugimp_1d(k->half_len, f, inv_dx, w, dw, a);
    break;
  case MPM_KERNEL_UGIMP_PAIRED: {
    /* the base's own 3 nodes, then moved up one node when the base is odd */
    const int odd = base & 1;
    mpm_ugimp_1d(k->half_len, f, inv_dx, w + odd, dw + odd, a + odd);
    w[3 - 3 * odd] = dw[3 - 3 * odd] = a[3 - 3 * odd] = 0;
    return base - odd;
  }
  }
  return base;
}

/* ANDed with floor(x/dx - shift), the base node: the even node at or below for the paired
 * kernel (mpm_kernel_paired), the node itself for the others. */
static inline int mpm_kernel_base_mask(const mpm_kernel *k) {
  return k->kind == MPM_KERNEL_UGIMP_PAIRED ? ~1 : ~0;
}

/* The base node of the stencil at position x (relative to the grid origin, m) alone, as
 * mpm_kernel_stencil gives it: for sorting and activation, which need no weights. */
static inline __attribute__((always_inline)) void
mpm_kernel_base(const mpm_kernel *k, const mpm_real x[3], int base[3]) {
  const int pair = mpm_kernel_base_mask(k);
  for (int d = 0; d < 3; ++d) base[d] = (int)mpm_floor(x[d] * k->inv_dx - k->shift) & pair;
}

/* Full stencil of a particle at position x (relative to the grid origin, m). */
static inline __attribute__((always_inline)) void
mpm_kernel_stencil(const mpm_kernel *k, const mpm_real x[3], mpm_stencil *s) {
  for (int d = 0; d < 3; ++d)
    s->base[d] = mpm_kernel_1d(k, x[d] * k->inv_dx, s->w[d], s->dw[d], s->a[d]);
}

/* Where a stencil of `width` nodes per axis sits in the transfers' tables of specialized
 * variants (one entry per width 2, 3, 4). */
static inline int mpm_width_index(int width) {
  return width == 2 ? 0 : width == 3 ? 1 : 2;
}

#endif
