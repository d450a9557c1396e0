/* step.c - one explicit symplectic-Euler MPM step (Gao sec. 3.2 steps 1-6; Zhu Algorithm 1
 * without enrichment for particle domains) as an ordered list of stages.
 *
 * Stages (explicit_stages below), each a function of the simulation and the step's context,
 * timed into sim->times; sort, layout, p2g and g2p are the grid stack's (grid_stack.h: one
 * uniform level with the particle domains, or Gao's multi-level grid), so the step never asks
 * which grids it runs on:
 *   sort     activate the grid from the particles' stencils (sparse: sort them into owner
 *            blocks; every 16 steps, or when the order has come apart, the particle arrays are
 *            permuted into that order) and around the domain corners
 *   layout   lay the DOF set out over the grids' nodes and clear what P2G accumulates
 *   p2g      particles -> grid (mass, momentum, force from the Kirchhoff stress; the sparse
 *            grid's APIC kernel folds dt f into the momentum); domain particles -> corners ->
 *            grid (Zhu eqs. 5, 6, 8)
 *   update   the explicit update of the DOF set: gravity, force, colliders, domain walls
 *            (solver/explicit_update.h)
 *   g2p      grid -> particles, fused with what follows it in an explicit step: velocity (APIC
 *            or PIC/FLIP), affine moment, F <- (I + dt grad v) F, the plasticity return map, and
 *            advection; for domains grid -> corners -> particles (Zhu eqs. 7, 9)
 * Work between steps (domain releases, the grid stack's refinement and resampling) runs in
 * frame.c before the guarded step, never inside it.
 *
 * Time step: dt = cfl dx / (c + max |v_p|) with c the largest elastic wave speed, bounded by
 * the scene's max_dt and clipped so that frames end exactly on their times. */
#include "sim/sim.h"
#include "core/alloc.h"
#include "domain/enrich.h"
#include "domain/enrich_contact.h"
#include "domain/enrich_surface_contact.h"
#include "sim/grid_stack.h"
#include "solver/explicit_update.h"
#include "solver/implicit.h"
#include "core/parallel.h"

#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>

double mpm_sim_finest_dx(const mpm_sim *sim) {
  return sim->stack->finest_dx(sim);
}

double mpm_sim_cfl_dt(const mpm_sim *sim) {
  const mpm_solver_desc *sd = &sim->scene.solver;
  if (sd->integrator == MPM_INTEGRATOR_IMPLICIT && sd->dt > 0)
    return sd->max_dt > 0 && sd->max_dt < sd->dt ? sd->max_dt : sd->dt; /* max_dt bounds it too */
  /* implicit: sim->wave_speed is 0, so the step follows particle speed alone */
  const double speed = (double)sim->wave_speed + (double)sim->max_speed;
  /* the multi-level grid: the finest level's spacing bounds the step */
  const double dx = mpm_sim_finest_dx(sim);
  double dt = speed > 0 ? sim->scene.solver.cfl * dx / speed : sim->frame_dt;
  /* enriched corners are the material's own nodes (domain/enrich.h) */
  const double rate = sim->domains.active_count ? sim->domains.enrich.rate : 0;
  if (sd->integrator == MPM_INTEGRATOR_EXPLICIT && rate > 0 && sd->cfl / rate < dt)
    dt = sd->cfl / rate;
  if (sim->scene.solver.max_dt > 0 && dt > sim->scene.solver.max_dt) dt = sim->scene.solver.max_dt;
  return dt;
}

typedef mpm_status (*stage_fn)(mpm_sim *sim, mpm_step_ctx *c);

typedef struct stage {
  const char *name;
  stage_fn run;
  size_t timer; /* offset of its seconds in mpm_stage_times */
} stage;

int mpm_sim_wants_reorder(const mpm_sim *sim, size_t breaks, size_t n) {
  return mpm_reorder_due(sim->steps, sim->reorder_interval, breaks, n);
}

