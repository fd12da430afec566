/* Pinned output bits of the equirect <-> cube conversions.
 *
 * Why: the equirect conversion is a large, carefully ordered float computation (windows, polar
 * integration, float lanes four and eight wide that must agree bit for bit). Restructuring it
 * (as when src/layout/equirect.c was split into src/layout/equirect/) must not change a single
 * output bit, and the accuracy tests of tests/test_layout.c would let small changes through.
 * These FNV-1a hashes over the output floats were recorded before that split, with the build
 * of that commit (GCC 12, glibc, x86-64), and the split reproduced all of them (and 3,359
 * more cases, listed in its commit message). A deliberate change of the algorithm changes them:
 * then record the new values here, and say why in the commit.
 *
 * The cases reach every mechanism: one to several samples per texel axis, windows narrower
 * than 1/16 pixel (a cube finer than the picture), the directly integrated polar texels, the
 * per-column windows of the polar faces (a picture much finer than the cube), a sun at the pole
 * and on the seam, fixed samples per axis, turned frames (yaw, mirror, z-up), both kernel
 * paths (a default context and IBL_KERNELS_PORTABLE) and one and two threads; then the way
 * back to an equirect, and the SH projection of an equirect (its row solid angles are the
 * conversion's). Libm's sin, cos and atan2 enter the results, so the values are only compared
 * on glibc x86-64; elsewhere they are printed. */
#include "test_support.h"

#include <inttypes.h>
#include <stdio.h>
#include <string.h>

#if defined(__x86_64__) && defined(__GLIBC__)
#define PINNED 1
#else
#define PINNED 0
#endif

static int mismatches;

static void check(const char *what, uint64_t got, uint64_t want)
{
    print_message("%-44s %016" PRIx64 "\n", what, got);
    if (PINNED && got != want) {
        print_message("  changed: pinned %016" PRIx64 "\n", want);
        mismatches++;
    }
}

/* A 512 x 256 picture from exact float arithmetic (no libm): a smooth ramp with a ripple, a
 * 3 x 3 sun of 1e5 three rows from the north pole and one across the seam on the equator. */
static ibl_image sun_picture(void)
{
    ibl_image im;
    assert_int_equal(ibl_image_alloc(NULL, 512, 256, &im), IBL_OK);
    for (int y = 0; y < 256; y++)
        for (int x = 0; x < 512; x++) {
            float *p = ibl_image_texel(&im, x, y);
            p[0] = 0.1f + 0.001f * (float)((x * 7 + y * 3) % 37);
            p[1] = 0.2f + 0.1f * (float)y / 256.0f;
            p[2] = 0.3f + 0.0005f * (float)(x % 64);
            p[3] = 1.0f;
        }
    for (int dy = -1; dy <= 1; dy++)
        for (int dx = -1; dx <= 1; dx++) {
            ibl_image_texel(&im, 300 + dx, 4 + dy)[0] = 1e5f;
            ibl_image_texel(&im, (512 + dx) % 512, 128 + dy)[1] = 1e5f;
        }
    return im;
}

typedef struct to_cube_case {
    int picture; /* 0: forest_128x64.exr, 1: uffizi_latlong_256x128.hdr, 2: sun_picture */
    int size, samples_per_axis;
    ibl_orientation orientation;
    uint64_t want;
} to_cube_case;

static const to_cube_case CASES[] = {
    {0, 16, 0, {0, 0, 0}, 0xf1894c18f39d898bull},
    {0, 40, 0, {17, 0, 0}, 0x13d2a1b376ebecaeull},
    {0, 64, 0, {-40, 1, 1}, 0xc85eb4f3011c8cf8ull},
    {0, 256, 0, {0, 0, 0}, 0xeae6cb7da4607e5full},
    {0, 40, 3, {90, 1, 0}, 0x3765d3838cbb605bull},
    {1, 8, 0, {0, 0, 0}, 0xaafc8f811d55c77bull},
    {1, 32, 0, {90, 1, 0}, 0x160b413a6bc65fc7ull},
    {2, 16, 0, {0, 0, 0}, 0x6262326b7d3075c0ull},
    {2, 64, 0, {-40, 1, 1}, 0x07891ebb2e03c7f6ull},
    {2, 128, 0, {17, 0, 0}, 0xcf56f130cda15316ull},
};
/* cube -> equirect from case 0's cube (natural width, then 32 wide) and SH of the pictures */
static const uint64_t BACK_NATURAL = 0x2832918431184a9dull, BACK_32 = 0x56ff1b0e8bea345bull;
static const uint64_t SH_WANT[3] = {0xbb0bf08f190c3364ull, 0xe787f78d6e0cf8a3ull,
                                   0x5ae9901a96562236ull};

