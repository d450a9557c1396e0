/* weights.c - one particle's weights on the multi-level grid; see adaptive/weights.h. */
#include "adaptive/weights.h"

#include "interp/gimp.h"

int mpm_adaptive_weights(const mpm_refinement *r, const mpm_real x[3], mpm_real gimp_length,
                         int level, mpm_adaptive_weight *out, int max, int *used) {
  const mpm_real half = gimp_length / 2;
  if (level < 0) {
    mpm_real lo[3], hi[3];
    for (int d = 0; d < 3; ++d) {
      lo[d] = x[d] - half;
      hi[d] = x[d] + half;
    }
    level = mpm_refinement_finest_level_in(r, lo, hi);
  }
  if (used) *used = level;
  const mpm_real dx = mpm_refinement_dx(r, level), inv_dx = 1 / dx;
  int base[3], n[3];
  mpm_real w[3][MPM_GIMP_NODES_MAX], dw[3][MPM_GIMP_NODES_MAX];
  for (int d = 0; d < 3; ++d) {
    n[d] = mpm_gimp_1d((x[d] - r->origin[d]) * inv_dx, half * inv_dx, &base[d], w[d], dw[d]);
    if (n[d] < 0) return -1;
  }
  int count = 0;
  mpm_row_term row[MPM_ROW_MAX];
  for (int i = 0; i < n[0]; ++i)
    for (int j = 0; j < n[1]; ++j)
      for (int k = 0; k < n[2]; ++k) {
        const double wg = (double)w[0][i] * w[1][j] * w[2][k];
        const double g[3] = {(double)dw[0][i] * w[1][j] * w[2][k] * inv_dx,
                             (double)w[0][i] * dw[1][j] * w[2][k] * inv_dx,
                             (double)w[0][i] * w[1][j] * dw[2][k] * inv_dx};
        if (wg == 0 && g[0] == 0 && g[1] == 0 && g[2] == 0) continue;
        const int32_t idx[3] = {base[0] + i, base[1] + j, base[2] + k};
        const int m = mpm_refinement_node_row(r, level, idx, row, MPM_ROW_MAX);
        if (m < 0) return -1;
        for (int t = 0; t < m; ++t) {
          int e = 0;
          while (e < count && !(out[e].level == row[t].level && out[e].idx[0] == row[t].idx[0] &&
                                out[e].idx[1] == row[t].idx[1] && out[e].idx[2] == row[t].idx[2]))
            ++e;
          if (e == count) {
            if (count == max) return -1;
            out[e].level = row[t].level;
            for (int d = 0; d < 3; ++d) {
              out[e].idx[d] = row[t].idx[d];
              out[e].dw[d] = 0;
            }
            out[e].w = 0;
            ++count;
          }
          out[e].w += row[t].w * wg;
          for (int d = 0; d < 3; ++d) out[e].dw[d] += row[t].w * g[d];
        }
      }
  return count;
}
