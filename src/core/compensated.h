/* compensated.h - a position advanced by small moves without losing them to rounding.
 *
 * A float position x that takes moves much smaller than its spacing rounds each one to a
 * multiple of the spacing: a body drifting slowly moves farther or less far than its velocity
 * says, and differently on either side of a power of two (issue 13). Summed with compensation
 * (Knuth's TwoSum), the rounding error of each sum is kept in a remainder and added to the next
 * move, so the sum of the moves is exact to the remainder's precision. Material points
 * (transfer/g2p.c) and domain corners (domain/domain_transfer.c) move this way. */
#ifndef MPM_CORE_COMPENSATED_H
#define MPM_CORE_COMPENSATED_H

#include "core/lanes.h"
#include "core/real.h"

/* x + move with *rem (what earlier sums lost) added, held in [lo, hi]; *rem becomes what this
 * sum lost (0 when held at a bound: exact there). */
static inline mpm_real mpm_compensated_move(mpm_real x, mpm_real move, mpm_real lo, mpm_real hi,
                                            mpm_real *rem) {
  const mpm_real y = move + *rem;
  mpm_real t = x + y;
  const mpm_real yb = t - x;
  mpm_real lost = (x - (t - yb)) + (y - yb);
  if (t < lo || t > hi) {
    t = t < lo ? lo : hi;
    lost = 0;
  }
  *rem = lost;
  return t;
}

/* mpm_compensated_move for MPM_LANES positions at once, the same operations lane by lane: bit
 * for bit the scalar one's results (the material points' and the corners' lane paths). */
static inline mpm_vl mpm_compensated_move_lanes(mpm_vl x, mpm_vl move, mpm_real lo, mpm_real hi,
                                                mpm_vl *rem) {
  const mpm_vl y = move + *rem;
  mpm_vl t = x + y;
  const mpm_vl yb = t - x;
  mpm_vl lost = (x - (t - yb)) + (y - yb);
  const mpm_vl vlo = mpm_vl_splat(lo), vhi = mpm_vl_splat(hi);
  const mpm_vl_index below = t < vlo, out = below | (t > vhi);
  t = mpm_vl_select(out, mpm_vl_select(below, vlo, vhi), t);
  *rem = mpm_vl_select(out, mpm_vl_splat(0), lost);
  return t;
}

#endif
