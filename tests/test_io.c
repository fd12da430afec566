/* Image I/O: round trips of every flat format (bounds stated per format), real files checked
 * against independent decodes written here, hostile input, the pixel policy and atomic
 * writes. */
#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <png.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include "test_io_helpers.h"

/* ---- helpers ------------------------------------------------------------------------- */

/* Counts allocations and remembers the largest, to prove refusals happen before allocating. */
typedef struct alloc_stats {
    size_t largest;
} alloc_stats;

static void *counting_alloc(size_t bytes, void *user)
{
    alloc_stats *st = user;
    if (bytes > st->largest) st->largest = bytes;
    void *p = NULL;
    if (posix_memalign(&p, 64, bytes ? bytes : 1) != 0) return NULL;
    return p;
}

static void counting_free(void *p, void *user)
{
    (void)user;
    free(p);
}

static ibl_context *counting_context(alloc_stats *st)
{
    ibl_context_desc d = {0};
    d.threads = 1;
    d.allocator.alloc = counting_alloc;
    d.allocator.free = counting_free;
    d.allocator.user = st;
    ibl_context *ctx = NULL;
    assert_int_equal(ibl_context_create(&d, &ctx), IBL_OK);
    return ctx;
}

/* Independent sRGB curves (IEC 61966-2-1) for the PNG checks. */
static double ref_srgb_encode(double v)
{
    return v <= 0.0031308 ? 12.92 * v : 1.055 * pow(v, 1 / 2.4) - 0.055;
}

/* ---- file types ---------------------------------------------------------------------- */

static void file_types(void **state)
{
    (void)state;
    assert_int_equal(ibl_file_type_from_path("a/b.HDR"), IBL_FILE_HDR);
    assert_int_equal(ibl_file_type_from_path("x.pic"), IBL_FILE_HDR);
    assert_int_equal(ibl_file_type_from_path("x.Exr"), IBL_FILE_EXR);
    assert_int_equal(ibl_file_type_from_path("x.pfm"), IBL_FILE_PFM);
    assert_int_equal(ibl_file_type_from_path("x.jpeg"), IBL_FILE_JPEG);
    assert_int_equal(ibl_file_type_from_path("x.ktx2"), IBL_FILE_KTX2);
    assert_int_equal(ibl_file_type_from_path("x.ktx"), IBL_FILE_KTX1);
    assert_int_equal(ibl_file_type_from_path("x.dds"), IBL_FILE_DDS);
    assert_int_equal(ibl_file_type_from_path("dir.exr/file"), IBL_FILE_UNKNOWN);
    assert_int_equal(ibl_file_type_from_path(".png"), IBL_FILE_UNKNOWN);
    assert_string_equal(ibl_file_type_name(IBL_FILE_KTX1), "ktx");
    assert_int_equal(ibl_file_type_sniff("#?RADIANCE\n", 11), IBL_FILE_HDR);
    assert_int_equal(ibl_file_type_sniff("PF\n1 1\n-1\n", 10), IBL_FILE_PFM);
    assert_int_equal(ibl_file_type_sniff("Pf 1 1", 6), IBL_FILE_PFM);
    assert_int_equal(ibl_file_type_sniff("P6\n", 3), IBL_FILE_UNKNOWN);
    assert_int_equal(ibl_file_type_sniff("\x76\x2f\x31\x01", 4), IBL_FILE_EXR);
    assert_int_equal(ibl_file_type_sniff("\x89PNG\r\n\x1a\n", 8), IBL_FILE_PNG);
    assert_int_equal(ibl_file_type_sniff("\xff\xd8\xff\xe0", 4), IBL_FILE_JPEG);
    assert_int_equal(ibl_file_type_sniff("\xabKTX 20\xbb\r\n\x1a\n", 12), IBL_FILE_KTX2);
    assert_int_equal(ibl_file_type_sniff("\xabKTX 11\xbb\r\n\x1a\n", 12), IBL_FILE_KTX1);
    assert_int_equal(ibl_file_type_sniff("DDS ", 4), IBL_FILE_DDS);
    assert_int_equal(ibl_file_type_sniff("\x89PN", 3), IBL_FILE_UNKNOWN);
    assert_true(ibl_file_type_is_container(IBL_FILE_DDS));
    assert_false(ibl_file_type_is_container(IBL_FILE_EXR));
}

/* ---- PFM ----------------------------------------------------------------------------- */

/* Float formats must round-trip bit for bit (alpha is not stored: it comes back as 1). */
static void pfm_round_trip(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_image im = make_image(ctx, 37, 23);
    for (size_t i = 0; i < 37 * 23 * 4; i++) im.pixels[i] = ldexpf(frand(), (int)(frand() * 60) - 30);
    ibl_file_info fi;
    ibl_image back = write_read(ctx, "a.pfm", &im, NULL, &fi);
    assert_int_equal(fi.type, IBL_FILE_PFM);
    assert_int_equal(fi.format, IBL_FORMAT_RGB32F);
    for (size_t i = 0; i < 37 * 23; i++) {
        for (int c = 0; c < 3; c++) assert_true(bits_equal(back.pixels[i * 4 + c], im.pixels[i * 4 + c]));
        assert_true(back.pixels[i * 4 + 3] == 1.0f);
    }
    ibl_image_free(ctx, &back);
    ibl_image_free(ctx, &im);
    ibl_context_destroy(ctx);
}

/* A hand-made big-endian grey file: rows are stored bottom first. */
static void pfm_grey_big_endian(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    uint8_t file[64];
    int hl = sprintf((char *)file, "Pf\n2 2\n1.0\n");
    const float v[4] = {1.0f, 2.0f, 3.0f, 4.0f}; /* stored order: bottom row (1 2), top (3 4) */
    for (int i = 0; i < 4; i++) {
        uint32_t u;
        memcpy(&u, &v[i], 4);
        for (int k = 0; k < 4; k++) file[hl + i * 4 + k] = (uint8_t)(u >> (24 - 8 * k));
    }
    ibl_texture t;
    assert_int_equal(decode(ctx, file, (size_t)hl + 16, &t, NULL), IBL_OK);
    assert_int_equal(t.width, 2);
    const float expect[4] = {3, 4, 1, 2};
    for (int i = 0; i < 4; i++)
        for (int c = 0; c < 3; c++) assert_true(t.data[i * 4 + c] == expect[i]);
    ibl_texture_free(ctx, &t);
    ibl_context_destroy(ctx);
}

