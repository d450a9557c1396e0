/* implicit_multigrid.c - the multigrid preconditioner of the implicit step (solver/multigrid.h)
 * on its DOF set: the finest level's rows are the grid nodes with mass, its matrix
 * M + dt^2 K assembled from the particles (transfer/operators.h, mpm_assemble_stiffness) with
 * each particle's factored stress derivative (the one the matrix-free action applies), the
 * constraints those of the step, and the V-cycle is CG's preconditioner; and the policy of the
 * Newton solves that use it (when to build it, which cycle, when to rebuild its values). */
#include "core/parallel.h"
#include "solver/implicit.h"
#include "core/clock.h"
#include "transfer/operators.h"

#include <string.h>

/* the coarsest level solved directly: at most this many nodes (a dense factor of 3 x 64
   unknowns costs less than one fine sweep) */
#define COARSEST_NODES 64

/* Gauss-Seidel sweeps on each level per cycle (after the coarse correction in the one-pass
   cycle, before and after it in the symmetric one). Two against one, `mpm bench implicit --only
   resolution --threads 2` (one run each, one sitting): CG iterations per Newton iteration 10.0,
   9.0, 10.5 -> 7.0, 6.0, 9.0 on the soft block (dx 4, 2, 1 cm) and 5.5, 4.0, 3.5 -> 3.5, 2.5,
   2.5 on the stiff one, the step 0.08, 0.46, 2.99 -> 0.07, 0.42, 2.80 s and 0.06, 0.31, 1.96 ->
   0.07, 0.29, 1.79 s; the rubber bunny's first 0.3 s (at the CFL rate) 18.6 -> 16.6 s, its
   steps on the floor 51-57 -> 31-35 iterations. Three sweeps: fewer iterations, more time. */
#define SWEEPS 2

int mpm_implicit_multigrid_supported(const mpm_implicit *s) {
  return s->p && s->p->count > 0 && !s->levels && !s->domains && s->part_count <= 1 && s->grid &&
         mpm_grid_paged(s->grid) && s->dofs->segment_count == 1;
}

mpm_status mpm_implicit_multigrid_prepare(mpm_implicit *s) {
  const mpm_grid *g = s->grid;
  const mpm_sparse_grid *sg = &g->impl.sparse;
  const size_t nodes = sg->block_count * MPM_BLOCK_NODES;
  const mpm_real *mass = s->dofs->mass + g->dof_begin;
  s->mg_row_of = mpm_arena_alloc(s->arena, (nodes + 1) * sizeof *s->mg_row_of);
  s->mg_dof = mpm_arena_alloc(s->arena, (nodes + 1) * sizeof *s->mg_dof);
  int32_t(*coord)[3] = mpm_arena_alloc(s->arena, (nodes + 1) * sizeof *coord);
  s->mg = mpm_arena_alloc(s->arena, sizeof *s->mg);
  if (!s->mg_row_of || !s->mg_dof || !coord || !s->mg) return MPM_ERR_NOMEM;
  size_t rows = 0;
  for (size_t b = 0; b < sg->block_count; ++b)
    for (int k = 0; k < MPM_BLOCK_NODES; ++k) {
      const size_t n = b * MPM_BLOCK_NODES + (size_t)k;
      if (!(mass[n] > 0)) {
        s->mg_row_of[n] = -1;
        continue;
      }
      s->mg_row_of[n] = (int32_t)rows;
      s->mg_dof[rows] = (uint32_t)(g->dof_begin + n);
      coord[rows][0] = sg->coord[b][0] * MPM_BLOCK + ((k >> 4) & 3);
      coord[rows][1] = sg->coord[b][1] * MPM_BLOCK + ((k >> 2) & 3);
      coord[rows][2] = sg->coord[b][2] * MPM_BLOCK + (k & 3);
      ++rows;
    }
  const mpm_kernel *k = &s->tc->kernel;
  const mpm_mg_prolongation kind =
      k->kind == MPM_KERNEL_QUADRATIC ? MPM_MG_QUADRATIC : MPM_MG_LINEAR;
  const mpm_status st = mpm_multigrid_setup(s->mg, s->arena, rows, (const int32_t(*)[3])coord,
                                            k->width - 1, kind, COARSEST_NODES);
  s->mg->sweeps = SWEEPS;
  return st; /* the cycle (mg->cheap) is chosen solve by solve (implicit.c) */
}

_Static_assert(MPM_LANES == MPM_NLANES, "the assembly's batches are the tangent's lanes");
static void tangent(void *user, const uint32_t particle[MPM_LANES], int count, mpm_vl C[81]) {
  mpm_implicit_tangent(user, particle, count, C);
}

