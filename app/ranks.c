/* ranks.c - `mpm run` on MPI ranks (ranks.h): MPI started and ended by the program, which rank
 * it is, and the ranks' agreement on a failure the program meets before its simulation exists.
 * MPI's own calls are this file's only; the build compiles them in with MPM_CLI_MPI
 * (CMakeLists.txt, MPM_MPI). */
#include "ranks.h"

#include <stdlib.h>

#ifdef MPM_CLI_MPI
#include <mpi.h>

static int started, rank;

/* A launcher tells its processes their place through the environment: OpenMPI's mpirun
 * (OMPI_COMM_WORLD_SIZE), MPICH's Hydra and PMI-based launchers (PMI_SIZE), PMIx launchers
 * (PMIX_RANK). A program started without one stays a single process: MPI's singleton start
 * would need the launcher's daemon for nothing. */
static int launched(void) {
  return getenv("OMPI_COMM_WORLD_SIZE") || getenv("PMI_SIZE") || getenv("PMIX_RANK");
}

int mpm_cli_ranks_start(void) {
  if (started || !launched()) return 0;
  /* the ranks' OpenMP threads never call MPI; only the main thread does */
  int provided = 0, size = 1;
  MPI_Init_thread(NULL, NULL, MPI_THREAD_FUNNELED, &provided);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  started = 1;
  return size;
}

void mpm_cli_ranks_end(void) {
  if (started) MPI_Finalize();
  started = 0;
}

int mpm_cli_rank(void) {
  return started ? rank : 0;
}

int mpm_cli_ranks_any(int failed, char *msg, size_t cap) {
  if (!started) return failed;
  int size = 1, first = 0;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  const int mine = failed ? rank : size;
  MPI_Allreduce(&mine, &first, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
  if (first == size) return 0;
  MPI_Bcast(msg, (int)cap, MPI_CHAR, first, MPI_COMM_WORLD);
  msg[cap - 1] = '\0';
  return 1;
}

#else

int mpm_cli_ranks_start(void) {
  return 0;
}

void mpm_cli_ranks_end(void) {}

int mpm_cli_rank(void) {
  return 0;
}

int mpm_cli_ranks_any(int failed, char *msg, size_t cap) {
  (void)msg;
  (void)cap;
  return failed;
}

#endif
