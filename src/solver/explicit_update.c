/* explicit_update.c - the explicit update over the DOF set (see explicit_update.h). */
#include "solver/explicit_update.h"
#include "core/parallel.h"

/* DOF i (mass m, position x) of a segment with the given boundary depth. With `ahead` the
 * boundary acts where the DOF is and again where the step takes it, x + dt v (domain corners,
 * which move with their own velocity: a grid node's band of half a cell is what stops
 * material before an obstacle; a corner has none, and a grip must hold what it holds). */
MPM_ALWAYS_INLINE void update_dof(const mpm_explicit_update *u, const int impulse, mpm_dofs *d,
                                  size_t i, const mpm_real x[3], mpm_real depth, int ahead) {
  const mpm_real mass = d->mass[i];
  if (!(mass > 0)) {
    for (int c = 0; c < 3; ++c) d->v0[c][i] = d->v[c][i] = 0;
    return;
  }
  const mpm_real inv_m = 1 / mass;
  mpm_real v0[3], v[3], g[3] = {u->gravity[0], u->gravity[1], u->gravity[2]};
  if (u->region_count) mpm_force_regions_add(u->regions, u->region_count, x, g);
  for (int c = 0; c < 3; ++c) {
    v0[c] = d->v0[c][i] * inv_m;
    v[c] = impulse ? v0[c] + u->dt * g[c] : v0[c] + u->dt * (d->f[c][i] * inv_m + g[c]);
  }
  mpm_boundary_apply(&u->boundary, x, depth, v);
  if (ahead) {
    const mpm_real y[3] = {x[0] + u->dt * v[0], x[1] + u->dt * v[1], x[2] + u->dt * v[2]};
    mpm_boundary_apply(&u->boundary, y, depth, v);
  }
  for (int c = 0; c < 3; ++c) {
    d->v0[c][i] = v0[c];
    d->v[c][i] = v[c];
  }
}

static void update_grid_segment(const mpm_explicit_update *u, const int impulse, mpm_dofs *d,
                                const mpm_dof_segment *s) {
  const mpm_grid *g = s->grid;
  const long boxes = (long)g->ops->box_count(g);
  const size_t begin = s->begin;
  const mpm_real depth = s->boundary_depth;
#pragma omp parallel for schedule(dynamic, 16)
  for (long b = 0; b < boxes; ++b) {
    const mpm_node_box box = g->ops->box(g, (size_t)b);
    size_t i = begin + box.first;
    for (int a = 0; a < box.n[0]; ++a)
      for (int e = 0; e < box.n[1]; ++e)
        for (int c = 0; c < box.n[2]; ++c, ++i) {
          const int32_t idx[3] = {box.lo[0] + a, box.lo[1] + e, box.lo[2] + c};
          mpm_real x[3];
          mpm_grid_node_position(g, idx, x);
          update_dof(u, impulse, d, i, x, depth, 0);
        }
  }
}

static void update_corner_segment(const mpm_explicit_update *u, const int impulse, mpm_dofs *d,
                                  const mpm_dof_segment *s) {
  const long n = (long)s->count;
#pragma omp parallel for schedule(static)
  for (long k = 0; k < n; ++k) {
    const mpm_real x[3] = {s->x[0][k], s->x[1][k], s->x[2][k]};
    update_dof(u, impulse, d, s->begin + (size_t)k, x, s->boundary_depth, 1);
  }
}

void mpm_dofs_explicit_update(const mpm_explicit_update *u, mpm_p2g_output in, mpm_dofs *d) {
  const int impulse = in == MPM_P2G_IMPULSE;
  for (int k = 0; k < d->segment_count; ++k) {
    const mpm_dof_segment *s = &d->segment[k];
    if (s->kind == MPM_DOF_GRID_NODE)
      update_grid_segment(u, impulse, d, s);
    else
      update_corner_segment(u, impulse, d, s);
  }
}
