/* bench_implicit.c - `mpm bench implicit`: the implicit integrator's costs and its payoff.
 *
 * Part 1, one Hessian action: on a resting neo-Hookean block (8 particles per cell, quadratic,
 * APIC), ns per DOF and per particle for one action of M + dt^2 K (gather, stress derivative,
 * scatter; solver/implicit.h) beside ns per particle of one explicit P2G + G2P on the same body;
 * CG iterations of one implicit step with and without the Jacobi preconditioner.
 *
 * Part 3, iterations against resolution: the third implicit step of 1/120 s of a spinning rubber
 * block hitting a floor at dx = 4, 2 and 1 cm, preconditioned by Jacobi and by the multigrid
 * V-cycle (solver/multigrid.h): iterations per Newton iteration and the step's seconds.
 *
 * Part 2, time to solution: 1 s of a block dropped onto a slip floor, for E = 5e6 Pa (Zhu's
 * Table 1 material) and E = 1e9 Pa, and of examples/rubber_bunny_implicit.json's rubber bunny
 * (E = 1e7 Pa, thrown spinning onto a floor with friction; its mesh is looked for beside the
 * working folder and the program): the explicit integrator at its CFL step, and the implicit
 * one at the CFL rate of the motion (each step as long as the fastest particle allows, up to
 * 1/60 s) and at each fixed step of a ladder (1/60 s down), with Zhu's single linearized step
 * (CG to 1e-4, fixed steps only) and with 2 Newton iterations (CG to 1e-2: inexact Newton)
 * (--ladder cfl|fixed: those runs only), judged against the explicit run:
 * (--preconditioner multigrid: the implicit runs with the multigrid V-cycle; --scheme newmark:
 * with Newmark's positions, solver/implicit.h)
 * "stable" = no guard stop and no energy growth beyond the start; "accurate" = the centre of
 * mass within half a cell of the explicit one at every frame up to the first impact, and at the
 * end within half a cell of the explicit block's lowest point after impact (resting on the
 * floor). The
 * elastic rebound after the impact is a compression wave faster than any of these steps:
 * backward Euler dissipates it, so it is printed for both runs and not judged. The fastest run
 * that is stable and accurate is reported with its speedup. Figures are printed, never
 * asserted. */
#define _POSIX_C_SOURCE 200809L /* readlink */
#include "bench.h"
#include "bench_util.h"
#include "cli.h"
#include "core/parallel.h"
#include "solver/implicit.h"
#include "sim/sim.h"
#include "transfer/transfer.h"

#include <math.h>
#include <stdio.h>
#include <unistd.h>
#include <stdlib.h>
#include <string.h>

/* A block of about n particles (8 per cell) at rest `drop` m above a slip floor, of Young's
 * modulus E, with the integrator's solver keys. */
static mpm_sim *block(int n, double dx, double E, double drop, const char *solver, double end,
                      mpm_error *err) {
  const double side = cbrt((double)n / 8) * dx, floor_y = 4 * dx;
  const double domain = side + 12 * dx + drop;
  char text[2048];
  snprintf(text, sizeof text,
           "{\"domain\": {\"min\": [0,0,0], \"max\": [%.6g,%.6g,%.6g], \"dx\": %g},"
           " \"time\": {\"end\": %g, \"fps\": 60}, \"solver\": {%s},"
           " \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\", \"E\": %g, "
           "\"nu\": 0.3, \"density\": 1000}],"
           " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [%.6g,%.6g,%.6g], "
           "\"half_extent\": [%.6g,%.6g,%.6g]}, \"material\": \"m\", \"particles_per_cell\": 8, "
           "\"jitter\": 0}],"
           " \"colliders\": [{\"shape\": {\"type\": \"halfspace\", \"point\": [0, %g, 0], "
           "\"normal\": [0, 1, 0]}, \"rule\": \"slip\"}]}",
           side + 12 * dx, domain, side + 12 * dx, dx, end, solver, E, 6 * dx + side / 2,
           floor_y + dx + drop + side / 2, 6 * dx + side / 2, side / 2, side / 2, side / 2,
           floor_y);
  return bench_sim_from_text(text, "bench-implicit.json", err);
}

