/* Daqi 2016's 2D mip atlas and channel packing as outputs (docs/ATLAS.md):
 *  - the coordinate table through its JSON (every arrangement round-trips; a table that is
 *    not the plan's is refused with the field named);
 *  - the atlas lookup against the cube lookup at every level of a smooth chain, both against
 *    the analytic field;
 *  - a bake with the atlas: the table from manifest.json, from the KTX2's key ibl.atlas and
 *    the plan are the same rectangles, the texels come back (half rounding; RGBM PNG within
 *    RGBM's bound), a manifest whose table was edited is refused;
 *  - the commands: `ibl prefilter --out-layout atlas`, `ibl render --atlas`, `ibl pack` and
 *    `ibl unpack` (exact 8- and 16-bit round trips, defaults, one-line errors). */
#include "test_support.h"

#include <jansson.h>
#include <math.h>
#include <png.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- the table ---------------------------------------------------------------------------- */

static void table_round_trip(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    int cases = 0;
    for (int size = 1; size <= 512; size *= 2)
        for (int levels = 1; levels <= ibl_full_mip_count(size); levels++)
            for (int gutter = -1; gutter <= 2; gutter++) {
                if (gutter == 0) continue; /* 0 means the default, 1 */
                ibl_atlas_layout plan, back;
                ibl_atlas_desc d = {.gutter = gutter};
                assert_int_equal(ibl_atlas_plan(size, levels, &d, &plan), IBL_OK);
                char *text = NULL;
                assert_int_equal(ibl_atlas_layout_to_json(ctx, &plan, &text), IBL_OK);
                assert_null(strchr(text, '\n')); /* one line: a KTX2 value */
                assert_int_equal(ibl_atlas_layout_from_json(ctx, text, "t", &back), IBL_OK);
                assert_memory_equal(&plan, &back, sizeof plan);
                ibl_free(ctx, text);
                cases++;
            }
    assert_true(cases > 100);
    /* a moved rectangle, a wrong count, a missing key: refused, naming the field */
    ibl_atlas_layout plan, back;
    assert_int_equal(ibl_atlas_plan(64, 5, NULL, &plan), IBL_OK);
    plan.x[3] += 1;
    char *text = NULL;
    assert_int_equal(ibl_atlas_layout_to_json(ctx, &plan, &text), IBL_OK);
    assert_int_equal(ibl_atlas_layout_from_json(ctx, text, "moved.json", &back), IBL_ERR_FORMAT);
    assert_non_null(strstr(ibl_context_message(ctx), "moved.json: rects"));
    ibl_free(ctx, text);
    assert_int_equal(ibl_atlas_layout_from_json(ctx, "{\"width\":198,\"height\":236,\"levels\":5,"
                                                     "\"gutter\":1,\"rects\":[[0,0,64]]}", "few", &back),
                     IBL_ERR_FORMAT);
    assert_non_null(strstr(ibl_context_message(ctx), "1 rectangles for 5 levels"));
    assert_int_equal(ibl_atlas_layout_from_json(ctx, "{\"width\":198}", "short", &back), IBL_ERR_FORMAT);
    assert_non_null(strstr(ibl_context_message(ctx), "short: height: missing"));
    ibl_context_destroy(ctx);
}

/* ---- the lookup against the cube ---------------------------------------------------------- */

/* A smooth field with curvature in every channel. */
static void field(const double d[3], double out[3])
{
    out[0] = 1.0 + 0.5 * d[0] + 0.25 * d[1] * d[2];
    out[1] = 2.0 + 0.3 * d[1] - 0.4 * d[0] * d[0];
    out[2] = exp(1.2 * d[2]);
}

static uint64_t rng_next(uint64_t *s)
{
    *s = *s * 6364136223846793005ull + 1442695040888963407ull;
    return *s >> 11;
}