/* ---- Radiance ------------------------------------------------------------------------ */

/* A minimal RGBE reader written from the format description, independent of src/io/hdr.c
 * (new-style RLE or flat scanlines, "-Y H +X W" only). */
static int ref_read_rgbe(const uint8_t *b, size_t n, int *w, int *h, float **out)
{
    const uint8_t *p = NULL;
    for (size_t i = 0; i + 1 < n; i++)
        if (b[i] == '\n' && b[i + 1] == '\n') {
            p = b + i + 2;
            break;
        }
    if (!p || sscanf((const char *)p, "-Y %d +X %d", h, w) != 2) return 0;
    p = memchr(p, '\n', (size_t)(b + n - p)) + 1;
    float *img = malloc((size_t)*w * (size_t)*h * 3 * sizeof(float));
    uint8_t *line = malloc((size_t)*w * 4);
    for (int y = 0; y < *h; y++) {
        if (p[0] == 2 && p[1] == 2) {
            p += 4;
            for (int c = 0; c < 4; c++)
                for (int x = 0; x < *w;) {
                    int count = *p++;
                    if (count > 128) { /* a run: one value repeated count - 128 times */
                        uint8_t v = *p++;
                        for (int k = 0; k < count - 128; k++) line[(x++) * 4 + c] = v;
                    } else { /* count literal values */
                        for (int k = 0; k < count; k++) line[(x++) * 4 + c] = *p++;
                    }
                }
        } else {
            memcpy(line, p, (size_t)*w * 4);
            p += (size_t)*w * 4;
        }
        for (int x = 0; x < *w; x++)
            for (int c = 0; c < 3; c++) {
                int e = line[x * 4 + 3];
                /* Radiance's colr_color: (mantissa + 0.5) * 2^(e - 136) */
                img[((size_t)y * (size_t)*w + (size_t)x) * 3 + (size_t)c] =
                    e ? (float)ldexp(line[x * 4 + c] + 0.5, e - 136) : 0.0f;
            }
    }
    free(line);
    *out = img;
    return 1;
}

static void hdr_uffizi(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_image im;
    ibl_file_info fi;
    assert_int_equal(ibl_read_image(ctx, test_data("uffizi_latlong_256x128.hdr"), NULL, &im, &fi), IBL_OK);
    assert_int_equal(fi.type, IBL_FILE_HDR);
    assert_int_equal(fi.format, IBL_FORMAT_RGBE);
    assert_int_equal(im.width, 256);
    assert_int_equal(im.height, 128);
    size_t n;
    uint8_t *b = slurp(test_data("uffizi_latlong_256x128.hdr"), &n);
    int w = 0, h = 0;
    float *ref = NULL;
    assert_true(ref_read_rgbe(b, n, &w, &h, &ref));
    assert_int_equal(w, 256);
    assert_int_equal(h, 128);
    double sum = 0;
    for (size_t i = 0; i < 256 * 128; i++) {
        for (int c = 0; c < 3; c++) assert_true(im.pixels[i * 4 + c] == ref[i * 3 + c]);
        sum += im.pixels[i * 4 + 1];
    }
    assert_true(sum > 0);
    free(ref);
    free(b);
    ibl_image_free(ctx, &im);
    ibl_context_destroy(ctx);
}

/* RGBE keeps 8 bits of mantissa for the largest channel (at least 128 of 256 steps) and the
 * reader returns the bucket centre: error <= half a step <= 2^-8 of the largest channel. */
static void check_rgbe_bound(const ibl_image *orig, const ibl_image *back)
{
    size_t n = (size_t)orig->width * (size_t)orig->height;
    for (size_t i = 0; i < n; i++) {
        const float *o = orig->pixels + i * 4, *r = back->pixels + i * 4;
        double m = fmax(o[0], fmax(o[1], o[2]));
        for (int c = 0; c < 3; c++) assert_true(fabs((double)r[c] - o[c]) <= ldexp(m, -8));
        assert_true(r[3] == 1.0f);
    }
}

/* Offset of the first scanline: after the empty line and the resolution line. */
static size_t hdr_data_offset(const uint8_t *b, size_t n)
{
    for (size_t i = 0; i + 1 < n; i++)
        if (b[i] == '\n' && b[i + 1] == '\n') {
            const uint8_t *nl = memchr(b + i + 2, '\n', n - i - 2);
            return (size_t)(nl - b) + 1;
        }
    return 0;
}

static void hdr_round_trip(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    const int sizes[][2] = {{64, 8}, {7, 5}, {33000, 2}, {300, 3}};
    for (size_t k = 0; k < sizeof sizes / sizeof sizes[0]; k++) {
        int w = sizes[k][0], h = sizes[k][1];
        ibl_image im = make_image(ctx, w, h);
        for (size_t i = 0; i < (size_t)w * (size_t)h; i++) {
            float *p = im.pixels + i * 4;
            if (i % 17 < 6) { /* runs of equal pixels exercise the run-length code */
                p[0] = 0.5f, p[1] = 2.0f, p[2] = 100.0f;
            } else {
                for (int c = 0; c < 3; c++) p[c] = ldexpf(frand(), (int)(frand() * 40) - 20);
            }
            p[3] = 1.0f;
        }
        im.pixels[0] = im.pixels[1] = im.pixels[2] = 0.0f;
        for (int flat = 0; flat < 2; flat++) {
            ibl_write_desc wd = {0};
            wd.hdr_no_rle = flat;
            ibl_image back = write_read(ctx, "r.hdr", &im, &wd, NULL);
            check_rgbe_bound(&im, &back);
            assert_true(back.pixels[0] == 0.0f);
            /* Re-encoding the decoded values reproduces the same bytes (bucket centres). */
            size_t n1, n2;
            uint8_t *b1 = slurp(test_path("r.hdr"), &n1);
            assert_int_equal(ibl_write_image(ctx, test_path("r2.hdr"), &back, &wd), IBL_OK);
            uint8_t *b2 = slurp(test_path("r2.hdr"), &n2);
            assert_int_equal(n1, n2);
            assert_memory_equal(b1, b2, n1);
            /* Flat scanlines (asked for, or widths RLE cannot code) are exactly 4 bytes a pixel. */
            size_t data = hdr_data_offset(b1, n1);
            if (flat || w < 8 || w > 32767) assert_int_equal(n1 - data, (size_t)w * (size_t)h * 4);
            else assert_true(b1[data] == 2 && b1[data + 1] == 2);
            free(b1);
            free(b2);
            ibl_image_free(ctx, &back);
        }
        ibl_image_free(ctx, &im);
    }
    ibl_context_destroy(ctx);
}

