/* An output set writes a KTX2's level images while the pool's workers are still encoding them
 * (src/io/output.c, ibl__encode_levels_begin in src/io/container.c): every slice is written
 * only once it is encoded, so the file holds the bytes of the plain encode, for every texel
 * format, with the same count of clamped texels; a write that fails ends the encode and leaves
 * the pool free. And the pool's loop beside the caller (ibl__parallel_begin/help/end) runs
 * every index exactly once. */
#include "test_io_helpers.h"

#include "core/context_internal.h"

#include <math.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* A 256 cube with its 9 levels: 4.2 MB at rgba16f, several of the writer's 1 MiB slices. Some
 * texels are past the largest half (65504) and past the RGBM range, so the formats clamp. */
static ibl_cubemap make_chain(ibl_context *ctx)
{
    ibl_cubemap cube;
    assert_int_equal(ibl_cubemap_alloc(ctx, 256, 9, &cube), IBL_OK);
    for (int l = 0; l < cube.levels; l++) {
        int n = ibl_level_size(cube.size, l);
        for (int f = 0; f < 6; f++) {
            float *p = ibl_cubemap_face(&cube, l, f);
            for (int i = 0; i < n * n; i++) {
                unsigned h = (unsigned)(i * 2654435761u) ^ (unsigned)(f * 97 + l * 13);
                float v = (float)(h % 10007) / 97.0f;
                if (h % 4099 == 3) v = 70000.0f + (float)(h % 7);
                p[i * 4 + 0] = v;
                p[i * 4 + 1] = 0.5f * v + 0.25f;
                p[i * 4 + 2] = (float)((h >> 8) % 1000) / 999.0f;
                p[i * 4 + 3] = 1.0f;
            }
        }
    }
    return cube;
}

/* The file written on two threads through an output set against ibl_encode_texture on one. */
static void streamed_file_matches_the_encode(void **state)
{
    (void)state;
    ibl_context *one = test_context(1), *two = test_context(2);
    ibl_cubemap chain = make_chain(one);
    ibl_texture tex = ibl_texture_from_cubemap(&chain);
    const ibl_format formats[] = {IBL_FORMAT_RGBA16F, IBL_FORMAT_RGBA32F, IBL_FORMAT_RG11B10F,
                                  IBL_FORMAT_RGB9E5, IBL_FORMAT_RGBM};
    const char *path = test_path("streamed.ktx2");
    for (size_t k = 0; k < sizeof formats / sizeof formats[0]; k++) {
        ibl_write_report want_report = {0}, got_report = {0};
        ibl_write_desc wd = {.format = formats[k], .report = &want_report};
        void *want;
        size_t want_size;
        assert_int_equal(ibl_encode_texture(one, IBL_FILE_KTX2, &tex, &wd, &want, &want_size), IBL_OK);
        wd.report = &got_report;
        ibl_output_set *set;
        assert_int_equal(ibl_output_set_create(two, &set), IBL_OK);
        assert_int_equal(ibl_output_set_add_texture(set, path, &tex, &wd), IBL_OK);
        assert_int_equal(ibl_output_set_commit(set), IBL_OK);
        ibl_output_set_destroy(set);
        size_t got_size;
        void *got = slurp(path, &got_size);
        assert_int_equal(got_size, want_size);
        assert_memory_equal(got, want, want_size);
        /* the rgba16f and RGBM writes clamp (the texels past 65504 or the range) */
        if (formats[k] == IBL_FORMAT_RGBA16F || formats[k] == IBL_FORMAT_RGBM)
            assert_true(want_report.clamped_texels > 0);
        assert_int_equal(got_report.clamped_texels, want_report.clamped_texels);
        free(got);
        ibl_free(one, want);
    }
    remove(path);
    ibl_cubemap_free(one, &chain);
    ibl_context_destroy(two);
    ibl_context_destroy(one);
}

typedef struct counts {
    atomic_int runs[4096];
} counts;

static void count_task(void *arg, int index)
{
    counts *c = arg;
    atomic_fetch_add(&c->runs[index], 1);
}

/* A write that fails (its folder does not exist) ends the encode beside it: nothing is
 * written, and the pool takes the next loop beside the caller again. */
static void failed_write_frees_the_pool(void **state)
{
    (void)state;
    ibl_context *two = test_context(2);
    ibl_cubemap chain = make_chain(two);
    ibl_texture tex = ibl_texture_from_cubemap(&chain);
    char path[512];
    snprintf(path, sizeof path, "%s/out.ktx2", test_path("no-such-folder"));
    ibl_output_set *set;
    assert_int_equal(ibl_output_set_create(two, &set), IBL_OK);
    assert_int_equal(ibl_output_set_add_texture(set, path, &tex, NULL), IBL_ERR_IO);
    assert_non_null(strstr(ibl_context_message(two), "out.ktx2"));
    ibl_output_set_destroy(set);
    struct stat st;
    assert_true(stat(path, &st) != 0);
    counts *c = calloc(1, sizeof *c);
    assert_non_null(c);
    assert_int_equal(ibl__parallel_begin(two, 100, count_task, c), 1);
    ibl__parallel_end(two);
    for (int i = 0; i < 100; i++) assert_int_equal(atomic_load(&c->runs[i]), 1);
    free(c);
    ibl_cubemap_free(two, &chain);
    ibl_context_destroy(two);
}

static void host_loop(void *host, int count, ibl_task_fn task, void *arg)
{
    (void)host;
    for (int i = 0; i < count; i++) task(arg, i);
}

/* Every index once, whoever runs it; no loop beside the caller without a pool to run it (one
 * thread, or the host's own parallel-for), nor while one already runs. */
static void loop_beside_the_caller(void **state)
{
    (void)state;
    ibl_context *two = test_context(2);
    counts *c = calloc(1, sizeof *c);
    assert_non_null(c);
    for (int round = 0; round < 50; round++) {
        memset(c, 0, sizeof *c);
        int n = 1 + round * 81;
        assert_int_equal(ibl__parallel_begin(two, n, count_task, c), 1);
        assert_int_equal(ibl__parallel_begin(two, n, count_task, c), 0); /* one at a time */
        for (int taken = 0; taken < round && ibl__parallel_help(two); taken++) {
        }
        ibl__parallel_end(two);
        for (int i = 0; i < n; i++) assert_int_equal(atomic_load(&c->runs[i]), 1);
    }
    ibl_context *one = test_context(1);
    assert_int_equal(ibl__parallel_begin(one, 10, count_task, c), 0);
    ibl_context_desc d = {.parallel_for = host_loop};
    ibl_context *hosted;
    assert_int_equal(ibl_context_create(&d, &hosted), IBL_OK);
    assert_int_equal(ibl__parallel_begin(hosted, 10, count_task, c), 0);
    ibl_context_destroy(hosted);
    ibl_context_destroy(one);
    free(c);
    ibl_context_destroy(two);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(streamed_file_matches_the_encode),
        cmocka_unit_test(failed_write_frees_the_pool),
        cmocka_unit_test(loop_beside_the_caller),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
