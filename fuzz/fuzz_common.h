/* What every fuzz target shares: contexts whose allocator counts the bytes it has handed out
 * (so a harness can tell that an input left nothing behind) under a memory budget large
 * enough that a small file declaring a huge image gets its allocation attempted and refused
 * by the library's own checks, not by the fuzzer's limits (run.sh sets libFuzzer's
 * -malloc_limit_mb to the budget and -rss_limit_mb well above it).
 *
 * FUZZ_BUDGET is given as ibl_context_desc.max_bytes, whichever way the library applies it
 * (to each allocation or to the total of live ones): the harnesses never rely on a
 * particular allocation within it succeeding. */
#ifndef IBL_FUZZ_COMMON_H
#define IBL_FUZZ_COMMON_H

#include <stdatomic.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "ibl/ibl.h"

#define FUZZ_BUDGET ((uint64_t)1 << 30)
/* Threads of the pooled context: more than the machine's two cores, so that bands are
 * interleaved and queued in different orders from run to run. */
enum { FUZZ_POOL_THREADS = 4 };

/* Bytes handed out by the fuzz allocator and not yet freed (every context's). */
static atomic_size_t fuzz_live_bytes;

typedef struct fuzz_block {
    size_t bytes;
    size_t pad; /* keeps the payload 16-byte aligned, as the allocator contract asks */
} fuzz_block;

static inline void *fuzz_alloc(size_t bytes, void *user)
{
    (void)user;
    if (bytes > SIZE_MAX - sizeof(fuzz_block)) return NULL;
    fuzz_block *b = aligned_alloc(16, (sizeof *b + bytes + 15) & ~(size_t)15);
    if (!b) return NULL;
    b->bytes = bytes;
    atomic_fetch_add(&fuzz_live_bytes, bytes);
    return b + 1;
}

static inline void fuzz_free(void *ptr, void *user)
{
    (void)user;
    if (!ptr) return;
    fuzz_block *b = (fuzz_block *)ptr - 1;
    atomic_fetch_sub(&fuzz_live_bytes, b->bytes);
    free(b);
}

static inline ibl_context *fuzz_make_context(int threads)
{
    ibl_context_desc d;
    memset(&d, 0, sizeof d);
    d.allocator.alloc = fuzz_alloc;
    d.allocator.free = fuzz_free;
    d.threads = threads;
    d.max_bytes = FUZZ_BUDGET;
    ibl_context *ctx = NULL;
    if (ibl_context_create(&d, &ctx) != IBL_OK) return NULL;
    /* The context keeps ASTC decoders from one call to the next (ibl_astc_decode), in a list
     * it allocates on its first ASTC decode: made here, before the first input, so that the
     * bytes live through the allocator change only by what an input leaves behind. (The
     * decoders themselves are astcenc's, allocated outside the context's allocator.) */
    static const uint8_t block[16];
    float texels[4 * 4 * 4];
    (void)ibl_astc_decode(ctx, NULL, block, 4, 4, texels);
    return ctx;
}

/* One thread: work runs in order on the caller's thread. */
static inline ibl_context *fuzz_context(void)
{
    static ibl_context *ctx;
    if (!ctx) ctx = fuzz_make_context(1);
    return ctx;
}

/* The built-in thread pool with FUZZ_POOL_THREADS threads (the parallel decoding paths). */
static inline ibl_context *fuzz_pool_context(void)
{
    static ibl_context *ctx;
    if (!ctx) ctx = fuzz_make_context(FUZZ_POOL_THREADS);
    return ctx;
}

#endif
