/* domain.c - building particle domains from a body's lattice, their weights, switching them
 * off (see domain.h). */
#include "domain/domain.h"
#include "domain/enrich.h"
#include "domain/lattice_map.h"
#include "core/alloc.h"
#include "core/arena.h"
#include "core/parallel.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void mpm_domain_set_init(mpm_domain_set *s) {
  memset(s, 0, sizeof *s);
  mpm_particles_init(&s->particles, 16);
}

/* The real-valued corner arrays, for loops that treat them alike (grow, free). */
static void corner_arrays(mpm_domain_set *s, mpm_real **out[28]) {
  int k = 0;
  for (int d = 0; d < 3; ++d) out[k++] = &s->cX[d];
  for (int d = 0; d < 3; ++d) out[k++] = &s->cx[d];
  for (int d = 0; d < 3; ++d) out[k++] = &s->cxc[d];
  for (int d = 0; d < 3; ++d) out[k++] = &s->cv[d];
  out[k++] = &s->cm;
  for (int d = 0; d < 3; ++d) out[k++] = &s->cp[d];
  for (int d = 0; d < 3; ++d) out[k++] = &s->cf[d];
  for (int e = 0; e < 9; ++e) out[k++] = &s->cB[e];
}
#define CORNER_REAL_ARRAYS 28

void mpm_domain_set_free(mpm_domain_set *s) {
  mpm_particles_free(&s->particles);
  mpm_free(s->corner);
  mpm_free(s->w);
  mpm_free(s->g);
  mpm_free(s->active);
  mpm_real **a[CORNER_REAL_ARRAYS];
  corner_arrays(s, a);
  for (int k = 0; k < CORNER_REAL_ARRAYS; ++k) mpm_free(*a[k]);
  mpm_free(s->adj_start);
  mpm_free(s->adj);
  mpm_free(s->corner_use);
  mpm_free(s->cube_g);
  mpm_free(s->cmass);
  mpm_embedding_free(&s->corner_grid);
  mpm_corner_pads_free(&s->pads);
  mpm_enrichment_free(&s->enrich);
  memset(s, 0, sizeof *s);
}

/* ---- weights ------------------------------------------------------------------------ */

mpm_status mpm_domain_weights(const double X[MPM_HEX_CORNERS][3], double w[MPM_HEX_CORNERS],
                              double g[MPM_HEX_CORNERS][3], double *volume) {
  /* 2-point Gauss rule per axis: +-1/sqrt(3), weight 1 */
  const double q = 1 / sqrt(3.0);
  double V = 0;
  memset(w, 0, MPM_HEX_CORNERS * sizeof w[0]);
  memset(g, 0, MPM_HEX_CORNERS * sizeof g[0]);
  for (int gp = 0; gp < 8; ++gp) {
    const double xi[3] = {(gp & 1) ? q : -q, (gp & 2) ? q : -q, (gp & 4) ? q : -q};
    double N[MPM_HEX_CORNERS], dN[MPM_HEX_CORNERS][3];
    mpm_hex_shape(xi, N, dN);
    /* J[r][c] = dX_r / dxi_c */
    double J[3][3] = {{0}};
    for (int a = 0; a < MPM_HEX_CORNERS; ++a)
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) J[r][c] += X[a][r] * dN[a][c];
    const double det = J[0][0] * (J[1][1] * J[2][2] - J[1][2] * J[2][1]) -
                       J[0][1] * (J[1][0] * J[2][2] - J[1][2] * J[2][0]) +
                       J[0][2] * (J[1][0] * J[2][1] - J[1][1] * J[2][0]);
    if (!(det > 0)) return MPM_ERR_INVALID;
    /* grad_X N = J^-T grad_xi N, and J^-T = cof(J) / det: det dV folds the division away */
    double cof[3][3];
    cof[0][0] = J[1][1] * J[2][2] - J[1][2] * J[2][1];
    cof[0][1] = J[1][2] * J[2][0] - J[1][0] * J[2][2];
    cof[0][2] = J[1][0] * J[2][1] - J[1][1] * J[2][0];
    cof[1][0] = J[0][2] * J[2][1] - J[0][1] * J[2][2];
    cof[1][1] = J[0][0] * J[2][2] - J[0][2] * J[2][0];
    cof[1][2] = J[0][1] * J[2][0] - J[0][0] * J[2][1];
    cof[2][0] = J[0][1] * J[1][2] - J[0][2] * J[1][1];
    cof[2][1] = J[0][2] * J[1][0] - J[0][0] * J[1][2];
    cof[2][2] = J[0][0] * J[1][1] - J[0][1] * J[1][0];
    V += det;
    for (int a = 0; a < MPM_HEX_CORNERS; ++a) {
      w[a] += N[a] * det;
      for (int r = 0; r < 3; ++r)
        g[a][r] += cof[r][0] * dN[a][0] + cof[r][1] * dN[a][1] + cof[r][2] * dN[a][2];
    }
  }
  for (int a = 0; a < MPM_HEX_CORNERS; ++a) {
    w[a] /= V;
    for (int r = 0; r < 3; ++r) g[a][r] /= V;
  }
  *volume = V;
  return MPM_OK;
}

