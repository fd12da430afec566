/* ASTC HDR (Khronos Data Format Specification 1.3, "ASTC Compressed Texture Image
 * Formats"; VK_FORMAT_ASTC_{4x4..8x8}_SFLOAT_BLOCK) through ARM's astcenc. Images are split
 * into bands of block rows run on the context's parallel-for, each band by a single-threaded
 * astcenc context: ASTC blocks are coded independently, so the output does not depend on the
 * number of bands or threads, nor on which context decoded a band.
 *
 * Encoding makes a context per band (its search dominates the cost). Decoding keeps its
 * contexts: a decompress-only astcenc context costs 4-14 ms of CPU to build (its partition
 * tables) against well under a millisecond to decode a probe's small mip levels, so each
 * ibl_context holds idle decoders per footprint (IBL__CACHE_ASTC_DECODERS, created on the first
 * decode, freed with the context). A band takes one from the idle list, or builds one when the
 * list is empty, and puts it back when done: there are never more decoders than bands decoded
 * at once, whichever threads run them, and no decoder is used by two threads at a time. */
#include <pthread.h>
#include <stdatomic.h>
#include <stdint.h>
#include <string.h>

#include "compress/astc_bridge.h"
#include "core/context_internal.h"
#include "ibl/compress.h"

enum {
    BAND_BLOCK_ROWS = 8,
    ASTC_FOOTPRINTS = 8,
    ASTC_ENCODER_BYTES = 4 << 20, /* an estimate of an encoding context's tables */
    /* a decoder's resident memory, rounded up from astcenc 4.2 on x86-64: 4.2 MiB (4x4) to
     * 9.3 MiB (8x8) measured as the growth of the process's resident set per context */
    ASTC_DECODER_BYTES = 10 << 20,
    IDLE_DECODERS = 64 /* per footprint: the built-in pool's largest thread count */
};

static const uint8_t footprints[ASTC_FOOTPRINTS][2] = {{4, 4}, {5, 4}, {5, 5}, {6, 5},
                                                      {6, 6}, {8, 5}, {8, 6}, {8, 8}};

/* The index of a 2D footprint from 4x4 to 8x8 in `footprints`, or -1. */
static int footprint_index(int bw, int bh)
{
    for (int i = 0; i < ASTC_FOOTPRINTS; i++)
        if (footprints[i][0] == bw && footprints[i][1] == bh) return i;
    return -1;
}

size_t ibl_astc_bytes(int block_width, int block_height, int width, int height)
{
    if (footprint_index(block_width, block_height) < 0 || width <= 0 || height <= 0) return 0;
    return (size_t)((width + block_width - 1) / block_width) *
           (size_t)((height + block_height - 1) / block_height) * 16;
}

static float preset_of(ibl_quality q)
{
    switch (q) {
    case IBL_QUALITY_FAST: return 10.0f;     /* ASTCENC_PRE_FAST     */
    case IBL_QUALITY_THOROUGH: return 98.0f; /* ASTCENC_PRE_THOROUGH */
    default: return 60.0f;                   /* ASTCENC_PRE_MEDIUM   */
    }
}

/* ---- the context's idle decoders ------------------------------------------------------ */

typedef struct astc_decoders {
    pthread_mutex_t lock; /* ibl_astc_decode may run on several threads with one context */
    int idle_count[ASTC_FOOTPRINTS];
    ibl__astc_decoder *idle[ASTC_FOOTPRINTS][IDLE_DECODERS];
} astc_decoders;

static void *decoders_create(ibl_context *ctx)
{
    astc_decoders *d = ibl_calloc(ctx, 1, sizeof *d);
    if (d && pthread_mutex_init(&d->lock, NULL) != 0) {
        ibl_free(ctx, d);
        ibl__fail(ctx, IBL_ERR_OUT_OF_MEMORY, "ASTC decode: cannot create a lock");
        return NULL;
    }
    return d;
}

/* Every decoder in the list is idle: the context is being destroyed, no call is running. */
static void decoders_free(ibl_context *ctx, void *cache)
{
    astc_decoders *d = cache;
    for (int f = 0; f < ASTC_FOOTPRINTS; f++)
        for (int i = 0; i < d->idle_count[f]; i++) {
            ibl__astc_decoder_free(d->idle[f][i]);
            ibl__budget_release(ctx, ASTC_DECODER_BYTES);
        }
    pthread_mutex_destroy(&d->lock);
    ibl_free(ctx, d);
}

/* An idle decoder of footprint f, or a new one (its memory reserved in the budget until it is
 * freed). With no cache (no context) every band builds its own. On failure, TOO_LARGE with the
 * budget's message in the context, or OUT_OF_MEMORY with astcenc's in err. */
static ibl_status decoder_take(ibl_context *ctx, astc_decoders *cache, int f, ibl__astc_decoder **out,
                               char *err, size_t err_size)
{
    *out = NULL;
    if (cache) {
        pthread_mutex_lock(&cache->lock);
        if (cache->idle_count[f] > 0) *out = cache->idle[f][--cache->idle_count[f]];
        pthread_mutex_unlock(&cache->lock);
        if (*out) return IBL_OK;
    }
    ibl_status st = ibl__budget_reserve(ctx, ASTC_DECODER_BYTES);
    if (st != IBL_OK) return st;
    *out = ibl__astc_decoder_create(footprints[f][0], footprints[f][1], err, err_size);
    if (*out) return IBL_OK;
    ibl__budget_release(ctx, ASTC_DECODER_BYTES);
    return IBL_ERR_OUT_OF_MEMORY;
}

