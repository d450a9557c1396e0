/* guard.c - the instability guards around one step, and the retry with a smaller dt.
 *
 * After each raw step (step.c, which already stops at non-finite values found in G2P and at
 * a collapsing dt) one parallel scan over the particles looks for
 *   - a particle that left the domain: G2P keeps positions one cell inside the domain faces,
 *     so a particle at that clamp has gone through the whole wall band;
 *   - a CFL violation: a particle that moved more than one cell in the step (dt was chosen
 *     for the speeds before the step; a particle that outran it is the first sign of a
 *     blow-up, before any value is infinite);
 *   - an inverted F (det F <= 0) for a model that cannot take one (neo-Hookean without a
 *     min_stretch clamp evaluates log J).
 * Standard and domain particles are scanned alike (a domain particle is interpolated from
 * its corners, so it leaves the domain or outruns the step with them).
 * The first offending particle (lowest index, whatever the threads) is named with its id,
 * body, material, the step, the time and the quantity. With solver.on_instability = "retry"
 * the particles, time and step count saved before the step are restored and the step is
 * redone with half the dt, up to solver.max_retries halvings; the following steps keep the
 * smaller dt, and one halving is given back per frame (frame.c). */
#include "sim/sim.h"
#include "core/alloc.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

typedef enum guard_kind { GUARD_NONE, GUARD_DOMAIN, GUARD_CFL, GUARD_INVERSION } guard_kind;

typedef struct guard_hit {
  guard_kind kind;
  long particle;
  double value; /* cells moved (CFL) or det F (inversion) */
} guard_hit;

static int model_takes_inversion(const mpm_material *m) {
  return !(m->kind == MPM_MODEL_NEO_HOOKEAN && !(m->min_stretch > 0));
}

/* The particles of p (those with active[i] set, when active is given). */
static guard_hit scan(const mpm_sim *sim, const mpm_particles *p, const uint8_t *active,
                      double dt) {
  const long n = (long)p->count;
  const double dx = sim->scene.dx;
  mpm_real lo[3], hi[3];
  for (int d = 0; d < 3; ++d) { /* the G2P clamp (step.c step_setup), rounded alike */
    lo[d] = (mpm_real)(sim->scene.box_min[d] + dx);
    hi[d] = (mpm_real)(sim->scene.box_max[d] - dx);
  }
  int fragile[64] = {0}, any_fragile = 0;
  for (int m = 0; m < sim->material_count && m < 64; ++m)
    any_fragile |= fragile[m] = !model_takes_inversion(&sim->materials[m]);
  /* a particle moved more than a cell (of the finest level): |v| dt > dx */
  const double vmax = mpm_sim_finest_dx(sim) / dt;
  const mpm_real vmax2 = (mpm_real)(vmax * vmax);
  long first_domain = n, first_cfl = n, first_inv = n;
#pragma omp parallel for schedule(static) reduction(min : first_domain, first_cfl, first_inv)
  for (long i = 0; i < n; ++i) {
    if (active && !active[i]) continue;
    int out = 0;
    for (int d = 0; d < 3; ++d) out |= !(p->x[d][i] > lo[d] && p->x[d][i] < hi[d]);
    if (out && i < first_domain) first_domain = i;
    const mpm_real v2 = p->v[0][i] * p->v[0][i] + p->v[1][i] * p->v[1][i] + p->v[2][i] * p->v[2][i];
    if (v2 > vmax2 && i < first_cfl) first_cfl = i;
    const int m = p->material[i];
    if (any_fragile && m < 64 && fragile[m]) {
      const mpm_real *F[9];
      for (int c = 0; c < 9; ++c) F[c] = p->F[c] + i;
      const mpm_real J = *F[0] * (*F[4] * *F[8] - *F[5] * *F[7]) -
                         *F[1] * (*F[3] * *F[8] - *F[5] * *F[6]) +
                         *F[2] * (*F[3] * *F[7] - *F[4] * *F[6]);
      if (!(J > 0) && i < first_inv) first_inv = i;
    }
  }
  guard_hit h = {GUARD_NONE, -1, 0};
  if (first_domain < n) {
    h.kind = GUARD_DOMAIN;
    h.particle = first_domain;
  } else if (first_cfl < n) {
    const long i = first_cfl;
    h.kind = GUARD_CFL;
    h.particle = i;
    const double v2 = (double)p->v[0][i] * p->v[0][i] + (double)p->v[1][i] * p->v[1][i] +
                      (double)p->v[2][i] * p->v[2][i];
    h.value = sqrt(v2) * dt / dx;
  } else if (first_inv < n) {
    const long i = first_inv;
    h.kind = GUARD_INVERSION;
    h.particle = i;
    double F[9];
    for (int c = 0; c < 9; ++c) F[c] = p->F[c][i];
    h.value = F[0] * (F[4] * F[8] - F[5] * F[7]) - F[1] * (F[3] * F[8] - F[5] * F[6]) +
              F[2] * (F[3] * F[7] - F[4] * F[6]);
  }
  return h;
}

