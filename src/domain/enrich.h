/* enrich.h - Zhu et al. 2017's dynamic enrichment (sec. 5): domain corners that become
 * degrees of freedom of their own when their particles are badly deformed.
 *
 * At the start of every step each active domain particle p evaluates the enrichment metric
 * (eq. 10) on its clamped deformation gradient (sec. 5.3); when K(F_p) <= epsilon (the body's
 * `enrichment` key) all 8 of its corners are marked enriched. A particle is then
 *   enriched       all its corners are enriched,
 *   transitional   some are,
 *   unenriched     none is (sec. 5.2, Fig. 3).
 *
 * An enriched corner is a DOF of the DOF set (grid/dofs.h, a corner segment after the grid
 * levels: eq. 12's set {i, alpha-hat}) and its row of the corner embedding is the identity: the
 * two-step rasterization stops there (the corner's mass, momentum and force, rasterized from
 * its particles with omega_ap and the reference-gradient averages, go to its own DOF), the DOF
 * is updated by the same explicit update or solved in the same implicit system as the grid
 * nodes, and interpolation back (eq. 11) takes the corner's own velocity. Everything else
 * in domain_transfer.c and domain_hessian.c is unchanged, because it goes through the
 * embedding. A corner that is no longer marked returns to its grid row the next step.
 *
 * The metric. The paper calls K "the reciprocal of the condition number" of F, a value in
 * (0, 1] with greater values for better conditioned F, and enriches below epsilon = 0.6; eq. 10
 * writes it K = 1 / (||F^-1||_F ||F||_F), but with Frobenius norms in 3D ||F^-1||_F ||F||_F >= 3
 * (equality for F = s R), so that literal formula is at most 1/3 and would enrich every
 * particle at rest. Two readings, per body (bodies[].enrichment_metric):
 *   condition (default)  K(F) = sigma_min / sigma_max, the reciprocal of the 2-norm condition
 *                        number: 0.67 for a uniaxial stretch of 1.5, 0.33 for a stretch of 3;
 *   frobenius            K(F) = 3 / (||F^-1||_F ||F||_F), normalized so that K(s R) = 1: 0.93
 *                        for a stretch of 1.5, 0.62 for 3 or a compression to 1/3.
 * F is clamped first (sec. 5.3): its signed singular values below the material's min_stretch c
 * are raised to c, so that flat and inverted particles get a small finite K. An enriched
 * particle stays enriched while K <= the body's exit threshold (bodies[].enrichment_exit >=
 * epsilon), and, with a wait (bodies[].enrichment_exit_wait), until it has been relaxed for that
 * long in a row (a flag counts the relaxed steps: 1 + the count, at most 255): the flags are
 * state.
 *
 * Bending the metric does not see (beyond Zhu; bodies[].enrichment_hourglass). A domain has one
 * quadrature point, so K(F) sees only its hexahedron's average gradient. A layer one domain
 * thick (a bunny's ear) bends through its hexahedra's hourglass modes while its particles' F
 * stay rotations (K = 1): no threshold on K enriches it. While the grid carries its corners
 * (8 nodes per cell for 27 corners) it can add such a sub-cell shape but not take it away, so
 * the bend stays in the body at rest (measured on examples/zhu/bunny_tunnel_squeeze.json: an
 * unenriched ear 0.13 m out of place at rest, 1.9e-4 of the diagonal). A body's bend threshold
 * enriches a particle also when the hourglass strain of its hexahedron,
 *   gamma = max_alpha |q_alpha| / (4 h),   q_alpha = sum_a h_alpha,a x_a   (below),
 * reaches it: gamma is the bending strain at the faces of a cube of side h bent by the pattern
 * u = d xi eta (q = 8 d, strain 2 d / h), zero for every affine motion. Such a particle stays
 * enriched while K <= exit_k, gamma >= the threshold or gamma >= 1 - exit_k: it returns to the
 * grid only with its bend within the strain its stretch must be within, and keeps the bend it
 * had then (a plate one domain thick, bent and released: tests/test_enrich_bend.c).
 *
 * The explicit time step. Grid nodes are dx apart whatever the material does, but enriched
 * corners are the material's own nodes: h apart at rest, h sigma_min apart in a compressed
 * particle, whose stiffness also grows (like 1/sigma_min^2 for neo-Hookean). The marks give
 * the bound dt <= cfl h s^2 / c, s = min(sigma_min, 1) with sigma_min clamped as above, over
 * the particles that touch an enriched corner (e->rate); the implicit step needs none. */
