/* particles.c - structure-of-arrays storage of material points (see particles.h). */
#include "core/particles.h"
#include "core/alloc.h"
#include "core/parallel.h"

#include <string.h>

/* Under AddressSanitizer the block's padding (each slot past the capacity) is poisoned: an
 * array overrun is caught there as it was at the end of an array of its own. */
#if defined(__SANITIZE_ADDRESS__)
#include <sanitizer/asan_interface.h>
#define POISON(p, n) ASAN_POISON_MEMORY_REGION(p, n)
#define UNPOISON(p, n) ASAN_UNPOISON_MEMORY_REGION(p, n)
#else
#define POISON(p, n) ((void)(p), (void)(n))
#define UNPOISON(p, n) ((void)(p), (void)(n))
#endif

void mpm_particles_real_arrays(mpm_particles *p, mpm_real **arrays[MPM_PARTICLE_REAL_ARRAYS]) {
  int k = 0;
  for (int d = 0; d < 3; ++d) arrays[k++] = &p->x[d];
  for (int d = 0; d < 3; ++d) arrays[k++] = &p->v[d];
  for (int d = 0; d < 9; ++d) arrays[k++] = &p->F[d];
  for (int d = 0; d < 9; ++d) arrays[k++] = &p->B[d];
  arrays[k++] = &p->plastic;
  arrays[k++] = &p->mass;
  arrays[k++] = &p->vol0;
  arrays[k++] = &p->temperature;
  for (int d = 0; d < 3; ++d) arrays[k++] = &p->xc[d];
}

mpm_particles mpm_particles_range(const mpm_particles *p, size_t begin, size_t count) {
  mpm_particles v = *p;
  v.count = v.capacity = count;
  v.block = NULL; /* a range owns no storage: it is neither grown nor reordered */
  v.keep = NULL;
  if (!p->capacity) return v; /* no arrays to offset */
  mpm_real **arrays[MPM_PARTICLE_REAL_ARRAYS];
  mpm_particles_real_arrays(&v, arrays);
  for (int k = 0; k < MPM_PARTICLE_REAL_ARRAYS; ++k) *arrays[k] += begin;
  v.material += begin;
  v.body += begin;
  v.level += begin;
  v.id += begin;
  return v;
}

/* An integer array grown to new_count, its first old_count items kept; the old one to keep. */
static mpm_status regrow(void **ptr, size_t old_count, size_t new_count, size_t elem,
                         mpm_keep *keep) {
  void *q = mpm_alloc(new_count * elem);
  if (!q) return MPM_ERR_NOMEM;
  if (*ptr && old_count) memcpy(q, *ptr, old_count * elem);
  mpm_keep_free(keep, *ptr);
  *ptr = q;
  return MPM_OK;
}

/* The slot stride for a capacity: whole 4 KiB pages plus 128 bytes (particles.h). */
static size_t slot_stride(size_t capacity) {
  const size_t page = 4096, bytes = (capacity * sizeof(mpm_real) + page - 1) / page * page;
  return (bytes + 128) / sizeof(mpm_real);
}

/* Point the real arrays at their slots of p->block, from slot p->first. */
static void point_arrays(mpm_particles *p) {
  mpm_real **arrays[MPM_PARTICLE_REAL_ARRAYS];
  mpm_particles_real_arrays(p, arrays);
  for (int k = 0; k < MPM_PARTICLE_REAL_ARRAYS; ++k)
    *arrays[k] = p->block + (size_t)(p->first + k) * p->stride;
}

static size_t block_bytes(size_t stride) {
  return (MPM_PARTICLE_REAL_ARRAYS + 1) * stride * sizeof(mpm_real);
}

static void poison_padding(const mpm_particles *p) {
  for (size_t k = 0; k <= MPM_PARTICLE_REAL_ARRAYS; ++k)
    POISON(p->block + k * p->stride + p->capacity, (p->stride - p->capacity) * sizeof(mpm_real));
}

