/* step.c - one explicit symplectic-Euler MPM step (Gao sec. 3.2 steps 1-6) and the frame loop.
 *
 * Stages, each timed: sort particles into grid blocks -> P2G (mass, momentum, force from the
 * Kirchhoff stress) -> grid update (gravity, colliders, walls) -> G2P (velocity, C, F, x).
 * Time step: dt = cfl dx / (c + max |v_p|) with c the largest elastic wave speed, bounded by
 * the scene's max_dt and clipped so that frames end exactly on their times. */
#include "solver/sim.h"
#include "solver/grid_update.h"
#include "core/alloc.h"
#include "domain/domain_transfer.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

double mpm_sim_cfl_dt(const mpm_sim *sim) {
  const double speed = (double)sim->wave_speed + (double)sim->max_speed;
  double dt = speed > 0 ? sim->scene.solver.cfl * sim->scene.dx / speed : sim->frame_dt;
  if (sim->scene.solver.max_dt > 0 && dt > sim->scene.solver.max_dt) dt = sim->scene.solver.max_dt;
  return dt;
}

static int ensure_scratch(mpm_sim *sim) {
  const size_t cap = sim->particles.capacity;
  if (sim->scratch_capacity >= cap) return 0;
  mpm_free(sim->scratch);
  mpm_free(sim->iscratch);
  sim->scratch = mpm_alloc(cap * sizeof(mpm_real));
  sim->iscratch = mpm_alloc(cap * sizeof(uint32_t));
  if (!sim->scratch || !sim->iscratch) return -1;
  sim->scratch_capacity = cap;
  return 0;
}

static void fill_transfer_ctx(const mpm_sim *sim, mpm_real dt, mpm_transfer_ctx *t) {
  memset(t, 0, sizeof *t);
  t->kernel = sim->kernel;
  t->dt = dt;
  t->transfer = sim->scene.solver.transfer;
  t->flip_alpha = (mpm_real)sim->scene.solver.flip_alpha;
  t->materials = sim->materials;
  t->material_count = sim->material_count;
  for (int d = 0; d < 3; ++d) {
    t->origin[d] = sim->origin[d];
    /* keep every stencil inside the grid: one cell from the domain faces */
    t->clamp_lo[d] = (mpm_real)(sim->scene.domain_min[d] + sim->scene.dx);
    t->clamp_hi[d] = (mpm_real)(sim->scene.domain_max[d] - sim->scene.dx);
  }
}

static const char *bad_quantity(const mpm_particles *p, long i) {
  for (int d = 0; d < 3; ++d)
    if (!isfinite(p->x[d][i])) return "position";
  for (int d = 0; d < 3; ++d)
    if (!isfinite(p->v[d][i])) return "velocity";
  return "deformation gradient";
}

