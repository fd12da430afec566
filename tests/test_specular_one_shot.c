/* The one-shot plan of ibl_specular_prefilter (src/bake/specular_internal.h): the same bits as a
 * reusable plan, in less memory.
 *
 * A one-shot plan keeps the geometric fields of the coarse levels only the run's pyramid reads
 * apart (face-local, once for all six faces), makes those levels' records during the run and
 * frees them as the pyramid goes (the first of them made block row by block row with the next
 * one, never whole: pyramid.c, ibl__fast_pyramid_streamed; the GGX 128 and 64 cases below
 * take that path, with centroid corrections made again from the source), finds its
 * precomputed normalisers without keeping the weights, makes the weights again just before
 * their products (batch by batch of base rows where they outweigh the six padded faces: the
 * triace case below), and frees everything but the grids before the output is allocated. A reusable plan (ibl_specular_plan_create) keeps its
 * weights and its records, and its runs allocate nothing. Both must give the output bit for
 * bit: compared here on chains that use every mechanism the one-shot plan changes (precomputed
 * pieces over the source and over coarse levels with centroid corrections, bright texels
 * gathered from coarse levels, leaf sums over kept levels, sub-texels, Lagrange grids, a
 * mirror level smaller than the source read from the pyramid), and a reusable plan's second
 * run against its first (neither allocates). test_specular_bits pins the same outputs' hashes
 * from before these mechanisms existed. */
#include "test_support.h"
#include "bake/specular_internal.h"

#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct chain_case {
    const char *file;
    ibl_specular_filter filter;
    int size, mirror;
    ibl_edge_fixup fixup;
    ibl_specular_mapping mapping;
    const float *table; /* IBL_MAPPING_TABLE: a shininess a level */
    int table_count;
} chain_case;

/* cmft's default exponents, 2^(10 (1 - l/(L-1)) + 1) + 1, over the 8 levels of a 128 chain and
 * the 9 of a 256 one: level 0 a narrow Phong core on the output texels, whose normalisers a
 * one-shot plan finds at the run, and whose grid it makes after the geometry of the weights */
static const float cmft_128[] = {2049, 761.829f, 283.647f, 106.003f, 40.0084f, 15.4916f, 6.3836f, 3};
static const float cmft_256[] = {2049, 862.078f, 363.039f, 153.219f, 65, 27.9087f, 12.3137f, 5.75683f, 3};

static const chain_case cases[] = {
    /* corrections, bright texels */
    {"city.exr", IBL_FILTER_GGX, 128, 0, IBL_EDGE_FIXUP_NONE, IBL_MAPPING_DEFAULT, NULL, 0},
    /* mirror level from the pyramid */
    {"city.exr", IBL_FILTER_GGX, 64, 1, IBL_EDGE_FIXUP_NONE, IBL_MAPPING_DEFAULT, NULL, 0},
    /* Lagrange grids */
    {"forest.exr", IBL_FILTER_BLINN, 64, 0, IBL_EDGE_FIXUP_NONE, IBL_MAPPING_DEFAULT, NULL, 0},
    /* sub-texels, leaf sums */
    {"night.exr", IBL_FILTER_PHONG, 32, 1, IBL_EDGE_FIXUP_BENT, IBL_MAPPING_DEFAULT, NULL, 0},
    /* level 0's core at ~4.5 texels a half width: its weights outweigh the six padded faces,
     * so the one-shot plan makes them batch by batch of base rows (products.c) */
    {"city.exr", IBL_FILTER_GGX, 128, 0, IBL_EDGE_FIXUP_NONE, IBL_MAPPING_TRIACE, NULL, 0},
    /* normalisers at the run, on the output texels and on Lagrange grids */
    {"city.exr", IBL_FILTER_PHONG, 128, 0, IBL_EDGE_FIXUP_NONE, IBL_MAPPING_TABLE, cmft_128, 8},
};

/* The source cube the prefilter itself would use for this chain from an input of edge
 * source_size (the edge it needs, at most that), so that a reusable plan gets the same one. */
