/* particles.h - material points stored as structure of arrays.
 *
 * Every component is its own aligned array so that kernels stream and vectorize across
 * particles. The order of particles changes every step (they are sorted into grid blocks);
 * `id` is the stable identity written to outputs.
 *
 * The 31 real arrays share one block of 32 slots of `stride` reals each, in
 * mpm_particles_real_arrays order from slot `first` (0 or 1); the other end's slot is free. A
 * reorder gathers each array into its free neighbour, walking away from the free slot, so the
 * free slot moves to the other end and the arrays stay in order: a vector's components (x, v,
 * F, ...) are always `stride` reals apart, which the public view states (a binding can show
 * them as one strided array without a copy), and the reorder needs no scratch of its own.
 * The slot stride is the capacity rounded up to whole 4 KiB pages plus 128 bytes, so that
 * element i of consecutive arrays falls in different cache sets (as alloc.c staggers separate
 * arrays). */
#ifndef MPM_CORE_PARTICLES_H
#define MPM_CORE_PARTICLES_H

#include "core/real.h"
#include "mpm/mpm.h"

#include <stddef.h>
#include <stdint.h>

typedef struct mpm_particles {
  size_t count, capacity;
  mpm_real *x[3];        /* position, m */
  mpm_real *xc[3];       /* what the rounded x could not hold of the position, m: the steps'
                            moves are summed with compensation (Knuth's TwoSum), so that a body
                            drifting slowly does not round differently on either side of a
                            power of two in float, nor move farther than its velocity says
                            (issue 13); 0 after a jump (sampling, split, merge, release) */
  mpm_real *v[3];        /* velocity, m/s */
  mpm_real *F[9];        /* deformation gradient, row-major components */
  mpm_real *B[9];        /* APIC affine moment B_p = C_p D_p (Jiang et al. 2015), m^2/s, row-major.
                            Storing B rather than C keeps angular momentum exact for every kernel,
                            including those whose D_p varies with position (linear, uGIMP). */
  mpm_real *plastic;     /* plastic state of the material's model (snow: J_p), 1 at rest */
  mpm_real *mass;        /* kg */
  mpm_real *vol0;        /* initial volume V_p^0, m^3 */
  mpm_real *temperature; /* heat (heat/heat.h): the scene's temperature unit (K or degrees
                            C); 0 and unused without a scene `heat` */
  int32_t *material;
  int32_t *body;
  int32_t *level; /* particle type (Gao et al. sec. 7.1): the grid level whose spacing its box
                     matches, L_p = dx_level; 0 on a uniform grid */
  uint32_t *id;
  /* storage (see above): NULL block for a range of another set (mpm_particles_range) */
  mpm_real *block;
  size_t stride; /* reals from one real array to the next */
  int first;     /* the slot of the first real array, 0 or 1 */
  /* NULL, or where replaced arrays go instead of being freed while a view holds them */
  struct mpm_keep *keep;
} mpm_particles;

/* All real-valued component arrays, for loops that treat them alike (permute, grow). */
#define MPM_PARTICLE_REAL_ARRAYS 31

/* An empty set with room for `capacity` particles (at least 16); room for `capacity` in all, the
 * particles kept. Each MPM_OK, or MPM_ERR_NOMEM when out of memory. */
mpm_status mpm_particles_init(mpm_particles *p, size_t capacity);
void mpm_particles_free(mpm_particles *p);
mpm_status mpm_particles_reserve(mpm_particles *p, size_t capacity);
/* Give back the capacity past count + count / 16 (+ 16) when whole pages of every array are
 * spare: a set sampled by appending grows by doubling, and up to half of it can lie unused.
 * Nothing while a view holds the arrays. MPM_OK, or MPM_ERR_NOMEM when out of memory (the set as
 * it was, or with larger integer arrays than needed). */
mpm_status mpm_particles_fit(mpm_particles *p);

/* Append one particle at rest state (F = I, B = 0, xc = 0, level 0, temperature 0); returns its
 * index or -1 on OOM. */
