/* PNG through libpng both ways: 8-bit and 16-bit reading, 8-bit sRGB previews, 8-bit and
 * 16-bit linear data (tables, packed material channels) and 8-bit RGBM on writing. Also the two pieces the JPEG reader and writer (jpeg.c) share
 * with it: RGBA samples to linear float, and the 8-bit display encoding.
 *
 * Transfer functions on read: a PNG with an sRGB chunk is sRGB; one with only a gAMA chunk
 * uses that power law (gAMA 1.0 = linear, which is how the 16-bit tables are written); one
 * with neither is sRGB. iCCP profiles are not interpreted. Alpha is linear. The sRGB curve
 * is the exact piecewise function of IEC 61966-2-1. */
#include "io/io_internal.h"
#include "core/context_internal.h"

#include <math.h>
#include <png.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* IEC 61966-2-1 decoding (EOTF). */
static double srgb_to_linear(double v)
{
    return v <= 0.04045 ? v / 12.92 : pow((v + 0.055) / 1.055, 2.4);
}

static uint32_t be32(const uint8_t *p)
{
    return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | (uint32_t)p[3];
}

/* The PNG's declared encoding from the chunks before the image data: returns the decoding
 * exponent for a gAMA-only file, or 0 for sRGB. */
static double png_decoding_power(const uint8_t *b, size_t size)
{
    size_t pos = 8;
    int has_srgb = 0;
    uint32_t gama = 0;
    while (size - pos >= 12) {
        uint32_t len = be32(b + pos);
        const uint8_t *type = b + pos + 4;
        if (len > size - pos - 12) break;
        if (memcmp(type, "IDAT", 4) == 0 || memcmp(type, "IEND", 4) == 0) break;
        if (memcmp(type, "sRGB", 4) == 0) has_srgb = 1;
        if (memcmp(type, "gAMA", 4) == 0 && len == 4) gama = be32(b + pos + 8);
        pos += 12 + (size_t)len;
    }
    if (has_srgb || gama == 0) return 0.0;
    /* gAMA stores the encoding exponent times 100000 (45455 for 1/2.2). */
    return 100000.0 / (double)gama;
}

/* The text of a tEXt chunk before the image data ("" when absent), at most cap - 1 bytes. */
static void png_text_value(const uint8_t *b, size_t size, const char *keyword, char *out, size_t cap)
{
    size_t pos = 8, klen = strlen(keyword);
    out[0] = 0;
    while (size - pos >= 12) {
        uint32_t len = be32(b + pos);
        const uint8_t *type = b + pos + 4, *data = b + pos + 8;
        if (len > size - pos - 12) break;
        if (memcmp(type, "IDAT", 4) == 0 || memcmp(type, "IEND", 4) == 0) break;
        if (memcmp(type, "tEXt", 4) == 0 && len > klen && memcmp(data, keyword, klen) == 0 &&
            data[klen] == 0) {
            size_t n = len - klen - 1 < cap - 1 ? len - klen - 1 : cap - 1;
            memcpy(out, data + klen + 1, n);
            out[n] = 0;
            return;
        }
        pos += 12 + (size_t)len;
    }
}

/* 8-bit RGBM samples (the tail of dst, as ibl__rgba_samples_to_linear) to linear RGB, A = 1. */
static void rgbm_samples_to_linear(const uint8_t *pix, float range, size_t texels, float *dst)
{
    for (size_t i = 0; i < texels; i++) {
        uint8_t q[4];
        memcpy(q, pix + i * 4, 4); /* read whole before the float overwrites it */
        float *o = dst + i * 4;
        ibl_rgbm_decode(q, range, o);
        o[3] = 1.0f;
    }
}

