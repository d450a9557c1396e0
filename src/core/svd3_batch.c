/* svd3_batch.c - mpm_svd3 over arrays of matrices, MPM_SVD_GROUPS x MPM_NLANES at a time
 * (svd3_lanes.h). */
#include "core/svd3.h"
#include "core/svd3_lanes.h"

#ifndef MPM_SVD_GROUPS
#define MPM_SVD_GROUPS 4
#endif

void mpm_svd3_batch(int n, const mpm_real *const F[9], mpm_real *const U[9],
                    mpm_real *const sigma[3], mpm_real *const V[9]) {
  enum { G = MPM_SVD_GROUPS, W = MPM_SVD_GROUPS * MPM_NLANES };
  const unsigned fp_mode = mpm_ftz_begin();
  for (int i0 = 0; i0 < n; i0 += W) {
    const int m = n - i0 < W ? n - i0 : W;
    mpm_vn f[G][9], u[G][9], s[G][3], v[G][9];
    for (int g = 0; g < G; ++g)
      for (int c = 0; c < 9; ++c) {
        if (m == W) {
          __builtin_memcpy(&f[g][c], F[c] + i0 + g * MPM_NLANES, sizeof f[g][c]);
        } else { /* a partial batch: idle lanes hold the identity */
          f[g][c] = mpm_vn_splat(c % 4 == 0 ? 1 : 0);
          for (int l = 0; l < MPM_NLANES && g * MPM_NLANES + l < m; ++l)
            f[g][c][l] = F[c][i0 + g * MPM_NLANES + l];
        }
      }
    mpm_svd3_lanes(G, (const mpm_vn(*)[9])f, u, s, v);
    for (int g = 0; g < G; ++g) {
      const int j0 = i0 + g * MPM_NLANES;
      if (m == W) {
        for (int c = 0; c < 9; ++c) {
          __builtin_memcpy(U[c] + j0, &u[g][c], sizeof u[g][c]);
          __builtin_memcpy(V[c] + j0, &v[g][c], sizeof v[g][c]);
        }
        for (int c = 0; c < 3; ++c) __builtin_memcpy(sigma[c] + j0, &s[g][c], sizeof s[g][c]);
        continue;
      }
      for (int l = 0; l < MPM_NLANES && g * MPM_NLANES + l < m; ++l) {
        for (int c = 0; c < 9; ++c) {
          U[c][j0 + l] = u[g][c][l];
          V[c][j0 + l] = v[g][c][l];
        }
        for (int c = 0; c < 3; ++c) sigma[c][j0 + l] = s[g][c][l];
      }
    }
  }
  mpm_ftz_end(fp_mode);
}
