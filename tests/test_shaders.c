/* shaders/ibl.glsl and ibl.hlsl against the C runtime (include/ibl/shade.h) on a real OpenGL
 * driver: Mesa's llvmpipe through a headless EGL context (tests/support/gl_harness.c).
 *  1. both files compile in every dialect (glslangValidator: GLSL 4.50 core, ES 3.00, Vulkan
 *     to SPIR-V; HLSL to SPIR-V);
 *  2. every GLSL function runs over >= 10240 inputs (random and edge cases) in a compute
 *     shader and matches its C twin within a stated tolerance (shader_cases.h);
 *  3. the sphere grid of `ibl render` drawn by a fragment shader from the uploaded bake
 *     matches the C renderer's runtime image (mean and 99th-percentile error bounded). */
#include "test_support.h"
#include "sphere_grid.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "shader_test.h"

static char *read_shader(const char *name) { return glh_read_shader(IBL_SHADER_SOURCE_DIR, name); }

/* forest (128x64 equirect) on a 32 cube, baked as `ibl render` bakes (GGX chain to 4x4,
 * irradiance cube, SH, split-sum and AmbientBRDF tables, the environment as mirror). */
static int make_probe(fixture *f)
{
    ibl_image im;
    if (ibl_read_image(f->ctx, test_data("forest_128x64.exr"), NULL, &im, NULL) != IBL_OK) return -1;
    ibl_to_cube_desc cd = {.layout = IBL_LAYOUT_EQUIRECT, .size = 32};
    ibl_status st = ibl_image_to_cubemap(f->ctx, &im, &cd, &f->env);
    ibl_image_free(f->ctx, &im);
    if (st != IBL_OK) return -1;
    ibl_bake_desc d;
    ibl_render_bake_desc(&f->env, 32, &d);
    d.lut_size = 64;
    if (ibl_bake_compute(f->ctx, &f->env, &d, &f->bake) != IBL_OK) return -1;
    if (ibl_bake_probe(f->ctx, &f->bake, &f->probe) != IBL_OK) return -1;
    if (glp_probe_upload(&f->gl.gl, f->ctx, &f->probe, &f->gpu) != IBL_OK) return -1;
    ibl_atlas_desc ad = {.gutter = 1};
    if (ibl_atlas_pack(f->ctx, &f->probe.specular, &ad, &f->atlas, &f->atlas_layout) != IBL_OK)
        return -1;
    const glh_gl *gl = &f->gl.gl;
    f->atlas_texture = glp_image_texture(gl, &f->atlas);
    ibl_shader_atlas block;
    ibl_shader_atlas_fill(&f->atlas_layout, &block);
    gl->GenBuffers(1, &f->atlas_block);
    gl->BindBuffer(GL_UNIFORM_BUFFER, f->atlas_block);
    gl->BufferData(GL_UNIFORM_BUFFER, sizeof block, &block, GL_STATIC_DRAW);
    return gl->GetError() == GL_NO_ERROR ? 0 : -1;
}

static int teardown(void **state);

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
    f->glsl = read_shader("ibl.glsl");
    if (!f->glsl || make_probe(f) != 0) {
        print_error("fixture: %s\n", ibl_context_message(f->ctx));
        teardown(state);
        return -1;
    }
    return 0;
}

static int teardown(void **state)
{
    fixture *f = *state;
    const glh_gl *gl = &f->gl.gl;
    glp_probe_free(gl, &f->gpu);
    if (f->atlas_texture) gl->DeleteTextures(1, &f->atlas_texture);
    if (f->atlas_block) gl->DeleteBuffers(1, &f->atlas_block);
    glh_destroy(&f->gl);
    ibl_image_free(f->ctx, &f->atlas);
    ibl_bake_free(f->ctx, &f->bake);
    ibl_cubemap_free(f->ctx, &f->env);
    ibl_context_destroy(f->ctx);
    free(f->glsl);
    free(f);
    return 0;
}

static void gl_context(void **state)
{
    fixture *f = *state;
    print_message("renderer: %s, %s\n", f->gl.renderer, f->gl.version);
    assert_non_null(strstr(f->gl.version, "4.5"));
}

/* ---- 1. every dialect through glslangValidator ------------------------------------------ */

/* Writes head + file + tail to path and runs glslangValidator with args on it. */
static int validate(const char *args, const char *path, const char *head, const char *file,
                    const char *tail)
{
    const char *parts[] = {head, file, tail};
    return glh_validate(IBL_GLSLANG_VALIDATOR, args, path, parts, 3);
}

/* A fragment shader that calls ibl_shade (so every function is reached from main). */
static const char *const glsl_frag_main =
    "layout(std140) uniform ProbeBlock { ibl_probe probe; };\n"
    "layout(std140) uniform LightBlock { ibl_light_set lights; };\n"
    "uniform samplerCube u_specular, u_mirror, u_irradiance;\n"
    "uniform sampler2D u_splitsum;\n"
    "uniform highp sampler3D u_ambient;\n"
    "in vec3 v_normal; in vec3 v_view;\n"
    "layout(location = 0) out vec4 o_color;\n"
    "void main() {\n"
    "  ibl_shade_desc desc = ibl_shade_desc(0, 0, 0, 0, 0.0, 0, 0, 0, 0, 0);\n"
    "  ibl_surface s = ibl_surface(normalize(v_normal), normalize(v_view), vec3(0.0), vec3(0.0));\n"
    "  ibl_material m = ibl_material_gltf(vec3(1.0, 0.766, 0.336), 1.0, 0.5);\n"
    "  ibl_light_result l = ibl_lights_shade(lights.light, lights.count, desc, m, s, v_view);\n"
    "  s.direct_specular = l.specular;\n"
    "  ibl_shade_result r = ibl_shade(probe, u_specular, u_mirror, u_irradiance, u_splitsum,\n"
    "                                 u_ambient, desc, m, s);\n"
    "  o_color = vec4(r.color + l.diffuse, 1.0);\n"
    "}\n";

static const char *const vulkan_frag_main =
    "layout(set = 0, binding = 0, std140) uniform ProbeBlock { ibl_probe probe; };\n"
    "layout(set = 0, binding = 1) uniform samplerCube u_specular;\n"
    "layout(set = 0, binding = 2) uniform samplerCube u_mirror;\n"
    "layout(set = 0, binding = 3) uniform samplerCube u_irradiance;\n"
    "layout(set = 0, binding = 4) uniform sampler2D u_splitsum;\n"
    "layout(set = 0, binding = 5) uniform sampler3D u_ambient;\n"
    "layout(location = 0) in vec3 v_normal; layout(location = 1) in vec3 v_view;\n"
    "layout(location = 0) out vec4 o_color;\n"
    "void main() {\n"
    "  ibl_shade_desc desc = ibl_shade_desc(0, 0, 0, 0, 0.0, 0, 0, 0, 0, 0);\n"
    "  ibl_surface s = ibl_surface(normalize(v_normal), normalize(v_view), vec3(0.0), vec3(0.0));\n"
    "  ibl_material m = ibl_material_gltf(vec3(1.0, 0.766, 0.336), 1.0, 0.5);\n"
    "  ibl_shade_result r = ibl_shade(probe, u_specular, u_mirror, u_irradiance, u_splitsum,\n"
    "                                 u_ambient, desc, m, s);\n"
    "  o_color = vec4(r.color, 1.0);\n"
    "}\n";

