/* quat.h - unit quaternions for rotations, and their average.
 *
 * q = (w, x, y, z) with w the scalar part; q and -q are the same rotation. The average is
 * Markley, Cheng, Crassidis and Oshman 2007 ("Averaging quaternions", J. Guidance, Control and
 * Dynamics 30(4)): the unit eigenvector of M = sum_i w_i q_i q_i^T of the largest eigenvalue,
 * which minimizes the weighted sum of squared Frobenius distances between the rotation
 * matrices and is blind to the signs of the inputs. Particle merging (Gao et al. sec. 7.2)
 * averages the U and V of the merged particles' SVDs with it. */
#ifndef MPM_CORE_QUAT_H
#define MPM_CORE_QUAT_H

/* The rotation matrix (row-major) of unit quaternion q. */
void mpm_quat_to_matrix(const double q[4], double R[9]);

/* The unit quaternion of rotation matrix R (Shepperd's method: the largest of the four
 * diagonal combinations is the pivot, so no division by a small number), with w >= 0. */
void mpm_quat_from_matrix(const double R[9], double q[4]);

/* The weighted average of n unit quaternions (weights > 0; NULL for equal weights), with the
 * sign that agrees with q[0] (q.q[0] >= 0). */
void mpm_quat_average(int n, const double (*q)[4], const double *w, double out[4]);

/* A uniformly distributed random rotation from three uniform numbers in [0, 1) (Shoemake 1992,
 * "Uniform random rotations", Graphics Gems III). */
void mpm_quat_uniform(const double u[3], double q[4]);

#endif
