/* ibl_decode_info and ibl_read_info (the header-only readers) against the full decode: for
 * every file the other tests read (tests/data) and one of each container, texel format and
 * flat-image variant written here, the info of the header alone equals field by field the
 * info ibl_read_texture gives; every prefix of each file either yields that same info or
 * fails exactly as ibl_decode_texture fails on it (same status, same message naming the
 * file); and files whose pixel data is cut or corrupt still give their info while the decode
 * refuses them. There is no tolerance anywhere: the fields are integers and enums. */
#include <dirent.h>
#include <png.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "test_io_helpers.h"

/* ---- comparisons --------------------------------------------------------------------- */

static void expect_same_info(const ibl_file_info *got, const ibl_file_info *want, const char *what)
{
    int same = got->type == want->type && got->format == want->format && got->kind == want->kind &&
               got->width == want->width && got->height == want->height &&
               got->depth == want->depth && got->levels == want->levels &&
               got->has_alpha == want->has_alpha;
    if (!same)
        fail_msg("%s: header info type %d format %d kind %d %dx%dx%d levels %d alpha %d; the decode "
                 "says type %d format %d kind %d %dx%dx%d levels %d alpha %d",
                 what, got->type, got->format, got->kind, got->width, got->height, got->depth,
                 got->levels, got->has_alpha, want->type, want->format, want->kind, want->width,
                 want->height, want->depth, want->levels, want->has_alpha);
    /* no pixel was looked at */
    assert_int_equal(got->pixels.nan_count + got->pixels.inf_count + got->pixels.negative_count +
                         got->pixels.texel_count,
                     0);
}

/* The message of a failure: one line that starts with the name. */
static void expect_named_failure(ibl_context *ctx, const char *name)
{
    const char *m = ibl_context_message(ctx);
    if (strncmp(m, name, strlen(name)) != 0) fail_msg("message \"%s\" does not start with %s", m, name);
    assert_null(strchr(m, '\n'));
}

/* Every prefix of the file (each of the first 600 cuts, then about 150 more): the decode's
 * success implies the header reader's with the same info; the header reader's success gives
 * the whole file's info; its failure is the decode's failure, the same status and message. */
static void check_prefixes(ibl_context *ctx, const uint8_t *bytes, size_t size,
                           const ibl_file_info *whole, const char *what)
{
    char info_message[512];
    for (size_t cut = 0; cut < size; cut += cut < 600 ? 1 : size / 150 + 1) {
        ibl_file_info head, full;
        ibl_status hs = ibl_decode_info(ctx, bytes, cut, "cut.bin", &head);
        snprintf(info_message, sizeof info_message, "%s", ibl_context_message(ctx));
        ibl_texture t;
        ibl_status ds = ibl_decode_texture(ctx, bytes, cut, "cut.bin", NULL, &t, &full);
        if (ds == IBL_OK) {
            ibl_texture_free(ctx, &t);
            if (hs != IBL_OK) fail_msg("%s cut at %zu: decodes, but its header fails: %s", what, cut, info_message);
            full.pixels = (ibl_pixel_report){0, 0, 0, 0};
            expect_same_info(&head, &full, what);
        }
        if (hs == IBL_OK) {
            expect_same_info(&head, whole, what);
            continue;
        }
        if (ds == IBL_OK || ds != hs || strcmp(info_message, ibl_context_message(ctx)) != 0)
            fail_msg("%s cut at %zu: the header reader says (%d) \"%s\", the decode (%d) \"%s\"", what,
                     cut, hs, info_message, ds, ibl_context_message(ctx));
        assert_int_equal(strncmp(info_message, "cut.bin", 7), 0);
        assert_null(strchr(info_message, '\n'));
    }
}

/* A file the decoder reads: ibl_read_info and ibl_decode_info give ibl_read_texture's info;
 * with `prefixes`, every prefix is checked too. Returns 0 when the decode refuses the file
 * (then the header readers may succeed or fail, a failure naming the file). */
