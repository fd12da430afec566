/* A split Phong core (src/bake/specular/pieces.c, split_core_step): a narrow Phong lobe whose
 * core would be summed over texels finer than a quarter of its half width is cut in two, the
 * inner core over those texels and a split ring over the next coarser level on the core's own
 * grid, with the ring's centroid corrections. Exponent 600 from a 128 cube (half width 0.048
 * rad, 4.25 source texels) is split, exponent 1400 (2.8 source texels a half width) is not; the plan's statistics tell them apart (one piece more). Against
 * the reference (the float64 sum over every source texel) on a cube with a sun of 1e4 the
 * sky's radiance, with the accuracy bar; the same bits on one thread and two, and from the
 * one-shot plan of ibl_specular_prefilter; a constant environment stays constant (the inner
 * core and the split ring add up to the core at every grid point). */
#include "test_support.h"
#include "bake/specular_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

enum { EDGE = 128, SAMPLES = 400 };

/* A smooth sky with a small sun of 1e4 its radiance (the source's brightest texels are the
 * ones the centroid corrections exist for). */
static void fill_sun_sky(ibl_cubemap *c)
{
    const double len = sqrt(0.5 * 0.5 + 0.7 * 0.7 + 0.35 * 0.35), cos_sun = cos(1.6 * 2.0 / EDGE);
    const double sun[3] = {0.5 / len, 0.7 / len, -0.35 / len};
    for (int f = 0; f < 6; f++) {
        float *p = ibl_cubemap_face(c, 0, f);
        for (int y = 0; y < EDGE; y++)
            for (int x = 0; x < EDGE; x++, p += 4) {
                ibl_vec3 d = ibl_cube_texel_direction(f, EDGE, x, y);
                p[0] = 0.4f + 0.3f * d.y + 0.1f * d.x;
                p[1] = 0.5f + 0.3f * d.y - 0.1f * d.z * d.x;
                p[2] = 0.9f + 0.5f * d.y * d.y;
                p[3] = 1.0f;
                if (d.x * sun[0] + d.y * sun[1] + d.z * sun[2] > cos_sun)
                    p[0] += 1e4f, p[1] += 0.9e4f, p[2] += 0.8e4f;
            }
    }
}

/* The worst channel's solid-angle weighted relative RMS and the largest error relative to
 * max(reference, level mean), at a deterministic sample of the level's texels. */
static void error_against_reference(const ibl_specular_reference *ref, const ibl_specular_info *info,
                                    const ibl_cubemap *out, double *rms, double *max)
{
    double mean[4], se[3] = {0, 0, 0}, sr[3] = {0, 0, 0};
    ibl_cubemap_mean(out, 0, mean);
    size_t total = (size_t)6 * EDGE * EDGE;
    *max = 0;
    for (size_t k = 0; k < SAMPLES; k++) {
        size_t t = (k * 2654435761u) % total;
        int f = (int)(t / ((size_t)EDGE * EDGE)), y = (int)(t / EDGE % EDGE), x = (int)(t % EDGE);
        double r[4];
        ibl_specular_reference_eval(ref, info, 0, ibl_cube_texel_direction(f, EDGE, x, y), r);
        const float *a = ibl_cubemap_face(out, 0, f) + ((size_t)y * EDGE + x) * 4;
        double w = ibl_cube_texel_solid_angle(EDGE, x, y);
        for (int c = 0; c < 3; c++) {
            double e = a[c] - r[c];
            se[c] += w * e * e, sr[c] += w * r[c] * r[c];
            double rel = fabs(e) / fmax(r[c], mean[c]);
            *max = rel > *max ? rel : *max;
        }
    }
    *rms = 0;
    for (int c = 0; c < 3; c++) *rms = fmax(*rms, sqrt(se[c] / sr[c]));
}

static ibl_specular_desc one_level(const float *exponent)
{
    ibl_specular_desc d = {0};
    d.filter = IBL_FILTER_PHONG;
    d.size = EDGE;
    d.source_size = EDGE;
    d.levels = 1;
    d.mapping = IBL_MAPPING_TABLE;
    d.table = exponent;
    d.table_count = 1;
    return d;
}

