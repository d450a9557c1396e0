/* domain.h - Zhu et al. 2017's particle domains (sec. 4): every particle of a domain body owns
 * a hexahedron whose 8 corners it shares with its lattice neighbours, and talks to the grid
 * only through those corners.
 *
 * The domain particles are kept apart from the standard material points (their own
 * mpm_particles, never reordered, so that corner connectivity stays put) and carry the same
 * state: position, velocity, F, plastic state, mass, V0, material, body, id. Corners are
 * first-class data with their own positions and velocities: an enriched corner is a DOF of its
 * own in the DOF set (enrich.h), which the implicit solve takes like a grid node.
 *
 * Per particle, precomputed in the reference configuration by Gauss quadrature:
 *   w[p][a] = omega_ap = (1/V_p^0) int N_a dOmega                        (Zhu eq. 6)
 *   g[p][a] = (1/V_p^0) int grad_X N_a dOmega, so that
 *             grad_X omega_ip = sum_a omega_i(x_a) g[p][a]               (Zhu eq. 5)
 * A particle switched off (Zhu sec. 7, topology change) leaves the set: it is copied into the
 * standard particles, and its slot stays as an inactive entry whose corners it no longer
 * touches. */
#ifndef MPM_DOMAIN_DOMAIN_H
#define MPM_DOMAIN_DOMAIN_H

#include "core/arena.h"
#include "core/error.h"
#include "core/particles.h"
#include "domain/corner_pads.h"
#include "domain/hex.h"
#include "grid/embedding.h"

#include <stdint.h>

/* A body's enrichment settings (the scene's; all 0 for a body without them). */
typedef struct mpm_enrichment_body {
  mpm_real epsilon;    /* enriched when K(F) <= epsilon (0: never) */
  mpm_real exit_k;     /* an enriched particle stays enriched while K(F) <= exit_k (>= epsilon:
                          hysteresis) */
  mpm_real spacing;    /* the domain lattice's spacing h, m */
  mpm_real bend;       /* also enriched when the hourglass strain of the particle's hexahedron
                          (mpm_enrichment_hourglass_strain) is >= bend (0: never; beyond Zhu) */
  int metric;          /* MPM_ENRICHMENT_CONDITION or _FROBENIUS (domain/enrich.h) */
  int hourglass_all;   /* hourglass control on every particle, not only on those touching an
                          enriched corner (domain/enrich.h) */
  int contact;         /* its enriched corners meet other material on the grid
                          (domain/enrich_contact.h) */
  int surface_contact; /* its enriched surface meets other bodies' enriched surfaces
                          (domain/enrich_surface_contact.h) */
  int self_contact;    /* ... and its own enriched surface elsewhere */
  double exit_wait;    /* seconds an enriched particle stays relaxed (K(F) > exit_k, its bend
                          below 1 - exit_k where bend > 0) before it returns (0: at once) */
} mpm_enrichment_body;

/* Dynamic enrichment (Zhu sec. 5, domain/enrich.h): the marks of one step. */
typedef struct mpm_domain_enrichment {
  mpm_enrichment_body *body; /* per body */
  int body_count;
  int any;             /* some body has epsilon > 0 or bend > 0 */
  int hourglass_any;   /* some body has hourglass_all */
  uint8_t *flag;       /* per particle: 0 not enriched this step; 1 + the steps it has been
                          relaxed in a row when enriched (domain/enrich.h: the exit's wait, at
                          most 254): state, kept in checkpoints */
  double step_dt;      /* the step the flags' wait counts in (the last step's), s */
  uint8_t *category;   /* per particle: MPM_DOMAIN_UNENRICHED / TRANSITIONAL / ENRICHED */
  uint8_t *enriched;   /* per corner: 1 when it is a DOF of its own this step */
  uint8_t *on_grid;    /* per corner: used and not enriched (it is embedded in the grid) */
  uint32_t *corner;    /* the enriched corners in corner order: k -> corner */
  uint32_t *slot;      /* per enriched corner c: its k (other corners: unspecified) */
  mpm_real *x[3];      /* their positions, in that order (the DOF segment's) */
  size_t count;        /* enriched corners */
  size_t dof_begin;    /* the DOF index of enriched corner 0 (set by the layout) */
  size_t particles[3]; /* active particles per category */
  /* the explicit step's bound from the enriched corners: max over particles with an enriched
   * corner of c / (h s^2), s = min(sigma_min(F), 1) (1/s: the corners are h s apart, and the
   * stiffness of a compressed particle grows like 1/s^2), 1/s; dt <= cfl / rate */
  double rate;
  size_t particle_capacity, corner_capacity;
  /* the marks are those of the state at the start of step `marked_step` (valid: 1); a rebuild
   * of the set (releases) makes them stale */
  int valid;
  long long marked_step;
} mpm_domain_enrichment;

