/* frame.c - the frame loop: steps of the guarded step until the frame's time, the work that
 * runs between steps, and the frame's outputs.
 *
 * Between steps (between_steps below) is where the state may change shape: domains switched
 * off, the multi-level grid's refinement, and particle split and merge (Gao sec. 7). These stages
 * run before the guarded step (guard.c) saves its state for a retry, so a retry never undoes them
 * and never repeats them. */
#include "sim/sim.h"

#include "sim/frame_writer.h"
#include "sim/grid_stack.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

typedef struct between_stage {
  const char *name;
  mpm_status (*run)(mpm_sim *sim);
} between_stage;

/* the grid stack's work between steps (grid_stack.h) */
static mpm_status refinement(mpm_sim *sim) {
  return sim->stack->refine(sim);
}

static mpm_status particle_resampling(mpm_sim *sim) {
  return sim->stack->resample(sim);
}

static const between_stage between_steps[] = {
    {"domain releases", mpm_sim_apply_domain_releases},
    {"refinement", refinement},
    {"particle resampling", particle_resampling},
};

mpm_status mpm_sim_between_steps(mpm_sim *sim) {
  for (size_t k = 0; k < sizeof between_steps / sizeof between_steps[0]; ++k) {
    const mpm_status st = between_steps[k].run(sim);
    if (st != MPM_OK) return st;
  }
  return MPM_OK;
}

/* One step, counted into the frame's step figures; `shortened`: the frame loop cut the step
 * short to land on the frame's time, so it does not count towards the typical step. */
static mpm_status counted_step(mpm_sim *sim, double max_dt, int shortened) {
  mpm_thread_tuner_before(&sim->threads, sim->particles.count + sim->domains.particles.count);
  const double raw0 = sim->times.total;
  mpm_status st = mpm_sim_between_steps(sim);
  if (st == MPM_OK) st = mpm_sim_guarded_step(sim, max_dt);
  mpm_thread_tuner_after(&sim->threads, sim->times.total - raw0);
  if (st != MPM_OK) return st;
  mpm_step_figures *f = &sim->step_figures;
  const double dt = sim->last_dt;
  if (f->steps == 0 || dt < f->min) f->min = dt;
  if (f->steps == 0 || dt > f->max) f->max = dt;
  f->steps++;
  f->sum += dt;
  for (int k = 0; k < 3 * sim->collider_count; ++k) sim->collider_frame[k] += sim->collider_step[k];
  /* scripted colliders are where the step took them (collide/collider.h) */
  for (int k = 0; k < sim->collider_count; ++k) mpm_collider_script_commit(&sim->colliders[k], dt);
  if (!shortened) {
    f->full_steps++;
    f->full_sum += dt;
  }
  return MPM_OK;
}

/* The end of the frame in progress: the next frame's time, or the end time. */
static double frame_end(const mpm_sim *sim) {
  const double end = (sim->frame + 1) * sim->frame_dt;
  return end > sim->scene.end_time ? sim->scene.end_time : end;
}

/* Whether the frame in progress has reached its time (a tiny remainder is merged into the
 * last step, so steps land exactly on the frame's time). */
static int frame_reached(const mpm_sim *sim) {
  const double end = frame_end(sim);
  return !(sim->time < end - 1e-12 * (1 + end));
}

/* A simulation whose state is lost (non-finite, or half-updated when memory ran out) steps no
 * further: the first failure's status and message come back until it is destroyed. */
static mpm_status refuse_if_failed(mpm_sim *sim, const char *what) {
  if (sim->failed == MPM_OK) return MPM_OK;
  return mpm_error_set(&sim->error, sim->failed,
                       "%s: the simulation failed at step %lld and cannot go on (%s); destroy it, "
                       "or create it again and resume from a checkpoint",
                       what, (long long)sim->steps, sim->failed_message);
}

/* Record a failure that lost the state (see refuse_if_failed); others pass through. */
static mpm_status latch(mpm_sim *sim, mpm_status st) {
  if ((st == MPM_ERR_UNSTABLE || st == MPM_ERR_NOMEM) && sim->failed == MPM_OK) {
    sim->failed = st;
    snprintf(sim->failed_message, sizeof sim->failed_message, "%s", sim->error.message);
  }
  return st;
}

/* A frame's outputs: their failures lose no state (a full disk), except a non-finite value
 * found in the state they write. */
static mpm_status latch_unstable(mpm_sim *sim, mpm_status st) {
  return st == MPM_ERR_UNSTABLE ? latch(sim, st) : st;
}

/* One step of the frame in progress, of at most max_dt (0: no bound of the caller's), never
 * past the frame's time. */
