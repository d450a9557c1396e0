/* mpi_comm.c - the processes of a distributed run and their reductions (comm.h), on MPI. */
#include "dist/comm.h"
#include "dist/mpi_internal.h"
#include "core/alloc.h"

#include <math.h>
#include <mpi.h>
#include <string.h>

struct mpm_dist {
  MPI_Comm comm;
  int rank, size;
  double *gathered; /* size x capacity values, the reduction's scratch */
  int capacity;
  /* the migration's: one packed particle as an element of the exchange, and scratch kept from
     call to call (a step allocates nothing once warm) */
  MPI_Datatype particle;
  int *counts; /* 4 x size */
  uint32_t *idx;
  uint8_t *gone;
  unsigned char *sendbuf, *recvbuf;
  size_t idx_cap, gone_cap, send_cap, recv_cap;
};

mpm_dist *mpm_dist_create_world(mpm_error *err) {
  /* the communicator first (a collective): a rank short of memory before it would leave the
     others waiting in it; after it, the ranks vote */
  MPI_Comm comm;
  MPI_Comm_dup(MPI_COMM_WORLD, &comm);
  mpm_dist *d = mpm_calloc(1, sizeof *d);
  int failed = !d;
  if (d) {
    d->comm = comm;
    d->particle = MPI_DATATYPE_NULL;
    MPI_Comm_rank(d->comm, &d->rank);
    MPI_Comm_size(d->comm, &d->size);
    d->counts = mpm_calloc(4 * (size_t)d->size, sizeof *d->counts);
    /* room for the reductions' values made now (a step's are at most the ten of stats.csv): a
       reduction allocates nothing while the run goes on, so one rank short of memory cannot
       fail it alone */
    d->capacity = 64;
    d->gathered = mpm_alloc((size_t)d->size * (size_t)d->capacity * sizeof *d->gathered);
    failed = !d->counts || !d->gathered;
  }
  int any = 0;
  MPI_Allreduce(&failed, &any, 1, MPI_INT, MPI_MAX, comm);
  if (any) {
    if (d)
      mpm_dist_destroy(d);
    else
      MPI_Comm_free(&comm);
    mpm_error_set(err, MPM_ERR_NOMEM, "out of memory making the run's process group");
    return NULL;
  }
  /* counts in particles stay within int where counts in bytes would not */
  MPI_Type_contiguous((int)mpm_particles_packed_bytes(), MPI_BYTE, &d->particle);
  MPI_Type_commit(&d->particle);
  return d;
}

void mpm_dist_destroy(mpm_dist *d) {
  if (!d) return;
  if (d->particle != MPI_DATATYPE_NULL) MPI_Type_free(&d->particle);
  MPI_Comm_free(&d->comm);
  mpm_free(d->gathered);
  mpm_free(d->counts), mpm_free(d->idx), mpm_free(d->gone);
  mpm_free(d->sendbuf), mpm_free(d->recvbuf);
  mpm_free(d);
}

MPI_Comm mpm_dist_comm(const mpm_dist *d) {
  return d->comm;
}
int mpm_dist_rank(const mpm_dist *d) {
  return d->rank;
}
int mpm_dist_size(const mpm_dist *d) {
  return d->size;
}

/* Every rank's values gathered, then combined in rank order: the same bits on every rank. */
static void reduce_all(void *ctx, mpm_reduce_op op, double *values, int count) {
  mpm_dist *d = ctx;
  if (count <= 0) return;
  if (count > d->capacity) {
    double *bigger = mpm_realloc(d->gathered, (size_t)d->size * (size_t)count * sizeof *bigger);
    if (!bigger) MPI_Abort(d->comm, 3); /* past 64 values: a reduction cannot fail alone */
    d->gathered = bigger;
    d->capacity = count;
  }
  MPI_Allgather(values, count, MPI_DOUBLE, d->gathered, count, MPI_DOUBLE, d->comm);
  for (int k = 0; k < count; ++k) {
    double acc = d->gathered[k];
    for (int r = 1; r < d->size; ++r) {
      const double v = d->gathered[(size_t)r * (size_t)count + (size_t)k];
      if (op == MPM_REDUCE_SUM)
        acc += v;
      else if (isnan(acc) || isnan(v)) /* a NaN of any rank wins, so that every rank sees it */
        acc = NAN;
      else if (op == MPM_REDUCE_MAX ? v > acc : v < acc)
        acc = v;
    }
    values[k] = acc;
  }
}