/* Hand-made flat files: orientations, old-style run-length records, refusals. */
static size_t make_hdr(uint8_t *buf, const char *res, const uint8_t *pix, size_t npix_bytes)
{
    int hl = sprintf((char *)buf, "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\nEXPOSURE=2.0\n\n%s\n", res);
    memcpy(buf + hl, pix, npix_bytes);
    return (size_t)hl + npix_bytes;
}

static void hdr_orientations(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    /* 2x2 pixels in stored order; mantissa 128 + k, exponent 129: value (128 + k + 0.5) / 128 */
    const uint8_t pix[16] = {128, 128, 128, 129, 129, 129, 129, 129,
                             130, 130, 130, 129, 131, 131, 131, 129};
    struct {
        const char *res;
        float expect[4]; /* red of top-left, top-right, bottom-left, bottom-right */
    } cases[] = {
        {"-Y 2 +X 2", {0, 1, 2, 3}},
        {"+Y 2 +X 2", {2, 3, 0, 1}},
        {"-Y 2 -X 2", {1, 0, 3, 2}},
        {"+Y 2 -X 2", {3, 2, 1, 0}},
    };
    uint8_t buf[256];
    for (size_t k = 0; k < 4; k++) {
        size_t n = make_hdr(buf, cases[k].res, pix, 16);
        ibl_texture t;
        assert_int_equal(decode(ctx, buf, n, &t, NULL), IBL_OK);
        for (int i = 0; i < 4; i++)
            assert_true(t.data[i * 4] == (128.0f + cases[k].expect[i] + 0.5f) / 128.0f);
        ibl_texture_free(ctx, &t);
    }
    size_t n = make_hdr(buf, "+X 2 -Y 2", pix, 16);
    ibl_texture t;
    assert_int_equal(decode(ctx, buf, n, &t, NULL), IBL_ERR_UNSUPPORTED);
    assert_non_null(strstr(ibl_context_message(ctx), "mem.bin"));
    /* Old-style RLE: pixel A, repeat x2, pixel B, repeat 1 then (shifted) 0 -> A A A B B */
    const uint8_t old[] = {200, 100, 50, 130, 1, 1, 1, 2, 160, 160, 160, 128, 1, 1, 1, 1, 1, 1, 1, 0};
    n = make_hdr(buf, "-Y 1 +X 5", old, sizeof old);
    assert_int_equal(decode(ctx, buf, n, &t, NULL), IBL_OK);
    const float a = (200 + 0.5f) / 64.0f, bv = (160 + 0.5f) / 256.0f;
    const float expect[5] = {a, a, a, bv, bv};
    for (int i = 0; i < 5; i++) assert_true(t.data[i * 4] == expect[i]);
    ibl_texture_free(ctx, &t);
    /* A repeat running past the end of the scanline is malformed. */
    const uint8_t over[] = {200, 100, 50, 130, 1, 1, 1, 9};
    n = make_hdr(buf, "-Y 1 +X 5", over, sizeof over);
    assert_int_equal(decode(ctx, buf, n, &t, NULL), IBL_ERR_FORMAT);
    /* XYZE is refused by name. */
    n = (size_t)sprintf((char *)buf, "#?RADIANCE\nFORMAT=32-bit_rle_xyze\n\n-Y 1 +X 1\n");
    memset(buf + n, 128, 4);
    assert_int_equal(decode(ctx, buf, n + 4, &t, NULL), IBL_ERR_UNSUPPORTED);
    ibl_context_destroy(ctx);
}

/* ---- PNG and JPEG -------------------------------------------------------------------- */

/* 16-bit linear PNG: each value is rounded to the nearest of 65536 codes (error <= 0.5/65535,
 * plus float rounding of the decoded value). */
static void png16_round_trip(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_image im = make_image(ctx, 33, 17);
    for (size_t i = 0; i < 33 * 17 * 4; i++) im.pixels[i] = frand();
    im.pixels[0] = 0.0f;
    im.pixels[1] = 1.0f;
    ibl_write_desc wd = {0};
    wd.format = IBL_FORMAT_RGBA16_UNORM;
    wd.exposure_ev = 3.0f; /* ignored for the linear 16-bit tables */
    ibl_file_info fi;
    ibl_image back = write_read(ctx, "t.png", &im, &wd, &fi);
    assert_int_equal(fi.format, IBL_FORMAT_RGBA16_UNORM);
    assert_int_equal(fi.has_alpha, 1);
    for (size_t i = 0; i < 33 * 17 * 4; i++) assert_near(back.pixels[i], im.pixels[i], 0.5 / 65535 + 1e-7);
    assert_true(back.pixels[0] == 0.0f && back.pixels[1] == 1.0f);
    ibl_image_free(ctx, &back);
    ibl_image_free(ctx, &im);
    ibl_context_destroy(ctx);
}

/* 8-bit sRGB without a tone map: the decoded value re-encoded to sRGB code units is within
 * half a code of the original's (+1e-3 for float rounding); alpha within half a code too. */
static void png8_round_trip(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_image im = make_image(ctx, 29, 13);
    for (size_t i = 0; i < 29 * 13 * 4; i++) im.pixels[i] = frand();
    ibl_write_desc wd = {0};
    wd.tonemap = IBL_TONEMAP_NONE;
    ibl_file_info fi;
    ibl_image back = write_read(ctx, "s.png", &im, &wd, &fi);
    assert_int_equal(fi.format, IBL_FORMAT_RGBA8_SRGB);
    for (size_t i = 0; i < 29 * 13; i++) {
        for (int c = 0; c < 3; c++)
            assert_near(ref_srgb_encode(back.pixels[i * 4 + c]) * 255,
                        ref_srgb_encode(im.pixels[i * 4 + c]) * 255, 0.5 + 1e-3);
        assert_near(back.pixels[i * 4 + 3], im.pixels[i * 4 + 3], 0.5 / 255 + 1e-6);
    }
    ibl_image_free(ctx, &back);
    /* Opaque images are written without an alpha channel. */
    for (size_t i = 0; i < 29 * 13; i++) im.pixels[i * 4 + 3] = 1.0f;
    back = write_read(ctx, "o.png", &im, &wd, &fi);
    assert_int_equal(fi.has_alpha, 0);
    ibl_image_free(ctx, &back);
    ibl_image_free(ctx, &im);
    ibl_context_destroy(ctx);
}

