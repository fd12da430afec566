/* The OpenEXR reader and writer: float and half round trips, a real DWAB file, data and
 * display windows, tiles, grey and every compression, exact scanline reads, bit-identical
 * decoding at any thread count, and the pixel policy as the decoding bands apply it. */
#include "test_io_helpers.h"

/* ---- OpenEXR ------------------------------------------------------------------------- */

static void exr_float_round_trip(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_image im = make_image(ctx, 41, 19);
    for (size_t i = 0; i < 41 * 19 * 4; i++) im.pixels[i] = ldexpf(frand(), (int)(frand() * 80) - 40);
    const ibl_exr_compression comps[] = {IBL_EXR_DEFAULT, IBL_EXR_NONE, IBL_EXR_RLE,
                                         IBL_EXR_ZIPS, IBL_EXR_ZIP, IBL_EXR_PIZ};
    for (size_t k = 0; k < sizeof comps / sizeof comps[0]; k++) {
        for (int rgba = 0; rgba < 2; rgba++) {
            ibl_write_desc wd = {0};
            wd.format = rgba ? IBL_FORMAT_RGBA32F : IBL_FORMAT_RGB32F;
            wd.exr_compression = comps[k];
            ibl_file_info fi;
            ibl_image back = write_read(ctx, "f.exr", &im, &wd, &fi);
            assert_int_equal(fi.format, wd.format);
            assert_int_equal(fi.has_alpha, rgba);
            for (size_t i = 0; i < 41 * 19; i++) {
                for (int c = 0; c < 3; c++) assert_true(bits_equal(back.pixels[i * 4 + c], im.pixels[i * 4 + c]));
                assert_true(bits_equal(back.pixels[i * 4 + 3], rgba ? im.pixels[i * 4 + 3] : 1.0f));
            }
            ibl_image_free(ctx, &back);
        }
    }
    ibl_image_free(ctx, &im);
    ibl_context_destroy(ctx);
}

/* Half: values with an 11-bit significand inside the half range come back exactly; finite
 * values above the largest half (65504) are clamped to it rather than becoming infinite. */
static void exr_half_round_trip(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_image im = make_image(ctx, 16, 9);
    for (size_t i = 0; i < 16 * 9 * 4; i++) {
        float m = (float)(1024 + (int)(frand() * 1024)) / 2048.0f; /* 11 significant bits */
        im.pixels[i] = ldexpf(m, (int)(frand() * 28) - 13);      /* normal half range */
    }
    im.pixels[0] = 1e6f;
    im.pixels[5] = 0.0f;
    ibl_write_desc wd = {0};
    wd.format = IBL_FORMAT_RGBA16F;
    wd.exr_compression = IBL_EXR_PIZ;
    ibl_file_info fi;
    ibl_image back = write_read(ctx, "h.exr", &im, &wd, &fi);
    assert_int_equal(fi.format, IBL_FORMAT_RGBA16F);
    assert_true(back.pixels[0] == 65504.0f);
    for (size_t i = 1; i < 16 * 9 * 4; i++) assert_true(back.pixels[i] == im.pixels[i]);
    ibl_image_free(ctx, &back);
    wd.format = IBL_FORMAT_RGB16F;
    back = write_read(ctx, "h3.exr", &im, &wd, &fi);
    assert_int_equal(fi.format, IBL_FORMAT_RGB16F);
    assert_true(back.pixels[7] == 1.0f);
    assert_true(back.pixels[6] == im.pixels[6]);
    ibl_image_free(ctx, &back);
    ibl_image_free(ctx, &im);
    ibl_context_destroy(ctx);
}

