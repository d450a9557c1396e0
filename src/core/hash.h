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

/* A fast 64-bit digest of a large buffer, continuing from h (start with any constant): FNV-1a's
 * xor-multiply on 8-byte words instead of bytes, then a final avalanche. Used to check that
 * a checkpoint's arrays read back exactly as written. */
static inline uint64_t mpm_hash64_words(const void *data, size_t len, uint64_t h) {
  const unsigned char *b = (const unsigned char *)data;
  size_t i = 0;
  for (; i + 8 <= len; i += 8) {
    uint64_t w;
    __builtin_memcpy(&w, b + i, 8);
    h = (h ^ w) * 0x100000001b3ull;
    h ^= h >> 29;
  }
  for (; i < len; ++i) h = (h ^ b[i]) * 0x100000001b3ull;
  h ^= h >> 33;
  h *= 0xff51afd7ed558ccdull;
  h ^= h >> 33;
  return h;
}

#endif
