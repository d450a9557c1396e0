/* sym_eigen.h - eigen-decomposition of small symmetric matrices by cyclic Jacobi rotations
 * (Golub and Van Loan, sec. 8.5), in double: shape matching (analysis/rest_error.c) and the
 * quaternion average (core/quat.c) use it. */
#ifndef MPM_CORE_SYM_EIGEN_H
#define MPM_CORE_SYM_EIGEN_H

/* A = V diag(lambda) V^T for the symmetric n x n A (row-major, n in 1..4): the eigenvalues in
 * ascending order, V's columns the unit eigenvectors. */
void mpm_sym_eigen(int n, const double *A, double *lambda, double *V);

#endif
