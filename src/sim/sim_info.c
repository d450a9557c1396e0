/* sim_info.c - the public calls a program needs around a run (mpm/mpm.h): the size and the
 * figures of a simulation (mpm_sim_get_info), a frame limit, a per-step callback, the scene's
 * warnings and the next step's dt. `mpm run` and `mpm check` are written on these alone. */
#include "sim/grid_stack.h"
#include "sim/sim.h"
#include "heat/heat.h"
#include "core/parallel.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

size_t mpm_sim_particle_count(const mpm_sim *sim) {
  return sim->particles.count + sim->domains.active_count;
}

/* The frames the scene's time asks for (as mpm_sim_create_from_scene counts them). */
static int scene_frames(const mpm_scene *sc) {
  const int n = (int)ceil(sc->end_time * sc->fps - 1e-9);
  return n < 1 ? 1 : n;
}

mpm_status mpm_sim_set_frame_limit(mpm_sim *sim, int frames) {
  const int most = scene_frames(&sim->scene);
  if (frames < 1 || frames > most)
    return mpm_error_set(&sim->error, MPM_ERR_INVALID,
                         "mpm_sim_set_frame_limit: expected 1 to %d frames (the scene's "
                         "time.end %g s at %g fps), got %d",
                         most, sim->scene.end_time, sim->scene.fps, frames);
  if (sim->out.enabled && frames > sim->frame_count)
    return mpm_error_set(&sim->error, MPM_ERR_INVALID,
                         "mpm_sim_set_frame_limit: output is enabled for %d frames; the count "
                         "can only be lowered now (got %d)",
                         sim->frame_count, frames);
  sim->frame_count = frames;
  return MPM_OK;
}

void mpm_sim_set_step_callback(mpm_sim *sim, mpm_step_callback callback, void *ctx) {
  sim->on_step = callback;
  sim->on_step_ctx = callback ? ctx : NULL;
}

/* Conduction substeps per step past which check and run warn of the cost. */
#define HEAT_SUBSTEPS_WARN 100

int mpm_sim_warnings(const mpm_sim *sim, char *buf, size_t cap) {
  size_t len = 0;
  int found = 0;
  if (buf && cap) buf[0] = 0;
  found += mpm_scene_advice(&sim->scene, buf, cap);
  if (buf && cap) len = strlen(buf);
  /* heat: conduction substeps each step at its stable rate; a conductivity typed in the wrong
     unit (1e30) made every step take minutes at the cap of 10^6 without a word */
  if (sim->scene.heat.enabled) {
    const double dt = mpm_sim_cfl_dt(sim);
    const int n =
        mpm_heat_substeps(dt, mpm_sim_finest_dx(sim), sim->materials, sim->material_count);
    if (n > HEAT_SUBSTEPS_WARN) {
      if (buf && len < cap)
        snprintf(buf + len, cap - len,
                 "%sheat: conduction needs %d%s substeps per step (dt = %.3g s, dx = %g m): each "
                 "step costs that many conduction passes over the grid; check the units of "
                 "materials[].conductivity (W/(m K)), specific_heat (J/(kg K)) and density, "
                 "or use a coarser dx",
                 len ? "\n" : "", n, n >= 1000000 ? " (the cap)" : "", dt, mpm_sim_finest_dx(sim));
      len = buf && cap ? strlen(buf) : 0;
      ++found;
    }
  }
  /* where the bodies start: only the initial state can say (a resumed run has moved on) */
  if (sim->steps == 0) {
    char text[4096];
    const int placed = mpm_sim_placement_report(sim, text, sizeof text);
    if (placed) {
      const size_t n = strlen(text);
      if (n && text[n - 1] == '\n') text[n - 1] = 0; /* the report ends each line */
      if (buf && len < cap) snprintf(buf + len, cap - len, "%s%s", len ? "\n" : "", text);
      found += placed;
    }
  }
  return found;
}

mpm_status mpm_sim_next_dt(mpm_sim *sim, double *dt) {
  const mpm_status st = mpm_sim_mark_enrichment(sim); /* the marks bound an explicit dt */
  if (st != MPM_OK) return st;
  *dt = mpm_sim_cfl_dt(sim);
  return MPM_OK;
}

mpm_status mpm_sim_get_info(const mpm_sim *sim, mpm_sim_info *info, size_t size) {
  if (!info) return MPM_ERR_INVALID;
  const mpm_scene *sc = &sim->scene;
  mpm_sim_info in;
  memset(&in, 0, sizeof in);
  in.particles = mpm_sim_particle_count(sim);
  in.domain_particles = sim->domains.active_count;
  in.bodies = sc->body_count;
  in.materials = sim->material_count;
  in.colliders = sim->collider_count;
  in.dx = sc->dx;
  in.finest_dx = mpm_sim_finest_dx(sim);
  in.fps = sc->fps;
  in.frame_dt = sim->frame_dt;
  in.end_time = sc->end_time;
  in.frame_count = sim->frame_count;
  in.implicit = sc->solver.integrator == MPM_INTEGRATOR_IMPLICIT;
  in.fixed_dt = in.implicit && sc->solver.dt > 0;
  in.threads = sim->thread_request > 0 ? sim->thread_request : mpm_thread_count();
  in.memory_bytes =
      mpm_scene_memory_for(sc, (double)(sim->particles.count + sim->domains.particles.count));
  in.output_enabled = sim->out.enabled;
  in.output_dir = sim->out.dir;
  in.written_frames = sim->out.written_frames;
  in.last_checkpoint = sim->out.last_checkpoint;
  const mpm_solver_figures *sf = &sim->last_frame_solver;
  in.solver_steps = sf->steps;
  in.cg_iterations = sf->cg_iterations;
  in.newton_iterations = sf->newton_iterations;
  in.cg_unconverged = sf->cg_unconverged;
  in.cg_max = sf->cg_max;
  in.cg_residual_max = sf->residual_max;
  in.surfaces = sc->output.surface.enabled;
  in.surface_seconds = sim->out.surface_seconds;
  in.surface_triangles = sim->out.surface_triangles;
  in.surface_seconds_total = sim->out.surface_seconds_total;
  in.surface_frames = sim->out.surface_frames;
  in.resampling = sc->resample.enabled;
  in.rank = 0; /* a run on ranks: its stack says (src/dist) */
  in.ranks = 1;
  in.run_particles = in.particles;
  sim->stack->info(sim, &in); /* refinement and resampling; a rank's part of a run */
  in.heat = sc->heat.enabled;
  in.melted_domains = sim->melted_domains;
  in.conduction_substeps = sim->heat.figures.substeps;
  /* an older program's smaller struct gets its members only; a newer one's extra are zero */
  memset(info, 0, size);
  memcpy(info, &in, size < sizeof in ? size : sizeof in);
  return MPM_OK;
}
