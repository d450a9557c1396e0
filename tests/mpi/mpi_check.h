/* mpi_check.h - what the programs of tests/mpi share: every rank checks, counts its failures
 * and prints where; the program fails when any rank's check did (mpi_check_finish). */
#ifndef MPM_TEST_MPI_CHECK_H
#define MPM_TEST_MPI_CHECK_H

#include <mpi.h>
#include <mpm/mpm.h>
#include <stdio.h>

static int rank, size, failures;

#define CHECK(cond, ...)                                                                           \
  do {                                                                                             \
    if (!(cond)) {                                                                                 \
      fprintf(stderr, "rank %d: %s:%d: ", rank, __FILE__, __LINE__);                               \
      fprintf(stderr, __VA_ARGS__);                                                                \
      fprintf(stderr, "\n");                                                                       \
      ++failures;                                                                                  \
    }                                                                                              \
  } while (0)

static inline void mpi_check_start(int *argc, char ***argv) {
  MPI_Init(argc, argv);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
}

/* A simulation of the JSON scene, one thread; a scene refused ends the run (the test's own
 * mistake). */
static inline mpm_sim *mpi_check_sim(const char *json) {
  mpm_sim *sim = NULL;
  char msg[1024];
  if (mpm_sim_create_from_json(json, NULL, &sim, msg, sizeof msg) != MPM_OK) {
    fprintf(stderr, "rank %d: %s\n", rank, msg);
    MPI_Abort(MPI_COMM_WORLD, 2);
  }
  mpm_sim_set_threads(sim, 1);
  return sim;
}

/* The failures of every rank added; rank 0 prints the verdict. The program's exit status. */
static inline int mpi_check_finish(const char *name) {
  int all = 0;
  MPI_Allreduce(&failures, &all, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
  if (rank == 0)
    printf("%s on %d ranks: %s (%d failures)\n", name, size, all ? "FAILED" : "passed", all);
  MPI_Finalize();
  return all ? 1 : 0;
}

#endif
