/* mpi_sim.c - a simulation as one rank's part of a distributed run (dist_sim.h): the uniform
 * grid stack wrapped with the migration at the sort, the ghost blocks named to their owners,
 * their sums sent after P2G and the updated values fetched before G2P. */
#include "dist/dist_sim.h"
#include "core/alloc.h"
#include "core/clock.h"
#include "dist/mpi_internal.h"
#include "dist/partition.h"
#include "sim/grid_stack.h"
#include "sim/sim.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#ifdef MPM_USE_DOUBLE
#define MPI_REAL_TYPE MPI_DOUBLE
#else
#define MPI_REAL_TYPE MPI_FLOAT
#endif

typedef struct dist_stack {
  mpm_dist *d;
  const mpm_grid_stack_ops *inner;
  mpm_reduction reduction;
  mpm_partition pt;
  int rank, size;
  /* per step: the ghost blocks here (local block indices) grouped by owner, and the blocks
     here that ranks hold as ghosts, grouped by rank, in the order that rank names them */
  int *ghost_count, *ghost_at, *shared_count, *shared_at, *send_n, *send_at, *recv_n, *recv_at;
  uint32_t *ghost, *shared;
  size_t ghost_total, shared_total, ghost_cap, shared_cap;
  uint64_t *keys;
  size_t keys_cap;
  int32_t *owner; /* each block's rank, this step */
  size_t owner_cap;
  mpm_real *buf; /* the node values sent and received */
  size_t buf_cap;
  int32_t *dest;
  size_t dest_cap;
  double rebalance_at; /* recut when the largest rank holds this many times the mean */
  mpm_dist_figures figures;
  long long run_particles; /* over every rank, at the last step's start (or the attach) */
  int owns_dist;           /* d is destroyed with the simulation (mpm_dist_sim_own) */
} dist_stack;

static dist_stack *state(const mpm_sim *sim) {
  return sim->stack_data;
}

/* Room for n items in *buf (capacity *cap): every buffer here is written whole before it is
 * read, so the contents need not be kept (mpm_reserve). Nonzero when out of memory. */
#define ROOM(buf, cap, n) (mpm_reserve((void **)&(buf), &(cap), (n), sizeof *(buf)) != MPM_OK)

/* The block of the cell holding particle i (the one rule of a particle's block, for the cut,
 * the migration and the recut): floor((x - origin) / dx) by the inverse spacing, and floor(c / 4)
 * as an arithmetic shift (as gcc and clang shift a signed value), so that the migration's pass over
 * every particle stays cheap. */
static inline void particle_block(const mpm_grid *g, double inv_dx, const mpm_particles *p,
                                  size_t i, int32_t c[3]) {
  for (int d = 0; d < 3; ++d)
    c[d] = (int32_t)floor(((double)p->x[d][i] - (double)g->origin[d]) * inv_dx) >> 2;
}

static uint64_t particle_key(const mpm_grid *g, const mpm_particles *p, size_t i) {
  int32_t c[3];
  particle_block(g, 1.0 / (double)g->dx, p, i, c);
  return mpm_morton_key(c);
}

/* ---- the stages ------------------------------------------------------------------------- */

/* The status of a rank whose step stops because another rank's failed (that one says why). */
static mpm_status another_rank(mpm_sim *sim, const char *where) {
  return mpm_error_set_elsewhere(
      &sim->error, MPM_ERR_NOMEM,
      "step %lld: another rank of the run ran out of memory %s (its message names what)",
      (long long)sim->steps, where);
}

/* Whether any rank failed (a collective vote): a rank that runs out of memory must not leave the
 * others waiting in the exchange it skips, so every failure before an exchange is voted on. */
static int any_failed(const dist_stack *s, int mine) {
  int failed = mine != 0, any = 0; /* mine: any nonzero failure (a -1 too) */
  MPI_Allreduce(&failed, &any, 1, MPI_INT, MPI_MAX, mpm_dist_comm(s->d));
  return any;
}

