/* alloc.h - aligned allocation through one hook with a live-byte counter.
 *
 * Every large array (particles, grid blocks) goes through here so that tests can check for
 * leaks and benchmarks can report memory per particle. */
#ifndef MPM_CORE_ALLOC_H
#define MPM_CORE_ALLOC_H

#include <stddef.h>

void *mpm_alloc(size_t bytes); /* aligned to MPM_ALIGN, NULL on failure */
void *mpm_calloc(size_t count, size_t size);
void mpm_free(void *p); /* NULL is fine */
/* Room for n items of `size` bytes in *buf, whose capacity is *cap items: doubled from 1024 as
 * needed, the contents kept. 0, or -1 when out of memory (*buf untouched). */
int mpm_grow(void **buf, size_t *cap, size_t n, size_t size);
/* Room for `need` items of `size` bytes in *buf, whose capacity is *cap items, without keeping
 * its contents (per-step tables rebuilt every time): a new buffer 1/8 larger than asked when it
 * is too small. 0, or -1 when out of memory (*buf NULL, *cap 0). */
int mpm_reserve(void **buf, size_t *cap, size_t need, size_t size);
size_t mpm_alloc_live_bytes(void); /* bytes currently allocated through mpm_alloc */
size_t mpm_alloc_calls(void);      /* mpm_alloc calls since start (tests: a warm step makes none) */
size_t mpm_alloc_peak_bytes(void); /* high-water mark since start or last reset */
void mpm_alloc_reset_peak(void);

#endif
