/* intmath.h - integer arithmetic the C operators round the wrong way for lattices. */
#ifndef MPM_CORE_INTMATH_H
#define MPM_CORE_INTMATH_H

#include <stdint.h>

/* floor(a / b) for b > 0 (C's division truncates towards zero: a cell or box coordinate of a
 * negative position would be one too high) */
static inline int64_t mpm_floor_div(int32_t a, int32_t b) {
  return a >= 0 ? a / b : -((-(int64_t)a + b - 1) / b);
}

#endif
