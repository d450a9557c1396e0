/* rules.c - the refinement rules of the multi-level grid (domain.refine; Gao et al.
 * sec. 7.1; docs/adaptive-grid.md), at setup and, with domain.refine_every, again every so many
 * steps from the material as it is then:
 *   box       the cells overlapping a box (setup and rebuilds)
 *   collider  the cells within a distance of a collider's surface, at its pose of the time
 *             (setup and rebuilds: the refinement follows a moving collider)
 *   body      the cells of a body's material sampled at the rule's level, or a band around its
 *             surface, or of either the part in a box (`within`; setup only: where its
 *             particles are born fine)
 *   surface   a band within a distance of the current material's free surface, on both sides,
 *             from the particles' boxes (rebuilds: Gao's free-surface refinement)
 *   types     the cells of level q - 1 that a particle of type q overlaps (rebuilds: the grid
 *             follows the particle types of a hyperelastic body, Gao sec. 7.1)
 *   strain    the cells that particles with ||F - I||_F above a threshold overlap (rebuilds;
 *             beyond Gao, who leave strain-driven refinement out of their scope)
 * A rebuild makes a new tree from the rules, swaps it in (caches keyed by the tree's version
 * drop what they held), and indexes it densely; particle resampling (adaptive/resample.c) then
 * makes the particle types follow it where the scene asks. The tree is kept in checkpoints. */
#include "adaptive/adaptive.h"

#include "core/alloc.h"
#include "core/clock.h"
#include "scene/sample.h"

#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The cell of `level` holding x. */
static void cell_of(const mpm_refinement *r, int level, const double x[3], int32_t cell[3]) {
  const double dx = (double)mpm_refinement_dx(r, level);
  for (int d = 0; d < 3; ++d) cell[d] = (int32_t)floor((x[d] - (double)r->origin[d]) / dx);
}

/* Refine the cells of `level` overlapping [lo, hi] (m) inside the domain. 0 or -1. */
static int refine_box_cells(const mpm_scene *sc, mpm_refinement *r, int level, const double *lo_m,
                            const double *hi_m) {
  const double dx = (double)mpm_refinement_dx(r, level);
  int32_t lo[3], hi[3];
  for (int d = 0; d < 3; ++d) {
    const double a = fmax(lo_m[d], sc->box_min[d]), b = fmin(hi_m[d], sc->box_max[d]);
    /* a box face on a cell face (up to the rounding of dx in float) takes no cell beyond it */
    lo[d] = (int32_t)floor((a - (double)r->origin[d]) / dx + 1e-5);
    hi[d] = (int32_t)ceil((b - (double)r->origin[d]) / dx - 1e-5) - 1;
  }
  for (int32_t a = lo[0]; a <= hi[0]; ++a)
    for (int32_t b = lo[1]; b <= hi[1]; ++b)
      for (int32_t c = lo[2]; c <= hi[2]; ++c) {
        const int32_t cell[3] = {a, b, c};
        if (mpm_refinement_refine(r, level, cell)) return -1;
      }
  return 0;
}

/* Cells within rule->distance of the collider's surface at time t: from level 0 down, a cell
 * whose centre is within the distance plus its half diagonal is refined and its children
 * tested. */
