/* Irradiance environment maps: constant environments, an analytic band-limited radiance, a
 * brute-force double integral written here, fast vs reference, plans that do not allocate,
 * and thread-count independence. */
#include "test_support.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static const double PI = 3.14159265358979323846;

static void radiance_z2(const double *d, float *out) { out[0] = out[1] = out[2] = (float)(d[2] * d[2]); }

static void sky(const double *d, float *out)
{
    double sun = pow(fmax(0.0, 0.48 * d[0] + 0.6 * d[1] + 0.64 * d[2]), 200.0);
    double up = fmax(0.0, d[1]);
    out[0] = (float)(0.3 + 0.5 * up + 40 * sun);
    out[1] = (float)(0.4 + 0.7 * up + 35 * sun);
    out[2] = (float)(0.5 + 1.2 * up + 25 * sun);
}

/* Largest |a - b| over RGB of two cubes of one size, relative to b's mean. */
static double max_rel_diff(const ibl_cubemap *a, const ibl_cubemap *b)
{
    double mean[4], worst = 0;
    ibl_cubemap_mean(b, 0, mean);
    double m = (mean[0] + mean[1] + mean[2]) / 3;
    size_t n = 6 * (size_t)a->size * a->size * 4;
    for (size_t i = 0; i < n; i++) {
        if (i % 4 == 3) continue;
        double e = fabs((double)a->data[i] - b->data[i]) / m;
        if (e > worst) worst = e;
    }
    return worst;
}

/* A constant environment gives exactly that constant with every method, in both scales,
 * at several sizes: float rounding of a normalised weighted sum, 1e-5 relative. */
static void constant_environment(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2);
    static const int src_sizes[] = {3, 8, 16, 24};
    static const int out_sizes[] = {1, 5, 16};
    static const ibl_irradiance_method methods[] = {IBL_IRRADIANCE_CONVOLVE, IBL_IRRADIANCE_SH,
                                                    IBL_IRRADIANCE_REFERENCE};
    for (size_t s = 0; s < 4; s++) {
        ibl_cubemap src;
        assert_int_equal(ibl_cubemap_alloc(ctx, src_sizes[s], 1, &src), IBL_OK);
        test_fill_cube(&src, 0.5f, 2.0f, 7.0f);
        for (size_t o = 0; o < 3; o++)
            for (int m = 0; m < 3; m++)
                for (int scale = 0; scale < 2; scale++) {
                    ibl_irradiance_desc d = {0};
                    d.size = out_sizes[o];
                    d.method = methods[m];
                    d.scale = scale ? IBL_IRRADIANCE_SCALE_FULL : IBL_IRRADIANCE_SCALE_OVER_PI;
                    ibl_cubemap out;
                    assert_int_equal(ibl_irradiance_cubemap(ctx, &src, &d, &out), IBL_OK);
                    assert_int_equal(out.size, out_sizes[o]);
                    double k = scale ? PI : 1.0;
                    for (size_t i = 0; i < 6 * (size_t)out.size * out.size; i++) {
                        assert_near(out.data[4 * i + 0], 0.5 * k, 1e-5 * 0.5 * k);
                        assert_near(out.data[4 * i + 1], 2.0 * k, 1e-5 * 2.0 * k);
                        assert_near(out.data[4 * i + 2], 7.0 * k, 1e-5 * 7.0 * k);
                        assert_true(out.data[4 * i + 3] == 1.0f);
                    }
                    ibl_cubemap_free(ctx, &out);
                }
        ibl_cubemap_free(ctx, &src);
    }
    ibl_context_destroy(ctx);
}

/* Radiance z^2: E(n)/pi = (1 + n_z^2)/4 exactly. Tolerances are the measured errors times
 * about 3: the reference on a 32-cube carries the texel quadrature error of the cosine's
 * horizon kink (measured 6.7e-5, bound 2e-4); SH only the projection's O(N^-2) error
 * (6.3e-5, bound 2e-4); tri-Ace 2010's convolution of an 8x8x6 reduction (1.4e-3, bound 5e-3). */