static void read_source(ibl_context *ctx, const chain_case *c, const ibl_specular_desc *d, int source_size,
                        ibl_cubemap *src)
{
    ibl_image image;
    assert_int_equal(ibl_read_image(ctx, test_data(c->file), NULL, &image, NULL), IBL_OK);
    int edge = 0;
    assert_int_equal(ibl_specular_source_size(ctx, d, source_size, &edge), IBL_OK);
    assert_int_equal(ibl_image_to_cubemap(ctx, &image, &(ibl_to_cube_desc){.size = edge}, src), IBL_OK);
    ibl_image_free(ctx, &image);
}

static ibl_specular_desc case_desc(const chain_case *c)
{
    ibl_specular_desc d = {0};
    d.filter = c->filter;
    d.size = c->size;
    d.mirror = c->mirror;
    d.edge_fixup = c->fixup;
    d.mapping = c->mapping;
    d.table = c->table;
    d.table_count = c->table_count;
    return d;
}

static uint64_t chain_hash(const ibl_cubemap *out)
{
    return test_fnv1a(out->data, ibl_cubemap_floats(out->size, out->levels) * sizeof(float));
}

/* An allocator that counts its calls: a reusable plan's runs allocate nothing. */
static void *count_alloc(size_t bytes, void *user)
{
    atomic_fetch_add((atomic_long *)user, 1);
    return malloc(bytes);
}

static void count_free(void *ptr, void *user)
{
    (void)user;
    free(ptr);
}

static void one_shot_matches_reusable_plan(void **state)
{
    (void)state;
    atomic_long allocs;
    atomic_init(&allocs, 0);
    ibl_context_desc cd = {0};
    cd.threads = 2;
    cd.allocator = (ibl_allocator){count_alloc, count_free, &allocs};
    ibl_context *ctx = NULL;
    assert_int_equal(ibl_context_create(&cd, &ctx), IBL_OK);
    ibl__specular_stats used = {0}; /* over the cases: what they exercised */
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        const chain_case *c = &cases[i];
        ibl_specular_desc d = case_desc(c);
        ibl_cubemap src, once = {0}, reused = {0};
        read_source(ctx, c, &d, 256, &src);
        assert_int_equal(ibl_specular_prefilter(ctx, &src, &d, &once, NULL), IBL_OK);

        d.source_size = src.size;
        d.levels = once.levels;
        ibl_specular_plan *plan = NULL;
        ibl_status st = ibl_specular_plan_create(ctx, &d, &plan);
        if (st != IBL_OK) printf("  %s\n", ibl_context_message(ctx));
        assert_int_equal(st, IBL_OK);
        assert_int_equal(ibl_cubemap_alloc(ctx, c->size, once.levels, &reused), IBL_OK);
        long before = atomic_load(&allocs);
        assert_int_equal(ibl_specular_plan_run(plan, &src, &reused), IBL_OK);
        uint64_t first = chain_hash(&reused);
        memset(reused.data, 0, ibl_cubemap_floats(c->size, reused.levels) * sizeof(float));
        assert_int_equal(ibl_specular_plan_run(plan, &src, &reused), IBL_OK);
        uint64_t second = chain_hash(&reused);
        assert_int_equal(atomic_load(&allocs), before);
        ibl__specular_stats stats;
        ibl__specular_plan_stats(plan, &stats);
        used.precomputed_coarse += stats.precomputed_coarse;
        used.correction_blocks += stats.correction_blocks;
        used.bright_blocks += stats.bright_blocks;
        used.pieces += stats.pieces - stats.precomputed; /* summed by leaves */
        ibl_specular_plan_destroy(plan);

        uint64_t one_shot = chain_hash(&once);
        if (one_shot != first || first != second)
            printf("  %s %s %d: one-shot %016llx, plan %016llx then %016llx\n", c->file,
                   ibl_specular_filter_name(c->filter), c->size, (unsigned long long)one_shot,
                   (unsigned long long)first, (unsigned long long)second);
        assert_true(one_shot == first);
        assert_true(first == second);
        ibl_cubemap_free(ctx, &once);
        ibl_cubemap_free(ctx, &reused);
        ibl_cubemap_free(ctx, &src);
    }
    assert_true(used.precomputed_coarse > 0 && used.correction_blocks > 0);
    assert_true(used.bright_blocks > 0 && used.pieces > 0);
    ibl_context_destroy(ctx);
}

