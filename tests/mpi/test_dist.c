/* test_dist.c - the distributed run's processes (src/dist/comm.h, partition.h) on 1 to 4 ranks
 * (run by mpirun --oversubscribe from ctest; every rank runs every check, and the run fails when
 * any rank does):
 *   reductions: sums, maxima and minima of every rank's values equal the rank-order combination
 *     made here from the values every rank is known to hold, bit for bit, on every rank, and a NaN
 *     of one rank reaches all of them;
 *   the cut: every rank computes the same partition from the same blocks;
 *   migration: particles sent round robin, all to rank 0, and away from rank 1 (which is then
 *     empty) arrive with every array as it was (each value a function of the particle's id, so
 *     a value left behind or mixed with another particle's shows), none lost or duplicated, in
 *     the documented order, with the byte counts of the packed particles. */
#include "core/particles.h"
#include "dist/comm.h"
#include "dist/partition.h"
#include "mpi_check.h"

#include <math.h>
#include <mpi.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* rank r's k-th value: 1, 1, 1e16, -1e16, 1, ... times 1 + k, whose sum depends on the order of
 * adding (in rank order 2 + 1e16 is exact and the large ones cancel: 2 (1 + k) on 4 ranks; 1 and
 * 1e16 alone round to 1e16) */
static double value_of(int r, int k) {
  return (r % 4 == 2 ? 1e16 : r % 4 == 3 ? -1e16 : 1.0) * (1 + k);
}

static void test_reductions(mpm_dist *d) {
  const mpm_reduction red = mpm_dist_reduction(d);
  enum { K = 5 };
  double v[K], sum[K], mx[K], mn[K];
  for (int k = 0; k < K; ++k) {
    sum[k] = mx[k] = mn[k] = value_of(0, k);
    for (int r = 1; r < size; ++r) {
      sum[k] += value_of(r, k);
      mx[k] = fmax(mx[k], value_of(r, k));
      mn[k] = fmin(mn[k], value_of(r, k));
    }
  }
  for (int k = 0; k < K; ++k) v[k] = value_of(rank, k);
  mpm_reduce_all(&red, MPM_REDUCE_SUM, v, K);
  CHECK(!memcmp(v, sum, sizeof v), "sum: %.17g against %.17g", v[0], sum[0]);
  for (int k = 0; k < K; ++k) v[k] = value_of(rank, k);
  mpm_reduce_all(&red, MPM_REDUCE_MAX, v, K);
  CHECK(!memcmp(v, mx, sizeof v), "max");
  for (int k = 0; k < K; ++k) v[k] = value_of(rank, k);
  mpm_reduce_all(&red, MPM_REDUCE_MIN, v, K);
  CHECK(!memcmp(v, mn, sizeof v), "min");
  /* a NaN of the last rank reaches every rank's maximum */
  double one = rank == size - 1 ? NAN : (double)rank;
  mpm_reduce_all(&red, MPM_REDUCE_MAX, &one, 1);
  CHECK(isnan(one), "a NaN of rank %d is lost to rank %d's maximum", size - 1, rank);
}

static void test_same_cut(void) {
  enum { N = 700 };
  uint64_t keys[N];
  double w[N];
  for (int i = 0; i < N; ++i) {
    const int32_t c[3] = {i % 11, (i / 11) % 9, i / 99};
    keys[i] = mpm_morton_key(c);
    w[i] = 1 + (i * 7919 % 13);
  }
  mpm_partition pt;
  CHECK(mpm_partition_cut(&pt, size, N, keys, w) == MPM_OK, "cut");
  uint64_t *all = malloc((size_t)size * (size_t)(size + 1) * sizeof *all);
  MPI_Allgather(pt.start, size + 1, MPI_UINT64_T, all, size + 1, MPI_UINT64_T, MPI_COMM_WORLD);
  for (int r = 0; r < size; ++r)
    CHECK(!memcmp(all + (size_t)r * (size_t)(size + 1), pt.start, (size_t)(size + 1) * sizeof *all),
          "rank %d cut the blocks otherwise", r);
  free(all);
  mpm_partition_free(&pt);
}

/* Every array of particle id `id`: the reals a function of the id and the array. */
static mpm_real real_of(uint32_t id, int a) {
  return (mpm_real)(id * 0.5 + a * 0.03125);
}

static void fill(mpm_particles *p, int n) {
  for (int i = 0; i < n; ++i) {
    const mpm_real x[3] = {0, 0, 0}, v[3] = {0, 0, 0};
    mpm_particles_push(p, x, v, 1, 1, 0, 0);
  }
  mpm_real **arrays[MPM_PARTICLE_REAL_ARRAYS];
  mpm_particles_real_arrays(p, arrays);
  for (int i = 0; i < n; ++i) {
    const uint32_t id = (uint32_t)(1000 * rank + i);
    p->id[i] = id;
    p->material[i] = (int32_t)(id % 7);
    p->body[i] = (int32_t)(id % 5);
    p->level[i] = (int32_t)(id % 3);
    for (int a = 0; a < MPM_PARTICLE_REAL_ARRAYS; ++a) (*arrays[a])[i] = real_of(id, a);
  }
}

