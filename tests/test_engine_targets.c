/* The native-engine targets (filament, unity, unreal, godot) and the CLI pieces that came
 * with them: the SH each engine takes against float64 brute-force projections written here
 * from the engines' own definitions, the Filament files (sh.txt, the KTX1 "sh" key, cmgen's
 * glType), the equirect EXR and --units, -jN, the upsampling warning. */
#include "test_support.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PI 3.14159265358979323846
/* small tables: the bakes here are about their environments, not the BRDF tables */
#define FAST "--lut-size 8 --irradiance-size 4 --preview-width 0 --working-size 32"


/* ---- an independent cube walk: the face table of docs/CONVENTIONS.md and the exact texel
 * solid angle (the area of a face rectangle seen from the centre) ---------------------------- */

static void face_direction(int face, double sc, double tc, double d[3])
{
    switch (face) {
    case 0: d[0] = 1, d[1] = -tc, d[2] = -sc; break;
    case 1: d[0] = -1, d[1] = -tc, d[2] = sc; break;
    case 2: d[0] = sc, d[1] = 1, d[2] = tc; break;
    case 3: d[0] = sc, d[1] = -1, d[2] = -tc; break;
    case 4: d[0] = sc, d[1] = -tc, d[2] = 1; break;
    default: d[0] = -sc, d[1] = -tc, d[2] = -1; break;
    }
    double l = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (int i = 0; i < 3; i++) d[i] /= l;
}

static double area(double x, double y) { return atan2(x * y, sqrt(x * x + y * y + 1.0)); }

static double texel_solid_angle(int n, int x, int y)
{
    double x0 = 2.0 * x / n - 1, x1 = 2.0 * (x + 1) / n - 1, y0 = 2.0 * y / n - 1, y1 = 2.0 * (y + 1) / n - 1;
    return area(x0, y0) - area(x0, y1) - area(x1, y0) + area(x1, y1);
}

/* A smooth environment with every band present (not band-limited) and different channels. */
static void radiance(const double d[3], double rgb[3])
{
    rgb[0] = 0.5 + exp(2.0 * d[0]);
    rgb[1] = 1.0 + d[1] * d[2] + 0.5 * d[0] * d[1];
    rgb[2] = exp(1.5 * d[2] - 0.5 * d[1]);
}

static void make_environment(ibl_context *ctx, int n, ibl_cubemap *env)
{
    assert_int_equal(ibl_cubemap_alloc(ctx, n, 1, env), IBL_OK);
    for (int f = 0; f < 6; f++) {
        float *p = ibl_cubemap_face(env, 0, f);
        for (int y = 0; y < n; y++)
            for (int x = 0; x < n; x++, p += 4) {
                double d[3], c[3];
                face_direction(f, 2.0 * (x + 0.5) / n - 1, 2.0 * (y + 0.5) / n - 1, d);
                radiance(d, c);
                for (int k = 0; k < 3; k++) p[k] = (float)c[k];
                p[3] = 1.0f;
            }
    }
}

/* Filament's SH basis (tools/cmgen CubemapSH::TSH and preprocessSHForShader's A[]): the
 * polynomial P_i and its signed constant c_i, Y_i = c_i P_i, index l(l+1)+m. */
static void filament_basis(const double d[3], double y[9], double c[9])
{
    double x = d[0], yy = d[1], z = d[2], sp = sqrt(PI);
    const double k[9] = {1 / (2 * sp), -sqrt(3.0) / (2 * sp), sqrt(3.0) / (2 * sp), -sqrt(3.0) / (2 * sp),
                         sqrt(15.0) / (2 * sp), -sqrt(15.0) / (2 * sp), sqrt(5.0) / (4 * sp),
                         -sqrt(15.0) / (2 * sp), sqrt(15.0) / (4 * sp)};
    const double p[9] = {1, yy, z, x, yy * x, yy * z, 3 * z * z - 1, z * x, x * x - yy * yy};
    for (int i = 0; i < 9; i++) c[i] = k[i], y[i] = k[i] * p[i];
}

