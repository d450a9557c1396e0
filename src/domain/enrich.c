/* enrich.c - the enrichment metric and the per-step marks of Zhu et al.'s dynamic enrichment
 * (see enrich.h). */
#include "domain/enrich.h"
#include "core/alloc.h"
#include "core/mat3.h"
#include "core/parallel.h"
#include "core/svd3.h"

#include <math.h>
#include <string.h>

/* corner a = (i, j, k) in bits 0, 1, 2 (hex.h), s = +-1 per bit: s_i s_j, s_j s_k, s_i s_k and
 * s_i s_j s_k, each orthogonal to 1, x, y and z over the cube's corners */
const mpm_real mpm_hourglass_modes[4][MPM_HEX_CORNERS] = {
    {1, -1, -1, 1, 1, -1, -1, 1},
    {1, 1, -1, -1, -1, -1, 1, 1},
    {1, -1, 1, -1, -1, 1, -1, 1},
    {-1, 1, 1, -1, 1, -1, -1, 1},
};

mpm_real mpm_hourglass_kappa(const mpm_domain_set *s, const mpm_material *materials, size_t q) {
  const mpm_domain_enrichment *e = &s->enrich;
  if (!s->active[q]) return 0;
  const int all = mpm_enrichment_body_of(e, s->particles.body[q])->hourglass_all;
  if (!all && (!e->count || e->category[q] == MPM_DOMAIN_UNENRICHED)) return 0;
  const mpm_real h = (mpm_real)cbrt((double)s->particles.vol0[q]);
  const mpm_material *m = &materials[s->particles.material[q]];
  /* Young's modulus from the Lame parameters (0 while a strength schedule zeroes them) */
  const double E = mpm_young_from_lame((double)m->mu, (double)m->lambda);
  return (mpm_real)(E * (double)h / 48);
}

mpm_real mpm_enrichment_hourglass_strain(const mpm_domain_set *s, size_t q, mpm_real h) {
  mpm_real qa[4][3];
  mpm_hourglass_q(s, q, s->cx, qa);
  double m2 = 0;
  for (int al = 0; al < 4; ++al) {
    double n2 = 0;
    for (int d = 0; d < 3; ++d) n2 += (double)qa[al][d] * (double)qa[al][d];
    m2 = n2 > m2 ? n2 : m2;
  }
  return (mpm_real)(sqrt(m2) / (4 * (double)h));
}

mpm_real mpm_enrichment_metric(const mpm_real F[9], mpm_real c) {
  const double J = (double)mpm_m3_det(F), f2 = (double)mpm_m3_ddot(F, F);
  /* sigma_min >= 2 J / ||F||^2 (sigma_1 sigma_2 <= ||F||^2 / 2): when that is >= c no singular
   * value is clamped and ||F^-1||_F = ||cof F||_F / J needs no SVD */
  if (J > 0 && 2 * J >= (double)c * f2) {
    mpm_real C[9];
    mpm_m3_cofactor(F, C);
    const double c2 = (double)mpm_m3_ddot(C, C);
    return (mpm_real)(3 * J / sqrt(f2 * c2));
  }
  mpm_real U[9], sigma[3], V[9];
  mpm_svd3(F, U, sigma, V);
  double a = 0, b = 0;
  for (int i = 0; i < 3; ++i) {
    const double s = sigma[i] > c ? (double)sigma[i] : (double)c; /* signed: inverted -> c */
    a += s * s;
    b += 1 / (s * s);
  }
  return (mpm_real)(3 / sqrt(a * b));
}

mpm_real mpm_enrichment_condition(const mpm_real F[9], mpm_real c) {
  mpm_real U[9], sigma[3], V[9];
  mpm_svd3(F, U, sigma, V);
  double lo = HUGE_VAL, hi = 0;
  for (int i = 0; i < 3; ++i) {
    const double s = sigma[i] > c ? (double)sigma[i] : (double)c; /* signed: inverted -> c */
    lo = s < lo ? s : lo;
    hi = s > hi ? s : hi;
  }
  return (mpm_real)(lo / hi);
}

mpm_status mpm_enrichment_set_body(mpm_domain_set *s, int b, mpm_enrichment_body settings) {
  mpm_domain_enrichment *e = &s->enrich;
  if (b < 0) return MPM_ERR_INVALID;
  if (b >= e->body_count) {
    mpm_enrichment_body *grown = mpm_alloc((size_t)(b + 1) * sizeof *grown);
    if (!grown) return MPM_ERR_NOMEM;
    memset(grown, 0, (size_t)(b + 1) * sizeof *grown);
    if (e->body_count) memcpy(grown, e->body, (size_t)e->body_count * sizeof *grown);
    mpm_free(e->body);
    e->body = grown;
    e->body_count = b + 1;
  }
  if (settings.exit_k < settings.epsilon) settings.exit_k = settings.epsilon;
  settings.hourglass_all = settings.hourglass_all != 0;
  settings.contact = settings.contact != 0;
  settings.surface_contact = settings.surface_contact != 0;
  settings.self_contact = settings.surface_contact && settings.self_contact != 0;
  if (!(settings.exit_wait > 0)) settings.exit_wait = 0;
  e->body[b] = settings;
  e->any = e->hourglass_any = 0;
  for (int k = 0; k < e->body_count; ++k) {
    if (e->body[k].epsilon > 0 || e->body[k].bend > 0) e->any = 1;
    if (e->body[k].hourglass_all) e->hourglass_any = 1;
  }
  return MPM_OK;
}