static int check_file(ibl_context *ctx, const char *path, int prefixes)
{
    ibl_texture t;
    ibl_file_info full, head, mem;
    ibl_status s = ibl_read_texture(ctx, path, NULL, &t, &full);
    ibl_texture_free(ctx, &t);
    ibl_status hs = ibl_read_info(ctx, path, &head);
    if (hs != IBL_OK) expect_named_failure(ctx, path);
    size_t n;
    uint8_t *bytes = slurp(path, &n);
    ibl_status ms = ibl_decode_info(ctx, bytes, n, path, &mem);
    if (ms != IBL_OK) expect_named_failure(ctx, path);
    assert_int_equal(hs, ms);
    if (s == IBL_OK) {
        if (hs != IBL_OK) fail_msg("%s decodes, but ibl_read_info fails", path);
        full.pixels = (ibl_pixel_report){0, 0, 0, 0};
        expect_same_info(&head, &full, path);
        expect_same_info(&mem, &full, path);
        if (prefixes) check_prefixes(ctx, bytes, n, &full, path);
    }
    free(bytes);
    return s == IBL_OK;
}

/* ---- every file in tests/data -------------------------------------------------------- */

static int has_suffix(const char *name, const char *suffix)
{
    size_t n = strlen(name), k = strlen(suffix);
    return n >= k && strcmp(name + n - k, suffix) == 0;
}

static void data_files_agree(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2);
    DIR *dir = opendir(IBL_TEST_DATA);
    assert_non_null(dir);
    int images = 0, decoded = 0;
    struct dirent *e;
    while ((e = readdir(dir)) != NULL) {
        const char *n = e->d_name;
        if (!has_suffix(n, ".exr") && !has_suffix(n, ".hdr") && !has_suffix(n, ".png")) continue;
        char path[1024];
        snprintf(path, sizeof path, "%s/%s", IBL_TEST_DATA, n);
        struct stat st;
        assert_int_equal(stat(path, &st), 0);
        images++;
        /* the prefixes of the small files (a cut EXR fails in the structure check: cheap) */
        int ok = check_file(ctx, path, st.st_size < (64 << 10));
        decoded += ok;
        /* the files named fuzz_ are the hostile ones the decoder must refuse */
        assert_int_equal(ok, strncmp(n, "fuzz_", 5) != 0);
    }
    closedir(dir);
    assert_true(images >= 26);
    assert_int_equal(decoded, images - 3);
    ibl_context_destroy(ctx);
}

/* ---- files written here -------------------------------------------------------------- */

static void fill_random(float *p, size_t floats)
{
    for (size_t i = 0; i < floats; i++) p[i] = frand() * 3.0f;
}

/* Flat images through every writer and its options. */
static void flat_files_agree(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2);
    ibl_image im = make_image(ctx, 21, 10);
    fill_random(im.pixels, 21 * 10 * 4);
    static const struct {
        const char *name;
        ibl_format format;
        ibl_exr_compression exr;
        int hdr_no_rle;
    } flat[] = {
        {"rle.hdr", 0, 0, 0},
        {"flat.hdr", 0, 0, 1},
        {"half.exr", 0, 0, 0},
        {"rgb16f.exr", IBL_FORMAT_RGB16F, 0, 0},
        {"rgba32f.exr", IBL_FORMAT_RGBA32F, 0, 0},
        {"rgb32f_none.exr", IBL_FORMAT_RGB32F, IBL_EXR_NONE, 0},
        {"rle.exr", 0, IBL_EXR_RLE, 0},
        {"zips.exr", 0, IBL_EXR_ZIPS, 0},
        {"piz.exr", IBL_FORMAT_RGBA32F, IBL_EXR_PIZ, 0},
        {"f.pfm", 0, 0, 0},
        {"srgb8.png", 0, 0, 0},
        {"unorm8.png", IBL_FORMAT_RGBA8_UNORM, 0, 0},
        {"unorm16.png", IBL_FORMAT_RGBA16_UNORM, 0, 0},
        {"rgbm.png", IBL_FORMAT_RGBM, 0, 0},
        {"f.jpg", 0, 0, 0},
    };
    for (size_t i = 0; i < sizeof flat / sizeof flat[0]; i++) {
        ibl_write_desc wd = {0};
        wd.format = flat[i].format;
        wd.exr_compression = flat[i].exr;
        wd.hdr_no_rle = flat[i].hdr_no_rle;
        const char *path = test_path(flat[i].name);
        assert_int_equal(ibl_write_image(ctx, path, &im, &wd), IBL_OK);
        assert_true(check_file(ctx, path, 1));
    }
    ibl_image_free(ctx, &im);
    ibl_context_destroy(ctx);
}

