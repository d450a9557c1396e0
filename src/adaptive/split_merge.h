/* split_merge.h - particle split and merge (Gao et al. sec. 7.2, after Yue et al. 2015).
 *
 * Split: a particle of type q becomes 8 of type q + 1 at the corners of a randomly rotated cube
 * around it; mass and volume are shared equally, F and the plastic state are copied. Merge:
 * particles of one type, body and material become one of type q - 1 at their centroid; mass and
 * volume are summed, the velocity is the mass-weighted mean, and F is rebuilt from the mean of
 * the singular values and the quaternion averages of U and V (Markley et al. 2007).
 *
 * APIC's affine moment B = C D (particles.h) is carried through both:
 *   split  the children keep the parent's velocity gradient C = B / D_parent: each takes the
 *          parent's affine velocity at its place, v_c = v + C r_c, and B_c = C D_child. Mass
 *          and momentum stay exact (the offsets r_c sum to zero); the kinetic energy does not
 *          grow (D_child + |r_c|^2 / 3 <= D_parent); angular momentum changes by
 *          m (D_child + h^2/3 - D_parent) (C - C^T)-axial, which is reported
 *   merge  the moment about the new centre: B = sum_j m_j (B_j + v_j (x_j - x)^T) / M, so that
 *          linear and angular momentum are both exact.
 * Without APIC the velocity is copied by a split and B stays zero. D here is the isotropic
 * mean of the transfer's D_p (for uGIMP on spacing dx with box L: dx^2/6 + L^2/12 per axis). */
#ifndef MPM_ADAPTIVE_SPLIT_MERGE_H
#define MPM_ADAPTIVE_SPLIT_MERGE_H

#include "mpm/mpm.h"
#include "core/particles.h"

/* How a split places and sets its children. */
typedef struct mpm_split_desc {
  double half_diagonal;     /* of the cube, m */
  double rotation[9];       /* the cube's orientation (a proper rotation, row-major) */
  int apic;                 /* carry the affine moment (else v copied, B left as it is) */
  double D_parent, D_child; /* mean D of the parent and of a child, m^2 (with apic) */
} mpm_split_desc;

/* Split particle i of p: it becomes child 0 in place, children 1..7 are appended with ids
 * *next_id, *next_id + 1, ... (advanced). Type level + 1. MPM_OK, or MPM_ERR_NOMEM when out of
 * memory (p is unchanged then). */
mpm_status mpm_split_particle(mpm_particles *p, size_t i, const mpm_split_desc *s,
                              uint32_t *next_id);

/* The mean isotropic D of uGIMP on a grid of spacing dx with box side L (per axis). */
static inline double mpm_ugimp_mean_D(double dx, double L) {
  return dx * dx / 6 + L * L / 12;
}

/* Merge the n particles idx[0..n) of p (one type, body and material; n >= 2) into particle
 * idx[0], whose type becomes level - 1. The others are left in place for the caller to remove
 * (their mass is set to 0). With apic the affine moment is carried (above). */
void mpm_merge_particles(mpm_particles *p, const uint32_t *idx, int n, int apic);

/* The deformation gradient that merging the n gradients F[k] (row-major) with weights w (NULL:
 * equal) gives: each F = U diag(sigma) V^T (core/svd3.h), every SVD's column signs aligned with
 * the first's (F is unchanged by flipping a pair of columns of U and V together), then
 * U_avg diag(sigma_avg) V_avg^T. */
void mpm_merge_F(int n, const double (*F)[9], const double *w, double out[9]);

/* The APIC angular momentum of particles idx[0..n) of p about the origin (Jiang et al. 2015:
 * sum m (x cross v + axial(B^T)) with axial(A)_a = eps_abc A_bc), in L. idx NULL: all. */
void mpm_particles_angular_momentum(const mpm_particles *p, const uint32_t *idx, size_t n,
                                    double L[3]);

#endif