ibl_status ibl__rgba_samples_to_linear(ibl_context *ctx, const uint8_t *pix, int is16, double power,
                                      size_t texels, float *dst, const char *name)
{
    if (is16) {
        /* 65536-entry table: cheaper than a pow per channel beyond ~16k texels. */
        float *lut = ibl_alloc(ctx, 65536 * sizeof(float));
        if (!lut) return ibl__fail_named(ctx, ibl_context_status(ctx), name);
        for (int i = 0; i < 65536; i++) {
            double v = i / 65535.0;
            lut[i] = (float)(power == 0.0 ? srgb_to_linear(v) : power == 1.0 ? v : pow(v, power));
        }
        for (size_t i = 0; i < texels; i++) {
            const uint8_t *q = pix + i * 8;
            float r = lut[q[0] << 8 | q[1]], g = lut[q[2] << 8 | q[3]], b = lut[q[4] << 8 | q[5]];
            float a = (float)((q[6] << 8 | q[7]) / 65535.0);
            float *o = dst + i * 4;
            o[0] = r;
            o[1] = g;
            o[2] = b;
            o[3] = a;
        }
        ibl_free(ctx, lut);
        return IBL_OK;
    }
    float lut[256];
    for (int i = 0; i < 256; i++) {
        double v = i / 255.0;
        lut[i] = (float)(power == 0.0 ? srgb_to_linear(v) : power == 1.0 ? v : pow(v, power));
    }
    for (size_t i = 0; i < texels; i++) {
        const uint8_t *q = pix + i * 4;
        float r = lut[q[0]], g = lut[q[1]], b = lut[q[2]], a = (float)(q[3] / 255.0);
        float *o = dst + i * 4;
        o[0] = r;
        o[1] = g;
        o[2] = b;
        o[3] = a;
    }
    return IBL_OK;
}

/* ---- PNG reader (libpng) ------------------------------------------------------------- */

/* libpng rather than stb_image: it inflates straight into rows of the declared size, so a
 * zlib bomb or a chunk declaring gigabytes cannot make it allocate (stb_image grows its
 * buffers to whatever the stream holds; fuzzing found a 556-byte file asking for 1 GiB).
 * The rows are the tail of the float image itself (4 or 8 bytes of samples per texel of its
 * 16), converted in place afterwards: the image is the only large buffer. */
typedef struct png_read_state {
    ibl_context *ctx;
    const char *name;
    const uint8_t *data;
    size_t size, pos;
    ibl_texture *out;
    int header_only; /* stop after IHDR (ibl__png_info): no image, no IDAT check */
    png_uint_32 width, height;
    int is16, has_alpha;
    uint8_t *raw;    /* RGBA samples of the whole image: the tail of out->data */
    png_bytep *rows; /* into raw */
    ibl_status status;
    char error[200];
} png_read_state;

/* Bytes of all IDAT chunks (the compressed image); the chunk walk stops at anything that does
 * not fit in the file, where libpng will stop too. */
static uint64_t png_idat_bytes(const uint8_t *b, size_t size)
{
    uint64_t total = 0;
    size_t pos = 8;
    while (size - pos >= 12) {
        uint32_t len = be32(b + pos);
        if (len > size - pos - 12) break;
        if (memcmp(b + pos + 4, "IDAT", 4) == 0) total += len;
        if (memcmp(b + pos + 4, "IEND", 4) == 0) break;
        pos += 12 + (size_t)len;
    }
    return total;
}

/* Deflate codes a match of 258 bytes (its longest) in two bits at best (a one-bit length
 * code and a one-bit distance code), so no zlib stream expands more than 1032 times. */
enum { DEFLATE_MAX_RATIO = 1032 };

static void png_on_read_error(png_structp png, png_const_charp msg)
{
    png_read_state *st = png_get_error_ptr(png);
    snprintf(st->error, sizeof st->error, "%s", msg);
    png_longjmp(png, 1);
}

static void png_on_read(png_structp png, png_bytep dst, size_t n)
{
    png_read_state *st = png_get_io_ptr(png);
    if (n > st->size - st->pos) png_error(png, "truncated PNG data");
    memcpy(dst, st->data + st->pos, n);
    st->pos += n;
}

static void png_on_warning(png_structp png, png_const_charp msg);

