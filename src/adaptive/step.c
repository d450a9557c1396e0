/* step.c - the stages of a step on the multi-level grid (see adaptive.h). */
#include "adaptive/adaptive.h"

#include "core/alloc.h"
#include "core/parallel.h"
#include "transfer/operators.h"

#include <math.h>
#include <string.h>

static int reserve(mpm_adaptive *a, size_t n) {
  if (n <= a->capacity) return 0;
  mpm_free(a->of);
  mpm_free(a->perm);
  mpm_free(a->stable);
  a->capacity = n + n / 2 + 16;
  a->of = mpm_alloc(a->capacity);
  a->perm = mpm_alloc(a->capacity * sizeof *a->perm);
  a->stable = mpm_alloc(a->capacity);
  a->stable_step = -1; /* the flags are gone */
  if (!a->of || !a->perm || !a->stable) {
    a->capacity = 0;
    return -1;
  }
  return 0;
}

/* How far above its base cell a particle's box can reach over one step, on grid kernel k (and
 * one below, always): x lies in [base + shift, base + shift + span) cells (span 2 when bases are
 * paired: the even node below), its box reaches half_len either side, and a step moves it at
 * most one cell of the finest level (the guard refuses more, guard.c). So the box stays in cells
 * base + floor(shift - half_len - 1) .. base + ceil(shift + span + half_len + 1) - 1: one below
 * for every kernel here, 2 above for the standard uGIMP box (3 paired or wide). */
static int step_reach(const mpm_kernel *k) {
  const double span = mpm_kernel_base_mask(k) == ~0 ? 1 : 2, s = (double)k->shift,
               h = (double)k->half_len;
  if (floor(s - h - 1) < -1) return 0; /* more than one below: not kept (not reached here) */
  return (int)ceil(s + span + h + 1) - 1;
}

/* After the sorts and the reorder, in the particles' order now: whether each particle stays on
 * its transfer grid next step (the cells its box can reach are leaves of its grid's level). */
static mpm_status mark_stable(mpm_adaptive *a) {
  if (a->grid.tree.levels == 1) return MPM_OK;
  for (int t = 0; t < a->tgrid_count; ++t) {
    const mpm_transfer_grid *tg = &a->tgrid[t];
    const mpm_sparse_grid *sg = &mpm_adaptive_grid_at(&a->grid, tg->G)->impl.sparse;
    const size_t nmat = (size_t)sg->material_count;
    if (a->range[t + 1] == a->range[t]) continue;
    /* the blocks' masks from the cache (which a lookup may fill: one thread), then the
       particles' flags block by block in parallel */
    const long nb = (long)sg->owner_count;
    if (mpm_grow((void **)&a->stable_cells, &a->stable_cells_capacity, (size_t)nb + 1,
                 sizeof *a->stable_cells))
      return mpm_error_set(a->host.error, MPM_ERR_NOMEM, "out of memory classifying particles");
    uint64_t *cells = a->stable_cells;
    const int reach = step_reach(&tg->kernel);
    for (long b = 0; b < nb; ++b)
      if (mpm_adaptive_grid_block_stable_cells(&a->grid, tg->level, sg->coord[b], reach, &cells[b]))
        return mpm_error_set(a->host.error, MPM_ERR_NOMEM, "out of memory classifying particles");
    uint8_t *stable = a->stable + a->range[t];
#pragma omp parallel for schedule(static) if (nb > 64)
    for (long b = 0; b < nb; ++b)
      for (size_t m = 0; m < nmat; ++m)
        for (int c = 0; c < MPM_BLOCK_NODES; ++c) {
          const size_t q = ((size_t)b * nmat + m) * MPM_BLOCK_NODES + (size_t)c;
          const uint8_t u = (uint8_t)(cells[b] >> c & 1);
          for (uint32_t j = sg->cell_start[q]; j < sg->cell_start[q + 1]; ++j)
            stable[sg->perm[j]] = u;
        }
  }
  /* each range's transfer grid, in the order now (the arrays were permuted since classify) */
  for (int t = 0; t < a->tgrid_count; ++t)
    memset(a->of + a->range[t], t, a->range[t + 1] - a->range[t]);
  a->stable_step = *a->host.steps + 1;
  return MPM_OK;
}