static void equirect_bits_pinned(void **state)
{
    (void)state;
    ibl_image pictures[3];
    assert_int_equal(ibl_read_image(NULL, test_data("forest_128x64.exr"), NULL, &pictures[0], NULL),
                     IBL_OK);
    assert_int_equal(
        ibl_read_image(NULL, test_data("uffizi_latlong_256x128.hdr"), NULL, &pictures[1], NULL),
        IBL_OK);
    pictures[2] = sun_picture();
    ibl_context *ctxs[3];
    ctxs[0] = test_context(2);
    ctxs[1] = test_context(1);
    ibl_context_desc pd = {0};
    pd.threads = 2;
    pd.kernels = IBL_KERNELS_PORTABLE;
    assert_int_equal(ibl_context_create(&pd, &ctxs[2]), IBL_OK);
    static const char *ctx_names[3] = {"-j2", "-j1", "portable -j2"};
    char what[96];
    for (size_t i = 0; i < sizeof CASES / sizeof CASES[0]; i++) {
        const to_cube_case *c = &CASES[i];
        for (int k = 0; k < 3; k++) {
            ibl_to_cube_desc d = {0};
            d.layout = IBL_LAYOUT_EQUIRECT;
            d.size = c->size;
            d.samples_per_axis = c->samples_per_axis;
            d.orientation = c->orientation;
            ibl_cubemap cube;
            assert_int_equal(ibl_image_to_cubemap(ctxs[k], &pictures[c->picture], &d, &cube),
                             IBL_OK);
            snprintf(what, sizeof what, "case %zu: picture %d -> cube %d, %s", i, c->picture,
                     c->size, ctx_names[k]);
            check(what, test_fnv1a(cube.data, (size_t)6 * c->size * c->size * 4 * sizeof(float)),
                  c->want);
            if (i == 0 && k == 0) {
                int widths[2] = {0, 32};
                uint64_t want[2] = {BACK_NATURAL, BACK_32};
                for (int w = 0; w < 2; w++) {
                    ibl_from_cube_desc fd = {0};
                    fd.layout = IBL_LAYOUT_EQUIRECT;
                    fd.width = widths[w];
                    ibl_image back;
                    assert_int_equal(ibl_cubemap_to_image(ctxs[0], &cube, &fd, &back), IBL_OK);
                    snprintf(what, sizeof what, "case 0's cube -> equirect %dx%d", back.width,
                             back.height);
                    check(what, test_fnv1a(back.pixels, (size_t)back.width * back.height * 4 *
                                                       sizeof(float)),
                          want[w]);
                    ibl_image_free(NULL, &back);
                }
            }
            ibl_cubemap_free(NULL, &cube);
        }
    }
    for (int p = 0; p < 3; p++) {
        ibl_sh sh;
        assert_int_equal(ibl_sh_project_equirect(ctxs[0], &pictures[p], 3, &sh), IBL_OK);
        snprintf(what, sizeof what, "SH of picture %d", p);
        check(what, test_fnv1a(sh.c, sizeof sh.c), SH_WANT[p]);
    }
    for (int k = 0; k < 3; k++) ibl_context_destroy(ctxs[k]);
    for (int p = 0; p < 3; p++) ibl_image_free(NULL, &pictures[p]);
    if (!PINNED) print_message("(not glibc x86-64: the values above are not compared)\n");
    assert_int_equal(mismatches, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(equirect_bits_pinned),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