static mpm_status nomem(mpm_sim *sim, const char *what) {
  return mpm_error_set(&sim->error, MPM_ERR_NOMEM, "step %lld: out of memory %s",
                       (long long)sim->steps, what);
}

/* The particles whose block another rank owns now go there. */
static mpm_status migrate(mpm_sim *sim, dist_stack *s) {
  mpm_particles *p = &sim->particles;
  if (any_failed(s, ROOM(s->dest, s->dest_cap, p->count + 1)))
    return nomem(sim, "choosing the particles' ranks");
  /* a block's owner from a small direct-mapped cache of the blocks met (the particles lie in
     the sort's block order, so few blocks are met in a row: the Morton key and the search run
     once per block, not per particle) */
  enum { CACHE = 256 };
  int32_t cache_block[CACHE][3], cache_owner[CACHE];
  for (int k = 0; k < CACHE; ++k) cache_block[k][0] = INT32_MIN;
  const double inv_dx = 1.0 / (double)sim->grid.dx;
  for (size_t i = 0; i < p->count; ++i) {
    int32_t c[3];
    particle_block(&sim->grid, inv_dx, p, i, c);
    const unsigned h =
        ((unsigned)c[0] * 73856093u ^ (unsigned)c[1] * 19349663u ^ (unsigned)c[2] * 83492791u) &
        (CACHE - 1);
    if (cache_block[h][0] != c[0] || cache_block[h][1] != c[1] || cache_block[h][2] != c[2]) {
      memcpy(cache_block[h], c, sizeof c);
      cache_owner[h] = (int32_t)mpm_partition_owner(&s->pt, mpm_morton_key(c));
    }
    s->dest[i] = cache_owner[h];
  }
  mpm_error err;
  const mpm_status st = mpm_dist_migrate(s->d, p, s->dest, &s->figures.migration, &err);
  if (st != MPM_OK)
    return mpm_error_set(&sim->error, st, "step %lld: %s", (long long)sim->steps, err.message);
  return MPM_OK;
}

