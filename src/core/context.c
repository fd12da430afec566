/* The context: allocator, memory budget, failure message, progress and the parallel-for hook
 * over the built-in thread pool (pool.c) or the host's. */
#define _POSIX_C_SOURCE 200809L
#include "ibl/core.h"
#include "core/cpu.h"
#include "core/context_internal.h"
#include "core/pool.h"

#include <fcntl.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <unistd.h>

enum { MESSAGE_BYTES = 512 };

/* Blocks of ibl_alloc: see "the memory budget" below. A large block is kept without a header,
 * its start and its size as asked for in the context's table of LARGE_BLOCK_SLOTS. */
enum { BLOCK_HEADER = 64, HEADER_SLACK = 2 * BLOCK_HEADER, PAGE_BYTES = 4096, LARGE_BLOCK_SLOTS = 256 };
#define LARGE_BLOCK_MIN ((size_t)64 << 10)
typedef struct large_block {
    void *start;
    size_t bytes;
} large_block;

struct ibl_context {
    ibl_context_desc desc; /* desc.max_bytes: the budget in effect (never 0) */
    ibl__pool *pool; /* NULL: one thread, or the host's parallel-for */
    int thread_count;
    unsigned cpu_features; /* what kernels may use (core/cpu.h) */
    /* The budget's accounts: bytes of live blocks from ibl_alloc plus what decoders hold by
     * ibl__budget_reserve, and the highest that sum has been. Worker threads allocate too. */
    _Atomic uint64_t live_bytes;
    _Atomic uint64_t peak_bytes;
    atomic_flag message_lock; /* a failure on a worker thread may race one on another */
    /* read without the lock: a pool task checks whether another one has failed */
    _Atomic int last_status;
    char message[MESSAGE_BYTES];
    /* The large blocks this context counts, whose size is kept here rather than in a header
     * (see "the memory budget" below). Pool tasks allocate too: one writer at a time. */
    atomic_flag large_lock;
    int large_count;
    large_block large[LARGE_BLOCK_SLOTS];
    /* state kept across calls (ibl__context_cache), published by compare-and-swap */
    void *_Atomic caches[IBL__CACHE_SLOTS];
    ibl__cache_free_fn cache_free[IBL__CACHE_SLOTS]; /* written by the thread that published */
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
    /* large blocks on a page boundary, so that ibl_alloc keeps their header out of them */
    if (posix_memalign(&p, bytes >= LARGE_BLOCK_MIN ? PAGE_BYTES : 64, bytes) != 0) return NULL;
    return p;
}

static void default_free(void *ptr, void *user)
{
    (void)user;
    free(ptr);
}

/* ---- the memory budget --------------------------------------------------------------- */

/* What ibl_free needs to know of a block: its size, to give the bytes back to the budget, and
 * the context that counted them: a block freed through another context (or none) is not
 * subtracted from that one's count, which would wrap.
 *
 * Small blocks keep it in a 64-byte header just before the caller's bytes (64 keep them at
 * the allocator's alignment: cache lines and AVX-512 loads with the default allocator).
 *
 * Large blocks (LARGE_BLOCK_MIN bytes and more) keep it beside them, in the context's table:
 * a header written at allocation would be the first touch of the block's first page, so that
 * page would be faulted and zeroed by the allocating thread rather than by the worker that
 * fills it. With the CLI's arena that page is a 2 MiB huge page (cli/arena.c): on two threads
 * those serial faults were about 7 ms of the 256 GGX chain's 120. Such a block is the
 * allocator's pointer itself, and only when that is page-aligned (the arena's and the default
 * allocator's large blocks are); a block with a header is never page-aligned (its start moves
 * 64 bytes further when it would be). So ibl_free tells the two kinds apart by the address
 * alone, through any context, without reading outside the block. */

typedef struct block_header {
    size_t bytes;    /* as asked for by the caller */
    uintptr_t owner; /* the context whose budget counts them (0: none); only compared */
    void *start;     /* what the allocator returned */
} block_header;


static int page_aligned(const void *p)
{
    return (uintptr_t)p % PAGE_BYTES == 0;
}

/* Records a large block in the table; 0 when the table is full (the block then takes a
 * header). A few dozen large blocks live at once in a prefilter, so the search is in order. */
static int large_remember(ibl_context *ctx, void *start, size_t bytes)
{
    while (atomic_flag_test_and_set_explicit(&ctx->large_lock, memory_order_acquire)) ibl__cpu_relax();
    int kept = ctx->large_count < LARGE_BLOCK_SLOTS;
    if (kept) ctx->large[ctx->large_count++] = (large_block){start, bytes};
    atomic_flag_clear_explicit(&ctx->large_lock, memory_order_release);
    return kept;
}

