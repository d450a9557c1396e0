/* alloc.c - aligned allocation with a live-byte counter (see alloc.h).
 *
 * A small header in front of each block holds the raw pointer and the size, so mpm_free needs
 * no size. Counters are atomic because allocation may happen from several threads.
 *
 * Large arrays (particle components, grid pools) get two treatments:
 *  - they are marked for transparent huge pages (2 MiB), because transfers stream through ~30
 *    particle arrays at once and 4 KiB pages would add a TLB miss per array and page;
 *  - their starts are staggered by a different multiple of 128 bytes each, because structure-of-
 *    arrays components allocated at the same offset within a page map element i of every array
 *    to the same cache set, and 26 streams then thrash an 8-way L1/L2. */
#define _DEFAULT_SOURCE /* madvise flags */
#include "core/alloc.h"
#include "core/real.h"

#include <stdatomic.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>

#define HUGE_THRESHOLD ((size_t)1 << 20)
#define HUGE_ALIGN ((size_t)2 << 20)
#define STAGGER_STEP 128
#define STAGGER_SLOTS 31 /* odd, so successive arrays cycle through distinct sets */

static atomic_size_t live_bytes;
static atomic_size_t alloc_calls;
static atomic_size_t peak_bytes;
static atomic_uint stagger_counter;

typedef struct header {
  void *raw;
  size_t bytes;
} header;

void *mpm_alloc(size_t bytes) {
  atomic_fetch_add(&alloc_calls, 1);
  const int large = bytes >= HUGE_THRESHOLD;
  const size_t align = large ? HUGE_ALIGN : MPM_ALIGN;
  size_t offset = MPM_ALIGN; /* room for the header, keeps MPM_ALIGN alignment */
  if (large) offset += STAGGER_STEP * (atomic_fetch_add(&stagger_counter, 1) % STAGGER_SLOTS);
  size_t total = bytes + offset;
  total = (total + align - 1) / align * align;
  unsigned char *raw = aligned_alloc(align, total);
  if (!raw) return NULL;
#ifdef MADV_HUGEPAGE
  if (large) madvise(raw, total, MADV_HUGEPAGE); /* a hint; failure is harmless */
#endif
  unsigned char *p = raw + offset;
  header h = {raw, bytes};
  memcpy(p - sizeof h, &h, sizeof h);
  size_t now = atomic_fetch_add(&live_bytes, bytes) + bytes;
  size_t peak = atomic_load(&peak_bytes);
  while (now > peak && !atomic_compare_exchange_weak(&peak_bytes, &peak, now)) {
  }
  return p;
}

void *mpm_calloc(size_t count, size_t size) {
  if (size && count > (size_t)-1 / size) return NULL;
  void *p = mpm_alloc(count * size);
  if (p) memset(p, 0, count * size);
  return p;
}

void mpm_free(void *p) {
  if (!p) return;
  header h;
  memcpy(&h, (unsigned char *)p - sizeof h, sizeof h);
  atomic_fetch_sub(&live_bytes, h.bytes);
  free(h.raw);
}

size_t mpm_alloc_live_bytes(void) {
  return atomic_load(&live_bytes);
}
size_t mpm_alloc_calls(void) {
  return atomic_load(&alloc_calls);
}
size_t mpm_alloc_peak_bytes(void) {
  return atomic_load(&peak_bytes);
}
void mpm_alloc_reset_peak(void) {
  atomic_store(&peak_bytes, atomic_load(&live_bytes));
}

int mpm_reserve(void **buf, size_t *cap, size_t need, size_t size) {
  if (need <= *cap && *buf) return 0;
  mpm_free(*buf);
  const size_t n = need + need / 8 + 16;
  *buf = mpm_alloc(n * size);
  *cap = *buf ? n : 0;
  return *buf ? 0 : -1;
}

int mpm_grow(void **buf, size_t *cap, size_t n, size_t size) {
  if (n <= *cap) return 0;
  size_t c = *cap ? *cap : 1024;
  while (c < n) c *= 2;
  void *b = mpm_alloc(c * size);
  if (!b) return -1;
  if (*buf && *cap) memcpy(b, *buf, *cap * size);
  mpm_free(*buf);
  *buf = b;
  *cap = c;
  return 0;
}