typedef struct mpm_domain_set {
  mpm_particles particles;             /* the domain particles */
  uint32_t (*corner)[MPM_HEX_CORNERS]; /* corner indices of each particle's hexahedron */
  mpm_real (*w)[MPM_HEX_CORNERS];      /* omega_ap (Zhu eq. 6) */
  mpm_real (*g)[MPM_HEX_CORNERS][3];   /* reference gradient averages (Zhu eq. 5), 1/m */
  /* per particle (set with the adjacency): g's magnitude when the hexahedron is an axis-aligned
   * cube, so that w[a] = 1/8 and g[a][d] = s_ad cube_g with s_ad = +-1 the corner's side
   * (mpm_hex_sign), bit for bit as stored; 0 otherwise. Every lattice domain is such a cube: the
   * transfers' loops take w and g from it instead of reading 32 values per particle */
  mpm_real *cube_g;
  uint8_t *active; /* 0 once switched off */
  size_t active_count;
  /* corners */
  size_t corner_count, corner_capacity;
  mpm_real *cX[3]; /* reference position, m */
  mpm_real *cx[3]; /* current position, m */
  /* what the rounded cx could not hold of the position (compensated summation of the steps'
   * moves, Kahan): a body drifting slowly does not round differently on either side of a
   * power of two in float (issue 13) */
  mpm_real *cxc[3];
  mpm_real *cv[3]; /* velocity, m/s (hybrid PIC/FLIP of the grid's, or APIC's grid velocity) */
  /* APIC (solver.transfer "apic"): the corner's affine moment from the grid, B_a = sum_i
   * omega_i(x_a) v_i (x_i - x_a)^T (Jiang et al. 2015 at the corner -> grid step), m^2/s,
   * row-major; 0 for enriched corners (their own DOF: no grid stencil) */
  mpm_real *cB[9];
  /* per step: rasterized mass, momentum and force (the grid's velocity at the corner, v^g, is
   * in corner_pack: nothing else reads it) */
  mpm_real *cm, *cp[3], *cf[3];
  /* corner -> particle slots (p * 8 + a), CSR, for race-free particle -> corner gathers */
  uint32_t *adj_start, *adj;
  uint8_t *corner_use; /* 1 when an active particle uses the corner (it takes part in steps) */
  /* the corner's mass m_a = sum_p omega_ap m_p over its particle slots in slot order, in double
   * (made with the adjacency: the particles' masses and weights stay put between rebuilds), so
   * that P2G need not sum it every step */
  double *cmass;
  /* per step: the embedding of the corners in the grid (Zhu eqs. 2-3: row a holds the grid
   * nodes of corner a's stencil and their weights omega_i(x_a); rows of unused corners are
   * empty), and its scatter schedule: corners keyed by base block, blocks coloured by parity */
  mpm_embedding corner_grid;
  /* per step, with APIC (step scratch, set by P2G for G2P): per entry e of corner_grid the
   * APIC factor a_e = D_a^-1 omega_i(x_a) (x_i - x_a), 1/m, and per corner D_a's diagonal, m^2
   * (interp/kernel.h) */
  mpm_real *apic_a[3], *apic_d[3];
  /* per step (step scratch, set by P2G for G2P): each corner's new position, velocity and grid
   * velocity v^g (the grid's PIC velocity at the corner, which moved it) side by side (x at 0,
   * v at 3, v^g at 6; one row more, zeroed), written by G2P's corner half (corner_motion.h)
   * for its particle loop, which reads 8 corners per particle: one or two cache lines each
   * instead of nine arrays', each vector in one load of 4 lanes (the fourth unused) */
  mpm_real (*corner_pack)[9];
  /* set by the step: 1 when it applies the corners' embedding as a matrix (the implicit
   * Hessian, domain_hessian.c), so that P2G builds corner_grid's rows; else on the sparse grid
   * the corner transfers go through pads (domain/corner_pads.h) and corner_grid is empty */
  int corner_rows;
  mpm_corner_pads pads;
  mpm_domain_enrichment enrich;
} mpm_domain_set;

void mpm_domain_set_init(mpm_domain_set *s);
void mpm_domain_set_free(mpm_domain_set *s);

/* An empty set with room for, and counts of, `particles` domain particles and `corners`
 * corners, their values to be filled in (checkpoint reading); call mpm_domain_set_rebuild
 * after filling corner and active. MPM_OK, or MPM_ERR_NOMEM when out of memory. */
