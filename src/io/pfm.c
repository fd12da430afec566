/* Portable Float Map (.pfm): "PF" (RGB) or "Pf" (grey), width, height, then a scale whose
 * sign gives the byte order (negative: little-endian), one white-space byte, and rows of
 * 32-bit floats stored bottom row first. The magnitude of the scale is ignored, as in most
 * readers. Written as little-endian RGB ("PF", scale -1); alpha is not stored. */
#include "io/io_internal.h"
#include "core/context_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int is_space(uint8_t c)
{
    return c == ' ' || c == '\t' || c == '\n' || c == '\r';
}

/* Copies the next white-space separated token (at most cap-1 bytes) into tok. */
static int next_token(const uint8_t *b, size_t size, size_t *pos, char *tok, size_t cap)
{
    while (*pos < size && is_space(b[*pos])) (*pos)++;
    size_t n = 0;
    while (*pos < size && !is_space(b[*pos])) {
        if (n + 1 >= cap) return 0;
        tok[n++] = (char)b[(*pos)++];
    }
    tok[n] = 0;
    return n > 0;
}

static int parse_dim(const char *tok, int *out)
{
    long v = 0;
    if (!tok[0]) return 0;
    for (const char *c = tok; *c; c++) {
        if (*c < '0' || *c > '9') return 0;
        if (v <= 100000000L) v = v * 10 + (*c - '0');
    }
    if (v <= 0 || v > IBL_MAX_DIMENSION) return 0;
    *out = (int)v;
    return 1;
}

static float load_float(const uint8_t *p, int little)
{
    uint32_t u = little ? (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24
                        : (uint32_t)p[3] | (uint32_t)p[2] << 8 | (uint32_t)p[1] << 16 | (uint32_t)p[0] << 24;
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

/* The header: "PF" or "Pf", width, height, scale, one white-space byte. */
typedef struct pfm_header {
    int width, height, channels;
    int little;         /* the scale is negative: little-endian floats */
    size_t data_offset; /* the first byte of the bottom row          */
} pfm_header;

static ibl_status parse_header(ibl_context *ctx, const uint8_t *bytes, size_t size,
                               const char *name, pfm_header *hd)
{
    memset(hd, 0, sizeof *hd);
    if (size < 3 || bytes[0] != 'P' || (bytes[1] != 'F' && bytes[1] != 'f'))
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: not a PFM file", name);
    int channels = bytes[1] == 'F' ? 3 : 1;
    size_t pos = 2;
    char tw[32], th[32], ts[64];
    int w = 0, h = 0;
    if (!next_token(bytes, size, &pos, tw, sizeof tw) || !next_token(bytes, size, &pos, th, sizeof th) ||
        !next_token(bytes, size, &pos, ts, sizeof ts) || pos >= size)
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: truncated PFM header", name);
    if (!parse_dim(tw, &w) || !parse_dim(th, &h))
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: bad PFM size \"%s x %s\" (1..%d)", name, tw, th,
                        (int)IBL_MAX_DIMENSION);
    char *endp = NULL;
    double scale = strtod(ts, &endp);
    if (!endp || *endp || scale == 0.0 || !isfinite(scale))
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: bad PFM scale \"%s\"", name, ts);
    pos++; /* the single white-space byte ending the header */
    hd->width = w;
    hd->height = h;
    hd->channels = channels;
    hd->little = scale < 0.0;
    hd->data_offset = pos;
    return IBL_OK;
}

ibl_status ibl__pfm_info(ibl_context *ctx, const uint8_t *bytes, size_t size, const char *name,
                         ibl_file_info *info)
{
    pfm_header hd;
    ibl_status s = parse_header(ctx, bytes, size, name, &hd);
    if (s != IBL_OK) return s;
    info->width = hd.width;
    info->height = hd.height;
    info->format = IBL_FORMAT_RGB32F; /* as ibl__pfm_decode reports */
    info->has_alpha = 0;
    return IBL_OK;
}

ibl_status ibl__pfm_decode(ibl_context *ctx, const uint8_t *bytes, size_t size, const char *name,
                           ibl_texture *out, ibl_file_info *info)
{
    pfm_header hd;
    ibl_status s = parse_header(ctx, bytes, size, name, &hd);
    if (s != IBL_OK) return s;
    int w = hd.width, h = hd.height, channels = hd.channels, little = hd.little;
    size_t pos = hd.data_offset;
    size_t row_bytes = (size_t)w * (size_t)channels * 4;
    size_t need = row_bytes * (size_t)h; /* w, h <= 2^16: no overflow in 64-bit size_t */
    if (size - pos < need)
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: truncated PFM data (%zu of %zu bytes)", name,
                        size - pos, need);
    s = ibl_texture_alloc(ctx, IBL_TEXTURE_2D, w, h, 1, 1, out);
    if (s != IBL_OK) {
        return ibl__fail_named(ctx, s, name);
    }
    for (int y = 0; y < h; y++) {
        const uint8_t *src = bytes + pos + (size_t)(h - 1 - y) * row_bytes; /* bottom row first */
        float *dst = out->data + (size_t)y * (size_t)w * 4;
        for (int x = 0; x < w; x++) {
            const uint8_t *q = src + (size_t)x * (size_t)channels * 4;
            float *o = dst + (size_t)x * 4;
            if (channels == 3) {
                o[0] = load_float(q, little);
                o[1] = load_float(q + 4, little);
                o[2] = load_float(q + 8, little);
            } else {
                o[0] = o[1] = o[2] = load_float(q, little);
            }
            o[3] = 1.0f;
        }
    }
    out->format = IBL_FORMAT_RGB32F;
    info->format = IBL_FORMAT_RGB32F;
    info->has_alpha = 0;
    return IBL_OK;
}

ibl_status ibl__pfm_encode(ibl_context *ctx, const ibl_image *image, const ibl_write_desc *desc,
                           const char *name, void **bytes, size_t *size)
{
    if (desc->format != IBL_FORMAT_DEFAULT && desc->format != IBL_FORMAT_RGB32F)
        return ibl__fail(ctx, IBL_ERR_UNSUPPORTED, "%s: PFM stores only rgb32f, not %s", name,
                        ibl_format_name(desc->format));
    int w = image->width, h = image->height;
    if (w > IBL_MAX_DIMENSION || h > IBL_MAX_DIMENSION)
        return ibl__fail(ctx, IBL_ERR_TOO_LARGE, "%s: image %dx%d too large", name, w, h);
    char header[64];
    int hl = snprintf(header, sizeof header, "PF\n%d %d\n-1.0\n", w, h);
    size_t row_bytes = (size_t)w * 12;
    size_t total = (size_t)hl + row_bytes * (size_t)h;
    uint8_t *buf = ibl_alloc(ctx, total);
    if (!buf) {
        return ibl__fail_named(ctx, ibl_context_status(ctx), name);
    }
    memcpy(buf, header, (size_t)hl);
    for (int y = 0; y < h; y++) {
        const float *src = image->pixels + (size_t)(h - 1 - y) * (size_t)w * 4;
        uint8_t *o = buf + hl + (size_t)y * row_bytes;
        for (int x = 0; x < w; x++) {
            for (int c = 0; c < 3; c++) {
                uint32_t u;
                memcpy(&u, &src[(size_t)x * 4 + (size_t)c], 4);
                o[0] = (uint8_t)u;
                o[1] = (uint8_t)(u >> 8);
                o[2] = (uint8_t)(u >> 16);
                o[3] = (uint8_t)(u >> 24);
                o += 4;
            }
        }
    }
    *bytes = buf;
    *size = total;
    return IBL_OK;
}