static const char *const hlsl_no3d_main =
    "cbuffer ProbeBlock : register(b0) { ibl_probe probe; };\n"
    "cbuffer AtlasBlock : register(b1) { ibl_atlas_layout atlas_layout; };\n"
    "TextureCube u_specular : register(t0);\n"
    "TextureCube u_mirror : register(t1);\n"
    "TextureCube u_irradiance : register(t2);\n"
    "Texture2D u_splitsum : register(t3);\n"
    "Texture2D u_atlas : register(t5);\n"
    "SamplerState u_sampler : register(s0);\n"
    "float4 main(float3 normal : NORMAL, float3 view : TEXCOORD0) : SV_Target {\n"
    "  ibl_shade_desc desc = (ibl_shade_desc)0;\n"
    "  ibl_surface s = (ibl_surface)0;\n"
    "  s.n = normalize(normal); s.v = normalize(view);\n"
    "  ibl_material m = ibl_material_gltf(float3(1.0, 0.766, 0.336), 1.0, 0.5);\n"
    "  ibl_shade_result r = ibl_shade(probe, u_specular, u_mirror, u_irradiance, u_splitsum,\n"
    "                                 u_sampler, desc, m, s);\n"
    "  float4 a = ibl_atlas_sample(u_atlas, u_sampler, atlas_layout, r.lod, r.r);\n"
    "  return float4(r.color + a.rgb, 1.0);\n"
    "}\n";

static const char *const hlsl_frag_main =
    "cbuffer ProbeBlock : register(b0) { ibl_probe probe; };\n"
    "cbuffer LightBlock : register(b2) { ibl_light_set lights; };\n"
    "TextureCube u_specular : register(t0);\n"
    "TextureCube u_mirror : register(t1);\n"
    "TextureCube u_irradiance : register(t2);\n"
    "Texture2D u_splitsum : register(t3);\n"
    "Texture3D u_ambient : register(t4);\n"
    "SamplerState u_sampler : register(s0);\n"
    "float4 main(float3 normal : NORMAL, float3 view : TEXCOORD0) : SV_Target {\n"
    "  ibl_shade_desc desc = (ibl_shade_desc)0;\n"
    "  ibl_surface s = (ibl_surface)0;\n"
    "  s.n = normalize(normal); s.v = normalize(view);\n"
    "  ibl_material m = ibl_material_gltf(float3(1.0, 0.766, 0.336), 1.0, 0.5);\n"
    "  float vis[IBL_MAX_LIGHTS];\n"
    "  for (int k = 0; k < IBL_MAX_LIGHTS; k++) vis[k] = 1.0;\n"
    "  ibl_light_result l = ibl_lights_shade(lights.light, lights.count, vis, desc, m, s, view);\n"
    "  s.direct_specular = l.specular;\n"
    "  ibl_shade_result r = ibl_shade(probe, u_specular, u_mirror, u_irradiance, u_splitsum,\n"
    "                                 u_ambient, u_sampler, desc, m, s);\n"
    "  return float4(r.color + l.diffuse, 1.0);\n"
    "}\n";

/* WebGL2 / 8-slot GLES: no sampler3D (IBL_NO_AMBIENT_BRDF_3D), the chain as a 2D atlas. */
static const char *const es_atlas_main =
    "layout(std140) uniform ProbeBlock { ibl_probe probe; };\n"
    "layout(std140) uniform AtlasBlock { ibl_atlas_layout atlas_layout; };\n"
    "uniform samplerCube u_specular, u_mirror, u_irradiance;\n"
    "uniform sampler2D u_splitsum, u_atlas;\n"
    "in vec3 v_normal; in vec3 v_view;\n"
    "layout(location = 0) out vec4 o_color;\n"
    "void main() {\n"
    "  ibl_shade_desc desc = ibl_shade_desc(0, 0, 0, 0, 0.0, 0, 0, 0, 0, 0);\n"
    "  ibl_surface s = ibl_surface(normalize(v_normal), normalize(v_view), vec3(0.0), vec3(0.0));\n"
    "  ibl_material m = ibl_material_gltf(vec3(1.0, 0.766, 0.336), 1.0, 0.5);\n"
    "  ibl_shade_result r = ibl_shade(probe, u_specular, u_mirror, u_irradiance, u_splitsum,\n"
    "                                 desc, m, s);\n"
    "  vec4 a = ibl_atlas_sample(u_atlas, atlas_layout, r.lod, r.r);\n"
    "  o_color = vec4(r.color + a.rgb, 1.0);\n"
    "}\n";

static void compile_all_dialects(void **state)
{
    fixture *f = *state;
    char *hlsl = read_shader("ibl.hlsl");
    assert_non_null(hlsl);
    char path[6][1024];
    const char *names[6] = {"gl450.frag",    "es300.frag",        "vulkan.frag",
                            "ibl.hlsl.frag", "es300_atlas.frag", "ibl_no3d.hlsl.frag"};
    for (int i = 0; i < 6; i++) snprintf(path[i], sizeof path[i], "%s", test_path(names[i]));
    /* OpenGL 4.50 core and ES 3.00 as the GL driver would see them; Vulkan GLSL compiled to
     * SPIR-V (-V defines VULKAN); HLSL (-D) compiled to SPIR-V with entry point main */
    assert_int_equal(validate("-S frag", path[0], "#version 450 core", f->glsl, glsl_frag_main), 0);
    assert_int_equal(validate("-S frag", path[1], "#version 300 es", f->glsl, glsl_frag_main), 0);
    assert_int_equal(validate("-V -S frag -o /dev/null", path[2], "#version 450", f->glsl,
                              vulkan_frag_main), 0);
    assert_int_equal(validate("-D -V -e main -S frag -o /dev/null", path[3], "", hlsl,
                              hlsl_frag_main), 0);
    /* the switch for devices short of texture slots, in both languages */
    assert_int_equal(validate("-S frag", path[4], "#version 300 es\n#define IBL_NO_AMBIENT_BRDF_3D",
                              f->glsl, es_atlas_main), 0);
    assert_int_equal(validate("-D -V -e main -S frag -o /dev/null", path[5],
                              "#define IBL_NO_AMBIENT_BRDF_3D", hlsl, hlsl_no3d_main), 0);
    /* and the driver itself: ES 3.00 has no context here, 4.50 core is compiled by llvmpipe */
    char *src = malloc(strlen(f->glsl) + strlen(glsl_frag_main) + 64);
    assert_non_null(src);
    sprintf(src, "#version 450 core\n%s\n%s", f->glsl, glsl_frag_main);
    static const char vs[] = "#version 450 core\nout vec3 v_normal; out vec3 v_view;\n"
                             "void main() { v_normal = vec3(0, 0, 1); v_view = vec3(0, 0, 1);"
                             " gl_Position = vec4(0, 0, 0, 1); }\n";
    const GLenum types[2] = {GL_VERTEX_SHADER, GL_FRAGMENT_SHADER};
    const char *sources[2] = {vs, src};
    char log[4096] = "";
    GLuint prog = glh_program(&f->gl, log, sizeof log, 2, types, sources);
    if (!prog) print_error("llvmpipe: %s\n", log);
    assert_true(prog != 0);
    f->gl.gl.DeleteProgram(prog);
    free(src);
    free(hlsl);
}

/* ---- 2. every function against its C twin ------------------------------------------------- */

enum { SAMPLES = 10240, MAX_IN = 80, MAX_OUT = 16 };

