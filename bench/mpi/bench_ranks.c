/* bench_ranks.c - `mpm bench step`'s scene on ranks (built with -DMPM_MPI=ON: mpm-bench-ranks):
 * a falling neo-Hookean block of ~1M particles, 8 per cell, quadratic B-spline, APIC, run on
 * the ranks of mpirun with `--threads` OpenMP threads each (src/dist/dist_sim.h). Prints the
 * whole run's ns per particle-step (the wall time of a step over all its particles: compare it
 * with `mpm bench step --threads N` for the same cores), the halo's bytes and messages per step,
 * the particles migrated, and the share of the step spent in the exchanges (packing and waiting
 * included). Figures printed, never asserted.
 *
 *   mpirun -np 2 build-mpi/mpm-bench-ranks --threads 1 [--particles N] [--steps N]
 *          [--repeats N] */
#include "bench_util.h"
#include "core/clock.h"
#include "dist/comm.h"
#include "dist/dist_sim.h"

#include <math.h>
#include <mpi.h>
#include <mpm/mpm.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int cmp_double(const void *a, const void *b) {
  const double x = *(const double *)a, y = *(const double *)b;
  return x < y ? -1 : x > y;
}

int main(int argc, char **argv) {
  MPI_Init(&argc, &argv);
  int rank = 0, size = 1, threads = 1, steps = 10, repeats = 5;
  long particles = 1000000;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!strcmp(argv[i], "--threads"))
      threads = atoi(argv[i + 1]);
    else if (!strcmp(argv[i], "--particles"))
      particles = atol(argv[i + 1]);
    else if (!strcmp(argv[i], "--steps"))
      steps = atoi(argv[i + 1]);
    else if (!strcmp(argv[i], "--repeats"))
      repeats = atoi(argv[i + 1]);
  }
  if (threads < 1 || particles < 1000 || steps < 1 || repeats < 1 || repeats > 100) {
    if (rank == 0)
      fprintf(stderr, "mpm-bench-ranks: [--threads N] [--particles N] [--steps N] "
                      "[--repeats N (at most 100)]\n");
    MPI_Finalize();
    return 2;
  }
  if (rank == 0) bench_print_machine();
  /* bench step's block: side L at spacing h = dx / 2 (8 per cell), 20 cells from the walls,
     10 cells above its place to fall */
  const double dx = 0.02, side = cbrt((double)particles) * dx / 2, domain = side + 40 * dx;
  const double c = 20 * dx + side / 2;
  char json[2048];
  snprintf(json, sizeof json,
           "{\"name\": \"bench\", \"domain\": {\"min\": [0, 0, 0], \"max\": [%.17g, %.17g, %.17g],"
           " \"dx\": %g}, \"time\": {\"end\": 1},"
           " \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\", \"E\": 1e5, \"nu\": 0.3,"
           "  \"density\": 1000}],"
           " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [%.17g, %.17g, %.17g],"
           "  \"half_extent\": [%.17g, %.17g, %.17g]}, \"material\": \"m\"}]}",
           domain, domain, domain, dx, c, c + 10 * dx, c, side / 2, side / 2, side / 2);
  mpm_sim *sim = NULL;
  char msg[1024];
  mpm_error err;
  if (mpm_sim_create_from_json(json, NULL, &sim, msg, sizeof msg) != MPM_OK) {
    fprintf(stderr, "rank %d: %s\n", rank, msg);
    MPI_Abort(MPI_COMM_WORLD, 2);
  }
  mpm_sim_set_threads(sim, threads);
  const double n = (double)mpm_sim_particle_count(sim); /* every rank holds all of them now */
  mpm_dist *d = mpm_dist_create_world(&err);
  if (!d || mpm_dist_attach(d, sim, &err) != MPM_OK) {
    fprintf(stderr, "rank %d: %s\n", rank, err.message);
    MPI_Abort(MPI_COMM_WORLD, 2);
  }
  for (int w = 0; w < 3; ++w) mpm_sim_step(sim, 1e-3);
  double ns[100], exchange[100], bytes = 0, messages = 0, migrated = 0;
  for (int r = 0; r < repeats; ++r) {
    const mpm_dist_figures f0 = mpm_dist_sim_figures(sim);
    MPI_Barrier(MPI_COMM_WORLD);
    const double w0 = mpm_wall_seconds();
    for (int k = 0; k < steps; ++k) {
      if (mpm_sim_step(sim, 1e-3) != MPM_OK) {
        fprintf(stderr, "rank %d: %s\n", rank, mpm_sim_last_error(sim));
        MPI_Abort(MPI_COMM_WORLD, 1);
      }
      const mpm_dist_figures f = mpm_dist_sim_figures(sim);
      bytes += (double)f.halo_bytes;
      messages += (double)f.halo_messages;
      migrated += (double)f.migration.sent;
    }
    MPI_Barrier(MPI_COMM_WORLD);
    const double wall = mpm_wall_seconds() - w0;
    ns[r] = 1e9 * wall / (n * steps);
    exchange[r] = (mpm_dist_sim_figures(sim).exchange_seconds - f0.exchange_seconds) / wall;
  }
  double sums[3] = {bytes, messages, migrated}, all[3];
  MPI_Reduce(sums, all, 3, MPI_DOUBLE, MPI_SUM, 0, MPI_COMM_WORLD);
  double ex_max[100];
  MPI_Reduce(exchange, ex_max, repeats, MPI_DOUBLE, MPI_MAX, 0, MPI_COMM_WORLD);
  if (rank == 0) {
    double sorted[100];
    memcpy(sorted, ns, (size_t)repeats * sizeof *ns);
    qsort(sorted, (size_t)repeats, sizeof *sorted, cmp_double);
    qsort(ex_max, (size_t)repeats, sizeof *ex_max, cmp_double);
    const double per_step = 1.0 / (repeats * steps);
    printf("step benchmark on ranks: %.0f particles, 8 per cell, quadratic, APIC, neo-Hookean, "
           "%d ranks x %d threads, median of %d runs of %d steps\n",
           n, size, threads, repeats, steps);
    printf("  guarded step (mpm_sim_step) over all ranks: %.1f ns per particle-step (runs "
           "%.1f-%.1f)\n",
           sorted[repeats / 2], sorted[0], sorted[repeats - 1]);
    printf("  per step, all ranks: halo %.0f bytes in %.1f messages, %.1f particles migrated; "
           "exchanges %.0f%% of the step (the busiest rank, median)\n",
           all[0] * per_step, all[1] * per_step, all[2] * per_step, 100 * ex_max[repeats / 2]);
  }
  mpm_sim_destroy(sim);
  mpm_dist_destroy(d);
  MPI_Finalize();
  return 0;
}