/* Exposure and the default (filmic) tone map against the published curve. */
static void png8_exposure_filmic(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    const float values[4] = {0.0f, 0.05f, 0.18f, 3.0f};
    ibl_image im = make_image(ctx, 4, 1);
    for (int i = 0; i < 4; i++) {
        im.pixels[i * 4] = im.pixels[i * 4 + 1] = im.pixels[i * 4 + 2] = values[i];
        im.pixels[i * 4 + 3] = 1.0f;
    }
    ibl_write_desc wd = {0};
    wd.exposure_ev = 1.0f;
    ibl_image back = write_read(ctx, "f.png", &im, &wd, NULL);
    for (int i = 0; i < 4; i++) {
        double x = values[i] * 2.0; /* 2^ev */
        double y = x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14);
        if (y > 1) y = 1;
        /* within half an 8-bit code of the exact display value */
        assert_near(ref_srgb_encode(back.pixels[i * 4]) * 255, ref_srgb_encode(y) * 255, 0.5 + 1e-3);
    }
    ibl_image_free(ctx, &back);
    ibl_image_free(ctx, &im);
    assert_near(ibl_tonemap_apply(IBL_TONEMAP_FILMIC, 1.0f), 2.54 / 3.16, 1e-6);
    assert_true(ibl_tonemap_apply(IBL_TONEMAP_DEFAULT, 1e30f) == 1.0f);
    assert_true(ibl_tonemap_apply(IBL_TONEMAP_NONE, 2.0f) == 1.0f);
    assert_true(ibl_tonemap_apply(IBL_TONEMAP_NONE, 0.25f) == 0.25f);
    assert_true(ibl_tonemap_apply(IBL_TONEMAP_FILMIC, NAN) == 0.0f);
    assert_true(ibl_tonemap_apply(IBL_TONEMAP_FILMIC, -1.0f) == 0.0f);
    ibl_context_destroy(ctx);
}

/* JPEG is lossy: a flat colour (no AC energy) must come back within 2 codes. */
static void jpeg_round_trip(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_image im = make_image(ctx, 48, 24);
    for (size_t i = 0; i < 48 * 24; i++) {
        im.pixels[i * 4] = 0.2f, im.pixels[i * 4 + 1] = 0.5f, im.pixels[i * 4 + 2] = 0.05f;
        im.pixels[i * 4 + 3] = 1.0f;
    }
    ibl_write_desc wd = {0};
    wd.tonemap = IBL_TONEMAP_NONE;
    ibl_file_info fi;
    ibl_image back = write_read(ctx, "p.jpg", &im, &wd, &fi);
    assert_int_equal(fi.type, IBL_FILE_JPEG);
    assert_int_equal(fi.format, IBL_FORMAT_RGBA8_SRGB);
    for (size_t i = 0; i < 48 * 24; i++)
        for (int c = 0; c < 3; c++)
            assert_near(ref_srgb_encode(back.pixels[i * 4 + c]) * 255,
                        ref_srgb_encode(im.pixels[i * 4 + c]) * 255, 2.0);
    ibl_image_free(ctx, &back);
    wd.format = IBL_FORMAT_RGBA32F;
    assert_int_equal(ibl_write_image(ctx, test_path("bad.jpg"), &im, &wd), IBL_ERR_UNSUPPORTED);
    ibl_image_free(ctx, &im);
    ibl_context_destroy(ctx);
}

/* PNG layouts our writer never makes, written here with libpng itself (gAMA 1.0, so the
 * expected value of a sample is simply sample / max): 1-bit grey, grey+alpha, 4-bit palette
 * with transparency, 16-bit grey and Adam7-interlaced 16-bit RGB. Exact up to float rounding. */

/* sample(x, y, c) in [0, 2^depth) for the file's channels; palette files index pal. */
static unsigned png_sample(int x, int y, int c, int depth)
{
    return (unsigned)(x * 7 + y * 3 + c * 5) % (1u << depth);
}

static void png_variant(ibl_context *ctx, int color, int depth, int interlace)
{
    const int w = 9, h = 5;
    int ch = color == PNG_COLOR_TYPE_GRAY ? 1 : color == PNG_COLOR_TYPE_GRAY_ALPHA ? 2
           : color == PNG_COLOR_TYPE_PALETTE ? 1 : color == PNG_COLOR_TYPE_RGB ? 3 : 4;
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
    png_infop info = png_create_info_struct(png);
    test_bytes m = {NULL, 0, 0};
    assert_int_equal(setjmp(png_jmpbuf(png)), 0);
    test_png_write_to_memory(png, &m);
    png_set_IHDR(png, info, w, h, depth, color, interlace, PNG_COMPRESSION_TYPE_DEFAULT,
                 PNG_FILTER_TYPE_DEFAULT);
    png_set_gAMA(png, info, 1.0);
    png_color pal[16];
    png_byte trans[16];
    for (int i = 0; i < 16; i++) {
        pal[i].red = (png_byte)(i * 16), pal[i].green = (png_byte)(255 - i * 16), pal[i].blue = (png_byte)(i * 3);
        trans[i] = (png_byte)(i * 17);
    }
    if (color == PNG_COLOR_TYPE_PALETTE) {
        png_set_PLTE(png, info, pal, 16);
        png_set_tRNS(png, info, trans, 16, NULL);
    }
    png_write_info(png, info);
    int passes = png_set_interlace_handling(png);
    uint8_t row[9 * 4 * 2];
    for (int pass = 0; pass < passes; pass++)
        for (int y = 0; y < h; y++) {
            memset(row, 0, sizeof row);
            for (int x = 0; x < w; x++)
                for (int c = 0; c < ch; c++) {
                    unsigned v = png_sample(x, y, c, depth);
                    if (depth == 16) {
                        row[(x * ch + c) * 2] = (uint8_t)(v >> 8);
                        row[(x * ch + c) * 2 + 1] = (uint8_t)v;
                    } else if (depth == 8) {
                        row[x * ch + c] = (uint8_t)v;
                    } else { /* packed, most significant bits first */
                        int bit = (x * ch + c) * depth;
                        row[bit / 8] |= (uint8_t)(v << (8 - depth - bit % 8));
                    }
                }
            png_write_row(png, row);
        }
    png_write_end(png, info);
    png_destroy_write_struct(&png, &info);
    ibl_texture t;
    ibl_file_info fi;
    assert_int_equal(decode(ctx, m.b, m.n, &t, &fi), IBL_OK);
    assert_int_equal(fi.has_alpha, ch == 2 || ch == 4 || color == PNG_COLOR_TYPE_PALETTE);
    assert_int_equal(fi.format, depth == 16 ? IBL_FORMAT_RGBA16_UNORM : IBL_FORMAT_RGBA8_SRGB);
    double max = (double)((1u << depth) - 1);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            const float *p = t.data + ((size_t)y * w + (size_t)x) * 4;
            double e[4];
            if (color == PNG_COLOR_TYPE_PALETTE) {
                unsigned i = png_sample(x, y, 0, depth);
                e[0] = pal[i].red / 255.0, e[1] = pal[i].green / 255.0, e[2] = pal[i].blue / 255.0;
                e[3] = trans[i] / 255.0;
            } else {
                for (int c = 0; c < 3; c++) e[c] = png_sample(x, y, ch >= 3 ? c : 0, depth) / max;
                e[3] = (ch == 2 || ch == 4) ? png_sample(x, y, ch - 1, depth) / max : 1.0;
            }
            for (int c = 0; c < 4; c++) assert_near(p[c], e[c], 1e-6);
        }
    ibl_texture_free(ctx, &t);
    free(m.b);
}

