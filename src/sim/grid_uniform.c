/* grid_uniform.c - the grid stack of one uniform level (sparse paged blocks or the dense
 * reference; grid_stack.h), with Zhu's particle domains: their corners are activated, planned and
 * transferred on the same level, and enriched corners are DOFs of their own after the level's
 * nodes (Zhu eq. 12). */
#include "sim/grid_stack.h"

#include "core/alloc.h"
#include "domain/domain_transfer.h"
#include "domain/enrich_contact.h"
#include "scene/sample.h"
#include "sim/sim.h"
#include "transfer/operators.h"

/* The level itself is the simulation's grid, made with its geometry (sim.c). */
static mpm_status make(mpm_sim *sim, mpm_error *err) {
  (void)sim;
  (void)err;
  return MPM_OK;
}

static void destroy(mpm_sim *sim) {
  (void)sim;
}

static mpm_status sample_body(mpm_sim *sim, int b, mpm_error *err) {
  return mpm_sample_body(&sim->scene, b, &sim->particles, err);
}

static double finest_dx(const mpm_sim *sim) {
  return sim->scene.dx;
}

/* The domain corners' transfer plan (domain_transfer.h), their renumbering into its order when
 * it has come apart, and then the guard's copies of the corners' state (guard.c, a retry
 * restores them) renumbered alike. */
static mpm_status plan_corners(mpm_sim *sim, mpm_step_ctx *c) {
  mpm_domain_set *s = &sim->domains;
  /* the implicit Hessian and the enriched corners' contact (enrich_contact.h) apply the
   * embedding's rows */
  s->corner_rows =
      sim->scene.solver.integrator == MPM_INTEGRATOR_IMPLICIT || mpm_enrich_contact_on(s);
  uint32_t *order = NULL;
  if (mpm_domain_plan(s, &sim->grid, &c->dtc.kernel, &sim->step_arena) ||
      mpm_domain_order_corners(s, &sim->grid, &c->dtc.kernel, &sim->step_arena, &order))
    return mpm_error_set(&sim->error, MPM_ERR_NOMEM,
                         "step %lld: out of memory planning the transfers of %zu domain corners",
                         (long long)sim->steps, s->corner_count);
  if (!order || sim->retry.corner_backup_capacity < s->corner_count) return MPM_OK;
  mpm_real *tmp = mpm_arena_alloc(&sim->step_arena, (s->corner_count + 1) * sizeof *tmp);
  if (!tmp)
    return mpm_error_set(&sim->error, MPM_ERR_NOMEM,
                         "step %lld: out of memory renumbering %zu domain corners",
                         (long long)sim->steps, s->corner_count);
  for (size_t k = 0; k < sizeof sim->retry.corner_backup / sizeof *sim->retry.corner_backup; ++k)
    mpm_domain_permute_values(sim->retry.corner_backup[k], tmp, sizeof(mpm_real), order,
                              s->corner_count);
  return MPM_OK;
}

static mpm_status sort(mpm_sim *sim, mpm_step_ctx *c) {
  mpm_grid *g = &sim->grid;
  mpm_particles *p = &sim->particles;
  if (g->ops->activate(g, &c->tc.kernel, sim->material_count, p, &sim->step_arena))
    return mpm_error_set(&sim->error, MPM_ERR_NOMEM,
                         "step %lld: out of memory sorting %zu particles into grid blocks",
                         (long long)sim->steps, p->count);
  uint32_t *perm = g->ops->particle_order(g);
  if (perm && mpm_sim_wants_reorder(sim, mpm_order_breaks(perm, p->count), p->count)) {
    /* move particles into block order now and then, so transfers stream through memory */
    if (mpm_sim_ensure_scratch(sim))
      return mpm_error_set(&sim->error, MPM_ERR_NOMEM, "out of memory reordering particles");
    mpm_particles_permute(p, perm, sim->iscratch);
    for (size_t j = 0; j < p->count; ++j) perm[j] = (uint32_t)j;
  }
  if (c->domains && mpm_domain_activate(&sim->domains, g, &c->dtc.kernel))
    return mpm_error_set(&sim->error, MPM_ERR_NOMEM,
                         "step %lld: out of memory activating the grid around domain corners",
                         (long long)sim->steps);
  if (c->domains && sim->scene.heat.enabled) { /* heat reaches the grid from the particles */
    const mpm_particles *dp = &sim->domains.particles;
    const mpm_real *const x[3] = {dp->x[0], dp->x[1], dp->x[2]};
    if (g->ops->activate_points(g, &c->tc.kernel, dp->count, x, sim->domains.active))
      return mpm_error_set(&sim->error, MPM_ERR_NOMEM,
                           "step %lld: out of memory activating the grid around domain particles",
                           (long long)sim->steps);
  }
  return c->domains ? plan_corners(sim, c) : MPM_OK;
}

