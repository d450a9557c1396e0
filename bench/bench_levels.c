/* bench_levels.c - `mpm bench transfer --levels N`: Gao et al.'s Table 1 block on the
 * multi-level grid, fine near its surface and coarse inside (body rules with a band: level L
 * within 4 cells of level L of the surface), beside the uniform grid at the finest dx. Both
 * uGIMP, sparse, APIC, neo-Hookean at rest, one sitting. Per configuration: particles (per
 * level), sort (activation, grouping, ghost rows), P2G (with the ghosts' scatter and the APIC
 * pass) and G2P (with the gather) ns per particle, median of repeats, and the library's memory.
 * Figures printed, never asserted. */
#include "bench.h"
#include "bench_util.h"
#include "cli.h"
#include "core/alloc.h"
#include "core/parallel.h"
#include "solver/adaptive.h"
#include "solver/sim.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static mpm_sim *block(double dx_fine, int levels, mpm_error *err) {
  char json[4096], rules[2048] = "";
  const double dx0 = dx_fine * (double)(1 << (levels > 0 ? levels - 1 : 0));
  for (int L = 1; L < levels; ++L) {
    char r[160];
    snprintf(r, sizeof r, "%s{\"level\": %d, \"body\": 0, \"distance\": %.17g}", L > 1 ? ", " : "",
             L, 4 * dx0 / (double)(1 << L));
    strncat(rules, r, sizeof rules - strlen(rules) - 1);
  }
  char grid[2200] = "";
  if (levels > 0) snprintf(grid, sizeof grid, ", \"levels\": %d, \"refine\": [%s]", levels, rules);
  snprintf(json, sizeof json,
           "{\"domain\": {\"min\": [0,0,0], \"max\": [1,1,1], \"dx\": %.17g%s},"
           " \"gravity\": [0,0,0], \"time\": {\"end\": 1, \"fps\": 24},"
           " \"solver\": {\"kernel\": \"ugimp\", \"transfer\": \"apic\"},"
           " \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\", \"E\": 1e5, \"nu\": 0.3,"
           " \"density\": 1000}],"
           " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.5,0.5,0.5], "
           "\"half_extent\": [0.375,0.375,0.375]}, \"material\": \"m\", \"jitter\": 0}],"
           " \"output\": {\"vtu\": false, \"stats\": false}}",
           dx0, grid);
  return bench_sim_from_text(json, "bench-levels", err);
}

int mpm_bench_levels(const int *threads, int nthreads, int repeats, double scale, int levels) {
  const double dx = scale / 128.0;
  printf("multi-level transfer benchmark: Gao et al. 2017 Table 1's block [1/8, 7/8]^3, finest "
         "dx = 1/%g, 8 particles per cell of each level, uGIMP, APIC; level L within 4 of its "
         "cells of the surface; median of %d repeats\n",
         128.0 / scale, repeats);
  printf("%-9s %7s %10s %10s %10s %12s %10s\n", "grid", "threads", "sort ns/p", "P2G ns/p",
         "G2P ns/p", "P2G+G2P ns/p", "MiB");
  const int configs[2] = {levels, 0};
  for (int k = 0; k < 2; ++k) {
    mpm_error err;
    const size_t live0 = mpm_alloc_live_bytes();
    mpm_sim *sim = block(dx, configs[k], &err);
    if (!sim) {
      fprintf(stderr, "mpm bench: %s\n", err.message);
      return MPM_EXIT_FAILURE;
    }
    const double n = (double)sim->particles.count;
    char name[32];
    snprintf(name, sizeof name, configs[k] ? "%d levels" : "uniform", configs[k]);
    for (int t = 0; t < nthreads; ++t) {
      mpm_set_threads(threads[t]);
      double m[3];
      if (bench_transfer_stages(sim, repeats, m)) {
        mpm_sim_destroy(sim);
        return MPM_EXIT_FAILURE;
      }
      const double ms = m[0], mp = m[1], mg = m[2];
      printf("%-9s %7d %10.1f %10.1f %10.1f %12.1f %10.1f\n", name, threads[t], ms, mp, mg, mp + mg,
             (double)(mpm_alloc_live_bytes() - live0) / 1048576.0);
      fflush(stdout);
    }
    printf("  (%.0f particles", n);
    if (sim->adaptive) {
      size_t per[MPM_LEVELS_MAX] = {0};
      for (size_t i = 0; i < sim->particles.count; ++i) per[sim->particles.level[i]]++;
      for (int L = 0; L < configs[k]; ++L) printf("%s%zu of type %d", L ? ", " : ": ", per[L], L);
      printf("; %zu DOF slots, %zu ghosts, %zu APIC boundary particles", sim->dofs.count,
             sim->adaptive->grid.ghost_count, sim->adaptive->boundary_count);
    } else {
      printf("; %zu DOF slots", sim->dofs.count);
    }
    printf(")\n");
    mpm_sim_destroy(sim);
  }
  printf("peak memory: %.1f MiB (resident set)\n", bench_peak_rss_mib());
  return MPM_EXIT_OK;
}