mpm_status mpm_implicit_multigrid_build(mpm_implicit *s) {
  mpm_multigrid *mg = s->mg;
  mpm_mg_level *L = &mg->level[0];
  mpm_multigrid_clear(mg);
  const mpm_status assembled =
      mpm_assemble_stiffness(s->tc, s->grid, s->p, tangent, s, s->mg_row_of, L->radius, L->val);
  if (assembled != MPM_OK) return assembled;
  mpm_multigrid_mirror_lower(mg);
  /* the lumped mass on the diagonal blocks */
  const size_t centre = L->slots / 2;
  const long n = (long)L->n;
#pragma omp parallel for schedule(static) if (n > MPM_PARALLEL_MIN)
  for (long i = 0; i < n; ++i) {
    mpm_real *D = L->val + ((size_t)i * L->slots + centre) * 9;
    const mpm_real m = s->dofs->mass[s->mg_dof[i]];
    D[0] += m, D[4] += m, D[8] += m;
  }
  /* the constraints as rows (every constrained DOF has mass, so a row) */
  const size_t nk = s->constraint_count;
  uint32_t *row = mpm_arena_alloc(s->arena, (nk + 1) * sizeof *row);
  if (!row) return MPM_ERR_NOMEM;
  for (size_t k = 0; k < nk; ++k)
    row[k] = (uint32_t)s->mg_row_of[s->constraint_dof[k] - s->grid->dof_begin];
  mpm_multigrid_factor(mg, nk, row, (const mpm_real(*)[6])s->constraint_P);
  return MPM_OK;
}

void mpm_implicit_multigrid_precondition(void *user, mpm_real *const r[3], mpm_real *const z[3]) {
  mpm_implicit *s = user;
  const double t0 = mpm_wall_seconds();
  mpm_multigrid *mg = s->mg;
  mpm_mg_level *L = &mg->level[0];
  const long n = (long)L->n;
#pragma omp parallel for schedule(static) if (n > MPM_PARALLEL_MIN)
  for (long i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) L->b[3 * i + c] = r[c][s->mg_dof[i]];
  mpm_multigrid_vcycle(mg);
  const long nd = (long)s->dofs->count;
  for (int c = 0; c < 3; ++c) memset(z[c], 0, (size_t)nd * sizeof(mpm_real));
#pragma omp parallel for schedule(static) if (n > MPM_PARALLEL_MIN)
  for (long i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) z[c][s->mg_dof[i]] = L->x[3 * i + c];
  s->mg_cycle_seconds += mpm_wall_seconds() - t0;
}

/* ---- the solve's policy: Jacobi first near balance, the one-pass cycle, the symmetric one -- */

static void cg_apply(void *user, mpm_real *const x[3], mpm_real *const y[3]) {
  mpm_implicit *s = user;
  mpm_implicit_apply(s, 1, s->apply_scale, x, y);
}

static void cg_project(void *user, mpm_real *const v[3]) {
  mpm_implicit_project(user, v);
}

static void cg_record(mpm_implicit_result *r, const mpm_cg_result *cg) {
  r->cg_iterations += cg->iterations;
  const double rel = cg->scale > 0 ? cg->residual / cg->scale : 0;
  if (rel > r->cg_residual) r->cg_residual = rel;
  if (!cg->converged) r->cg_converged = 0;
}

/* The iterations the multigrid's one-pass cycle gets before the solve goes on with the
 * symmetric cycle: on a spinning block in free flight it converged in 3.5-16 per Newton
 * iteration where the symmetric cycle took 12-15, on the rubber bunny sliding to rest with
 * friction it took 71 a step where the symmetric cycle took 21. */
#define MG_ONE_PASS_ITERATIONS 12

/* The Jacobi iterations a solve near balance gets before the multigrid is built for it: a body
 * at rest or in free fall ends within them, for less than building the hierarchy costs (the
 * assembly and the Galerkin products: some 20 Jacobi iterations on the rubber bunny). */
#define JACOBI_BEFORE_MULTIGRID 4

/* The iterations past which a Newton iteration's solve has the multigrid's values rebuilt at
 * the next iterate (the hierarchy's rows stay: the DOFs are the step's): a solve the one-pass
 * cycle did not end (MG_ONE_PASS_ITERATIONS) and the symmetric one took 20 more for. Rebuilt
 * every Newton iteration, the rubber bunny at the CFL rate (1 s, 2 threads, one sitting) took
 * 19.3 s against 18.3 s, 574 CG iterations against 666; after the solves of more than 32 (its
 * landing at 1/60 s, where the second iterate's matrix is far from the first's): 16.5-17.0 s
 * against 17.4-18.3, 606 iterations; after more than 24 or 42: 17.8, 17.5-17.6 s. */
#define MG_REBUILD_ITERATIONS (MG_ONE_PASS_ITERATIONS + 20)

/* The smallest drop of its first residual a solve may ask for and still take the multigrid's
 * one-pass cycle (see build_multigrid). */
#define MG_ONE_PASS_DROP 1e-6

/* Build the multigrid for this step's system (the matrix of the Newton iteration that first
 * needs it: a preconditioner need only be near the matrix; its values again where the last
 * solve marked them stale, MG_REBUILD_ITERATIONS) and set o's preconditioner to it. */
