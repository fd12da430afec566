/* Our BC6H decoder (src/compress/bc6h_decode.c) against an independent one: Mesa's BPTC
 * decoder, reached the way a renderer reaches it. The blocks are uploaded to llvmpipe as
 * GL_COMPRESSED_RGB_BPTC_UNSIGNED_FLOAT / _SIGNED_FLOAT textures (tests/support/gl_harness.c,
 * headless EGL) and a compute shader reads every texel back with texelFetch. Every texel must
 * be bit-identical: BC6H decodes to half floats, which a float32 holds exactly, and the
 * specification leaves no rounding freedom (Khronos Data Format Specification 1.3, "BC6H":
 * integer interpolation and the fixed final unquantization), so any difference is a bug.
 *  1. random blocks of every mode (ibl_bc6h_test_vectors) covering every partition of every
 *     two-region mode, unsigned and signed;
 *  2. the blocks our encoder makes from the HDRIs of tests/data at every quality. */
#include "test_support.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gl_harness.h"

typedef struct fixture {
    glh_context gl;
    ibl_context *ctx;
    GLuint fetch_program;
} fixture;

/* One invocation per texel: the texel's float RGB, as the sampler returns it, into an SSBO. */
static const char *const FETCH_SHADER =
    "#version 450 core\n"
    "layout(local_size_x = 8, local_size_y = 8) in;\n"
    "layout(binding = 0) uniform sampler2D u_blocks;\n"
    "layout(std430, binding = 0) writeonly buffer Out { vec4 texels[]; };\n"
    "uniform ivec2 u_size;\n"
    "void main() {\n"
    "  ivec2 p = ivec2(gl_GlobalInvocationID.xy);\n"
    "  if (p.x >= u_size.x || p.y >= u_size.y) return;\n"
    "  texels[p.y * u_size.x + p.x] = texelFetch(u_blocks, p, 0);\n"
    "}\n";

static int teardown(void **state);

static int setup(void **state)
{
    fixture *f = calloc(1, sizeof *f);
    char log[4096] = "";
    if (!f) return -1;
    if (glh_create_for_test(&f->gl) != 0) {
        free(f);
        return -1;
    }
    *state = f;
    f->ctx = test_context(0);
    GLenum type = GL_COMPUTE_SHADER;
    f->fetch_program = glh_program(&f->gl, log, sizeof log, 1, &type, &FETCH_SHADER);
    if (!f->fetch_program) {
        print_error("fetch shader: %s\n", log);
        teardown(state);
        *state = NULL; /* cmocka may call the group teardown after a failed setup */
        return -1;
    }
    return 0;
}

static int teardown(void **state)
{
    fixture *f = *state;
    if (!f) return 0;
    if (f->fetch_program) f->gl.gl.DeleteProgram(f->fetch_program);
    glh_destroy(&f->gl);
    ibl_context_destroy(f->ctx);
    free(f);
    return 0;
}

/* Uploads blocks_x * blocks_y blocks (rows of blocks top first, as our encoder writes them)
 * as one BPTC float texture and reads its 16 * blocks texels back as float RGBA. */
static void gpu_decode(fixture *f, int is_signed, const uint8_t *blocks, int blocks_x,
                       int blocks_y, float *rgba)
{
    const glh_gl *gl = &f->gl.gl;
    int w = 4 * blocks_x, h = 4 * blocks_y;
    size_t texels = (size_t)w * (size_t)h;
    GLuint tex, buf;
    gl->GenTextures(1, &tex);
    gl->ActiveTexture(GL_TEXTURE0);
    gl->BindTexture(GL_TEXTURE_2D, tex);
    gl->TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    gl->TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    gl->TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAX_LEVEL, 0);
    GLenum fmt = is_signed ? GL_COMPRESSED_RGB_BPTC_SIGNED_FLOAT
                           : GL_COMPRESSED_RGB_BPTC_UNSIGNED_FLOAT;
    gl->CompressedTexImage2D(GL_TEXTURE_2D, 0, fmt, w, h, 0,
                             (GLsizei)((size_t)blocks_x * (size_t)blocks_y * 16), blocks);
    assert_int_equal(gl->GetError(), GL_NO_ERROR);
    gl->GenBuffers(1, &buf);
    gl->BindBuffer(GL_SHADER_STORAGE_BUFFER, buf);
    gl->BufferData(GL_SHADER_STORAGE_BUFFER, (GLsizeiptr)(texels * 4 * sizeof(float)), NULL,
                   GL_DYNAMIC_READ);
    gl->BindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, buf);
    gl->UseProgram(f->fetch_program);
    gl->Uniform1i(gl->GetUniformLocation(f->fetch_program, "u_blocks"), 0);
    gl->Uniform2i(gl->GetUniformLocation(f->fetch_program, "u_size"), w, h);
    gl->DispatchCompute((GLuint)(w + 7) / 8, (GLuint)(h + 7) / 8, 1);
    gl->MemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    gl->GetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, (GLsizeiptr)(texels * 4 * sizeof(float)),
                         rgba);
    assert_int_equal(gl->GetError(), GL_NO_ERROR);
    gl->UseProgram(0);
    gl->DeleteBuffers(1, &buf);
    gl->DeleteTextures(1, &tex);
}