static const char *const compute_head =
    "layout(local_size_x = 64) in;\n"
    "layout(std430, binding = 0) readonly buffer Inputs { float in_[]; };\n"
    "layout(std430, binding = 1) writeonly buffer Outputs { float out_[]; };\n"
    "layout(std140, binding = 0) uniform ProbeBlock { ibl_probe probe; };\n"
    "layout(std140, binding = 1) uniform AtlasBlock { ibl_atlas_layout atlas_layout; };\n"
    "layout(binding = 0) uniform samplerCube u_specular;\n"
    "layout(binding = 1) uniform samplerCube u_mirror;\n"
    "layout(binding = 2) uniform samplerCube u_irradiance;\n"
    "layout(binding = 3) uniform sampler2D u_splitsum;\n"
    "layout(binding = 4) uniform sampler3D u_ambient;\n"
    "layout(binding = 5) uniform sampler2D u_atlas;\n"
    "uniform int u_count, u_in, u_out;\n"
    "int g_in, g_out;\n"
    "float X(int k) { return in_[g_in + k]; }\n"
    "int I(int k) { return int(in_[g_in + k]); }\n"
    "vec3 V(int k) { return vec3(X(k), X(k + 1), X(k + 2)); }\n"
    "void Y(int k, float v) { out_[g_out + k] = v; }\n"
    "void Y3(int k, vec3 v) { Y(k, v.x); Y(k + 1, v.y); Y(k + 2, v.z); }\n"
    "ibl_material M(int k) { return ibl_material(I(k), V(k + 1), X(k + 4), X(k + 5), V(k + 6),\n"
    "                                            X(k + 9), X(k + 10)); }\n"
    "ibl_surface S(int k) { return ibl_surface(V(k), V(k + 3), V(k + 6), V(k + 9)); }\n"
    "ibl_shade_desc D(int k) { return ibl_shade_desc(I(k), I(k + 1), I(k + 2), I(k + 3),\n"
    "    X(k + 4), I(k + 5), I(k + 6), I(k + 7), I(k + 8), 0); }\n"
    "ibl_light L(int k) { return ibl_light(V(k + 1), X(k + 4), V(k + 5), X(k + 11), V(k + 8),\n"
    "    X(k + 14), I(k), X(k + 12), X(k + 13), 0); }\n"
    "ibl_volume VOL(int k) { return ibl_volume(I(k), V(k + 1), V(k + 4), X(k + 7), X(k + 8)); }\n"
    "void Yr(int k, ibl_shade_result r) { Y3(k, r.color); Y3(k + 3, r.diffuse);\n"
    "    Y3(k + 6, r.specular); Y(k + 9, r.so); Y(k + 10, r.lod); Y3(k + 11, r.r); }\n";

static const char *const compute_main_head =
    "void main() {\n"
    "  int i = int(gl_GlobalInvocationID.x);\n"
    "  if (i >= u_count) return;\n"
    "  g_in = i * u_in; g_out = i * u_out;\n";

/* Runs one case's GLSL body over the inputs; out receives SAMPLES * n_out floats. */
static void run_case_gpu(fixture *f, const shader_case *c, const float *in, float *out)
{
    const glh_gl *gl = &f->gl.gl;
    size_t len = strlen(f->glsl) + strlen(compute_head) + strlen(compute_main_head) +
                 strlen(c->glsl) + 64;
    char *src = malloc(len);
    assert_non_null(src);
    snprintf(src, len, "#version 450 core\n%s\n%s%s  %s\n}\n", f->glsl, compute_head,
             compute_main_head, c->glsl);
    GLenum type = GL_COMPUTE_SHADER;
    const char *srcs[1] = {src};
    char log[4096] = "";
    GLuint prog = glh_program(&f->gl, log, sizeof log, 1, &type, srcs);
    if (!prog) print_error("%s: %s\n", c->name, log);
    assert_true(prog != 0);
    free(src);
    GLuint buf[2];
    gl->GenBuffers(2, buf);
    gl->BindBuffer(GL_SHADER_STORAGE_BUFFER, buf[0]);
    gl->BufferData(GL_SHADER_STORAGE_BUFFER, (GLsizeiptr)(SAMPLES * c->n_in * sizeof(float)), in,
                   GL_STATIC_DRAW);
    gl->BindBuffer(GL_SHADER_STORAGE_BUFFER, buf[1]);
    gl->BufferData(GL_SHADER_STORAGE_BUFFER, (GLsizeiptr)(SAMPLES * c->n_out * sizeof(float)),
                   NULL, GL_DYNAMIC_READ);
    gl->BindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, buf[0]);
    gl->BindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, buf[1]);
    glp_probe_bind(gl, &f->gpu);
    gl->BindBufferBase(GL_UNIFORM_BUFFER, 1, f->atlas_block);
    gl->ActiveTexture(GL_TEXTURE5);
    gl->BindTexture(GL_TEXTURE_2D, f->atlas_texture);
    gl->ActiveTexture(GL_TEXTURE0);
    gl->UseProgram(prog);
    gl->Uniform1i(gl->GetUniformLocation(prog, "u_count"), SAMPLES);
    gl->Uniform1i(gl->GetUniformLocation(prog, "u_in"), c->n_in);
    gl->Uniform1i(gl->GetUniformLocation(prog, "u_out"), c->n_out);
    gl->DispatchCompute((SAMPLES + 63) / 64, 1, 1);
    gl->MemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    gl->GetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0,
                         (GLsizeiptr)(SAMPLES * c->n_out * sizeof(float)), out);
    assert_int_equal(gl->GetError(), GL_NO_ERROR);
    gl->UseProgram(0);
    gl->DeleteBuffers(2, buf);
    gl->DeleteProgram(prog);
}

/* One case over SAMPLES inputs; returns 1 when a sample is out of its bound. */
static int check_case(fixture *f, const shader_case *c, int seed, float *in, float *gpu)
{
    assert_true(c->n_in <= MAX_IN && c->n_out <= MAX_OUT);
    uint64_t rng = 0x9E3779B97F4A7C15ull ^ (uint64_t)(seed + 1) * 0xD1B54A32D192ED03ull;
    for (int i = 0; i < SAMPLES; i++) c->gen(f, i, &rng, in + (size_t)i * c->n_in);
    run_case_gpu(f, c, in, gpu);
    double worst_abs = 0, worst_rel = 0;
    int bad = -1, bad_k = 0;
    for (int i = 0; i < SAMPLES; i++) {
        float ref[MAX_OUT];
        const float *x = in + (size_t)i * c->n_in;
        c->ref(f, x, ref);
        double abs_tol = c->abs_tol + (c->extra_abs ? c->extra_abs(x) : 0.0);
        for (int k = 0; k < c->n_out; k++) {
            double g = gpu[(size_t)i * c->n_out + k], r = ref[k];
            double err = fabs(g - r);
            if (!(err <= abs_tol + c->rel_tol * fabs(r)) && bad < 0) {
                bad = i;
                bad_k = k;
            }
            if (err > worst_abs) worst_abs = err;
            double rel = err / fmax(fabs(r), 1e-30);
            if (fabs(r) > 1e-3 && rel > worst_rel) worst_rel = rel;
            if (!(err == err)) worst_abs = INFINITY; /* NaN */
        }
    }
    print_message("%-32s %9.2e %9.2e  %.0e+%.0e|c| %s\n", c->name, worst_abs, worst_rel,
                  c->abs_tol, c->rel_tol, c->why);
    if (bad < 0) return 0;
    float ref[MAX_OUT];
    const float *x = in + (size_t)bad * c->n_in;
    c->ref(f, x, ref);
    print_error("%s: sample %d output %d: GPU %.9g, C %.9g; inputs:", c->name, bad, bad_k,
                (double)gpu[(size_t)bad * c->n_out + bad_k], (double)ref[bad_k]);
    for (int k = 0; k < c->n_in; k++) print_error(" %.9g", (double)x[k]);
    print_error("\n");
    return 1;
}