/* A real DWAB file: known size, plausible radiance, and our float re-encoding is exact. */
static void exr_real_dwab(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_image im;
    ibl_file_info fi;
    assert_int_equal(ibl_read_image(ctx, test_data("studio.exr"), NULL, &im, &fi), IBL_OK);
    assert_int_equal(fi.type, IBL_FILE_EXR);
    assert_int_equal(im.width, 1024);
    assert_int_equal(im.height, 512);
    assert_int_equal(fi.format, IBL_FORMAT_RGB32F);
    assert_int_equal(fi.has_alpha, 0);
    assert_true(fi.pixels.nan_count == 0 && fi.pixels.inf_count == 0);
    double sum = 0, maxv = 0;
    for (size_t i = 0; i < 1024 * 512; i++)
        for (int c = 0; c < 3; c++) {
            sum += im.pixels[i * 4 + c];
            if (im.pixels[i * 4 + c] > maxv) maxv = im.pixels[i * 4 + c];
        }
    double mean = sum / (1024.0 * 512 * 3);
    assert_true(isfinite(mean) && mean > 0.0);
    assert_true(maxv > mean); /* a studio has lights brighter than its average */
    ibl_write_desc wd = {0};
    wd.format = IBL_FORMAT_RGB32F;
    ibl_image back = write_read(ctx, "studio_zip.exr", &im, &wd, NULL);
    assert_memory_equal(back.pixels, im.pixels, 1024 * 512 * 4 * sizeof(float));
    ibl_image_free(ctx, &back);
    ibl_image_free(ctx, &im);
    ibl_context_destroy(ctx);
}

/* Hand-built uncompressed OpenEXR files (the layout of the OpenEXR file-format document),
 * to pin what our writer never produces: tiles, grey, and data != display window. */
typedef struct exr_builder {
    uint8_t b[16384];
    size_t n, table; /* bytes used; where the chunk offset table starts */
} exr_builder;

static void put(exr_builder *e, const void *v, size_t len)
{
    memcpy(e->b + e->n, v, len);
    e->n += len;
}

static void put_i32(exr_builder *e, int32_t v)
{
    put(e, &v, 4); /* little-endian host */
}

static void put_attr(exr_builder *e, const char *name, const char *type, const void *v, int32_t len)
{
    put(e, name, strlen(name) + 1);
    put(e, type, strlen(type) + 1);
    put_i32(e, len);
    put(e, v, (size_t)len);
}

/* The value stored for channel c (index in the sorted name list) at absolute pixel (x, y). */
static float exr_value(int c, int x, int y)
{
    return (float)(c * 100 + x * 10 + y) + 0.25f;
}

/* channels: names in sorted order (all FLOAT); tile 0 = scanlines. */
static size_t build_exr(exr_builder *e, const char *const *channels, int nch, const int32_t data[4],
                        const int32_t disp[4], int tile)
{
    e->n = 0;
    const uint8_t magic[8] = {0x76, 0x2f, 0x31, 0x01, 2, tile ? 2 : 0, 0, 0};
    put(e, magic, 8);
    uint8_t ch[256];
    size_t cn = 0;
    for (int c = 0; c < nch; c++) {
        size_t l = strlen(channels[c]) + 1;
        memcpy(ch + cn, channels[c], l), cn += l;
        const int32_t fields[4] = {2 /* FLOAT */, 0 /* pLinear + reserved */, 1, 1};
        memcpy(ch + cn, fields, 16), cn += 16;
    }
    ch[cn++] = 0;
    put_attr(e, "channels", "chlist", ch, (int32_t)cn);
    const uint8_t zero = 0;
    put_attr(e, "compression", "compression", &zero, 1);
    put_attr(e, "dataWindow", "box2i", data, 16);
    put_attr(e, "displayWindow", "box2i", disp, 16);
    put_attr(e, "lineOrder", "lineOrder", &zero, 1);
    const float one = 1.0f, centre[2] = {0, 0};
    put_attr(e, "pixelAspectRatio", "float", &one, 4);
    put_attr(e, "screenWindowCenter", "v2f", centre, 8);
    put_attr(e, "screenWindowWidth", "float", &one, 4);
    if (tile) {
        uint8_t td[9];
        int32_t t32 = tile;
        memcpy(td, &t32, 4), memcpy(td + 4, &t32, 4), td[8] = 0; /* one level */
        put_attr(e, "tiles", "tiledesc", td, 9);
    }
    put(e, &zero, 1);
    int w = data[2] - data[0] + 1, h = data[3] - data[1] + 1;
    int tx = tile ? (w + tile - 1) / tile : 1, ty = tile ? (h + tile - 1) / tile : h;
 size_t table = e->n;
    e->table = table;
    e->n += (size_t)tx * (size_t)ty * 8;
    for (int j = 0; j < ty; j++)
        for (int i = 0; i < tx; i++) {
            uint64_t off = e->n;
            memcpy(e->b + table + ((size_t)j * (size_t)tx + (size_t)i) * 8, &off, 8);
            int x0 = tile ? i * tile : 0, x1 = tile ? x0 + tile : w;
            int y0 = tile ? j * tile : j, y1 = tile ? y0 + tile : j + 1;
            if (x1 > w) x1 = w;
            if (y1 > h) y1 = h;
            if (tile) {
                put_i32(e, i), put_i32(e, j), put_i32(e, 0), put_i32(e, 0);
            } else {
                put_i32(e, data[1] + j);
            }
            put_i32(e, (y1 - y0) * (x1 - x0) * nch * 4);
            for (int y = y0; y < y1; y++)
                for (int c = 0; c < nch; c++)
                    for (int x = x0; x < x1; x++) {
                        float v = exr_value(c, data[0] + x, data[1] + y);
                        put(e, &v, 4);
                    }
        }
    return e->n;
}

