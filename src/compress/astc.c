/* ASTC HDR (Khronos Data Format Specification 1.3, "ASTC Compressed Texture Image
 * Formats"; VK_FORMAT_ASTC_{4x4..8x8}_SFLOAT_BLOCK) through ARM's astcenc. Images are split
 * into bands of block rows encoded on the context's parallel-for, each by its own
 * single-threaded astcenc context: ASTC blocks are encoded independently, so the output does
 * not depend on the number of bands or threads. */
#include <stdatomic.h>
#include <stdint.h>
#include <string.h>

#include "compress/astc_bridge.h"
#include "core/context_internal.h"
#include "ibl/compress.h"

enum { BAND_BLOCK_ROWS = 8, ASTC_CONTEXT_BYTES = 4 << 20 /* an estimate of astcenc's tables */ };

/* The 2D ASTC block footprints from 4x4 to 8x8. */
static int valid_block(int bw, int bh)
{
    static const uint8_t sizes[8][2] = {{4, 4}, {5, 4}, {5, 5}, {6, 5}, {6, 6}, {8, 5}, {8, 6}, {8, 8}};
    for (int i = 0; i < 8; i++)
        if (sizes[i][0] == bw && sizes[i][1] == bh) return 1;
    return 0;
}

size_t ibl_astc_bytes(int block_width, int block_height, int width, int height)
{
    if (!valid_block(block_width, block_height) || width <= 0 || height <= 0) return 0;
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

typedef struct band_job {
    int encode, bw, bh, width, height, bands;
    float preset;
    float *rgba;
    uint8_t *blocks;
    atomic_int failed;
    char err[200];
} band_job;

static void band(void *arg, int index)
{
    band_job *j = arg;
    int y0 = index * BAND_BLOCK_ROWS * j->bh;
    int rows = j->height - y0 < BAND_BLOCK_ROWS * j->bh ? j->height - y0 : BAND_BLOCK_ROWS * j->bh;
    size_t bytes = ibl_astc_bytes(j->bw, j->bh, j->width, rows);
    size_t offset = ibl_astc_bytes(j->bw, j->bh, j->width, j->bh) * (size_t)(index * BAND_BLOCK_ROWS);
    char err[200];
    if (ibl__astc_codec(j->encode, j->bw, j->bh, j->preset, j->rgba + (size_t)y0 * (size_t)j->width * 4,
                        j->width, rows, j->blocks + offset, bytes, err, sizeof err) &&
        atomic_fetch_add(&j->failed, 1) == 0)
        memcpy(j->err, err, sizeof err);
}

static ibl_status run(ibl_context *ctx, int encode, const ibl_astc_desc *desc, float *rgba,
                      int width, int height, uint8_t *blocks)
{
    int bw = desc && desc->block_width ? desc->block_width : 4;
    int bh = desc && desc->block_height ? desc->block_height : 4;
    if (!rgba || !blocks || width <= 0 || height <= 0 || !valid_block(bw, bh))
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "ASTC %s: invalid arguments (block %dx%d)",
                        encode ? "encode" : "decode", bw, bh);
    band_job *j = ibl_calloc(ctx, 1, sizeof *j);
    if (!j) return ibl_context_status(ctx);
    j->encode = encode, j->bw = bw, j->bh = bh, j->width = width, j->height = height;
    j->preset = preset_of(desc ? desc->quality : IBL_QUALITY_DEFAULT);
    j->rgba = rgba, j->blocks = blocks;
    int block_rows = (height + bh - 1) / bh;
    j->bands = (block_rows + BAND_BLOCK_ROWS - 1) / BAND_BLOCK_ROWS;
    int threads = ibl_context_threads(ctx);
    uint64_t working = (uint64_t)ASTC_CONTEXT_BYTES * (uint64_t)(threads < j->bands ? threads : j->bands);
    ibl_status st = ibl__budget_reserve(ctx, working);
    if (st == IBL_OK) {
        ibl_parallel_for(ctx, j->bands, band, j);
        ibl__budget_release(ctx, working);
        if (atomic_load(&j->failed)) st = ibl__fail(ctx, IBL_ERR_FORMAT, "%s", j->err);
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
