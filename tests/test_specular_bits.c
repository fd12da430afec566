/* The fast prefilter's exact output, pinned: FNV-1a 64 hashes of the output floats of a handful
 * of chains, for the AVX2 kernels and for the portable ones (a context created with
 * IBL_KERNELS_PORTABLE), on one and two threads.
 *
 * Why: a refactoring of src/bake/specular/ must not change a single bit of the output (the
 * library is also bit-identical at any thread count), and the accuracy tests elsewhere would
 * let small changes through. A deliberate change of the algorithm updates these hashes in the
 * same commit and says so in its message.
 *
 * The hashes hold on x86-64 with glibc (the portable path reads libm's powf, the AVX2 path
 * needs AVX2, FMA and F16C), on any vendor's CPU: the kernels use no instruction whose bits
 * are the vendor's own (the reciprocal estimates: vrcpps made the GGX chains' AVX2 hashes
 * differ between AMD and Intel); elsewhere the test is skipped. The chains of size 32 also run on
 * one thread (same hash), the others on two only, to keep the test under a few seconds. The
 * chains cover every mechanism of the method: precomputed pieces over the source texels and
 * over coarse levels with centroid corrections, rings whose bright texels go apart, sub-texels
 * (a narrow Phong lobe at 32), bent and warped output directions (leaf sums at the output
 * texels), mirror levels, Phong cores and corrections on Lagrange grids (blinn 128), and the
 * dynamic plan. The sources are the test HDRIs converted to
 * cubes by the library; their hashes are pinned too, so that a change of the reader or the
 * conversion is told apart from a change of the prefilter. */
#include "test_support.h"
#include "bake/specular_internal.h"
#include "core/cpu.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct pinned_chain {
    const char *file;
    ibl_specular_filter filter;
    int size, mirror;
    ibl_edge_fixup fixup;
    int dynamic;           /* a dynamic plan from a source of twice the size        */
    int one_thread_too;    /* also on one thread (the others: two threads only)     */
    uint64_t source;       /* the source cube                                       */
    uint64_t avx2, portable; /* the dynamic plan's two kernels add in one order: equal */
} pinned_chain;

static const pinned_chain chains[] = {
    {"city.exr", IBL_FILTER_GGX, 64, 0, IBL_EDGE_FIXUP_NONE, 0, 0,
     0x67ea18478f45e63eull, 0x5da7fc193724f94bull, 0x93e63c488e2a1417ull},
    {"city.exr", IBL_FILTER_GGX, 128, 0, IBL_EDGE_FIXUP_NONE, 0, 0,
     0x9a7bd9f7e6694e82ull, 0x159a4a767e8db737ull, 0xa74ce481f1f0d240ull},
    {"interior.exr", IBL_FILTER_PHONG, 64, 0, IBL_EDGE_FIXUP_NONE, 0, 0,
     0xda9a9b27c316ca07ull, 0xfda523664ac54e16ull, 0xc1d17ea8f5fb3cb6ull},
    {"night.exr", IBL_FILTER_PHONG, 32, 1, IBL_EDGE_FIXUP_BENT, 0, 1,
     0x723c896457523649ull, 0x2b1f3cf1bec93719ull, 0xff94215e5d27d521ull},
    {"studio.exr", IBL_FILTER_BLINN, 32, 0, IBL_EDGE_FIXUP_WARP, 0, 1,
     0xd697ad19261a4477ull, 0xd64b2e3c55e3c6d6ull, 0xd44a9937c2e1dd9dull},
    {"sunset.exr", IBL_FILTER_BLINN, 32, 1, IBL_EDGE_FIXUP_NONE, 0, 1,
     0xaeea2e21cc77c6b6ull, 0xdac4a80733fdedcaull, 0x6b937715c945a165ull},
    /* level 0 (exponent 238, 6.7 texels a half width): core and corrections on Lagrange grids */
    {"forest.exr", IBL_FILTER_BLINN, 128, 0, IBL_EDGE_FIXUP_NONE, 0, 0,
     0xe4deff29119d2a9full, 0x8c47e54cb987566cull, 0x6ae0c744451e9e26ull},
    {"city.exr", IBL_FILTER_PHONG, 16, 0, IBL_EDGE_FIXUP_NONE, 1, 0,
     0x4f87c6f03eaa0d3aull, 0x043e2e901978e65aull, 0x043e2e901978e65aull},
};

/* The chain's output hash on a context made from cd, by ibl_specular_prefilter or (a dynamic
 * chain, or `reusable`) a plan made and run once. */
static uint64_t hash_on(const pinned_chain *c, const ibl_cubemap *src, ibl_context_desc cd,
                        int reusable)
{
    ibl_context *ctx = NULL;
    assert_int_equal(ibl_context_create(&cd, &ctx), IBL_OK);
    ibl_specular_desc d = {0};
    d.filter = c->filter;
    d.size = c->size;
    d.mirror = c->mirror;
    d.edge_fixup = c->fixup;
    ibl_cubemap out = {0};
    if (c->dynamic || reusable) {
        d.dynamic = c->dynamic;
        d.source_size = src->size;
        ibl_specular_plan *plan = NULL;
        assert_int_equal(ibl_specular_plan_create(ctx, &d, &plan), IBL_OK);
        assert_int_equal(ibl_cubemap_alloc(ctx, c->size, ibl_specular_plan_info(plan)->levels, &out), IBL_OK);
        assert_int_equal(ibl_specular_plan_run(plan, src, &out), IBL_OK);
        ibl_specular_plan_destroy(plan);
    } else {
        assert_int_equal(ibl_specular_prefilter(ctx, src, &d, &out, NULL), IBL_OK);
    }
    uint64_t h = test_fnv1a(out.data, ibl_cubemap_floats(c->size, out.levels) * sizeof(float));
    ibl_cubemap_free(ctx, &out);
    ibl_context_destroy(ctx);
    return h;
}

