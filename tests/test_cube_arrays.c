/* Cube-map arrays in the core texture type (IBL_TEXTURE_CUBE_ARRAY: depth = layers), KTX2
 * (layerCount) and DDS (DX10 arraySize): round trips in every storage family, the bytes
 * against the independent splicing writer of src/io/ktx2_array.c (which only ever encodes
 * single cubes), the DDS header and data order checked field by field against Microsoft's
 * DDS_HEADER_DXT10 description, refusals, and the CLI (`ibl info`, `ibl convert`). */
#include "test_support.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { LAYERS = 3, SIZE = 8, LEVELS = 4 };

/* Texel values: a different smooth-ish pattern per layer, face and level, all in [0.05, 7.5]. */
static float pattern(size_t k, int layer)
{
    return 0.05f + (float)((k * 31 + (size_t)layer * 7) % 97) / 13.0f;
}

static void make_array(ibl_context *ctx, ibl_texture *tex, ibl_cubemap cubes[LAYERS])
{
    assert_int_equal(ibl_texture_alloc(ctx, IBL_TEXTURE_CUBE_ARRAY, SIZE, SIZE, LAYERS, LEVELS, tex),
                     IBL_OK);
    assert_int_equal(ibl_texture_faces(tex), 6 * LAYERS);
    for (int i = 0; i < LAYERS; i++) {
        assert_int_equal(ibl_cubemap_alloc(ctx, SIZE, LEVELS, &cubes[i]), IBL_OK);
        size_t k = 0;
        for (int l = 0; l < LEVELS; l++)
            for (int f = 0; f < 6; f++) {
                int n = ibl_level_size(SIZE, l);
                float *dst = ibl_texture_level(tex, l, 6 * i + f), *src = ibl_cubemap_face(&cubes[i], l, f);
                for (int t = 0; t < n * n * 4; t++, k++) dst[t] = src[t] = t % 4 == 3 ? 1.0f : pattern(k, i);
            }
    }
}

static void free_cubes(ibl_context *ctx, ibl_cubemap cubes[LAYERS])
{
    for (int i = 0; i < LAYERS; i++) ibl_cubemap_free(ctx, &cubes[i]);
}

/* Largest difference between a decoded array and the source cubes. */
static double worst_difference(const ibl_texture *back, const ibl_cubemap cubes[LAYERS])
{
    double worst = 0;
    for (int i = 0; i < LAYERS; i++)
        for (int l = 0; l < LEVELS; l++)
            for (int f = 0; f < 6; f++) {
                int n = ibl_level_size(SIZE, l);
                const float *a = ibl_texture_level(back, l, 6 * i + f), *b = ibl_cubemap_face(&cubes[i], l, f);
                for (int t = 0; t < n * n * 4; t++) worst = fmax(worst, fabs((double)a[t] - b[t]));
            }
    return worst;
}

static uint64_t rd64(const uint8_t *p)
{
    uint64_t v = 0;
    for (int i = 7; i >= 0; i--) v = v << 8 | p[i];
    return v;
}

/* KTX2: each level of the array file is the layers' own level images (each cube written
 * alone as a KTX2 cube) one after the other, as the specification orders them (layer, face);
 * reading it back gives the texels (exactly for rgba32f; within the format's step otherwise),
 * and ibl_decode_cube_array the same cubes; Zstandard, BC6H and RGBE included. */