/* The rubber bunny of examples/rubber_bunny_implicit.json (dx 1.5 cm, E = 1e7 Pa, nu 0.4, thrown
 * at 0.4 m/s spinning at 2 rad/s, 5.5 cm above a floor with friction 0.5), 1 s at 60 frames per
 * second, with the integrator's solver keys; `mesh` is bunny.obj's path. */
static mpm_sim *bunny(const char *mesh, const char *solver, mpm_error *err) {
  char text[4096];
  snprintf(
      text, sizeof text,
      "{\"domain\": {\"min\": [0,0,0], \"max\": [1,1,1], \"dx\": 0.015},"
      " \"time\": {\"end\": 1.0, \"fps\": 60}, \"solver\": {%s},"
      " \"materials\": [{\"name\": \"rubber\", \"model\": \"neo_hookean\", \"E\": 1e7,"
      " \"nu\": 0.4, \"density\": 1100}],"
      " \"bodies\": [{\"shape\": {\"type\": \"mesh\", \"file\": \"%s\", \"center\": [0.5,0.55,0.5],"
      " \"scale\": 0.04}, \"material\": \"rubber\", \"velocity\": [0.4,0,0],"
      " \"angular_velocity\": [0,2,0]}],"
      " \"colliders\": [{\"shape\": {\"type\": \"halfspace\", \"point\": [0,0.1,0],"
      " \"normal\": [0,1,0]}, \"rule\": \"separate\", \"friction\": 0.5}]}",
      solver, mesh);
  return bench_sim_from_text(text, "bench-bunny.json", err);
}

/* examples/meshes/bunny.obj from the working folder or beside the program (build/mpm), or NULL. */
static const char *find_bunny(char *buf, size_t cap) {
  static const char *const tries[] = {"examples/meshes/bunny.obj", "../examples/meshes/bunny.obj"};
  for (int k = 0; k < 2; ++k) {
    FILE *f = fopen(tries[k], "r");
    if (f) {
      fclose(f);
      snprintf(buf, cap, "%s", tries[k]);
      return buf;
    }
  }
  char exe[4096];
  const ssize_t n = readlink("/proc/self/exe", exe, sizeof exe - 1);
  if (n <= 0) return NULL;
  exe[n] = '\0';
  char *slash = strrchr(exe, '/');
  if (!slash) return NULL;
  *slash = '\0';
  snprintf(buf, cap, "%s/../examples/meshes/bunny.obj", exe);
  FILE *f = fopen(buf, "r");
  if (!f) return NULL;
  fclose(f);
  return buf;
}

/* A scene of part 2: made with the integrator's solver keys. */
typedef struct drop_case {
  const char *name;
  int particles;    /* the block's */
  double E, dx;     /* the block's modulus; the grid's cell (accuracy: half of it) */
  const char *mesh; /* the bunny's mesh: the case is the bunny */
} drop_case;

static mpm_sim *make_case(const drop_case *c, const char *solver, mpm_error *err) {
  return c->mesh ? bunny(c->mesh, solver, err)
                 : block(c->particles, c->dx, c->E, 0.1, solver, 1.0, err);
}

static double com_height(const mpm_sim *sim) {
  const mpm_particles *p = &sim->particles;
  double m = 0, my = 0;
  for (size_t i = 0; i < p->count; ++i) {
    m += p->mass[i];
    my += (double)p->mass[i] * p->x[1][i];
  }
  return m > 0 ? my / m : 0;
}

static double total_energy(const mpm_sim *sim) {
  const mpm_diagnostics d = mpm_sim_diagnostics(sim);
  double pot = 0;
  const mpm_particles *p = &sim->particles;
  for (size_t i = 0; i < p->count; ++i) pot += (double)p->mass[i] * 9.81 * (double)p->x[1][i];
  return d.kinetic + d.elastic + pot;
}

/* ---- part 1 ---- */

