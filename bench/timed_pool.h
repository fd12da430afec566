/* A host parallel-for for benchmarks that times every task: ibl_context_desc.parallel_for with
 * .parallel_host a timed_pool, and .threads its thread count, so the library splits its work
 * as for its own pool. The loops run on the library's own pool (a second context's, so they
 * are shared out exactly as in a command), each task wrapped in two clock reads; the task
 * times are summed over the threads. What the process spends outside them (on one thread, wall
 * minus task time) is its serial part, and the task time on two threads against one is what
 * running both at once costs each (a shared memory bus, a host's two virtual CPUs). */
#ifndef IBL_BENCH_TIMED_POOL_H
#define IBL_BENCH_TIMED_POOL_H

#include <ibl/ibl.h>

typedef struct timed_pool timed_pool;

/* threads >= 1 (the caller and threads - 1 workers); NULL when the threads cannot start. */
timed_pool *timed_pool_create(int threads);
void timed_pool_destroy(timed_pool *pool);
/* The ibl_parallel_for_fn to hand the context, with the pool as its host. */
void timed_pool_parallel_for(void *pool, int count, ibl_task_fn task, void *task_arg);
/* Milliseconds spent inside tasks so far, summed over the threads. */
double timed_pool_task_ms(const timed_pool *pool);

#endif