/* The transfer grid of particles with box side `box` on `level` (made by
 * mpm_adaptive_make_transfer_grids), or -1. */
static int transfer_grid(const mpm_adaptive *a, int level, double box) {
  for (int t = 0; t < a->tgrid_count; ++t)
    if (a->tgrid[t].level == level && a->tgrid[t].box == box) return t;
  return -1;
}

/* Per (body, type): half its box side (as the particle's box is computed) and, per level the
 * box may meet, its transfer grid (-1 when the box is wider than 2 cells of the level), in
 * a->box_half[b * levels + q] and a->box_tgrid[(b * levels + q) * levels + L]. -1 when out of
 * memory. */
static int make_box_table(mpm_adaptive *a, int bodies) {
  const mpm_refinement *r = &a->grid.tree;
  const size_t nl = (size_t)r->levels, n = (size_t)bodies * nl;
  if (mpm_grow((void **)&a->box_half, &a->box_half_capacity, n + 1, sizeof *a->box_half) ||
      mpm_grow((void **)&a->box_tgrid, &a->box_tgrid_capacity, n * nl + 1, sizeof *a->box_tgrid))
    return -1;
  for (size_t b = 0; b < (size_t)bodies; ++b)
    for (int q = 0; q < r->levels; ++q) {
      const double box = ldexp(a->body_box[b], -q);
      a->box_half[b * nl + (size_t)q] = (mpm_real)(0.5 * box);
      for (int L = 0; L < r->levels; ++L)
        a->box_tgrid[(b * nl + (size_t)q) * nl + (size_t)L] =
            (int8_t)(box > 2 * (double)mpm_refinement_dx(r, L) * (1 + 1e-6)
                         ? -1
                         : transfer_grid(a, L, box));
    }
  return 0;
}

/* Each particle's transfer grid (Gao sec. 6.1: the finest level its box meets), in a.of. A
 * leaf that only touches the box (lattice-sampled particles' boxes end on cell faces) does not
 * count: the weights are averages of the basis over the box, and on the finest level the box
 * overlaps they are exact already, so such a particle keeps its own level's grid instead of a
 * finer grid of its own whose every slot is a ghost. The boxes of a chunk of particles are
 * computed first, in a loop the compiler vectorizes, then asked of the tree one by one. */
#define CLASSIFY_CHUNK 64
/* A coordinate of a box face (m) in level-0 cell units, as the tree's queries take it. */
static inline double in_units(mpm_real v, double origin, double dx0) {
  return ((double)v - origin) / dx0;
}