/* Takes a block out of the table: 1 and its size if this context counted it. */
static int large_forget(ibl_context *ctx, const void *start, size_t *bytes)
{
    while (atomic_flag_test_and_set_explicit(&ctx->large_lock, memory_order_acquire)) ibl__cpu_relax();
    int found = 0;
    for (int i = ctx->large_count - 1; i >= 0 && !found; i--) {
        if (ctx->large[i].start != start) continue;
        *bytes = ctx->large[i].bytes;
        ctx->large[i] = ctx->large[--ctx->large_count];
        found = 1;
    }
    atomic_flag_clear_explicit(&ctx->large_lock, memory_order_release);
    return found;
}

/* A decimal number from a one-line file such as a cgroup limit; 0 if absent or "max". */
static uint64_t read_limit_file(const char *path)
{
    int fd = open(path, O_RDONLY | O_CLOEXEC);
    if (fd < 0) return 0;
    char text[32];
    ssize_t n = read(fd, text, sizeof text - 1);
    close(fd);
    if (n <= 0) return 0;
    text[n] = 0;
    uint64_t v = 0;
    for (const char *c = text; *c >= '0' && *c <= '9'; c++) {
        if (v > (UINT64_MAX - 9) / 10) return 0;
        v = v * 10 + (uint64_t)(*c - '0');
    }
    return v;
}

static uint64_t lower_limit(uint64_t limit, uint64_t other)
{
    return other != 0 && (limit == 0 || other < limit) ? other : limit;
}

/* Half of the memory this process may use: the smallest of the machine's physical memory,
 * the process's address-space and data limits (ulimit -v, -d) and its container's memory
 * limit (cgroup v2 memory.max or v1 memory.limit_in_bytes, as seen from inside it).
 *
 * Half, because the budget counts only what the library holds; everything else shares the
 * other half: the decoders' internal buffers (reserved by estimate while they run, not to
 * the byte), thread stacks, the page cache of the files being read, the host program and the
 * rest of the machine. A run that would exceed it then fails with a message before the
 * kernel's out-of-memory killer ends the process. Physical memory rather than what is free
 * now (MemAvailable): the same machine gives the same budget on every run, so whether an
 * input is accepted does not depend on what else happened to be running. */
uint64_t ibl_default_max_bytes(void)
{
    uint64_t limit = 0;
    long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGESIZE);
    if (pages > 0 && page > 0) limit = (uint64_t)pages * (uint64_t)page;
    struct rlimit rl;
    if (getrlimit(RLIMIT_AS, &rl) == 0 && rl.rlim_cur != RLIM_INFINITY)
        limit = lower_limit(limit, (uint64_t)rl.rlim_cur);
#ifdef RLIMIT_DATA
    if (getrlimit(RLIMIT_DATA, &rl) == 0 && rl.rlim_cur != RLIM_INFINITY)
        limit = lower_limit(limit, (uint64_t)rl.rlim_cur);
#endif
#ifdef __linux__
    limit = lower_limit(limit, read_limit_file("/sys/fs/cgroup/memory.max"));
    limit = lower_limit(limit, read_limit_file("/sys/fs/cgroup/memory/memory.limit_in_bytes"));
#endif
    if (limit == 0) limit = (uint64_t)4 << 30; /* nothing could be measured */
    return limit / 2;
}

/* "512 bytes", "3.5 KiB", "2048.0 MiB": the units a reader of the message can act on. */
static void format_bytes(char *out, size_t cap, uint64_t n)
{
    if (n < 1024) snprintf(out, cap, "%llu bytes", (unsigned long long)n);
    else if (n < ((uint64_t)1 << 20)) snprintf(out, cap, "%.1f KiB", (double)n / 1024.0);
    else snprintf(out, cap, "%.1f MiB", (double)n / 1048576.0);
}

static void raise_peak(ibl_context *ctx, uint64_t live)
{
    uint64_t peak = atomic_load_explicit(&ctx->peak_bytes, memory_order_relaxed);
    while (live > peak &&
           !atomic_compare_exchange_weak_explicit(&ctx->peak_bytes, &peak, live, memory_order_relaxed,
                                                  memory_order_relaxed)) {
    }
}

/* Adds bytes to the live total if the total stays within the budget. */
static int budget_take(ibl_context *ctx, uint64_t bytes)
{
    uint64_t live = atomic_load_explicit(&ctx->live_bytes, memory_order_relaxed);
    do {
        if (bytes > ctx->desc.max_bytes || live > ctx->desc.max_bytes - bytes) return 0;
    } while (!atomic_compare_exchange_weak_explicit(&ctx->live_bytes, &live, live + bytes,
                                                    memory_order_relaxed, memory_order_relaxed));
    raise_peak(ctx, live + bytes);
    return 1;
}

