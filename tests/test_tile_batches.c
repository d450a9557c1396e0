/* test_tile_batches.c - items batched by coloured tiles (core/tile_batches.h):
 *   - every item comes once, each tile's items in their given order, every tile of a colour of
 *     that colour's parity;
 *   - items in different tiles of one colour lie more than a tile's side apart along some axis,
 *     so a pass whose items touch only what lies within half a side of them runs the tiles of a
 *     colour at once safely;
 *   - a Gauss-Seidel pass run by the batches on 1 and 2 threads gives the same bits;
 *   - far tiles (coordinates past the key's range) still come once each, in colours that keep
 *     them apart. */
#include "support.h"
#include "core/parallel.h"
#include "core/tile_batches.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

enum { N = 6000 };

typedef struct items {
  double x[N][3];
  int32_t tile[N][3];
  double side;
} items;

/* N points in a 1 m box (a few far off), tiled by cubes of side, and their batches (scratch
 * from a, initialized here) */
static void make_items(items *it, double side, uint64_t seed, mpm_arena *a, mpm_tile_batches *b) {
  for (int i = 0; i < N; ++i)
    for (int d = 0; d < 3; ++d) {
      it->x[i][d] = test_rand(&seed, 0, 1);
      if (i % 1000 == 7) it->x[i][d] += 3e6 * side; /* past the key's 2^19 tiles */
      it->tile[i][d] = (int32_t)floor(it->x[i][d] / side);
    }
  it->side = side;
  mpm_arena_init(a);
  assert_int_equal(mpm_tile_batches_build(N, (const int32_t(*)[3])it->tile, a, b), MPM_OK);
}

static void test_every_item_once_in_order(void **state) {
  (void)state;
  static items it;
  mpm_arena a;
  mpm_tile_batches b;
  make_items(&it, 0.07, 11, &a, &b);
  int seen[N] = {0};
  assert_int_equal(b.colour_start[0], 0);
  assert_int_equal(b.colour_start[MPM_TILE_COLOURS], b.tiles);
  assert_int_equal(b.tile_start[b.tiles], N);
  for (int k = 0; k < MPM_TILE_COLOURS; ++k) {
    assert_true(b.colour_start[k] <= b.colour_start[k + 1]);
    for (size_t t = b.colour_start[k]; t < b.colour_start[k + 1]; ++t) {
      assert_true(b.tile_start[t] < b.tile_start[t + 1]); /* no empty tile */
      for (size_t i = b.tile_start[t]; i < b.tile_start[t + 1]; ++i) {
        const uint32_t q = b.item[i];
        seen[q]++;
        for (int d = 0; d < 3; ++d) {
          assert_int_equal(it.tile[q][d] & 1, k >> d & 1); /* the colour's parity */
          assert_int_equal(it.tile[q][d], it.tile[b.item[b.tile_start[t]]][d]);
        }
        if (i > b.tile_start[t]) assert_true(b.item[i - 1] < q);
      }
    }
  }
  for (int i = 0; i < N; ++i) assert_int_equal(seen[i], 1);
  mpm_arena_free(&a);
}

static void test_one_colour_tiles_apart(void **state) {
  (void)state;
  static items it;
  mpm_arena a;
  mpm_tile_batches b;
  make_items(&it, 0.05, 12, &a, &b);
  static int32_t tile_of[N];
  for (size_t t = 0; t < b.tiles; ++t)
    for (size_t i = b.tile_start[t]; i < b.tile_start[t + 1]; ++i) tile_of[b.item[i]] = (int32_t)t;
  long pairs = 0;
  for (int k = 0; k < MPM_TILE_COLOURS; ++k) {
    const size_t i0 = b.tile_start[b.colour_start[k]], i1 = b.tile_start[b.colour_start[k + 1]];
    for (size_t i = i0; i < i1; ++i)
      for (size_t j = i + 1; j < i1; ++j) {
        const uint32_t p = b.item[i], q = b.item[j];
        if (tile_of[p] == tile_of[q]) continue;
        double apart = 0;
        for (int d = 0; d < 3; ++d) apart = fmax(apart, fabs(it.x[p][d] - it.x[q][d]));
        assert_true(apart > it.side);
        ++pairs;
      }
  }
  assert_true(pairs > 100000);
  mpm_arena_free(&a);
}

/* A Gauss-Seidel pass: each item pulls the values of the points within half a side of it
 * (their grid of 0.01 m cells) towards their mean, in the batches' order. */
enum { G = 100 };
static void relax(const items *it, const mpm_tile_batches *b, double *grid) {
  const int reach = (int)floor(0.5 * it->side / 0.01) - 1;
  for (int k = 0; k < MPM_TILE_COLOURS; ++k) {
    const long t0 = (long)b->colour_start[k], t1 = (long)b->colour_start[k + 1];
#pragma omp parallel for schedule(dynamic, 1) if (t1 - t0 > 1)
    for (long t = t0; t < t1; ++t)
      for (size_t i = b->tile_start[t]; i < b->tile_start[t + 1]; ++i) {
        const double *x = it->x[b->item[i]];
        if (x[0] >= 1 || x[1] >= 1 || x[2] >= 1) continue; /* the far ones */
        int c[3];
        for (int d = 0; d < 3; ++d) c[d] = (int)(x[d] / 0.01);
        double sum = 0;
        int n = 0;
        for (int u = c[0] - reach; u <= c[0] + reach; ++u)
          for (int v = c[1] - reach; v <= c[1] + reach; ++v)
            for (int w = c[2] - reach; w <= c[2] + reach; ++w)
              if (u >= 0 && v >= 0 && w >= 0 && u < G && v < G && w < G) {
                sum += grid[(u * G + v) * G + w];
                ++n;
              }
        const double mean = sum / n;
        for (int u = c[0] - reach; u <= c[0] + reach; ++u)
          for (int v = c[1] - reach; v <= c[1] + reach; ++v)
            for (int w = c[2] - reach; w <= c[2] + reach; ++w)
              if (u >= 0 && v >= 0 && w >= 0 && u < G && v < G && w < G) {
                double *g = &grid[(u * G + v) * G + w];
                *g = 0.5 * (*g + mean) + 1e-3 * x[0];
              }
      }
  }
}

static void test_pass_same_on_any_threads(void **state) {
  (void)state;
  static items it;
  mpm_arena a;
  mpm_tile_batches b;
  make_items(&it, 0.1, 13, &a, &b);
  double *grid[2];
  for (int r = 0; r < 2; ++r) {
    grid[r] = malloc(sizeof(double) * G * G * G);
    uint64_t seed = 5;
    for (int i = 0; i < G * G * G; ++i) grid[r][i] = test_rand(&seed, 0, 1);
    mpm_set_threads(r + 1);
    for (int sweep = 0; sweep < 3; ++sweep) relax(&it, &b, grid[r]);
  }
  mpm_set_threads(2);
  assert_memory_equal(grid[0], grid[1], sizeof(double) * G * G * G);
  free(grid[0]);
  free(grid[1]);
  mpm_arena_free(&a);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_every_item_once_in_order),
      cmocka_unit_test(test_one_colour_tiles_apart),
      cmocka_unit_test(test_pass_same_on_any_threads),
  };
  return test_cleanup(cmocka_run_group_tests_name("tile_batches", tests, NULL, NULL));
}
