/* The built-in thread pool: loops ("jobs") posted by any thread, the pool's tasks included,
 * run side by side on the workers and on the threads that posted them.
 *
 * A job lives on its poster's stack while it runs and sits in one of the pool's job slots.
 * A thread with nothing to do, a worker or a poster waiting for the last indices of its own
 * job, takes the oldest job that has indices left and runs them. So a loop started inside a
 * task runs on every thread, and two pieces of work that do not depend on each other (a
 * specular plan, which needs only sizes, and the decoding of the input it will filter) can be
 * started as the two indices of one loop: whichever finishes first helps the other's loops.
 * Which thread runs an index never changes what it computes. */
#define _POSIX_C_SOURCE 200809L
#include "core/pool.h"
#include "core/context_internal.h"

#include <pthread.h>
#include <sched.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* One thread's share of a job's indices, [next, end), on a cache line of its own. */
typedef struct index_share {
    _Alignas(64) atomic_int next;
    int end;
} index_share;

typedef struct pool_job pool_job;
struct pool_job {
    index_share share[IBL__POOL_MAX_THREADS];
    ibl_task_fn task;
    void *arg;
    int count;
    int shares;          /* 1: one share that every thread takes front to back */
    atomic_int finished; /* indices whose task has returned */
    unsigned ticket;     /* the order of posting: the lower, the older */
    int slot;            /* where it is posted */
};

/* Posting, finding and retiring a job take no lock. A loop's hand-off between two threads
 * that arrive at once (the poster retiring its last loop or posting the next one, the worker
 * looking for it) went through one mutex four or five times a loop; contended, glibc's mutex
 * sleeps in the kernel, and a loop of empty tasks cost ~6 us on two threads of a 2-core VM
 * against ~0.3 us on one.
 *
 * A slot holds 0 (free), SLOT_DRAINING (its job retired, readers leaving) or a job. A reader
 * counts itself in the slot's users, then reads the slot; the retiring poster writes
 * SLOT_DRAINING, then reads the users and waits for them to leave. Both orders are
 * sequentially consistent, so either the reader sees the job gone or the poster sees the
 * reader and waits: a job is never read after its poster's frame is gone. */
enum { JOB_SLOTS = 64 };
#define SLOT_DRAINING ((uintptr_t)1)

typedef struct job_slot {
    _Alignas(64) atomic_uintptr_t job;
    atomic_int users; /* threads that may be reading the slot's job */
} job_slot;

typedef struct worker_seat {
    ibl__pool *pool;
    int seat; /* 1 + the worker's number; every other thread sits at 0 */
} worker_seat;

struct ibl__pool {
    pthread_t threads[IBL__POOL_MAX_THREADS];
    worker_seat seats[IBL__POOL_MAX_THREADS];
    int worker_count;
    pthread_mutex_t lock;
    pthread_cond_t wake;    /* a job posted or finished, or the pool ends */
    job_slot slots[JOB_SLOTS];
    atomic_int slots_used;  /* no slot at or past it has ever held a job */
    atomic_uint tickets;
    atomic_uint generation; /* moves on every post, on every job's last index and at the end */
    atomic_int sleepers;    /* threads waiting on `wake` */
    atomic_int quit;
    pool_job begun;         /* the in-order loop of ibl__pool_begin */
    atomic_flag begun_busy;
};

/* A parallel-for usually follows the last one within microseconds, so a thread waits awake
 * for a while before it sleeps on a condition variable: a wake-up through the kernel cost
 * ~35 us per call on a 2-core VM, and a prefilter makes hundreds of calls. The while is
 * SPIN_NS of the monotonic clock (read every SPIN_CHECK pauses; a pause takes ~25 ns on one
 * CPU and ~140 on another): 0.5 ms covers most of the serial stretches between a prefilter's
 * loops (the 256 GGX chain has ~14 a run over 0.1 ms, ~12 of them under 0.5 ms), after
 * which a worker woken through the kernel joined ~75 us late; with 0.1 ms of spinning that
 * was ~1 ms a run of the caller working alone. */
