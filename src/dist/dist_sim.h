/* dist_sim.h - a simulation as one rank's part of a distributed run (built with -DMPM_MPI=ON).
 *
 * Every rank makes the simulation from the same scene; mpm_dist_attach then keeps this rank's
 * particles (those whose block, the 4x4x4-cell block of their cell, the partition gives it:
 * partition.h) and wraps the grid stack (sim/grid_stack.h) with the ranks' exchanges, and sets
 * the simulation's reduction to the ranks' (comm.h). A step then runs as on one process, with:
 *   sort   when the ranks' particles are out of balance, the blocks are cut again; then the
 *          particles whose block now belongs to another rank migrate there, every array of
 *          them (comm.h); the grid is activated around this rank's particles; each block it
 *          holds but does not own (a ghost: the stencils of its particles near the range's
 *          edge reach it) is named to its owner, which activates it too;
 *   P2G    the ghosts' partial sums (mass, momentum, force) go to their owners, which add them
 *          after their own, in the order of the sending ranks (a run is reproducible for a
 *          given rank count); the ghosts are then emptied, so the grid update and the
 *          colliders' reaction sums see each node once, at its owner;
 *   G2P    the owners send the updated values (mass, v^n, v^{n+1}) back to the ghosts first.
 * The bytes a step sends grow with the surface of the ranks' ranges (the ghost blocks), not with
 * the particles or the grid.
 *
 * A rank that runs out of memory tells the others instead of leaving them waiting in an exchange
 * it skips: a vote before each of these exchanges, and the step's verdict after each stage
 * (sim/step.c, through the reduction): every rank's step fails, the others naming the stage.
 *
 * What runs on ranks so far: material points on the uniform sparse grid, the explicit step,
 * with every kernel, transfer, material, collider and body force. The rest (the implicit step,
 * the multi-level grid, particle domains, heat, the dense grid) is refused by mpm_dist_attach
 * with a message naming it. */
#ifndef MPM_DIST_DIST_SIM_H
#define MPM_DIST_DIST_SIM_H

#include "core/error.h"
#include "dist/comm.h"

#include <mpm/mpm.h>

/* Make sim (new, no step taken, made from the same scene on every rank) this rank's part of the
 * run over d; d must outlive sim. Collective. MPM_OK; MPM_ERR_INVALID naming what does not run
 * on ranks yet (on every rank); MPM_ERR_NOMEM. */
mpm_status mpm_dist_attach(mpm_dist *d, mpm_sim *sim, mpm_error *err);

/* The last step's exchanges on this rank (and the counts and time since the attach). */
typedef struct mpm_dist_figures {
  size_t ghost_blocks;  /* blocks held here and owned by another rank */
  size_t shared_blocks; /* blocks owned here that other ranks hold as ghosts */
  size_t halo_bytes;    /* node values sent (after P2G and before G2P) */
  size_t halo_messages; /* nonzero sends among them */
  mpm_migration migration;
  double imbalance;  /* the largest rank's particles over the mean, at the last step's start */
  size_t rebalances; /* cuts made again since the attach */
  /* wall seconds in the exchanges since the attach (the recut, the migration, the ghosts'
     names and values, their packing and the waits for the other ranks included) */
  double exchange_seconds;
} mpm_dist_figures;

/* The cut is made again, at a step's sort, when the largest rank holds more than this many times
 * the mean of the particles (MPM_DIST_REBALANCE unless set; 0: never). The figures count it. */
#define MPM_DIST_REBALANCE 1.25
void mpm_dist_set_rebalance(mpm_sim *sim, double threshold);

mpm_dist_figures mpm_dist_sim_figures(const mpm_sim *sim);

/* The run's processes of an attached simulation, NULL for one that is not a rank's part. */
mpm_dist *mpm_dist_of(const mpm_sim *sim);

/* The simulation destroys its d with itself (mpm_sim_join_mpi_world's, made for it). */
void mpm_dist_sim_own(mpm_sim *sim);

/* The frame writer of a run on ranks (mpi_frame_writer.c): each rank writes its particles as a
 * piece, frame_NNNN_pRRRR.vtu and .ply (RRRR the rank, four digits or more), and rank 0 the
 * frame's index frame_NNNN.pvtu (VTK XML PUnstructuredGrid), frames.pvd and run.pvd pointing
 * at the indexes, and stats.csv with the figures over every rank; rank 0 alone claims and
 * locks the output folder. No checkpoint yet (refused, with the reason). */
extern const struct mpm_frame_writer mpm_frame_ranks;

#endif
