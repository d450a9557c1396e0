/* heat.c - heat transfer on the DOF set (see heat.h for the equations and why each part is as
 * it is). */
#define _POSIX_C_SOURCE 200809L /* clock_gettime */
#include "heat/heat.h"
#include "core/intmath.h"
#include "core/alloc.h"
#include "core/parallel.h"

#include <math.h>
#include <string.h>
#include <time.h>

/* A link of a node to a heat source closer than this fraction of a cell counts as this close:
 * the ghost-fluid conductance G / theta would otherwise need ever shorter substeps (Gibou et
 * al. 2002 clamp it likewise). */
#define THETA_MIN 0.1
/* Depths inside a source beyond this (cells) are continued no further (ghost_values). */
#define GHOST_DEPTH_MAX 1.5
/* An explicit conduction substep may take this share of the operator's stability bound
 * (1: the largest C_i / sum_j G_ij); below it the update is a convex combination. */
#define SUBSTEP_SHARE 0.9

void mpm_heat_init(mpm_heat *h) {
  memset(h, 0, sizeof *h);
  mpm_embedding_init(&h->E);
}

void mpm_heat_free(mpm_heat *h) {
  mpm_embedding_free(&h->E);
  for (int d = 0; d < 3; ++d) {
    mpm_free(h->g[d]);
    mpm_free(h->cg[d]);
  }
  mpm_free(h->capacity);
  mpm_free(h->heat);
  mpm_free(h->vol);
  mpm_free(h->vk);
  mpm_free(h->cgx);
  mpm_free(h->key);
  mpm_free(h->colour);
  mpm_free(h->key_colour);
  mpm_free(h->held);
  mpm_free(h->links);
  mpm_free(h->box_slot);
  mpm_free(h->ghosts);
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
  void **arrays[] = {(void **)&h->capacity, (void **)&h->heat,  (void **)&h->vol,
                     (void **)&h->vk,       (void **)&h->cg[0], (void **)&h->cg[1],
                     (void **)&h->cg[2],    (void **)&h->cgx};
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
  /* the 7-point operator's rate in the bulk is 6 alpha / dx^2 (heat.h); a node beside a source
   * may need more, which the step measures on the operator itself */
  const double stable = SUBSTEP_SHARE * dx * dx / (6 * alpha);
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

/* The carriers' rows: weights and gradients to the level's nodes, heat capacity, heat, volume
 * and V k per particle, and the scatter keys. MPM_OK, or MPM_ERR_INVALID when a node is
 * missing. */
static mpm_status build_rows(mpm_heat *h, const mpm_heat_step_desc *s) {
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
        h->capacity[a] = h->heat[a] = h->vol[a] = h->vk[a] = 0;
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
        h->vol[a] = mpm_fabs(J) * p->vol0[i];
        h->vk[a] = h->vol[a] * m->conductivity;
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
  return missing ? MPM_ERR_INVALID : MPM_OK;
}

/* ---- the sources: held nodes as ghosts ------------------------------------------------- */

/* A node inside a heat source that particles reach: its value continues the material's
 * temperature linearly through the source's surface, where it is the source's (Fedkiw et al.'s
 * ghost fluid, 1999), so that the field the particles read takes the source's temperature on
 * the surface itself, wherever the surface lies between nodes. The temperature is continued from
 * a probe one cell outside the surface along its normal. The conduction does not use the
 * ghosts: it reaches the surface through its own links (links()). */
#define GHOST_STENCIL (MPM_STENCIL_MAX * MPM_STENCIL_MAX * MPM_STENCIL_MAX)
typedef struct mpm_heat_ghost {
  long node;       /* the held DOF */
  mpm_real depth;  /* -phi / dx at the node, 0 .. GHOST_DEPTH_MAX: how far inside the source */
  mpm_real source; /* the source's temperature */
  int probe_count; /* 0: no probe (its nodes are not on the grid): the source's temperature */
  uint32_t probe[GHOST_STENCIL];
  mpm_real weight[GHOST_STENCIL];
} mpm_heat_ghost;

/* The ghosts' values T[node] from the free nodes' temperatures T (C: their capacities). */
static void ghost_values(const mpm_heat *h, const mpm_real *C, mpm_real *T) {
  for (size_t k = 0; k < h->ghost_count; ++k) {
    const mpm_heat_ghost *gh = &h->ghosts[k];
    mpm_real sum = 0, wsum = 0;
    for (int e = 0; e < gh->probe_count; ++e) {
      const uint32_t j = gh->probe[e];
      if (h->held[j] || !(C[j] > 0) || gh->weight[e] == 0) continue;
      sum += gh->weight[e] * T[j];
      wsum += gh->weight[e];
    }
    /* too little of the probe on free nodes (a corner of the source): the source's value */
    T[gh->node] =
        wsum > (mpm_real)0.5 ? gh->source + (gh->source - sum / wsum) * gh->depth : gh->source;
  }
}

/* The ghosts of this step's held nodes (h->held[i]: the source's index + 1), with their probes'
 * stencils on the level. 0, or -1 when out of memory. */
static int make_ghosts(mpm_heat *h, const mpm_heat_step_desc *s, size_t held) {
  h->ghost_count = 0;
  if (!held) return 0;
  if (held > h->ghost_capacity) {
    mpm_free(h->ghosts);
    h->ghosts = mpm_alloc(held * sizeof *h->ghosts);
    h->ghost_capacity = h->ghosts ? held : 0;
    if (!h->ghosts) return -1;
  }
  const mpm_grid *g = s->grid;
  const mpm_dofs *d = s->dofs;
  const long b0 = (long)g->dof_begin, b1 = b0 + (long)g->ops->node_count(g);
  const int W = s->kernel.width;
  const mpm_real dx = g->dx;
  mpm_grid_cursor cursor;
  mpm_grid_cursor_init(&cursor);
  size_t n = 0;
  for (long i = b0; i < b1 && n < held; ++i) {
    if (!h->held[i]) continue;
    const mpm_collider_pose *pose = &s->poses[h->held[i] - 1];
    mpm_real x[3], nrm[3];
    mpm_dofs_position(d, (size_t)i, x);
    const mpm_real phi = mpm_collider_phi(pose, x, nrm);
    mpm_heat_ghost *gh = &h->ghosts[n++];
    gh->node = i;
    gh->source = (mpm_real)pose->collider->desc.temperature;
    gh->depth = -phi / dx;
    if (gh->depth > (mpm_real)GHOST_DEPTH_MAX) gh->depth = (mpm_real)GHOST_DEPTH_MAX;
    if (gh->depth < 0) gh->depth = 0;
    gh->probe_count = 0;
    mpm_real p[3];
    for (int c = 0; c < 3; ++c) p[c] = x[c] + (-phi + dx) * nrm[c] - g->origin[c];
    mpm_stencil st;
    mpm_kernel_stencil(&s->kernel, p, &st);
    uint32_t nodes[GHOST_STENCIL];
    int32_t key;
    uint8_t colour;
    if (g->ops->stencil_nodes(g, st.base, W, &cursor, nodes, &key, &colour)) continue;
    int e = 0;
    for (int a = 0; a < W; ++a)
      for (int b = 0; b < W; ++b)
        for (int c = 0; c < W; ++c, ++e) {
          gh->probe[e] = (uint32_t)b0 + nodes[e];
          gh->weight[e] = st.w[0][a] * st.w[1][b] * st.w[2][c];
        }
    gh->probe_count = e;
  }
  h->ghost_count = n;
  return 0;
}

/* ---- P2G --------------------------------------------------------------------------------- */

/* P2G again with each particle's temperature continued linearly to the nodes (APIC's affine
 * P2G, Jiang et al. 2015, for a scalar): C_i T_i = sum_a w_ai C_a (T_a + g_a . (x_i - x_a)),
 * g_a the gradient at the particle of the first P2G's field (the ghosts included). The plain
 * average puts a node beside a face or a source at the temperature of the particles on one side
 * of it, a quarter to half a cell away; the continued one is exact for a linear field. With it
 * the PIC transfer back keeps a smooth profile (the two transfers' smoothing of a quadratic
 * cancels to leading order) where the plain one diffused it by about dx^2 / 4 a step. The sums
 * are scattered as C_a g_a and C_a g_a . x_a (x from the level's origin). hv[2] gets T_i^P2G,
 * hv[1] the same on the free nodes. */
static int affine_p2g(mpm_heat *h, const mpm_heat_step_desc *s, mpm_real **hv) {
  const mpm_grid *g = s->grid;
  mpm_dofs *d = s->dofs;
  mpm_real **aff = mpm_dofs_vector(d, "heat_affine");
  if (!aff) return -1;
  const mpm_real *const T = hv[1];
  size_t first = 0;
  for (int set = 0; set < s->set_count; ++set) {
    const mpm_particles *p = s->sets[set].p;
    const long n = (long)p->count;
#pragma omp parallel for schedule(static) if (n > MPM_PARALLEL_MIN)
    for (long i = 0; i < n; ++i) {
      const long a = (long)first + i;
      mpm_real gT[3] = {0, 0, 0};
      if (h->key[a] >= 0) {
        const uint32_t e0 = h->E.row_start[a], e1 = e0 + h->E.row_len[a];
        for (uint32_t e = e0; e < e1; ++e)
          for (int k = 0; k < 3; ++k) gT[k] += h->g[k][e] * T[h->E.col[e]];
      }
      mpm_real gx = 0;
      for (int k = 0; k < 3; ++k) {
        mpm_real x = p->x[k][i];
        x = x < s->clamp_lo[k] ? s->clamp_lo[k] : x > s->clamp_hi[k] ? s->clamp_hi[k] : x;
        h->cg[k][a] = h->capacity[a] * gT[k];
        gx += h->cg[k][a] * (x - g->origin[k]);
      }
      h->cgx[a] = gx;
    }
    first += p->count;
  }
  const long b0 = (long)g->dof_begin, b1 = b0 + (long)g->ops->node_count(g);
#pragma omp parallel for schedule(static) if (b1 - b0 > MPM_PARALLEL_MIN)
  for (long i = b0; i < b1; ++i) aff[0][i] = aff[1][i] = aff[2][i] = 0;
  mpm_real **hx = mpm_dofs_vector(d, "heat_moment");
  if (!hx) return -1;
#pragma omp parallel for schedule(static) if (b1 - b0 > MPM_PARALLEL_MIN)
  for (long i = b0; i < b1; ++i) hx[0][i] = 0;
  {
    const mpm_real *c[4] = {h->cg[0], h->cg[1], h->cg[2], h->cgx};
    mpm_real *const u[4] = {aff[0], aff[1], aff[2], hx[0]};
    mpm_embedding_scatter(&h->E, 4, c, u);
  }
#pragma omp parallel for schedule(static) if (b1 - b0 > MPM_PARALLEL_MIN)
  for (long i = b0; i < b1; ++i) {
    const mpm_real C = hv[0][i];
    if (!(C > 0)) continue;
    mpm_real x[3];
    mpm_dofs_position(d, (size_t)i, x);
    const mpm_real H = C * hv[2][i] + (x[0] - g->origin[0]) * aff[0][i] +
                       (x[1] - g->origin[1]) * aff[1][i] + (x[2] - g->origin[2]) * aff[2][i] -
                       hx[0][i];
    hv[2][i] = H / C;
    if (!h->held[i]) hv[1][i] = hv[2][i];
  }
  return 0;
}

/* ---- conduction -------------------------------------------------------------------------- */

/* A free node's links (heat.h): to its 6 axis neighbours (UINT32_MAX: none) with conductances,
 * and the sum of its links to sources, G / theta, and of their G T_s / theta. */
typedef struct mpm_heat_links {
  uint32_t nb[6];
  mpm_real G[6];
  mpm_real source_G, source_GT;
} mpm_heat_links;

/* The level's node boxes (grid.h: they cover its nodes, all of one size and aligned to it: the
 * sparse grid's blocks, the dense grid's slabs) in a hash by box coordinate, for the nodes'
 * neighbours: a stencil lookup would need the blocks around the neighbour as well. */
static uint64_t box_hash(const int64_t k[3]) {
  uint64_t h = (uint64_t)k[0] * 0x9E3779B97F4A7C15ull ^ (uint64_t)k[1] * 0xC2B2AE3D27D4EB4Full ^
               (uint64_t)k[2] * 0x165667B19E3779F9ull;
  return h ^ (h >> 29);
}

static int box_index_build(mpm_heat *h, const mpm_grid *g) {
  const size_t boxes = g->ops->box_count(g);
  size_t slots = 16;
  while (slots < 2 * boxes) slots *= 2;
  size_t cap = h->box_slot_capacity;
  if (grow((void **)&h->box_slot, &cap, slots, sizeof *h->box_slot)) return -1;
  h->box_slot_capacity = cap;
  h->box_slots = slots;
  for (size_t k = 0; k < slots; ++k) h->box_slot[k] = SIZE_MAX;
  const mpm_node_box b0 = g->ops->box(g, 0);
  for (int d = 0; d < 3; ++d) h->box_size[d] = b0.n[d];
  for (size_t b = 0; b < boxes; ++b) {
    const mpm_node_box box = g->ops->box(g, b);
    int64_t k[3];
    for (int d = 0; d < 3; ++d) k[d] = mpm_floor_div(box.lo[d], h->box_size[d]);
    size_t at = box_hash(k) & (slots - 1);
    while (h->box_slot[at] != SIZE_MAX) at = (at + 1) & (slots - 1);
    h->box_slot[at] = b;
  }
  return 0;
}

/* The DOF of the node at integer coordinates c of the level, or UINT32_MAX. */
static uint32_t node_at(const mpm_heat *h, const mpm_grid *g, const int32_t c[3]) {
  int64_t k[3];
  for (int d = 0; d < 3; ++d) k[d] = mpm_floor_div(c[d], h->box_size[d]);
  for (size_t at = box_hash(k) & (h->box_slots - 1);; at = (at + 1) & (h->box_slots - 1)) {
    const size_t b = h->box_slot[at];
    if (b == SIZE_MAX) return UINT32_MAX;
    const mpm_node_box box = g->ops->box(g, b);
    int inside = 1;
    for (int d = 0; d < 3; ++d) inside &= c[d] >= box.lo[d] && c[d] < box.lo[d] + box.n[d];
    if (!inside) continue;
    const size_t r = ((size_t)(c[0] - box.lo[0]) * (size_t)box.n[1] + (size_t)(c[1] - box.lo[1])) *
                         (size_t)box.n[2] +
                     (size_t)(c[2] - box.lo[2]);
    return (uint32_t)(g->dof_begin + box.first + r);
  }
}

/* The heat source nearest inside at x (the most negative phi), or -1 when x is in none. */
static int source_at(const mpm_heat_step_desc *s, const mpm_real x[3], mpm_real *phi_out) {
  int best = -1;
  mpm_real best_phi = 0;
  for (int k = 0; k < s->pose_count; ++k) {
    if (!s->poses[k].collider->desc.heat_source) continue;
    mpm_real n[3];
    const mpm_real phi = mpm_collider_phi(&s->poses[k], x, n);
    if (phi <= 0 && (best < 0 || phi < best_phi)) best = k, best_phi = phi;
  }
  if (phi_out) *phi_out = best_phi;
  return best;
}

/* Every free node's links; the largest sum_j G_ij / C_i over the links between nodes (the
 * explicit part's rate) in *rate. The
 * conductance of the face between nodes i and j is dx min(f_i, f_j) k_ij, f the nodes' material
 * volume fraction (sum_p w_ip V_p / dx^3) and k_ij the harmonic mean of the nodes' conductivities
 * (sum w V k / sum w V): dx k in the bulk (the 7-point Laplacian), less where the material thins
 * out, so that G_ij / C_i stays near alpha / dx^2 and a node at a free surface is insulated on its
 * empty side. A neighbour inside a heat source is the surface itself at theta = phi_i / (phi_i -
 * phi_j) of the way (Gibou et al. 2002): the link conducts dx min(1, 2 f_i) k_i / theta towards
 * the source's temperature. */
static int links(mpm_heat *h, const mpm_heat_step_desc *s, mpm_real **hv, mpm_real **hvol,
                 double *rate) {
  const mpm_grid *g = s->grid;
  const mpm_dofs *d = s->dofs;
  const long b0 = (long)g->dof_begin, b1 = b0 + (long)g->ops->node_count(g);
  size_t cap = h->link_capacity;
  if (grow((void **)&h->links, &cap, (size_t)(b1 - b0), sizeof *h->links)) return -1;
  h->link_capacity = cap;
  if (box_index_build(h, g)) return -1;
  const mpm_real dx = g->dx, inv_v = 1 / (dx * dx * dx);
  double worst = 0;
#pragma omp parallel reduction(max : worst) if (b1 - b0 > MPM_PARALLEL_MIN)
  {
#pragma omp for schedule(static)
    for (long i = b0; i < b1; ++i) {
      mpm_heat_links *L = &h->links[i - b0];
      L->source_G = L->source_GT = 0;
      for (int k = 0; k < 6; ++k) L->nb[k] = UINT32_MAX, L->G[k] = 0;
      const mpm_real C = hv[0][i];
      if (!(C > 0) || h->held[i] || !(hvol[0][i] > 0)) continue;
      mpm_real x[3];
      mpm_dofs_position(d, (size_t)i, x);
      int32_t c[3];
      for (int a = 0; a < 3; ++a) c[a] = (int32_t)lround((x[a] - g->origin[a]) / dx);
      const mpm_real f_i = hvol[0][i] * inv_v, k_i = hvol[1][i] / hvol[0][i];
      uint32_t nb[6];
      for (int k = 0; k < 6; ++k) {
        int32_t cj[3] = {c[0], c[1], c[2]};
        cj[k >> 1] += k & 1 ? 1 : -1;
        nb[k] = node_at(h, g, cj);
      }
      double sum = 0;
      for (int k = 0; k < 6; ++k) {
        const uint32_t j = nb[k];
        if (j == UINT32_MAX) continue;
        if (!h->held[j] && hv[0][j] > 0 && hvol[0][j] > 0) { /* material on both sides */
          const mpm_real f_j = hvol[0][j] * inv_v, k_j = hvol[1][j] / hvol[0][j];
          const mpm_real kk = k_i + k_j > 0 ? 2 * k_i * k_j / (k_i + k_j) : 0;
          L->nb[k] = j;
          L->G[k] = dx * (f_i < f_j ? f_i : f_j) * kk;
          sum += L->G[k];
          continue;
        }
        mpm_real xj[3], phi_j, phi_i, n[3];
        mpm_dofs_position(d, j, xj);
        const int src = source_at(s, xj, &phi_j);
        if (src < 0) continue; /* empty on that side: insulated */
        phi_i = mpm_collider_phi(&s->poses[src], x, n);
        double theta = phi_i > 0 ? (double)phi_i / ((double)phi_i - (double)phi_j) : 0;
        if (theta < THETA_MIN) theta = THETA_MIN;
        /* the face's material share: the node's volume fraction counts the material along the
           link too (a node half a cell from the surface has 0.83 of it); the node behind it,
           away from the source, has the same share across the link and all of it along */
        mpm_real a = f_i;
        const uint32_t o = nb[k ^ 1];
        if (o != UINT32_MAX && !h->held[o] && hvol[0][o] * inv_v > a) a = hvol[0][o] * inv_v;
        if (a > 1) a = 1;
        const double G = dx * a * k_i / theta;
        L->source_G += (mpm_real)G;
        L->source_GT += (mpm_real)(G * s->poses[src].collider->desc.temperature);
      }
      const double r = sum / C;
      if (r > worst) worst = r;
    }
  }
  /* the substeps follow from the fastest node of every process of the run */
  mpm_reduce_all(d->reduction, MPM_REDUCE_MAX, &worst, 1);
  *rate = worst;
  return 0;
}

/* One substep of C_i dT_i/dt = sum_j G_ij (T_j - T_i) + sum_s G_is (T_s - T_i) on the free
 * nodes, from T into Tn: explicit in the links between nodes, implicit in the links to sources
 * (T_i on their side taken at the substep's end), so that a node close to a source's surface,
 * whose link is up to 1 / THETA_MIN times stronger, needs no shorter substep; the result stays
 * a convex combination of T_i, its neighbours and T_s while dts sum_j G_ij <= C_i. */
static void conduct(const mpm_heat *h, long b0, long b1, mpm_real dts, const mpm_real *C,
                    const mpm_real *T, mpm_real *Tn) {
#pragma omp parallel for schedule(static) if (b1 - b0 > MPM_PARALLEL_MIN)
  for (long i = b0; i < b1; ++i) {
    if (!(C[i] > 0) || h->held[i]) {
      Tn[i] = T[i];
      continue;
    }
    const mpm_heat_links *L = &h->links[i - b0];
    mpm_real q = L->source_GT;
    for (int k = 0; k < 6; ++k)
      if (L->nb[k] != UINT32_MAX) q += L->G[k] * (T[L->nb[k]] - T[i]);
    const mpm_real r = dts / C[i];
    Tn[i] = (T[i] + r * q) / (1 + r * L->source_G);
  }
}

/* ---- the step ---------------------------------------------------------------------------- */

mpm_status mpm_heat_step(mpm_heat *h, const mpm_heat_step_desc *s) {
  const double t0 = now_seconds();
  const mpm_grid *g = s->grid;
  mpm_dofs *d = s->dofs;
  size_t rows = 0;
  for (int set = 0; set < s->set_count; ++set) rows += s->sets[set].p->count;
  const uint32_t W3 = (uint32_t)(s->kernel.width * s->kernel.width * s->kernel.width);
  if (reserve_rows(h, rows) || mpm_embedding_layout(&h->E, rows, NULL, W3)) return MPM_ERR_NOMEM;
  h->E.rows = rows;
  if (h->E.entry_capacity > h->entry_capacity || !h->g[0]) {
    for (int k = 0; k < 3; ++k) {
      mpm_free(h->g[k]);
      h->g[k] = mpm_alloc((h->E.entry_capacity + 1) * sizeof(mpm_real));
      if (!h->g[k]) {
        h->entry_capacity = 0;
        return MPM_ERR_NOMEM;
      }
    }
    h->entry_capacity = h->E.entry_capacity;
  }
  const mpm_status built = build_rows(h, s);
  if (built != MPM_OK) return built;
  const size_t keys = g->ops->scatter_key_count(g);
  if (grow((void **)&h->key_colour, &h->key_capacity, keys, 1)) return MPM_ERR_NOMEM;
  for (size_t a = 0; a < rows; ++a)
    if (h->key[a] >= 0) h->key_colour[h->key[a]] = h->colour[a];
  if (mpm_embedding_schedule(&h->E, h->key, keys, h->key_colour)) return MPM_ERR_NOMEM;

  /* the node values: C_i, T_i, T_i^P2G (vector "heat"); the material's volume and V k
   * ("heat_volume"); the next substep's T (component 0 of "heat_next") */
  mpm_real **hv = mpm_dofs_vector(d, "heat");
  mpm_real **hvol = hv ? mpm_dofs_vector(d, "heat_volume") : NULL;
  mpm_real **hn = hvol ? mpm_dofs_vector(d, "heat_next") : NULL;
  if (!hn || grow((void **)&h->held, &h->held_capacity, d->count, 1)) return MPM_ERR_NOMEM;
  const long b0 = (long)g->dof_begin, b1 = b0 + (long)g->ops->node_count(g);
#pragma omp parallel for schedule(static) if (b1 - b0 > MPM_PARALLEL_MIN)
  for (long i = b0; i < b1; ++i) hv[0][i] = hv[1][i] = hvol[0][i] = hvol[1][i] = 0;
  {
    const mpm_real *c[4] = {h->capacity, h->heat, h->vol, h->vk};
    mpm_real *const u[4] = {hv[0], hv[1], hvol[0], hvol[1]};
    mpm_embedding_scatter(&h->E, 4, c, u);
  }
  /* the first P2G's temperatures; nodes inside a source that particles reach are held */
  size_t held = 0;
  int sources = 0; /* without heat sources no node's position is needed here */
  for (int k = 0; k < s->pose_count; ++k) sources |= s->poses[k].collider->desc.heat_source;
#pragma omp parallel for schedule(static) reduction(+ : held) if (b1 - b0 > MPM_PARALLEL_MIN)
  for (long i = b0; i < b1; ++i) {
    h->held[i] = 0;
    const mpm_real C = hv[0][i];
    const mpm_real T = C > 0 ? hv[1][i] / C : 0;
    hv[1][i] = hv[2][i] = T;
    if (!(C > 0) || !sources) continue;
    mpm_real x[3];
    mpm_dofs_position(d, (size_t)i, x);
    const int k = source_at(s, x, NULL);
    if (k >= 0) {
      h->held[i] = (uint8_t)(k < 254 ? k + 1 : 255);
      ++held;
    }
  }
  if (make_ghosts(h, s, held)) return MPM_ERR_NOMEM;
  ghost_values(h, hv[0], hv[1]);
  if (affine_p2g(h, s, hv)) return MPM_ERR_NOMEM;
  ghost_values(h, hv[0], hv[1]);
  /* a ghost's FLIP increment is its own change over the step: from the value it starts with,
     not from what the particles put there (that difference, added to the particles beside a
     source every step, would heat them past the conduction) */
  for (size_t k = 0; k < h->ghost_count; ++k) hv[2][h->ghosts[k].node] = hv[1][h->ghosts[k].node];

  /* conduction, in substeps within the operator's own stability bound */
  double rate = 0;
  if (links(h, s, hv, hvol, &rate)) return MPM_ERR_NOMEM;
  const double n = ceil(s->dt * rate / SUBSTEP_SHARE);
  const int substeps = n < 1 ? 1 : n > 1e6 ? 1000000 : (int)n;
  const mpm_real dts = (mpm_real)(s->dt / substeps);
  mpm_real *T = hv[1], *Tn = hn[0];
  for (int sub = 0; sub < substeps; ++sub) {
    conduct(h, b0, b1, dts, hv[0], T, Tn);
    mpm_real *const t = T;
    T = Tn, Tn = t;
  }
  if (T != hv[1]) memcpy(hv[1] + b0, T + b0, (size_t)(b1 - b0) * sizeof *T);
  ghost_values(h, hv[0], hv[1]);

  /* back to the particles: PIC from the nodes (hv[1]), blended with the FLIP increment
   * T_p + sum_i w_ip (T_i - T_i^P2G) by the share 1 - beta, beta = 1 - exp(-4 pic alpha dt /
   * dx^2) for the particle's material: the PIC transfer's smoothing then acts per second, not
   * per step (heat.h) */
#pragma omp parallel for schedule(static) if (b1 - b0 > MPM_PARALLEL_MIN)
  for (long i = b0; i < b1; ++i) hv[2][i] = hv[1][i] - hv[2][i];
  const double scale = 4.0 * (double)s->pic * s->dt / ((double)g->dx * (double)g->dx);
  size_t first = 0;
  for (int set = 0; set < s->set_count; ++set) {
    mpm_particles *p = s->sets[set].p;
    const long np = (long)p->count;
#pragma omp parallel for schedule(static) if (np > MPM_PARALLEL_MIN)
    for (long i = 0; i < np; ++i) {
      const size_t a = first + (size_t)i;
      if (h->key[a] < 0) continue;
      const uint32_t e0 = h->E.row_start[a], e1 = e0 + h->E.row_len[a];
      mpm_real change = 0, pic = 0;
      for (uint32_t e = e0; e < e1; ++e) {
        const uint32_t col = h->E.col[e];
        change += h->E.w[e] * hv[2][col];
        pic += h->E.w[e] * hv[1][col];
      }
      const mpm_material *m = &s->materials[p->material[i]];
      const double rc = (double)m->density * (double)m->specific_heat;
      const double alpha = rc > 0 ? (double)m->conductivity / rc : 0;
      const mpm_real keep = (mpm_real)exp(-scale * alpha); /* the FLIP share, 1 - beta */
      const mpm_real flip = p->temperature[i] + change;
      p->temperature[i] = pic + keep * (flip - pic);
    }
    first += p->count;
  }
  h->figures.substeps = substeps;
  h->figures.held_nodes = held;
  h->figures.seconds = now_seconds() - t0;
  return MPM_OK;
}
