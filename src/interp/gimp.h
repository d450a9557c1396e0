/* gimp.h - uGIMP weights of a particle box of any size on a uniform level (Gao et al. eqs. 4-6).
 *
 * kernel.h's ugimp kernel needs L_p <= dx (3 nodes per axis). On the multi-level grid a
 * particle transfers on the finest level its box Omega_p meets (Gao sec. 6.1), which may be
 * finer than the particle's own type: then L_p = 2^k dx_level and the box covers more cells.
 * The 1D weight is the hat averaged over the box,
 *   w_i = 1 / (2a) * integral_{x - a}^{x + a} hat(t - i) dt   (node units, half width a),
 * and its derivative (hat(x + a - i) - hat(x - a - i)) / (2a). Each piece of the integral is
 * written as a product (hi - lo)(2 +- (hi + lo)) / 2, never a difference of numbers near one,
 * so small weights keep their digits (as kernel.h's mpm_ugimp_outer does). */
#ifndef MPM_INTERP_GIMP_H
#define MPM_INTERP_GIMP_H

#include "core/real.h"

/* Nodes per axis: a box of half width a (node units) meets at most 2a + 2 nodes, so boxes up to
 * 16 cells wide (a particle four levels coarser than the level it transfers on). */
#define MPM_GIMP_NODES_MAX 18

static inline mpm_real mpm_gimp_hat(mpm_real u) {
  const mpm_real a = mpm_fabs(u);
  return a < 1 ? 1 - a : 0;
}

/* The integral of the hat over [u0, u1], u0 <= u1. */
static inline mpm_real mpm_gimp_hat_integral(mpm_real u0, mpm_real u1) {
  mpm_real s = 0;
  mpm_real lo = u0 > -1 ? u0 : -1, hi = u1 < 0 ? u1 : 0;
  if (hi > lo) s += (hi - lo) * (2 + hi + lo) / 2;
  lo = u0 > 0 ? u0 : 0;
  hi = u1 < 1 ? u1 : 1;
  if (hi > lo) s += (hi - lo) * (2 - hi - lo) / 2;
  return s;
}

/* 1D weights of a box of half width a (node units, 0 < a <= (MPM_GIMP_NODES_MAX - 2) / 2) around
 * xg (node units): nodes *base .. *base + n - 1, weights w and d w / d xg (per node unit: the
 * caller multiplies by 1/dx). Returns n, or -1 when the box is too wide for MPM_GIMP_NODES_MAX. The
 * largest weight is set to one minus the others (and its derivative to minus theirs), so that the
 * weights sum to one in any precision. */
static inline int mpm_gimp_1d(mpm_real xg, mpm_real a, int *base, mpm_real *w, mpm_real *dw) {
  const int b = (int)mpm_floor(xg - a);
  int n = (int)mpm_floor(xg + a) - b + 2;
  if (n > MPM_GIMP_NODES_MAX) return -1;
  const mpm_real inv2a = 1 / (2 * a);
  int big = 0;
  for (int i = 0; i < n; ++i) {
    const mpm_real u0 = xg - a - (mpm_real)(b + i), u1 = xg + a - (mpm_real)(b + i);
    w[i] = mpm_gimp_hat_integral(u0, u1) * inv2a;
    dw[i] = (mpm_gimp_hat(u1) - mpm_gimp_hat(u0)) * inv2a;
    if (w[i] > w[big]) big = i;
  }
  mpm_real sw = 0, sd = 0;
  for (int i = 0; i < n; ++i)
    if (i != big) {
      sw += w[i];
      sd += dw[i];
    }
  w[big] = 1 - sw;
  dw[big] = -sd;
  *base = b;
  return n;
}

#endif