static int refine_collider(mpm_adaptive *a, mpm_refinement *r, const mpm_refine_desc *rule,
                           double t) {
  const mpm_collider_pose pose = mpm_collider_pose_at(&(*a->host.colliders)[rule->collider], t);
  const int *cells = a->host.cells;
  size_t n = (size_t)cells[0] * (size_t)cells[1] * (size_t)cells[2], cap = n;
  int32_t(*cur)[3] = mpm_alloc(cap * sizeof *cur);
  if (!cur) return -1;
  size_t k = 0;
  for (int32_t ci = 0; ci < cells[0]; ++ci)
    for (int32_t cj = 0; cj < cells[1]; ++cj)
      for (int32_t ck = 0; ck < cells[2]; ++ck) {
        cur[k][0] = ci;
        cur[k][1] = cj;
        cur[k][2] = ck;
        ++k;
      }
  int status = 0;
  for (int L = 0; L < rule->level && n; ++L) {
    const double dx = (double)mpm_refinement_dx(r, L), reach = rule->distance + 0.5 * sqrt(3) * dx;
    size_t kept = 0;
    for (size_t i = 0; i < n; ++i) {
      mpm_real x[3], normal[3];
      for (int d = 0; d < 3; ++d) x[d] = (mpm_real)((double)r->origin[d] + (cur[i][d] + 0.5) * dx);
      if (fabs((double)mpm_collider_phi(&pose, x, normal)) > reach) continue;
      if (mpm_refinement_refine(r, L, cur[i])) {
        status = -1;
        goto done;
      }
      for (int d = 0; d < 3; ++d) cur[kept][d] = cur[i][d];
      ++kept;
    }
    /* the children of the refined cells are the next level's candidates */
    if (L + 1 < rule->level) {
      if (kept * 8 > cap) {
        cap = kept * 8;
        int32_t(*grown)[3] = mpm_realloc(cur, cap * sizeof *cur);
        if (!grown) {
          status = -1;
          goto done;
        }
        cur = grown;
      }
      for (size_t i = kept; i-- > 0;) {
        const int32_t parent[3] = {cur[i][0], cur[i][1], cur[i][2]};
        for (int o = 0; o < 8; ++o)
          for (int d = 0; d < 3; ++d)
            cur[8 * i + (size_t)o][d] = 2 * parent[d] + ((o >> (2 - d)) & 1);
      }
      n = kept * 8;
    }
  }
done:
  mpm_free(cur);
  return status;
}

/* One pass of a separable erosion in the max norm: along axis `axis` of the n[0] x n[1] x n[2]
 * bitmap, a point stays set only when every point within k of it along the axis is set; points
 * past the ends count as `edge`. */
static void erode_axis(uint8_t *m, const long n[3], int axis, long k, int edge, uint8_t *line,
                       long *left) {
  const long stride[3] = {n[1] * n[2], n[2], 1};
  const long len = n[axis];
  const int u = axis == 0 ? 1 : 0, v = axis == 2 ? 1 : 2;
  for (long a = 0; a < n[u]; ++a)
    for (long b = 0; b < n[v]; ++b) {
      uint8_t *row = m + a * stride[u] + b * stride[v];
      for (long i = 0; i < len; ++i) line[i] = row[i * stride[axis]];
      /* runs of set points ending at i from the left, and from the right */
      long run = edge ? k + 1 : 0;
      for (long i = 0; i < len; ++i) left[i] = run = line[i] ? run + 1 : 0;
      run = edge ? k + 1 : 0;
      for (long i = len - 1; i >= 0; --i) {
        run = line[i] ? run + 1 : 0;
        row[i * stride[axis]] = (uint8_t)(left[i] > k && run > k);
      }
    }
}

static void erode(uint8_t *m, const long n[3], long k, int edge, uint8_t *line, long *left) {
  for (int axis = 0; axis < 3; ++axis) erode_axis(m, n, axis, k, edge, line, left);
}

/* Material on a lattice of spacing h (points at box_min + (idx + 1/2) h): the boxes
 * [x - L/2, x + L/2) of a set of points, each marking the lattice points inside it (the one
 * holding x when none is). */
typedef struct lattice {
  double h;
  long lo[3], n[3], k;                   /* k: the band's half width in points */
  int close;                             /* fill holes of a point first (particles' boxes) */
  const double *within_min, *within_max; /* refine only points in this box (NULL: all) */
  uint8_t *in;
} lattice;

typedef struct box_source {
  const mpm_particles *p;
  const double *L; /* per particle box side, NULL: 0 (samples) */
  const uint8_t *keep;
} box_source;

static void point_range(const mpm_scene *sc, const lattice *l, int d, double x, double L, long *a,
                        long *b) {
  const double u = (x - sc->box_min[d]) / l->h;
  *a = (long)ceil(u - 0.5 * L / l->h - 0.5);
  *b = (long)floor(u + 0.5 * L / l->h - 0.5 - 1e-9);
  if (*b < *a) *a = *b = (long)floor(u);
}

/* The lattice of the sources' boxes with room for a band of `distance`; in == NULL when there
 * is no point. 0, or -1 when out of memory. */
