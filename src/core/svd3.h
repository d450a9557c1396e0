/* svd3.h - singular value and polar decomposition of a 3x3 matrix.
 *
 * Method of McAdams, Selle, Tamstorf, Teran and Sifakis 2011, "Computing the singular value
 * decomposition of 3x3 matrices with minimal branching and elementary floating point
 * operations": Jacobi eigen-analysis of F^T F with a fixed number of sweeps, columns of F V
 * sorted by norm, Givens QR of F V. The sign convention is the one invertible elasticity needs
 * (Irving et al. 2004; Zhu et al. 2017 sec. 5.3): U and V are proper rotations and an
 * inverted F shows exactly one negative singular value, the last. Tested in tests/test_svd.c. */
#ifndef MPM_CORE_SVD3_H
#define MPM_CORE_SVD3_H

#include "core/real.h"

/* F = U diag(sigma) V^T (row-major 3x3 arrays, no aliasing) with det U = det V = +1 and
 * sigma[0] >= sigma[1] >= |sigma[2]|; sigma[2] < 0 exactly when det F < 0. Defined for every
 * finite F, including singular F and F = 0 (then U = V = I). Thread safe, no allocation. */
void mpm_svd3(const mpm_real F[9], mpm_real U[9], mpm_real sigma[3], mpm_real V[9]);

/* Polar decomposition F = R S with R = U V^T a proper rotation and S = V diag(sigma) V^T
 * symmetric (indefinite when F is inverted), from mpm_svd3. */
void mpm_polar3(const mpm_real F[9], mpm_real R[9], mpm_real S[9]);

/* mpm_svd3 of n matrices stored by component (F[c][i]: entry c of matrix i, likewise U, V and
 * sigma), computed MPM_LANES at a time (core/svd3_lanes.h). Agrees with mpm_svd3 to rounding.
 * The arrays need no alignment; outputs must not alias inputs. */
void mpm_svd3_batch(int n, const mpm_real *const F[9], mpm_real *const U[9],
                    mpm_real *const sigma[3], mpm_real *const V[9]);

#endif