/* PNG colour types and depths the writer does not make (grey, grey + alpha, palette with
 * tRNS, 16-bit, interlaced): has_alpha and format follow IHDR and tRNS as in the decode. */
static void png_file(const char *path, int color, int depth, int interlace, int trns)
{
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
    png_infop pinfo = png_create_info_struct(png);
    assert_non_null(pinfo);
    test_bytes out = {0};
    test_png_write_to_memory(png, &out);
    const int w = 9, h = 5;
    png_set_IHDR(png, pinfo, w, h, depth, color, interlace, PNG_COMPRESSION_TYPE_DEFAULT,
                 PNG_FILTER_TYPE_DEFAULT);
    if (color == PNG_COLOR_TYPE_PALETTE) {
        png_color palette[4] = {{0, 0, 0}, {255, 0, 0}, {0, 255, 0}, {0, 0, 255}};
        png_set_PLTE(png, pinfo, palette, 4);
    }
    if (trns) {
        png_byte alpha[4] = {0, 128, 255, 255};
        png_set_tRNS(png, pinfo, alpha, 4, NULL);
    }
    png_write_info(png, pinfo);
    png_byte row[9 * 8];
    memset(row, 0, sizeof row);
    if (interlace == PNG_INTERLACE_ADAM7) {
        int passes = png_set_interlace_handling(png);
        for (int p = 0; p < passes; p++)
            for (int y = 0; y < h; y++) png_write_row(png, row);
    } else {
        for (int y = 0; y < h; y++) png_write_row(png, row);
    }
    png_write_end(png, pinfo);
    png_destroy_write_struct(&png, &pinfo);
    spit(path, out.b, out.n);
    free(out.b);
}

static void png_layouts_agree(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    png_file(test_path("grey1.png"), PNG_COLOR_TYPE_GRAY, 1, PNG_INTERLACE_NONE, 0);
    png_file(test_path("greyalpha8.png"), PNG_COLOR_TYPE_GRAY_ALPHA, 8, PNG_INTERLACE_NONE, 0);
    png_file(test_path("palette4.png"), PNG_COLOR_TYPE_PALETTE, 4, PNG_INTERLACE_NONE, 0);
    png_file(test_path("palette_trns.png"), PNG_COLOR_TYPE_PALETTE, 8, PNG_INTERLACE_NONE, 1);
    png_file(test_path("grey16.png"), PNG_COLOR_TYPE_GRAY, 16, PNG_INTERLACE_NONE, 0);
    png_file(test_path("rgb16_adam7.png"), PNG_COLOR_TYPE_RGB, 16, PNG_INTERLACE_ADAM7, 0);
    png_file(test_path("rgba8_adam7.png"), PNG_COLOR_TYPE_RGB_ALPHA, 8, PNG_INTERLACE_ADAM7, 0);
    const char *names[] = {"grey1.png", "greyalpha8.png", "palette4.png", "palette_trns.png",
                           "grey16.png", "rgb16_adam7.png", "rgba8_adam7.png"};
    int alpha = 0;
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) {
        assert_true(check_file(ctx, test_path(names[i]), 1));
        ibl_file_info fi;
        assert_int_equal(ibl_read_info(ctx, test_path(names[i]), &fi), IBL_OK);
        alpha += fi.has_alpha;
    }
    assert_int_equal(alpha, 3); /* grey + alpha, tRNS, RGBA */
    ibl_context_destroy(ctx);
}