#define SPIN_NS 500000L
enum { SPIN_CHECK = 64, YIELD_AFTER = 4096 };

void ibl__cpu_relax(void)
{
#if defined(__x86_64__) || defined(__i386__)
    __builtin_ia32_pause();
#elif defined(__aarch64__)
    __asm__ __volatile__("yield");
#endif
}

static long monotonic_ns(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (long)t.tv_sec * 1000000000L + t.tv_nsec;
}

/* Every thread that waits for the generation to move: a spinning one sees it, a sleeping one
 * is woken. The store comes before the count of sleepers is read, and a sleeper counts itself
 * before it reads the generation (both sequentially consistent), so one of the two always
 * sees the other. */
static void announce(ibl__pool *pool)
{
    atomic_fetch_add(&pool->generation, 1u);
    if (atomic_load(&pool->sleepers) > 0) {
        pthread_mutex_lock(&pool->lock);
        pthread_cond_broadcast(&pool->wake);
        pthread_mutex_unlock(&pool->lock);
    }
}

/* Waits, awake for up to SPIN_NS and then asleep, until the generation is no longer `seen`. */
static void wait_for_news(ibl__pool *pool, unsigned seen)
{
    long deadline = 0;
    for (int i = 0; atomic_load(&pool->generation) == seen; i++) {
        if (i % SPIN_CHECK == 0) {
            long now = monotonic_ns();
            if (!deadline) deadline = now + SPIN_NS;
            else if (now >= deadline) break;
        }
        ibl__cpu_relax();
    }
    pthread_mutex_lock(&pool->lock);
    atomic_fetch_add(&pool->sleepers, 1);
    while (atomic_load(&pool->generation) == seen) pthread_cond_wait(&pool->wake, &pool->lock);
    atomic_fetch_sub(&pool->sleepers, 1);
    pthread_mutex_unlock(&pool->lock);
}

static void job_init(pool_job *job, const ibl__pool *pool, int count, ibl_task_fn task, void *arg,
                     int in_order)
{
    job->task = task;
    job->arg = arg;
    job->count = count;
    int shares = in_order ? 1 : pool->worker_count + 1;
    job->shares = shares < count ? shares : count;
    for (int s = 0; s < job->shares; s++) {
        atomic_init(&job->share[s].next, (int)((int64_t)count * s / job->shares));
        job->share[s].end = (int)((int64_t)count * (s + 1) / job->shares);
    }
    atomic_init(&job->finished, 0);
    job->ticket = 0;
    job->slot = -1;
}

static int has_indices(const pool_job *job)
{
    for (int s = 0; s < job->shares; s++)
        if (atomic_load_explicit(&job->share[s].next, memory_order_relaxed) < job->share[s].end)
            return 1;
    return 0;
}

/* Puts the job in a free slot and wakes the waiting threads; 0 when every slot is taken (as
 * many jobs open at once as JOB_SLOTS: the caller then runs its indices alone). */
static int post(ibl__pool *pool, pool_job *job)
{
    job->ticket = atomic_fetch_add(&pool->tickets, 1u);
    for (int s = 0; s < JOB_SLOTS; s++) {
        uintptr_t free_slot = 0;
        if (atomic_load_explicit(&pool->slots[s].job, memory_order_relaxed) != 0) continue;
        job->slot = s;
        if (!atomic_compare_exchange_strong(&pool->slots[s].job, &free_slot, (uintptr_t)job))
            continue;
        int used = atomic_load(&pool->slots_used);
        while (used <= s && !atomic_compare_exchange_weak(&pool->slots_used, &used, s + 1)) {}
        announce(pool);
        return 1;
    }
    job->slot = -1;
    return 0;
}

/* The job in slot s, counted in the slot's users until release(); NULL if the slot holds
 * none. */
