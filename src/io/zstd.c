/* Zstandard (libzstd; RFC 8878) for KTX2 supercompression scheme 2: one frame per level,
 * written with its content size and checksum (the reader verifies both when present). */
#include <zstd.h>

#include "core/context_internal.h"
#include "io/io_internal.h"

ibl_status ibl__zstd_compress(ibl_context *ctx, const char *name, const void *src, size_t size,
                              int level, uint8_t **out, size_t *out_size)
{
    *out = NULL;
    *out_size = 0;
    size_t bound = ZSTD_compressBound(size);
    /* libzstd's own tables and window (malloc'ed, counted as an estimate): its window never
     * exceeds the input, and the match tables stay within a few times it plus a constant */
    uint64_t working = (level >= 20 ? 8u : 4u) * (uint64_t)size + ((uint64_t)8 << 20);
    ibl_status st = ibl__budget_reserve(ctx, working);
    if (st != IBL_OK) return ibl__fail_named(ctx, st, name);
    uint8_t *buf = ibl_alloc(ctx, bound);
    if (!buf) {
        ibl__budget_release(ctx, working);
        return ibl__fail_named(ctx, ibl_context_status(ctx), name);
    }
    /* with the frame's content checksum, so that a corrupt level is refused on reading */
    ZSTD_CCtx *cctx = ZSTD_createCCtx();
    size_t n = cctx ? ZSTD_CCtx_setParameter(cctx, ZSTD_c_compressionLevel, level) : 0;
    if (cctx && !ZSTD_isError(n)) n = ZSTD_CCtx_setParameter(cctx, ZSTD_c_checksumFlag, 1);
    if (cctx && !ZSTD_isError(n)) n = ZSTD_compress2(cctx, buf, bound, src, size);
    ZSTD_freeCCtx(cctx);
    ibl__budget_release(ctx, working);
    if (!cctx) {
        ibl_free(ctx, buf);
        return ibl__fail(ctx, IBL_ERR_OUT_OF_MEMORY, "%s: out of memory for Zstandard", name);
    }
    if (ZSTD_isError(n)) {
        ibl_free(ctx, buf);
        return ibl__fail(ctx, IBL_ERR_IO, "%s: Zstandard compression failed: %s", name,
                        ZSTD_getErrorName(n));
    }
    *out = buf;
    *out_size = n;
    return IBL_OK;
}

ibl_status ibl__zstd_decompress(ibl_context *ctx, const char *name, int level, const void *src,
                                size_t size, void *dst, size_t expect)
{
    unsigned long long content = ZSTD_getFrameContentSize(src, size);
    if (content == ZSTD_CONTENTSIZE_ERROR)
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: level %d is not a Zstandard frame", name, level);
    if (content != ZSTD_CONTENTSIZE_UNKNOWN && content != expect)
        return ibl__fail(ctx, IBL_ERR_FORMAT,
                        "%s: level %d's Zstandard frame holds %llu bytes, the level needs %zu",
                        name, level, content, expect);
    uint64_t working = (uint64_t)1 << 20; /* the decompression context (window = the output) */
    ibl_status st = ibl__budget_reserve(ctx, working);
    if (st != IBL_OK) return ibl__fail_named(ctx, st, name);
    size_t n = ZSTD_decompress(dst, expect, src, size);
    ibl__budget_release(ctx, working);
    if (ZSTD_isError(n))
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: level %d: corrupt Zstandard data (%s)", name,
                        level, ZSTD_getErrorName(n));
    if (n != expect)
        return ibl__fail(ctx, IBL_ERR_FORMAT,
                        "%s: level %d inflates to %zu bytes, the level needs %zu", name, level, n,
                        expect);
    return IBL_OK;
}
