/* bench_contact.c - `mpm bench contact`: the enriched surfaces' contact pass
 * (domain/enrich_surface_contact.h) alone, on two blocks of every-domain-enriched particles
 * pressed against each other, at three sizes: its seconds per pass and per enriched corner,
 * so that its growth with the corners shows (linear, or not). Figures are printed, never
 * asserted. */
#include "bench.h"
#include "bench_util.h"
#include "cli.h"
#include "core/clock.h"
#include "core/parallel.h"
#include "domain/enrich_surface_contact.h"
#include "sim/sim.h"

#include <stdio.h>
#include <string.h>

/* Two blocks of side x side x side domains of 0.01 m, every one enriched, 2 mm apart and
 * coming together at 1 m/s each (so that the pass finds contacts), no gravity. */
static mpm_sim *pair(int side, mpm_error *err) {
  const double h = 0.01, half = side * h / 2, gap = 0.002;
  const double extent = 2 * (2 * half + gap) + 0.2, c = extent / 2;
  char text[2048];
  snprintf(text, sizeof text,
           "{\"domain\": {\"min\": [0, 0, 0], \"max\": [%.6g, %.6g, %.6g], \"dx\": 0.02},"
           " \"gravity\": [0, 0, 0], \"time\": {\"end\": 1.0, \"fps\": 10},"
           " \"materials\": [{\"name\": \"rubber\", \"model\": \"neo_hookean\", \"E\": 1e5, "
           "\"nu\": 0.3, \"density\": 1000}],"
           " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [%.6g, %.6g, %.6g], "
           "\"half_extent\": [%.6g, %.6g, %.6g]}, \"material\": \"rubber\", \"velocity\": [1, 0, "
           "0], \"domains\": true, \"enrichment\": 1},"
           " {\"shape\": {\"type\": \"box\", \"center\": [%.6g, %.6g, %.6g], "
           "\"half_extent\": [%.6g, %.6g, %.6g]}, \"material\": \"rubber\", \"velocity\": [-1, "
           "0, 0], \"domains\": true, \"enrichment\": 1}]}",
           extent, extent, extent, c - half - gap / 2, c, c, half, half, half, c + half + gap / 2,
           c, c, half, half, half);
  return bench_sim_from_text(text, "bench-contact", err);
}

int mpm_bench_contact(int argc, char **argv) {
  int repeats = 5, threads[16] = {1, 2}, nthreads = 2;
  for (int i = 0; i < argc; ++i) {
    if (!strcmp(argv[i], "--repeats")) {
      if (mpm_cli_parse_int("--repeats", i + 1 < argc ? argv[i + 1] : NULL, 1, 100, &repeats))
        return MPM_EXIT_USAGE;
      ++i;
    } else if (!strcmp(argv[i], "--threads") && i + 1 < argc) {
      nthreads = bench_parse_threads(argv[++i], threads, 16);
      if (nthreads < 1) {
        fprintf(stderr, "mpm bench contact: --threads expects a list like 1,2\n");
        return MPM_EXIT_USAGE;
      }
    } else {
      fprintf(stderr, "mpm bench contact: unknown option '%s'\n", argv[i]);
      return MPM_EXIT_USAGE;
    }
  }
  bench_print_machine();
  printf("contact benchmark: the enriched surfaces' contact pass alone, two blocks of enriched "
         "domains 2 mm apart closing at 2 m/s, after one step of 1e-4 s; median of %d passes\n",
         repeats);
  static const int sides[] = {8, 16, 32};
  for (int t = 0; t < nthreads; ++t) {
    mpm_set_threads(threads[t]);
    for (size_t k = 0; k < sizeof sides / sizeof sides[0]; ++k) {
      mpm_error err;
      mpm_sim *sim = pair(sides[k], &err);
      if (!sim) {
        fprintf(stderr, "mpm bench: %s\n", err.message);
        return MPM_EXIT_FAILURE;
      }
      if (mpm_sim_step(sim, 1e-4) != MPM_OK) {
        fprintf(stderr, "mpm bench: %s\n", mpm_sim_last_error(sim));
        mpm_sim_destroy(sim);
        return MPM_EXIT_FAILURE;
      }
      /* the pass on the DOF set the step left (its velocities after the update), with the
         step's dt; each pass from the same velocities */
      mpm_dofs *d = &sim->dofs;
      const size_t bytes = d->count * sizeof(mpm_real);
      mpm_real *saved[3];
      for (int c = 0; c < 3; ++c) {
        saved[c] = mpm_alloc(bytes + 1);
        memcpy(saved[c], d->v[c], bytes);
      }
      const mpm_grid_values gv = {.mass = d->mass, .v = {d->v[0], d->v[1], d->v[2]}};
      double s[100];
      mpm_surface_contact_stats st = {0, 0, 0};
      mpm_arena scratch; /* the pass's own (the step's arena holds the DOF set's layout) */
      mpm_arena_init(&scratch);
      for (int r = 0; r < repeats; ++r) {
        for (int c = 0; c < 3; ++c) memcpy(d->v[c], saved[c], bytes);
        mpm_arena_reset(&scratch);
        const double t0 = mpm_wall_seconds();
        if (mpm_surface_contact(&sim->domains, &gv, 1e-4, &scratch, &st) != MPM_OK) {
          fprintf(stderr, "mpm bench: out of memory\n");
          return MPM_EXIT_FAILURE;
        }
        s[r] = mpm_wall_seconds() - t0;
      }
      const double med = bench_median(s, repeats);
      const size_t corners = sim->domains.enrich.count;
      printf("threads %d, blocks of %d^3 domains: %zu particles, %zu enriched corners, %zu "
             "surface faces, %zu surface corners, %zu contacts; %.3f ms a pass, %.1f ns per "
             "enriched corner\n",
             threads[t], sides[k], sim->domains.active_count, corners, st.faces, st.corners,
             st.contacts, 1e3 * med, 1e9 * med / (double)corners);
      fflush(stdout);
      mpm_arena_free(&scratch);
      for (int c = 0; c < 3; ++c) mpm_free(saved[c]);
      mpm_sim_destroy(sim);
    }
  }
  printf("peak memory: %.1f MiB (resident set)\n", bench_peak_rss_mib());
  return MPM_EXIT_OK;
}
