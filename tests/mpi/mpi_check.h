/* mpi_check.h - what the programs of tests/mpi share: every rank checks, counts its failures
 * and prints where; the program fails when any rank's check did (mpi_check_finish). */
#ifndef MPM_TEST_MPI_CHECK_H
#define MPM_TEST_MPI_CHECK_H

#include <mpi.h>
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
