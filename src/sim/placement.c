/* placement.c - what a scene's bodies start in that is likely a mistake (issue 17): bodies that
 * overlap (their particle lattices interpenetrate: the material there is twice as dense) and
 * bodies that start inside a slip or separating collider (their particles are thrown out in the
 * first steps; material inside a sticky collider is held by it, as a grip holds a bar). */
#include "sim/sim.h"

#include "core/alloc.h"
#include "core/hash.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The particles of body b, standard and active domain ones: their positions appended to xyz. */
static size_t body_points(const mpm_sim *sim, int b, float **xyz, size_t *cap, double *h) {
  size_t n = 0;
  *h = INFINITY;
  for (int pass = 0; pass < 2; ++pass) {
    const mpm_particles *p = pass ? &sim->domains.particles : &sim->particles;
    for (size_t i = 0; i < p->count; ++i) {
      if (p->body[i] != b || (pass && !sim->domains.active[i])) continue;
      if (n == *cap) {
        const size_t c = *cap ? 2 * *cap : 4096;
        float *g = mpm_realloc(*xyz, 3 * c * sizeof *g);
        if (!g) return n;
        *xyz = g;
        *cap = c;
      }
      for (int d = 0; d < 3; ++d) (*xyz)[3 * n + d] = (float)p->x[d][i];
      *h = fmin(*h, cbrt((double)p->vol0[i]));
      ++n;
    }
  }
  return n;
}

static uint64_t cell_key(const float *x, const double o[3], double h) {
  uint64_t k = 0;
  for (int d = 0; d < 3; ++d)
    k = k << 21 | ((uint64_t)((int64_t)floor((x[d] - o[d]) / h) + (1 << 20)) & 0x1fffff);
  return k;
}

static int cmp_u64(const void *a, const void *b) {
  const uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
  return x < y ? -1 : x > y;
}

int mpm_sim_placement_report(const mpm_sim *sim, char *out, size_t cap) {
  const mpm_scene *sc = &sim->scene;
  int found = 0;
  size_t len = 0;
  out[0] = 0;
#define SAY(...)                                                                                   \
  do {                                                                                             \
    if (len < cap) len += (size_t)snprintf(out + len, cap - len, __VA_ARGS__);                     \
    ++found;                                                                                       \
  } while (0)
  float *a = NULL, *b = NULL;
  size_t acap = 0, bcap = 0;
  uint64_t *keys = NULL;
  for (int i = 0; i < sc->body_count; ++i) {
    double ha;
    const size_t na = body_points(sim, i, &a, &acap, &ha);
    if (!na) continue;
    /* inside a collider acting at t = 0 */
    for (int c = 0; c < sim->collider_count; ++c) {
      const mpm_collider_desc *cd = &sim->colliders[c].desc;
      /* a sticky collider holding material is a grip (Zhu's bars): meant */
      if (!(0 >= cd->active[0] && 0 < cd->active[1]) || cd->rule == MPM_BOUNDARY_STICKY) continue;
      const mpm_collider_pose pose = mpm_collider_pose_at(&sim->colliders[c], 0);
      size_t inside = 0;
      for (size_t k = 0; k < na; ++k) {
        const mpm_real x[3] = {a[3 * k], a[3 * k + 1], a[3 * k + 2]}, *xp = x;
        mpm_real nrm[3];
        inside += mpm_collider_phi(&pose, xp, nrm) < 0;
      }
      if (inside)
        SAY("bodies[%d] (\"%s\"): %zu of its %zu particles start inside colliders[%d] (\"%s\"); "
            "they are pushed out in the first steps. Move the body or the collider\n",
            i, sc->bodies[i].name, inside, na, c, cd->name);
    }
    /* overlapping a later body: a particle of body j in a cell of body i's lattice that holds
     * one of i's particles */
    for (int j = i + 1; j < sc->body_count; ++j) {
      double hb;
      const size_t nb = body_points(sim, j, &b, &bcap, &hb);
      if (!nb) continue;
      const double h = ha; /* body i's particle spacing; its lattice is offset by half of it */
      const double o[3] = {sc->box_min[0], sc->box_min[1], sc->box_min[2]};
      uint64_t *grown = mpm_realloc(keys, na * sizeof *keys);
      if (!grown) break;
      keys = grown;
      for (size_t k = 0; k < na; ++k) keys[k] = cell_key(a + 3 * k, o, h);
      qsort(keys, na, sizeof *keys, cmp_u64);
      size_t shared = 0;
      for (size_t k = 0; k < nb; ++k) {
        const uint64_t q = cell_key(b + 3 * k, o, h);
        shared += bsearch(&q, keys, na, sizeof *keys, cmp_u64) != NULL;
      }
      if (shared)
        SAY("bodies[%d] (\"%s\") and bodies[%d] (\"%s\") overlap: %zu particles of the second lie "
            "in the first's material, which is twice as dense there. Move them apart\n",
            i, sc->bodies[i].name, j, sc->bodies[j].name, shared);
    }
  }
#undef SAY
  mpm_free(a);
  mpm_free(b);
  mpm_free(keys);
  return found;
}
