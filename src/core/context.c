/* The context: allocator, memory limit, failure message, progress and the parallel-for hook
 * with a default thread pool (workers pull indices from an atomic counter). */
#define _POSIX_C_SOURCE 200809L
#include "ibl/core.h"
#include "core/cpu.h"
#include "core/context_internal.h"

#include <pthread.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

enum { MAX_POOL_THREADS = 64, MESSAGE_BYTES = 512 };

typedef struct thread_pool {
    pthread_t threads[MAX_POOL_THREADS];
    int worker_count; /* threads besides the caller */
    pthread_mutex_t lock;
    pthread_cond_t wake;
    pthread_cond_t done;
    /* the current job */
    ibl_task_fn task;
    void *task_arg;
    int count;
    atomic_int next;
    atomic_int active_workers;
    atomic_uint generation;
    atomic_int quit;
} thread_pool;

struct ibl_context {
    ibl_context_desc desc;
    thread_pool *pool;
    int thread_count;
    unsigned cpu_features; /* what kernels may use (core/cpu.h) */
    ibl_status last_status;
    char message[MESSAGE_BYTES];
};

const char *ibl_status_name(ibl_status status)
{
    switch (status) {
    case IBL_OK: return "ok";
    case IBL_ERR_INVALID_ARGUMENT: return "invalid argument";
    case IBL_ERR_OUT_OF_MEMORY: return "out of memory";
    case IBL_ERR_TOO_LARGE: return "too large";
    case IBL_ERR_IO: return "input/output error";
    case IBL_ERR_FORMAT: return "malformed input";
    case IBL_ERR_UNSUPPORTED: return "unsupported";
    case IBL_ERR_BAD_PIXELS: return "bad pixel values";
    case IBL_ERR_CANCELLED: return "cancelled";
    }
    return "unknown status";
}

static void *default_alloc(size_t bytes, void *user)
{
    (void)user;
    void *p = NULL;
    if (bytes == 0) bytes = 1;
    if (posix_memalign(&p, 64, bytes) != 0) return NULL;
    return p;
}

static void default_free(void *ptr, void *user)
{
    (void)user;
    free(ptr);
}

static void run_indices(thread_pool *pool)
{
    for (;;) {
        int i = atomic_fetch_add_explicit(&pool->next, 1, memory_order_relaxed);
        if (i >= pool->count) break;
        pool->task(pool->task_arg, i);
    }
}

/* A parallel-for usually follows the last one within microseconds, so a thread waits awake
 * for a while (about 0.1 ms) before it sleeps on a condition variable: a wake-up through the
 * kernel cost ~35 us per call on a 2-core VM, and a prefilter makes hundreds of calls. */
enum { SPIN_ROUNDS = 4000 };

static void cpu_relax(void)
{
#if defined(__x86_64__) || defined(__i386__)
    __builtin_ia32_pause();
#elif defined(__aarch64__)
    __asm__ __volatile__("yield");
#endif
}

static void *worker_main(void *arg)
{
    thread_pool *pool = arg;
    unsigned seen = 0;
    for (;;) {
        for (int i = 0; i < SPIN_ROUNDS && atomic_load(&pool->generation) == seen && !atomic_load(&pool->quit); i++)
            cpu_relax();
        pthread_mutex_lock(&pool->lock);
        while (!atomic_load(&pool->quit) && atomic_load(&pool->generation) == seen)
            pthread_cond_wait(&pool->wake, &pool->lock);
        int quit = atomic_load(&pool->quit);
        pthread_mutex_unlock(&pool->lock);
        if (quit) break;
        /* the caller waits for every worker before it starts the next job: one job a round */
        seen = atomic_load(&pool->generation);
        run_indices(pool);
        if (atomic_fetch_sub(&pool->active_workers, 1) == 1) {
            pthread_mutex_lock(&pool->lock);
            pthread_cond_signal(&pool->done);
            pthread_mutex_unlock(&pool->lock);
        }
    }
    return NULL;
}

static void pool_destroy(thread_pool *pool)
{
    if (!pool) return;
    pthread_mutex_lock(&pool->lock);
    atomic_store(&pool->quit, 1);
    pthread_cond_broadcast(&pool->wake);
    pthread_mutex_unlock(&pool->lock);
    for (int i = 0; i < pool->worker_count; i++) pthread_join(pool->threads[i], NULL);
    pthread_mutex_destroy(&pool->lock);
    pthread_cond_destroy(&pool->wake);
    pthread_cond_destroy(&pool->done);
    free(pool);
}

static thread_pool *pool_create(int workers)
{
    thread_pool *pool = calloc(1, sizeof *pool);
    if (!pool) return NULL;
    pthread_mutex_init(&pool->lock, NULL);
    pthread_cond_init(&pool->wake, NULL);
    pthread_cond_init(&pool->done, NULL);
    for (int i = 0; i < workers; i++) {
        if (pthread_create(&pool->threads[i], NULL, worker_main, pool) != 0) break;
        pool->worker_count++;
    }
    return pool;
}

static void pool_run(thread_pool *pool, int count, ibl_task_fn task, void *arg)
{
    pthread_mutex_lock(&pool->lock);
    pool->task = task;
    pool->task_arg = arg;
    pool->count = count;
    atomic_store(&pool->next, 0);
    atomic_store(&pool->active_workers, pool->worker_count);
    atomic_fetch_add(&pool->generation, 1u);
    pthread_cond_broadcast(&pool->wake);
    pthread_mutex_unlock(&pool->lock);
    run_indices(pool);
    for (int i = 0; i < SPIN_ROUNDS && atomic_load(&pool->active_workers) > 0; i++) cpu_relax();
    if (atomic_load(&pool->active_workers) > 0) {
        pthread_mutex_lock(&pool->lock);
        while (atomic_load(&pool->active_workers) > 0) pthread_cond_wait(&pool->done, &pool->lock);
        pthread_mutex_unlock(&pool->lock);
    }
}

