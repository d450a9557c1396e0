/* resample.c - particle split and merge on the multi-level grid (Gao et al. sec. 7.2;
 * adaptive/split_merge.h for the operations, scene.h's mpm_resample_desc for the rule).
 *
 * Between steps (frame.c; every domain.resample.every steps) each particle of a resampled body is
 * compared with the leaves around it:
 *   split  its type q is coarser than the leaf holding its position: it becomes 8 of type q + 1,
 *          unless that leaf cell would then hold more than max_per_cell particles;
 *   merge  the box it would have at type q - 1, grown by merge_margin cells of level q - 1,
 *          meets no leaf finer than q - 1: it is a candidate, and the candidates of one body,
 *          material and type in one cell of level q - 1 merge 8 at a time (a seed, the lowest
 *          id left, with its 7 nearest), where the cell holds at least min_per_cell of them.
 * The margin is the hysteresis between the two (Gao's d_small .. d_large): a particle that just
 * split does not merge back until it is a margin away from the finer leaves.
 *
 * Everything is decided from the state alone, in the particles' order, with the split cubes'
 * orientations drawn from a hash of (seed, particle id, step): 1 and 2 threads, and a run
 * resumed from a checkpoint (which keeps *a->host.next_id), take the same decisions bit for bit. */
#include "adaptive/adaptive.h"

#include "adaptive/split_merge.h"
#include "core/alloc.h"
#include "core/quat.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

enum { KEEP = 0, SPLIT = 1, MERGE = 2 };