/* The message for a guard hit, in sim->error. */
static mpm_status report(mpm_sim *sim, const mpm_particles *p, const guard_hit *h, double dt) {
  const char *kind = p == &sim->particles ? "" : "domain ";
  const long i = h->particle;
  const int m = p->material[i];
  const char *mname = sim->scene.materials[m].name;
  char where[200];
  snprintf(where, sizeof where,
           "simulation unstable at step %lld (t = %.6g s, dt = %.3g s): %sparticle id %u (body "
           "%d, material %d '%s')",
           (long long)sim->steps, sim->time, dt, kind, p->id[i], p->body[i], m, mname);
  switch (h->kind) {
  case GUARD_DOMAIN:
    return mpm_error_set(
        &sim->error, MPM_ERR_UNSTABLE,
        "%s left the domain: position (%.4g, %.4g, %.4g) m passed the walls; try a "
        "smaller solver.cfl, stiffer walls or a larger domain",
        where, (double)p->x[0][i], (double)p->x[1][i], (double)p->x[2][i]);
  case GUARD_CFL:
    return mpm_error_set(&sim->error, MPM_ERR_UNSTABLE,
                         "%s violated the CFL condition: it moved %.3g cells in one step (speed "
                         "%.3g m/s); try a smaller solver.cfl or solver.max_dt, or "
                         "solver.on_instability = \"retry\"",
                         where, h->value, h->value * mpm_sim_finest_dx(sim) / dt);
  case GUARD_INVERSION:
    return mpm_error_set(&sim->error, MPM_ERR_UNSTABLE,
                         "%s has an inverted deformation gradient (det F = %.3g) that the "
                         "neo-Hookean model without min_stretch cannot evaluate; set "
                         "materials[%d].min_stretch (e.g. 0.1) or use fixed_corotated",
                         where, h->value, m);
  case GUARD_NONE:
    break;
  }
  return MPM_OK;
}

mpm_status mpm_sim_guard_check(mpm_sim *sim, double dt) {
  const mpm_particles *at = &sim->particles;
  guard_hit h = scan(sim, at, NULL, dt);
  if (h.kind == GUARD_NONE && sim->domains.active_count) {
    at = &sim->domains.particles;
    h = scan(sim, at, sim->domains.active, dt);
  }
  /* every process of the run takes the same decision (a retry is redone by all of them) */
  double hit = h.kind != GUARD_NONE;
  mpm_reduce_all(sim->reduction, MPM_REDUCE_MAX, &hit, 1);
  if (h.kind != GUARD_NONE) return report(sim, at, &h, dt);
  if (hit > 0)
    return mpm_error_set_elsewhere(&sim->error, MPM_ERR_UNSTABLE,
                                   "simulation unstable at step %lld (t = %.6g s, dt = %.3g s): a "
                                   "particle of another process of the run (its message names it)",
                                   (long long)sim->steps, sim->time, dt);
  return MPM_OK;
}

