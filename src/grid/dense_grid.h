/* dense_grid.h - a full box of grid nodes: the reference implementation the sparse grid is
 * tested against, and the baseline of the benchmarks. Serial P2G in particle order, no
 * blocks, no colouring: as plain as a grid can be. */
#ifndef MPM_GRID_DENSE_GRID_H
#define MPM_GRID_DENSE_GRID_H

#include "grid/grid.h"

#include <stddef.h>

typedef struct mpm_dense_grid {
  int n[3];                        /* nodes per axis */
  size_t count;                    /* n[0] n[1] n[2] */
  mpm_real *ch[MPM_GRID_CHANNELS]; /* node (i,j,k) at (i n[1] + j) n[2] + k */
} mpm_dense_grid;

/* Allocate a grid of n[0] x n[1] x n[2] nodes; 0 or -1 on OOM. */
int mpm_dense_grid_init(mpm_dense_grid *g, const int n[3]);
void mpm_dense_grid_free(mpm_dense_grid *g);
void mpm_dense_grid_clear(mpm_dense_grid *g);

#endif