/* A hand-made grey big-endian PFM and a bottom-up Radiance file (orientations the writers
 * do not produce). */
static void hand_made_flat_files_agree(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    uint8_t pfm[64 + 3 * 2 * 4];
    int n = snprintf((char *)pfm, 64, "Pf\n3 2\n1.0\n");
    for (int i = 0; i < 3 * 2 * 4; i++) pfm[n + i] = (uint8_t)(i * 3 % 64);
    spit(test_path("grey_be.pfm"), pfm, (size_t)n + 3 * 2 * 4);
    assert_true(check_file(ctx, test_path("grey_be.pfm"), 1));
    uint8_t hdr[128];
    n = snprintf((char *)hdr, 64, "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n+Y 2 -X 3\n");
    for (int i = 0; i < 3 * 2 * 4; i++) hdr[n + i] = (uint8_t)(100 + i);
    spit(test_path("bottom_up.hdr"), hdr, (size_t)n + 3 * 2 * 4);
    assert_true(check_file(ctx, test_path("bottom_up.hdr"), 1));
    /* an EXR whose display window (the decoded image) is not its data window: the 21x10 data
     * at (0, 0) shown in a window from (-2, -1) to (24, 12) */
    ibl_image im = make_image(ctx, 21, 10);
    fill_random(im.pixels, 21 * 10 * 4);
    assert_int_equal(ibl_write_image(ctx, test_path("windows.exr"), &im, NULL), IBL_OK);
    ibl_image_free(ctx, &im);
    size_t size;
    uint8_t *b = slurp(test_path("windows.exr"), &size);
    static const char attribute[] = "displayWindow\0box2i";
    uint8_t *at = NULL;
    for (size_t i = 0; i + sizeof attribute < size && !at; i++)
        if (memcmp(b + i, attribute, sizeof attribute) == 0) at = b + i + sizeof attribute + 4;
    assert_non_null(at);
    const int32_t display[4] = {-2, -1, 24, 12};
    for (int k = 0; k < 4; k++)
        for (int j = 0; j < 4; j++) at[4 * k + j] = (uint8_t)((uint32_t)display[k] >> (8 * j));
    spit(test_path("windows.exr"), b, size);
    free(b);
    assert_true(check_file(ctx, test_path("windows.exr"), 1));
    ibl_file_info fi;
    assert_int_equal(ibl_read_info(ctx, test_path("windows.exr"), &fi), IBL_OK);
    assert_int_equal(fi.width, 27);
    assert_int_equal(fi.height, 14);
    ibl_context_destroy(ctx);
}

/* A texture of the kind, size and levels given, random texels. */
static ibl_texture make_texture(ibl_context *ctx, ibl_texture_kind kind, int w, int h, int d,
                                int levels)
{
    ibl_texture t;
    assert_int_equal(ibl_texture_alloc(ctx, kind, w, h, d, levels, &t), IBL_OK);
    fill_random(t.data, ibl_texture_floats(kind, w, h, d, levels));
    return t;
}

/* Every container with every texel format it stores, 2D, cube with mips, 3D and cube-map
 * arrays, KTX2 Zstandard supercompression, the DDS legacy and DX10 headers, KTX1 as cmgen
 * writes it. */
