/* no_mpi.c - the public calls of a run on MPI ranks (mpm/mpm.h) in a library built without MPI
 * (the default; -DMPM_MPI=ON builds mpi_world.c in its place): the join is refused with the
 * reason, and a simulation is never a rank's part. */
#include "sim/sim.h"

mpm_status mpm_sim_join_mpi_world(mpm_sim *sim) {
  return mpm_error_set(&sim->error, MPM_ERR_INVALID,
                       "mpm_sim_join_mpi_world: this library was built without MPI (configure "
                       "with -DMPM_MPI=ON, docs/distributed.md)");
}

mpm_status mpm_sim_ranks_agree(mpm_sim *sim, mpm_status st) {
  (void)sim;
  return st;
}