static mpm_status classify(mpm_adaptive *a) {
  const mpm_particles *p = a->host.particles;
  const mpm_refinement *r = &a->grid.tree;
  const long n = (long)p->count;
  long bad = n;
  const uint8_t *stable = a->stable_step == *a->host.steps ? a->stable : NULL;
  const int bodies = a->host.scene->body_count, levels = r->levels;
  if (make_box_table(a, bodies))
    return mpm_error_set(a->host.error, MPM_ERR_NOMEM, "out of memory classifying particles");
  const mpm_real *box_half = a->box_half;
  const int8_t *box_tgrid = a->box_tgrid;
  const double o[3] = {(double)r->origin[0], (double)r->origin[1], (double)r->origin[2]};
  const double dx0 = (double)r->dx0;
#pragma omp parallel for schedule(dynamic, 4) reduction(min : bad)
  for (long c = 0; c < (n + CLASSIFY_CHUNK - 1) / CLASSIFY_CHUNK; ++c) {
    const long i0 = c * CLASSIFY_CHUNK, m = n - i0 < CLASSIFY_CHUNK ? n - i0 : CLASSIFY_CHUNK;
    mpm_real half[CLASSIFY_CHUNK];
    double lo[3][CLASSIFY_CHUNK], hi[3][CLASSIFY_CHUNK];
    for (long k = 0; k < m; ++k) {
      const int q = p->level[i0 + k], b = p->body[i0 + k];
      half[k] = q >= 0 && q < levels && b >= 0 && b < bodies ? box_half[b * levels + q] : 0;
    }
    for (int d = 0; d < 3; ++d) {
      const mpm_real *x = p->x[d] + i0;
#pragma omp simd
      for (long k = 0; k < m; ++k) {
        lo[d][k] = in_units(x[k] - half[k], o[d], dx0);
        hi[d][k] = in_units(x[k] + half[k], o[d], dx0);
      }
    }
    for (long k = 0; k < m; ++k) {
      const long i = i0 + k;
      if (stable && stable[i]) continue; /* a.of[i] stands */
      const int q = p->level[i], b = p->body[i];
      int t = -1;
      if (q >= 0 && q < levels && b >= 0 && b < bodies) {
        const double A[3] = {lo[0][k], lo[1][k], lo[2][k]}, B[3] = {hi[0][k], hi[1][k], hi[2][k]};
        const int L = levels > 1 ? mpm_refinement_finest_level_overlapping(r, A, B) : 0;
        t = box_tgrid[(b * levels + q) * levels + L];
      }
      if (t < 0 && i < bad) bad = i;
      a->of[i] = (uint8_t)(t < 0 ? 0 : t);
    }
  }
  if (bad == n) return MPM_OK;
  const size_t i = (size_t)bad;
  const int q = p->level[i];
  if (q < 0 || q >= r->levels)
    return mpm_error_set(a->host.error, MPM_ERR_INVALID,
                         "step %lld: particle id %u has type %d, expected 0 .. %d (the grid's "
                         "levels)",
                         (long long)*a->host.steps, p->id[i], q, r->levels - 1);
  const double box = ldexp(a->body_box[p->body[i]], -q);
  double blo[3], bhi[3]; /* as classified */
  for (int d = 0; d < 3; ++d) {
    blo[d] = in_units(p->x[d][i] - (mpm_real)(0.5 * box), r->origin[d], r->dx0);
    bhi[d] = in_units(p->x[d][i] + (mpm_real)(0.5 * box), r->origin[d], r->dx0);
  }
  const int level = r->levels > 1 ? mpm_refinement_finest_level_overlapping(r, blo, bhi) : 0;
  return mpm_error_set(
      a->host.error, MPM_ERR_INVALID,
      "step %lld: particle id %u (body %d) of type %d (box %g m) at (%g, %g, %g) meets a leaf of "
      "level %d, whose spacing %g m is less than half its box: the multi-level grid transfers "
      "boxes of at most 2 cells; let the refinement change by one level at a time near the "
      "material (domain.refine)",
      (long long)*a->host.steps, p->id[i], p->body[i], q, box, (double)p->x[0][i],
      (double)p->x[1][i], (double)p->x[2][i], level, (double)mpm_refinement_dx(r, level));
}

/* Keep the particles grouped by transfer grid, the ranges in a.range. When some particles
 * changed grid, only they move: a particle outside its grid's new range trades places with
 * another, the k-th such particle of grid t (in array order) going to the k-th slot of t's new
 * range that holds a particle of another grid (as many of each). A step after a rebuild of the
 * tree moves a few percent of the particles, not all of them. When more than half would move,
 * a stable counting sort permutes the arrays whole instead. Either way the order depends only
 * on the particles, not on the threads. */
