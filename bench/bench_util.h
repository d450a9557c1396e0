/* bench_util.h - helpers shared by the benchmarks (bench*.c). */
#ifndef MPM_BENCH_UTIL_H
#define MPM_BENCH_UTIL_H

#include "core/error.h"

/* One line: CPU model, OpenMP threads available, real type, version. */
void bench_print_machine(void);

/* Peak resident set of the process, MiB. */
double bench_peak_rss_mib(void);

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
struct mpm_sim *bench_block(int n, int domains, const char *on_instability, mpm_error *err);

#endif