static void analytic_z2(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2);
    ibl_cubemap src;
    assert_int_equal(ibl_cubemap_alloc(ctx, 32, 1, &src), IBL_OK);
    test_fill_cube_fn(&src, radiance_z2);
    static const ibl_irradiance_method methods[] = {IBL_IRRADIANCE_REFERENCE, IBL_IRRADIANCE_SH,
                                                    IBL_IRRADIANCE_CONVOLVE};
    static const double tol[] = {2e-4, 2e-4, 5e-3};
    for (int m = 0; m < 3; m++) {
        ibl_irradiance_desc d = {0};
        d.size = 8;
        d.method = methods[m];
        ibl_cubemap out;
        assert_int_equal(ibl_irradiance_cubemap(ctx, &src, &d, &out), IBL_OK);
        double worst = 0;
        for (int f = 0; f < 6; f++) {
            const float *p = ibl_cubemap_face(&out, 0, f);
            for (int y = 0; y < 8; y++)
                for (int x = 0; x < 8; x++, p += 4) {
                    double dir[3];
                    test_texel_dir(f, 8, x, y, dir);
                    double e = fabs(p[0] - 0.25 * (1 + dir[2] * dir[2]));
                    if (e > worst) worst = e;
                }
        }
        print_message("z^2 method %d: max error %.2e\n", m, worst);
        assert_true(worst <= tol[m]);
        ibl_cubemap_free(ctx, &out);
    }
    ibl_cubemap_free(ctx, &src);
    ibl_context_destroy(ctx);
}

/* The reference method against a double sum written here (every source texel, exact solid
 * angle, normalised by the sum of weights): same arithmetic, float output, 2e-6 relative. */
static void reference_matches_brute_force(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2);
    int n = 6, m = 3;
    ibl_cubemap src;
    assert_int_equal(ibl_cubemap_alloc(ctx, n, 1, &src), IBL_OK);
    test_fill_cube_fn(&src, sky);
    ibl_irradiance_desc d = {0};
    d.size = m;
    d.method = IBL_IRRADIANCE_REFERENCE;
    ibl_cubemap out;
    assert_int_equal(ibl_irradiance_cubemap(ctx, &src, &d, &out), IBL_OK);
    for (int f = 0; f < 6; f++)
        for (int y = 0; y < m; y++)
            for (int x = 0; x < m; x++) {
                double nrm[3], acc[3] = {0, 0, 0}, wsum = 0;
                test_texel_dir(f, m, x, y, nrm);
                for (int g = 0; g < 6; g++)
                    for (int j = 0; j < n; j++)
                        for (int i = 0; i < n; i++) {
                            double w[3];
                            test_texel_dir(g, n, i, j, w);
                            double c = nrm[0] * w[0] + nrm[1] * w[1] + nrm[2] * w[2];
                            if (c <= 0) continue;
                            double wt = c * ibl_cube_texel_solid_angle(n, i, j);
                            const float *p = ibl_cubemap_face(&src, 0, g) + (j * n + i) * 4;
                            for (int k = 0; k < 3; k++) acc[k] += wt * p[k];
                            wsum += wt;
                        }
                const float *o = ibl_cubemap_face(&out, 0, f) + (y * m + x) * 4;
                for (int k = 0; k < 3; k++) assert_near(o[k], acc[k] / wsum, 2e-6 * acc[k] / wsum);
            }
    ibl_cubemap_free(ctx, &out);
    ibl_cubemap_free(ctx, &src);
    ibl_context_destroy(ctx);
}

/* Fast (8x8x6 -> 16) vs reference (full resolution, double) on a sky with a sun: the
 * reduction blurs the sun over an 8x8 texel (~11 degrees) before the cosine, which the cosine
 * lobe barely sees: 1% of the mean, measured 0.62%. The SH method (3 bands) differs by its
 * band limit: 6% of the mean, measured 4.1%. */