mpm_status mpm_dist_agree(mpm_dist *d, mpm_status st, mpm_error *err) {
  /* the first rank whose failure is its own, and the first rank that failed (size: none) */
  const int mine[2] = {st != MPM_OK && !err->elsewhere ? d->rank : d->size,
                       st != MPM_OK ? d->rank : d->size};
  int all[2];
  MPI_Allreduce(mine, all, 2, MPI_INT, MPI_MIN, d->comm);
  if (all[1] == d->size) return MPM_OK;
  const int from = all[0] < d->size ? all[0] : all[1];
  int status = (int)st;
  char text[sizeof err->message];
  if (d->rank == from) memcpy(text, err->message, sizeof text);
  MPI_Bcast(&status, 1, MPI_INT, from, d->comm);
  MPI_Bcast(text, (int)sizeof text, MPI_CHAR, from, d->comm);
  text[sizeof text - 1] = '\0';
  mpm_error_set(err, (mpm_status)status, "%s", text);
  return (mpm_status)status;
}

mpm_reduction mpm_dist_reduction(mpm_dist *d) {
  mpm_reduction r = {reduce_all, d};
  return r;
}

/* The largest of every rank's vote (a collective). */
static int vote(mpm_dist *d, int mine) {
  int most = 0;
  MPI_Allreduce(&mine, &most, 1, MPI_INT, MPI_MAX, d->comm);
  return most;
}

/* Room for n bytes in *buf (capacity *cap), the contents not kept (mpm_reserve): every buffer
 * of the migration is written whole before it is read. Nonzero when out of memory. */
static int room(void *buf, size_t *cap, size_t n) {
  return mpm_reserve((void **)buf, cap, n, 1) != MPM_OK;
}

mpm_status mpm_dist_migrate(mpm_dist *d, mpm_particles *p, const int32_t *dest, mpm_migration *m,
                            mpm_error *err) {
  memset(m, 0, sizeof *m);
  const size_t n = p->count, one = mpm_particles_packed_bytes();
  const int R = d->size;
  int *send_count = d->counts, *send_at = d->counts + R, *recv_count = d->counts + 2 * R,
      *recv_at = d->counts + 3 * R;
  memset(send_count, 0, (size_t)R * sizeof *send_count);
  int bad = 0;
  size_t leaving = 0;
  for (size_t i = 0; i < n; ++i) {
    if (dest[i] < 0 || dest[i] >= R) {
      bad = 1;
      break;
    }
    if (dest[i] != d->rank) ++send_count[dest[i]], ++leaving;
  }
  /* the particles leaving, grouped by destination in their order here */
  int failed = !bad && (room(&d->idx, &d->idx_cap, (leaving + 1) * sizeof *d->idx) ||
                        room(&d->sendbuf, &d->send_cap, leaving * one + 1));
  const int verdict = vote(d, bad ? 2 : failed);
  if (verdict == 2)
    return mpm_error_set(err, MPM_ERR_INVALID,
                         "particle migration: a destination rank outside [0, %d) (nothing moved)",
                         R);
  if (verdict == 1)
    return mpm_error_set(err, MPM_ERR_NOMEM,
                         "particle migration: out of memory packing %zu particles (nothing moved)",
                         leaving);
  send_at[0] = 0;
  for (int r = 1; r < R; ++r) send_at[r] = send_at[r - 1] + send_count[r - 1];
  memcpy(recv_at, send_at, (size_t)R * sizeof *recv_at); /* a cursor until the counts come */
  for (size_t i = 0; i < n; ++i)
    if (dest[i] != d->rank) d->idx[recv_at[dest[i]]++] = (uint32_t)i;
  mpm_particles_pack(p, d->idx, leaving, d->sendbuf);
  MPI_Alltoall(send_count, 1, MPI_INT, recv_count, 1, MPI_INT, d->comm);
  size_t arriving = 0;
  for (int r = 0; r < R; ++r) {
    recv_at[r] = (int)arriving;
    arriving += (size_t)recv_count[r];
  }
  failed = room(&d->recvbuf, &d->recv_cap, arriving * one + 1) ||
           (leaving > 0 && room(&d->gone, &d->gone_cap, n + 1));
  if (vote(d, failed))
    return mpm_error_set(err, MPM_ERR_NOMEM,
                         "particle migration: out of memory for the particles arriving (nothing "
                         "moved)");
  MPI_Alltoallv(d->sendbuf, send_count, send_at, d->particle, d->recvbuf, recv_count, recv_at,
                d->particle, d->comm);
  if (leaving > 0) { /* the others keep their order */
    memset(d->gone, 0, n);
    for (size_t k = 0; k < leaving; ++k) d->gone[d->idx[k]] = 1;
    mpm_particles_remove(p, d->gone);
  }
  const mpm_status st = mpm_particles_unpack(p, d->recvbuf, arriving);
  if (st != MPM_OK)
    return mpm_error_set(err, st, "particle migration: out of memory receiving %zu particles",
                         arriving);
  m->sent = leaving;
  m->received = arriving;
  m->bytes_sent = leaving * one;
  m->bytes_received = arriving * one;
  return MPM_OK;
}
