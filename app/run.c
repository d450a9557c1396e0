/* run.c - `mpm run` and `mpm check`: load and validate a scene, simulate it frame by frame
 * with a progress display, write the outputs. Written on the public API (mpm/mpm.h) alone,
 * as a program embedding the library would be: the build compiles it without the engine's
 * internal headers on the include path (CMakeLists.txt, mpm_cli_public). */
#define _POSIX_C_SOURCE 200809L

#include "cli.h"
#include "progress.h"
#include "ranks.h"
#include "mpm/mpm.h"

#ifdef _OPENMP
#include <omp.h>
#endif

#include <signal.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

/* The signal that asked the run to stop (SIGINT, SIGTERM), or 0. The handler only records it;
 * the frame loop sees it between two steps, writes a checkpoint and exits. A second signal
 * gets the default action (SA_RESETHAND): the atomic writes keep everything on disk whole. */
static volatile int stop_signal;

static void on_stop_signal(int sig) {
  stop_signal = sig;
}

static void catch_stop_signals(void) {
  struct sigaction sa;
  memset(&sa, 0, sizeof sa);
  sa.sa_handler = on_stop_signal;
  sa.sa_flags = SA_RESETHAND;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, NULL);
  sigaction(SIGTERM, &sa, NULL);
}

/* The longest path the program builds (an output folder and a file name in it). */
enum { PATH_CAP = 4096 + 64 };

/* The scene's warnings (a kernel that goes unstable, overlapping bodies, bodies inside
 * colliders), one line each. */
static void print_warnings(const mpm_sim *sim, const char *scene) {
  char text[8192];
  if (!mpm_sim_warnings(sim, text, sizeof text)) return;
  for (char *line = text, *end; *line; line = end + 1) {
    end = strchr(line, '\n');
    if (end) *end = 0;
    fprintf(stderr, "mpm: warning: %s: %s\n", scene, line);
    if (!end) break;
  }
}

static mpm_sim_info info_of(const mpm_sim *sim) {
  mpm_sim_info info;
  mpm_sim_get_info(sim, &info, sizeof info);
  return info;
}

/* Progress within a frame (the step callback): the particles of every rank (on one process,
 * mpm_sim_particle_count's). */
static void progress_on_step(void *ctx, const mpm_sim *sim) {
  mpm_progress_step(ctx, mpm_sim_frame(sim), mpm_sim_time(sim), mpm_sim_steps(sim),
                    info_of(sim).run_particles);
}

/* Above this many expected particles `mpm check` answers from the scene's description alone
 * unless --sample: sampling 10^8 particles took 75 s and 14.8 GB to say "ok". */
#define CHECK_SAMPLE_MAX 5e6

/* 12.3 million, 450,000: the count as read aloud. */
static void count_text(double n, char *buf, size_t cap) {
  if (n >= 1e6)
    snprintf(buf, cap, "%.3g million", n / 1e6);
  else
    snprintf(buf, cap, "%.0f", n);
}

/* `mpm check` of a large scene: what it will need, from the description alone. */
static int check_estimate(const char *path, const mpm_scene_estimate *e) {
  char n[64];
  count_text(e->particles, n, sizeof n);
  printf("%s: ok (about %s particles from the bodies' volumes, not sampled; %d bodies, %d "
         "materials, %d colliders, dx = %g m, %d frames, about %.1f GiB of the %.1f GiB "
         "available)\n",
         path, n, e->bodies, e->materials, e->colliders, e->dx, e->frame_count,
         e->memory_bytes / (1024.0 * 1024 * 1024), e->available_bytes / (1024.0 * 1024 * 1024));
  printf("%s: the bodies were not sampled (more than %.0f million particles expected): their "
         "placement (inside the domain, apart from each other and from the colliders) is "
         "checked when the run starts; `mpm check --sample %s` samples them now\n",
         path, CHECK_SAMPLE_MAX / 1e6, path);
  const double per_frame = e->first_dt > 0 ? ceil(e->frame_dt / e->first_dt - 1e-9) : 0;
  printf("%s: first step dt = %.3g s (the bodies' initial speeds), about %.0f steps per frame "
         "(%g frames per second)\n",
         path, e->first_dt, per_frame, 1 / e->frame_dt);
  return MPM_EXIT_OK;
}

