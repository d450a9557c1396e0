/* enrich_contact.h - enriched corners meet other material on the grid: material points and
 * other bodies' unenriched corners (beyond Zhu et al. 2017, whose sec. 8 leaves contact of
 * enriched parts out).
 *
 * Why: an enriched corner is a DOF of its own (domain/enrich.h): its particles give their mass
 * and forces to it, not to the grid, so another body's material on the grid does not see the
 * enriched part at all and passes into it (measured on examples/zhu/bunny_hit_by_ball.json with
 * the bend threshold: the ball sank into the bunny and stayed there, docs/zhu-table1.md).
 *
 * What: after the velocity update (explicit or implicit), before G2P, every enriched corner of a
 * body with `enrichment_contact` looks at the grid around it (the corner kernel's stencil at its
 * position). Of the grid's mass, the part other material gave, m_o (the nodes' mass less what
 * the body's own unenriched corners rasterized: material points and other domain bodies),
 * says where it is: its kernel-weighted sum at the corner, and its gradient n (unit, pointing
 * into that material). The grid's
 * velocity there is v_g = sum_i w_i m_i v_i / M, M = sum_i w_i m_i. A corner that approaches
 * it, (v_c - v_g) . n > 0, and the grid take the impulse that brings their normal velocities
 * together, as two bodies in a slip contact of reduced mass mu = m_c M / (m_c + M):
 *   j = mu (v_c - v_g) . n,   v_c -= (j / m_c) n,   v_i += (j w_i / M) n   (i in the stencil),
 * so that sum_i m_i dv_i = j n: linear momentum is conserved exactly (up to rounding), and the
 * tangential velocities are left alone. Body by body, the corners touch the grid one after the
 * other within tiles of the grid, the tiles of a colour in parallel (core/tile_batches.h): the
 * order, and so the result, does not depend on the thread count. The body's
 * own corners' mass on the grid comes from the embedding's rows, which the step then builds
 * (s->corner_rows). Enriched parts meeting each other (of two bodies, or of one) are not on the
 * grid: domain/enrich_surface_contact.h meets them. */
#ifndef MPM_DOMAIN_ENRICH_CONTACT_H
#define MPM_DOMAIN_ENRICH_CONTACT_H

#include "mpm/mpm.h"
#include "core/arena.h"
#include "domain/domain.h"
#include "grid/grid.h"

/* Whether some body's enriched corners meet other material (and some corner is enriched). */
int mpm_enrich_contact_on(const mpm_domain_set *s);

/* The contacts of this step (above): dofs holds every DOF's mass and its velocity after the
 * update (v), count the DOFs; g and k the grid level and the corner kernel. *contacts: the
 * corners that took an impulse. MPM_OK, or MPM_ERR_NOMEM when out of memory. */
mpm_status mpm_enrich_contact(const mpm_domain_set *s, const mpm_grid *g, const mpm_kernel *k,
                              const mpm_grid_values *dofs, size_t count, mpm_arena *scratch,
                              size_t *contacts);

#endif