mpm_status mpm_sim_raw_step(mpm_sim *sim, double max_dt) {
  mpm_particles *p = &sim->particles;
  const mpm_scene *sc = &sim->scene;
  double dt = mpm_sim_cfl_dt(sim);
  if (max_dt > 0 && dt > max_dt) dt = max_dt;
  if (!(dt > 1e-12 * sim->frame_dt) || !isfinite(dt)) {
    /* name the fastest particle (non-finite speeds count as fastest) */
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
  const double t0 = mpm_wall_seconds();

  mpm_transfer_ctx tc;
  fill_transfer_ctx(sim, (mpm_real)dt, &tc);
  mpm_grid_update_ctx gu;
  memset(&gu, 0, sizeof gu);
  gu.dt = (mpm_real)dt;
  gu.dx = (mpm_real)sc->dx;
  for (int d = 0; d < 3; ++d) {
    gu.gravity[d] = (mpm_real)sc->gravity[d];
    gu.origin[d] = sim->origin[d];
    gu.wall_lo[d] = sc->wall_cells;
    gu.wall_hi[d] = sim->cells[d] - sc->wall_cells;
  }
  gu.wall_rule = sc->wall_rule;
  gu.wall_friction = (mpm_real)sc->wall_friction;
  gu.collider_count = sim->collider_count;
  for (int c = 0; c < sim->collider_count; ++c)
    sim->poses[c] = mpm_collider_pose_at(&sim->colliders[c], sim->time + dt);
  gu.poses = sim->poses;

  mpm_g2p_result r;
  const mpm_particles *bad_set = p; /* the set r.bad_particle indexes */
  if (sc->solver.grid == MPM_GRID_SPARSE) {
    mpm_sparse_grid *g = &sim->sparse;
    if (mpm_sparse_grid_sort(g, &sim->kernel, sim->origin, sim->material_count, p))
      return mpm_error_set(&sim->error, MPM_ERR_NOMEM,
                           "step %lld: out of memory sorting %zu particles into grid blocks",
                           (long long)sim->steps, p->count);
    if (sim->steps % sim->reorder_interval == 0) {
      /* move particles into block order now and then, so transfers stream through memory */
      if (ensure_scratch(sim))
        return mpm_error_set(&sim->error, MPM_ERR_NOMEM, "out of memory reordering particles");
      mpm_particles_permute(p, g->perm, &sim->scratch, sim->iscratch);
      for (size_t j = 0; j < p->count; ++j) g->perm[j] = (uint32_t)j;
    }
    /* APIC P2G fuses the force into the momentum and leaves the force channels alone. Domain
     * corners bring their force in the force channels (their FLIP update needs the grid's
     * velocity before the force), so with domains every channel is cleared and read. */
    const int domains = sim->domains.active_count > 0;
    const int fused = sc->solver.transfer == MPM_TRANSFER_APIC && !domains;
    gu.force_in_momentum = fused;
    if (domains && mpm_domain_activate(&sim->domains, g, &sim->domain_kernel, sim->origin))
      return mpm_error_set(&sim->error, MPM_ERR_NOMEM,
                           "step %lld: out of memory activating the grid around domain corners",
                           (long long)sim->steps);
    mpm_sparse_grid_clear(g, fused ? MPM_CH_F : MPM_GRID_CHANNELS);
    mpm_transfer_ctx dtc = tc;
    dtc.kernel = sim->domain_kernel;
    const double t1 = mpm_wall_seconds();
    mpm_p2g_sparse(&tc, g, p);
    if (domains && mpm_domain_p2g(&dtc, &sim->domains, g))
      return mpm_error_set(&sim->error, MPM_ERR_NOMEM,
                           "step %lld: out of memory for the stresses of %zu domain particles",
                           (long long)sim->steps, sim->domains.particles.count);
    const double t2 = mpm_wall_seconds();
    mpm_grid_update_sparse(&gu, g);
    const double t3 = mpm_wall_seconds();
    r = mpm_g2p_sparse(&tc, g, p);
    if (domains) {
      const mpm_g2p_result rd =
          mpm_domain_g2p(&dtc, &sim->domains, g, sim->poses, sim->collider_count);
      if (rd.max_speed > r.max_speed) r.max_speed = rd.max_speed;
      if (rd.bad_particle >= 0 && r.bad_particle < 0) {
        bad_set = &sim->domains.particles;
        r.bad_particle = rd.bad_particle;
      }
    }
    const double t4 = mpm_wall_seconds();
    sim->times.sort += t1 - t0;
    sim->times.p2g += t2 - t1;
    sim->times.grid += t3 - t2;
    sim->times.g2p += t4 - t3;
  } else {
    mpm_dense_grid_clear(&sim->dense);
    const double t1 = mpm_wall_seconds();
    mpm_p2g_dense(&tc, &sim->dense, p);
    const double t2 = mpm_wall_seconds();
    mpm_grid_update_dense(&gu, &sim->dense);
    const double t3 = mpm_wall_seconds();
    r = mpm_g2p_dense(&tc, &sim->dense, p);
    const double t4 = mpm_wall_seconds();
    sim->times.sort += t1 - t0;
    sim->times.p2g += t2 - t1;
    sim->times.grid += t3 - t2;
    sim->times.g2p += t4 - t3;
  }
  sim->times.total += mpm_wall_seconds() - t0;
  sim->time += dt;
  sim->steps++;
  sim->last_dt = dt;
  sim->max_speed = r.max_speed;
  if (r.bad_particle >= 0) {
    const long i = r.bad_particle;
    const mpm_particles *q = bad_set;
    return mpm_error_set(
        &sim->error, MPM_ERR_UNSTABLE,
        "simulation blew up at step %lld (t = %.6g s, dt = %.3g s): %sparticle id %u "
        "(body %d, material %d) has a non-finite %s; try a smaller solver.cfl or "
        "solver.max_dt, or a finer domain.dx",
        (long long)sim->steps, sim->time, dt, q == p ? "" : "domain ", q->id[i], q->body[i],
        q->material[i], bad_quantity(q, i));
  }
  return MPM_OK;
}

mpm_status mpm_sim_advance_frame(mpm_sim *sim) {
  if (sim->frame >= sim->frame_count)
    return mpm_error_set(&sim->error, MPM_ERR_INVALID,
                         "the simulation already reached its end time");
  sim->frame_wall_start = mpm_wall_seconds();
  double end = (sim->frame + 1) * sim->frame_dt;
  if (end > sim->scene.end_time) end = sim->scene.end_time;
  /* steps land exactly on the frame time; a tiny remainder is merged into the last step */
  while (sim->time < end - 1e-12 * (1 + end)) {
    /* only between two steps: the state is whole, a checkpoint of it resumes exactly */
    if (sim->interrupt && *sim->interrupt)
      return mpm_error_set(&sim->error, MPM_ERR_INTERRUPTED,
                           "interrupted at step %lld (t = %.6g s, frame %d of %d)",
                           (long long)sim->steps, sim->time, sim->frame, sim->frame_count);
    double remaining = end - sim->time;
    /* after an unstable step the retry guard runs on halved steps for a while */
    double dt = ldexp(mpm_sim_cfl_dt(sim), -sim->dt_level);
    if (dt >= remaining)
      dt = remaining;
    else if (dt > 0.5 * remaining)
      dt = 0.5 * remaining;
    mpm_status st = mpm_sim_step(sim, dt);
    if (st != MPM_OK) return st;
  }
  sim->time = end;
  sim->frame++;
  if (sim->dt_level > 0) sim->dt_level--; /* one halving is given back per calm frame */
  if (!sim->output_enabled) return MPM_OK;
  mpm_status st = mpm_sim_write_frame(sim);
  const int every = sim->scene.output.checkpoint_every;
  if (st == MPM_OK && every > 0 && sim->frame % every == 0 &&
      sim->time < sim->scene.end_time * (1 - 1e-12))
    st = mpm_sim_write_checkpoint(sim, NULL, 0);
  return st;
}