static void functions_match_c(void **state)
{
    fixture *f = *state;
    float *in = malloc((size_t)SAMPLES * MAX_IN * sizeof(float));
    float *gpu = malloc((size_t)SAMPLES * MAX_OUT * sizeof(float));
    assert_non_null(in);
    assert_non_null(gpu);
    int failed = 0;
    print_message("%-32s %9s %9s  %-10s %s\n", "function", "max abs", "max rel", "bound",
                  "why");
    for (int ci = 0; ci < shader_case_count; ci++)
        failed += check_case(f, &shader_cases[ci], ci, in, gpu);
    for (int ci = 0; ci < shader_light_case_count; ci++)
        failed += check_case(f, &shader_light_cases[ci], 1000 + ci, in, gpu);
    free(in);
    free(gpu);
    assert_int_equal(failed, 0);
}

/* ---- 3. the full frame -------------------------------------------------------------------- */

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static double luminance(const float *c)
{
    return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
}

/* Bounds of the per-pixel relative luminance error |gpu - c| / (c + 1% of the frame's mean)
 * over the sphere pixels. Measured on llvmpipe (256x128, forest): mean 1.2e-4, p99 1.9e-3,
 * max 4.2e-2 (docs/SHADERS.md). The texture reads agree to 1e-7 (functions_match_c); what
 * remains is the hit point and normal, which the GPU rounds differently (fused multiply-adds
 * in the ray-sphere solve): a normal that moves by 1e-6 rad on a near-mirror sphere moves
 * the reflected texel, most at the silhouettes where R sweeps fastest. The bounds leave 5x. */
#define FRAME_MEAN_BOUND 1e-3
#define FRAME_P99_BOUND 1e-2

/* The sphere grid drawn by examples/sphere_grid.frag against ibl_render, with lights (count
 * may be 0), within the bounds on the mean and 99th percentile. */
static void compare_frame(fixture *f, const ibl_light *lights, int count, double mean_bound,
                          double p99_bound)
{
    enum { W = 256, H = 128 };
    ibl_render_desc rd = {.width = W, .height = H, .supersample = 1, .lights = lights,
                          .light_count = count};
    ibl_shader_lights block;
    assert_int_equal(ibl_shader_lights_fill(f->ctx, lights, count, &block), IBL_OK);
    ibl_image ref, gpu;
    int *ids = malloc(sizeof(int) * W * H);
    unsigned char *hit = malloc(W * H);
    assert_non_null(ids);
    assert_non_null(hit);
    assert_int_equal(ibl_render(f->ctx, &f->probe, &rd, &ref, ids), IBL_OK);
    char *frag = glh_read_text(IBL_EXAMPLES_DIR "/sphere_grid.frag");
    assert_non_null(frag);
    char log[4096] = "";
    ibl_status st = sg_render(&f->gl, f->ctx, &f->gpu, &block, f->glsl, frag, W, H, &gpu, hit,
                              log, sizeof log);
    if (st != IBL_OK) print_error("sphere grid: %s\n", log);
    assert_int_equal(st, IBL_OK);
    double mean_lum = 0;
    for (int i = 0; i < W * H; i++) mean_lum += luminance(ref.pixels + (size_t)i * 4);
    mean_lum /= W * H;
    double *err = malloc(sizeof(double) * W * H), bg_worst = 0, sum = 0;
    assert_non_null(err);
    int n = 0, id_mismatch = 0;
    for (int i = 0; i < W * H; i++) {
        double c = luminance(ref.pixels + (size_t)i * 4), g = luminance(gpu.pixels + (size_t)i * 4);
        double e = fabs(g - c) / (c + 0.01 * mean_lum);
        if ((ids[i] >= 0) != (hit[i] != 0)) {
            id_mismatch++; /* a silhouette pixel whose centre ray the two round differently */
            continue;
        }
        if (ids[i] < 0) {
            if (e > bg_worst) bg_worst = e;
            continue;
        }
        err[n++] = e;
        sum += e;
    }
    qsort(err, (size_t)n, sizeof(double), cmp_double);
    double mean = sum / n, p99 = err[(size_t)(0.99 * (n - 1))], worst = err[n - 1];
    print_message("full frame %dx%d, %d lights (frame mean %.3g), %d sphere pixels: mean %.2e, "
                  "p99 %.2e, max %.2e; "
                  "background max %.2e; %d silhouette pixels hit differently\n",
                  W, H, count, mean_lum, n, mean, p99, worst, bg_worst, id_mismatch);
    assert_true(mean <= mean_bound);
    assert_true(p99 <= p99_bound);
    assert_true(bg_worst <= FRAME_P99_BOUND);
    assert_true(id_mismatch <= W * H / 1000);
    free(err);
    free(frag);
    free(ids);
    free(hit);
    ibl_image_free(f->ctx, &ref);
    ibl_image_free(f->ctx, &gpu);
}

static void full_frame_matches_c_renderer(void **state)
{
    compare_frame(*state, NULL, 0, FRAME_MEAN_BOUND, FRAME_P99_BOUND);
}

/* The same with three lights of every type, each with a size (the shininess hack and Karis'
 * alpha widen the highlights), a range and a cone edge crossing the grid. The highlights of
 * the near-mirror spheres are where a normal rounded differently moves the result most (the
 * lobe's n.h, as in functions_match_c); measured on llvmpipe: mean 1.25e-4, p99 1.9e-3 (the
 * lights raise the frame's mean luminance from 0.27 to 0.38). Same bounds as without lights. */
static void full_frame_with_lights_matches_c_renderer(void **state)
{
    ibl_light lights[3];
    memset(lights, 0, sizeof lights);
    lights[0].type = IBL_LIGHT_DIRECTIONAL; /* a sun from the upper left, in front */
    lights[0].direction = (ibl_vec3){0.5f, -0.6f, -0.6f};
    lights[0].color[0] = 1.0f, lights[0].color[1] = 0.95f, lights[0].color[2] = 0.85f;
    lights[0].intensity = 2.0f;
    lights[0].size = 0.0047f;
    lights[1].type = IBL_LIGHT_POINT; /* a warm lamp on the right, reaching the middle row */
    lights[1].position = (ibl_vec3){3.0f, 1.5f, 2.0f};
    lights[1].color[0] = 1.0f, lights[1].color[1] = 0.6f, lights[1].color[2] = 0.3f;
    lights[1].intensity = 12.0f;
    lights[1].range = 6.0f;
    lights[1].size = 0.1f;
    lights[2].type = IBL_LIGHT_SPOT; /* a blue spot on the left spheres, its edge across them */
    lights[2].position = (ibl_vec3){-2.5f, 0.0f, 3.0f};
    lights[2].direction = (ibl_vec3){0.0f, 0.0f, -1.0f};
    lights[2].color[0] = 0.4f, lights[2].color[1] = 0.6f, lights[2].color[2] = 1.0f;
    lights[2].intensity = 20.0f;
    lights[2].inner_cone = 0.2f;
    lights[2].outer_cone = 0.45f;
    lights[2].size = 0.05f;
    compare_frame(*state, lights, 3, FRAME_MEAN_BOUND, FRAME_P99_BOUND);
}

