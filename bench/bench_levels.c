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
#include "core/lanes.h"
#include "core/parallel.h"
#include "adaptive/adaptive.h"
#include "sim/sim.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The block [1/8, 7/8]^3 at finest spacing dx_fine, on `levels` levels (0: the uniform sparse
 * grid), uGIMP, APIC, 8 particles per cell of each level, at rest; with `gravity`, falling. The
 * domain is [0, 1]^3 widened by `pad` on every side (room for the wall band of coarse levels). */
static mpm_sim *block(double dx_fine, int levels, int gravity, double pad, mpm_error *err) {
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
           "{\"domain\": {\"min\": [%.17g,%.17g,%.17g], \"max\": [%.17g,%.17g,%.17g], "
           "\"dx\": %.17g%s},"
           " \"gravity\": [0,%d,0], \"time\": {\"end\": 1, \"fps\": 24},"
           " \"solver\": {\"kernel\": \"ugimp\", \"transfer\": \"apic\"},"
           " \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\", \"E\": 1e5, \"nu\": 0.3,"
           " \"density\": 1000}],"
           " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.5,0.5,0.5], "
           "\"half_extent\": [0.375,0.375,0.375]}, \"material\": \"m\", \"jitter\": 0}],"
           " \"output\": {\"vtu\": false, \"stats\": false}}",
           -pad, -pad, -pad, 1 + pad, 1 + pad, 1 + pad, dx0, grid, gravity ? -10 : 0);
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
    mpm_sim *sim = block(dx, configs[k], 0, 0, &err);
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

/* Per particle-step over `repeats` runs of `steps` steps: the stages and the guarded step's
 * median, and the guarded runs' range. */
typedef struct step_figures {
  double total, sort, p2g, grid, g2p, guarded, lo, hi, bytes;
  double state, grids, values; /* after the steps: particles, grids and their caches, DOF values */
  size_t particles;
} step_figures;

static int time_steps(mpm_sim *sim, int steps, int repeats, size_t live0, step_figures *f) {
  const double n = (double)sim->particles.count;
  for (int w = 0; w < 3; ++w)
    if (mpm_sim_step(sim, 1e-3) != MPM_OK) goto failed;
  double total[100], sort[100], p2g[100], grid[100], g2p[100], guarded[100];
  for (int r = 0; r < repeats; ++r) {
    const mpm_stage_times before = sim->times;
    const double w0 = mpm_wall_seconds();
    for (int k = 0; k < steps; ++k)
      if (mpm_sim_step(sim, 1e-3) != MPM_OK) goto failed;
    const double c = 1e9 / (n * steps);
    guarded[r] = (mpm_wall_seconds() - w0) * c;
    total[r] = (sim->times.total - before.total) * c;
    sort[r] = (sim->times.sort - before.sort) * c;
    p2g[r] = (sim->times.p2g - before.p2g) * c;
    grid[r] = (sim->times.grid - before.grid) * c;
    g2p[r] = (sim->times.g2p - before.g2p) * c;
  }
  f->lo = f->hi = guarded[0];
  for (int r = 1; r < repeats; ++r) {
    if (guarded[r] < f->lo) f->lo = guarded[r];
    if (guarded[r] > f->hi) f->hi = guarded[r];
  }
  f->total = bench_median(total, repeats);
  f->sort = bench_median(sort, repeats);
  f->p2g = bench_median(p2g, repeats);
  f->grid = bench_median(grid, repeats);
  f->g2p = bench_median(g2p, repeats);
  f->guarded = bench_median(guarded, repeats);
  f->bytes = (double)(mpm_alloc_peak_bytes() - live0) / n;
  f->particles = sim->particles.count;
  /* where the memory lies: the particles' block (32 real slots) and its 4 int arrays, the grids
     (the tree, the ghosts, the blocks' caches, every level's sparse grid), the DOF values */
  const mpm_particles *p = &sim->particles;
  f->state = (32.0 * (double)p->stride * sizeof(mpm_real) + 16.0 * (double)p->capacity) / n;
  f->grids = (double)(sim->adaptive ? mpm_adaptive_grid_bytes(&sim->adaptive->grid)
                                    : sim->grid.ops->bytes(&sim->grid)) /
             n;
  f->values = 10.0 * (double)sim->dofs.capacity * sizeof(mpm_real) / n;
  return 0;
failed:
  fprintf(stderr, "mpm bench: %s\n", mpm_sim_last_error(sim));
  return -1;
}

