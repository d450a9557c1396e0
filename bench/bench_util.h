/* bench_util.h - helpers shared by the benchmarks (bench*.c). */
#ifndef MPM_BENCH_UTIL_H
#define MPM_BENCH_UTIL_H

#include "core/error.h"

/* One line: CPU model, OpenMP threads available, real type, version. */
void bench_print_machine(void);

/* Peak resident set of the process, MiB. */
double bench_peak_rss_mib(void);

/* CPU time: this process's (user + system, all threads) and the time the hypervisor took from
 * the machine's CPUs (steal, Linux /proc/stat; 0 where unknown), s. Differences over a run tell
 * why its wall time varies: threads off their cores (less process time per wall second, or
 * steal) or slower at the same work (more process time). */
typedef struct bench_cpu_sample {
  double process, stolen;
} bench_cpu_sample;
bench_cpu_sample bench_cpu_now(void);

/* The process's anonymous memory and the part of it on transparent huge pages, MiB (Linux
 * /proc/self/smaps_rollup): the particle arrays and grid pools ask for them (core/alloc.c), and
 * whether the kernel grants them changes a step's speed. 0, or -1 where the file is missing. */
int bench_huge_page_share(double *huge_mib, double *anon_mib);

/* Parse a thread list like "1,2" into list (at most max entries); the count, or -1 if invalid. */
int bench_parse_threads(const char *s, int *list, int max);

/* Median of v[0..n) (sorts v in place). */
double bench_median(double *v, int n);

/* One warm-up step of 1 us, then `repeats` more (at most 100): the medians of their sort, P2G and
 * G2P stage times, ns per particle, in out[0..2]. 0, or -1 with the step's error printed (the
 * simulation is left to the caller). */
int bench_transfer_stages(struct mpm_sim *sim, int repeats, double out[3]);

/* A neo-Hookean cube of about n particles (8 per cell, no jitter, dx = 2 cm) a few cells above
 * the floor of its box, as a simulation: with particle domains when `domains`, with the solver's
 * on_instability = `on_instability`. NULL with err set on failure. */
/* A simulation from scene text (`name` for messages); NULL with err set. */
struct mpm_sim *bench_sim_from_text(const char *text, const char *name, mpm_error *err);

struct mpm_sim *bench_block(int n, int domains, const char *on_instability, mpm_error *err);

#endif