mpm_status mpm_domain_set_alloc(mpm_domain_set *s, size_t particles, size_t corners);

/* g_qa (Zhu eq. 5): from the cube's pattern into gc when particle q's hexahedron is a cube
 * (cube_g; then w_qa = 1/8), else the stored one. The same values either way, bit for bit; the
 * returned pointer is gc exactly when the pattern was used. */
static inline const mpm_real *mpm_domain_gradient(const mpm_domain_set *s, uint32_t q, uint32_t a,
                                                  mpm_real gc[3]) {
  const mpm_real m = s->cube_g[q];
  if (m == 0) return s->g[q][a];
  for (int d = 0; d < 3; ++d) gc[d] = (a >> d) & 1 ? m : -m;
  return gc;
}

/* The body of corner c (its first particle's: a lattice is one body's); -1 for a corner no
 * particle uses. */
static inline int mpm_domain_corner_body(const mpm_domain_set *s, size_t c) {
  if (s->adj_start[c] == s->adj_start[c + 1]) return -1;
  return s->particles.body[s->adj[s->adj_start[c]] / MPM_HEX_CORNERS];
}
/* omega_ap and the reference gradient averages of the hexahedron with reference corners X
 * (in corner order, hex.h), by 2x2x2 Gauss quadrature (exact for trilinear hexahedra), and
 * its volume. MPM_OK, or MPM_ERR_INVALID when the hexahedron is inverted or flat at a quadrature
 * point. */
mpm_status mpm_domain_weights(const double X[MPM_HEX_CORNERS][3], double w[MPM_HEX_CORNERS],
                              double g[MPM_HEX_CORNERS][3], double *volume);

/* Fragments (beyond Zhu): where a body is thinner than the lattice spacing, sampling can leave
 * a few particles whose cells touch the rest only along an edge or at a corner. Such a domain
 * turns about its shared edge or corner at no cost once its corners are enriched (measured:
 * the straw's rabbit, two fragments of 1 and 2 of its 919 particles swung 0.3 to 1 m off the
 * ears and made 0.3 of its rest-state error). Face-connected components of the lattice cells
 * with fewer particles than this are dropped when the domains are made, unless the component is
 * the body's largest. */
#define MPM_DOMAIN_MIN_FRAGMENT 8

/* Turn particles [first, p->count) of p, which must lie on a lattice of spacing h whose points
 * are lattice_origin + (k + 1/2) h (the body sampler's, without jitter), into domain
 * particles: they are moved out of p into s (fragments, above, are dropped), each gets the
 * lattice cell around it as its hexahedron, and corners are shared between neighbours. Errors
 * name the body. */
mpm_status mpm_domain_set_add_lattice(mpm_domain_set *s, mpm_particles *p, size_t first,
                                      const double lattice_origin[3], double h,
                                      const char *body_name, mpm_error *err);

/* Position and velocity of every active domain particle from its corners:
 * x_p = sum_a omega_ap x_a, v_p = sum_a omega_ap v_a (Zhu sec. 4). */
void mpm_domain_set_sync_particles(mpm_domain_set *s);

/* Switch the domain of particle i off: its state is appended to `to` as a standard material
 * point (APIC affine moment zero) and the slot becomes inactive. MPM_OK, or MPM_ERR_NOMEM when
 * out of memory. Call mpm_domain_set_rebuild once after a batch of releases. */
mpm_status mpm_domain_set_release(mpm_domain_set *s, size_t i, mpm_particles *to);

/* Renumber the corners: corner order[k] becomes corner k (order: a permutation of the corner
 * indices). Every corner array, the particles' corner indices, the adjacency and this step's
 * enrichment marks follow. The transfers take the same terms, and results change only by
 * rounding: the sums over a corner's particles and over a cell's corners go in the new order.
 * The step keeps the corners in the order of its grid blocks with it (domain_transfer.h,
 * mpm_domain_order_corners). Its scratch comes from `scratch`.
 * MPM_OK, or MPM_ERR_NOMEM when out of memory (nothing changed then). */
mpm_status mpm_domain_set_permute_corners(mpm_domain_set *s, const uint32_t *order,
                                          mpm_arena *scratch);

/* a[k] = a[order[k]] for n elements of `size` bytes (1, 4 or 8) through tmp (n elements): the
 * renumbering of one corner array, for copies of corner values held elsewhere. */
void mpm_domain_permute_values(void *a, void *tmp, size_t size, const uint32_t *order, size_t n);

/* Rebuild the corner adjacency over the active particles. MPM_OK, or MPM_ERR_NOMEM when out of
 * memory. */
mpm_status mpm_domain_set_rebuild(mpm_domain_set *s);

#endif