static void container_files_agree(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2);
    ibl_texture shapes[4] = {
        make_texture(ctx, IBL_TEXTURE_2D, 12, 8, 1, 1),
        make_texture(ctx, IBL_TEXTURE_CUBE, 8, 8, 1, 4),
        make_texture(ctx, IBL_TEXTURE_3D, 4, 4, 3, 2),
        make_texture(ctx, IBL_TEXTURE_CUBE_ARRAY, 4, 4, 2, 3),
    };
    static const ibl_format formats[] = {
        IBL_FORMAT_RGBA16F, IBL_FORMAT_RGBA32F, IBL_FORMAT_RG11B10F, IBL_FORMAT_RGB9E5,
        IBL_FORMAT_RG16F,   IBL_FORMAT_RG32F,   IBL_FORMAT_BC6H,     IBL_FORMAT_BC6H_SIGNED,
        IBL_FORMAT_RGBM,    IBL_FORMAT_RGBD,    IBL_FORMAT_RGBE,     IBL_FORMAT_ASTC_4x4,
    };
    static const char *ext[3] = {"ktx2", "ktx", "dds"};
    static const ibl_file_type types[3] = {IBL_FILE_KTX2, IBL_FILE_KTX1, IBL_FILE_DDS};
    int files = 0;
    for (int c = 0; c < 3; c++)
        for (size_t f = 0; f < sizeof formats / sizeof formats[0]; f++) {
            if (!ibl_file_type_writes_format(types[c], formats[f])) continue;
            for (int k = 0; k < 4; k++) {
                ibl_texture *t = &shapes[k];
                /* KTX1 stores no arrays; ASTC blocks of 3D levels are not written */
                if (types[c] == IBL_FILE_KTX1 && t->kind == IBL_TEXTURE_CUBE_ARRAY) continue;
                if (formats[f] == IBL_FORMAT_ASTC_4x4 && t->kind == IBL_TEXTURE_3D) continue;
                for (int variant = 0; variant < 2; variant++) {
                    ibl_write_desc wd = {0};
                    wd.format = formats[f];
                    wd.quality = IBL_QUALITY_FAST;
                    /* the second file of each: KTX2 Zstandard, DDS DX10 header, KTX1 cmgen's types */
                    if (variant == 1 && types[c] == IBL_FILE_KTX2) wd.zstd_level = 3;
                    else if (variant == 1 && types[c] == IBL_FILE_DDS) wd.dds_header = IBL_DDS_HEADER_DX10;
                    else if (variant == 1 && formats[f] == IBL_FORMAT_RG11B10F) wd.ktx1_cmgen_types = 1;
                    else if (variant == 1) continue;
                    char name[64];
                    snprintf(name, sizeof name, "c%d_f%zu_k%d_v%d.%s", c, f, k, variant, ext[c]);
                    const char *path = test_path(name);
                    ibl_status ws = ibl_write_texture(ctx, path, t, &wd);
                    if (ws != IBL_OK) fail_msg("writing %s: %s", name, ibl_context_message(ctx));
                    /* the prefixes of one shape per format (each cut is a whole decode) */
                    assert_true(check_file(ctx, path, k == 1));
                    files++;
                }
            }
        }
    assert_true(files >= 80);
    for (int k = 0; k < 4; k++) ibl_texture_free(ctx, &shapes[k]);
    ibl_context_destroy(ctx);
}

/* Key/value data past the first 64 KiB: ibl_read_info reads on until the header is whole. */
static void header_past_the_first_read(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_texture t = make_texture(ctx, IBL_TEXTURE_CUBE, 4, 4, 1, 1);
    size_t big = 200 << 10;
    char *value = malloc(big + 1);
    memset(value, 'v', big);
    value[big] = 0;
    assert_int_equal(ibl_texture_set_metadata(ctx, &t, "comment", value), IBL_OK);
    free(value);
    const char *names[2] = {"big_kv.ktx2", "big_kv.ktx"};
    for (int i = 0; i < 2; i++) {
        assert_int_equal(ibl_write_texture(ctx, test_path(names[i]), &t, NULL), IBL_OK);
        assert_true(check_file(ctx, test_path(names[i]), 0));
        ibl_file_info fi;
        assert_int_equal(ibl_read_info(ctx, test_path(names[i]), &fi), IBL_OK);
        assert_int_equal(fi.kind, IBL_TEXTURE_CUBE);
    }
    ibl_texture_free(ctx, &t);
    ibl_context_destroy(ctx);
}

