/* test_partition.c - the distributed run's ownership of blocks (src/dist/partition.h): Morton
 * keys against the bit-by-bit definition, and the cut into ranks: every block owned, contiguous
 * ranges in key order, weights even to within one block, the same cut whatever the order of the
 * blocks given, ranks left without blocks, and octants as ranges (a cube of blocks cut in eight
 * by count gives each rank one octant: ranges are compact in space). */
#include "support.h"
#include "dist/partition.h"

#include <math.h>
#include <stdlib.h>

/* The definition: bit b of x, y, z at bits 3 b + 2, 3 b + 1, 3 b of the key. */
static uint64_t morton_by_bits(const int32_t c[3]) {
  uint64_t key = 0;
  for (int b = MPM_MORTON_BITS - 1; b >= 0; --b)
    for (int a = 0; a < 3; ++a) {
      const uint64_t v = (uint64_t)(int64_t)(c[a] + (1 << (MPM_MORTON_BITS - 1)));
      key = key << 1 | ((v >> b) & 1u);
    }
  return key;
}

static void test_morton(void **state) {
  (void)state;
  srand(7);
  for (int i = 0; i < 10000; ++i) {
    int32_t c[3], back[3];
    for (int a = 0; a < 3; ++a)
      c[a] = (int32_t)(rand() % (1 << MPM_MORTON_BITS)) - (1 << (MPM_MORTON_BITS - 1));
    if (i < 8) c[0] = c[1] = c[2] = (i & 1 ? -1 : 1) * (i >> 1); /* around the origin */
    const uint64_t key = mpm_morton_key(c);
    assert_true(key == morton_by_bits(c));
    assert_true(key < (UINT64_C(1) << 63));
    mpm_morton_coords(key, back);
    assert_memory_equal(c, back, sizeof c);
  }
}

/* n blocks of random weight in [0.5, 1.5), cut into each rank count up to 9 */
static void test_cut_even(void **state) {
  (void)state;
  enum { N = 2000 };
  uint64_t *keys = malloc(N * sizeof *keys);
  double *w = malloc(N * sizeof *w), rank_w[9];
  srand(11);
  double total = 0;
  for (int i = 0; i < N; ++i) {
    const int32_t c[3] = {rand() % 64, rand() % 64, rand() % 64};
    keys[i] = mpm_morton_key(c);
    w[i] = 0.5 + (double)rand() / RAND_MAX;
    total += w[i];
  }
  for (int ranks = 1; ranks <= 9; ++ranks) {
    mpm_partition pt;
    assert_int_equal(mpm_partition_cut(&pt, ranks, N, keys, w), MPM_OK);
    assert_true(pt.start[0] == 0 && pt.start[ranks] == UINT64_MAX);
    for (int r = 0; r < ranks; ++r) assert_true(pt.start[r] <= pt.start[r + 1]);
    for (int i = 0; i < N; ++i) {
      const int r = mpm_partition_owner(&pt, keys[i]);
      assert_true(pt.start[r] <= keys[i] && keys[i] < pt.start[r + 1]);
    }
    const double imbalance = mpm_partition_weights(&pt, N, keys, w, rank_w);
    double sum = 0;
    for (int r = 0; r < ranks; ++r) {
      sum += rank_w[r];
      /* each cut is within half a block's weight of its target: a rank within one block */
      assert_true(fabs(rank_w[r] - total / ranks) <= 1.5 + 1e-9);
    }
    assert_true(fabs(sum - total) < 1e-9 * total);
    assert_true(imbalance >= 1 && imbalance <= 1 + 1.5 * ranks / total + 1e-12);
    /* the same cut from the blocks in another order */
    uint64_t *k2 = malloc(N * sizeof *k2);
    double *w2 = malloc(N * sizeof *w2);
    for (int i = 0; i < N; ++i) k2[i] = keys[N - 1 - i], w2[i] = w[N - 1 - i];
    mpm_partition pt2;
    assert_int_equal(mpm_partition_cut(&pt2, ranks, N, k2, w2), MPM_OK);
    assert_memory_equal(pt.start, pt2.start, (size_t)(ranks + 1) * sizeof *pt.start);
    mpm_partition_free(&pt2);
    free(k2);
    free(w2);
    mpm_partition_free(&pt);
  }
  free(keys);
  free(w);
}

/* A cube of 8^3 blocks with no weights (cut by count) into 8 ranks: each rank one octant. */
static void test_octants(void **state) {
  (void)state;
  uint64_t keys[512];
  int32_t c[3];
  int n = 0;
  for (c[0] = 0; c[0] < 8; ++c[0])
    for (c[1] = 0; c[1] < 8; ++c[1])
      for (c[2] = 0; c[2] < 8; ++c[2]) keys[n++] = mpm_morton_key(c);
  mpm_partition pt;
  assert_int_equal(mpm_partition_cut(&pt, 8, 512, keys, NULL), MPM_OK);
  for (c[0] = 0; c[0] < 8; ++c[0])
    for (c[1] = 0; c[1] < 8; ++c[1])
      for (c[2] = 0; c[2] < 8; ++c[2]) {
        const int octant = (c[0] >= 4) * 4 + (c[1] >= 4) * 2 + (c[2] >= 4);
        assert_int_equal(mpm_partition_owner(&pt, mpm_morton_key(c)), octant);
      }
  /* a block no particle reached yet has an owner too: the cube's neighbours belong to a rank */
  const int32_t outside[3] = {9, -3, 2};
  const int r = mpm_partition_owner(&pt, mpm_morton_key(outside));
  assert_true(r >= 0 && r < 8);
  mpm_partition_free(&pt);
}

/* Fewer blocks than ranks, repeated keys, and the refusals. */
static void test_few_blocks(void **state) {
  (void)state;
  const int32_t a[3] = {1, 2, 3}, b[3] = {5, 5, 5};
  const uint64_t keys[4] = {mpm_morton_key(b), mpm_morton_key(a), mpm_morton_key(b),
                            mpm_morton_key(a)};
  const double w[4] = {1, 1, 1, 1};
  mpm_partition pt;
  assert_int_equal(mpm_partition_cut(&pt, 5, 4, keys, w), MPM_OK);
  double rank_w[5];
  mpm_partition_weights(&pt, 4, keys, w, rank_w);
  int owning = 0;
  for (int r = 0; r < 5; ++r) owning += rank_w[r] > 0;
  assert_int_equal(owning, 2); /* two blocks (each key twice): two ranks hold them */
  for (int r = 0; r < 5; ++r) assert_true(rank_w[r] == 0 || rank_w[r] == 2);
  mpm_partition_free(&pt);
  assert_int_equal(mpm_partition_cut(&pt, 3, 0, NULL, NULL), MPM_OK); /* no blocks at all */
  assert_int_equal(mpm_partition_owner(&pt, 12345), 2);
  mpm_partition_free(&pt);
  assert_int_equal(mpm_partition_cut(&pt, 0, 4, keys, w), MPM_ERR_INVALID);
  assert_null(pt.start);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_morton),
      cmocka_unit_test(test_cut_even),
      cmocka_unit_test(test_octants),
      cmocka_unit_test(test_few_blocks),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
