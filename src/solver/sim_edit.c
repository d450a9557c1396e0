/* sim_edit.c - what a script changes between two steps (include/mpm/mpm.h): particles'
 * velocities and positions, chosen by their stable ids.
 *
 * Every request is checked before anything changes (ids simulated now, on material points,
 * finite values, positions inside the domain), so a refused call leaves the state as it was. */
#include "solver/sim.h"
#include "core/alloc.h"

#include <math.h>
#include <string.h>

/* The material point index of every requested id in *index (count entries), or an error naming
 * the first id that is not a material point simulated now. */
static mpm_status find_ids(mpm_sim *sim, const char *what, size_t count, const uint32_t *ids,
                           uint32_t **index) {
  const mpm_particles *p = &sim->particles;
  *index = NULL;
  if (sim->failed != MPM_OK)
    return mpm_error_set(&sim->error, sim->failed,
                         "%s: the simulation failed at step %lld and cannot go on (%s)", what,
                         (long long)sim->steps, sim->failed_message);
  if (count && !ids) return mpm_error_set(&sim->error, MPM_ERR_INVALID, "%s: ids is NULL", what);
  uint32_t top = 0;
  for (size_t i = 0; i < p->count; ++i)
    if (p->id[i] > top) top = p->id[i];
  /* id -> index + 1 (0: not a material point); ids past the largest are none */
  uint32_t *slot = mpm_calloc((size_t)top + 1, sizeof *slot);
  uint32_t *out = mpm_alloc((count + 1) * sizeof *out);
  if (!slot || !out) {
    mpm_free(slot);
    mpm_free(out);
    return mpm_error_set(&sim->error, MPM_ERR_NOMEM, "%s: out of memory", what);
  }
  for (size_t i = 0; i < p->count; ++i) slot[p->id[i]] = (uint32_t)i + 1;
  for (size_t k = 0; k < count; ++k) {
    if (ids[k] <= top && slot[ids[k]]) {
      out[k] = slot[ids[k]] - 1;
      continue;
    }
    int domain = 0; /* a particle whose domain is on moves with its corners */
    const mpm_particles *d = &sim->domains.particles;
    for (size_t q = 0; q < d->count && !domain; ++q)
      domain = d->id[q] == ids[k] && sim->domains.active[q];
    mpm_free(slot);
    mpm_free(out);
    return mpm_error_set(&sim->error, MPM_ERR_INVALID,
                         domain ? "%s: particle id %u has its domain on: it moves with its "
                                  "domain's corners (release its domain first)"
                                : "%s: no particle with id %u is simulated now",
                         what, ids[k]);
  }
  mpm_free(slot);
  *index = out;
  return MPM_OK;
}

mpm_status mpm_sim_set_velocities(mpm_sim *sim, size_t count, const uint32_t *ids,
                                  const double *v) {
  uint32_t *index;
  mpm_status st = find_ids(sim, "mpm_sim_set_velocities", count, ids, &index);
  if (st != MPM_OK) return st;
  for (size_t k = 0; k < count; ++k)
    for (int d = 0; d < 3; ++d)
      if (!isfinite(v[3 * k + d]) || fabs(v[3 * k + d]) > 1e30) {
        mpm_free(index);
        return mpm_error_set(&sim->error, MPM_ERR_INVALID,
                             "mpm_sim_set_velocities: particle id %u: velocity component %d is "
                             "%g; expected a finite number (m/s)",
                             ids[k], d, v[3 * k + d]);
      }
  mpm_particles *p = &sim->particles;
  for (size_t k = 0; k < count; ++k)
    for (int d = 0; d < 3; ++d) p->v[d][index[k]] = (mpm_real)v[3 * k + d];
  mpm_free(index);
  return MPM_OK;
}