static void png_layouts(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    png_variant(ctx, PNG_COLOR_TYPE_GRAY, 1, PNG_INTERLACE_NONE);
    png_variant(ctx, PNG_COLOR_TYPE_GRAY_ALPHA, 8, PNG_INTERLACE_NONE);
    png_variant(ctx, PNG_COLOR_TYPE_PALETTE, 4, PNG_INTERLACE_NONE);
    png_variant(ctx, PNG_COLOR_TYPE_GRAY, 16, PNG_INTERLACE_NONE);
    png_variant(ctx, PNG_COLOR_TYPE_RGB, 16, PNG_INTERLACE_ADAM7);
    png_variant(ctx, PNG_COLOR_TYPE_RGB_ALPHA, 8, PNG_INTERLACE_ADAM7);
    ibl_context_destroy(ctx);
}

/* ---- bad input ----------------------------------------------------------------------- */

/* Every proper prefix of a valid file is refused with a message naming it, never crashes
 * (a JPEG must end with its end marker; a PNG may lack its IEND chunk). */
static void truncated_files(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_image im = make_image(ctx, 20, 10);
    for (size_t i = 0; i < 20 * 10 * 4; i++) im.pixels[i] = frand() * 4;
    const char *names[] = {"t.hdr", "tf.hdr", "t.pfm", "t.exr", "tp.exr", "t.png", "t.jpg"};
    for (size_t k = 0; k < sizeof names / sizeof names[0]; k++) {
        ibl_write_desc wd = {0};
        wd.hdr_no_rle = k == 1;
        wd.exr_compression = k == 4 ? IBL_EXR_PIZ : IBL_EXR_DEFAULT;
        assert_int_equal(ibl_write_image(ctx, test_path(names[k]), &im, &wd), IBL_OK);
        size_t n;
        uint8_t *b = slurp(test_path(names[k]), &n);
        for (size_t cut = 0; cut < n; cut += (cut < 64 ? 1 : 7)) {
            ibl_texture t;
            ibl_status s = ibl_decode_texture(ctx, b, cut, "cut.bin", NULL, &t, NULL);
            if (k == 5 && cut >= n - 12) { /* a PNG without its IEND chunk still decodes */
                ibl_texture_free(ctx, &t);
                continue;
            }
            assert_int_not_equal(s, IBL_OK);
            assert_null(t.data);
            assert_non_null(strstr(ibl_context_message(ctx), "cut.bin"));
        }
        free(b);
    }
    ibl_image_free(ctx, &im);
    ibl_context_destroy(ctx);
}

static void wrong_magic(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_texture t;
    assert_int_equal(ibl_decode_texture(ctx, "hello world, not an image", 25, "x.exr", NULL, &t, NULL),
                     IBL_ERR_FORMAT);
    assert_non_null(strstr(ibl_context_message(ctx), "x.exr"));
    assert_int_equal(ibl_decode_texture(ctx, "", 0, "empty.hdr", NULL, &t, NULL), IBL_ERR_FORMAT);
    spit(test_path("garbage.png"), "GIF89a....", 10);
    ibl_image im;
    assert_int_equal(ibl_read_image(ctx, test_path("garbage.png"), NULL, &im, NULL), IBL_ERR_FORMAT);
    assert_non_null(strstr(ibl_context_message(ctx), "garbage.png"));
    ibl_context_destroy(ctx);
}

/* Writes one OpenEXR attribute. */
static size_t exr_attr(uint8_t *p, const char *name, const char *type, const void *v, int len)
{
    size_t n = 0;
    memcpy(p + n, name, strlen(name) + 1), n += strlen(name) + 1;
    memcpy(p + n, type, strlen(type) + 1), n += strlen(type) + 1;
    memcpy(p + n, &len, 4), n += 4; /* little-endian host, as the test machines are */
    memcpy(p + n, v, (size_t)len), n += (size_t)len;
    return n;
}

static size_t exr_header(uint8_t *p, int32_t xmax, int32_t ymax)
{
    size_t n = 0;
    const uint8_t magic[8] = {0x76, 0x2f, 0x31, 0x01, 2, 0, 0, 0};
    memcpy(p, magic, 8), n = 8;
    uint8_t ch[19] = {'R', 0, 2, 0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 0};
    n += exr_attr(p + n, "channels", "chlist", ch, 19);
    uint8_t comp = 0;
    n += exr_attr(p + n, "compression", "compression", &comp, 1);
    int32_t box[4] = {0, 0, xmax, ymax};
    n += exr_attr(p + n, "dataWindow", "box2i", box, 16);
    n += exr_attr(p + n, "displayWindow", "box2i", box, 16);
    p[n++] = 0;
    return n;
}

