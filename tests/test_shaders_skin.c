/* shaders/ibl_skin.glsl and ibl_skin.hlsl against the C (src/shade/skin.c) on Mesa's llvmpipe
 * through the headless harness (tests/support/gl_harness.c):
 *  1. both files compile after ibl.glsl / ibl.hlsl in GLSL 4.50, ES 3.00, Vulkan and HLSL
 *     (glslangValidator);
 *  2. ibl_skin_shade and ibl_skin_transmittance run in a compute shader over 10240 inputs
 *     (random normals, albedos, transmittances, ranges and scales, edge values included), with
 *     the probe's SH and with its irradiance cube, and match the C within a stated bound. */
#include "test_support.h"
#include "gl_harness.h"
#include "gl_probe.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { SAMPLES = 10240, N_IN = 18, N_OUT = 12 };

typedef struct fixture {
    glh_context gl;
    ibl_context *ctx;
    ibl_cubemap env;
    ibl_bake_data bake;
    ibl_probe probe;
    char *glsl; /* ibl.glsl + ibl_skin.glsl */
} fixture;

static char *read_shaders(const char *a, const char *b)
{
    char *x = glh_read_shader(IBL_SHADER_SOURCE_DIR, a), *y = glh_read_shader(IBL_SHADER_SOURCE_DIR, b);
    char *s = x && y ? malloc(strlen(x) + strlen(y) + 2) : NULL;
    if (s) sprintf(s, "%s\n%s", x, y);
    free(x);
    free(y);
    return s;
}

/* forest (128x64 equirect) on a 32 cube, baked as `ibl render` bakes: SH and irradiance cube */
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
    f->glsl = read_shaders("ibl.glsl", "ibl_skin.glsl");
    ibl_image im;
    if (!f->glsl || ibl_read_image(f->ctx, test_data("forest_128x64.exr"), NULL, &im, NULL) != IBL_OK)
        return -1;
    ibl_to_cube_desc cd = {.layout = IBL_LAYOUT_EQUIRECT, .size = 32};
    ibl_status st = ibl_image_to_cubemap(f->ctx, &im, &cd, &f->env);
    ibl_image_free(f->ctx, &im);
    ibl_bake_desc d;
    if (st == IBL_OK) {
        ibl_render_bake_desc(&f->env, 32, &d);
        d.lut_size = 32;
        st = ibl_bake_compute(f->ctx, &f->env, &d, &f->bake);
    }
    if (st == IBL_OK) st = ibl_bake_probe(f->ctx, &f->bake, &f->probe);
    return st == IBL_OK ? 0 : -1;
}

static int teardown(void **state)
{
    fixture *f = *state;
    glh_destroy(&f->gl);
    ibl_bake_free(f->ctx, &f->bake);
    ibl_cubemap_free(f->ctx, &f->env);
    ibl_context_destroy(f->ctx);
    free(f->glsl);
    free(f);
    return 0;
}

/* ---- 1. dialects ------------------------------------------------------------------------ */

static int validate(const char *args, const char *path, const char *text)
{
    return glh_validate(IBL_GLSLANG_VALIDATOR, args, path, &text, 1);
}

static const char *const glsl_main =
    "layout(std140) uniform ProbeBlock { ibl_probe probe; };\n"
    "uniform samplerCube u_irradiance;\n"
    "in vec3 v_normal;\n"
    "layout(location = 0) out vec4 o_color;\n"
    "void main() {\n"
    "  vec3 n = normalize(v_normal);\n"
    "  ibl_skin_surface s = ibl_skin_surface(n, n, n, n, vec3(0.8, 0.5, 0.4), 0.5, 0.0, 0.0);\n"
    "  o_color = vec4(ibl_skin_shade(probe, u_irradiance, s).color, 1.0);\n"
    "}\n";

static const char *const vulkan_main =
    "layout(set = 0, binding = 0, std140) uniform ProbeBlock { ibl_probe probe; };\n"
    "layout(set = 0, binding = 1) uniform samplerCube u_irradiance;\n"
    "layout(location = 0) in vec3 v_normal;\n"
    "layout(location = 0) out vec4 o_color;\n"
    "void main() {\n"
    "  vec3 n = normalize(v_normal);\n"
    "  ibl_skin_surface s = ibl_skin_surface(n, n, n, n, vec3(0.8, 0.5, 0.4), 0.5, 0.0, 0.0);\n"
    "  o_color = vec4(ibl_skin_shade(probe, u_irradiance, s).color, 1.0);\n"
    "}\n";

static const char *const hlsl_main =
    "cbuffer ProbeBlock : register(b0) { ibl_probe probe; };\n"
    "TextureCube u_irradiance : register(t2);\n"
    "SamplerState u_sampler : register(s0);\n"
    "float4 main(float3 normal : NORMAL) : SV_Target {\n"
    "  ibl_skin_surface s = (ibl_skin_surface)0;\n"
    "  s.n_r = s.n_g = s.n_b = s.geometric_normal = normalize(normal);\n"
    "  s.albedo = float3(0.8, 0.5, 0.4); s.transmittance = 0.5;\n"
    "  return float4(ibl_skin_shade(probe, u_irradiance, u_sampler, s).color, 1.0);\n"
    "}\n";

