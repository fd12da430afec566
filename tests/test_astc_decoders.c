/* The ASTC decoders a context keeps from one ibl_astc_decode to the next
 * (src/compress/astc.c): reused decoders give the texels a fresh astcenc context gives, for
 * every footprint in any order, when one context decodes on several threads at once (the
 * built-in pool's, a host's parallel-for running bands and whole decodes on threads of its
 * own), their memory is counted in the budget, a budget too small
 * for one is refused with the budget's message, and the sanitizer build's leak check sees
 * them all freed by ibl_context_destroy. Also: ASTC HDR and BC6H decode to half floats
 * exactly (what `ibl view` relies on). */
#include "test_support.h"

#include "core/pixel_format.h"

#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

static const uint64_t MiB = 1024 * 1024;
/* astc.c's estimate per decoder, as documented in include/ibl/compress.h */
static const uint64_t DECODER_BYTES = 10 * 1024 * 1024;

static const int footprints[8][2] = {{4, 4}, {5, 4}, {5, 5}, {6, 5}, {6, 6}, {8, 5}, {8, 6}, {8, 8}};
/* 19 rows of 4x4 blocks: three bands of eight block rows at 4x4, two at 8x8; odd sizes pad */
enum { W = 70, H = 75, TEXELS = W * H };

typedef struct case_data {
    uint8_t *blocks[8];
    float *fresh[8]; /* decoded with no context: a new astcenc context per band */
} case_data;

/* An HDR image with structure at every scale (values from 2^-6 to 2^9). */
static float *test_image(void)
{
    float *img = malloc((size_t)TEXELS * 16);
    assert_non_null(img);
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            float *t = img + ((size_t)y * W + (size_t)x) * 4;
            float e = (float)((x * 7 + y * 3) % 16) - 6.0f;
            t[0] = exp2f(e) * (1.0f + 0.3f * sinf((float)x * 0.37f));
            t[1] = exp2f(e * 0.5f) * (1.0f + 0.5f * cosf((float)y * 0.21f));
            t[2] = (float)((x ^ y) & 15) * 0.25f + 0.01f;
            t[3] = 1.0f;
        }
    return img;
}

static case_data *make_cases(void)
{
    case_data *c = calloc(1, sizeof *c);
    float *img = test_image();
    for (int f = 0; f < 8; f++) {
        ibl_astc_desc d = {footprints[f][0], footprints[f][1], IBL_QUALITY_FAST};
        c->blocks[f] = malloc(ibl_astc_bytes(d.block_width, d.block_height, W, H));
        c->fresh[f] = malloc((size_t)TEXELS * 16);
        assert_int_equal(ibl_astc_encode(NULL, &d, img, W, H, c->blocks[f]), IBL_OK);
        assert_int_equal(ibl_astc_decode(NULL, &d, c->blocks[f], W, H, c->fresh[f]), IBL_OK);
    }
    free(img);
    return c;
}

static void free_cases(case_data *c)
{
    for (int f = 0; f < 8; f++) {
        free(c->blocks[f]);
        free(c->fresh[f]);
    }
    free(c);
}

/* Decodes footprint f with ctx: 1 when it succeeds with the texels of a fresh context, bit
 * for bit. Called on the host's threads too, where cmocka's asserts cannot be used. */
static int decodes_as_fresh(ibl_context *ctx, const case_data *c, int f)
{
    ibl_astc_desc d = {footprints[f][0], footprints[f][1], IBL_QUALITY_DEFAULT};
    float *out = malloc((size_t)TEXELS * 16);
    if (!out) return 0;
    memset(out, 0xff, (size_t)TEXELS * 16); /* NaNs: a texel left unwritten would show */
    int same = ibl_astc_decode(ctx, &d, c->blocks[f], W, H, out) == IBL_OK &&
               memcmp(out, c->fresh[f], (size_t)TEXELS * 16) == 0;
    free(out);
    return same;
}

static void decode_and_compare(ibl_context *ctx, const case_data *c, int f)
{
    if (!decodes_as_fresh(ctx, c, f))
        fail_msg("%dx%d: the context's decoders differ from a fresh one (%s)", footprints[f][0],
                 footprints[f][1], ibl_context_message(ctx));
}

/* Every footprint twice, forwards then backwards, on one context of `threads` threads: a
 * reused decoder must give what a new one gives, and the held bytes must stay at one
 * decoder per footprint and band decoded at once (never more than the threads). */
static void reuse_matches_fresh(void **state)
{
    case_data *c = *state;
    for (int threads = 1; threads <= 3; threads += 2) {
        ibl_context *ctx = test_context(threads);
        for (int round = 0; round < 2; round++)
            for (int i = 0; i < 8; i++) decode_and_compare(ctx, c, round ? 7 - i : i);
        uint64_t held = ibl_context_current_bytes(ctx);
        print_message("%d thread(s): %.1f MiB held after 16 decodes\n", threads, (double)held / (double)MiB);
        assert_true(held >= 8 * DECODER_BYTES);                     /* at least one per footprint */
        assert_true(held <= 8 * (uint64_t)threads * DECODER_BYTES + MiB); /* + the list itself */
        for (int i = 0; i < 8; i++) decode_and_compare(ctx, c, i);
        /* on one thread every decoder is reused and none is built; on more, a footprint whose
         * bands first overlap in this round may build one more, never past the bound */
        if (threads == 1) assert_int_equal(ibl_context_current_bytes(ctx), held);
        assert_true(ibl_context_current_bytes(ctx) <= 8 * (uint64_t)threads * DECODER_BYTES + MiB);
        ibl_context_destroy(ctx);
    }
}