mpm_status mpm_particles_reserve(mpm_particles *p, size_t capacity) {
  if (capacity <= p->capacity) return MPM_OK;
  const size_t stride = slot_stride(capacity);
  /* the integer arrays first: when the block cannot grow after them, they are merely larger */
  if (regrow((void **)&p->material, p->count, capacity, sizeof(int32_t), p->keep) ||
      regrow((void **)&p->body, p->count, capacity, sizeof(int32_t), p->keep) ||
      regrow((void **)&p->level, p->count, capacity, sizeof(int32_t), p->keep) ||
      regrow((void **)&p->id, p->count, capacity, sizeof(uint32_t), p->keep))
    return MPM_ERR_NOMEM;
  mpm_real *block;
  if (p->block) UNPOISON(p->block, block_bytes(p->stride));
  if (p->block && !(p->keep && p->keep->holds > 0)) {
    /* in place: the mapping grows (its pages move, no copy), then the arrays move up to their
       new slots, the top one first (each lands above every slot still to move) */
    block = mpm_block_grow(p->block, block_bytes(p->stride), block_bytes(stride));
    if (!block) return MPM_ERR_NOMEM;
    for (int k = MPM_PARTICLE_REAL_ARRAYS - 1; k >= 0; --k) {
      const size_t slot = (size_t)(p->first + k);
      if (p->count)
        memmove(block + slot * stride, block + slot * p->stride, p->count * sizeof(mpm_real));
    }
  } else {
    /* a new block (the first, or the old one is held by a view and must stay where it is) */
    block = mpm_block_alloc(block_bytes(stride));
    if (!block) return MPM_ERR_NOMEM;
    mpm_real **arrays[MPM_PARTICLE_REAL_ARRAYS];
    mpm_particles_real_arrays(p, arrays);
    for (int k = 0; k < MPM_PARTICLE_REAL_ARRAYS; ++k)
      if (p->count)
        memcpy(block + (size_t)(p->first + k) * stride, *arrays[k], p->count * sizeof(mpm_real));
    if (p->block) mpm_keep_free_block(p->keep, p->block, block_bytes(p->stride));
  }
  p->block = block;
  p->stride = stride;
  p->capacity = capacity;
  point_arrays(p);
  poison_padding(p);
  return MPM_OK;
}

mpm_status mpm_particles_fit(mpm_particles *p) {
  const size_t want = p->count + p->count / 16 + 16;
  if (!p->block || want >= p->capacity || (p->keep && p->keep->holds > 0)) return MPM_OK;
  const size_t stride = slot_stride(want), old = p->stride;
  if (stride >= old) return MPM_OK; /* within the pages it has */
  mpm_real *block = p->block;
  UNPOISON(block, block_bytes(old));
  /* the arrays down to their new slots, the lowest first (each lands below every slot still to
     move), then the mapping shrinks; moved back up should it fail */
  for (int k = 0; k < MPM_PARTICLE_REAL_ARRAYS; ++k) {
    const size_t slot = (size_t)(p->first + k);
    if (p->count) memmove(block + slot * stride, block + slot * old, p->count * sizeof(mpm_real));
  }
  mpm_real *fitted = mpm_block_grow(block, block_bytes(old), block_bytes(stride));
  if (!fitted) {
    for (int k = MPM_PARTICLE_REAL_ARRAYS - 1; k >= 0; --k) {
      const size_t slot = (size_t)(p->first + k);
      if (p->count) memmove(block + slot * old, block + slot * stride, p->count * sizeof(mpm_real));
    }
    poison_padding(p);
    return MPM_ERR_NOMEM;
  }
  p->block = fitted;
  p->stride = stride;
  p->capacity = want;
  point_arrays(p);
  poison_padding(p);
  /* the integer arrays likewise (a failure leaves them larger than needed, which is fine) */
  if (regrow((void **)&p->material, p->count, want, sizeof(int32_t), p->keep) ||
      regrow((void **)&p->body, p->count, want, sizeof(int32_t), p->keep) ||
      regrow((void **)&p->level, p->count, want, sizeof(int32_t), p->keep) ||
      regrow((void **)&p->id, p->count, want, sizeof(uint32_t), p->keep))
    return MPM_ERR_NOMEM;
  return MPM_OK;
}