static void exr_windows_tiles_grey(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    static exr_builder e;
    ibl_texture t;
    ibl_file_info fi;
    const char *const bgr[3] = {"B", "G", "R"};
    /* Data window inside a larger display window: the rest is black and transparent. */
    const int32_t data[4] = {1, 1, 2, 2}, disp[4] = {0, 0, 3, 2};
    size_t n = build_exr(&e, bgr, 3, data, disp, 0);
    assert_int_equal(decode(ctx, e.b, n, &t, &fi), IBL_OK);
    assert_int_equal(t.width, 4);
    assert_int_equal(t.height, 3);
    assert_int_equal(fi.format, IBL_FORMAT_RGB32F);
    for (int y = 0; y < 3; y++)
        for (int x = 0; x < 4; x++) {
            const float *p = t.data + ((size_t)y * 4 + (size_t)x) * 4;
            int inside = x >= 1 && x <= 2 && y >= 1 && y <= 2;
            assert_true(p[0] == (inside ? exr_value(2, x, y) : 0.0f)); /* R is channel 2 */
            assert_true(p[1] == (inside ? exr_value(1, x, y) : 0.0f));
            assert_true(p[2] == (inside ? exr_value(0, x, y) : 0.0f));
            assert_true(p[3] == (inside ? 1.0f : 0.0f));
        }
    ibl_texture_free(ctx, &t);
    /* Data window beyond the display window: cropped. */
    const int32_t data2[4] = {-1, -2, 3, 3}, disp2[4] = {0, 0, 1, 1};
    n = build_exr(&e, bgr, 3, data2, disp2, 0);
    assert_int_equal(decode(ctx, e.b, n, &t, NULL), IBL_OK);
    assert_int_equal(t.width, 2);
    assert_int_equal(t.height, 2);
    for (int y = 0; y < 2; y++)
        for (int x = 0; x < 2; x++) assert_true(t.data[((size_t)y * 2 + (size_t)x) * 4] == exr_value(2, x, y));
    ibl_texture_free(ctx, &t);
    /* Tiled (2x2 tiles, partial at the edges), grey Y with alpha. */
    const char *const ay[2] = {"A", "Y"};
    const int32_t data3[4] = {0, 0, 4, 2};
    n = build_exr(&e, ay, 2, data3, data3, 2);
    assert_int_equal(decode(ctx, e.b, n, &t, &fi), IBL_OK);
    assert_int_equal(t.width, 5);
    assert_int_equal(t.height, 3);
    assert_int_equal(fi.format, IBL_FORMAT_RGBA32F);
    assert_int_equal(fi.has_alpha, 1);
    for (int y = 0; y < 3; y++)
        for (int x = 0; x < 5; x++) {
            const float *p = t.data + ((size_t)y * 5 + (size_t)x) * 4;
            for (int c = 0; c < 3; c++) assert_true(p[c] == exr_value(1, x, y));
            assert_true(p[3] == exr_value(0, x, y));
        }
    ibl_texture_free(ctx, &t);
    /* Absurd tiles (one 60000x60000 tile for a 5x3 image) would make OpenEXR allocate
     * gigabytes for its tile buffer: refused from the header (found by fuzzing). */
    n = build_exr(&e, ay, 2, data3, data3, 60000);
    assert_int_equal(decode(ctx, e.b, n, &t, NULL), IBL_ERR_UNSUPPORTED);
    assert_non_null(strstr(ibl_context_message(ctx), "tiles"));
    /* Inputs found by fuzzing, each of which made OpenEXR ask for gigabytes: a huge tile, and
     * a channel list shorter than its declared size (OpenEXR reads it by structure and lost
     * track of the header). */
    ibl_image im;
    assert_int_equal(ibl_read_image(ctx, test_data("fuzz_exr_huge_tile.exr"), NULL, &im, NULL),
                     IBL_ERR_UNSUPPORTED);
    assert_int_equal(ibl_read_image(ctx, test_data("fuzz_exr_chlist_desync.exr"), NULL, &im, NULL),
                     IBL_ERR_FORMAT);
    assert_non_null(strstr(ibl_context_message(ctx), "channel list"));
    /* Same for a fixed-size attribute declared with another size. */
    n = build_exr(&e, bgr, 3, data, disp, 0);
    for (size_t i = 8; i + 12 < n; i++)
        if (memcmp(e.b + i, "compression\0compression\0", 24) == 0) {
            e.b[i + 24] = 2; /* declared size 2 for a 1-byte value */
            break;
        }
    assert_int_equal(decode(ctx, e.b, n, &t, NULL), IBL_ERR_FORMAT);
    assert_non_null(strstr(ibl_context_message(ctx), "does not match its type"));
    /* Channels that are neither colour nor grey are refused by name. */
    const char *const z[1] = {"Z"};
    n = build_exr(&e, z, 1, data3, data3, 0);
    assert_int_equal(decode(ctx, e.b, n, &t, NULL), IBL_ERR_UNSUPPORTED);
    assert_non_null(strstr(ibl_context_message(ctx), "Z"));
    /* A chunk offset pointing past the end is refused before decoding. */
    n = build_exr(&e, bgr, 3, data, disp, 0);
    memset(e.b + e.table + 8, 0xff, 8);
    assert_int_equal(decode(ctx, e.b, n, &t, NULL), IBL_ERR_FORMAT);
    ibl_context_destroy(ctx);
}

