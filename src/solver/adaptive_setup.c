/* adaptive_setup.c - the multi-level grid of a scene: the tree its refinement rules make, and
 * its bodies sampled leaf by leaf (see adaptive.h). */
#include "solver/adaptive.h"

#include "core/alloc.h"
#include "scene/sample.h"
#include "solver/sim.h"

#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

_Static_assert(MPM_SCENE_LEVELS_MAX == MPM_LEVELS_MAX, "scene and grid agree on the levels");

static mpm_status oom(mpm_error *err, const char *what) {
  return mpm_error_set(err, MPM_ERR_NOMEM, "out of memory for %s", what);
}

/* The cell of `level` holding x. */
static void cell_of(const mpm_refinement *r, int level, const double x[3], int32_t cell[3]) {
  const double dx = (double)mpm_refinement_dx(r, level);
  for (int d = 0; d < 3; ++d) cell[d] = (int32_t)floor((x[d] - (double)r->origin[d]) / dx);
}

static int refine_box(const mpm_scene *sc, mpm_refinement *r, const mpm_refine_desc *rule) {
  const int L = rule->level - 1; /* cells of this level get children of the rule's level */
  const double dx = (double)mpm_refinement_dx(r, L);
  int32_t lo[3], hi[3];
  for (int d = 0; d < 3; ++d) { /* cells overlapping the box inside the domain */
    const double a = fmax(rule->min[d], sc->domain_min[d]),
                 b = fmin(rule->max[d], sc->domain_max[d]);
    /* a box face on a cell face (up to the rounding of dx in float) takes no cell beyond it */
    lo[d] = (int32_t)floor((a - (double)r->origin[d]) / dx + 1e-5);
    hi[d] = (int32_t)ceil((b - (double)r->origin[d]) / dx - 1e-5) - 1;
  }
  for (int32_t a = lo[0]; a <= hi[0]; ++a)
    for (int32_t b = lo[1]; b <= hi[1]; ++b)
      for (int32_t c = lo[2]; c <= hi[2]; ++c) {
        const int32_t cell[3] = {a, b, c};
        if (mpm_refinement_refine(r, L, cell)) return -1;
      }
  return 0;
}

/* Cells within rule->distance of the collider's surface: from level 0 down, a cell whose centre
 * is within the distance plus its half diagonal is refined and its children tested. */