/* Every level of a 64-texel chain holds the field at its texel centres. At each level the
 * cube's seamless bilinear and the atlas's 2D bilinear are both interpolations of the
 * field's samples, each within the field's curvature times the texel size squared of it.
 * Levels 0 and 1 are the cube's own texels: inside a face, away from the edge texels, the
 * two lookups are the same four texels with the same weights (equal to 1e-6). At face edges
 * the atlas reads its gutter (the neighbour sampled at the gutter texel's direction) and
 * levels >= 2 are enlarged to level 2's size by bilinear sampling, so a lookup there
 * interpolates twice: the second interpolation of a function already within E of the field
 * adds at most E again (its weights are convex) plus the finer grid's own error, which is
 * smaller. Bound: the atlas's worst error at a level is at most twice the cube's. */
static void lookup_matches_cube_every_level(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_cubemap chain;
    const int size = 64, levels = 7;
    assert_int_equal(ibl_cubemap_alloc(ctx, size, levels, &chain), IBL_OK);
    for (int k = 0; k < levels; k++) {
        int n = ibl_level_size(size, k);
        for (int f = 0; f < 6; f++) {
            float *face = ibl_cubemap_face(&chain, k, f);
            for (int y = 0; y < n; y++)
                for (int x = 0; x < n; x++) {
                    double d[3], v[3];
                    test_texel_dir(f, n, x, y, d);
                    field(d, v);
                    float *t = face + ((size_t)y * n + x) * 4;
                    t[0] = (float)v[0], t[1] = (float)v[1], t[2] = (float)v[2], t[3] = 1.0f;
                }
        }
    }
    ibl_image atlas;
    ibl_atlas_layout layout;
    assert_int_equal(ibl_atlas_pack(ctx, &chain, NULL, &atlas, &layout), IBL_OK);
    uint64_t rng = 7;
    for (int k = 0; k < levels; k++) {
        int n = ibl_level_size(size, k);
        double worst_cube = 0, worst_atlas = 0, worst_inside = 0;
        for (int i = 0; i < 20000; i++) {
            double d[3], v[3];
            for (int c = 0; c < 3; c++) d[c] = (double)(rng_next(&rng) % 2000001) / 1e6 - 1.0;
            double len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            if (len < 1e-3) continue;
            for (int c = 0; c < 3; c++) d[c] /= len;
            field(d, v);
            ibl_vec3 dir = {(float)d[0], (float)d[1], (float)d[2]};
            float a[4], b[4];
            ibl_cubemap_sample_bilinear(&chain, k, dir, a);
            ibl_atlas_sample(&atlas, &layout, (float)k, dir, b);
            for (int c = 0; c < 3; c++) {
                worst_cube = fmax(worst_cube, fabs(a[c] - v[c]));
                worst_atlas = fmax(worst_atlas, fabs(b[c] - v[c]));
            }
            float s, t;
            ibl_cube_face_st(dir, &s, &t);
            int inside = s * n > 1.0f && s * n < n - 1.0f && t * n > 1.0f && t * n < n - 1.0f;
            if (k < 2 && inside)
                for (int c = 0; c < 3; c++) worst_inside = fmax(worst_inside, fabs(a[c] - b[c]));
        }
        print_message("level %d (%d texels): max |cube - field| %.2e, |atlas - field| %.2e%s\n", k, n,
                      worst_cube, worst_atlas, k < 2 ? ", inside faces identical" : "");
        assert_true(worst_atlas <= 2.0 * worst_cube + 1e-6);
        if (k < 2) assert_true(worst_inside <= 1e-6 * 3.4); /* e^1.2 = 3.3 is the largest value */
    }
    ibl_image_free(ctx, &atlas);
    ibl_cubemap_free(ctx, &chain);
    ibl_context_destroy(ctx);
}

/* ---- a bake with the atlas ---------------------------------------------------------------- */

static void smooth(const double *d, float *rgb)
{
    double v[3];
    field(d, v);
    for (int c = 0; c < 3; c++) rgb[c] = (float)(0.5 * v[c]);
}