/* ---- building from a lattice ---------------------------------------------------------- */

static int grow(void **ptr, size_t old_n, size_t new_n, size_t elem) {
  void *q = mpm_alloc(new_n * elem);
  if (!q) return -1;
  if (*ptr && old_n) memcpy(q, *ptr, old_n * elem);
  mpm_free(*ptr);
  *ptr = q;
  return 0;
}

static int reserve_corners(mpm_domain_set *s, size_t need) {
  if (need <= s->corner_capacity) return 0;
  size_t cap = s->corner_capacity ? s->corner_capacity : 1024;
  while (cap < need) cap *= 2;
  mpm_real **a[CORNER_REAL_ARRAYS];
  corner_arrays(s, a);
  for (int k = 0; k < CORNER_REAL_ARRAYS; ++k)
    if (grow((void **)a[k], s->corner_count, cap, sizeof(mpm_real))) return -1;
  s->corner_capacity = cap;
  return 0;
}

static int reserve_particles(mpm_domain_set *s, size_t need) {
  const size_t old = s->particles.capacity;
  if (need <= old && s->corner) return 0;
  size_t cap = old > 16 ? old : 16;
  while (cap < need) cap *= 2;
  if (mpm_particles_reserve(&s->particles, cap)) return -1;
  const size_t n = s->particles.count;
  if (grow((void **)&s->corner, n, cap, sizeof *s->corner) ||
      grow((void **)&s->w, n, cap, sizeof *s->w) || grow((void **)&s->g, n, cap, sizeof *s->g) ||
      grow((void **)&s->active, n, cap, sizeof *s->active))
    return -1;
  return 0;
}

mpm_status mpm_domain_set_alloc(mpm_domain_set *s, size_t particles, size_t corners) {
  mpm_domain_set_init(s);
  if (reserve_particles(s, particles ? particles : 1) || reserve_corners(s, corners ? corners : 1))
    return MPM_ERR_NOMEM;
  s->particles.count = particles;
  s->corner_count = corners;
  return MPM_OK;
}

/* Rebuild the corner -> particle-slot adjacency (CSR) over the active particles. */
/* s->cube_g (domain.h): the magnitude of g where w and g are exactly the cube's pattern. */
static void cube_scales(mpm_domain_set *s) {
  for (size_t q = 0; q < s->particles.count; ++q) {
    const mpm_real m = s->g[q][MPM_HEX_CORNERS - 1][0]; /* the corner at +x, +y, +z */
    int cube = m > 0;
    for (int a = 0; a < MPM_HEX_CORNERS && cube; ++a) {
      cube = s->w[q][a] == (mpm_real)0.125;
      for (int d = 0; d < 3 && cube; ++d) cube = s->g[q][a][d] == (mpm_real)mpm_hex_sign(a, d) * m;
    }
    s->cube_g[q] = cube ? m : 0;
  }
}