static void compile_all_dialects(void **state)
{
    fixture *f = *state;
    char *hlsl = read_shaders("ibl.hlsl", "ibl_skin.hlsl");
    assert_non_null(hlsl);
    const char *heads[3] = {"#version 450 core", "#version 300 es", "#version 450"};
    const char *mains[3] = {glsl_main, glsl_main, vulkan_main};
    const char *args[3] = {"-S frag", "-S frag", "-V -S frag -o /dev/null"};
    const char *names[3] = {"skin_gl450.frag", "skin_es300.frag", "skin_vulkan.frag"};
    for (int i = 0; i < 3; i++) {
        size_t n = strlen(heads[i]) + strlen(f->glsl) + strlen(mains[i]) + 8;
        char *text = malloc(n);
        assert_non_null(text);
        snprintf(text, n, "%s\n%s\n%s", heads[i], f->glsl, mains[i]);
        assert_int_equal(validate(args[i], test_path(names[i]), text), 0);
        free(text);
    }
    size_t n = strlen(hlsl) + strlen(hlsl_main) + 8;
    char *text = malloc(n);
    assert_non_null(text);
    snprintf(text, n, "%s\n%s", hlsl, hlsl_main);
    assert_int_equal(validate("-D -V -e main -S frag -o /dev/null", test_path("skin.hlsl.frag"), text), 0);
    free(text);
    free(hlsl);
}

/* ---- 2. the functions against the C --------------------------------------------------------- */

static const char *const compute_src =
    "layout(local_size_x = 64) in;\n"
    "layout(std430, binding = 0) readonly buffer Inputs { float in_[]; };\n"
    "layout(std430, binding = 1) writeonly buffer Outputs { float out_[]; };\n"
    "layout(std140, binding = 0) uniform ProbeBlock { ibl_probe probe; };\n"
    "layout(binding = 2) uniform samplerCube u_irradiance;\n"
    "uniform int u_count;\n"
    "int g;\n"
    "float X(int k) { return in_[g * 18 + k]; }\n"
    "vec3 V(int k) { return vec3(X(k), X(k + 1), X(k + 2)); }\n"
    "void Y3(int k, vec3 v) { out_[g * 12 + k] = v.x; out_[g * 12 + k + 1] = v.y; out_[g * 12 + k + 2] = v.z; }\n"
    "void main() {\n"
    "  g = int(gl_GlobalInvocationID.x);\n"
    "  if (g >= u_count) return;\n"
    "  ibl_skin_surface s = ibl_skin_surface(V(0), V(3), V(6), V(9), V(12), X(15), X(16), X(17));\n"
    "  ibl_skin_result r = ibl_skin_shade(probe, u_irradiance, s);\n"
    "  Y3(0, r.diffuse); Y3(3, r.translucent); Y3(6, r.color);\n"
    "  Y3(9, ibl_skin_transmittance((1.0 - X(15)) * 8.0));\n"
    "}\n";

static float rnd(uint64_t *s)
{
    *s = *s * 6364136223846793005ull + 1442695040888963407ull;
    return (float)((*s >> 40) * (1.0 / 16777216.0));
}

static void random_dir(uint64_t *s, float *d)
{
    float z = 2 * rnd(s) - 1, phi = 6.2831853f * rnd(s), r = sqrtf(fmaxf(0.0f, 1 - z * z));
    d[0] = r * cosf(phi), d[1] = r * sinf(phi), d[2] = z;
}

static void generate(float *in)
{
    uint64_t s = 12345;
    for (int i = 0; i < SAMPLES; i++) {
        float *x = in + (size_t)i * N_IN;
        for (int k = 0; k < 4; k++) random_dir(&s, x + 3 * k);
        if (i % 7 == 0) memcpy(x + 3, x, 3 * sizeof(float)); /* equal normals */
        for (int c = 0; c < 3; c++) x[12 + c] = rnd(&s);
        static const float edges[] = {0.0f, 1.0f, 0.999f, 1e-3f};
        x[15] = i < 4 ? edges[i] : rnd(&s);                  /* transmittance             */
        x[16] = i % 5 == 0 ? 0.0f : 2.0f + 18.0f * rnd(&s);  /* range (0: the default)    */
        x[17] = i % 3 == 0 ? 0.0f : 3.0f * rnd(&s);          /* scale (0: 1)              */
    }
}