/* binary16 -> binary32, written here so the comparison does not lean on the library. */
static float half_bits_to_float(uint16_t h)
{
    uint32_t sign = (uint32_t)(h & 0x8000u) << 16, exp = (h >> 10) & 31u, man = h & 1023u, bits;
    if (exp == 31) bits = sign | 0x7F800000u | (man << 13);
    else if (exp != 0) bits = sign | ((exp + 112u) << 23) | (man << 13);
    else if (man == 0) bits = sign;
    else {
        float v = ldexpf((float)man, -24); /* denormal: exact in float */
        memcpy(&bits, &v, 4);
        bits |= sign;
    }
    float out;
    memcpy(&out, &bits, 4);
    return out;
}

static uint32_t float_bits(float v)
{
    uint32_t b;
    memcpy(&b, &v, 4);
    return b;
}

/* Compares the GPU's texels with our halves; block b sits at (b % blocks_x, b / blocks_x).
 * Returns the number of differing channels and prints the first few. */
static long compare_blocks(const uint8_t *blocks, const uint16_t *expected, int count,
                           int blocks_x, const float *gpu, const char *what)
{
    long bad = 0;
    int w = 4 * blocks_x;
    for (int b = 0; b < count; b++) {
        int bx = b % blocks_x, by = b / blocks_x;
        for (int t = 0; t < 16; t++) {
            const float *g = gpu + ((size_t)(4 * by + t / 4) * (size_t)w + (size_t)(4 * bx + t % 4)) * 4;
            for (int c = 0; c < 3; c++) {
                uint16_t want = expected[(size_t)b * 48 + 3 * (size_t)t + (size_t)c];
                if (float_bits(g[c]) == float_bits(half_bits_to_float(want))) continue;
                if (bad++ < 8) {
                    char hex[33];
                    for (int i = 0; i < 16; i++) snprintf(hex + 2 * i, 3, "%02x", blocks[16 * b + i]);
                    print_message("%s: block %d (%s) texel %d channel %d: ours 0x%04x = %g, GL %g\n",
                                  what, b, hex, t, c, want, (double)half_bits_to_float(want),
                                  (double)g[c]);
                }
            }
        }
    }
    return bad;
}

enum { VEC_BLOCKS_X = 128, VEC_BLOCKS_Y = 128, VEC_COUNT = VEC_BLOCKS_X * VEC_BLOCKS_Y };

/* 16384 test vectors per signedness: three in four random blocks cycling through the 14
 * modes (about 880 per mode, so each of the 32 partitions of each two-region mode turns up
 * about 27 times: the coverage is asserted), one in four encoder blocks of HDR gradients. */
static void random_vectors(void **state, int is_signed)
{
    fixture *f = *state;
    uint8_t *blocks = malloc((size_t)VEC_COUNT * 16);
    uint16_t *expected = malloc((size_t)VEC_COUNT * 48 * sizeof *expected);
    float *gpu = malloc((size_t)VEC_COUNT * 16 * 4 * sizeof *gpu);
    assert_true(blocks && expected && gpu);
    ibl_bc6h_test_vectors(is_signed ? 0x5EED5u : 0xB6u, VEC_COUNT, is_signed, blocks, expected);

    int mode_seen[32] = {0}, partition_seen[32][32] = {{0}}, modes = 0, pairs = 0;
    for (int b = 0; b < VEC_COUNT; b++) {
        uint16_t h[48];
        int mode = ibl_bc6h_decode_block(blocks + 16 * b, is_signed, h);
        assert_true(mode >= 0 && mode < 32);
        if (!mode_seen[mode]++) modes++;
        /* two-region modes (0, 1 and numbers ending in binary 10) keep the partition in bits
         * 77..81, just before their indices */
        if (mode < 2 || (mode & 3) == 2) {
            const uint8_t *k = blocks + 16 * b;
            int pb = 0;
            for (int i = 0; i < 5; i++) pb |= ((k[(77 + i) >> 3] >> ((77 + i) & 7)) & 1) << i;
            if (!partition_seen[mode][pb]++) pairs++;
        }
    }
    assert_int_equal(modes, 14);
    assert_int_equal(pairs, 10 * 32);

    gpu_decode(f, is_signed, blocks, VEC_BLOCKS_X, VEC_BLOCKS_Y, gpu);
    long bad = compare_blocks(blocks, expected, VEC_COUNT, VEC_BLOCKS_X, gpu,
                              is_signed ? "signed vectors" : "unsigned vectors");
    print_message("%s: %d blocks, %d modes, %d mode/partition pairs, %ld channels differ\n",
                  is_signed ? "signed" : "unsigned", VEC_COUNT, modes, pairs, bad);
    assert_int_equal(bad, 0);
    /* the comparison can fail: one mantissa bit off in one texel is one difference */
    expected[48 * 7 + 5] ^= 1u;
    assert_int_equal(compare_blocks(blocks, expected, VEC_COUNT, VEC_BLOCKS_X, gpu, "control"), 1);
    free(blocks);
    free(expected);
    free(gpu);
}

