/* alloc.c - aligned allocation with a live-byte counter (see alloc.h).
 *
 * The size is stored in a header in front of the aligned block, so mpm_free needs no size.
 * Counters are atomic because allocation may happen from several threads. */
#include "core/alloc.h"
#include "core/real.h"

#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

static atomic_size_t live_bytes;
static atomic_size_t peak_bytes;

void *mpm_alloc(size_t bytes) {
  size_t total = bytes + MPM_ALIGN;
  total = (total + MPM_ALIGN - 1) / MPM_ALIGN * MPM_ALIGN;
  unsigned char *raw = aligned_alloc(MPM_ALIGN, total);
  if (!raw) return NULL;
  memcpy(raw, &bytes, sizeof bytes);
  size_t now = atomic_fetch_add(&live_bytes, bytes) + bytes;
  size_t peak = atomic_load(&peak_bytes);
  while (now > peak && !atomic_compare_exchange_weak(&peak_bytes, &peak, now)) {
  }
  return raw + MPM_ALIGN;
}

void *mpm_calloc(size_t count, size_t size) {
  if (size && count > (size_t)-1 / size) return NULL;
  void *p = mpm_alloc(count * size);
  if (p) memset(p, 0, count * size);
  return p;
}

void mpm_free(void *p) {
  if (!p) return;
  unsigned char *raw = (unsigned char *)p - MPM_ALIGN;
  size_t bytes;
  memcpy(&bytes, raw, sizeof bytes);
  atomic_fetch_sub(&live_bytes, bytes);
  free(raw);
}

size_t mpm_alloc_live_bytes(void) { return atomic_load(&live_bytes); }
size_t mpm_alloc_peak_bytes(void) { return atomic_load(&peak_bytes); }
void mpm_alloc_reset_peak(void) { atomic_store(&peak_bytes, atomic_load(&live_bytes)); }
