/* enrich_surface_contact.h - enriched parts meet enriched parts: the enriched corners on a
 * body's surface against the enriched faces of other bodies' surfaces and of their own body's
 * surface elsewhere (self-contact; beyond Zhu et al. 2017, whose sec. 8 leaves contact of
 * enriched parts out).
 *
 * Why: an enriched corner is a DOF of its own (domain/enrich.h), off the grid, so two enriched
 * parts never meet on the grid: two bodies whose domains are all enriched pass through each
 * other, and a body folding onto itself (the roller's ear at 27 particles per cell,
 * docs/zhu-table1.md) passes through itself. enrich_contact.h covers an enriched corner meeting
 * material that is on the grid; this covers the rest.
 *
 * What: after the velocity update (explicit or implicit), before G2P moves the corners, with the
 * step's dt:
 *   faces     the surface faces of the domain lattice whose four corners are enriched (a face
 *             of an active particle's hexahedron that no other active particle shares), with
 *             the outward normal of their particle;
 *   corners   the enriched corners of those faces;
 *   pairs     a corner and a face of another body, both bodies with the contact on
 *             (surface_contact), or of its own body where it has self_contact on and the
 *             face's reference centre lies more than SELF_REACH lattice spacings from the
 *             corner's reference position (nearer faces are the corner's own neighbourhood,
 *             which elasticity keeps apart), from the front only, found through a spatial hash
 *             of the faces' boxes swept over the step (cost linear in the corners);
 *   contact   the corner's closest point p on the face (its two triangles); in front of the
 *             face the gap d = |x_c - p| along n = (x_c - p) / d (a corner over an edge or a
 *             crease meets the edge); behind it, where the corner projects onto the face, d the
 *             depth along the face's outward normal n, down to -DEPTH h (never behind a face
 *             of its own body: that is mostly the body's own inside); a pair is a contact when
 *             the gap would close past the skin s (SKIN h) within the step at the current
 *             velocities: d + dt (v_c - v_p) . n < s, v_p = sum_k beta_k v_k (beta: p's
 *             barycentric weights over the triangle's three corners);
 *   impulse   each contact brings its relative normal velocity up to t = (s - d) / dt where
 *             d > s (the corner stops at the skin), t = RECOVERY (s - d) / dt within it (out
 *             by a fifth of the depth a step: a corner that slid in at an edge or a turning
 *             face comes back out), as two masses in a slip contact of reduced mass
 *             mu = 1 / (1/m_c + sum_k beta_k^2 / m_k):
 *               j = mu (t - (v_c - v_p) . n) > 0,  v_c += (j / m_c) n,  v_k -= (j beta_k / m_k) n,
 *             so linear momentum is conserved exactly (sum_k beta_k = 1), the tangential
 *             velocities are left alone, and an impulse that stops an approach lowers the
 *             kinetic energy (the relative normal speed only falls; only the slow recovery
 *             out of a skin adds any). A few Gauss-Seidel sweeps over the contacts (a
 *             corner at an edge touches two faces).
 * The faces, the hash and the pairs are found in parallel into per-corner slots; the sweeps run
 * in parallel by coloured tiles of space twice the widest contact's reach
 * (core/tile_batches.h): the order of the impulses, and so the result, does not depend on the
 * thread count. */
#ifndef MPM_DOMAIN_ENRICH_SURFACE_CONTACT_H
#define MPM_DOMAIN_ENRICH_SURFACE_CONTACT_H

#include "mpm/mpm.h"
#include "core/arena.h"
#include "domain/domain.h"
#include "grid/grid.h"

/* Whether some body's enriched surface meets enriched surfaces (its key on, and some corner
 * enriched). */
int mpm_surface_contact_on(const mpm_domain_set *s);

typedef struct mpm_surface_contact_stats {
  size_t faces;    /* enriched surface faces */
  size_t corners;  /* enriched corners on them */
  size_t contacts; /* corner-face pairs that took an impulse */
} mpm_surface_contact_stats;

/* The contacts of a step of length dt (above): dofs holds every DOF's mass and its velocity
 * after the update (v); the enriched corners' velocities are changed in place. MPM_OK, or
 * MPM_ERR_NOMEM when out of memory (scratch from `scratch`). */
mpm_status mpm_surface_contact(const mpm_domain_set *s, const mpm_grid_values *dofs, double dt,
                               mpm_arena *scratch, mpm_surface_contact_stats *stats);

#endif
