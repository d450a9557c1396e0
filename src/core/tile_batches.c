/* tile_batches.c - items batched by coloured tiles (see tile_batches.h). */
#include "core/tile_batches.h"

#include <stdlib.h>
#include <string.h>

typedef struct entry {
  uint64_t key; /* colour, then the tile's coordinates */
  uint32_t item;
} entry;

static int entry_order(const void *a, const void *b) {
  const entry *x = a, *y = b;
  if (x->key != y->key) return x->key < y->key ? -1 : 1;
  return (x->item > y->item) - (x->item < y->item);
}

mpm_status mpm_tile_batches_build(size_t n, const int32_t (*tile)[3], mpm_arena *scratch,
                                  mpm_tile_batches *out) {
  memset(out, 0, sizeof *out);
  entry *e = mpm_arena_alloc(scratch, (n + 1) * sizeof *e);
  out->item = mpm_arena_alloc(scratch, (n + 1) * sizeof *out->item);
  out->tile_start = mpm_arena_alloc(scratch, (n + 1) * sizeof *out->tile_start);
  if (!e || !out->item || !out->tile_start) return MPM_ERR_NOMEM;
  /* 20 bits an axis after the bias, the colour above them. Coordinates beyond +-2^19 wrap: two
     tiles of one colour may then share a key and run as one tile, in order, which is still
     safe (the colour comes from the coordinates themselves) */
  const int64_t bias = (int64_t)1 << 19, mask = ((int64_t)1 << 20) - 1;
  for (size_t i = 0; i < n; ++i) {
    uint64_t key = 0, colour = 0;
    for (int d = 0; d < 3; ++d) {
      const int64_t c = (int64_t)tile[i][d];
      colour |= (uint64_t)(c & 1) << d;
      key = key << 20 | (uint64_t)((c + bias) & mask);
    }
    e[i] = (entry){colour << 60 | key, (uint32_t)i};
  }
  qsort(e, n, sizeof *e, entry_order);
  size_t t = 0;
  int colour = 0;
  for (size_t i = 0; i < n; ++i) {
    out->item[i] = e[i].item;
    if (i > 0 && e[i].key == e[i - 1].key) continue;
    const int c = (int)(e[i].key >> 60);
    while (colour <= c) out->colour_start[colour++] = t;
    out->tile_start[t++] = i;
  }
  while (colour <= MPM_TILE_COLOURS) out->colour_start[colour++] = t;
  out->tile_start[t] = n;
  out->tiles = t;
  return MPM_OK;
}
