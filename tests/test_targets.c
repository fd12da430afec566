/* Engine targets (ibl/target.h, src/bake/target*.c): the table, the SH forms against a
 * float64 brute-force irradiance integral, Babylon's .env and the glTF lights read back by
 * an independent parser (jansson, libpng, RGBD decoded here from Babylon's formula) and
 * compared with the float chain, the README, the manifest, the CLI's override order. The
 * renders in the engines themselves are tests/viewer/engines_test.mjs. */
#include "test_support.h"

#include <jansson.h>
#include <math.h>
#include <png.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const double PI = 3.14159265358979323846;

/* ---- fixtures -------------------------------------------------------------------------------- */

/* smooth colours plus a bright lobe (values up to ~60: RGBD's D below 1) around +X+Y */
static void field(const double *d, float *rgb)
{
    double lobe = 60.0 * exp(8.0 * ((d[0] + d[1]) / sqrt(2.0) - 1.0));
    rgb[0] = (float)(0.6 + 0.3 * d[0] + lobe);
    rgb[1] = (float)(0.4 + 0.2 * d[1] * d[2] + 0.5 * lobe);
    rgb[2] = (float)(0.3 + 0.25 * d[2] * d[2] + 0.2 * lobe);
}

static void environment(ibl_context *ctx, int size, ibl_cubemap *env)
{
    assert_int_equal(ibl_cubemap_alloc(ctx, size, 1, env), IBL_OK);
    test_fill_cube_fn(env, field);
}

/* a small bake for a target: 32-texel chain, small tables */
static void bake_target(ibl_context *ctx, ibl_target t, const char *dir, ibl_bake_data *out)
{
    const ibl_target_profile *p = ibl_target_profile_of(t);
    assert_non_null(p);
    ibl_bake_desc d;
    ibl_bake_desc_for_target(p, &d);
    d.specular.size = 32;
    d.specular.levels = ibl_target_levels(32, p->last_level_size);
    d.lut_size = 8;
    d.irradiance_size = 4;
    d.ambient_brdf = -1;
    d.preview_width = -1;
    ibl_cubemap env;
    environment(ctx, 32, &env);
    assert_int_equal(ibl_bake(ctx, &env, &d, dir, out), IBL_OK);
    ibl_cubemap_free(ctx, &env);
}

static char *slurp(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *b = malloc((size_t)n + 1);
    assert_int_equal(fread(b, 1, (size_t)n, f), (size_t)n);
    b[n] = 0;
    fclose(f);
    if (size) *size = (size_t)n;
    return b;
}

/* ---- the table ------------------------------------------------------------------------------- */

static void table_rows(void **state)
{
    (void)state;
    const char *const *names = ibl_target_names();
    int count = 0;
    for (; names[count]; count++) {
        ibl_target t;
        assert_true(ibl_target_from_name(names[count], &t));
        assert_string_equal(ibl_target_name(t), names[count]);
        assert_int_equal(ibl_target_profile_of(t)->target, t);
    }
    assert_int_equal(count, IBL_TARGET_COUNT - 1);
    assert_false(ibl_target_from_name("unknown", NULL));
    /* three: Filament's mapping down to 8x8 (PMREMGenerator's LOD_MIN 3), mirrored in x */
    const ibl_target_profile *three = ibl_target_profile_of(IBL_TARGET_THREE);
    assert_int_equal(three->mapping, IBL_MAPPING_FILAMENT);
    assert_int_equal(ibl_target_levels(256, three->last_level_size), 6);
    assert_int_equal(three->orientation.mirror, 1);
    /* glTF: EXT_lights_image_based's "say, 16x16" last mip, roughness linear in the mip */
    const ibl_target_profile *gltf = ibl_target_profile_of(IBL_TARGET_GLTF);
    assert_int_equal(ibl_target_levels(256, gltf->last_level_size), 5);
    assert_int_equal(gltf->mapping, IBL_MAPPING_LINEAR);
    assert_int_equal(ibl_target_levels(8, 8), 0);
    /* the native engines' rows are filled (test_engine_targets.c checks their files) */
    const ibl_target filled[] = {IBL_TARGET_FILAMENT, IBL_TARGET_UNITY, IBL_TARGET_UNREAL, IBL_TARGET_GODOT};
    for (size_t i = 0; i < sizeof filled / sizeof filled[0]; i++)
        assert_null(ibl_target_profile_of(filled[i])->not_ready);
    const ibl_target_profile *filament = ibl_target_profile_of(IBL_TARGET_FILAMENT);
    assert_true(filament->orientation.yaw_degrees == 180.0f);
    assert_int_equal(ibl_target_levels(256, filament->last_level_size), 5);
}