static mpm_status frame_step(mpm_sim *sim, double max_dt) {
  /* only between two steps: the state is whole, a checkpoint of it resumes exactly */
  if (sim->interrupt && *sim->interrupt)
    return mpm_error_set(&sim->error, MPM_ERR_INTERRUPTED,
                         "interrupted at step %lld (t = %.6g s, frame %d of %d)",
                         (long long)sim->steps, sim->time, sim->frame, sim->frame_count);
  const double remaining = frame_end(sim) - sim->time;
  /* after an unstable step the retry guard runs on halved steps for a while */
  const mpm_status marked = mpm_sim_mark_enrichment(sim); /* they bound dt */
  if (marked != MPM_OK) return marked;
  double nominal = ldexp(mpm_sim_cfl_dt(sim), -sim->retry.dt_level);
  const int callers = max_dt > 0 && max_dt < nominal; /* the caller's bound is the step */
  if (callers) nominal = max_dt;
  double dt = nominal;
  const mpm_solver_desc *sd = &sim->scene.solver;
  if (sd->integrator == MPM_INTEGRATOR_IMPLICIT && sd->dt > 0 && !callers) {
    /* a fixed step: the frame's remaining time in equal steps no longer than dt (one step when
       dt is longer than the frame); dt read from text may be a hair short */
    const double steps = ceil(remaining / dt - 1e-6);
    dt = remaining / (steps > 1 ? steps : 1);
  } else if (dt >= remaining * (1 - 1e-9)) { /* (a remainder of rounding is not a step) */
    dt = remaining;
  } else if (dt > 0.5 * remaining && !callers) {
    dt = 0.5 * remaining; /* two even steps rather than a full one and a sliver */
  }
  /* the relative margin: the fixed step's even division may round a hair below dt */
  return counted_step(sim, dt, dt < nominal * (1 - 1e-9));
}

/* The frame has reached its time: count it, write its outputs, and a checkpoint when due. */
static mpm_status complete_frame(mpm_sim *sim) {
  sim->time = frame_end(sim);
  sim->frame++;
  if (sim->retry.dt_level > 0) sim->retry.dt_level--; /* one halving is given back per calm frame */
  mpm_status st = sim->out.enabled ? mpm_sim_write_frame(sim) : MPM_OK;
  /* the frame's solver figures went into its stats row; the next frame starts from zero (a
   * checkpoint taken mid-frame carries them) */
  sim->last_frame_solver = sim->solver_figures;
  memset(&sim->solver_figures, 0, sizeof sim->solver_figures);
  memset(&sim->step_figures, 0, sizeof sim->step_figures);
  memset(sim->collider_frame, 0, 3 * (size_t)sim->collider_count * sizeof *sim->collider_frame);
  sim->out.frame_wall_start = mpm_wall_seconds(); /* the next frame's, for steps taken one by one */
  if (!sim->out.enabled) return st;
  /* (a writer that writes no checkpoint, a run on ranks', takes none: frame_writer.h) */
  const int every = sim->writer->no_checkpoints ? 0 : sim->scene.output.checkpoint_every;
  if (st == MPM_OK && every > 0 && sim->frame % every == 0 &&
      sim->time < sim->scene.end_time * (1 - 1e-12))
    st = mpm_sim_write_checkpoint(sim, NULL, 0);
  return st;
}

static mpm_status at_end(mpm_sim *sim) {
  return mpm_error_set(&sim->error, MPM_ERR_INVALID,
                       "the simulation already reached its end time (t = %g s, frame %d of %d)",
                       sim->time, sim->frame, sim->frame_count);
}

static mpm_status step(mpm_sim *sim, double max_dt) {
  mpm_status st = refuse_if_failed(sim, "mpm_sim_step");
  if (st != MPM_OK) return st;
  if (sim->frame >= sim->frame_count) return at_end(sim);
  if (!frame_reached(sim)) {
    st = latch(sim, frame_step(sim, max_dt));
    if (st != MPM_OK) return st;
  }
  /* (a frame's outputs failing loses no state: not latched, unless they found it non-finite) */
  return frame_reached(sim) ? latch_unstable(sim, complete_frame(sim)) : MPM_OK;
}

mpm_status mpm_sim_step(mpm_sim *sim, double max_dt) {
  const int saved = mpm_sim_threads_enter(sim);
  const mpm_status st = step(sim, max_dt);
  mpm_sim_threads_leave(sim, saved);
  return st;
}

static mpm_status advance_frame(mpm_sim *sim) {
  mpm_status st = refuse_if_failed(sim, "mpm_sim_advance_frame");
  if (st != MPM_OK) return st;
  if (sim->frame >= sim->frame_count) return at_end(sim);
  sim->out.frame_wall_start = mpm_wall_seconds();
  while (!frame_reached(sim)) {
    st = latch(sim, frame_step(sim, 0));
    if (st != MPM_OK) return st;
    if (sim->on_step) sim->on_step(sim->on_step_ctx, sim);
  }
  return latch_unstable(sim, complete_frame(sim));
}

mpm_status mpm_sim_advance_frame(mpm_sim *sim) {
  const int saved = mpm_sim_threads_enter(sim);
  const mpm_status st = advance_frame(sim);
  mpm_sim_threads_leave(sim, saved);
  return st;
}
