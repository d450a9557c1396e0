/* arena.c - the per-step scratch arena (see arena.h). */
#include "core/arena.h"
#include "core/alloc.h"
#include "core/real.h"

#include <string.h>

void mpm_arena_init(mpm_arena *a) {
  memset(a, 0, sizeof *a);
}

static void free_overflow(mpm_arena *a) {
  for (int k = 0; k < a->overflow_count; ++k) mpm_free(a->overflow[k]);
  a->overflow_count = 0;
  a->overflow_bytes = 0;
}

void mpm_arena_free(mpm_arena *a) {
  free_overflow(a);
  mpm_free(a->base);
  memset(a, 0, sizeof *a);
}

/* Large blocks start a different multiple of 128 bytes into the arena, as mpm_alloc staggers
 * large arrays (alloc.c): arrays walked side by side then do not map to the same cache sets. */
#define STAGGER_THRESHOLD ((size_t)1 << 20)
#define STAGGER_STEP 128
#define STAGGER_SLOTS 31

void *mpm_arena_alloc(mpm_arena *a, size_t bytes) {
  size_t size = (bytes + MPM_ALIGN - 1) / MPM_ALIGN * MPM_ALIGN;
  if (size >= STAGGER_THRESHOLD)
    size += STAGGER_STEP * (1 + (size_t)(a->large_count++ % STAGGER_SLOTS));
  if (a->used + a->overflow_bytes + size > a->peak) a->peak = a->used + a->overflow_bytes + size;
  const size_t lead = size - (bytes + MPM_ALIGN - 1) / MPM_ALIGN * MPM_ALIGN; /* the stagger */
  if (a->base && a->used + size <= a->capacity) {
    void *p = a->base + a->used + lead;
    a->used += size;
    return p;
  }
  if (a->overflow_count == MPM_ARENA_MAX_OVERFLOW) return NULL;
  void *p = mpm_alloc(size ? size : MPM_ALIGN);
  if (!p) return NULL;
  a->overflow[a->overflow_count++] = p;
  a->overflow_bytes += size;
  return p;
}

mpm_status mpm_arena_reset(mpm_arena *a) {
  const int overflowed = a->overflow_count > 0;
  free_overflow(a);
  a->used = 0;
  a->large_count = 0;
  if (!overflowed) return MPM_OK;
  /* grow to the peak, with room for some growth of the step */
  const size_t want = a->peak + a->peak / 8;
  mpm_free(a->base);
  a->base = mpm_alloc(want);
  a->capacity = a->base ? want : 0;
  a->grown++;
  return a->base ? MPM_OK : MPM_ERR_NOMEM;
}
