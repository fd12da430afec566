/* shaders/ibl_hdr8.glsl against src/compress/hdr8.c on Mesa's llvmpipe (headless EGL,
 * tests/support/gl_harness.c), and ibl_hdr8.glsl / .hlsl through glslangValidator in every
 * dialect. An R8G8B8A8_UNORM texture of 256 x 256 texels holds every channel code (x) with
 * every alpha code (y) in red and green (red x, green 255 - x; blue mixes both), so every
 * code pair each decode can meet is decoded once per run; a compute shader fetches each texel
 * with texelFetch, decodes it with the three functions and writes the floats to a buffer.
 * Required: the GPU's float equals the C's bit for bit (the decodes are written with the same
 * correctly rounded operations in the same order), except RGBE values below 2^-126, which a
 * GPU may flush to 0 (docs/FORMATS.md). */
#include "test_support.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gl_harness.h"

enum { SIDE = 256, TEXELS = SIDE * SIDE };

typedef struct fixture {
    glh_context gl;
    ibl_context *ctx;
    char *glsl, *hlsl;
} fixture;

static char *read_shader(const char *name) { return glh_read_shader(IBL_SHADER_SOURCE_DIR, name); }

static int teardown(void **state)
{
    fixture *f = *state;
    if (!f) return 0;
    glh_destroy(&f->gl);
    ibl_context_destroy(f->ctx);
    free(f->glsl);
    free(f->hlsl);
    free(f);
    return 0;
}

static int setup(void **state)
{
    fixture *f = calloc(1, sizeof *f);
    if (!f) return -1;
    if (glh_create_for_test(&f->gl) != 0) {
        free(f);
        return -1;
    }
    *state = f;
    f->ctx = test_context(0);
    f->glsl = read_shader("ibl_hdr8.glsl");
    f->hlsl = read_shader("ibl_hdr8.hlsl");
    if (!f->glsl || !f->hlsl) {
        teardown(state);
        *state = NULL; /* cmocka may call the group teardown after a failed setup */
        return -1;
    }
    return 0;
}

/* The code pattern: red = x, green = 255 - x, blue = 37 x + y (mod 256), alpha = y. */
static void texel_codes(int x, int y, uint8_t out[4])
{
    out[0] = (uint8_t)x;
    out[1] = (uint8_t)(255 - x);
    out[2] = (uint8_t)((37 * x + y) & 255);
    out[3] = (uint8_t)y;
}

static const char *const COMPUTE_MAIN =
    "layout(local_size_x = 8, local_size_y = 8) in;\n"
    "layout(binding = 0) uniform sampler2D u_codes;\n"
    "layout(std430, binding = 0) writeonly buffer Out { float decoded[]; };\n"
    "uniform float u_range;\n"
    "void main() {\n"
    "  ivec2 p = ivec2(gl_GlobalInvocationID.xy);\n"
    "  vec4 t = texelFetch(u_codes, p, 0);\n"
    "  vec3 v[3] = vec3[3](ibl_decode_rgbm(t, u_range), ibl_decode_rgbd(t), ibl_decode_rgbe(t));\n"
    "  int o = (p.y * 256 + p.x) * 9;\n"
    "  for (int k = 0; k < 3; k++) for (int c = 0; c < 3; c++) decoded[o + 3 * k + c] = v[k][c];\n"
    "}\n";

/* Decodes the pattern on the GPU with RGBM range `range`: 9 floats per texel (RGBM, RGBD,
 * RGBE). */