static mpm_status group(mpm_adaptive *a) {
  mpm_particles *p = a->host.particles;
  const int nt = a->tgrid_count;
  size_t count[MPM_TRANSFER_GRIDS_MAX + 1] = {0};
  int grouped = 1;
  const long n = (long)p->count;
  const uint8_t *of = a->of;
#pragma omp parallel if (n > MPM_PARALLEL_MIN)
  {
    size_t mine[MPM_TRANSFER_GRIDS_MAX + 1] = {0};
    int in_order = 1;
#pragma omp for schedule(static) nowait
    for (long i = 0; i < n; ++i) {
      mine[of[i] + 1]++;
      in_order &= i == 0 || of[i] >= of[i - 1];
    }
#pragma omp critical(mpm_group_counts)
    { /* integer sums: the same in any order */
      for (int t = 0; t <= nt; ++t) count[t] += mine[t];
      grouped &= in_order;
    }
  }
  for (int t = 0; t < nt; ++t) count[t + 1] += count[t];
  for (int t = 0; t <= nt; ++t) a->range[t] = count[t];
  if (grouped) return MPM_OK;
  if (mpm_particles_scratch(a->host.particles, a->host.iscratch, a->host.scratch_capacity))
    return mpm_error_set(a->host.error, MPM_ERR_NOMEM, "out of memory reordering particles");
  /* the slots of each new range that hold another grid's particle */
  size_t holes[MPM_TRANSFER_GRIDS_MAX + 1] = {0}, moving = 0;
  for (int t = 0; t < nt; ++t)
    for (size_t i = a->range[t]; i < a->range[t + 1]; ++i)
      if (a->of[i] != t) holes[t + 1]++, moving++;
  if (2 * moving > p->count) { /* most move: one stable counting sort */
    for (size_t i = 0; i < p->count; ++i) a->perm[count[a->of[i]]++] = (uint32_t)i;
    mpm_particles_permute(p, a->perm, *a->host.iscratch);
    return MPM_OK;
  }
  for (int t = 0; t < nt; ++t) holes[t + 1] += holes[t];
  uint32_t *dest = a->perm, *src = a->perm + moving; /* 2 moving <= n: a->perm holds n + 1 */
  size_t at_dest[MPM_TRANSFER_GRIDS_MAX], at_src[MPM_TRANSFER_GRIDS_MAX];
  for (int t = 0; t < nt; ++t) at_dest[t] = at_src[t] = holes[t];
  for (int t = 0; t < nt; ++t)
    for (size_t i = a->range[t]; i < a->range[t + 1]; ++i)
      if (a->of[i] != t) {
        dest[at_dest[t]++] = (uint32_t)i;      /* a hole of t */
        src[at_src[a->of[i]]++] = (uint32_t)i; /* a particle bound for its grid's holes */
      }
  mpm_particles_move(p, dest, src, moving, *a->host.iscratch);
  return MPM_OK;
}

