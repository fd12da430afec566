/* Radiance RGBE (.hdr, .pic), after Ward, "Real Pixels" (Graphics Gems II, 1991) and the
 * Radiance file format notes: a text header ended by an empty line, a resolution string,
 * then scanlines of 4-byte RGBE pixels, flat, old-style run-length or new-style per-channel
 * run-length encoded.
 *
 * Pixel value: (m + 0.5) * 2^(e - 136) for e != 0, else 0, exactly as Radiance's colr_color;
 * the encoder truncates (Radiance's setcolr), so decoding returns the centre of the bucket.
 * EXPOSURE= lines are ignored (as stb_image, OpenImageIO and most tools do): the values are
 * returned as stored. Only FORMAT=32-bit_rle_rgbe is accepted (XYZE is refused). */
#include "io/io_internal.h"
#include "core/context_internal.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* ---- header -------------------------------------------------------------------------- */

typedef struct hdr_layout {
    int width, height;
    int flip_x, flip_y; /* stored right-to-left / bottom-to-top */
    size_t data_offset;
} hdr_layout;

/* The next line of the header: [*pos, returned end), and *pos moves past its '\n'. */
static const uint8_t *next_line(const uint8_t *b, size_t size, size_t *pos, size_t *len)
{
    const uint8_t *start = b + *pos;
    const uint8_t *nl = memchr(start, '\n', size - *pos);
    if (!nl) return NULL;
    *len = (size_t)(nl - start);
    *pos += *len + 1;
    return start;
}

static int line_is(const uint8_t *line, size_t len, const char *prefix)
{
    size_t n = strlen(prefix);
    return len >= n && memcmp(line, prefix, n) == 0;
}

/* Parses "<sign><axis> <number>" from a resolution string. */
static int parse_axis(const uint8_t *s, size_t len, size_t *i, char *sign, char *axis, long *value)
{
    while (*i < len && s[*i] == ' ') (*i)++;
    if (*i + 2 > len) return 0;
    *sign = (char)s[*i];
    *axis = (char)s[*i + 1];
    if ((*sign != '+' && *sign != '-') || (*axis != 'X' && *axis != 'Y')) return 0;
    *i += 2;
    size_t spaces = 0;
    while (*i < len && s[*i] == ' ') {
        (*i)++;
        spaces++;
    }
    if (!spaces || *i >= len || s[*i] < '0' || s[*i] > '9') return 0;
    long v = 0;
    while (*i < len && s[*i] >= '0' && s[*i] <= '9') {
        if (v <= 100000000L) v = v * 10 + (s[*i] - '0'); /* saturate: absurd either way */
        (*i)++;
    }
    *value = v;
    return 1;
}

static ibl_status parse_header(ibl_context *ctx, const uint8_t *b, size_t size, const char *name,
                               hdr_layout *lay)
{
    memset(lay, 0, sizeof *lay);
    if (size < 2 || b[0] != '#' || b[1] != '?')
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: not a Radiance file (no \"#?\" signature)", name);
    size_t pos = 0, len = 0;
    const uint8_t *line = next_line(b, size, &pos, &len); /* "#?RADIANCE" */
    if (!line) return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: truncated Radiance header", name);
    for (;;) {
        line = next_line(b, size, &pos, &len);
        if (!line)
            return ibl__fail(ctx, IBL_ERR_FORMAT,
                            "%s: truncated Radiance header (no empty line before the resolution)",
                            name);
        if (len && line[len - 1] == '\r') len--;
        if (len == 0) break;
        if (line_is(line, len, "FORMAT=")) {
            const uint8_t *v = line + 7;
            size_t vl = len - 7;
            while (vl && (v[vl - 1] == ' ' || v[vl - 1] == '\t')) vl--;
            if (vl == 15 && memcmp(v, "32-bit_rle_rgbe", 15) == 0) continue;
            if (vl == 15 && memcmp(v, "32-bit_rle_xyze", 15) == 0)
                return ibl__fail(ctx, IBL_ERR_UNSUPPORTED,
                                "%s: XYZE Radiance files are not supported (only RGBE)", name);
            return ibl__fail(ctx, IBL_ERR_UNSUPPORTED, "%s: unknown Radiance FORMAT \"%.*s\"", name,
                            (int)(vl > 40 ? 40 : vl), (const char *)v);
        }
        /* EXPOSURE, PRIMARIES, COLORCORR, comments, program lines: ignored. */
    }
    line = next_line(b, size, &pos, &len);
    if (!line) return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: truncated Radiance resolution line", name);
    if (len && line[len - 1] == '\r') len--;
    size_t i = 0;
    char s1, a1, s2, a2;
    long v1, v2;
    if (!parse_axis(line, len, &i, &s1, &a1, &v1) || !parse_axis(line, len, &i, &s2, &a2, &v2) ||
        a1 == a2)
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: bad Radiance resolution line \"%.*s\"", name,
                        (int)(len > 40 ? 40 : len), (const char *)line);
    if (a1 == 'X')
        return ibl__fail(ctx, IBL_ERR_UNSUPPORTED,
                        "%s: column-major Radiance orientation \"%.*s\" is not supported "
                        "(expected \"-Y H +X W\")",
                        name, (int)(len > 40 ? 40 : len), (const char *)line);
    if (v1 <= 0 || v2 <= 0 || v1 > IBL_MAX_DIMENSION || v2 > IBL_MAX_DIMENSION)
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: absurd Radiance image size %ldx%ld", name, v2, v1);
    lay->height = (int)v1;
    lay->width = (int)v2;
    lay->flip_y = s1 == '+';
    lay->flip_x = s2 == '-';
    lay->data_offset = pos;
    return IBL_OK;
}

