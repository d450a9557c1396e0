/* alloc.h - aligned allocation through one hook with a live-byte counter.
 *
 * Every allocation of the library goes through here (none calls malloc, calloc, realloc or
 * strdup directly), so that tests can check for leaks and benchmarks can report memory per
 * particle. What is allocated here is freed with mpm_free, never with free(). */
#ifndef MPM_CORE_ALLOC_H
#define MPM_CORE_ALLOC_H

#include "mpm/mpm.h"

#include <stddef.h>

void *mpm_alloc(size_t bytes); /* aligned to MPM_ALIGN, NULL on failure */
void *mpm_calloc(size_t count, size_t size);
void mpm_free(void *p); /* NULL is fine */
/* p's first min(old, bytes) bytes in a new block, p freed; p NULL: mpm_alloc(bytes). NULL on
 * failure, p then untouched. */
void *mpm_realloc(void *p, size_t bytes);
char *mpm_strdup(const char *s); /* a copy of s, NULL on failure */
/* Room for n items of `size` bytes in *buf, whose capacity is *cap items: doubled from 1024 as
 * needed, the contents kept. MPM_OK, or MPM_ERR_NOMEM when out of memory (*buf untouched). */
mpm_status mpm_grow(void **buf, size_t *cap, size_t n, size_t size);
/* Room for `need` items of `size` bytes in *buf, whose capacity is *cap items, without keeping
 * its contents (per-step tables rebuilt every time): a new buffer 1/8 larger than asked when it
 * is too small. MPM_OK, or MPM_ERR_NOMEM when out of memory (*buf NULL, *cap 0). */
mpm_status mpm_reserve(void **buf, size_t *cap, size_t need, size_t size);
/* Frees that wait while a caller holds the memory: a binding that gave an array's pointer to
 * garbage-collected code (the Python module's numpy views) holds the keep of its simulation,
 * and the arrays the engine would free meanwhile (a particle set grown, a view's buffer
 * replaced) are kept allocated until the last hold is released: such a pointer may then read
 * stale values, never freed memory. */
typedef struct mpm_keep {
  int holds;
  size_t count, cap;
  struct mpm_kept {
    void *p;
    size_t block_bytes; /* 0: from mpm_alloc; else a block of mpm_block_alloc of this size */
  } * kept;
} mpm_keep;
/* mpm_free(p) now, or when k's holds return to 0 (k NULL: now). */
void mpm_keep_free(mpm_keep *k, void *p);
/* The same for a block of mpm_block_alloc. */
void mpm_keep_free_block(mpm_keep *k, void *p, size_t bytes);
/* holds += delta; at 0 the kept blocks are freed. */
void mpm_keep_hold(mpm_keep *k, int delta);
/* Free what k keeps whatever its holds (its owner is destroyed). */
void mpm_keep_clear(mpm_keep *k);
/* Growable blocks (a particle set's storage): page-aligned anonymous mappings, counted with the
 * rest, that grow in place or by moving their pages (mremap), never by a second copy, so that
 * growing n bytes of particles does not take 2 n at the moment it happens. */
void *mpm_block_alloc(size_t bytes);                               /* NULL on failure */
void *mpm_block_grow(void *p, size_t old_bytes, size_t new_bytes); /* NULL: failed, p kept */
void mpm_block_free(void *p, size_t bytes);                        /* NULL is fine */
/* The embedding program's allocator (mpm_set_allocator in mpm.h); alloc NULL: the default. */
void mpm_alloc_set_hook(void *(*alloc)(size_t bytes, size_t alignment, void *user),
                        void (*release)(void *p, void *user), void *user);
size_t mpm_alloc_live_bytes(void); /* bytes currently allocated through mpm_alloc */
size_t mpm_alloc_calls(void);      /* mpm_alloc calls since start (tests: a warm step makes none) */
size_t mpm_alloc_peak_bytes(void); /* high-water mark since start or last reset */
void mpm_alloc_reset_peak(void);

#endif
