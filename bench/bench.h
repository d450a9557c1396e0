/* bench.h - the benchmarks behind `mpm bench` that live outside bench.c. */
#ifndef MPM_BENCH_H
#define MPM_BENCH_H

/* `mpm bench stress`: ns per particle of each constitutive model's batch stress and return
 * map, and ns per mpm_svd3 call (bench_stress.c). argv holds the options after "stress". */
int mpm_bench_stress(int argc, char **argv);

/* `mpm bench checkpoint`: checkpoint write, read and resume times and sizes, and the per-step
 * cost of the instability guards and of retry mode (bench_checkpoint.c). */
int mpm_bench_checkpoint(int argc, char **argv);

/* `mpm bench domains`: ns per particle-step with particle domains against standard material
 * points on the same block, per thread count (bench_domains.c). */
int mpm_bench_domains(int argc, char **argv);

/* `mpm bench implicit`: the Hessian action against explicit P2G + G2P, CG iterations with and
 * without the preconditioner, and time to simulate 1 s of a dropped block explicit against
 * implicit (bench_implicit.c). */
int mpm_bench_implicit(int argc, char **argv);

/* `mpm bench transfer --levels N`: Table 1's block on N levels, fine near its surface, beside
 * the uniform grid at the finest dx (bench_levels.c). */
int mpm_bench_levels(const int *threads, int nthreads, int repeats, double scale, int levels);

/* `mpm bench step --levels N`: a falling block on N levels, fine near its surface, beside the
 * uniform sparse grid at the finest dx: ns per particle-step, by stage, and the ratio
 * (bench_levels.c). */
int mpm_bench_step_levels(const int *threads, int nthreads, int steps, int repeats, int particles,
                          int levels);

/* `mpm bench surface`: the seconds of one frame's particle surface (level set, filter, mesh,
 * writers) for about 1M particles, per thread count (bench_surface.c). */
int mpm_bench_surface(int argc, char **argv);
int mpm_bench_contact(int argc, char **argv);

#endif