/* Samples written by OpenEXR itself (tests/data/make_exr_samples.cpp) from this pattern. */
static void exr_pattern(int x, int y, float *rgb)
{
    rgb[0] = 0.5f + 0.25f * sinf(x / 5.0f);
    rgb[1] = (y + 1) / 16.0f;
    rgb[2] = 0.1f + 0.05f * (float)((x + 2 * y) % 7);
}

/* Largest error relative to the pattern (whose values lie in [0.06, 1.5]). */
static double exr_sample_error(ibl_context *ctx, const char *name, ibl_format expect_format)
{
    ibl_image im;
    ibl_file_info fi;
    assert_int_equal(ibl_read_image(ctx, test_data(name), NULL, &im, &fi), IBL_OK);
    assert_int_equal(im.width, 32);
    assert_int_equal(im.height, 24);
    assert_int_equal(fi.format, expect_format);
    double worst = 0;
    for (int y = 0; y < 24; y++)
        for (int x = 0; x < 32; x++) {
            float p[3];
            exr_pattern(x, y, p);
            const float *q = ibl_image_texel(&im, x, y);
            for (int c = 0; c < 3; c++) worst = fmax(worst, fabs(q[c] - p[c]) / p[c]);
            assert_true(q[3] == 1.0f);
        }
    ibl_image_free(ctx, &im);
    return worst;
}