static void unknown_targets_refuse(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_cubemap env;
    environment(ctx, 8, &env);
    ibl_bake_data b;
    ibl_bake_desc d = {.target = IBL_TARGET_COUNT, .specular = {.size = 8}, .preview_width = -1};
    assert_int_equal(ibl_bake_compute(ctx, &env, &d, &b), IBL_ERR_INVALID_ARGUMENT);
    assert_non_null(strstr(ibl_context_message(ctx), "unknown target"));
    ibl_cubemap_free(ctx, &env);
    ibl_context_destroy(ctx);
    const char *out;
    assert_int_equal(test_run_cli(&out, "bake --target nosuch -o %s", test_path("nosuch")), 2);
    assert_false(test_file_exists(test_path("nosuch")));
    assert_non_null(strstr(out, "--target wants"));
}

/* ---- SH forms against a brute-force irradiance --------------------------------------------- */

/* E(n) = integral of L(w) max(0, n.w) dw in float64 over a 400 x 800 grid of the sphere. L is
 * the 3-band function of radiance (band-limited, so the clamped-cosine convolution keeps it
 * exactly in the first 3 bands: the forms must reproduce E to the grid's accuracy). */
static void brute_irradiance(const ibl_sh *radiance, const double n[3], double e[3])
{
    const int NT = 400, NP = 800;
    e[0] = e[1] = e[2] = 0;
    for (int i = 0; i < NT; i++) {
        double th = PI * (i + 0.5) / NT, st = sin(th), ct = cos(th);
        double dw = (PI / NT) * (2 * PI / NP) * st;
        for (int j = 0; j < NP; j++) {
            double ph = 2 * PI * (j + 0.5) / NP;
            double w[3] = {st * cos(ph), st * sin(ph), ct};
            double c = n[0] * w[0] + n[1] * w[1] + n[2] * w[2];
            if (c <= 0) continue;
            double l[3];
            ibl_sh_eval(radiance, w, l);
            for (int k = 0; k < 3; k++) e[k] += l[k] * c * dw;
        }
    }
}