int mpm_cmd_check(int argc, char **argv) {
  int force_sample = 0;
  const char *path = NULL;
  for (int k = 0; k < argc; ++k) {
    if (!strcmp(argv[k], "--sample")) {
      force_sample = 1;
    } else if (argv[k][0] == '-') {
      static const char *const known[] = {"--sample", NULL};
      mpm_cli_unknown_option("check", argv[k], known);
      return MPM_EXIT_USAGE;
    } else {
      path = path ? "" : argv[k];
    }
  }
  if (!path || !path[0]) {
    fprintf(stderr, "usage: mpm check SCENE.json [--sample]\n");
    return MPM_EXIT_USAGE;
  }
  char err[4096];
  /* first from the description alone: a scene too large to sample in a moment is answered
     from it (every key, the meshes, memory and steps checked; not the bodies' placement) */
  mpm_scene_estimate e;
  mpm_status st = mpm_scene_estimate_file(path, &e, sizeof e, err, sizeof err);
  if (st != MPM_OK) {
    fprintf(stderr, "mpm: %s\n", err);
    return st == MPM_ERR_NOMEM ? MPM_EXIT_FAILURE : MPM_EXIT_USAGE;
  }
  if (e.particles > CHECK_SAMPLE_MAX && !force_sample) return check_estimate(path, &e);
  /* the scene is read, checked and its bodies sampled (which checks meshes and placement);
     nothing is written */
  mpm_sim *sim = NULL;
  st = mpm_sim_create_from_file(path, &sim, err, sizeof err);
  if (st != MPM_OK) {
    fprintf(stderr, "mpm: %s\n", err);
    return st == MPM_ERR_NOMEM ? MPM_EXIT_FAILURE : MPM_EXIT_USAGE;
  }
  print_warnings(sim, path);
  const mpm_sim_info in = info_of(sim);
  printf("%s: ok (%zu particles, %zu of them with domains, %d materials, %d colliders, dx = %g "
         "m, %d frames, about %.0f MiB)\n",
         path, in.particles, in.domain_particles, in.materials, in.colliders, in.dx, in.frame_count,
         in.memory_bytes / (1024.0 * 1024.0));
  /* the first step, as the frame loop will plan it: a frame needing very many steps is
     usually a unit slip (E in Pa, dx in m) or a far too fine grid for the material's stiffness */
  double dt = 0;
  st = mpm_sim_next_dt(sim, &dt);
  if (st == MPM_OK) {
    const double per_frame = dt > 0 ? ceil(in.frame_dt / dt - 1e-9) : 0;
    /* the rule the step follows: explicit steps are bounded by the stiffest material's wave
       speed, implicit ones by particle speed alone (or fixed) */
    const char *rule =
        in.fixed_dt   ? "; implicit: the scene's fixed solver.dt, each frame in equal steps"
        : in.implicit ? "; implicit: the step follows the particles' speed alone (no wave-speed "
                        "bound; at rest it is the frame or solver.max_dt) and shrinks as they "
                        "speed up"
                      : "; the step follows the material's wave speed and shrinks as it speeds up";
    printf("%s: first step dt = %.3g s, about %.0f steps per frame (%g frames per second)%s\n",
           path, dt, per_frame, in.fps, rule);
    if (per_frame > 1e4 && !in.implicit)
      fprintf(stderr,
              "mpm: warning: %s: a frame will need about %.0f steps (more than 10^4): check the "
              "units of E (Pa) and dx (m), or use a coarser dx, a softer material or the "
              "implicit integrator (solver.integrator)\n",
              path, per_frame);
  }
  mpm_sim_destroy(sim);
  return MPM_EXIT_OK;
}

/* 1 when the newest checkpoint written is of the current step already. */
static int checkpoint_is_current(const mpm_sim *sim) {
  char name[64];
  snprintf(name, sizeof name, "checkpoint_%012lld.h5", (long long)mpm_sim_steps(sim));
  const char *last = info_of(sim).last_checkpoint, *slash = strrchr(last, '/');
  return !strcmp(slash ? slash + 1 : last, name);
}