static double band_lobe(int i) { return i == 0 ? PI : i < 4 ? 2.0 * PI / 3.0 : PI / 4.0; }

/* Float64 sums over the texels of env: Filament's sh[i] = c_i E_i / pi (E in its basis, the
 * cube's frame) and Unity's u_i = E_i / pi in the Condon-Shortley basis taken in Unity's
 * frame, where the cube's direction (x, y, z) is (-z, y, -x). */
static void brute_force(const ibl_cubemap *env, double filament[9][3], double unity[9][3])
{
    memset(filament, 0, 9 * 3 * sizeof(double));
    memset(unity, 0, 9 * 3 * sizeof(double));
    int n = env->size;
    for (int f = 0; f < 6; f++) {
        const float *p = ibl_cubemap_face(env, 0, f);
        for (int y = 0; y < n; y++)
            for (int x = 0; x < n; x++, p += 4) {
                double d[3], w = texel_solid_angle(n, x, y), yf[9], cf[9], yu[9], cu[9];
                face_direction(f, 2.0 * (x + 0.5) / n - 1, 2.0 * (y + 0.5) / n - 1, d);
                filament_basis(d, yf, cf);
                double du[3] = {-d[2], d[1], -d[0]};
                filament_basis(du, yu, cu); /* Filament's basis IS the Condon-Shortley one */
                for (int i = 0; i < 9; i++)
                    for (int k = 0; k < 3; k++) {
                        filament[i][k] += cf[i] * band_lobe(i) / PI * p[k] * yf[i] * w;
                        unity[i][k] += band_lobe(i) / PI * p[k] * yu[i] * w;
                    }
            }
    }
}

static double largest(double v[9][3])
{
    double m = 0;
    for (int i = 0; i < 9; i++)
        for (int k = 0; k < 3; k++) m = fmax(m, fabs(v[i][k]));
    return m;
}

static void bake_target(ibl_context *ctx, const ibl_cubemap *env, ibl_target target, const char *dir)
{
    ibl_bake_desc d;
    ibl_bake_desc_for_target(ibl_target_profile_of(target), &d);
    d.specular.size = 16;
    d.specular.levels = 0;
    d.lut_size = 8;
    d.irradiance_size = 4;
    d.preview_width = -1;
    d.ambient_brdf = -1;
    assert_int_equal(ibl_bake(ctx, env, &d, dir, NULL), IBL_OK);
}

static char *read_text(const char *path)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    char *s = calloc(1, 1 << 20);
    assert_non_null(s);
    size_t n = fread(s, 1, (1 << 20) - 1, f);
    fclose(f);
    s[n] = 0;
    return s;
}

/* sh.txt and the KTX1 "sh" key against the brute force. Bounds: the library and the brute
 * force both sum the same float texels in double with exact solid angles, in different orders
 * and with independently written geometry: they agree to ~1e-13 relative; sh.txt prints 15
 * decimals (5e-16 absolute), the key 9 significant digits (5e-9 relative). Bounds 1e-10 and
 * 1e-8 of the largest value. */