static void bake_round_trip(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(0);
    ibl_cubemap env;
    assert_int_equal(ibl_cubemap_alloc(ctx, 32, 1, &env), IBL_OK);
    test_fill_cube_fn(&env, smooth);
    ibl_bake_desc d = {.specular = {.size = 32}, .atlas = 1, .preview_width = -1, .ambient_brdf = -1};
    const char *dir = test_path("atlas_bake");
    ibl_bake_data made, back;
    assert_int_equal(ibl_bake(ctx, &env, &d, dir, &made), IBL_OK);
    assert_non_null(made.atlas.pixels);
    /* the plan, the manifest's table and the KTX2's own are the same rectangles */
    ibl_atlas_layout plan;
    assert_int_equal(ibl_atlas_plan(32, made.specular_info.levels, NULL, &plan), IBL_OK);
    assert_memory_equal(&plan, &made.atlas_layout, sizeof plan);
    assert_int_equal(ibl_bake_load(ctx, dir, NULL, &back), IBL_OK);
    assert_memory_equal(&plan, &back.atlas_layout, sizeof plan);
    char path[1024];
    snprintf(path, sizeof path, "%s/specular_atlas.ktx2", dir);
    ibl_texture tex;
    assert_int_equal(ibl_read_texture(ctx, path, NULL, &tex, NULL), IBL_OK);
    ibl_atlas_layout own;
    assert_int_equal(ibl_atlas_layout_from_json(ctx, ibl_texture_get_metadata(&tex, "ibl.atlas"), path, &own), IBL_OK);
    assert_memory_equal(&plan, &own, sizeof plan);
    assert_non_null(ibl_texture_get_metadata(&tex, "ibl.specular.filter"));
    ibl_texture_free(ctx, &tex);
    /* texels: rgba16f, so within half an ulp of half (2^-11 relative) */
    size_t n = (size_t)plan.width * plan.height * 4;
    for (size_t i = 0; i < n; i++)
        assert_true(fabsf(back.atlas.pixels[i] - made.atlas.pixels[i]) <= fabsf(made.atlas.pixels[i]) * 4.9e-4f + 1e-7f);
    /* the RGBM PNG decodes to the RGBM of the atlas, bit for bit */
    snprintf(path, sizeof path, "%s/specular_atlas.png", dir);
    ibl_image png;
    ibl_file_info info;
    assert_int_equal(ibl_read_image(ctx, path, NULL, &png, &info), IBL_OK);
    assert_int_equal(info.format, IBL_FORMAT_RGBM);
    for (size_t t = 0; t < n / 4; t++) {
        uint8_t code[4];
        float want[3];
        ibl_rgbm_encode(made.atlas.pixels + t * 4, IBL_RGBM_DEFAULT_RANGE, code);
        ibl_rgbm_decode(code, IBL_RGBM_DEFAULT_RANGE, want);
        for (int c = 0; c < 3; c++) assert_true(png.pixels[t * 4 + c] == want[c]);
    }
    ibl_image_free(ctx, &png);
    /* the probe offers the atlas; use_atlas reads it */
    ibl_probe probe;
    assert_int_equal(ibl_bake_probe(ctx, &back, &probe), IBL_OK);
    assert_non_null(probe.atlas);
    probe.use_atlas = 1;
    assert_int_equal(ibl_probe_validate(ctx, &probe), IBL_OK);
    float via_atlas[3], direct[4];
    ibl_vec3 up = {0.2f, 0.9f, 0.1f};
    ibl_probe_sample_specular(&probe, 1.5f, up, via_atlas);
    ibl_atlas_sample(&back.atlas, &back.atlas_layout, 1.5f, up, direct);
    for (int c = 0; c < 3; c++) assert_true(via_atlas[c] == direct[c]);
    ibl_bake_free(ctx, &back);
    /* a manifest whose table was edited is refused, naming the field */
    char manifest[1024];
    snprintf(manifest, sizeof manifest, "%s/manifest.json", dir);
    json_error_t err;
    json_t *root = json_load_file(manifest, 0, &err);
    assert_non_null(root);
    json_t *rect = json_array_get(json_object_get(json_object_get(root, "atlas"), "rects"), 2);
    json_array_set_new(rect, 0, json_integer(json_integer_value(json_array_get(rect, 0)) + 2));
    assert_int_equal(json_dump_file(root, manifest, 0), 0);
    json_decref(root);
    assert_int_equal(ibl_bake_load(ctx, dir, NULL, &back), IBL_ERR_FORMAT);
    assert_non_null(strstr(ibl_context_message(ctx), "atlas.rects"));
    ibl_bake_free(ctx, &made);
    ibl_cubemap_free(ctx, &env);
    ibl_context_destroy(ctx);
}