/* Absurd or zero sizes are refused before any large allocation (the largest block the
 * context hands out stays under 1 MiB, the Radiance scanline buffer being the biggest). */
static void absurd_dimensions(void **state)
{
    (void)state;
    alloc_stats st = {0};
    ibl_context *ctx = counting_context(&st);
    uint8_t buf[4096];
    ibl_texture t;
    const char *hdrs[] = {"#?RADIANCE\n\n-Y 100000 +X 100000\n", "#?RADIANCE\n\n-Y 60000 +X 60000\n",
                          "#?RADIANCE\n\n-Y 0 +X 16\n", "#?RADIANCE\n\n-Y 99999999999999999999 +X 1\n"};
    for (size_t k = 0; k < 4; k++) {
        size_t n = strlen(hdrs[k]);
        memcpy(buf, hdrs[k], n);
        memset(buf + n, 0x80, 64);
        assert_int_equal(decode(ctx, buf, n + 64, &t, NULL), IBL_ERR_FORMAT);
    }
    const char *pfms[] = {"PF\n60000 60000\n-1.0\n", "PF\n0 7\n-1.0\n", "PF\n-3 7\n-1.0\n",
                          "PF\n70000 1\n-1.0\n", "PF\n4 4\n0\n"};
    for (size_t k = 0; k < 5; k++) {
        size_t n = strlen(pfms[k]);
        memcpy(buf, pfms[k], n);
        memset(buf + n, 0, 256);
        assert_int_equal(decode(ctx, buf, n + 256, &t, NULL), IBL_ERR_FORMAT);
    }
    size_t n = exr_header(buf, 59999, 59999); /* no offset table, no data */
    assert_int_equal(decode(ctx, buf, n, &t, NULL), IBL_ERR_FORMAT);
    n = exr_header(buf, 99999, 0);
    assert_int_equal(decode(ctx, buf, n, &t, NULL), IBL_ERR_FORMAT);
    n = exr_header(buf, -5, 10); /* xmax < xmin */
    assert_int_equal(decode(ctx, buf, n, &t, NULL), IBL_ERR_FORMAT);
    /* PNG header claiming 100000 x 10 (stb reads the IHDR without checking its CRC) */
    const uint8_t png[] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n', 0, 0, 0, 13, 'I', 'H', 'D', 'R',
                           0, 1, 0x86, 0xa0, 0, 0, 0, 10, 8, 2, 0, 0, 0, 0, 0, 0, 0,
                           0, 0, 0, 0, 'I', 'E', 'N', 'D', 0xae, 0x42, 0x60, 0x82};
    assert_int_equal(decode(ctx, png, sizeof png, &t, NULL), IBL_ERR_FORMAT);
    /* Found by fuzzing: a 556-byte PNG whose IDAT made stb_image ask for 1 GiB. */
    size_t fn;
    uint8_t *fb = slurp(test_data("fuzz_png_idat_huge.png"), &fn);
    ibl_status fs = decode(ctx, fb, fn, &t, NULL);
    if (fs == IBL_OK) ibl_texture_free(ctx, &t);
    free(fb);
    assert_true(st.largest < (1u << 20));
    ibl_context_destroy(ctx);
}

/* The pixel policy: NaN and negatives become 0 and are counted; infinities are refused
 * unless clamping, then +Inf becomes the clamp value and -Inf 0. */
static void non_finite_pixels(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_image im = make_image(ctx, 4, 2);
    for (size_t i = 0; i < 4 * 2 * 4; i++) im.pixels[i] = 0.5f;
    im.pixels[0] = NAN;                  /* texel 0: NaN */
    im.pixels[4 + 1] = -2.0f;            /* texel 1: negative */
    im.pixels[8 + 2] = INFINITY;         /* texel 2: +Inf */
    im.pixels[12 + 0] = -INFINITY;       /* texel 3: -Inf */
    im.pixels[16 + 0] = NAN;             /* texel 4: NaN and negative */
    im.pixels[16 + 1] = -1.0f;
    const char *path = test_path("bad.pfm");
    assert_int_equal(ibl_write_image(ctx, path, &im, NULL), IBL_OK);
    ibl_image back;
    ibl_file_info fi;
    assert_int_equal(ibl_read_image(ctx, path, NULL, &back, &fi), IBL_ERR_BAD_PIXELS);
    assert_null(back.pixels);
    assert_non_null(strstr(ibl_context_message(ctx), "bad.pfm"));
    assert_int_equal(fi.pixels.inf_count, 2);
    ibl_read_desc rd = {.clamp_infinite = 1, .clamp_value = 1000.0f};
    assert_int_equal(ibl_read_image(ctx, path, &rd, &back, &fi), IBL_OK);
    assert_int_equal(fi.pixels.nan_count, 2);
    assert_int_equal(fi.pixels.negative_count, 2);
    assert_int_equal(fi.pixels.inf_count, 2);
    assert_int_equal(fi.pixels.texel_count, 8);
    assert_true(back.pixels[0] == 0.0f && back.pixels[1] == 0.5f);
    assert_true(back.pixels[5] == 0.0f);
    assert_true(back.pixels[10] == 1000.0f);
    assert_true(back.pixels[12] == 0.0f);
    assert_true(back.pixels[16] == 0.0f && back.pixels[17] == 0.0f);
    ibl_image_free(ctx, &back);
    ibl_image_free(ctx, &im);
    ibl_context_destroy(ctx);
}

/* ---- files and API edges ------------------------------------------------------------- */

static int count_entries(const char *dir)
{
    DIR *d = opendir(dir);
    assert_non_null(d);
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)))
        if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..")) n++;
    closedir(d);
    return n;
}

/* The pixel policy runs in chunks on several threads and large files are read in pieces:
 * at 1, 2 and 8 threads the same pixels and counts come back, the counts those planted
 * (the image is over two chunks of 65,536 texels; the file over two pieces of 4 MiB). */