mpm_status mpm_sim_set_positions(mpm_sim *sim, size_t count, const uint32_t *ids, const double *x) {
  uint32_t *index;
  mpm_status st = find_ids(sim, "mpm_sim_set_positions", count, ids, &index);
  if (st != MPM_OK) return st;
  const mpm_scene *sc = &sim->scene;
  for (size_t k = 0; k < count; ++k)
    for (int d = 0; d < 3; ++d) {
      const double c = x[3 * k + d];
      /* inside the domain, away from its walls' band as sampling keeps bodies */
      if (!(c > sc->domain_min[d] && c < sc->domain_max[d])) {
        mpm_free(index);
        return mpm_error_set(&sim->error, MPM_ERR_INVALID,
                             "mpm_sim_set_positions: particle id %u: coordinate %d is %g; "
                             "expected a number inside the domain, %g to %g (m)",
                             ids[k], d, c, sc->domain_min[d], sc->domain_max[d]);
      }
    }
  mpm_particles *p = &sim->particles;
  for (size_t k = 0; k < count; ++k)
    for (int d = 0; d < 3; ++d) {
      p->x[d][index[k]] = (mpm_real)x[3 * k + d];
      p->xc[d][index[k]] = 0; /* a jump: nothing left of the old position's rounding */
    }
  mpm_free(index);
  return MPM_OK;
}

mpm_status mpm_sim_set_collider_pose(mpm_sim *sim, int index, const double center[3],
                                     const double rotation[9]) {
  const char *what = "mpm_sim_set_collider_pose";
  if (sim->failed != MPM_OK)
    return mpm_error_set(&sim->error, sim->failed,
                         "%s: the simulation failed at step %lld and cannot go on (%s)", what,
                         (long long)sim->steps, sim->failed_message);
  if (index < 0 || index >= sim->collider_count)
    return mpm_error_set(&sim->error, MPM_ERR_INVALID,
                         "%s: collider %d does not exist (the scene has %d)", what, index,
                         sim->collider_count);
  if (!center) return mpm_error_set(&sim->error, MPM_ERR_INVALID, "%s: center is NULL", what);
  mpm_collider *c = &sim->colliders[index];
  for (int d = 0; d < 3; ++d)
    if (!isfinite(center[d]) || fabs(center[d]) > 1e15)
      return mpm_error_set(&sim->error, MPM_ERR_INVALID,
                           "%s: collider '%s': center[%d] is %g; expected a finite number (m)",
                           what, c->desc.name, d, center[d]);
  double R[9];
  if (rotation) {
    memcpy(R, rotation, sizeof R);
    /* a rotation: R R^T = I within 1e-6, det +1 */
    double worst = 0;
    for (int r = 0; r < 3; ++r)
      for (int k = 0; k < 3; ++k) {
        const double dot =
            R[3 * r] * R[3 * k] + R[3 * r + 1] * R[3 * k + 1] + R[3 * r + 2] * R[3 * k + 2];
        const double e = fabs(dot - (r == k));
        if (!isfinite(e))
          worst = INFINITY;
        else if (e > worst)
          worst = e;
      }
    const double det = R[0] * (R[4] * R[8] - R[5] * R[7]) - R[1] * (R[3] * R[8] - R[5] * R[6]) +
                       R[2] * (R[3] * R[7] - R[4] * R[6]);
    if (!(worst <= 1e-6) || !(det > 0))
      return mpm_error_set(&sim->error, MPM_ERR_INVALID,
                           "%s: collider '%s': the rotation is not a rotation (|R R^T - I| = %g, "
                           "det R = %g); expected an orthonormal matrix, row-major, det +1",
                           what, c->desc.name, worst, det);
  } else { /* the rotation it has now */
    const mpm_collider_pose p = mpm_collider_pose_at(c, sim->time);
    for (int k = 0; k < 9; ++k) R[k] = c->script.on ? c->script.R[k] : (double)p.R[k];
  }
  mpm_collider_script_set(c, sim->time, center, R);
  return MPM_OK;
}