/* The level's pieces (core and rings) as the plan made them. */
static int plan_pieces(float exponent)
{
    ibl_context *ctx = test_context(1);
    ibl_specular_desc d = one_level(&exponent);
    ibl_specular_plan *plan;
    assert_int_equal(ibl_specular_plan_create(ctx, &d, &plan), IBL_OK);
    ibl__specular_stats st;
    ibl__specular_plan_stats(plan, &st);
    ibl_specular_plan_destroy(plan);
    ibl_context_destroy(ctx);
    return st.pieces;
}

static void split_core(void **state)
{
    (void)state;
    int verbose = getenv("IBL_TEST_VERBOSE") != NULL;
    /* 600: core, split ring, first ring; 1400: core and first ring */
    int split = plan_pieces(600.0f), whole = plan_pieces(1400.0f);
    if (verbose) printf("  pieces: exponent 600 %d, exponent 1400 %d\n", split, whole);
    assert_int_equal(split, 3);
    assert_int_equal(whole, 2);

    const float exponent = 600.0f;
    ibl_specular_desc d = one_level(&exponent);
    ibl_cubemap src, out[3];
    ibl_context *ctx1 = test_context(1), *ctx2 = test_context(2);
    assert_int_equal(ibl_cubemap_alloc(ctx1, EDGE, 1, &src), IBL_OK);
    fill_sun_sky(&src);
    ibl_specular_plan *plan[2];
    for (int t = 0; t < 2; t++) {
        ibl_context *ctx = t ? ctx2 : ctx1;
        assert_int_equal(ibl_specular_plan_create(ctx, &d, &plan[t]), IBL_OK);
        assert_int_equal(ibl_cubemap_alloc(ctx, EDGE, 1, &out[t]), IBL_OK);
        assert_int_equal(ibl_specular_plan_run(plan[t], &src, &out[t]), IBL_OK);
    }
    size_t bytes = ibl_cubemap_floats(EDGE, 1) * sizeof(float);
    assert_memory_equal(out[0].data, out[1].data, bytes);
    /* the one-shot plan (normalisers made at the run, the split ring's corrections) */
    assert_int_equal(ibl_specular_prefilter(ctx2, &src, &d, &out[2], NULL), IBL_OK);
    assert_memory_equal(out[0].data, out[2].data, bytes);

    ibl__specular_stats st;
    ibl__specular_plan_stats(plan[1], &st);
    ibl_specular_reference *ref;
    assert_int_equal(ibl_specular_reference_create(ctx2, &src, &ref), IBL_OK);
    double rms, max;
    error_against_reference(ref, ibl_specular_plan_info(plan[1]), &out[1], &rms, &max);
    if (verbose)
        printf("  exponent 600: %d correction blocks, rms %.3f%% max %.3f%%\n", st.correction_blocks,
               100 * rms, 100 * max);
    /* the split ring reads the 64 level as uniform light: the sun's texels are corrected */
    assert_true(st.correction_blocks > 0);
    /* the accuracy bar (docs/SPECULAR.md "Accuracy"): 0.5% RMS, 5% max */
    assert_true(rms <= 0.005);
    assert_true(max <= 0.05);
    ibl_specular_reference_destroy(ref);

    /* a constant environment: every piece's numerator and normaliser from the same weights */
    test_fill_cube(&src, 1.5f, 0.25f, 3.0f);
    assert_int_equal(ibl_specular_plan_run(plan[1], &src, &out[1]), IBL_OK);
    const float expect[3] = {1.5f, 0.25f, 3.0f};
    for (size_t i = 0; i < ibl_cubemap_floats(EDGE, 1) / 4; i++)
        for (int c = 0; c < 3; c++) assert_near(out[1].data[i * 4 + c] / expect[c], 1.0, 1e-5);

    for (int t = 0; t < 2; t++) ibl_specular_plan_destroy(plan[t]);
    ibl_cubemap_free(ctx1, &out[0]);
    ibl_cubemap_free(ctx2, &out[1]);
    ibl_cubemap_free(ctx2, &out[2]);
    ibl_cubemap_free(ctx1, &src);
    ibl_context_destroy(ctx1);
    ibl_context_destroy(ctx2);
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(split_core)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
