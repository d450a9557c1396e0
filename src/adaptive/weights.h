/* adaptive/weights.h - a particle's GIMP weights over the real nodes of the multi-level grid,
 * w_ip = sum_g w_gp E_gi (Gao et al. eq. 15), evaluated directly, one particle at a time.
 *
 * The step's transfers never form this list: they transfer on one uniform level and let the
 * embedding operator carry ghost values to real nodes (Gao sec. 6.1, Fig. 10). This is the
 * plain statement of what they compute, for tests and for the few callers that need one
 * particle's weights (a probe, a diagnostic): the finest level whose leaves meet the particle's
 * box, the box-averaged hats there (interp/gimp.h), and each node's embedding row
 * (adaptive/refinement.h) summed per real node. */
#ifndef MPM_ADAPTIVE_WEIGHTS_H
#define MPM_ADAPTIVE_WEIGHTS_H

#include "adaptive/refinement.h"

/* One real node's weight and gradient for a particle. */
typedef struct mpm_adaptive_weight {
  int32_t idx[3];
  int32_t level;
  double w;
  double dw[3]; /* 1/m */
} mpm_adaptive_weight;

/* Weights of a particle at x (m) with box side gimp_length (m) on the real nodes, transferred
 * at `level` (-1: the finest level its box meets, which is exact; a finer level gives the same
 * weights, a coarser one does not). Count, or -1 past max entries or when the box is wider than
 * interp/gimp.h handles. The level used in *used. */
int mpm_adaptive_weights(const mpm_refinement *r, const mpm_real x[3], mpm_real gimp_length,
                         int level, mpm_adaptive_weight *out, int max, int *used);

#endif