static int lattice_make(const mpm_scene *sc, const box_source *s, double h, double distance,
                        lattice *l) {
  memset(l, 0, sizeof *l);
  l->h = h;
  l->k = (long)ceil(distance / h - 1e-9);
  long lo[3] = {LONG_MAX, LONG_MAX, LONG_MAX}, hi[3] = {LONG_MIN, LONG_MIN, LONG_MIN};
  size_t count = 0;
  for (size_t i = 0; i < s->p->count; ++i) {
    if (s->keep && !s->keep[i]) continue;
    ++count;
    for (int d = 0; d < 3; ++d) {
      long a, b;
      point_range(sc, l, d, (double)s->p->x[d][i], s->L ? s->L[i] : 0, &a, &b);
      lo[d] = a < lo[d] ? a : lo[d];
      hi[d] = b > hi[d] ? b : hi[d];
    }
  }
  if (!count) return 0;
  size_t cells = 1;
  for (int d = 0; d < 3; ++d) { /* room for the dilation */
    l->lo[d] = lo[d] - l->k - 1;
    l->n[d] = hi[d] + l->k + 1 - l->lo[d] + 1;
    cells *= (size_t)l->n[d];
  }
  l->in = mpm_calloc(cells, 1);
  if (!l->in) return -1;
  for (size_t i = 0; i < s->p->count; ++i) {
    if (s->keep && !s->keep[i]) continue;
    long a[3], b[3];
    for (int d = 0; d < 3; ++d)
      point_range(sc, l, d, (double)s->p->x[d][i], s->L ? s->L[i] : 0, &a[d], &b[d]);
    for (long u = a[0]; u <= b[0]; ++u)
      for (long v = a[1]; v <= b[1]; ++v)
        for (long w = a[2]; w <= b[2]; ++w)
          l->in[((size_t)(u - l->lo[0]) * (size_t)l->n[1] + (size_t)(v - l->lo[1])) *
                    (size_t)l->n[2] +
                (size_t)(w - l->lo[2])] = 1;
  }
  return 0;
}

/* Refine, at `level`, the cells holding the lattice's points (k == 0: all of them) or those
 * within k points of the material's surface on either side (the points of the material
 * dilated by k and not in it eroded by k, in the max norm). 0, or -1 when out of memory. */
static int lattice_refine(const mpm_scene *sc, mpm_refinement *r, int level, lattice *l) {
  const long *n = l->n;
  const size_t cells = (size_t)n[0] * (size_t)n[1] * (size_t)n[2];
  long longest = n[0] > n[1] ? n[0] : n[1];
  longest = n[2] > longest ? n[2] : longest;
  uint8_t *out = NULL, *line = NULL;
  long *left = NULL;
  int status = 0;
  if (l->k > 0 || l->close) {
    out = mpm_alloc(cells);
    line = mpm_alloc((size_t)longest);
    left = mpm_alloc((size_t)longest * sizeof *left);
    if (!out || !line || !left) {
      status = -1;
      goto done;
    }
  }
  if (l->close) {
    /* the boxes of particles that resampling moved off a lattice leave holes of a point between
     * them: a closing (a dilation by one point, then an erosion) fills them, so that no surface
     * is seen inside the material */
    for (size_t c = 0; c < cells; ++c) out[c] = !l->in[c];
    erode(out, n, 1, 1, line, left);
    for (size_t c = 0; c < cells; ++c) l->in[c] = !out[c];
    erode(l->in, n, 1, 1, line, left);
  }
  if (l->k > 0) {
    for (size_t c = 0; c < cells; ++c) out[c] = !l->in[c];
    erode(l->in, n, l->k, 0, line, left); /* the material deeper than the distance */
    erode(out, n, l->k, 1, line, left);   /* the outside farther than the distance */
  }
  for (long a = 0; a < n[0] && !status; ++a)
    for (long b = 0; b < n[1] && !status; ++b)
      for (long c = 0; c < n[2]; ++c) {
        const size_t q = ((size_t)a * (size_t)n[1] + (size_t)b) * (size_t)n[2] + (size_t)c;
        if (l->k > 0 ? l->in[q] || out[q] : !l->in[q]) continue;
        const long idx[3] = {l->lo[0] + a, l->lo[1] + b, l->lo[2] + c};
        double x[3];
        int inside = 1;
        for (int d = 0; d < 3; ++d) {
          x[d] = sc->box_min[d] + ((double)idx[d] + 0.5) * l->h;
          inside &= x[d] > sc->box_min[d] && x[d] < sc->box_max[d];
          if (l->within_min) inside &= x[d] >= l->within_min[d] && x[d] <= l->within_max[d];
        }
        if (!inside) continue;
        int32_t cell[3];
        cell_of(r, level, x, cell);
        if (mpm_refinement_refine(r, level, cell)) {
          status = -1;
          break;
        }
      }
done:
  mpm_free(out);
  mpm_free(line);
  mpm_free(left);
  return status;
}

