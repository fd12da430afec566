/* The timed host pool of timed_pool.h: the library's pool, every task timed. */
#include "timed_pool.h"

#include <stdatomic.h>
#include <stdlib.h>
#include <time.h>

struct timed_pool {
    ibl_context *runner; /* its built-in pool runs the loops */
    atomic_llong task_ns;
};

typedef struct timed_loop {
    timed_pool *pool;
    ibl_task_fn task;
    void *task_arg;
} timed_loop;

static long long now_ns(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (long long)t.tv_sec * 1000000000LL + t.tv_nsec;
}

/* Set on a thread while it runs a task. A loop a task starts runs on the pool as any other
 * (the library's pool runs it on every thread): a thread inside a task that runs one of its
 * indices (helping while it waits) is already being timed, so only a thread outside any task
 * times the index it runs. Each thread's time inside tasks is counted once. */
static _Thread_local int in_task;

static void timed_task(void *arg, int index)
{
    const timed_loop *loop = arg;
    if (in_task) {
        loop->task(loop->task_arg, index);
        return;
    }
    long long t0 = now_ns();
    in_task = 1;
    loop->task(loop->task_arg, index);
    in_task = 0;
    atomic_fetch_add_explicit(&loop->pool->task_ns, now_ns() - t0, memory_order_relaxed);
}

timed_pool *timed_pool_create(int threads)
{
    timed_pool *pool = calloc(1, sizeof *pool);
    ibl_context_desc d = {.threads = threads};
    if (!pool || threads < 1 || ibl_context_create(&d, &pool->runner) != IBL_OK) {
        free(pool);
        return NULL;
    }
    return pool;
}

void timed_pool_destroy(timed_pool *pool)
{
    if (!pool) return;
    ibl_context_destroy(pool->runner);
    free(pool);
}

void timed_pool_parallel_for(void *host, int count, ibl_task_fn task, void *task_arg)
{
    timed_pool *pool = host;
    timed_loop loop = {pool, task, task_arg};
    ibl_parallel_for(pool->runner, count, timed_task, &loop);
}

double timed_pool_task_ms(const timed_pool *pool)
{
    return (double)atomic_load(&((timed_pool *)pool)->task_ns) * 1e-6;
}
