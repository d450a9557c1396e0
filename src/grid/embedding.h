/* embedding.h - the embedding operator E: a sparse matrix from "carrier" values to DOFs
 * (DESIGN.md, "Embedding operator").
 *
 * Zhu et al.'s corner -> grid rasterization (sec. 4, eqs. 2-3 and 8: m_i = sum_a omega_i(x_a)
 * m_a) and Gao et al.'s ghost -> parent distribution (sec. 6.1, eq. 15) are the same thing: a
 * carrier a (a domain corner, a ghost node of a finer level) holds values that belong, with
 * weights E_ai, to real DOFs i. P2G applies the transpose, G2P the operator itself:
 *   after P2G   u_i += sum_a E_ai c_a        (mpm_embedding_scatter: mass, momentum, force)
 *   before G2P  c_a  = sum_i E_ai u_i        (mpm_embedding_gather: velocities)
 * With weights that sum to one over each row (a partition of unity) the scatter conserves
 * mass and momentum, and with weights that reproduce linear functions the gather of a linear
 * field is exact (tests/test_embedding.c). An enriched corner (Zhu sec. 5) will be an identity
 * row: the corner is its own DOF; a T-junction node (Gao eqs. 11-14) a row of its parents'
 * weights.
 *
 * Storage is CSR with room reserved per row: row a's entries are
 *   col[row_start[a] .. row_start[a] + row_len[a]), with weights w[...],
 * row_len[a] <= row_start[a + 1] - row_start[a], so that rows can be filled in parallel without
 * a counting pass. Columns are DOF indices of the DOF set (grid/dofs.h).
 *
 * The scatter is parallel and deterministic: rows are grouped and the groups coloured so that
 * rows of two groups of one colour never share a column (mpm_embedding_schedule); colours run
 * one after the other, the groups of a colour in parallel, the rows of a group in row order. A
 * DOF then receives its contributions in one fixed order for any number of threads. Without a
 * schedule the scatter is one serial pass in row order. */
#ifndef MPM_GRID_EMBEDDING_H
#define MPM_GRID_EMBEDDING_H

#include "mpm/mpm.h"
#include "core/real.h"
#include "grid/scatter_schedule.h"

#include <stddef.h>
#include <stdint.h>

#define MPM_EMBEDDING_COLOURS MPM_SCHEDULE_COLOURS

typedef struct mpm_embedding {
  size_t rows, row_capacity;
  size_t entry_capacity;
  uint32_t *row_start; /* rows + 1 */
  uint32_t *row_len;
  uint32_t *col; /* DOF indices */
  mpm_real *w;
  mpm_scatter_schedule schedule; /* the scatter's (grid/scatter_schedule.h); built: scheduled */
} mpm_embedding;

/* The key of a row whose columns belong to it alone (an enriched corner's identity row, Zhu
 * sec. 5: the corner is its own DOF): it needs no colour. */
#define MPM_EMBEDDING_OWN_COLUMNS MPM_SCHEDULE_OWN_COLUMNS

void mpm_embedding_init(mpm_embedding *E);
void mpm_embedding_free(mpm_embedding *E);

/* Room for `rows` rows; row a may hold up to max_len[a] entries (max_len NULL: uniform_len
 * each). Row lengths start at 0; the caller fills col, w and row_len per row (in parallel if it
 * likes). Drops the schedule. MPM_OK; MPM_ERR_NOMEM when out of memory; MPM_ERR_INVALID when the
 * rows would hold 2^32 entries or more. */
mpm_status mpm_embedding_layout(mpm_embedding *E, size_t rows, const uint32_t *max_len,
                                uint32_t uniform_len);

/* Append entry (col, w) to row a (serial use per row). */
static inline void mpm_embedding_push(mpm_embedding *E, size_t a, uint32_t col, mpm_real w) {
  const uint32_t e = E->row_start[a] + E->row_len[a]++;
  E->col[e] = col;
  E->w[e] = w;
}

/* The scatter's schedule: rows with key[a] == MPM_EMBEDDING_OWN_COLUMNS are scattered after the
 * groups, in parallel (the caller guarantees that no other row has their columns); other rows
 * with key[a] < 0 take no part (their values are not scattered); the others are grouped by key (0
 * <= key < key_count), groups numbered by colour (key_colour[key] in 0..MPM_EMBEDDING_COLOURS-1)
 * then by key, the rows of a group in row order. The caller guarantees that rows in groups of one
 * colour share no column. MPM_OK, or MPM_ERR_NOMEM when out of memory. */
mpm_status mpm_embedding_schedule(mpm_embedding *E, const int32_t *key, size_t key_count,
                                  const uint8_t *key_colour);

/* u[k][col] += w c[k][a] for every entry of every scheduled row (all rows without a schedule),
 * for the `fields` pairs of arrays (c: carrier values, u: DOF values). */
void mpm_embedding_scatter(const mpm_embedding *E, int fields, const mpm_real *const *c,
                           mpm_real *const *u);

/* The scatter with first moments, in the same pass and order: besides mpm_embedding_scatter's
 * sums, um[k][col] += sum_j a[j][e] cm[3 k + j][a] for k = 0..2, where a[j][e] is given per
 * entry e and cm per carrier. APIC through an embedding (Jiang et al. 2015 at the carrier):
 * with a_e = D_a^-1 E_ai (x_i - x_a) and cm = m_a B_a (row-major), the affine part
 * m_a C_a E_ai (x_i - x_a) of carrier a's momentum, C_a = B_a D_a^-1. */
void mpm_embedding_scatter_moments(const mpm_embedding *E, int fields, const mpm_real *const *c,
                                   mpm_real *const *u, const mpm_real *const a[3],
                                   const mpm_real *const cm[9], mpm_real *const um[3]);

/* c[k][a] = sum over row a of w u[k][col], for every row, the `fields` pairs of arrays.
 * Parallel over rows, deterministic. */
void mpm_embedding_gather(const mpm_embedding *E, int fields, const mpm_real *const *u,
                          mpm_real *const *c);

/* The gather's first moments, the twin of mpm_embedding_scatter_moments: for every row a,
 * cm[3 k + j][a] = sum over row a's entries e of u[k][col] a[j][e] (k, j = 0..2). With
 * a_e = E_ai (x_i - x_a) this is M_a = sum_i E_ai u_i (x_i - x_a)^T, what a carrier must pass on
 * besides its gathered value for APIC's B_p to be the exact sum over the DOFs behind it
 * (docs/adaptive-grid.md). Parallel over rows, deterministic. */
void mpm_embedding_gather_moments(const mpm_embedding *E, const mpm_real *const u[3],
                                  const mpm_real *const a[3], mpm_real *const cm[9]);

/* Bytes held. */
size_t mpm_embedding_bytes(const mpm_embedding *E);

#endif