static pool_job *enter_slot(ibl__pool *pool, int s)
{
    job_slot *slot = &pool->slots[s];
    if (atomic_load_explicit(&slot->job, memory_order_relaxed) <= SLOT_DRAINING) return NULL;
    atomic_fetch_add(&slot->users, 1);
    uintptr_t job = atomic_load(&slot->job);
    if (job > SLOT_DRAINING) return (pool_job *)job;
    atomic_fetch_sub(&slot->users, 1);
    return NULL;
}

static void release(ibl__pool *pool, const pool_job *job)
{
    atomic_fetch_sub(&pool->slots[job->slot].users, 1); /* the job may be gone after this */
}

/* The oldest open job with indices left, counted as used until release(); NULL if none. */
static pool_job *take_open_job(ibl__pool *pool)
{
    pool_job *best = NULL;
    int used = atomic_load(&pool->slots_used);
    for (int s = 0; s < used; s++) {
        pool_job *job = enter_slot(pool, s);
        if (!job) continue;
        if (has_indices(job) && (!best || (int)(job->ticket - best->ticket) < 0)) {
            if (best) release(pool, best);
            best = job;
        } else {
            release(pool, job);
        }
    }
    return best;
}

/* A loop's indices are cut into one contiguous share per thread: each thread runs its own
 * front to back, then takes what is left of the others'. Consecutive loops mostly walk the
 * same data in the same order (faces, rows, tiles), so a thread reads what it wrote itself,
 * from its own core's cache. With one counter for all, neighbouring indices went to both
 * threads in turn, and the 256 chain's tasks took 13% longer on two threads than on one,
 * against 5% with the shares (bench/threads_split.sh). */
static void run_job(ibl__pool *pool, pool_job *job, int seat)
{
    int ran = 0;
    for (int k = 0; k < job->shares; k++) {
        index_share *s = &job->share[(seat + k) % job->shares];
        for (;;) {
            int i = atomic_fetch_add_explicit(&s->next, 1, memory_order_relaxed);
            if (i >= s->end) break;
            job->task(job->arg, i);
            ran++;
        }
    }
    if (ran && atomic_fetch_add(&job->finished, ran) + ran == job->count) announce(pool);
}

/* Until every index of `job` has run: the thread runs other jobs' indices, or waits. */
static void wait_for_job(ibl__pool *pool, pool_job *job, int seat)
{
    while (atomic_load(&job->finished) < job->count) {
        unsigned seen = atomic_load(&pool->generation);
        pool_job *other = take_open_job(pool);
        if (other) {
            run_job(pool, other, seat);
            release(pool, other);
            continue;
        }
        if (atomic_load(&job->finished) < job->count) wait_for_news(pool, seen);
    }
}

/* Takes a finished job out of its slot; returns once no other thread reads it. */
static void retire(ibl__pool *pool, pool_job *job)
{
    job_slot *slot = &pool->slots[job->slot];
    atomic_store(&slot->job, SLOT_DRAINING);
    /* a thread that took it just before has found no index left and is on its way out */
    for (int i = 1; atomic_load(&slot->users) > 0; i++) {
        if (i % YIELD_AFTER == 0) sched_yield();
        else ibl__cpu_relax();
    }
    atomic_store(&slot->job, 0);
}

/* The calling thread's seat: a worker's own (its share comes first in every job), 0 for any
 * other thread. */
static int seat_of_caller(const ibl__pool *pool)
{
    pthread_t me = pthread_self();
    for (int i = 0; i < pool->worker_count; i++)
        if (pthread_equal(pool->threads[i], me)) return pool->seats[i].seat;
    return 0;
}