mpm_status mpm_particles_init(mpm_particles *p, size_t capacity) {
  memset(p, 0, sizeof *p);
  return mpm_particles_reserve(p, capacity < 16 ? 16 : capacity);
}

void mpm_particles_free(mpm_particles *p) {
  if (p->block) {
    UNPOISON(p->block, block_bytes(p->stride));
    mpm_keep_free_block(p->keep, p->block, block_bytes(p->stride));
  }
  mpm_keep_free(p->keep, p->material);
  mpm_keep_free(p->keep, p->body);
  mpm_keep_free(p->keep, p->level);
  mpm_keep_free(p->keep, p->id);
  memset(p, 0, sizeof *p);
}

long mpm_particles_push(mpm_particles *p, const mpm_real x[3], const mpm_real v[3], mpm_real mass,
                        mpm_real vol0, int32_t material, int32_t body) {
  if (p->count == p->capacity && mpm_particles_reserve(p, p->capacity * 2)) return -1;
  size_t i = p->count++;
  for (int d = 0; d < 3; ++d) {
    p->x[d][i] = x[d];
    p->xc[d][i] = 0;
    p->v[d][i] = v[d];
  }
  for (int d = 0; d < 9; ++d) {
    p->F[d][i] = (d % 4 == 0) ? 1 : 0;
    p->B[d][i] = 0;
  }
  p->plastic[i] = 1;
  p->mass[i] = mass;
  p->vol0[i] = vol0;
  p->temperature[i] = 0;
  p->material[i] = material;
  p->body[i] = body;
  p->level[i] = 0;
  p->id[i] = (uint32_t)i;
  return (long)i;
}

/* The 32-bit integer arrays, as words (permutes move them without looking inside). */
static void int_arrays(mpm_particles *p, uint32_t *a[4]) {
  a[0] = (uint32_t *)p->material;
  a[1] = (uint32_t *)p->body;
  a[2] = (uint32_t *)p->level;
  a[3] = p->id;
}

/* The free slot: the end away from p->first. */
static mpm_real *free_slot(const mpm_particles *p) {
  return p->block + (size_t)(p->first ? 0 : MPM_PARTICLE_REAL_ARRAYS) * p->stride;
}

void mpm_particles_permute(mpm_particles *p, const uint32_t *perm, uint32_t *iscratch) {
  const long n = (long)p->count;
  if (n == 0) return;
  mpm_real **arrays[MPM_PARTICLE_REAL_ARRAYS];
  mpm_particles_real_arrays(p, arrays);
  /* each array into the free slot beside it, walking away from the free slot: from the top when
     it is the last slot (each array one slot up), from the bottom when it is the first */
  const int up = p->first == 0;
  for (int j = 0; j < MPM_PARTICLE_REAL_ARRAYS; ++j) {
    const int k = up ? MPM_PARTICLE_REAL_ARRAYS - 1 - j : j;
    const mpm_real *src = *arrays[k];
    mpm_real *dst = p->block + (size_t)(k + (up ? 1 : 0)) * p->stride;
#pragma omp parallel for schedule(static)
    for (long i = 0; i < n; ++i) dst[i] = src[perm[i]];
    *arrays[k] = dst;
  }
  p->first = up;
  /* integer arrays go through the integer scratch (their pointers stay) */
  uint32_t *iarrays[4];
  int_arrays(p, iarrays);
  for (int k = 0; k < 4; ++k) {
    const uint32_t *src = iarrays[k];
#pragma omp parallel for schedule(static)
    for (long i = 0; i < n; ++i) iscratch[i] = src[perm[i]];
    memcpy(iarrays[k], iscratch, (size_t)n * sizeof(uint32_t));
  }
}