ibl_status ibl_context_create(const ibl_context_desc *desc, ibl_context **out)
{
    if (!out) return IBL_ERR_INVALID_ARGUMENT;
    *out = NULL;
    ibl_context_desc d;
    if (desc) d = *desc;
    else memset(&d, 0, sizeof d);
    if ((d.allocator.alloc == NULL) != (d.allocator.free == NULL)) return IBL_ERR_INVALID_ARGUMENT;
    if (!d.allocator.alloc) {
        d.allocator.alloc = default_alloc;
        d.allocator.free = default_free;
    }
    if (d.max_bytes == 0) d.max_bytes = (uint64_t)4 << 30;
    ibl_context *ctx = d.allocator.alloc(sizeof *ctx, d.allocator.user);
    if (!ctx) return IBL_ERR_OUT_OF_MEMORY;
    memset(ctx, 0, sizeof *ctx);
    ctx->desc = d;
    ctx->thread_count = 1;
    ctx->cpu_features = d.kernels == IBL_KERNELS_PORTABLE ? 0u : ibl__cpu_detect();
    if (!d.parallel_for) {
        int threads = d.threads;
        if (threads <= 0) {
            long online = sysconf(_SC_NPROCESSORS_ONLN);
            threads = online > 0 ? (int)online : 1;
        }
        if (threads > MAX_POOL_THREADS) threads = MAX_POOL_THREADS;
        if (threads > 1) {
            ctx->pool = pool_create(threads - 1);
            if (!ctx->pool) {
                d.allocator.free(ctx, d.allocator.user);
                return IBL_ERR_OUT_OF_MEMORY;
            }
            ctx->thread_count = ctx->pool->worker_count + 1;
        }
    }
    *out = ctx;
    return IBL_OK;
}

void ibl_context_destroy(ibl_context *ctx)
{
    if (!ctx) return;
    pool_destroy(ctx->pool);
    ibl_allocator a = ctx->desc.allocator;
    a.free(ctx, a.user);
}

unsigned ibl__cpu_features(const ibl_context *ctx)
{
    return ctx ? ctx->cpu_features : ibl__cpu_detect();
}

const char *ibl_context_message(const ibl_context *ctx)
{
    return ctx ? ctx->message : "";
}

ibl_status ibl_context_status(const ibl_context *ctx)
{
    return ctx ? ctx->last_status : IBL_OK;
}

int ibl_context_threads(const ibl_context *ctx)
{
    return ctx ? ctx->thread_count : 1;
}

ibl_status ibl__fail(ibl_context *ctx, ibl_status status, const char *fmt, ...)
{
    if (ctx) ctx->last_status = status;
    if (ctx && fmt) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(ctx->message, sizeof ctx->message, fmt, ap);
        va_end(ap);
    }
    return status;
}

void *ibl_alloc(ibl_context *ctx, size_t bytes)
{
    if (!ctx) return default_alloc(bytes, NULL);
    if ((uint64_t)bytes > ctx->desc.max_bytes) {
        ibl__fail(ctx, IBL_ERR_TOO_LARGE,
                 "needs %.1f MiB in one block, over the memory limit of %.1f MiB",
                 (double)bytes / 1048576.0, (double)ctx->desc.max_bytes / 1048576.0);
        return NULL;
    }
    void *p = ctx->desc.allocator.alloc(bytes, ctx->desc.allocator.user);
    if (!p) ibl__fail(ctx, IBL_ERR_OUT_OF_MEMORY, "out of memory allocating %zu bytes", bytes);
    return p;
}

void *ibl_calloc(ibl_context *ctx, size_t count, size_t size)
{
    if (size != 0 && count > SIZE_MAX / size) {
        ibl__fail(ctx, IBL_ERR_TOO_LARGE, "allocation size overflows");
        return NULL;
    }
    void *p = ibl_alloc(ctx, count * size);
    if (p) memset(p, 0, count * size);
    return p;
}

char *ibl__strdup(ibl_context *ctx, const char *s)
{
    if (!s) return NULL;
    size_t n = strlen(s) + 1;
    char *c = ibl_alloc(ctx, n);
    if (c) memcpy(c, s, n);
    return c;
}

void ibl_free(ibl_context *ctx, void *ptr)
{
    if (!ptr) return;
    if (ctx) ctx->desc.allocator.free(ptr, ctx->desc.allocator.user);
    else free(ptr);
}

void ibl_parallel_for(ibl_context *ctx, int count, ibl_task_fn task, void *task_arg)
{
    if (count <= 0) return;
    if (ctx && ctx->desc.parallel_for) {
        ctx->desc.parallel_for(ctx->desc.parallel_host, count, task, task_arg);
        return;
    }
    if (!ctx || !ctx->pool || count == 1) {
        for (int i = 0; i < count; i++) task(task_arg, i);
        return;
    }
    pool_run(ctx->pool, count, task, task_arg);
}

ibl_status ibl__progress(ibl_context *ctx, const char *stage, double fraction)
{
    if (!ctx || !ctx->desc.progress) return IBL_OK;
    if (ctx->desc.progress(ctx->desc.progress_user, stage, fraction))
        return ibl__fail(ctx, IBL_ERR_CANCELLED, "%s: cancelled", stage ? stage : "work");
    return IBL_OK;
}
