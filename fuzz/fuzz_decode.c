/* libFuzzer target for one reader: IBL_FUZZ_DECODER names an ibl__*_decode function, or
 * ibl_decode_any for the dispatcher (sniffing + pixel policy). Built by fuzz/CMakeLists.txt
 * once per reader; the same file replays the corpus in `make test` (replay.c).
 *
 * Each input is decoded by two contexts, one with the built-in thread pool and one without
 * threads; which goes first depends on the input's length, so that both meet every failure
 * path. When the first succeeds, the second must succeed too with the same texels, bit for
 * bit (the library's results do not depend on the thread count). Traps otherwise, and when:
 * - a failure's message does not start with the input's name (the one-line-error contract);
 * - an input leaves bytes allocated through the context behind.
 * Every target also runs the header-only reader (ibl_decode_info) on the input, under the same
 * two traps; for ibl_decode_any, whose decode it must agree with, a decode that succeeds must
 * give the same info field by field. */
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "fuzz_common.h"
#include "core/context_internal.h"
#include "io/io_internal.h"

__attribute__((unused)) static ibl_status ibl_decode_any(ibl_context *ctx, const uint8_t *bytes, size_t size,
                                 const char *name, ibl_texture *out, ibl_file_info *info)
{
    ibl_read_desc rd = {.clamp_infinite = 1};
    ibl_status s = ibl_decode_texture(ctx, bytes, size, name, &rd, out, info);
    if (s != IBL_OK) return s;
    /* what the header alone says is what the decode found (the pixel report aside) */
    ibl_file_info head;
    if (ibl_decode_info(ctx, bytes, size, name, &head) != IBL_OK || head.type != info->type ||
        head.format != info->format || head.kind != info->kind || head.width != info->width ||
        head.height != info->height || head.depth != info->depth || head.levels != info->levels ||
        head.has_alpha != info->has_alpha)
        __builtin_trap();
    return s;
}

/* The block readers on their own (targets bc6h and astc). An input is a 2-byte header and
 * whole 16-byte blocks: byte 0 bits 0..3 = width in blocks - 1, bit 4 = BC6H signed, bits
 * 5..7 = ASTC footprint (4x4, 5x4, 5x5, 6x5, 6x6, 8x5, 8x6, 8x8); byte 1 bits 0..2 and 3..5 =
 * texels cut from the last block column and row (a padded image). The block rows are as
 * many as the blocks fill. fuzz/corpus-gen/blocks.c writes the starting corpora. */
static ibl_status block_image(ibl_context *ctx, const uint8_t *bytes, size_t size, const char *name,
                              int bw, int bh, ibl_texture *out)
{
    int columns = (bytes[0] & 15) + 1;
    size_t blocks = (size - 2) / 16;
    if (blocks < (size_t)columns || blocks > (1u << 16))
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: %zu blocks for rows of %d", name, blocks, columns);
    int rows = (int)(blocks / (size_t)columns);
    int cut_x = bytes[1] & 7, cut_y = (bytes[1] >> 3) & 7;
    int width = columns * bw - (cut_x < bw ? cut_x : bw - 1), height = rows * bh - (cut_y < bh ? cut_y : bh - 1);
    ibl_status st = ibl_texture_alloc(ctx, IBL_TEXTURE_2D, width, height, 1, 1, out);
    return st == IBL_OK ? IBL_OK : ibl__fail_named(ctx, st, name);
}

__attribute__((unused)) static ibl_status fuzz_bc6h_blocks(ibl_context *ctx, const uint8_t *bytes, size_t size,
                                                           const char *name, ibl_texture *out, ibl_file_info *info)
{
    (void)info;
    if (size < 2 + 16) return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: shorter than one block", name);
    ibl_status st = block_image(ctx, bytes, size, name, 4, 4, out);
    if (st == IBL_OK) st = ibl_bc6h_decode(ctx, (bytes[0] >> 4) & 1, bytes + 2, out->width, out->height, out->data);
    if (st != IBL_OK && out->data) {
        ibl_texture_free(ctx, out);
        return ibl__fail_named(ctx, st, name);
    }
    return st;
}

__attribute__((unused)) static ibl_status fuzz_astc_blocks(ibl_context *ctx, const uint8_t *bytes, size_t size,
                                                           const char *name, ibl_texture *out, ibl_file_info *info)
{
    static const uint8_t footprints[8][2] = {{4, 4}, {5, 4}, {5, 5}, {6, 5}, {6, 6}, {8, 5}, {8, 6}, {8, 8}};
    (void)info;
    if (size < 2 + 16) return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: shorter than one block", name);
    const uint8_t *fp = footprints[bytes[0] >> 5];
    ibl_status st = block_image(ctx, bytes, size, name, fp[0], fp[1], out);
    ibl_astc_desc d = {fp[0], fp[1], IBL_QUALITY_DEFAULT};
    if (st == IBL_OK) st = ibl_astc_decode(ctx, &d, bytes + 2, out->width, out->height, out->data);
    if (st != IBL_OK && out->data) {
        ibl_texture_free(ctx, out);
        return ibl__fail_named(ctx, st, name);
    }
    return st;
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
    ibl_file_info head;
    if (ibl_decode_info(first, data, size, "<fuzz>", &head) != IBL_OK &&
        strncmp(ibl_context_message(first), "<fuzz>", 6) != 0)
        __builtin_trap();
    if (atomic_load(&fuzz_live_bytes) != live) __builtin_trap(); /* the header reader's leak */
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
