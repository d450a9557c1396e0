/* embed.c - embedded surface meshes (see embed.h). */
#include "domain/embed.h"
#include "domain/lattice_map.h"
#include "core/alloc.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

mpm_status mpm_embed_surface(mpm_embedded_surface *e, int body, mpm_mesh *mesh,
                             const mpm_domain_set *s, size_t first, const double origin[3],
                             double h, mpm_error *err) {
  memset(e, 0, sizeof *e);
  const size_t n = s->particles.count - first;
  if (!n) return mpm_error_set(err, MPM_ERR_INVALID, "no domain to embed the surface in");
  mpm_lattice_map m; /* lattice cell -> domain particle */
  const int nv = mesh->vertex_count;
  e->domain = mpm_alloc((size_t)(nv ? nv : 1) * sizeof *e->domain);
  e->xi = mpm_alloc((size_t)(nv ? nv : 1) * sizeof *e->xi);
  e->rest = mpm_alloc((size_t)(nv ? nv : 1) * sizeof *e->rest);
  if (mpm_lattice_map_init(&m, n) || !e->domain || !e->xi || !e->rest) {
    mpm_lattice_map_free(&m);
    mpm_embedded_surface_free(e);
    return mpm_error_set(err, MPM_ERR_NOMEM, "out of memory embedding a surface mesh");
  }
  /* the particles' cells: from their reference positions, the centres of their corners */
  for (size_t q = first; q < s->particles.count; ++q) {
    int64_t k[3];
    for (int d = 0; d < 3; ++d) {
      double c = 0;
      for (int a = 0; a < MPM_HEX_CORNERS; ++a) c += s->cX[d][s->corner[q][a]];
      k[d] = (int64_t)floor((c / MPM_HEX_CORNERS - origin[d]) / h);
    }
    const uint64_t key = mpm_lattice_key(k);
    const size_t i = mpm_lattice_map_slot(&m, key);
    m.keys[i] = key;
    m.values[i] = (uint32_t)q;
  }
  for (int v = 0; v < nv; ++v) {
    const double *X = mesh->vertices + 3 * v;
    int64_t k[3];
    for (int d = 0; d < 3; ++d) k[d] = (int64_t)floor((X[d] - origin[d]) / h);
    /* the domain containing the vertex, else the nearest one in growing shells of cells */
    long best = -1;
    double best_d2 = INFINITY;
    for (int r = 0; r <= 3 && best < 0; ++r)
      for (int64_t a = -r; a <= r; ++a)
        for (int64_t b = -r; b <= r; ++b)
          for (int64_t c = -r; c <= r; ++c) {
            if (llabs(a) != r && llabs(b) != r && llabs(c) != r) continue; /* the shell only */
            const int64_t kk[3] = {k[0] + a, k[1] + b, k[2] + c};
            const uint64_t key = mpm_lattice_key(kk);
            const size_t i = mpm_lattice_map_slot(&m, key);
            if (m.keys[i] != key) continue;
            double d2 = 0;
            for (int d = 0; d < 3; ++d) {
              const double cd = origin[d] + ((double)kk[d] + 0.5) * h - X[d];
              d2 += cd * cd;
            }
            if (d2 < best_d2) {
              best_d2 = d2;
              best = m.values[i];
            }
          }
    if (best < 0) {
      mpm_lattice_map_free(&m);
      mpm_embedded_surface_free(e);
      return mpm_error_set(err, MPM_ERR_INVALID,
                           "surface vertex %d at (%g, %g, %g) is more than 3 lattice cells from "
                           "every particle domain of its body",
                           v, X[0], X[1], X[2]);
    }
    e->domain[v] = (uint32_t)best;
    for (int d = 0; d < 3; ++d) {
      /* the reference hexahedron is the lattice cube [X_0, X_0 + h]: xi = 2 (X - X_0) / h - 1 */
      const double lo = s->cX[d][s->corner[best][0]];
      e->xi[v][d] = 2 * (X[d] - lo) / h - 1;
      e->rest[v][d] = X[d];
    }
  }
  mpm_lattice_map_free(&m);
  e->body = body;
  e->vertex_count = nv;
  e->triangle_count = mesh->triangle_count;
  e->triangles = mesh->triangles; /* taken over */
  mesh->triangles = NULL;
  mesh->triangle_count = 0;
  return MPM_OK;
}

void mpm_embedded_positions(const mpm_embedded_surface *e, const mpm_domain_set *s, double *x) {
#pragma omp parallel for schedule(static)
  for (int v = 0; v < e->vertex_count; ++v) {
    double N[MPM_HEX_CORNERS], dN[MPM_HEX_CORNERS][3];
    mpm_hex_shape(e->xi[v], N, dN);
    const uint32_t q = e->domain[v];
    double p[3] = {0, 0, 0};
    for (int a = 0; a < MPM_HEX_CORNERS; ++a)
      for (int d = 0; d < 3; ++d) p[d] += N[a] * (double)s->cx[d][s->corner[q][a]];
    for (int d = 0; d < 3; ++d) x[3 * v + d] = p[d];
  }
}

void mpm_embedded_surface_free(mpm_embedded_surface *e) {
  mpm_free(e->triangles); /* the mesh loader's allocation (core/alloc.h) */
  mpm_free(e->domain);
  mpm_free(e->xi);
  mpm_free(e->rest);
  memset(e, 0, sizeof *e);
}
