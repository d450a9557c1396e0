/* bench_stress.c - `mpm bench stress`: the cost of the constitutive models and of the SVD.
 *
 * For every model the table has (mpm_model_of non-NULL for kinds 0..MPM_MODEL_COUNT-1): N
 * particles (default 1M) with deformation gradients F = U diag(s) V^T, U and V uniformly random
 * rotations and s in [0.8, 1.25] (near rotations with moderate stretch; a deterministic
 * generator seeded per particle, so F does not depend on the thread count), stored as the
 * solver stores them (9 component arrays), plastic state at model->plastic_initial.
 *   stress_ns/p:     kirchhoff_batch over chunks of MPM_STRESS_CHUNK particles read in place;
 *   return_map_ns/p: return_map (plastic models) over the same chunks, on a fresh copy of F
 *                    and of the plastic state each repeat (the copy is not timed).
 * Chunks are spread over threads with an OpenMP parallel for. Also: ns per mpm_svd3 call on
 * the same F (gathered from the component arrays). Wall-clock medians of --repeats after one
 * warm-up run; figures are printed, never asserted. */
#include "bench.h"
#include "bench_util.h"
#include "cli.h"
#include "core/alloc.h"
#include "core/parallel.h"
#include "core/svd3.h"
#include "material/material.h"
#include "sim/sim.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#define MAX_REPEATS 100

/* The results flow here so that no computation can be dropped. */
static volatile double g_sink;

/* splitmix64: a per-particle seed, so the data are the same for any thread count. */
static uint64_t splitmix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

/* Uniform in [lo, hi) (xorshift64*). */
static double rand_uniform(uint64_t *s, double lo, double hi) {
  *s ^= *s >> 12;
  *s ^= *s << 25;
  *s ^= *s >> 27;
  const uint64_t r = *s * 0x2545F4914F6CDD1Dull;
  return lo + (hi - lo) * (double)(r >> 11) * (1.0 / 9007199254740992.0);
}

/* Uniformly random rotation (row-major) from a normalized random quaternion. */
static void rand_rotation(uint64_t *s, double Q[9]) {
  double q[4], n;
  do {
    n = 0;
    for (int i = 0; i < 4; ++i) {
      q[i] = rand_uniform(s, -1, 1);
      n += q[i] * q[i];
    }
  } while (n > 1 || n < 1e-4);
  n = sqrt(n);
  const double w = q[0] / n, x = q[1] / n, y = q[2] / n, z = q[3] / n;
  Q[0] = 1 - 2 * (y * y + z * z);
  Q[1] = 2 * (x * y - w * z);
  Q[2] = 2 * (x * z + w * y);
  Q[3] = 2 * (x * y + w * z);
  Q[4] = 1 - 2 * (x * x + z * z);
  Q[5] = 2 * (y * z - w * x);
  Q[6] = 2 * (x * z - w * y);
  Q[7] = 2 * (y * z + w * x);
  Q[8] = 1 - 2 * (x * x + y * y);
}

/* F of particle i: U diag(s) V^T with s in [0.8, 1.25]. */
static void particle_F(uint64_t i, double F[9]) {
  uint64_t s = splitmix64(i + 0x5EEDull) | 1;
  double U[9], V[9], st[3];
  rand_rotation(&s, U);
  rand_rotation(&s, V);
  for (int k = 0; k < 3; ++k) st[k] = rand_uniform(&s, 0.8, 1.25);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      F[3 * r + c] = U[3 * r] * st[0] * V[3 * c] + U[3 * r + 1] * st[1] * V[3 * c + 1] +
                     U[3 * r + 2] * st[2] * V[3 * c + 2];
}

/* The material of one model: E = 100 kPa, nu = 0.3, 1000 kg/m^3, and plasticity parameters
 * that the stretches above exceed for part of the particles. */
static mpm_material bench_material(mpm_model_kind kind) {
  mpm_material_desc d = mpm_material_desc_default();
  d.model = kind;
  d.E = 1e5;
  d.nu = 0.3;
  d.density = 1000;
  d.friction_angle = 30;
  d.cohesion = 0;
  d.yield_stress = 5e3;
  d.theta_c = 2.5e-2;
  d.theta_s = 7.5e-3;
  d.hardening = 10;
  mpm_material m;
  memset(&m, 0, sizeof m);
  mpm_material_init(&m, &d);
  return m;
}

/* What a timed pass works on: the material, the arrays, and (return maps) their copies. */
typedef struct pass_ctx {
  const mpm_material *m;
  mpm_real *const *F; /* 9 component arrays */
  mpm_real *plastic;
} pass_ctx;

/* One chunk of k particles from `base`; returns a value that depends on the result. */
typedef double (*chunk_fn)(const pass_ctx *p, long base, int k);

