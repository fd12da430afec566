/* shaders/ibl_atlas.glsl (Daqi 2016's 2D mip atlas and channel packing) on Mesa's llvmpipe
 * against its C twins, and the atlas against the cube it replaces:
 *  1. ibl_atlas.glsl and .hlsl compile as GLSL 4.50, ES 3.00 (the 8-slot device's dialect)
 *     and HLSL (glslangValidator);
 *  2. the sphere grid of `ibl render` (GGX roughness 0..1 for a metal and a dielectric row,
 *     Blinn-Phong shininess 1..100000) drawn four times by one fragment shader: the
 *     prefiltered radiance each sphere pixel reads from the cube (ibl_probe_sample_specular),
 *     from the float atlas (ibl_atlas_probe_specular), from the 8-bit RGBM atlas
 *     (ibl_atlas_sample_rgbm), and the lookup itself (direction and lod). The C twins are
 *     evaluated at the GPU's own lookups, so each comparison sees only the sampling;
 *  3. ibl_unpack_material against the packed texel.
 * The probe: forest (128x64) on a 32 cube, a GGX chain of 4 levels (32 .. 4 texels) as
 * `ibl render` bakes it, with the atlas the bake writes (atlas = 1); no mirror, which the
 * atlas path has no slot for. */
#include "test_support.h"
#include "sphere_grid.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct atlas_fixture {
    glh_context gl;
    ibl_context *ctx;
    ibl_bake_data bake;
    ibl_probe probe, probe_atlas; /* the same probe, cube and atlas lookups */
    ibl_cubemap env;
    glp_probe gpu;
    ibl_image rgbm_decoded; /* the RGBM atlas as the C reads it back (ibl_rgbm_decode) */
    float rgbm_range;
    GLuint atlas_texture, rgbm_texture, atlas_block;
    char *glsl, *glsl_atlas, *hlsl, *hlsl_atlas;
} atlas_fixture;

static char *read_shader(const char *name) { return glh_read_shader(IBL_SHADER_SOURCE_DIR, name); }

/* The atlas as 8-bit RGBM bytes in an RGBA8 texture, and the floats the C decodes from them. */
static int upload_rgbm(atlas_fixture *f)
{
    const ibl_image *a = &f->bake.atlas;
    size_t n = (size_t)a->width * a->height;
    uint8_t *bytes = malloc(n * 4);
    if (!bytes || ibl_image_alloc(f->ctx, a->width, a->height, &f->rgbm_decoded) != IBL_OK) {
        free(bytes);
        return -1;
    }
    /* the range covers the chain's largest value: no texel is clipped, every error left is
     * the 8-bit quantisation */
    float top = 0.0f;
    for (size_t i = 0; i < n * 4; i++)
        if (i % 4 != 3 && a->pixels[i] > top) top = a->pixels[i];
    f->rgbm_range = ceilf(top);
    for (size_t i = 0; i < n; i++) {
        const float *x = a->pixels + i * 4;
        float *y = f->rgbm_decoded.pixels + i * 4;
        ibl_rgbm_encode(x, f->rgbm_range, bytes + i * 4);
        ibl_rgbm_decode(bytes + i * 4, f->rgbm_range, y);
        y[3] = 1.0f;
        /* RGBM's own error (what the RGBM atlas adds to the float one, since bilinear weights
         * sum to 1): the multiplier M = ceil(255 max / range) range / 255 is at most one step
         * of range / 255 above the largest channel, and each channel is rounded to half a code
         * of M / 255: |error| <= 0.5 / 255 (max + range / 255) (+ float rounding) */
        float mx = fmaxf(x[0], fmaxf(x[1], x[2]));
        double bound = 0.5 / 255.0 * (mx + f->rgbm_range / 255.0) * (1.0 + 1e-5);
        for (int c = 0; c < 3; c++)
            if (fabs((double)y[c] - x[c]) > bound) {
                print_error("RGBM texel %zu channel %d: %g -> %g (bound %g)\n", i, c, (double)x[c],
                            (double)y[c], bound);
                free(bytes);
                return -1;
            }
    }
    const glh_gl *gl = &f->gl.gl;
    gl->GenTextures(1, &f->rgbm_texture);
    gl->BindTexture(GL_TEXTURE_2D, f->rgbm_texture);
    gl->TexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, a->width, a->height, 0, GL_RGBA, GL_UNSIGNED_BYTE,
                   bytes);
    gl->TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    gl->TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    free(bytes);
    return 0;
}