static mpm_status build_adjacency(mpm_domain_set *s) {
  mpm_free(s->cube_g);
  s->cube_g = mpm_alloc((s->particles.count + 1) * sizeof *s->cube_g);
  if (!s->cube_g) return MPM_ERR_NOMEM;
  cube_scales(s);
  mpm_free(s->adj_start);
  mpm_free(s->adj);
  mpm_free(s->corner_use);
  s->adj_start = mpm_calloc(s->corner_count + 1, sizeof *s->adj_start);
  s->adj = mpm_alloc((s->particles.count * MPM_HEX_CORNERS + 1) * sizeof *s->adj);
  s->corner_use = mpm_alloc(s->corner_count + 1);
  if (!s->adj_start || !s->adj || !s->corner_use) return MPM_ERR_NOMEM;
  for (size_t p = 0; p < s->particles.count; ++p)
    if (s->active[p])
      for (int a = 0; a < MPM_HEX_CORNERS; ++a) s->adj_start[s->corner[p][a] + 1]++;
  for (size_t c = 0; c < s->corner_count; ++c) {
    s->corner_use[c] = s->adj_start[c + 1] != 0;
    s->adj_start[c + 1] += s->adj_start[c];
  }
  uint32_t *fill = mpm_alloc((s->corner_count + 1) * sizeof *fill);
  if (!fill) return MPM_ERR_NOMEM;
  memcpy(fill, s->adj_start, (s->corner_count + 1) * sizeof *fill);
  for (size_t p = 0; p < s->particles.count; ++p)
    if (s->active[p])
      for (int a = 0; a < MPM_HEX_CORNERS; ++a)
        s->adj[fill[s->corner[p][a]]++] = (uint32_t)(p * MPM_HEX_CORNERS + (size_t)a);
  mpm_free(fill);
  /* m_a = sum_p omega_ap m_p in slot order (domain.h, cmass) */
  mpm_free(s->cmass);
  s->cmass = mpm_alloc((s->corner_count + 1) * sizeof *s->cmass);
  if (!s->cmass) return MPM_ERR_NOMEM;
  for (size_t c = 0; c < s->corner_count; ++c) {
    double m = 0;
    for (uint32_t j = s->adj_start[c]; j < s->adj_start[c + 1]; ++j) {
      const uint32_t q = s->adj[j] / MPM_HEX_CORNERS, a = s->adj[j] % MPM_HEX_CORNERS;
      const double w = s->cube_g[q] != 0 ? 0.125 : s->w[q][a];
      m += w * (double)s->particles.mass[q];
    }
    s->cmass[c] = m;
  }
  return MPM_OK;
}

/* keep[i] = 0 for the particles of fragments (domain.h, MPM_DOMAIN_MIN_FRAGMENT): the
 * components of the lattice cells k[0..n) joined through faces, smaller than the minimum and
 * than the largest component. Returns the count kept, or (size_t)-1 when out of memory. */