static int hessian_action(int particles, int repeats) {
  mpm_error err;
  const double dx = 0.02, dt = 1e-3;
  mpm_sim *ex = block(particles, dx, 1e5, 0, "", 1, &err);
  mpm_sim *im = block(particles, dx, 1e5, 0, "\"integrator\": \"implicit\"", 1, &err);
  if (!ex || !im) {
    fprintf(stderr, "mpm bench: %s\n", err.message);
    return -1;
  }
  /* explicit P2G + G2P per particle, from the stage timers of a few steps */
  for (int k = 0; k < 2; ++k) mpm_sim_step(ex, dt);
  double runs[100], act[100];
  for (int r = 0; r < repeats; ++r) {
    const mpm_stage_times t0 = ex->times;
    const int steps = 5;
    for (int k = 0; k < steps; ++k) mpm_sim_step(ex, dt);
    runs[r] = ((ex->times.p2g - t0.p2g) + (ex->times.g2p - t0.g2p)) * 1e9 /
              ((double)ex->particles.count * steps);
  }
  const double explicit_ns = bench_median(runs, repeats);
  /* one Hessian action */
  mpm_implicit s;
  if (mpm_sim_implicit_system(im, dt, &s) != MPM_OK) {
    fprintf(stderr, "mpm bench: %s\n", mpm_sim_last_error(im));
    return -1;
  }
  mpm_dofs *d = s.dofs;
  mpm_real **x = mpm_dofs_vector(d, "bench.x"), **y = mpm_dofs_vector(d, "bench.y");
  if (!x || !y) return -1;
  uint64_t rng = 1;
  for (size_t i = 0; i < d->count; ++i)
    for (int c = 0; c < 3; ++c) {
      rng ^= rng << 13, rng ^= rng >> 7, rng ^= rng << 17;
      x[c][i] = d->mass[i] > 0 ? (mpm_real)((double)(rng >> 11) / 9007199254740992.0 - 0.5) : 0;
    }
  mpm_implicit_displace(&s, NULL);
  const double b0 = mpm_wall_seconds();
  mpm_implicit_build(&s);
  const double build_s = mpm_wall_seconds() - b0;
  const int actions = 10;
  mpm_implicit_apply(&s, 1, s.apply_scale, x, y);
  for (int r = 0; r < repeats; ++r) {
    const double t0 = mpm_wall_seconds();
    for (int k = 0; k < actions; ++k) mpm_implicit_apply(&s, 1, s.apply_scale, x, y);
    act[r] = (mpm_wall_seconds() - t0) / actions;
  }
  const double a = bench_median(act, repeats);
  const size_t np = im->particles.count, nd = d->count;
  printf("  %d threads, %zu particles, %zu DOFs: Hessian action %.1f ns per DOF = %.1f ns per "
         "particle; explicit P2G + G2P %.1f ns per particle (action / explicit %.2fx); building "
         "the factored dP/dF %.1f ns per particle\n",
         mpm_thread_count(), np, nd, a * 1e9 / (double)nd, a * 1e9 / (double)np, explicit_ns,
         a * 1e9 / (double)np / explicit_ns, build_s * 1e9 / (double)np);
  /* CG iterations of one step (from the resting state plus gravity), with and without Jacobi */
  for (int pre = 1; pre >= 0; --pre) {
    if (mpm_sim_implicit_system(im, 5e-3, &s) != MPM_OK) return -1;
    const mpm_implicit_options o = {1, 1e-4, 2000, pre};
    mpm_implicit_result r;
    const double t0 = mpm_wall_seconds();
    if (mpm_implicit_solve(&s, &o, &r)) return -1;
    printf("    one step of 5 ms, CG to 1e-4 %s the Jacobi preconditioner: %d iterations, %.3f "
           "s%s\n",
           pre ? "with   " : "without", r.cg_iterations, mpm_wall_seconds() - t0,
           r.cg_converged ? "" : " (not converged)");
  }
  mpm_sim_destroy(ex);
  mpm_sim_destroy(im);
  return 0;
}

/* ---- part 3: iterations against resolution ---- */

/* A rubber block (E = 1e7 Pa, nu 0.4, 0.32 m wide) spinning at 2 rad/s about y and falling at
 * 0.5 m/s onto a slip floor it touches, on a grid of spacing dx, with the solver keys (frames
 * of 1/120 s). */