/* The example program (examples/render_spheres) on a bake folder writes the PNG `ibl render`
 * writes of the same folder: same framing, shading and tone mapping. Silhouette pixels may
 * differ (the two round the ray-sphere test differently): at most 0.5% of the pixels. */
static void example_png_matches_cli(void **state)
{
    fixture *f = *state;
    char dir[1024], cli_png[1024], gl_png[1024];
    snprintf(dir, sizeof dir, "%s", test_path("bake"));
    snprintf(cli_png, sizeof cli_png, "%s", test_path("cli.png"));
    snprintf(gl_png, sizeof gl_png, "%s", test_path("gl.png"));
    assert_int_equal(ibl_bake_write(f->ctx, &f->bake, dir), IBL_OK);
    const char *out = NULL;
    int rc = test_run_cli(&out, "render -q '%s' -o '%s' --width 256 --height 128", dir, cli_png);
    if (rc != 0) print_error("%s\n", out);
    assert_int_equal(rc, 0);
    char cmd[4096];
    snprintf(cmd, sizeof cmd, "'%s' '%s' '%s' 256 128", IBL_EXAMPLE_PATH, dir, gl_png);
    assert_int_equal(system(cmd), 0);
    ibl_image a, b;
    assert_int_equal(ibl_read_image(f->ctx, cli_png, NULL, &a, NULL), IBL_OK);
    assert_int_equal(ibl_read_image(f->ctx, gl_png, NULL, &b, NULL), IBL_OK);
    assert_int_equal(a.width, b.width);
    assert_int_equal(a.height, b.height);
    int differ = 0, n = a.width * a.height;
    for (int i = 0; i < n; i++)
        for (int c = 0; c < 3; c++) {
            float x = a.pixels[(size_t)i * 4 + c], y = b.pixels[(size_t)i * 4 + c];
            if (fabsf(x - y) > 0.02f * fmaxf(x, y) + 1e-3f) {
                differ++;
                break;
            }
        }
    print_message("example PNG vs `ibl render` PNG: %d of %d pixels differ\n", differ, n);
    assert_true(differ <= n / 200);
    ibl_image_free(f->ctx, &a);
    ibl_image_free(f->ctx, &b);
}

/* shaders/ibl_box_mip.comp (the box chain of the dynamic path) against ibl_cubemap_build_mips:
 * the forest cube's 32 -> 1 chain. Bound: 1e-6 relative (float accumulation of four products
 * against the C's double). */
static void box_mips_match_c(void **state)
{
    fixture *f = *state;
    const glh_gl *gl = &f->gl.gl;
    char *src = read_shader("ibl_box_mip.comp");
    assert_non_null(src);
    assert_int_equal(validate("-V -S comp -o /dev/null", test_path("box_mip.comp"), "", src, ""), 0);
    const char *srcs[1] = {src};
    GLenum type = GL_COMPUTE_SHADER;
    char log[4096] = "";
    GLuint prog = glh_program(&f->gl, log, sizeof log, 1, &type, srcs);
    if (!prog) print_error("ibl_box_mip.comp: %s\n", log);
    assert_true(prog != 0);
    int size = f->env.size, levels = ibl_full_mip_count(size);
    ibl_cubemap ref;
    assert_int_equal(ibl_cubemap_alloc(f->ctx, size, levels, &ref), IBL_OK);
    for (int face = 0; face < 6; face++)
        memcpy(ibl_cubemap_face(&ref, 0, face), ibl_cubemap_face(&f->env, 0, face),
               (size_t)size * size * 4 * sizeof(float));
    assert_int_equal(ibl_cubemap_build_mips(f->ctx, &ref), IBL_OK);
    /* level 0 uploaded, the others made on the GPU */
    GLuint tex = glp_cube_texture(gl, &ref, 1), buf;
    gl->BindTexture(GL_TEXTURE_CUBE_MAP, tex);
    for (int k = 1; k < levels; k++)
        for (int face = 0; face < 6; face++)
            gl->TexImage2D(GL_TEXTURE_CUBE_MAP_POSITIVE_X + (GLenum)face, k, GL_RGBA32F,
                           ibl_level_size(size, k), ibl_level_size(size, k), 0, GL_RGBA, GL_FLOAT,
                           NULL);
    /* an image unit needs its level inside [BASE_LEVEL, MAX_LEVEL] of a complete texture */
    gl->TexParameteri(GL_TEXTURE_CUBE_MAP, GL_TEXTURE_MAX_LEVEL, levels - 1);
    gl->TexParameteri(GL_TEXTURE_CUBE_MAP, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
    gl->GenBuffers(1, &buf);
    float *table = malloc((size_t)size * size * sizeof(float));
    float *back = malloc((size_t)size * size * 4 * sizeof(float));
    assert_non_null(table);
    assert_non_null(back);
    gl->UseProgram(prog);
    for (int k = 1; k < levels; k++) {
        int cn = ibl_level_size(size, k - 1), n = ibl_level_size(size, k);
        ibl_cube_solid_angle_table(cn, table);
        gl->BindBuffer(GL_SHADER_STORAGE_BUFFER, buf);
        gl->BufferData(GL_SHADER_STORAGE_BUFFER, (GLsizeiptr)((size_t)cn * cn * sizeof(float)),
                       table, GL_STATIC_DRAW);
        gl->BindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, buf);
        gl->BindImageTexture(0, tex, k - 1, GL_TRUE, 0, GL_READ_ONLY, GL_RGBA32F);
        gl->BindImageTexture(1, tex, k, GL_TRUE, 0, GL_WRITE_ONLY, GL_RGBA32F);
        gl->Uniform1i(gl->GetUniformLocation(prog, "u_child_size"), cn);
        gl->DispatchCompute((GLuint)(n + 7) / 8, (GLuint)(n + 7) / 8, 6);
        gl->MemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_UPDATE_BARRIER_BIT);
    }
    double worst = 0;
    gl->BindTexture(GL_TEXTURE_CUBE_MAP, tex);
    gl->PixelStorei(GL_PACK_ALIGNMENT, 4);
    for (int k = 1; k < levels; k++)
        for (int face = 0; face < 6; face++) {
            int n = ibl_level_size(size, k);
            gl->GetTexImage(GL_TEXTURE_CUBE_MAP_POSITIVE_X + (GLenum)face, k, GL_RGBA, GL_FLOAT, back);
            const float *c = ibl_cubemap_face(&ref, k, face);
            for (int i = 0; i < n * n * 4; i++) {
                double e = fabs((double)back[i] - c[i]) / fmax(fabs((double)c[i]), 1e-6);
                if (e > worst) worst = e;
            }
        }
    assert_int_equal(gl->GetError(), GL_NO_ERROR);
    print_message("box mips %d -> 1 (%d levels): max relative error %.2e\n", size, levels, worst);
    assert_true(worst <= 1e-6);
    gl->UseProgram(0);
    gl->DeleteBuffers(1, &buf);
    gl->DeleteTextures(1, &tex);
    gl->DeleteProgram(prog);
    free(table);
    free(back);
    free(src);
    ibl_cubemap_free(f->ctx, &ref);
}

/* ---- 4. the dynamic path: the Gaussian chain on the GPU ---------------------------------- */

static double now_ms(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec * 1e3 + t.tv_nsec * 1e-6;
}