static int make_probe(atlas_fixture *f)
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
    d.keep_environment = 0; /* no mirror: the atlas path has none */
    d.atlas = 1;
    if (ibl_bake_compute(f->ctx, &f->env, &d, &f->bake) != IBL_OK) return -1;
    if (ibl_bake_probe(f->ctx, &f->bake, &f->probe) != IBL_OK) return -1;
    f->probe_atlas = f->probe;
    f->probe_atlas.use_atlas = 1;
    if (ibl_probe_validate(f->ctx, &f->probe_atlas) != IBL_OK) return -1;
    if (glp_probe_upload(&f->gl.gl, f->ctx, &f->probe, &f->gpu) != IBL_OK) return -1;
    const glh_gl *gl = &f->gl.gl;
    f->atlas_texture = glp_image_texture(gl, &f->bake.atlas);
    ibl_shader_atlas block;
    ibl_shader_atlas_fill(&f->bake.atlas_layout, &block);
    gl->GenBuffers(1, &f->atlas_block);
    gl->BindBuffer(GL_UNIFORM_BUFFER, f->atlas_block);
    gl->BufferData(GL_UNIFORM_BUFFER, sizeof block, &block, GL_STATIC_DRAW);
    if (upload_rgbm(f) != 0) return -1;
    return gl->GetError() == GL_NO_ERROR ? 0 : -1;
}

static int teardown(void **state)
{
    atlas_fixture *f = *state;
    const glh_gl *gl = &f->gl.gl;
    glp_probe_free(gl, &f->gpu);
    if (f->atlas_texture) gl->DeleteTextures(1, &f->atlas_texture);
    if (f->rgbm_texture) gl->DeleteTextures(1, &f->rgbm_texture);
    if (f->atlas_block) gl->DeleteBuffers(1, &f->atlas_block);
    glh_destroy(&f->gl);
    ibl_image_free(f->ctx, &f->rgbm_decoded);
    ibl_bake_free(f->ctx, &f->bake);
    ibl_cubemap_free(f->ctx, &f->env);
    ibl_context_destroy(f->ctx);
    free(f->glsl);
    free(f->glsl_atlas);
    free(f->hlsl);
    free(f->hlsl_atlas);
    free(f);
    return 0;
}

static int setup(void **state)
{
    atlas_fixture *f = calloc(1, sizeof *f);
    if (!f) return -1;
    if (glh_create_for_test(&f->gl) != 0) {
        free(f);
        return -1;
    }
    *state = f;
    f->ctx = test_context(0);
    f->glsl = read_shader("ibl.glsl");
    f->glsl_atlas = read_shader("ibl_atlas.glsl");
    f->hlsl = read_shader("ibl.hlsl");
    f->hlsl_atlas = read_shader("ibl_atlas.hlsl");
    if (!f->glsl || !f->glsl_atlas || !f->hlsl || !f->hlsl_atlas || make_probe(f) != 0) {
        print_error("fixture: %s\n", ibl_context_message(f->ctx));
        teardown(state);
        return -1;
    }
    return 0;
}

/* ---- 1. the dialects ---------------------------------------------------------------------- */

static int validate(const char *args, const char *name, const char *head, const char *a,
                    const char *b, const char *tail)
{
    const char *parts[] = {head, a, b, tail};
    return glh_validate(IBL_GLSLANG_VALIDATOR, args, test_path(name), parts, 4);
}