static void reference(const ibl_probe *p, const float *x, float *y)
{
    ibl_skin_surface s;
    memset(&s, 0, sizeof s);
    for (int k = 0; k < 3; k++) s.n[k] = (ibl_vec3){x[3 * k], x[3 * k + 1], x[3 * k + 2]};
    s.geometric_normal = (ibl_vec3){x[9], x[10], x[11]};
    for (int c = 0; c < 3; c++) s.albedo[c] = x[12 + c];
    s.transmittance = x[15];
    s.thickness_range_mm = x[16];
    s.translucency = x[17];
    ibl_skin_result r;
    ibl_skin_shade(p, NULL, &s, &r);
    memcpy(y, r.diffuse, sizeof r.diffuse);
    memcpy(y + 3, r.translucent, sizeof r.translucent);
    memcpy(y + 6, r.color, sizeof r.color);
    ibl_skin_transmittance(NULL, (1.0f - x[15]) * 8.0f, y + 9);
}

/* Runs the compute shader with the probe as uploaded; returns the worst error against the C
 * measured as |gpu - c| / (1e-5 + 1e-4 |c|). */
static double run(fixture *f, const ibl_probe *probe, const float *in, float *out)
{
    const glh_gl *gl = &f->gl.gl;
    glp_probe gpu;
    assert_int_equal(glp_probe_upload(gl, f->ctx, probe, &gpu), IBL_OK);
    size_t n = strlen(f->glsl) + strlen(compute_src) + 32;
    char *src = malloc(n);
    assert_non_null(src);
    snprintf(src, n, "#version 450 core\n%s\n%s", f->glsl, compute_src);
    GLenum type = GL_COMPUTE_SHADER;
    const char *srcs[1] = {src};
    char log[4096] = "";
    GLuint prog = glh_program(&f->gl, log, sizeof log, 1, &type, srcs);
    if (!prog) print_error("%s\n", log);
    assert_true(prog != 0);
    free(src);
    GLuint buf[2];
    gl->GenBuffers(2, buf);
    gl->BindBuffer(GL_SHADER_STORAGE_BUFFER, buf[0]);
    gl->BufferData(GL_SHADER_STORAGE_BUFFER, (GLsizeiptr)(SAMPLES * N_IN * sizeof(float)), in, GL_STATIC_DRAW);
    gl->BindBuffer(GL_SHADER_STORAGE_BUFFER, buf[1]);
    gl->BufferData(GL_SHADER_STORAGE_BUFFER, (GLsizeiptr)(SAMPLES * N_OUT * sizeof(float)), NULL, GL_DYNAMIC_READ);
    gl->BindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, buf[0]);
    gl->BindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, buf[1]);
    glp_probe_bind(gl, &gpu);
    gl->UseProgram(prog);
    gl->Uniform1i(gl->GetUniformLocation(prog, "u_count"), SAMPLES);
    gl->DispatchCompute((SAMPLES + 63) / 64, 1, 1);
    gl->MemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    gl->GetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, (GLsizeiptr)(SAMPLES * N_OUT * sizeof(float)), out);
    assert_int_equal(gl->GetError(), GL_NO_ERROR);
    gl->UseProgram(0);
    gl->DeleteBuffers(2, buf);
    gl->DeleteProgram(prog);
    glp_probe_free(gl, &gpu);
    double worst = 0, worst_abs = 0;
    for (int i = 0; i < SAMPLES; i++) {
        float ref[N_OUT];
        reference(probe, in + (size_t)i * N_IN, ref);
        for (int k = 0; k < N_OUT; k++) {
            double g = out[(size_t)i * N_OUT + k], e = fabs(g - ref[k]);
            double score = e / (1e-5 + 1e-4 * fabs(ref[k]));
            if (!(score == score)) score = INFINITY;
            if (score > worst) worst = score;
            if (e > worst_abs) worst_abs = e;
        }
    }
    print_message("sh_kind %d: worst |gpu - c| %.2e, %.3f of the bound\n", probe->sh_kind, worst_abs, worst);
    return worst;
}

/* Bound |gpu - c| <= 1e-5 + 1e-4 |c|: float SH arithmetic, exp of the profile and, without SH,
 * the bilinear cube read, which on llvmpipe matches the C's seamless bilinear to 1e-5 (the
 * bound ibl_probe_irradiance has in tests/test_shaders.c); radiances here are O(1). */
static void shade_matches_c(void **state)
{
    fixture *f = *state;
    float *in = malloc(sizeof(float) * SAMPLES * N_IN), *out = malloc(sizeof(float) * SAMPLES * N_OUT);
    assert_non_null(in);
    assert_non_null(out);
    generate(in);
    /* the bake's SH (a radiance projection), then its irradiance cube */
    ibl_probe p = f->probe;
    assert_true(p.sh[0][0] > 0.0f);
    p.sh_kind = IBL_SH_KIND_RADIANCE;
    assert_true(run(f, &p, in, out) <= 1.0);
    assert_true(f->probe.irradiance.data != NULL);
    p.sh_kind = IBL_SH_KIND_NONE;
    assert_true(run(f, &p, in, out) <= 1.0);
    free(in);
    free(out);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(compile_all_dialects),
        cmocka_unit_test(shade_matches_c),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