/* ---- the commands ------------------------------------------------------------------------- */

static void prefilter_and_render(void **state)
{
    (void)state;
    const char *out;
    char sky[600], ktx[600], png[600], manifest[600], bake[600], r0[600], r1[600];
    snprintf(sky, sizeof sky, "%s", test_path("sky.exr"));
    snprintf(ktx, sizeof ktx, "%s", test_path("chain_atlas.ktx2"));
    snprintf(png, sizeof png, "%s", test_path("chain_atlas.png"));
    snprintf(manifest, sizeof manifest, "%s", test_path("chain_atlas.manifest.json"));
    assert_int_equal(test_run_cli(&out, "sky -q --size 128 -o '%s'", sky), 0);
    assert_int_equal(test_run_cli(&out, "prefilter -q '%s' --size 16 --out-layout atlas -o '%s'", sky, ktx), 0);
    assert_int_equal(test_run_cli(&out, "prefilter -q '%s' --size 16 --out-layout atlas -o '%s'", sky, png), 0);
    /* the manifest's table and the KTX2's */
    json_error_t err;
    json_t *root = json_load_file(manifest, 0, &err);
    assert_non_null(root);
    char *table = json_dumps(json_object_get(root, "atlas"), JSON_COMPACT);
    assert_non_null(table);
    ibl_context *ctx = test_context(1);
    ibl_atlas_layout from_manifest, from_ktx2, plan;
    assert_int_equal(ibl_atlas_layout_from_json(ctx, table, manifest, &from_manifest), IBL_OK);
    ibl_texture tex;
    assert_int_equal(ibl_read_texture(ctx, ktx, NULL, &tex, NULL), IBL_OK);
    assert_int_equal(ibl_atlas_layout_from_json(ctx, ibl_texture_get_metadata(&tex, "ibl.atlas"), ktx, &from_ktx2), IBL_OK);
    assert_int_equal(ibl_atlas_plan(16, from_manifest.levels, NULL, &plan), IBL_OK);
    assert_memory_equal(&plan, &from_manifest, sizeof plan);
    assert_memory_equal(&plan, &from_ktx2, sizeof plan);
    assert_int_equal(tex.width, plan.width);
    assert_int_equal(tex.height, plan.height);
    ibl_texture_free(ctx, &tex);
    free(table);
    json_decref(root);
    /* a container the atlas does not go into: a usage error before any work */
    assert_int_equal(test_run_cli(&out, "prefilter -q '%s' --out-layout atlas -o '%s'", sky,
                                  test_path("chain.dds")), 2);
    assert_non_null(strstr(out, "an atlas is written as .ktx2, .exr or .png"));
    /* render --atlas: a bake with an atlas renders close to its cube; one without is refused */
    snprintf(bake, sizeof bake, "%s", test_path("bake_cli"));
    snprintf(r0, sizeof r0, "%s", test_path("cube.exr"));
    snprintf(r1, sizeof r1, "%s", test_path("atlas.exr"));
    assert_int_equal(test_run_cli(&out, "bake -q '%s' --size 32 --preview-width 0 --out-layout atlas -o '%s'", sky, bake), 0);
    assert_int_equal(test_run_cli(&out, "render -q '%s' --width 128 -o '%s'", bake, r0), 0);
    assert_int_equal(test_run_cli(&out, "render -q '%s' --atlas --width 128 -o '%s'", bake, r1), 0);
    ibl_image a, b;
    assert_int_equal(ibl_read_image(ctx, r0, NULL, &a, NULL), IBL_OK);
    assert_int_equal(ibl_read_image(ctx, r1, NULL, &b, NULL), IBL_OK);
    double sa = 0, sb = 0, diff = 0;
    for (size_t i = 0; i < (size_t)a.width * a.height * 4; i++) {
        sa += a.pixels[i], sb += b.pixels[i];
        diff += fabs(a.pixels[i] - b.pixels[i]);
    }
    /* the spheres read the same chain two ways (the background is the same cube in both):
     * the images differ (the atlas is really read) by little (see test_shaders_atlas for the
     * per-pixel bounds); measured 0.5% of the image's sum */
    print_message("render --atlas against the cube: sum %.6g vs %.6g, mean |difference| / mean %.2e\n", sb, sa, diff / sa);
    assert_true(diff > 0.0);
    assert_true(diff / sa < 0.02);
    ibl_image_free(ctx, &a);
    ibl_image_free(ctx, &b);
    snprintf(bake, sizeof bake, "%s", test_path("bake_plain"));
    assert_int_equal(test_run_cli(&out, "bake -q '%s' --size 16 --preview-width 0 -o '%s'", sky, bake), 0);
    assert_int_equal(test_run_cli(&out, "render -q '%s' --atlas -o '%s'", bake, r1), 1);
    assert_non_null(strstr(out, "holds no mip atlas"));
    ibl_context_destroy(ctx);
}

