/* The JPEG reader and writer (src/io/jpeg.c, libjpeg-turbo): files written here with the
 * libjpeg API (baseline, progressive, one scan per component, grey, arithmetic, CMYK) read
 * back exactly as libjpeg decodes them and within a stated bound of what was written;
 * truncated files, with or without an end marker appended, are refused with one line naming
 * the file; ibl's own previews are 4:4:4 at quality 95 whatever their size. */
#include "test_support.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jpeglib.h>

/* ---- helpers ------------------------------------------------------------------------- */

/* An RGB (or grey) image of w x h 8-bit samples: smooth gradients with a little texture, so
 * that every DCT band carries something but quantisation at quality 100 stays exact. */
static uint8_t *make_samples(int w, int h, int channels)
{
    uint8_t *s = malloc((size_t)w * (size_t)h * (size_t)channels);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            for (int c = 0; c < channels; c++) {
                double v = 128 + 90 * sin(0.11 * x + 0.07 * y + 1.9 * c) + 20 * cos(0.9 * x * (c + 1) - 0.4 * y);
                s[((size_t)y * (size_t)w + (size_t)x) * (size_t)channels + (size_t)c] =
                    (uint8_t)(v < 0 ? 0 : v > 255 ? 255 : v + 0.5);
            }
    return s;
}

typedef enum coding { BASELINE, PROGRESSIVE, SCAN_PER_COMPONENT, ARITHMETIC } coding;

typedef struct encoded {
    unsigned char *bytes;
    unsigned long size;
} encoded;

/* Encodes samples with libjpeg itself. Progressive uses libjpeg's standard script; the scan
 * script, when given, replaces it. */
static encoded encode(const uint8_t *samples, int w, int h, int channels, J_COLOR_SPACE space,
                      int quality, int chroma_halved, coding how, const jpeg_scan_info *script,
                      int script_scans)
{
    struct jpeg_compress_struct c;
    struct jpeg_error_mgr err;
    encoded out = {NULL, 0};
    c.err = jpeg_std_error(&err);
    jpeg_create_compress(&c);
    jpeg_mem_dest(&c, &out.bytes, &out.size);
    c.image_width = (JDIMENSION)w;
    c.image_height = (JDIMENSION)h;
    c.input_components = channels;
    c.in_color_space = space;
    jpeg_set_defaults(&c);
    jpeg_set_quality(&c, quality, TRUE);
    if (channels == 3 && !chroma_halved) c.comp_info[0].h_samp_factor = c.comp_info[0].v_samp_factor = 1;
    static jpeg_scan_info per_component[3];
    if (how == PROGRESSIVE) jpeg_simple_progression(&c);
    if (how == SCAN_PER_COMPONENT) {
        for (int i = 0; i < 3; i++) {
            per_component[i].comps_in_scan = 1;
            per_component[i].component_index[0] = i;
            per_component[i].Ss = 0, per_component[i].Se = 63, per_component[i].Ah = 0, per_component[i].Al = 0;
        }
        c.scan_info = per_component;
        c.num_scans = 3;
    }
    if (script) {
        c.scan_info = script;
        c.num_scans = script_scans;
    }
    if (how == ARITHMETIC) c.arith_code = TRUE;
    jpeg_start_compress(&c, TRUE);
    while (c.next_scanline < c.image_height) {
        JSAMPROW row = (JSAMPROW)(samples + (size_t)c.next_scanline * (size_t)w * (size_t)channels);
        jpeg_write_scanlines(&c, &row, 1);
    }
    jpeg_finish_compress(&c);
    jpeg_destroy_compress(&c);
    return out;
}

/* libjpeg's own decode to RGBA, with the settings ibl uses (its defaults). */
static uint8_t *libjpeg_decode(const unsigned char *bytes, size_t size, int *w, int *h)
{
    struct jpeg_decompress_struct d;
    struct jpeg_error_mgr err;
    d.err = jpeg_std_error(&err);
    jpeg_create_decompress(&d);
    jpeg_mem_src(&d, bytes, (unsigned long)size);
    jpeg_read_header(&d, TRUE);
    d.out_color_space = JCS_EXT_RGBA;
    jpeg_start_decompress(&d);
    *w = (int)d.output_width;
    *h = (int)d.output_height;
    uint8_t *rgba = malloc((size_t)*w * (size_t)*h * 4);
    while (d.output_scanline < d.output_height) {
        JSAMPROW row = rgba + (size_t)d.output_scanline * (size_t)*w * 4;
        jpeg_read_scanlines(&d, &row, 1);
    }
    jpeg_finish_decompress(&d);
    jpeg_destroy_decompress(&d);
    return rgba;
}