static size_t drop_fragments(const int64_t (*k)[3], size_t n, uint8_t *keep) {
  mpm_lattice_map m;
  uint32_t *comp = mpm_alloc((n + 1) * sizeof *comp), *stack = mpm_alloc((n + 1) * sizeof *stack);
  uint32_t *size = mpm_alloc((n + 1) * sizeof *size);
  size_t kept = (size_t)-1;
  if (mpm_lattice_map_init(&m, n) || !comp || !stack || !size) goto done;
  for (size_t i = 0; i < n; ++i) {
    const uint64_t key = mpm_lattice_key(k[i]);
    const size_t at = mpm_lattice_map_slot(&m, key);
    m.keys[at] = key;
    m.values[at] = (uint32_t)i;
    comp[i] = UINT32_MAX;
  }
  uint32_t comps = 0, largest = 0;
  for (size_t i = 0; i < n; ++i) { /* depth-first over the face neighbours */
    if (comp[i] != UINT32_MAX) continue;
    size_t top = 0;
    stack[top++] = (uint32_t)i;
    comp[i] = comps;
    size[comps] = 0;
    while (top) {
      const uint32_t j = stack[--top];
      ++size[comps];
      for (int f = 0; f < 6; ++f) {
        int64_t nb[3] = {k[j][0], k[j][1], k[j][2]};
        nb[f / 2] += f % 2 ? 1 : -1;
        const uint64_t key = mpm_lattice_key(nb);
        const size_t at = mpm_lattice_map_slot(&m, key);
        if (m.keys[at] != key || comp[m.values[at]] != UINT32_MAX) continue;
        comp[m.values[at]] = comps;
        stack[top++] = m.values[at];
      }
    }
    if (size[comps] > size[largest]) largest = comps;
    ++comps;
  }
  kept = 0;
  for (size_t i = 0; i < n; ++i) {
    keep[i] = comp[i] == largest || size[comp[i]] >= MPM_DOMAIN_MIN_FRAGMENT;
    kept += keep[i];
  }
done:
  mpm_lattice_map_free(&m);
  mpm_free(comp);
  mpm_free(stack);
  mpm_free(size);
  return kept;
}