static void large_inputs_identical_at_any_thread_count(void **state)
{
    (void)state;
    enum { W = 1000, H = 800 };
    ibl_context *one = test_context(1);
    ibl_image im = make_image(one, W, H);
    uint64_t nan = 0, inf = 0, neg = 0;
    for (size_t t = 0; t < (size_t)W * H; t++) {
        float *p = im.pixels + t * 4;
        p[0] = p[1] = p[2] = frand() * 4.0f;
        p[3] = 1.0f;
        if (t % 1009 == 5) p[1] = NAN, nan++;
        else if (t % 1013 == 7) p[2] = (t & 1) ? INFINITY : -INFINITY, inf++;
        else if (t % 997 == 11) p[0] = -frand() - 0.5f, neg++;
    }
    const char *path = test_path("large.pfm");
    assert_int_equal(ibl_write_image(one, path, &im, NULL), IBL_OK);
    void *file_ref;
    size_t file_size;
    assert_int_equal(ibl_read_file(one, path, &file_ref, &file_size), IBL_OK);
    assert_true(file_size > 8u << 20);
    ibl_image ref = {0};
    const int threads[3] = {1, 2, 8};
    for (int t = 0; t < 3; t++) {
        ibl_context *ctx = test_context(threads[t]);
        void *bytes;
        size_t size;
        assert_int_equal(ibl_read_file(ctx, path, &bytes, &size), IBL_OK);
        assert_int_equal(size, file_size);
        assert_memory_equal(bytes, file_ref, size);
        ibl_free(ctx, bytes);
        ibl_image back;
        ibl_file_info fi;
        assert_int_equal(ibl_read_image(ctx, path, NULL, &back, &fi), IBL_ERR_BAD_PIXELS);
        assert_int_equal(fi.pixels.inf_count, inf);
        char want[80];
        snprintf(want, sizeof want, "%llu texels are infinite", (unsigned long long)inf);
        assert_non_null(strstr(ibl_context_message(ctx), want));
        ibl_read_desc rd = {.clamp_infinite = 1};
        assert_int_equal(ibl_read_image(ctx, path, &rd, &back, &fi), IBL_OK);
        assert_int_equal(fi.pixels.nan_count, nan);
        assert_int_equal(fi.pixels.inf_count, inf);
        assert_int_equal(fi.pixels.negative_count, neg);
        assert_int_equal(fi.pixels.texel_count, (uint64_t)W * H);
        if (t == 0) {
            ref = back;
        } else {
            assert_memory_equal(back.pixels, ref.pixels, (size_t)W * H * 4 * sizeof(float));
            ibl_image_free(ctx, &back);
        }
        ibl_context_destroy(ctx);
    }
    ibl_image_free(one, &ref);
    ibl_free(one, file_ref);
    ibl_image_free(one, &im);
    ibl_context_destroy(one);
}

/* A host that says it runs loops on two threads gets the work split for two: the ZIP EXR's
 * bands (1000x1024: 64 chunks of 16 rows, in 16 bands) come to it as one loop and decode to
 * the same pixels as on one thread; a host that says nothing gets them in order on the
 * calling thread, as before. */
static void host_parallel_for_told_its_threads(void **state)
{
    (void)state;
    enum { W = 1000, H = 1024, BANDS = 16 };
    ibl_context *one = test_context(1);
    ibl_image im = make_image(one, W, H);
    for (size_t t = 0; t < (size_t)W * H; t++) {
        float *p = im.pixels + t * 4;
        p[0] = frand() * 8.0f, p[1] = frand(), p[2] = frand() * 0.5f, p[3] = 1.0f;
    }
    const char *path = test_path("hosted.exr");
    ibl_write_desc wd = {.format = IBL_FORMAT_RGBA32F, .exr_compression = IBL_EXR_ZIP};
    assert_int_equal(ibl_write_image(one, path, &im, &wd), IBL_OK);
    ibl_image ref;
    assert_int_equal(ibl_read_image(one, path, NULL, &ref, NULL), IBL_OK);
    for (int told = 0; told <= 2; told += 2) {
        test_host host = {.threads = 2};
        ibl_context_desc d = {.parallel_for = test_host_parallel_for, .parallel_host = &host,
                              .threads = told};
        ibl_context *ctx;
        assert_int_equal(ibl_context_create(&d, &ctx), IBL_OK);
        assert_int_equal(ibl_context_threads(ctx), told ? 2 : 1);
        ibl_image back;
        assert_int_equal(ibl_read_image(ctx, path, NULL, &back, NULL), IBL_OK);
        assert_memory_equal(back.pixels, ref.pixels, (size_t)W * H * 4 * sizeof(float));
        if (told) assert_true(atomic_load(&host.largest_loop) >= BANDS);
        else assert_true(atomic_load(&host.largest_loop) < BANDS);
        ibl_image_free(ctx, &back);
        ibl_context_destroy(ctx);
    }
    ibl_image_free(one, &ref);
    ibl_image_free(one, &im);
    ibl_context_destroy(one);
}

static void atomic_write(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    char dir[600];
    snprintf(dir, sizeof dir, "%s", test_path("atomic"));
    assert_int_equal(mkdir(dir, 0755), 0);
    char target[700];
    snprintf(target, sizeof target, "%s/out.bin", dir);
    const char original[] = "ORIGINAL CONTENT";
    spit(target, original, sizeof original);

    /* A write that fails half-way (file size limit): the target is untouched, no temp left. */
    static uint8_t big[1 << 16];
    memset(big, 'x', sizeof big);
    struct rlimit old;
    assert_int_equal(getrlimit(RLIMIT_FSIZE, &old), 0);
    struct rlimit lim = old;
    lim.rlim_cur = 4096;
    void (*prev)(int) = signal(SIGXFSZ, SIG_IGN);
    assert_int_equal(setrlimit(RLIMIT_FSIZE, &lim), 0);
    ibl_status s = ibl_write_file_atomic(ctx, target, big, sizeof big);
    assert_int_equal(setrlimit(RLIMIT_FSIZE, &old), 0);
    signal(SIGXFSZ, prev);
    assert_int_equal(s, IBL_ERR_IO);
    assert_non_null(strstr(ibl_context_message(ctx), target));
    size_t n;
    uint8_t *b = slurp(target, &n);
    assert_int_equal(n, sizeof original);
    assert_memory_equal(b, original, n);
    free(b);
    assert_int_equal(count_entries(dir), 1);

    /* The rename fails (the target is a directory): the temporary is removed. */
    char sub[800];
    snprintf(sub, sizeof sub, "%s/sub", dir);
    assert_int_equal(mkdir(sub, 0755), 0);
    assert_int_equal(ibl_write_file_atomic(ctx, sub, big, 100), IBL_ERR_IO);
    assert_int_equal(count_entries(dir), 2);

    /* A successful write replaces the content. */
    assert_int_equal(ibl_write_file_atomic(ctx, target, big, 100), IBL_OK);
    b = slurp(target, &n);
    assert_int_equal(n, 100);
    free(b);
    assert_int_equal(count_entries(dir), 2);
    struct stat stt;
    assert_int_equal(stat(target, &stt), 0);
    assert_int_equal(stt.st_mode & 0777, 0644);

    /* A folder that cannot be written: missing, or read-only (root ignores the mode). */
    char missing[800];
    snprintf(missing, sizeof missing, "%s/no/such/dir/x.exr", dir);
    assert_int_equal(ibl_write_file_atomic(ctx, missing, big, 10), IBL_ERR_IO);
    assert_non_null(strstr(ibl_context_message(ctx), missing));
    if (geteuid() != 0) {
        char ro[800], file[900];
        snprintf(ro, sizeof ro, "%s/ro", dir);
        assert_int_equal(mkdir(ro, 0555), 0);
        snprintf(file, sizeof file, "%s/x.png", ro);
        assert_int_equal(ibl_write_file_atomic(ctx, file, big, 10), IBL_ERR_IO);
        assert_non_null(strstr(ibl_context_message(ctx), file));
        chmod(ro, 0755);
    }
    ibl_context_destroy(ctx);
}

