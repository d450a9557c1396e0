/* alloc.c - aligned allocation with a live-byte counter (see alloc.h).
 *
 * The size is stored in a header in front of the aligned block, so mpm_free needs no size.
 * Counters are atomic because allocation may happen from several threads. */
#include "core/alloc.h"
#include "core/real.h"

#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>

/* Large arrays (particle components, grid pools) are placed on 2 MiB boundaries and marked for
 * transparent huge pages: transfers stream through ~30 particle arrays at once, and with 4 KiB
 * pages the TLB misses alone cost as much as the arithmetic. */
#define HUGE_THRESHOLD ((size_t)4 << 20)
#define HUGE_ALIGN ((size_t)2 << 20)

static atomic_size_t live_bytes;
static atomic_size_t peak_bytes;

void *mpm_alloc(size_t bytes) {
  const size_t align = bytes >= HUGE_THRESHOLD ? HUGE_ALIGN : MPM_ALIGN;
  size_t total = bytes + MPM_ALIGN;
  total = (total + align - 1) / align * align;
  unsigned char *raw = aligned_alloc(align, total);
  if (!raw) return NULL;
#ifdef MADV_HUGEPAGE
  if (align == HUGE_ALIGN) madvise(raw, total, MADV_HUGEPAGE); /* a hint; failure is harmless */
#endif
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
