/* sim_view.c - what a program embedding the library reads back (include/mpm/mpm.h): the
 * particle view, with the per-particle J and Cauchy stress it derives, and the colliders' poses.
 *
 * The view points at the simulation's own arrays when there are no particle domains. With
 * domains, the standard and the active domain particles are copied into one set first (the
 * order of the frame files), so that a caller sees one list of every particle. */
#include "sim/sim.h"
#include "core/alloc.h"
#include "core/mat3.h"

#include <string.h>

/* The view's J and stress arrays for n particles: 10 arrays of capacity each in one block. */
static mpm_real *derived_buffer(mpm_sim *sim, size_t n) {
  if (n > sim->views.capacity || !sim->views.derived) {
    const size_t cap = n + n / 4 + 1; /* a split or a release adds particles: room to grow */
    mpm_real *b = mpm_alloc(10 * cap * sizeof(mpm_real));
    if (!b) return NULL;
    mpm_keep_free(&sim->views.keep, sim->views.derived);
    sim->views.derived = b;
    sim->views.capacity = cap;
  }
  return sim->views.derived;
}

mpm_real mpm_sim_kirchhoff(const mpm_sim *sim, const mpm_particles *p, size_t i, mpm_real tau[9]) {
  mpm_real F[9], P[9];
  for (int c = 0; c < 9; ++c) F[c] = p->F[c][i];
  /* the moduli the step's stress uses: hardened by the plastic state (snow) and softened by
   * melting (transfer/stress_window.h) */
  const mpm_material mat = mpm_material_at_temperature(&sim->materials[p->material[i]],
                                                       p->plastic[i], p->temperature[i]);
  mat.model->pk1(&mat, F, P);
  mpm_m3_mul_bt(P, F, tau); /* Kirchhoff tau = P F^T = J sigma */
  return mpm_m3_det(F);
}

/* J = det F and sigma = P F^T / J per particle (as the frame files compute theirs). */
static void derive_stress(const mpm_sim *sim, const mpm_particles *p, mpm_real *J,
                          mpm_real *const sigma[9]) {
  const long n = (long)p->count;
#pragma omp parallel for schedule(static)
  for (long i = 0; i < n; ++i) {
    mpm_real tau[9];
    J[i] = mpm_sim_kirchhoff(sim, p, (size_t)i, tau);
    const mpm_real inv = J[i] != 0 ? 1 / J[i] : 0; /* a degenerate F: no stress to speak of */
    for (int c = 0; c < 9; ++c) sigma[c][i] = tau[c] * inv;
  }
}

/* The particle set the views show: the simulation's own, or with domains its copy of every
 * particle (NULL when out of memory). Every set whose arrays a view hands out frees them
 * through the simulation's keep from now on (mpm_sim_hold_particle_arrays). */
static const mpm_particles *view_set(mpm_sim *sim) {
  sim->particles.keep = sim->retry.backup.keep = sim->views.particles.keep = &sim->views.keep;
  if (sim->domains.active_count == 0) return &sim->particles;
  if (mpm_sim_all_particles(sim, &sim->views.particles)) return NULL;
  sim->views.particles.keep = &sim->views.keep; /* (a first copy initializes the set) */
  return &sim->views.particles;
}

mpm_particle_view mpm_sim_particle_state(const mpm_sim *sim_in) {
  /* the view's buffers are a cache, not state: the handle is const to the caller */
  mpm_sim *sim = (mpm_sim *)sim_in;
  mpm_particle_view v;
  memset(&v, 0, sizeof v);
  const mpm_particles *p = view_set(sim);
  if (!p) return v;
  v.count = p->count;
  v.real_size = sizeof(mpm_real);
  for (int d = 0; d < 3; ++d) {
    v.x[d] = p->x[d];
    v.v[d] = p->v[d];
  }
  for (int c = 0; c < 9; ++c) v.F[c] = p->F[c];
  v.mass = p->mass;
  v.volume0 = p->vol0;
  v.material = p->material;
  v.body = p->body;
  v.id = p->id;
  v.temperature = sim->scene.heat.enabled ? p->temperature : NULL;
  v.plastic = p->plastic;
  v.component_stride = p->stride * sizeof(mpm_real);
  return v;
}