/* The corner arrays a step changes: positions (with their compensation), velocities and APIC
 * affine moments. */
#define CORNER_STATE 18
static void corner_state(mpm_domain_set *s, mpm_real *out[CORNER_STATE]) {
  for (int d = 0; d < 3; ++d) {
    out[d] = s->cx[d];
    out[3 + d] = s->cv[d];
    out[6 + d] = s->cxc[d];
  }
  for (int e = 0; e < 9; ++e) out[9 + e] = s->cB[e];
}

/* Save what a step changes: the particles, the domain particles and their corners (the clock
 * is saved by the caller). */
static int save_state(mpm_sim *sim) {
  if (mpm_particles_assign(&sim->retry.backup, &sim->particles)) return -1;
  mpm_domain_set *s = &sim->domains;
  if (!s->active_count) return 0;
  if (mpm_particles_assign(&sim->retry.domain_backup, &s->particles)) return -1;
  if (sim->retry.corner_backup_capacity < s->corner_count) {
    for (int k = 0; k < CORNER_STATE; ++k) {
      mpm_free(sim->retry.corner_backup[k]);
      sim->retry.corner_backup[k] = mpm_alloc((s->corner_count + 1) * sizeof(mpm_real));
      if (!sim->retry.corner_backup[k]) {
        sim->retry.corner_backup_capacity = 0;
        return -1;
      }
    }
    sim->retry.corner_backup_capacity = s->corner_count;
  }
  mpm_real *c[CORNER_STATE];
  corner_state(s, c);
  for (int k = 0; k < CORNER_STATE; ++k)
    memcpy(sim->retry.corner_backup[k], c[k], s->corner_count * sizeof(mpm_real));
  return 0;
}

static void restore_state(mpm_sim *sim) {
  /* swap the arrays: the backup becomes the particles (the failed state is dropped) */
  mpm_particles t = sim->particles;
  sim->particles = sim->retry.backup;
  sim->retry.backup = t;
  mpm_domain_set *s = &sim->domains;
  if (!s->active_count) return;
  mpm_particles_assign(&s->particles, &sim->retry.domain_backup); /* same size: cannot fail */
  mpm_real *c[CORNER_STATE];
  corner_state(s, c);
  for (int k = 0; k < CORNER_STATE; ++k)
    memcpy(c[k], sim->retry.corner_backup[k], s->corner_count * sizeof(mpm_real));
}

mpm_status mpm_sim_guarded_step(mpm_sim *sim, double max_dt) {
  const int retry = sim->scene.solver.on_instability == MPM_INSTABILITY_RETRY;
  const double time0 = sim->time, last_dt0 = sim->last_dt;
  const int64_t steps0 = sim->steps;
  const mpm_real speed0 = sim->max_speed;
  double dt_cap = max_dt;
  for (;;) {
    if (retry && save_state(sim))
      return mpm_error_set(&sim->error, MPM_ERR_NOMEM,
                           "out of memory saving the state of step %lld for a retry",
                           (long long)sim->steps);
    mpm_status st = mpm_sim_raw_step(sim, dt_cap);
    if (st == MPM_OK) st = mpm_sim_guard_check(sim, sim->last_dt);
    if (st != MPM_ERR_UNSTABLE || !retry) return st;
    if (sim->retry.dt_level >= sim->scene.solver.max_retries) {
      char msg[sizeof sim->error.message];
      snprintf(msg, sizeof msg, "%s", sim->error.message);
      return mpm_error_set(&sim->error, MPM_ERR_UNSTABLE, "%s (still, after halving dt %d times)",
                           msg, sim->retry.dt_level);
    }
    /* undo the step and redo it with half the dt it took */
    const double dt_failed = sim->last_dt;
    restore_state(sim);
    sim->time = time0;
    sim->steps = steps0;
    sim->last_dt = last_dt0;
    sim->max_speed = speed0;
    sim->retry.dt_level++;
    sim->retry.retries++;
    dt_cap = 0.5 * dt_failed;
  }
}