static void *worker_main(void *arg)
{
    const worker_seat *seat = arg;
    ibl__pool *pool = seat->pool;
    /* ibl__pool_create holds the lock until every thread's id is stored (seat_of_caller) */
    pthread_mutex_lock(&pool->lock);
    pthread_mutex_unlock(&pool->lock);
    for (;;) {
        unsigned seen = atomic_load(&pool->generation);
        pool_job *job = take_open_job(pool);
        if (job) {
            run_job(pool, job, seat->seat);
            release(pool, job);
            continue;
        }
        if (atomic_load(&pool->quit)) return NULL;
        wait_for_news(pool, seen);
    }
}

ibl__pool *ibl__pool_create(int workers)
{
    if (workers > IBL__POOL_MAX_THREADS - 1) workers = IBL__POOL_MAX_THREADS - 1;
    /* the index shares sit on cache lines of their own: the pool is aligned as they are */
    size_t align = _Alignof(ibl__pool);
    size_t bytes = (sizeof(ibl__pool) + align - 1) / align * align;
    ibl__pool *pool = aligned_alloc(align, bytes);
    if (!pool) return NULL;
    memset(pool, 0, bytes);
    atomic_flag_clear(&pool->begun_busy);
    pthread_mutex_init(&pool->lock, NULL);
    pthread_cond_init(&pool->wake, NULL);
    pthread_mutex_lock(&pool->lock);
    for (int i = 0; i < workers; i++) {
        pool->seats[i].pool = pool;
        pool->seats[i].seat = 1 + i;
        if (pthread_create(&pool->threads[i], NULL, worker_main, &pool->seats[i]) != 0) break;
        pool->worker_count++;
    }
    pthread_mutex_unlock(&pool->lock);
    return pool;
}

void ibl__pool_destroy(ibl__pool *pool)
{
    if (!pool) return;
    atomic_store(&pool->quit, 1);
    pthread_mutex_lock(&pool->lock);
    atomic_fetch_add(&pool->generation, 1u);
    pthread_cond_broadcast(&pool->wake);
    pthread_mutex_unlock(&pool->lock);
    for (int i = 0; i < pool->worker_count; i++) pthread_join(pool->threads[i], NULL);
    pthread_mutex_destroy(&pool->lock);
    pthread_cond_destroy(&pool->wake);
    free(pool);
}

int ibl__pool_threads(const ibl__pool *pool)
{
    return pool->worker_count + 1;
}

void ibl__pool_run(ibl__pool *pool, int count, ibl_task_fn task, void *arg)
{
    pool_job job;
    job_init(&job, pool, count, task, arg, 0);
    int seat = seat_of_caller(pool);
    if (!post(pool, &job)) {
        for (int i = 0; i < count; i++) task(arg, i);
        return;
    }
    run_job(pool, &job, seat);
    wait_for_job(pool, &job, seat);
    retire(pool, &job);
}

int ibl__pool_begin(ibl__pool *pool, int count, ibl_task_fn task, void *arg)
{
    if (atomic_flag_test_and_set(&pool->begun_busy)) return 0;
    job_init(&pool->begun, pool, count, task, arg, 1);
    if (post(pool, &pool->begun)) return 1;
    atomic_flag_clear(&pool->begun_busy);
    return 0;
}

int ibl__pool_help(ibl__pool *pool)
{
    pool_job *job = &pool->begun;
    int i = atomic_fetch_add_explicit(&job->share[0].next, 1, memory_order_relaxed);
    if (i >= job->share[0].end) return 0;
    job->task(job->arg, i);
    if (atomic_fetch_add(&job->finished, 1) + 1 == job->count) announce(pool);
    return 1;
}

void ibl__pool_end(ibl__pool *pool)
{
    int seat = seat_of_caller(pool);
    run_job(pool, &pool->begun, seat);
    wait_for_job(pool, &pool->begun, seat);
    retire(pool, &pool->begun);
    atomic_flag_clear(&pool->begun_busy);
}

void ibl__pool_warm(ibl__pool *pool)
{
    announce(pool); /* a generation without a job: the workers wake, find none, and spin */
}