static void gpu_decode(fixture *f, float range, float *out)
{
    const glh_gl *gl = &f->gl.gl;
    uint8_t *codes = malloc((size_t)TEXELS * 4);
    assert_non_null(codes);
    for (int y = 0; y < SIDE; y++)
        for (int x = 0; x < SIDE; x++) texel_codes(x, y, codes + ((size_t)y * SIDE + (size_t)x) * 4);
    size_t len = strlen(f->glsl) + strlen(COMPUTE_MAIN) + 64;
    char *src = malloc(len);
    assert_non_null(src);
    snprintf(src, len, "#version 450 core\n%s\n%s", f->glsl, COMPUTE_MAIN);
    GLenum type = GL_COMPUTE_SHADER;
    const char *srcs[1] = {src};
    char log[4096] = "";
    GLuint prog = glh_program(&f->gl, log, sizeof log, 1, &type, srcs);
    if (!prog) print_error("%s\n", log);
    assert_true(prog != 0);
    GLuint tex, buf;
    gl->GenTextures(1, &tex);
    gl->ActiveTexture(GL_TEXTURE0);
    gl->BindTexture(GL_TEXTURE_2D, tex);
    gl->TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    gl->TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    gl->TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAX_LEVEL, 0);
    gl->PixelStorei(GL_UNPACK_ALIGNMENT, 1);
    gl->TexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, SIDE, SIDE, 0, GL_RGBA, GL_UNSIGNED_BYTE, codes);
    gl->GenBuffers(1, &buf);
    gl->BindBuffer(GL_SHADER_STORAGE_BUFFER, buf);
    gl->BufferData(GL_SHADER_STORAGE_BUFFER, (GLsizeiptr)((size_t)TEXELS * 9 * sizeof(float)),
                   NULL, GL_DYNAMIC_READ);
    gl->BindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, buf);
    gl->UseProgram(prog);
    gl->Uniform1i(gl->GetUniformLocation(prog, "u_codes"), 0);
    gl->Uniform1f(gl->GetUniformLocation(prog, "u_range"), range);
    gl->DispatchCompute(SIDE / 8, SIDE / 8, 1);
    gl->MemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    gl->GetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0,
                         (GLsizeiptr)((size_t)TEXELS * 9 * sizeof(float)), out);
    assert_int_equal(gl->GetError(), GL_NO_ERROR);
    gl->UseProgram(0);
    gl->DeleteBuffers(1, &buf);
    gl->DeleteTextures(1, &tex);
    gl->DeleteProgram(prog);
    free(src);
    free(codes);
}

static int same_bits(float a, float b)
{
    return memcmp(&a, &b, sizeof a) == 0;
}

/* Every code pair through the three decodes at several RGBM ranges (the default 8, a power
 * of two, and ranges whose products round). */
static void decodes_match_c(void **state)
{
    fixture *f = *state;
    static const float ranges[] = {IBL_RGBM_DEFAULT_RANGE, 16.0f, 6.0f, 51.7f};
    float *gpu = malloc((size_t)TEXELS * 9 * sizeof *gpu);
    assert_non_null(gpu);
    long bad[3] = {0, 0, 0}, flushed = 0, old_order_differs = 0;
    for (size_t r = 0; r < sizeof ranges / sizeof *ranges; r++) {
        gpu_decode(f, ranges[r], gpu);
        for (int y = 0; y < SIDE; y++)
            for (int x = 0; x < SIDE; x++) {
                uint8_t q[4];
                texel_codes(x, y, q);
                float want[3][3];
                ibl_rgbm_decode(q, ranges[r], want[0]);
                ibl_rgbd_decode(q, want[1]);
                ibl_rgbe_decode(q, want[2]);
                const float *g = gpu + ((size_t)y * SIDE + (size_t)x) * 9;
                for (int k = 0; k < 3; k++)
                    for (int c = 0; c < 3; c++) {
                        float w = want[k][c], v = g[3 * k + c];
                        if (same_bits(w, v)) continue;
                        if (k == 2 && w < 0x1p-126f && v == 0.0f) {
                            flushed++;
                            continue;
                        }
                        if (bad[k]++ < 4)
                            print_message("%s range %g codes %d %d %d %d channel %d: C %.9g GPU %.9g\n",
                                          k == 0 ? "rgbm" : k == 1 ? "rgbd" : "rgbe",
                                          (double)ranges[r], q[0], q[1], q[2], q[3], c,
                                          (double)w, (double)v);
                    }
                /* the test tells orders of operations apart: the textbook order
                 * (c / 255) (a / 255) R differs from ours in the last bit for some codes */
                float textbook = (float)q[0] / 255.0f * ((float)q[3] / 255.0f) * ranges[r];
                if (!same_bits(textbook, want[0][0])) old_order_differs++;
            }
    }
    print_message("4 ranges x %d texels x 3 channels: differences rgbm %ld, rgbd %ld, rgbe %ld; "
                  "rgbe denormals flushed %ld; textbook RGBM order differs in %ld\n",
                  TEXELS, bad[0], bad[1], bad[2], flushed, old_order_differs);
    assert_int_equal(bad[0] + bad[1] + bad[2], 0);
    assert_true(old_order_differs > 0);
    free(gpu);
}