mpm_status mpm_adaptive_sort(mpm_adaptive *a) {
  mpm_adaptive_grid *ag = &a->grid;
  mpm_particles *p = a->host.particles;
  if (reserve(a, p->count + 1))
    return mpm_error_set(a->host.error, MPM_ERR_NOMEM, "out of memory sorting particles");
  mpm_status st = classify(a);
  if (st == MPM_OK) st = group(a);
  if (st != MPM_OK) return st;
  /* every grid is sorted (an empty one that held blocks too: that resets them), then marked */
  int sorted[MPM_TRANSFER_GRIDS_MAX] = {0};
  for (int t = 0; t < a->tgrid_count; ++t) {
    const mpm_transfer_grid *tg = &a->tgrid[t];
    const mpm_particles v = mpm_particles_range(p, a->range[t], a->range[t + 1] - a->range[t]);
    mpm_grid *g = mpm_adaptive_grid_at(ag, tg->G);
    sorted[tg->G] = 1;
    if (!v.count && !g->impl.sparse.block_count) continue; /* empty, and already clear */
    if (g->ops->activate(g, &tg->kernel, *a->host.material_count, &v, a->host.arena)) goto nomem;
  }
  for (int G = 0; G >= 0; G = mpm_adaptive_grid_next(ag, G)) {
    if (sorted[G] || !mpm_adaptive_grid_at(ag, G)->impl.sparse.block_count) continue;
    const mpm_particles none = mpm_particles_range(p, 0, 0);
    mpm_grid *g = mpm_adaptive_grid_at(ag, G);
    const mpm_kernel k = mpm_kernel_make(MPM_KERNEL_UGIMP, g->dx, 0);
    if (g->ops->activate(g, &k, *a->host.material_count, &none, a->host.arena)) goto nomem;
  }
  size_t breaks = 0; /* the ranges' orders come apart as the material moves */
  for (int t = 0; t < a->tgrid_count; ++t)
    breaks += mpm_order_breaks(mpm_adaptive_grid_at(ag, a->tgrid[t].G)->impl.sparse.perm,
                               a->range[t + 1] - a->range[t]);
  if (p->count && mpm_reorder_due(*a->host.steps, *a->host.reorder_interval, breaks, p->count)) {
    /* into block order now and then, every range in its grid's order */
    for (int t = 0; t < a->tgrid_count; ++t) {
      uint32_t *perm = mpm_adaptive_grid_at(ag, a->tgrid[t].G)->impl.sparse.perm;
      for (size_t j = a->range[t]; j < a->range[t + 1]; ++j)
        a->perm[j] = (uint32_t)a->range[t] + perm[j - a->range[t]];
    }
    if (mpm_particles_scratch(a->host.particles, a->host.iscratch, a->host.scratch_capacity))
      return mpm_error_set(a->host.error, MPM_ERR_NOMEM, "out of memory reordering particles");
    mpm_particles_permute(p, a->perm, *a->host.iscratch);
    for (int t = 0; t < a->tgrid_count; ++t) {
      uint32_t *perm = mpm_adaptive_grid_at(ag, a->tgrid[t].G)->impl.sparse.perm;
      for (size_t j = 0; j < a->range[t + 1] - a->range[t]; ++j) perm[j] = (uint32_t)j;
    }
  }
  if (ag->tree.levels == 1) return MPM_OK; /* one level: no ghosts */
  if ((st = mark_stable(a)) != MPM_OK) return st;
  mpm_adaptive_grid_clear_marks(ag);
  for (int t = 0; t < a->tgrid_count; ++t)
    if (mpm_adaptive_grid_mark_sorted(ag, a->tgrid[t].G, a->tgrid[t].kernel.width)) goto nomem;
  if (mpm_adaptive_grid_close(ag))
    return mpm_error_set(a->host.error, MPM_ERR_NOMEM,
                         "step %lld: out of memory activating the parents of the ghost nodes (or "
                         "a node constrained through more than %d real nodes)",
                         (long long)*a->host.steps, MPM_ROW_MAX);
  return MPM_OK;
nomem:
  return mpm_error_set(a->host.error, MPM_ERR_NOMEM,
                       "step %lld: out of memory sorting %zu particles into grid blocks",
                       (long long)*a->host.steps, p->count);
}

mpm_status mpm_adaptive_layout(mpm_adaptive *a, unsigned fields) {
  mpm_adaptive_grid *ag = &a->grid;
  mpm_dofs *d = a->host.dofs;
  mpm_dofs_begin_layout(d);
  mpm_status added = MPM_OK;
  for (int G = 0; G >= 0 && added == MPM_OK; G = mpm_adaptive_grid_next(ag, G)) {
    mpm_grid *g = mpm_adaptive_grid_at(ag, G);
    if (g->impl.sparse.block_count)
      added = mpm_dofs_add_grid(d, g);
    else
      g->dof_begin = d->count; /* no nodes, no segment */
  }
  if (added != MPM_OK || mpm_dofs_end_layout(d, fields) ||
      (ag->tree.levels > 1 && mpm_adaptive_grid_build_rows(ag)))
    return mpm_error_set(a->host.error, MPM_ERR_NOMEM,
                         "step %lld: out of memory for the values of %zu grid nodes",
                         (long long)*a->host.steps, d->count);
  mpm_dofs_clear(d, fields & ~(unsigned)MPM_DOF_V);
  if (ag->tree.levels > 1 && a->host.scene->solver.transfer == MPM_TRANSFER_APIC)
    return mpm_adaptive_apic_prepare(a);
  return MPM_OK;
}