static mpm_status layout(mpm_sim *sim, mpm_step_ctx *c, unsigned fields) {
  mpm_dofs *d = &sim->dofs;
  mpm_domain_enrichment *en = &sim->domains.enrich;
  mpm_status added = mpm_dofs_add_grid(d, &sim->grid);
  if (c->domains && en->count) { /* enriched corners: DOFs of their own (Zhu eq. 12) */
    en->dof_begin = d->count;
    const mpm_real *const x[3] = {en->x[0], en->x[1], en->x[2]};
    if (added == MPM_OK) added = mpm_dofs_add_corners(d, en->count, x);
  }
  if (added != MPM_OK || mpm_dofs_end_layout(d, fields))
    return mpm_error_set(&sim->error, MPM_ERR_NOMEM,
                         "step %lld: out of memory for the values of %zu grid nodes",
                         (long long)sim->steps, d->count);
  mpm_dofs_clear(d, fields & ~(unsigned)MPM_DOF_V); /* the update writes every v */
  c->val = mpm_dofs_grid_values(d, &sim->grid);
  c->all = mpm_dofs_values(d);
  return MPM_OK;
}

static mpm_status p2g(mpm_sim *sim, mpm_step_ctx *c) {
  if (sim->scene.solver.integrator == MPM_INTEGRATOR_IMPLICIT &&
      mpm_p2g_fuses_force(&c->tc, &sim->grid)) {
    /* the implicit solve needs v^n and f^n apart (the Newton gradient), not the fused impulse */
    mpm_p2g_mass_momentum(&c->tc, &sim->grid, &c->val, &sim->particles);
    mpm_p2g_stress_force(&c->tc, &sim->grid, c->val.f, &sim->particles);
  } else {
    mpm_p2g(&c->tc, &sim->grid, &c->val, &sim->particles);
  }
  /* the implicit step applies the corners' embedding as a matrix (its Hessian): it needs the
   * rows, which the explicit step does without (domain/corner_pads.h) */
  if (c->domains && mpm_domain_p2g(&c->dtc, &sim->domains, &sim->grid, &c->all, &sim->step_arena))
    return mpm_error_set(&sim->error, MPM_ERR_NOMEM,
                         "step %lld: out of memory for the stresses of %zu domain particles",
                         (long long)sim->steps, sim->domains.particles.count);
  return MPM_OK;
}

/* One level: the material points are one part on sim->grid (implicit.h's default). */
static void implicit_parts(mpm_sim *sim, mpm_implicit *s) {
  s->grid = &sim->grid;
}

static mpm_status g2p(mpm_sim *sim, mpm_step_ctx *c) {
  c->val = mpm_dofs_grid_values(&sim->dofs, &sim->grid); /* with the update's motion field */
  c->r = mpm_g2p(&c->tc, &sim->grid, &c->val, &sim->particles);
  c->bad_set = &sim->particles;
  if (c->domains) {
    const mpm_g2p_result rd = mpm_domain_g2p(&c->dtc, &sim->domains, &c->all, &c->update.boundary);
    if (rd.max_speed > c->r.max_speed) c->r.max_speed = rd.max_speed;
    if (rd.bad_particle >= 0 && c->r.bad_particle < 0) {
      c->bad_set = &sim->domains.particles;
      c->r.bad_particle = rd.bad_particle;
    }
  }
  return MPM_OK;
}

static mpm_status nothing(mpm_sim *sim) {
  (void)sim;
  return MPM_OK;
}

static void moved(mpm_sim *sim) {
  (void)sim;
}

static mpm_status save(mpm_sim *sim, mpm_checkpoint *c) {
  (void)sim;
  (void)c;
  return MPM_OK;
}

static mpm_status load(mpm_sim *sim, const mpm_checkpoint *c) {
  (void)sim;
  (void)c;
  return MPM_OK;
}

static mpm_status write_frame(mpm_sim *sim, int frame) {
  (void)sim;
  (void)frame;
  return MPM_OK;
}

static const char *frame_part(const mpm_sim *sim) {
  (void)sim;
  return NULL;
}

static void info(const mpm_sim *sim, mpm_sim_info *in) {
  (void)sim;
  (void)in;
}

const mpm_grid_stack_ops mpm_grid_uniform = {
    .name = "uniform",
    .make = make,
    .destroy = destroy,
    .sample_body = sample_body,
    .finest_dx = finest_dx,
    .sort = sort,
    .layout = layout,
    .p2g = p2g,
    .implicit_parts = implicit_parts,
    .g2p = g2p,
    .refine = nothing,
    .resample = nothing,
    .particles_moved = moved,
    .adds_bodies = 1,
    .save = save,
    .load = load,
    .write_frame = write_frame,
    .frame_part = frame_part,
    .info = info,
};

const mpm_grid_stack_ops *mpm_grid_stack_for(const mpm_scene *scene) {
  return scene->levels > 0 ? &mpm_grid_levels : &mpm_grid_uniform;
}