/* Runs libpng; everything it may touch after setjmp lives in *st (not in locals). */
static int png_read_run(png_read_state *st)
{
    png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, st, png_on_read_error, png_on_warning);
    png_infop pinfo = png ? png_create_info_struct(png) : NULL;
    if (!pinfo) {
        if (png) png_destroy_read_struct(&png, NULL, NULL);
        snprintf(st->error, sizeof st->error, "cannot start libpng");
        return 0;
    }
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_read_struct(&png, &pinfo, NULL);
        return 0;
    }
    png_set_read_fn(png, st, png_on_read);
    png_set_user_limits(png, IBL_MAX_DIMENSION, IBL_MAX_DIMENSION);
    png_read_info(png, pinfo);
    png_uint_32 w = 0, h = 0;
    int depth = 0, color = 0;
    png_get_IHDR(png, pinfo, &w, &h, &depth, &color, NULL, NULL, NULL);
    st->width = w;
    st->height = h;
    if (st->header_only) {
        st->has_alpha = (color & PNG_COLOR_MASK_ALPHA) || png_get_valid(png, pinfo, PNG_INFO_tRNS);
        st->is16 = depth == 16;
        png_destroy_read_struct(&png, &pinfo, NULL);
        return 1;
    }
    /* A file too small to hold the declared image even at deflate's best ratio is refused
     * before anything is allocated; one that can hold it (a large image of one colour
     * compresses to almost nothing) is decoded if the budget allows. */
    uint64_t stored_bits = (uint64_t)w * h * png_get_channels(png, pinfo) * (uint64_t)depth;
    uint64_t least = stored_bits / 8 / DEFLATE_MAX_RATIO, idat = png_idat_bytes(st->data, st->size);
    if (idat < least) {
        st->status = ibl__fail(st->ctx, IBL_ERR_FORMAT,
                               "%s: a %ux%u PNG needs at least %llu bytes of compressed data, the "
                               "file has %llu (truncated, or a forged size)",
                               st->name, (unsigned)w, (unsigned)h, (unsigned long long)least,
                               (unsigned long long)idat);
        png_error(png, "too little image data");
    }
    st->has_alpha = (color & PNG_COLOR_MASK_ALPHA) || png_get_valid(png, pinfo, PNG_INFO_tRNS);
    st->is16 = depth == 16;
    png_set_expand(png); /* palette -> RGB, grey < 8 bits -> 8, tRNS -> alpha */
    if (!(color & PNG_COLOR_MASK_COLOR)) png_set_gray_to_rgb(png);
    if (!st->has_alpha) png_set_add_alpha(png, st->is16 ? 0xFFFF : 0xFF, PNG_FILLER_AFTER);
    (void)png_set_interlace_handling(png);
    png_read_update_info(png, pinfo);
    size_t texel_bytes = st->is16 ? 8 : 4;
    if (png_get_rowbytes(png, pinfo) != (size_t)w * texel_bytes) png_error(png, "unexpected row layout");
    st->status = ibl_texture_alloc(st->ctx, IBL_TEXTURE_2D, (int)w, (int)h, 1, 1, st->out);
    if (st->status != IBL_OK) png_error(png, "out of memory");
    size_t texels = (size_t)w * (size_t)h;
    st->raw = (uint8_t *)st->out->data + texels * (4 * sizeof(float) - texel_bytes);
    st->rows = ibl_alloc(st->ctx, (size_t)h * sizeof *st->rows);
    if (!st->rows) {
        st->status = ibl_context_status(st->ctx);
        png_error(png, "out of memory");
    }
    for (png_uint_32 y = 0; y < h; y++) st->rows[y] = st->raw + (size_t)y * (size_t)w * texel_bytes;
    png_read_image(png, st->rows);
    /* The end (IEND and text after the image) is not needed: files cut after it still load. */
    png_destroy_read_struct(&png, &pinfo, NULL);
    return 1;
}

/* 0 if a chunk before the image data runs past the end of the file. libpng allocates a
 * chunk's declared length before reading it, and a length over its limit is only a warning
 * (a benign error): fuzzing found an 81-byte file whose tEXt chunk asked for 1 GiB. */
static int png_chunks_inside(const uint8_t *b, size_t size)
{
    size_t pos = 8;
    while (size - pos >= 8 && memcmp(b + pos + 4, "IDAT", 4) != 0) {
        uint32_t len = be32(b + pos);
        if (len > size - pos - 8 || size - pos - 8 - len < 4) return 0; /* data and CRC */
        pos += 12 + (size_t)len;
    }
    return 1;
}