static void exr_every_compression(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    /* Lossless codecs on half data: only the float -> half rounding, <= 2^-11 relative. PXR24
     * is lossless for half too. Tiled mip-mapped: level 0, also exact half. */
    const char *lossless[] = {"exr_none.exr", "exr_rle.exr", "exr_zips.exr", "exr_zip.exr",
                              "exr_piz.exr", "exr_pxr24.exr", "exr_tiled_mip.exr"};
    for (size_t i = 0; i < sizeof lossless / sizeof lossless[0]; i++)
        assert_true(exr_sample_error(ctx, lossless[i], IBL_FORMAT_RGB16F) <= ldexp(1, -11));
    /* PXR24 on float keeps 15 of 23 mantissa bits (rounded): <= 2^-16 relative. */
    assert_true(exr_sample_error(ctx, "exr_pxr24_float.exr", IBL_FORMAT_RGB32F) <= ldexp(1, -16));
    /* Lossy codecs: a loose bound that still catches any misdecoded block, swapped channel
     * or shifted row (those give errors of order 1). B44 quantises 4x4 blocks of half; DWA
     * is a DCT codec at its default quality; luminance/chroma subsamples chroma 2x2. */
    /* Measured with OpenEXR 3.1.5: 0.021 for B44/B44A, 0.054 for DWAA/DWAB (half or float). */
    assert_true(exr_sample_error(ctx, "exr_b44.exr", IBL_FORMAT_RGB16F) <= 0.05);
    assert_true(exr_sample_error(ctx, "exr_b44a.exr", IBL_FORMAT_RGB16F) <= 0.05);
    assert_true(exr_sample_error(ctx, "exr_dwaa.exr", IBL_FORMAT_RGB16F) <= 0.1);
    assert_true(exr_sample_error(ctx, "exr_dwab.exr", IBL_FORMAT_RGB16F) <= 0.1);
    assert_true(exr_sample_error(ctx, "exr_dwaa_float.exr", IBL_FORMAT_RGB32F) <= 0.1);
    /* Luminance/chroma: this pattern's blue changes every pixel, so subsampled chroma cannot
     * hold it (OpenEXR's own RgbaInputFile gives the same 178% on blue); luminance is kept at
     * full resolution: Rec. 709 luminance within 1% (measured 0.45%). */
    ibl_image yc;
    ibl_file_info fi;
    assert_int_equal(ibl_read_image(ctx, test_data("exr_yc.exr"), NULL, &yc, &fi), IBL_OK);
    assert_int_equal(fi.format, IBL_FORMAT_RGB16F);
    for (int y = 0; y < 24; y++)
        for (int x = 0; x < 32; x++) {
            float p[3];
            exr_pattern(x, y, p);
            const float *q = ibl_image_texel(&yc, x, y);
            double lp = 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
            double lq = 0.2126 * q[0] + 0.7152 * q[1] + 0.0722 * q[2];
            assert_true(fabs(lq - lp) <= 0.01 * lp);
        }
    ibl_image_free(ctx, &yc);
    /* A file whose only colour is a named layer: that layer is read (float, exact). */
    assert_true(exr_sample_error(ctx, "exr_layer.exr", IBL_FORMAT_RGB32F) == 0.0);
    ibl_context_destroy(ctx);
}

/* Scanline EXRs without compression or with ZIP / ZIPS are decoded by src/io/exr.c itself,
 * in bands on several threads: every value OpenEXR's writer stored must come back bit for bit
 * (float: any finite positive value incl. float denormals; half: values exact in half), with
 * alpha when written and 1 when not, at 1, 2 and 8 threads. The image's odd size gives a
 * partial last chunk and, with ZIPS (one line per chunk), bands of several chunks. */