#ifndef MPM_DOMAIN_ENRICH_H
#define MPM_DOMAIN_ENRICH_H

#include "mpm/mpm.h"
#include "domain/domain.h"
#include "material/material.h"

enum { MPM_DOMAIN_UNENRICHED = 0, MPM_DOMAIN_TRANSITIONAL = 1, MPM_DOMAIN_ENRICHED = 2 };

/* The metric's two readings (the scene's bodies[].enrichment_metric, scene.h's values). */
enum { MPM_ENRICHMENT_CONDITION = 0, MPM_ENRICHMENT_FROBENIUS = 1 };

/* K(F) = 3 / (||F^-1||_F ||F||_F) as above, singular values clamped at c > 0. */
mpm_real mpm_enrichment_metric(const mpm_real F[9], mpm_real c);

/* K(F) = sigma_min / sigma_max, the reciprocal of the (2-norm) condition number, singular
 * values clamped at c > 0 (signed: an inverted direction counts as c). */
mpm_real mpm_enrichment_condition(const mpm_real F[9], mpm_real c);

/* Mark the corners and classify the particles of the set from their current F (materials: the
 * clamp of each particle's material; s->enrich.body[b].epsilon), and list the enriched
 * corners in corner order with their positions (the DOF segment's). Deterministic, parallel.
 * MPM_OK, or MPM_ERR_NOMEM when out of memory. */
mpm_status mpm_domain_mark_enrichment(mpm_domain_set *s, const mpm_material *materials);

/* Body b's settings: all 0 (never enriched, the condition metric) for a body without any. */
static inline const mpm_enrichment_body *mpm_enrichment_body_of(const mpm_domain_enrichment *e,
                                                                int b) {
  static const mpm_enrichment_body none = {0, 0, 0, 0, MPM_ENRICHMENT_CONDITION, 0, 0, 0, 0, 0};
  return b >= 0 && b < e->body_count ? &e->body[b] : &none;
}

/* The threshold of body b (0: never enriched). */
static inline mpm_real mpm_enrichment_epsilon(const mpm_domain_set *s, int b) {
  return mpm_enrichment_body_of(&s->enrich, b)->epsilon;
}

/* Set body b's settings (sim setup): the threshold epsilon, the exit threshold (an enriched
 * particle stays enriched while K <= exit_k; raised to epsilon when below), the bend threshold,
 * the metric (MPM_ENRICHMENT_*), hourglass control on every particle (hourglass_all, below)
 * and the lattice spacing h. MPM_OK; MPM_ERR_NOMEM when out of memory; MPM_ERR_INVALID for a
 * negative b. */
mpm_status mpm_enrichment_set_body(mpm_domain_set *s, int b, mpm_enrichment_body settings);

/* The hourglass strain gamma = max_alpha |q_alpha| / (4 h) of particle q's hexahedron at its
 * corners' current positions (above; h: the body's lattice spacing). */
mpm_real mpm_enrichment_hourglass_strain(const mpm_domain_set *s, size_t q, mpm_real h);

/* Move the per-body settings (mpm_enrichment_set_body's: thresholds, metrics, hourglass
 * control, spacings) from `from` to `to`, freeing those `to` held; `from` is left without any.
 * The marks stay where they are (a resumed state keeps the scene's settings). */
