/* heat.c - heat transfer on the DOF set (see heat.h for the equations). */
#define _POSIX_C_SOURCE 200809L /* clock_gettime */
#include "heat/heat.h"
#include "core/alloc.h"
#include "core/parallel.h"

#include <math.h>
#include <string.h>
#include <time.h>

void mpm_heat_init(mpm_heat *h) {
  memset(h, 0, sizeof *h);
  mpm_embedding_init(&h->E);
}

void mpm_heat_free(mpm_heat *h) {
  mpm_embedding_free(&h->E);
  for (int d = 0; d < 3; ++d) {
    mpm_free(h->g[d]);
    mpm_free(h->flux[d]);
  }
  mpm_free(h->capacity);
  mpm_free(h->heat);
  mpm_free(h->vk);
  mpm_free(h->zero);
  mpm_free(h->key);
  mpm_free(h->colour);
  mpm_free(h->key_colour);
  mpm_free(h->held);
  memset(h, 0, sizeof *h);
}

/* *p resized to n elements of `elem` bytes (contents dropped) when it holds fewer. */
static int grow(void **p, size_t *cap, size_t n, size_t elem) {
  if (n <= *cap && *p) return 0;
  mpm_free(*p);
  *p = mpm_alloc((n + 1) * elem);
  *cap = *p ? n : 0;
  return *p ? 0 : -1;
}

static int reserve_rows(mpm_heat *h, size_t rows) {
  if (rows <= h->row_capacity && h->capacity) return 0;
  void **arrays[] = {(void **)&h->capacity, (void **)&h->heat,    (void **)&h->vk,
                     (void **)&h->flux[0],  (void **)&h->flux[1], (void **)&h->flux[2],
                     (void **)&h->zero};
  for (size_t k = 0; k < sizeof arrays / sizeof arrays[0]; ++k) {
    size_t cap = h->row_capacity;
    if (grow(arrays[k], &cap, rows, sizeof(mpm_real))) return -1;
  }
  size_t cap = h->row_capacity;
  if (grow((void **)&h->key, &cap, rows, sizeof(int32_t))) return -1;
  cap = h->row_capacity;
  if (grow((void **)&h->colour, &cap, rows, sizeof(uint8_t))) return -1;
  h->row_capacity = rows;
  return 0;
}

int mpm_heat_substeps(double dt, double dx, const mpm_material *materials, int material_count) {
  double alpha = 0;
  for (int m = 0; m < material_count; ++m) {
    const double c = materials[m].specific_heat, rho = materials[m].density;
    if (materials[m].conductivity > 0 && c > 0 && rho > 0) {
      const double a = (double)materials[m].conductivity / (rho * c);
      if (a > alpha) alpha = a;
    }
  }
  if (!(alpha > 0)) return 1;
  /* the quadratic B-spline's Laplacian with lumped capacities has its largest eigenvalue near
   * 4/dx^2 per axis over 3 (12/dx^2 for the finite-difference stencil), so 3 axes give
   * dt < dx^2 / (2 alpha); half of that leaves room for uneven particle spacing */
  const double stable = 0.25 * dx * dx / alpha;
  const double n = ceil(dt / stable);
  return n < 1 ? 1 : n > 1e6 ? 1000000 : (int)n;
}

double mpm_heat_total(const mpm_heat_set *set, const mpm_material *materials) {
  const mpm_particles *p = set->p;
  double sum = 0;
  for (size_t i = 0; i < p->count; ++i)
    if (!set->active || set->active[i])
      sum += (double)p->mass[i] * (double)materials[p->material[i]].specific_heat *
             (double)p->temperature[i];
  return sum;
}