static void sh_forms_against_brute_force(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_sh r = {.bands = 3};
    for (int i = 0; i < 9; i++)
        for (int c = 0; c < 3; c++) r.c[i][c] = (i == 0 ? 2.0 : 0.3) * cos(1.7 * i + 0.9 * c) + 0.05 * c;
    ibl_target_sh three, gltf, babylon;
    assert_int_equal(ibl_target_sh_form_of(ctx, IBL_TARGET_SH_THREE, &r, &three), IBL_OK);
    assert_int_equal(ibl_target_sh_form_of(ctx, IBL_TARGET_SH_GLTF_IRRADIANCE, &r, &gltf), IBL_OK);
    assert_int_equal(ibl_target_sh_form_of(ctx, IBL_TARGET_SH_BABYLON, &r, &babylon), IBL_OK);
    assert_non_null(three.frame);
    assert_non_null(gltf.signs);
    assert_non_null(babylon.normalisation);
    const double dirs[4][3] = {{0.48, 0.6, 0.64}, {-0.8, 0.36, -0.48}, {0, -1, 0}, {0.6, 0, -0.8}};
    for (int k = 0; k < 4; k++) {
        const double *n = dirs[k];
        double x = n[0], y = n[1], z = n[2];
        double e[3];
        brute_irradiance(&r, n, e);
        /* the grid's error is ~1e-5 of E; Babylon's own constants (0.886277 for sqrt(pi)/2,
         * 5 digits elsewhere) add up to 6e-5 relative: 2e-4 of E's scale */
        double tol = 2e-4 * (fabs(e[0]) + fabs(e[1]) + fabs(e[2]) + 1.0);
        for (int c = 0; c < 3; c++) {
            /* three.js's shGetIrradianceAt (lights_pars_begin), in three's frame: the cube's x
             * negated, so three at (-x, y, z) is E at (x, y, z) */
            const double (*t)[3] = three.values;
            double xm = -x;
            double e3 = 0.886227 * t[0][c] + 2.0 * 0.511664 * (t[1][c] * y + t[2][c] * z + t[3][c] * xm) +
                        2.0 * 0.429043 * (t[4][c] * xm * y + t[5][c] * y * z + t[7][c] * xm * z) +
                        t[6][c] * (0.743125 * z * z - 0.247708) + t[8][c] * 0.429043 * (xm * xm - y * y);
            assert_near(e3, e[c], tol);
            /* EXT_lights_image_based: E_lm in the Condon-Shortley-signed basis (Babylon's
             * SH3ylmBasisConstants) */
            const double (*g)[3] = gltf.values;
            double k0 = sqrt(1 / (4 * PI)), k1 = sqrt(3 / (4 * PI)), k2 = sqrt(15 / (4 * PI));
            double k20 = sqrt(5 / (16 * PI)), k22 = sqrt(15 / (16 * PI));
            double eg = g[0][c] * k0 - g[1][c] * k1 * y + g[2][c] * k1 * z - g[3][c] * k1 * x +
                        g[4][c] * k2 * x * y - g[5][c] * k2 * y * z + g[6][c] * k20 * (3 * z * z - 1) -
                        g[7][c] * k2 * x * z + g[8][c] * k22 * (x * x - y * y);
            assert_near(eg, e[c], tol);
            /* Babylon's SphericalPolynomial, turned back into harmonics as Babylon does for its
             * shader (SphericalHarmonics.FromPolynomial, its constants) and summed in the
             * Condon-Shortley basis: E / pi */
            const double (*p)[3] = babylon.values; /* x y z xx yy zz yz zx xy */
            double h[9] = {
                PI * (0.376127 * p[3][c] + 0.376127 * p[4][c] + 0.376126 * p[5][c]),
                PI * -0.977204 * p[1][c], PI * 0.977204 * p[2][c], PI * -0.977204 * p[0][c],
                PI * 1.16538 * p[8][c], PI * -1.16538 * p[6][c],
                PI * (1.34567 * p[5][c] - 0.672834 * p[3][c] - 0.672834 * p[4][c]),
                PI * -1.16538 * p[7][c], PI * 1.16538 * (p[3][c] - p[4][c])};
            double eb = h[0] * k0 - h[1] * k1 * y + h[2] * k1 * z - h[3] * k1 * x + h[4] * k2 * x * y -
                        h[5] * k2 * y * z + h[6] * k20 * (3 * z * z - 1) - h[7] * k2 * x * z +
                        h[8] * k22 * (x * x - y * y);
            assert_near(eb * PI, e[c], tol);
        }
    }
    ibl_sh two = {.bands = 2};
    assert_int_equal(ibl_target_sh_form_of(ctx, IBL_TARGET_SH_THREE, &two, &three), IBL_ERR_INVALID_ARGUMENT);
    ibl_context_destroy(ctx);
}

/* ---- RGBD faces ---------------------------------------------------------------------------- */

/* 8-bit RGBA of a PNG in memory (libpng's simplified API, no colour conversion: the file has
 * no colour chunk) */
static uint8_t *decode_png(const void *bytes, size_t size, int *w, int *h)
{
    png_image im;
    memset(&im, 0, sizeof im);
    im.version = PNG_IMAGE_VERSION;
    assert_true(png_image_begin_read_from_memory(&im, bytes, size));
    im.format = PNG_FORMAT_RGBA;
    uint8_t *px = malloc(PNG_IMAGE_SIZE(im));
    assert_true(png_image_finish_read(&im, NULL, px, 0, NULL));
    *w = (int)im.width;
    *h = (int)im.height;
    return px;
}

/* Compares an RGBD face (stored bottom row first) with the float face. Babylon's decoding,
 * written from its fromRGBD: rgb = (c / 255)^2.2 / (a / 255). Bound: the colour code is rounded
 * to half a step of a gamma-2.2 value that is at most 1, so its linear error is at most
 * 2.2 * 0.5 / 255 (the slope of x^2.2 below 1), divided by D = a / 255; values over 255 (D at
 * its floor 1/255) saturate. Returns the largest error over the bound. */