/* Counts the bytes allocated through the context. */
static void *counting_alloc(size_t bytes, void *user)
{
    *(size_t *)user += bytes;
    return malloc(bytes ? bytes : 1);
}

static void counting_free(void *p, void *user)
{
    (void)user;
    free(p);
}

/* ibl_read_info takes the head of a file, not the file: what it allocates through the context
 * (the buffer of what it read, and small things) stays under 68 KiB for city.exr, a 208 KiB
 * file of which the first 64 KiB are read. */
static void reads_only_the_head(void **state)
{
    (void)state;
    size_t allocated = 0;
    ibl_context_desc d = {0};
    d.threads = 1;
    d.allocator.alloc = counting_alloc;
    d.allocator.free = counting_free;
    d.allocator.user = &allocated;
    ibl_context *ctx = NULL;
    assert_int_equal(ibl_context_create(&d, &ctx), IBL_OK);
    size_t before = allocated;
    ibl_file_info fi;
    assert_int_equal(ibl_read_info(ctx, test_data("city.exr"), &fi), IBL_OK);
    assert_true(fi.width > 0);
    size_t used = allocated - before;
    if (used > (68u << 10)) fail_msg("ibl_read_info allocated %zu bytes for city.exr", used);
    ibl_texture t;
    before = allocated;
    assert_int_equal(ibl_read_texture(ctx, test_data("city.exr"), NULL, &t, NULL), IBL_OK);
    ibl_texture_free(ctx, &t);
    assert_true(allocated - before > (208u << 10)); /* the decode holds the file, at least */
    ibl_context_destroy(ctx);
}

/* ---- broken pixel data, broken headers ----------------------------------------------- */

/* A file whose pixel data is cut or scrambled after its header: the decode refuses it, the
 * header readers give the info of the intact file (and read none of the broken bytes). */
static void broken_pixel_data(ibl_context *ctx, const char *intact, const char *name,
                              size_t keep, int scramble_after)
{
    size_t n;
    uint8_t *b = slurp(intact, &n);
    ibl_file_info whole;
    assert_int_equal(ibl_read_info(ctx, intact, &whole), IBL_OK);
    assert_true(keep <= n);
    if (scramble_after)
        for (size_t i = (size_t)scramble_after; i < n; i++) b[i] = (uint8_t)(b[i] * 31 + 7);
    const char *path = test_path(name);
    spit(path, b, keep);
    free(b);
    ibl_texture t;
    if (ibl_read_texture(ctx, path, NULL, &t, NULL) == IBL_OK)
        fail_msg("%s: the broken file decodes", name);
    expect_named_failure(ctx, path);
    ibl_file_info fi;
    if (ibl_read_info(ctx, path, &fi) != IBL_OK)
        fail_msg("%s: ibl_read_info fails: %s", name, ibl_context_message(ctx));
    expect_same_info(&fi, &whole, name);
}

