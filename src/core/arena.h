/* arena.h - the per-step scratch arena: one block of memory handed out by bumping a pointer
 * and taken back all at once when the next step begins (Box2D's b2ArenaAllocator has the same
 * shape).
 *
 * Scratch that lives for one step only (the sparse grid's sort keys and histograms, the stresses
 * of domain particles, the scatter schedule of the corner embedding) comes from here, so that a
 * step allocates nothing once the arena has seen the largest step: a request that does not fit
 * is served by a chunk of its own (mpm_alloc), and the next reset frees those chunks and grows
 * the arena to the peak it saw. Every block is aligned to MPM_ALIGN. Not thread safe: allocate
 * outside parallel regions. */
#ifndef MPM_CORE_ARENA_H
#define MPM_CORE_ARENA_H

#include "mpm/mpm.h"

#include <stddef.h>

#define MPM_ARENA_MAX_OVERFLOW 256

typedef struct mpm_arena {
  unsigned char *base;
  size_t capacity, used, peak; /* bytes */
  void *overflow[MPM_ARENA_MAX_OVERFLOW];
  int overflow_count;
  size_t overflow_bytes;
  size_t grown;         /* times the arena was grown (reported by tests and benchmarks) */
  unsigned large_count; /* large blocks handed out this round (their stagger) */
} mpm_arena;

void mpm_arena_init(mpm_arena *a);
void mpm_arena_free(mpm_arena *a);

/* `bytes` of scratch, aligned, valid until the next mpm_arena_reset; NULL when out of memory. */
void *mpm_arena_alloc(mpm_arena *a, size_t bytes);

/* Take everything back. When the last round overflowed, the arena grows to its peak (so the
 * next round of the same size allocates nothing). MPM_OK, or MPM_ERR_NOMEM when growing ran out
 * of memory (the arena is then empty and still usable). */
mpm_status mpm_arena_reset(mpm_arena *a);

#endif
