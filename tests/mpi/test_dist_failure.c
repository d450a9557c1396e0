/* test_dist_failure.c - a rank that runs out of memory stops every rank's step (src/dist/'s
 * votes before its exchanges, sim/step.c's verdict after each stage), where it would leave the
 * others waiting in the next exchange. The last rank's allocator fails from its k-th allocation
 * of the first step on, for every k until the step needs no more than k: at each, every rank's
 * step fails, or every rank's succeeds (ctest's timeout catches a rank left waiting). */
#include "dist/comm.h"
#include "dist/dist_sim.h"
#include "mpi_check.h"

#include <mpi.h>
#include <mpm/mpm.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static long allowed = -1; /* allocations left before they fail; -1: no limit */

static void *alloc(size_t bytes, size_t alignment, void *user) {
  (void)user;
  if (allowed == 0) return NULL;
  if (allowed > 0) --allowed;
  return aligned_alloc(alignment, (bytes + alignment - 1) / alignment * alignment);
}

static void release(void *p, void *user) {
  (void)user;
  free(p);
}

int main(int argc, char **argv) {
  mpi_check_start(&argc, &argv);
  const mpm_allocator a = {alloc, release, NULL};
  CHECK(mpm_set_allocator(&a) == MPM_OK, "the allocator");
  mpm_error err;
  mpm_dist *d = mpm_dist_create_world(&err);
  const char *scene =
      "{\"domain\": {\"min\": [0, 0, 0], \"max\": [1, 1, 1], \"dx\": 0.025},"
      " \"time\": {\"end\": 1},"
      " \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\", \"E\": 1e5, \"nu\": 0.3,"
      "  \"density\": 1000}],"
      " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.45, 0.3, 0.5],"
      "  \"half_extent\": [0.15, 0.1, 0.12]}, \"material\": \"m\"}]}";
  int k = 0, stopped_at = 0;
  for (;; ++k) {
    mpm_sim *sim = mpi_check_sim(scene);
    CHECK(mpm_dist_attach(d, sim, &err) == MPM_OK, "attach: %s", err.message);
    allowed = rank == size - 1 ? k : -1;
    const mpm_status st = mpm_sim_step(sim, 4e-4);
    const int left = rank == size - 1 && allowed > 0; /* the step needed fewer than k */
    allowed = -1;
    int mine[2] = {st != MPM_OK, left}, all[2];
    MPI_Allreduce(mine, all, 2, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
    CHECK(all[0] == 0 || all[0] == size, "failing from allocation %d: %d of %d ranks stopped", k,
          all[0], size);
    stopped_at += all[0] == size;
    mpm_sim_destroy(sim);
    if (all[1] || k > 2000) break; /* every allocation of the step has failed once */
  }
  if (rank == 0)
    printf("%d ranks: the first step's %d allocations on rank %d failed one by one: every rank "
           "stopped %d times, none left waiting\n",
           size, k, size - 1, stopped_at);
  mpm_dist_destroy(d);
  return mpi_check_finish("test_dist_failure");
}