static GLuint compute_program(fixture *f, const char *name)
{
    char *src = read_shader(name);
    assert_non_null(src);
    char vk[1024];
    snprintf(vk, sizeof vk, "%s", test_path(name));
    assert_int_equal(validate("-V -S comp -o /dev/null", vk, "", src, ""), 0);
    const char *srcs[1] = {src};
    GLenum type = GL_COMPUTE_SHADER;
    char log[4096] = "";
    GLuint prog = glh_program(&f->gl, log, sizeof log, 1, &type, srcs);
    if (!prog) print_error("%s: %s\n", name, log);
    assert_true(prog != 0);
    free(src);
    return prog;
}

/* An empty RGBA32F cube with `levels` levels of edge n, complete (image units need that). */
/* The solid angles of the box mips' child levels, 64 down to 2, one storage buffer each (the
 * dynamic chains' area-correct box mips read them). */
static void upload_solid_angles(const glh_gl *gl, GLuint buffers[8])
{
    float *table = malloc((size_t)64 * 64 * sizeof(float));
    assert_non_null(table);
    gl->GenBuffers(8, buffers);
    for (int t = 0; t < 6; t++) {
        int cn = 64 >> t;
        ibl_cube_solid_angle_table(cn, table);
        gl->BindBuffer(GL_SHADER_STORAGE_BUFFER, buffers[t]);
        gl->BufferData(GL_SHADER_STORAGE_BUFFER, (GLsizeiptr)((size_t)cn * cn * sizeof(float)),
                       table, GL_STATIC_DRAW);
    }
    free(table);
}

/* The largest relative error of a GPU chain (texture tex, levels of edge `edge` down) against
 * the C plan's cube, RGB, relative to max(|C|, 1e-3 of the level's mean). */
static double chain_max_relative_error(const glh_gl *gl, GLuint tex, const ibl_cubemap *dst,
                                       int edge, int levels)
{
    float *back = malloc((size_t)edge * edge * 4 * sizeof(float));
    assert_non_null(back);
    double worst = 0;
    gl->BindTexture(GL_TEXTURE_CUBE_MAP, tex);
    gl->PixelStorei(GL_PACK_ALIGNMENT, 4);
    for (int l = 0; l < levels; l++) {
        int n = ibl_level_size(edge, l);
        double mean = 0;
        for (int face = 0; face < 6; face++) {
            const float *c = ibl_cubemap_face(dst, l, face);
            for (int i = 0; i < n * n; i++) mean += (c[4 * i] + c[4 * i + 1] + c[4 * i + 2]) / 3.0;
        }
        mean /= 6.0 * n * n;
        for (int face = 0; face < 6; face++) {
            gl->GetTexImage(GL_TEXTURE_CUBE_MAP_POSITIVE_X + (GLenum)face, l, GL_RGBA, GL_FLOAT, back);
            const float *c = ibl_cubemap_face(dst, l, face);
            for (int i = 0; i < n * n; i++)
                for (int k = 0; k < 3; k++) {
                    double e = fabs((double)back[4 * i + k] - c[4 * i + k]) /
                               fmax(fabs((double)c[4 * i + k]), 1e-3 * mean);
                    if (e > worst) worst = e;
                }
        }
    }
    free(back);
    return worst;
}

static GLuint empty_cube(const glh_gl *gl, int n, int levels)
{
    GLuint tex;
    gl->GenTextures(1, &tex);
    gl->BindTexture(GL_TEXTURE_CUBE_MAP, tex);
    for (int k = 0; k < levels; k++)
        for (int face = 0; face < 6; face++)
            gl->TexImage2D(GL_TEXTURE_CUBE_MAP_POSITIVE_X + (GLenum)face, k, GL_RGBA32F,
                           ibl_level_size(n, k), ibl_level_size(n, k), 0, GL_RGBA, GL_FLOAT, NULL);
    gl->TexParameteri(GL_TEXTURE_CUBE_MAP, GL_TEXTURE_MAX_LEVEL, levels - 1);
    gl->TexParameteri(GL_TEXTURE_CUBE_MAP, GL_TEXTURE_MIN_FILTER, GL_NEAREST_MIPMAP_NEAREST);
    return tex;
}

static void dispatch(const glh_gl *gl, GLuint prog, GLuint src, int src_level, GLuint dst,
                     int dst_level, int n)
{
    gl->UseProgram(prog);
    gl->BindImageTexture(0, src, src_level, GL_TRUE, 0, GL_READ_ONLY, GL_RGBA32F);
    gl->BindImageTexture(1, dst, dst_level, GL_TRUE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    gl->DispatchCompute((GLuint)(n + 7) / 8, (GLuint)(n + 7) / 8, 6);
    gl->MemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_UPDATE_BARRIER_BIT);
}

typedef struct gauss_gpu {
    GLuint box, gauss, fixup;          /* programs                                           */
    GLuint src, chain, scratch, blurred, out; /* cubes                                        */
    GLuint angles[8];                  /* solid-angle tables of the child edges 64 .. 2      */
    int source, edge, levels;
    float sigma[IBL_MAX_LEVELS];
    int radius[IBL_MAX_LEVELS];
} gauss_gpu;

/* One frame: box chain from the source (level 0 the 2x2 block means), each level blurred
 * (rows, columns), then its overlap fixup into the output. */
static void gauss_frame(const glh_gl *gl, const gauss_gpu *g)
{
    for (int l = 0; l < g->levels; l++) {
        int n = ibl_level_size(g->edge, l), cn = l == 0 ? g->source : 2 * n, t = 0;
        while ((g->source >> t) != cn) t++;
        gl->UseProgram(g->box);
        gl->BindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, g->angles[t]);
        gl->Uniform1i(gl->GetUniformLocation(g->box, "u_child_size"), cn);
        dispatch(gl, g->box, l == 0 ? g->src : g->chain, l == 0 ? 0 : l - 1, g->chain, l, n);
        for (int pass = 0; pass < 2; pass++) {
            gl->UseProgram(g->gauss);
            gl->Uniform1i(gl->GetUniformLocation(g->gauss, "u_size"), n);
            gl->Uniform1i(gl->GetUniformLocation(g->gauss, "u_radius"), g->radius[l]);
            gl->Uniform1f(gl->GetUniformLocation(g->gauss, "u_sigma"), g->sigma[l]);
            gl->Uniform1i(gl->GetUniformLocation(g->gauss, "u_pass"), pass);
            dispatch(gl, g->gauss, pass == 0 ? g->chain : g->scratch, l,
                     pass == 0 ? g->scratch : g->blurred, l, n);
        }
        gl->UseProgram(g->fixup);
        gl->Uniform1i(gl->GetUniformLocation(g->fixup, "u_size"), n);
        dispatch(gl, g->fixup, g->blurred, l, g->out, l, n);
    }
}

/* shaders/ibl_box_mip.comp + ibl_dynamic_gauss.comp + ibl_dynamic_fixup.comp against the C
 * plan of dynamic-gauss32 (ibl_specular_plan_run, .dynamic = 1) on the forest as a 64x64x6
 * "freshly rendered" cube. The kernel weights are computed in the shader (float) from sigma
 * and radius (the documented formula, in double here); the C accumulates in double. Bound:
 * 2e-6 of max(|C|, 1e-3 of the level's mean): float sums of <= 63 taps (a few ulps per
 * stage, four stages). Timing on llvmpipe reported, not asserted. */
