/* ranks.h - `mpm run` on MPI ranks: in a build with MPI (-DMPM_MPI=ON), a program that an MPI
 * launcher started (mpirun, mpiexec, srun with PMI or PMIx) starts MPI and runs as one rank of
 * the run; started alone, or in a build without MPI, it is one process, rank 0 of 1, and these
 * calls do nothing. */
#ifndef MPM_APP_RANKS_H
#define MPM_APP_RANKS_H

#include <stddef.h>

/* Start MPI when a launcher started this program (MPI_Init). Returns the ranks of the run: 0
 * when it is not a run on ranks (no launcher, or no MPI in the build), else at least 1. */
int mpm_cli_ranks_start(void);
/* End MPI when mpm_cli_ranks_start started it (after the simulation is destroyed). */
void mpm_cli_ranks_end(void);
/* This process's rank (0 alone). */
int mpm_cli_rank(void);
/* On ranks: whether any rank's `failed` is nonzero, and then the message of the first rank that
 * failed copied into every rank's msg (cap bytes). Collective. Alone: failed. */
int mpm_cli_ranks_any(int failed, char *msg, size_t cap);

#endif