mpm_status mpm_sim_ensure_scratch(mpm_sim *sim) {
  return mpm_particles_scratch(&sim->particles, &sim->iscratch, &sim->scratch_capacity);
}

static mpm_status stage_sort(mpm_sim *sim, mpm_step_ctx *c) {
  return sim->stack->sort(sim, c);
}

static mpm_status stage_layout(mpm_sim *sim, mpm_step_ctx *c) {
  mpm_dofs_begin_layout(&sim->dofs);
  const int impulse = c->p2g_output == MPM_P2G_IMPULSE;
  const unsigned fields = impulse ? MPM_DOF_MASS | MPM_DOF_V0 | MPM_DOF_V : MPM_DOF_ALL;
  return sim->stack->layout(sim, c, fields);
}

static mpm_status stage_p2g(mpm_sim *sim, mpm_step_ctx *c) {
  return sim->stack->p2g(sim, c);
}

/* Whether the step measures what the colliders take (only for stats.csv: a step without
 * colliders, or whose figures nobody writes, does no more work than before). */
static int measures_colliders(const mpm_sim *sim, const mpm_step_ctx *c) {
  return c->update.boundary.collider_count > 0 && sim->out.enabled && sim->scene.output.stats;
}

/* Pose c's taken momentum to its collider's sum of the step (the poses are the active
 * colliders only). */
static void collect_taken(mpm_sim *sim, const mpm_step_ctx *c, const double *taken) {
  const mpm_boundary *b = &c->update.boundary;
  for (int k = 0; k < b->collider_count; ++k) {
    const size_t at = (size_t)(b->poses[k].collider - sim->colliders);
    for (int e = 0; e < 3; ++e) sim->collider_step[3 * at + e] += taken[3 * k + e];
  }
}

static mpm_status stage_update(mpm_sim *sim, mpm_step_ctx *c) {
  if (!measures_colliders(sim, c)) {
    mpm_dofs_explicit_update(&c->update, c->p2g_output, &sim->dofs);
    return MPM_OK;
  }
  double *taken =
      mpm_arena_alloc(&sim->step_arena, 3 * (size_t)sim->collider_count * sizeof *taken);
  if (taken) memset(taken, 0, 3 * (size_t)sim->collider_count * sizeof *taken);
  c->update.taken = taken;
  c->update.arena = &sim->step_arena;
  if (!taken || mpm_dofs_explicit_update(&c->update, c->p2g_output, &sim->dofs))
    return mpm_error_set(&sim->error, MPM_ERR_NOMEM,
                         "step %lld: out of memory for the colliders' reaction sums",
                         (long long)sim->steps);
  collect_taken(sim, c, taken);
  return MPM_OK;
}

/* The step's implicit system over the DOF set laid out by P2G. */
static void implicit_system(mpm_sim *sim, mpm_step_ctx *c, mpm_implicit *s) {
  memset(s, 0, sizeof *s);
  s->dt = c->update.dt;
  s->theta = sim->scene.solver.scheme == MPM_SCHEME_NEWMARK ? R_(0.5) : 1;
  for (int d = 0; d < 3; ++d) s->gravity[d] = c->update.gravity[d];
  s->region_count = c->update.region_count;
  s->regions = c->update.regions;
  s->dofs = &sim->dofs;
  s->tc = &c->tc;
  s->p = &sim->particles;
  sim->stack->implicit_parts(sim, s);
  s->domains = c->domains ? &sim->domains : NULL;
  s->boundary = &c->update.boundary;
  s->arena = &sim->step_arena;
}

