/* lattice_map.h - a map from integer lattice coordinates (3 x 21 bits around 0) to indices,
 * open addressing with linear probing: shared corners of particle domains (domain.c) and the
 * domain of each lattice cell for embedded surfaces (embed.c). */
#ifndef MPM_DOMAIN_LATTICE_MAP_H
#define MPM_DOMAIN_LATTICE_MAP_H

#include "core/alloc.h"

#include <stdint.h>
#include <string.h>

typedef struct mpm_lattice_map {
  uint64_t *keys; /* UINT64_MAX: empty */
  uint32_t *values;
  size_t mask;
} mpm_lattice_map;

/* Room for `count` entries at a load of at most 1/2. MPM_OK, or MPM_ERR_NOMEM when out of
 * memory. */
static inline mpm_status mpm_lattice_map_init(mpm_lattice_map *m, size_t count) {
  size_t size = 64;
  while (size < 2 * count) size *= 2;
  m->keys = mpm_alloc(size * sizeof *m->keys);
  m->values = mpm_alloc(size * sizeof *m->values);
  m->mask = size - 1;
  if (!m->keys || !m->values) return MPM_ERR_NOMEM;
  memset(m->keys, 0xFF, size * sizeof *m->keys);
  return MPM_OK;
}

static inline void mpm_lattice_map_free(mpm_lattice_map *m) {
  mpm_free(m->keys);
  mpm_free(m->values);
  memset(m, 0, sizeof *m);
}

static inline uint64_t mpm_lattice_key(const int64_t k[3]) {
  const int64_t b = 1 << 20;
  return ((uint64_t)(k[0] + b) << 42) | ((uint64_t)(k[1] + b) << 21) | (uint64_t)(k[2] + b);
}

/* The slot of key: the one holding it, or the empty one where it would go. */
static inline size_t mpm_lattice_map_slot(const mpm_lattice_map *m, uint64_t key) {
  size_t i = (size_t)((key * 0x9E3779B97F4A7C15ull) >> 17) & m->mask;
  while (m->keys[i] != UINT64_MAX && m->keys[i] != key) i = (i + 1) & m->mask;
  return i;
}

#endif