static double compare_rgbd_face(const uint8_t *px, int s, const float *face)
{
    double worst = 0;
    for (int y = 0; y < s; y++)
        for (int x = 0; x < s; x++) {
            const uint8_t *q = px + ((size_t)(s - 1 - y) * (size_t)s + (size_t)x) * 4;
            const float *f = face + ((size_t)y * (size_t)s + (size_t)x) * 4;
            double d = q[3] / 255.0;
            assert_true(q[3] >= 1);
            for (int c = 0; c < 3; c++) {
                double v = pow(q[c] / 255.0, 2.2) / d;
                double want = f[c] > 255.0 ? 255.0 : f[c];
                double bound = 2.2 * 0.5 / 255.0 / d + 1e-6 * want;
                double ratio = fabs(v - want) / bound;
                if (ratio > worst) worst = ratio;
            }
        }
    return worst;
}

static void babylon_env_file(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2);
    const char *dir = test_path("babylon");
    ibl_bake_data b;
    bake_target(ctx, IBL_TARGET_BABYLON, dir, &b);
    assert_int_equal(b.specular.levels, 6); /* 32 .. 1: the .env wants the whole chain */
    char path[1024];
    snprintf(path, sizeof path, "%s/engine_babylon.env", dir);
    size_t size;
    uint8_t *file = (uint8_t *)slurp(path, &size);
    static const uint8_t magic[8] = {0x86, 0x16, 0x87, 0x96, 0xf6, 0xd6, 0x96, 0x36};
    assert_memory_equal(file, magic, 8);
    size_t jlen = strlen((const char *)file + 8);
    json_error_t err;
    json_t *root = json_loadb((const char *)file + 8, jlen, 0, &err);
    assert_non_null(root);
    size_t data = 8 + jlen + 1;
    assert_int_equal(json_integer_value(json_object_get(root, "version")), 2);
    assert_int_equal(json_integer_value(json_object_get(root, "width")), 32);
    assert_string_equal(json_string_value(json_object_get(root, "imageType")), "image/png");
    json_t *spec = json_object_get(root, "specular");
    assert_near(json_number_value(json_object_get(spec, "lodGenerationScale")), 0.8, 1e-7);
    json_t *mips = json_object_get(spec, "mipmaps");
    assert_int_equal(json_array_size(mips), 6 * 6);
    size_t expect_position = 0;
    double worst = 0;
    for (size_t i = 0; i < json_array_size(mips); i++) {
        json_t *m = json_array_get(mips, i);
        size_t pos = (size_t)json_integer_value(json_object_get(m, "position"));
        size_t len = (size_t)json_integer_value(json_object_get(m, "length"));
        assert_int_equal(pos, expect_position); /* packed in order, level-major */
        expect_position += len;
        assert_true(data + pos + len <= size);
        int w, h;
        uint8_t *px = decode_png(file + data + pos, len, &w, &h);
        int level = (int)i / 6, face = (int)i % 6;
        assert_int_equal(w, ibl_level_size(32, level));
        assert_int_equal(h, w);
        double r = compare_rgbd_face(px, w, ibl_cubemap_face(&b.specular, level, face));
        if (r > worst) worst = r;
        free(px);
    }
    assert_int_equal(data + expect_position, size);
    assert_true(worst <= 1.0);
    /* the polynomial is the Babylon form of the bake's SH */
    ibl_target_sh poly;
    assert_int_equal(ibl_target_sh_form_of(ctx, IBL_TARGET_SH_BABYLON, &b.sh, &poly), IBL_OK);
    json_t *irr = json_object_get(root, "irradiance");
    for (int k = 0; k < 9; k++)
        for (int c = 0; c < 3; c++)
            assert_near(json_number_value(json_array_get(json_object_get(irr, poly.names[k]), (size_t)c)),
                        poly.values[k][c], 1e-8 * (1 + fabs(poly.values[k][c]))); /* JSON's digits */
    json_decref(root);
    free(file);
    /* the chain's mapping with the scale: alpha = 2^(l / 0.8) / 32 */
    for (int l = 1; l < 6; l++) {
        double alpha = pow(2.0, l / 0.8) / 32.0;
        assert_near(b.specular_info.roughness[l], fmin(1.0, sqrt(alpha)), 1e-6);
    }
    ibl_bake_free(ctx, &b);
    ibl_context_destroy(ctx);
}