/* What an 8-slot ES device runs: no sampler3D, no specular cube; the atlas, the packed
 * material texture, the irradiance cube and the split-sum table. */
static const char *const es_main =
    "layout(std140) uniform ProbeBlock { ibl_probe probe; };\n"
    "layout(std140) uniform AtlasBlock { ibl_atlas_layout atlas_layout; };\n"
    "uniform sampler2D u_atlas, u_material;\n"
    "uniform float u_rgbm_range;\n"
    "in vec3 v_normal; in vec3 v_view; in vec2 v_uv;\n"
    "layout(location = 0) out vec4 o_color;\n"
    "void main() {\n"
    "  ibl_material m = ibl_material_gltf(vec3(1.0, 0.766, 0.336), 1.0, 0.5);\n"
    "  float transmittance = ibl_material_apply_packed(m, texture(u_material, v_uv));\n"
    "  vec3 r = reflect(-normalize(v_view), normalize(v_normal));\n"
    "  float lod = ibl_probe_lod_from_roughness(probe, m.roughness);\n"
    "  vec3 a = ibl_atlas_probe_specular(probe, u_atlas, atlas_layout, lod, r);\n"
    "  vec3 b = ibl_atlas_sample_rgbm(u_atlas, atlas_layout, u_rgbm_range, lod, r);\n"
    "  o_color = vec4(a + b, transmittance);\n"
    "}\n";

static const char *const hlsl_main =
    "cbuffer ProbeBlock : register(b0) { ibl_probe probe; };\n"
    "cbuffer AtlasBlock : register(b1) { ibl_atlas_layout atlas_layout; };\n"
    "Texture2D u_atlas : register(t5);\n"
    "Texture2D u_material : register(t6);\n"
    "SamplerState u_sampler : register(s0);\n"
    "float4 main(float3 normal : NORMAL, float3 view : TEXCOORD0, float2 uv : TEXCOORD1) : SV_Target {\n"
    "  ibl_material m = ibl_material_gltf(float3(1.0, 0.766, 0.336), 1.0, 0.5);\n"
    "  float transmittance = ibl_material_apply_packed(m, u_material.Sample(u_sampler, uv));\n"
    "  float3 r = reflect(-normalize(view), normalize(normal));\n"
    "  float lod = ibl_probe_lod_from_roughness(probe, m.roughness);\n"
    "  float3 a = ibl_atlas_probe_specular(probe, u_atlas, u_sampler, atlas_layout, lod, r);\n"
    "  float3 b = ibl_atlas_sample_rgbm(u_atlas, atlas_layout, 8.0, lod, r);\n"
    "  return float4(a + b, transmittance);\n"
    "}\n";

static void compile_all_dialects(void **state)
{
    atlas_fixture *f = *state;
    assert_int_equal(validate("-S frag", "atlas_es300.frag", "#version 300 es\n#define IBL_NO_AMBIENT_BRDF_3D",
                              f->glsl, f->glsl_atlas, es_main), 0);
    assert_int_equal(validate("-S frag", "atlas_gl450.frag", "#version 450 core", f->glsl,
                              f->glsl_atlas, es_main), 0);
    assert_int_equal(validate("-D -V -e main -S frag -o /dev/null", "atlas.hlsl.frag",
                              "#define IBL_NO_AMBIENT_BRDF_3D", f->hlsl, f->hlsl_atlas, hlsl_main), 0);
}

/* ---- 2. the sphere grid ------------------------------------------------------------------- */