static double chunk_stress(const pass_ctx *p, long base, int k) {
  _Alignas(MPM_ALIGN) mpm_real tau[9][MPM_STRESS_CHUNK];
  const mpm_real *Fc[9];
  for (int q = 0; q < 9; ++q) Fc[q] = p->F[q] + base;
  p->m->model->kirchhoff_batch(p->m, k, Fc, p->plastic + base, tau);
  return (double)tau[0][0] + (double)tau[8][k - 1];
}

static double chunk_return_map(const pass_ctx *p, long base, int k) {
  mpm_real *Fc[9];
  for (int q = 0; q < 9; ++q) Fc[q] = p->F[q] + base;
  p->m->model->return_map(p->m, k, Fc, p->plastic + base);
  return (double)p->plastic[base];
}

/* U, V and sigma written to stack buffers, as a stress kernel would keep them. */
static double chunk_svd_batch(const pass_ctx *p, long base, int k) {
  _Alignas(MPM_ALIGN) mpm_real U[9][MPM_STRESS_CHUNK], V[9][MPM_STRESS_CHUNK],
      s[3][MPM_STRESS_CHUNK];
  const mpm_real *Fc[9];
  mpm_real *Up[9], *Vp[9], *sp[3];
  for (int q = 0; q < 9; ++q) {
    Fc[q] = p->F[q] + base;
    Up[q] = U[q];
    Vp[q] = V[q];
  }
  for (int q = 0; q < 3; ++q) sp[q] = s[q];
  mpm_svd3_batch(k, Fc, Up, sp, Vp);
  return (double)s[2][0] + (double)U[0][k - 1] + (double)V[8][0];
}

/* Seconds for one pass of `fn` over n particles in chunks of MPM_STRESS_CHUNK spread over the
 * threads; *sink keeps the results alive. */
static double time_chunks(chunk_fn fn, const pass_ctx *p, long n, double *sink) {
  const long chunks = (n + MPM_STRESS_CHUNK - 1) / MPM_STRESS_CHUNK;
  double acc = 0;
  const double t0 = mpm_wall_seconds();
#pragma omp parallel for schedule(static) reduction(+ : acc)
  for (long c = 0; c < chunks; ++c) {
    const long base = c * MPM_STRESS_CHUNK;
    acc += fn(p, base, (int)(n - base < MPM_STRESS_CHUNK ? n - base : MPM_STRESS_CHUNK));
  }
  const double t1 = mpm_wall_seconds();
  *sink += acc;
  return t1 - t0;
}

/* Seconds for one mpm_svd3 call per particle. */
static double time_svd(mpm_real *const F[9], long n, double *sink) {
  double acc = 0;
  const double t0 = mpm_wall_seconds();
#pragma omp parallel for schedule(static) reduction(+ : acc)
  for (long i = 0; i < n; ++i) {
    mpm_real A[9], U[9], s[3], V[9];
    for (int q = 0; q < 9; ++q) A[q] = F[q][i];
    mpm_svd3(A, U, s, V);
    acc += (double)s[2] + (double)U[0] + (double)V[8];
  }
  const double t1 = mpm_wall_seconds();
  *sink += acc;
  return t1 - t0;
}

static void copy_state(mpm_real *const F[9], const mpm_real *plastic, mpm_real *const Fw[9],
                       mpm_real *pw, long n) {
  for (int q = 0; q < 9; ++q) memcpy(Fw[q], F[q], (size_t)n * sizeof(mpm_real));
  memcpy(pw, plastic, (size_t)n * sizeof(mpm_real));
}