static void babylon_lod_scale_parameter(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_specular_desc d = {.mapping = IBL_MAPPING_BABYLON, .size = 256, .babylon_lod_scale = 0.5f};
    ibl_specular_info info;
    assert_int_equal(ibl_specular_levels(ctx, &d, 256, &info), IBL_OK);
    assert_near(info.babylon_lod_scale, 0.5, 0);
    for (int l = 1; l < info.levels; l++)
        assert_near(info.roughness[l], fmin(1.0, sqrt(pow(2.0, l / 0.5) / 256.0)), 1e-6);
    d.babylon_lod_scale = 0;
    assert_int_equal(ibl_specular_levels(ctx, &d, 256, &info), IBL_OK);
    assert_near(info.roughness[3], sqrt(pow(2.0, 3 / 0.8) / 256.0), 1e-6);
    d.babylon_lod_scale = -1;
    assert_int_equal(ibl_specular_levels(ctx, &d, 256, &info), IBL_ERR_INVALID_ARGUMENT);
    ibl_context_destroy(ctx);
}

/* ---- glTF ------------------------------------------------------------------------------------ */

static void gltf_lights(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2);
    const char *dir = test_path("gltf");
    ibl_bake_data b;
    bake_target(ctx, IBL_TARGET_GLTF, dir, &b);
    assert_int_equal(b.specular.levels, 2); /* 32, 16: the last mip 16x16 */
    char path[1024];
    snprintf(path, sizeof path, "%s/engine_gltf.gltf", dir);
    json_error_t err;
    json_t *root = json_load_file(path, 0, &err);
    assert_non_null(root);
    assert_string_equal(json_string_value(json_object_get(json_object_get(root, "asset"), "version")), "2.0");
    assert_string_equal(json_string_value(json_array_get(json_object_get(root, "extensionsUsed"), 0)),
                        "EXT_lights_image_based");
    json_t *lights = json_object_get(json_object_get(json_object_get(root, "extensions"),
                                                     "EXT_lights_image_based"), "lights");
    assert_int_equal(json_array_size(lights), 1);
    json_t *light = json_array_get(lights, 0);
    assert_int_equal(json_integer_value(json_object_get(light, "specularImageSize")), 32);
    assert_near(json_number_value(json_object_get(light, "intensity")), 1.0, 0);
    assert_int_equal(json_array_size(json_object_get(light, "rotation")), 4);
    json_t *coeffs = json_object_get(light, "irradianceCoefficients");
    assert_int_equal(json_array_size(coeffs), 9);
    ibl_target_sh g;
    assert_int_equal(ibl_target_sh_form_of(ctx, IBL_TARGET_SH_GLTF_IRRADIANCE, &b.sh, &g), IBL_OK);
    for (int k = 0; k < 9; k++) {
        assert_int_equal(json_array_size(json_array_get(coeffs, (size_t)k)), 3);
        for (int c = 0; c < 3; c++)
            assert_near(json_number_value(json_array_get(json_array_get(coeffs, (size_t)k), (size_t)c)),
                        g.values[k][c], 1e-8 * (1 + fabs(g.values[k][c]))); /* JSON's digits */
    }
    /* the scene references the light */
    json_t *scene = json_array_get(json_object_get(root, "scenes"), 0);
    assert_int_equal(json_integer_value(json_object_get(json_object_get(json_object_get(scene, "extensions"),
                                                                        "EXT_lights_image_based"), "light")), 0);
    json_t *images = json_object_get(root, "images");
    json_t *mips = json_object_get(light, "specularImages");
    assert_int_equal(json_array_size(mips), 2);
    double worst = 0;
    for (int l = 0; l < 2; l++) {
        json_t *faces = json_array_get(mips, (size_t)l);
        assert_int_equal(json_array_size(faces), 6);
        for (int f = 0; f < 6; f++) {
            json_t *img = json_array_get(images, (size_t)json_integer_value(json_array_get(faces, (size_t)f)));
            assert_string_equal(json_string_value(json_object_get(img, "mimeType")), "image/png");
            char file[1100];
            snprintf(file, sizeof file, "%s/%s", dir, json_string_value(json_object_get(img, "uri")));
            size_t size;
            char *bytes = slurp(file, &size);
            int w, h;
            uint8_t *px = decode_png(bytes, size, &w, &h);
            assert_int_equal(w, 32 >> l);
            double r = compare_rgbd_face(px, w, ibl_cubemap_face(&b.specular, l, f));
            if (r > worst) worst = r;
            free(px);
            free(bytes);
        }
    }
    assert_true(worst <= 1.0);
    json_decref(root);
    /* the KHR_lights_environment draft: the KTX2 cube and the same SH */
    snprintf(path, sizeof path, "%s/engine_khr_lights_environment.gltf", dir);
    root = json_load_file(path, 0, &err);
    assert_non_null(root);
    json_t *klight = json_array_get(json_object_get(json_object_get(json_object_get(root, "extensions"),
                                                                     "KHR_lights_environment"), "lights"), 0);
    assert_int_equal(json_array_size(json_object_get(klight, "irradianceCoefficients")), 9);
    json_t *img = json_array_get(json_object_get(root, "images"), 0);
    assert_string_equal(json_string_value(json_object_get(img, "mimeType")), "image/ktx2");
    snprintf(path, sizeof path, "%s/%s", dir, json_string_value(json_object_get(img, "uri")));
    assert_true(test_file_exists(path));
    json_decref(root);
    ibl_bake_free(ctx, &b);
    ibl_context_destroy(ctx);
}