static void exr_scanline_exact(void **state)
{
    (void)state;
    enum { W = 67, H = 53 };
    ibl_context *one = test_context(1);
    ibl_image im;
    assert_int_equal(ibl_image_alloc(one, W, H, &im), IBL_OK);
    const ibl_format formats[4] = {IBL_FORMAT_RGBA32F, IBL_FORMAT_RGB32F, IBL_FORMAT_RGBA16F,
                                   IBL_FORMAT_RGB16F};
    const ibl_exr_compression comps[3] = {IBL_EXR_NONE, IBL_EXR_ZIPS, IBL_EXR_ZIP};
    for (int fi = 0; fi < 4; fi++) {
        int half = formats[fi] == IBL_FORMAT_RGBA16F || formats[fi] == IBL_FORMAT_RGB16F;
        int alpha = formats[fi] == IBL_FORMAT_RGBA32F || formats[fi] == IBL_FORMAT_RGBA16F;
        for (size_t i = 0; i < (size_t)W * H * 4; i++) {
            /* log-uniform magnitudes over the whole range of the format (tiny to huge) */
            float v = ldexpf(0.5f + 0.5f * frand(), (int)(frand() * (half ? 30 : 250)) - (half ? 14 : 140));
            if (i % 97 == 0) v = 0.0f;
            if (half) v = ibl_half_to_float_exact(v);
            if (i % 4 == 3) v = alpha ? (half ? ibl_half_to_float_exact(frand()) : frand()) : 1.0f;
            im.pixels[i] = v;
        }
        for (int ci = 0; ci < 3; ci++) {
            ibl_write_desc wd = {0};
            wd.format = formats[fi];
            wd.exr_compression = comps[ci];
            void *bytes;
            size_t size;
            ibl_texture view = {0};
            view.kind = IBL_TEXTURE_2D;
            view.width = W;
            view.height = H;
            view.depth = view.levels = 1;
            view.data = im.pixels;
            assert_int_equal(ibl_encode_texture(one, IBL_FILE_EXR, &view, &wd, &bytes, &size), IBL_OK);
            const int threads[3] = {1, 2, 8};
            for (int t = 0; t < 3; t++) {
                ibl_context *ctx = test_context(threads[t]);
                ibl_texture tex;
                assert_int_equal(ibl_decode_texture(ctx, bytes, size, "x.exr", NULL, &tex, NULL), IBL_OK);
                assert_int_equal(tex.width, W);
                assert_int_equal(tex.height, H);
                if (memcmp(tex.data, im.pixels, (size_t)W * H * 4 * sizeof(float)) != 0)
                    fail_msg("format %d compression %d threads %d: pixels differ", fi, ci, threads[t]);
                ibl_texture_free(ctx, &tex);
                ibl_context_destroy(ctx);
            }
            ibl_free(one, bytes);
            /* a damaged chunk (the last one's compressed bytes, of a smooth image that zlib
             * does shrink): the file is refused with OpenEXR's own message, at any thread
             * count, and nothing is left allocated */
            if (comps[ci] != IBL_EXR_NONE) {
                ibl_image smooth;
                assert_int_equal(ibl_image_alloc(one, W, H, &smooth), IBL_OK);
                for (size_t i = 0; i < (size_t)W * H * 4; i++) smooth.pixels[i] = (float)(i % 8) * 0.125f;
                view.data = smooth.pixels;
                assert_int_equal(ibl_encode_texture(one, IBL_FILE_EXR, &view, &wd, &bytes, &size), IBL_OK);
                ibl_image_free(one, &smooth);
                uint8_t *b = bytes;
                for (size_t k = size - 40; k < size - 8; k++) b[k] ^= 0x5A;
                for (int t = 0; t < 3; t++) {
                    ibl_context *ctx = test_context(threads[t]);
                    ibl_texture tex;
                    ibl_status st = ibl_decode_texture(ctx, bytes, size, "x.exr", NULL, &tex, NULL);
                    assert_int_equal(st, IBL_ERR_FORMAT);
                    assert_true(strncmp(ibl_context_message(ctx), "x.exr: ", 7) == 0);
                    ibl_context_destroy(ctx);
                }
                ibl_free(one, bytes);
            }
        }
    }
    ibl_image_free(one, &im);
    ibl_context_destroy(one);
}

/* Real files through every decoding path (DWAB float, the test HDRIs; the samples of every
 * compression) give the same pixels at 1, 2 and 8 threads. */
static void exr_identical_at_any_thread_count(void **state)
{
    (void)state;
    const char *files[] = {"city.exr", "forest_128x64.exr", "exr_zip.exr", "exr_zips.exr",
                           "exr_piz.exr", "exr_tiled_mip.exr", "exr_layer.exr", "exr_yc.exr"};
    for (size_t i = 0; i < sizeof files / sizeof files[0]; i++) {
        ibl_texture ref = {0};
        const int threads[3] = {1, 2, 8};
        ibl_context *ctxs[3];
        for (int t = 0; t < 3; t++) {
            ctxs[t] = test_context(threads[t]);
            ibl_texture tex;
            assert_int_equal(ibl_read_texture(ctxs[t], test_data(files[i]), NULL, &tex, NULL), IBL_OK);
            if (t == 0) {
                ref = tex;
                continue;
            }
            size_t n = ibl_texture_floats(tex.kind, tex.width, tex.height, tex.depth, tex.levels);
            if (memcmp(tex.data, ref.data, n * sizeof(float)) != 0)
                fail_msg("%s: %d threads differ from 1", files[i], threads[t]);
            ibl_texture_free(ctxs[t], &tex);
        }
        ibl_texture_free(ctxs[0], &ref);
        for (int t = 0; t < 3; t++) ibl_context_destroy(ctxs[t]);
    }
}