static void broken_pixels_keep_their_info(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2);
    /* city.exr cut to its first 64 KiB of 208 KiB, and its chunks scrambled */
    broken_pixel_data(ctx, test_data("city.exr"), "city_head.exr", 64 << 10, 0);
    size_t n;
    uint8_t *b = slurp(test_data("city.exr"), &n);
    free(b);
    broken_pixel_data(ctx, test_data("city.exr"), "city_scrambled.exr", n, 2048);
    /* the files of the other formats cut at half their length */
    ibl_image im = make_image(ctx, 64, 32);
    fill_random(im.pixels, 64 * 32 * 4);
    const char *flat[] = {"h.hdr", "h.pfm", "h.png", "h.jpg", "h.exr"};
    for (size_t i = 0; i < sizeof flat / sizeof flat[0]; i++) {
        char intact[64], cut[64];
        snprintf(intact, sizeof intact, "intact_%s", flat[i]);
        snprintf(cut, sizeof cut, "cut_%s", flat[i]);
        assert_int_equal(ibl_write_image(ctx, test_path(intact), &im, NULL), IBL_OK);
        b = slurp(test_path(intact), &n);
        free(b);
        broken_pixel_data(ctx, test_path(intact), cut, n / 2, 0);
    }
    ibl_image_free(ctx, &im);
    ibl_texture t = make_texture(ctx, IBL_TEXTURE_CUBE, 16, 16, 1, 5);
    const char *containers[] = {"c.ktx2", "c.ktx", "c.dds"};
    for (size_t i = 0; i < 3; i++) {
        char intact[64], cut[64];
        snprintf(intact, sizeof intact, "intact_%s", containers[i]);
        snprintf(cut, sizeof cut, "cut_%s", containers[i]);
        assert_int_equal(ibl_write_texture(ctx, test_path(intact), &t, NULL), IBL_OK);
        b = slurp(test_path(intact), &n);
        free(b);
        broken_pixel_data(ctx, test_path(intact), cut, n / 2, 0);
    }
    ibl_texture_free(ctx, &t);
    ibl_context_destroy(ctx);
}

/* Headers cut short or damaged fail in ibl_read_info as in ibl_read_texture: the same status
 * and the same message, which names the path. */
static void broken_headers_fail_as_the_decode(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_image im = make_image(ctx, 8, 4);
    fill_random(im.pixels, 8 * 4 * 4);
    ibl_texture cube = make_texture(ctx, IBL_TEXTURE_CUBE, 4, 4, 1, 1);
    static const struct {
        const char *name;
        size_t keep;  /* bytes kept (0: all) */
        size_t poke;  /* a byte set to 0xFF (0: none) */
    } cases[] = {
        {"a.hdr", 12, 0},  {"b.pfm", 5, 0},   {"c.exr", 40, 0},  {"d.exr", 0, 9},
        {"e.png", 20, 0},  {"f.png", 0, 17},  {"g.jpg", 100, 0}, {"h.ktx2", 60, 0},
        {"i.ktx2", 0, 13}, {"j.ktx", 50, 0},  {"k.ktx", 0, 37},  {"l.dds", 100, 0},
        {"m.dds", 0, 84},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        const char *path = test_path(cases[i].name);
        ibl_file_type type = ibl_file_type_from_path(path);
        ibl_status ws = ibl_file_type_is_container(type) ? ibl_write_texture(ctx, path, &cube, NULL)
                                                         : ibl_write_image(ctx, path, &im, NULL);
        assert_int_equal(ws, IBL_OK);
        size_t n;
        uint8_t *b = slurp(path, &n);
        if (cases[i].keep) n = cases[i].keep;
        if (cases[i].poke) b[cases[i].poke] = 0xFF;
        spit(path, b, n);
        free(b);
        ibl_texture t;
        ibl_status ds = ibl_read_texture(ctx, path, NULL, &t, NULL);
        if (ds == IBL_OK) fail_msg("%s: the damaged file decodes", cases[i].name);
        char decode_message[512];
        snprintf(decode_message, sizeof decode_message, "%s", ibl_context_message(ctx));
        ibl_file_info fi;
        ibl_status hs = ibl_read_info(ctx, path, &fi);
        if (hs != ds || strcmp(decode_message, ibl_context_message(ctx)) != 0)
            fail_msg("%s: ibl_read_info says (%d) \"%s\", ibl_read_texture (%d) \"%s\"", cases[i].name,
                     hs, ibl_context_message(ctx), ds, decode_message);
        expect_named_failure(ctx, path);
    }
    ibl_texture_free(ctx, &cube);
    ibl_image_free(ctx, &im);
    ibl_context_destroy(ctx);
}

