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
};

mpm_dist *mpm_dist_create_world(mpm_error *err) {
  mpm_dist *d = mpm_calloc(1, sizeof *d);
  if (!d) {
    mpm_error_set(err, MPM_ERR_NOMEM, "out of memory making the run's process group");
    return NULL;
  }
  MPI_Comm_dup(MPI_COMM_WORLD, &d->comm);
  MPI_Comm_rank(d->comm, &d->rank);
  MPI_Comm_size(d->comm, &d->size);
  return d;
}

void mpm_dist_destroy(mpm_dist *d) {
  if (!d) return;
  MPI_Comm_free(&d->comm);
  mpm_free(d->gathered);
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
    if (!bigger) MPI_Abort(d->comm, 3); /* a reduction cannot fail on one rank alone */
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

mpm_reduction mpm_dist_reduction(mpm_dist *d) {
  mpm_reduction r = {reduce_all, d};
  return r;
}

/* Whether any rank says so (a collective vote). */
static int any_rank(mpm_dist *d, int mine) {
  int any = 0;
  MPI_Allreduce(&mine, &any, 1, MPI_INT, MPI_MAX, d->comm);
  return any;
}

mpm_status mpm_dist_migrate(mpm_dist *d, mpm_particles *p, const int32_t *dest, mpm_migration *m,
                            mpm_error *err) {
  memset(m, 0, sizeof *m);
  const size_t n = p->count, one = mpm_particles_packed_bytes();
  const int R = d->size;
  int bad = 0;
  for (size_t i = 0; i < n && !bad; ++i) bad = dest[i] < 0 || dest[i] >= R;
  if (any_rank(d, bad))
    return mpm_error_set(err, MPM_ERR_INVALID,
                         "particle migration: a destination rank outside [0, %d) (nothing moved)",
                         R);
  /* the particles leaving, grouped by destination in their order here */
  int *send_count = mpm_calloc((size_t)R, sizeof *send_count);
  int *recv_count = mpm_calloc((size_t)R, sizeof *recv_count);
  int *send_at = mpm_calloc((size_t)R, sizeof *send_at);
  int *recv_at = mpm_calloc((size_t)R, sizeof *recv_at);
  size_t leaving = 0;
  for (size_t i = 0; i < n; ++i)
    if (dest[i] != d->rank) ++leaving;
  uint32_t *idx = mpm_alloc((leaving + 1) * sizeof *idx);
  uint8_t *gone = mpm_calloc(n + 1, 1);
  unsigned char *sendbuf = mpm_alloc(leaving * one + 1);
  int failed = !send_count || !recv_count || !send_at || !recv_at || !idx || !gone || !sendbuf;
  if (!failed) {
    for (size_t i = 0; i < n; ++i)
      if (dest[i] != d->rank) ++send_count[dest[i]];
    for (int r = 1; r < R; ++r) send_at[r] = send_at[r - 1] + send_count[r - 1];
    int *fill = recv_at; /* scratch until the counts come back */
    memcpy(fill, send_at, (size_t)R * sizeof *fill);
    for (size_t i = 0; i < n; ++i)
      if (dest[i] != d->rank) {
        idx[fill[dest[i]]++] = (uint32_t)i;
        gone[i] = 1;
      }
    mpm_particles_pack(p, idx, leaving, sendbuf);
  }
  if (any_rank(d, failed)) {
    mpm_free(send_count), mpm_free(recv_count), mpm_free(send_at), mpm_free(recv_at);
    mpm_free(idx), mpm_free(gone), mpm_free(sendbuf);
    return mpm_error_set(err, MPM_ERR_NOMEM,
                         "particle migration: out of memory packing %zu particles (nothing moved)",
                         leaving);
  }
  MPI_Alltoall(send_count, 1, MPI_INT, recv_count, 1, MPI_INT, d->comm);
  size_t arriving = 0;
  for (int r = 0; r < R; ++r) {
    recv_at[r] = (int)arriving;
    arriving += (size_t)recv_count[r];
  }
  /* one particle is one element of the exchange: counts in particles stay within int where
     counts in bytes would not */
  MPI_Datatype particle;
  MPI_Type_contiguous((int)one, MPI_BYTE, &particle);
  MPI_Type_commit(&particle);
  unsigned char *recvbuf = mpm_alloc(arriving * one + 1);
  const int short_of_memory = any_rank(d, !recvbuf);
  mpm_status st = MPM_OK;
  if (!short_of_memory) {
    MPI_Alltoallv(sendbuf, send_count, send_at, particle, recvbuf, recv_count, recv_at, particle,
                  d->comm);
    mpm_particles_remove(p, gone);
    st = mpm_particles_unpack(p, recvbuf, arriving);
    if (st != MPM_OK)
      mpm_error_set(err, st, "particle migration: out of memory receiving %zu particles", arriving);
    m->sent = leaving;
    m->received = arriving;
    m->bytes_sent = leaving * one;
    m->bytes_received = arriving * one;
  } else {
    st = mpm_error_set(err, MPM_ERR_NOMEM,
                       "particle migration: out of memory for the particles arriving (nothing "
                       "moved)");
  }
  MPI_Type_free(&particle);
  mpm_free(recvbuf);
  mpm_free(send_count), mpm_free(recv_count), mpm_free(send_at), mpm_free(recv_at);
  mpm_free(idx), mpm_free(gone), mpm_free(sendbuf);
  return st;
}