static mpm_status build_multigrid(mpm_implicit *s, mpm_cg_options *o, mpm_implicit_result *r) {
  if (!s->mg_built || s->mg_stale) {
    s->mg_stale = 0;
    const double t0 = mpm_wall_seconds();
    if (!s->mg_prepared && mpm_implicit_multigrid_prepare(s)) return MPM_ERR_NOMEM;
    s->mg_prepared = 1;
    if (mpm_implicit_multigrid_build(s)) return MPM_ERR_NOMEM;
    s->mg_built = 1;
    r->mg_setup_seconds += mpm_wall_seconds() - t0;
    r->mg_bytes = s->mg->bytes;
  }
  o->precondition = mpm_implicit_multigrid_precondition;
  /* the one-pass cycle (not symmetric: flexible CG) where the solve asks a drop of 1e-6 or less
     of its first residual; beyond it flexible CG stagnates (the double build's first solves, to
     1e-10: 40 iterations per Newton iteration where the symmetric cycle took 21) and the
     symmetric cycle under plain CG takes them, and also where the one-pass cycle has not ended a
     solve in MG_ONE_PASS_ITERATIONS (mpm_implicit_pcg). Not with Newmark's scheme: its flights
     solved with the one-pass cycle left the rubber bunny creeping on the floor for 20 frames
     after it landed, at 45-60 iterations a step (1 s at the CFL rate: 1,819 CG iterations
     against 627 with the symmetric cycle throughout; backward Euler's run: 606 against 847) */
  o->flexible = o->floor_drop >= MG_ONE_PASS_DROP && !s->newmark;
  return MPM_OK;
}

/* CG on (M + dt^2 K) x = b from x (cg_record'ed into r, the last solve's figures in cg). With
 * the multigrid (s->mg_wanted): where it is not built yet and the solve is near balance
 * (`near`), JACOBI_BEFORE_MULTIGRID Jacobi iterations first; a solve they do not end goes on
 * with the multigrid, from where they left x or, where they raised the residual, from x as it
 * was (a few Jacobi iterations from far out of balance raised it 50-fold on the falling rubber
 * bunny, and the multigrid then took 60 iterations where it takes 10 from the start). With the
 * multigrid, its one-pass cycle under flexible CG first, for at most MG_ONE_PASS_ITERATIONS,
 * then the symmetric cycle under plain CG (solver/multigrid.h), from where the one-pass cycle
 * stopped; cg's residual0 is the first part's, its iterations all parts'. MPM_OK, or MPM_ERR_NOMEM
 * when out of memory. */
mpm_status mpm_implicit_pcg(mpm_implicit *s, mpm_real *const D[3], mpm_real *const b[3],
                            mpm_real *const x[3], int near, const mpm_cg_options *o,
                            mpm_implicit_result *r, mpm_cg_result *cg) {
  mpm_cg_options opt = *o;
  double residual0 = -1; /* the first part's, when the solve is split */
  int left = o->max_iterations;
  if (s->mg_wanted) {
    if (!s->mg_built && near) {
      mpm_real **x0 = mpm_dofs_vector(s->dofs, "imp.x0");
      if (!x0) return MPM_ERR_NOMEM;
      mpm_dofs_copy(s->dofs, x, x0);
      opt.max_iterations = left < JACOBI_BEFORE_MULTIGRID ? left : JACOBI_BEFORE_MULTIGRID;
      if (mpm_cg_solve(s->dofs, cg_apply, cg_project, s, D, b, x, &opt, cg)) return MPM_ERR_NOMEM;
      if (cg->converged || cg->iterations >= left) {
        cg_record(r, cg);
        return MPM_OK;
      }
      r->cg_iterations += cg->iterations;
      residual0 = cg->residual0;
      left -= cg->iterations;
      if (cg->residual > cg->residual0) mpm_dofs_copy(s->dofs, x0, x);
    }
    if (build_multigrid(s, &opt, r)) return MPM_ERR_NOMEM;
  }
  if (opt.precondition && opt.flexible) {
    s->mg->cheap = 1;
    opt.max_iterations = left < MG_ONE_PASS_ITERATIONS ? left : MG_ONE_PASS_ITERATIONS;
    if (mpm_cg_solve(s->dofs, cg_apply, cg_project, s, D, b, x, &opt, cg)) return MPM_ERR_NOMEM;
    if (residual0 < 0) residual0 = cg->residual0;
    if (cg->converged || cg->iterations >= left) {
      cg_record(r, cg);
      cg->residual0 = residual0;
      cg->iterations += o->max_iterations - left; /* the Jacobi iterations' before it */
      return MPM_OK;
    }
    r->cg_iterations += cg->iterations; /* the symmetric cycle's solve reports the rest */
    left -= cg->iterations;
    opt.flexible = 0;
  }
  if (opt.precondition) s->mg->cheap = 0;
  opt.max_iterations = left;
  if (mpm_cg_solve(s->dofs, cg_apply, cg_project, s, D, b, x, &opt, cg)) return MPM_ERR_NOMEM;
  cg_record(r, cg);
  if (residual0 >= 0) cg->residual0 = residual0;
  cg->iterations += o->max_iterations - left; /* the solve's, all parts */
  return MPM_OK;
}

void mpm_implicit_multigrid_mark(mpm_implicit *s, int iterations) {
  if (s->mg_built && iterations > MG_REBUILD_ITERATIONS) s->mg_stale = 1;
}
