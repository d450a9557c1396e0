/* mpi_world.c - the public calls of a run on MPI ranks (mpm/mpm.h: mpm_sim_join_mpi_world,
 * mpm_sim_ranks_agree), in a library built with MPI: the simulation becomes a rank's part of a
 * run over MPI_COMM_WORLD (dist_sim.h) and writes its frames through the ranks' writer
 * (mpi_frame_writer.c). Without MPI, no_mpi.c answers both. */
#include "dist/comm.h"
#include "dist/dist_sim.h"
#include "dist/mpi_internal.h"
#include "sim/frame_writer.h"
#include "sim/sim.h"

mpm_status mpm_sim_join_mpi_world(mpm_sim *sim) {
  int up = 0, down = 0;
  MPI_Initialized(&up);
  MPI_Finalized(&down);
  if (!up || down)
    return mpm_error_set(&sim->error, MPM_ERR_INVALID,
                         "mpm_sim_join_mpi_world: MPI is not initialised (call MPI_Init first)");
  if (mpm_dist_of(sim)) /* (every rank's is: they joined together) */
    return mpm_error_set(&sim->error, MPM_ERR_INVALID,
                         "mpm_sim_join_mpi_world: the simulation is a rank's part already");
  mpm_error err;
  mpm_error_clear(&err);
  mpm_dist *d = mpm_dist_create_world(&err);
  if (!d) return mpm_error_set(&sim->error, err.status, "%s", err.message);
  /* a rank's surface would end at its blocks' edge: not on ranks yet; and frame 0 written by
     one process's writer would be another run's (every rank has the same scene and made the
     same calls, so every rank refuses alike; the vote keeps it so) */
  const int mine = sim->out.enabled ? 2 : sim->scene.output.surface.enabled ? 1 : 0;
  int why = 0;
  MPI_Allreduce(&mine, &why, 1, MPI_INT, MPI_MAX, mpm_dist_comm(d));
  mpm_status st = MPM_OK;
  if (why == 2)
    st = mpm_error_set(&err, MPM_ERR_INVALID,
                       "mpm_sim_join_mpi_world: the output is open already (join first, then "
                       "open it: every rank writes its part)");
  else if (why == 1)
    st = mpm_error_set(&err, MPM_ERR_INVALID,
                       "a run on %d ranks: particle surfaces (output.surface) are not made on "
                       "ranks yet",
                       mpm_dist_size(d));
  if (st == MPM_OK) st = mpm_dist_attach(d, sim, &err);
  if (st != MPM_OK) {
    mpm_dist_destroy(d);
    return mpm_error_set(&sim->error, st, "%s", err.message);
  }
  mpm_dist_sim_own(sim);
  mpm_sim_set_writer(sim, &mpm_frame_ranks);
  return MPM_OK;
}

mpm_status mpm_sim_ranks_agree(mpm_sim *sim, mpm_status st) {
  mpm_dist *d = mpm_dist_of(sim);
  return d ? mpm_dist_agree(d, st, &sim->error) : st;
}
