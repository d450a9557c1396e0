/* test_particle_storage.c - the particle set's storage (core/particles.h) and the memory a
 * binding holds (core/alloc.h, mpm_keep):
 *   - the 31 real arrays lie `stride` reals apart, in order, before and after reorders (the
 *     public view's component stride), and a reorder moves every array's values as the
 *     permutation says, through the free slot;
 *   - growing keeps every value (the block grows in place) and, while a holder holds the keep,
 *     leaves the old block readable with its values; releasing the hold gives it back (the
 *     live-byte counter returns);
 *   - move through the free slot, a range owns no storage;
 *   - the moves that keep a particle whole (copy, append, assign, remove, and the migration's
 *     pack and unpack, append by mask) carry every array: each value lands where the move says. */
#include "support.h"
#include "core/alloc.h"
#include "core/particles.h"

#include <string.h>

/* n particles whose real arrays hold k * 1000 + i and integers i, 2 i, 3 i, 4 i */
static void fill(mpm_particles *p, size_t n) {
  const mpm_real zero[3] = {0, 0, 0};
  for (size_t i = 0; i < n; ++i) assert_true(mpm_particles_push(p, zero, zero, 1, 1, 0, 0) >= 0);
  mpm_real **a[MPM_PARTICLE_REAL_ARRAYS];
  mpm_particles_real_arrays(p, a);
  for (int k = 0; k < MPM_PARTICLE_REAL_ARRAYS; ++k)
    for (size_t i = 0; i < n; ++i) (*a[k])[i] = (mpm_real)(k * 1000 + (int)i);
  for (size_t i = 0; i < n; ++i) {
    p->material[i] = (int32_t)i;
    p->body[i] = (int32_t)(2 * i);
    p->level[i] = (int32_t)(3 * i);
    p->id[i] = (uint32_t)(4 * i);
  }
}

/* Every real array at block + (first + k) stride, and particle i holds the values of original
 * particle orig[i]. */
static void check(mpm_particles *p, const uint32_t *orig) {
  mpm_real **a[MPM_PARTICLE_REAL_ARRAYS];
  mpm_particles_real_arrays(p, a);
  for (int k = 0; k < MPM_PARTICLE_REAL_ARRAYS; ++k) {
    assert_ptr_equal(*a[k], p->block + (size_t)(p->first + k) * p->stride);
    for (size_t i = 0; i < p->count; ++i)
      assert_true((*a[k])[i] == (mpm_real)(k * 1000 + (int)orig[i]));
  }
  for (size_t i = 0; i < p->count; ++i) {
    assert_int_equal(p->material[i], (int32_t)orig[i]);
    assert_int_equal(p->body[i], (int32_t)(2 * orig[i]));
    assert_int_equal(p->level[i], (int32_t)(3 * orig[i]));
    assert_int_equal(p->id[i], 4 * orig[i]);
  }
  assert_true(p->stride >= p->capacity);
}

static void test_reorders_keep_the_layout(void **state) {
  (void)state;
  enum { N = 500 };
  mpm_particles p;
  assert_int_equal(mpm_particles_init(&p, 16), MPM_OK);
  fill(&p, N); /* grown from 16 by pushes: the block grew in place several times */
  uint32_t orig[N], perm[N], next[N], iscratch[N];
  for (uint32_t i = 0; i < N; ++i) orig[i] = i;
  check(&p, orig);
  uint64_t rng = 7;
  for (int round = 0; round < 5; ++round) { /* odd and even: the free slot at both ends */
    for (uint32_t i = 0; i < N; ++i) perm[i] = i;
    for (uint32_t i = N - 1; i > 0; --i) {
      const uint32_t j = (uint32_t)test_rand(&rng, 0, i + 1), t = perm[i];
      perm[i] = perm[j], perm[j] = t;
    }
    const int first = p.first;
    mpm_particles_permute(&p, perm, iscratch);
    assert_int_equal(p.first, 1 - first);
    for (uint32_t i = 0; i < N; ++i) next[i] = orig[perm[i]];
    memcpy(orig, next, sizeof orig);
    check(&p, orig);
  }
  /* three particles trade places through the free slot */
  const uint32_t src[3] = {5, 9, 200}, dest[3] = {9, 200, 5};
  mpm_particles_move(&p, dest, src, 3, iscratch);
  const uint32_t o5 = orig[5], o9 = orig[9], o200 = orig[200];
  orig[9] = o5, orig[200] = o9, orig[5] = o200;
  check(&p, orig);
  /* a range offsets the arrays and owns nothing */
  const mpm_particles r = mpm_particles_range(&p, 100, 50);
  assert_null(r.block);
  assert_ptr_equal(r.x[1], p.x[1] + 100);
  mpm_particles_free(&p);
}