void mpm_particles_move(mpm_particles *p, const uint32_t *dest, const uint32_t *src, size_t n,
                        uint32_t *iscratch) {
  if (n == 0) return;
  mpm_real *rscratch = free_slot(p);
  mpm_real **arrays[MPM_PARTICLE_REAL_ARRAYS];
  mpm_particles_real_arrays(p, arrays);
  for (int k = 0; k < MPM_PARTICLE_REAL_ARRAYS; ++k) {
    mpm_real *a = *arrays[k];
    for (size_t j = 0; j < n; ++j) rscratch[j] = a[src[j]];
    for (size_t j = 0; j < n; ++j) a[dest[j]] = rscratch[j];
  }
  uint32_t *iarrays[4];
  int_arrays(p, iarrays);
  for (int k = 0; k < 4; ++k) {
    uint32_t *a = iarrays[k];
    for (size_t j = 0; j < n; ++j) iscratch[j] = a[src[j]];
    for (size_t j = 0; j < n; ++j) a[dest[j]] = iscratch[j];
  }
}

size_t mpm_order_breaks(const uint32_t *perm, size_t n) {
  const long m = (long)n;
  long breaks = 0;
#pragma omp parallel for schedule(static) reduction(+ : breaks) if (m > MPM_PARALLEL_MIN)
  for (long j = 1; j < m; ++j) breaks += perm[j] != perm[j - 1] + 1;
  return (size_t)breaks;
}

int mpm_reorder_due(int64_t steps, int interval, size_t breaks, size_t n) {
  if (steps % interval == 0) return 1;
  /* the order's breaks: the transfers read the particles in perm's order, so they stream while
   * it runs through memory and gather once particles have moved to other cells. Reordering
   * costs about a fifth of a step; a moving body breaks a tenth of the order within a few steps
   * and then costs more than that in gathers (bench step, 100 steps of a falling block, 1 thread:
   * 101.5 ns per particle-step reordering every 16 steps, 88.8-89.1 reordering also when a
   * twentieth to a seventh of the order is broken, 99.3 at three tenths). The decision follows
   * from the state alone, so a resumed run takes the same ones. */
  return (double)breaks > 0.1 * (double)n;
}

mpm_status mpm_particles_scratch(const mpm_particles *p, uint32_t **scratch, size_t *capacity) {
  const size_t cap = p->capacity;
  if (*capacity >= cap) return MPM_OK;
  mpm_free(*scratch);
  *scratch = mpm_alloc(cap * sizeof(uint32_t));
  if (!*scratch) {
    *capacity = 0;
    return MPM_ERR_NOMEM;
  }
  *capacity = cap;
  return MPM_OK;
}

/* Every array of a set, looked up once for a loop of single-particle copies. */
typedef struct particle_arrays {
  mpm_real *real[MPM_PARTICLE_REAL_ARRAYS];
  uint32_t *word[4];
} particle_arrays;

static particle_arrays arrays_of(const mpm_particles *p) {
  particle_arrays a;
  mpm_real **r[MPM_PARTICLE_REAL_ARRAYS];
  mpm_particles_real_arrays((mpm_particles *)p, r);
  for (int k = 0; k < MPM_PARTICLE_REAL_ARRAYS; ++k) a.real[k] = *r[k];
  int_arrays((mpm_particles *)p, a.word);
  return a;
}

static void copy_one(const particle_arrays *to, size_t j, const particle_arrays *from, size_t i) {
  for (int k = 0; k < MPM_PARTICLE_REAL_ARRAYS; ++k) to->real[k][j] = from->real[k][i];
  for (int k = 0; k < 4; ++k) to->word[k][j] = from->word[k][i];
}

void mpm_particles_copy(mpm_particles *dst, size_t j, const mpm_particles *src, size_t i) {
  const particle_arrays to = arrays_of(dst), from = arrays_of(src);
  copy_one(&to, j, &from, i);
}

long mpm_particles_append(mpm_particles *dst, const mpm_particles *src, size_t i) {
  if (dst->count == dst->capacity &&
      mpm_particles_reserve(dst, dst->capacity > 8 ? 2 * dst->capacity : 16))
    return -1;
  const size_t j = dst->count++;
  mpm_particles_copy(dst, j, src, i);
  return (long)j;
}