/* examples/sphere_grid.frag's scene; MODE picks what a sphere pixel writes. */
static const char *const grid_frag =
    "layout(std140, binding = 0) uniform ProbeBlock { ibl_probe probe; };\n"
    "layout(std140, binding = 1) uniform AtlasBlock { ibl_atlas_layout atlas_layout; };\n"
    "layout(binding = 0) uniform samplerCube u_specular;\n"
    "layout(binding = 1) uniform samplerCube u_mirror;\n"
    "layout(binding = 2) uniform samplerCube u_irradiance;\n"
    "layout(binding = 3) uniform sampler2D u_splitsum;\n"
    "layout(binding = 4) uniform sampler3D u_ambient;\n"
    "layout(binding = 5) uniform sampler2D u_atlas;\n"
    "layout(binding = 6) uniform sampler2D u_atlas_rgbm;\n"
    "uniform float u_rgbm_range;\n"
    "uniform vec2 u_size, u_half;\n"
    "uniform vec4 u_params[21], u_base[21], u_f0[21];\n"
    "layout(location = 0) out vec4 o_color;\n"
    "void main() {\n"
    "  vec2 p = vec2(gl_FragCoord.x, u_size.y - gl_FragCoord.y);\n"
    "  vec2 ndc = vec2(p.x / u_size.x * 2.0 - 1.0, 1.0 - p.y / u_size.y * 2.0);\n"
    "  vec3 eye = vec3(0.0, 0.0, 12.0), d = normalize(vec3(ndc * u_half, -12.0));\n"
    "  int best = -1; float best_t = 3.402823466e38;\n"
    "  for (int i = 0; i < 21; i++) {\n"
    "    vec3 c = vec3((float(i % 7) - 3.0) * 1.1, (1.0 - float(i / 7)) * 1.1, 0.0);\n"
    "    vec3 oc = eye - c;\n"
    "    float b = dot(oc, d), q = dot(oc, oc) - 0.48 * 0.48, disc = b * b - q;\n"
    "    if (disc < 0.0) continue;\n"
    "    float t = -b - sqrt(disc);\n"
    "    if (t > 1e-4 && t < best_t) { best_t = t; best = i; }\n"
    "  }\n"
    "  if (best < 0) { o_color = vec4(0.0); return; }\n"
    "  vec3 c = vec3((float(best % 7) - 3.0) * 1.1, (1.0 - float(best / 7)) * 1.1, 0.0);\n"
    "  vec4 q = u_params[best];\n"
    "  ibl_material m = ibl_material(int(q.x), u_base[best].rgb, q.y, q.z, u_f0[best].rgb, q.w, 1.0);\n"
    "  ibl_surface s = ibl_surface(normalize(eye + best_t * d - c), -d, vec3(0.0), vec3(0.0));\n"
    "  ibl_shade_desc desc = ibl_shade_desc(0, 0, 0, 0, 0.0, 0, 0, 0, 0, 0);\n"
    "  ibl_shade_result r = ibl_shade(probe, u_specular, u_mirror, u_irradiance, u_splitsum,\n"
    "                                 u_ambient, desc, m, s);\n"
    "#if MODE == 0\n"
    "  o_color = vec4(ibl_probe_sample_specular(probe, u_specular, u_mirror, r.lod, r.r), 1.0);\n"
    "#elif MODE == 1\n"
    "  o_color = vec4(ibl_atlas_probe_specular(probe, u_atlas, atlas_layout, r.lod, r.r), 1.0);\n"
    "#elif MODE == 2\n"
    "  float lod = clamp(r.lod, 0.0, float(probe.levels - 1));\n"
    "  o_color = vec4(probe.intensity * ibl_atlas_sample_rgbm(u_atlas_rgbm, atlas_layout,\n"
    "                                                         u_rgbm_range, lod, r.r), 1.0);\n"
    "#elif MODE == 3\n"
    "  o_color = vec4(r.r, 1.0);\n"
    "#else\n"
    "  o_color = vec4(r.lod, 0.0, 0.0, 1.0);\n"
    "#endif\n"
    "}\n";

enum { W = 256, H = 128, MODES = 5 };

/* Draws the grid in one mode; the program is sg_render's (it binds the probe and sets the
 * scene's uniforms), the atlas texture and block are bound here first. */