void mpm_enrichment_move_settings(mpm_domain_enrichment *to, mpm_domain_enrichment *from) {
  mpm_free(to->body);
  to->body = from->body;
  to->body_count = from->body_count;
  to->any = from->any;
  to->hourglass_any = from->hourglass_any;
  from->body = NULL;
  from->body_count = from->any = from->hourglass_any = 0;
}

void mpm_enrichment_free(mpm_domain_enrichment *e) {
  mpm_free(e->body);
  mpm_free(e->flag);
  mpm_free(e->category);
  mpm_free(e->enriched);
  mpm_free(e->on_grid);
  mpm_free(e->corner);
  mpm_free(e->slot);
  for (int d = 0; d < 3; ++d) mpm_free(e->x[d]);
  memset(e, 0, sizeof *e);
}

/* Room for the set's particles and corners (contents not kept). */
mpm_status mpm_enrichment_reserve(mpm_domain_enrichment *e, size_t particles, size_t corners) {
  if (particles > e->particle_capacity || !e->flag) {
    /* the flags are state (the hysteresis reads last step's): kept across a growth */
    uint8_t *old = e->flag;
    const size_t kept = e->particle_capacity;
    mpm_free(e->category);
    const size_t n = particles + particles / 8 + 16;
    e->flag = mpm_calloc(n, 1);
    if (e->flag && old) memcpy(e->flag, old, kept);
    mpm_free(old);
    e->category = mpm_alloc(n);
    e->particle_capacity = e->flag && e->category ? n : 0;
    if (!e->particle_capacity) return MPM_ERR_NOMEM;
  }
  if (corners > e->corner_capacity || !e->enriched) {
    mpm_free(e->enriched);
    mpm_free(e->on_grid);
    mpm_free(e->corner);
    mpm_free(e->slot);
    const size_t n = corners + corners / 8 + 16;
    e->enriched = mpm_alloc(n);
    e->on_grid = mpm_alloc(n);
    e->corner = mpm_alloc(n * sizeof *e->corner);
    e->slot = mpm_alloc(n * sizeof *e->slot);
    int ok = e->enriched && e->on_grid && e->corner && e->slot;
    for (int d = 0; d < 3; ++d) {
      mpm_free(e->x[d]);
      e->x[d] = mpm_alloc(n * sizeof(mpm_real));
      ok = ok && e->x[d];
    }
    e->corner_capacity = ok ? n : 0;
    if (!ok) return MPM_ERR_NOMEM;
  }
  return MPM_OK;
}