ibl_status ibl__hdr_info(ibl_context *ctx, const uint8_t *bytes, size_t size, const char *name,
                         ibl_file_info *info)
{
    hdr_layout lay;
    ibl_status s = parse_header(ctx, bytes, size, name, &lay);
    if (s != IBL_OK) return s;
    info->width = lay.width;
    info->height = lay.height;
    info->format = IBL_FORMAT_RGBE; /* as ibl__hdr_decode reports */
    info->has_alpha = 0;
    return IBL_OK;
}

/* ---- scanlines ----------------------------------------------------------------------- */

/* Decodes one scanline of w pixels into scan (4w bytes); NULL or the problem. */
static const char *read_scanline(const uint8_t **cursor, const uint8_t *end, int w, uint8_t *scan)
{
    const uint8_t *p = *cursor;
    static const char *truncated = "truncated pixel data";
    /* New-style RLE: 2, 2, width (15 bits big-endian), then each channel run-length coded. */
    if (w >= 8 && w <= 0x7fff && end - p >= 4 && p[0] == 2 && p[1] == 2 && !(p[2] & 0x80)) {
        if ((p[2] << 8 | p[3]) != w) return "run-length scanline width differs from the image width";
        p += 4;
        for (int c = 0; c < 4; c++) {
            int x = 0;
            while (x < w) {
                if (p >= end) return truncated;
                int code = *p++;
                if (code > 128) {
                    int n = code - 128;
                    if (n > w - x) return "run-length run overflows the scanline";
                    if (p >= end) return truncated;
                    uint8_t v = *p++;
                    for (int k = 0; k < n; k++) scan[(size_t)(x + k) * 4 + (size_t)c] = v;
                    x += n;
                } else {
                    int n = code;
                    if (n > w - x) return "run-length literal overflows the scanline";
                    if (end - p < n) return truncated;
                    for (int k = 0; k < n; k++) scan[(size_t)(x + k) * 4 + (size_t)c] = p[k];
                    p += n;
                    x += n;
                }
            }
        }
        *cursor = p;
        return NULL;
    }
    /* Flat pixels, with old-style RLE: (1,1,1,n) repeats the previous pixel n << shift times,
     * the shift growing by 8 for each consecutive repeat record. */
    int x = 0, shift = 0;
    while (x < w) {
        if (end - p < 4) return truncated;
        if (p[0] == 1 && p[1] == 1 && p[2] == 1) {
            if (x == 0) return "old-style repeat record at the start of a scanline";
            if (shift > 16) return "old-style repeat count too large";
            uint32_t n = (uint32_t)p[3] << shift;
            if (n > (uint32_t)(w - x)) return "old-style repeat overflows the scanline";
            for (uint32_t k = 0; k < n; k++) memcpy(scan + (size_t)(x + (int)k) * 4, scan + (size_t)(x - 1) * 4, 4);
            x += (int)n;
            shift += 8;
        } else {
            memcpy(scan + (size_t)x * 4, p, 4);
            x++;
            shift = 0;
        }
        p += 4;
    }
    *cursor = p;
    return NULL;
}