int mpm_bench_stress(int argc, char **argv) {
  int threads[16] = {1, 2}, nthreads = 2, repeats = 5, particles = 1000000;
  for (int i = 0; i < argc; ++i) {
    if (!strcmp(argv[i], "--threads") && i + 1 < argc) {
      nthreads = bench_parse_threads(argv[++i], threads, 16);
      if (nthreads <= 0) {
        fprintf(stderr, "mpm bench: --threads expects a list like 1,2\n");
        return MPM_EXIT_USAGE;
      }
    } else if (!strcmp(argv[i], "--repeats")) {
      if (mpm_cli_parse_int("--repeats", i + 1 < argc ? argv[i + 1] : NULL, 1, MAX_REPEATS,
                            &repeats))
        return MPM_EXIT_USAGE;
      ++i;
    } else if (!strcmp(argv[i], "--particles")) {
      if (mpm_cli_parse_int("--particles", i + 1 < argc ? argv[i + 1] : NULL, 1000, 100000000,
                            &particles))
        return MPM_EXIT_USAGE;
      ++i;
    } else {
      fprintf(stderr, "mpm bench stress: unknown option '%s'\n", argv[i]);
      return MPM_EXIT_USAGE;
    }
  }
  const long n = particles;
  const size_t bytes = (size_t)n * sizeof(mpm_real);
  mpm_real *F[9] = {0}, *Fw[9] = {0}, *plastic = mpm_alloc(bytes), *pw = mpm_alloc(bytes);
  int ok = plastic && pw;
  for (int q = 0; q < 9; ++q) {
    F[q] = mpm_alloc(bytes);
    Fw[q] = mpm_alloc(bytes);
    ok = ok && F[q] && Fw[q];
  }
  if (!ok) {
    fprintf(stderr, "mpm bench stress: out of memory for %ld particles\n", n);
    for (int q = 0; q < 9; ++q) {
      mpm_free(F[q]);
      mpm_free(Fw[q]);
    }
    mpm_free(plastic);
    mpm_free(pw);
    return MPM_EXIT_FAILURE;
  }
#pragma omp parallel for schedule(static)
  for (long i = 0; i < n; ++i) {
    double Fi[9];
    particle_F((uint64_t)i, Fi);
    for (int q = 0; q < 9; ++q) {
      F[q][i] = (mpm_real)Fi[q];
      Fw[q][i] = (mpm_real)Fi[q];
    }
  }

  bench_print_machine();
  printf("stress benchmark: %ld particles, F = U diag(s) V^T (U, V random rotations, s in "
         "[0.8, 1.25]), chunks of %d, median of %d repeats\n",
         n, MPM_STRESS_CHUNK, repeats);
  printf("  E = 100 kPa, nu = 0.3; von Mises yield 5 kPa; Drucker-Prager 30 deg, no cohesion; "
         "snow theta_c 2.5e-2, theta_s 7.5e-3, xi 10\n");
  printf("%-18s %7s %12s %16s\n", "model", "threads", "stress_ns/p", "return_map_ns/p");
  double sink = 0, tim[MAX_REPEATS];
  for (int kind = 0; kind < MPM_MODEL_COUNT; ++kind) {
    const mpm_model *model = mpm_model_of((mpm_model_kind)kind);
    if (!model || !model->kirchhoff_batch) continue;
    const mpm_material m = bench_material((mpm_model_kind)kind);
    if (m.model != model) continue;
    for (long i = 0; i < n; ++i) plastic[i] = model->plastic_initial;
    for (int t = 0; t < nthreads; ++t) {
      mpm_set_threads(threads[t]);
      const pass_ctx stress = {&m, F, plastic}, rmap = {&m, Fw, pw};
      time_chunks(chunk_stress, &stress, n, &sink); /* warm-up */
      for (int r = 0; r < repeats; ++r)
        tim[r] = time_chunks(chunk_stress, &stress, n, &sink) * 1e9 / n;
      const double stress_ns = bench_median(tim, repeats);
      char rm[32] = "-";
      if (model->return_map) {
        for (int r = -1; r < repeats; ++r) { /* r = -1: warm-up */
          copy_state(F, plastic, Fw, pw, n);
          const double s = time_chunks(chunk_return_map, &rmap, n, &sink) * 1e9 / n;
          if (r >= 0) tim[r] = s;
        }
        snprintf(rm, sizeof rm, "%.1f", bench_median(tim, repeats));
      }
      printf("%-18s %7d %12.1f %16s\n", model->name, threads[t], stress_ns, rm);
      fflush(stdout);
    }
  }
  printf("SVD: one 3x3 SVD per particle; mpm_svd3 on F gathered from the component arrays, "
         "mpm_svd3_batch on the arrays in chunks; wall time / calls (with several threads the "
         "throughput figure)\n");
  printf("%-18s %7s %12s\n", "", "threads", "ns/call");
  for (int t = 0; t < nthreads; ++t) {
    mpm_set_threads(threads[t]);
    time_svd(F, n, &sink); /* warm-up */
    for (int r = 0; r < repeats; ++r) tim[r] = time_svd(F, n, &sink) * 1e9 / n;
    printf("%-18s %7d %12.1f\n", "mpm_svd3", threads[t], bench_median(tim, repeats));
    const pass_ctx svd = {NULL, F, NULL};
    time_chunks(chunk_svd_batch, &svd, n, &sink); /* warm-up */
    for (int r = 0; r < repeats; ++r)
      tim[r] = time_chunks(chunk_svd_batch, &svd, n, &sink) * 1e9 / n;
    printf("%-18s %7d %12.1f\n", "mpm_svd3_batch", threads[t], bench_median(tim, repeats));
    fflush(stdout);
  }
  g_sink = sink;
  printf("peak memory: %.1f MiB (resident set)\n", bench_peak_rss_mib());
  for (int q = 0; q < 9; ++q) {
    mpm_free(F[q]);
    mpm_free(Fw[q]);
  }
  mpm_free(plastic);
  mpm_free(pw);
  return MPM_EXIT_OK;
}