static mpm_sim *spinning_block(double dx, double E, const char *solver, mpm_error *err) {
  const double side = 0.32, floor_y = 4 * dx + 0.05, pad = 6 * dx;
  char text[2048];
  snprintf(text, sizeof text,
           "{\"domain\": {\"min\": [0,0,0], \"max\": [%.6g,%.6g,%.6g], \"dx\": %g},"
           " \"time\": {\"end\": 1, \"fps\": 120}, \"solver\": {%s},"
           " \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\", \"E\": %g, "
           "\"nu\": 0.4, \"density\": 1100}],"
           " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [%.6g,%.6g,%.6g], "
           "\"half_extent\": [%.6g,%.6g,%.6g]}, \"material\": \"m\", \"particles_per_cell\": 8, "
           "\"jitter\": 0, \"velocity\": [0,-0.5,0], \"angular_velocity\": [0,2,0]}],"
           " \"colliders\": [{\"shape\": {\"type\": \"halfspace\", \"point\": [0, %g, 0], "
           "\"normal\": [0, 1, 0]}, \"rule\": \"slip\"}]}",
           side * 1.5 + 2 * pad, side + floor_y + 2 * pad, side * 1.5 + 2 * pad, dx, solver, E,
           pad + side * 0.75, floor_y + side / 2 + 0.25 * dx, pad + side * 0.75, side / 2, side / 2,
           side / 2, floor_y);
  return bench_sim_from_text(text, "bench-spin.json", err);
}

/* The third implicit step of 1/120 s of the spinning block at three resolutions (the fastest
 * particle moves 0.8 of the finest cell), Jacobi against
 * multigrid: preconditioned iterations per Newton iteration (a multigrid's stay nearly flat
 * as dx halves, Jacobi's grow) and the seconds of the step. */
static int resolution(void) {
  static const double spacing[] = {0.04, 0.02, 0.01}, moduli[] = {1e7, 1e9};
  static const char *const pre[] = {"jacobi", "multigrid"};
  for (int e = 0; e < 2; ++e)
    for (int k = 0; k < 3; ++k)
      for (int m = 0; m < 2; ++m) {
        char solver[256];
        snprintf(solver, sizeof solver,
                 "\"integrator\": \"implicit\", \"dt\": %.9g, \"cg_tolerance\": 1e-3, "
                 "\"cg_max_iterations\": 20000, \"preconditioner\": \"%s\"",
                 1.0 / 120, pre[m]);
        mpm_error err;
        mpm_sim *sim = spinning_block(spacing[k], moduli[e], solver, &err);
        if (!sim) {
          fprintf(stderr, "mpm bench: %s\n", err.message);
          return -1;
        }
        /* the second step is timed: the first one grows the step's scratch to its size */
        double t0 = 0;
        for (int step = 0; step < 2; ++step) {
          t0 = mpm_wall_seconds();
          if (mpm_sim_step(sim, 1.0 / 120) != MPM_OK) {
            fprintf(stderr, "mpm bench: %s\n", mpm_sim_last_error(sim));
            mpm_sim_destroy(sim);
            return -1;
          }
        }
        const double sec = mpm_wall_seconds() - t0;
        const mpm_solver_figures *f = &sim->last_frame_solver; /* the step was the frame */
        char where[160] = "";
        if (m == 1)
          snprintf(where, sizeof where,
                   " (building the hierarchy %.2f s, V-cycles %.2f s; the hierarchy %.1f MiB)",
                   f->mg_setup_seconds, f->mg_cycle_seconds, (double)f->mg_bytes / 1048576.0);
        printf("    E = %g Pa, dx = %g m, %zu particles, %s: %lld Newton iterations, %.1f CG "
               "iterations per Newton iteration, %.2f s for the step%s%s\n",
               moduli[e], spacing[k], sim->particles.count, pre[m], f->newton_iterations,
               f->newton_iterations ? (double)f->cg_iterations / (double)f->newton_iterations : 0,
               sec, where, f->cg_unconverged ? " (a solve stopped short)" : "");
        fflush(stdout);
        mpm_sim_destroy(sim);
      }
  return 0;
}

/* ---- part 2 ---- */

typedef struct run_figures {
  int ok;         /* finished without a guard stop, energy never above the start */
  double seconds; /* wall */
  long long steps;
  double com[64]; /* centre-of-mass height per frame */
  double mean_cg; /* implicit: CG iterations per step */
} run_figures;

