/* The timed host pool of timed_pool.h. */
#include "timed_pool.h"

#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

enum { MAX_THREADS = 64 };
#define SPIN_NS 500000LL /* as the library's pool (src/core/context.c) */

struct timed_pool {
    int threads;
    pthread_t workers[MAX_THREADS];
    int started;
    pthread_mutex_t lock;
    pthread_cond_t wake;
    atomic_uint generation;
    atomic_int quit;
    int open; /* under lock: the current loop still takes workers */
    ibl_task_fn task;
    void *task_arg;
    int shares;
    struct share {
        _Alignas(64) atomic_int next;
        int end;
    } share[MAX_THREADS]; /* each thread's cut of the indices, [next, end) */
    atomic_int active; /* workers inside the current loop */
    atomic_flag running; /* a loop is on: a loop a task starts runs inside it */
    atomic_llong task_ns[MAX_THREADS]; /* [0]: the caller */
    struct worker_arg {
        timed_pool *pool;
        int id;
    } args[MAX_THREADS];
};

static long long now_ns(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (long long)t.tv_sec * 1000000000LL + t.tv_nsec;
}

/* Its own share front to back, then what is left of the others'. */
static void run_indices(timed_pool *pool, int id)
{
    long long spent = 0;
    for (int k = 0; k < pool->shares; k++) {
        struct share *s = &pool->share[(id + k) % pool->shares];
        for (int i; (i = atomic_fetch_add(&s->next, 1)) < s->end;) {
            long long t0 = now_ns();
            pool->task(pool->task_arg, i);
            spent += now_ns() - t0;
        }
    }
    atomic_fetch_add(&pool->task_ns[id], spent);
}

static void *worker_main(void *p)
{
    struct worker_arg *a = p;
    timed_pool *pool = a->pool;
    unsigned seen = 0;
    for (;;) {
        long long deadline = now_ns() + SPIN_NS;
        while (atomic_load(&pool->generation) == seen && !atomic_load(&pool->quit) && now_ns() < deadline) {
#if defined(__x86_64__) || defined(__i386__)
            __builtin_ia32_pause();
#endif
        }
        pthread_mutex_lock(&pool->lock);
        while (atomic_load(&pool->generation) == seen && !atomic_load(&pool->quit))
            pthread_cond_wait(&pool->wake, &pool->lock);
        seen = atomic_load(&pool->generation);
        int join = !atomic_load(&pool->quit) && pool->open;
        if (join) atomic_fetch_add(&pool->active, 1);
        pthread_mutex_unlock(&pool->lock);
        if (atomic_load(&pool->quit)) return NULL;
        if (!join) continue;
        run_indices(pool, a->id);
        atomic_fetch_sub(&pool->active, 1);
    }
}

timed_pool *timed_pool_create(int threads)
{
    if (threads < 1 || threads > MAX_THREADS) return NULL;
    size_t bytes = (sizeof(timed_pool) + 63) / 64 * 64;
    timed_pool *pool = aligned_alloc(64, bytes);
    if (!pool) return NULL;
    memset(pool, 0, bytes);
    pool->threads = threads;
    atomic_flag_clear(&pool->running);
    pthread_mutex_init(&pool->lock, NULL);
    pthread_cond_init(&pool->wake, NULL);
    for (int i = 1; i < threads; i++) {
        pool->args[i].pool = pool, pool->args[i].id = i;
        if (pthread_create(&pool->workers[i], NULL, worker_main, &pool->args[i]) != 0) {
            timed_pool_destroy(pool);
            return NULL;
        }
        pool->started = i;
    }
    return pool;
}

void timed_pool_destroy(timed_pool *pool)
{
    if (!pool) return;
    pthread_mutex_lock(&pool->lock);
    atomic_store(&pool->quit, 1);
    pthread_cond_broadcast(&pool->wake);
    pthread_mutex_unlock(&pool->lock);
    for (int i = 1; i <= pool->started; i++) pthread_join(pool->workers[i], NULL);
    pthread_mutex_destroy(&pool->lock);
    pthread_cond_destroy(&pool->wake);
    free(pool);
}

void timed_pool_parallel_for(void *host, int count, ibl_task_fn task, void *task_arg)
{
    timed_pool *pool = host;
    if (count <= 0) return;
    if (atomic_flag_test_and_set(&pool->running)) {
        /* started by a task (a large image zeroed in parallel): its time is that task's */
        for (int i = 0; i < count; i++) task(task_arg, i);
        return;
    }
    pthread_mutex_lock(&pool->lock);
    pool->task = task, pool->task_arg = task_arg;
    pool->shares = pool->threads < count ? pool->threads : count;
    for (int s = 0; s < pool->shares; s++) {
        atomic_store(&pool->share[s].next, (int)((long long)count * s / pool->shares));
        pool->share[s].end = (int)((long long)count * (s + 1) / pool->shares);
    }
    pool->open = pool->threads > 1;
    atomic_fetch_add(&pool->generation, 1u);
    pthread_cond_broadcast(&pool->wake);
    pthread_mutex_unlock(&pool->lock);
    run_indices(pool, 0);
    pthread_mutex_lock(&pool->lock);
    pool->open = 0; /* every index is taken: no more workers join */
    pthread_mutex_unlock(&pool->lock);
    while (atomic_load(&pool->active) > 0) {
#if defined(__x86_64__) || defined(__i386__)
        __builtin_ia32_pause();
#endif
    }
    atomic_flag_clear(&pool->running);
}

double timed_pool_task_ms(const timed_pool *pool)
{
    long long ns = 0;
    for (int i = 0; i < pool->threads; i++) ns += atomic_load(&((timed_pool *)pool)->task_ns[i]);
    return (double)ns * 1e-6;
}