static void filament_files_against_float64(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2);
    ibl_cubemap env;
    make_environment(ctx, 24, &env);
    double want[9][3], unity[9][3];
    brute_force(&env, want, unity);
    double scale = largest(want);
    const char *dir = test_path("filament");
    bake_target(ctx, &env, IBL_TARGET_FILAMENT, dir);

    char path[600];
    snprintf(path, sizeof path, "%s/sh.txt", dir);
    char *text = read_text(path), *at = text;
    for (int i = 0; i < 9; i++) {
        double v[3];
        assert_int_equal(sscanf(at, " (%lf, %lf, %lf);", &v[0], &v[1], &v[2]), 3);
        for (int k = 0; k < 3; k++) assert_near(v[k], want[i][k], 1e-10 * scale);
        at = strchr(at, '\n');
        assert_non_null(at);
        at++;
    }
    assert_non_null(strstr(text, "// L2-2, irradiance, pre-scaled base"));
    free(text);

    ibl_texture t;
    snprintf(path, sizeof path, "%s/engine_filament_ibl.ktx", dir);
    assert_int_equal(ibl_read_texture(ctx, path, NULL, &t, NULL), IBL_OK);
    assert_int_equal(t.kind, IBL_TEXTURE_CUBE);
    assert_int_equal(t.format, IBL_FORMAT_RG11B10F);
    /* cmgen ends its chain at 16 texels unless the cube is no larger (then: down to 1x1) */
    assert_int_equal(t.levels, 5);
    const char *key = ibl_texture_get_metadata(&t, "sh");
    assert_non_null(key);
    at = (char *)key;
    for (int i = 0; i < 9; i++)
        for (int k = 0; k < 3; k++) {
            char *end;
            double v = strtod(at, &end);
            assert_true(end != at);
            assert_near(v, want[i][k], 1e-8 * scale);
            at = end;
        }
    ibl_texture_free(ctx, &t);
    /* cmgen's glType, which Filament's reader needs (the spec's 0x8C3B aborts it) */
    FILE *f = fopen(path, "rb");
    unsigned char head[32];
    assert_int_equal(fread(head, 1, 32, f), 32);
    fclose(f);
    assert_int_equal(head[16] | head[17] << 8 | head[18] << 16 | head[19] << 24, 0x8C3A);
    snprintf(path, sizeof path, "%s/engine_filament_skybox.ktx", dir);
    assert_true(test_file_exists(path));
    ibl_cubemap_free(ctx, &env);
    ibl_context_destroy(ctx);
}

/* Unity's SphericalHarmonicsL2 in sh.json against the brute force in Unity's frame (the
 * library gets there by substituting the basis polynomials, the brute force by projecting
 * in the turned frame directly). Bound 1e-9 of the largest value: double sums of the same
 * texels in different orders, and the 9 significant digits jansson keeps are more. */
static void unity_sh_against_float64(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2);
    ibl_cubemap env;
    make_environment(ctx, 24, &env);
    double filament[9][3], want[9][3];
    brute_force(&env, filament, want);
    double scale = largest(want);
    const char *dir = test_path("unity");
    bake_target(ctx, &env, IBL_TARGET_UNITY, dir);
    char path[600];
    snprintf(path, sizeof path, "%s/sh.json", dir);
    char *text = read_text(path);
    char *u = strstr(text, "\"unity\"");
    assert_non_null(u);
    u = strstr(u, "\"values\"");
    assert_non_null(u);
    for (int i = 0; i < 9; i++)
        for (int k = 0; k < 3; k++) {
            u += strcspn(u, "-0123456789");
            char *end;
            double v = strtod(u, &end);
            assert_near(v, want[i][k], 1e-9 * scale);
            u = end;
        }
    free(text);
    /* and the equirect EXR for the engine to filter: 4 x 2 pixels per working texel */
    ibl_image img;
    snprintf(path, sizeof path, "%s/engine_environment.exr", dir);
    assert_int_equal(ibl_read_image(ctx, path, NULL, &img, NULL), IBL_OK);
    assert_int_equal(img.width, 4 * 24);
    assert_int_equal(img.height, 2 * 24);
    ibl_image_free(ctx, &img);
    ibl_cubemap_free(ctx, &env);
    ibl_context_destroy(ctx);
}

/* The first radiance coefficient in a bake's sh.json. */
static double sh_l00(const char *dir)
{
    char path[600];
    snprintf(path, sizeof path, "%s/sh.json", dir);
    char *text = read_text(path);
    char *r = strstr(text, "\"radiance\"");
    assert_non_null(r);
    r += strcspn(r, "-0123456789");
    double v = strtod(r, NULL);
    free(text);
    return v;
}