/* A body rule at setup: the body sampled at the rule's level. */
static mpm_status refine_body(mpm_adaptive *a, mpm_refinement *r, const mpm_refine_desc *rule,
                              mpm_error *err) {
  const mpm_scene *sc = a->host.scene;
  const double scale = ldexp(1, -rule->level), h = mpm_sample_spacing(sc, rule->body) * scale;
  mpm_particles p;
  if (mpm_particles_init(&p, 1024)) return MPM_ERR_NOMEM;
  mpm_status st = mpm_sample_body_kept(sc, rule->body, scale, NULL, NULL, &p, err);
  if (st == MPM_OK) {
    const box_source s = {&p, NULL, NULL};
    lattice l;
    const int failed = lattice_make(sc, &s, h, rule->distance, &l);
    if (rule->within) { /* the band is of the whole body; only its part in the box is refined */
      l.within_min = rule->min;
      l.within_max = rule->max;
    }
    if (failed || (l.in && lattice_refine(sc, r, rule->level - 1, &l))) st = MPM_ERR_NOMEM;
    mpm_free(l.in);
  }
  mpm_particles_free(&p);
  return st;
}

/* The particles' box sides (their type's particle spacing), in a new array. */
static double *particle_boxes(const mpm_adaptive *a) {
  const mpm_particles *p = a->host.particles;
  double *L = mpm_alloc((p->count + 1) * sizeof *L);
  if (!L) return NULL;
  for (size_t i = 0; i < p->count; ++i) L[i] = ldexp(a->body_box[p->body[i]], -p->level[i]);
  return L;
}

/* A surface rule: the band around the current material (of one body, or all). */
static int refine_surface(mpm_adaptive *a, mpm_refinement *r, const mpm_refine_desc *rule,
                          const double *L) {
  const mpm_particles *p = a->host.particles;
  uint8_t *keep = NULL;
  if (rule->body >= 0) {
    keep = mpm_alloc(p->count + 1);
    if (!keep) return -1;
    for (size_t i = 0; i < p->count; ++i) keep[i] = p->body[i] == rule->body;
  }
  const box_source s = {p, L, keep};
  lattice l;
  /* the lattice of the rule's level's cells: a particle's box covers about one */
  int failed = lattice_make(a->host.scene, &s, (double)mpm_refinement_dx(r, rule->level),
                            rule->distance + (double)mpm_refinement_dx(r, rule->level), &l);
  if (!failed && l.in) {
    l.close = 1;
    l.k = (long)ceil(rule->distance / l.h - 1e-9); /* the room above has the closing's point */
    failed = lattice_refine(a->host.scene, r, rule->level - 1, &l);
  }
  mpm_free(l.in);
  mpm_free(keep);
  return failed ? -1 : 0;
}

/* Types and strain rules: the cells of level `level` - 1 (types: the particle's type - 1,
 * at most the rule's) that the selected particles' boxes overlap. Each particle marks its cells
 * in a bitmap of the level's cells over the domain (many particles share a cell), and the
 * marked cells are refined once each. */