static void simulate(const drop_case *c, const char *solver, run_figures *f) {
  memset(f, 0, sizeof *f);
  mpm_error err;
  mpm_sim *sim = make_case(c, solver, &err);
  if (!sim) {
    fprintf(stderr, "mpm bench: %s\n", err.message);
    return;
  }
  const double e0 = total_energy(sim);
  long long cg = 0, isteps = 0;
  f->ok = 1;
  const double t0 = mpm_wall_seconds();
  for (int fr = 0; fr < sim->frame_count && fr < 64; ++fr) {
    if (mpm_sim_advance_frame(sim) != MPM_OK) {
      f->ok = 0;
      break;
    }
    f->com[fr] = com_height(sim);
    if (total_energy(sim) > e0 * (1 + 1e-3) + 1e-6) f->ok = 0;
  }
  f->seconds = mpm_wall_seconds() - t0;
  cg = sim->cg_iterations;
  isteps = sim->implicit_steps;
  f->steps = (long long)sim->steps;
  f->mean_cg = isteps ? (double)cg / (double)isteps : 0;
  mpm_sim_destroy(sim);
}

/* The first frame of greatest compression (the centre of mass's first local minimum) and the
 * rebound after it (highest centre of mass later minus that minimum), m. */
static int first_minimum(const double *com, int n) {
  for (int k = 1; k + 1 < n; ++k)
    if (com[k] <= com[k - 1] && com[k] < com[k + 1]) return k;
  return n - 1;
}

static double rebound(const double *com, int n, int k0) {
  double hi = com[k0];
  for (int k = k0; k < n; ++k) hi = fmax(hi, com[k]);
  return hi - com[k0];
}

/* The implicit runs' preconditioner key (--preconditioner): "" for the default (Jacobi). */
static const char *preconditioner_key = "";

/* The implicit runs' scheme key (--scheme): "" for the default (backward Euler). */
static const char *scheme_key = "";

/* Which steps part 2 runs (--ladder): 0 all, 1 the fixed steps only, 2 the CFL rate only. */
static int ladder_choice = 0;

/* The CFL-rate run's keys: each step as long as the fastest particle allows (solver.dt 0), up to
 * a frame of 1/60 s: the implicit step at the rate of the material's motion (HOT's setting). */
#define CFL_RATE 0.8

static int time_to_solution(const drop_case *c) {
  const double dx = c->dx;
  const char *name = c->name;
  enum { FRAMES = 60 };
  run_figures ref, im;
  simulate(c, "", &ref);
  if (!ref.ok) {
    printf("    %s: the explicit reference run failed\n", name);
    return 0;
  }
  const int impact = first_minimum(ref.com, FRAMES);
  printf("    %s, %d threads: explicit %lld steps in %.2f s (first impact at frame %d, "
         "rebound %.4f m)\n",
         name, mpm_thread_count(), ref.steps, ref.seconds, impact,
         rebound(ref.com, FRAMES, impact));
  /* 0: at the CFL rate of the motion (2 Newton iterations only: Zhu's single step there stops
     with the guard's cell-a-step rule) */
  static const double ladder[] = {0, 1.0 / 60, 1.0 / 120, 1.0 / 240, 1.0 / 480};
  /* Zhu's single linearized step needs an accurate solve; Newton iterations with a line search
   * can take inexact ones (inexact Newton) */
  static const struct {
    int newton;
    double tol;
  } solves[] = {{1, 1e-4}, {2, 1e-2}};
  double contact = ref.com[impact]; /* the explicit block's lowest centre of mass after impact */
  for (int fr = impact; fr < FRAMES; ++fr) contact = fmin(contact, ref.com[fr]);
  double best_seconds = 0, best_tol = 0;
  char best_rung[64] = "";
  int best_newton = 0;
  for (size_t k = 0; k < sizeof ladder / sizeof ladder[0]; ++k)
    for (int v = 0; v < 2; ++v) {
      const int cfl = ladder[k] == 0;
      if ((cfl && (ladder_choice == 1 || v == 0)) || (!cfl && ladder_choice == 2)) continue;
      const int newton = solves[v].newton;
      char solver[300], rung[64], rate[64] = "";
      if (cfl) {
        snprintf(rung, sizeof rung, "at the CFL rate %g (up to 1/60 s)", CFL_RATE);
        snprintf(rate, sizeof rate, ", \"cfl\": %g, \"max_dt\": %.10g", CFL_RATE, 1.0 / 60);
      } else {
        snprintf(rung, sizeof rung, "= 1/%.0f s", 1 / ladder[k]);
      }
      snprintf(solver, sizeof solver,
               "\"integrator\": \"implicit\", \"dt\": %.9g, \"cg_tolerance\": %g, "
               "\"newton_iterations\": %d%s%s%s",
               ladder[k], solves[v].tol, newton, preconditioner_key, scheme_key, rate);
      simulate(c, solver, &im);
      /* accurate: within half a cell of the explicit run up to its first impact, and resting at
       * the end where the explicit block touches the floor; the rebound, a wave faster than
       * dt, is printed, not judged */
      double fall = 0;
      for (int fr = 0; fr <= impact; ++fr) fall = fmax(fall, fabs(im.com[fr] - ref.com[fr]));
      const double rest = fabs(im.com[FRAMES - 1] - contact), err = fmax(fall, rest);
      const int accurate = im.ok && err <= 0.5 * dx;
      const int k0 = first_minimum(im.com, FRAMES);
      printf("      implicit dt %s, %d Newton, CG to %g: %lld steps, %.1f CG iterations "
             "per step, %.2f s, %s, %s (error %.4f m in the fall, %.4f m at rest; rebound "
             "%.4f m) -> %.1fx\n",
             rung, newton, solves[v].tol, im.steps, im.mean_cg, im.seconds,
             im.ok ? "stable" : "UNSTABLE", accurate ? "accurate" : "not accurate", fall, rest,
             im.ok ? rebound(im.com, FRAMES, k0) : 0, ref.seconds / im.seconds);
      fflush(stdout);
      if (accurate && (best_seconds == 0 || im.seconds < best_seconds)) {
        best_seconds = im.seconds;
        snprintf(best_rung, sizeof best_rung, "%s", rung);
        best_newton = newton;
        best_tol = solves[v].tol;
      }
    }
  if (best_seconds > 0)
    printf("    %s: fastest stable and accurate implicit run: dt %s, %d Newton, CG to "
           "%g: %.2f s against explicit %.2f s: %.1fx faster to solution\n",
           name, best_rung, best_newton, best_tol, best_seconds, ref.seconds,
           ref.seconds / best_seconds);
  else
    printf("    %s: no implicit run of the ladder was stable and accurate\n", name);
  return 0;
}