mpm_status mpm_domain_set_add_lattice(mpm_domain_set *s, mpm_particles *p, size_t first,
                                      const double lattice_origin[3], double h,
                                      const char *body_name, mpm_error *err) {
  const size_t all = p->count - first;
  /* the particles' lattice cells, then the fragments dropped */
  int64_t(*k)[3] = mpm_alloc((all + 1) * sizeof *k);
  uint8_t *keep = mpm_alloc(all + 1);
  if (!k || !keep) {
    mpm_free(k);
    mpm_free(keep);
    return mpm_error_set(err, MPM_ERR_NOMEM, "out of memory building the particle domains of %s",
                         body_name);
  }
  for (size_t i = first; i < p->count; ++i)
    for (int d = 0; d < 3; ++d) {
      const double u = ((double)p->x[d][i] - lattice_origin[d]) / h - 0.5;
      k[i - first][d] = (int64_t)llround(u);
      const double off = fabs(u - (double)k[i - first][d]);
      if (off > 1e-3) {
        mpm_free(k);
        mpm_free(keep);
        return mpm_error_set(err, MPM_ERR_INVALID,
                             "%s: particle domains need particles on the body's lattice (jitter "
                             "0); a particle is %.3g spacings off it",
                             body_name, off);
      }
    }
  const size_t n = drop_fragments((const int64_t(*)[3])k, all, keep);
  if (n == (size_t)-1) {
    mpm_free(k);
    mpm_free(keep);
    return mpm_error_set(err, MPM_ERR_NOMEM, "out of memory building the particle domains of %s",
                         body_name);
  }
  if (reserve_particles(s, s->particles.count + n) ||
      reserve_corners(s, s->corner_count + 2 * n + 64))
    return mpm_error_set(err, MPM_ERR_NOMEM, "out of memory building the particle domains of %s",
                         body_name);
  mpm_lattice_map m; /* lattice vertex -> corner */
  if (mpm_lattice_map_init(&m, 8 * n)) {
    mpm_lattice_map_free(&m);
    return mpm_error_set(err, MPM_ERR_NOMEM, "out of memory building the particle domains of %s",
                         body_name);
  }
  mpm_status st = MPM_OK;
  mpm_particles *dp = &s->particles;
  for (size_t i = first; i < p->count && st == MPM_OK; ++i) {
    if (!keep[i - first]) continue; /* a fragment */
    const int64_t *ki = k[i - first];
    if (reserve_corners(s, s->corner_count + MPM_HEX_CORNERS)) {
      st = mpm_error_set(err, MPM_ERR_NOMEM, "out of memory building the domains of %s", body_name);
      break;
    }
    const size_t q = dp->count;
    double X[MPM_HEX_CORNERS][3];
    for (int a = 0; a < MPM_HEX_CORNERS; ++a) {
      const int64_t v[3] = {ki[0] + ((a >> 0) & 1), ki[1] + ((a >> 1) & 1), ki[2] + ((a >> 2) & 1)};
      for (int d = 0; d < 3; ++d) X[a][d] = lattice_origin[d] + (double)v[d] * h;
      const uint64_t key = mpm_lattice_key(v);
      const size_t at = mpm_lattice_map_slot(&m, key);
      uint32_t *slot = &m.values[at];
      if (m.keys[at] != key) {
        m.keys[at] = key;
        const size_t c = s->corner_count++;
        *slot = (uint32_t)c;
        for (int d = 0; d < 3; ++d) {
          s->cX[d][c] = s->cx[d][c] = (mpm_real)X[a][d];
          s->cxc[d][c] = 0;
          s->cv[d][c] = p->v[d][i]; /* the body's initial velocity field at the vertex, below */
        }
        for (int e = 0; e < 9; ++e) s->cB[e][c] = 0; /* no grid affine before the first G2P */
      }
      s->corner[q][a] = *slot;
    }
    /* a lattice cube of side h: omega_ap = 1/8 and g_ap = s_a / (4 h) exactly (what
     * mpm_domain_weights' quadrature gives up to rounding), so that the transfers can take them
     * from one value per particle (domain.h, cube_g) */
    for (int a = 0; a < MPM_HEX_CORNERS; ++a) {
      s->w[q][a] = (mpm_real)0.125;
      for (int d = 0; d < 3; ++d) s->g[q][a][d] = (mpm_real)(mpm_hex_sign(a, d) * 0.25 / h);
    }
    /* move the particle's state over */
    mpm_real pos[3], vel[3];
    for (int d = 0; d < 3; ++d) {
      pos[d] = p->x[d][i];
      vel[d] = p->v[d][i];
    }
    mpm_particles_push(dp, pos, vel, p->mass[i], p->vol0[i], p->material[i], p->body[i]);
    for (int c = 0; c < 9; ++c) dp->F[c][q] = p->F[c][i];
    dp->plastic[q] = p->plastic[i];
    dp->temperature[q] = p->temperature[i];
    dp->id[q] = p->id[i];
    s->active[q] = 1;
    s->active_count++;
  }
  mpm_lattice_map_free(&m);
  mpm_free(k);
  mpm_free(keep);
  if (st != MPM_OK) return st;
  p->count = first; /* the body's particles now live in the domain set, fragments dropped */
  if (build_adjacency(s))
    return mpm_error_set(err, MPM_ERR_NOMEM, "out of memory building the domains of %s", body_name);
  /* corner velocities: the least-squares affine fit v0 + A (x - c) of the body's particle
   * velocities, evaluated at the corners. The sampler's fields (uniform, rigid rotation) are
   * affine, so the fit is exact and v_p = sum_a omega_ap v_a gives them back at the particles. */
  const size_t q0 = dp->count - n;
  double c[3] = {0, 0, 0}, v0[3] = {0, 0, 0}, C[3][3] = {{0}}, M[3][3] = {{0}};
  for (size_t q = q0; q < dp->count; ++q)
    for (int d = 0; d < 3; ++d) {
      c[d] += (double)dp->x[d][q] / (double)n;
      v0[d] += (double)dp->v[d][q] / (double)n;
    }
  for (size_t q = q0; q < dp->count; ++q)
    for (int r = 0; r < 3; ++r)
      for (int t = 0; t < 3; ++t) {
        const double dt = (double)dp->x[t][q] - c[t];
        C[r][t] += ((double)dp->x[r][q] - c[r]) * dt;
        M[r][t] += ((double)dp->v[r][q] - v0[r]) * dt;
      }
  const double det = C[0][0] * (C[1][1] * C[2][2] - C[1][2] * C[2][1]) -
                     C[0][1] * (C[1][0] * C[2][2] - C[1][2] * C[2][0]) +
                     C[0][2] * (C[1][0] * C[2][1] - C[1][1] * C[2][0]);
  double A[3][3] = {{0}};
  const double scale = C[0][0] + C[1][1] + C[2][2];
  if (det > 1e-12 * scale * scale * scale) {
    double Ci[3][3]; /* symmetric inverse by cofactors */
    for (int r = 0; r < 3; ++r)
      for (int t = 0; t < 3; ++t) {
        const int r1 = (t + 1) % 3, r2 = (t + 2) % 3, c1 = (r + 1) % 3, c2 = (r + 2) % 3;
        Ci[r][t] = (C[r1][c1] * C[r2][c2] - C[r1][c2] * C[r2][c1]) / det;
      }
    for (int r = 0; r < 3; ++r)
      for (int t = 0; t < 3; ++t)
        for (int u = 0; u < 3; ++u) A[r][t] += M[r][u] * Ci[u][t];
  }
  for (size_t cn = 0; cn < s->corner_count; ++cn) {
    if (s->adj_start[cn] == s->adj_start[cn + 1]) continue;
    const uint32_t first_slot = s->adj[s->adj_start[cn]] / MPM_HEX_CORNERS;
    if (first_slot < q0) continue; /* a corner of an earlier body */
    for (int r = 0; r < 3; ++r) {
      double v = v0[r];
      for (int t = 0; t < 3; ++t) v += A[r][t] * ((double)s->cX[t][cn] - c[t]);
      s->cv[r][cn] = (mpm_real)v;
    }
  }
  mpm_domain_set_sync_particles(s);
  return MPM_OK;
}

