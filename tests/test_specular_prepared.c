/* ibl_specular_prepare / ibl_specular_prefilter_prepared: the prefilter in two halves, the
 * first needing only the source's edge. Prepared beside the making of its source (the two
 * tasks of one ibl_parallel_for, as `ibl prefilter` runs them: the pool's loops of both
 * halves then share the threads), the chain must equal ibl_specular_prefilter's on one thread
 * bit for bit, on 1, 2 and 8 threads, for each method the prepared half holds (the fast
 * plan, the dynamic plan, the box kernel, the reference); and a prepared chain takes only a
 * source of its edge, once. */
#include "test_support.h"

#include <stdlib.h>
#include <string.h>

typedef struct prepared_case {
    ibl_specular_filter filter;
    int size, cube, dynamic;
    ibl_specular_method method;
} prepared_case;

static const prepared_case cases[] = {
    {IBL_FILTER_GGX, 128, 256, 0, IBL_METHOD_FAST},  /* fast plan, working edge 256 */
    {IBL_FILTER_PHONG, 64, 96, 0, IBL_METHOD_FAST},  /* fast plan, resampled to 128 */
    {IBL_FILTER_BLINN, 32, 64, 1, IBL_METHOD_FAST},  /* dynamic plan */
    {IBL_FILTER_BOX, 16, 32, 0, IBL_METHOD_FAST},    /* box kernel, no plan */
    {IBL_FILTER_GGX, 8, 16, 0, IBL_METHOD_REFERENCE},   /* reference, no plan */
};

typedef struct side_by_side {
    ibl_context *ctx;
    const ibl_image *image;
    const ibl_specular_desc *desc;
    int cube_size;
    ibl_cubemap cube;
    ibl_status cube_status, prepare_status;
    ibl_specular_prepared *prepared;
} side_by_side;

static void side_by_side_task(void *arg, int index)
{
    side_by_side *j = arg;
    if (index == 0)
        j->cube_status = ibl_image_to_cubemap(j->ctx, j->image,
                                              &(ibl_to_cube_desc){.size = j->cube_size}, &j->cube);
    else
        j->prepare_status = ibl_specular_prepare(j->ctx, j->desc, j->cube_size, &j->prepared);
}

static ibl_specular_desc case_desc(const prepared_case *c)
{
    ibl_specular_desc d = {0};
    d.filter = c->filter;
    d.size = c->size;
    d.dynamic = c->dynamic;
    d.method = c->method;
    return d;
}

static void prepared_beside_its_source_matches_prefilter(void **state)
{
    (void)state;
    ibl_context *one = test_context(1);
    ibl_image image;
    assert_int_equal(ibl_read_image(one, test_data("city.exr"), NULL, &image, NULL), IBL_OK);
    static const int threads[3] = {1, 2, 8};
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        const prepared_case *c = &cases[k];
        ibl_specular_desc d = case_desc(c);
        ibl_cubemap src, expected;
        assert_int_equal(ibl_image_to_cubemap(one, &image, &(ibl_to_cube_desc){.size = c->cube}, &src),
                         IBL_OK);
        assert_int_equal(ibl_specular_prefilter(one, &src, &d, &expected, NULL), IBL_OK);
        size_t floats = ibl_cubemap_floats(expected.size, expected.levels);
        for (int t = 0; t < 3; t++) {
            ibl_context *ctx = test_context(threads[t]);
            side_by_side job = {ctx, &image, &d, c->cube, {0}, IBL_OK, IBL_OK, NULL};
            ibl_parallel_for(ctx, 2, side_by_side_task, &job);
            assert_int_equal(job.cube_status, IBL_OK);
            assert_int_equal(job.prepare_status, IBL_OK);
            ibl_cubemap chain;
            ibl_specular_info info;
            assert_int_equal(ibl_specular_prefilter_prepared(job.prepared, &job.cube, &chain, &info),
                             IBL_OK);
            assert_int_equal(chain.size, expected.size);
            assert_int_equal(chain.levels, expected.levels);
            assert_int_equal(info.levels, expected.levels);
            if (memcmp(chain.data, expected.data, floats * sizeof(float)) != 0)
                fail_msg("case %zu on %d threads: not the bits of ibl_specular_prefilter", k,
                         threads[t]);
            ibl_cubemap_free(ctx, &chain);
            ibl_cubemap_free(ctx, &job.cube);
            ibl_specular_prepared_destroy(job.prepared);
            ibl_context_destroy(ctx);
        }
        ibl_cubemap_free(one, &expected);
        ibl_cubemap_free(one, &src);
    }
    ibl_image_free(one, &image);
    ibl_context_destroy(one);
}

static void prepared_takes_its_edge_once(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2);
    ibl_specular_desc d = {0};
    d.size = 16;
    ibl_specular_prepared *p = NULL;
    assert_int_equal(ibl_specular_prepare(ctx, &d, 0, &p), IBL_ERR_INVALID_ARGUMENT);
    assert_null(p);
    assert_int_equal(ibl_specular_prepare(ctx, &d, 32, &p), IBL_OK);
    ibl_cubemap wrong, right, chain;
    assert_int_equal(ibl_cubemap_alloc(ctx, 64, 1, &wrong), IBL_OK);
    assert_int_equal(ibl_cubemap_alloc(ctx, 32, 1, &right), IBL_OK);
    assert_int_equal(ibl_specular_prefilter_prepared(p, &wrong, &chain, NULL), IBL_ERR_INVALID_ARGUMENT);
    assert_non_null(strstr(ibl_context_message(ctx), "prepared for a source of edge 32, given one of 64"));
    assert_null(chain.data);
    assert_int_equal(ibl_specular_prefilter_prepared(p, &right, &chain, NULL), IBL_OK);
    assert_int_equal(chain.size, 16);
    ibl_cubemap_free(ctx, &chain);
    assert_int_equal(ibl_specular_prefilter_prepared(p, &right, &chain, NULL), IBL_ERR_INVALID_ARGUMENT);
    assert_non_null(strstr(ibl_context_message(ctx), "runs once"));
    ibl_specular_prepared_destroy(p);
    ibl_cubemap_free(ctx, &wrong);
    ibl_cubemap_free(ctx, &right);
    ibl_context_destroy(ctx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(prepared_beside_its_source_matches_prefilter),
        cmocka_unit_test(prepared_takes_its_edge_once),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