static int refine_particles(mpm_adaptive *a, mpm_refinement *r, const mpm_refine_desc *rule,
                            const double *L) {
  const mpm_particles *p = a->host.particles;
  const mpm_scene *sc = a->host.scene;
  uint8_t *marks[MPM_LEVELS_MAX] = {0};
  long n[MPM_LEVELS_MAX][3];
  int status = 0;
  for (size_t i = 0; i < p->count && !status; ++i) {
    int level = rule->level;
    if (rule->kind == MPM_REFINE_TYPES) {
      if (p->level[i] < 1) continue;
      level = p->level[i] < rule->level ? p->level[i] : rule->level;
    } else {
      double e = 0;
      for (int c = 0; c < 9; ++c) {
        const double f = (double)p->F[c][i] - (c % 4 == 0);
        e += f * f;
      }
      if (!(e > rule->strain * rule->strain)) continue;
    }
    const int Lc = level - 1; /* the level of the cells refined */
    const double dx = (double)mpm_refinement_dx(r, Lc);
    if (!marks[Lc]) {
      size_t bytes = 1;
      for (int d = 0; d < 3; ++d) bytes *= (size_t)(n[Lc][d] = (long)a->host.cells[d] << Lc);
      if (bytes > ((size_t)64 << 20) || !(marks[Lc] = mpm_calloc(bytes, 1))) {
        status = -1; /* a grid this fine marks through the tree itself: not built */
        break;
      }
    }
    long lo[3], hi[3];
    for (int d = 0; d < 3; ++d) {
      const double x = (double)p->x[d][i] - sc->box_min[d], h = 0.5 * L[i] + rule->distance;
      lo[d] = (long)floor((x - h) / dx);
      hi[d] = (long)floor((x + h) / dx);
      lo[d] = lo[d] < 0 ? 0 : lo[d];
      hi[d] = hi[d] >= n[Lc][d] ? n[Lc][d] - 1 : hi[d];
    }
    for (long ci = lo[0]; ci <= hi[0]; ++ci)
      for (long cj = lo[1]; cj <= hi[1]; ++cj)
        for (long ck = lo[2]; ck <= hi[2]; ++ck)
          marks[Lc][((size_t)ci * (size_t)n[Lc][1] + (size_t)cj) * (size_t)n[Lc][2] + (size_t)ck] =
              1;
  }
  for (int Lc = 0; Lc < MPM_LEVELS_MAX && !status; ++Lc) {
    if (!marks[Lc]) continue;
    const int32_t offset[3] = {
        (int32_t)lround((sc->box_min[0] - (double)r->origin[0]) / (double)mpm_refinement_dx(r, Lc)),
        (int32_t)lround((sc->box_min[1] - (double)r->origin[1]) / (double)mpm_refinement_dx(r, Lc)),
        (int32_t)lround((sc->box_min[2] - (double)r->origin[2]) /
                        (double)mpm_refinement_dx(r, Lc))};
    size_t q = 0;
    for (long ci = 0; ci < n[Lc][0] && !status; ++ci)
      for (long cj = 0; cj < n[Lc][1] && !status; ++cj)
        for (long ck = 0; ck < n[Lc][2]; ++ck, ++q) {
          if (!marks[Lc][q]) continue;
          const int32_t cell[3] = {(int32_t)ci + offset[0], (int32_t)cj + offset[1],
                                   (int32_t)ck + offset[2]};
          if (mpm_refinement_refine(r, Lc, cell)) {
            status = -1;
            break;
          }
        }
  }
  for (int Lc = 0; Lc < MPM_LEVELS_MAX; ++Lc) mpm_free(marks[Lc]);
  return status;
}

mpm_status mpm_adaptive_apply_rules(mpm_adaptive *a, mpm_refinement *r, int rebuild,
                                    mpm_error *err) {
  const mpm_scene *sc = a->host.scene;
  double *L = NULL;
  if (rebuild && !(L = particle_boxes(a))) goto nomem;
  for (int k = 0; k < sc->refine_count; ++k) {
    const mpm_refine_desc *rule = &sc->refine[k];
    int failed = 0;
    switch (rule->kind) {
    case MPM_REFINE_BOX:
      failed = refine_box_cells(sc, r, rule->level - 1, rule->min, rule->max);
      break;
    case MPM_REFINE_COLLIDER:
      failed = refine_collider(a, r, rule, rebuild ? *a->host.time : 0);
      break;
    case MPM_REFINE_BODY:
      if (!rebuild) {
        const mpm_status st = refine_body(a, r, rule, err);
        if (st == MPM_ERR_NOMEM) goto nomem;
        if (st != MPM_OK) return st;
      }
      break;
    case MPM_REFINE_SURFACE:
      failed = rebuild && refine_surface(a, r, rule, L);
      break;
    case MPM_REFINE_TYPES:
    case MPM_REFINE_STRAIN:
      failed = rebuild && refine_particles(a, r, rule, L);
      break;
    }
    if (failed) {
      mpm_free(L);
      return mpm_error_set(err, MPM_ERR_NOMEM,
                           "%s: domain.refine[%d]: out of memory for the refined cells (or a "
                           "cell outside the %d-level grid's coordinate range)",
                           sc->path, k, sc->levels);
    }
  }
  mpm_free(L);
  return MPM_OK;
nomem:
  mpm_free(L);
  return mpm_error_set(err, MPM_ERR_NOMEM, "%s: out of memory for the refined cells", sc->path);
}