void mpm_domain_set_sync_particles(mpm_domain_set *s) {
  mpm_particles *p = &s->particles;
  const long n = (long)p->count;
#pragma omp parallel for schedule(static)
  for (long i = 0; i < n; ++i) {
    if (!s->active[i]) continue;
    mpm_real x[3] = {0, 0, 0}, v[3] = {0, 0, 0};
    for (int a = 0; a < MPM_HEX_CORNERS; ++a) {
      const uint32_t c = s->corner[i][a];
      const mpm_real w = s->w[i][a];
      for (int d = 0; d < 3; ++d) {
        x[d] += w * s->cx[d][c];
        v[d] += w * s->cv[d][c];
      }
    }
    for (int d = 0; d < 3; ++d) {
      p->x[d][i] = x[d];
      p->v[d][i] = v[d];
    }
  }
}

mpm_status mpm_domain_set_release(mpm_domain_set *s, size_t i, mpm_particles *to) {
  if (i >= s->particles.count || !s->active[i]) return MPM_OK;
  const mpm_particles *p = &s->particles;
  mpm_real x[3], v[3];
  for (int d = 0; d < 3; ++d) {
    x[d] = p->x[d][i];
    v[d] = p->v[d][i];
  }
  const long j = mpm_particles_push(to, x, v, p->mass[i], p->vol0[i], p->material[i], p->body[i]);
  if (j < 0) return MPM_ERR_NOMEM;
  for (int c = 0; c < 9; ++c) to->F[c][j] = p->F[c][i];
  to->plastic[j] = p->plastic[i];
  to->temperature[j] = p->temperature[i];
  to->id[j] = p->id[i];
  s->active[i] = 0;
  s->active_count--;
  return MPM_OK;
}