/* The sRGB decoding the library applies to 8-bit codes (IEC 61966-2-1), computed here the
 * same way, so that equal codes give bit-identical floats. */
static float code_to_linear(int code)
{
    double v = code / 255.0;
    return (float)(v <= 0.04045 ? v / 12.92 : pow((v + 0.055) / 1.055, 2.4));
}

static int bits_equal(float a, float b)
{
    return memcmp(&a, &b, sizeof a) == 0;
}

/* Decodes through ibl and checks each texel against libjpeg's own decode, bit for bit
 * through the sRGB table; returns the largest difference, in codes, between the decoded
 * image and the samples that were encoded. */
static int check_read_back(ibl_context *ctx, encoded e, const uint8_t *samples, int w, int h, int channels)
{
    ibl_texture t;
    ibl_file_info fi;
    ibl_status s = ibl_decode_texture(ctx, e.bytes, e.size, "back.jpg", NULL, &t, &fi);
    if (s != IBL_OK) fail_msg("%s", ibl_context_message(ctx));
    assert_int_equal(fi.type, IBL_FILE_JPEG);
    assert_int_equal(fi.format, IBL_FORMAT_RGBA8_SRGB);
    assert_int_equal(fi.has_alpha, 0);
    assert_int_equal(t.width, w);
    assert_int_equal(t.height, h);
    int lw, lh;
    uint8_t *ref = libjpeg_decode(e.bytes, e.size, &lw, &lh);
    int worst = 0;
    for (size_t i = 0; i < (size_t)w * (size_t)h; i++) {
        for (int c = 0; c < 3; c++) {
            if (!bits_equal(t.data[i * 4 + (size_t)c], code_to_linear(ref[i * 4 + (size_t)c])))
                fail_msg("texel %zu channel %d: %.9g, libjpeg's code %d", i, c, t.data[i * 4 + (size_t)c],
                         ref[i * 4 + (size_t)c]);
            int written = samples[i * (size_t)channels + (size_t)(channels == 3 ? c : 0)];
            int d = abs(ref[i * 4 + (size_t)c] - written);
            if (d > worst) worst = d;
        }
        assert_true(t.data[i * 4 + 3] == 1.0f);
    }
    free(ref);
    ibl_texture_free(ctx, &t);
    return worst;
}

/* Offsets of the entropy-coded data of every scan: from the end of each SOS segment to the
 * next marker that is not a restart or a stuffed byte. */
typedef struct scan_span {
    size_t start, end;
} scan_span;

static int find_scans(const unsigned char *b, size_t n, scan_span *spans, int max)
{
    int count = 0;
    size_t pos = 2;
    while (pos + 4 <= n && count < max) {
        assert_int_equal(b[pos], 0xFF);
        int marker = b[pos + 1];
        if (marker == 0xD9) break;
        size_t len = (size_t)b[pos + 2] << 8 | b[pos + 3];
        pos += 2 + len;
        if (marker != 0xDA) continue;
        spans[count].start = pos;
        while (pos + 1 < n && !(b[pos] == 0xFF && b[pos + 1] != 0 && !(b[pos + 1] >= 0xD0 && b[pos + 1] <= 0xD7)))
            pos++;
        spans[count++].end = pos;
    }
    return count;
}

/* The file cut at `cut` bytes, with an end marker appended or not, must be refused with one
 * line naming it. */
static void expect_cut_refused(ibl_context *ctx, encoded e, size_t cut, int end_marker)
{
    unsigned char *b = malloc(cut + 2);
    memcpy(b, e.bytes, cut);
    size_t n = cut;
    if (end_marker) b[n++] = 0xFF, b[n++] = 0xD9;
    ibl_texture t;
    ibl_status s = ibl_decode_texture(ctx, b, n, "cut.jpg", NULL, &t, NULL);
    if (s == IBL_OK) fail_msg("a file cut at %zu of %lu bytes%s was read", cut, e.size, end_marker ? " + EOI" : "");
    assert_int_equal(s, IBL_ERR_FORMAT);
    assert_null(t.data);
    const char *m = ibl_context_message(ctx);
    assert_int_equal(strncmp(m, "cut.jpg: ", 9), 0);
    assert_null(strchr(m, '\n'));
    free(b);
}