/* Name each ghost block to its owner, and activate the blocks others name here. */
static mpm_status exchange_ghosts(mpm_sim *sim, dist_stack *s, const mpm_kernel *k) {
  mpm_grid *g = &sim->grid;
  mpm_sparse_grid *sg = &g->impl.sparse;
  const MPI_Comm comm = mpm_dist_comm(s->d);
  const int R = s->size;
  const size_t nb = sg->block_count;
  if (any_failed(s, ROOM(s->ghost, s->ghost_cap, nb + 1) || ROOM(s->keys, s->keys_cap, nb + 1) ||
                        ROOM(s->owner, s->owner_cap, nb + 1)))
    return nomem(sim, "listing the ghost blocks");
  memset(s->ghost_count, 0, (size_t)R * sizeof *s->ghost_count);
  for (size_t b = 0; b < nb; ++b) { /* each block's owner, once */
    s->owner[b] = (int32_t)mpm_partition_owner(&s->pt, mpm_morton_key(sg->coord[b]));
    if (s->owner[b] != s->rank) ++s->ghost_count[s->owner[b]];
  }
  s->ghost_at[0] = 0;
  for (int r = 1; r < R; ++r) s->ghost_at[r] = s->ghost_at[r - 1] + s->ghost_count[r - 1];
  s->ghost_total = (size_t)s->ghost_at[R - 1] + (size_t)s->ghost_count[R - 1];
  memcpy(s->send_at, s->ghost_at, (size_t)R * sizeof *s->send_at);
  for (size_t b = 0; b < nb; ++b) {
    const int r = s->owner[b];
    if (r == s->rank) continue;
    const int at = s->send_at[r]++;
    s->ghost[at] = (uint32_t)b;
    s->keys[at] = mpm_morton_key(sg->coord[b]);
  }
  MPI_Alltoall(s->ghost_count, 1, MPI_INT, s->shared_count, 1, MPI_INT, comm);
  s->shared_at[0] = 0;
  for (int r = 1; r < R; ++r) s->shared_at[r] = s->shared_at[r - 1] + s->shared_count[r - 1];
  s->shared_total = (size_t)s->shared_at[R - 1] + (size_t)s->shared_count[R - 1];
  uint64_t *named = mpm_alloc((s->shared_total + 1) * sizeof *named);
  if (any_failed(s, !named || ROOM(s->shared, s->shared_cap, s->shared_total + 1))) {
    mpm_free(named);
    return nomem(sim, "receiving the ghost blocks' names");
  }
  MPI_Alltoallv(s->keys, s->ghost_count, s->ghost_at, MPI_UINT64_T, named, s->shared_count,
                s->shared_at, MPI_UINT64_T, comm);
  /* the named blocks no particle here reaches: activated by a point whose stencil lies inside
     the block (at node 4 B + 1.5 on each axis: the stencils of every kernel, 2 to 4 nodes wide,
     stay within nodes 4 B .. 4 B + 3) */
  mpm_status st = MPM_OK;
  for (size_t q = 0; q < s->shared_total && st == MPM_OK; ++q) {
    int32_t c[3];
    mpm_morton_coords(named[q], c);
    if (mpm_sparse_grid_find(sg, c) >= 0) continue;
    mpm_real x[3];
    for (int d = 0; d < 3; ++d) x[d] = g->origin[d] + (mpm_real)(4 * c[d] + 1.5) * g->dx;
    const mpm_real *const px[3] = {&x[0], &x[1], &x[2]};
    st = g->ops->activate_points(g, k, 1, px, NULL);
  }
  for (size_t q = 0; q < s->shared_total && st == MPM_OK; ++q) {
    int32_t c[3];
    mpm_morton_coords(named[q], c);
    const int32_t b = mpm_sparse_grid_find(sg, c);
    if (b < 0) st = MPM_ERR_INVALID;
    s->shared[q] = (uint32_t)b;
  }
  mpm_free(named);
  if (any_failed(s, st != MPM_OK)) return nomem(sim, "activating the blocks other ranks reach");
  s->figures.ghost_blocks = s->ghost_total;
  s->figures.shared_blocks = s->shared_total;
  return MPM_OK;
}

static int by_key(const void *a, const void *b) {
  const uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
  return x < y ? -1 : x > y;
}

/* When the largest rank holds more than rebalance_at times the mean of the particles, the
 * blocks are cut again by their particles (every rank's blocks with their counts gathered on
 * every rank: a rare step's cost, which grows with the blocks), and the migration that follows
 * moves the particles to their new ranks. */
