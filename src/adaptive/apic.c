/* apic.c - APIC with exact angular momentum across the levels of the multi-level grid
 * (docs/adaptive-grid.md, "APIC with exact angular momentum across levels"; Gao et al. list it
 * as future work).
 *
 * A particle whose stencil reaches a ghost with a row of several real nodes (a T-junction or a
 * refined node inside a coarser leaf) is a *boundary particle*. For it the lane kernels alone are
 * not the real-node APIC transfer:
 *   P2G  the real nodes need C_p = B_p D_p^-1 with D_p = D~_p + sum_g w_gp S_g (D~_p the ghost
 *        level's, diagonal, which the lanes divide by), and at each ghost the affine moment
 *        A_g = sum_p w_gp m_p C_p, which mpm_adaptive_grid_scatter_apic carries to the real nodes
 *        as m_p C_p (x_i - x_g);
 *   G2P  the lanes give sum_g w_gp v_g (x_g - x_p)^T, and B_p needs sum_g w_gp M_g besides, the
 *        ghosts' velocity moments (mpm_adaptive_grid_gather_moments).
 * The particles' part runs inside the P2G and G2P lanes, from the weights they compute anyway
 * (transfer/ghost_apic_lanes.h). Here: the boundary cells (occupied cells of a transfer grid
 * whose stencils reach such ghosts: their particles share the stencil) with their lists of
 * (stencil node, ghost), the lanes' view of them, and the ghosts' sums. Each A_g is summed by one
 * thread over its contributions in boundary-particle order (the entries transposed by ghost), so
 * results do not depend on the thread count. */
#include "adaptive/adaptive.h"

#include "core/alloc.h"
#include "core/parallel.h"

#include <assert.h>
#include <string.h>

/* The cells' entries by ghost: a counting sort, stable (cell order within a ghost), with the
 * entries in one chunk per thread and a histogram per chunk, so the result is the serial one for
 * any thread count. */
#define TRANSPOSE_CHUNKS_MAX 64
static int transpose_by_ghost(mpm_adaptive *a, size_t ng, mpm_arena *scratch) {
  const size_t ne = a->cell_ghost_count;
  if (mpm_grow((void **)&a->ghost_start, &a->ghost_start_capacity, ng + 2,
               sizeof *a->ghost_start) ||
      mpm_grow((void **)&a->ghost_entry, &a->ghost_entry_capacity, ne + 1, sizeof *a->ghost_entry))
    return -1;
  const int threads = mpm_thread_count();
  const int nch = ne < 4096 ? 1 : threads < TRANSPOSE_CHUNKS_MAX ? threads : TRANSPOSE_CHUNKS_MAX;
  uint32_t *hist = mpm_arena_alloc(scratch, ((size_t)nch * ng + 1) * sizeof *hist);
  if (!hist) return -1;
  const mpm_stencil_ghost *cg = a->cell_ghost;
#pragma omp parallel for schedule(static, 1) if (nch > 1)
  for (int t = 0; t < nch; ++t) {
    uint32_t *h = hist + (size_t)t * ng;
    memset(h, 0, ng * sizeof *h);
    for (size_t e = ne * (size_t)t / (size_t)nch; e < ne * (size_t)(t + 1) / (size_t)nch; ++e)
      ++h[cg[e].ghost];
  }
  uint32_t at = 0; /* ghost by ghost, chunk by chunk: where each chunk's entries of g go */
  for (size_t g = 0; g < ng; ++g) {
    a->ghost_start[g] = at;
    for (int t = 0; t < nch; ++t) {
      const uint32_t c = hist[(size_t)t * ng + g];
      hist[(size_t)t * ng + g] = at;
      at += c;
    }
  }
  a->ghost_start[ng] = at;
#pragma omp parallel for schedule(static, 1) if (nch > 1)
  for (int t = 0; t < nch; ++t) {
    uint32_t *h = hist + (size_t)t * ng;
    for (size_t e = ne * (size_t)t / (size_t)nch; e < ne * (size_t)(t + 1) / (size_t)nch; ++e)
      a->ghost_entry[h[cg[e].ghost]++] = (uint32_t)e;
  }
  return 0;
}

