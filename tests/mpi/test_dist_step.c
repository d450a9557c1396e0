/* test_dist_step.c - explicit steps on ranks (src/dist/dist_sim.h) against the same scene on one
 * process: an elastic block thrown sideways and spinning, falling onto a floor, so that
 * particles cross the ranks' ranges every step. After 60 steps of a fixed dt every particle
 * (found by its id) is where the single process has it: within 1e-5 of the body's extent in
 * position and of its largest speed in velocity (the ranks add a node's sums in another order),
 * bit for bit on one rank; no particle is lost or doubled and each keeps its mass to the bit;
 * two runs on the same rank count agree bit for bit. On 2 ranks and more, particles migrated
 * and ghost blocks were exchanged. Cut again whenever a rank holds 1% more particles than the
 * mean, the run stays as close to one process. The bytes a step exchanges grow with the cut's
 * surface (a cube of twice the side: 2.6-3.1 times, not the volume's 8). A value blown up on
 * one rank stops every rank in the same step. A scene the ranks cannot
 * run yet is refused on every rank. */
#include "dist/comm.h"
#include "dist/dist_sim.h"
#include "sim/sim.h"
#include "mpi_check.h"

#include <math.h>
#include <mpi.h>
#include <mpm/mpm.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *const scene =
    "{\"domain\": {\"min\": [0, 0, 0], \"max\": [1, 1, 1], \"dx\": 0.025},"
    " \"time\": {\"end\": 1},"
    " \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\", \"E\": 1e5, \"nu\": 0.3,"
    "  \"density\": 1000}],"
    " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.45, 0.2, 0.5],"
    "  \"half_extent\": [0.15, 0.1, 0.12]}, \"material\": \"m\","
    "  \"velocity\": [1.5, -0.5, 0.3], \"angular_velocity\": [0, 0, 4]}],"
    " \"colliders\": [{\"shape\": {\"type\": \"halfspace\", \"point\": [0, 0.08, 0],"
    "  \"normal\": [0, 1, 0]}, \"rule\": \"slip\"}]}";

enum { STEPS = 60 };
static const double DT = 4e-4;

typedef struct state {
  long count;
  uint32_t *id;
  double *xv; /* 7 per particle: x, v, mass; in id order */
} state;

static double real_at(const void *a, size_t real_size, size_t i) {
  return real_size == 4 ? (double)((const float *)a)[i] : ((const double *)a)[i];
}

static int by_id(const void *a, const void *b) {
  const uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
  return x < y ? -1 : x > y;
}

/* Every particle of the run (all ranks' when gather), sorted by id, on rank 0. */
static state collect(const mpm_sim *sim, int gather) {
  const mpm_particle_view v = mpm_sim_particles(sim);
  const size_t stride = v.component_stride;
  double *mine = malloc((v.count * 8 + 1) * sizeof *mine);
  for (size_t i = 0; i < v.count; ++i) {
    mine[8 * i] = v.id[i];
    for (int d = 0; d < 3; ++d) {
      mine[8 * i + 1 + d] = real_at((const char *)v.x[0] + d * stride, v.real_size, i);
      mine[8 * i + 4 + d] = real_at((const char *)v.v[0] + d * stride, v.real_size, i);
    }
    mine[8 * i + 7] = real_at(v.mass, v.real_size, i);
  }
  int n = (int)(8 * v.count), *counts = NULL, *at = NULL, total = n;
  double *all = mine;
  if (gather) {
    counts = malloc((size_t)size * sizeof *counts);
    at = malloc((size_t)size * sizeof *at);
    MPI_Gather(&n, 1, MPI_INT, counts, 1, MPI_INT, 0, MPI_COMM_WORLD);
    total = 0;
    if (rank == 0)
      for (int r = 0; r < size; ++r) at[r] = total, total += counts[r];
    all = malloc(((size_t)total + 1) * sizeof *all);
    MPI_Gatherv(mine, n, MPI_DOUBLE, all, counts, at, MPI_DOUBLE, 0, MPI_COMM_WORLD);
    free(mine);
  }
  state s = {total / 8, NULL, NULL};
  /* sort the 8-value records by id (the id is exact in a double) */
  typedef struct rec {
    uint32_t id;
    double r[8];
  } rec;
  rec *recs = malloc(((size_t)s.count + 1) * sizeof *recs);
  for (long i = 0; i < s.count; ++i) {
    recs[i].id = (uint32_t)all[8 * i];
    memcpy(recs[i].r, all + 8 * i, sizeof recs[i].r);
  }
  qsort(recs, (size_t)s.count, sizeof *recs, by_id);
  s.id = malloc(((size_t)s.count + 1) * sizeof *s.id);
  s.xv = malloc(((size_t)s.count * 7 + 1) * sizeof *s.xv);
  for (long i = 0; i < s.count; ++i) {
    s.id[i] = recs[i].id;
    memcpy(s.xv + 7 * i, recs[i].r + 1, 7 * sizeof(double));
  }
  free(recs);
  free(all);
  free(counts);
  free(at);
  return s;
}