static void vectors_unsigned(void **state) { random_vectors(state, 0); }
static void vectors_signed(void **state) { random_vectors(state, 1); }

enum { HDRI_W = 256, HDRI_H = 128 };

/* An HDRI box-filtered to 256 x 128 (the sources are multiples of it); with `negate`, the red
 * channel of every other 8x8 tile is made negative so signed BC6H meets both signs. */
static float *load_hdri(fixture *f, const char *name, int negate)
{
    ibl_image im;
    assert_int_equal(ibl_read_image(f->ctx, test_data(name), NULL, &im, NULL), IBL_OK);
    assert_true(im.width % HDRI_W == 0 && im.height % HDRI_H == 0);
    int fx = im.width / HDRI_W, fy = im.height / HDRI_H;
    float *out = calloc((size_t)HDRI_W * HDRI_H * 4, sizeof *out);
    assert_non_null(out);
    for (int y = 0; y < HDRI_H; y++)
        for (int x = 0; x < HDRI_W; x++) {
            float *o = out + ((size_t)y * HDRI_W + (size_t)x) * 4;
            for (int j = 0; j < fy; j++)
                for (int i = 0; i < fx; i++) {
                    const float *p = ibl_image_texel(&im, x * fx + i, y * fy + j);
                    for (int c = 0; c < 3; c++) o[c] += p[c];
                }
            for (int c = 0; c < 3; c++) o[c] /= (float)(fx * fy);
            if (negate && ((x / 8 + y / 8) & 1)) o[0] = -o[0];
            o[3] = 1.0f;
        }
    ibl_image_free(f->ctx, &im);
    return out;
}

/* The encoder's blocks for the six HDRIs: unsigned at every quality, signed (both signs) at
 * the default quality; 2048 blocks each, 512 for thorough (the 32 rows around the horizon,
 * where the detail is: thorough costs 13x default, too slow for the sanitizer build). */
static void encoder_blocks(void **state)
{
    static const char *const files[] = {"city.exr",  "forest.exr", "interior.exr",
                                        "night.exr", "studio.exr", "sunset.exr"};
    static const struct { int is_signed; ibl_quality q; } runs[] = {
        {0, IBL_QUALITY_FAST}, {0, IBL_QUALITY_DEFAULT}, {0, IBL_QUALITY_THOROUGH},
        {1, IBL_QUALITY_DEFAULT}};
    fixture *f = *state;
    enum { BX = HDRI_W / 4, BY = HDRI_H / 4, COUNT = BX * BY };
    uint8_t *blocks = malloc((size_t)COUNT * 16);
    uint16_t *expected = malloc((size_t)COUNT * 48 * sizeof *expected);
    float *gpu = malloc((size_t)COUNT * 16 * 4 * sizeof *gpu);
    assert_true(blocks && expected && gpu);
    long total_bad = 0;
    int mode_seen[32] = {0}, modes = 0;
    int total_blocks = 0;
    for (size_t i = 0; i < sizeof files / sizeof *files; i++) {
        float *image[2] = {load_hdri(f, files[i], 0), load_hdri(f, files[i], 1)};
        for (size_t r = 0; r < sizeof runs / sizeof *runs; r++) {
            ibl_bc6h_desc d = {runs[r].is_signed, runs[r].q};
            int rows = d.quality == IBL_QUALITY_THOROUGH ? 32 : HDRI_H, count = BX * rows / 4;
            const float *rgba = image[d.is_signed] + (size_t)((HDRI_H - rows) / 2) * HDRI_W * 4;
            assert_int_equal(ibl_bc6h_encode(f->ctx, &d, rgba, HDRI_W, rows, blocks), IBL_OK);
            total_blocks += count;
            for (int b = 0; b < count; b++) {
                int mode = ibl_bc6h_decode_block(blocks + 16 * b, d.is_signed,
                                                 expected + (size_t)b * 48);
                assert_true(mode >= 0);
                if (!mode_seen[mode]++) modes++;
            }
            gpu_decode(f, d.is_signed, blocks, BX, rows / 4, gpu);
            char what[96];
            snprintf(what, sizeof what, "%s %s %s", files[i], d.is_signed ? "signed" : "unsigned",
                     ibl_quality_name(d.quality));
            total_bad += compare_blocks(blocks, expected, count, BX, gpu, what);
        }
        free(image[0]);
        free(image[1]);
    }
    print_message("encoder blocks: 6 HDRIs x 4 runs, %d blocks, %d modes used, %ld channels differ\n",
                  total_blocks, modes, total_bad);
    assert_int_equal(total_bad, 0);
    free(blocks);
    free(expected);
    free(gpu);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(vectors_unsigned),
        cmocka_unit_test(vectors_signed),
        cmocka_unit_test(encoder_blocks),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