static ibl_status budget_refuse(ibl_context *ctx, uint64_t bytes)
{
    char need[32], live[32], budget[32];
    format_bytes(need, sizeof need, bytes);
    format_bytes(live, sizeof live, atomic_load_explicit(&ctx->live_bytes, memory_order_relaxed));
    format_bytes(budget, sizeof budget, ctx->desc.max_bytes);
    return ibl__fail(ctx, IBL_ERR_TOO_LARGE, "needs %s more with %s in use, over the memory budget of %s",
                     need, live, budget);
}

ibl_status ibl__budget_reserve(ibl_context *ctx, uint64_t bytes)
{
    if (!ctx) return IBL_OK;
    return budget_take(ctx, bytes) ? IBL_OK : budget_refuse(ctx, bytes);
}

void ibl__budget_release(ibl_context *ctx, uint64_t bytes)
{
    if (ctx) atomic_fetch_sub_explicit(&ctx->live_bytes, bytes, memory_order_relaxed);
}

ibl_status ibl__budget_check(ibl_context *ctx, uint64_t bytes)
{
    if (!ctx) return IBL_OK;
    uint64_t live = atomic_load_explicit(&ctx->live_bytes, memory_order_relaxed);
    if (bytes > ctx->desc.max_bytes || live > ctx->desc.max_bytes - bytes) return budget_refuse(ctx, bytes);
    return IBL_OK;
}

uint64_t ibl_context_max_bytes(const ibl_context *ctx)
{
    return ctx ? ctx->desc.max_bytes : ibl_default_max_bytes();
}

uint64_t ibl_context_current_bytes(const ibl_context *ctx)
{
    return ctx ? atomic_load_explicit(&((ibl_context *)ctx)->live_bytes, memory_order_relaxed) : 0;
}

uint64_t ibl_context_peak_bytes(const ibl_context *ctx)
{
    return ctx ? atomic_load_explicit(&((ibl_context *)ctx)->peak_bytes, memory_order_relaxed) : 0;
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
    if (d.max_bytes == 0) d.max_bytes = ibl_default_max_bytes();
    ibl_context *ctx = d.allocator.alloc(sizeof *ctx, d.allocator.user);
    if (!ctx) return IBL_ERR_OUT_OF_MEMORY;
    memset(ctx, 0, sizeof *ctx);
    ctx->desc = d;
    atomic_init(&ctx->live_bytes, 0);
    atomic_init(&ctx->peak_bytes, 0);
    atomic_init(&ctx->last_status, (int)IBL_OK);
    atomic_flag_clear(&ctx->message_lock);
    atomic_flag_clear(&ctx->large_lock);
    for (int i = 0; i < IBL__CACHE_SLOTS; i++) atomic_init(&ctx->caches[i], NULL);
    ctx->thread_count = 1;
    ctx->cpu_features = d.kernels == IBL_KERNELS_PORTABLE ? 0u : ibl__cpu_detect();
    if (d.parallel_for) {
        /* the host's word for its concurrency: the work is split for it, and a loop that runs
         * on more threads at once only waits (the EXR bands' buffer slots) */
        if (d.threads > 1) ctx->thread_count = d.threads < IBL__POOL_MAX_THREADS ? d.threads : IBL__POOL_MAX_THREADS;
    } else {
        int threads = d.threads;
        if (threads <= 0) {
            long online = sysconf(_SC_NPROCESSORS_ONLN);
            threads = online > 0 ? (int)online : 1;
        }
        if (threads > IBL__POOL_MAX_THREADS) threads = IBL__POOL_MAX_THREADS;
        if (threads > 1) {
            ctx->pool = ibl__pool_create(threads - 1);
            if (!ctx->pool) {
                d.allocator.free(ctx, d.allocator.user);
                return IBL_ERR_OUT_OF_MEMORY;
            }
            ctx->thread_count = ibl__pool_threads(ctx->pool);
        }
    }
    *out = ctx;
    return IBL_OK;
}

void ibl_context_destroy(ibl_context *ctx)
{
    if (!ctx) return;
    ibl__pool_destroy(ctx->pool);
    for (int i = 0; i < IBL__CACHE_SLOTS; i++) {
        void *cache = atomic_load(&ctx->caches[i]);
        if (cache) ctx->cache_free[i](ctx, cache);
    }
    ibl_allocator a = ctx->desc.allocator;
    a.free(ctx, a.user);
}

void *ibl__context_cache(ibl_context *ctx, ibl__cache_slot slot, ibl__cache_create_fn create,
                         ibl__cache_free_fn free_fn)
{
    if (!ctx) return NULL;
    void *cache = atomic_load(&ctx->caches[slot]);
    if (cache) return cache;
    void *made = create(ctx);
    if (!made) return NULL;
    void *expected = NULL;
    if (atomic_compare_exchange_strong(&ctx->caches[slot], &expected, made)) {
        /* only ibl_context_destroy reads it, after every call on the context has returned */
        ctx->cache_free[slot] = free_fn;
        return made;
    }
    free_fn(ctx, made); /* another thread published first: use its object */
    return expected;
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
    return ctx ? (ibl_status)atomic_load_explicit(&((ibl_context *)ctx)->last_status, memory_order_relaxed)
               : IBL_OK;
}