/* ---- reading ------------------------------------------------------------------------- */

/* Quality 100 with full-resolution chroma quantises every coefficient with step 1: what is
 * left is rounding, of the colour conversion (up to 1.4 codes in blue alone) and of the 64
 * coefficients of a block (each off by up to half a step), which on this image sums to at
 * most 4 codes: the bound is 6. At quality 90 with 4:2:0 chroma the error is the image's own
 * (its fine chroma texture is lost by design): there only libjpeg's decode is matched. */
enum { Q100_BOUND = 6 };

static void baseline_and_progressive_read_back(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    const int w = 67, h = 45;
    uint8_t *rgb = make_samples(w, h, 3);
    const coding codings[] = {BASELINE, PROGRESSIVE, SCAN_PER_COMPONENT};
    for (int k = 0; k < 3; k++) {
        encoded e = encode(rgb, w, h, 3, JCS_RGB, 100, 0, codings[k], NULL, 0);
        assert_true(check_read_back(ctx, e, rgb, w, h, 3) <= Q100_BOUND);
        free(e.bytes);
        e = encode(rgb, w, h, 3, JCS_RGB, 90, 1, codings[k], NULL, 0);
        (void)check_read_back(ctx, e, rgb, w, h, 3);
        free(e.bytes);
    }
    free(rgb);
    ibl_context_destroy(ctx);
}

/* A grey JPEG reads as R = G = B; without a colour conversion, quality 100 leaves only the
 * coefficients' rounding (at most 1 code on this image; the bound is 2). */
static void grey_reads_as_rgb(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    const int w = 30, h = 17;
    uint8_t *grey = make_samples(w, h, 1);
    for (int progressive = 0; progressive < 2; progressive++) {
        encoded e = encode(grey, w, h, 1, JCS_GRAYSCALE, 100, 0, progressive ? PROGRESSIVE : BASELINE, NULL, 0);
        assert_true(check_read_back(ctx, e, grey, w, h, 1) <= 2);
        ibl_texture t;
        assert_int_equal(ibl_decode_texture(ctx, e.bytes, e.size, "grey.jpg", NULL, &t, NULL), IBL_OK);
        for (size_t i = 0; i < (size_t)w * h; i++) {
            assert_true(t.data[i * 4] == t.data[i * 4 + 1]);
            assert_true(t.data[i * 4] == t.data[i * 4 + 2]);
        }
        ibl_texture_free(ctx, &t);
        free(e.bytes);
    }
    free(grey);
    ibl_context_destroy(ctx);
}

/* Cut inside the coded data at 25, 50, 75 and 90 % of its scan, with an end marker appended
 * (libjpeg meets it mid-scan and would fill the rest with grey) and without one. */
static void truncated_scan_refused(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    const int w = 96, h = 64;
    uint8_t *rgb = make_samples(w, h, 3);
    const coding codings[] = {BASELINE, PROGRESSIVE};
    for (int k = 0; k < 2; k++) {
        encoded e = encode(rgb, w, h, 3, JCS_RGB, 95, 1, codings[k], NULL, 0);
        scan_span spans[16];
        int scans = find_scans(e.bytes, e.size, spans, 16);
        assert_true(scans >= 1);
        /* the longest scan: the baseline file's only one, a progressive file's largest */
        scan_span longest = spans[0];
        for (int i = 1; i < scans; i++)
            if (spans[i].end - spans[i].start > longest.end - longest.start) longest = spans[i];
        const int percent[] = {25, 50, 75, 90};
        for (int p = 0; p < 4; p++) {
            size_t cut = longest.start + (longest.end - longest.start) * (size_t)percent[p] / 100;
            expect_cut_refused(ctx, e, cut, 1);
            expect_cut_refused(ctx, e, cut, 0);
        }
        /* the whole coded data without the end marker */
        expect_cut_refused(ctx, e, e.size - 2, 0);
        free(e.bytes);
    }
    free(rgb);
    ibl_context_destroy(ctx);
}