ibl_status ibl__png_decode(ibl_context *ctx, const uint8_t *bytes, size_t size, const char *name,
                           ibl_texture *out, ibl_file_info *info)
{
    return ibl__png_decode_as(ctx, bytes, size, name, 0, out, info);
}

/* The checks before libpng runs, then libpng on a new state (header_only: up to IHDR).
 * Returns the state (ibl_free it and its rows) with *status, or NULL when none was made. */
static png_read_state *png_read(ibl_context *ctx, const uint8_t *bytes, size_t size,
                                const char *name, int header_only, ibl_texture *out,
                                ibl_status *status)
{
    /* the chunk walks below start after the signature */
    static const uint8_t signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
    *status = IBL_OK;
    if (size < sizeof signature || memcmp(bytes, signature, sizeof signature) != 0) {
        *status = ibl__fail(ctx, IBL_ERR_FORMAT, "%s: not a PNG file (no PNG signature)", name);
        return NULL;
    }
    if (!png_chunks_inside(bytes, size)) {
        *status = ibl__fail(ctx, IBL_ERR_FORMAT,
                            "%s: truncated PNG (a chunk runs past the end of the file)", name);
        return NULL;
    }
    png_read_state *st = ibl_calloc(ctx, 1, sizeof *st);
    if (!st) {
        *status = ibl__fail_named(ctx, ibl_context_status(ctx), name);
        return NULL;
    }
    st->ctx = ctx;
    st->name = name;
    st->data = bytes;
    st->size = size;
    st->out = out;
    st->header_only = header_only;
    if (!png_read_run(st)) {
        if (st->status == IBL_ERR_FORMAT) *status = st->status; /* its message names the file */
        else if (st->status != IBL_OK) *status = ibl__fail_named(ctx, st->status, name);
        else *status = ibl__fail(ctx, IBL_ERR_FORMAT, "%s: corrupt PNG (%s)", name, st->error);
    }
    return st;
}

/* 8-bit files whose tEXt ibl.encoding is rgbm (read as data: never) hold RGBM. */
static int png_is_rgbm(const uint8_t *bytes, size_t size, int as_data, int is16)
{
    char encoding[16];
    png_text_value(bytes, size, "ibl.encoding", encoding, sizeof encoding);
    return !as_data && !is16 && strcmp(encoding, "rgbm") == 0;
}

/* The format and alpha the decoder reports. */
static void png_fill_info(ibl_file_info *info, int rgbm, const png_read_state *st)
{
    info->format = rgbm ? IBL_FORMAT_RGBM : st->is16 ? IBL_FORMAT_RGBA16_UNORM : IBL_FORMAT_RGBA8_SRGB;
    info->has_alpha = rgbm ? 0 : st->has_alpha; /* RGBM's alpha is the multiplier */
}

ibl_status ibl__png_info(ibl_context *ctx, const uint8_t *bytes, size_t size, const char *name,
                         ibl_file_info *info)
{
    ibl_status s;
    png_read_state *st = png_read(ctx, bytes, size, name, 1, NULL, &s);
    if (!st) return s;
    if (s == IBL_OK) {
        info->width = (int)st->width;
        info->height = (int)st->height;
        png_fill_info(info, png_is_rgbm(bytes, size, 0, st->is16), st);
    }
    ibl_free(ctx, st);
    return s;
}