static uint64_t mix64(uint64_t x) { /* splitmix64's finalizer */
  x ^= x >> 30;
  x *= 0xbf58476d1ce4e5b9ull;
  x ^= x >> 27;
  x *= 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

/* The split cube's orientation for particle `id` at `step`. */
static void split_rotation(unsigned seed, uint32_t id, int64_t step, double R[9]) {
  uint64_t h = mix64(((uint64_t)seed << 32 | id) ^ mix64((uint64_t)step + 0x9e3779b97f4a7c15ull));
  double u[3];
  for (int k = 0; k < 3; ++k) {
    h = mix64(h + 0x9e3779b97f4a7c15ull);
    u[k] = (double)(h >> 11) * 0x1.0p-53;
  }
  double q[4];
  mpm_quat_uniform(u, q);
  mpm_quat_to_matrix(q, R);
}

/* A cell of one level, as a key. */
typedef struct cell_key {
  int32_t c[3], level;
} cell_key;

static uint64_t key_hash(const cell_key *k) {
  uint64_t h = (uint64_t)(uint32_t)k->c[0] * 0x9e3779b97f4a7c15ull;
  h ^= (uint64_t)(uint32_t)k->c[1] * 0xc2b2ae3d27d4eb4full;
  h ^= (uint64_t)(uint32_t)k->c[2] * 0x165667b19e3779f9ull;
  return mix64(h ^ (uint64_t)k->level);
}

/* Open addressing over the split candidates' leaf cells, with a particle count each. */
typedef struct cell_table {
  cell_key *keys;
  uint32_t *count;
  uint8_t *used;
  size_t size;
} cell_table;

static long table_find(const cell_table *t, const cell_key *k, int insert) {
  size_t i = key_hash(k) & (t->size - 1);
  for (;;) {
    if (!t->used[i]) {
      if (!insert) return -1;
      t->used[i] = 1;
      t->keys[i] = *k;
      return (long)i;
    }
    if (!memcmp(&t->keys[i], k, sizeof *k)) return (long)i;
    i = (i + 1) & (t->size - 1);
  }
}

/* Merge candidates, sorted into groups (body, material, type, cell of level type - 1). */
typedef struct candidate {
  int32_t body, material, type;
  cell_key cell;
  uint32_t id, index;
} candidate;

static int by_group_and_id(const void *x, const void *y) {
  const candidate *a = x, *b = y;
  const int32_t ka[7] = {a->body, a->material, a->type, a->cell.c[0], a->cell.c[1], a->cell.c[2]};
  const int32_t kb[7] = {b->body, b->material, b->type, b->cell.c[0], b->cell.c[1], b->cell.c[2]};
  for (int k = 0; k < 6; ++k)
    if (ka[k] != kb[k]) return ka[k] < kb[k] ? -1 : 1;
  return a->id < b->id ? -1 : a->id > b->id;
}

static int same_group(const candidate *a, const candidate *b) {
  return a->body == b->body && a->material == b->material && a->type == b->type &&
         !memcmp(&a->cell, &b->cell, sizeof a->cell);
}

/* The limits of body b (0 in the scene: from its particles per cell). */
static int max_per_cell(const mpm_scene *sc, int b) {
  return sc->resample.max_per_cell > 0 ? sc->resample.max_per_cell
                                       : 2 * sc->bodies[b].particles_per_cell;
}
static int min_per_cell(const mpm_scene *sc, int b) {
  const int m = sc->resample.min_per_cell > 0 ? sc->resample.min_per_cell
                                              : 4 * sc->bodies[b].particles_per_cell;
  return m < 8 ? 8 : m;
}

/* Merge the groups of candidates c[0..n) (sorted); marks the merged-away particles in gone. */
static size_t merge_groups(mpm_adaptive *a, candidate *c, size_t n, uint8_t *gone, int apic,
                           double dL[3]) {
  mpm_particles *p = a->host.particles;
  size_t merges = 0;
  for (size_t g0 = 0, g1; g0 < n; g0 = g1) {
    for (g1 = g0 + 1; g1 < n && same_group(&c[g0], &c[g1]);) ++g1;
    const size_t size = g1 - g0;
    if (size < (size_t)min_per_cell(a->host.scene, c[g0].body)) continue;
    uint8_t used[1024];
    if (size > sizeof used) continue; /* a crowded cell (beyond any limit a scene sets) */
    memset(used, 0, size);
    size_t left = size;
    for (size_t s = 0; s < size && left >= 8; ++s) {
      if (used[s]) continue;
      /* the seed and its 7 nearest unused neighbours of the group */
      uint32_t idx[8] = {c[g0 + s].index};
      double best[7];
      size_t pick[7];
      int k = 0;
      used[s] = 1;
      const uint32_t i = idx[0];
      for (size_t t = 0; t < size; ++t) {
        if (used[t]) continue;
        const uint32_t j = c[g0 + t].index;
        double d2 = 0;
        for (int d = 0; d < 3; ++d) {
          const double r = (double)p->x[d][j] - (double)p->x[d][i];
          d2 += r * r;
        }
        int at;
        if (k < 7)
          at = k++;
        else if (d2 < best[6])
          at = 6; /* the farthest of the 7 drops out */
        else
          continue;
        while (at > 0 && d2 < best[at - 1]) { /* insertion, ties kept in id order */
          best[at] = best[at - 1];
          pick[at] = pick[at - 1];
          --at;
        }
        best[at] = d2;
        pick[at] = t;
      }
      for (int m = 0; m < 7; ++m) {
        used[pick[m]] = 1;
        idx[m + 1] = c[g0 + pick[m]].index;
      }
      left -= 8;
      double L0[3], L1[3];
      mpm_particles_angular_momentum(p, idx, 8, L0);
      mpm_merge_particles(p, idx, 8, apic);
      mpm_particles_angular_momentum(p, idx, 1, L1);
      for (int d = 0; d < 3; ++d) dL[d] += L1[d] - L0[d];
      for (int m = 1; m < 8; ++m) gone[idx[m]] = 1;
      ++merges;
    }
  }
  return merges;
}

mpm_status mpm_adaptive_resample(mpm_adaptive *a) {
  const mpm_scene *sc = a->host.scene;
  const mpm_resample_desc *rd = &sc->resample;
  if (!rd->enabled || *a->host.steps % rd->every) return MPM_OK;
  const mpm_refinement *r = &a->grid.tree;
  mpm_particles *p = a->host.particles;
  const size_t n = p->count;
  const int apic = sc->solver.transfer == MPM_TRANSFER_APIC;
  /* what each particle does, and its leaf cell: step scratch (core/arena.h; the next step's
   * reset takes it back), so that resampling every step allocates nothing once warm */
  uint8_t *action = mpm_arena_alloc(a->host.arena, n + 1), *gone = NULL;
  cell_key *leaf = mpm_arena_alloc(a->host.arena, (n + 1) * sizeof *leaf);
  candidate *cand = NULL;
  cell_table t = {0};
  mpm_status st = MPM_OK;
  if (!action || !leaf) goto nomem;
  long splits = 0, merges = 0;
#pragma omp parallel for schedule(static) reduction(+ : splits, merges)
  for (long i = 0; i < (long)n; ++i) {
    const int q = p->level[i];
    action[i] = KEEP;
    const mpm_real x[3] = {p->x[0][i], p->x[1][i], p->x[2][i]};
    leaf[i].level = mpm_refinement_leaf_at(r, x, leaf[i].c);
    if (!sc->bodies[p->body[i]].resample) continue;
    if (rd->split && leaf[i].level > q) {
      action[i] = SPLIT;
      ++splits;
      continue;
    }
    /* a merge needs coarser leaves all around, its own leaf included: only a particle in a
     * leaf coarser than its type asks the tree about its box */
    if (!rd->merge || q == 0 || leaf[i].level >= q) continue;
    const double box = ldexp(a->body_box[p->body[i]], -(q - 1)),
                 grow = rd->merge_margin * (double)mpm_refinement_dx(r, q - 1);
    mpm_real lo[3], hi[3];
    for (int d = 0; d < 3; ++d) {
      lo[d] = (mpm_real)((double)x[d] - 0.5 * box - grow);
      hi[d] = (mpm_real)((double)x[d] + 0.5 * box + grow);
    }
    if (mpm_refinement_finest_level_in(r, lo, hi) <= q - 1) {
      action[i] = MERGE;
      ++merges;
    }
  }
  if (!splits && !merges) goto done;
  double dL[3] = {0};
  size_t made_merges = 0, made_splits = 0;
  if (merges) {
    cand = mpm_alloc((size_t)merges * sizeof *cand);
    gone = mpm_calloc(n + 1, 1);
    if (!cand || !gone) goto nomem;
    size_t k = 0;
    for (size_t i = 0; i < n; ++i) {
      if (action[i] != MERGE) continue;
      candidate *c = &cand[k++];
      c->body = p->body[i];
      c->material = p->material[i];
      c->type = p->level[i];
      c->id = p->id[i];
      c->index = (uint32_t)i;
      const mpm_real dx = mpm_refinement_dx(r, c->type - 1);
      c->cell.level = c->type - 1;
      for (int d = 0; d < 3; ++d)
        c->cell.c[d] = (int32_t)floor((double)(p->x[d][i] - r->origin[d]) / (double)dx);
    }
    qsort(cand, k, sizeof *cand, by_group_and_id);
    made_merges = merge_groups(a, cand, k, gone, apic, dL);
  }
  if (splits) {
    /* the particles in each split candidate's leaf cell, all bodies and types */
    t.size = 16;
    while (t.size < 2 * (size_t)splits) t.size *= 2;
    t.keys = mpm_alloc(t.size * sizeof *t.keys);
    t.count = mpm_calloc(t.size, sizeof *t.count);
    t.used = mpm_calloc(t.size, 1);
    if (!t.keys || !t.count || !t.used) goto nomem;
    for (size_t i = 0; i < n; ++i)
      if (action[i] == SPLIT) table_find(&t, &leaf[i], 1);
#pragma omp parallel for schedule(static)
    for (long i = 0; i < (long)n; ++i) {
      if (gone && gone[i]) continue;
      const long s = table_find(&t, &leaf[i], 0);
      if (s < 0) continue;
#pragma omp atomic
      t.count[s]++;
    }
    const size_t n0 = n;
    for (size_t i = 0; i < n0; ++i) {
      if (action[i] != SPLIT) continue;
      const long s = table_find(&t, &leaf[i], 0);
      if (t.count[s] + 7 > (uint32_t)max_per_cell(sc, p->body[i])) continue;
      const int q = p->level[i];
      const double L = ldexp(a->body_box[p->body[i]], -q);
      mpm_split_desc sd = {.half_diagonal = sqrt(3) / 4 * L, .apic = apic};
      if (apic) {
        /* both on the leaf's level: the parent's box meets it (at least), the children's too */
        sd.D_parent = mpm_ugimp_mean_D((double)mpm_refinement_dx(r, leaf[i].level), L);
        sd.D_child = mpm_ugimp_mean_D((double)mpm_refinement_dx(r, leaf[i].level), L / 2);
      }
      split_rotation(rd->seed, p->id[i], *a->host.steps, sd.rotation);
      const size_t first = p->count;
      double L0[3], L1[3];
      const uint32_t one = (uint32_t)i;
      mpm_particles_angular_momentum(p, &one, 1, L0);
      if (mpm_split_particle(p, i, &sd, a->host.next_id)) goto nomem;
      /* the children stay inside the domain's stencil clamp */
      for (size_t j = first; j < p->count; ++j)
        for (int d = 0; d < 3; ++d) {
          const mpm_real lo = (mpm_real)(sc->box_min[d] + sc->dx),
                         hi = (mpm_real)(sc->box_max[d] - sc->dx);
          if (p->x[d][j] < lo || p->x[d][j] > hi) p->xc[d][j] = 0;
          p->x[d][j] = p->x[d][j] < lo ? lo : p->x[d][j] > hi ? hi : p->x[d][j];
        }
      uint32_t kids[8] = {(uint32_t)i};
      for (size_t j = first; j < p->count; ++j) kids[j - first + 1] = (uint32_t)j;
      mpm_particles_angular_momentum(p, kids, 8, L1);
      for (int d = 0; d < 3; ++d) dL[d] += L1[d] - L0[d];
      t.count[s] += 7;
      ++made_splits;
    }
  }
  if (gone) { /* the appended children are past gone's end: never gone */
    uint8_t *g = mpm_realloc(gone, p->count + 1);
    if (!g) goto nomem;
    memset(g + n, 0, p->count + 1 - n);
    gone = g;
    mpm_particles_remove(p, gone);
  }
  if (made_splits || made_merges) {
    a->stable_step = -1; /* the particles moved in the arrays */
    a->resample_figures.splits += (long long)made_splits;
    a->resample_figures.merges += (long long)made_merges;
    for (int d = 0; d < 3; ++d) a->resample_figures.angular_momentum_change[d] += dL[d];
  }
  goto done;
nomem:
  st = mpm_error_set(a->host.error, MPM_ERR_NOMEM,
                     "step %lld: out of memory resampling %zu particles (domain.resample)",
                     (long long)*a->host.steps, n);
done:
  mpm_free(cand);
  mpm_free(gone);
  mpm_free(t.keys);
  mpm_free(t.count);
  mpm_free(t.used);
  return st;
}