void mpm_adaptive_p2g(mpm_adaptive *a, const mpm_transfer_ctx *tc, int impulse) {
  const int apic = a->grid.tree.levels > 1 && tc->transfer == MPM_TRANSFER_APIC;
  if (apic) mpm_adaptive_apic_before_p2g(a);
  mpm_transfer_ctx t = *tc;
  for (int k = 0; k < a->tgrid_count; ++k) {
    const mpm_transfer_grid *tg = &a->tgrid[k];
    if (a->range[k + 1] == a->range[k]) continue; /* an empty grid: nothing to add */
    const mpm_particles v =
        mpm_particles_range(a->host.particles, a->range[k], a->range[k + 1] - a->range[k]);
    const mpm_grid *g = mpm_adaptive_grid_at(&a->grid, tg->G);
    const mpm_grid_values val = mpm_dofs_grid_values(a->host.dofs, g);
    /* the boundary particles' part of APIC across levels runs in the lanes */
    const mpm_ghost_apic ga =
        apic && a->boundary_count ? mpm_adaptive_apic_view(a, k) : (mpm_ghost_apic){0};
    t.ghost_apic = apic && a->boundary_count ? &ga : NULL;
    t.kernel = tg->kernel;
    if (!impulse && mpm_p2g_fuses_force(&t, g)) {
      /* the implicit solve needs the momentum and the force apart (step.c, stage_p2g) */
      mpm_p2g_mass_momentum(&t, g, &val, &v);
      mpm_p2g_stress_force(&t, g, val.f, &v);
    } else {
      mpm_p2g(&t, g, &val, &v);
    }
  }
  /* the ghosts' sums go to their real parents (Gao eq. 15) */
  if (apic) {
    mpm_adaptive_apic_after_p2g(a);
    mpm_adaptive_apic_scatter(a, impulse);
    return;
  }
  mpm_dofs *d = a->host.dofs;
  mpm_real *u[7] = {d->mass, d->v0[0], d->v0[1], d->v0[2], d->f[0], d->f[1], d->f[2]};
  mpm_adaptive_grid_scatter(&a->grid, impulse ? 4 : 7, u);
}

mpm_g2p_result mpm_adaptive_g2p(mpm_adaptive *a, const mpm_transfer_ctx *tc) {
  mpm_dofs *d = a->host.dofs;
  mpm_real *u[9] = {d->v[0], d->v[1], d->v[2]};
  const int apic = a->grid.tree.levels > 1 && tc->transfer == MPM_TRANSFER_APIC;
  int count = 3;
  if (!apic)
    for (int e = 0; e < 3; ++e) u[count++] = d->v0[e];
  if (d->vm[0]) /* the motion field, where the update set one (grid/dofs.h) */
    for (int e = 0; e < 3; ++e) u[count++] = d->vm[e];
  mpm_adaptive_grid_gather(&a->grid, count, u);
  if (apic) mpm_adaptive_apic_g2p_before(a);
  mpm_g2p_result r = {0, -1};
  mpm_transfer_ctx t = *tc;
  for (int k = 0; k < a->tgrid_count; ++k) {
    const mpm_transfer_grid *tg = &a->tgrid[k];
    if (a->range[k + 1] == a->range[k]) continue; /* no particle to update */
    mpm_particles v =
        mpm_particles_range(a->host.particles, a->range[k], a->range[k + 1] - a->range[k]);
    const mpm_grid *g = mpm_adaptive_grid_at(&a->grid, tg->G);
    const mpm_grid_values val = mpm_dofs_grid_values(a->host.dofs, g);
    const mpm_ghost_apic ga =
        apic && a->boundary_count ? mpm_adaptive_apic_view(a, k) : (mpm_ghost_apic){0};
    t.ghost_apic = apic && a->boundary_count ? &ga : NULL;
    t.kernel = tg->kernel;
    const mpm_g2p_result rk = mpm_g2p(&t, g, &val, &v);
    if (rk.max_speed > r.max_speed || rk.max_speed != rk.max_speed) r.max_speed = rk.max_speed;
    if (rk.bad_particle >= 0 && r.bad_particle < 0)
      r.bad_particle = rk.bad_particle + (long)a->range[k];
  }
  return r;
}