/* The chain's output hash on a context with these threads and kernels. */
static uint64_t chain_hash(const pinned_chain *c, const ibl_cubemap *src, int threads,
                           ibl_kernels kernels)
{
    return hash_on(c, src, (ibl_context_desc){.threads = threads, .kernels = kernels}, 0);
}

static void check(const char *what, const pinned_chain *c, uint64_t got, uint64_t want, int verbose)
{
    if (verbose || got != want)
        printf("  %s %s %s %d%s%s%s: %016llx (pinned %016llx)\n", what, c->file,
               ibl_specular_filter_name(c->filter), c->size, c->mirror ? " mirror" : "",
               c->fixup == IBL_EDGE_FIXUP_BENT ? " bent" : c->fixup == IBL_EDGE_FIXUP_WARP ? " warp" : "",
               c->dynamic ? " dynamic" : "", (unsigned long long)got, (unsigned long long)want);
    assert_true(got == want);
}

static void pinned_outputs(void **state)
{
    (void)state;
#if !defined(__x86_64__)
    skip();
#else
    int verbose = getenv("IBL_TEST_VERBOSE") != NULL;
    int avx2 = ibl__cpu_has(NULL, IBL__CPU_AVX2_FMA | IBL__CPU_F16C);
    if (!avx2) printf("  no AVX2 + FMA + F16C: the portable hashes only\n");
    ibl_context *ctx = test_context(2);
    for (size_t i = 0; i < sizeof chains / sizeof chains[0]; i++) {
        const pinned_chain *c = &chains[i];
        ibl_image image;
        assert_int_equal(ibl_read_image(ctx, test_data(c->file), NULL, &image, NULL), IBL_OK);
        ibl_cubemap src;
        int source_size = c->dynamic ? 2 * c->size : c->size;
        assert_int_equal(ibl_image_to_cubemap(ctx, &image, &(ibl_to_cube_desc){.size = source_size}, &src), IBL_OK);
        check("source", c, test_fnv1a(src.data, ibl_cubemap_floats(source_size, 1) * sizeof(float)), c->source, verbose);
        for (int threads = c->one_thread_too ? 1 : 2; threads <= 2; threads++) {
            if (avx2) check("avx2", c, chain_hash(c, &src, threads, IBL_KERNELS_AUTO), c->avx2, verbose);
            if (!c->dynamic || !avx2)
                check("portable", c, chain_hash(c, &src, threads, IBL_KERNELS_PORTABLE), c->portable, verbose);
        }
        ibl_cubemap_free(ctx, &src);
        ibl_image_free(ctx, &image);
    }
    ibl_context_destroy(ctx);
#endif
}

/* A reusable plan's run of chain c on a context of `threads`, on the library's pool or (host)
 * on a host's parallel_for that runs every loop on that many threads of its own. */
static uint64_t plan_hash(const pinned_chain *c, const ibl_cubemap *src, int threads, int host)
{
    test_host h = {.threads = threads};
    ibl_context_desc cd = {.threads = threads};
    if (host) cd.parallel_for = test_host_parallel_for, cd.parallel_host = &h;
    return hash_on(c, src, cd, 1);
}

/* The products of a piece whose weights the plan holds run a face a task when the threads
 * divide the six faces (each face padded in a buffer of its thread's), its rows a loop of their
 * own on the library's pool and in turn on a host's parallel_for, and face by face over all
 * threads otherwise: the GGX 128 chain is the pinned one at every such count, on either. */
static void face_tasks_at_any_thread_count(void **state)
{
    (void)state;
#if !defined(__x86_64__)
    skip();
#else
    const pinned_chain *c = &chains[1];
    uint64_t want = ibl__cpu_has(NULL, IBL__CPU_AVX2_FMA | IBL__CPU_F16C) ? c->avx2 : c->portable;
    ibl_context *ctx = test_context(1);
    ibl_image image;
    assert_int_equal(ibl_read_image(ctx, test_data(c->file), NULL, &image, NULL), IBL_OK);
    ibl_cubemap src;
    assert_int_equal(ibl_image_to_cubemap(ctx, &image, &(ibl_to_cube_desc){.size = 128}, &src), IBL_OK);
    static const int counts[] = {1, 2, 3, 4, 6};
    for (int i = 0; i < 5; i++) check("pool", c, plan_hash(c, &src, counts[i], 0), want, 0);
    for (int threads = 2; threads <= 3; threads++) check("host", c, plan_hash(c, &src, threads, 1), want, 0);
    ibl_cubemap_free(ctx, &src);
    ibl_image_free(ctx, &image);
    ibl_context_destroy(ctx);
#endif
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(pinned_outputs),
        cmocka_unit_test(face_tasks_at_any_thread_count),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
