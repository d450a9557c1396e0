/* explicit_update.c - the explicit update over the DOF set (see explicit_update.h). */
#include "solver/explicit_update.h"
#include "core/parallel.h"

/* DOF i (mass m, position x) of a segment with the given boundary depth. With `ahead` the
 * boundary acts where the DOF is and again where the step takes it, x + dt v (domain corners,
 * which move with their own velocity: a grid node's band of half a cell is what stops
 * material before an obstacle; a corner has none, and a grip must hold what it holds). */
MPM_ALWAYS_INLINE void update_dof(const mpm_explicit_update *u, const int impulse, mpm_dofs *d,
                                  size_t i, const mpm_real x[3], mpm_real depth, int ahead,
                                  double *taken) {
  const mpm_real mass = d->mass[i];
  if (!(mass > 0)) {
    for (int c = 0; c < 3; ++c) d->v0[c][i] = d->v[c][i] = 0;
    return;
  }
  const mpm_real inv_m = 1 / mass;
  mpm_real v0[3], v[3], g[3] = {u->gravity[0], u->gravity[1], u->gravity[2]}, drag = 0;
  if (u->region_count) drag = mpm_force_regions_add(u->regions, u->region_count, x, g);
  for (int c = 0; c < 3; ++c) {
    v0[c] = d->v0[c][i] * inv_m;
    v[c] = impulse ? v0[c] + u->dt * g[c] : v0[c] + u->dt * (d->f[c][i] * inv_m + g[c]);
  }
  mpm_force_drag(drag, u->dt, v);
  if (taken) /* a constant after inlining: the loops without colliders do not see it */
    mpm_boundary_apply_taken(&u->boundary, x, depth, ahead, mass, v, taken);
  else
    mpm_boundary_apply(&u->boundary, x, depth, ahead, v);
  if (ahead) {
    const mpm_real y[3] = {x[0] + u->dt * v[0], x[1] + u->dt * v[1], x[2] + u->dt * v[2]};
    if (taken)
      mpm_boundary_apply_taken(&u->boundary, y, depth, ahead, mass, v, taken);
    else
      mpm_boundary_apply(&u->boundary, y, depth, ahead, v);
  }
  for (int c = 0; c < 3; ++c) {
    d->v0[c][i] = v0[c];
    d->v[c][i] = v[c];
  }
}

/* The boxes of a grid segment; with `slots` (3 per pose per box) each box's taken momentum
 * goes to its own slot. */
MPM_ALWAYS_INLINE void grid_boxes(const mpm_explicit_update *u, const int impulse, mpm_dofs *d,
                                  const mpm_dof_segment *s, double *slots) {
  const mpm_grid *g = s->grid;
  const long boxes = (long)g->ops->box_count(g);
  const size_t begin = s->begin;
  const mpm_real depth = s->boundary_depth;
  const size_t per = 3 * (size_t)u->boundary.collider_count;
#pragma omp parallel for schedule(dynamic, 16)
  for (long b = 0; b < boxes; ++b) {
    const mpm_node_box box = g->ops->box(g, (size_t)b);
    double *taken = slots ? slots + (size_t)b * per : NULL;
    if (slots)
      for (size_t k = 0; k < per; ++k) taken[k] = 0;
    size_t i = begin + box.first;
    for (int a = 0; a < box.n[0]; ++a)
      for (int e = 0; e < box.n[1]; ++e)
        for (int c = 0; c < box.n[2]; ++c, ++i) {
          const int32_t idx[3] = {box.lo[0] + a, box.lo[1] + e, box.lo[2] + c};
          mpm_real x[3];
          mpm_grid_node_position(g, idx, x);
          update_dof(u, impulse, d, i, x, depth, 0, taken);
        }
  }
}

/* Corners in chunks of CORNER_CHUNK, one slot each when measured. */
#define CORNER_CHUNK 256
MPM_ALWAYS_INLINE void corner_chunks(const mpm_explicit_update *u, const int impulse, mpm_dofs *d,
                                     const mpm_dof_segment *s, double *slots) {
  const long n = (long)s->count;
  if (!slots) {
#pragma omp parallel for schedule(static)
    for (long k = 0; k < n; ++k) {
      const mpm_real x[3] = {s->x[0][k], s->x[1][k], s->x[2][k]};
      update_dof(u, impulse, d, s->begin + (size_t)k, x, s->boundary_depth, 1, NULL);
    }
    return;
  }
  const size_t per = 3 * (size_t)u->boundary.collider_count;
  const long chunks = (n + CORNER_CHUNK - 1) / CORNER_CHUNK;
#pragma omp parallel for schedule(static)
  for (long h = 0; h < chunks; ++h) {
    double *taken = slots + (size_t)h * per;
    for (size_t k = 0; k < per; ++k) taken[k] = 0;
    const long end = (h + 1) * CORNER_CHUNK < n ? (h + 1) * CORNER_CHUNK : n;
    for (long k = h * CORNER_CHUNK; k < end; ++k) {
      const mpm_real x[3] = {s->x[0][k], s->x[1][k], s->x[2][k]};
      update_dof(u, impulse, d, s->begin + (size_t)k, x, s->boundary_depth, 1, taken);
    }
  }
}

/* Work units (boxes, corner chunks) of segment s. */
static size_t segment_units(const mpm_dof_segment *s) {
  if (s->kind == MPM_DOF_GRID_NODE) return s->grid->ops->box_count(s->grid);
  return (s->count + CORNER_CHUNK - 1) / CORNER_CHUNK;
}

mpm_status mpm_dofs_explicit_update(const mpm_explicit_update *u, mpm_p2g_output in, mpm_dofs *d) {
  const int impulse = in == MPM_P2G_IMPULSE;
  const int measure = u->taken && u->boundary.collider_count > 0;
  double *slots = NULL;
  const size_t per = 3 * (size_t)u->boundary.collider_count;
  if (measure) {
    size_t most = 1;
    for (int k = 0; k < d->segment_count; ++k)
      if (segment_units(&d->segment[k]) > most) most = segment_units(&d->segment[k]);
    slots = mpm_arena_alloc(u->arena, most * per * sizeof *slots);
    if (!slots) return MPM_ERR_NOMEM;
  }
  for (int k = 0; k < d->segment_count; ++k) {
    const mpm_dof_segment *s = &d->segment[k];
    if (s->kind == MPM_DOF_GRID_NODE) {
      if (measure)
        grid_boxes(u, impulse, d, s, slots);
      else
        grid_boxes(u, impulse, d, s, NULL);
    } else {
      if (measure)
        corner_chunks(u, impulse, d, s, slots);
      else
        corner_chunks(u, impulse, d, s, NULL);
    }
    if (measure) /* in the order of the units: the same sums on any number of threads */
      for (size_t b = 0, units = segment_units(s); b < units; ++b)
        for (size_t j = 0; j < per; ++j) u->taken[j] += slots[b * per + j];
  }
  return MPM_OK;
}