static mpm_status rebalance(mpm_sim *sim, dist_stack *s) {
  const MPI_Comm comm = mpm_dist_comm(s->d);
  const mpm_particles *p = &sim->particles;
  long long n = (long long)p->count, most = 0, all = 0;
  MPI_Allreduce(&n, &most, 1, MPI_LONG_LONG, MPI_MAX, comm);
  MPI_Allreduce(&n, &all, 1, MPI_LONG_LONG, MPI_SUM, comm);
  s->figures.imbalance = all > 0 ? (double)most * s->size / (double)all : 1;
  s->run_particles = all;
  if (!(s->rebalance_at > 1) || !(s->figures.imbalance > s->rebalance_at)) return MPM_OK;
  /* this rank's blocks and their particles, in key order */
  uint64_t *key = mpm_alloc((p->count + 1) * sizeof *key);
  double *w = mpm_alloc((p->count + 1) * sizeof *w);
  int *count = mpm_alloc(2 * (size_t)s->size * sizeof *count);
  int blocks = 0, failed = !key || !w || !count;
  if (!failed) {
    for (size_t i = 0; i < p->count; ++i) key[i] = particle_key(&sim->grid, p, i);
    qsort(key, p->count, sizeof *key, by_key);
    for (size_t i = 0; i < p->count; ++i) {
      if (blocks > 0 && key[blocks - 1] == key[i]) {
        w[blocks - 1] += 1;
      } else {
        key[blocks] = key[i];
        w[blocks++] = 1;
      }
    }
  }
  int any = 0;
  MPI_Allreduce(&failed, &any, 1, MPI_INT, MPI_MAX, comm);
  uint64_t *all_key = NULL;
  double *all_w = NULL;
  int total = 0;
  if (!any) {
    int *at = count + s->size;
    MPI_Allgather(&blocks, 1, MPI_INT, count, 1, MPI_INT, comm);
    for (int r = 0; r < s->size; ++r) at[r] = total, total += count[r];
    all_key = mpm_alloc(((size_t)total + 1) * sizeof *all_key);
    all_w = mpm_alloc(((size_t)total + 1) * sizeof *all_w);
    failed = !all_key || !all_w;
    MPI_Allreduce(&failed, &any, 1, MPI_INT, MPI_MAX, comm);
    if (!any) {
      MPI_Allgatherv(key, blocks, MPI_UINT64_T, all_key, count, at, MPI_UINT64_T, comm);
      MPI_Allgatherv(w, blocks, MPI_DOUBLE, all_w, count, at, MPI_DOUBLE, comm);
    }
  }
  mpm_status st = MPM_OK;
  if (!any) {
    mpm_partition cut;
    st = mpm_partition_cut(&cut, s->size, (size_t)total, all_key, all_w);
    failed = st != MPM_OK;
    MPI_Allreduce(&failed, &any, 1, MPI_INT, MPI_MAX, comm);
    if (!any) {
      mpm_partition_free(&s->pt);
      s->pt = cut;
      s->figures.rebalances++;
    } else if (st == MPM_OK) {
      mpm_partition_free(&cut);
    }
  }
  mpm_free(key), mpm_free(w), mpm_free(count), mpm_free(all_key), mpm_free(all_w);
  return any ? nomem(sim, "cutting the blocks into ranks again") : MPM_OK;
}

static mpm_status sort(mpm_sim *sim, mpm_step_ctx *c) {
  dist_stack *s = state(sim);
  const double t0 = mpm_wall_seconds();
  mpm_status st = rebalance(sim, s);
  if (st == MPM_OK) st = migrate(sim, s);
  const double t1 = mpm_wall_seconds();
  if (st == MPM_OK) {
    st = s->inner->sort(sim, c);
    if (any_failed(s, st != MPM_OK) && st == MPM_OK) st = another_rank(sim, "sorting");
  }
  const double t2 = mpm_wall_seconds();
  if (st == MPM_OK) st = exchange_ghosts(sim, s, &c->tc.kernel);
  s->figures.exchange_seconds += (t1 - t0) + (mpm_wall_seconds() - t2);
  return st;
}

/* The DOF fields a block's nodes carry in an exchange, and their count. */
static int fields_of(const mpm_dofs *dofs, int after_update, mpm_real *field[7]) {
  int n = 0;
  field[n++] = dofs->mass;
  for (int e = 0; e < 3; ++e) field[n++] = dofs->v0[e];
  const int third =
      after_update ? (dofs->fields & MPM_DOF_V) != 0 : (dofs->fields & MPM_DOF_F) != 0;
  if (third)
    for (int e = 0; e < 3; ++e) field[n++] = after_update ? dofs->v[e] : dofs->f[e];
  return n;
}

/* Send the values of blocks out[..] (grouped by rank: out_n, out_at) and receive those of
 * in[..] (in_n, in_at); `add`: the received values are added to the nodes' (in the order of the
 * sending ranks), else they replace them. */
