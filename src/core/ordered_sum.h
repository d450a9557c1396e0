/* ordered_sum.h - a parallel sum over many items whose result does not depend on the thread
 * count: the items are summed in at most MPM_ORDERED_SUM_CHUNKS chunks of at least
 * MPM_ORDERED_SUM_MIN consecutive items (their size set by the item count alone), each chunk in
 * order by one thread, and the chunks' sums are added in chunk order. (A reduction clause adds
 * the threads' partial sums, which depend on how the items were split among them.) Allocates
 * nothing. */
#ifndef MPM_CORE_ORDERED_SUM_H
#define MPM_CORE_ORDERED_SUM_H

#include <stddef.h>

#define MPM_ORDERED_SUM_CHUNKS 256
#define MPM_ORDERED_SUM_MIN 512

/* sum over i < n of term(ctx, i) */
double mpm_ordered_sum(size_t n, double (*term)(const void *ctx, size_t i), const void *ctx);

#endif