/* --units: the built-in sky is made in kcd/m^2; nits scales every output by exactly 1000
 * (each texel is multiplied once, in float: the ratio of any linear output is 1000 to float
 * rounding, 1e-6 relative); a file is stated, not scaled; the manifest records the units. */
static void units_scale_exactly(void **state)
{
    (void)state;
    const char *out;
    const char *kcd = test_path("sky_kcd"), *nits = test_path("sky_nits");
    assert_int_equal(test_run_cli(&out, "bake -q -o '%s' --target godot --size 16 --units kcd %s", kcd, FAST), 0);
    assert_int_equal(test_run_cli(&out, "bake -q -o '%s' --target godot --size 16 --units nits %s", nits, FAST), 0);
    assert_near(sh_l00(nits) / sh_l00(kcd), 1000.0, 1000.0 * 1e-6);
    char a[600], b[600];
    snprintf(a, sizeof a, "%s/engine_environment.exr", kcd);
    snprintf(b, sizeof b, "%s/engine_environment.exr", nits);
    ibl_context *ctx = test_context(1);
    ibl_image x, y;
    assert_int_equal(ibl_read_image(ctx, a, NULL, &x, NULL), IBL_OK);
    assert_int_equal(ibl_read_image(ctx, b, NULL, &y, NULL), IBL_OK);
    assert_int_equal(x.width, y.width);
    double worst = 0;
    for (size_t i = 0; i < (size_t)x.width * x.height * 4; i++)
        if (i % 4 != 3 && x.pixels[i] > 0) worst = fmax(worst, fabs(y.pixels[i] / x.pixels[i] / 1000.0 - 1.0));
    assert_true(worst < 1e-6);
    ibl_image_free(ctx, &x);
    ibl_image_free(ctx, &y);
    snprintf(a, sizeof a, "%s/manifest.json", nits);
    char *m = read_text(a);
    assert_non_null(strstr(m, "\"units\": \"cd/m^2\""));
    free(m);
    /* a file is taken to be in the stated units: no scaling, the units recorded */
    const char *file = test_path("env.exr"), *stated = test_path("stated");
    assert_int_equal(test_run_cli(&out, "sky -q -o '%s' --size 64", file), 0);
    assert_int_equal(test_run_cli(&out, "bake -q '%s' -o '%s' --size 16 --units nits %s", file, stated, FAST), 0);
    const char *plain = test_path("plain");
    assert_int_equal(test_run_cli(&out, "bake -q '%s' -o '%s' --size 16 %s", file, plain, FAST), 0);
    assert_true(sh_l00(stated) == sh_l00(plain));
    snprintf(a, sizeof a, "%s/manifest.json", stated);
    m = read_text(a);
    assert_non_null(strstr(m, "\"units\": \"cd/m^2\""));
    free(m);
    assert_int_equal(test_run_cli(&out, "bake -q -o '%s' --units lumens", test_path("bad")), 2);
    ibl_context_destroy(ctx);
}

/* -j2 is -j 2 (same bits), and an output cube larger than the input's detail warns on stderr
 * (from the CLI), but not within the detail and not with -q. */
