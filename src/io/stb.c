/* PNG and JPEG. PNG goes through libpng both ways (8-bit and 16-bit; stb_image_write cannot
 * write 16-bit, and stb_image's reader is unbounded on hostile input, see png_decode). JPEG
 * goes through stb_image (its JPEG decoder compiled below) and stb_image_write (libstb):
 * baseline and progressive, written for previews.
 *
 * Transfer functions on read: JPEG is sRGB. A PNG with an sRGB chunk is sRGB; one with only
 * a gAMA chunk uses that power law (gAMA 1.0 = linear, which is how the 16-bit tables are
 * written); one with neither is sRGB. iCCP profiles are not interpreted. Alpha is linear.
 * The sRGB curve is the exact piecewise function of IEC 61966-2-1. */
#include "io/io_internal.h"
#include "core/context_internal.h"

#include <limits.h>
#include <math.h>
#include <png.h>
#include <stdlib.h>
#include <stb_image_write.h>

/* stb_image's JPEG decoder, compiled here from Debian's header (v2.27) rather than taken
 * from libstb.a: its other decoders (GIF, TGA, PSD...) are left out, and its allocations
 * are zeroed, since v2.27 reads fields of its decoder state (Huffman and quantisation tables)
 * that a corrupt file never defines: the pixels then depended on the heap's old contents
 * (fuzzing found a 677-byte file decoding differently from one run to the next). */
#define STB_IMAGE_STATIC
#define STB_IMAGE_IMPLEMENTATION
#define STBI_ONLY_JPEG
#define STBI_NO_STDIO
#define STBI_MALLOC(size) calloc(1, size)
#define STBI_REALLOC(p, size) realloc(p, size)
#define STBI_FREE(p) free(p)
#if defined(__GNUC__)
/* for the whole file: GCC checks static declarations left unused at its end */
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wsign-compare"
#pragma GCC diagnostic ignored "-Wunused-parameter"
#pragma GCC diagnostic ignored "-Wimplicit-fallthrough"
#endif
#include <stb_image.h>
#if defined(__GNUC__)
#pragma GCC diagnostic pop
#endif
#include <stdio.h>
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

/* Decoded samples (RGBA; 8-bit, or 16-bit big-endian as PNG stores them) to linear float.
 * The samples may lie in the tail of dst itself (the PNG reader decodes there): texel i is
 * read whole before it is written, and its float lands at or before samples not yet read. */