/* Every particle here carries its own values, and the ids over all ranks are the ones made. */
static void check_intact(mpm_particles *p, long expected_total, long expected_idsum,
                         const char *what) {
  mpm_real **arrays[MPM_PARTICLE_REAL_ARRAYS];
  mpm_particles_real_arrays(p, arrays);
  int bad = 0;
  for (size_t i = 0; i < p->count; ++i) {
    const uint32_t id = p->id[i];
    bad += p->material[i] != (int32_t)(id % 7) || p->body[i] != (int32_t)(id % 5) ||
           p->level[i] != (int32_t)(id % 3);
    for (int a = 0; a < MPM_PARTICLE_REAL_ARRAYS; ++a) bad += (*arrays[a])[i] != real_of(id, a);
  }
  CHECK(bad == 0, "%s: %d values are not their particle's", what, bad);
  long count = (long)p->count, total = 0;
  MPI_Allreduce(&count, &total, 1, MPI_LONG, MPI_SUM, MPI_COMM_WORLD);
  CHECK(total == expected_total, "%s: %ld particles in all, %ld made", what, total, expected_total);
  /* no id twice: the sum of the ids is that of the ids made */
  long idsum = 0, all_ids = 0;
  for (size_t i = 0; i < p->count; ++i) idsum += p->id[i];
  MPI_Allreduce(&idsum, &all_ids, 1, MPI_LONG, MPI_SUM, MPI_COMM_WORLD);
  CHECK(all_ids == expected_idsum, "%s: the ids add to %ld, not %ld", what, all_ids,
        expected_idsum);
}

static void test_migration(mpm_dist *d) {
  enum { N = 50 };
  long made = (long)N * size, idsum = 0;
  for (int r = 0; r < size; ++r)
    for (int i = 0; i < N; ++i) idsum += 1000 * r + i;
  mpm_particles p;
  CHECK(mpm_particles_init(&p, N) == MPM_OK, "init");
  fill(&p, N);
  mpm_error err;
  mpm_migration m;
  int32_t *dest = malloc((size_t)(N * size + 1) * sizeof *dest);

  /* round robin: particle i to rank (rank + i) % size */
  for (int i = 0; i < N; ++i) dest[i] = (rank + i) % size;
  CHECK(mpm_dist_migrate(d, &p, dest, &m, &err) == MPM_OK, "round robin: %s", err.message);
  check_intact(&p, made, idsum, "round robin");
  CHECK(m.bytes_sent == m.sent * mpm_particles_packed_bytes(), "bytes sent");
  for (size_t i = 0; i < p.count; ++i) {
    const int from = (int)(p.id[i] / 1000), k = (int)(p.id[i] % 1000);
    CHECK((from + k) % size == rank, "particle %u on rank %d", p.id[i], rank);
  }
  /* the order: those that stayed, then the arrivals by source rank and index there */
  for (size_t i = 1; i < p.count; ++i) {
    const int stay_a = p.id[i - 1] / 1000 == (uint32_t)rank,
              stay_b = p.id[i] / 1000 == (uint32_t)rank;
    CHECK(stay_a >= stay_b, "an arrival before a particle that stayed");
    if (stay_a == stay_b) CHECK(p.id[i - 1] < p.id[i], "order %u then %u", p.id[i - 1], p.id[i]);
  }

  /* all to rank 0 */
  for (size_t i = 0; i < p.count; ++i) dest[i] = 0;
  CHECK(mpm_dist_migrate(d, &p, dest, &m, &err) == MPM_OK, "to rank 0: %s", err.message);
  check_intact(&p, made, idsum, "all to rank 0");
  CHECK(rank == 0 ? p.count == (size_t)made : p.count == 0, "rank %d holds %zu", rank, p.count);
  long sum_here = 0;
  for (size_t i = 0; i < p.count; ++i) sum_here += p.id[i];
  if (rank == 0) CHECK(sum_here == idsum, "the ids on rank 0");

  /* from rank 0 out again, none to rank 1: rank 1 left with nothing */
  for (size_t i = 0; i < p.count; ++i)
    dest[i] = size > 1 ? (int32_t)(i % size == 1 ? 0 : i % size) : 0;
  CHECK(mpm_dist_migrate(d, &p, dest, &m, &err) == MPM_OK, "out again: %s", err.message);
  check_intact(&p, made, idsum, "out again");
  if (rank == 1) CHECK(p.count == 0, "rank 1 holds %zu", p.count);

  /* a destination out of range on one rank: refused on every rank, nothing moved */
  const size_t before = p.count;
  for (size_t i = 0; i < p.count; ++i) dest[i] = rank;
  if (p.count > 0 && rank == 0) dest[0] = size;
  CHECK(mpm_dist_migrate(d, &p, dest, &m, &err) == MPM_ERR_INVALID, "a bad destination passed");
  CHECK(p.count == before, "a refused migration moved particles");
  free(dest);
  mpm_particles_free(&p);
}

int main(int argc, char **argv) {
  mpi_check_start(&argc, &argv);
  mpm_error err;
  mpm_dist *d = mpm_dist_create_world(&err);
  CHECK(d && mpm_dist_rank(d) == rank && mpm_dist_size(d) == size, "create");
  test_reductions(d);
  test_same_cut();
  test_migration(d);
  mpm_dist_destroy(d);
  return mpi_check_finish("test_dist");
}