int mpm_bench_step_levels(const int *threads, int nthreads, int steps, int repeats, int particles,
                          int levels) {
  bench_print_machine();
  /* the finest spacing that puts about `particles` in the uniform block (8 per cell) */
  const double dx = 0.75 / cbrt(particles / 8.0);
  printf("multi-level step benchmark: a falling neo-Hookean block [1/8, 7/8]^3, finest dx = %.4g "
         "m, uGIMP, APIC, 8 particles per cell of each level, level L within 4 of its cells of "
         "the surface (static refinement), against the uniform sparse grid at the finest dx; "
         "median of %d runs of %d steps\n",
         dx, repeats, steps);
  for (int t = 0; t < nthreads; ++t) {
    mpm_set_threads(threads[t]);
    step_figures f[2];
    const int configs[2] = {levels, 0};
    for (int k = 0; k < 2; ++k) {
      mpm_error err;
      mpm_alloc_reset_peak();
      const size_t live0 = mpm_alloc_live_bytes();
      /* the same domain for both: the coarsest level's wall band (3 cells) and one more */
      mpm_sim *sim = block(dx, configs[k], 1, 4 * dx * (double)(1 << (levels - 1)), &err);
      if (!sim) {
        fprintf(stderr, "mpm bench: %s\n", err.message);
        return MPM_EXIT_FAILURE;
      }
      const int failed = time_steps(sim, steps, repeats, live0, &f[k]);
      char where[256] = "", grids[1024] = "";
      if (sim->adaptive) {
        const mpm_adaptive *a = sim->adaptive;
        snprintf(where, sizeof where,
                 "; %zu ghosts, %zu APIC boundary particles in %zu cells (%.1f ghosts of several "
                 "real nodes in a cell's stencil)",
                 a->grid.ghost_count, a->boundary_count, a->cell_count,
                 a->cell_count ? (double)a->cell_ghost_count / (double)a->cell_count : 0.0);
        /* the transfer grids: how full their blocks are (a block's P2G and G2P cost depends
           on its nodes as well as its particles) */
        for (int q = 0; q < a->tgrid_count; ++q) {
          const mpm_grid *g = mpm_adaptive_grid_at((mpm_adaptive_grid *)&a->grid, a->tgrid[q].G);
          const mpm_sparse_grid *sg = &g->impl.sparse;
          const size_t np = a->range[q + 1] - a->range[q], blocks = sg->owner_count;
          /* the lanes' batches: a cell's particles 8 at a time */
          size_t batches = 0;
          for (size_t c = 0; c < blocks * (size_t)sg->material_count * MPM_BLOCK_NODES; ++c)
            batches += (sg->cell_start[c + 1] - sg->cell_start[c] + MPM_LANES - 1) / MPM_LANES;
          const size_t used = strlen(grids);
          snprintf(grids + used, sizeof grids - used,
                   "%s level %d, box %.2g cells: %zu particles in %zu blocks (%.0f per block, "
                   "%.0f%% of the lanes used)",
                   q ? ";" : "  transfer grids:", a->tgrid[q].level,
                   a->tgrid[q].box / (double)g->dx, np, blocks,
                   blocks ? (double)np / (double)blocks : 0.0,
                   batches ? 100.0 * (double)np / (double)(batches * MPM_LANES) : 0.0);
        }
      }
      mpm_sim_destroy(sim);
      if (failed) return MPM_EXIT_FAILURE;
      if (grids[0]) printf("%s\n", grids);
      char name[32];
      snprintf(name, sizeof name, configs[k] ? "%d levels" : "uniform", configs[k]);
      printf("%-9s %d threads: %zu particles%s\n", name, threads[t], f[k].particles, where);
      printf("  ns per particle-step: total %.1f = sort %.1f + P2G %.1f + grid %.1f + G2P %.1f; "
             "guarded step %.1f (runs %.1f-%.1f); memory %.1f bytes per particle\n",
             f[k].total, f[k].sort, f[k].p2g, f[k].grid, f[k].g2p, f[k].guarded, f[k].lo, f[k].hi,
             f[k].bytes);
      printf("  memory per particle: particles %.1f, grids %.1f, grid values %.1f, the rest "
             "(scratch, lists, transients at the peak) %.1f bytes\n",
             f[k].state, f[k].grids, f[k].values,
             f[k].bytes - f[k].state - f[k].grids - f[k].values);
      fflush(stdout);
    }
    printf("ratio %d levels / uniform, per particle-step, %d threads: guarded step %.2f (total "
           "%.2f: sort %.2f, P2G %.2f, grid %.2f, G2P %.2f)\n",
           levels, threads[t], f[0].guarded / f[1].guarded, f[0].total / f[1].total,
           f[0].sort / f[1].sort, f[0].p2g / f[1].p2g, f[0].grid / f[1].grid, f[0].g2p / f[1].g2p);
    fflush(stdout);
  }
  printf("peak memory: %.1f MiB (resident set)\n", bench_peak_rss_mib());
  return MPM_EXIT_OK;
}