static ibl_status samples_to_float(ibl_context *ctx, const uint8_t *pix, int is16, double power,
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

static ibl_status png_decode(ibl_context *ctx, const uint8_t *bytes, size_t size, const char *name,
                             ibl_texture *out, ibl_file_info *info)
{
    if (!png_chunks_inside(bytes, size))
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: truncated PNG (a chunk runs past the end of the file)", name);
    png_read_state *st = ibl_calloc(ctx, 1, sizeof *st);
    if (!st) return ibl__fail_named(ctx, ibl_context_status(ctx), name);
    st->ctx = ctx;
    st->name = name;
    st->data = bytes;
    st->size = size;
    st->out = out;
    int ok = png_read_run(st);
    ibl_free(ctx, st->rows);
    ibl_status s = IBL_OK;
    if (!ok) {
        if (st->status == IBL_ERR_FORMAT) s = st->status; /* its message names the file */
        else if (st->status != IBL_OK) s = ibl__fail_named(ctx, st->status, name);
        else s = ibl__fail(ctx, IBL_ERR_FORMAT, "%s: corrupt PNG (%s)", name, st->error);
    } else {
        size_t texels = (size_t)out->width * (size_t)out->height;
        s = samples_to_float(ctx, st->raw, st->is16, png_decoding_power(bytes, size), texels,
                             out->data, name);
    }
    if (s != IBL_OK) {
        ibl_texture_free(ctx, out);
    } else {
        out->format = st->is16 ? IBL_FORMAT_RGBA16_UNORM : IBL_FORMAT_RGBA8_SRGB;
        info->format = out->format;
        info->has_alpha = st->has_alpha;
    }
    ibl_free(ctx, st);
    return s;
}

/* ---- JPEG reader (stb_image) --------------------------------------------------------- */

/* What the frame header (SOFn) of a JPEG declares, and where it ends. */
typedef struct jpeg_frame {
    int huffman;                    /* SOF0, SOF1 or SOF2: the codings stb_image decodes */
    int progressive;
    uint32_t width, height;
    int components;
    int h[4], v[4];                 /* sampling factors of the first four components */
    size_t end;                     /* offset of the first byte after the frame header */
} jpeg_frame;

/* Walks the marker segments from SOI to the first frame header; 0 if there is none. */
static int jpeg_find_frame(const uint8_t *b, size_t size, jpeg_frame *f)
{
    memset(f, 0, sizeof *f);
    size_t pos = 2; /* after SOI */
    while (pos + 4 <= size) {
        if (b[pos] != 0xFF) { /* padding between segments, which stb_image skips too */
            pos++;
            continue;
        }
        uint8_t m = b[pos + 1];
        if (m == 0xFF) { /* fill byte */
            pos++;
            continue;
        }
        if (m == 0x01 || (m >= 0xD0 && m <= 0xD8)) { /* markers without a length */
            pos += 2;
            continue;
        }
        if (m == 0xD9 || m == 0xDA) return 0; /* EOI or a scan before any frame */
        size_t len = (size_t)b[pos + 2] << 8 | b[pos + 3];
        if (len < 2 || len > size - pos - 2) return 0;
        int sof = m >= 0xC0 && m <= 0xCF && m != 0xC4 && m != 0xC8 && m != 0xCC;
        if (sof) {
            const uint8_t *p = b + pos + 4;
            if (len < 8) return 0;
            f->huffman = m <= 0xC2;
            f->progressive = m == 0xC2;
            f->height = (uint32_t)p[1] << 8 | p[2];
            f->width = (uint32_t)p[3] << 8 | p[4];
            f->components = p[5];
            if (f->components < 1 || len < 8 + 3 * (size_t)f->components) return 0;
            for (int c = 0; c < f->components && c < 4; c++) {
                f->h[c] = p[6 + 3 * c + 1] >> 4;
                f->v[c] = p[6 + 3 * c + 1] & 15;
                if (f->h[c] < 1 || f->v[c] < 1) return 0;
            }
            f->end = pos + 2 + len;
            return 1;
        }
        pos += 2 + len;
    }
    return 0;
}

/* The fewest bytes of entropy-coded data that can hold a frame: every 8x8 block of every
 * component is coded, and a Huffman-coded block takes at least one bit (its DC difference's
 * code; a baseline block also needs an end-of-block code). The component with the most blocks
 * bounds it from below, whatever the other components hold. */
static uint64_t jpeg_min_coded_bytes(const jpeg_frame *f)
{
    int hmax = 1, vmax = 1, n = f->components < 4 ? f->components : 4;
    for (int c = 0; c < n; c++) {
        if (f->h[c] > hmax) hmax = f->h[c];
        if (f->v[c] > vmax) vmax = f->v[c];
    }
    uint64_t most = 0;
    for (int c = 0; c < n; c++) {
        uint64_t cw = ((uint64_t)f->width * (uint64_t)f->h[c] + (uint64_t)hmax - 1) / (uint64_t)hmax;
        uint64_t ch = ((uint64_t)f->height * (uint64_t)f->v[c] + (uint64_t)vmax - 1) / (uint64_t)vmax;
        uint64_t blocks = ((cw + 7) / 8) * ((ch + 7) / 8);
        if (blocks > most) most = blocks;
    }
    return most / 8;
}

/* What stb_image allocates itself to decode a w x h JPEG to 4 channels, from its source
 * (stbi__jpeg: one plane per component padded to whole MCUs of at most 32x32 pixels, the
 * 16-bit coefficients of every block when progressive, the output), with the line buffers
 * and tables rounded up into 1 MiB. */
static uint64_t jpeg_stb_bytes(const jpeg_frame *f)
{
    uint64_t pw = ((uint64_t)f->width + 31) / 32 * 32, ph = ((uint64_t)f->height + 31) / 32 * 32;
    uint64_t planes = pw * ph * (uint64_t)f->components;
    return planes + (f->progressive ? 2 * planes : 0) + 4 * (uint64_t)f->width * f->height + ((uint64_t)1 << 20);
}

/* What stb_image reads as a DHT segment at b[p] (0xFF 0xC4): its length, then tables of a
 * class/id byte, 16 code counts and that many symbols until the length is used up, reading
 * zeros past the end of the data. 0 if a table has more than 256 codes: Debian's stb_image
 * (2022-09-08) does not check, and writes them past its 257-entry size table and 256-entry
 * symbol table (fuzzing found a 656-byte file doing so). */
static int jpeg_dht_ok(const uint8_t *b, size_t size, size_t p)
{
    size_t q = p + 4;
    long left = p + 3 < size ? (long)(b[p + 2] << 8 | b[p + 3]) - 2 : 0;
    while (left > 0) {
        long n = 0;
        for (size_t i = 1; i <= 16; i++) n += q + i < size ? b[q + i] : 0;
        if (n > 256) return 0;
        q += 17 + (size_t)n;
        left -= 17 + n;
    }
    return 1;
}

/* 0 if stb_image could meet a Huffman table with more than 256 codes in this file. Up to the
 * first scan, markers (0xFF, fill bytes 0xFF, the code) and segments are followed by their
 * lengths as stb_image reads them; from where that walk stops, entropy-coded data and
 * segments alternate, so every 0xFF 0xC4 is checked as a possible table. */
static int jpeg_huffman_tables_ok(const uint8_t *b, size_t size)
{
    size_t pos = 0;
    while (pos + 1 < size && b[pos] == 0xFF) {
        while (pos + 2 < size && b[pos + 1] == 0xFF) pos++; /* fill bytes */
        uint8_t m = b[pos + 1];
        if (m == 0xC4 && !jpeg_dht_ok(b, size, pos)) return 0;
        if (m == 0xD8) { /* SOI: no length */
            pos += 2;
            continue;
        }
        if (m == 0xDA || m == 0xD9 || pos + 3 >= size) break;
        pos += 2 + (size_t)(b[pos + 2] << 8 | b[pos + 3]);
    }
    for (; pos + 1 < size; pos++)
        if (b[pos] == 0xFF && b[pos + 1] == 0xC4 && !jpeg_dht_ok(b, size, pos)) return 0;
    return 1;
}

ibl_status ibl__stb_decode(ibl_context *ctx, const uint8_t *bytes, size_t size, const char *name,
                           ibl_texture *out, ibl_file_info *info)
{
    if (size >= 8 && bytes[0] == 0x89 && bytes[1] == 'P') return png_decode(ctx, bytes, size, name, out, info);
    if (size > INT_MAX) return ibl__fail(ctx, IBL_ERR_TOO_LARGE, "%s: JPEG file too large", name);
    if (!jpeg_huffman_tables_ok(bytes, size))
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: corrupt JPEG (Huffman table of more than 256 codes)", name);
    int w = 0, h = 0, comp = 0;
    if (!stbi_info_from_memory(bytes, (int)size, &w, &h, &comp))
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: bad JPEG header (%s)", name, stbi_failure_reason());
    if (w <= 0 || h <= 0 || w > IBL_MAX_DIMENSION || h > IBL_MAX_DIMENSION)
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: absurd JPEG image size %dx%d", name, w, h);
    /* stb_image decodes whatever the header declares and fills missing data with grey: a
     * few kilobytes claiming 16000x8000 would cost gigabytes. The file must be able to hold
     * the declared size, and the decoding must fit the budget, before anything is allocated. */
    jpeg_frame frame;
    if (!jpeg_find_frame(bytes, size, &frame) || frame.width != (uint32_t)w || frame.height != (uint32_t)h)
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: bad JPEG header (no frame header before the first scan)", name);
    uint64_t coded = jpeg_min_coded_bytes(&frame);
    if (frame.huffman && size - frame.end < coded)
        return ibl__fail(ctx, IBL_ERR_FORMAT,
                         "%s: a %dx%d JPEG needs at least %llu bytes of coded data, the file has %zu "
                         "after its header (truncated, or a forged size)",
                         name, w, h, (unsigned long long)coded, size - frame.end);
    uint64_t stb_bytes = jpeg_stb_bytes(&frame);
    ibl_status s = ibl__budget_check(ctx, stb_bytes + (uint64_t)w * (uint64_t)h * 4 * sizeof(float));
    if (s != IBL_OK) return ibl__fail_named(ctx, s, name);
    s = ibl_texture_alloc(ctx, IBL_TEXTURE_2D, w, h, 1, 1, out);
    if (s != IBL_OK) return ibl__fail_named(ctx, s, name);
    s = ibl__budget_reserve(ctx, stb_bytes);
    if (s != IBL_OK) {
        ibl_texture_free(ctx, out);
        return ibl__fail_named(ctx, s, name);
    }
    int lw = 0, lh = 0, lc = 0;
    uint8_t *pix = stbi_load_from_memory(bytes, (int)size, &lw, &lh, &lc, 4);
    ibl__budget_release(ctx, stb_bytes - 4 * (uint64_t)w * (uint64_t)h); /* its output remains */
    if (!pix || lw != w || lh != h) {
        ibl__budget_release(ctx, 4 * (uint64_t)w * (uint64_t)h);
        if (pix) stbi_image_free(pix);
        ibl_texture_free(ctx, out);
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: corrupt JPEG data (%s)", name,
                        pix ? "size changed" : stbi_failure_reason());
    }
    s = samples_to_float(ctx, pix, 0, 0.0, (size_t)w * (size_t)h, out->data, name);
    stbi_image_free(pix);
    ibl__budget_release(ctx, 4 * (uint64_t)w * (uint64_t)h);
    if (s != IBL_OK) {
        ibl_texture_free(ctx, out);
        return s;
    }
    out->format = IBL_FORMAT_RGBA8_SRGB;
    info->format = out->format;
    info->has_alpha = 0;
    return IBL_OK;
}