static mpm_sim *make(void) {
  return mpi_check_sim(scene);
}

/* STEPS steps on the ranks; the particles on rank 0 (and the figures summed over ranks). */
static state run_on_ranks(mpm_dist *d, double rebalance, long *migrated, long *ghosts,
                          long *rebalances) {
  mpm_sim *sim = make();
  mpm_error err;
  CHECK(mpm_dist_attach(d, sim, &err) == MPM_OK, "attach: %s", err.message);
  mpm_dist_set_rebalance(sim, rebalance);
  long moved = 0, ghost = 0;
  for (int k = 0; k < STEPS; ++k) {
    CHECK(mpm_sim_step(sim, DT) == MPM_OK, "step %d: %s", k, mpm_sim_last_error(sim));
    const mpm_dist_figures f = mpm_dist_sim_figures(sim);
    moved += (long)f.migration.sent;
    ghost += (long)f.ghost_blocks;
  }
  MPI_Allreduce(&moved, migrated, 1, MPI_LONG, MPI_SUM, MPI_COMM_WORLD);
  MPI_Allreduce(&ghost, ghosts, 1, MPI_LONG, MPI_SUM, MPI_COMM_WORLD);
  *rebalances = (long)mpm_dist_sim_figures(sim).rebalances;
  state s = collect(sim, 1);
  mpm_sim_destroy(sim);
  return s;
}

static void compare(const state *ranks, const state *one) {
  CHECK(ranks->count == one->count, "%ld particles on the ranks, %ld on one process", ranks->count,
        one->count);
  if (ranks->count != one->count) return;
  CHECK(!memcmp(ranks->id, one->id, (size_t)one->count * sizeof *one->id),
        "not the same particle ids");
  double lo[3] = {1e30, 1e30, 1e30}, hi[3] = {-1e30, -1e30, -1e30}, vmax = 0;
  for (long i = 0; i < one->count; ++i)
    for (int d = 0; d < 3; ++d) {
      lo[d] = fmin(lo[d], one->xv[7 * i + d]);
      hi[d] = fmax(hi[d], one->xv[7 * i + d]);
      vmax = fmax(vmax, fabs(one->xv[7 * i + 3 + d]));
    }
  const double extent = fmax(hi[0] - lo[0], fmax(hi[1] - lo[1], hi[2] - lo[2]));
  double dx = 0, dv = 0;
  int mass_bits = 1;
  for (long i = 0; i < one->count; ++i) {
    for (int d = 0; d < 3; ++d) {
      dx = fmax(dx, fabs(ranks->xv[7 * i + d] - one->xv[7 * i + d]));
      dv = fmax(dv, fabs(ranks->xv[7 * i + 3 + d] - one->xv[7 * i + 3 + d]));
    }
    mass_bits &= ranks->xv[7 * i + 6] == one->xv[7 * i + 6];
  }
  printf("%d ranks: %ld particles, largest difference from one process: position %.3g of the "
         "extent, velocity %.3g of the largest speed\n",
         size, one->count, dx / extent, dv / vmax);
  CHECK(mass_bits, "a particle's mass changed");
  CHECK(dx <= 1e-5 * extent, "position differs by %.3g m (extent %.3g m)", dx, extent);
  CHECK(dv <= 1e-5 * vmax, "velocity differs by %.3g m/s (largest speed %.3g m/s)", dv, vmax);
  if (size == 1)
    CHECK(!memcmp(ranks->xv, one->xv, (size_t)one->count * 7 * sizeof *one->xv),
          "one rank differs from one process");
}

static void free_state(state *s) {
  free(s->id);
  free(s->xv);
}