static void fast_vs_reference(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2);
    ibl_cubemap src;
    assert_int_equal(ibl_cubemap_alloc(ctx, 64, 1, &src), IBL_OK);
    test_fill_cube_fn(&src, sky);
    ibl_irradiance_desc d = {0};
    ibl_cubemap ref, fast, sh;
    d.method = IBL_IRRADIANCE_REFERENCE;
    assert_int_equal(ibl_irradiance_cubemap(ctx, &src, &d, &ref), IBL_OK);
    d.method = IBL_IRRADIANCE_CONVOLVE;
    assert_int_equal(ibl_irradiance_cubemap(ctx, &src, &d, &fast), IBL_OK);
    d.method = IBL_IRRADIANCE_SH;
    assert_int_equal(ibl_irradiance_cubemap(ctx, &src, &d, &sh), IBL_OK);
    double e_fast = max_rel_diff(&fast, &ref), e_sh = max_rel_diff(&sh, &ref);
    print_message("convolve vs reference %.4f, sh vs reference %.4f (of the mean)\n", e_fast, e_sh);
    assert_true(e_fast <= 0.01);
    assert_true(e_sh <= 0.06);
    ibl_cubemap_free(ctx, &ref);
    ibl_cubemap_free(ctx, &fast);
    ibl_cubemap_free(ctx, &sh);
    ibl_cubemap_free(ctx, &src);
    ibl_context_destroy(ctx);
}

/* Real HDRIs (tests/data, CC0): the 8x8x6 reduction moves each bright light to the
 * centre of an ~11 degree texel before the cosine, so the fast result is off by up to the
 * cosine's change over that texel times the light's share of the irradiance. Measured on
 * 64-cubes (max over texels, relative to the mean): studio 0.070, sunset 0.024 with the
 * default 8x8x6; 0.0076 and 0.0038 with 32x32x6. Bounds: the measurements plus about a third. */
static void fast_vs_reference_hdri(void **state)
{
    (void)state;
    static const char *const files[] = {"studio.exr", "sunset.exr"};
    static const double bound8[] = {0.09, 0.033}, bound32[] = {0.01, 0.005};
    ibl_context *ctx = test_context(0);
    for (int k = 0; k < 2; k++) {
        ibl_image im;
        assert_int_equal(ibl_read_image(ctx, test_data(files[k]), NULL, &im, NULL), IBL_OK);
        ibl_to_cube_desc cd = {0};
        cd.layout = IBL_LAYOUT_EQUIRECT;
        cd.size = 64;
        ibl_cubemap src;
        assert_int_equal(ibl_image_to_cubemap(ctx, &im, &cd, &src), IBL_OK);
        ibl_irradiance_desc d = {0};
        ibl_cubemap ref, fast, fast32;
        d.method = IBL_IRRADIANCE_REFERENCE;
        assert_int_equal(ibl_irradiance_cubemap(ctx, &src, &d, &ref), IBL_OK);
        d.method = IBL_IRRADIANCE_CONVOLVE;
        assert_int_equal(ibl_irradiance_cubemap(ctx, &src, &d, &fast), IBL_OK);
        d.source_size = 32;
        assert_int_equal(ibl_irradiance_cubemap(ctx, &src, &d, &fast32), IBL_OK);
        double e8 = max_rel_diff(&fast, &ref), e32 = max_rel_diff(&fast32, &ref);
        print_message("%s: convolve 8 vs reference %.4f, convolve 32 %.4f\n", files[k], e8, e32);
        assert_true(e8 <= bound8[k]);
        assert_true(e32 <= bound32[k]);
        ibl_cubemap_free(ctx, &ref);
        ibl_cubemap_free(ctx, &fast);
        ibl_cubemap_free(ctx, &fast32);
        ibl_cubemap_free(ctx, &src);
        ibl_image_free(ctx, &im);
    }
    ibl_context_destroy(ctx);
}

/* Counting allocator: the per-frame run must not allocate. */
static size_t alloc_count;
static void *count_alloc(size_t bytes, void *user)
{
    (void)user;
    alloc_count++;
    return malloc(bytes);
}
static void count_free(void *p, void *user)
{
    (void)user;
    free(p);
}