/* The budget's peak of one call (its context made for it): the prefilter, or a reusable plan
 * made and run once into a chain allocated first (what a caller of the plan API does). */
static uint64_t peak_bytes(const ibl_cubemap *src, const ibl_specular_desc *desc, int one_shot)
{
    ibl_context *ctx = test_context(2);
    ibl_cubemap out = {0};
    ibl_specular_desc d = *desc;
    if (one_shot) {
        assert_int_equal(ibl_specular_prefilter(ctx, src, &d, &out, NULL), IBL_OK);
    } else {
        d.source_size = src->size;
        ibl_specular_plan *plan = NULL;
        assert_int_equal(ibl_specular_plan_create(ctx, &d, &plan), IBL_OK);
        assert_int_equal(ibl_cubemap_alloc(ctx, d.size, ibl_specular_plan_info(plan)->levels, &out), IBL_OK);
        assert_int_equal(ibl_specular_plan_run(plan, src, &out), IBL_OK);
        ibl_specular_plan_destroy(plan);
    }
    uint64_t peak = ibl_context_peak_bytes(ctx);
    ibl_cubemap_free(ctx, &out);
    ibl_context_destroy(ctx);
    return peak;
}

/* The 256 GGX chain from city.exr on a 256 source, on two threads. Measured: the reusable plan
 * peaks at 48.9 MB (every coarse level's records next to every piece's weights and the chain),
 * the one-shot prefilter at 18.7 MB (0.38). The bar, 0.8 of the reusable plan's peak, fails if
 * the one-shot plan comes to hold its weights or its pyramid's records through the run again.
 * And a bar of its own, on the count (exact: the blocks' sizes, the same at every run): the
 * command `ibl prefilter city.exr --size 256` peaks at 35-39 MB of RSS (docs/PERFORMANCE.md
 * "At large sizes"), under its bound of 3 x (the 1024x512 image in float RGBA + the chain in
 * float RGBA) = 50 MB: this count plus the source cube (6.3 MB), the process (5.5 MB: `ibl
 * --version`) and what the CLI's arena keeps in 2 MiB pages shared by live blocks and free
 * ones. The count may grow by 0.9 MB at most: 19.6 MB, which fails if the run comes to hold
 * one more buffer of that size at its peak (the padded faces, one a thread, beside the weights
 * or the geometry they are made from, for one). (The RSS also depends on where the arena puts
 * the blocks; cli/arena.c and test_cli_arena keep that part.) */
/* The peaks of case c's chain from city.exr on a 256 source: the one-shot prefilter's and, when
 * reusable is not NULL, a reusable plan's. */
static uint64_t peaks_of(const chain_case *c, uint64_t *reusable)
{
    ibl_context *ctx = test_context(1);
    ibl_specular_desc d = case_desc(c);
    ibl_cubemap src;
    read_source(ctx, c, &d, c->size, &src);
    assert_int_equal(src.size, 256);
    if (reusable) *reusable = peak_bytes(&src, &d, 0);
    uint64_t once = peak_bytes(&src, &d, 1);
    ibl_cubemap_free(ctx, &src);
    ibl_context_destroy(ctx);
    return once;
}

static void one_shot_peak_is_lower(void **state)
{
    (void)state;
    chain_case c = {"city.exr", IBL_FILTER_GGX, 256, 0, IBL_EDGE_FIXUP_NONE, IBL_MAPPING_DEFAULT, NULL, 0};
    uint64_t reusable = 0, once = peaks_of(&c, &reusable);
    printf("  256 GGX chain: reusable plan peak %.3f MB, one-shot %.3f MB\n", reusable / 1e6,
           once / 1e6);
    assert_true((double)once < 0.8 * (double)reusable);
    assert_true(once <= 19600000u);
}