static void draw(atlas_fixture *f, int mode, ibl_image *out, unsigned char *hit)
{
    const glh_gl *gl = &f->gl.gl;
    gl->ActiveTexture(GL_TEXTURE0 + 5);
    gl->BindTexture(GL_TEXTURE_2D, f->atlas_texture);
    gl->ActiveTexture(GL_TEXTURE0 + 6);
    gl->BindTexture(GL_TEXTURE_2D, f->rgbm_texture);
    gl->ActiveTexture(GL_TEXTURE0);
    gl->BindBufferBase(GL_UNIFORM_BUFFER, 1, f->atlas_block);
    size_t n = strlen(f->glsl) + strlen(f->glsl_atlas) + 64;
    char *glsl = malloc(n), frag[8192];
    assert_non_null(glsl);
    snprintf(glsl, n, "%s\n%s", f->glsl, f->glsl_atlas);
    /* u_rgbm_range is a constant here: sg_render owns the program's uniforms */
    snprintf(frag, sizeof frag, "#define MODE %d\n%s", mode, grid_frag);
    char *at = strstr(frag, "uniform float u_rgbm_range;");
    assert_non_null(at);
    char range[64];
    int len = snprintf(range, sizeof range, "const float u_rgbm_range = %.1f;", (double)f->rgbm_range);
    char tail[8192];
    snprintf(tail, sizeof tail, "%s", at + strlen("uniform float u_rgbm_range;"));
    snprintf(at, sizeof frag - (size_t)(at - frag), "%.*s%s", len, range, tail);
    char log[4096] = "";
    ibl_status st = sg_render(&f->gl, f->ctx, &f->gpu, NULL, glsl, frag, W, H, out, hit, log, sizeof log);
    if (st != IBL_OK) print_error("mode %d: %s\n", mode, log);
    assert_int_equal(st, IBL_OK);
    free(glsl);
}

static double max3(const float *c)
{
    return fmax(fabs(c[0]), fmax(fabs(c[1]), fabs(c[2])));
}