ibl_status ibl__png_decode_as(ibl_context *ctx, const uint8_t *bytes, size_t size, const char *name,
                              int as_data, ibl_texture *out, ibl_file_info *info)
{
    ibl_status s;
    png_read_state *st = png_read(ctx, bytes, size, name, 0, out, &s);
    if (!st) return s;
    ibl_free(ctx, st->rows);
    int ok = s == IBL_OK;
    char range_text[32];
    int rgbm = png_is_rgbm(bytes, size, as_data, st->is16);
    if (ok && rgbm) {
        png_text_value(bytes, size, "ibl.rgbm_range", range_text, sizeof range_text);
        float range = (float)strtod(range_text, NULL);
        if (!(range > 0.0f && range <= 65504.0f)) range = IBL_RGBM_DEFAULT_RANGE;
        rgbm_samples_to_linear(st->raw, range, (size_t)out->width * (size_t)out->height, out->data);
    } else if (ok) {
        /* data (as_data) and gAMA 1.0 files: code / max, no curve */
        size_t texels = (size_t)out->width * (size_t)out->height;
        s = ibl__rgba_samples_to_linear(ctx, st->raw, st->is16,
                                        as_data ? 1.0 : png_decoding_power(bytes, size), texels,
                                        out->data, name);
    }
    if (s != IBL_OK) {
        ibl_texture_free(ctx, out);
    } else {
        png_fill_info(info, rgbm, st);
        out->format = info->format;
    }
    ibl_free(ctx, st);
    return s;
}

/* ---- 8-bit display encoding shared by the PNG and JPEG writers ----------------------- */

void ibl__display_encoder_init(ibl__display_encoder *d, const ibl_write_desc *desc)
{
    d->scale = exp2f(desc->exposure_ev);
    d->tonemap = desc->tonemap == IBL_TONEMAP_DEFAULT ? IBL_TONEMAP_FILMIC : desc->tonemap;
    for (int k = 0; k < 255; k++) d->level[k] = (float)srgb_to_linear((k + 0.5) / 255.0);
    d->level[255] = 2.0f; /* sentinel above every tone-mapped value */
    int code = 0;
    for (int b = 0; b <= IBL_DISPLAY_BUCKETS; b++) {
        float edge = (float)b / IBL_DISPLAY_BUCKETS;
        while (code < 255 && d->level[code] <= edge) code++;
        d->base[b] = (uint8_t)code;
    }
}

static uint8_t unit_code8(float a)
{
    if (!(a > 0.0f)) return 0;
    if (a >= 1.0f) return 255;
    return (uint8_t)(a * 255.0f + 0.5f);
}

static uint16_t unit_code16(float a)
{
    if (!(a > 0.0f)) return 0;
    if (a >= 1.0f) return 65535;
    return (uint16_t)((double)a * 65535.0 + 0.5);
}

static int image_has_alpha(const ibl_image *im)
{
    size_t n = (size_t)im->width * (size_t)im->height;
    for (size_t i = 0; i < n; i++)
        if (im->pixels[i * 4 + 3] != 1.0f) return 1;
    return 0;
}

/* ---- PNG writer (libpng) ------------------------------------------------------------- */

typedef struct png_state {
    ibl_context *ctx;
    uint8_t *buf;
    size_t len, cap;
    uint8_t *row;
    const uint8_t *raw; /* PNG_SAMPLES_RAW8: the RGBA rows */
    char error[200];
} png_state;

static void png_on_error(png_structp png, png_const_charp msg)
{
    png_state *st = png_get_error_ptr(png);
    snprintf(st->error, sizeof st->error, "%s", msg);
    png_longjmp(png, 1);
}

static void png_on_warning(png_structp png, png_const_charp msg)
{
    (void)png; /* the library never prints */
    (void)msg;
}

static void png_on_write(png_structp png, png_bytep data, size_t n)
{
    png_state *st = png_get_io_ptr(png);
    if (n > st->cap - st->len) {
        size_t ncap = st->cap ? st->cap : 65536;
        while (ncap - st->len < n) {
            if (ncap > SIZE_MAX / 2) png_error(png, "output too large");
            ncap *= 2;
        }
        uint8_t *grown = ibl_alloc(st->ctx, ncap);
        if (!grown) png_error(png, "out of memory");
        if (st->len) memcpy(grown, st->buf, st->len);
        ibl_free(st->ctx, st->buf);
        st->buf = grown;
        st->cap = ncap;
    }
    memcpy(st->buf + st->len, data, n);
    st->len += n;
}

static void png_on_flush(png_structp png)
{
    (void)png;
}