/* Back to the idle list; freed when the list is full or there is no cache. */
static void decoder_give_back(ibl_context *ctx, astc_decoders *cache, int f, ibl__astc_decoder *decoder)
{
    if (cache) {
        pthread_mutex_lock(&cache->lock);
        if (cache->idle_count[f] < IDLE_DECODERS) {
            cache->idle[f][cache->idle_count[f]++] = decoder;
            decoder = NULL;
        }
        pthread_mutex_unlock(&cache->lock);
    }
    if (decoder) {
        ibl__astc_decoder_free(decoder);
        ibl__budget_release(ctx, ASTC_DECODER_BYTES);
    }
}

/* ---- bands ---------------------------------------------------------------------------- */

typedef struct band_job {
    ibl_context *ctx;
    astc_decoders *cache; /* decoding only; NULL without a context */
    int encode, footprint, bw, bh, width, height, bands;
    float preset;
    float *rgba;
    uint8_t *blocks;
    atomic_int failed;
    ibl_status status; /* of the first band that failed */
    char err[200];     /* its message; empty when the budget's is in the context */
} band_job;

static void band(void *arg, int index)
{
    band_job *j = arg;
    int y0 = index * BAND_BLOCK_ROWS * j->bh;
    int rows = j->height - y0 < BAND_BLOCK_ROWS * j->bh ? j->height - y0 : BAND_BLOCK_ROWS * j->bh;
    size_t bytes = ibl_astc_bytes(j->bw, j->bh, j->width, rows);
    size_t offset = ibl_astc_bytes(j->bw, j->bh, j->width, j->bh) * (size_t)(index * BAND_BLOCK_ROWS);
    float *texels = j->rgba + (size_t)y0 * (size_t)j->width * 4;
    char err[200] = "";
    ibl_status st = IBL_OK;
    if (j->encode) {
        if (ibl__astc_encode_image(j->bw, j->bh, j->preset, texels, j->width, rows, j->blocks + offset,
                                   bytes, err, sizeof err))
            st = IBL_ERR_FORMAT;
    } else {
        ibl__astc_decoder *decoder;
        st = decoder_take(j->ctx, j->cache, j->footprint, &decoder, err, sizeof err);
        if (st == IBL_OK) {
            if (ibl__astc_decoder_run(decoder, j->blocks + offset, bytes, texels, j->width, rows, err, sizeof err))
                st = IBL_ERR_FORMAT;
            decoder_give_back(j->ctx, j->cache, j->footprint, decoder);
        }
    }
    if (st != IBL_OK && atomic_fetch_add(&j->failed, 1) == 0) {
        j->status = st;
        memcpy(j->err, err, sizeof err);
    }
}

static ibl_status run(ibl_context *ctx, int encode, const ibl_astc_desc *desc, float *rgba,
                      int width, int height, uint8_t *blocks)
{
    int bw = desc && desc->block_width ? desc->block_width : 4;
    int bh = desc && desc->block_height ? desc->block_height : 4;
    int footprint = footprint_index(bw, bh);
    if (!rgba || !blocks || width <= 0 || height <= 0 || footprint < 0)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "ASTC %s: invalid arguments (block %dx%d)",
                        encode ? "encode" : "decode", bw, bh);
    astc_decoders *cache = NULL;
    if (!encode && ctx) {
        cache = ibl__context_cache(ctx, IBL__CACHE_ASTC_DECODERS, decoders_create, decoders_free);
        if (!cache) return ibl_context_status(ctx);
    }
    band_job *j = ibl_calloc(ctx, 1, sizeof *j);
    if (!j) return ibl_context_status(ctx);
    j->ctx = ctx, j->cache = cache, j->encode = encode, j->footprint = footprint;
    j->bw = bw, j->bh = bh, j->width = width, j->height = height;
    j->preset = preset_of(desc ? desc->quality : IBL_QUALITY_DEFAULT);
    j->rgba = rgba, j->blocks = blocks;
    int block_rows = (height + bh - 1) / bh;
    j->bands = (block_rows + BAND_BLOCK_ROWS - 1) / BAND_BLOCK_ROWS;
    /* encoding contexts live only while the bands run: their estimate is reserved for as many
     * as can run at once; decoders reserve their own as they are built */
    int threads = ibl_context_threads(ctx);
    uint64_t working = encode ? (uint64_t)ASTC_ENCODER_BYTES * (uint64_t)(threads < j->bands ? threads : j->bands) : 0;
    ibl_status st = ibl__budget_reserve(ctx, working);
    if (st == IBL_OK) {
        ibl_parallel_for(ctx, j->bands, band, j);
        ibl__budget_release(ctx, working);
        if (atomic_load(&j->failed)) {
            st = j->status;
            if (j->err[0]) ibl__fail(ctx, st, "%s", j->err);
        }
    }
    ibl_free(ctx, j);
    return st;
}

ibl_status ibl_astc_encode(ibl_context *ctx, const ibl_astc_desc *desc, const float *rgba,
                           int width, int height, void *blocks)
{
    /* astcenc reads the texels through a non-const pointer; it does not write them */
    return run(ctx, 1, desc, (float *)(uintptr_t)rgba, width, height, blocks);
}

ibl_status ibl_astc_decode(ibl_context *ctx, const ibl_astc_desc *desc, const void *blocks,
                           int width, int height, float *rgba)
{
    return run(ctx, 0, desc, rgba, width, height, (uint8_t *)(uintptr_t)blocks);
}