/* ---- README, manifest, sh.json, the CLI ------------------------------------------------------ */

static void readme_manifest_and_sh_json(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2);
    const char *dir = test_path("three");
    ibl_bake_data b;
    bake_target(ctx, IBL_TARGET_THREE, dir, &b);
    char path[1024];
    snprintf(path, sizeof path, "%s/README.txt", dir);
    char *readme = slurp(path, NULL);
    assert_non_null(strstr(readme, "isPMREMTexture"));
    assert_non_null(strstr(readme, "ktx-parse"));
    free(readme);
    snprintf(path, sizeof path, "%s/manifest.json", dir);
    json_error_t err;
    json_t *m = json_load_file(path, 0, &err);
    assert_string_equal(json_string_value(json_object_get(json_object_get(m, "parameters"), "target")), "three");
    json_decref(m);
    snprintf(path, sizeof path, "%s/sh.json", dir);
    json_t *sh = json_load_file(path, 0, &err);
    json_t *engines = json_object_get(sh, "engines");
    const char *keys[3] = {"three", "babylon", "gltf"};
    for (int i = 0; i < 3; i++) {
        json_t *e = json_object_get(engines, keys[i]);
        assert_non_null(e);
        const char *labels[4] = {"basis", "normalisation", "signs", "frame"};
        for (int k = 0; k < 4; k++) assert_non_null(json_string_value(json_object_get(e, labels[k])));
        assert_int_equal(json_array_size(json_object_get(e, "values")), 9);
    }
    /* three's values: the radiance array with c3, c4, c7 negated */
    json_t *radiance = json_object_get(sh, "radiance"), *three = json_object_get(json_object_get(engines, "three"), "values");
    for (int k = 0; k < 9; k++) {
        double s = (k == 3 || k == 4 || k == 7) ? -1 : 1;
        assert_near(json_number_value(json_array_get(json_array_get(three, (size_t)k), 0)),
                    s * json_number_value(json_array_get(json_array_get(radiance, (size_t)k), 0)), 0);
    }
    json_decref(sh);
    /* the folder loads back, target and all */
    ibl_bake_data back;
    assert_int_equal(ibl_bake_load(ctx, dir, NULL, &back), IBL_OK);
    assert_int_equal(back.target, IBL_TARGET_THREE);
    ibl_bake_free(ctx, &back);
    ibl_bake_free(ctx, &b);
    ibl_context_destroy(ctx);
}

static int manifest_levels(const char *dir)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/manifest.json", dir);
    json_error_t err;
    json_t *m = json_load_file(path, 0, &err);
    assert_non_null(m);
    int n = (int)json_integer_value(json_object_get(json_object_get(m, "specular"), "level_count"));
    json_decref(m);
    return n;
}

