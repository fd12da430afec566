/* The probe bake's shaders against the C run time (src/probes/probe_runtime.c) on Mesa's
 * llvmpipe (tests/support/gl_harness.c):
 *  1. shaders/ibl_probes.glsl (after ibl.glsl) compiles as GLSL 4.50 and Vulkan GLSL, its
 *     twin ibl_probes.hlsl (after ibl.hlsl) as HLSL, ibl_probe_cull.comp as GLSL and Vulkan;
 *  2. the per-pixel blend (weights, parallax on box and sphere proxies, alpha-aware priority
 *     blend, the global probe last; and each comparison switch) over a real probe bake read
 *     from disk (its probes.bin bound as the shader's buffer, its probes.ktx2 as a cube-map
 *     array) equals ibl_probes_shade; tri-Ace's blending and the environment switch equal
 *     their definitions evaluated with the C's ibl_shade_dir;
 *  3. the tiled culling on the GPU gives the C's lists (ibl_cull_probes, each of the three
 *     sorts, the same comparison counts) and, in exact mode, a per-pixel brute force's. */
#include "test_support.h"
#include "gl_harness.h"
#include "gl_probe.h"

#include "ibl/probes.h"
#include "ibl/shader.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static char *read_shader(const char *name) { return glh_read_shader(IBL_SHADER_SOURCE_DIR, name); }

static float rnd(uint64_t *s)
{
    *s ^= *s << 13; /* xorshift64 (Marsaglia 2003) */
    *s ^= *s >> 7;
    *s ^= *s << 17;
    return (float)((*s >> 40) * (1.0 / 16777216.0));
}

/* ---- the fixture: a probe bake on disk and on the GPU ------------------------------------ */

/* Three local probes in a 6 x 3 x 4 room: the room (box, far-plane: a window leaves alpha 0),
 * a sphere around a corner (sphere proxy) and a box of higher priority by the window (box
 * proxy). Small cubes keep the bake quick. */
static const char SET[] =
    "{\"format\": \"ibl-probes\", \"version\": 1, \"global\": {\"size\": 16},"
    " \"probes\": ["
    "  {\"name\": \"room\", \"position\": [0, 1.5, 0], \"size\": 16,"
    "   \"influence\": {\"shape\": \"box\", \"center\": [0, 1.5, 0], \"half_extent\": [3, 1.5, 2], \"blend\": 0.5}},"
    "  {\"name\": \"corner\", \"position\": [2, 1, 1], \"size\": 16,"
    "   \"influence\": {\"shape\": \"sphere\", \"radius\": 1.4, \"blend\": 0.4},"
    "   \"proxy\": {\"shape\": \"sphere\", \"radius\": 1.8}},"
    "  {\"name\": \"window\", \"position\": [-1.5, 1.5, -1], \"size\": 16, \"priority\": 1,"
    "   \"influence\": {\"shape\": \"box\", \"half_extent\": [1.2, 1, 0.9], \"blend\": 0.3},"
    "   \"proxy\": {\"shape\": \"box\", \"center\": [0, 1.5, 0], \"half_extent\": [3, 1.5, 2]}}]}";

typedef struct fixture {
    glh_context gl;
    ibl_context *ctx;
    ibl_probe_bake_data bake;
    ibl_probe global, locals[3];
    glp_probe gpu;
    GLuint chains, records, layer_block; /* the layers' shared ibl_probe block (binding 1) */
    char *glsl, *probes_glsl;
} fixture;

/* smooth premultiplied radiance with a soft uncovered patch (alpha 0 around -Z) */
static void fill_capture(ibl_cubemap *c, int seed)
{
    for (int f = 0; f < 6; f++)
        for (int y = 0; y < c->size; y++)
            for (int x = 0; x < c->size; x++) {
                double d[3];
                test_texel_dir(f, c->size, x, y, d);
                float a = (float)fmin(1.0, fmax(0.0, 2.0 * (d[2] + 0.6 + 0.2 * seed)));
                float *t = ibl_cubemap_face(c, 0, f) + 4 * ((size_t)y * c->size + x);
                t[0] = a * (float)(0.6 + 0.3 * d[0] + 0.1 * seed);
                t[1] = a * (float)(0.5 + 0.2 * d[1]);
                t[2] = a * (float)(0.4 + 0.1 * seed + 0.2 * d[2]);
                t[3] = a;
            }
}

