/* Internal: the built-in thread pool behind ibl_parallel_for (context.c) when the host gives
 * no parallel-for of its own. */
#ifndef IBL_CORE_POOL_H
#define IBL_CORE_POOL_H

#include "ibl/core.h"

enum { IBL__POOL_MAX_THREADS = 64 };

typedef struct ibl__pool ibl__pool;

/* A pool of `workers` threads besides the threads that call it; NULL when out of memory.
 * When the system refuses a thread the pool runs with fewer (ibl__pool_threads). */
ibl__pool *ibl__pool_create(int workers);
void ibl__pool_destroy(ibl__pool *pool);
/* The threads a loop can run on: the workers and the caller. */
int ibl__pool_threads(const ibl__pool *pool);

/* Runs task(arg, i) for every i in [0, count) and returns when all are done. Any thread may
 * call it, a pool task too: loops run side by side, and a thread that waits for its own loop
 * runs indices of the others meanwhile. */
void ibl__pool_run(ibl__pool *pool, int count, ibl_task_fn task, void *arg);

/* A loop taken in index order by the workers while the caller does something else (context
 * internal: ibl__parallel_begin). Begin returns 0 when another such loop is running. */
int ibl__pool_begin(ibl__pool *pool, int count, ibl_task_fn task, void *arg);
int ibl__pool_help(ibl__pool *pool);
void ibl__pool_end(ibl__pool *pool);

/* Wakes the workers without a job: they wait awake for a while (ibl__parallel_warm). */
void ibl__pool_warm(ibl__pool *pool);

#endif