static mpm_status exchange_values(mpm_sim *sim, dist_stack *s, int after_update,
                                  const uint32_t *out, const int *out_n, const int *out_at,
                                  size_t out_total, const uint32_t *in, const int *in_n,
                                  const int *in_at, size_t in_total, int add) {
  mpm_dofs *dofs = &sim->dofs;
  mpm_real *field[7];
  const int nf = fields_of(dofs, after_update, field);
  const size_t per_block = (size_t)nf * MPM_BLOCK_NODES, begin = sim->grid.dof_begin;
  const int R = s->size;
  if (any_failed(s, ROOM(s->buf, s->buf_cap, (out_total + in_total) * per_block + 1)))
    return nomem(sim, "for the ghost blocks' values");
  mpm_real *send = s->buf, *recv = s->buf + out_total * per_block;
  for (size_t q = 0; q < out_total; ++q) {
    const size_t node = begin + (size_t)out[q] * MPM_BLOCK_NODES;
    mpm_real *o = send + q * per_block;
    for (int f = 0; f < nf; ++f)
      memcpy(o + (size_t)f * MPM_BLOCK_NODES, field[f] + node, MPM_BLOCK_NODES * sizeof *o);
  }
  /* counts and displacements in values (int: a rank's halo stays far below 2^31 values) */
  size_t messages = 0;
  for (int r = 0; r < R; ++r) {
    s->send_n[r] = out_n[r] * (int)per_block;
    s->send_at[r] = out_at[r] * (int)per_block;
    s->recv_n[r] = in_n[r] * (int)per_block;
    s->recv_at[r] = in_at[r] * (int)per_block;
    messages += out_n[r] > 0;
  }
  MPI_Alltoallv(send, s->send_n, s->send_at, MPI_REAL_TYPE, recv, s->recv_n, s->recv_at,
                MPI_REAL_TYPE, mpm_dist_comm(s->d));
  s->figures.halo_bytes += out_total * per_block * sizeof *send;
  s->figures.halo_messages += messages;
  for (size_t q = 0; q < in_total; ++q) { /* in rank order, then the sender's order */
    const size_t node = begin + (size_t)in[q] * MPM_BLOCK_NODES;
    const mpm_real *v = recv + q * per_block;
    for (int f = 0; f < nf; ++f) {
      mpm_real *restrict to = field[f] + node;
      const mpm_real *restrict from = v + (size_t)f * MPM_BLOCK_NODES;
      if (add)
        for (int k = 0; k < MPM_BLOCK_NODES; ++k) to[k] += from[k];
      else
        memcpy(to, from, MPM_BLOCK_NODES * sizeof *to);
    }
  }
  return MPM_OK;
}

static mpm_status p2g(mpm_sim *sim, mpm_step_ctx *c) {
  dist_stack *s = state(sim);
  mpm_status st = s->inner->p2g(sim, c);
  if (any_failed(s, st != MPM_OK)) return st != MPM_OK ? st : another_rank(sim, "in P2G");
  const double t0 = mpm_wall_seconds();
  s->figures.halo_bytes = s->figures.halo_messages = 0;
  st = exchange_values(sim, s, 0, s->ghost, s->ghost_count, s->ghost_at, s->ghost_total, s->shared,
                       s->shared_count, s->shared_at, s->shared_total, 1);
  if (st != MPM_OK) return st;
  /* the ghosts emptied: the update and the reaction sums see each node at its owner only */
  mpm_dofs *dofs = &sim->dofs;
  mpm_real *field[7];
  const int nf = fields_of(dofs, 0, field);
  for (size_t q = 0; q < s->ghost_total; ++q) {
    const size_t node = sim->grid.dof_begin + (size_t)s->ghost[q] * MPM_BLOCK_NODES;
    for (int f = 0; f < nf; ++f) memset(field[f] + node, 0, MPM_BLOCK_NODES * sizeof(mpm_real));
  }
  s->figures.exchange_seconds += mpm_wall_seconds() - t0;
  return MPM_OK;
}

static mpm_status g2p(mpm_sim *sim, mpm_step_ctx *c) {
  dist_stack *s = state(sim);
  const double t0 = mpm_wall_seconds();
  const mpm_status st =
      exchange_values(sim, s, 1, s->shared, s->shared_count, s->shared_at, s->shared_total,
                      s->ghost, s->ghost_count, s->ghost_at, s->ghost_total, 0);
  s->figures.exchange_seconds += mpm_wall_seconds() - t0;
  return st != MPM_OK ? st : s->inner->g2p(sim, c);
}