static void dynamic_gauss_matches_plan(void **state)
{
    fixture *f = *state;
    const glh_gl *gl = &f->gl.gl;
    ibl_image im;
    ibl_cubemap src, dst;
    assert_int_equal(ibl_read_image(f->ctx, test_data("forest_128x64.exr"), NULL, &im, NULL), IBL_OK);
    ibl_to_cube_desc cd = {.layout = IBL_LAYOUT_EQUIRECT, .size = 64};
    assert_int_equal(ibl_image_to_cubemap(f->ctx, &im, &cd, &src), IBL_OK);
    ibl_image_free(f->ctx, &im);
    ibl_specular_desc d;
    assert_true(ibl_specular_preset("dynamic-gauss32", &d));
    d.source_size = 64;
    ibl_specular_plan *plan;
    assert_int_equal(ibl_specular_plan_create(f->ctx, &d, &plan), IBL_OK);
    const ibl_specular_info *info = ibl_specular_plan_info(plan);
    gauss_gpu g = {.source = 64, .edge = info->size, .levels = info->levels};
    assert_int_equal(ibl_cubemap_alloc(f->ctx, g.edge, g.levels, &dst), IBL_OK);
    double t0 = now_ms();
    assert_int_equal(ibl_specular_plan_run(plan, &src, &dst), IBL_OK);
    double cpu_ms = now_ms() - t0;
    for (int l = 0; l < g.levels; l++) {
        int n = ibl_level_size(g.edge, l);
        double e = ibl_specular_level_phong_exponent(info, l);
        double var = e > 0 && isfinite(e) ? 0.25 * n * n / (e + 3.0) - 1.0 / 12.0 : 0.0;
        double sigma = var > 0 ? sqrt(var) : 0.0;
        g.sigma[l] = (float)sigma;
        g.radius[l] = sigma < 1e-3 || n < 2 ? 0 : (int)fmin(n - 1, ceil(4.0 * sigma));
    }
    g.box = compute_program(f, "ibl_box_mip.comp");
    g.gauss = compute_program(f, "ibl_dynamic_gauss.comp");
    g.fixup = compute_program(f, "ibl_dynamic_fixup.comp");
    g.src = glp_cube_texture(gl, &src, 1);
    g.chain = empty_cube(gl, g.edge, g.levels);
    g.scratch = empty_cube(gl, g.edge, g.levels);
    g.blurred = empty_cube(gl, g.edge, g.levels);
    g.out = empty_cube(gl, g.edge, g.levels);
    upload_solid_angles(gl, g.angles);
    gauss_frame(gl, &g); /* the first frame compiles the pipelines' shaders in the driver */
    gl->Finish();
    enum { FRAMES = 5 };
    t0 = now_ms();
    for (int i = 0; i < FRAMES; i++) gauss_frame(gl, &g);
    gl->Finish();
    double gpu_ms = (now_ms() - t0) / FRAMES;
    double worst = chain_max_relative_error(gl, g.out, &dst, g.edge, g.levels);
    assert_int_equal(gl->GetError(), GL_NO_ERROR);
    print_message("dynamic-gauss32 on the GPU (64 -> %d, %d levels): max relative error %.2e; "
                  "llvmpipe %.2f ms per frame (C plan %.2f ms, one run)\n",
                  g.edge, g.levels, worst, gpu_ms, cpu_ms);
    assert_true(worst <= 2e-6);
    gl->UseProgram(0);
    gl->DeleteBuffers(8, g.angles);
    GLuint cubes[5] = {g.src, g.chain, g.scratch, g.blurred, g.out};
    gl->DeleteTextures(5, cubes);
    gl->DeleteProgram(g.box);
    gl->DeleteProgram(g.gauss);
    gl->DeleteProgram(g.fixup);
    ibl_specular_plan_destroy(plan);
    ibl_cubemap_free(f->ctx, &dst);
    ibl_cubemap_free(f->ctx, &src);
}

/* ---- 5. the dynamic path: the spherical Phong presets on the GPU ------------------------- */

typedef struct phong_gpu {
    GLuint box, phong, fixup;          /* programs                                           */
    GLuint pyramid, filtered, out;     /* cubes: source + its box mips, rows' output, final   */
    GLuint angles[8];                  /* solid-angle tables of the child edges 64 .. 2      */
    GLuint csr[IBL_MAX_LEVELS][3];     /* per level: row offsets, columns, weights           */
    ibl_specular_plan_rows rows[IBL_MAX_LEVELS];
    int source, edge, levels, mips;
} phong_gpu;

/* One frame: the box mips of the source (level 0 rendered there), every level's rows, and
 * the fixup where the plan applies one (dynamic-phong: its 1x1 level). */
static void phong_frame(const glh_gl *gl, const phong_gpu *g)
{
    for (int m = 1; m < g->mips; m++) {
        int cn = g->source >> (m - 1);
        gl->UseProgram(g->box);
        gl->BindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, g->angles[m - 1]);
        gl->Uniform1i(gl->GetUniformLocation(g->box, "u_child_size"), cn);
        dispatch(gl, g->box, g->pyramid, m - 1, g->pyramid, m, cn / 2);
    }
    for (int l = 0; l < g->levels; l++) {
        const ibl_specular_plan_rows *r = &g->rows[l];
        int fix = r->fixup != IBL_EDGE_FIXUP_NONE;
        gl->UseProgram(g->phong);
        for (int b = 0; b < 3; b++) gl->BindBufferBase(GL_SHADER_STORAGE_BUFFER, (GLuint)b, g->csr[l][b]);
        gl->Uniform1i(gl->GetUniformLocation(g->phong, "u_size"), r->size);
        gl->Uniform1i(gl->GetUniformLocation(g->phong, "u_mip_size"), r->source_size);
        dispatch(gl, g->phong, g->pyramid, r->source_mip, fix ? g->filtered : g->out, l, r->size);
        if (!fix) continue;
        gl->UseProgram(g->fixup);
        gl->Uniform1i(gl->GetUniformLocation(g->fixup, "u_size"), r->size);
        dispatch(gl, g->fixup, g->filtered, l, g->out, l, r->size);
    }
}

/* shaders/ibl_box_mip.comp + ibl_dynamic_phong.comp (+ ibl_dynamic_fixup.comp at 1x1) against
 * the C plan of a dynamic Phong preset (ibl_specular_plan_run) on the forest as a 64x64x6
 * cube. The GPU reads the plan's own float weights (ibl_specular_plan_rows_fill), so only the
 * order of the float additions differs: the C sums eight lanes and two chunk sets apart, the
 * shader one tap after another (rows of up to a few thousand positive taps), plus the box
 * mips' float means (2.7e-7, box_mips_match_c). Bound: 5e-6 of max(|C|, 1e-3 of the level's
 * mean); measured 1.4e-6 (phong16) and 2.1e-6 (phong32). Timing on llvmpipe reported, not
 * asserted. */