static void ktx2_round_trip(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2);
    ibl_texture tex;
    ibl_cubemap cubes[LAYERS];
    make_array(ctx, &tex, cubes);
    static const struct { ibl_format format; int zstd; double tol; } runs[] = {
        {IBL_FORMAT_RGBA32F, 0, 0.0},
        {IBL_FORMAT_RGBA16F, 3, 4e-3},   /* half: 2^-11 relative of values below 8 */
        {IBL_FORMAT_BC6H, 0, -1.0},      /* texels uncorrelated by design, no bound for a block
                                            codec: the layers equal the single cubes' decodes */
        {IBL_FORMAT_RGBE, 0, 0.06}};     /* RGBE: M / 256 with M <= 7.5 */
    for (size_t r = 0; r < sizeof runs / sizeof *runs; r++) {
        ibl_write_desc wd = {.format = runs[r].format, .zstd_level = runs[r].zstd};
        void *bytes;
        size_t size;
        assert_int_equal(ibl_encode_texture(ctx, IBL_FILE_KTX2, &tex, &wd, &bytes, &size), IBL_OK);
        const uint8_t *b = bytes;
        assert_int_equal(b[32], LAYERS); /* layerCount */
        assert_int_equal(b[36], 6);      /* faceCount */
        if (!runs[r].zstd) {
            void *one[LAYERS];
            size_t one_size[LAYERS];
            for (int i = 0; i < LAYERS; i++) {
                ibl_texture cube = ibl_texture_from_cubemap(&cubes[i]);
                assert_int_equal(ibl_encode_texture(ctx, IBL_FILE_KTX2, &cube, &wd, &one[i], &one_size[i]), IBL_OK);
            }
            for (int l = 0; l < LEVELS; l++) {
                const uint8_t *e = b + 80 + 24 * l;
                size_t at = (size_t)rd64(e), len = (size_t)rd64(e + 8), part = len / LAYERS;
                for (int i = 0; i < LAYERS; i++) {
                    const uint8_t *c = (const uint8_t *)one[i] + 80 + 24 * l;
                    assert_int_equal(rd64(c + 8), part);
                    assert_memory_equal(b + at + part * (size_t)i, (const uint8_t *)one[i] + rd64(c), part);
                }
            }
            for (int i = 0; i < LAYERS; i++) {
                ibl_texture single, whole;
                assert_int_equal(ibl_decode_texture(ctx, one[i], one_size[i], "one.ktx2", NULL, &single, NULL), IBL_OK);
                assert_int_equal(ibl_decode_texture(ctx, bytes, size, "a.ktx2", NULL, &whole, NULL), IBL_OK);
                for (int l = 0; l < LEVELS; l++) {
                    size_t n = (size_t)ibl_level_size(SIZE, l);
                    assert_memory_equal(ibl_texture_level(&single, l, 0), ibl_texture_level(&whole, l, 6 * i),
                                        6 * n * n * 4 * sizeof(float));
                }
                ibl_texture_free(ctx, &single);
                ibl_texture_free(ctx, &whole);
                ibl_free(ctx, one[i]);
            }
        }
        ibl_texture back;
        ibl_file_info info;
        assert_int_equal(ibl_decode_texture(ctx, bytes, size, "a.ktx2", NULL, &back, &info), IBL_OK);
        assert_int_equal(back.kind, IBL_TEXTURE_CUBE_ARRAY);
        assert_int_equal(info.kind, IBL_TEXTURE_CUBE_ARRAY);
        assert_int_equal(back.depth, LAYERS);
        assert_int_equal(back.levels, LEVELS);
        assert_int_equal(back.format, runs[r].format);
        double worst = worst_difference(&back, cubes);
        if (runs[r].tol >= 0 && worst > runs[r].tol)
            print_message("%s: worst %g\n", ibl_format_name(runs[r].format), worst);
        assert_true(runs[r].tol < 0 || worst <= runs[r].tol);
        /* the splicing reader agrees texel for texel */
        ibl_cubemap *layers;
        int count;
        ibl_status split = ibl_decode_cube_array(ctx, bytes, size, "a.ktx2", &layers, &count, NULL);
        if (split != IBL_OK) print_message("run %zu: %s\n", r, ibl_context_message(ctx));
        assert_int_equal(split, IBL_OK);
        assert_int_equal(count, LAYERS);
        for (int i = 0; i < LAYERS; i++) {
            assert_memory_equal(layers[i].data, ibl_texture_level(&back, 0, 6 * i),
                                6 * SIZE * SIZE * 4 * sizeof(float));
            ibl_cubemap_free(ctx, &layers[i]);
        }
        ibl_free(ctx, layers);
        ibl_texture_free(ctx, &back);
        ibl_free(ctx, bytes);
    }
    ibl_texture_free(ctx, &tex);
    free_cubes(ctx, cubes);
    ibl_context_destroy(ctx);
}