/* The node values one step sends over all ranks for a resting cube of side `cells`. */
static double halo_bytes(mpm_dist *d, int cells) {
  char json[1024];
  const double dx = 0.025, half = 0.5 * cells * dx;
  snprintf(json, sizeof json,
           "{\"domain\": {\"min\": [0, 0, 0], \"max\": [1.2, 1.2, 1.2], \"dx\": %g},"
           " \"time\": {\"end\": 1}, \"gravity\": [0, 0, 0],"
           " \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\", \"E\": 1e5,"
           "  \"nu\": 0.3, \"density\": 1000}],"
           " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.6, 0.6, 0.6],"
           "  \"half_extent\": [%.17g, %.17g, %.17g]}, \"material\": \"m\","
           "  \"particles_per_cell\": 1}]}",
           dx, half, half, half);
  mpm_sim *sim = mpi_check_sim(json);
  mpm_error err;
  CHECK(mpm_dist_attach(d, sim, &err) == MPM_OK, "attach: %s", err.message);
  CHECK(mpm_sim_step(sim, DT) == MPM_OK, "step: %s", mpm_sim_last_error(sim));
  double bytes = (double)mpm_dist_sim_figures(sim).halo_bytes, all = 0;
  MPI_Allreduce(&bytes, &all, 1, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
  mpm_sim_destroy(sim);
  return all;
}

/* The halo grows with the cut's surface: a cube of twice the side sends 2.6-3.1 times the bytes
 * here (4 in the limit of large cubes: at these sizes the ghost layer's edges still count), where
 * the volume (the grid, or the particles) would give 8. */
static void test_halo_scales_with_surface(mpm_dist *d) {
  if (size < 2) return;
  const double small = halo_bytes(d, 16), large = halo_bytes(d, 32);
  if (rank == 0)
    printf("%d ranks: halo of a cube of 16 cells %.0f bytes a step, of 32 cells %.0f (x%.2f)\n",
           size, small, large, large / small);
  CHECK(small > 0 && large / small > 2 && large / small < 5.5,
        "the halo grew %.2f times when the cube's side doubled (the surface: 4)", large / small);
}

/* A value blown up on one rank stops every rank in the same step, with the status that names
 * it: the rank that holds the particle names its id, the others the step. */
static void test_instability_stops_all(mpm_dist *d) {
  mpm_sim *sim = make();
  mpm_error err;
  CHECK(mpm_dist_attach(d, sim, &err) == MPM_OK, "attach: %s", err.message);
  for (int k = 0; k < 3; ++k) CHECK(mpm_sim_step(sim, DT) == MPM_OK, "step %d", k);
  if (rank == size - 1 && sim->particles.count > 0) sim->particles.v[0][0] = (mpm_real)NAN;
  const mpm_status st = mpm_sim_step(sim, DT);
  int stopped = st == MPM_ERR_UNSTABLE, all = 0;
  MPI_Allreduce(&stopped, &all, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
  CHECK(all == size, "%d of %d ranks stopped (this one: status %d, '%s')", all, size, (int)st,
        mpm_sim_last_error(sim));
  CHECK(strstr(mpm_sim_last_error(sim), "step 4") != NULL, "the message names no step: %s",
        mpm_sim_last_error(sim));
  if (rank == 0)
    printf("%d ranks: a NaN on rank %d stopped every rank: %s\n", size, size - 1,
           mpm_sim_last_error(sim));
  mpm_sim_destroy(sim);
}

int main(int argc, char **argv) {
  mpi_check_start(&argc, &argv);
  mpm_error err;
  mpm_dist *d = mpm_dist_create_world(&err);
  long migrated = 0, ghosts = 0, migrated2 = 0, ghosts2 = 0, cuts = 0, cuts2 = 0;
  state a = run_on_ranks(d, MPM_DIST_REBALANCE, &migrated, &ghosts, &cuts);
  state b = run_on_ranks(d, MPM_DIST_REBALANCE, &migrated2, &ghosts2, &cuts2);
  /* cut again whenever a rank holds 1% more than the mean (the thrown block moves particles
     into the next rank's range every step) */
  long cuts3 = 0;
  state c = run_on_ranks(d, 1.01, &migrated2, &ghosts2, &cuts3);
  if (rank == 0) {
    /* the same on one process, without the ranks */
    mpm_sim *sim = make();
    for (int k = 0; k < STEPS; ++k)
      CHECK(mpm_sim_step(sim, DT) == MPM_OK, "one process, step %d", k);
    state one = collect(sim, 0);
    mpm_sim_destroy(sim);
    compare(&a, &one);
    CHECK(a.count == b.count && !memcmp(a.xv, b.xv, (size_t)a.count * 7 * sizeof *a.xv),
          "two runs on %d ranks differ", size);
    printf("%d ranks: %ld particles migrated, %ld ghost blocks exchanged over %d steps\n", size,
           migrated, ghosts, STEPS);
    if (size > 1) CHECK(migrated > 0 && ghosts > 0, "nothing crossed the ranks' ranges");
    printf("%d ranks, cut again past 1.01 of the mean: %ld new cuts\n", size, cuts3);
    compare(&c, &one);
    if (size > 1) CHECK(cuts3 > 0, "the blocks were never cut again");
    free_state(&one);
  }
  free_state(&a);
  free_state(&b);
  free_state(&c);
  test_halo_scales_with_surface(d);
  test_instability_stops_all(d);
  /* a scene the ranks cannot run yet: refused on every rank, naming it */
  const char *implicit =
      "{\"domain\": {\"min\": [0, 0, 0], \"max\": [1, 1, 1], \"dx\": 0.1},"
      " \"time\": {\"end\": 1}, \"solver\": {\"integrator\": \"implicit\"},"
      " \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\","
      "  \"E\": 1e5, \"nu\": 0.3, \"density\": 1000}],"
      " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.5, 0.5, 0.5],"
      "  \"half_extent\": [0.1, 0.1, 0.1]}, \"material\": \"m\"}]}";
  mpm_sim *sim = mpi_check_sim(implicit);
  CHECK(mpm_dist_attach(d, sim, &err) == MPM_ERR_INVALID && strstr(err.message, "implicit"),
        "the implicit step was not refused: %s", err.message);
  mpm_sim_destroy(sim);
  mpm_dist_destroy(d);
  return mpi_check_finish("test_dist_step");
}