typedef struct nested_job {
    ibl_context *ctx;
    const case_data *c;
    atomic_int failures;
} nested_job;

/* Task i of the outer parallel-for: footprint i % 8, its bands on the same parallel-for. */
static void nested_decode(void *arg, int i)
{
    nested_job *j = arg;
    if (!decodes_as_fresh(j->ctx, j->c, i % 8)) atomic_fetch_add(&j->failures, 1);
}

/* A host's parallel-for runs 32 decodes four at a time, each decode's bands four at a time on
 * threads of their own: the context's first decodes race to create the list of idle decoders,
 * and bands of several decodes take and give back decoders of one footprint at once. (The
 * built-in pool runs one parallel-for at a time: a context is used by one host thread.) */
static void shared_by_threads(void **state)
{
    case_data *c = *state;
    ibl_context_desc desc = {0};
    test_host host = {.threads = 4};
    desc.parallel_for = test_host_parallel_for;
    desc.parallel_host = &host;
    ibl_context *ctx = NULL;
    assert_int_equal(ibl_context_create(&desc, &ctx), IBL_OK);
    nested_job j = {ctx, c, 0};
    ibl_parallel_for(ctx, 32, nested_decode, &j);
    if (atomic_load(&j.failures)) fail_msg("%d of 32 decodes differ from a fresh context's", atomic_load(&j.failures));
    /* at most four decodes x four bands at once per footprint */
    assert_true(ibl_context_current_bytes(ctx) <= 8 * 16 * DECODER_BYTES + MiB);
    for (int i = 0; i < 8; i++) decode_and_compare(ctx, c, i); /* and single decodes after */
    ibl_context_destroy(ctx);
}

/* A decoder does not fit a 6 MiB budget: the decode fails with the budget's message and
 * leaves nothing counted; within a budget that holds one, the same call succeeds. */
static void budget_counts_decoders(void **state)
{
    case_data *c = *state;
    ibl_context_desc desc = {0};
    desc.threads = 1;
    desc.max_bytes = 6 * MiB;
    ibl_context *ctx = NULL;
    assert_int_equal(ibl_context_create(&desc, &ctx), IBL_OK);
    ibl_astc_desc d = {4, 4, IBL_QUALITY_DEFAULT};
    float *out = malloc((size_t)TEXELS * 16);
    assert_int_equal(ibl_astc_decode(ctx, &d, c->blocks[0], W, H, out), IBL_ERR_TOO_LARGE);
    assert_non_null(strstr(ibl_context_message(ctx), "over the memory budget of 6.0 MiB"));
    uint64_t list = ibl_context_current_bytes(ctx); /* the (empty) list of idle decoders */
    assert_true(list < MiB);
    ibl_context_destroy(ctx);
    desc.max_bytes = 12 * MiB;
    assert_int_equal(ibl_context_create(&desc, &ctx), IBL_OK);
    assert_int_equal(ibl_astc_decode(ctx, &d, c->blocks[0], W, H, out), IBL_OK);
    assert_memory_equal(out, c->fresh[0], (size_t)TEXELS * 16);
    assert_int_equal(ibl_context_current_bytes(ctx), list + DECODER_BYTES);
    /* a second footprint needs a second decoder, which the budget cannot hold */
    ibl_astc_desc d88 = {8, 8, IBL_QUALITY_DEFAULT};
    assert_int_equal(ibl_astc_decode(ctx, &d88, c->blocks[7], W, H, out), IBL_ERR_TOO_LARGE);
    ibl_context_destroy(ctx);
    free(out);
}

/* Every decoded value is a half float: ASTC HDR and BC6H decode to 16-bit floats (Khronos
 * Data Format Specification 1.3, "ASTC Compressed Texture Image Formats", HDR endpoint
 * decoding and "BC6H"), which the library returns as floats. `ibl view` embeds a compressed
 * bake's decoded chain as half floats (cli/viewer_html.c) and docs/VIEWER.md says that this
 * is lossless, i.e. what a GPU sampling the blocks would read: checked here bit for bit. */
static int all_halves(const float *v, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        float back = ibl_half_to_float(ibl_float_to_half(v[i]));
        if (memcmp(&back, &v[i], sizeof back) != 0) return 0;
    }
    return 1;
}

static void decoded_values_are_halves(void **state)
{
    case_data *c = *state;
    for (int f = 0; f < 8; f++)
        if (!all_halves(c->fresh[f], (size_t)TEXELS * 4))
            fail_msg("ASTC %dx%d decodes to a value that is not a half float", footprints[f][0], footprints[f][1]);
    float *img = test_image(), *back = malloc((size_t)TEXELS * 16);
    uint8_t *blocks = malloc(ibl_bc6h_bytes(W, H));
    ibl_bc6h_desc d = {0, IBL_QUALITY_FAST};
    assert_int_equal(ibl_bc6h_encode(NULL, &d, img, W, H, blocks), IBL_OK);
    assert_int_equal(ibl_bc6h_decode(NULL, 0, blocks, W, H, back), IBL_OK);
    assert_true(all_halves(back, (size_t)TEXELS * 4));
    /* the check can fail: the image itself holds values that are not halves */
    assert_false(all_halves(img, (size_t)TEXELS * 4));
    free(blocks);
    free(back);
    free(img);
}

static int setup(void **state)
{
    *state = make_cases();
    return 0;
}

static int teardown(void **state)
{
    free_cases(*state);
    return 0;
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(reuse_matches_fresh),
        cmocka_unit_test(shared_by_threads),
        cmocka_unit_test(budget_counts_decoders),
        cmocka_unit_test(decoded_values_are_halves),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