/* The implicit update (solver/implicit.h) in place of the explicit one. */
static mpm_status stage_solve(mpm_sim *sim, mpm_step_ctx *c) {
  const mpm_solver_desc *sd = &sim->scene.solver;
  mpm_implicit s;
  implicit_system(sim, c, &s);
  const mpm_implicit_options o = {sd->newton_iterations, mpm_solver_cg_tolerance(sd),
                                  sd->cg_max_iterations,
                                  sd->preconditioner == MPM_PRECONDITIONER_MULTIGRID ? 2 : 1};
  if (mpm_implicit_init(&s) || mpm_implicit_solve(&s, &o, &c->solve))
    return mpm_error_set(&sim->error, MPM_ERR_NOMEM,
                         "step %lld: out of memory for the implicit solve over %zu DOFs",
                         (long long)sim->steps, sim->dofs.count);
  if (measures_colliders(sim, c)) {
    const size_t n = 3 * (size_t)sim->collider_count;
    double *taken = mpm_arena_alloc(&sim->step_arena, n * sizeof *taken);
    if (taken) memset(taken, 0, n * sizeof *taken);
    if (!taken || mpm_implicit_collider_taken(&s, taken))
      return mpm_error_set(&sim->error, MPM_ERR_NOMEM,
                           "step %lld: out of memory for the colliders' reaction sums",
                           (long long)sim->steps);
    collect_taken(sim, c, taken);
  }
  mpm_solver_figures *f = &sim->solver_figures;
  sim->implicit_steps++;
  sim->cg_iterations += c->solve.cg_iterations;
  f->steps++;
  f->cg_iterations += c->solve.cg_iterations;
  f->newton_iterations += c->solve.newton_iterations;
  f->mg_setup_seconds += c->solve.mg_setup_seconds;
  f->mg_cycle_seconds += c->solve.mg_cycle_seconds;
  if (c->solve.mg_bytes > f->mg_bytes) f->mg_bytes = c->solve.mg_bytes;
  if (c->solve.cg_iterations > f->cg_max) f->cg_max = c->solve.cg_iterations;
  if (c->solve.cg_residual > f->residual_max) f->residual_max = c->solve.cg_residual;
  f->last_cg = c->solve.cg_iterations;
  f->last_newton = c->solve.newton_iterations;
  f->last_residual = c->solve.cg_residual;
  if (!c->solve.cg_converged) {
    f->cg_unconverged++;
    if (sd->on_cg_failure == MPM_CG_FAILURE_STOP)
      return mpm_error_set(&sim->error, MPM_ERR_UNSTABLE,
                           "step %lld (t = %.6g s, dt = %.3g s): conjugate gradients did not "
                           "converge: relative residual %.3g after %d iterations over %zu DOFs, "
                           "expected at most solver.cg_tolerance = %g; raise "
                           "solver.cg_max_iterations, lower solver.dt, or set "
                           "solver.on_cg_failure to \"warn\"",
                           (long long)sim->steps, sim->time, c->dt, c->solve.cg_residual,
                           c->solve.cg_iterations, sim->dofs.count, o.cg_tolerance);
  }
  return MPM_OK;
}

/* Enriched corners meet other material on the grid (enrich_contact.h), then enriched surfaces
 * meet enriched surfaces (enrich_surface_contact.h), after the velocity update and before G2P
 * reads it. */
static mpm_status stage_contact(mpm_sim *sim, mpm_step_ctx *c) {
  if (!c->domains) return MPM_OK;
  if (mpm_enrich_contact_on(&sim->domains)) {
    size_t contacts = 0;
    if (mpm_enrich_contact(&sim->domains, &sim->grid, &c->dtc.kernel, &c->all, sim->dofs.count,
                           &sim->step_arena, &contacts))
      return mpm_error_set(&sim->error, MPM_ERR_NOMEM,
                           "step %lld: out of memory for the contacts of %zu enriched corners",
                           (long long)sim->steps, sim->domains.enrich.count);
    sim->enriched_contacts += contacts;
  }
  if (mpm_surface_contact_on(&sim->domains)) {
    mpm_surface_contact_stats st;
    if (mpm_surface_contact(&sim->domains, &c->all, c->dt, &sim->step_arena, &st))
      return mpm_error_set(&sim->error, MPM_ERR_NOMEM,
                           "step %lld: out of memory for the surface contacts of %zu enriched "
                           "corners",
                           (long long)sim->steps, sim->domains.enrich.count);
    sim->surface_contacts += st.contacts;
  }
  return MPM_OK;
}