static void cli_threads_and_upsampling(void **state)
{
    (void)state;
    const char *out;
    const char *in = test_path("small.exr"); /* 128x64: 32 texels of detail per face */
    assert_int_equal(test_run_cli(&out, "sky -q -o '%s' --size 128", in), 0);
    const char *a = test_path("j2.ktx2"), *b = test_path("j_2.ktx2");
    assert_int_equal(test_run_cli(&out, "prefilter '%s' -o '%s' --size 32 -j2", in, a), 0);
    assert_null(strstr(out, "warning"));
    assert_int_equal(test_run_cli(&out, "prefilter -q '%s' -o '%s' --size 32 -j 2", in, b), 0);
    ibl_context *ctx = test_context(1);
    void *x, *y;
    size_t nx, ny;
    assert_int_equal(ibl_read_file(ctx, a, &x, &nx), IBL_OK);
    assert_int_equal(ibl_read_file(ctx, b, &y, &ny), IBL_OK);
    assert_int_equal(nx, ny);
    assert_memory_equal(x, y, nx);
    ibl_free(ctx, x);
    ibl_free(ctx, y);
    assert_int_equal(test_run_cli(&out, "prefilter '%s' -o '%s' --size 64", in, test_path("up.ktx2")), 0);
    assert_non_null(strstr(out, "warning"));
    assert_non_null(strstr(out, "64-texel cube"));
    assert_non_null(strstr(out, "about 32 texels"));
    assert_int_equal(test_run_cli(&out, "prefilter -q '%s' -o '%s' --size 64", in, test_path("up2.ktx2")), 0);
    assert_null(strstr(out, "warning"));
    assert_int_equal(test_run_cli(&out, "bake '%s' -o '%s' --size 64 %s", in, test_path("upbake"), FAST), 0);
    assert_non_null(strstr(out, "warning"));
    /* a Filament chain from prefilter gets cmgen's glType too; a plain KTX1 keeps the spec's */
    for (int filament = 0; filament < 2; filament++) {
        const char *k = test_path(filament ? "f.ktx" : "plain.ktx");
        assert_int_equal(test_run_cli(&out, "prefilter -q '%s' -o '%s' --size 16 --format rg11b10f %s", in,
                                      k, filament ? "--target filament" : ""), 0);
        void *bytes;
        size_t n;
        assert_int_equal(ibl_read_file(ctx, k, &bytes, &n), IBL_OK);
        const unsigned char *h = bytes;
        assert_int_equal(h[16] | h[17] << 8 | h[18] << 16 | h[19] << 24, filament ? 0x8C3A : 0x8C3B);
        ibl_free(ctx, bytes);
    }
    ibl_context_destroy(ctx);
}

/* ---- the equirect EXR in each engine's frame ------------------------------------------------ */

static void picture_colour(const double d[3], double c[3])
{
    for (int k = 0; k < 3; k++) c[k] = 0.6 + 0.5 * d[k];
}

/* The colour engine_environment.exr shows at picture coordinates (u, v), v = 0 at the top. */
static void exr_at(const ibl_image *img, double u, double v, double c[3])
{
    int x = (int)floor(u * img->width), y = (int)floor(v * img->height);
    x = ((x % img->width) + img->width) % img->width;
    y = y < 0 ? 0 : y >= img->height ? img->height - 1 : y;
    for (int k = 0; k < 3; k++) c[k] = img->pixels[((size_t)y * img->width + x) * 4 + k];
}

/* Unreal's frame, worked out by hand (Unreal cannot run here).
 * * long-lat import, worked out by hand (Unreal cannot run here).
 *
 * Unreal turns a 2:1 panorama into a TextureCube in its texture compressor
 * (TextureCompressorModule, GenerateBaseCubeMipFromLongitudeLatitude2D in Epic's API
 * reference). Each texel of the cube, at the Direct3D cube direction c of its face and
 * position, is filled from the panorama through the swizzle (c.x, c.z, c.y) ("the Unreal way,
 * z and y flipped") and the lookup u = (1 + atan2(q.x, -q.z) / pi) / 2, v = acos(q.y) / pi of
 * the usual latitude-longitude map (v = 0 at the top row). Unreal samples the cube with the
 * world direction w itself (its reflection shaders' GetCubemapVector is the Direct3D face
 * convention), so in Unreal's world (left-handed, +X forward, +Y right, +Z up) a panorama pixel
 * shows at
 *     u = 1/2 + atan2(w.x, -w.y) / 2pi,  v = acos(w.z) / pi:
 * the picture's centre on -Y, its right quarter on +X, its top on +Z.
 * ibl's panorama puts its centre on -Z, its right quarter on +X and its top on +Y
 * (docs/CONVENTIONS.md), so without a turn ibl's (x, y, z) would show at Unreal's (x, z, y):
 * ibl's front (-Z) on Unreal's left. The unreal row turns the environment by -90 degrees about
 * +Y first, so that a direction (x, y, z) of the input shows at Unreal's (-z, x, y): ibl's
 * front on Unreal's forward (+X), its right (+X) on Unreal's right (+Y), up on up, the
 * right- to left-handed change of the Unity row with Unreal's axis names. */