/* probes.ktx2's chains as one RGBA32F cube-map array, every level, trilinear. */
static GLuint cube_array(const glh_gl *gl, const ibl_cubemap *chains, int layers)
{
    GLuint t;
    gl->GenTextures(1, &t);
    gl->BindTexture(GL_TEXTURE_CUBE_MAP_ARRAY, t);
    int n0 = chains[0].size, levels = chains[0].levels;
    float *buf = malloc(sizeof(float) * 4 * 6 * (size_t)layers * n0 * n0);
    for (int k = 0; k < levels; k++) {
        int n = ibl_level_size(n0, k);
        size_t face = (size_t)4 * n * n;
        for (int l = 0; l < layers; l++)
            for (int f = 0; f < 6; f++)
                memcpy(buf + (6 * (size_t)l + f) * face, ibl_cubemap_face(&chains[l], k, f), sizeof(float) * face);
        gl->TexImage3D(GL_TEXTURE_CUBE_MAP_ARRAY, k, GL_RGBA32F, n, n, 6 * layers, 0, GL_RGBA, GL_FLOAT, buf);
    }
    free(buf);
    gl->TexParameteri(GL_TEXTURE_CUBE_MAP_ARRAY, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
    gl->TexParameteri(GL_TEXTURE_CUBE_MAP_ARRAY, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    gl->TexParameteri(GL_TEXTURE_CUBE_MAP_ARRAY, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    gl->TexParameteri(GL_TEXTURE_CUBE_MAP_ARRAY, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    gl->TexParameteri(GL_TEXTURE_CUBE_MAP_ARRAY, GL_TEXTURE_MAX_LEVEL, levels - 1);
    return t;
}

static GLuint storage(const glh_gl *gl, const void *data, size_t bytes)
{
    GLuint b;
    gl->GenBuffers(1, &b);
    gl->BindBuffer(GL_SHADER_STORAGE_BUFFER, b);
    gl->BufferData(GL_SHADER_STORAGE_BUFFER, (GLsizeiptr)bytes, data, GL_DYNAMIC_DRAW);
    return b;
}

static int make_bake(fixture *f)
{
    ibl_probe_set set;
    if (ibl_probe_set_parse(f->ctx, SET, strlen(SET), "set.json", ".", &set) != IBL_OK) return -1;
    ibl_cubemap env, caps[3];
    ibl_cubemap_alloc(f->ctx, 16, 1, &env);
    test_fill_smooth(&env);
    for (int i = 0; i < 3; i++) {
        ibl_cubemap_alloc(f->ctx, 16, 1, &caps[i]);
        fill_capture(&caps[i], i);
    }
    ibl_bake_desc g;
    memset(&g, 0, sizeof g);
    ibl_specular_preset("gltf", &g.specular);
    g.specular.size = 16;
    g.lut_size = 32;
    g.irradiance_size = 8;
    g.ambient_brdf = -1;
    g.preview_width = -1;
    ibl_probe_bake_desc d = {.cubes = caps, .global = &g, .format = IBL_FORMAT_RGBA32F};
    const char *dir = test_path("bake");
    ibl_status st = ibl_probe_bake(f->ctx, &set, &env, &d, dir, NULL);
    for (int i = 0; i < 3; i++) ibl_cubemap_free(f->ctx, &caps[i]);
    ibl_cubemap_free(f->ctx, &env);
    ibl_probe_set_free(f->ctx, &set);
    if (st == IBL_OK) st = ibl_probe_bake_load(f->ctx, dir, &f->bake);
    if (st == IBL_OK) st = ibl_bake_probe(f->ctx, &f->bake.global, &f->global);
    if (st == IBL_OK) st = ibl_probe_bake_locals(f->ctx, &f->bake, &f->global, f->locals);
    if (st == IBL_OK) st = glp_probe_upload(&f->gl.gl, f->ctx, &f->global, &f->gpu);
    if (st != IBL_OK) return -1;
    /* the shader reads the property buffer as the bake wrote it */
    char path[1100];
    snprintf(path, sizeof path, "%s/probes.bin", dir);
    FILE *in = fopen(path, "rb");
    if (!in) return -1;
    unsigned char bytes[3 * IBL_PROBE_RECORD_BYTES];
    size_t n = fread(bytes, 1, sizeof bytes, in);
    fclose(in);
    if (n != sizeof bytes) return -1;
    f->records = storage(&f->gl.gl, bytes, sizeof bytes);
    ibl_shader_probe block;
    if (ibl_shader_probe_fill(f->ctx, &f->locals[0], &block) != IBL_OK) return -1;
    const glh_gl *gl = &f->gl.gl;
    gl->GenBuffers(1, &f->layer_block);
    gl->BindBuffer(GL_UNIFORM_BUFFER, f->layer_block);
    gl->BufferData(GL_UNIFORM_BUFFER, sizeof block, &block, GL_STATIC_DRAW);
    f->chains = cube_array(&f->gl.gl, f->bake.chains, f->bake.count);
    return f->gl.gl.GetError() == GL_NO_ERROR ? 0 : -1;
}

static int teardown(void **state)
{
    fixture *f = *state;
    const glh_gl *gl = &f->gl.gl;
    glp_probe_free(gl, &f->gpu);
    if (f->chains) gl->DeleteTextures(1, &f->chains);
    if (f->records) gl->DeleteBuffers(1, &f->records);
    if (f->layer_block) gl->DeleteBuffers(1, &f->layer_block);
    glh_destroy(&f->gl);
    ibl_probe_bake_free(f->ctx, &f->bake);
    ibl_context_destroy(f->ctx);
    free(f->glsl);
    free(f->probes_glsl);
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
    f->glsl = read_shader("ibl.glsl");
    f->probes_glsl = read_shader("ibl_probes.glsl");
    if (!f->glsl || !f->probes_glsl || make_bake(f) != 0) {
        print_error("fixture: %s\n", ibl_context_message(f->ctx));
        teardown(state);
        return -1;
    }
    return 0;
}

/* ---- 1. the dialects --------------------------------------------------------------------- */

static int validate(const char *args, const char *name, const char *text)
{
    return glh_validate(IBL_GLSLANG_VALIDATOR, args, test_path(name), &text, 1);
}

/* A fragment shader that reaches every function of ibl_probes.glsl from main. */
static const char GLSL_FRAG_MAIN[] =
    "layout(std140, binding = 0) uniform ProbeBlock { ibl_probe probe; };\n"
    "layout(std140, binding = 1) uniform LayerBlock { ibl_probe layers; };\n"
    "layout(std430, binding = 0) readonly buffer Records { ibl_local_probe records[]; };\n"
    "layout(std430, binding = 1) readonly buffer Tiles { int list[]; };\n"
    "layout(binding = 0) uniform samplerCube u_specular;\n"
    "layout(binding = 1) uniform samplerCube u_mirror;\n"
    "layout(binding = 2) uniform samplerCube u_irradiance;\n"
    "layout(binding = 3) uniform sampler2D u_splitsum;\n"
    "layout(binding = 4) uniform sampler3D u_ambient;\n"
    "layout(binding = 5) uniform samplerCubeArray u_chains;\n"
    "layout(location = 0) in vec3 v_position;\n"
    "layout(location = 1) in vec3 v_normal;\n"
    "layout(location = 0) out vec4 o_color;\n"
    "void main() {\n"
    "  ibl_shade_desc desc = ibl_shade_desc(0, 0, 0, 0, 0.0, 0, 0, 0, 0, 0);\n"
    "  ibl_material m = ibl_material_gltf(vec3(0.8), 0.0, 0.4);\n"
    "  ibl_surface s = ibl_surface(normalize(v_normal), vec3(0.0, 0.0, 1.0), vec3(0.0), vec3(0.0));\n"
    "  vec3 dir = ibl_shade_lookup_direction(desc, m, s);\n"
    "  ibl_probe_blend b = ibl_probe_blend_begin();\n"
    "  for (int i = 0; i < list[0] && ibl_probe_blend_open(b); i++)\n"
    "    ibl_probe_blend_layer(b, layers, records[list[i + 1]], list[i + 1], u_chains, u_splitsum,\n"
    "                          desc, m, v_position, s, dir, 0);\n"
    "  ibl_shade_result r = ibl_probe_blend_end(b, ibl_shade_dir(probe, u_specular, u_mirror,\n"
    "      u_irradiance, u_splitsum, u_ambient, desc, m, s, dir), m.ao);\n"
    "  float t = ibl_attenuation_zone(v_position.x, 0.0, 1.0);\n"
    "  r.color += ibl_triace_blend(layers, records[0], 0, records[1], 1, t, u_chains, u_splitsum,\n"
    "                              desc, m, s, dir).color;\n"
    "  ibl_environment_slots slots = ibl_environment_slots_update(ibl_environment_slots(0, 0), 1, t);\n"
    "  float k = ibl_environment_switch_at(v_position, vec3(0.0), vec3(1.0, 0.0, 0.0), 0.5);\n"
    "  r.color += ibl_environment_switch_shade(layers, slots, records[slots.older],\n"
    "      records[slots.newer], k, u_chains, u_splitsum, desc, m, s, dir).color;\n"
    "  o_color = vec4(r.color, float(ibl_probe_blend_heaviest(b)));\n"
    "}\n";

static const char HLSL_FRAG_MAIN[] =
    "cbuffer ProbeBlock : register(b0) { ibl_probe probe; };\n"
    "cbuffer LayerBlock : register(b1) { ibl_probe layers; };\n"
    "StructuredBuffer<ibl_local_probe> records : register(t6);\n"
    "StructuredBuffer<int> list : register(t7);\n"
    "TextureCube u_specular : register(t0);\n"
    "TextureCube u_mirror : register(t1);\n"
    "TextureCube u_irradiance : register(t2);\n"
    "Texture2D u_splitsum : register(t3);\n"
    "Texture3D u_ambient : register(t4);\n"
    "TextureCubeArray u_chains : register(t5);\n"
    "SamplerState smp : register(s0);\n"
    "float4 main(float3 v_position : POSITION, float3 v_normal : NORMAL) : SV_Target {\n"
    "  ibl_shade_desc desc = (ibl_shade_desc)0;\n"
    "  ibl_material m = ibl_material_gltf(float3(0.8, 0.8, 0.8), 0.0, 0.4);\n"
    "  ibl_surface s;\n"
    "  s.n = normalize(v_normal); s.v = float3(0.0, 0.0, 1.0);\n"
    "  s.geometric_normal = float3(0.0, 0.0, 0.0); s.direct_specular = float3(0.0, 0.0, 0.0);\n"
    "  float3 dir = ibl_shade_lookup_direction(desc, m, s);\n"
    "  ibl_probe_blend b = ibl_probe_blend_begin();\n"
    "  for (int i = 0; i < list[0] && ibl_probe_blend_open(b); i++)\n"
    "    ibl_probe_blend_layer(b, layers, records[list[i + 1]], list[i + 1], u_chains, u_splitsum,\n"
    "                          smp, desc, m, v_position, s, dir, 0);\n"
    "  ibl_shade_result r = ibl_probe_blend_end(b, ibl_shade_dir(probe, u_specular, u_mirror,\n"
    "      u_irradiance, u_splitsum, u_ambient, smp, desc, m, s, dir), m.ao);\n"
    "  float t = ibl_attenuation_zone(v_position.x, 0.0, 1.0);\n"
    "  r.color += ibl_triace_blend(layers, records[0], 0, records[1], 1, t, u_chains, u_splitsum,\n"
    "                              smp, desc, m, s, dir).color;\n"
    "  ibl_environment_slots slots;\n"
    "  slots.older = 0; slots.newer = 0;\n"
    "  slots = ibl_environment_slots_update(slots, 1, t);\n"
    "  float k = ibl_environment_switch_at(v_position, float3(0.0, 0.0, 0.0), float3(1.0, 0.0, 0.0), 0.5);\n"
    "  r.color += ibl_environment_switch_shade(layers, slots, records[slots.older],\n"
    "      records[slots.newer], k, u_chains, u_splitsum, smp, desc, m, s, dir).color;\n"
    "  return float4(r.color, float(ibl_probe_blend_heaviest(b)));\n"
    "}\n";

static char *concat(const char *a, const char *b, const char *c, const char *d)
{
    size_t n = strlen(a) + strlen(b) + strlen(c) + strlen(d) + 4;
    char *s = malloc(n);
    snprintf(s, n, "%s\n%s\n%s\n%s", a, b, c, d);
    return s;
}

static void compile_all_dialects(void **state)
{
    fixture *f = *state;
    char *glsl = concat("#version 450 core", f->glsl, f->probes_glsl, GLSL_FRAG_MAIN);
    assert_int_equal(validate("-S frag", "probes_450.frag", glsl), 0);
    free(glsl);
    char *vk = concat("#version 450", f->glsl, f->probes_glsl, GLSL_FRAG_MAIN);
    assert_int_equal(validate("-V -S frag -o /dev/null", "probes_vk.frag", vk), 0);
    free(vk);
    char *hlsl_base = read_shader("ibl.hlsl"), *hlsl_probes = read_shader("ibl_probes.hlsl");
    assert_non_null(hlsl_base);
    assert_non_null(hlsl_probes);
    char *hlsl = concat("", hlsl_base, hlsl_probes, HLSL_FRAG_MAIN);
    assert_int_equal(validate("-D -V -S frag -e main -o /dev/null", "probes.hlsl", hlsl), 0);
    free(hlsl);
    free(hlsl_base);
    free(hlsl_probes);
    char *cull = read_shader("ibl_probe_cull.comp");
    assert_non_null(cull);
    assert_int_equal(validate("-S comp", "cull_450.comp", cull), 0);
    assert_int_equal(validate("-V -S comp -o /dev/null", "cull_vk.comp", cull), 0);
    free(cull);
}

/* ---- 2. the blend against ibl_probes_shade ----------------------------------------------- */

enum { SAMPLES = 2048, IN = 16, OUT = 16 };

/* inputs per sample: p (3), n (3), v (3), base colour (3), metallic, roughness, flags, - */
static void gen_inputs(float *x, uint64_t *s)
{
    for (int i = 0; i < SAMPLES; i++) {
        float *q = x + IN * i;
        q[0] = -3.2f + 6.4f * rnd(s), q[1] = 0.05f + 2.9f * rnd(s), q[2] = -2.2f + 4.4f * rnd(s);
        float n[3], v[3], len;
        do {
            for (int c = 0; c < 3; c++) n[c] = 2.0f * rnd(s) - 1.0f;
            len = sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        } while (len < 0.1f || len > 1.0f);
        for (int c = 0; c < 3; c++) q[3 + c] = n[c] / len;
        float nv;
        do { /* the eye on the front side, not grazing below 0.05 */
            for (int c = 0; c < 3; c++) v[c] = 2.0f * rnd(s) - 1.0f;
            len = sqrtf(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
            nv = len > 0.1f ? (v[0] * q[3] + v[1] * q[4] + v[2] * q[5]) / len : -1.0f;
        } while (len < 0.1f || len > 1.0f || nv < 0.05f);
        for (int c = 0; c < 3; c++) q[6 + c] = v[c] / len;
        for (int c = 0; c < 3; c++) q[9 + c] = 0.05f + 0.9f * rnd(s);
        q[12] = rnd(s) < 0.3f ? 1.0f : 0.0f;
        q[13] = i % 8 == 0 ? 0.0f : i % 8 == 1 ? 1.0f : rnd(s);
        q[14] = (float)(i % 4 == 0 ? 0 : 1 << (i % 4 - 1)); /* none, no parallax, no blend, no alpha */
        q[15] = 0.0f;
    }
}

static const char BLEND_MAIN[] =
    "layout(local_size_x = 64) in;\n"
    "layout(std140, binding = 0) uniform ProbeBlock { ibl_probe probe; };\n"
    "layout(std140, binding = 1) uniform LayerBlock { ibl_probe layers; };\n"
    "layout(std430, binding = 0) readonly buffer Records { ibl_local_probe records[]; };\n"
    "layout(std430, binding = 1) readonly buffer In { float x[]; };\n"
    "layout(std430, binding = 2) writeonly buffer Out { float y[]; };\n"
    "layout(binding = 0) uniform samplerCube u_specular;\n"
    "layout(binding = 1) uniform samplerCube u_mirror;\n"
    "layout(binding = 2) uniform samplerCube u_irradiance;\n"
    "layout(binding = 3) uniform sampler2D u_splitsum;\n"
    "layout(binding = 4) uniform sampler3D u_ambient;\n"
    "layout(binding = 5) uniform samplerCubeArray u_chains;\n"
    "uniform int u_count, u_layers;\n"
    "vec3 X3(int i, int k) { return vec3(x[i + k], x[i + k + 1], x[i + k + 2]); }\n"
    "void main() {\n"
    "  int i = int(gl_GlobalInvocationID.x);\n"
    "  if (i >= u_count) return;\n"
    "  int a = i * 16, o = i * 16;\n"
    "  vec3 p = X3(a, 0);\n"
    "  ibl_shade_desc desc = ibl_shade_desc(0, 0, 0, 0, 0.0, 0, 0, 0, 0, 0);\n"
    "  ibl_material m = ibl_material_gltf(X3(a, 9), x[a + 12], x[a + 13]);\n"
    "  ibl_surface s = ibl_surface(X3(a, 3), X3(a, 6), vec3(0.0), vec3(0.0));\n"
    "  int flags = int(x[a + 14]);\n"
    "  vec3 dir = ibl_shade_lookup_direction(desc, m, s);\n"
    "  ibl_probe_blend b = ibl_probe_blend_begin();\n"
    "  for (int k = 0; k < u_layers && ibl_probe_blend_open(b); k++)\n"
    "    ibl_probe_blend_layer(b, layers, records[k], k, u_chains, u_splitsum, desc, m, p, s, dir, flags);\n"
    "  ibl_shade_result r = ibl_probe_blend_end(b, ibl_shade_dir(probe, u_specular, u_mirror,\n"
    "      u_irradiance, u_splitsum, u_ambient, desc, m, s, dir), m.ao);\n"
    "  for (int c = 0; c < 3; c++) { y[o + c] = r.color[c]; y[o + 3 + c] = r.specular[c]; y[o + 6 + c] = r.diffuse[c]; }\n"
    "  y[o + 9] = float(ibl_probe_blend_heaviest(b)); y[o + 10] = b.rs; y[o + 11] = b.rd;\n"
    "  vec3 q1 = ibl_parallax_correct(ibl_local_probe_proxy(records[1]), records[1].position_size.xyz, p, dir);\n"
    "  y[o + 12] = q1.x; y[o + 13] = q1.y; y[o + 14] = q1.z;\n"
    "  y[o + 15] = ibl_local_probe_diffuse_alpha(records[0], s.n);\n"
    "}\n";

static GLuint build_compute(fixture *f, const char *main_text)
{
    char *src = concat("#version 450 core", f->glsl, f->probes_glsl, main_text);
    const char *srcs[1] = {src};
    GLenum type = GL_COMPUTE_SHADER;
    char log[4096] = "";
    GLuint prog = glh_program(&f->gl, log, sizeof log, 1, &type, srcs);
    if (!prog) print_error("%s\n", log);
    free(src);
    return prog;
}

static void run_compute(fixture *f, GLuint prog, const float *in, float *out, int count)
{
    const glh_gl *gl = &f->gl.gl;
    GLuint bin = storage(gl, in, sizeof(float) * IN * count);
    GLuint bout = storage(gl, NULL, sizeof(float) * OUT * count);
    gl->UseProgram(prog);
    glp_probe_bind(gl, &f->gpu);
    gl->BindBufferBase(GL_UNIFORM_BUFFER, 1, f->layer_block);
    gl->ActiveTexture(GL_TEXTURE0 + 5);
    gl->BindTexture(GL_TEXTURE_CUBE_MAP_ARRAY, f->chains);
    gl->BindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, f->records);
    gl->BindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, bin);
    gl->BindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, bout);
    gl->Uniform1i(gl->GetUniformLocation(prog, "u_count"), count);
    gl->Uniform1i(gl->GetUniformLocation(prog, "u_layers"), f->bake.count);
    gl->DispatchCompute((GLuint)(count + 63) / 64, 1, 1);
    gl->MemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    gl->BindBuffer(GL_SHADER_STORAGE_BUFFER, bout);
    gl->GetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, (GLsizeiptr)(sizeof(float) * OUT * count), out);
    assert_int_equal(gl->GetError(), GL_NO_ERROR);
    gl->DeleteBuffers(1, &bin);
    gl->DeleteBuffers(1, &bout);
}

static ibl_vec3 v3(const float *x) { return (ibl_vec3){x[0], x[1], x[2]}; }

static void blend_matches_c(void **state)
{
    fixture *f = *state;
    float *in = malloc(sizeof(float) * IN * SAMPLES), *out = malloc(sizeof(float) * OUT * SAMPLES);
    uint64_t seed = 0x9e3779b97f4a7c15ull;
    gen_inputs(in, &seed);
    GLuint prog = build_compute(f, BLEND_MAIN);
    assert_true(prog != 0);
    run_compute(f, prog, in, out, SAMPLES);
    int list[3] = {0, 1, 2};
    double worst = 0.0, worst_dir = 0.0;
    int heaviest_differs = 0, partial = 0, sphere_hits = 0;
    for (int i = 0; i < SAMPLES; i++) {
        const float *q = in + IN * i, *g = out + OUT * i;
        ibl_material m = ibl_material_gltf(q + 9, q[12], q[13]);
        ibl_surface s;
        memset(&s, 0, sizeof s);
        s.n = v3(q + 3);
        s.v = v3(q + 6);
        int flags = (int)q[14];
        ibl_probe_blend_desc bd = {.no_parallax = flags & 1, .no_blend = (flags >> 1) & 1, .no_alpha = (flags >> 2) & 1};
        ibl_shade_result r;
        ibl_probe_blend_info info;
        ibl_probes_shade(&f->bake, &f->global, f->locals, list, 3, &bd, NULL, &m, v3(q), &s, &r, &info);
        /* llvmpipe filters RGBA32F in float: the difference is float rounding through ~20
         * products and sums per layer (measured 1.9e-6 relative at worst, relative to the
         * value + 0.01); the bound 1e-4 leaves room for other JIT contractions, far below
         * what a wrong weight, alpha or direction gives (> 1e-2 on these smooth cubes) */
        const float *want[3] = {r.color, r.specular, r.diffuse};
        for (int k = 0; k < 3; k++)
            for (int c = 0; c < 3; c++) {
                double err = fabs(g[3 * k + c] - want[k][c]) / (fabs(want[k][c]) + 1e-2);
                if (err > worst) worst = err;
                if (!(err <= 1e-4)) fail_msg("sample %d (flags %d) term %d channel %d: GLSL %.7g, C %.7g", i, flags, k, c, g[3 * k + c], want[k][c]);
            }
        assert_near(g[10], info.specular_global, 1e-5); /* weights in [0, 1]: rounding */
        assert_near(g[11], info.diffuse_global, 1e-5);
        if ((int)g[9] != info.heaviest) heaviest_differs++;
        if (info.specular_global > 0.01f && info.specular_global < 0.99f) partial++;
        /* parallax on the sphere proxy (record 1), against the C */
        ibl_vec3 dir = ibl_shade_lookup_direction(NULL, &m, &s);
        ibl_vec3 c1 = ibl_parallax_correct(&f->bake.records[1].proxy, f->bake.records[1].position, v3(q), dir);
        double e = fabs(g[12] - c1.x) + fabs(g[13] - c1.y) + fabs(g[14] - c1.z);
        if (e > worst_dir) worst_dir = e;
        assert_true(e <= 1e-5); /* + - * / sqrt: float rounding */
        if (fabs(c1.x - dir.x) + fabs(c1.y - dir.y) + fabs(c1.z - dir.z) > 1e-3) sphere_hits++;
    }
    print_message("blend: worst %.2e relative, parallax %.2e, %d samples with a partial global share, "
                  "%d corrected on the sphere, heaviest differs %d times\n",
                  worst, worst_dir, partial, sphere_hits, heaviest_differs);
    /* the inputs must exercise what they test: partial shares and corrected directions */
    assert_true(partial > SAMPLES / 10);
    assert_true(sphere_hits > SAMPLES / 20);
    assert_true(heaviest_differs <= 2); /* only a tie within rounding may go either way (measured 0) */
    f->gl.gl.DeleteProgram(prog);
    free(in);
    free(out);
}

/* tri-Ace's blending and the environment switch against their definitions through the C */
static const char TRIACE_MAIN[] =
    "layout(local_size_x = 64) in;\n"
    "layout(std140, binding = 0) uniform ProbeBlock { ibl_probe probe; };\n"
    "layout(std140, binding = 1) uniform LayerBlock { ibl_probe layers; };\n"
    "layout(std430, binding = 0) readonly buffer Records { ibl_local_probe records[]; };\n"
    "layout(std430, binding = 1) readonly buffer In { float x[]; };\n"
    "layout(std430, binding = 2) writeonly buffer Out { float y[]; };\n"
    "layout(binding = 3) uniform sampler2D u_splitsum;\n"
    "layout(binding = 5) uniform samplerCubeArray u_chains;\n"
    "uniform int u_count, u_layers;\n"
    "vec3 X3(int i, int k) { return vec3(x[i + k], x[i + k + 1], x[i + k + 2]); }\n"
    "void main() {\n"
    "  int i = int(gl_GlobalInvocationID.x);\n"
    "  if (i >= u_count) return;\n"
    "  int a = i * 16, o = i * 16;\n"
    "  ibl_shade_desc desc = ibl_shade_desc(0, 0, 0, 0, 0.0, 0, 0, 0, 0, 0);\n"
    "  ibl_material m = ibl_material_gltf(X3(a, 9), x[a + 12], x[a + 13]);\n"
    "  ibl_surface s = ibl_surface(X3(a, 3), X3(a, 6), vec3(0.0), vec3(0.0));\n"
    "  vec3 dir = ibl_shade_lookup_direction(desc, m, s);\n"
    "  float t = ibl_attenuation_zone(x[a], -1.0, 1.0);\n"
    "  ibl_shade_result r = ibl_triace_blend(layers, records[0], 0, records[2], 2, t, u_chains, u_splitsum, desc, m, s, dir);\n"
    "  float k = ibl_environment_switch_at(X3(a, 0), vec3(0.5, 0.0, 0.0), vec3(1.0, 0.0, 0.0), 1.0);\n"
    "  ibl_environment_slots slots = ibl_environment_slots_update(ibl_environment_slots(1, 1), 2, k);\n"
    "  ibl_shade_result e = ibl_environment_switch_shade(layers, slots, records[slots.older], records[slots.newer],\n"
    "      k, u_chains, u_splitsum, desc, m, s, dir);\n"
    "  for (int c = 0; c < 3; c++) { y[o + c] = r.specular[c]; y[o + 3 + c] = r.diffuse[c];\n"
    "                                y[o + 6 + c] = e.specular[c]; y[o + 9 + c] = e.diffuse[c]; }\n"
    "  y[o + 12] = t; y[o + 13] = k; y[o + 14] = float(slots.older); y[o + 15] = float(slots.newer);\n"
    "}\n";

static void mix3(const float *a, const float *b, float t, float *out)
{
    for (int c = 0; c < 3; c++) out[c] = a[c] + (b[c] - a[c]) * t;
}

static void triace_and_switch_match_c(void **state)
{
    fixture *f = *state;
    float *in = malloc(sizeof(float) * IN * SAMPLES), *out = malloc(sizeof(float) * OUT * SAMPLES);
    uint64_t seed = 0x2545f4914f6cdd1dull;
    gen_inputs(in, &seed);
    GLuint prog = build_compute(f, TRIACE_MAIN);
    assert_true(prog != 0);
    run_compute(f, prog, in, out, SAMPLES);
    double worst = 0.0;
    int zone = 0, switching = 0;
    for (int i = 0; i < SAMPLES; i++) {
        const float *q = in + IN * i, *g = out + OUT * i;
        ibl_material m = ibl_material_gltf(q + 9, q[12], q[13]);
        ibl_surface s;
        memset(&s, 0, sizeof s);
        s.n = v3(q + 3);
        s.v = v3(q + 6);
        ibl_vec3 dir = ibl_shade_lookup_direction(NULL, &m, &s);
        /* the definitions: both layers along dir, specular mixed by t, diffuse from the SH
         * mixed by t (linear: the mix of the two diffuse results) */
        float t = fminf(1.0f, fmaxf(0.0f, (q[0] + 1.0f) / 2.0f));
        ibl_shade_result a, b;
        ibl_shade_dir(&f->locals[0], NULL, &m, &s, dir, &a);
        ibl_shade_dir(&f->locals[2], NULL, &m, &s, dir, &b);
        float want[12];
        mix3(a.specular, b.specular, t, want);
        mix3(a.diffuse, b.diffuse, t, want + 3);
        /* the switch: older layer 1, newer 2 once touched; t = saturate((x - 0.5) / 1 + 0.5) */
        float k = ibl_environment_switch(q[0], 0.5f, 1.0f);
        ibl_shade_result e1, e2;
        ibl_shade_dir(&f->locals[1], NULL, &m, &s, dir, &e1);
        ibl_shade_dir(&f->locals[2], NULL, &m, &s, dir, &e2);
        int older = k >= 1.0f ? 2 : 1;
        const ibl_shade_result *eo = older == 2 ? &e2 : &e1;
        mix3(eo->specular, e2.specular, older == 2 ? 0.0f : k, want + 6);
        mix3(eo->diffuse, e2.diffuse, older == 2 ? 0.0f : k, want + 9);
        assert_near(g[12], t, 1e-6);
        assert_near(g[13], k, 1e-6);
        assert_int_equal((int)g[14], older);
        assert_int_equal((int)g[15], 2);
        for (int c = 0; c < 12; c++) {
            double err = fabs(g[c] - want[c]) / (fabs(want[c]) + 1e-2);
            if (err > worst) worst = err;
            /* as above: measured 7.5e-7 */
            if (!(err <= 1e-4)) fail_msg("sample %d value %d: GLSL %.7g, C %.7g", i, c, g[c], want[c]);
        }
        zone += t > 0.0f && t < 1.0f;
        switching += k > 0.0f && k < 1.0f;
    }
    print_message("tri-Ace blend and switch: worst %.2e relative; %d samples in the zone, %d switching\n",
                  worst, zone, switching);
    assert_true(zone > SAMPLES / 10 && switching > SAMPLES / 10);
    f->gl.gl.DeleteProgram(prog);
    free(in);
    free(out);
}

/* ---- 3. tiled culling ------------------------------------------------------------------------ */

typedef struct gpu_record { /* probes.bin's std430 layout, 240 bytes */
    float position_size[4], influence_center_radius[4], influence_half_extent_blend[4];
    float proxy_center_radius[4], proxy_half_extent_coverage[4];
    int32_t shapes_layer_priority[4];
    float sh[9][4];
} gpu_record;

/* View depths of a floor and a back wall seen from eye height, with sky above the wall. */
static void scene_depth(const ibl_camera *cam, float *depth)
{
    for (int y = 0; y < cam->height; y++)
        for (int x = 0; x < cam->width; x++) {
            ibl_vec3 r = ibl_camera_ray(cam, x + 0.5f, y + 0.5f);
            float t = 1e30f;
            if (r.y < 0) t = fminf(t, -cam->position.y / r.y);
            float tw = (-8.0f - cam->position.z) / r.z;
            if (r.z < 0 && cam->position.y + tw * r.y < 5.0f) t = fminf(t, tw);
            depth[(size_t)y * cam->width + x] = t < 1e29f ? t : 0.0f;
        }
}

static void random_volumes(ibl_volume *v, gpu_record *rec, int n, uint64_t *s)
{
    memset(rec, 0, sizeof *rec * (size_t)n);
    for (int i = 0; i < n; i++) {
        ibl_vec3 c = {-7 + 14 * rnd(s), 2.5f * rnd(s) - 0.5f, -9 + 12 * rnd(s)};
        if (i % 2)
            v[i] = (ibl_volume){.shape = IBL_VOLUME_SPHERE, .center = c, .radius = 0.5f + 2.5f * rnd(s),
                                .blend_distance = i % 4 == 1 ? 0.0f : 0.2f};
        else
            v[i] = (ibl_volume){.shape = IBL_VOLUME_BOX, .center = c,
                                .half_extent = {0.5f + 2.5f * rnd(s), 0.3f + 1.5f * rnd(s), 0.5f + 2.5f * rnd(s)},
                                .blend_distance = i % 4 == 0 ? 0.0f : 0.2f};
        float *cr = rec[i].influence_center_radius, *hb = rec[i].influence_half_extent_blend;
        cr[0] = c.x, cr[1] = c.y, cr[2] = c.z, cr[3] = v[i].shape == IBL_VOLUME_SPHERE ? v[i].radius : 0.0f;
        hb[0] = v[i].half_extent.x, hb[1] = v[i].half_extent.y, hb[2] = v[i].half_extent.z;
        hb[3] = v[i].blend_distance;
        rec[i].shapes_layer_priority[0] = v[i].shape == IBL_VOLUME_BOX ? 1 : 0;
        rec[i].shapes_layer_priority[2] = i;
    }
}

typedef struct gpu_lists {
    int *lists, *lengths;
    unsigned compares;
} gpu_lists;

static void gpu_cull(fixture *f, GLuint prog, const ibl_camera *cam, const float *depth,
                     const gpu_record *rec, int count, int sort, int exact, int capacity,
                     gpu_lists *out)
{
    const glh_gl *gl = &f->gl.gl;
    int tx = (cam->width + 15) / 16, ty = (cam->height + 15) / 16;
    GLuint b[5];
    b[0] = storage(gl, rec, sizeof *rec * (size_t)count);
    b[1] = storage(gl, depth, sizeof(float) * (size_t)cam->width * cam->height);
    b[2] = storage(gl, NULL, sizeof(int) * (size_t)tx * ty * capacity);
    b[3] = storage(gl, NULL, sizeof(int) * (size_t)tx * ty);
    unsigned zero = 0;
    b[4] = storage(gl, &zero, sizeof zero);
    for (int i = 0; i < 5; i++) gl->BindBufferBase(GL_SHADER_STORAGE_BUFFER, (GLuint)i, b[i]);
    gl->UseProgram(prog);
    ibl_vec3 r, u, fw;
    ibl_camera_basis(cam, &r, &u, &fw);
    float tany = tanf(cam->fov_y_degrees * 0.5f * 3.14159265358979f / 180.0f);
    float vecs[4][4] = {{cam->position.x, cam->position.y, cam->position.z, 0},
                        {r.x, r.y, r.z, 0}, {u.x, u.y, u.z, 0}, {fw.x, fw.y, fw.z, 0}};
    const char *names[4] = {"u_position", "u_right", "u_up", "u_forward"};
    for (int i = 0; i < 4; i++) gl->Uniform4fv(gl->GetUniformLocation(prog, names[i]), 1, vecs[i]);
    gl->Uniform2f(gl->GetUniformLocation(prog, "u_tan"), tany * (float)cam->width / (float)cam->height, tany);
    gl->Uniform1i(gl->GetUniformLocation(prog, "u_count"), count);
    gl->Uniform1i(gl->GetUniformLocation(prog, "u_sort"), sort);
    gl->Uniform1i(gl->GetUniformLocation(prog, "u_exact"), exact);
    gl->Uniform1i(gl->GetUniformLocation(prog, "u_capacity"), capacity);
    gl->Uniform2i(gl->GetUniformLocation(prog, "u_size"), cam->width, cam->height);
    gl->DispatchCompute((GLuint)tx, (GLuint)ty, 1);
    gl->MemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    out->lists = malloc(sizeof(int) * (size_t)tx * ty * capacity);
    out->lengths = malloc(sizeof(int) * (size_t)tx * ty);
    gl->BindBuffer(GL_SHADER_STORAGE_BUFFER, b[2]);
    gl->GetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, (GLsizeiptr)(sizeof(int) * (size_t)tx * ty * capacity), out->lists);
    gl->BindBuffer(GL_SHADER_STORAGE_BUFFER, b[3]);
    gl->GetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, (GLsizeiptr)(sizeof(int) * (size_t)tx * ty), out->lengths);
    gl->BindBuffer(GL_SHADER_STORAGE_BUFFER, b[4]);
    gl->GetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, sizeof zero, &out->compares);
    assert_int_equal(gl->GetError(), GL_NO_ERROR);
    gl->DeleteBuffers(5, b);
}

