/* rest_error.h - the rest-state error of Zhu et al. 2017 (sec. 7, Table 1): how far a body has
 * come back to its rest shape, rigid motion removed.
 *
 * Particles of the rest frame and of the final frame are matched by id. The rigid motion that
 * best maps the rest positions q onto the final ones p is found by shape matching (Mueller et
 * al. 2005, "Meshless deformations based on shape matching"): both clouds about their centres
 * of mass, A_pq = sum m (p - p_c)(q - q_c)^T, and the rotation R of A_pq's polar decomposition
 * (A_pq = U S V^T, R = U diag(1, 1, det(U V^T)) V^T: the nearest rotation, never a reflection).
 * The error is then
 *   mean over particles of |R (q - q_c) + p_c - p|, divided by the rest shape's bounding-box
 *   diagonal,
 * and the largest such distance over the same diagonal. Everything is computed in double. */
#ifndef MPM_ANALYSIS_REST_ERROR_H
#define MPM_ANALYSIS_REST_ERROR_H

#include "mpm/mpm.h"

#include <stddef.h>
#include <stdint.h>

typedef struct mpm_rest_error {
  double mean, max;      /* relative to the rest diagonal */
  double diagonal;       /* the rest shape's bounding-box diagonal, m */
  size_t matched;        /* particles found in both frames */
  double R[9];           /* the rotation removed (row-major) */
  double translation[3]; /* p_c - R q_c, m */
} mpm_rest_error;

/* One cloud: n positions x[i][0..2], ids, optional masses (NULL: equal). */
typedef struct mpm_point_cloud {
  size_t n;
  const double (*x)[3];
  const uint32_t *id;
  const double *mass;
} mpm_point_cloud;

/* The error of `final` against `rest` into *out. MPM_OK; MPM_ERR_INVALID when no particle is in
 * both (or the rest shape has no extent); MPM_ERR_NOMEM when out of memory. Ids must be unique
 * per cloud. */
mpm_status mpm_rest_error_compute(const mpm_point_cloud *rest, const mpm_point_cloud *final,
                                  mpm_rest_error *out);

/* The nearest rotation to A (row-major): the orthogonal factor of its polar decomposition with
 * the reflection fix. A singular A of rank 2 still gives a rotation. */
void mpm_nearest_rotation(const double A[9], double R[9]);

#endif