/* The decodes against their definitions in double (docs/FORMATS.md): RGBM and RGBD within
 * one float rounding of each operation (3 and 1 ulp: 2^-22 and 2^-23 relative), RGBE exact. */
static void decodes_match_formulas(void **state)
{
    (void)state;
    for (int a = 0; a < 256; a++)
        for (int c = 0; c < 256; c++) {
            uint8_t q[4] = {(uint8_t)c, 0, 0, (uint8_t)a};
            float m[3], d[3], e[3];
            ibl_rgbm_decode(q, 8.0f, m);
            ibl_rgbd_decode(q, d);
            ibl_rgbe_decode(q, e);
            double rm = c / 255.0 * (a / 255.0) * 8.0, rd = c / (double)(a ? a : 1);
            double re = a ? (c + 0.5) * ldexp(1.0, a - 136) : 0.0;
            assert_true(fabs(m[0] - rm) <= rm * 0x1p-22);
            assert_true(fabs(d[0] - rd) <= rd * 0x1p-23);
            assert_true(e[0] == (float)re);
        }
}

/* Writes head + file + tail to path and runs glslangValidator with args on it. */
static int validate(const char *args, const char *name, const char *head, const char *file,
                    const char *tail)
{
    const char *parts[] = {head, file, tail};
    return glh_validate(IBL_GLSLANG_VALIDATOR, args, test_path(name), parts, 3);
}

static const char *const GLSL_FRAG =
    "uniform sampler2D u_tex;\n"
    "in vec2 v_uv;\n"
    "layout(location = 0) out vec4 o_color;\n"
    "void main() {\n"
    "  vec4 t = texture(u_tex, v_uv);\n"
    "  o_color = vec4(ibl_decode_rgbm(t, 8.0) + ibl_decode_rgbd(t) + ibl_decode_rgbe(t), 1.0);\n"
    "}\n";

static const char *const VULKAN_FRAG =
    "layout(set = 0, binding = 0) uniform sampler2D u_tex;\n"
    "layout(location = 0) in vec2 v_uv;\n"
    "layout(location = 0) out vec4 o_color;\n"
    "void main() {\n"
    "  vec4 t = texture(u_tex, v_uv);\n"
    "  o_color = vec4(ibl_decode_rgbm(t, 8.0) + ibl_decode_rgbd(t) + ibl_decode_rgbe(t), 1.0);\n"
    "}\n";

static const char *const HLSL_FRAG =
    "Texture2D u_tex : register(t0);\n"
    "SamplerState u_sampler : register(s0);\n"
    "float4 main(float2 uv : TEXCOORD0) : SV_Target {\n"
    "  float4 t = u_tex.Sample(u_sampler, uv);\n"
    "  return float4(ibl_decode_rgbm(t, 8.0) + ibl_decode_rgbd(t) + ibl_decode_rgbe(t), 1.0);\n"
    "}\n";

static void dialects_compile(void **state)
{
    fixture *f = *state;
    assert_int_equal(validate("-S frag", "hdr8_450.frag", "#version 450 core", f->glsl, GLSL_FRAG), 0);
    assert_int_equal(validate("-S frag", "hdr8_es.frag", "#version 300 es", f->glsl, GLSL_FRAG), 0);
    assert_int_equal(validate("-V -S frag -o /dev/null", "hdr8_vk.frag", "#version 450", f->glsl,
                              VULKAN_FRAG), 0);
    assert_int_equal(validate("-D -V -S frag -e main -o /dev/null", "hdr8.hlsl", "", f->hlsl,
                              HLSL_FRAG), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(decodes_match_formulas),
        cmocka_unit_test(decodes_match_c),
        cmocka_unit_test(dialects_compile),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
