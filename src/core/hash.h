/* hash.h - FNV-1a, 64 bits: a fingerprint of a scene's text, so that a checkpoint is resumed
 * only by the scene that wrote it. Not cryptographic; collisions of edited scenes are
 * negligible for this use. */
#ifndef MPM_CORE_HASH_H
#define MPM_CORE_HASH_H

#include <stddef.h>
#include <stdint.h>

static inline uint64_t mpm_fnv1a64(const void *data, size_t len) {
  const unsigned char *b = (const unsigned char *)data;
  uint64_t h = 0xcbf29ce484222325ull;
  for (size_t i = 0; i < len; ++i) {
    h ^= b[i];
    h *= 0x100000001b3ull;
  }
  return h;
}

#endif