/* ---- the rest of the table: the uniform stack's ------------------------------------------ */

static mpm_status make(mpm_sim *sim, mpm_error *err) {
  return state(sim)->inner->make(sim, err);
}

static void free_state(dist_stack *s) {
  mpm_partition_free(&s->pt);
  mpm_free(s->ghost_count);
  mpm_free(s->ghost), mpm_free(s->shared), mpm_free(s->keys), mpm_free(s->buf);
  mpm_free(s->owner);
  mpm_free(s->dest);
  mpm_free(s);
}

static void destroy(mpm_sim *sim) {
  dist_stack *s = state(sim);
  mpm_dist *owned = s->owns_dist ? s->d : NULL;
  s->inner->destroy(sim);
  free_state(s);
  sim->stack_data = NULL;
  mpm_dist_destroy(owned);
}

static mpm_status sample_body(mpm_sim *sim, int b, mpm_error *err) {
  return state(sim)->inner->sample_body(sim, b, err);
}
static double finest_dx(const mpm_sim *sim) {
  return state(sim)->inner->finest_dx(sim);
}
static mpm_status layout(mpm_sim *sim, mpm_step_ctx *c, unsigned fields) {
  return state(sim)->inner->layout(sim, c, fields);
}
static void implicit_parts(mpm_sim *sim, mpm_implicit *i) {
  state(sim)->inner->implicit_parts(sim, i);
}
static mpm_status refine(mpm_sim *sim) {
  return state(sim)->inner->refine(sim);
}
static mpm_status resample(mpm_sim *sim) {
  return state(sim)->inner->resample(sim);
}
static void particles_moved(mpm_sim *sim) {
  state(sim)->inner->particles_moved(sim);
}
static mpm_status save(mpm_sim *sim, mpm_checkpoint *c) {
  return state(sim)->inner->save(sim, c);
}
static mpm_status load(mpm_sim *sim, const mpm_checkpoint *c) {
  return state(sim)->inner->load(sim, c);
}
static mpm_status write_frame(mpm_sim *sim, int frame) {
  return state(sim)->inner->write_frame(sim, frame);
}
static const char *frame_part(const mpm_sim *sim) {
  return state(sim)->inner->frame_part(sim);
}
static void info(const mpm_sim *sim, mpm_sim_info *in) {
  const dist_stack *s = state(sim);
  s->inner->info(sim, in);
  in->rank = s->rank;
  in->ranks = s->size;
  in->run_particles = (size_t)s->run_particles;
}

static const mpm_grid_stack_ops dist_ops = {
    .name = "ranks",
    .make = make,
    .destroy = destroy,
    .sample_body = sample_body,
    .finest_dx = finest_dx,
    .sort = sort,
    .layout = layout,
    .p2g = p2g,
    .implicit_parts = implicit_parts,
    .g2p = g2p,
    .refine = refine,
    .resample = resample,
    .particles_moved = particles_moved,
    .adds_bodies = 0,
    .save = save,
    .load = load,
    .write_frame = write_frame,
    .frame_part = frame_part,
    .info = info,
};

/* ---- attaching ----------------------------------------------------------------------------- */

/* What does not run on ranks yet, or NULL. */
static const char *unsupported(const mpm_sim *sim) {
  if (sim->stack != &mpm_grid_uniform) return "the multi-level grid (domain.levels)";
  if (sim->grid.kind != MPM_GRID_SPARSE) return "the dense grid (solver.grid \"dense\")";
  if (sim->scene.solver.integrator != MPM_INTEGRATOR_EXPLICIT)
    return "the implicit step (solver.integrator \"implicit\")";
  if (sim->domains.particles.count > 0) return "particle domains (bodies[].domains)";
  if (sim->scene.heat.enabled) return "heat conduction (heat)";
  if (sim->steps > 0) return "a simulation that has taken steps (attach it when made)";
  return NULL;
}