mpm_status mpm_particles_append_set(mpm_particles *dst, const mpm_particles *src,
                                    const uint8_t *keep) {
  size_t n = 0;
  for (size_t i = 0; i < src->count; ++i) n += !keep || keep[i];
  if (dst->count + n > dst->capacity && mpm_particles_reserve(dst, dst->count + n))
    return MPM_ERR_NOMEM;
  const particle_arrays to = arrays_of(dst), from = arrays_of(src);
  for (size_t i = 0; i < src->count; ++i)
    if (!keep || keep[i]) copy_one(&to, dst->count++, &from, i);
  return MPM_OK;
}

mpm_status mpm_particles_assign(mpm_particles *dst, const mpm_particles *src) {
  /* a copy may become the particles (the guard's restore swaps them): it always has arrays */
  const size_t want = src->capacity > 16 ? src->capacity : 16;
  if ((dst->capacity < src->count || !dst->capacity) && mpm_particles_reserve(dst, want))
    return MPM_ERR_NOMEM;
  dst->count = 0;
  const size_t n = src->count;
  if (!n) return MPM_OK;
  mpm_real **a[MPM_PARTICLE_REAL_ARRAYS], **b[MPM_PARTICLE_REAL_ARRAYS];
  mpm_particles_real_arrays((mpm_particles *)src, a);
  mpm_particles_real_arrays(dst, b);
  for (int k = 0; k < MPM_PARTICLE_REAL_ARRAYS; ++k) memcpy(*b[k], *a[k], n * sizeof(mpm_real));
  uint32_t *ia[4], *ib[4];
  int_arrays((mpm_particles *)src, ia);
  int_arrays(dst, ib);
  for (int k = 0; k < 4; ++k) memcpy(ib[k], ia[k], n * sizeof(uint32_t));
  dst->count = n;
  return MPM_OK;
}

void mpm_particles_remove(mpm_particles *p, const uint8_t *gone) {
  const particle_arrays a = arrays_of(p);
  size_t w = 0;
  for (size_t i = 0; i < p->count; ++i) {
    if (gone[i]) continue;
    if (w != i) copy_one(&a, w, &a, i);
    ++w;
  }
  p->count = w;
}

size_t mpm_particles_packed_bytes(void) {
  return MPM_PARTICLE_REAL_ARRAYS * sizeof(mpm_real) + 4 * sizeof(uint32_t);
}

void mpm_particles_pack(const mpm_particles *p, const uint32_t *idx, size_t n, void *buf) {
  mpm_real **a[MPM_PARTICLE_REAL_ARRAYS];
  uint32_t *ia[4];
  mpm_particles_real_arrays((mpm_particles *)p, a);
  int_arrays((mpm_particles *)p, ia);
  unsigned char *out = buf;
  for (size_t q = 0; q < n; ++q) {
    const size_t i = idx[q];
    for (int k = 0; k < MPM_PARTICLE_REAL_ARRAYS; ++k, out += sizeof(mpm_real))
      memcpy(out, &(*a[k])[i], sizeof(mpm_real));
    for (int k = 0; k < 4; ++k, out += sizeof(uint32_t)) memcpy(out, &ia[k][i], sizeof(uint32_t));
  }
}

mpm_status mpm_particles_unpack(mpm_particles *p, const void *buf, size_t n) {
  if (p->count + n > p->capacity && mpm_particles_reserve(p, p->count + n)) return MPM_ERR_NOMEM;
  mpm_real **a[MPM_PARTICLE_REAL_ARRAYS];
  uint32_t *ia[4];
  mpm_particles_real_arrays(p, a);
  int_arrays(p, ia);
  const unsigned char *in = buf;
  for (size_t q = 0; q < n; ++q) {
    const size_t j = p->count + q;
    for (int k = 0; k < MPM_PARTICLE_REAL_ARRAYS; ++k, in += sizeof(mpm_real))
      memcpy(&(*a[k])[j], in, sizeof(mpm_real));
    for (int k = 0; k < 4; ++k, in += sizeof(uint32_t)) memcpy(&ia[k][j], in, sizeof(uint32_t));
  }
  p->count += n;
  return MPM_OK;
}