/* A FIFO cannot be read twice: it is read whole, and gives the file's info. */
static void fifo_is_read_whole(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_texture t = make_texture(ctx, IBL_TEXTURE_CUBE, 8, 8, 1, 4);
    const char *file = test_path("fifo_source.ktx2");
    assert_int_equal(ibl_write_texture(ctx, file, &t, NULL), IBL_OK);
    ibl_texture_free(ctx, &t);
    ibl_file_info want, got;
    assert_int_equal(ibl_read_info(ctx, file, &want), IBL_OK);
    size_t n;
    uint8_t *b = slurp(file, &n);
    char fifo[1024];
    snprintf(fifo, sizeof fifo, "%s", test_path("info.fifo"));
    assert_int_equal(mkfifo(fifo, 0600), 0);
    pid_t writer = fork();
    assert_true(writer >= 0);
    if (writer == 0) { /* the child writes the file into the FIFO and leaves */
        FILE *f = fopen(fifo, "wb");
        size_t w = f ? fwrite(b, 1, n, f) : 0;
        if (f) fclose(f);
        _exit(w == n ? 0 : 1);
    }
    ibl_status s = ibl_read_info(ctx, fifo, &got);
    int status = 0;
    assert_int_equal(waitpid(writer, &status, 0), writer);
    assert_int_equal(s, IBL_OK);
    assert_true(WIFEXITED(status) && WEXITSTATUS(status) == 0);
    expect_same_info(&got, &want, "info.fifo");
    free(b);
    ibl_context_destroy(ctx);
}

/* Missing files, directories, empty and unknown files, missing arguments. */
static void api_edges(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_file_info fi;
    const char *missing = test_path("missing.exr");
    assert_int_equal(ibl_read_info(ctx, missing, &fi), IBL_ERR_IO);
    expect_named_failure(ctx, missing);
    assert_int_equal(ibl_read_info(ctx, test_tmpdir(), &fi), IBL_ERR_IO);
    expect_named_failure(ctx, test_tmpdir());
    spit(test_path("empty.hdr"), "", 0);
    assert_int_equal(ibl_read_info(ctx, test_path("empty.hdr"), &fi), IBL_ERR_FORMAT);
    expect_named_failure(ctx, test_path("empty.hdr"));
    spit(test_path("text.png"), "GIF89a, not a PNG", 17);
    assert_int_equal(ibl_read_info(ctx, test_path("text.png"), &fi), IBL_ERR_FORMAT);
    expect_named_failure(ctx, test_path("text.png"));
    assert_int_equal(ibl_decode_info(ctx, "#?RADIANCE\n", 11, NULL, &fi), IBL_ERR_FORMAT);
    expect_named_failure(ctx, "<memory>");
    assert_int_equal(ibl_decode_info(ctx, NULL, 4, "x", &fi), IBL_ERR_INVALID_ARGUMENT);
    assert_int_equal(ibl_decode_info(ctx, "abcd", 4, "x", NULL), IBL_ERR_INVALID_ARGUMENT);
    assert_int_equal(ibl_read_info(ctx, NULL, &fi), IBL_ERR_INVALID_ARGUMENT);
    assert_int_equal(ibl_read_info(ctx, missing, NULL), IBL_ERR_INVALID_ARGUMENT);
    ibl_context_destroy(ctx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(data_files_agree),
        cmocka_unit_test(flat_files_agree),
        cmocka_unit_test(png_layouts_agree),
        cmocka_unit_test(hand_made_flat_files_agree),
        cmocka_unit_test(container_files_agree),
        cmocka_unit_test(header_past_the_first_read),
        cmocka_unit_test(reads_only_the_head),
        cmocka_unit_test(broken_pixels_keep_their_info),
        cmocka_unit_test(broken_headers_fail_as_the_decode),
        cmocka_unit_test(fifo_is_read_whole),
        cmocka_unit_test(api_edges),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
