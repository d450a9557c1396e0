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

#endif