mpm_status mpm_dist_attach(mpm_dist *d, mpm_sim *sim, mpm_error *err) {
  const MPI_Comm comm = mpm_dist_comm(d);
  const char *why = unsupported(sim);
  int refused = why != NULL, any = 0;
  MPI_Allreduce(&refused, &any, 1, MPI_INT, MPI_MAX, comm);
  if (any)
    return mpm_error_set(err, MPM_ERR_INVALID, "a run on %d ranks: %s does not run on ranks yet",
                         mpm_dist_size(d), why ? why : "what another rank's scene asks");
  const int R = mpm_dist_size(d);
  dist_stack *s = mpm_calloc(1, sizeof *s);
  int *ints = mpm_calloc(8 * (size_t)R, sizeof *ints);
  mpm_particles *p = &sim->particles;
  uint64_t *keys = mpm_alloc((p->count + 1) * sizeof *keys);
  uint8_t *gone = mpm_calloc(p->count + 1, 1);
  int failed = !s || !ints || !keys || !gone;
  /* the particles' blocks, every one weighing one particle: every rank holds every particle
     (made from the same scene), so every rank cuts alike and keeps its own */
  if (!failed) {
    for (size_t i = 0; i < p->count; ++i) keys[i] = particle_key(&sim->grid, p, i);
    failed = mpm_partition_cut(&s->pt, R, p->count, keys, NULL) != MPM_OK;
  }
  MPI_Allreduce(&failed, &any, 1, MPI_INT, MPI_MAX, comm);
  if (any) {
    if (s) mpm_partition_free(&s->pt);
    mpm_free(s), mpm_free(ints), mpm_free(keys), mpm_free(gone);
    return mpm_error_set(err, MPM_ERR_NOMEM,
                         "a run on %d ranks: out of memory cutting %zu "
                         "particles' blocks into ranks",
                         R, p->count);
  }
  s->d = d;
  s->rank = mpm_dist_rank(d);
  s->size = R;
  s->inner = sim->stack;
  s->ghost_count = ints, s->ghost_at = ints + R, s->shared_count = ints + 2 * R;
  s->shared_at = ints + 3 * R, s->send_n = ints + 4 * R, s->send_at = ints + 5 * R;
  s->recv_n = ints + 6 * R, s->recv_at = ints + 7 * R;
  double *rank_w = mpm_calloc((size_t)R, sizeof *rank_w);
  if (rank_w) {
    s->figures.imbalance = mpm_partition_weights(&s->pt, p->count, keys, NULL, rank_w);
    mpm_free(rank_w);
  }
  s->run_particles = (long long)p->count; /* every rank holds every particle until now */
  for (size_t i = 0; i < p->count; ++i) gone[i] = mpm_partition_owner(&s->pt, keys[i]) != s->rank;
  mpm_particles_remove(p, gone);
  mpm_free(keys);
  mpm_free(gone);
  s->rebalance_at = MPM_DIST_REBALANCE;
  s->reduction = mpm_dist_reduction(d);
  sim->stack_data = s;
  sim->stack = &dist_ops;
  mpm_sim_set_reduction(sim, &s->reduction);
  return MPM_OK;
}

void mpm_dist_set_rebalance(mpm_sim *sim, double threshold) {
  if (sim->stack == &dist_ops) state(sim)->rebalance_at = threshold;
}

mpm_dist *mpm_dist_of(const mpm_sim *sim) {
  return sim->stack == &dist_ops ? state(sim)->d : NULL;
}

void mpm_dist_sim_own(mpm_sim *sim) {
  if (sim->stack == &dist_ops) state(sim)->owns_dist = 1;
}

mpm_dist_figures mpm_dist_sim_figures(const mpm_sim *sim) {
  const dist_stack *s = sim->stack == &dist_ops ? state(sim) : NULL;
  mpm_dist_figures none = {0};
  return s ? s->figures : none;
}
