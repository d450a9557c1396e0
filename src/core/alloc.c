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
#define _GNU_SOURCE /* madvise flags, mremap */
#include "core/alloc.h"
#include "core/real.h"

#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
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

/* The embedding program's allocator, or (alloc NULL) the C library's and anonymous mappings.
 * Set only while nothing is allocated (mpm_set_allocator), so every live block came from the
 * one in place. */
static struct {
  void *(*alloc)(size_t bytes, size_t alignment, void *user);
  void (*release)(void *p, void *user);
  void *user;
} hook;

void mpm_alloc_set_hook(void *(*alloc)(size_t bytes, size_t alignment, void *user),
                        void (*release)(void *p, void *user), void *user) {
  hook.alloc = alloc;
  hook.release = release;
  hook.user = user;
}

static void *raw_alloc(size_t total, size_t align) {
  return hook.alloc ? hook.alloc(total, align, hook.user) : aligned_alloc(align, total);
}

static void raw_free(void *p) {
  if (hook.alloc)
    hook.release(p, hook.user);
  else
    free(p);
}

/* Before every block: where its allocation starts, its size, and a mark that it is one of ours
 * (mpm_free of memory that mpm_alloc did not make stops with a message instead of miscounting
 * the live bytes and freeing a wrong address). */
#define HEADER_MARK 0x6d706d616c6c6f63ull /* "mpmalloc" */
typedef struct header {
  uint64_t mark;
  void *raw;
  size_t bytes;
} header;

/* Count bytes as allocated, and the peak with them. */
static void count_bytes(size_t bytes) {
  size_t now = atomic_fetch_add(&live_bytes, bytes) + bytes;
  size_t peak = atomic_load(&peak_bytes);
  while (now > peak && !atomic_compare_exchange_weak(&peak_bytes, &peak, now)) {
  }
}

void *mpm_alloc(size_t bytes) {
  atomic_fetch_add(&alloc_calls, 1);
  const int large = bytes >= HUGE_THRESHOLD;
  const size_t align = large ? HUGE_ALIGN : MPM_ALIGN;
  size_t offset = MPM_ALIGN; /* room for the header, keeps MPM_ALIGN alignment */
  if (large) offset += STAGGER_STEP * (atomic_fetch_add(&stagger_counter, 1) % STAGGER_SLOTS);
  size_t total = bytes + offset;
  total = (total + align - 1) / align * align;
  unsigned char *raw = raw_alloc(total, align);
  if (!raw) return NULL;
#ifdef MADV_HUGEPAGE
  if (large && !hook.alloc) madvise(raw, total, MADV_HUGEPAGE); /* a hint; failure is harmless */
#endif
  unsigned char *p = raw + offset;
  header h = {HEADER_MARK, raw, bytes};
  memcpy(p - sizeof h, &h, sizeof h);
  count_bytes(bytes);
  return p;
}

void *mpm_calloc(size_t count, size_t size) {
  if (size && count > (size_t)-1 / size) return NULL;
  void *p = mpm_alloc(count * size);
  if (p) memset(p, 0, count * size);
  return p;
}

/* The header of block p, which must be one of ours. */
static header header_of(const void *p, const char *what) {
  header h;
  memcpy(&h, (const unsigned char *)p - sizeof h, sizeof h);
  if (h.mark != HEADER_MARK) {
    fprintf(stderr,
            "mpm: %s(%p): not a block of mpm_alloc (freed twice, or allocated with "
            "another allocator)\n",
            what, p);
    abort();
  }
  return h;
}

void mpm_free(void *p) {
  if (!p) return;
  const header h = header_of(p, "mpm_free");
  memset((unsigned char *)p - sizeof h, 0, sizeof h.mark); /* a second free is seen */
  atomic_fetch_sub(&live_bytes, h.bytes);
  raw_free(h.raw);
}

void *mpm_realloc(void *p, size_t bytes) {
  if (!p) return mpm_alloc(bytes);
  const header h = header_of(p, "mpm_realloc");
  void *q = mpm_alloc(bytes);
  if (!q) return NULL;
  memcpy(q, p, h.bytes < bytes ? h.bytes : bytes);
  mpm_free(p);
  return q;
}

