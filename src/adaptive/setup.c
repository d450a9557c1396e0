/* setup.c - the multi-level grid of a scene: the tree its refinement rules make, and
 * its bodies sampled leaf by leaf (see adaptive.h). */
#include "adaptive/adaptive.h"

#include "core/alloc.h"
#include "scene/memory_estimate.h"
#include "scene/sample.h"

#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

_Static_assert(MPM_SCENE_LEVELS_MAX == MPM_LEVELS_MAX, "scene and grid agree on the levels");

static mpm_status oom(mpm_error *err, const char *what) {
  return mpm_error_set(err, MPM_ERR_NOMEM, "out of memory for %s", what);
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
static mpm_status make_transfer_grids(mpm_adaptive *a, mpm_error *err) {
  const mpm_scene *sc = a->host.scene;
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
    const double dx = (double)mpm_refinement_dx(r, tg->level);
    tg->kernel = mpm_kernel_make(MPM_KERNEL_UGIMP, (mpm_real)dx, (mpm_real)tg->box);
    /* boxes near a cell wide (particles of a coarser type) lie about one per cell: paired
       bases put 8 of them in a batch of 4-wide stencils instead of 8 batches of one lane
       (mpm_kernel_paired); from 0.7 dx, where a cell holds fewer than 3 */
    if (tg->box > 0.7 * dx) tg->kernel = mpm_kernel_paired(tg->kernel);
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
static double refined_particles(mpm_adaptive *a) {
  leaf_count c = {a->host.scene, &a->grid.tree, 0};
  mpm_refinement_fine_leaves(c.r, count_leaf, &c);
  return c.extra;
}

mpm_status mpm_adaptive_setup(const mpm_adaptive_host *host, mpm_adaptive **out, mpm_error *err) {
  const mpm_scene *sc = host->scene;
  mpm_adaptive *a = mpm_calloc(1, sizeof *a);
  *out = a;
  if (!a) return oom(err, "the multi-level grid");
  a->host = *host;
  mpm_adaptive_grid_init(&a->grid, sc->levels, a->host.origin, (mpm_real)sc->dx);
  a->body_box = mpm_calloc((size_t)sc->body_count + 1, sizeof *a->body_box);
  if (!a->body_box) return oom(err, "the multi-level grid");
  for (int b = 0; b < sc->body_count; ++b) a->body_box[b] = mpm_sample_spacing(sc, b);
  mpm_refinement *r = &a->grid.tree;
  const mpm_status made = make_transfer_grids(a, err);
  if (made != MPM_OK) return made;
  const mpm_status ruled = mpm_adaptive_apply_rules(a, r, 0, err);
  if (ruled != MPM_OK) return ruled;
  /* the particles the levels will hold, before any is sampled: each body's level-0 count, and
   * for every finer leaf inside its bounding box the extra particles of that level, in the share
   * of the box the body fills */
  double n = 0;
  mpm_scene_memory_estimate(sc, &n);
  a->expected_particles = n + refined_particles(a);
  const mpm_status fits = mpm_scene_check_memory_for(sc, a->expected_particles, err);
  if (fits != MPM_OK) return fits;
  if (mpm_adaptive_index_tree(a, r)) return oom(err, "the refined cells");
  return MPM_OK;
}

void mpm_adaptive_free(mpm_adaptive *a) {
  if (!a) return;
  mpm_adaptive_grid_free(&a->grid);
  mpm_free(a->body_box);
  mpm_free(a->of);
  mpm_free(a->perm);
  mpm_free(a->stable);
  mpm_free(a->box_half);
  mpm_free(a->box_tgrid);
  mpm_free(a->ghost_of);
  mpm_free(a->block_multi);
  mpm_free(a->stable_cells);
  mpm_free(a->block_count);
  mpm_free(a->cell);
  mpm_free(a->cell_ghost);
  mpm_free(a->ghost_start);
  mpm_free(a->ghost_entry);
  mpm_free(a->moment);
  mpm_free(a->cell_of);
  mpm_free(a->affine);
  mpm_free(a);
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

mpm_status mpm_adaptive_sample_body(mpm_adaptive *a, int b, mpm_error *err) {
  const mpm_scene *sc = a->host.scene;
  mpm_particles *p = a->host.particles;
  const size_t start = p->count;
  for (int q = 0; q < sc->levels; ++q) {
    const size_t first = p->count;
    const keep_level k = {&a->grid.tree, q};
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

double mpm_adaptive_finest_dx(const mpm_adaptive *a) {
  return a->host.scene->dx / (double)(1 << (a->host.scene->levels - 1));
}
