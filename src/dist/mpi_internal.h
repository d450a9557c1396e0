/* mpi_internal.h - what the MPI files of src/dist/ share: the ranks' communicator. Included by
 * src/dist/mpi_*.c only (the others name no MPI type). */
#ifndef MPM_DIST_MPI_INTERNAL_H
#define MPM_DIST_MPI_INTERNAL_H

#include "dist/comm.h"

#include <mpi.h>

MPI_Comm mpm_dist_comm(const mpm_dist *d);

#endif
