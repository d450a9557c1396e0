/* bench_checkpoint.c - `mpm bench checkpoint`: what robustness costs on a block of elastic
 * particles: writing a checkpoint (seconds, MB/s, bytes per particle), reading one back and
 * resuming from it, and the extra time per step of the guards' scan and of the retry mode's
 * copy of the particles. Figures are printed, never asserted. */
#define _POSIX_C_SOURCE 200809L

#include "bench.h"
#include "bench_util.h"
#include "cli.h"
#include "core/parallel.h"
#include "io/checkpoint.h"
#include "sim/sim.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* ns per particle-step of `steps` steps */
static double time_steps(mpm_sim *sim, int steps) {
  const double t0 = mpm_wall_seconds();
  for (int k = 0; k < steps; ++k)
    if (mpm_sim_step(sim, 1e-3) != MPM_OK) return NAN;
  return (mpm_wall_seconds() - t0) * 1e9 / ((double)sim->particles.count * steps);
}

int mpm_bench_checkpoint(int argc, char **argv) {
  int particles = 1000000, repeats = 3, steps = 10;
  const char *dir = NULL;
  for (int i = 0; i < argc; ++i) {
    if (!strcmp(argv[i], "--particles")) {
      if (mpm_cli_parse_int("--particles", i + 1 < argc ? argv[i + 1] : NULL, 1000, 100000000,
                            &particles))
        return MPM_EXIT_USAGE;
      ++i;
    } else if (!strcmp(argv[i], "--repeats")) {
      if (mpm_cli_parse_int("--repeats", i + 1 < argc ? argv[i + 1] : NULL, 1, 100, &repeats))
        return MPM_EXIT_USAGE;
      ++i;
    } else if (!strcmp(argv[i], "--dir") && i + 1 < argc) {
      dir = argv[++i];
    } else {
      fprintf(stderr, "mpm bench checkpoint: unknown option '%s'\n", argv[i]);
      return MPM_EXIT_USAGE;
    }
  }
  bench_print_machine();
  char tmp[] = "/tmp/mpm-bench-checkpoint-XXXXXX";
  if (!dir && !(dir = mkdtemp(tmp))) {
    fprintf(stderr, "mpm bench checkpoint: cannot create a temporary directory\n");
    return MPM_EXIT_FAILURE;
  }
  mpm_error err;
  mpm_sim *sim = bench_block(particles, 0, "stop", &err);
  if (!sim || mpm_sim_enable_output(sim, dir) != MPM_OK) {
    fprintf(stderr, "mpm bench: %s\n", sim ? mpm_sim_last_error(sim) : err.message);
    mpm_sim_destroy(sim);
    return MPM_EXIT_FAILURE;
  }
  const double n = (double)sim->particles.count;
  for (int k = 0; k < 3; ++k) mpm_sim_step(sim, 1e-3);
  char path[MPM_PATH_MAX + 64];
  double write[100], read[100], resume[100], bytes = 0;
  for (int r = 0; r < repeats; ++r) {
    double t0 = mpm_wall_seconds();
    if (mpm_sim_write_checkpoint(sim, path, sizeof path) != MPM_OK) {
      fprintf(stderr, "mpm bench: %s\n", mpm_sim_last_error(sim));
      mpm_sim_destroy(sim);
      return MPM_EXIT_FAILURE;
    }
    write[r] = mpm_wall_seconds() - t0;
    struct stat st;
    if (stat(path, &st) == 0) bytes = (double)st.st_size;
    mpm_checkpoint c;
    t0 = mpm_wall_seconds();
    if (mpm_checkpoint_read(path, &c, &err) != MPM_OK) {
      fprintf(stderr, "mpm bench: %s\n", err.message);
      mpm_sim_destroy(sim);
      return MPM_EXIT_FAILURE;
    }
    read[r] = mpm_wall_seconds() - t0;
    mpm_checkpoint_free(&c);
    mpm_sim *again = bench_block(particles, 0, "stop", &err);
    t0 = mpm_wall_seconds();
    const mpm_status st2 = again ? mpm_sim_resume(again, dir, NULL, 0) : MPM_ERR_NOMEM;
    resume[r] = mpm_wall_seconds() - t0;
    mpm_sim_destroy(again);
    if (st2 != MPM_OK) {
      fprintf(stderr, "mpm bench: resume failed\n");
      mpm_sim_destroy(sim);
      return MPM_EXIT_FAILURE;
    }
  }
  printf("checkpoint benchmark: %.0f particles (neo-Hookean block), %d threads, %s, median of "
         "%d\n",
         n, mpm_thread_count(), mpm_real_type(), repeats);
  const double w = bench_median(write, repeats), rd = bench_median(read, repeats);
  printf("  file: %.1f MB, %.1f bytes per particle\n", bytes / 1e6, bytes / n);
  printf("  write %.3f s (%.0f MB/s), read %.3f s (%.0f MB/s), resume (read + install) %.3f s\n", w,
         bytes / 1e6 / w, rd, bytes / 1e6 / rd, bench_median(resume, repeats));

  /* guards: the step with the scan (always on) against the raw step; retry mode's copy */
  double raw[100], guarded[100], retry[100];
  mpm_sim *rsim = bench_block(particles, 0, "retry", &err);
  if (rsim) time_steps(rsim, 3);
  for (int r = 0; r < repeats && rsim; ++r) {
    const double t0 = mpm_wall_seconds();
    for (int k = 0; k < steps; ++k) mpm_sim_raw_step(sim, 1e-3);
    raw[r] = (mpm_wall_seconds() - t0) * 1e9 / (n * steps);
    guarded[r] = time_steps(sim, steps);
    retry[r] = time_steps(rsim, steps);
  }
  if (rsim)
    printf("  step ns per particle: raw %.1f, with the guards' scan %.1f, in retry mode %.1f\n",
           bench_median(raw, repeats), bench_median(guarded, repeats),
           bench_median(retry, repeats));
  mpm_sim_destroy(rsim);
  mpm_sim_destroy(sim);
  if (dir == tmp) { /* remove what this benchmark wrote */
    char cmd[128];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmp);
    if (system(cmd) != 0) fprintf(stderr, "mpm bench: could not remove %s\n", tmp);
  }
  return MPM_EXIT_OK;
}