static void cli_options_after_target_override(void **state)
{
    (void)state;
    const char *out;
    /* the row's 8x8 end follows a later --size; a later --levels wins */
    const char *a = test_path("cli_a"), *b = test_path("cli_b");
    assert_int_equal(test_run_cli(&out, "bake --target three --size 32 --lut-size 8 --preview-width 0 -o %s -q", a), 0);
    assert_int_equal(manifest_levels(a), 3);
    assert_int_equal(test_run_cli(&out, "bake --target three --size 32 --levels 5 --lut-size 8 --preview-width 0 -o %s -q", b), 0);
    assert_int_equal(manifest_levels(b), 5);
    char path[1024];
    snprintf(path, sizeof path, "%s/README.txt", b);
    assert_true(test_file_exists(path));
    snprintf(path, sizeof path, "%s/specular.dds", a);
    assert_false(test_file_exists(path)); /* three's row: KTX2 only */
    /* a Babylon bake whose chain cannot make a .env is refused whole, naming the file */
    const char *c = test_path("cli_c");
    assert_int_equal(test_run_cli(&out, "bake --target babylon --size 32 --levels 3 --lut-size 8 -o %s -q", c), 2);
    assert_non_null(strstr(out, "engine_babylon.env"));
    assert_null(strstr(out, "staging"));
    assert_false(test_file_exists(c));
}

/* ---- KHR_materials_sheen's albedo ----------------------------------------------------------- */

/* The extension's implementation notes, written again here in float64: Charlie D with
 * alphaG = sheenRoughness, the "Charlie" visibility with its fitted Lambda, F = 1. */
static double khr_l(double x, double a)
{
    double t = (1 - a) * (1 - a);
    double A = 21.5473 * (1 - t) + 25.3245 * t, B = 3.82987 * (1 - t) + 3.32435 * t;
    double C = 0.19823 * (1 - t) + 0.16801 * t, D = -1.97760 * (1 - t) - 1.27393 * t;
    double E = -4.32054 * (1 - t) - 4.85967 * t;
    return A / (1 + B * pow(x, C)) + D * x + E;
}

static double khr_lambda(double c, double a)
{
    return fabs(c) < 0.5 ? exp(khr_l(fabs(c), a)) : exp(2 * khr_l(0.5, a) - khr_l(1 - fabs(c), a));
}

/* E(nv) = integral of D V (n.l) dl over the hemisphere, midpoint rule in (cos theta_l, phi)
 * (uniform in solid angle), phi over [0, pi] by symmetry */
static double khr_sheen_brute(double nv, double alpha, int n)
{
    double sv = sqrt(1 - nv * nv), lv = khr_lambda(nv, alpha), sum = 0;
    for (int i = 0; i < n; i++) {
        double nl = (i + 0.5) / n, sl = sqrt(1 - nl * nl), ll = khr_lambda(nl, alpha);
        double vis = 1.0 / ((1 + lv + ll) * 4 * nv * nl);
        for (int j = 0; j < 2 * n; j++) {
            double ph = PI * (j + 0.5) / (2 * n);
            /* h = normalize(v + l) with v = (sv, 0, nv), l = (sl cos ph, sl sin ph, nl) */
            double hx = sv + sl * cos(ph), hy = sl * sin(ph), hz = nv + nl;
            double nh = hz / sqrt(hx * hx + hy * hy + hz * hz);
            double s2 = 1 - nh * nh;
            double d = (2 + 1 / alpha) * pow(s2 > 0 ? s2 : 0, 0.5 / alpha) / (2 * PI);
            sum += d * vis * nl * (1.0 / n) * (PI / (2 * n));
        }
    }
    return 2 * sum;
}

static void sheen_khr_vs_brute_force(void **state)
{
    (void)state;
    const double rough[3] = {0.3, 0.6, 1.0}, mus[3] = {0.2, 0.5, 0.9};
    for (int a = 0; a < 3; a++)
        for (int m = 0; m < 3; m++) {
            double table = ibl_brdf_sheen_khr_albedo(mus[m], rough[a], 0);
            double brute = khr_sheen_brute(mus[m], rough[a], 600);
            /* the midpoint rule converges as h^2 here (n.v 0.2, r 0.3: 0.441309 at 200 x 400,
             * 0.441305 at 400 x 800), so at 600 x 1200 it is within ~3e-6 of its limit; the
             * table's quadrature is accurate to 1e-4 (brdf.h) */
            assert_near(table, brute, 2e-4);
        }
    /* it is not the table's other sheen (alpha = r^2, Neubelt-Pettineo visibility) */
    assert_true(fabs(ibl_brdf_sheen_khr_albedo(0.5, 0.6, 0) - ibl_brdf_sheen_albedo(0.5, 0.6, 0)) > 0.01);
}

/* ---- the Charlie chain --------------------------------------------------------------------- */