void mpm_enrichment_move_settings(mpm_domain_enrichment *to, mpm_domain_enrichment *from);

void mpm_enrichment_free(mpm_domain_enrichment *e);

/* Room for the marks of `particles` particles and `corners` corners; the flags already held
 * are kept (checkpoint reading fills them). MPM_OK, or MPM_ERR_NOMEM when out of memory. */
mpm_status mpm_enrichment_reserve(mpm_domain_enrichment *e, size_t particles, size_t corners);

/* Hourglass control of enriched domains (beyond Zhu: a domain has one quadrature point, its
 * particle, so the four hourglass modes of its hexahedron cost no energy; the grid's smooth
 * field keeps them small while it carries the corners, enriched corners are free).
 * Flanagan and Belytschko 1981, stiffness form, on the reference lattice cube (where the
 * hourglass vectors h_alpha are orthogonal to every linear field, so gamma = h): with
 *   q_alpha = sum_a h_alpha,a x_a   (m; zero for every affine motion, rotations included),
 *   E_hg = 1/2 kappa sum_alpha |q_alpha|^2,  kappa = E h / 48 (N/m, E Young's modulus),
 *   f_a  = -kappa sum_alpha h_alpha,a q_alpha,
 * an hourglass pattern of corner amplitude d (q = 8 d) costs 32 kappa d^2 = (2/3) E h d^2:
 * what linear elasticity gives a cube of side h bent by the pattern u_x = d xi eta (a one-domain
 * layer bent, e.g. a thin ear: the strain 2 d eta / h along x in uniaxial stress, averaged over
 * the cube). The warping pattern u_z = d xi eta costs (4/3) mu h d^2 there and xi eta zeta
 * (2/9)(lambda + 4 mu) h d^2, 1.3 and 1.4 times less at nu = 0.3: one kappa for all modes
 * errs on the stiff side for those two so that bending is right. (mu h / 80, a quarter of the
 * bending stiffness, left the bunnies' enriched ears bent for good: docs/zhu-table1.md.)
 * Applied to the particles that touch an enriched corner (category other than unenriched), so
 * the unenriched path is unchanged; with the body's `hourglass: "all"` to every particle: the
 * grid moves the corners of an unenriched layer one domain thick too, bends it without the
 * single quadrature point seeing the strain, and the energy is the same (through the corners'
 * embedding, E^T f to the grid nodes). */
extern const mpm_real mpm_hourglass_modes[4][MPM_HEX_CORNERS];

/* Whether some particle has hourglass control this step. */
static inline int mpm_hourglass_on(const mpm_domain_set *s) {
  return s->enrich.count > 0 || s->enrich.hourglass_any;
}

/* kappa of particle q (0 for inactive particles, and for unenriched ones unless their body's
 * hourglass control is on every particle). */
mpm_real mpm_hourglass_kappa(const mpm_domain_set *s, const mpm_material *materials, size_t q);

/* q_alpha of particle q from per-corner values v[3] (positions or displacements). Each h_alpha
 * sums to 0, so corner 0's values are taken off first: the same q in exact arithmetic, and the
 * sums of positions far from the origin round at the domain's size, not at the positions'. */
static inline void mpm_hourglass_q(const mpm_domain_set *s, size_t q, mpm_real *const v[3],
                                   mpm_real out[4][3]) {
  const uint32_t c0 = s->corner[q][0];
  const mpm_real ref[3] = {v[0][c0], v[1][c0], v[2][c0]};
  for (int al = 0; al < 4; ++al) {
    out[al][0] = out[al][1] = out[al][2] = 0;
    for (int a = 1; a < MPM_HEX_CORNERS; ++a) {
      const uint32_t c = s->corner[q][a];
      const mpm_real w = mpm_hourglass_modes[al][a];
      for (int d = 0; d < 3; ++d) out[al][d] += w * (v[d][c] - ref[d]);
    }
  }
}

#endif