enum { ENGINE_UNITY, ENGINE_GODOT, ENGINE_UNREAL, ENGINE_COUNT };
static const char *const engine_names[ENGINE_COUNT] = {"unity", "godot", "unreal"};

/* The largest channel error, over a few directions, between what the engine shows and the
 * picture (see equirect_in_engine_frames). */
static double engine_frame_error(ibl_context *ctx, const char *file, int engine, const char *extra)
{
    static const double samples[][3] = {{0.8, 0.3, -0.5}, {-0.6, -0.2, 0.7}, {0.1, 0.5, 0.85},
                                        {-0.9, 0.1, -0.4}, {0.5, -0.7, 0.5}, {-0.3, 0.2, -0.93},
                                        {0.0, 0.0, -1.0}, {1.0, 0.0, 0.0}};
    char name[32];
    snprintf(name, sizeof name, "%s_dirs", engine_names[engine]);
    const char *dir = test_path(name), *out;
    assert_int_equal(test_run_cli(&out, "bake -q '%s' -o '%s' --target %s %s --size 32 %s", file, dir,
                                  engine_names[engine], extra, FAST), 0);
    char path[600];
    snprintf(path, sizeof path, "%s/engine_environment.exr", dir);
    ibl_image img;
    assert_int_equal(ibl_read_image(ctx, path, NULL, &img, NULL), IBL_OK);
    double worst = 0;
    for (size_t s = 0; s < sizeof samples / sizeof samples[0]; s++) {
        double d[3] = {samples[s][0], samples[s][1], samples[s][2]};
        double l = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        for (int k = 0; k < 3; k++) d[k] /= l;
        double u, v;
        if (engine == ENGINE_UNREAL) { /* Unreal: w = (-z, x, y), u = 1/2 + atan2(w.x, -w.y) / 2pi */
            double w[3] = {-d[2], d[0], d[1]};
            u = 0.5 + atan2(w[0], -w[1]) / (2 * PI);
            v = acos(w[2]) / PI;
        } else if (engine == ENGINE_UNITY) { /* Unity: w = (x, y, -z); u = 0.5 - atan2(w.z, w.x) / 2pi, v from the top */
            double w[3] = {d[0], d[1], -d[2]};
            u = 0.5 - atan2(w[2], w[0]) / (2 * PI);
            v = acos(w[1]) / PI;
        } else { /* Godot: w = d; u = atan(w.x, -w.z) / 2pi wrapped to [0, 1) */
            u = atan2(d[0], -d[2]) / (2 * PI);
            if (u < 0) u += 1;
            v = acos(d[1]) / PI;
        }
        double got[3], want[3];
        exr_at(&img, u, v, got);
        picture_colour(d, want);
        for (int k = 0; k < 3; k++) worst = fmax(worst, fabs(got[k] - want[k]));
    }
    ibl_image_free(ctx, &img);
    return worst;
}

/* Bakes a picture whose colour is its direction with --target T and checks, through the
 * engine's own panorama mapping (Unity: Skybox/Panoramic ToRadialCoords; Godot: the sky
 * shader), that the engine shows the picture's direction d at the world direction the docs
 * state: Unity (x, y, -z), Godot (x, y, z). Bound 0.05: the colour changes by at most 0.5 per
 * radian, a pixel is 0.049 rad wide and the working cube's texels 0.05 rad: nearest-pixel
 * and resampling errors stay under 0.04; a turn of 90 degrees the wrong way, or a mirror,
 * moves a colour by up to 1. */
