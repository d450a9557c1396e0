/* reduce.h - the global reductions of a step through one interface: the step's largest speed
 * (the CFL step and the guard), the energies and momenta of stats.csv, the guard's scans for
 * unstable particles, CG's dot products and norms and the implicit step's energies.
 *
 * Every such figure is first made over this process's particles or DOFs (deterministically, in a
 * fixed order) and then handed to mpm_reduce_all, which turns it into the figure over every
 * process of the run. A single process has nothing to combine: its reduction is NULL and the
 * call does nothing. A distributed run (MPI) fills the table with its all-reduce, which must
 * combine the ranks in a fixed order, so that a run is reproducible for a given rank count. */
#ifndef MPM_CORE_REDUCE_H
#define MPM_CORE_REDUCE_H

typedef enum mpm_reduce_op { MPM_REDUCE_SUM, MPM_REDUCE_MAX, MPM_REDUCE_MIN } mpm_reduce_op;

typedef struct mpm_reduction {
  /* values[0 .. count) become their sum (maximum, minimum) over every process, in place; a NaN
   * of any process wins a maximum, so that every process sees it */
  void (*all)(void *ctx, mpm_reduce_op op, double *values, int count);
  void *ctx;
} mpm_reduction;

static inline void mpm_reduce_all(const mpm_reduction *r, mpm_reduce_op op, double *values,
                                  int count) {
  if (r && r->all) r->all(r->ctx, op, values, count);
}

#endif
