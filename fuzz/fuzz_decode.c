/* libFuzzer target for one reader: IBL_FUZZ_DECODER names an ibl__*_decode function, or
 * ibl_decode_any for the dispatcher (sniffing + pixel policy). Built by fuzz/CMakeLists.txt
 * once per reader; the same file replays the corpus in `make test` (replay.c).
 *
 * Each input is decoded by two contexts, one with the built-in thread pool and one without
 * threads; which goes first depends on the input's length, so that both meet every failure
 * path. When the first succeeds, the second must succeed too with the same texels, bit for
 * bit (the library's results do not depend on the thread count). Traps otherwise, and when:
 * - a failure's message does not start with the input's name (the one-line-error contract);
 * - an input leaves bytes allocated through the context behind. */
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "fuzz_common.h"
#include "io/io_internal.h"

__attribute__((unused)) static ibl_status ibl_decode_any(ibl_context *ctx, const uint8_t *bytes, size_t size,
                                 const char *name, ibl_texture *out, ibl_file_info *info)
{
    ibl_read_desc rd = {.clamp_infinite = 1};
    return ibl_decode_texture(ctx, bytes, size, name, &rd, out, info);
}

typedef struct decoded {
    ibl_status status;
    int kind, width, height, depth, levels, format;
    uint64_t hash; /* texel_hash of the texels */
} decoded;

/* FNV-1a over the texels' bits. Reading them all also shows short buffers under ASan. Not
 * instrumented for coverage: the fuzzer would trace every comparison of the loop, which made
 * a 2817x2311 image take seconds, and its edges say nothing about the input. */
#if defined(__clang__)
__attribute__((no_sanitize("coverage")))
#endif
static uint64_t texel_hash(const float *texels, size_t n)
{
    uint64_t h = 1469598103934665603u;
    for (size_t i = 0; i < n; i++) {
        uint32_t bits;
        memcpy(&bits, &texels[i], sizeof bits);
        h = (h ^ bits) * 1099511628211u;
    }
    return h;
}

static decoded decode(ibl_context *ctx, const uint8_t *data, size_t size)
{
    decoded r;
    memset(&r, 0, sizeof r);
    ibl_texture tex;
    ibl_file_info info;
    memset(&tex, 0, sizeof tex);
    memset(&info, 0, sizeof info);
    r.status = IBL_FUZZ_DECODER(ctx, data, size, "<fuzz>", &tex, &info);
    if (r.status != IBL_OK) {
        /* every failure, memory bombs included, has a message naming the input */
        if (strncmp(ibl_context_message(ctx), "<fuzz>", 6) != 0) __builtin_trap();
        return r;
    }
    r.kind = (int)tex.kind;
    r.width = tex.width;
    r.height = tex.height;
    r.depth = tex.depth;
    r.levels = tex.levels;
    r.format = (int)tex.format;
    r.hash = texel_hash(tex.data, ibl_texture_floats(tex.kind, tex.width, tex.height, tex.depth, tex.levels));
    ibl_texture_free(ctx, &tex);
    return r;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    ibl_context *serial = fuzz_context(), *pool = fuzz_pool_context();
    if (!serial || !pool) return 0;
    size_t live = atomic_load(&fuzz_live_bytes);
    ibl_context *first = size & 1 ? pool : serial, *second = size & 1 ? serial : pool;
    decoded a = decode(first, data, size);
    if (atomic_load(&fuzz_live_bytes) != live) __builtin_trap(); /* a leak through the context */
    if (a.status == IBL_OK) {
        decoded b = decode(second, data, size);
        if (atomic_load(&fuzz_live_bytes) != live) __builtin_trap();
        /* the same file gives the same texels at any thread count (a pool may need more
         * memory at once: running out of the budget there is no disagreement) */
        if (b.status == IBL_ERR_TOO_LARGE || b.status == IBL_ERR_OUT_OF_MEMORY) return 0;
        if (b.status != a.status || b.kind != a.kind || b.width != a.width || b.height != a.height ||
            b.depth != a.depth || b.levels != a.levels || b.format != a.format || b.hash != a.hash)
            __builtin_trap();
    }
    return 0;
}