/* How the writer turns floats into samples. */
typedef enum png_samples {
    PNG_SAMPLES_DISPLAY8, /* exposure, tone map, sRGB (previews)                          */
    PNG_SAMPLES_LINEAR8,  /* round(v * 255), gAMA 1.0 (data)                              */
    PNG_SAMPLES_LINEAR16, /* round(v * 65535), gAMA 1.0 (tables, data)                    */
    PNG_SAMPLES_RGBM8,    /* RGBM (ibl/compress.h), gAMA 1.0, tEXt ibl.encoding = rgbm      */
    PNG_SAMPLES_RAW8      /* 8-bit RGBA bytes as given (png_state.raw), no colour chunk:
                             packed data such as Babylon's RGBD                            */
} png_samples;

static void png_fill_row(const float *src, int width, int channels, png_samples mode,
                         float rgbm_range, const ibl__display_encoder *enc, uint8_t *o)
{
    for (int x = 0; x < width; x++) {
        const float *p = src + (size_t)x * 4;
        if (mode == PNG_SAMPLES_RGBM8) {
            ibl_rgbm_encode(p, rgbm_range, o);
            o += 4;
            continue;
        }
        for (int c = 0; c < channels; c++) {
            if (mode == PNG_SAMPLES_LINEAR16) {
                uint16_t v = unit_code16(p[c]);
                *o++ = (uint8_t)(v >> 8); /* PNG samples are big-endian */
                *o++ = (uint8_t)(v & 0xFF);
            } else if (mode == PNG_SAMPLES_LINEAR8 || c == 3) {
                *o++ = unit_code8(p[c]);
            } else {
                *o++ = ibl__display_code(enc, p[c]);
            }
        }
    }
}

/* Runs libpng; everything it may touch after setjmp lives in *st (not in locals). */
static int png_run(png_state *st, const ibl_image *im, png_samples mode, int channels,
                   float rgbm_range, const ibl__display_encoder *enc)
{
    int sixteen = mode == PNG_SAMPLES_LINEAR16;
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, st, png_on_error, png_on_warning);
    if (!png) {
        snprintf(st->error, sizeof st->error, "cannot start libpng");
        return 0;
    }
    png_infop pinfo = png_create_info_struct(png);
    if (!pinfo) {
        png_destroy_write_struct(&png, NULL);
        snprintf(st->error, sizeof st->error, "cannot start libpng");
        return 0;
    }
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, &pinfo);
        return 0;
    }
    png_set_write_fn(png, st, png_on_write, png_on_flush);
    png_set_IHDR(png, pinfo, (png_uint_32)im->width, (png_uint_32)im->height, sixteen ? 16 : 8,
                 channels == 4 ? PNG_COLOR_TYPE_RGBA : PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    if (mode == PNG_SAMPLES_DISPLAY8) png_set_sRGB_gAMA_and_cHRM(png, pinfo, PNG_sRGB_INTENT_PERCEPTUAL);
    else if (mode != PNG_SAMPLES_RAW8) png_set_gAMA(png, pinfo, 1.0); /* read back without a curve */
    char range_text[32];
    png_text text[2];
    if (mode == PNG_SAMPLES_RGBM8) {
        /* the KTX2 writer's key names (src/io/ktx2.c), so either file says what it holds */
        snprintf(range_text, sizeof range_text, "%.9g", (double)rgbm_range);
        memset(text, 0, sizeof text);
        text[0].compression = text[1].compression = PNG_TEXT_COMPRESSION_NONE;
        text[0].key = (png_charp) "ibl.encoding";
        text[0].text = (png_charp) "rgbm";
        text[1].key = (png_charp) "ibl.rgbm_range";
        text[1].text = range_text;
        png_set_text(png, pinfo, text, 2);
    }
    /* Fast settings (zlib level 3, Paeth filter only): about twice as fast as libpng's
     * defaults for ~3% larger files (docs/PERFORMANCE.md). */
    png_set_compression_level(png, 3);
    png_set_filter(png, 0, PNG_FILTER_PAETH);
    png_write_info(png, pinfo);
    for (int y = 0; y < im->height; y++) {
        if (mode == PNG_SAMPLES_RAW8) {
            png_write_row(png, (png_bytep)(st->raw + (size_t)y * (size_t)im->width * 4));
            continue;
        }
        png_fill_row(im->pixels + (size_t)y * (size_t)im->width * 4, im->width, channels, mode,
                     rgbm_range, enc, st->row);
        png_write_row(png, st->row);
    }
    png_write_end(png, pinfo);
    png_destroy_write_struct(&png, &pinfo);
    return 1;
}