static double diff3(const float *a, const float *b)
{
    return fmax(fabs(a[0] - b[0]), fmax(fabs(a[1] - b[1]), fabs(a[2] - b[2])));
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* llvmpipe against the C at the same lookup: bilinear weights in float on both sides (the
 * functions' table in docs/SHADERS.md: 5.4e-6 for ibl_atlas_sample) and, for the cube, the
 * seamless filtering at face edges; 1e-4 relative to the largest channel leaves 20x. */
#define GPU_REL 1e-4

/* The sphere grid from the atlas and from the cube, and each against its C twin. */
static void sphere_grid_atlas_against_cube(void **state)
{
    atlas_fixture *f = *state;
    ibl_image img[MODES];
    unsigned char *hit = malloc(W * H);
    assert_non_null(hit);
    for (int m = 0; m < MODES; m++) draw(f, m, &img[m], hit);
    double worst_gpu[3] = {0, 0, 0}, *rel = malloc(sizeof(double) * W * H), worst_rgbm = 0;
    double excess = 0, mean_rel = 0;
    assert_non_null(rel);
    int n = 0;
    for (int i = 0; i < W * H; i++) {
        if (!hit[i]) continue;
        const float *dir = img[3].pixels + (size_t)i * 4;
        float lod = img[4].pixels[(size_t)i * 4];
        ibl_vec3 d = {dir[0], dir[1], dir[2]};
        float c_cube[3], c_atlas[3], c_rgbm[4];
        ibl_probe_sample_specular(&f->probe, lod, d, c_cube);
        ibl_probe_sample_specular(&f->probe_atlas, lod, d, c_atlas);
        float last = (float)(f->probe.mapping.levels - 1);
        ibl_atlas_sample(&f->rgbm_decoded, &f->bake.atlas_layout, lod < 0 ? 0 : lod > last ? last : lod,
                         d, c_rgbm);
        const float *g_cube = img[0].pixels + (size_t)i * 4, *g_atlas = img[1].pixels + (size_t)i * 4;
        const float *g_rgbm = img[2].pixels + (size_t)i * 4;
        double scale = max3(c_cube) + 1e-3;
        double e[3] = {diff3(g_cube, c_cube) / scale, diff3(g_atlas, c_atlas) / scale,
                       diff3(g_rgbm, c_rgbm) / scale};
        for (int k = 0; k < 3; k++) worst_gpu[k] = fmax(worst_gpu[k], e[k]);
        /* the GPU's atlas-to-cube difference is the C's, up to both GPU errors */
        double over = diff3(g_atlas, g_cube) / scale - (diff3(c_atlas, c_cube) / scale + 2 * GPU_REL);
        excess = fmax(excess, over);
        worst_rgbm = fmax(worst_rgbm, diff3(g_rgbm, g_atlas) / (max3(g_atlas) + 1e-3));
        rel[n] = diff3(g_atlas, g_cube) / scale;
        mean_rel += rel[n++];
    }
    qsort(rel, (size_t)n, sizeof(double), cmp_double);
    mean_rel /= n;
    print_message("%d sphere pixels; GPU against C (max, relative to the cube's largest channel): "
                  "cube %.2e, atlas %.2e, rgbm atlas %.2e\n", n, worst_gpu[0], worst_gpu[1], worst_gpu[2]);
    print_message("atlas against cube: mean %.2e, p99 %.2e, max %.2e; RGBM (range %.0f) against "
                  "float atlas: max %.2e\n", mean_rel, rel[(size_t)(0.99 * (n - 1))], rel[n - 1],
                  (double)f->rgbm_range, worst_rgbm);
    assert_true(n > W * H / 8);
    for (int k = 0; k < 3; k++) assert_true(worst_gpu[k] <= GPU_REL);
    assert_true(excess <= 0.0);
    /* The atlas against the cube: levels 0 and 1 are the cube's own texels, so away from face
     * edges the two agree to float rounding; at an edge the atlas's 1-texel gutter holds the
     * bilinear sample of the neighbouring face at the gutter texel's direction where GL's
     * seamless filter reads the neighbour's texel itself, and levels 2 and 3 (8 and 4 texels)
     * are enlarged to level 2's size by bilinear sampling, so a lookup there interpolates
     * twice. Either way both sides are convex blends of the same level's texels within one
     * texel of the lookup, so the difference is bounded by the level's variation across a
     * texel, not by anything the layout could get wrong (a wrong rectangle or level reads
     * another part of the sky: errors of order 1). Measured on llvmpipe: mean 2.3e-3, p99
     * 3.3e-2, max 0.115; the bounds (mean 1%, p99 10%, max 25%) leave 2-4x. */
    assert_true(mean_rel <= 0.01);
    assert_true(rel[(size_t)(0.99 * (n - 1))] <= 0.10);
    assert_true(rel[n - 1] <= 0.25);
    free(rel);
    free(hit);
    for (int m = 0; m < MODES; m++) ibl_image_free(f->ctx, &img[m]);
}

/* ---- 3. the packed material texel --------------------------------------------------------- */

static const char *const unpack_frag =
    "layout(binding = 7) uniform sampler2D u_material;\n"
    "uniform vec2 u_size;\n"
    "layout(location = 0) out vec4 o_color;\n"
    "void main() {\n"
    "  vec4 t = texelFetch(u_material, ivec2(int(gl_FragCoord.x), int(u_size.y - gl_FragCoord.y)), 0);\n"
    "#if MODE == 0\n"
    "  ibl_packed_material p = ibl_unpack_material(t);\n"
    "  o_color = vec4(p.metallic, p.roughness, p.ao, 1.0);\n"
    "#else\n"
    "  ibl_material m = ibl_material_gltf(vec3(1.0), 0.25, 0.75);\n"
    "  float tr = ibl_material_apply_packed(m, t);\n"
    "  o_color = vec4(tr, m.metallic - t.r + m.roughness - t.g, m.ao, 1.0);\n"
    "#endif\n"
    "}\n";

/* ibl_unpack_material and ibl_material_apply_packed read what ibl_pack_material_channels
 * packed, from a 16-bit UNORM texture: metalness, roughness and AO from maps, transmittance
 * the default constant 0. Exact but for the UNORM-to-float conversion (code / 65535 rounded
 * to float on both sides: 1 ulp, < 1.2e-7). */
static void unpack_material_matches_c(void **state)
{
    atlas_fixture *f = *state;
    enum { PW = 64, PH = 32 };
    ibl_image maps[3], packed;
    for (int k = 0; k < 3; k++) {
        assert_int_equal(ibl_image_alloc(f->ctx, PW, PH, &maps[k]), IBL_OK);
        for (int i = 0; i < PW * PH; i++) /* codes that cover the 16-bit range */
            maps[k].pixels[i * 4] = (float)(((i * 2654435761u + (unsigned)k * 40503u) % 65536u) / 65535.0);
    }
    assert_int_equal(ibl_pack_material_channels(f->ctx, &maps[0], &maps[1], &maps[2], NULL, &packed), IBL_OK);
    uint16_t *codes = malloc(sizeof(uint16_t) * PW * PH * 4);
    assert_non_null(codes);
    for (int i = 0; i < PW * PH * 4; i++) codes[i] = (uint16_t)lrint(packed.pixels[i] * 65535.0);
    const glh_gl *gl = &f->gl.gl;
    GLuint tex;
    gl->GenTextures(1, &tex);
    gl->ActiveTexture(GL_TEXTURE0 + 7);
    gl->BindTexture(GL_TEXTURE_2D, tex);
    gl->TexImage2D(GL_TEXTURE_2D, 0, GL_RGBA16, PW, PH, 0, GL_RGBA, GL_UNSIGNED_SHORT, codes);
    gl->TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    gl->TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    gl->ActiveTexture(GL_TEXTURE0);
    double worst = 0;
    for (int mode = 0; mode < 2; mode++) {
        char frag[4096], log[4096] = "";
        snprintf(frag, sizeof frag, "#define MODE %d\n%s", mode, unpack_frag);
        size_t n = strlen(f->glsl) + strlen(f->glsl_atlas) + 8;
        char *glsl = malloc(n);
        assert_non_null(glsl);
        snprintf(glsl, n, "%s\n%s", f->glsl, f->glsl_atlas);
        ibl_image out;
        ibl_status st = sg_render(&f->gl, f->ctx, &f->gpu, NULL, glsl, frag, PW, PH, &out, NULL, log, sizeof log);
        free(glsl);
        if (st != IBL_OK) print_error("unpack: %s\n", log);
        assert_int_equal(st, IBL_OK);
        for (int i = 0; i < PW * PH; i++) {
            const float *g = out.pixels + (size_t)i * 4, *c = packed.pixels + (size_t)i * 4;
            /* mode 0: R G B; mode 1: the transmittance (default 0), the applied maps' sum of
             * differences (0) and the AO */
            double want[3] = {mode ? c[3] : c[0], mode ? 0.0 : c[1], c[2]};
            for (int k = 0; k < 3; k++) worst = fmax(worst, fabs(g[k] - want[k]));
        }
        ibl_image_free(f->ctx, &out);
    }
    print_message("packed material, 16-bit codes: max |GPU - C| %.2e\n", worst);
    assert_true(worst <= 2.5e-7);
    gl->DeleteTextures(1, &tex);
    free(codes);
    ibl_image_free(f->ctx, &packed);
    for (int k = 0; k < 3; k++) ibl_image_free(f->ctx, &maps[k]);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(compile_all_dialects),
        cmocka_unit_test(sphere_grid_atlas_against_cube),
        cmocka_unit_test(unpack_material_matches_c),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