/* The boundary cells of owner block b of transfer grid t (its occupied cells whose stencils
 * reach a ghost of several real nodes), in cell order: with count, only their numbers (cells,
 * entries, particles) in count[0..2]; with first, written from those indices on (cell c's
 * entries run from cell[c] to the next cell's first, cell[c + 1], which the caller sets after
 * the last cell), and the block's cells in the lanes' map (cell_of). */
static void boundary_block(mpm_adaptive *a, int t, const uint64_t reach[MPM_BLOCK_NODES][8],
                           size_t b, uint32_t count[3], uint32_t first[3]) {
  const mpm_transfer_grid *tg = &a->tgrid[t];
  const mpm_grid *g = mpm_adaptive_grid_at(&a->grid, tg->G);
  const mpm_sparse_grid *sg = &g->impl.sparse;
  const int W = tg->kernel.width;
  const size_t nmat = (size_t)sg->material_count;
  const uint64_t *multi_at = a->block_multi + g->dof_begin / MPM_BLOCK_NODES;
  uint32_t cells = 0, entries = 0, particles = 0;
  if (count) count[0] = count[1] = count[2] = 0;
  uint32_t *cell_of = a->cell_of + a->cell_map_begin[t];
  if (!count)
    for (size_t q = b * nmat * MPM_BLOCK_NODES; q < (b + 1) * nmat * MPM_BLOCK_NODES; ++q)
      cell_of[q] = MPM_NOT_BOUNDARY;
  /* a stencil of the block reaches only its pad: the block and 7 neighbours */
  uint64_t pad[8], near = 0;
  for (int o = 0; o < 8; ++o) near |= pad[o] = multi_at[sg->neighbor[b][o]];
  if (!near) return;
  for (int c = 0; c < MPM_BLOCK_NODES; ++c) {
    uint64_t hit = 0;
    int reached = 0;
    for (int o = 0; o < 8; ++o) {
      const uint64_t h = pad[o] & reach[c][o];
      hit |= h;
      reached += __builtin_popcountll(h);
    }
    if (!hit) continue; /* its stencil reaches no such ghost */
    const size_t q0 = (b * nmat) * MPM_BLOCK_NODES + (size_t)c;
    uint32_t held = 0;
    for (size_t m = 0; m < nmat; ++m)
      held +=
          sg->cell_start[q0 + m * MPM_BLOCK_NODES + 1] - sg->cell_start[q0 + m * MPM_BLOCK_NODES];
    if (!held) continue;
    if (count) {
      cells++, entries += (uint32_t)reached, particles += held;
      continue;
    }
    const uint32_t cell = first[0] + cells++;
    a->cell[cell] = first[1] + entries;
    /* the stencil's nodes in (i, j, k) order, through the pad: a node holds such a ghost when
     * its bit is set in its pad block's mask; only those are looked up */
    const int cx = (c >> 4) & 3, cy = (c >> 2) & 3, cz = c & 3;
    for (int i = 0; i < W; ++i)
      for (int j = 0; j < W; ++j)
        for (int k = 0; k < W; ++k) {
          const int px = cx + i, py = cy + j, pz = cz + k;
          const int o = (px >> 2) << 2 | (py >> 2) << 1 | (pz >> 2);
          const int local = (px & 3) << 4 | (py & 3) << 2 | (pz & 3);
          if (!(pad[o] >> local & 1)) continue;
          const size_t slot =
              g->dof_begin + (size_t)sg->neighbor[b][o] * MPM_BLOCK_NODES + (size_t)local;
          mpm_stencil_ghost *e = &a->cell_ghost[first[1] + entries++];
          e->node = (uint32_t)(i | j << 4 | k << 8); /* (i, j, k), 4 bits each */
          e->ghost = (uint32_t)a->ghost_of[slot];
        }
    for (size_t m = 0; m < nmat; ++m) cell_of[q0 + m * MPM_BLOCK_NODES] = cell;
  }
  if (count) count[0] = cells, count[1] = entries, count[2] = particles;
}