/* A grey PNG of raw codes with an sRGB chunk (which `ibl pack` must ignore: the maps are data). */
static void write_codes(const char *path, int w, int h, int depth, unsigned (*code)(int, int))
{
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
    png_infop info = png_create_info_struct(png);
    test_bytes m = {NULL, 0, 0};
    assert_int_equal(setjmp(png_jmpbuf(png)), 0);
    test_png_write_to_memory(png, &m);
    png_set_IHDR(png, info, w, h, depth, PNG_COLOR_TYPE_GRAY, PNG_INTERLACE_NONE,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_set_sRGB(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
    png_write_info(png, info);
    uint8_t row[2 * 256];
    for (int y = 0; y < h; y++) {
        for (int x = 0; x < w; x++) {
            unsigned v = code(x, y);
            if (depth == 16) row[2 * x] = (uint8_t)(v >> 8), row[2 * x + 1] = (uint8_t)v;
            else row[x] = (uint8_t)v;
        }
        png_write_row(png, row);
    }
    png_write_end(png, info);
    png_destroy_write_struct(&png, &info);
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(m.b, 1, m.n, f), m.n);
    fclose(f);
    free(m.b);
}

static unsigned code8_metal(int x, int y) { return (unsigned)(x * 3 + y * 17) % 256; }
static unsigned code8_ao(int x, int y) { return (unsigned)(255 - (x * 5 + y * 7) % 256); }
static unsigned code16_rough(int x, int y) { return (unsigned)(x * 2999 + y * 40961) % 65536; }
static unsigned code16_trans(int x, int y) { return (unsigned)(x * 65521 + y * 257) % 65536; }

/* The codes of channel c of a linear PNG (read as data). */
static void read_codes(ibl_context *ctx, const char *path, int depth, int c, unsigned *out, int n)
{
    ibl_image im;
    ibl_read_desc rd = {.as_data = 1};
    assert_int_equal(ibl_read_image(ctx, path, &rd, &im, NULL), IBL_OK);
    assert_int_equal(im.width * im.height, n);
    double max = depth == 16 ? 65535.0 : 255.0;
    for (int i = 0; i < n; i++) out[i] = (unsigned)lrint(im.pixels[i * 4 + c] * max);
    ibl_image_free(ctx, &im);
}

static void pack_unpack(void **state)
{
    (void)state;
    enum { W = 40, H = 24, N = W * H };
    const char *out;
    char metal[600], ao[600], rough[600], trans[600], small[600], mixed8[600], mixed16[600], prefix[600];
    snprintf(metal, sizeof metal, "%s", test_path("metal.png"));
    snprintf(ao, sizeof ao, "%s", test_path("ao.png"));
    snprintf(rough, sizeof rough, "%s", test_path("rough16.png"));
    snprintf(trans, sizeof trans, "%s", test_path("trans16.png"));
    snprintf(small, sizeof small, "%s", test_path("small.png"));
    snprintf(mixed8, sizeof mixed8, "%s", test_path("mixed8.png"));
    snprintf(mixed16, sizeof mixed16, "%s", test_path("mixed16.png"));
    snprintf(prefix, sizeof prefix, "%s", test_path("split"));
    write_codes(metal, W, H, 8, code8_metal);
    write_codes(ao, W, H, 8, code8_ao);
    write_codes(rough, W, H, 16, code16_rough);
    write_codes(trans, W, H, 16, code16_trans);
    write_codes(small, W / 2, H, 8, code8_ao);
    ibl_context *ctx = test_context(1);
    unsigned got[N];
    /* 8-bit: metalness and AO given, roughness and transmittance their defaults (1, 0) */
    assert_int_equal(test_run_cli(&out, "pack -q --metal '%s' --ao '%s' -o '%s'", metal, ao, mixed8), 0);
    read_codes(ctx, mixed8, 8, 0, got, N);
    for (int i = 0; i < N; i++) assert_int_equal(got[i], code8_metal(i % W, i / W));
    read_codes(ctx, mixed8, 8, 1, got, N);
    for (int i = 0; i < N; i++) assert_int_equal(got[i], 255);
    read_codes(ctx, mixed8, 8, 2, got, N);
    for (int i = 0; i < N; i++) assert_int_equal(got[i], code8_ao(i % W, i / W));
    read_codes(ctx, mixed8, 8, 3, got, N);
    for (int i = 0; i < N; i++) assert_int_equal(got[i], 0);
    /* 16-bit (a 16-bit map makes the output 16-bit): every map, then unpack */
    assert_int_equal(test_run_cli(&out, "pack -q --metal '%s' --rough '%s' --ao '%s' --transmittance '%s' -o '%s'",
                                  metal, rough, ao, trans, mixed16), 0);
    read_codes(ctx, mixed16, 16, 1, got, N);
    for (int i = 0; i < N; i++) assert_int_equal(got[i], code16_rough(i % W, i / W));
    read_codes(ctx, mixed16, 16, 3, got, N);
    for (int i = 0; i < N; i++) assert_int_equal(got[i], code16_trans(i % W, i / W));
    read_codes(ctx, mixed16, 16, 0, got, N); /* an 8-bit code c is 257 c in 16 bits */
    for (int i = 0; i < N; i++) assert_int_equal(got[i], 257 * code8_metal(i % W, i / W));
    assert_int_equal(test_run_cli(&out, "unpack -q '%s' -o '%s'", mixed16, prefix), 0);
    char path[700];
    snprintf(path, sizeof path, "%s_roughness.png", prefix);
    read_codes(ctx, path, 16, 0, got, N);
    for (int i = 0; i < N; i++) assert_int_equal(got[i], code16_rough(i % W, i / W));
    snprintf(path, sizeof path, "%s_transmittance.png", prefix);
    read_codes(ctx, path, 16, 1, got, N); /* grey: G = R */
    for (int i = 0; i < N; i++) assert_int_equal(got[i], code16_trans(i % W, i / W));
    /* 8-bit unpack of the 8-bit texture: exact too */
    assert_int_equal(test_run_cli(&out, "unpack -q '%s' -o '%s'", mixed8, prefix), 0);
    snprintf(path, sizeof path, "%s_ao.png", prefix);
    read_codes(ctx, path, 8, 0, got, N);
    for (int i = 0; i < N; i++) assert_int_equal(got[i], code8_ao(i % W, i / W));
    /* mismatched sizes: one line naming the file, nothing written */
    char lone[600];
    snprintf(lone, sizeof lone, "%s", test_path("never.png"));
    assert_int_equal(test_run_cli(&out, "pack -q --metal '%s' --ao '%s' -o '%s'", metal, small, lone), 1);
    assert_non_null(strstr(out, small));
    assert_non_null(strstr(out, "20x24"));
    const char *nl = strchr(out, '\n');
    assert_true(nl && nl[1] == 0); /* one line */
    assert_false(test_file_exists(lone));
    /* a missing map file: named; no map at all: a usage error */
    assert_int_equal(test_run_cli(&out, "pack -q --rough '%s' -o '%s'", test_path("absent.png"), lone), 1);
    assert_non_null(strstr(out, "absent.png"));
    assert_int_equal(test_run_cli(&out, "pack -q -o '%s'", lone), 2);
    assert_false(test_file_exists(lone));
    ibl_context_destroy(ctx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(table_round_trip),
        cmocka_unit_test(lookup_matches_cube_every_level),
        cmocka_unit_test(bake_round_trip),
        cmocka_unit_test(prefilter_and_render),
        cmocka_unit_test(pack_unpack),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
