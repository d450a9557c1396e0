/* scatter_schedule.h - the order in which a parallel scatter visits its rows, so that it needs
 * no atomics and gives the same sums for any number of threads (grid/embedding.h).
 *
 * Rows (carriers: domain corners, ghost nodes, particles for heat) are grouped by a key, the
 * grid's scatter key of their stencil (for the sparse grid the base block), and the keys are
 * coloured so that the rows of two groups of one colour never touch the same node (for the
 * sparse grid the parity of the base block: blocks of one colour are two blocks apart). A
 * scatter runs the colours one after the other, the groups of a colour in parallel, the rows
 * of a group in row order: every node receives its contributions in one fixed order. Rows whose
 * columns no other row has (key MPM_SCHEDULE_OWN_COLUMNS) come last, all in parallel. */
#ifndef MPM_GRID_SCATTER_SCHEDULE_H
#define MPM_GRID_SCATTER_SCHEDULE_H

#include "mpm/mpm.h"

#include <stddef.h>
#include <stdint.h>

#define MPM_SCHEDULE_COLOURS 8

/* The key of a row whose columns belong to it alone (an enriched corner's identity row, Zhu
 * sec. 5: the corner is its own DOF): it needs no colour. */
#define MPM_SCHEDULE_OWN_COLUMNS (-2)

typedef struct mpm_scatter_schedule {
  int built;
  /* groups of rows: group q holds rows group_row[group_start[q] .. group_start[q + 1]); the
   * groups of colour c are colour_start[c] .. colour_start[c + 1] */
  uint32_t *group_row, *group_start;
  int32_t *key_group; /* per key: its group, or -1 */
  size_t group_row_capacity, group_capacity, key_capacity;
  size_t colour_start[MPM_SCHEDULE_COLOURS + 1];
  uint32_t *own_row; /* the rows of key MPM_SCHEDULE_OWN_COLUMNS, in row order */
  size_t own_rows, own_row_capacity;
  /* the build's per-thread counts per key and own rows (kept: a warm step allocates nothing) */
  uint32_t *count;
  size_t count_capacity;
  size_t *own_at;
  size_t own_at_capacity;
} mpm_scatter_schedule;

void mpm_scatter_schedule_init(mpm_scatter_schedule *s);
void mpm_scatter_schedule_free(mpm_scatter_schedule *s);
size_t mpm_scatter_schedule_bytes(const mpm_scatter_schedule *s);

/* Group rows 0 .. rows - 1 by key: rows with key[a] == MPM_SCHEDULE_OWN_COLUMNS are the own
 * rows; other rows with key[a] < 0 take no part; the others are grouped by key (0 <= key <
 * key_count), groups numbered by colour (key_colour[key] in 0 .. MPM_SCHEDULE_COLOURS - 1) then
 * by key, the rows of a group in row order. The caller guarantees that rows in groups of one
 * colour and different keys share no column. MPM_OK, or MPM_ERR_NOMEM when out of memory. */
mpm_status mpm_scatter_schedule_build(mpm_scatter_schedule *s, size_t rows, const int32_t *key,
                                      size_t key_count, const uint8_t *key_colour);

/* The key of group q (that of its first row). */
static inline int32_t mpm_scatter_schedule_group_key(const mpm_scatter_schedule *s,
                                                     const int32_t *key, size_t q) {
  return key[s->group_row[s->group_start[q]]];
}

#endif
