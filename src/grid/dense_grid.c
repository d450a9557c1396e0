/* dense_grid.c - a full box of nodes (see dense_grid.h). */
#include "grid/dense_grid.h"
#include "core/alloc.h"

#include <string.h>

int mpm_dense_grid_init(mpm_dense_grid *g, const int n[3]) {
  memset(g, 0, sizeof *g);
  for (int d = 0; d < 3; ++d) g->n[d] = n[d];
  g->count = (size_t)n[0] * (size_t)n[1] * (size_t)n[2];
  for (int c = 0; c < MPM_GRID_CHANNELS; ++c) {
    g->ch[c] = mpm_calloc(g->count, sizeof(mpm_real));
    if (!g->ch[c]) {
      mpm_dense_grid_free(g);
      return -1;
    }
  }
  return 0;
}

void mpm_dense_grid_free(mpm_dense_grid *g) {
  for (int c = 0; c < MPM_GRID_CHANNELS; ++c) mpm_free(g->ch[c]);
  memset(g, 0, sizeof *g);
}

void mpm_dense_grid_clear(mpm_dense_grid *g) {
  for (int c = 0; c < MPM_GRID_CHANNELS; ++c) memset(g->ch[c], 0, g->count * sizeof(mpm_real));
}