mpm_status mpm_domain_mark_enrichment(mpm_domain_set *s, const mpm_material *materials) {
  mpm_domain_enrichment *e = &s->enrich;
  const mpm_particles *p = &s->particles;
  const long np = (long)p->count, nc = (long)s->corner_count;
  if (mpm_enrichment_reserve(e, p->count + 1, s->corner_count + 1)) return MPM_ERR_NOMEM;
  e->rate = 0;
  if (!e->any) { /* no body enriches: nothing to evaluate (the domain step's common case) */
    memset(e->category, MPM_DOMAIN_UNENRICHED, p->count);
    e->count = 0;
    e->particles[0] = s->active_count;
    e->particles[1] = e->particles[2] = 0;
    return MPM_OK;
  }
  /* 1. the metric per particle (eq. 10 on the clamped F, sec. 5.3) */
#pragma omp parallel for schedule(static) if (np >= MPM_PARALLEL_MIN / 8)
  for (long q = 0; q < np; ++q) {
    const int was = e->flag[q];
    e->flag[q] = 0;
    const mpm_enrichment_body *eb = mpm_enrichment_body_of(e, p->body[q]);
    const mpm_real eps = eb->epsilon;
    if (!s->active[q] || !(eps > 0 || eb->bend > 0)) continue;
    mpm_real F[9];
    for (int k = 0; k < 9; ++k) F[k] = p->F[k][q];
    const mpm_real c = materials[p->material[q]].min_stretch;
    const mpm_real exit_k = eb->exit_k;
    /* K <= 1 always: epsilon 1 enriches every particle, even where rounding puts K a hair
     * above 1 (F = I). An enriched particle goes back to the grid only above exit_k: a
     * particle released while still deformed leaves its corners where no grid motion can
     * move them apart (a cell's 8 nodes carry its 27 corners), and the body locks in that
     * shape (measured: 2.2e-3 rest-state error against 1.7e-4 with exit_k = 0.95) */
    const mpm_real cc = c > 0 ? c : (mpm_real)1e-6;
    const int kind = eb->metric;
    const mpm_real K = eps >= 1                           ? 1
                       : kind == MPM_ENRICHMENT_FROBENIUS ? mpm_enrichment_metric(F, cc)
                                                          : mpm_enrichment_condition(F, cc);
    /* the bend K does not see (enrich.h); an enriched particle returns only once its bend is
       below 1 - exit_k too, the strain its stretch must be within (a particle let go at the
       entry's bend keeps that much bend for good) */
    const mpm_real bend =
        eb->bend > 0 && eps < 1 ? mpm_enrichment_hourglass_strain(s, (size_t)q, eb->spacing) : 0;
    const int bent = eb->bend > 0 && eps < 1 && bend >= eb->bend;
    const int relaxed = K > exit_k && !(eb->bend > 0 && bend >= 1 - exit_k);
    if (eps >= 1 || K <= eps || bent || (was && !relaxed)) {
      e->flag[q] = 1;
    } else if (was) {
      /* relaxed: back to the grid once it has been so for the body's wait (this step counted),
         not while it only passes through its rest shape (a ringing part let go there keeps
         the rest of its swing in the grid's hold) */
      const int steps = was; /* was - 1 earlier steps, and this one */
      const int waited = steps >= 255 || (double)steps * e->step_dt >= eb->exit_wait;
      e->flag[q] = waited ? 0 : (uint8_t)(steps + 1);
    }
  }
  /* 2. a corner is enriched when one of its particles is (gathered per corner: no races) */
#pragma omp parallel for schedule(static) if (nc >= MPM_PARALLEL_MIN)
  for (long c = 0; c < nc; ++c) {
    uint8_t on = 0;
    for (uint32_t j = s->adj_start[c]; j < s->adj_start[c + 1] && !on; ++j)
      on = e->flag[s->adj[j] / MPM_HEX_CORNERS] != 0;
    e->enriched[c] = on;
    e->on_grid[c] = s->corner_use[c] && !on;
  }
  /* 3. the particles' categories, and the explicit step's bound (enrich.h) */
  size_t n0 = 0, n1 = 0, n2 = 0;
  double rate = 0;
#pragma omp parallel for schedule(static) reduction(+ : n0, n1, n2) reduction(max : rate) if (np >= MPM_PARALLEL_MIN)
  for (long q = 0; q < np; ++q) {
    if (!s->active[q]) {
      e->category[q] = MPM_DOMAIN_UNENRICHED;
      continue;
    }
    int k = 0;
    for (int a = 0; a < MPM_HEX_CORNERS; ++a) k += e->enriched[s->corner[q][a]];
    const uint8_t cat = k == 0                 ? MPM_DOMAIN_UNENRICHED
                        : k == MPM_HEX_CORNERS ? MPM_DOMAIN_ENRICHED
                                               : MPM_DOMAIN_TRANSITIONAL;
    e->category[q] = cat;
    if (cat != MPM_DOMAIN_UNENRICHED) {
      mpm_real F[9], U[9], sigma[3], V[9];
      for (int j = 0; j < 9; ++j) F[j] = p->F[j][q];
      mpm_svd3(F, U, sigma, V);
      const mpm_material *m = &materials[p->material[q]];
      const double c = m->min_stretch > 0 ? m->min_stretch : 1e-6;
      const double sm = fmin(fmax((double)sigma[2], c), 1);
      const double h = mpm_enrichment_body_of(e, p->body[q])->spacing;
      const double r = h > 0 ? m->wave_speed / (h * sm * sm) : 0;
      if (r > rate) rate = r;
    }
    n0 += cat == MPM_DOMAIN_UNENRICHED;
    n1 += cat == MPM_DOMAIN_TRANSITIONAL;
    n2 += cat == MPM_DOMAIN_ENRICHED;
  }
  e->rate = rate;
  e->particles[0] = n0;
  e->particles[1] = n1;
  e->particles[2] = n2;
  /* 4. the enriched corners in corner order, and their positions (the DOF segment's) */
  size_t k = 0;
  for (long c = 0; c < nc; ++c)
    if (e->enriched[c]) {
      e->corner[k] = (uint32_t)c;
      e->slot[c] = (uint32_t)k;
      for (int d = 0; d < 3; ++d) e->x[d][k] = s->cx[d][c];
      ++k;
    }
  e->count = k;
  return MPM_OK;
}
