/* implicit_multigrid.c - the multigrid preconditioner of the implicit step (solver/multigrid.h)
 * on its DOF set: the finest level's rows are the grid nodes with mass, its matrix
 * M + dt^2 K assembled from the particles (transfer/operators.h, mpm_assemble_stiffness) with
 * each particle's factored stress derivative (the one the matrix-free action applies), the
 * constraints those of the step, and the V-cycle is CG's preconditioner. */
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
  return mpm_multigrid_factor(mg, nk, row, (const mpm_real(*)[6])s->constraint_P);
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
