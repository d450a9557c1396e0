/* grid.h - the grid interface: one level of grid nodes, whatever its variant.
 *
 * A grid level is topology and geometry: which nodes exist this step, their integer
 * coordinates, the level's origin and spacing dx. The values at its nodes (mass, velocities,
 * force) are not stored here but in the DOF set (grid/dofs.h), where the level's nodes are
 * DOFs dof_begin .. dof_begin + node_count. So one step, one explicit update and one solver
 * work on every level alike, and Gao et al.'s multi-level grid (sec. 5-6) will be a stack of
 * levels, each with its own origin and dx (dx_L = dx_0 / 2^L).
 *
 * Two variants fill the table of operations (mpm_grid_ops), PETSc style:
 *   sparse  paged 4x4x4-node blocks activated from particle positions (sparse_grid.h), the
 *           production grid;
 *   dense   a full box of nodes over the domain (dense_grid.h), the plain reference the tests
 *           compare the sparse grid with.
 * Both present their nodes as boxes (block.h): a sparse block is a 4x4x4 box, a dense grid
 * one box per x-slab. Transfers keep their variant-specific fast paths (transfer.h dispatches
 * on the variant); everything else sees only this interface. */
#ifndef MPM_GRID_GRID_H
#define MPM_GRID_GRID_H

#include "core/particles.h"
#include "grid/block.h"
#include "grid/dense_grid.h"
#include "grid/sparse_grid.h"
#include "interp/kernel.h"

typedef struct mpm_grid mpm_grid;

typedef enum mpm_grid_kind {
  MPM_GRID_SPARSE = 0, /* paged blocks activated from particles (the production grid) */
  MPM_GRID_DENSE = 1,  /* full box of nodes (reference implementation and baseline) */
} mpm_grid_kind;

/* What a variant remembers between lookups of one caller (the sparse grid: the blocks of the
 * last stencil's pad); one per thread, started with mpm_grid_cursor_init. */
typedef struct mpm_grid_cursor {
  int32_t key[3];
  int32_t blocks[8];
} mpm_grid_cursor;

static inline void mpm_grid_cursor_init(mpm_grid_cursor *c) {
  c->key[0] = c->key[1] = c->key[2] = INT32_MIN;
}

typedef struct mpm_grid_ops {
  const char *name;
  /* Make every node that the stencils of kernel k around the particles p touch part of the
   * level (sparse: sort p into owner blocks, activate their pads, colour them; dense: every node
   * already is). Nodes activated earlier in the step stay. Scratch comes from `scratch` (the
   * step's arena). MPM_OK, or MPM_ERR_NOMEM when out of memory. */
  mpm_status (*activate)(mpm_grid *g, const mpm_kernel *k, int material_count,
                         const mpm_particles *p, mpm_arena *scratch);
  /* Make the nodes of the stencils of kernel k at the points x[d][i], i < n, part of the level
   * (those with use[i] != 0; use NULL: all), as for carriers such as domain corners. Serial.
   * MPM_OK, or MPM_ERR_NOMEM when out of memory. */
  mpm_status (*activate_points)(mpm_grid *g, const mpm_kernel *k, size_t n,
                                const mpm_real *const x[3], const uint8_t *use);
  /* The level's nodes of the W^3 stencil nodes base + (i, j, k), 0 <= i, j, k < W, in (i, j, k)
   * order, and the stencil's scatter key (0 .. scatter_key_count) and colour (0..7): stencils
   * of one colour and different keys never share a node, so their scatters may run in
   * parallel (grid/embedding.h). Read-only: safe in parallel with one cursor per thread. MPM_OK,
   * or MPM_ERR_INVALID when a node is not part of the level. */
  mpm_status (*stencil_nodes)(const mpm_grid *g, const int32_t base[3], int W,
                              mpm_grid_cursor *cursor, uint32_t *nodes, int32_t *key,
                              uint8_t *colour);
  size_t (*scatter_key_count)(const mpm_grid *g);
  /* The order in which the last activation wants the particles visited (perm[j]: the particle
   * visited j-th; the caller may permute the particle arrays into it and reset it to the
   * identity), or NULL when the variant visits them in memory order. */
  uint32_t *(*particle_order)(mpm_grid *g);
  /* Nodes of the level now; they are DOFs dof_begin .. dof_begin + node_count(g). */
  size_t (*node_count)(const mpm_grid *g);
  /* The level's nodes as box_count(g) disjoint boxes covering them. */
  size_t (*box_count)(const mpm_grid *g);
  mpm_node_box (*box)(const mpm_grid *g, size_t b);
  /* Bytes held (not counting the values in the DOF set). */
  size_t (*bytes)(const mpm_grid *g);
  void (*free)(mpm_grid *g);
} mpm_grid_ops;

struct mpm_grid {
  const mpm_grid_ops *ops;
  mpm_grid_kind kind;
  int level;          /* 0: the coarsest */
  mpm_real origin[3]; /* position of node (0, 0, 0), m */
  mpm_real dx;        /* node spacing, m */
  size_t dof_begin;   /* the level's first DOF (set by mpm_dofs_add_grid) */
  union {
    mpm_sparse_grid sparse;
    mpm_dense_grid dense;
  } impl;
};

/* A sparse level at origin with spacing dx, no nodes yet. */
void mpm_grid_init_sparse(mpm_grid *g, int level, const mpm_real origin[3], mpm_real dx);
/* A dense level of n[0] x n[1] x n[2] nodes from origin. MPM_OK, or MPM_ERR_INVALID when a count
 * is not positive. */
mpm_status mpm_grid_init_dense(mpm_grid *g, int level, const mpm_real origin[3], mpm_real dx,
                               const int n[3]);

/* The paged blocks of a sparse level, or NULL for the dense reference: what the fast paths that
 * walk blocks ask for (the corners' transfer plan, the multigrid's assembly). */
static inline const mpm_sparse_grid *mpm_grid_paged(const mpm_grid *g) {
  return g->kind == MPM_GRID_SPARSE ? &g->impl.sparse : NULL;
}

static inline void mpm_grid_free(mpm_grid *g) {
  if (g->ops) g->ops->free(g);
  g->ops = NULL;
}

/* Position of node idx of the level, m: origin + dx idx, rounded as every user rounds it. */
static inline void mpm_grid_node_position(const mpm_grid *g, const int32_t idx[3], mpm_real x[3]) {
  for (int d = 0; d < 3; ++d) x[d] = g->origin[d] + (mpm_real)idx[d] * g->dx;
}

/* The values at one level's nodes: views into the DOF set, node n at index n of each array
 * (the arrays already start at the level's dof_begin). Fields the step does not use are NULL.
 *   mass  m_i
 *   v0    P2G accumulates the momentum sum w m v (APIC: + its affine part) here; the explicit
 *         update turns it into the velocity at the start of the step v^n (FLIP reads it)
 *   v     the velocity at the end of the step v^{n+1}
 *   f     the force, -sum V0 tau grad w (not used when P2G folds dt f into the momentum)
 *   vm    the velocity the particles move and deform by, where it is not v (the implicit step's
 *         Newmark scheme: (v^n + v^{n+1}) / 2); NULL: v */
typedef struct mpm_grid_values {
  mpm_real *mass;
  mpm_real *v0[3];
  mpm_real *v[3];
  mpm_real *f[3];
  mpm_real *vm[3];
} mpm_grid_values;

#endif