static mpm_status stage_g2p(mpm_sim *sim, mpm_step_ctx *c) {
  return sim->stack->g2p(sim, c);
}

/* Heat (heat/heat.h), after the velocity update and before G2P moves the particles: their
 * stencils are still those the grid was activated for. */
static mpm_status stage_heat(mpm_sim *sim, mpm_step_ctx *c) {
  if (!sim->scene.heat.enabled) return MPM_OK;
  mpm_heat_step_desc h;
  memset(&h, 0, sizeof h);
  h.dt = c->dt;
  h.pic = (mpm_real)sim->scene.heat.pic;
  h.grid = &sim->grid;
  h.dofs = &sim->dofs;
  h.kernel = sim->kernel;
  for (int d = 0; d < 3; ++d) {
    h.clamp_lo[d] = c->tc.clamp_lo[d];
    h.clamp_hi[d] = c->tc.clamp_hi[d];
  }
  h.materials = sim->materials;
  h.sets[h.set_count++] = (mpm_heat_set){&sim->particles, NULL};
  if (c->domains)
    h.sets[h.set_count++] = (mpm_heat_set){&sim->domains.particles, sim->domains.active};
  h.pose_count = c->update.boundary.collider_count;
  h.poses = c->update.boundary.poses;
  const mpm_status st = mpm_heat_step(&sim->heat, &h);
  if (st == MPM_ERR_NOMEM)
    return mpm_error_set(&sim->error, MPM_ERR_NOMEM, "step %lld: out of memory for heat transfer",
                         (long long)sim->steps);
  if (st != MPM_OK)
    return mpm_error_set(&sim->error, MPM_ERR_INVALID,
                         "step %lld: a particle's heat stencil reaches a grid node that is not "
                         "active",
                         (long long)sim->steps);
  return MPM_OK;
}

static const stage explicit_stages[] = {
    {"sort", stage_sort, offsetof(mpm_stage_times, sort)},
    {"layout", stage_layout, offsetof(mpm_stage_times, sort)},
    {"p2g", stage_p2g, offsetof(mpm_stage_times, p2g)},
    {"update", stage_update, offsetof(mpm_stage_times, grid)},
    {"contact", stage_contact, offsetof(mpm_stage_times, grid)},
    {"heat", stage_heat, offsetof(mpm_stage_times, heat)},
    {"g2p", stage_g2p, offsetof(mpm_stage_times, g2p)},
};

/* The implicit step: the same stages with the solve in place of the explicit update. */
static const stage implicit_stages[] = {
    {"sort", stage_sort, offsetof(mpm_stage_times, sort)},
    {"layout", stage_layout, offsetof(mpm_stage_times, sort)},
    {"p2g", stage_p2g, offsetof(mpm_stage_times, p2g)},
    {"solve", stage_solve, offsetof(mpm_stage_times, grid)},
    {"contact", stage_contact, offsetof(mpm_stage_times, grid)},
    {"heat", stage_heat, offsetof(mpm_stage_times, heat)},
    {"g2p", stage_g2p, offsetof(mpm_stage_times, g2p)},
};