static int refine_collider(mpm_sim *sim, mpm_refinement *r, const mpm_refine_desc *rule) {
  const mpm_collider_pose pose = mpm_collider_pose_at(&sim->colliders[rule->collider], 0);
  size_t n = (size_t)sim->cells[0] * (size_t)sim->cells[1] * (size_t)sim->cells[2], cap = n;
  int32_t(*cur)[3] = malloc(cap * sizeof *cur);
  if (!cur) return -1;
  size_t k = 0;
  for (int32_t a = 0; a < sim->cells[0]; ++a)
    for (int32_t b = 0; b < sim->cells[1]; ++b)
      for (int32_t c = 0; c < sim->cells[2]; ++c) {
        cur[k][0] = a;
        cur[k][1] = b;
        cur[k][2] = c;
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
        int32_t(*grown)[3] = realloc(cur, cap * sizeof *cur);
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
  free(cur);
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

/* Cells holding the body's material when it is sampled at the rule's level; with a distance,
 * the cells within it of the body's surface, on both sides (material leaving the surface stays
 * on the fine level): the sample lattice as a bitmap; the band is the lattice points of the
 * body dilated by the distance and not in the body eroded by it (the max norm, rounded up to
 * lattice steps: up to sqrt(3) times the distance away). */
static mpm_status refine_body(mpm_sim *sim, mpm_refinement *r, const mpm_refine_desc *rule,
                              mpm_error *err) {
  const mpm_scene *sc = &sim->scene;
  const double scale = ldexp(1, -rule->level), h = mpm_sample_spacing(sc, rule->body) * scale;
  mpm_particles p;
  if (mpm_particles_init(&p, 1024)) return oom(err, "a refinement rule's samples");
  mpm_status st = mpm_sample_body_kept(sc, rule->body, scale, NULL, NULL, &p, err);
  uint8_t *in = NULL, *out = NULL, *line = NULL;
  long *left = NULL;
  if (st != MPM_OK || !p.count) goto done;
  if (!(rule->distance > 0)) { /* all of the body */
    for (size_t i = 0; st == MPM_OK && i < p.count; ++i) {
      const double x[3] = {p.x[0][i], p.x[1][i], p.x[2][i]};
      int32_t cell[3];
      cell_of(r, rule->level - 1, x, cell);
      if (mpm_refinement_refine(r, rule->level - 1, cell)) st = oom(err, "the refined cells");
    }
    goto done;
  }
  const long k = (long)ceil(rule->distance / h - 1e-9);
  long lo[3], hi[3], n[3], longest = 0;
  for (int d = 0; d < 3; ++d) lo[d] = LONG_MAX, hi[d] = LONG_MIN;
  for (size_t i = 0; i < p.count; ++i)
    for (int d = 0; d < 3; ++d) {
      const long q = (long)floor(((double)p.x[d][i] - sc->domain_min[d]) / h);
      lo[d] = q < lo[d] ? q : lo[d];
      hi[d] = q > hi[d] ? q : hi[d];
    }
  for (int d = 0; d < 3; ++d) { /* room for the dilation */
    lo[d] -= k + 1;
    hi[d] += k + 1;
    n[d] = hi[d] - lo[d] + 1;
    longest = n[d] > longest ? n[d] : longest;
  }
  const size_t cells = (size_t)n[0] * (size_t)n[1] * (size_t)n[2];
  in = calloc(cells, 1);
  out = malloc(cells);
  line = malloc((size_t)longest);
  left = malloc((size_t)longest * sizeof *left);
  if (!in || !out || !line || !left) {
    st = oom(err, "a refinement rule's band");
    goto done;
  }
  for (size_t i = 0; i < p.count; ++i) {
    long q[3];
    for (int d = 0; d < 3; ++d)
      q[d] = (long)floor(((double)p.x[d][i] - sc->domain_min[d]) / h) - lo[d];
    in[(q[0] * n[1] + q[1]) * n[2] + q[2]] = 1;
  }
  for (size_t c = 0; c < cells; ++c) out[c] = !in[c];
  erode(in, n, k, 0, line, left);  /* the body deeper than the distance */
  erode(out, n, k, 1, line, left); /* the outside farther than the distance */
  for (long a = 0; a < n[0] && st == MPM_OK; ++a)
    for (long b = 0; b < n[1] && st == MPM_OK; ++b)
      for (long c = 0; c < n[2]; ++c) {
        const size_t q = ((size_t)a * (size_t)n[1] + (size_t)b) * (size_t)n[2] + (size_t)c;
        if (in[q] || out[q]) continue;
        const long idx[3] = {lo[0] + a, lo[1] + b, lo[2] + c};
        double x[3];
        int inside = 1;
        for (int d = 0; d < 3; ++d) {
          x[d] = sc->domain_min[d] + ((double)idx[d] + 0.5) * h;
          inside &= x[d] > sc->domain_min[d] && x[d] < sc->domain_max[d];
        }
        if (!inside) continue;
        int32_t cell[3];
        cell_of(r, rule->level - 1, x, cell);
        if (mpm_refinement_refine(r, rule->level - 1, cell)) {
          st = oom(err, "the refined cells");
          break;
        }
      }
done:
  free(in);
  free(out);
  free(line);
  free(left);
  mpm_particles_free(&p);
  return st;
}

static int by_level_and_box(const void *x, const void *y) {
  const mpm_transfer_grid *a = x, *b = y;
  if (a->level != b->level) return a->level < b->level ? -1 : 1;
  return a->box < b->box ? -1 : a->box > b->box;
}

/* Every transfer grid a particle can need, made once from the scene alone, in order of level
 * and box, so that a run and its resumed continuation lay the DOF set out alike: for each
 * distinct body spacing h and type q, box h / 2^q on every level where it is at most 2 cells
 * (finer levels: the particle's box meets finer leaves; coarser: it moved into coarser ones). A
 * level's own grid goes to its smallest box (the finest body's particles of the level's type); the
 * others get extra grids. */
static mpm_status make_transfer_grids(mpm_sim *sim, mpm_error *err) {
  mpm_adaptive *a = sim->adaptive;
  const mpm_scene *sc = &sim->scene;
  const mpm_refinement *r = &a->grid.tree;
  int n = 0;
  for (int b = 0; b < sc->body_count; ++b)
    for (int q = 0; q < r->levels; ++q)
      for (int L = 0; L < r->levels; ++L) { /* a particle may move into coarser leaves too */
        const double box = ldexp(a->body_box[b], -q);
        if (box > 2 * (double)mpm_refinement_dx(r, L) * (1 + 1e-6)) break;
        int seen = 0;
        for (int t = 0; t < n; ++t) seen |= a->tgrid[t].level == L && a->tgrid[t].box == box;
        if (seen) continue;
        if (n == MPM_TRANSFER_GRIDS_MAX)
          return mpm_error_set(err, MPM_ERR_INVALID,
                               "%s: the bodies' particle spacings need more than %d transfer "
                               "grids on %d levels; give more bodies the same particles_per_cell",
                               sc->path, MPM_TRANSFER_GRIDS_MAX, r->levels);
        a->tgrid[n].level = L;
        a->tgrid[n].box = box;
        ++n;
      }
  qsort(a->tgrid, (size_t)n, sizeof *a->tgrid, by_level_and_box);
  for (int t = 0; t < n; ++t) {
    mpm_transfer_grid *tg = &a->tgrid[t];
    const int own = t == 0 || a->tgrid[t - 1].level != tg->level;
    tg->G = own ? tg->level : mpm_adaptive_grid_add_extra(&a->grid, tg->level);
    if (tg->G < 0)
      return mpm_error_set(err, MPM_ERR_INVALID,
                           "%s: the bodies' particle spacings need more than %d extra transfer "
                           "grids; give more bodies the same particles_per_cell",
                           sc->path, MPM_EXTRA_GRIDS_MAX);
    tg->kernel =
        mpm_kernel_make(MPM_KERNEL_UGIMP, mpm_refinement_dx(r, tg->level), (mpm_real)tg->box);
  }
  a->tgrid_count = n;
  return MPM_OK;
}

typedef struct leaf_count {
  const mpm_scene *sc;
  const mpm_refinement *r;
  double extra; /* particles the fine leaves add to the level-0 estimate */
} leaf_count;

static void count_leaf(void *ctx, int level, const int32_t cell[3]) {
  leaf_count *c = ctx;
  const double dx = (double)mpm_refinement_dx(c->r, level), dx0 = (double)c->r->dx0;
  for (int b = 0; b < c->sc->body_count; ++b) {
    const mpm_body_desc *body = &c->sc->bodies[b];
    const double *lo = body->shape.bounds_lo, *hi = body->shape.bounds_hi;
    double overlap = 1, box = 1;
    for (int d = 0; d < 3; ++d) {
      const double a = (double)c->r->origin[d] + cell[d] * dx;
      const double w = fmin(a + dx, hi[d]) - fmax(a, lo[d]);
      overlap *= w > 0 ? w : 0;
      box *= hi[d] - lo[d];
    }
    if (!(overlap > 0) || !(box > 0)) continue;
    double n0 = 0; /* the body's level-0 count over its box: its fill */
    mpm_scene one = *c->sc;
    one.bodies = (mpm_body_desc *)body;
    one.body_count = 1;
    mpm_scene_memory_estimate(&one, &n0);
    const double fill = fmin(1, n0 / (box / (dx0 * dx0 * dx0) * body->particles_per_cell));
    c->extra +=
        overlap * fill * body->particles_per_cell / (dx0 * dx0 * dx0) * (ldexp(1, 3 * level) - 1);
  }
}

/* The particles the refined leaves add, estimated from the bodies' boxes. */
static double refined_particles(mpm_sim *sim) {
  leaf_count c = {&sim->scene, &sim->adaptive->grid.tree, 0};
  mpm_refinement_fine_leaves(c.r, count_leaf, &c);
  return c.extra;
}

mpm_status mpm_adaptive_setup(mpm_sim *sim, mpm_error *err) {
  const mpm_scene *sc = &sim->scene;
  mpm_adaptive *a = calloc(1, sizeof *a);
  if (!a) return oom(err, "the multi-level grid");
  sim->adaptive = a;
  mpm_adaptive_grid_init(&a->grid, sc->levels, sim->origin, (mpm_real)sc->dx);
  a->body_box = calloc((size_t)sc->body_count + 1, sizeof *a->body_box);
  if (!a->body_box) return oom(err, "the multi-level grid");
  for (int b = 0; b < sc->body_count; ++b) a->body_box[b] = mpm_sample_spacing(sc, b);
  mpm_refinement *r = &a->grid.tree;
  const mpm_status made = make_transfer_grids(sim, err);
  if (made != MPM_OK) return made;
  for (int k = 0; k < sc->refine_count; ++k) {
    const mpm_refine_desc *rule = &sc->refine[k];
    if (rule->kind == MPM_REFINE_BODY) {
      const mpm_status st = refine_body(sim, r, rule, err);
      if (st != MPM_OK) return st;
      continue;
    }
    if (rule->kind == MPM_REFINE_BOX ? refine_box(sc, r, rule) : refine_collider(sim, r, rule))
      return mpm_error_set(err, MPM_ERR_NOMEM,
                           "%s: domain.refine[%d]: out of memory for the refined cells (or a cell "
                           "outside the %d-level grid's coordinate range)",
                           sc->path, k, sc->levels);
  }
  /* the particles the levels will hold, before any is sampled: each body's level-0 count, and
   * for every finer leaf inside its bounding box the extra particles of that level, in the share
   * of the box the body fills */
  double n = 0;
  mpm_scene_memory_estimate(sc, &n);
  const mpm_status fits = mpm_scene_check_memory_for(sc, n + refined_particles(sim), err);
  if (fits != MPM_OK) return fits;
  /* the refined cells over the domain densely (a bit per cell, up to 64 MiB for all levels):
   * the step asks the tree for every particle */
  const int32_t lo0[3] = {-1, -1, -1},
                n0[3] = {sim->cells[0] + 2, sim->cells[1] + 2, sim->cells[2] + 2};
  if (mpm_refinement_index_dense(r, lo0, n0, (size_t)64 << 20))
    return oom(err, "the refined cells");
  return MPM_OK;
}

void mpm_adaptive_free(mpm_adaptive *a) {
  if (!a) return;
  mpm_adaptive_grid_free(&a->grid);
  free(a->body_box);
  mpm_free(a->of);
  mpm_free(a->perm);
  mpm_free(a->stable);
  mpm_free(a->ghost_of);
  mpm_free(a->boundary);
  mpm_free(a->cell);
  mpm_free(a->cell_ghost);
  mpm_free(a->moment);
  mpm_free(a->dB);
  mpm_free(a->work);
  free(a);
}

typedef struct keep_level {
  const mpm_refinement *tree;
  int level;
} keep_level;

static int in_leaf_of_level(const void *ctx, const double x[3]) {
  const keep_level *k = ctx;
  const mpm_real xr[3] = {(mpm_real)x[0], (mpm_real)x[1], (mpm_real)x[2]};
  int32_t cell[3];
  return mpm_refinement_leaf_at(k->tree, xr, cell) == k->level;
}

mpm_status mpm_adaptive_sample_body(mpm_sim *sim, int b, mpm_error *err) {
  const mpm_scene *sc = &sim->scene;
  mpm_particles *p = &sim->particles;
  const size_t start = p->count;
  for (int q = 0; q < sc->levels; ++q) {
    const size_t first = p->count;
    const keep_level k = {&sim->adaptive->grid.tree, q};
    const mpm_status st = mpm_sample_body_kept(sc, b, ldexp(1, -q), in_leaf_of_level, &k, p, err);
    if (st != MPM_OK) {
      p->count = start;
      return st;
    }
    for (size_t i = first; i < p->count; ++i) p->level[i] = q;
  }
  if (p->count == start)
    return mpm_error_set(err, MPM_ERR_INVALID,
                         "%s: bodies[%d] (\"%s\"): no particle lies inside the shape at lattice "
                         "spacing %g m (level 0); use a smaller dx or more particles_per_cell",
                         sc->path, b, sc->bodies[b].name, mpm_sample_spacing(sc, b));
  mpm_sample_spin(sc, b, p, start);
  return MPM_OK;
}

double mpm_adaptive_finest_dx(const mpm_sim *sim) {
  return sim->scene.dx / (double)(1 << (sim->scene.levels - 1));
}