ibl_status ibl__png_encode(ibl_context *ctx, const ibl_image *image, const ibl_write_desc *desc,
                           const char *name, void **bytes, size_t *size)
{
    png_samples mode;
    if (desc->format == IBL_FORMAT_DEFAULT || desc->format == IBL_FORMAT_RGBA8_SRGB) mode = PNG_SAMPLES_DISPLAY8;
    else if (desc->format == IBL_FORMAT_RGBA8_UNORM) mode = PNG_SAMPLES_LINEAR8;
    else if (desc->format == IBL_FORMAT_RGBA16_UNORM) mode = PNG_SAMPLES_LINEAR16;
    else if (desc->format == IBL_FORMAT_RGBM) mode = PNG_SAMPLES_RGBM8;
    else
        return ibl__fail(ctx, IBL_ERR_UNSUPPORTED,
                        "%s: PNG stores rgba8 (sRGB preview), rgba8-linear, rgba16 (linear) or "
                        "rgbm, not %s", name, ibl_format_name(desc->format));
    int sixteen = mode == PNG_SAMPLES_LINEAR16;
    float rgbm_range = desc->rgbm_range > 0.0f ? desc->rgbm_range : IBL_RGBM_DEFAULT_RANGE;
    if (image->width > IBL_MAX_DIMENSION || image->height > IBL_MAX_DIMENSION)
        return ibl__fail(ctx, IBL_ERR_TOO_LARGE, "%s: image %dx%d too large", name, image->width,
                        image->height);
    int channels = mode == PNG_SAMPLES_RGBM8 || image_has_alpha(image) ? 4 : 3;
    png_state *st = ibl_calloc(ctx, 1, sizeof *st);
    if (!st) return ibl__fail_named(ctx, ibl_context_status(ctx), name);
    st->ctx = ctx;
    st->row = ibl_alloc(ctx, (size_t)image->width * (size_t)channels * (sixteen ? 2 : 1));
    if (!st->row) {
        ibl_free(ctx, st);
        return ibl__fail_named(ctx, ibl_context_status(ctx), name);
    }
    ibl__display_encoder enc;
    ibl__display_encoder_init(&enc, desc);
    int ok = png_run(st, image, mode, channels, rgbm_range, &enc);
    ibl_free(ctx, st->row);
    if (!ok) {
        ibl_free(ctx, st->buf);
        ibl_status s = strcmp(st->error, "out of memory") == 0 ? IBL_ERR_OUT_OF_MEMORY : IBL_ERR_IO;
        ibl__fail(ctx, s, "%s: cannot encode PNG: %s", name, st->error);
        ibl_free(ctx, st);
        return s;
    }
    *bytes = st->buf;
    *size = st->len;
    ibl_free(ctx, st);
    return IBL_OK;
}

ibl_status ibl__png_encode_rgba8(ibl_context *ctx, const uint8_t *rgba, int width, int height,
                                 const char *name, void **bytes, size_t *size)
{
    ibl_image shape = {width, height, NULL};
    png_state *st = ibl_calloc(ctx, 1, sizeof *st);
    if (!st) return ibl__fail_named(ctx, ibl_context_status(ctx), name);
    st->ctx = ctx;
    st->raw = rgba;
    int ok = png_run(st, &shape, PNG_SAMPLES_RAW8, 4, 0.0f, NULL);
    if (!ok) {
        ibl_free(ctx, st->buf);
        ibl_status s = strcmp(st->error, "out of memory") == 0 ? IBL_ERR_OUT_OF_MEMORY : IBL_ERR_IO;
        ibl__fail(ctx, s, "%s: cannot encode PNG: %s", name, st->error);
        ibl_free(ctx, st);
        return s;
    }
    *bytes = st->buf;
    *size = st->len;
    ibl_free(ctx, st);
    return IBL_OK;
}