/* ---- 8-bit display encoding shared by the PNG and JPEG writers ----------------------- */

/* Exposure, tone map and sRGB encoding to the nearest 8-bit code, without a pow per channel:
 * the code is the number of decision levels (the linear values whose sRGB encoding is k + 0.5
 * codes) at or below the value, i.e. round(oetf(t) * 255). A 4096-bucket table gives the
 * count at each bucket's lower edge; levels are at least 1 / (255 * 12.92) = 3.0e-4 apart
 * (the steepest, linear part of the curve) and buckets 2.4e-4 wide, so at most one more
 * level can lie inside a bucket: one comparison finishes the job. */
enum { DISPLAY_BUCKETS = 4096 };

typedef struct display_encoder {
    float scale;
    ibl_tonemap tonemap;
    float level[256];                     /* level[k]: smallest value encoding to k + 1 */
    uint8_t base[DISPLAY_BUCKETS + 1];    /* levels <= bucket / DISPLAY_BUCKETS */
} display_encoder;

static void display_encoder_init(display_encoder *d, float exposure_ev, ibl_tonemap tm)
{
    d->scale = exp2f(exposure_ev);
    d->tonemap = tm;
    for (int k = 0; k < 255; k++) d->level[k] = (float)srgb_to_linear((k + 0.5) / 255.0);
    d->level[255] = 2.0f; /* sentinel above every tone-mapped value */
    int code = 0;
    for (int b = 0; b <= DISPLAY_BUCKETS; b++) {
        float edge = (float)b / DISPLAY_BUCKETS;
        while (code < 255 && d->level[code] <= edge) code++;
        d->base[b] = (uint8_t)code;
    }
}