static void plan_runs_without_allocation(void **state)
{
    (void)state;
    ibl_context_desc cd = {0};
    cd.allocator.alloc = count_alloc;
    cd.allocator.free = count_free;
    cd.threads = 1;
    ibl_context *ctx;
    assert_int_equal(ibl_context_create(&cd, &ctx), IBL_OK);
    ibl_irradiance_plan *plan;
    ibl_irradiance_plan_desc pd = {.source_size = 8, .size = 16};
    assert_int_equal(ibl_irradiance_plan_create(ctx, &pd, &plan), IBL_OK);
    /* about half the source texels face each output texel */
    size_t taps = ibl_irradiance_plan_taps(plan);
    assert_true(taps > 6 * 256 * 384 * 0.45 && taps < 6 * 256 * 384 * 0.55);
    ibl_sh_plan *shp;
    assert_int_equal(ibl_sh_plan_create(ctx, &(ibl_sh_plan_desc){.face_size = 8, .bands = 3}, &shp),
                     IBL_OK);
    float src[6 * 8 * 8 * 4], dst[6 * 16 * 16 * 4];
    for (int i = 0; i < 6 * 8 * 8 * 4; i++) src[i] = (float)(i % 17);
    ibl_cubemap src_cube, dst_cube;
    assert_int_equal(ibl_cubemap_wrap(8, 1, src, &src_cube), IBL_OK);
    assert_int_equal(ibl_cubemap_wrap(16, 1, dst, &dst_cube), IBL_OK);
    size_t before = alloc_count;
    ibl_sh sh;
    for (int r = 0; r < 3; r++) {
        assert_int_equal(ibl_irradiance_plan_run(plan, &src_cube, &dst_cube), IBL_OK);
        assert_int_equal(ibl_sh_plan_run(shp, &src_cube, &sh), IBL_OK);
    }
    assert_int_equal(alloc_count, before);
    /* a cube of another size is refused, not read out of bounds */
    assert_int_equal(ibl_irradiance_plan_run(plan, &dst_cube, &dst_cube), IBL_ERR_INVALID_ARGUMENT);
    assert_int_equal(ibl_sh_plan_run(shp, &dst_cube, &sh), IBL_ERR_INVALID_ARGUMENT);
    ibl_sh_plan_destroy(shp);
    ibl_irradiance_plan_destroy(plan);
    ibl_context_destroy(ctx);
}

static void identical_at_any_thread_count(void **state)
{
    (void)state;
    static const int threads[] = {1, 2, 8};
    float *first[3] = {NULL, NULL, NULL};
    size_t bytes = 6 * 8 * 8 * 4 * sizeof(float);
    for (int t = 0; t < 3; t++) {
        ibl_context *ctx = test_context(threads[t]);
        ibl_cubemap src;
        assert_int_equal(ibl_cubemap_alloc(ctx, 20, 1, &src), IBL_OK);
        test_fill_cube_fn(&src, sky);
        for (int m = 0; m < 3; m++) {
            ibl_irradiance_desc d = {0};
            d.size = 8;
            d.method = (ibl_irradiance_method)m;
            d.source_size = 5; /* not a power-of-two fraction: the resample path */
            ibl_cubemap out;
            assert_int_equal(ibl_irradiance_cubemap(ctx, &src, &d, &out), IBL_OK);
            if (t == 0) {
                first[m] = malloc(bytes);
                memcpy(first[m], out.data, bytes);
            } else {
                assert_memory_equal(out.data, first[m], bytes);
            }
            ibl_cubemap_free(ctx, &out);
        }
        ibl_cubemap_free(ctx, &src);
        ibl_context_destroy(ctx);
    }
    for (int m = 0; m < 3; m++) free(first[m]);
}

/* The reduction keeps the solid-angle-weighted mean: exactly (to float) for an integer ratio
 * (the block mean), to the resampler's accuracy otherwise (1e-3 on this smooth input). */
static void reduction_keeps_mean(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    static const int sizes[] = {32, 24};
    for (int s = 0; s < 2; s++) {
        ibl_cubemap src, small;
        assert_int_equal(ibl_cubemap_alloc(ctx, sizes[s], 1, &src), IBL_OK);
        test_fill_cube_fn(&src, radiance_z2);
        assert_int_equal(ibl_cubemap_alloc(ctx, 8, 1, &small), IBL_OK);
        assert_int_equal(ibl_cubemap_resample(ctx, &src, &small), IBL_OK);
        double a[4], b[4];
        ibl_cubemap_mean(&src, 0, a);
        ibl_cubemap_mean(&small, 0, b);
        assert_near(b[0], a[0], s == 0 ? 1e-6 : 1e-3);
        ibl_cubemap_free(ctx, &small);
        ibl_cubemap_free(ctx, &src);
    }
    ibl_context_destroy(ctx);
}