void mpm_domain_permute_values(void *a, void *tmp, size_t size, const uint32_t *order, size_t n) {
  const long m = (long)n;
  if (size == sizeof(uint32_t)) { /* mpm_real in float, and the slots */
    uint32_t *x = a, *t = tmp;
#pragma omp parallel for schedule(static) if (m > MPM_PARALLEL_MIN)
    for (long k = 0; k < m; ++k) t[k] = x[order[k]];
  } else if (size == sizeof(uint64_t)) {
    uint64_t *x = a, *t = tmp;
#pragma omp parallel for schedule(static) if (m > MPM_PARALLEL_MIN)
    for (long k = 0; k < m; ++k) t[k] = x[order[k]];
  } else {
    uint8_t *x = a, *t = tmp;
#pragma omp parallel for schedule(static) if (m > MPM_PARALLEL_MIN)
    for (long k = 0; k < m; ++k) t[k] = x[order[k]];
  }
  memcpy(a, tmp, n * size);
}

mpm_status mpm_domain_set_permute_corners(mpm_domain_set *s, const uint32_t *order,
                                          mpm_arena *scratch) {
  const size_t nc = s->corner_count, np = s->particles.count;
  uint32_t *inv = mpm_arena_alloc(scratch, (nc + 1) * sizeof *inv);
  void *tmp = mpm_arena_alloc(scratch, (nc + 1) * sizeof(uint64_t));
  uint32_t *adj_start = mpm_arena_alloc(scratch, (nc + 1) * sizeof *adj_start);
  uint32_t *adj = mpm_arena_alloc(scratch, (s->adj_start[nc] + 1) * sizeof *adj);
  if (!inv || !tmp || !adj_start || !adj) return MPM_ERR_NOMEM;
  const long m = (long)nc;
#pragma omp parallel for schedule(static) if (m > MPM_PARALLEL_MIN)
  for (long k = 0; k < m; ++k) inv[order[k]] = (uint32_t)k;
  mpm_real **a[CORNER_REAL_ARRAYS];
  corner_arrays(s, a);
  for (int k = 0; k < CORNER_REAL_ARRAYS; ++k)
    mpm_domain_permute_values(*a[k], tmp, sizeof(mpm_real), order, nc);
  mpm_domain_permute_values(s->corner_use, tmp, 1, order, nc);
  mpm_domain_permute_values(s->cmass, tmp, sizeof *s->cmass, order, nc);
  mpm_domain_enrichment *en = &s->enrich;
  if (en->count) { /* this step's marks, by corner; the enriched corners keep their DOF order */
    mpm_domain_permute_values(en->enriched, tmp, 1, order, nc);
    mpm_domain_permute_values(en->on_grid, tmp, 1, order, nc);
    mpm_domain_permute_values(en->slot, tmp, sizeof *en->slot, order, nc);
    for (size_t k = 0; k < en->count; ++k) en->corner[k] = inv[en->corner[k]];
  }
  /* the adjacency: corner k's particle slots are those of corner order[k] */
  adj_start[0] = 0;
  for (size_t k = 0; k < nc; ++k)
    adj_start[k + 1] = adj_start[k] + (s->adj_start[order[k] + 1] - s->adj_start[order[k]]);
#pragma omp parallel for schedule(static) if (m > MPM_PARALLEL_MIN)
  for (long k = 0; k < m; ++k)
    memcpy(adj + adj_start[k], s->adj + s->adj_start[order[k]],
           (adj_start[k + 1] - adj_start[k]) * sizeof *adj);
  memcpy(s->adj_start, adj_start, (nc + 1) * sizeof *adj_start);
  memcpy(s->adj, adj, adj_start[nc] * sizeof *adj);
  const long n = (long)np;
#pragma omp parallel for schedule(static) if (n > MPM_PARALLEL_MIN / 8)
  for (long q = 0; q < n; ++q)
    for (int c = 0; c < MPM_HEX_CORNERS; ++c) s->corner[q][c] = inv[s->corner[q][c]];
  return MPM_OK;
}

mpm_status mpm_domain_set_rebuild(mpm_domain_set *s) {
  s->enrich.valid = 0; /* other particles, other corners: the marks are stale */
  return build_adjacency(s);
}