mpm_particle_view mpm_sim_particles(const mpm_sim *sim_in) {
  mpm_sim *sim = (mpm_sim *)sim_in;
  mpm_particle_view v = mpm_sim_particle_state(sim);
  const mpm_particles *p = sim->domains.active_count > 0 ? &sim->views.particles : &sim->particles;
  mpm_real *derived = v.count || p->count == 0 ? derived_buffer(sim, p->count) : NULL;
  if (!derived) {
    memset(&v, 0, sizeof v);
    return v;
  }
  mpm_real *sigma[9];
  for (int c = 0; c < 9; ++c) sigma[c] = derived + (size_t)(c + 1) * sim->views.capacity;
  const int saved = mpm_sim_threads_enter(sim);
  derive_stress(sim, p, derived, sigma);
  mpm_sim_threads_leave(sim, saved);
  v.J = derived;
  for (int c = 0; c < 9; ++c) v.stress[c] = sigma[c];
  v.stress_stride = sim->views.capacity * sizeof(mpm_real);
  return v;
}

mpm_domain_view mpm_sim_domain_view(const mpm_sim *sim_in) {
  mpm_sim *sim = (mpm_sim *)sim_in;
  const mpm_domain_set *s = &sim->domains;
  mpm_domain_view v;
  memset(&v, 0, sizeof v);
  v.real_size = sizeof(mpm_real);
  v.first = sim->particles.count;
  if (s->corner_count == 0 || s->active_count == 0) return v;
  /* the active particles' corners, in the particle view's order (inactive slots left out) */
  if (s->active_count > sim->views.corner_capacity || !sim->views.corner) {
    const size_t cap = s->active_count + s->active_count / 4 + 1;
    uint32_t *b = mpm_alloc(8 * cap * sizeof *b);
    if (!b) return v;
    mpm_keep_free(&sim->views.keep, sim->views.corner);
    sim->views.corner = b;
    sim->views.corner_capacity = cap;
  }
  size_t j = 0;
  for (size_t q = 0; q < s->particles.count; ++q)
    if (s->active[q]) memcpy(sim->views.corner + 8 * j++, s->corner[q], 8 * sizeof(uint32_t));
  v.particles = j;
  v.corners = s->corner_count;
  for (int d = 0; d < 3; ++d) {
    v.x[d] = s->cx[d];
    v.v[d] = s->cv[d];
    v.X[d] = s->cX[d];
  }
  v.enriched = s->enrich.enriched && s->enrich.valid ? s->enrich.enriched : NULL;
  v.corner = sim->views.corner;
  return v;
}

void mpm_sim_hold_particle_arrays(mpm_sim *sim, int delta) {
  if (delta) mpm_keep_hold(&sim->views.keep, delta > 0 ? 1 : -1);
}

int mpm_sim_collider_count(const mpm_sim *sim) {
  return sim->collider_count;
}

mpm_status mpm_sim_collider_pose(const mpm_sim *sim, int index, mpm_collider_state *out) {
  if (index < 0 || index >= sim->collider_count) {
    /* the message goes to the handle's error, which a const handle may still set: it is the
     * caller's report, not the simulation's state */
    return mpm_error_set(&((mpm_sim *)sim)->error, MPM_ERR_INVALID,
                         "mpm_sim_collider_pose: collider %d does not exist (the scene has %d)",
                         index, sim->collider_count);
  }
  const mpm_collider *c = &sim->colliders[index];
  const mpm_collider_pose pose = mpm_collider_pose_at(c, sim->time);
  memset(out, 0, sizeof *out);
  out->name = c->desc.name;
  for (int d = 0; d < 3; ++d) {
    out->center[d] = pose.center[d];
    out->velocity[d] = pose.velocity[d];
    out->angular_velocity[d] = pose.omega[d];
  }
  for (int k = 0; k < 9; ++k) out->rotation[k] = pose.R[k];
  out->active = sim->time >= c->desc.active[0] && sim->time < c->desc.active[1];
  return MPM_OK;
}