/* The pixel policy applied by the decoding bands themselves (exr.c sanitizes each band's rows
 * as it finishes them): NaN, infinities and negatives planted in a float file come back as the
 * policy says, checked texel by texel against the rule written out here (not against
 * ibl_sanitize_pixels), with the planted counts, at 1, 2 and 8 threads, through the fast ZIP
 * path (16-line chunks: 13 bands) and OpenEXR's bands (PIZ, 32-line chunks: 7 bands). */
static void exr_pixel_policy_in_bands(void **state)
{
    (void)state;
    enum { W = 300, H = 200 };
    const float clamp = 1000.0f;
    ibl_context *one = test_context(1);
    ibl_image im = make_image(one, W, H), want = make_image(one, W, H);
    uint64_t nan = 0, inf = 0, neg = 0;
    for (size_t t = 0; t < (size_t)W * H; t++) {
        float *p = im.pixels + t * 4, *q = want.pixels + t * 4;
        for (int c = 0; c < 4; c++) p[c] = q[c] = 0.25f + frand();
        if (t % 101 == 3) p[1] = NAN, q[1] = 0.0f, nan++;
        else if (t % 103 == 5) p[2] = INFINITY, q[2] = clamp, inf++;
        else if (t % 107 == 7) p[0] = -INFINITY, q[0] = 0.0f, inf++;
        else if (t % 109 == 9) p[2] = -frand() - 0.5f, q[2] = 0.0f, neg++;
        else if (t % 113 == 11) p[3] = NAN, q[3] = 1.0f; /* alpha: kept, NaN as 1, uncounted */
    }
    const ibl_exr_compression comps[2] = {IBL_EXR_ZIP, IBL_EXR_PIZ};
    for (int k = 0; k < 2; k++) {
        ibl_write_desc wd = {0};
        wd.format = IBL_FORMAT_RGBA32F;
        wd.exr_compression = comps[k];
        const char *path = test_path(k ? "policy_piz.exr" : "policy_zip.exr");
        assert_int_equal(ibl_write_image(one, path, &im, &wd), IBL_OK);
        const int threads[3] = {1, 2, 8};
        for (int t = 0; t < 3; t++) {
            ibl_context *ctx = test_context(threads[t]);
            ibl_image back;
            ibl_file_info fi;
            assert_int_equal(ibl_read_image(ctx, path, NULL, &back, &fi), IBL_ERR_BAD_PIXELS);
            assert_int_equal(fi.pixels.inf_count, inf);
            char message[80];
            snprintf(message, sizeof message, "%llu texels are infinite", (unsigned long long)inf);
            assert_non_null(strstr(ibl_context_message(ctx), message));
            assert_non_null(strstr(ibl_context_message(ctx), "policy_"));
            ibl_read_desc rd = {.clamp_infinite = 1, .clamp_value = clamp};
            assert_int_equal(ibl_read_image(ctx, path, &rd, &back, &fi), IBL_OK);
            assert_int_equal(fi.pixels.nan_count, nan);
            assert_int_equal(fi.pixels.inf_count, inf);
            assert_int_equal(fi.pixels.negative_count, neg);
            assert_int_equal(fi.pixels.texel_count, (uint64_t)W * H);
            for (size_t i = 0; i < (size_t)W * H * 4; i++)
                if (!bits_equal(back.pixels[i], want.pixels[i]))
                    fail_msg("compression %d, %d threads: texel %zu channel %zu is %g, not %g", k,
                             threads[t], i / 4, i % 4, back.pixels[i], want.pixels[i]);
            ibl_image_free(ctx, &back);
            ibl_context_destroy(ctx);
        }
    }
    ibl_image_free(one, &want);
    ibl_image_free(one, &im);
    ibl_context_destroy(one);
}


int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(exr_float_round_trip),
        cmocka_unit_test(exr_half_round_trip),
        cmocka_unit_test(exr_real_dwab),
        cmocka_unit_test(exr_windows_tiles_grey),
        cmocka_unit_test(exr_every_compression),
        cmocka_unit_test(exr_scanline_exact),
        cmocka_unit_test(exr_identical_at_any_thread_count),
        cmocka_unit_test(exr_pixel_policy_in_bands),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