static void test_held_blocks_stay(void **state) {
  (void)state;
  const size_t live0 = mpm_alloc_live_bytes();
  mpm_keep keep = {0};
  mpm_particles p;
  assert_int_equal(mpm_particles_init(&p, 64), MPM_OK);
  p.keep = &keep;
  fill(&p, 64);
  /* a holder has the arrays' pointers: growing must not free or move them */
  mpm_keep_hold(&keep, 1);
  const mpm_real *old_x = p.x[0], *old_F8 = p.F[8];
  const uint32_t *old_id = p.id;
  assert_int_equal(mpm_particles_reserve(&p, 100000), MPM_OK);
  assert_ptr_not_equal(p.x[0], old_x);
  assert_true(keep.count > 0);
  for (size_t i = 0; i < 64; ++i) {
    assert_true(old_x[i] == (mpm_real)(0 * 1000 + (int)i));
    assert_true(old_F8[i] == (mpm_real)(14 * 1000 + (int)i));
    assert_int_equal(old_id[i], 4 * i);
  }
  uint32_t orig[64];
  for (uint32_t i = 0; i < 64; ++i) orig[i] = i;
  check(&p, orig);
  /* a second hold, released first: nothing freed until the last */
  mpm_keep_hold(&keep, 1);
  mpm_keep_hold(&keep, -1);
  assert_true(keep.count > 0);
  const size_t held = mpm_alloc_live_bytes();
  mpm_keep_hold(&keep, -1);
  assert_int_equal(keep.count, 0);
  assert_true(mpm_alloc_live_bytes() < held);
  /* without a hold the block grows in place and nothing is kept */
  assert_int_equal(mpm_particles_reserve(&p, 300000), MPM_OK);
  assert_int_equal(keep.count, 0);
  check(&p, orig);
  mpm_particles_free(&p);
  assert_int_equal(mpm_alloc_live_bytes(), live0);
}

/* Fitting gives back the pages past count + count/16, keeps every value in its slot layout,
 * and does nothing while the arrays are held or when no whole page is spare; the set grows
 * again after it. */
static void test_fit_gives_back_spare_capacity(void **state) {
  (void)state;
  const size_t live0 = mpm_alloc_live_bytes();
  enum { N = 140000 }; /* pushes from 16 double past it, to 262144 */
  mpm_particles p;
  assert_int_equal(mpm_particles_init(&p, 16), MPM_OK);
  fill(&p, N);
  static uint32_t orig[N + 1000];
  for (uint32_t i = 0; i < N + 1000; ++i) orig[i] = i;
  assert_true(p.capacity >= 2 * 131072);
  mpm_keep keep = {0};
  p.keep = &keep;
  mpm_keep_hold(&keep, 1); /* held: nothing moves */
  const size_t capacity = p.capacity;
  assert_int_equal(mpm_particles_fit(&p), MPM_OK);
  assert_int_equal(p.capacity, capacity);
  mpm_keep_hold(&keep, -1);
  const size_t before = mpm_alloc_live_bytes();
  assert_int_equal(mpm_particles_fit(&p), MPM_OK);
  assert_true(p.capacity < capacity && p.capacity >= N + N / 16);
  assert_true(mpm_alloc_live_bytes() < before - 31 * (capacity - p.capacity) * sizeof(mpm_real));
  check(&p, orig);
  const size_t fitted = p.capacity;
  assert_int_equal(mpm_particles_fit(&p), MPM_OK); /* nothing spare now */
  assert_int_equal(p.capacity, fitted);
  const mpm_real zero[3] = {0, 0, 0}; /* and it grows again */
  for (int i = 0; i < 20000; ++i) assert_true(mpm_particles_push(&p, zero, zero, 1, 1, 0, 0) >= 0);
  p.count = N;
  check(&p, orig);
  mpm_particles_free(&p);
  assert_int_equal(mpm_alloc_live_bytes(), live0);
}

