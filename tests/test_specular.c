/* Specular prefilter: white furnace, mirror level, fast method against the reference with a
 * bright sun, the analytic lobe shape of a single texel, symmetry, thread independence,
 * mapping presets and the manifest. */
#include "test_support.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PI 3.14159265358979323846

/* A smooth sky (gradient + colour variation) with a small sun of ~1e4 the sky's radiance. */
static void fill_sun_sky(ibl_cubemap *c, double sun_dir[3], double sun_radius, float sun_value)
{
    int n = c->size;
    double len = sqrt(sun_dir[0] * sun_dir[0] + sun_dir[1] * sun_dir[1] + sun_dir[2] * sun_dir[2]);
    double cs = cos(sun_radius);
    for (int f = 0; f < 6; f++) {
        float *p = ibl_cubemap_face(c, 0, f);
        for (int y = 0; y < n; y++)
            for (int x = 0; x < n; x++, p += 4) {
                ibl_vec3 d = ibl_cube_texel_direction(f, n, x, y);
                p[0] = 0.4f + 0.3f * d.y + 0.1f * d.x;
                p[1] = 0.5f + 0.3f * d.y - 0.1f * d.z * d.x;
                p[2] = 0.9f + 0.5f * d.y * d.y;
                p[3] = 1.0f;
                double c2 = (d.x * sun_dir[0] + d.y * sun_dir[1] + d.z * sun_dir[2]) / len;
                if (c2 > cs) {
                    p[0] += sun_value;
                    p[1] += sun_value * 0.9f;
                    p[2] += sun_value * 0.8f;
                }
            }
    }
}

typedef struct err_stats {
    double rms, max;
} err_stats;

/* Issue 7's error bar for one level: solid-angle weighted relative RMS per channel, and the
 * largest texel error relative to max(reference, level mean). */
static err_stats level_error(const ibl_cubemap *fast, const ibl_cubemap *ref, int level)
{
    int n = ibl_level_size(fast->size, level);
    double mean[4];
    ibl_cubemap_mean(ref, level, mean);
    double se[3] = {0, 0, 0}, sr[3] = {0, 0, 0}, mx = 0;
    for (int f = 0; f < 6; f++) {
        const float *a = ibl_cubemap_face(fast, level, f), *b = ibl_cubemap_face(ref, level, f);
        for (int y = 0; y < n; y++)
            for (int x = 0; x < n; x++) {
                double w = ibl_cube_texel_solid_angle(n, x, y);
                size_t i = ((size_t)y * n + x) * 4;
                for (int c = 0; c < 3; c++) {
                    double e = a[i + c] - b[i + c];
                    se[c] += w * e * e;
                    sr[c] += w * b[i + c] * b[i + c];
                    double scale = fmax(b[i + c], mean[c]);
                    if (fabs(e) / scale > mx) mx = fabs(e) / scale;
                }
            }
    }
    err_stats s = {0, mx};
    for (int c = 0; c < 3; c++) s.rms = fmax(s.rms, sqrt(se[c] / sr[c]));
    return s;
}

static ibl_cubemap make_sun_cube(int n)
{
    ibl_cubemap c;
    ibl_context *ctx = test_context(1);
    assert_int_equal(ibl_cubemap_alloc(ctx, n, 1, &c), IBL_OK);
    ibl_context_destroy(ctx);
    double sun[3] = {0.5, 0.7, -0.35};
    fill_sun_sky(&c, sun, 1.6 * 2.0 / n, 1e4f);
    return c;
}

static void fast_vs_reference_case(ibl_specular_filter filter, int src_size, int size, int verbose)
{
    ibl_context *ctx = test_context(0);
    ibl_cubemap src = make_sun_cube(src_size);
    ibl_specular_desc d = {0};
    d.filter = filter;
    d.size = size;
    ibl_cubemap fast, ref;
    ibl_specular_info info;
    assert_int_equal(ibl_specular_prefilter(ctx, &src, &d, &fast, &info), IBL_OK);
    d.method = IBL_METHOD_REFERENCE;
    assert_int_equal(ibl_specular_prefilter(ctx, &src, &d, &ref, NULL), IBL_OK);
    for (int l = 0; l < fast.levels; l++) {
        err_stats e = level_error(&fast, &ref, l);
        if (verbose)
            printf("  %s %d<-%d level %d (%s %g): rms %.4f%% max %.3f%%\n",
                   ibl_specular_filter_name(filter), size, src_size, l,
                   filter == IBL_FILTER_GGX ? "r" : "n",
                   filter == IBL_FILTER_GGX ? info.roughness[l] : info.shininess[l], 100 * e.rms,
                   100 * e.max);
        /* issue 7's error bar */
        assert_true(e.rms <= 0.005);
        assert_true(e.max <= 0.05);
    }
    ibl_cubemap_free(ctx, &fast);
    ibl_cubemap_free(ctx, &ref);
    ibl_cubemap_free(ctx, &src);
    ibl_context_destroy(ctx);
}

static void fast_vs_reference(void **state)
{
    (void)state;
    int verbose = getenv("IBL_TEST_VERBOSE") != NULL;
    ibl_specular_filter filters[3] = {IBL_FILTER_GGX, IBL_FILTER_PHONG, IBL_FILTER_BLINN};
    for (int i = 0; i < 3; i++) {
        fast_vs_reference_case(filters[i], 32, 16, verbose);
        fast_vs_reference_case(filters[i], 32, 32, verbose);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(fast_vs_reference),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