/* After a stop signal: checkpoint the state between the two steps where the run stopped and say
 * how to continue. Exit status 128 + the signal, as shells report a signal's end. */
static int interrupted(mpm_sim *sim, const char *scene_path, int sig) {
  char path[PATH_CAP];
  const char *name = sig == SIGTERM ? "SIGTERM" : "SIGINT";
  if (mpm_sim_write_checkpoint(sim, path, sizeof path) != MPM_OK) {
    fprintf(stderr, "mpm: stopped by %s at step %lld, but the checkpoint failed: %s\n", name,
            (long long)mpm_sim_steps(sim), mpm_sim_last_error(sim));
    return MPM_EXIT_FAILURE;
  }
  fprintf(stderr,
          "mpm: stopped by %s at step %lld (t = %.6g s, %d of %d frames done); checkpoint %s\n"
          "mpm: continue with: mpm run %s --resume %s\n",
          name, (long long)mpm_sim_steps(sim), mpm_sim_time(sim), mpm_sim_frame(sim),
          mpm_sim_frame_count(sim), path, scene_path, info_of(sim).output_dir);
  return 128 + sig;
}

/* `mpm run`; ranks: the ranks of a run on MPI ranks (ranks.h), 0 for one process. */
static int run_scene(int argc, char **argv, int ranks) {
  const char *scene_path = NULL, *out_dir = NULL, *resume_dir = NULL;
  int threads = 0, quiet = 0, max_frames = 0, render = 0, overwrite = 0;
  for (int i = 0; i < argc; ++i) {
    if (!strcmp(argv[i], "-o") || !strcmp(argv[i], "--output")) {
      if (i + 1 >= argc) {
        fprintf(stderr, "mpm run: %s needs a directory\n", argv[i]);
        return MPM_EXIT_USAGE;
      }
      out_dir = argv[++i];
    } else if (!strcmp(argv[i], "--resume")) {
      if (i + 1 >= argc) {
        fprintf(stderr, "mpm run: --resume needs the output directory of the run to continue\n");
        return MPM_EXIT_USAGE;
      }
      resume_dir = argv[++i];
    } else if (!strcmp(argv[i], "--threads")) {
      if (mpm_cli_parse_int("--threads", i + 1 < argc ? argv[i + 1] : NULL, 1, 1024, &threads))
        return MPM_EXIT_USAGE;
      ++i;
    } else if (!strcmp(argv[i], "--frames")) {
      if (mpm_cli_parse_int("--frames", i + 1 < argc ? argv[i + 1] : NULL, 1, 1000000, &max_frames))
        return MPM_EXIT_USAGE;
      ++i;
    } else if (!strcmp(argv[i], "--quiet") || !strcmp(argv[i], "-q")) {
      quiet = 1;
    } else if (!strcmp(argv[i], "--render")) {
      render = 1;
    } else if (!strcmp(argv[i], "--overwrite")) {
      overwrite = 1;
    } else if (argv[i][0] == '-') {
      static const char *const known[] = {"-o",        "--output",    "--resume",
                                          "--threads", "--frames",    "--quiet",
                                          "--render",  "--overwrite", NULL};
      mpm_cli_unknown_option("run", argv[i], known);
      return MPM_EXIT_USAGE;
    } else if (!scene_path) {
      scene_path = argv[i];
    } else {
      fprintf(stderr, "mpm run: more than one scene given ('%s' and '%s')\n", scene_path, argv[i]);
      return MPM_EXIT_USAGE;
    }
  }
  if (!scene_path) {
    fprintf(stderr, "usage: mpm run SCENE.json [-o DIR [--overwrite] | --resume DIR] [--threads N] "
                    "[--frames N] [--render] [--quiet]\n");
    return MPM_EXIT_USAGE;
  }
  if (resume_dir && out_dir && strcmp(resume_dir, out_dir) != 0) {
    fprintf(stderr, "mpm run: --resume %s continues in that directory; -o %s cannot move it\n",
            resume_dir, out_dir);
    return MPM_EXIT_USAGE;
  }
  if (mpm_cli_rank() != 0) quiet = 1; /* (its output goes nowhere: mpm_cmd_run) */
  /* what a run on ranks does not do yet (docs/distributed.md) */
  if (ranks && resume_dir) {
    fprintf(stderr, "mpm run: --resume: a run on MPI ranks writes no checkpoints yet, so there "
                    "is none to resume from (run it again from the start with -o DIR "
                    "--overwrite)\n");
    return MPM_EXIT_USAGE;
  }
  if (ranks && render) {
    fprintf(stderr, "mpm run: --render: not on MPI ranks yet (mpm render reads a frame from "
                    "one file, a run on ranks writes a piece per rank); open the run's run.pvd "
                    "in ParaView\n");
    return MPM_EXIT_USAGE;
  }
  /* the program's OpenMP threads, for everything it runs (the simulation, --render) */
#ifdef _OPENMP
  if (threads > 0) omp_set_num_threads(threads);
#endif

  char err[4096];
  mpm_sim *sim = NULL;
  mpm_status st = mpm_sim_create_from_file(scene_path, &sim, err, sizeof err);
  /* every rank made its simulation from the same scene, or none goes on (the message of the
     first rank that could not) */
  if (mpm_cli_ranks_any(st != MPM_OK, err, sizeof err)) {
    fprintf(stderr, "mpm: %s\n", err);
    mpm_sim_destroy(sim);
    return st == MPM_ERR_NOMEM ? MPM_EXIT_FAILURE : MPM_EXIT_USAGE;
  }
  /* this process's part of the run: what does not run on ranks yet is refused on every rank */
  if (ranks && (st = mpm_sim_join_mpi_world(sim)) != MPM_OK) {
    fprintf(stderr, "mpm: %s\n", mpm_sim_last_error(sim));
    mpm_sim_destroy(sim);
    return st == MPM_ERR_NOMEM ? MPM_EXIT_FAILURE : MPM_EXIT_USAGE;
  }
  if (threads > 0) mpm_sim_set_threads(sim, threads);
  if (!resume_dir) print_warnings(sim, scene_path);
  if (max_frames > 0 && max_frames < mpm_sim_frame_count(sim))
    mpm_sim_set_frame_limit(sim, max_frames);
  char checkpoint[PATH_CAP] = "";
  if (resume_dir) {
    st = mpm_sim_resume(sim, resume_dir, checkpoint, sizeof checkpoint);
    if (st != MPM_OK) {
      fprintf(stderr, "mpm: %s\n", mpm_sim_last_error(sim));
      mpm_sim_destroy(sim);
      return st == MPM_ERR_NOMEM ? MPM_EXIT_FAILURE : MPM_EXIT_USAGE;
    }
    /* a finished run: its last frame is written; resuming would redo the frames after the
     * last checkpoint */
    char last[PATH_CAP];
    snprintf(last, sizeof last, "%s/frame_%04d.vtu", info_of(sim).output_dir,
             mpm_sim_frame_count(sim));
    if (mpm_sim_frame(sim) < mpm_sim_frame_count(sim) && access(last, F_OK) == 0) {
      fprintf(stderr,
              "mpm: the run in %s is complete: its %d frames are written (the last, %s); "
              "nothing to resume (run again with -o DIR to simulate it anew)\n",
              resume_dir, mpm_sim_frame_count(sim), last);
      mpm_sim_destroy(sim);
      return MPM_EXIT_OK;
    }
    print_warnings(sim, scene_path); /* the scene's; where the bodies started is past */
  } else {
    /* the folder locked for this run (a second run into it is refused), an earlier run's
       files refused or, with --overwrite, removed (those alone); then frame 0 and the copy of
       the scene (scene.json, for `mpm render`) */
    st = mpm_sim_open_output(sim, out_dir, overwrite ? MPM_OUTPUT_OVERWRITE : MPM_OUTPUT_NEW);
    st = mpm_sim_ranks_agree(sim, st); /* on ranks: one verdict, one message */
    if (st != MPM_OK) {
      const char *dir = out_dir ? out_dir : info_of(sim).output_dir;
      fprintf(stderr, "mpm run: %s\n", mpm_sim_last_error(sim));
      if (st == MPM_ERR_INVALID && !ranks)
        fprintf(stderr,
                "mpm run: continue that run with --resume %s, replace it with --overwrite, or "
                "write this one elsewhere with -o DIR\n",
                dir);
      else if (st == MPM_ERR_INVALID) /* (no resume on ranks yet) */
        fprintf(stderr,
                "mpm run: replace that run with --overwrite, or write this one elsewhere with "
                "-o DIR\n");
      mpm_sim_destroy(sim);
      return st == MPM_ERR_INVALID ? MPM_EXIT_USAGE : MPM_EXIT_FAILURE;
    }
  }
  stop_signal = 0;
  /* (on ranks the signals keep their default action: a checkpoint to stop with is to come, and
     the ranks would see the signal at different steps; the atomic writes keep the files whole) */
  if (!ranks) catch_stop_signals();
  mpm_sim_set_interrupt(sim, &stop_signal);
  const mpm_sim_info start = info_of(sim);
  mpm_progress pr;
  mpm_progress_begin(&pr,
                     quiet ? MPM_PROGRESS_QUIET
                           : (isatty(STDERR_FILENO) ? MPM_PROGRESS_BAR : MPM_PROGRESS_LINES),
                     start.frame_count, start.run_particles);
  pr.first_frame = mpm_sim_frame(sim);
  pr.first_steps = mpm_sim_steps(sim);
  pr.t0 = mpm_sim_time(sim);
  pr.t_end = start.frame_count * start.frame_dt < start.end_time
                 ? start.frame_count * start.frame_dt
                 : start.end_time;
  mpm_sim_set_step_callback(sim, progress_on_step, &pr);
  if (!quiet && resume_dir)
    fprintf(stderr, "mpm: resuming %s from %s: frame %d of %d, t = %.6g s, step %lld\n", scene_path,
            checkpoint, mpm_sim_frame(sim), start.frame_count, mpm_sim_time(sim),
            (long long)mpm_sim_steps(sim));
  if (!quiet && !ranks)
    fprintf(stderr, "mpm: %s: %zu particles, dx = %g m, %d frames to %s/ (%d threads, %s)\n",
            scene_path, start.particles, start.dx, start.frame_count, start.output_dir,
            start.threads, mpm_real_type());
  if (!quiet && ranks)
    fprintf(stderr,
            "mpm: %s: %zu particles, dx = %g m, %d frames to %s/ (%d MPI ranks x %d threads, "
            "%s; no checkpoints on ranks yet)\n",
            scene_path, start.run_particles, start.dx, start.frame_count, start.output_dir,
            start.ranks, start.threads, mpm_real_type());
  int code = MPM_EXIT_OK;
  while (mpm_sim_frame(sim) < mpm_sim_frame_count(sim)) {
    st = mpm_sim_ranks_agree(sim, mpm_sim_advance_frame(sim));
    if (st == MPM_ERR_INTERRUPTED) {
      mpm_progress_end(&pr);
      code = interrupted(sim, scene_path, stop_signal);
      break;
    }
    const mpm_sim_info in = info_of(sim);
    if (st != MPM_OK) {
      mpm_progress_end(&pr);
      fprintf(stderr, "mpm: %s\n", mpm_sim_last_error(sim));
      if (mpm_sim_frame(sim) > 0 || in.written_frames > 0)
        fprintf(stderr, "mpm: the frames up to frame_%04d are complete%s%s\n",
                in.written_frames - 1, in.last_checkpoint[0] ? "; the last checkpoint is " : "",
                in.last_checkpoint);
      code = MPM_EXIT_FAILURE;
      break;
    }
    char solver[240] = "";
    if (in.solver_steps > 0) /* implicit: CG and Newton iterations per step over the frame */
      snprintf(solver, sizeof solver, "CG %.1f/step (max %d, residual %.2g) Newton %.2f/step%s",
               (double)in.cg_iterations / (double)in.solver_steps, in.cg_max, in.cg_residual_max,
               (double)in.newton_iterations / (double)in.solver_steps,
               in.cg_unconverged ? " unconverged" : "");
    if (in.surfaces) { /* the frame's surfaces (output.surface) */
      const size_t len = strlen(solver);
      snprintf(solver + len, sizeof solver - len, "%ssurface %.2f s (%zu triangles)",
               len ? ", " : "", in.surface_seconds, in.surface_triangles);
    }
    mpm_progress_update(&pr, mpm_sim_frame(sim), mpm_sim_time(sim), mpm_sim_steps(sim),
                        in.run_particles, solver);
  }
  /* stopped short of the scene's end by --frames: leave a checkpoint to continue from (not on
     ranks yet) */
  if (code == MPM_EXIT_OK && !ranks && mpm_sim_time(sim) < start.end_time * (1 - 1e-12) &&
      !checkpoint_is_current(sim)) {
    if (mpm_sim_write_checkpoint(sim, checkpoint, sizeof checkpoint) != MPM_OK) {
      fprintf(stderr, "mpm: %s\n", mpm_sim_last_error(sim));
      code = MPM_EXIT_FAILURE;
    }
  }
  if (code == MPM_EXIT_OK) {
    mpm_progress_end(&pr);
    const mpm_sim_info in = info_of(sim);
    if (!quiet)
      fprintf(stderr,
              "mpm: done: %d frames, %lld steps, %.1f s wall; open %s/run.pvd in ParaView\n",
              mpm_sim_frame(sim), (long long)mpm_sim_steps(sim), pr.elapsed, in.output_dir);
    if (!quiet && in.refining)
      fprintf(stderr,
              "mpm: refinement: %lld trees from the rules (%lld the same as the one in use), "
              "%.2f s\n",
              in.refinements, in.refinements_unchanged, in.refinement_seconds);
    if (!quiet && in.resampling) {
      const double *dL = in.angular_momentum_change;
      fprintf(stderr,
              "mpm: resampling: %lld splits, %lld merges; angular momentum changed by (%.3g, "
              "%.3g, %.3g) kg m^2/s\n",
              in.splits, in.merges, dL[0], dL[1], dL[2]);
    }
    if (!quiet && in.heat)
      fprintf(stderr,
              "mpm: heat: %zu domain particles melted off their domains (since this run started "
              "or resumed); the last step took %d conduction substeps\n",
              in.melted_domains, in.conduction_substeps);
    if (!quiet && in.surface_frames > 0) /* output.surface's share of the wall time */
      fprintf(stderr, "mpm: surfaces: %.1f s of it, %.2f s per frame (%d frames)\n",
              in.surface_seconds_total, in.surface_seconds_total / in.surface_frames,
              in.surface_frames);
  }
  if (code == MPM_EXIT_OK && render) { /* pictures of every frame: `mpm render DIR` */
    char dir[PATH_CAP];
    snprintf(dir, sizeof dir, "%s", info_of(sim).output_dir);
    mpm_sim_destroy(sim);
    char quiet_flag[] = "--quiet";
    char *rargv[] = {dir, quiet ? quiet_flag : NULL, NULL};
    return mpm_cmd_render(quiet ? 2 : 1, rargv);
  }
  mpm_sim_destroy(sim);
  return code;
}

int mpm_cmd_run(int argc, char **argv) {
  /* under an MPI launcher, one rank of a run on ranks (ranks.h). Rank 0 alone prints: the ranks
     agree on every failure and rank 0 holds the message of the rank where it began, so the
     others' output would only repeat it (their progress included) */
  const int ranks = mpm_cli_ranks_start();
  if (mpm_cli_rank() != 0) { /* (should /dev/null fail them, they print: nothing worse) */
    FILE *out = freopen("/dev/null", "w", stdout), *err = freopen("/dev/null", "w", stderr);
    (void)out;
    (void)err;
  }
  const int code = run_scene(argc, argv, ranks);
  mpm_cli_ranks_end();
  return code;
}