static void smooth_field(const double *d, float *rgb)
{
    rgb[0] = (float)(1.0 + 0.6 * d[0] + 0.3 * d[1] * d[2]);
    rgb[1] = (float)(0.8 + 0.5 * d[1] * d[1]);
    rgb[2] = (float)(0.5 + 0.4 * d[2] - 0.2 * d[0] * d[1]);
}

/* sum L D (n.w) / sum D (n.w) over a 300 x 600 (theta, phi) grid of the sphere in float64, with h
 * formed explicitly and the analytic field (not the cube) */
static void charlie_brute(const double n[3], double alpha, double out[3])
{
    const int NT = 300, NP = 600;
    double acc[3] = {0, 0, 0}, wsum = 0;
    for (int i = 0; i < NT; i++) {
        double th = PI * (i + 0.5) / NT, st = sin(th), ct = cos(th);
        for (int j = 0; j < NP; j++) {
            double ph = 2 * PI * (j + 0.5) / NP;
            double w[3] = {st * cos(ph), ct, st * sin(ph)};
            double c = n[0] * w[0] + n[1] * w[1] + n[2] * w[2];
            if (c <= 0) continue;
            double h[3] = {n[0] + w[0], n[1] + w[1], n[2] + w[2]};
            double hl = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
            double nh = (n[0] * h[0] + n[1] * h[1] + n[2] * h[2]) / hl;
            double s2 = 1 - nh * nh;
            double d = (2 + 1 / alpha) * pow(s2 > 0 ? s2 : 0, 0.5 / alpha) / (2 * PI);
            double wt = d * c * st;
            float l[3];
            smooth_field(w, l);
            for (int k = 0; k < 3; k++) acc[k] += wt * l[k];
            wsum += wt;
        }
    }
    for (int k = 0; k < 3; k++) out[k] = acc[k] / wsum;
}

static void charlie_chain_vs_brute_force(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2);
    ibl_cubemap env, chain;
    assert_int_equal(ibl_cubemap_alloc(ctx, 64, 1, &env), IBL_OK);
    test_fill_cube_fn(&env, smooth_field);
    assert_int_equal(ibl_charlie_prefilter(ctx, &env, 8, 3, &chain), IBL_OK);
    assert_near(ibl_charlie_level_roughness(0, 3), 1.0 / 64, 0);
    assert_near(ibl_charlie_level_roughness(1, 3), 0.5, 0);
    const int probes[4][4] = {{0, 0, 3, 2}, {1, 1, 1, 0}, {2, 2, 0, 1}, {0, 4, 5, 6}}; /* level face x y */
    for (int p = 0; p < 4; p++) {
        int level = probes[p][0], face = probes[p][1], s = 8 >> level;
        int x = probes[p][2] % s, y = probes[p][3] % s;
        double n[3], want[3];
        test_texel_dir(face, s, x, y, n);
        charlie_brute(n, ibl_charlie_level_roughness(level, 3), want);
        const float *got = ibl_cubemap_face(&chain, level, face) + ((size_t)y * (size_t)s + (size_t)x) * 4;
        /* the chain sums the cube at 32 texels (area means of a quadratic field: ~1e-4) with
         * a 2048-entry linear table of the weight, the reference an exact-h grid: 2e-3 of the
         * value covers both */
        for (int c = 0; c < 3; c++) assert_near(got[c], want[c], 2e-3 * fabs(want[c]));
    }
    /* a constant stays constant */
    test_fill_cube(&env, 0.7f, 0.7f, 0.7f);
    ibl_cubemap_free(ctx, &chain);
    assert_int_equal(ibl_charlie_prefilter(ctx, &env, 4, 2, &chain), IBL_OK);
    for (int l = 0; l < 2; l++) assert_near(ibl_cubemap_face(&chain, l, 3)[1], 0.7, 1e-5);
    ibl_cubemap_free(ctx, &chain);
    ibl_cubemap_free(ctx, &env);
    ibl_context_destroy(ctx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(table_rows),
        cmocka_unit_test(unknown_targets_refuse),
        cmocka_unit_test(sh_forms_against_brute_force),
        cmocka_unit_test(babylon_env_file),
        cmocka_unit_test(babylon_lod_scale_parameter),
        cmocka_unit_test(gltf_lights),
        cmocka_unit_test(readme_manifest_and_sh_json),
        cmocka_unit_test(cli_options_after_target_override),
        cmocka_unit_test(sheen_khr_vs_brute_force),
        cmocka_unit_test(charlie_chain_vs_brute_force),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