int ibl_context_threads(const ibl_context *ctx)
{
    return ctx ? ctx->thread_count : 1;
}

ibl_status ibl__fail(ibl_context *ctx, ibl_status status, const char *fmt, ...)
{
    if (!ctx) return status;
    /* one writer at a time: allocations fail on worker threads as well */
    while (atomic_flag_test_and_set_explicit(&ctx->message_lock, memory_order_acquire)) {
    }
    atomic_store_explicit(&ctx->last_status, (int)status, memory_order_relaxed);
    if (fmt) {
        /* formatted aside first: arguments may point into the message being replaced */
        char text[MESSAGE_BYTES];
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(text, sizeof text, fmt, ap);
        va_end(ap);
        memcpy(ctx->message, text, sizeof text);
    }
    atomic_flag_clear_explicit(&ctx->message_lock, memory_order_release);
    return status;
}

/* The allocator's block of `total` bytes for ctx (malloc's when there is none). */
static void *allocate_raw(ibl_context *ctx, size_t total)
{
    return ctx ? ctx->desc.allocator.alloc(total, ctx->desc.allocator.user) : default_alloc(total, NULL);
}

static void free_raw(ibl_context *ctx, void *start)
{
    if (ctx) ctx->desc.allocator.free(start, ctx->desc.allocator.user);
    else free(start);
}

void *ibl_alloc(ibl_context *ctx, size_t bytes)
{
    if (bytes > SIZE_MAX - HEADER_SLACK) {
        ibl__fail(ctx, IBL_ERR_TOO_LARGE, "needs %zu bytes, more than the address space", bytes);
        return NULL;
    }
    if (ctx && !budget_take(ctx, bytes)) {
        budget_refuse(ctx, bytes);
        return NULL;
    }
    /* the slack leaves room for a header in either place, whichever kind the block becomes */
    char *start = allocate_raw(ctx, bytes + HEADER_SLACK);
    if (!start) {
        if (ctx) {
            ibl__budget_release(ctx, bytes);
            char need[32];
            format_bytes(need, sizeof need, bytes);
            ibl__fail(ctx, IBL_ERR_OUT_OF_MEMORY, "out of memory allocating %s", need);
        }
        return NULL;
    }
    if (ctx && bytes >= LARGE_BLOCK_MIN && page_aligned(start) && large_remember(ctx, start, bytes))
        return start;
    char *block = start + BLOCK_HEADER;
    if (page_aligned(block)) block += BLOCK_HEADER;
    block_header *h = (block_header *)(void *)(block - BLOCK_HEADER);
    h->bytes = bytes;
    h->owner = (uintptr_t)ctx;
    h->start = start;
    return block;
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
    if (page_aligned(ptr)) { /* a large block without a header */
        size_t bytes;
        if (ctx && large_forget(ctx, ptr, &bytes)) ibl__budget_release(ctx, bytes);
        free_raw(ctx, ptr);
        return;
    }
    block_header *h = (block_header *)(void *)((char *)ptr - BLOCK_HEADER);
    if (ctx && h->owner == (uintptr_t)ctx) ibl__budget_release(ctx, h->bytes);
    free_raw(ctx, h->start);
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
    ibl__pool_run(ctx->pool, count, task, task_arg);
}

int ibl__parallel_begin(ibl_context *ctx, int count, ibl_task_fn task, void *task_arg)
{
    if (count <= 0 || !ctx || !ctx->pool || ctx->desc.parallel_for) return 0;
    return ibl__pool_begin(ctx->pool, count, task, task_arg);
}

int ibl__parallel_help(ibl_context *ctx)
{
    return ibl__pool_help(ctx->pool);
}

void ibl__parallel_end(ibl_context *ctx)
{
    ibl__pool_end(ctx->pool);
}

int ibl__parallel_on_own_pool(const ibl_context *ctx)
{
    return ctx && ctx->pool && !ctx->desc.parallel_for;
}

void ibl__parallel_warm(ibl_context *ctx)
{
    if (ctx && ctx->pool && !ctx->desc.parallel_for) ibl__pool_warm(ctx->pool);
}

ibl_status ibl__progress(ibl_context *ctx, const char *stage, double fraction)
{
    if (!ctx || !ctx->desc.progress) return IBL_OK;
    if (ctx->desc.progress(ctx->desc.progress_user, stage, fraction))
        return ibl__fail(ctx, IBL_ERR_CANCELLED, "%s: cancelled", stage ? stage : "work");
    return IBL_OK;
}