/* Particles q of `got` are original particles orig[q] of a set filled by fill(). */
static void check_values(mpm_particles *got, const uint32_t *orig) {
  mpm_real **a[MPM_PARTICLE_REAL_ARRAYS];
  mpm_particles_real_arrays(got, a);
  for (int k = 0; k < MPM_PARTICLE_REAL_ARRAYS; ++k)
    for (size_t i = 0; i < got->count; ++i)
      assert_true((*a[k])[i] == (mpm_real)(k * 1000 + (int)orig[i]));
  for (size_t i = 0; i < got->count; ++i) {
    assert_int_equal(got->material[i], (int32_t)orig[i]);
    assert_int_equal(got->body[i], (int32_t)(2 * orig[i]));
    assert_int_equal(got->level[i], (int32_t)(3 * orig[i]));
    assert_int_equal(got->id[i], 4 * orig[i]);
  }
}

static void test_moves_keep_particles_whole(void **state) {
  (void)state;
  mpm_particles p = {0}, q = {0}, r = {0};
  assert_int_equal(mpm_particles_init(&p, 8), MPM_OK);
  assert_int_equal(mpm_particles_init(&q, 4), MPM_OK);
  assert_int_equal(mpm_particles_init(&r, 4), MPM_OK);
  fill(&p, 40);
  /* pack particles 3, 17, 39, 0 and unpack them after two appended ones */
  const uint32_t idx[4] = {3, 17, 39, 0};
  unsigned char *buf = mpm_alloc(4 * mpm_particles_packed_bytes());
  assert_non_null(buf);
  mpm_particles_pack(&p, idx, 4, buf);
  assert_int_equal(mpm_particles_append(&q, &p, 5), 0);
  assert_int_equal(mpm_particles_append(&q, &p, 6), 1);
  assert_int_equal(mpm_particles_unpack(&q, buf, 4), MPM_OK);
  const uint32_t want_q[6] = {5, 6, 3, 17, 39, 0};
  assert_int_equal(q.count, 6);
  check_values(&q, want_q);
  /* copy one over another, then remove every third */
  mpm_particles_copy(&q, 1, &p, 22);
  uint8_t gone[6] = {0, 0, 1, 0, 0, 1};
  mpm_particles_remove(&q, gone);
  const uint32_t want_removed[4] = {5, 22, 17, 39};
  assert_int_equal(q.count, 4);
  check_values(&q, want_removed);
  /* a whole copy */
  assert_int_equal(mpm_particles_assign(&r, &p), MPM_OK);
  uint32_t all[40];
  for (uint32_t i = 0; i < 40; ++i) all[i] = i;
  assert_int_equal(r.count, 40);
  check_values(&r, all);
  /* those of a mask appended after them */
  uint8_t keep[40] = {0};
  keep[7] = keep[30] = 1;
  assert_int_equal(mpm_particles_append_set(&r, &p, keep), MPM_OK);
  const uint32_t tail[2] = {7, 30};
  assert_int_equal(r.count, 42);
  mpm_particles tail_set = mpm_particles_range(&r, 40, 2); /* the two appended */
  check_values(&tail_set, tail);
  mpm_free(buf);
  mpm_particles_free(&p);
  mpm_particles_free(&q);
  mpm_particles_free(&r);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_reorders_keep_the_layout),
      cmocka_unit_test(test_held_blocks_stay),
      cmocka_unit_test(test_fit_gives_back_spare_capacity),
      cmocka_unit_test(test_moves_keep_particles_whole),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