static void equirect_in_engine_frames(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_image pic;
    assert_int_equal(ibl_image_alloc(ctx, 128, 64, &pic), IBL_OK);
    for (int j = 0; j < 64; j++)
        for (int i = 0; i < 128; i++) {
            double phi = 2 * PI * ((i + 0.5) / 128 - 0.5), theta = PI * (j + 0.5) / 64, c[3];
            double d[3] = {sin(theta) * sin(phi), cos(theta), -sin(theta) * cos(phi)};
            picture_colour(d, c);
            float *p = pic.pixels + ((size_t)j * 128 + i) * 4;
            for (int k = 0; k < 3; k++) p[k] = (float)c[k];
            p[3] = 1.0f;
        }
    const char *file = test_path("directions.exr");
    assert_int_equal(ibl_write_image(ctx, file, &pic, NULL), IBL_OK);
    ibl_image_free(ctx, &pic);
    for (int engine = 0; engine < ENGINE_COUNT; engine++) {
        double err = engine_frame_error(ctx, file, engine, "");
        printf("%s row: largest channel error %.4f\n", engine_names[engine], err);
        assert_true(err <= 0.05);
        /* control: without the row's turn the same check fails by far */
        assert_true(engine_frame_error(ctx, file, engine, "--yaw 0") > 0.3);
    }
    /* and Unreal turned the other way */
    assert_true(engine_frame_error(ctx, file, ENGINE_UNREAL, "--yaw 90") > 0.3);
    ibl_context_destroy(ctx);
}

/* engine_environment.hdr (the file Unreal's importer makes a TextureCube of) is the EXR's picture
 * in Radiance RGBE: same size, every channel within RGBE's quantisation of it. RGBE keeps 8
 * bits of mantissa under the pixel's largest channel m, so a channel is off by at most
 * m / 256 (truncation) plus the float rounding of the decode: bound m / 200. */
static void unreal_hdr_is_the_exr_in_rgbe(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    const char *picture = test_path("directions.exr"); /* written by equirect_in_engine_frames */
    const char *dir = test_path("unreal_hdr"), *out;
    assert_int_equal(test_run_cli(&out, "bake -q '%s' -o '%s' --target unreal --size 32 %s", picture, dir, FAST), 0);
    char path[600];
    ibl_image exr, hdr;
    snprintf(path, sizeof path, "%s/engine_environment.exr", dir);
    assert_int_equal(ibl_read_image(ctx, path, NULL, &exr, NULL), IBL_OK);
    snprintf(path, sizeof path, "%s/engine_environment.hdr", dir);
    assert_int_equal(ibl_file_type_from_path(path), IBL_FILE_HDR);
    assert_int_equal(ibl_read_image(ctx, path, NULL, &hdr, NULL), IBL_OK);
    assert_int_equal(hdr.width, exr.width);
    assert_int_equal(hdr.height, exr.height);
    double worst = 0, sum = 0;
    for (size_t i = 0; i < (size_t)exr.width * exr.height; i++) {
        const float *e = exr.pixels + i * 4, *h = hdr.pixels + i * 4;
        double m = fmax(e[0], fmax(e[1], e[2]));
        for (int k = 0; k < 3; k++) {
            worst = fmax(worst, fabs(h[k] - e[k]) / m);
            sum += e[k];
        }
    }
    printf("unreal .hdr against .exr: largest error %.5f of the pixel's largest channel\n", worst);
    assert_true(sum > 0);
    assert_true(worst <= 1.0 / 200);
    ibl_image_free(ctx, &exr);
    ibl_image_free(ctx, &hdr);
    ibl_context_destroy(ctx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(filament_files_against_float64),
        cmocka_unit_test(unity_sh_against_float64),
        cmocka_unit_test(units_scale_exactly),
        cmocka_unit_test(cli_threads_and_upsampling),
        cmocka_unit_test(equirect_in_engine_frames),
        cmocka_unit_test(unreal_hdr_is_the_exr_in_rgbe),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
