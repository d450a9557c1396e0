/* grid.h - what every grid stores per node: the channels of one explicit step.
 *
 * P2G accumulates mass, momentum (m v) and force; the grid update turns them into the old
 * velocity v^n (kept for FLIP, Gao sec. 3.2 step 6) and the new velocity v^{n+1}, stored back
 * into the momentum and force channels respectively so that no extra memory is needed. */
#ifndef MPM_GRID_GRID_H
#define MPM_GRID_GRID_H

#include "core/real.h"

enum {
  MPM_CH_MASS = 0,
  MPM_CH_MV = 1, /* momentum x,y,z; after the grid update: old velocity v^n */
  MPM_CH_F = 4,  /* force x,y,z; after the grid update: new velocity v^{n+1} */
  MPM_GRID_CHANNELS = 7
};
#define MPM_CH_VOLD MPM_CH_MV
#define MPM_CH_VNEW MPM_CH_F

/* Sparse grid blocks are 4x4x4 nodes (SPGrid-like pages of 64 nodes per channel). */
#define MPM_BLOCK_BITS 2
#define MPM_BLOCK 4
#define MPM_BLOCK_NODES 64

/* A particle's stencil starts at its base node, which lies in its owner block, and reaches at
 * most MPM_STENCIL_MAX - 1 nodes forward: the owner block and its 7 forward neighbours cover
 * it, an 8x8x8 "pad" of nodes. P2G accumulates into a pad, then adds the pad to the 8 blocks. */
#define MPM_PAD 8
#define MPM_PAD_NODES 512

typedef struct mpm_grid_block {
  mpm_real ch[MPM_GRID_CHANNELS][MPM_BLOCK_NODES];
} mpm_grid_block;

#endif
