/* BC6H decoding, bit-exact to the Khronos Data Format Specification 1.3, section "BC6H":
 * the mode (low 2 or 5 bits), the endpoint fields of the mode's block description, sign
 * extension and the inverse transform (E_k = (E0 + E_k) & ((1 << EPB) - 1), sign-extended
 * again for signed formats), the indices (65 + ... for one region, 82 + ... for two, anchors
 * one bit shorter), unquantization, interpolation and the final unquantization. Reserved
 * modes decode to 0 (the spec's "(0.0, 0.0, 0.0, 1.0)"). */
#include <string.h>

#include "ibl/compress.h"
#include "compress/bc6h_internal.h"
#include "core/context_internal.h"
#include "core/pixel_format.h"

size_t ibl_bc6h_bytes(int width, int height)
{
    if (width <= 0 || height <= 0) return 0;
    return (size_t)((width + 3) / 4) * (size_t)((height + 3) / 4) * IBL_BC6H_BLOCK_BYTES;
}

/* Reads the endpoint and partition fields of a block described by mode m. */
static void read_fields(const bc6h_mode *m, const uint8_t block[16], int e[12], int *partition)
{
    int pos = 0;
    memset(e, 0, 12 * sizeof *e);
    *partition = 0;
    for (int s = 0; s < m->seg_count; s++) {
        const bc6h_seg *g = &m->segs[s];
        int n = g->a >= g->b ? g->a - g->b + 1 : g->b - g->a + 1;
        unsigned bits = ibl__bc6h_get_bits(block, pos, n);
        pos += n;
        if (g->field == BC6H_FIELD_M) continue;
        int value = 0;
        for (int i = 0; i < n; i++) {
            int dst = g->a >= g->b ? g->b + i : g->b - i;
            value |= (int)((bits >> i) & 1u) << dst;
        }
        if (g->field == BC6H_FIELD_PB) *partition |= value;
        else e[g->field] |= value;
    }
}

/* Sign extension and the inverse transform ("Sign Extension for Endpoint Values",
 * "Transform Inversion for Endpoint Values"). */
static void resolve_endpoints(const bc6h_mode *m, int is_signed, int e[12])
{
    int count = 2 * m->regions, mask = (1 << m->prec) - 1;
    for (int c = 0; c < 3; c++) {
        if (is_signed) e[c] = ibl__bc6h_sign_extend(e[c], m->prec);
        for (int k = 1; k < count; k++) {
            int *v = &e[3 * k + c];
            if (m->transformed || is_signed) *v = ibl__bc6h_sign_extend(*v, m->delta[c]);
            if (m->transformed) {
                *v = (e[c] + *v) & mask;
                if (is_signed) *v = ibl__bc6h_sign_extend(*v, m->prec);
            }
        }
    }
}

int ibl_bc6h_decode_block(const uint8_t block[16], int is_signed, uint16_t half_rgb[48])
{
    int mi = ibl__bc6h_mode_index(block);
    if (mi < 0) {
        memset(half_rgb, 0, 48 * sizeof *half_rgb);
        return -1;
    }
    const bc6h_mode *m = &ibl__bc6h_modes[mi];
    int e[12], partition;
    read_fields(m, block, e, &partition);
    resolve_endpoints(m, is_signed, e);
    int unq[12];
    for (int i = 0; i < 6 * m->regions; i++) unq[i] = ibl__bc6h_unquantize(e[i], m->prec, is_signed);

    int two = m->regions == 2;
    int bits = two ? 3 : 4, pos = two ? 82 : 65;
    uint16_t shape = two ? ibl__bc6h_partitions[partition] : 0;
    int anchor = two ? ibl__bc6h_anchor2[partition] : 0;
    const uint8_t *weights = two ? ibl__bc6h_weights3 : ibl__bc6h_weights4;
    for (int t = 0; t < 16; t++) {
        int n = (t == 0 || (two && t == anchor)) ? bits - 1 : bits;
        int index = (int)ibl__bc6h_get_bits(block, pos, n);
        pos += n;
        int s = (shape >> t) & 1;
        const int *a = &unq[6 * s], *b = &unq[6 * s + 3];
        for (int c = 0; c < 3; c++)
            half_rgb[3 * t + c] =
                ibl__bc6h_finish(ibl__bc6h_interpolate(a[c], b[c], weights[index]), is_signed);
    }
    return m->number;
}

typedef struct decode_job {
    int is_signed, width, height, blocks_x;
    const uint8_t *blocks;
    float *rgba;
} decode_job;

static void decode_row(void *arg, int by)
{
    const decode_job *j = arg;
    uint16_t h[48];
    for (int bx = 0; bx < j->blocks_x; bx++) {
        ibl_bc6h_decode_block(j->blocks + ((size_t)by * (size_t)j->blocks_x + (size_t)bx) * 16,
                              j->is_signed, h);
        for (int y = 0; y < 4 && by * 4 + y < j->height; y++)
            for (int x = 0; x < 4 && bx * 4 + x < j->width; x++) {
                float *p = j->rgba + ((size_t)(by * 4 + y) * (size_t)j->width + (size_t)(bx * 4 + x)) * 4;
                for (int c = 0; c < 3; c++) p[c] = ibl_half_to_float(h[3 * (4 * y + x) + c]);
                p[3] = 1.0f;
            }
    }
}

ibl_status ibl_bc6h_decode(ibl_context *ctx, int is_signed, const void *blocks, int width,
                           int height, float *rgba)
{
    if (!blocks || !rgba || width <= 0 || height <= 0)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "BC6H decode: invalid arguments");
    decode_job j = {is_signed != 0, width, height, (width + 3) / 4, blocks, rgba};
    ibl_parallel_for(ctx, (height + 3) / 4, decode_row, &j);
    return IBL_OK;
}