mpm_status mpm_adaptive_apic_prepare(mpm_adaptive *a) {
  mpm_adaptive_grid *ag = &a->grid;
  a->boundary_count = a->cell_count = a->cell_ghost_count = 0;
  const size_t dofs = a->host.dofs->count;
  if (mpm_grow((void **)&a->ghost_of, &a->ghost_of_capacity, dofs + 1, sizeof *a->ghost_of))
    goto nomem;
  /* the transfer grids' segments are whole blocks of 64 slots from slot 0 on (adaptive_layout),
   * so slot / 64 names a block: most blocks' pads hold no such ghost and are passed over whole.
   * ghost_of is read only at slots whose bit is set here, so only those are written */
  const size_t chunks = dofs / MPM_BLOCK_NODES + 1;
  if (mpm_grow((void **)&a->block_multi, &a->block_multi_capacity, chunks, sizeof(uint64_t)))
    goto nomem;
  memset(a->block_multi, 0, chunks * sizeof(uint64_t));
  size_t multi = 0;
  for (size_t g = 0; g < ag->ghost_count; ++g)
    if (ag->ghosts.row_len[g] > 1) {
      a->ghost_of[ag->ghost_slot[g]] = (int32_t)g;
      a->block_multi[ag->ghost_slot[g] / MPM_BLOCK_NODES] |=
          (uint64_t)1 << (ag->ghost_slot[g] % MPM_BLOCK_NODES);
      ++multi;
    }
  /* the ghosts' velocity moments (G2P) and affine moments (P2G), written for every ghost when
   * there are boundary particles (mpm_adaptive_apic_after_p2g, _g2p_before) */
  if (mpm_grow((void **)&a->moment, &a->moment_capacity, 18 * ag->ghost_count + 1,
               sizeof *a->moment))
    goto nomem;
  if (!multi) return MPM_OK;
  /* the lanes' map: a place per cell of every transfer grid */
  size_t map = 0;
  for (int t = 0; t < a->tgrid_count; ++t) {
    const mpm_sparse_grid *sg = &mpm_adaptive_grid_at(ag, a->tgrid[t].G)->impl.sparse;
    a->cell_map_begin[t] = map;
    map += sg->owner_count * (size_t)sg->material_count * MPM_BLOCK_NODES;
  }
  if (mpm_grow((void **)&a->cell_of, &a->cell_of_capacity, map + 1, sizeof *a->cell_of)) goto nomem;
  for (int t = 0; t < a->tgrid_count; ++t) {
    const mpm_transfer_grid *tg = &a->tgrid[t];
    const mpm_grid *g = mpm_adaptive_grid_at(ag, tg->G);
    const mpm_sparse_grid *sg = &g->impl.sparse;
    const long nblocks = (long)sg->owner_count;
    assert(g->dof_begin % MPM_BLOCK_NODES == 0);
    uint64_t reach[MPM_BLOCK_NODES][8]; /* per cell of a block, its stencil's nodes per pad block */
    mpm_adaptive_grid_stencil_masks(tg->kernel.width, reach);
    /* two passes over the blocks in parallel: count each block's cells, entries and particles,
     * then (after the prefix sums) write them where the serial order puts them */
    if (mpm_grow((void **)&a->block_count, &a->block_count_capacity, 3 * (size_t)nblocks + 3,
                 sizeof *a->block_count))
      goto nomem;
    uint32_t *count = a->block_count; /* per block: cells, entries, particles */
#pragma omp parallel for schedule(dynamic, 16) if (nblocks > 64)
    for (long b = 0; b < nblocks; ++b) boundary_block(a, t, reach, (size_t)b, count + 3 * b, NULL);
    size_t at[3] = {a->cell_count, a->cell_ghost_count, a->boundary_count};
    for (long b = 0; b < nblocks; ++b)
      for (int k = 0; k < 3; ++k) {
        const uint32_t c = count[3 * b + k];
        count[3 * b + k] = (uint32_t)at[k]; /* now the block's first */
        at[k] += c;
      }
    if (mpm_grow((void **)&a->cell, &a->cell_capacity, at[0] + 2, sizeof *a->cell) ||
        mpm_grow((void **)&a->cell_ghost, &a->cell_ghost_capacity, at[1] + 1,
                 sizeof *a->cell_ghost) ||
        mpm_grow((void **)&a->affine, &a->affine_capacity, 9 * at[1] + 1, sizeof *a->affine))
      goto nomem;
#pragma omp parallel for schedule(dynamic, 16) if (nblocks > 64)
    for (long b = 0; b < nblocks; ++b) {
      uint32_t first[3] = {count[3 * b], count[3 * b + 1], count[3 * b + 2]};
      boundary_block(a, t, reach, (size_t)b, NULL, first);
    }
    a->cell_count = at[0];
    a->cell_ghost_count = at[1];
    a->boundary_count = at[2];
    a->cell[a->cell_count] = (uint32_t)a->cell_ghost_count; /* the last cell's end */
  }
  if (transpose_by_ghost(a, ag->ghost_count, a->host.arena)) goto nomem;
  return MPM_OK;
nomem:
  return mpm_error_set(a->host.error, MPM_ERR_NOMEM,
                       "step %lld: out of memory for the APIC moments of the ghost nodes",
                       (long long)*a->host.steps);
}

