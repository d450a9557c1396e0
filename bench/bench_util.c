/* bench_util.c - helpers shared by the benchmarks. */
#define _POSIX_C_SOURCE 200809L /* sysconf, getrusage */
#include "bench_util.h"

#include "core/parallel.h"
#include "mpm/mpm.h"
#include "sim/sim.h"

#include <math.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <unistd.h>

void bench_print_machine(void) {
  char model[256] = "unknown";
  FILE *f = fopen("/proc/cpuinfo", "r");
  if (f) {
    char line[512];
    while (fgets(line, sizeof line, f))
      if (!strncmp(line, "model name", 10)) {
        char *c = strchr(line, ':');
        if (c) {
          snprintf(model, sizeof model, "%s", c + 2);
          model[strcspn(model, "\n")] = 0;
        }
        break;
      }
    fclose(f);
  }
  printf("machine: %s, %d hardware threads available to OpenMP; real type %s; mpm %s\n", model,
         mpm_thread_count(), mpm_real_type(), mpm_version());
}

double bench_peak_rss_mib(void) {
  struct rusage ru;
  getrusage(RUSAGE_SELF, &ru);
  return ru.ru_maxrss / 1024.0;
}

bench_cpu_sample bench_cpu_now(void) {
  bench_cpu_sample c = {0, 0};
  struct rusage ru;
  if (getrusage(RUSAGE_SELF, &ru) == 0)
    c.process = (double)ru.ru_utime.tv_sec + 1e-6 * (double)ru.ru_utime.tv_usec +
                (double)ru.ru_stime.tv_sec + 1e-6 * (double)ru.ru_stime.tv_usec;
  /* the machine's line of /proc/stat: user nice system idle iowait irq softirq steal, in
   * clock ticks */
  FILE *f = fopen("/proc/stat", "r");
  if (f) {
    unsigned long long v[8] = {0};
    if (fscanf(f, "cpu %llu %llu %llu %llu %llu %llu %llu %llu", &v[0], &v[1], &v[2], &v[3], &v[4],
               &v[5], &v[6], &v[7]) == 8) {
      const long hz = sysconf(_SC_CLK_TCK);
      c.stolen = (double)v[7] / (double)(hz > 0 ? hz : 100);
    }
    fclose(f);
  }
  return c;
}

int bench_huge_page_share(double *huge_mib, double *anon_mib) {
  FILE *f = fopen("/proc/self/smaps_rollup", "r");
  if (!f) return -1;
  char line[256];
  int found = 0;
  *huge_mib = *anon_mib = 0;
  while (fgets(line, sizeof line, f)) {
    unsigned long kb;
    if (sscanf(line, "Anonymous: %lu kB", &kb) == 1) {
      *anon_mib = kb / 1024.0;
      found |= 1;
    } else if (sscanf(line, "AnonHugePages: %lu kB", &kb) == 1) {
      *huge_mib = kb / 1024.0;
      found |= 2;
    }
  }
  fclose(f);
  return found == 3 ? 0 : -1;
}

int bench_parse_threads(const char *s, int *list, int max) {
  int n = 0;
  while (s && *s && n < max) {
    char *end;
    long v = strtol(s, &end, 10);
    if (end == s || v < 1 || v > 1024) return -1;
    list[n++] = (int)v;
    s = *end == ',' ? end + 1 : end;
    if (*end && *end != ',') return -1;
  }
  return n;
}

static int cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return x < y ? -1 : x > y;
}

double bench_median(double *v, int n) {
  qsort(v, (size_t)n, sizeof *v, cmp_double);
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

mpm_sim *bench_block(int n, int domains, const char *on_instability, mpm_error *err) {
  const double dx = 0.02, side = cbrt((double)n) * dx / 2, lo = 10 * dx;
  const double domain = side + 25 * dx;
  char text[2048];
  snprintf(
      text, sizeof text,
      "{\"domain\": {\"min\": [0,0,0], \"max\": [%.6g,%.6g,%.6g], \"dx\": %g},"
      " \"time\": {\"end\": 10, \"fps\": 10},"
      " \"solver\": {\"on_instability\": \"%s\"},"
      " \"materials\": [{\"name\": \"jello\", \"model\": \"neo_hookean\", \"E\": 1e5, "
      "\"nu\": 0.3, \"density\": 1000}],"
      " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [%.6g,%.6g,%.6g], "
      "\"half_extent\": [%.6g,%.6g,%.6g]}, \"material\": \"jello\", \"particles_per_cell\": 8, "
      "\"domains\": %s}]}",
      domain, domain, domain, dx, on_instability, lo + side / 2, lo + side / 2 + 5 * dx,
      lo + side / 2, side / 2, side / 2, side / 2, domains ? "true" : "false");
  return bench_sim_from_text(text, "bench-block", err);
}

struct mpm_sim *bench_sim_from_text(const char *text, const char *name, mpm_error *err) {
  mpm_scene scene;
  if (mpm_scene_parse(text, name, &scene, err) != MPM_OK) return NULL;
  mpm_sim *sim = NULL;
  const mpm_status st = mpm_sim_create_from_scene(&scene, &sim, err);
  mpm_scene_free(&scene);
  return st == MPM_OK ? sim : NULL;
}

int bench_transfer_stages(struct mpm_sim *sim, int repeats, double out[3]) {
  const double n = (double)sim->particles.count;
  double sort[100], p2g[100], g2p[100];
  for (int r = 0; r < repeats + 1; ++r) {
    const mpm_stage_times before = sim->times;
    if (mpm_sim_step(sim, 1e-6) != MPM_OK) {
      fprintf(stderr, "mpm bench: %s\n", mpm_sim_last_error(sim));
      return -1;
    }
    if (r == 0) continue; /* warm-up */
    sort[r - 1] = (sim->times.sort - before.sort) * 1e9 / n;
    p2g[r - 1] = (sim->times.p2g - before.p2g) * 1e9 / n;
    g2p[r - 1] = (sim->times.g2p - before.g2p) * 1e9 / n;
  }
  out[0] = bench_median(sort, repeats);
  out[1] = bench_median(p2g, repeats);
  out[2] = bench_median(g2p, repeats);
  return 0;
}
