/* embed.h - triangle meshes embedded in particle domains (Zhu et al. 2017, sec. 4.1): a body
 * made from a mesh keeps it, every vertex is tied to one domain by its trilinear coordinates
 * in the domain's reference hexahedron, and the deformed surface is interpolated from the
 * domain's corners each frame, x = sum_a N_a(xi) x_a, for rendering (the frame writer writes
 * it as OBJ, PLY and VTP: io/triangle_mesh.h).
 *
 * A vertex inside a domain gets xi in [-1, 1]^3. Surface vertices often lie in lattice cells
 * whose centre (hence particle) is outside the mesh; they are tied to the nearest domain of
 * the body and extrapolated with the same trilinear map (|xi| slightly above 1), which moves
 * them rigidly and with the stretch of that domain. */
#ifndef MPM_DOMAIN_EMBED_H
#define MPM_DOMAIN_EMBED_H

#include "domain/domain.h"
#include "core/mesh.h"

typedef struct mpm_embedded_surface {
  int body;
  int vertex_count, triangle_count;
  int *triangles;    /* 3 zero-based vertex indices per triangle */
  uint32_t *domain;  /* the domain particle (index in the domain set) of each vertex */
  double (*xi)[3];   /* the vertex's reference coordinates in that domain's hexahedron */
  double (*rest)[3]; /* rest position, m */
} mpm_embedded_surface;

/* Embed `mesh` (world coordinates; the surface takes its triangles over) in the domain
 * particles [first, s->particles.count) of the set, which lie on the lattice of spacing h
 * with points origin + (k + 1/2) h. */
mpm_status mpm_embed_surface(mpm_embedded_surface *e, int body, mpm_mesh *mesh,
                             const mpm_domain_set *s, size_t first, const double origin[3],
                             double h, mpm_error *err);

/* Current vertex positions (3 per vertex) from the domains' corners. */
void mpm_embedded_positions(const mpm_embedded_surface *e, const mpm_domain_set *s, double *x);

void mpm_embedded_surface_free(mpm_embedded_surface *e);

#endif