ibl_status ibl__hdr_decode(ibl_context *ctx, const uint8_t *bytes, size_t size, const char *name,
                           ibl_texture *out, ibl_file_info *info)
{
    hdr_layout lay;
    ibl_status s = parse_header(ctx, bytes, size, name, &lay);
    if (s != IBL_OK) return s;
    int w = lay.width, h = lay.height;
    /* Before pass 1 reads the whole file: every scanline takes at least one 4-byte group (a
     * pixel, a repeat record or a run-length header), and the image must fit the budget. */
    if ((size - lay.data_offset) / 4 < (size_t)h)
        return ibl__fail(ctx, IBL_ERR_FORMAT,
                         "%s: %zu bytes of pixel data cannot hold %d scanlines (truncated, or a "
                         "forged size)",
                         name, size - lay.data_offset, h);
    s = ibl__budget_check(ctx, ((uint64_t)w * (uint64_t)h + (uint64_t)w) * 4 * sizeof(float));
    if (s != IBL_OK) return ibl__fail_named(ctx, s, name);
    uint8_t *scan = ibl_alloc(ctx, (size_t)w * 4);
    if (!scan) return ibl__fail_named(ctx, ibl_context_status(ctx), name);
    const uint8_t *end = bytes + size;
    /* Pass 1 validates every scanline without the image, so truncated or hostile files are
     * refused before the (possibly large) float image is allocated. */
    const uint8_t *p = bytes + lay.data_offset;
    for (int y = 0; y < h; y++) {
        const char *problem = read_scanline(&p, end, w, scan);
        if (problem) {
            ibl_free(ctx, scan);
            return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: %s in scanline %d of %d", name, problem, y, h);
        }
    }
    s = ibl_texture_alloc(ctx, IBL_TEXTURE_2D, w, h, 1, 1, out);
    if (s != IBL_OK) {
        ibl_free(ctx, scan);
        return ibl__fail_named(ctx, s, name);
    }
    float scale[256]; /* 2^(e - 136); e = 0 means black */
    scale[0] = 0.0f;
    for (int e = 1; e < 256; e++) scale[e] = (float)ldexp(1.0, e - 136);
    p = bytes + lay.data_offset;
    for (int y = 0; y < h; y++) {
        (void)read_scanline(&p, end, w, scan); /* validated above */
        int row = lay.flip_y ? h - 1 - y : y;
        float *dst = out->data + (size_t)row * (size_t)w * 4;
        for (int x = 0; x < w; x++) {
            const uint8_t *q = scan + (size_t)x * 4;
            float *o = dst + (size_t)(lay.flip_x ? w - 1 - x : x) * 4;
            float f = scale[q[3]];
            float half = q[3] ? 0.5f : 0.0f;
            o[0] = ((float)q[0] + half) * f;
            o[1] = ((float)q[1] + half) * f;
            o[2] = ((float)q[2] + half) * f;
            o[3] = 1.0f;
        }
    }
    ibl_free(ctx, scan);
    out->format = IBL_FORMAT_RGBE;
    info->format = IBL_FORMAT_RGBE;
    info->has_alpha = 0;
    return IBL_OK;
}

/* ---- encoder ------------------------------------------------------------------------- */

/* frexp-based: the largest channel gets a mantissa byte in [128, 255]; every channel is
 * truncated, so the decoder's +0.5 lands in the middle of the bucket. The error is at most
 * half a step: 2^-8 of the largest channel. */
static void float_to_rgbe(const float *c, uint8_t *o)
{
    float v[3];
    float m = 0.0f;
    for (int k = 0; k < 3; k++) {
        v[k] = c[k] > 0.0f ? c[k] : 0.0f; /* negatives and NaN */
        if (v[k] > m) m = v[k];
    }
    if (!(m > 0.0f)) {
        memset(o, 0, 4);
        return;
    }
    int e = 128; /* +Inf: clamp to the largest representable value */
    if (isfinite(m)) (void)frexpf(m, &e);
    if (e < -127) { /* below the smallest exponent: black */
        memset(o, 0, 4);
        return;
    }
    if (e > 127) e = 127;
    /* 2^(8 - e) built from its bits (exact; the double range covers every e). */
    uint64_t bits = (uint64_t)(1023 + 8 - e) << 52;
    double scale;
    memcpy(&scale, &bits, sizeof scale);
    for (int k = 0; k < 3; k++) {
        double q = (double)v[k] * scale; /* < 256 unless clamped; truncation = floor */
        o[k] = q >= 255.0 ? 255 : (uint8_t)q;
    }
    o[3] = (uint8_t)(e + 128);
}

