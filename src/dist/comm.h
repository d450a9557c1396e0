/* comm.h - the processes of a distributed run (MPI; built with -DMPM_MPI=ON, src/dist/mpi_*.c):
 * which rank this is, how many there are, the global reductions the simulation's reduction seam
 * takes (core/reduce.h) and the particles' migration between ranks.
 *
 * Reproducible for a given rank count: a reduction gathers every rank's values and combines them
 * in rank order on every rank (MPI_Allreduce may sum in an order of its own choosing), so all
 * ranks hold the same bits, and the same run on the same rank count gives the same bits. The
 * values reduced per step are a few numbers (the largest speed, the energies, CG's dot products),
 * so gathering them costs no more than the all-reduce's latency.
 *
 * The header names no MPI type: the rest of the engine includes it without MPI's headers. */
#ifndef MPM_DIST_COMM_H
#define MPM_DIST_COMM_H

#include "core/error.h"
#include "core/particles.h"
#include "core/reduce.h"

#include <stddef.h>
#include <stdint.h>

typedef struct mpm_dist mpm_dist;

/* The run's processes: a duplicate of MPI_COMM_WORLD (MPI must be initialized; the caller
 * finalizes it). NULL with the message when out of memory. Collective. */
mpm_dist *mpm_dist_create_world(mpm_error *err);
void mpm_dist_destroy(mpm_dist *d);
int mpm_dist_rank(const mpm_dist *d);
int mpm_dist_size(const mpm_dist *d);

/* After a call that every rank made, st being this rank's result and err its message: MPM_OK
 * on every rank when every rank's was; else, on every rank, the status and the message of the
 * first rank whose failure is its own (err->elsewhere 0; else the first rank that failed), so
 * that one rank can print it for all. Collective. */
mpm_status mpm_dist_agree(mpm_dist *d, mpm_status st, mpm_error *err);

/* The reduction for mpm_sim_set_reduction (core/reduce.h), valid while d lives. Collective: every
 * rank makes the same calls in the same order. */
mpm_reduction mpm_dist_reduction(mpm_dist *d);

/* What a migration moved on this rank. */
typedef struct mpm_migration {
  size_t sent, received; /* particles */
  size_t bytes_sent, bytes_received;
} mpm_migration;

/* Send particle i of p to rank dest[i] (every array of it: positions, velocities, F, the affine
 * and plastic state, temperature, material, body, type, id) where dest[i] is another rank, and
 * append the particles other ranks send here, in the order of their source rank and, within one,
 * of their index there; the particles that stay keep their order. dest[i] in [0, size). p must
 * own its storage. Collective. MPM_OK; MPM_ERR_INVALID for a destination out of range (on every
 * rank: all ranks agree, nothing moved); MPM_ERR_NOMEM. */
mpm_status mpm_dist_migrate(mpm_dist *d, mpm_particles *p, const int32_t *dest, mpm_migration *m,
                            mpm_error *err);

#endif