/* The step's context for a step of dt. */
static void step_setup(mpm_sim *sim, double dt, mpm_step_ctx *c) {
  const mpm_scene *sc = &sim->scene;
  memset(c, 0, sizeof *c);
  c->dt = dt;
  mpm_transfer_ctx *t = &c->tc;
  t->kernel = sim->kernel;
  t->dt = (mpm_real)dt;
  t->transfer = sc->solver.transfer;
  t->flip_alpha = (mpm_real)sc->solver.flip_alpha;
  t->materials = sim->materials;
  t->material_count = sim->material_count;
  for (int d = 0; d < 3; ++d) {
    t->origin[d] = sim->grid.origin[d];
    /* keep every stencil inside the grid: one cell from the domain faces */
    t->clamp_lo[d] = (mpm_real)(sc->box_min[d] + sc->dx);
    t->clamp_hi[d] = (mpm_real)(sc->box_max[d] - sc->dx);
  }
  c->dtc = c->tc;
  c->dtc.kernel = sim->domain_kernel;
  c->domains = sim->domains.active_count > 0;
  /* the sparse grid's APIC P2G folds the force into the momentum; domain corners bring their
   * force apart (their FLIP update needs the grid's velocity before the force) */
  const int implicit = sc->solver.integrator == MPM_INTEGRATOR_IMPLICIT;
  c->p2g_output = mpm_p2g_fuses_force(t, &sim->grid) && !c->domains && !implicit
                      ? MPM_P2G_IMPULSE
                      : MPM_P2G_MOMENTUM_FORCE;
  mpm_explicit_update *u = &c->update;
  u->dt = (mpm_real)dt;
  const mpm_real dx = sim->grid.dx;
  for (int d = 0; d < 3; ++d) {
    u->gravity[d] = (mpm_real)sc->gravity[d];
    u->boundary.wall_lo[d] = sim->grid.origin[d] + (mpm_real)sc->wall_cells * dx;
    u->boundary.wall_hi[d] = sim->grid.origin[d] + (mpm_real)(sim->cells[d] - sc->wall_cells) * dx;
  }
  u->boundary.wall_rule = sc->wall_rule;
  u->boundary.wall_friction = (mpm_real)sc->wall_friction;
  /* the colliders acting at the end of the step (a grip's `active` window), their poses then */
  const double t_end = sim->time + dt;
  int active = 0;
  for (int k = 0; k < sim->collider_count; ++k) {
    const mpm_collider_desc *cd = &sim->colliders[k].desc;
    if (t_end >= cd->active[0] && t_end < cd->active[1])
      sim->poses[active++] = mpm_collider_pose_over(&sim->colliders[k], sim->time, t_end);
  }
  u->boundary.collider_count = active;
  u->boundary.poses = sim->poses;
  /* the body-force regions acting then, with their scheduled accelerations */
  int regions = 0;
  for (int k = 0; k < sim->force_count; ++k) {
    const mpm_force_desc *fd = &sc->forces[k];
    const mpm_collider_desc *cd = &sim->force_colliders[k].desc;
    const double f = mpm_schedule_at((const double(*)[2])fd->schedule, fd->schedule_count, t_end);
    if (!(t_end >= cd->active[0] && t_end < cd->active[1]) || f == 0) continue;
    mpm_force_region *r = &sim->force_regions[regions++];
    r->pose = mpm_collider_pose_at(&sim->force_colliders[k], t_end);
    for (int d = 0; d < 3; ++d) r->acceleration[d] = (mpm_real)(f * fd->acceleration[d]);
    r->drag = (mpm_real)(f * fd->drag);
  }
  u->region_count = regions;
  u->regions = sim->force_regions;
}

static const char *bad_quantity(const mpm_particles *p, long i) {
  for (int d = 0; d < 3; ++d)
    if (!isfinite(p->x[d][i])) return "position";
  for (int d = 0; d < 3; ++d)
    if (!isfinite(p->v[d][i])) return "velocity";
  return "deformation gradient";
}

/* The status that stops the step, this process's (st) or another's, or MPM_OK. With several
 * processes (a reduction set) they vote after each stage, so that one that failed (out of
 * memory, say) does not leave the others waiting in the next stage's exchange: every process
 * stops with the largest status of the vote, and the others' messages say where. One process:
 * st, no vote. */