/* Per-channel run-length code: runs of 4 or more equal bytes as (128 + n, v), n <= 127; the
 * rest as literals (n, bytes...), n <= 128. */
static uint8_t *rle_channel(const uint8_t *d, int w, uint8_t *o)
{
    int i = 0;
    while (i < w) {
        int beg = i, run = 0;
        while (beg < w) {
            run = 1;
            while (beg + run < w && run < 127 && d[beg + run] == d[beg]) run++;
            if (run >= 4) break;
            beg += run;
        }
        if (beg >= w) beg = w;
        while (i < beg) {
            int n = beg - i > 128 ? 128 : beg - i;
            *o++ = (uint8_t)n;
            memcpy(o, d + i, (size_t)n);
            o += n;
            i += n;
        }
        if (beg < w) {
            *o++ = (uint8_t)(128 + run);
            *o++ = d[beg];
            i = beg + run;
        }
    }
    return o;
}

ibl_status ibl__hdr_encode(ibl_context *ctx, const ibl_image *image, const ibl_write_desc *desc,
                           const char *name, void **bytes, size_t *size)
{
    int w = image->width, h = image->height;
    if (desc->format != IBL_FORMAT_DEFAULT && desc->format != IBL_FORMAT_RGBE)
        return ibl__fail(ctx, IBL_ERR_UNSUPPORTED, "%s: Radiance files store only rgbe, not %s",
                        name, ibl_format_name(desc->format));
    if (w > IBL_MAX_DIMENSION || h > IBL_MAX_DIMENSION)
        return ibl__fail(ctx, IBL_ERR_TOO_LARGE, "%s: image %dx%d too large", name, w, h);
    int rle = !desc->hdr_no_rle && w >= 8 && w <= 0x7fff;
    char header[160];
    int hl = snprintf(header, sizeof header,
                      "#?RADIANCE\n# Written by ibl %s\nFORMAT=32-bit_rle_rgbe\n\n-Y %d +X %d\n",
                      IBL_VERSION_STRING, h, w);
    /* Worst case per scanline: 4 marker bytes + per channel w bytes and one count per 128. */
    size_t per_line = rle ? 4 + 4 * ((size_t)w + ((size_t)w + 127) / 128) : (size_t)w * 4;
    size_t cap = (size_t)hl + per_line * (size_t)h;
    uint8_t *buf = ibl_alloc(ctx, cap);
    uint8_t *scan = ibl_alloc(ctx, (size_t)w * 5);
    if (!buf || !scan) {
        ibl_status s = ibl_context_status(ctx);
        ibl_free(ctx, buf);
        ibl_free(ctx, scan);
        return ibl__fail_named(ctx, s, name);
    }
    memcpy(buf, header, (size_t)hl);
    uint8_t *o = buf + hl;
    uint8_t *chan = scan + (size_t)w * 4;
    for (int y = 0; y < h; y++) {
        const float *src = image->pixels + (size_t)y * (size_t)w * 4;
        for (int x = 0; x < w; x++) float_to_rgbe(src + (size_t)x * 4, scan + (size_t)x * 4);
        if (!rle) {
            memcpy(o, scan, (size_t)w * 4);
            o += (size_t)w * 4;
            continue;
        }
        *o++ = 2;
        *o++ = 2;
        *o++ = (uint8_t)(w >> 8);
        *o++ = (uint8_t)(w & 0xFF);
        for (int c = 0; c < 4; c++) {
            for (int x = 0; x < w; x++) chan[x] = scan[(size_t)x * 4 + (size_t)c];
            o = rle_channel(chan, w, o);
        }
    }
    ibl_free(ctx, scan);
    *bytes = buf;
    *size = (size_t)(o - buf);
    return IBL_OK;
}
