/* block.h - the shape of a grid's nodes: sparse grids are made of 4x4x4-node blocks (SPGrid-like
 * pages of 64 nodes), and every grid presents its nodes as boxes (mpm_node_box) that the DOF
 * set (grid/dofs.h) and the explicit update iterate without knowing the grid's variant. */
#ifndef MPM_GRID_BLOCK_H
#define MPM_GRID_BLOCK_H

#include "core/real.h"

#include <stddef.h>
#include <stdint.h>

/* Sparse grid blocks are 4x4x4 nodes. */
#define MPM_BLOCK_BITS 2
#define MPM_BLOCK 4
#define MPM_BLOCK_NODES 64

/* A particle's stencil starts at its base node, which lies in its owner block, and reaches at
 * most MPM_STENCIL_MAX - 1 nodes forward: the owner block and its 7 forward neighbours cover
 * it, an 8x8x8 "pad" of nodes. P2G accumulates into a pad, then adds the pad to the 8 blocks. */
#define MPM_PAD 8
#define MPM_PAD_NODES 512

/* A box of nodes of one grid level: the nodes with integer coordinates lo + (a, b, c),
 * 0 <= a < n[0], 0 <= b < n[1], 0 <= c < n[2], which are the level's nodes
 * first + (a n[1] + b) n[2] + c. Node (i, j, k) sits at origin + dx (i, j, k). */
typedef struct mpm_node_box {
  size_t first;
  int32_t lo[3];
  int32_t n[3];
} mpm_node_box;

#endif
