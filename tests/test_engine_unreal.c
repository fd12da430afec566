/* `ibl bake --target unreal`: the frame of engine_environment.exr (and its .hdr twin) through Unreal's own
 * long-lat import, worked out by hand (Unreal cannot run here).
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
#include "test_support.h"

#include <math.h>
#include <stdio.h>

#define PI 3.14159265358979323846
#define FAST "--lut-size 8 --irradiance-size 4 --preview-width 0 --working-size 32"

/* The picture's colour for its direction d (ibl's frame): each axis its own channel ramp. */
static void picture_colour(const double d[3], double c[3])
{
    for (int k = 0; k < 3; k++) c[k] = 0.6 + 0.5 * d[k];
}

/* The colour of img at picture coordinates (u, v), v = 0 at the top, nearest pixel. */
static void exr_at(const ibl_image *img, double u, double v, double c[3])
{
    int x = (int)floor(u * img->width), y = (int)floor(v * img->height);
    x = ((x % img->width) + img->width) % img->width;
    y = y < 0 ? 0 : y >= img->height ? img->height - 1 : y;
    for (int k = 0; k < 3; k++) c[k] = img->pixels[((size_t)y * img->width + x) * 4 + k];
}

static const char *write_direction_picture(ibl_context *ctx)
{
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
    const char *file = test_path("unreal_directions.exr");
    assert_int_equal(ibl_write_image(ctx, file, &pic, NULL), IBL_OK);
    ibl_image_free(ctx, &pic);
    return file;
}

/* The largest channel error, over directions spread around the sphere, between what Unreal
 * shows at world direction (-z, x, y) and the picture's colour of (x, y, z). */
static double unreal_frame_error(ibl_context *ctx, const char *picture, const char *extra)
{
    static const double samples[][3] = {{0.8, 0.3, -0.5}, {-0.6, -0.2, 0.7}, {0.1, 0.5, 0.85},
                                        {-0.9, 0.1, -0.4}, {0.5, -0.7, 0.5}, {-0.3, 0.2, -0.93},
                                        {0.0, 0.0, -1.0}, {1.0, 0.0, 0.0}};
    const char *dir = test_path("unreal_frame"), *out;
    assert_int_equal(test_run_cli(&out, "bake -q '%s' -o '%s' --target unreal %s --size 32 %s", picture, dir,
                                  extra, FAST), 0);
    char path[600];
    snprintf(path, sizeof path, "%s/engine_environment.exr", dir);
    ibl_image img;
    assert_int_equal(ibl_read_image(ctx, path, NULL, &img, NULL), IBL_OK);
    double worst = 0;
    for (size_t s = 0; s < sizeof samples / sizeof samples[0]; s++) {
        double d[3] = {samples[s][0], samples[s][1], samples[s][2]};
        double l = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        for (int k = 0; k < 3; k++) d[k] /= l;
        const double w[3] = {-d[2], d[0], d[1]}; /* Unreal's world */
        double got[3], want[3];
        exr_at(&img, 0.5 + atan2(w[0], -w[1]) / (2 * PI), acos(w[2]) / PI, got);
        picture_colour(d, want);
        for (int k = 0; k < 3; k++) worst = fmax(worst, fabs(got[k] - want[k]));
    }
    ibl_image_free(ctx, &img);
    return worst;
}

/* engine_environment.hdr (the file Unreal's importer makes a TextureCube of) is the EXR's picture
 * in Radiance RGBE: same size, every channel within RGBE's quantisation of it. RGBE keeps 8
 * bits of mantissa under the pixel's largest channel m, so a channel is off by at most
 * m / 256 (truncation) plus the float rounding of the decode: bound m / 200. */
static void unreal_hdr_is_the_exr_in_rgbe(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    const char *picture = write_direction_picture(ctx);
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

/* Bound 0.05, as for Unity and Godot in test_engine_targets.c: the colour changes by at most 0.5
 * per radian, a pixel of the 128-wide EXR is 0.049 rad and the 32-texel working cube's texels
 * 0.05 rad, so nearest-pixel and resampling errors stay under 0.04; the row without its turn,
 * or turned the other way, moves a colour by up to 1. */
static void unreal_import_shows_the_stated_frame(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    const char *picture = write_direction_picture(ctx);
    double row = unreal_frame_error(ctx, picture, "");
    printf("unreal row: largest channel error %.4f\n", row);
    assert_true(row <= 0.05);
    /* controls: the same check fails without the turn and with the opposite turn */
    assert_true(unreal_frame_error(ctx, picture, "--yaw 0") > 0.3);
    assert_true(unreal_frame_error(ctx, picture, "--yaw 90") > 0.3);
    ibl_context_destroy(ctx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(unreal_import_shows_the_stated_frame),
        cmocka_unit_test(unreal_hdr_is_the_exr_in_rgbe),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
