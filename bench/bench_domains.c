/* bench_domains.c - `mpm bench domains`: a falling elastic block simulated with standard
 * material points and with particle domains (Zhu et al. 2017), the same particles: ns per
 * particle per step for each, at each thread count asked. Figures are printed, never
 * asserted. */
#include "bench.h"
#include "bench_util.h"
#include "cli.h"
#include "core/parallel.h"
#include "sim/sim.h"

#include <stdio.h>
#include <string.h>

int mpm_bench_domains(int argc, char **argv) {
  int particles = 200000, steps = 10, repeats = 3, threads[16] = {1, 2}, nthreads = 2;
  for (int i = 0; i < argc; ++i) {
    if (!strcmp(argv[i], "--particles")) {
      if (mpm_cli_parse_int("--particles", i + 1 < argc ? argv[i + 1] : NULL, 1000, 50000000,
                            &particles))
        return MPM_EXIT_USAGE;
      ++i;
    } else if (!strcmp(argv[i], "--steps")) {
      if (mpm_cli_parse_int("--steps", i + 1 < argc ? argv[i + 1] : NULL, 1, 10000, &steps))
        return MPM_EXIT_USAGE;
      ++i;
    } else if (!strcmp(argv[i], "--repeats")) {
      if (mpm_cli_parse_int("--repeats", i + 1 < argc ? argv[i + 1] : NULL, 1, 100, &repeats))
        return MPM_EXIT_USAGE;
      ++i;
    } else if (!strcmp(argv[i], "--threads") && i + 1 < argc) {
      nthreads = bench_parse_threads(argv[++i], threads, 16);
      if (nthreads < 1) {
        fprintf(stderr, "mpm bench domains: --threads expects a list like 1,2\n");
        return MPM_EXIT_USAGE;
      }
    } else {
      fprintf(stderr, "mpm bench domains: unknown option '%s'\n", argv[i]);
      return MPM_EXIT_USAGE;
    }
  }
  bench_print_machine();
  printf("domains benchmark: a falling neo-Hookean block, 8 particles per cell, quadratic grid "
         "kernel for material points, linear corner kernel for domains; median of %d runs of %d "
         "steps\n",
         repeats, steps);
  for (int t = 0; t < nthreads; ++t) {
    mpm_set_threads(threads[t]);
    double ns[2] = {0, 0}, stage[2][4] = {{0}};
    size_t n = 0, corners = 0;
    for (int domains = 0; domains < 2; ++domains) {
      mpm_error err;
      mpm_sim *sim = bench_block(particles, domains, "stop", &err);
      if (!sim) {
        fprintf(stderr, "mpm bench: %s\n", err.message);
        return MPM_EXIT_FAILURE;
      }
      n = sim->particles.count + sim->domains.active_count;
      corners = sim->domains.corner_count ? sim->domains.corner_count : corners;
      for (int k = 0; k < 2; ++k) mpm_sim_step(sim, 1e-3);
      double runs[100];
      const mpm_stage_times t0s = sim->times;
      for (int r = 0; r < repeats; ++r) {
        const double t0 = mpm_wall_seconds();
        for (int k = 0; k < steps; ++k)
          if (mpm_sim_step(sim, 1e-3) != MPM_OK) {
            fprintf(stderr, "mpm bench: %s\n", mpm_sim_last_error(sim));
            mpm_sim_destroy(sim);
            return MPM_EXIT_FAILURE;
          }
        runs[r] = (mpm_wall_seconds() - t0) * 1e9 / ((double)n * steps);
      }
      ns[domains] = bench_median(runs, repeats);
      /* where the time goes, averaged over every repeat */
      const double per = 1e9 / ((double)n * steps * repeats);
      stage[domains][0] = (sim->times.sort - t0s.sort) * per;
      stage[domains][1] = (sim->times.p2g - t0s.p2g) * per;
      stage[domains][2] = (sim->times.grid - t0s.grid) * per;
      stage[domains][3] = (sim->times.g2p - t0s.g2p) * per;
      mpm_sim_destroy(sim);
    }
    printf("  %d threads, %zu particles (%zu corners): material points %.1f ns, particle domains "
           "%.1f ns per particle-step (%.2fx)\n",
           threads[t], n, corners, ns[0], ns[1], ns[1] / ns[0]);
    for (int k = 0; k < 2; ++k)
      printf("    %s: activation and layout %.1f, P2G %.1f, grid update %.1f, G2P %.1f ns\n",
             k ? "particle domains" : "material points", stage[k][0], stage[k][1], stage[k][2],
             stage[k][3]);
    fflush(stdout);
  }
  return MPM_EXIT_OK;
}