static uint32_t rd32(const uint8_t *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

/* DDS: DX10 header with misc TEXTURECUBE (0x4) and arraySize = cubes; the data is every
 * array slice (layer-major cube faces) with all its mips, base first. Checked at the offsets
 * that layout implies, then read back. */
static void dds_round_trip(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_texture tex;
    ibl_cubemap cubes[LAYERS];
    make_array(ctx, &tex, cubes);
    ibl_write_desc wd = {.format = IBL_FORMAT_RGBA32F};
    void *bytes;
    size_t size;
    assert_int_equal(ibl_encode_texture(ctx, IBL_FILE_DDS, &tex, &wd, &bytes, &size), IBL_OK);
    const uint8_t *b = bytes, *x = b + 4 + 124;
    assert_int_equal(rd32(x + 0), 2);   /* DXGI_FORMAT_R32G32B32A32_FLOAT */
    assert_int_equal(rd32(x + 4), 3);   /* D3D10_RESOURCE_DIMENSION_TEXTURE2D */
    assert_int_equal(rd32(x + 8), 4);   /* DDS_RESOURCE_MISC_TEXTURECUBE */
    assert_int_equal(rd32(x + 12), LAYERS);
    assert_int_equal(rd32(b + 4 + 108) & 0xFE00u, 0xFE00u); /* caps2: CUBEMAP + all faces */
    size_t chain = 0; /* bytes of one face's mip chain */
    for (int l = 0; l < LEVELS; l++) chain += (size_t)ibl_level_size(SIZE, l) * (size_t)ibl_level_size(SIZE, l) * 16;
    assert_int_equal(size, 148 + (size_t)LAYERS * 6 * chain);
    for (int i = 0; i < LAYERS; i++)
        for (int f = 0; f < 6; f++) {
            /* texel (0, 0) of level 1 of face f of layer i */
            const uint8_t *p = b + 148 + (size_t)(6 * i + f) * chain + (size_t)SIZE * SIZE * 16;
            float v;
            memcpy(&v, p, 4);
            assert_true(v == ibl_cubemap_face(&cubes[i], 1, f)[0]);
        }
    ibl_texture back;
    assert_int_equal(ibl_decode_texture(ctx, bytes, size, "a.dds", NULL, &back, NULL), IBL_OK);
    assert_int_equal(back.kind, IBL_TEXTURE_CUBE_ARRAY);
    assert_int_equal(back.depth, LAYERS);
    assert_true(worst_difference(&back, cubes) == 0.0);
    ibl_texture_free(ctx, &back);
    /* BC6H keeps the layout too: its file decodes as the KTX2 BC6H file of the same array */
    ibl_write_desc bc = {.format = IBL_FORMAT_BC6H};
    void *ktx;
    size_t ktx_size;
    ibl_free(ctx, bytes);
    assert_int_equal(ibl_encode_texture(ctx, IBL_FILE_DDS, &tex, &bc, &bytes, &size), IBL_OK);
    assert_int_equal(ibl_encode_texture(ctx, IBL_FILE_KTX2, &tex, &bc, &ktx, &ktx_size), IBL_OK);
    ibl_texture from_dds, from_ktx;
    assert_int_equal(ibl_decode_texture(ctx, bytes, size, "a.dds", NULL, &from_dds, NULL), IBL_OK);
    assert_int_equal(ibl_decode_texture(ctx, ktx, ktx_size, "a.ktx2", NULL, &from_ktx, NULL), IBL_OK);
    assert_memory_equal(from_dds.data, from_ktx.data,
                        ibl_texture_floats(IBL_TEXTURE_CUBE_ARRAY, SIZE, SIZE, LAYERS, LEVELS) * sizeof(float));
    ibl_texture_free(ctx, &from_dds);
    ibl_texture_free(ctx, &from_ktx);
    ibl_free(ctx, ktx);
    ibl_free(ctx, bytes);
    ibl_texture_free(ctx, &tex);
    free_cubes(ctx, cubes);
    ibl_context_destroy(ctx);
}

/* What stays refused: KTX1 output, 2D arrays, arrays as flat images. */
static void refusals(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_texture tex;
    ibl_cubemap cubes[LAYERS];
    make_array(ctx, &tex, cubes);
    void *bytes;
    size_t size;
    assert_int_equal(ibl_encode_texture(ctx, IBL_FILE_KTX1, &tex, NULL, &bytes, &size), IBL_ERR_UNSUPPORTED);
    assert_non_null(strstr(ibl_context_message(ctx), "cube-map arrays"));
    /* a KTX2 cube array turned into a 2D array (faceCount 1) */
    assert_int_equal(ibl_encode_texture(ctx, IBL_FILE_KTX2, &tex, NULL, &bytes, &size), IBL_OK);
    uint8_t *b = bytes;
    b[36] = 1;
    ibl_texture back;
    assert_int_equal(ibl_decode_texture(ctx, bytes, size, "two.ktx2", NULL, &back, NULL), IBL_ERR_UNSUPPORTED);
    assert_non_null(strstr(ibl_context_message(ctx), "two.ktx2: 2D array textures"));
    ibl_free(ctx, bytes);
    /* a DDS array without the cube flag */
    assert_int_equal(ibl_encode_texture(ctx, IBL_FILE_DDS, &tex, NULL, &bytes, &size), IBL_OK);
    b = bytes;
    b[4 + 124 + 8] = 0;
    assert_int_equal(ibl_decode_texture(ctx, bytes, size, "two.dds", NULL, &back, NULL), IBL_ERR_UNSUPPORTED);
    assert_non_null(strstr(ibl_context_message(ctx), "two.dds: arraySize 3"));
    /* arraySize larger than the data */
    b[4 + 124 + 8] = 4;
    b[4 + 124 + 12] = 4;
    assert_int_equal(ibl_decode_texture(ctx, bytes, size, "short.dds", NULL, &back, NULL), IBL_ERR_FORMAT);
    assert_non_null(strstr(ibl_context_message(ctx), "short.dds: truncated"));
    ibl_free(ctx, bytes);
    ibl_texture_free(ctx, &tex);
    free_cubes(ctx, cubes);
    ibl_context_destroy(ctx);
}

/* `ibl info` reports the layers (text and JSON); `ibl convert` copies an array between
 * containers and refuses what would need one cube, with no output left behind. */
static void cli(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_texture tex;
    ibl_cubemap cubes[LAYERS];
    make_array(ctx, &tex, cubes);
    /* layer i is a constant i + 1 so its mean radiance is known exactly */
    for (int i = 0; i < LAYERS; i++)
        for (int l = 0; l < LEVELS; l++)
            for (int f = 0; f < 6; f++) {
                int n = ibl_level_size(SIZE, l);
                float *p = ibl_texture_level(&tex, l, 6 * i + f);
                for (int t = 0; t < n * n; t++) p[4 * t] = p[4 * t + 1] = p[4 * t + 2] = (float)(i + 1);
            }
    const char *arr = test_path("arr.ktx2");
    ibl_write_desc wd = {.format = IBL_FORMAT_RGBA16F};
    assert_int_equal(ibl_write_texture(ctx, arr, &tex, &wd), IBL_OK);
    const char *out;
    assert_int_equal(test_run_cli(&out, "info '%s'", arr), 0);
    assert_non_null(strstr(out, "kind:            cube-array"));
    assert_non_null(strstr(out, "layers:          3 cubes"));
    assert_non_null(strstr(out, "layer 2        3 3 3"));
    assert_int_equal(test_run_cli(&out, "info --json '%s'", arr), 0);
    assert_non_null(strstr(out, "\"layers\": 3"));
    assert_non_null(strstr(out, "\"mean_radiance\": [\n    2.0"));

    const char *dds = test_path("arr.dds"), *again = test_path("again.ktx2");
    assert_int_equal(test_run_cli(&out, "convert -q '%s' -o '%s' --format bc6h", arr, dds), 0);
    assert_int_equal(test_run_cli(&out, "info '%s'", dds), 0);
    assert_non_null(strstr(out, "layers:          3 cubes"));
    assert_non_null(strstr(out, "mip levels:      4"));
    assert_int_equal(test_run_cli(&out, "convert -q '%s' -o '%s' --zstd", dds, again), 0);
    ibl_texture back;
    assert_int_equal(ibl_read_texture(ctx, again, NULL, &back, NULL), IBL_OK);
    assert_int_equal(back.kind, IBL_TEXTURE_CUBE_ARRAY);
    assert_int_equal(back.depth, LAYERS);
    /* constants survive BC6H exactly when they are halves: 1, 2, 3 are */
    for (int i = 0; i < LAYERS; i++) assert_true(ibl_texture_level(&back, 2, 6 * i + 5)[0] == (float)(i + 1));
    ibl_texture_free(ctx, &back);

    const char *bad = test_path("bad.ktx2");
    assert_int_equal(test_run_cli(&out, "convert '%s' -o '%s' --size 4", arr, bad), 2);
    assert_non_null(strstr(out, "a cube-map array of 3 layers converts only to .ktx2 or .dds"));
    assert_int_equal(test_run_cli(&out, "convert '%s' -o '%s'", arr, test_path("flat.exr")), 2);
    assert_int_equal(test_run_cli(&out, "prefilter '%s' -o '%s'", arr, bad), 1);
    assert_non_null(strstr(out, "is not one environment"));
    assert_false(test_file_exists(bad));
    assert_false(test_file_exists(test_path("flat.exr")));
    ibl_texture_free(ctx, &tex);
    free_cubes(ctx, cubes);
    ibl_context_destroy(ctx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(ktx2_round_trip),
        cmocka_unit_test(dds_round_trip),
        cmocka_unit_test(refusals),
        cmocka_unit_test(cli),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