char *mpm_strdup(const char *s) {
  const size_t n = strlen(s) + 1;
  char *d = mpm_alloc(n);
  if (d) memcpy(d, s, n);
  return d;
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

mpm_status mpm_reserve(void **buf, size_t *cap, size_t need, size_t size) {
  if (need <= *cap && *buf) return MPM_OK;
  mpm_free(*buf);
  const size_t n = need + need / 8 + 16;
  *buf = mpm_alloc(n * size);
  *cap = *buf ? n : 0;
  return *buf ? MPM_OK : MPM_ERR_NOMEM;
}

mpm_status mpm_grow(void **buf, size_t *cap, size_t n, size_t size) {
  if (n <= *cap) return MPM_OK;
  size_t c = *cap ? *cap : 1024;
  while (c < n) c *= 2;
  void *b = mpm_alloc(c * size);
  if (!b) return MPM_ERR_NOMEM;
  if (*buf && *cap) memcpy(b, *buf, *cap * size);
  mpm_free(*buf);
  *buf = b;
  *cap = c;
  return MPM_OK;
}

/* ---- growable blocks ---------------------------------------------------------------- */

static size_t page_round(size_t bytes) {
  const size_t page = 4096;
  return (bytes + page - 1) / page * page;
}

/* An address range of `total` bytes (a page multiple), aligned to 2 MiB when it is large enough
 * for huge pages (the kernel backs a range with them only where 2 MiB-aligned), reserved with
 * `prot`. MAP_FAILED on failure. */
static void *map_aligned(size_t total, int prot) {
  const int flags = MAP_PRIVATE | MAP_ANONYMOUS | (prot == PROT_NONE ? MAP_NORESERVE : 0);
  if (total < HUGE_THRESHOLD) return mmap(NULL, total, prot, flags, -1, 0);
  unsigned char *raw = mmap(NULL, total + HUGE_ALIGN, prot, flags, -1, 0);
  if (raw == MAP_FAILED) return MAP_FAILED;
  unsigned char *start =
      (unsigned char *)(((uintptr_t)raw + HUGE_ALIGN - 1) & ~(uintptr_t)(HUGE_ALIGN - 1));
  if (start > raw) munmap(raw, (size_t)(start - raw));
  const size_t tail = (size_t)(raw + total + HUGE_ALIGN - (start + total));
  if (tail) munmap(start + total, tail);
  return start;
}

void *mpm_block_alloc(size_t bytes) {
  atomic_fetch_add(&alloc_calls, 1);
  const size_t total = page_round(bytes ? bytes : 1);
  if (hook.alloc) { /* the program's allocator: page-aligned pages of its own */
    void *p = hook.alloc(total, total >= HUGE_THRESHOLD ? HUGE_ALIGN : 4096, hook.user);
    if (p) count_bytes(bytes);
    return p;
  }
  void *p = map_aligned(total, PROT_READ | PROT_WRITE);
  if (p == MAP_FAILED) return NULL;
#ifdef MADV_HUGEPAGE
  if (total >= HUGE_THRESHOLD) madvise(p, total, MADV_HUGEPAGE);
#endif
  count_bytes(bytes);
  return p;
}

void *mpm_block_grow(void *p, size_t old_bytes, size_t new_bytes) {
  if (!p) return mpm_block_alloc(new_bytes);
  if (hook.alloc) { /* no pages to move: a new block and a copy */
    void *q = mpm_block_alloc(new_bytes);
    if (!q) return NULL;
    memcpy(q, p, old_bytes < new_bytes ? old_bytes : new_bytes);
    mpm_block_free(p, old_bytes);
    return q;
  }
  atomic_fetch_add(&alloc_calls, 1);
  const size_t old_total = page_round(old_bytes ? old_bytes : 1), total = page_round(new_bytes);
  void *q;
  if (total >= HUGE_THRESHOLD) {
    /* onto an aligned range reserved for it: the pages move, huge ones stay huge */
    void *at = map_aligned(total, PROT_NONE);
    if (at == MAP_FAILED) return NULL;
    q = mremap(p, old_total, total, MREMAP_MAYMOVE | MREMAP_FIXED, at);
    if (q == MAP_FAILED) {
      munmap(at, total);
      return NULL;
    }
  } else {
    q = mremap(p, old_total, total, MREMAP_MAYMOVE);
    if (q == MAP_FAILED) return NULL;
  }
#ifdef MADV_HUGEPAGE
  if (total >= HUGE_THRESHOLD) madvise(q, total, MADV_HUGEPAGE);
#endif
  atomic_fetch_sub(&live_bytes, old_bytes);
  count_bytes(new_bytes);
  return q;
}

void mpm_block_free(void *p, size_t bytes) {
  if (!p) return;
  if (hook.alloc)
    hook.release(p, hook.user);
  else
    munmap(p, page_round(bytes ? bytes : 1));
  atomic_fetch_sub(&live_bytes, bytes);
}

/* ---- frees that wait for a holder ---------------------------------------------------- */

static void keep_add(mpm_keep *k, void *p, size_t block_bytes) {
  if (!p) return;
  if (!k || k->holds <= 0) {
    if (block_bytes)
      mpm_block_free(p, block_bytes);
    else
      mpm_free(p);
    return;
  }
  if (k->count == k->cap) {
    const size_t cap = k->cap ? 2 * k->cap : 16;
    struct mpm_kept *q = realloc(k->kept, cap * sizeof *q);
    /* no room to remember it: it is never freed (a leak is safe; a pointer a holder still has
       must not dangle) */
    if (!q) return;
    k->kept = q;
    k->cap = cap;
  }
  k->kept[k->count++] = (struct mpm_kept){p, block_bytes};
}

void mpm_keep_free(mpm_keep *k, void *p) {
  keep_add(k, p, 0);
}

void mpm_keep_free_block(mpm_keep *k, void *p, size_t bytes) {
  keep_add(k, p, bytes ? bytes : 1);
}

void mpm_keep_hold(mpm_keep *k, int delta) {
  k->holds += delta;
  if (k->holds <= 0) {
    k->holds = 0;
    mpm_keep_clear(k);
  }
}

void mpm_keep_clear(mpm_keep *k) {
  for (size_t i = 0; i < k->count; ++i) {
    if (k->kept[i].block_bytes)
      mpm_block_free(k->kept[i].p, k->kept[i].block_bytes);
    else
      mpm_free(k->kept[i].p);
  }
  free(k->kept);
  k->kept = NULL;
  k->count = k->cap = 0;
}