long mpm_particles_push(mpm_particles *p, const mpm_real x[3], const mpm_real v[3], mpm_real mass,
                        mpm_real vol0, int32_t material, int32_t body);

/* Pointers to the 31 real arrays, in a fixed order (xc last). */
void mpm_particles_real_arrays(mpm_particles *p, mpm_real **arrays[MPM_PARTICLE_REAL_ARRAYS]);

/* Particles begin .. begin + count of p as a set of their own: every array of p offset, none
 * copied (writes go to p). For transfers over a contiguous range (the multi-level grid's
 * transfer grids); it offsets every array, so that an array added later cannot be left behind. */
mpm_particles mpm_particles_range(const mpm_particles *p, size_t begin, size_t count);

/* Reorder all arrays so that new[i] = old[perm[i]]: the real arrays' pointers change (each moves
 * one slot), the integer arrays go through iscratch (`count` integers) and keep theirs. Parallel
 * over particles. p must own its storage (not a range). */
void mpm_particles_permute(mpm_particles *p, const uint32_t *perm, uint32_t *iscratch);

/* The breaks of a sort's visiting order perm[0 .. n): the j with perm[j] != perm[j - 1] + 1. */
size_t mpm_order_breaks(const uint32_t *perm, size_t n);
/* Whether a sort moves its n particles into their sorted order at step `steps`: every
 * `interval` steps, and between them when the order has come apart (`breaks` of it,
 * mpm_order_breaks). */
int mpm_reorder_due(int64_t steps, int interval, size_t breaks, size_t n);
/* Room in *scratch for the permute's per-particle integers, p's capacity of them (*capacity:
 * what it holds, grown when smaller). MPM_OK, or MPM_ERR_NOMEM when out of memory. */
mpm_status mpm_particles_scratch(const mpm_particles *p, uint32_t **scratch, size_t *capacity);

/* Particle moves that keep every array together (a particle's state never stays behind: its
 * reals, material, body, type and id move as one). Copy particle i of src over slot j of dst
 * (dst may be src); append particle i of src to dst (grown as needed: its index, or -1 when out
 * of memory); make dst a copy of the whole of src (grown as needed: MPM_OK, or MPM_ERR_NOMEM);
 * remove the
 * particles with gone[i] set, the others keeping their order. */
void mpm_particles_copy(mpm_particles *dst, size_t j, const mpm_particles *src, size_t i);
long mpm_particles_append(mpm_particles *dst, const mpm_particles *src, size_t i);
/* Append the particles of src with keep[i] set (every one when keep is NULL), in order. MPM_OK,
 * or MPM_ERR_NOMEM when out of memory (dst as it was). */
mpm_status mpm_particles_append_set(mpm_particles *dst, const mpm_particles *src,
                                    const uint8_t *keep);
mpm_status mpm_particles_assign(mpm_particles *dst, const mpm_particles *src);
void mpm_particles_remove(mpm_particles *p, const uint8_t *gone);

/* Migration between processes: particles idx[0 .. n) of p packed into buf
 * (n mpm_particles_packed_bytes() bytes: every array of each), and n packed particles appended
 * to p as they were (MPM_OK, or MPM_ERR_NOMEM when out of memory: p as it was). */
size_t mpm_particles_packed_bytes(void);
void mpm_particles_pack(const mpm_particles *p, const uint32_t *idx, size_t n, void *buf);
mpm_status mpm_particles_unpack(mpm_particles *p, const void *buf, size_t n);

/* Move particle src[k] to slot dest[k] in every array, k < n, where dest is a permutation of src
 * (the particles at those slots trade places; the others stay), through the free slot and
 * iscratch (n integers). For reorders that touch a few particles: a full permute reads and
 * writes every array whole. */
void mpm_particles_move(mpm_particles *p, const uint32_t *dest, const uint32_t *src, size_t n,
                        uint32_t *iscratch);

#endif