static mpm_status stage_verdict(mpm_sim *sim, mpm_status st, const char *where) {
  if (!sim->reduction) return st;
  double worst = (double)st;
  mpm_reduce_all(sim->reduction, MPM_REDUCE_MAX, &worst, 1);
  if (worst > 0 && st == MPM_OK) {
    mpm_error_set_elsewhere(&sim->error, (mpm_status)worst,
                            "step %lld: another process of the run failed (%s); its message says "
                            "why",
                            (long long)sim->steps, where);
  }
  return st != MPM_OK ? st : (mpm_status)worst;
}

/* The collapse of dt: name the fastest particle (non-finite speeds count as fastest). */
static mpm_status dt_collapsed(mpm_sim *sim, double dt) {
  const mpm_particles *p = &sim->particles;
  size_t worst = 0;
  double worst_v2 = -1;
  for (size_t i = 0; i < p->count; ++i) {
    double v2 = 0;
    for (int d = 0; d < 3; ++d) v2 += (double)p->v[d][i] * (double)p->v[d][i];
    if (!isfinite(v2)) v2 = INFINITY;
    if (v2 > worst_v2) {
      worst_v2 = v2;
      worst = i;
    }
  }
  return mpm_error_set(&sim->error, MPM_ERR_UNSTABLE,
                       "simulation blew up at step %lld (t = %.6g s): the time step collapsed to "
                       "%.3g s because particle id %u (body %d, material %d) moves at %.3g m/s; "
                       "check initial velocities and material stiffness",
                       (long long)sim->steps, sim->time, dt, p->count ? p->id[worst] : 0,
                       p->count ? p->body[worst] : -1, p->count ? p->material[worst] : -1,
                       sqrt(worst_v2));
}

mpm_status mpm_sim_mark_enrichment(mpm_sim *sim) {
  mpm_domain_enrichment *e = &sim->domains.enrich;
  if (!sim->domains.active_count || (e->valid && e->marked_step == sim->steps)) return MPM_OK;
  /* the exit's wait counts steps of the last step's length (this one's is not set yet: its
     bound reads the marks) */
  e->step_dt = sim->last_dt > 0 ? sim->last_dt : fmax(sim->scene.solver.dt, 0);
  if (mpm_domain_mark_enrichment(&sim->domains, sim->materials))
    return mpm_error_set(&sim->error, MPM_ERR_NOMEM,
                         "step %lld: out of memory marking the enrichment of %zu domain particles",
                         (long long)sim->steps, sim->domains.particles.count);
  e->valid = 1;
  e->marked_step = sim->steps;
  return MPM_OK;
}