static double now_seconds(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* The carriers' rows: weights and gradients to the level's nodes, heat capacity, heat and
 * V k per particle, and the scatter keys. -2 when a node is missing. */
static int build_rows(mpm_heat *h, const mpm_heat_step_desc *s, size_t rows) {
  const mpm_grid *g = s->grid;
  const mpm_kernel *k = &s->kernel;
  const int W = k->width;
  const uint32_t dof_begin = (uint32_t)g->dof_begin;
  int missing = 0;
  size_t first = 0;
  for (int set = 0; set < s->set_count; ++set) {
    const mpm_particles *p = s->sets[set].p;
    const uint8_t *active = s->sets[set].active;
    const long n = (long)p->count;
#pragma omp parallel reduction(| : missing) if (n > MPM_PARALLEL_MIN)
    {
      mpm_grid_cursor cursor;
      mpm_grid_cursor_init(&cursor);
#pragma omp for schedule(static)
      for (long i = 0; i < n; ++i) {
        const size_t a = first + (size_t)i;
        h->key[a] = -1;
        h->capacity[a] = h->heat[a] = h->vk[a] = h->zero[a] = 0;
        if (active && !active[i]) continue;
        const mpm_material *m = &s->materials[p->material[i]];
        mpm_real xr[3];
        for (int d = 0; d < 3; ++d) {
          mpm_real x = p->x[d][i];
          x = x < s->clamp_lo[d] ? s->clamp_lo[d] : x > s->clamp_hi[d] ? s->clamp_hi[d] : x;
          xr[d] = x - g->origin[d];
        }
        mpm_stencil st;
        mpm_kernel_stencil(k, xr, &st);
        uint32_t nodes[MPM_STENCIL_MAX * MPM_STENCIL_MAX * MPM_STENCIL_MAX];
        if (g->ops->stencil_nodes(g, st.base, W, &cursor, nodes, &h->key[a], &h->colour[a])) {
          missing = 1;
          h->key[a] = -1;
          continue;
        }
        const mpm_real *F[9];
        for (int e = 0; e < 9; ++e) F[e] = p->F[e] + i;
        const mpm_real J = *F[0] * (*F[4] * *F[8] - *F[5] * *F[7]) -
                           *F[1] * (*F[3] * *F[8] - *F[5] * *F[6]) +
                           *F[2] * (*F[3] * *F[7] - *F[4] * *F[6]);
        h->capacity[a] = p->mass[i] * m->specific_heat;
        h->heat[a] = h->capacity[a] * p->temperature[i];
        h->vk[a] = mpm_fabs(J) * p->vol0[i] * m->conductivity;
        int e = 0;
        for (int ii = 0; ii < W; ++ii)
          for (int jj = 0; jj < W; ++jj)
            for (int ll = 0; ll < W; ++ll, ++e) {
              const mpm_real w = st.w[0][ii] * st.w[1][jj] * st.w[2][ll];
              if (w == 0) continue;
              const uint32_t at = h->E.row_start[a] + h->E.row_len[a];
              h->g[0][at] = st.dw[0][ii] * st.w[1][jj] * st.w[2][ll];
              h->g[1][at] = st.w[0][ii] * st.dw[1][jj] * st.w[2][ll];
              h->g[2][at] = st.w[0][ii] * st.w[1][jj] * st.dw[2][ll];
              mpm_embedding_push(&h->E, a, dof_begin + nodes[e], w);
            }
      }
    }
    first += p->count;
  }
  (void)rows;
  return missing ? -2 : 0;
}

int mpm_heat_step(mpm_heat *h, const mpm_heat_step_desc *s) {
  const double t0 = now_seconds();
  const mpm_grid *g = s->grid;
  mpm_dofs *d = s->dofs;
  size_t rows = 0;
  for (int set = 0; set < s->set_count; ++set) rows += s->sets[set].p->count;
  const uint32_t W3 = (uint32_t)(s->kernel.width * s->kernel.width * s->kernel.width);
  if (reserve_rows(h, rows) || mpm_embedding_layout(&h->E, rows, NULL, W3)) return -1;
  h->E.rows = rows;
  if (h->E.entry_capacity > h->entry_capacity || !h->g[0]) {
    for (int k = 0; k < 3; ++k) {
      mpm_free(h->g[k]);
      h->g[k] = mpm_alloc((h->E.entry_capacity + 1) * sizeof(mpm_real));
      if (!h->g[k]) {
        h->entry_capacity = 0;
        return -1;
      }
    }
    h->entry_capacity = h->E.entry_capacity;
  }
  const int built = build_rows(h, s, rows);
  if (built) return built;
  const size_t keys = g->ops->scatter_key_count(g);
  if (grow((void **)&h->key_colour, &h->key_capacity, keys, 1)) return -1;
  for (size_t a = 0; a < rows; ++a)
    if (h->key[a] >= 0) h->key_colour[h->key[a]] = h->colour[a];
  if (mpm_embedding_schedule(&h->E, h->key, keys, h->key_colour)) return -1;

  /* the node values: C_i, T_i, T_i^P2G (vector "heat"); the conduction rate (vector
   * "heat_rate", components 1 and 2 are the moment scatter's unused outputs) */
  mpm_real **hv = mpm_dofs_vector(d, "heat");
  mpm_real **hq = hv ? mpm_dofs_vector(d, "heat_rate") : NULL;
  if (!hq || grow((void **)&h->held, &h->held_capacity, d->count, 1)) return -1;
  const long b0 = (long)g->dof_begin, b1 = b0 + (long)g->ops->node_count(g);
#pragma omp parallel for schedule(static) if (b1 - b0 > MPM_PARALLEL_MIN)
  for (long i = b0; i < b1; ++i) hv[0][i] = hv[1][i] = 0;
  {
    const mpm_real *c[2] = {h->capacity, h->heat};
    mpm_real *const u[2] = {hv[0], hv[1]};
    mpm_embedding_scatter(&h->E, 2, c, u);
  }
  size_t held = 0;
#pragma omp parallel for schedule(static) reduction(+ : held) if (b1 - b0 > MPM_PARALLEL_MIN)
  for (long i = b0; i < b1; ++i) {
    h->held[i] = 0;
    const mpm_real C = hv[0][i];
    mpm_real T = C > 0 ? hv[1][i] / C : 0;
    hv[2][i] = T;
    if (C > 0)
      for (int k = 0; k < s->pose_count; ++k) {
        const mpm_collider_desc *cd = &s->poses[k].collider->desc;
        if (!cd->heat_source) continue;
        mpm_real x[3], n[3];
        mpm_dofs_position(d, (size_t)i, x);
        if (mpm_collider_phi(&s->poses[k], x, n) <= 0) {
          T = (mpm_real)cd->temperature;
          h->held[i] = 1;
          ++held;
          break;
        }
      }
    hv[1][i] = T;
  }

  /* conduction, in substeps */
  int material_count = 0;
  for (int set = 0; set < s->set_count; ++set)
    for (size_t i = 0; i < s->sets[set].p->count; ++i)
      if (s->sets[set].p->material[i] + 1 > material_count)
        material_count = s->sets[set].p->material[i] + 1;
  const int substeps = mpm_heat_substeps(s->dt, g->dx, s->materials, material_count);
  const mpm_real dts = (mpm_real)(s->dt / substeps);
  const long nrows = (long)rows;
  const mpm_real *const ga[3] = {h->g[0], h->g[1], h->g[2]};
  for (int sub = 0; sub < substeps; ++sub) {
    /* the flux -V k grad T_p of every carrier that conducts */
#pragma omp parallel for schedule(static) if (nrows > MPM_PARALLEL_MIN)
    for (long a = 0; a < nrows; ++a) {
      mpm_real gT[3] = {0, 0, 0};
      if (h->vk[a] > 0) {
        const uint32_t e0 = h->E.row_start[a], e1 = e0 + h->E.row_len[a];
        for (uint32_t e = e0; e < e1; ++e) {
          const mpm_real T = hv[1][h->E.col[e]];
          for (int k = 0; k < 3; ++k) gT[k] += ga[k][e] * T;
        }
      }
      for (int k = 0; k < 3; ++k) h->flux[k][a] = -h->vk[a] * gT[k];
    }
#pragma omp parallel for schedule(static) if (b1 - b0 > MPM_PARALLEL_MIN)
    for (long i = b0; i < b1; ++i) hq[0][i] = hq[1][i] = hq[2][i] = 0;
    /* q_i = sum_p grad w_ip . flux_p: the moment scatter with the flux as row 0 of cm */
    const mpm_real *cm[9] = {h->flux[0], h->flux[1], h->flux[2], h->zero, h->zero,
                             h->zero,    h->zero,    h->zero,    h->zero};
    mpm_real *const um[3] = {hq[0], hq[1], hq[2]};
    mpm_embedding_scatter_moments(&h->E, 0, NULL, NULL, ga, cm, um);
#pragma omp parallel for schedule(static) if (b1 - b0 > MPM_PARALLEL_MIN)
    for (long i = b0; i < b1; ++i)
      if (!h->held[i] && hv[0][i] > 0) hv[1][i] += dts * hq[0][i] / hv[0][i];
  }

  /* back to the particles: the nodes' change since P2G (FLIP). A particle whose stencil
   * touches a held node takes the nodes' temperature itself (PIC): the held nodes' jump to
   * the source's temperature would otherwise be added to it again every step, and the
   * particles beside a source would overshoot it (by 9% on the bar of tests/test_heat.c) */
#pragma omp parallel for schedule(static) if (b1 - b0 > MPM_PARALLEL_MIN)
  for (long i = b0; i < b1; ++i) hv[2][i] = hv[1][i] - hv[2][i];
  size_t first = 0;
  for (int set = 0; set < s->set_count; ++set) {
    mpm_particles *p = s->sets[set].p;
    const long n = (long)p->count;
#pragma omp parallel for schedule(static) if (n > MPM_PARALLEL_MIN)
    for (long i = 0; i < n; ++i) {
      const size_t a = first + (size_t)i;
      if (h->key[a] < 0) continue;
      const uint32_t e0 = h->E.row_start[a], e1 = e0 + h->E.row_len[a];
      mpm_real change = 0, pic = 0;
      int touches = 0;
      for (uint32_t e = e0; e < e1; ++e) {
        const uint32_t col = h->E.col[e];
        change += h->E.w[e] * hv[2][col];
        pic += h->E.w[e] * hv[1][col];
        touches |= h->held[col];
      }
      const mpm_real flip = p->temperature[i] + change;
      p->temperature[i] = touches ? pic : flip + s->pic * (pic - flip);
    }
    first += p->count;
  }
  h->figures.substeps = substeps;
  h->figures.held_nodes = held;
  h->figures.seconds = now_seconds() - t0;
  return 0;
}