static uint8_t display_code(const display_encoder *d, float linear)
{
    float t = ibl_tonemap_apply(d->tonemap, linear * d->scale); /* in [0, 1] */
    int code = d->base[(int)(t * DISPLAY_BUCKETS)];
    return (uint8_t)(code + (d->level[code] <= t));
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

static ibl_tonemap preview_tonemap(const ibl_write_desc *desc)
{
    return desc->tonemap == IBL_TONEMAP_DEFAULT ? IBL_TONEMAP_FILMIC : desc->tonemap;
}

/* ---- PNG writer (libpng) ------------------------------------------------------------- */

typedef struct png_state {
    ibl_context *ctx;
    uint8_t *buf;
    size_t len, cap;
    uint8_t *row;
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

/* Runs libpng; everything it may touch after setjmp lives in *st (not in locals). */
static int png_run(png_state *st, const ibl_image *im, int sixteen, int channels,
                   const display_encoder *enc)
{
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
    if (sixteen) png_set_gAMA(png, pinfo, 1.0); /* linear: read back without a curve */
    else png_set_sRGB_gAMA_and_cHRM(png, pinfo, PNG_sRGB_INTENT_PERCEPTUAL);
    /* Fast settings (zlib level 3, Paeth filter only): about twice as fast as libpng's
     * defaults for ~3% larger files (docs/PERFORMANCE.md). */
    png_set_compression_level(png, 3);
    png_set_filter(png, 0, PNG_FILTER_PAETH);
    png_write_info(png, pinfo);
    for (int y = 0; y < im->height; y++) {
        const float *src = im->pixels + (size_t)y * (size_t)im->width * 4;
        uint8_t *o = st->row;
        for (int x = 0; x < im->width; x++) {
            const float *p = src + (size_t)x * 4;
            for (int c = 0; c < channels; c++) {
                if (sixteen) {
                    uint16_t v = unit_code16(p[c]);
                    *o++ = (uint8_t)(v >> 8); /* PNG samples are big-endian */
                    *o++ = (uint8_t)(v & 0xFF);
                } else {
                    *o++ = c == 3 ? unit_code8(p[3]) : display_code(enc, p[c]);
                }
            }
        }
        png_write_row(png, st->row);
    }
    png_write_end(png, pinfo);
    png_destroy_write_struct(&png, &pinfo);
    return 1;
}

ibl_status ibl__png_encode(ibl_context *ctx, const ibl_image *image, const ibl_write_desc *desc,
                           const char *name, void **bytes, size_t *size)
{
    int sixteen;
    if (desc->format == IBL_FORMAT_DEFAULT || desc->format == IBL_FORMAT_RGBA8_SRGB) sixteen = 0;
    else if (desc->format == IBL_FORMAT_RGBA16_UNORM) sixteen = 1;
    else
        return ibl__fail(ctx, IBL_ERR_UNSUPPORTED,
                        "%s: PNG stores rgba8 (sRGB preview) or rgba16 (linear), not %s", name,
                        ibl_format_name(desc->format));
    if (image->width > IBL_MAX_DIMENSION || image->height > IBL_MAX_DIMENSION)
        return ibl__fail(ctx, IBL_ERR_TOO_LARGE, "%s: image %dx%d too large", name, image->width,
                        image->height);
    int channels = image_has_alpha(image) ? 4 : 3;
    png_state *st = ibl_calloc(ctx, 1, sizeof *st);
    if (!st) return ibl__fail_named(ctx, ibl_context_status(ctx), name);
    st->ctx = ctx;
    st->row = ibl_alloc(ctx, (size_t)image->width * (size_t)channels * (sixteen ? 2 : 1));
    if (!st->row) {
        ibl_free(ctx, st);
        return ibl__fail_named(ctx, ibl_context_status(ctx), name);
    }
    display_encoder enc;
    display_encoder_init(&enc, desc->exposure_ev, preview_tonemap(desc));
    int ok = png_run(st, image, sixteen, channels, &enc);
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

/* ---- JPEG writer (stb_image_write) --------------------------------------------------- */

typedef struct jpeg_sink {
    ibl_context *ctx;
    uint8_t *buf;
    size_t len, cap;
    int failed;
} jpeg_sink;

static void jpeg_on_write(void *user, void *data, int n)
{
    jpeg_sink *s = user;
    if (s->failed || n <= 0) return;
    if ((size_t)n > s->cap - s->len) {
        size_t ncap = s->cap ? s->cap * 2 : 65536;
        while (ncap - s->len < (size_t)n) ncap *= 2;
        uint8_t *grown = ibl_alloc(s->ctx, ncap);
        if (!grown) {
            s->failed = 1;
            return;
        }
        if (s->len) memcpy(grown, s->buf, s->len);
        ibl_free(s->ctx, s->buf);
        s->buf = grown;
        s->cap = ncap;
    }
    memcpy(s->buf + s->len, data, (size_t)n);
    s->len += (size_t)n;
}

ibl_status ibl__jpeg_encode(ibl_context *ctx, const ibl_image *image, const ibl_write_desc *desc,
                            const char *name, void **bytes, size_t *size)
{
    if (desc->format != IBL_FORMAT_DEFAULT && desc->format != IBL_FORMAT_RGBA8_SRGB)
        return ibl__fail(ctx, IBL_ERR_UNSUPPORTED, "%s: JPEG stores only 8-bit sRGB, not %s", name,
                        ibl_format_name(desc->format));
    int w = image->width, h = image->height;
    if (w > 65535 || h > 65535)
        return ibl__fail(ctx, IBL_ERR_TOO_LARGE, "%s: JPEG is limited to 65535 pixels a side", name);
    size_t n = (size_t)w * (size_t)h;
    uint8_t *rgb = ibl_alloc(ctx, n * 3);
    if (!rgb) return ibl__fail_named(ctx, ibl_context_status(ctx), name);
    display_encoder enc;
    display_encoder_init(&enc, desc->exposure_ev, preview_tonemap(desc));
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < 3; c++) rgb[i * 3 + (size_t)c] = display_code(&enc, image->pixels[i * 4 + (size_t)c]);
    jpeg_sink sink = {ctx, NULL, 0, 0, 0};
    int ok = stbi_write_jpg_to_func(jpeg_on_write, &sink, w, h, 3, rgb, 95);
    ibl_free(ctx, rgb);
    if (!ok || sink.failed) {
        ibl_free(ctx, sink.buf);
        return ibl__fail(ctx, sink.failed ? IBL_ERR_OUT_OF_MEMORY : IBL_ERR_IO,
                        "%s: cannot encode JPEG", name);
    }
    *bytes = sink.buf;
    *size = sink.len;
    return IBL_OK;
}