mpm_status mpm_sim_raw_step(mpm_sim *sim, double max_dt) {
  mpm_sim_apply_strength(sim, sim->time); /* the moduli of this step (strength schedules) */
  const mpm_status marked = mpm_sim_mark_enrichment(sim);
  if (marked != MPM_OK) return marked;
  double dt = mpm_sim_cfl_dt(sim);
  const mpm_solver_desc *sd = &sim->scene.solver;
  const int fixed = sd->integrator == MPM_INTEGRATOR_IMPLICIT && sd->dt > 0;
  /* a fixed step: the frame loop's even division of the frame (within a hair of dt) */
  if (max_dt > 0 && (dt > max_dt || (fixed && max_dt <= dt * (1 + 1e-6)))) dt = max_dt;
  if (!(dt > 1e-12 * sim->frame_dt) || !isfinite(dt)) return dt_collapsed(sim, dt);
  const double t0 = mpm_wall_seconds();
  /* the last step's scratch is taken back (the arena grows to the largest step it saw) */
  mpm_status reset = mpm_arena_reset(&sim->step_arena);
  if (reset != MPM_OK)
    mpm_error_set(&sim->error, reset, "step %lld: out of memory for step scratch",
                  (long long)sim->steps);
  reset = stage_verdict(sim, reset, "making the step's scratch");
  if (reset != MPM_OK) return reset;
  mpm_step_ctx c;
  step_setup(sim, dt, &c);
  /* a retried step starts over: only the accepted attempt's reactions count (frame.c) */
  memset(sim->collider_step, 0, 3 * (size_t)sim->collider_count * sizeof *sim->collider_step);
  double t = t0;
  const int implicit = sim->scene.solver.integrator == MPM_INTEGRATOR_IMPLICIT;
  const stage *stages = implicit ? implicit_stages : explicit_stages;
  const size_t stage_count = implicit ? sizeof implicit_stages / sizeof implicit_stages[0]
                                      : sizeof explicit_stages / sizeof explicit_stages[0];
  for (size_t k = 0; k < stage_count; ++k) {
    const stage *s = &stages[k];
    const mpm_status st = stage_verdict(sim, s->run(sim, &c), s->name);
    if (st != MPM_OK) return st;
    const double now = mpm_wall_seconds();
    *(double *)((char *)&sim->times + s->timer) += now - t;
    t = now;
  }
  sim->times.total += mpm_wall_seconds() - t0;
  sim->time += dt;
  sim->steps++;
  sim->last_dt = dt;
  /* the step's largest speed and whether a value blew up, over every process of the run */
  double speed_bad[2] = {(double)c.r.max_speed, c.r.bad_particle >= 0};
  mpm_reduce_all(sim->reduction, MPM_REDUCE_MAX, speed_bad, 2);
  sim->max_speed = (mpm_real)speed_bad[0];
  if (c.r.bad_particle < 0 && speed_bad[1] > 0)
    return mpm_error_set_elsewhere(&sim->error, MPM_ERR_UNSTABLE,
                                   "simulation blew up at step %lld (t = %.6g s, dt = %.3g s) on "
                                   "another process of the run (its message names the particle)",
                                   (long long)sim->steps, sim->time, dt);
  if (c.r.bad_particle >= 0) {
    const long i = c.r.bad_particle;
    const mpm_particles *q = c.bad_set;
    return mpm_error_set(
        &sim->error, MPM_ERR_UNSTABLE,
        "simulation blew up at step %lld (t = %.6g s, dt = %.3g s): %sparticle id %u "
        "(body %d, material %d) has a non-finite %s; try a smaller solver.cfl or "
        "solver.max_dt, or a finer domain.dx",
        (long long)sim->steps, sim->time, dt, q == &sim->particles ? "" : "domain ", q->id[i],
        q->body[i], q->material[i], bad_quantity(q, i));
  }
  return MPM_OK;
}

mpm_status mpm_sim_implicit_system(mpm_sim *sim, double dt, mpm_implicit *s) {
  if (mpm_arena_reset(&sim->step_arena))
    return mpm_error_set(&sim->error, MPM_ERR_NOMEM, "out of memory for step scratch");
  mpm_step_ctx *c = mpm_arena_alloc(&sim->step_arena, sizeof *c);
  if (!c) return mpm_error_set(&sim->error, MPM_ERR_NOMEM, "out of memory for step scratch");
  const mpm_status marked = mpm_sim_mark_enrichment(sim);
  if (marked != MPM_OK) return marked;
  step_setup(sim, dt, c);
  c->p2g_output = MPM_P2G_MOMENTUM_FORCE;
  const mpm_integrator_kind was = sim->scene.solver.integrator;
  sim->scene.solver.integrator = MPM_INTEGRATOR_IMPLICIT; /* P2G keeps v^n and f^n apart */
  mpm_status st = MPM_OK;
  for (size_t k = 0; k < 3 && st == MPM_OK; ++k) st = implicit_stages[k].run(sim, c);
  sim->scene.solver.integrator = was;
  if (st != MPM_OK) return st;
  implicit_system(sim, c, s);
  if (mpm_implicit_init(s))
    return mpm_error_set(&sim->error, MPM_ERR_NOMEM, "out of memory for the implicit system");
  return MPM_OK;
}