int mpm_bench_implicit(int argc, char **argv) {
  int particles = 50000, drop_particles = 1000, repeats = 5, threads[16] = {1, 2}, nthreads = 2;
  int part = 0;       /* 0 both, 1 action, 2 time to solution */
  int only_case = -1; /* part 2: --case block5e6|block1e9|bunny */
  for (int i = 0; i < argc; ++i) {
    if (!strcmp(argv[i], "--particles")) {
      if (mpm_cli_parse_int("--particles", i + 1 < argc ? argv[i + 1] : NULL, 1000, 50000000,
                            &particles))
        return MPM_EXIT_USAGE;
      ++i;
    } else if (!strcmp(argv[i], "--drop-particles")) {
      if (mpm_cli_parse_int("--drop-particles", i + 1 < argc ? argv[i + 1] : NULL, 64, 1000000,
                            &drop_particles))
        return MPM_EXIT_USAGE;
      ++i;
    } else if (!strcmp(argv[i], "--repeats")) {
      if (mpm_cli_parse_int("--repeats", i + 1 < argc ? argv[i + 1] : NULL, 1, 100, &repeats))
        return MPM_EXIT_USAGE;
      ++i;
    } else if (!strcmp(argv[i], "--only") && i + 1 < argc) {
      ++i;
      part = !strcmp(argv[i], "action")       ? 1
             : !strcmp(argv[i], "drop")       ? 2
             : !strcmp(argv[i], "resolution") ? 3
                                              : -1;
      if (part < 0) {
        fprintf(stderr, "mpm bench implicit: --only expects action, drop or resolution\n");
        return MPM_EXIT_USAGE;
      }
    } else if (!strcmp(argv[i], "--case") && i + 1 < argc) {
      ++i;
      only_case = !strcmp(argv[i], "block5e6")   ? 0
                  : !strcmp(argv[i], "block1e9") ? 1
                  : !strcmp(argv[i], "bunny")    ? 2
                                                 : -2;
      if (only_case < -1) {
        fprintf(stderr, "mpm bench implicit: --case expects block5e6, block1e9 or bunny\n");
        return MPM_EXIT_USAGE;
      }
    } else if (!strcmp(argv[i], "--ladder") && i + 1 < argc) {
      ++i;
      ladder_choice = !strcmp(argv[i], "all")     ? 0
                      : !strcmp(argv[i], "fixed") ? 1
                      : !strcmp(argv[i], "cfl")   ? 2
                                                  : -1;
      if (ladder_choice < 0) {
        fprintf(stderr, "mpm bench implicit: --ladder expects all, fixed or cfl\n");
        return MPM_EXIT_USAGE;
      }
    } else if (!strcmp(argv[i], "--preconditioner") && i + 1 < argc) {
      ++i;
      if (!strcmp(argv[i], "multigrid"))
        preconditioner_key = ", \"preconditioner\": \"multigrid\"";
      else if (!strcmp(argv[i], "jacobi"))
        preconditioner_key = "";
      else {
        fprintf(stderr, "mpm bench implicit: --preconditioner expects jacobi or multigrid\n");
        return MPM_EXIT_USAGE;
      }
    } else if (!strcmp(argv[i], "--scheme") && i + 1 < argc) {
      ++i;
      if (!strcmp(argv[i], "newmark"))
        scheme_key = ", \"scheme\": \"newmark\"";
      else if (!strcmp(argv[i], "backward_euler"))
        scheme_key = "";
      else {
        fprintf(stderr, "mpm bench implicit: --scheme expects backward_euler or newmark\n");
        return MPM_EXIT_USAGE;
      }
    } else if (!strcmp(argv[i], "--threads") && i + 1 < argc) {
      nthreads = bench_parse_threads(argv[++i], threads, 16);
      if (nthreads < 1) {
        fprintf(stderr, "mpm bench implicit: --threads expects a list like 1,2\n");
        return MPM_EXIT_USAGE;
      }
    } else {
      fprintf(stderr, "mpm bench implicit: unknown option '%s'\n", argv[i]);
      return MPM_EXIT_USAGE;
    }
  }
  bench_print_machine();
  if (part == 0 || part == 1) {
    printf("implicit benchmark, part 1: one Hessian action against one explicit P2G + G2P "
           "(neo-Hookean block, 8 particles per cell, quadratic, APIC; median of %d)\n",
           repeats);
    for (int t = 0; t < nthreads; ++t) {
      mpm_set_threads(threads[t]);
      if (hessian_action(particles, repeats)) return MPM_EXIT_FAILURE;
      fflush(stdout);
    }
  }
  if (part == 0 || part == 3) {
    printf("implicit benchmark, part 3: the third step of 1/120 s of a block (0.32 "
           "m) spinning at 2 rad/s onto a slip floor at 0.5 m/s, 2 Newton iterations, CG to 1e-3, "
           "at three resolutions and two moduli: Jacobi against multigrid\n");
    for (int t = 0; t < nthreads; ++t) {
      mpm_set_threads(threads[t]);
      printf("  %d threads:\n", threads[t]);
      if (resolution()) return MPM_EXIT_FAILURE;
    }
  }
  if (part == 0 || part == 2) {
    printf("implicit benchmark, part 2: 1 s of a block (about %d particles, dx = 4 cm) dropped "
           "10 cm onto a slip floor; stable = no guard stop and no energy growth, accurate = "
           "centre of mass within half a cell of the explicit run up to the first impact and at "
           "rest; implicit runs preconditioned by %s, positions by %s\n",
           drop_particles, preconditioner_key[0] ? "a multigrid V-cycle" : "Jacobi",
           scheme_key[0] ? "Newmark's scheme" : "backward Euler");
    char mesh[4200];
    const drop_case cases[3] = {
        {"block, E = 5e+06 Pa", drop_particles, 5e6, 0.04, NULL},
        {"block, E = 1e+09 Pa", drop_particles, 1e9, 0.04, NULL},
        {"rubber bunny, E = 1e+07 Pa, dx = 1.5 cm", 0, 1e7, 0.015, find_bunny(mesh, sizeof mesh)}};
    for (int t = 0; t < nthreads; ++t) {
      mpm_set_threads(threads[t]);
      for (int e = 0; e < 3; ++e) {
        if (only_case >= 0 && e != only_case) continue;
        if (e == 2 && !cases[2].mesh) {
          printf("    rubber bunny: examples/meshes/bunny.obj not found beside the working "
                 "folder or the program; left out\n");
          continue;
        }
        time_to_solution(&cases[e]);
      }
    }
  }
  printf("peak memory: %.1f MiB (resident set)\n", bench_peak_rss_mib());
  return MPM_EXIT_OK;
}
