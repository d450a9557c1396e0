/* dense_grid.h - a full box of grid nodes: the reference implementation the sparse grid is
 * tested against, and the baseline of the benchmarks. Serial P2G in particle order, no
 * blocks, no colouring: as plain as a grid can be. Node (i, j, k) is DOF (i n[1] + j) n[2] + k
 * of its level; every node exists from the start. */
#ifndef MPM_GRID_DENSE_GRID_H
#define MPM_GRID_DENSE_GRID_H

#include "grid/block.h"

#include <stddef.h>

typedef struct mpm_dense_grid {
  int n[3];     /* nodes per axis */
  size_t count; /* n[0] n[1] n[2] */
} mpm_dense_grid;

#endif