mpm_ghost_apic mpm_adaptive_apic_view(mpm_adaptive *a, int t) {
  const mpm_ghost_apic v = {a->cell_of + a->cell_map_begin[t],
                            a->cell,
                            a->cell_ghost,
                            a->grid.spread,
                            a->affine,
                            a->moment};
  return v;
}

void mpm_adaptive_apic_before_p2g(mpm_adaptive *a) {
  const long n = (long)(9 * a->cell_ghost_count);
#pragma omp parallel for schedule(static) if (n > MPM_PARALLEL_MIN)
  for (long i = 0; i < n; ++i) a->affine[i] = 0;
}

void mpm_adaptive_apic_after_p2g(mpm_adaptive *a) {
  const size_t ng = a->grid.ghost_count;
  /* the ghosts' affine moments A_g = sum_p w_gp m_p C_p (stencils overlap): each ghost summed
   * by one thread over its entries in cell order (a ghost is once in a cell's entries), into one
   * plane per component for the scatter */
  mpm_real *planes = a->moment + 9 * ng;
  if (!a->boundary_count) {
    memset(planes, 0, 9 * ng * sizeof *planes);
    return;
  }
  const uint32_t *start = a->ghost_start, *ge = a->ghost_entry;
  const mpm_real *affine = a->affine;
  /* the ghosts with entries lie together in the numbering: chunks, not halves */
#pragma omp parallel for schedule(dynamic, 512)
  for (long g = 0; g < (long)ng; ++g) {
    mpm_real A[9] = {0};
    for (uint32_t j = start[g]; j < start[g + 1]; ++j)
      for (int c = 0; c < 9; ++c) A[c] += affine[9 * (size_t)ge[j] + (size_t)c];
    for (int c = 0; c < 9; ++c) planes[(size_t)c * ng + (size_t)g] = A[c];
  }
}

void mpm_adaptive_apic_scatter(mpm_adaptive *a, int impulse) {
  mpm_adaptive_grid *ag = &a->grid;
  mpm_dofs *d = a->host.dofs;
  mpm_real *u[7] = {d->mass, d->v0[0], d->v0[1], d->v0[2], d->f[0], d->f[1], d->f[2]};
  const mpm_real *A[9]; /* the ghosts' affine moments, one plane per component */
  for (int c = 0; c < 9; ++c) A[c] = a->moment + (size_t)(9 + c) * ag->ghost_count;
  mpm_adaptive_grid_scatter_apic(ag, impulse ? 4 : 7, u, A);
}

void mpm_adaptive_apic_g2p_before(mpm_adaptive *a) {
  const mpm_adaptive_grid *ag = &a->grid;
  if (!a->boundary_count) return;
  const size_t n = ag->ghost_count;
  mpm_real *M[9];
  for (int c = 0; c < 9; ++c) M[c] = a->moment + (size_t)(9 + c) * n; /* P2G's are spent */
  const mpm_real *const v[3] = {a->host.dofs->v[0], a->host.dofs->v[1], a->host.dofs->v[2]};
  mpm_adaptive_grid_gather_moments(ag, v, M);
  mpm_real *Mi = a->moment; /* interleaved, for the G2P lanes' reads */
#pragma omp parallel for schedule(static) if (n > MPM_PARALLEL_MIN)
  for (long g = 0; g < (long)n; ++g)
    for (int c = 0; c < 9; ++c) Mi[9 * (size_t)g + (size_t)c] = M[c][g];
}