static void read_file_errors(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    void *bytes;
    size_t n;
    const char *missing = test_path("does-not-exist.hdr");
    assert_int_equal(ibl_read_file(ctx, missing, &bytes, &n), IBL_ERR_IO);
    char expect[700];
    snprintf(expect, sizeof expect, "%s: cannot open: %s", missing, strerror(ENOENT));
    assert_string_equal(ibl_context_message(ctx), expect);
    assert_int_equal(ibl_read_file(ctx, test_tmpdir(), &bytes, &n), IBL_ERR_IO);
    ibl_context_destroy(ctx);

    /* Files beyond the context's memory limit are refused. */
    ibl_context_desc d = {0};
    d.threads = 1;
    d.max_bytes = 1000;
    assert_int_equal(ibl_context_create(&d, &ctx), IBL_OK);
    static uint8_t two_k[2000];
    spit(test_path("2k.bin"), two_k, sizeof two_k);
    assert_int_equal(ibl_read_file(ctx, test_path("2k.bin"), &bytes, &n), IBL_ERR_TOO_LARGE);
    assert_non_null(strstr(ibl_context_message(ctx), "2k.bin"));
    ibl_context_destroy(ctx);
}

static void api_edges(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_image im = make_image(ctx, 8, 4);
    assert_int_equal(ibl_write_image(ctx, test_path("x.tiff"), &im, NULL), IBL_ERR_INVALID_ARGUMENT);
    assert_false(test_file_exists(test_path("x.tiff")));
    ibl_write_desc wd = {0};
    wd.format = IBL_FORMAT_RG11B10F;
    assert_int_equal(ibl_write_image(ctx, test_path("x.exr"), &im, &wd), IBL_ERR_UNSUPPORTED);
    assert_int_equal(ibl_write_image(ctx, test_path("x.hdr"), &im, &wd), IBL_ERR_UNSUPPORTED);
    assert_int_equal(ibl_write_image(ctx, test_path("x.pfm"), &im, &wd), IBL_ERR_UNSUPPORTED);
    assert_int_equal(ibl_write_image(ctx, test_path("x.png"), &im, &wd), IBL_ERR_UNSUPPORTED);
    assert_false(test_file_exists(test_path("x.exr")));
    /* Flat formats hold one 2D image: a cube is refused, not silently cut. */
    ibl_texture cube;
    assert_int_equal(ibl_texture_alloc(ctx, IBL_TEXTURE_CUBE, 4, 4, 1, 1, &cube), IBL_OK);
    assert_int_equal(ibl_write_texture(ctx, test_path("c.exr"), &cube, NULL), IBL_ERR_UNSUPPORTED);
    void *bytes = NULL;
    size_t n = 0;
    assert_int_equal(ibl_encode_texture(ctx, IBL_FILE_HDR, &cube, NULL, &bytes, &n), IBL_ERR_UNSUPPORTED);
    ibl_texture_free(ctx, &cube);
    /* A one-level 2D texture goes to a flat format, and ibl_read_texture reads it back. */
    ibl_texture t;
    assert_int_equal(ibl_texture_alloc(ctx, IBL_TEXTURE_2D, 8, 4, 1, 1, &t), IBL_OK);
    for (size_t i = 0; i < 8 * 4 * 4; i++) t.data[i] = (float)i;
    assert_int_equal(ibl_encode_texture(ctx, IBL_FILE_EXR, &t, NULL, &bytes, &n), IBL_OK);
    ibl_texture r;
    ibl_file_info fi;
    assert_int_equal(decode(ctx, bytes, n, &r, &fi), IBL_OK);
    ibl_free(ctx, bytes);
    assert_int_equal(fi.kind, IBL_TEXTURE_2D);
    assert_int_equal(fi.levels, 1);
    assert_int_equal(fi.format, IBL_FORMAT_RGBA32F); /* alpha was not all 1 */
    assert_memory_equal(r.data, t.data, 8 * 4 * 4 * sizeof(float));
    ibl_texture_free(ctx, &r);
    ibl_texture_free(ctx, &t);
    ibl_image_free(ctx, &im);
    ibl_context_destroy(ctx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(file_types),         cmocka_unit_test(pfm_round_trip),
        cmocka_unit_test(pfm_grey_big_endian), cmocka_unit_test(hdr_uffizi),
        cmocka_unit_test(hdr_round_trip),     cmocka_unit_test(hdr_orientations),
        cmocka_unit_test(png16_round_trip),   cmocka_unit_test(png8_round_trip),
        cmocka_unit_test(png8_exposure_filmic), cmocka_unit_test(jpeg_round_trip),
        cmocka_unit_test(png_layouts),        cmocka_unit_test(truncated_files),
        cmocka_unit_test(wrong_magic),        cmocka_unit_test(absurd_dimensions),
        cmocka_unit_test(non_finite_pixels),  cmocka_unit_test(atomic_write),
        cmocka_unit_test(large_inputs_identical_at_any_thread_count),
        cmocka_unit_test(host_parallel_for_told_its_threads),
        cmocka_unit_test(read_file_errors),   cmocka_unit_test(api_edges),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