/* the brute force: for each tile, every probe that some pixel's point lies in, ascending */
static void brute_force_tile(const ibl_camera *cam, const float *depth, const ibl_volume *v,
                             int count, int tile, int tiles_x, int *list, int *n)
{
    int x0 = (tile % tiles_x) * 16, y0 = (tile / tiles_x) * 16;
    *n = 0;
    for (int k = 0; k < count; k++) {
        int hit = 0;
        for (int y = y0; y < y0 + 16 && y < cam->height && !hit; y++)
            for (int x = x0; x < x0 + 16 && x < cam->width && !hit; x++) {
                float d = depth[(size_t)y * cam->width + x];
                if (!(d > 0.0f)) continue;
                ibl_vec3 ray = ibl_camera_ray(cam, x + 0.5f, y + 0.5f);
                ibl_vec3 p = {cam->position.x + ray.x * d, cam->position.y + ray.y * d, cam->position.z + ray.z * d};
                hit = ibl_volume_weight(&v[k], p) > 0.0f;
            }
        if (hit) list[(*n)++] = k;
    }
}

static void culling_matches_c(void **state)
{
    fixture *f = *state;
    enum { N = 48, W = 200, H = 120 };
    ibl_camera cam = {.position = {0, 1.7f, 6}, .forward = {0.1f, -0.2f, -1}, .up = {0, 1, 0},
                      .fov_y_degrees = 70, .width = W, .height = H};
    float *depth = malloc(sizeof(float) * W * H);
    scene_depth(&cam, depth);
    ibl_volume v[N];
    gpu_record rec[N];
    uint64_t seed = 77;
    random_volumes(v, rec, N, &seed);
    char *src = read_shader("ibl_probe_cull.comp");
    const char *srcs[1] = {src};
    GLenum type = GL_COMPUTE_SHADER;
    char log[4096] = "";
    GLuint prog = glh_program(&f->gl, log, sizeof log, 1, &type, srcs);
    if (!prog) fail_msg("%s", log);
    free(src);
    int tiles = ((W + 15) / 16) * ((H + 15) / 16), bf[N], nbf;
    long long total = 0, exact_total = 0;
    for (int exact = 0; exact < 2; exact++)
        for (int sort = 0; sort < 3; sort++) {
            ibl_cull_desc cd = {.tile_size = 16, .sort = (ibl_tile_sort)sort, .exact = exact};
            ibl_tile_lists c;
            ibl_cull_stats stats;
            assert_int_equal(ibl_cull_probes(f->ctx, &cam, depth, v, N, &cd, &c, &stats), IBL_OK);
            gpu_lists g;
            gpu_cull(f, prog, &cam, depth, rec, N, sort, exact, N, &g);
            for (int t = 0; t < tiles; t++) {
                int n = c.offsets[t + 1] - c.offsets[t];
                if (g.lengths[t] != n) fail_msg("sort %d exact %d tile %d: GPU %d probes, C %d", sort, exact, t, g.lengths[t], n);
                assert_memory_equal(g.lists + (size_t)t * N, c.indices + c.offsets[t], sizeof(int) * (size_t)n);
                if (exact) { /* and the brute force */
                    brute_force_tile(&cam, depth, v, N, t, c.tiles_x, bf, &nbf);
                    assert_int_equal(nbf, n);
                    assert_memory_equal(bf, g.lists + (size_t)t * N, sizeof(int) * (size_t)n);
                }
            }
            assert_int_equal((long long)g.compares, stats.compares);
            if (exact) exact_total = stats.entries;
            else total = stats.entries;
            free(g.lists);
            free(g.lengths);
            ibl_tile_lists_free(f->ctx, &c);
        }
    print_message("culling: %lld entries conservative, %lld exact over %d tiles\n", total, exact_total, tiles);
    assert_true(exact_total > tiles && total > exact_total); /* the cases are not empty */
    f->gl.gl.DeleteProgram(prog);
    free(depth);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(compile_all_dialects),
        cmocka_unit_test(blend_matches_c),
        cmocka_unit_test(triace_and_switch_match_c),
        cmocka_unit_test(culling_matches_c),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