mpm_status mpm_adaptive_index_tree(mpm_adaptive *a, mpm_refinement *r) {
  /* the refined cells over the domain densely (a bit per cell, up to 64 MiB for all levels):
   * the step asks the tree for every particle */
  const int32_t lo0[3] = {-1, -1, -1},
                n0[3] = {a->host.cells[0] + 2, a->host.cells[1] + 2, a->host.cells[2] + 2};
  return mpm_refinement_index_dense(r, lo0, n0, (size_t)64 << 20);
}

/* Put tree `t` in place of the current one (which is freed). */
static void swap_tree(mpm_adaptive *a, mpm_refinement *t) {
  /* caches keyed by the version hold the old tree's: the new one's is beyond every old one */
  t->version += a->grid.tree.version + 1;
  mpm_refinement_free(&a->grid.tree);
  a->grid.tree = *t;
  a->stable_step = -1;
}

mpm_status mpm_adaptive_refine(mpm_adaptive *a) {
  const mpm_scene *sc = a->host.scene;
  if (sc->refine_every <= 0 || *a->host.steps % sc->refine_every) return MPM_OK;
  mpm_refinement t;
  mpm_refinement_init(&t, sc->levels, a->grid.tree.origin, a->grid.tree.dx0);
  const double t0 = mpm_wall_seconds();
  mpm_status st = mpm_adaptive_apply_rules(a, &t, 1, a->host.error);
  if (st == MPM_OK && mpm_adaptive_index_tree(a, &t))
    st = mpm_error_set(a->host.error, MPM_ERR_NOMEM,
                       "step %lld: out of memory for the refined cells", (long long)*a->host.steps);
  if (st != MPM_OK) {
    mpm_refinement_free(&t);
    return st;
  }
  /* the material moved less than the rules see: the same tree, whose caches (ghost rows, block
   * flags, the particles' stable flags) stay valid */
  if (mpm_refinement_same_cells(&t, &a->grid.tree))
    mpm_refinement_free(&t), a->unchanged_rebuilds++;
  else
    swap_tree(a, &t);
  a->rebuilds++;
  a->rebuild_seconds += mpm_wall_seconds() - t0;
  return MPM_OK;
}

/* ---- the tree in checkpoints ---- */

typedef struct cell_list {
  int32_t (*cells)[4];
  size_t count, capacity;
  int failed;
} cell_list;

static void collect_refined(void *ctx, int level, const int32_t cell[3]) {
  cell_list *l = ctx;
  if (l->failed) return;
  if (l->count == l->capacity) {
    const size_t cap = l->capacity ? 2 * l->capacity : 256;
    int32_t(*grown)[4] = mpm_realloc(l->cells, cap * sizeof *grown);
    if (!grown) {
      l->failed = 1;
      return;
    }
    l->cells = grown;
    l->capacity = cap;
  }
  int32_t *c = l->cells[l->count++];
  c[0] = level;
  c[1] = cell[0];
  c[2] = cell[1];
  c[3] = cell[2];
}

int32_t (*mpm_adaptive_tree_cells(const mpm_adaptive *a, size_t *count))[4] {
  cell_list l = {0};
  *count = 0;
  if (!a) return NULL;
  mpm_refinement_refined_cells(&a->grid.tree, collect_refined, &l);
  if (l.failed) {
    mpm_free(l.cells);
    return NULL;
  }
  *count = l.count;
  if (!l.cells) l.cells = mpm_alloc(sizeof *l.cells); /* an empty tree: not a failure */
  return l.cells;
}

mpm_status mpm_adaptive_set_tree(mpm_adaptive *a, const int32_t (*cells)[4], size_t count,
                                 mpm_error *err) {
  mpm_refinement t;
  mpm_refinement_init(&t, a->host.scene->levels, a->grid.tree.origin, a->grid.tree.dx0);
  for (size_t i = 0; i < count; ++i) {
    if (cells[i][0] < 0 || cells[i][0] >= a->host.scene->levels - 1 ||
        mpm_refinement_refine(&t, cells[i][0], cells[i] + 1)) {
      mpm_refinement_free(&t);
      return mpm_error_set(err, MPM_ERR_INVALID,
                           "refined cell %zu (level %d) is outside the %d-level grid", i,
                           cells[i][0], a->host.scene->levels);
    }
  }
  if (mpm_adaptive_index_tree(a, &t)) {
    mpm_refinement_free(&t);
    return mpm_error_set(err, MPM_ERR_NOMEM, "out of memory for the refined cells");
  }
  swap_tree(a, &t);
  return MPM_OK;
}