static void bad_arguments(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_cubemap src, out;
    assert_int_equal(ibl_cubemap_alloc(ctx, 8, 1, &src), IBL_OK);
    ibl_irradiance_desc d = {0};
    d.size = 65;
    assert_int_equal(ibl_irradiance_cubemap(ctx, &src, &d, &out), IBL_ERR_INVALID_ARGUMENT);
    d.size = 16;
    d.sh_bands = 6;
    d.method = IBL_IRRADIANCE_SH;
    assert_int_equal(ibl_irradiance_cubemap(ctx, &src, &d, &out), IBL_ERR_INVALID_ARGUMENT);
    ibl_irradiance_plan *plan;
    assert_int_equal(ibl_irradiance_plan_create(ctx, &(ibl_irradiance_plan_desc){.size = 16}, &plan),
                     IBL_ERR_INVALID_ARGUMENT);
    ibl_cubemap_free(ctx, &src);
    ibl_context_destroy(ctx);
}

/* ibl irradiance writes a cube container (read back: the library's result for the same input,
 * within half-float storage, 1e-3 relative) or a flat image in a cross; bad usage exits 2. */
static void cli_irradiance(void **state)
{
    (void)state;
    const char *in = test_data("uffizi_latlong_256x128.hdr");
    const char *ktx = test_path("irr.ktx2");
    assert_int_equal(test_run_cli(NULL, "irradiance '%s' -o '%s' --size 8 -q", in, ktx), 0);
    ibl_context *ctx = test_context(0);
    ibl_texture tex;
    assert_int_equal(ibl_read_texture(ctx, ktx, NULL, &tex, NULL), IBL_OK);
    assert_int_equal(tex.kind, IBL_TEXTURE_CUBE);
    assert_int_equal(tex.width, 8);
    const char *norm = ibl_texture_get_metadata(&tex, "ibl.irradiance");
    assert_non_null(norm);
    assert_string_equal(norm, "E/pi");
    ibl_image im;
    assert_int_equal(ibl_read_image(ctx, in, NULL, &im, NULL), IBL_OK);
    ibl_cubemap src, expect;
    ibl_to_cube_desc cd = {0};
    cd.size = 64; /* the CLI reads the input at 8x the reduced edge for convolve */
    assert_int_equal(ibl_image_to_cubemap(ctx, &im, &cd, &src), IBL_OK);
    ibl_irradiance_desc d = {0};
    d.size = 8;
    assert_int_equal(ibl_irradiance_cubemap(ctx, &src, &d, &expect), IBL_OK);
    for (size_t i = 0; i < 6 * 8 * 8 * 4; i++)
        assert_near(tex.data[i], expect.data[i], 1e-3 * fabs(expect.data[i]) + 1e-6);
    ibl_cubemap_free(ctx, &expect);
    ibl_cubemap_free(ctx, &src);
    ibl_image_free(ctx, &im);
    ibl_texture_free(ctx, &tex);
    const char *flat = test_path("irr.pfm");
    assert_int_equal(test_run_cli(NULL, "irradiance '%s' -o '%s' --size 8 --method sh -q", in, flat), 0);
    assert_int_equal(ibl_read_image(ctx, flat, NULL, &im, NULL), IBL_OK);
    assert_int_equal(im.width, 32); /* horizontal cross: 4 x 3 faces */
    assert_int_equal(im.height, 24);
    ibl_image_free(ctx, &im);
    ibl_context_destroy(ctx);
    assert_int_equal(test_run_cli(NULL, "irradiance '%s'", in), 2);
    assert_int_equal(test_run_cli(NULL, "irradiance '%s' -o '%s' --size 65", in, ktx), 2);
    assert_int_equal(test_run_cli(NULL, "irradiance '%s' -o '%s' --method magic", in, ktx), 2);
    assert_int_equal(test_run_cli(NULL, "irradiance '%s' -o '%s'", test_path("none.exr"), ktx), 1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(constant_environment),
        cmocka_unit_test(analytic_z2),
        cmocka_unit_test(reference_matches_brute_force),
        cmocka_unit_test(fast_vs_reference),
        cmocka_unit_test(fast_vs_reference_hdri),
        cmocka_unit_test(plan_runs_without_allocation),
        cmocka_unit_test(identical_at_any_thread_count),
        cmocka_unit_test(reduction_keeps_mean),
        cmocka_unit_test(bad_arguments),
        cmocka_unit_test(cli_irradiance),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
