/* hex.h - the trilinear hexahedron of a particle domain (Zhu et al. 2017, sec. 4).
 *
 * Corner alpha = i + 2 j + 4 k (i, j, k in {0, 1}) sits at the reference coordinate
 * xi = (2i - 1, 2j - 1, 2k - 1) of the cube [-1, 1]^3, and its FEM shape function is
 * N_alpha(xi) = (1 + xi_a x) (1 + eta_a y) (1 + zeta_a z) / 8. The same ordering is VTK's
 * VTK_VOXEL; VTK_HEXAHEDRON lists the corners 0 1 3 2 4 5 7 6 (MPM_HEX_VTK_ORDER). */
#ifndef MPM_DOMAIN_HEX_H
#define MPM_DOMAIN_HEX_H

#define MPM_HEX_CORNERS 8

static const int MPM_HEX_VTK_ORDER[MPM_HEX_CORNERS] = {0, 1, 3, 2, 4, 5, 7, 6};

/* Reference coordinate component d (0, 1, 2) of corner a: -1 or +1. */
static inline double mpm_hex_sign(int a, int d) {
  return ((a >> d) & 1) ? 1.0 : -1.0;
}

/* Shape functions N[8] at xi, and their derivatives dN[a][d] = dN_a / dxi_d. */
static inline void mpm_hex_shape(const double xi[3], double N[MPM_HEX_CORNERS],
                                 double dN[MPM_HEX_CORNERS][3]) {
  for (int a = 0; a < MPM_HEX_CORNERS; ++a) {
    double f[3], g[3];
    for (int d = 0; d < 3; ++d) {
      const double s = mpm_hex_sign(a, d);
      f[d] = 0.5 * (1 + s * xi[d]);
      g[d] = 0.5 * s;
    }
    N[a] = f[0] * f[1] * f[2];
    dN[a][0] = g[0] * f[1] * f[2];
    dN[a][1] = f[0] * g[1] * f[2];
    dN[a][2] = f[0] * f[1] * g[2];
  }
}

#endif