/* A file of several scans cut between two of them, with an end marker appended, is a valid
 * JPEG to libjpeg: it decodes without a warning, the missing scans as zeros. Refused. */
static void cut_between_scans_refused(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    const int w = 40, h = 24;
    uint8_t *rgb = make_samples(w, h, 3);
    const coding codings[] = {PROGRESSIVE, SCAN_PER_COMPONENT};
    for (int k = 0; k < 2; k++) {
        encoded e = encode(rgb, w, h, 3, JCS_RGB, 100, 0, codings[k], NULL, 0);
        scan_span spans[16];
        int scans = find_scans(e.bytes, e.size, spans, 16);
        assert_int_equal(scans, k == 0 ? 10 : 3);
        /* just before each later scan's SOS marker (and any tables in front of it) */
        for (int i = 0; i + 1 < scans; i++) expect_cut_refused(ctx, e, spans[i].end, 1);
        assert_true(check_read_back(ctx, e, rgb, w, h, 3) <= Q100_BOUND);
        free(e.bytes);
    }
    free(rgb);
    ibl_context_destroy(ctx);
}

/* Arithmetic coding (a cut file cannot be told from a whole one) and CMYK (no conversion to
 * RGB in libjpeg) are refused as unsupported, with one line naming the file. */
static void unsupported_codings(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    uint8_t *rgb = make_samples(16, 16, 3);
    encoded e = encode(rgb, 16, 16, 3, JCS_RGB, 90, 1, ARITHMETIC, NULL, 0);
    ibl_texture t;
    assert_int_equal(ibl_decode_texture(ctx, e.bytes, e.size, "arith.jpg", NULL, &t, NULL), IBL_ERR_UNSUPPORTED);
    assert_non_null(strstr(ibl_context_message(ctx), "arith.jpg: arithmetic-coded JPEG"));
    free(e.bytes);
    free(rgb);
    uint8_t *cmyk = make_samples(16, 16, 4);
    e = encode(cmyk, 16, 16, 4, JCS_CMYK, 90, 0, BASELINE, NULL, 0);
    assert_int_equal(ibl_decode_texture(ctx, e.bytes, e.size, "cmyk.jpg", NULL, &t, NULL), IBL_ERR_UNSUPPORTED);
    assert_non_null(strstr(ibl_context_message(ctx), "cmyk.jpg: CMYK JPEG"));
    assert_null(strchr(ibl_context_message(ctx), '\n'));
    free(e.bytes);
    free(cmyk);
    ibl_context_destroy(ctx);
}

/* Progressive scripts of 100 scans (read) and 101 (refused): the DC of all components, the
 * AC of the two chroma components, each luma AC coefficient alone without its last bit, and
 * that bit in `refinements` bands. */
static int many_scans_script(jpeg_scan_info *script, int refinements)
{
    int n = 0;
    script[n].comps_in_scan = 3;
    for (int c = 0; c < 3; c++) script[n].component_index[c] = c;
    script[n].Ss = script[n].Se = script[n].Ah = script[n].Al = 0;
    n++;
    for (int c = 1; c < 3; c++, n++) {
        script[n].comps_in_scan = 1;
        script[n].component_index[0] = c;
        script[n].Ss = 1, script[n].Se = 63, script[n].Ah = script[n].Al = 0;
    }
    for (int k = 1; k < 64; k++, n++) {
        script[n].comps_in_scan = 1;
        script[n].component_index[0] = 0;
        script[n].Ss = script[n].Se = k, script[n].Ah = 0, script[n].Al = 1;
    }
    for (int i = 0; i < refinements; i++, n++) {
        script[n].comps_in_scan = 1;
        script[n].component_index[0] = 0;
        script[n].Ss = 1 + 63 * i / refinements, script[n].Se = 63 * (i + 1) / refinements;
        script[n].Ah = 1, script[n].Al = 0;
    }
    return n;
}

