/* Internal: how library code reports failures and progress through the context. */
#ifndef IBL_CORE_CONTEXT_INTERNAL_H
#define IBL_CORE_CONTEXT_INTERNAL_H

#include "ibl/core.h"

/* Records a printf-style failure message in the context and returns status. */
ibl_status ibl__fail(ibl_context *ctx, ibl_status status, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
/* A copy of s allocated through the context (NULL for NULL s, or on failure with the
 * context's message set). */
char *ibl__strdup(ibl_context *ctx, const char *s);
/* Reports progress; returns IBL_ERR_CANCELLED (with a message) if the host asked to stop. */
ibl_status ibl__progress(ibl_context *ctx, const char *stage, double fraction);

/* Wakes the context's pool threads without a job: they wait awake (spinning, ~0.5 ms) for
 * the next parallel-for instead of asleep. For a caller about to start a loop after a short
 * serial stretch that follows a long pause (a decoder parsing a header before its first
 * loop): a sleeping worker joined the 256 chain's first loop ~1 ms late. A no-op without a
 * pool or while a loop runs. */
void ibl__parallel_warm(ibl_context *ctx);

/* A loop whose indices the pool's workers start on at once while the calling thread does
 * something else (writes a file's finished front while the rest is encoded): begin posts it
 * and returns 1, or returns 0 and runs nothing when it cannot be posted (no pool, the host's
 * parallel_for hook, another begun loop running: the caller then runs it with ibl_parallel_for).
 * While it runs the caller may take indices itself with ibl__parallel_help (1 if it ran one,
 * 0 when none is left to take) and must end it with ibl__parallel_end, which runs what is
 * left and returns once every index is done. Parallel-fors started meanwhile run beside it
 * (one begun loop at a time: begin returns 0 while another runs). Which thread runs an index
 * never changes what it computes. */
int ibl__parallel_begin(ibl_context *ctx, int count, ibl_task_fn task, void *task_arg);
int ibl__parallel_help(ibl_context *ctx);
void ibl__parallel_end(ibl_context *ctx);

/* 1 when loops run on the library's own pool (src/core/pool.c), 0 for a host's parallel_for
 * or none. The own pool's thread that waits for its loop's last indices takes the oldest open
 * loop with indices left, so a task that holds something while a loop of its own finishes is
 * not entered again on that thread while an older loop has indices: a host's scheduler may
 * start any task there (work stealing), and a task that then waits for what the first one
 * holds never returns. */
int ibl__parallel_on_own_pool(const ibl_context *ctx);

/* One pause of a spin-wait (the CPU's pause or yield instruction). */
void ibl__cpu_relax(void);

/* The memory budget (ibl_context_desc.max_bytes) for memory the library does not allocate
 * itself: third-party decoders (stb_image, OpenEXR) allocate with malloc, so their estimated
 * need is reserved while they run and released afterwards. Reserve fails with
 * IBL_ERR_TOO_LARGE and the budget's message ("needs N more with M in use, over the memory
 * budget of B") when the bytes do not fit. Check fails the same way without reserving: the
 * early refusal of an input whose decoding would not fit. A NULL context has no budget. */
ibl_status ibl__budget_reserve(ibl_context *ctx, uint64_t bytes);
void ibl__budget_release(ibl_context *ctx, uint64_t bytes);
ibl_status ibl__budget_check(ibl_context *ctx, uint64_t bytes);

/* State a module keeps in the context from one call to the next, because building it costs
 * more than the work of a typical call (astcenc's decoder tables: 4-14 ms each). One slot per
 * kind of state; the module creates its object on first use and the context frees it when
 * destroyed. */
typedef enum ibl__cache_slot { IBL__CACHE_ASTC_DECODERS, IBL__CACHE_SLOTS } ibl__cache_slot;
typedef void *(*ibl__cache_create_fn)(ibl_context *ctx);
typedef void (*ibl__cache_free_fn)(ibl_context *ctx, void *cache);
/* The slot's object, made by create(ctx) if there is none yet. Any thread may ask: when two
 * race to create it, one object is kept and the other given to free_fn. NULL when create
 * returned NULL (its failure recorded in the context) or when ctx is NULL (no context, no
 * cache: the caller does without). free_fn(ctx, object) runs in ibl_context_destroy, after
 * the thread pool has stopped and while the context's allocator and budget still work. */
void *ibl__context_cache(ibl_context *ctx, ibl__cache_slot slot, ibl__cache_create_fn create,
                         ibl__cache_free_fn free_fn);

#endif
