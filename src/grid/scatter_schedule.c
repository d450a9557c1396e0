/* scatter_schedule.c - grouping and colouring of a scatter's rows (see scatter_schedule.h). */
#include "grid/scatter_schedule.h"
#include "core/alloc.h"

#include <string.h>

void mpm_scatter_schedule_init(mpm_scatter_schedule *s) {
  memset(s, 0, sizeof *s);
}

void mpm_scatter_schedule_free(mpm_scatter_schedule *s) {
  mpm_free(s->group_row);
  mpm_free(s->group_start);
  mpm_free(s->key_group);
  mpm_free(s->own_row);
  memset(s, 0, sizeof *s);
}

size_t mpm_scatter_schedule_bytes(const mpm_scatter_schedule *s) {
  return (s->group_row_capacity + s->group_capacity + s->own_row_capacity) * sizeof(uint32_t) +
         s->key_capacity * sizeof(int32_t);
}

int mpm_scatter_schedule_build(mpm_scatter_schedule *s, size_t rows, const int32_t *key,
                               size_t key_count, const uint8_t *key_colour) {
  s->built = 0;
  if (mpm_reserve((void **)&s->key_group, &s->key_capacity, key_count + 1, sizeof(int32_t)))
    return -1;
  /* the keys in use, numbered as groups in colour order, then key order */
  int32_t *kg = s->key_group;
  for (size_t k = 0; k < key_count; ++k) kg[k] = -1;
  size_t used_rows = 0, own = 0;
  for (size_t a = 0; a < rows; ++a)
    if (key[a] >= 0) {
      kg[key[a]] = 0;
      ++used_rows;
    } else if (key[a] == MPM_SCHEDULE_OWN_COLUMNS) {
      ++own;
    }
  if (mpm_reserve((void **)&s->own_row, &s->own_row_capacity, own + 1, sizeof(uint32_t))) return -1;
  s->own_rows = 0;
  for (size_t a = 0; a < rows; ++a)
    if (key[a] == MPM_SCHEDULE_OWN_COLUMNS) s->own_row[s->own_rows++] = (uint32_t)a;
  size_t groups = 0;
  for (int colour = 0; colour < MPM_SCHEDULE_COLOURS; ++colour) {
    s->colour_start[colour] = groups;
    for (size_t k = 0; k < key_count; ++k)
      if (kg[k] >= 0 && key_colour[k] == colour) kg[k] = (int32_t)groups++;
  }
  s->colour_start[MPM_SCHEDULE_COLOURS] = groups;
  if (mpm_reserve((void **)&s->group_start, &s->group_capacity, groups + 2, sizeof(uint32_t)) ||
      mpm_reserve((void **)&s->group_row, &s->group_row_capacity, used_rows + 1, sizeof(uint32_t)))
    return -1;
  /* counting sort of the rows by group, stable in row order */
  uint32_t *start = s->group_start;
  memset(start, 0, (groups + 1) * sizeof *start);
  for (size_t a = 0; a < rows; ++a)
    if (key[a] >= 0) start[kg[key[a]] + 1]++;
  for (size_t q = 0; q < groups; ++q) start[q + 1] += start[q];
  for (size_t a = 0; a < rows; ++a)
    if (key[a] >= 0) s->group_row[start[kg[key[a]]]++] = (uint32_t)a;
  for (size_t q = groups; q > 0; --q) start[q] = start[q - 1]; /* back to the starts */
  start[0] = 0;
  s->built = 1;
  return 0;
}