/* The Phong chain with cmft's exponents at 256 (on two threads, as above): the chain of that
 * size that holds the most, its peak in level 0's products (the core's weights over the source
 * texels, 7.2 MB, the level's grids, 8.3 MB, with one padded face a thread). Measured: 27.9 MB.
 * Its command peaks at 44-47 MB of RSS (docs/PERFORMANCE.md "The Phong family against GGX"),
 * under the same 50 MB bound; the bar, 1.6 MB more, is what keeps it there. It fails if the
 * level's grids are made before the weights' geometry is freed (30.3 MB), or if the plan keeps
 * every level's grids through the run (32.9 MB). */
static void cmft_chain_peak(void **state)
{
    (void)state;
    chain_case c = {"city.exr", IBL_FILTER_PHONG, 256, 0, IBL_EDGE_FIXUP_NONE, IBL_MAPPING_TABLE, cmft_256, 9};
    uint64_t once = peaks_of(&c, NULL);
    printf("  256 Phong chain, cmft's exponents: one-shot %.3f MB\n", once / 1e6);
    assert_true(once <= 29500000u);
}

/* Under any memory budget the one-shot prefilter either makes the chain it makes without one
 * or fails with IBL_ERR_TOO_LARGE and holds nothing after: budgets from a twelfth of its peak
 * to twice the peak, on a chain with Lagrange grids (whose bordered copies the one-shot plan
 * makes only for the level's combine, after the run's buffers are freed) and on the GGX 128
 * chain (padded faces a level, one a thread where that keeps under the peak so far; the
 * corrections' records made as they are gathered). A plan whose weights would take more than
 * half of what the budget leaves sums those pieces as leaves instead (a different chain): on
 * these two, a budget that small is too small for the leaves as well (at the peak itself the
 * GGX 128 chain is refused that way), so every chain made is the same. */
static void one_shot_under_any_budget(void **state)
{
    (void)state;
    static const size_t picks[2] = {2, 0};
    ibl_context *io = test_context(1);
    for (int i = 0; i < 2; i++) {
        const chain_case *c = &cases[picks[i]];
        ibl_specular_desc d = case_desc(c);
        ibl_cubemap src, out = {0};
        read_source(io, c, &d, 256, &src);
        ibl_context *ctx = test_context(2);
        assert_int_equal(ibl_specular_prefilter(ctx, &src, &d, &out, NULL), IBL_OK);
        uint64_t want = chain_hash(&out), peak = ibl_context_peak_bytes(ctx);
        ibl_cubemap_free(ctx, &out);
        ibl_context_destroy(ctx);
        int made = 0, refused = 0;
        for (int k = 1; k <= 24; k++) {
            ibl_context_desc cd = {.threads = 2, .max_bytes = peak * (uint64_t)k / 12};
            assert_int_equal(ibl_context_create(&cd, &ctx), IBL_OK);
            ibl_cubemap o = {0};
            ibl_status st = ibl_specular_prefilter(ctx, &src, &d, &o, NULL);
            if (st == IBL_OK) {
                assert_true(chain_hash(&o) == want);
                ibl_cubemap_free(ctx, &o);
                made++;
            } else {
                assert_int_equal(st, IBL_ERR_TOO_LARGE);
                assert_non_null(strstr(ibl_context_message(ctx), "memory budget"));
                assert_null(o.data);
                refused++;
            }
            assert_int_equal(ibl_context_current_bytes(ctx), 0);
            ibl_context_destroy(ctx);
        }
        assert_true(made >= 1 && refused >= 1); /* twice the peak makes it, a twelfth does not */
        ibl_cubemap_free(io, &src);
    }
    ibl_context_destroy(io);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(one_shot_matches_reusable_plan),
        cmocka_unit_test(one_shot_peak_is_lower),
        cmocka_unit_test(cmft_chain_peak),
        cmocka_unit_test(one_shot_under_any_budget),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