static void scan_count_limit(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    const int w = 16, h = 16;
    uint8_t *rgb = make_samples(w, h, 3);
    static jpeg_scan_info script[128];
    for (int scans = 100; scans <= 101; scans++) {
        int n = many_scans_script(script, scans - 66);
        assert_int_equal(n, scans);
        encoded e = encode(rgb, w, h, 3, JCS_RGB, 100, 0, PROGRESSIVE, script, n);
        ibl_texture t;
        ibl_status s = ibl_decode_texture(ctx, e.bytes, e.size, "scans.jpg", NULL, &t, NULL);
        if (scans == 100) {
            if (s != IBL_OK) fail_msg("%s", ibl_context_message(ctx));
            ibl_texture_free(ctx, &t);
            assert_true(check_read_back(ctx, e, rgb, w, h, 3) <= Q100_BOUND);
        } else {
            assert_int_equal(s, IBL_ERR_FORMAT);
            assert_string_equal(ibl_context_message(ctx), "scans.jpg: JPEG of more than 100 scans refused");
        }
        free(e.bytes);
    }
    free(rgb);
    ibl_context_destroy(ctx);
}

/* ---- writing ------------------------------------------------------------------------- */

/* ibl's previews: baseline, 4:4:4, quality 95 (libjpeg's quantisation tables scaled to it),
 * and larger than the writer's first 64 KiB buffer, so that it grows; libjpeg reads the file
 * without a warning and ibl reads exactly what libjpeg decodes. */
static void preview_written_by_libjpeg(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    const int w = 300, h = 200;
    ibl_image im;
    assert_int_equal(ibl_image_alloc(ctx, w, h, &im), IBL_OK);
    uint32_t rng = 7;
    for (size_t i = 0; i < (size_t)w * h * 4; i++) {
        rng = rng * 1664525u + 1013904223u;
        im.pixels[i] = (float)((rng >> 8) / 16777216.0);
    }
    ibl_write_desc wd = {0};
    wd.tonemap = IBL_TONEMAP_NONE;
    const char *path = test_path("preview.jpg");
    assert_int_equal(ibl_write_image(ctx, path, &im, &wd), IBL_OK);
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    assert_true(n > 65536);
    unsigned char *b = malloc((size_t)n);
    assert_int_equal(fread(b, 1, (size_t)n, f), (size_t)n);
    fclose(f);

    struct jpeg_decompress_struct d;
    struct jpeg_error_mgr err;
    d.err = jpeg_std_error(&err);
    jpeg_create_decompress(&d);
    jpeg_mem_src(&d, b, (unsigned long)n);
    jpeg_read_header(&d, TRUE);
    assert_int_equal(d.num_components, 3);
    assert_false(d.progressive_mode);
    for (int c = 0; c < 3; c++) {
        assert_int_equal(d.comp_info[c].h_samp_factor, 1);
        assert_int_equal(d.comp_info[c].v_samp_factor, 1);
    }
    /* quality 95 scales the standard luminance table by 10% (jpeg_quality_scaling) */
    assert_int_equal(d.quant_tbl_ptrs[0]->quantval[0], (16 * 10 + 50) / 100);
    jpeg_abort_decompress(&d);
    jpeg_destroy_decompress(&d);

    uint8_t *codes = malloc((size_t)w * h * 3);
    for (size_t i = 0; i < (size_t)w * h; i++)
        for (int c = 0; c < 3; c++) {
            double v = im.pixels[i * 4 + (size_t)c];
            double e = v <= 0.0031308 ? 12.92 * v : 1.055 * pow(v, 1 / 2.4) - 0.055;
            codes[i * 3 + (size_t)c] = (uint8_t)(e * 255 + 0.5);
        }
    encoded e = {b, (unsigned long)n};
    /* uniform noise is JPEG's worst case: 24 codes at most at quality 95 (the bound is 32) */
    assert_true(check_read_back(ctx, e, codes, w, h, 3) <= 32);
    free(codes);
    free(b);
    ibl_image_free(ctx, &im);
    ibl_context_destroy(ctx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(baseline_and_progressive_read_back),
        cmocka_unit_test(grey_reads_as_rgb),
        cmocka_unit_test(truncated_scan_refused),
        cmocka_unit_test(cut_between_scans_refused),
        cmocka_unit_test(unsupported_codings),
        cmocka_unit_test(scan_count_limit),
        cmocka_unit_test(preview_written_by_libjpeg),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
