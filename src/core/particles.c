/* particles.c - structure-of-arrays storage of material points (see particles.h). */
#include "core/particles.h"
#include "core/alloc.h"
#include "core/parallel.h"

#include <string.h>

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

static int regrow(void **ptr, size_t old_count, size_t new_count, size_t elem) {
  void *q = mpm_alloc(new_count * elem);
  if (!q) return -1;
  if (*ptr && old_count) memcpy(q, *ptr, old_count * elem);
  mpm_free(*ptr);
  *ptr = q;
  return 0;
}

int mpm_particles_reserve(mpm_particles *p, size_t capacity) {
  if (capacity <= p->capacity) return 0;
  mpm_real **arrays[MPM_PARTICLE_REAL_ARRAYS];
  mpm_particles_real_arrays(p, arrays);
  for (int k = 0; k < MPM_PARTICLE_REAL_ARRAYS; ++k)
    if (regrow((void **)arrays[k], p->count, capacity, sizeof(mpm_real))) return -1;
  if (regrow((void **)&p->material, p->count, capacity, sizeof(int32_t)) ||
      regrow((void **)&p->body, p->count, capacity, sizeof(int32_t)) ||
      regrow((void **)&p->level, p->count, capacity, sizeof(int32_t)) ||
      regrow((void **)&p->id, p->count, capacity, sizeof(uint32_t)))
    return -1;
  p->capacity = capacity;
  return 0;
}

int mpm_particles_init(mpm_particles *p, size_t capacity) {
  memset(p, 0, sizeof *p);
  return mpm_particles_reserve(p, capacity < 16 ? 16 : capacity);
}

void mpm_particles_free(mpm_particles *p) {
  mpm_real **arrays[MPM_PARTICLE_REAL_ARRAYS];
  mpm_particles_real_arrays(p, arrays);
  for (int k = 0; k < MPM_PARTICLE_REAL_ARRAYS; ++k) mpm_free(*arrays[k]);
  mpm_free(p->material);
  mpm_free(p->body);
  mpm_free(p->level);
  mpm_free(p->id);
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

void mpm_particles_permute(mpm_particles *p, const uint32_t *perm, mpm_real **scratch,
                           uint32_t *iscratch) {
  const long n = (long)p->count;
  if (n == 0) return;
  mpm_real **arrays[MPM_PARTICLE_REAL_ARRAYS];
  mpm_particles_real_arrays(p, arrays);
  for (int k = 0; k < MPM_PARTICLE_REAL_ARRAYS; ++k) {
    const mpm_real *src = *arrays[k];
    mpm_real *dst = *scratch;
#pragma omp parallel for schedule(static)
    for (long i = 0; i < n; ++i) dst[i] = src[perm[i]];
    *scratch = *arrays[k];
    *arrays[k] = dst;
  }
  /* integer arrays go through the integer scratch the same way */
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
                        mpm_real *rscratch, uint32_t *iscratch) {
  if (n == 0) return;
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