static void phong_preset_matches_plan(fixture *f, const char *preset)
{
    const glh_gl *gl = &f->gl.gl;
    ibl_image im;
    ibl_cubemap src, dst;
    assert_int_equal(ibl_read_image(f->ctx, test_data("forest_128x64.exr"), NULL, &im, NULL), IBL_OK);
    ibl_to_cube_desc cd = {.layout = IBL_LAYOUT_EQUIRECT, .size = 64};
    assert_int_equal(ibl_image_to_cubemap(f->ctx, &im, &cd, &src), IBL_OK);
    ibl_image_free(f->ctx, &im);
    ibl_specular_desc d;
    assert_true(ibl_specular_preset(preset, &d));
    d.source_size = 64;
    ibl_specular_plan *plan;
    assert_int_equal(ibl_specular_plan_create(f->ctx, &d, &plan), IBL_OK);
    const ibl_specular_info *info = ibl_specular_plan_info(plan);
    phong_gpu g = {.source = 64, .edge = info->size, .levels = info->levels, .mips = 1};
    assert_int_equal(ibl_cubemap_alloc(f->ctx, g.edge, g.levels, &dst), IBL_OK);
    double t0 = now_ms();
    assert_int_equal(ibl_specular_plan_run(plan, &src, &dst), IBL_OK);
    double cpu_ms = now_ms() - t0;
    size_t taps = 0;
    for (int l = 0; l < g.levels; l++) {
        ibl_specular_plan_rows *r = &g.rows[l];
        assert_int_equal(ibl_specular_plan_rows_info(plan, l, r), IBL_OK);
        assert_int_equal(r->size, ibl_level_size(g.edge, l));
        assert_int_equal(r->source_size, 64 >> r->source_mip);
        assert_true(r->fixup == IBL_EDGE_FIXUP_NONE || r->fixup == IBL_EDGE_FIXUP_OVERLAP);
        if (r->source_mip + 1 > g.mips) g.mips = r->source_mip + 1;
        uint32_t *offsets = malloc((r->rows + 1) * sizeof(uint32_t));
        uint32_t *columns = malloc((r->taps ? r->taps : 1) * sizeof(uint32_t));
        float *weights = malloc((r->taps ? r->taps : 1) * sizeof(float));
        assert_true(offsets && columns && weights);
        assert_int_equal(ibl_specular_plan_rows_fill(plan, l, offsets, columns, weights), IBL_OK);
        assert_int_equal(offsets[0], 0);
        assert_int_equal(offsets[r->rows], r->taps);
        /* every row a normalised list of texels of the mip */
        size_t mip_texels = (size_t)6 * r->source_size * r->source_size;
        for (size_t i = 0; i < r->rows; i++) {
            double sum = 0;
            assert_true(offsets[i] <= offsets[i + 1]);
            for (uint32_t k = offsets[i]; k < offsets[i + 1]; k++) {
                assert_true(columns[k] < mip_texels);
                sum += weights[k];
            }
            assert_true(fabs(sum - 1.0) < 1e-5);
        }
        taps += r->taps;
        gl->GenBuffers(3, g.csr[l]);
        const void *data[3] = {offsets, columns, weights};
        size_t bytes[3] = {(r->rows + 1) * sizeof(uint32_t), (r->taps ? r->taps : 1) * sizeof(uint32_t),
                           (r->taps ? r->taps : 1) * sizeof(float)};
        for (int b = 0; b < 3; b++) {
            gl->BindBuffer(GL_SHADER_STORAGE_BUFFER, g.csr[l][b]);
            gl->BufferData(GL_SHADER_STORAGE_BUFFER, (GLsizeiptr)bytes[b], data[b], GL_STATIC_DRAW);
        }
        free(offsets);
        free(columns);
        free(weights);
    }
    /* not a lobe plan: no rows */
    ibl_specular_desc gd;
    ibl_specular_plan *gauss;
    ibl_specular_plan_rows none;
    assert_true(ibl_specular_preset("dynamic-gauss32", &gd));
    gd.source_size = 64;
    assert_int_equal(ibl_specular_plan_create(f->ctx, &gd, &gauss), IBL_OK);
    assert_int_equal(ibl_specular_plan_rows_info(gauss, 0, &none), IBL_ERR_INVALID_ARGUMENT);
    assert_int_equal(ibl_specular_plan_rows_info(plan, g.levels, &none), IBL_ERR_INVALID_ARGUMENT);
    ibl_specular_plan_destroy(gauss);

    g.box = compute_program(f, "ibl_box_mip.comp");
    g.phong = compute_program(f, "ibl_dynamic_phong.comp");
    g.fixup = compute_program(f, "ibl_dynamic_fixup.comp");
    /* the source's level 0 uploaded (the "freshly rendered" cube), its box mips made here */
    g.pyramid = glp_cube_texture(gl, &src, 1);
    gl->BindTexture(GL_TEXTURE_CUBE_MAP, g.pyramid);
    for (int k = 1; k < g.mips; k++)
        for (int face = 0; face < 6; face++)
            gl->TexImage2D(GL_TEXTURE_CUBE_MAP_POSITIVE_X + (GLenum)face, k, GL_RGBA32F, 64 >> k, 64 >> k, 0,
                           GL_RGBA, GL_FLOAT, NULL);
    gl->TexParameteri(GL_TEXTURE_CUBE_MAP, GL_TEXTURE_MAX_LEVEL, g.mips - 1);
    gl->TexParameteri(GL_TEXTURE_CUBE_MAP, GL_TEXTURE_MIN_FILTER, GL_NEAREST_MIPMAP_NEAREST);
    g.filtered = empty_cube(gl, g.edge, g.levels);
    g.out = empty_cube(gl, g.edge, g.levels);
    upload_solid_angles(gl, g.angles);
    phong_frame(gl, &g); /* the first frame compiles the pipelines' shaders in the driver */
    gl->Finish();
    enum { FRAMES = 5 };
    t0 = now_ms();
    for (int i = 0; i < FRAMES; i++) phong_frame(gl, &g);
    gl->Finish();
    double gpu_ms = (now_ms() - t0) / FRAMES;
    double worst = chain_max_relative_error(gl, g.out, &dst, g.edge, g.levels);
    assert_int_equal(gl->GetError(), GL_NO_ERROR);
    print_message("%s on the GPU (64 -> %d, %d levels, box mips to %d, %zu taps): max relative "
                  "error %.2e; llvmpipe %.2f ms per frame (C plan %.2f ms, one run)\n",
                  preset, g.edge, g.levels, 64 >> (g.mips - 1), taps, worst, gpu_ms, cpu_ms);
    assert_true(worst <= 5e-6);
    gl->UseProgram(0);
    gl->DeleteBuffers(8, g.angles);
    for (int l = 0; l < g.levels; l++) gl->DeleteBuffers(3, g.csr[l]);
    GLuint cubes[3] = {g.pyramid, g.filtered, g.out};
    gl->DeleteTextures(3, cubes);
    gl->DeleteProgram(g.box);
    gl->DeleteProgram(g.phong);
    gl->DeleteProgram(g.fixup);
    ibl_specular_plan_destroy(plan);
    ibl_cubemap_free(f->ctx, &dst);
    ibl_cubemap_free(f->ctx, &src);
}

static void dynamic_phong16_matches_plan(void **state)
{
    phong_preset_matches_plan(*state, "dynamic-phong16");
}

static void dynamic_phong32_matches_plan(void **state)
{
    phong_preset_matches_plan(*state, "dynamic-phong32");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(gl_context),
        cmocka_unit_test(compile_all_dialects),
        cmocka_unit_test(functions_match_c),
        cmocka_unit_test(full_frame_matches_c_renderer),
        cmocka_unit_test(full_frame_with_lights_matches_c_renderer),
        cmocka_unit_test(example_png_matches_cli),
        cmocka_unit_test(box_mips_match_c),
        cmocka_unit_test(dynamic_gauss_matches_plan),
        cmocka_unit_test(dynamic_phong16_matches_plan),
        cmocka_unit_test(dynamic_phong32_matches_plan),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
