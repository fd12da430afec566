/*
 * ibl.glsl - the runtime of ibl (include/ibl/shade.h) in GLSL: the same functions under the
 * same names, parameters and conventions, tested against the C on Mesa's llvmpipe
 * (tests/test_shaders.c). docs/SHADERS.md: how to include it, the textures and samplers it
 * expects, the uniform block a C helper fills (include/ibl/shader.h), a complete shader.
 *
 * Dialects: include after your own #version line.
 *   #version 450 core  OpenGL 4.5 (desktop)
 *   #version 300 es    OpenGL ES 3.00 / WebGL2: detected by GL_ES; the file sets highp
 *                      float, int and sampler3D precision
 *   #version 450       Vulkan GLSL (glslang -V): detected by VULKAN; nothing changes
 *                      here, the file declares no resources (bindings are yours)
 * Switches (#define before including):
 *   IBL_MAX_VOLUMES n  array size of ibl_volume_blend (default 8)
 *   IBL_MAX_LIGHTS n   array size of ibl_lights_shade and ibl_light_set (default 8, the
 *                      size of ibl_shader_lights in include/ibl/shader.h)
 *   IBL_NO_AMBIENT_BRDF_3D  leave out the functions that take the AmbientBRDF sampler3D
 *                      (tri-Ace Blinn-Phong), e.g. on devices short of texture slots; then
 *                      ibl_shade uses F0 in its place as the C does without a table
 *
 * Conventions (docs/CONVENTIONS.md): world right-handed, +Y up; V points from the surface to
 * the eye; N unit; roughness perceptual (alpha = r^2); shininess the exponent of tri-Ace
 * 2010's normalised Blinn-Phong; radiance linear RGB; cube faces in the OpenGL order and
 * orientation (what the KTX2 files hold). C functions that write one out array return it
 * here; those that write two scalars keep `out` parameters. Textures are parameters, so the
 * file works with any binding scheme.
 */
#ifndef IBL_GLSL
#define IBL_GLSL

#ifdef GL_ES
precision highp float;
precision highp int;
precision highp sampler3D;
#endif
#ifndef IBL_MAX_VOLUMES
#define IBL_MAX_VOLUMES 8
#endif
#ifndef IBL_MAX_LIGHTS
#define IBL_MAX_LIGHTS 8
#endif

#define IBL_PI 3.14159265358979
#define IBL_FLT_MAX 3.402823466e38
#define IBL_MIRROR_SHININESS 1e6
#define IBL_MIN_GGX_ALPHA 1e-3

/* enums of shade.h, same values */
#define IBL_SH_KIND_NONE 0
#define IBL_SH_KIND_RADIANCE 1
#define IBL_SH_KIND_IRRADIANCE 2
#define IBL_MATERIAL_GGX 0
#define IBL_MATERIAL_BLINN_PHONG 1
#define IBL_SO_NONE 0
#define IBL_SO_AO 1
#define IBL_SO_TRIACE 2
#define IBL_SO_TRIACE_SHININESS 3
#define IBL_SO_TRIACE_FAST 4
#define IBL_SO_FROSTBITE 5
#define IBL_SO_CONE 6
#define IBL_MIX_MULTIPLY 0
#define IBL_MIX_LERP_ALBEDO 1
#define IBL_MIX_LERP_AO 2
#define IBL_MIX_AO_LERP_AO 3
#define IBL_MIX_LERP_AO2 4
#define IBL_MIX_ENTIRE 5
#define IBL_ENERGY_NONE 0
#define IBL_ENERGY_FDEZ_AGUERA 1
#define IBL_ENERGY_TURQUIN 2
#define IBL_BP_DIFFUSE_AMBIENT_BRDF 0
#define IBL_BP_DIFFUSE_F0 1
#define IBL_VOLUME_SPHERE 0
#define IBL_VOLUME_BOX 1
#define IBL_LIGHT_SIZE_WIDEN 0
#define IBL_LIGHT_SIZE_IGNORE 1
/* enums of light.h */
#define IBL_LIGHT_DIRECTIONAL 0
#define IBL_LIGHT_POINT 1
#define IBL_LIGHT_SPOT 2

/* ---- data: std140 layouts, filled by include/ibl/shader.h ------------------------------- */

/* One table axis: sample i holds first + (last - first) i / (count - 1), or the same in log. */
struct ibl_table_axis {
    int count;
    float first;
    float last;
    int logarithmic;
};

/* The probe's numbers (ibl_probe less its textures): ibl_shader_probe in C, 384 bytes. */
struct ibl_probe {
    vec4 roughness[4];  /* mapping.roughness[k] = roughness[k / 4][k % 4]                 */
    vec4 shininess[4];  /* mapping.shininess[k], likewise                                 */
    vec4 sh[9];         /* rgb: the 9 SH coefficients (order and basis of shade.h)        */
    ibl_table_axis splitsum_n_dot_v, splitsum_roughness;
    ibl_table_axis ambient_n_dot_v, ambient_shininess, ambient_f0;
    int levels;             /* mapping.levels                                             */
    int sh_kind;            /* IBL_SH_KIND_*: NONE reads the irradiance cube              */
    float intensity;        /* scales every radiance read; resolved (never 0)             */
    float mirror_shininess; /* resolved (never 0)                                         */
    int has_mirror, has_splitsum, has_ambient_brdf, reserved;
};

/* Daqi 2016's 2D mip atlas layout (ibl_atlas_layout): ibl_shader_atlas in C. */
struct ibl_atlas_layout {
    int width, height, levels, gutter;
    ivec4 face_size[4]; /* face_size[k] = face_size[k / 4][k % 4]; x, y likewise          */
    ivec4 x[4];
    ivec4 y[4];
};

struct ibl_material {
    int model;          /* IBL_MATERIAL_*                                                 */
    vec3 base_color;    /* GGX: glTF baseColor; Blinn-Phong: Rd                           */
    float metallic;
    float roughness;
    vec3 f0;            /* Blinn-Phong F0 (GGX: dielectric F0, all-zero means 0.04)       */
    float shininess;
    float ao;
};

struct ibl_shade_desc {
    int energy, so, mix;
    int horizon_occlusion;
    float horizon_k;    /* 0: 1.3                                                         */
    int bp_diffuse, no_mirror, nearest_level, mirror_direction;
    int light_size;     /* IBL_LIGHT_SIZE_*: what a punctual light's size does            */
};

struct ibl_surface {
    vec3 n;
    vec3 v;
    vec3 geometric_normal; /* zero: same as n                                             */
    vec3 direct_specular;
};

struct ibl_shade_result {
    vec3 color;
    vec3 diffuse;
    vec3 specular;
    float so;
    float lod;
    vec3 r;
};

struct ibl_volume {
    int shape;
    vec3 center;
    vec3 half_extent;
    float radius;
    float blend_distance;
};

/* ---- small helpers -------------------------------------------------------------------- */

float ibli_level_roughness(ibl_probe p, int k) { return p.roughness[k / 4][k - 4 * (k / 4)]; }
float ibli_level_shininess(ibl_probe p, int k) { return p.shininess[k / 4][k - 4 * (k / 4)]; }
int ibli_ivec(ivec4 a[4], int k) { return a[k / 4][k - 4 * (k / 4)]; }
/* pow with C's powf at a zero base: 0^y = 0 for y > 0, 1 for y = 0 */
float ibli_pow(float x, float y) { return x > 0.0 ? pow(x, y) : (y > 0.0 ? 0.0 : 1.0); }
float ibli_asinh(float x) { float a = abs(x); return sign(x) * log(a + sqrt(a * a + 1.0)); }
float ibli_sinh(float x) { return 0.5 * (exp(x) - exp(-x)); }
/* acos and asin through atan: GLSL leaves their precision loose (Mesa's llvmpipe: 1.6e-4 and
 * 3.9e-4 rad), the atan forms hold 3e-6 there */
float ibli_acos(float x) { return atan(sqrt(max(1.0 - x * x, 0.0)), x); }
float ibli_asin(float x) { return atan(x, sqrt(max(1.0 - x * x, 0.0))); }
/* C's ibl__norm: a zero vector stays zero (GLSL's normalize would give NaN) */
vec3 ibli_normalize(vec3 v) { float l = length(v); return l > 0.0 ? v / l : v; }

/* ---- cube geometry (include/ibl/cubemap.h) ------------------------------------------- */

/* Face and (s, t) in [0, 1] of a direction, OpenGL's table (cubemap.h; ties x, y, z). */
int ibl_cube_face_st(vec3 d, out float s, out float t)
{
    vec3 a = abs(d);
    int face;
    float ma, sc, tc;
    if (a.x >= a.y && a.x >= a.z) {
        face = d.x >= 0.0 ? 0 : 1;
        ma = a.x;
        sc = d.x >= 0.0 ? -d.z : d.z;
        tc = -d.y;
    } else if (a.y >= a.z) {
        face = d.y >= 0.0 ? 2 : 3;
        ma = a.y;
        sc = d.x;
        tc = d.y >= 0.0 ? d.z : -d.z;
    } else {
        face = d.z >= 0.0 ? 4 : 5;
        ma = a.z;
        sc = d.z >= 0.0 ? d.x : -d.x;
        tc = -d.y;
    }
    if (ma == 0.0) ma = 1.0;
    float inv = 0.5 / ma;
    s = sc * inv + 0.5;
    t = tc * inv + 0.5;
    return face;
}

/* Unnormalised direction through face coordinates (s, t) in [0, 1] (cubemap.h). */
vec3 ibl_cube_direction(int face, float s, float t)
{
    float sc = 2.0 * s - 1.0, tc = 2.0 * t - 1.0;
    if (face == 0) return vec3(1.0, -tc, -sc);
    if (face == 1) return vec3(-1.0, -tc, sc);
    if (face == 2) return vec3(sc, 1.0, tc);
    if (face == 3) return vec3(sc, -1.0, -tc);
    if (face == 4) return vec3(sc, -tc, 1.0);
    return vec3(-sc, -tc, -1.0);
}

/* ---- tables (Karis 2013 split sum; tri-Ace 2010 AmbientBRDF) ------------------------- */

/* Value of sample i of an axis (linear or logarithmic). */
float ibl_table_axis_value(ibl_table_axis a, int i)
{
    if (a.count <= 1) return a.first;
    float t = float(i) / float(a.count - 1);
    if (a.logarithmic != 0) return exp(log(a.first) + t * (log(a.last) - log(a.first)));
    return a.first + t * (a.last - a.first);
}

/* Fractional sample index of a value, clamped to [0, count - 1]. */
float ibl_table_axis_index(ibl_table_axis a, float value)
{
    if (a.count <= 1) return 0.0;
    float t;
    if (a.logarithmic != 0) {
        if (value <= 0.0) return 0.0;
        t = (log(value) - log(a.first)) / (log(a.last) - log(a.first));
    } else {
        t = (value - a.first) / (a.last - a.first);
    }
    return clamp(t, 0.0, 1.0) * float(a.count - 1);
}

/* Normalised texture coordinate of a value on an axis of a texture with count texels. */
float ibli_axis_coord(ibl_table_axis a, float value)
{
    return (ibl_table_axis_index(a, value) + 0.5) / float(max(a.count, 1));
}

/* Split-sum A, B (Karis 2013) at n.v and roughness: table.rg, bilinear (shade.h). */
void ibl_splitsum_lookup(sampler2D table, ibl_probe p, float n_dot_v, float roughness,
                         out float a, out float b)
{
    vec2 uv = vec2(ibli_axis_coord(p.splitsum_n_dot_v, n_dot_v),
                   ibli_axis_coord(p.splitsum_roughness, roughness));
    vec2 ab = textureLod(table, uv, 0.0).rg;
    a = ab.x;
    b = ab.y;
}

#ifndef IBL_NO_AMBIENT_BRDF_3D
/* tri-Ace 2010 AmbientBRDF(n.v, shininess, F0): table.r, trilinear (shade.h). */
float ibl_ambient_brdf_lookup(sampler3D table, ibl_probe p, float n_dot_v, float shininess,
                              float f0)
{
    vec3 uvw = vec3(ibli_axis_coord(p.ambient_n_dot_v, n_dot_v),
                    ibli_axis_coord(p.ambient_shininess, shininess),
                    ibli_axis_coord(p.ambient_f0, f0));
    return textureLod(table, uvw, 0.0).r;
}
#endif

/* ---- BRDF pieces (src/shade/brdf_eval.c) --------------------------------------------- */

/* Schlick 1994: F0 + (1 - F0)(1 - v.h)^5. */
float ibl_fresnel_schlick(float f0, float v_dot_h)
{
    float c = 1.0 - max(v_dot_h, 0.0);
    float c2 = c * c;
    return f0 + (1.0 - f0) * c2 * c2 * c;
}

/* Trowbridge-Reitz / GGX (Walter et al. 2007): a^2 / (pi ((n.h)^2 (a^2 - 1) + 1)^2). */
float ibl_ggx_d(float alpha, float n_dot_h)
{
    if (n_dot_h <= 0.0) return 0.0;
    float a2 = alpha * alpha;
    float d = n_dot_h * n_dot_h * (a2 - 1.0) + 1.0;
    return a2 / (IBL_PI * d * d);
}

/* Height-correlated Smith V = G / (4 n.l n.v) (Heitz 2014). */
float ibl_smith_ggx_v(float alpha, float n_dot_v, float n_dot_l)
{
    if (n_dot_v <= 0.0 || n_dot_l <= 0.0) return 0.0;
    float a2 = alpha * alpha;
    float gv = n_dot_l * sqrt(n_dot_v * n_dot_v * (1.0 - a2) + a2);
    float gl = n_dot_v * sqrt(n_dot_l * n_dot_l * (1.0 - a2) + a2);
    return 0.5 / (gv + gl);
}

/* tri-Ace 2010's fitted normalisation of their Blinn-Phong lobe: 0.0397436 n + 0.0856832. */
float ibl_blinn_phong_norm(float shininess) { return 0.0397436 * shininess + 0.0856832; }

/* Blinn-Phong exponent of GGX alpha = r^2: n = 2 / alpha^2 - 2 (Walter et al. 2007). */
float ibl_shininess_from_roughness(float roughness)
{
    float a = roughness * roughness;
    if (a * a < 2e-6) return IBL_MIRROR_SHININESS;
    return max(2.0 / (a * a) - 2.0, 0.0);
}

/* The inverse: r = (2 / (n + 2))^(1/4) (Walter et al. 2007). */
float ibl_roughness_from_shininess(float shininess)
{
    return sqrt(sqrt(2.0 / (max(shininess, 0.0) + 2.0)));
}

/* ---- the probe (src/shade/probe.c) ---------------------------------------------------- */

/* Fractional level of a roughness: piecewise linear through the mapping (level k at r_k). */
float ibl_probe_lod_from_roughness(ibl_probe p, float roughness)
{
    int last = p.levels - 1;
    if (roughness <= ibli_level_roughness(p, 0)) return 0.0;
    int top = last; /* a run of equal values at the end: its sharpest level */
    while (top > 0 && ibli_level_roughness(p, top - 1) == ibli_level_roughness(p, top)) top--;
    if (roughness >= ibli_level_roughness(p, top)) return float(top);
    int k = 0;
    while (k < top - 1 && roughness >= ibli_level_roughness(p, k + 1)) k++;
    float r0 = ibli_level_roughness(p, k), span = ibli_level_roughness(p, k + 1) - r0;
    return span > 0.0 ? float(k) + (roughness - r0) / span : float(k);
}

/* Fractional level of a shininess: linear in log2 between levels (tri-Ace's a - 0.5 log2 n);
 * above level 0's shininess, minus the fraction toward the mirror cube when there is one. */
float ibl_probe_lod_from_shininess(ibl_probe p, float shininess)
{
    int last = p.levels - 1;
    shininess = max(shininess, 1e-3);
    float s0 = ibli_level_shininess(p, 0);
    if (shininess >= s0) {
        float ms = p.mirror_shininess;
        if (p.has_mirror == 0 || ms <= s0) return 0.0;
        return -min(log(shininess / s0) / log(ms / s0), 1.0);
    }
    int top = last;
    while (top > 0 && ibli_level_shininess(p, top - 1) == ibli_level_shininess(p, top)) top--;
    if (shininess <= ibli_level_shininess(p, top)) return float(top);
    int k = 0;
    while (k < top - 1 && shininess <= ibli_level_shininess(p, k + 1)) k++;
    float l0 = log2(ibli_level_shininess(p, k)), l1 = log2(ibli_level_shininess(p, k + 1));
    return l1 < l0 ? float(k) + (log2(shininess) - l0) / (l1 - l0) : float(k);
}

/* Prefiltered radiance along dir: trilinear between levels; lod in [-1, 0) blends level 0
 * toward the mirror cube (tri-Ace 2010 mirror option). Needs seamless cube filtering. */
vec3 ibl_probe_sample_specular(ibl_probe p, samplerCube specular, samplerCube mirror, float lod,
                               vec3 dir)
{
    if (lod < 0.0 && p.has_mirror != 0) {
        vec3 a = textureLod(specular, dir, 0.0).rgb, b = textureLod(mirror, dir, 0.0).rgb;
        return p.intensity * mix(a, b, min(-lod, 1.0));
    }
    return p.intensity * textureLod(specular, dir, clamp(lod, 0.0, float(p.levels - 1))).rgb;
}

/* Irradiance E(n) from 9 SH coefficients (Ramamoorthi & Hanrahan 2001; A = pi, 2pi/3, pi/4
 * convolve a RADIANCE set). Basis and order of shade.h. */
vec3 ibl_sh9_eval_irradiance(vec4 sh[9], int kind, vec3 n)
{
    float b1 = kind == IBL_SH_KIND_RADIANCE ? 2.09439510 : 1.0;
    float b2 = kind == IBL_SH_KIND_RADIANCE ? 0.78539816 : 1.0;
    float b0 = kind == IBL_SH_KIND_RADIANCE ? 3.14159265 : 1.0;
    vec3 e = b0 * 0.282095 * sh[0].rgb;
    e += b1 * 0.488603 * (n.y * sh[1].rgb + n.z * sh[2].rgb + n.x * sh[3].rgb);
    e += b2 * (1.092548 * (n.x * n.y * sh[4].rgb + n.y * n.z * sh[5].rgb + n.x * n.z * sh[7].rgb) +
               0.315392 * (3.0 * n.z * n.z - 1.0) * sh[6].rgb +
               0.546274 * (n.x * n.x - n.y * n.y) * sh[8].rgb);
    return max(e, vec3(0.0));
}

/* The IEM (tri-Ace 2010): E(n) / pi, from the SH or the irradiance cube. */
vec3 ibl_probe_irradiance(ibl_probe p, samplerCube irradiance, vec3 n)
{
    if (p.sh_kind != IBL_SH_KIND_NONE)
        return ibl_sh9_eval_irradiance(p.sh, p.sh_kind, n) * (p.intensity / IBL_PI);
    return p.intensity * textureLod(irradiance, n, 0.0).rgb;
}

/* ---- materials (src/shade/material.c) -------------------------------------------------- */

/* glTF 2.0 metal/roughness material, ao = 1. */
ibl_material ibl_material_gltf(vec3 base_color, float metallic, float roughness)
{
    return ibl_material(IBL_MATERIAL_GGX, base_color, metallic, roughness, vec3(0.0), 0.0, 1.0);
}

/* tri-Ace 2010 normalised Blinn-Phong material, ao = 1. */
ibl_material ibl_material_blinn_phong(vec3 rd, vec3 f0, float shininess)
{
    return ibl_material(IBL_MATERIAL_BLINN_PHONG, rd, 0.0, 0.0, f0, shininess, 1.0);
}

/* The BRDF's own reflectances: GGX F0 = lerp(0.04 or f0, base, metallic), albedo base (1 - m);
 * Blinn-Phong F0 = f0, albedo Rd (1 - F0) (tri-Ace 2010, "Equations"). */
void ibl_material_reflectances(ibl_material m, out vec3 f0, out vec3 diffuse_albedo)
{
    if (m.model == IBL_MATERIAL_BLINN_PHONG) {
        f0 = m.f0;
        diffuse_albedo = m.base_color * (1.0 - m.f0);
    } else {
        vec3 fd = m.f0 != vec3(0.0) ? m.f0 : vec3(0.04);
        f0 = fd + (m.base_color - fd) * m.metallic;
        diffuse_albedo = m.base_color * (1.0 - m.metallic);
    }
}

/* Lean t of the lookup lerp(N, R, t): GGX, Lagarde & de Rousiers 2014 (1 - r)(sqrt(1 - r) + r);
 * Blinn-Phong, the lobe centroid g / (1 + g), g = 0.1785 s^0.9805 (docs/SHADING.md). */
float ibl_dominant_direction_lean(ibl_material m)
{
    if (m.model == IBL_MATERIAL_BLINN_PHONG) {
        float g = 0.1785 * ibli_pow(max(m.shininess, 0.0), 0.9805);
        return g / (1.0 + g);
    }
    float rough = clamp(m.roughness, 0.0, 1.0), smooth_ = 1.0 - rough;
    return smooth_ * (sqrt(smooth_) + rough);
}

/* ---- occlusion and compositions (src/shade/occlusion.c) ------------------------------- */

/* Solid angle of two intersecting caps, smoothstep for partial overlap (Oat & Sander 2007);
 * 1 - cos r written 2 sin^2(r/2), which thin cones need. */
float ibli_cap_intersection(float r1, float r2, float d)
{
    float rmin = min(r1, r2), rmax = max(r1, r2);
    float h = sin(0.5 * rmin);
    float small_cap = 4.0 * IBL_PI * h * h;
    if (d <= rmax - rmin) return small_cap;
    if (d >= r1 + r2) return 0.0;
    float x = 1.0 - clamp((d - (rmax - rmin)) / (2.0 * rmin), 0.0, 1.0);
    return small_cap * x * x * (3.0 - 2.0 * x);
}

/* acos(1 - x) as 2 asin(sqrt(x / 2)): acos loses the angle near 1, 1 - c keeps its digits. */
float ibli_acos_one_minus(float x) { return 2.0 * ibli_asin(sqrt(clamp(0.5 * x, 0.0, 1.0))); }

/* Jimenez et al. 2016 cone SO: visibility cone (AO = sin^2) against the specular cone, the
 * half-angle where cos^n falls to 1/2 (1 - c = 1 - 2^(-1/(n+1)), a series when tiny). */
float ibli_cone_so(float n_dot_e, float ao, float roughness)
{
    float vis = ibli_asin(sqrt(clamp(ao, 0.0, 1.0)));
    float n = ibl_shininess_from_roughness(roughness);
    float k = 0.69314718 / (n + 1.0);
    float one_minus_c = k < 1e-3 ? k * (1.0 - k * (0.5 - k / 6.0)) : 1.0 - exp(-k);
    float spec = max(ibli_acos_one_minus(one_minus_c), 1e-4);
    float d = ibli_acos_one_minus(1.0 - clamp(n_dot_e, 0.0, 1.0));
    float h = sin(0.5 * spec);
    float cap = 4.0 * IBL_PI * h * h;
    return clamp(ibli_cap_intersection(vis, spec, d) / cap, 0.0, 1.0);
}

/* Specular occlusion (tri-Ace 2010 SO (1)-(3); Lagarde & de Rousiers 2014; Jimenez 2016). */
float ibl_specular_occlusion(int f, float n_dot_e, float ao, float roughness, float shininess)
{
    float ne = clamp(n_dot_e, 0.0, 1.0);
    ao = clamp(ao, 0.0, 1.0);
    if (f == IBL_SO_AO) return ao;
    if (f == IBL_SO_TRIACE) return clamp(ne * ne + 2.0 * ao - 1.0, 0.0, 1.0);
    if (f == IBL_SO_TRIACE_SHININESS)
        return clamp(ibli_pow(ne + ao, 0.01 * shininess) - 1.0 + ao, 0.0, 1.0);
    if (f == IBL_SO_TRIACE_FAST) return clamp((ne + ao) * (ne + ao) - 1.0 + ao, 0.0, 1.0);
    if (f == IBL_SO_FROSTBITE)
        return clamp(ibli_pow(ne + ao, exp2(-16.0 * roughness - 1.0)) - 1.0 + ao, 0.0, 1.0);
    if (f == IBL_SO_CONE) return ibli_cone_so(ne, ao, roughness);
    return 1.0;
}

/* Horizon fade saturate(1 + k R.Ng)^2 (Russell 2015, Marmoset); k <= 0 means 1.3. */
float ibl_horizon_occlusion(vec3 r, vec3 geometric_normal, float k)
{
    float h = clamp(1.0 + (k > 0.0 ? k : 1.3) * dot(r, geometric_normal), 0.0, 1.0);
    return h * h;
}

/* tri-Ace 2010's compositions of direct specular s_d, ambient diffuse and specular. */
vec3 ibl_ambient_mix_apply(int m, vec3 s_d, vec3 diffuse_ambient, vec3 specular_ambient,
                           vec3 albedo, float ao, float so)
{
    vec3 da = diffuse_ambient, sa = specular_ambient;
    if (m == IBL_MIX_LERP_ALBEDO) return s_d + mix(da * albedo, sa, so);
    if (m == IBL_MIX_LERP_AO) return s_d + mix(da * ao, sa, so);
    if (m == IBL_MIX_AO_LERP_AO) return s_d + ao * mix(da * ao, sa, so);
    if (m == IBL_MIX_LERP_AO2) return s_d + mix(da * (ao * ao), sa, so);
    if (m == IBL_MIX_ENTIRE) return s_d * so + ao * mix(da * ao, sa, so);
    return s_d + sa * so;
}

/* ---- shading (src/shade/material.c) --------------------------------------------------- */

/* Ambient lighting with the specular lookup direction given (Karis 2013 split sum with
 * Fdez-Aguera 2019 / Turquin 2019 compensation; tri-Ace 2010 AmbientBRDF). */
#ifndef IBL_NO_AMBIENT_BRDF_3D
ibl_shade_result ibl_shade_dir(ibl_probe probe, samplerCube specular, samplerCube mirror,
                               samplerCube irradiance, sampler2D splitsum,
                               sampler3D ambient_brdf, ibl_shade_desc desc, ibl_material m,
                               ibl_surface s, vec3 dir)
#else
ibl_shade_result ibl_shade_dir(ibl_probe probe, samplerCube specular, samplerCube mirror,
                               samplerCube irradiance, sampler2D splitsum, ibl_shade_desc desc,
                               ibl_material m, ibl_surface s, vec3 dir)
#endif
{
    /* n.v at 0 makes the tables' edge column meaningless; 1e-4 is below their step */
    float nv = max(dot(s.n, s.v), 1e-4);
    vec3 irr = ibl_probe_irradiance(probe, irradiance, s.n);
    float roughness, shininess, lod;
    bool bp = m.model == IBL_MATERIAL_BLINN_PHONG;
    if (bp) {
        shininess = m.shininess;
        roughness = ibl_roughness_from_shininess(shininess);
        lod = ibl_probe_lod_from_shininess(probe, shininess);
        if (desc.no_mirror != 0 && lod < 0.0) lod = 0.0;
    } else {
        roughness = clamp(m.roughness, 0.0, 1.0);
        shininess = ibl_shininess_from_roughness(roughness);
        lod = ibl_probe_lod_from_roughness(probe, roughness);
    }
    if (desc.nearest_level != 0 && lod > 0.0) lod = floor(lod + 0.5);
    vec3 pref = ibl_probe_sample_specular(probe, specular, mirror, lod, dir);
    vec3 spec, diffuse_color;
    if (bp) {
        vec3 ab = m.f0;
#ifndef IBL_NO_AMBIENT_BRDF_3D
        if (probe.has_ambient_brdf != 0)
            ab = vec3(ibl_ambient_brdf_lookup(ambient_brdf, probe, nv, shininess, m.f0.r),
                      ibl_ambient_brdf_lookup(ambient_brdf, probe, nv, shininess, m.f0.g),
                      ibl_ambient_brdf_lookup(ambient_brdf, probe, nv, shininess, m.f0.b));
#endif
        spec = pref * ab;
        vec3 kd = desc.bp_diffuse == IBL_BP_DIFFUSE_F0 ? 1.0 - m.f0 : 1.0 - ab;
        diffuse_color = m.base_color * clamp(kd, 0.0, 1.0);
    } else {
        float a = 1.0, b = 0.0;
        if (probe.has_splitsum != 0) ibl_splitsum_lookup(splitsum, probe, nv, roughness, a, b);
        float ess = a + b;
        vec3 fd = m.f0 != vec3(0.0) ? m.f0 : vec3(0.04);
        vec3 f0 = fd + (m.base_color - fd) * m.metallic;
        vec3 fss_ess = f0 * a + b;
        spec = pref * fss_ess;
        if (desc.energy == IBL_ENERGY_FDEZ_AGUERA && ess > 0.0) {
            /* Fdez-Aguera 2019 section 3: multiply-scattered energy lit by the irradiance */
            float ems = 1.0 - ess;
            vec3 favg = f0 + (1.0 - f0) / 21.0;
            vec3 fms = fss_ess * favg / (1.0 - ems * favg);
            spec += fms * ems * irr;
        } else if (desc.energy == IBL_ENERGY_TURQUIN && ess > 0.0) {
            spec *= 1.0 + f0 * (1.0 / ess - 1.0); /* Turquin 2019 */
        }
        diffuse_color = m.base_color * (1.0 - m.metallic);
    }
    float so = ibl_specular_occlusion(desc.so, nv, m.ao, roughness, shininess);
    if (desc.horizon_occlusion != 0) {
        vec3 ng = s.geometric_normal != vec3(0.0) ? s.geometric_normal : s.n;
        so *= ibl_horizon_occlusion(dir, ng, desc.horizon_k);
    }
    vec3 mixed = ibl_ambient_mix_apply(desc.mix, s.direct_specular, irr, spec, diffuse_color,
                                       m.ao, so);
    ibl_shade_result r;
    r.diffuse = diffuse_color * irr;
    r.specular = spec;
    r.color = r.diffuse * m.ao + mixed;
    r.so = so;
    r.lod = lod;
    r.r = dir;
    return r;
}

/* The lookup direction of ibl_shade: R = 2 (n.v) n - v leaned toward N by
 * ibl_dominant_direction_lean unless desc.mirror_direction (Lagarde & de Rousiers 2014). */
vec3 ibl_shade_lookup_direction(ibl_shade_desc desc, ibl_material m, ibl_surface s)
{
    vec3 r = 2.0 * dot(s.n, s.v) * s.n - s.v;
    if (desc.mirror_direction == 0) {
        vec3 d = mix(s.n, r, ibl_dominant_direction_lean(m));
        float len = length(d);
        if (len > 0.0) r = d / len;
    }
    return r;
}

/* Ambient lighting of one surface point: diffuse * AO + composed specular (shade.h). */
#ifndef IBL_NO_AMBIENT_BRDF_3D
ibl_shade_result ibl_shade(ibl_probe probe, samplerCube specular, samplerCube mirror,
                           samplerCube irradiance, sampler2D splitsum, sampler3D ambient_brdf,
                           ibl_shade_desc desc, ibl_material m, ibl_surface s)
{
    return ibl_shade_dir(probe, specular, mirror, irradiance, splitsum, ambient_brdf, desc, m, s,
                         ibl_shade_lookup_direction(desc, m, s));
}
#else
ibl_shade_result ibl_shade(ibl_probe probe, samplerCube specular, samplerCube mirror,
                           samplerCube irradiance, sampler2D splitsum, ibl_shade_desc desc,
                           ibl_material m, ibl_surface s)
{
    return ibl_shade_dir(probe, specular, mirror, irradiance, splitsum, desc, m, s,
                         ibl_shade_lookup_direction(desc, m, s));
}
#endif

/* One step of ibl_shade_blend (tri-Ace 2010 "IBL Blending"): adds a probe's result by its
 * weight; so, lod and r follow the heaviest probe so far (start with heaviest = -1). */
void ibl_shade_blend_add(inout ibl_shade_result acc, inout float heaviest, float weight,
                         ibl_shade_result r)
{
    if (weight <= 0.0) return;
    acc.color += weight * r.color;
    acc.diffuse += weight * r.diffuse;
    acc.specular += weight * r.specular;
    if (weight > heaviest) {
        heaviest = weight;
        acc.so = r.so;
        acc.lod = r.lod;
        acc.r = r.r;
    }
}

/* ---- local probes (src/shade/volumes.c) ----------------------------------------------- */

/* Volume of a box or sphere (the priority order's key). */
float ibl_volume_size(ibl_volume v)
{
    if (v.shape == IBL_VOLUME_BOX) return 8.0 * v.half_extent.x * v.half_extent.y * v.half_extent.z;
    return 4.18879020 * v.radius * v.radius * v.radius;
}

/* Distance from p to the volume's surface, positive inside. */
float ibli_inside_distance(ibl_volume v, vec3 p)
{
    vec3 d = p - v.center;
    if (v.shape == IBL_VOLUME_BOX) {
        vec3 a = v.half_extent - abs(d);
        return min(min(a.x, a.y), a.z);
    }
    return v.radius - length(d);
}

/* Influence weight: 1 deeper than blend_distance, linear to 0 at the surface (JAGE 2015). */
float ibl_volume_weight(ibl_volume v, vec3 p)
{
    float d = ibli_inside_distance(v, p);
    if (d < 0.0) return 0.0;
    if (v.blend_distance <= 0.0) return 1.0;
    return clamp(d / v.blend_distance, 0.0, 1.0);
}

/* Priority blending (JAGE 2015): in `order` (smallest first, ibl_volume_sort on the CPU) each
 * volume takes w_i (1 - sum before); returns the rest, the global probe's weight. */
float ibl_volume_blend(ibl_volume volumes[IBL_MAX_VOLUMES], int order[IBL_MAX_VOLUMES], int count,
                       vec3 p, out float weights[IBL_MAX_VOLUMES])
{
    float used = 0.0;
    for (int i = 0; i < IBL_MAX_VOLUMES; i++) weights[i] = 0.0;
    for (int i = 0; i < IBL_MAX_VOLUMES; i++) {
        if (i >= count) break;
        int k = order[i];
        float w = ibl_volume_weight(volumes[k], p) * (1.0 - used);
        weights[k] = w;
        used += w;
        if (used >= 1.0) {
            used = 1.0;
            break;
        }
    }
    return 1.0 - used;
}

/* Parallax correction (Lagarde 2012): the ray p + t r meets the proxy (p inside); returns the
 * direction from the capture position to the hit, or r when p is outside. */
vec3 ibl_parallax_correct(ibl_volume proxy, vec3 probe_position, vec3 p, vec3 r)
{
    if (ibli_inside_distance(proxy, p) < 0.0) return r;
    float t;
    if (proxy.shape == IBL_VOLUME_BOX) {
        t = IBL_FLT_MAX; /* the nearest of the far planes */
        for (int i = 0; i < 3; i++) {
            if (r[i] == 0.0) continue;
            float plane = r[i] > 0.0 ? proxy.center[i] + proxy.half_extent[i]
                                     : proxy.center[i] - proxy.half_extent[i];
            t = min(t, (plane - p[i]) / r[i]);
        }
        if (t == IBL_FLT_MAX) return r;
    } else {
        vec3 o = p - proxy.center; /* far root of |o + t r|^2 = R^2 */
        float a = dot(r, r), b = dot(o, r), c = dot(o, o) - proxy.radius * proxy.radius;
        if (a <= 0.0) return r;
        t = (-b + sqrt(max(b * b - a * c, 0.0))) / a;
    }
    return ibli_normalize(p + t * r - probe_position);
}

/* The IBL offset (tri-Ace 2010): normalize(c (P_obj - P_IBL) + R). */
vec3 ibl_offset_reflection(vec3 r, vec3 p_obj, vec3 p_ibl, float c)
{
    return ibli_normalize(c * (p_obj - p_ibl) + r);
}

/* The IBL offset's coefficient for surroundings at environment_radius: k / radius (k <= 0:
 * 1), the first-order parallax of a sphere of that radius (docs/SHADING.md); 0 if no radius. */
float ibl_offset_coefficient(float environment_radius, float k)
{
    if (!(environment_radius > 0.0)) return 0.0;
    return (k > 0.0 ? k : 1.0) / environment_radius;
}

/* The shininess hack (tri-Ace 2010): n saturate(60 / light_size (1 - attenuation))^2. */
float ibl_shininess_hack(float shininess, float light_size, float attenuation)
{
    if (light_size <= 0.0) return shininess;
    float s = clamp(60.0 / light_size * (1.0 - attenuation), 0.0, 1.0);
    return shininess * s * s;
}

/* The environment switch (Daqi 2016): saturate((position - border) / size + 0.5). */
float ibl_environment_switch(float position, float border, float size)
{
    if (size <= 0.0) return position >= border ? 1.0 : 0.0;
    return clamp((position - border) / size + 0.5, 0.0, 1.0);
}

/* ---- the 2D mip atlas (Daqi 2016; src/shade/atlas.c) ---------------------------------- */

/* Atlas UV (u right, v down from the top row) of a direction on a level. */
void ibl_atlas_uv(ibl_atlas_layout l, int level, vec3 dir, out float u, out float v)
{
    float s, t;
    int f = ibl_cube_face_st(dir, s, t);
    s = clamp(s, 0.0, 1.0); /* rounding never leaves the face's cell (the gutter is there) */
    t = clamp(t, 0.0, 1.0);
    int n = ibli_ivec(l.face_size, level);
    int c = n + 2 * l.gutter;
    int ox = ibli_ivec(l.x, level) + (f - 3 * (f / 3)) * c, oy = ibli_ivec(l.y, level) + (f / 3) * c;
    u = (float(ox + l.gutter) + s * float(n)) / float(l.width);
    v = (float(oy + l.gutter) + t * float(n)) / float(l.height);
}

/* Trilinear read of the atlas: bilinear at the two levels around lod, then linear. The
 * atlas texture: one level, GL_LINEAR, clamp to edge, its first row at v = 0. */
vec4 ibl_atlas_sample(sampler2D atlas, ibl_atlas_layout l, float lod, vec3 dir)
{
    lod = clamp(lod, 0.0, float(l.levels - 1));
    int k = int(floor(lod));
    float w = lod - float(k), u, v;
    ibl_atlas_uv(l, k, dir, u, v);
    vec4 a = textureLod(atlas, vec2(u, v), 0.0);
    if (w == 0.0 || k + 1 >= l.levels) return a;
    ibl_atlas_uv(l, k + 1, dir, u, v);
    return mix(a, textureLod(atlas, vec2(u, v), 0.0), w);
}

/* ---- warp edge fixup lookup (Castano 2012; src/bake/edge_fixup.c) --------------------- */

/* Direction to sample on a warped level of edge n: face coordinates through the inverse of
 * w = u + a u^3, a = n^2 / (n - 1)^3 (Cardano's hyperbolic form). */
vec3 ibl_edge_fixup_warp_lookup(vec3 dir, int n)
{
    if (n < 2) return normalize(dir);
    float s, t;
    int face = ibl_cube_face_st(dir, s, t);
    float fn = float(n), a = fn * fn / ((fn - 1.0) * (fn - 1.0) * (fn - 1.0));
    float k = sqrt(3.0 * a);
    float u = 2.0 / k * ibli_sinh(ibli_asinh(1.5 * k * (2.0 * s - 1.0)) / 3.0);
    float v = 2.0 / k * ibli_sinh(ibli_asinh(1.5 * k * (2.0 * t - 1.0)) / 3.0);
    return normalize(ibl_cube_direction(face, 0.5 * u + 0.5, 0.5 * v + 0.5));
}

/* ---- punctual lights (include/ibl/light.h; src/shade/light.c) ------------------------- */

/* A KHR_lights_punctual light (ibl_light): ibl_shader_light in C (include/ibl/shader.h),
 * four 16-byte rows, std140 and HLSL packing alike. Zero means the C's defaults. */
struct ibl_light {
    vec3 color;       /* linear RGB; all zero: white                                       */
    float intensity;  /* lux (directional) or candela (point, spot); 0: 1                  */
    vec3 position;    /* point, spot                                                       */
    float range;      /* point, spot: where the light reaches zero; 0: infinite            */
    vec3 direction;   /* directional, spot: the direction the light travels; any length   */
    float size;       /* emitter radius; directional: tan of its angular radius; 0: point  */
    int type;         /* IBL_LIGHT_*                                                       */
    float inner_cone; /* spot: half-angles in radians; outer 0: pi/4                       */
    float outer_cone;
    int reserved;
};

/* A uniform block's worth of lights: ibl_shader_lights in C (ibl_shader_lights_fill). */
struct ibl_light_set {
    int count, reserved0, reserved1, reserved2;
    ibl_light light[IBL_MAX_LIGHTS];
};

/* What a light delivers at a point (ibl_light_incidence). distance: IBL_FLT_MAX for a
 * directional light, where the C has INFINITY (GLSL ES need not represent infinities). */
struct ibl_light_incidence {
    vec3 l;
    float distance;
    vec3 illuminance;
    float size;
    float attenuation;
};

/* One light's reflected radiance (ibl_light_result): specular is s_d of the compositions. */
struct ibl_light_result {
    vec3 diffuse;
    vec3 specular;
    float n_dot_l;
    float shininess;
    float alpha;
};

/* KHR_lights_punctual's range window saturate(1 - (d / range)^4); 1 without a range. */
float ibl_light_range_window(float distance, float range)
{
    if (!(range > 0.0)) return 1.0;
    float x = distance / range, x2 = x * x;
    return clamp(1.0 - x2 * x2, 0.0, 1.0);
}

/* KHR_lights_punctual's distance falloff: window / d^2, d floored at 1e-4. */
float ibl_light_distance_falloff(float distance, float range)
{
    float d = distance > 1e-4 ? distance : 1e-4;
    return ibl_light_range_window(d, range) / (d * d);
}

/* KHR_lights_punctual's cone falloff saturate((cos - cos_outer) / (cos_inner - cos_outer))^2. */
float ibl_light_cone_falloff(float cos_angle, float inner_cone, float outer_cone)
{
    float cos_inner = cos(inner_cone), cos_outer = cos(outer_cone);
    float t = clamp((cos_angle - cos_outer) / max(1e-3, cos_inner - cos_outer), 0.0, 1.0);
    return t * t;
}

/* Karis 2013 sphere light: GGX alpha widened to saturate(alpha + radius / (2 distance)). */
float ibl_ggx_sphere_alpha(float alpha, float radius, float distance)
{
    if (!(radius > 0.0) || !(distance > 0.0)) return alpha;
    return clamp(alpha + radius / (2.0 * distance), 0.0, 1.0);
}

/* Direction, distance, illuminance and tri-Ace's attenuation factor of a light at p. */
ibl_light_incidence ibl_light_incidence_at(ibl_light light, vec3 p)
{
    ibl_light_incidence r;
    float scale = light.intensity > 0.0 ? light.intensity : 1.0;
    vec3 color = light.color == vec3(0.0) ? vec3(1.0) : light.color;
    float falloff = 1.0;
    r.size = light.size > 0.0 ? light.size : 0.0;
    r.attenuation = 0.0;
    if (light.type == IBL_LIGHT_DIRECTIONAL) {
        r.l = ibli_normalize(-light.direction);
        r.distance = IBL_FLT_MAX;
    } else {
        vec3 to_light = light.position - p;
        float d = sqrt(dot(to_light, to_light));
        r.distance = d;
        if (d > 0.0) {
            r.l = to_light / d;
            falloff = ibl_light_distance_falloff(d, light.range);
        } else { /* at the light itself there is no direction to light from */
            r.l = vec3(0.0, 1.0, 0.0);
            falloff = 0.0;
        }
        /* the talk's attenuation factor: the range window (1 at the light, 0 at its range) */
        if (light.range > 0.0) r.attenuation = ibl_light_range_window(d, light.range);
        if (light.type == IBL_LIGHT_SPOT) {
            float outer = light.outer_cone > 0.0 ? light.outer_cone : 0.78539816;
            falloff *= ibl_light_cone_falloff(-dot(ibli_normalize(light.direction), r.l),
                                              light.inner_cone, outer);
        }
    }
    r.illuminance = color * scale * falloff;
    return r;
}

/* One light from its incidence on tri-Ace 2010's Blinn-Phong ("Equations", with the shininess
 * hack) or glTF 2.0's GGX (D with Karis 2013's alpha, V the material's); desc.light_size. */
ibl_light_result ibl_light_shade_incidence(ibl_light_incidence inc, ibl_shade_desc desc,
                                           ibl_material m, ibl_surface s)
{
    ibl_light_result r = ibl_light_result(vec3(0.0), vec3(0.0), 0.0, 0.0, 0.0);
    bool widen = desc.light_size == IBL_LIGHT_SIZE_WIDEN;
    bool bp = m.model == IBL_MATERIAL_BLINN_PHONG;
    float alpha = max(m.roughness * m.roughness, IBL_MIN_GGX_ALPHA);
    if (bp) {
        r.shininess = widen ? ibl_shininess_hack(m.shininess, inc.size, inc.attenuation)
                            : m.shininess;
    } else { /* a directional light's size is already the ratio radius / distance */
        float distance = inc.distance >= IBL_FLT_MAX ? 1.0 : inc.distance;
        r.alpha = widen ? ibl_ggx_sphere_alpha(alpha, inc.size, distance) : alpha;
    }
    float nl = dot(s.n, inc.l);
    if (nl <= 0.0) return r;
    float nv = max(dot(s.n, s.v), 1e-4);
    vec3 h = ibli_normalize(s.v + inc.l);
    float nh = max(dot(s.n, h), 0.0), vh = max(dot(s.v, h), 0.0);
    float lobe;
    if (bp)
        lobe = ibl_blinn_phong_norm(r.shininess) * ibli_pow(nh, r.shininess) / max(nl, nv);
    else
        lobe = ibl_ggx_d(r.alpha, nh) * ibl_smith_ggx_v(alpha, nv, nl);
    vec3 f0, albedo;
    ibl_material_reflectances(m, f0, albedo);
    vec3 e = inc.illuminance * nl;
    vec3 fresnel = vec3(ibl_fresnel_schlick(f0.r, vh), ibl_fresnel_schlick(f0.g, vh),
                        ibl_fresnel_schlick(f0.b, vh));
    r.specular = lobe * fresnel * e;
    r.diffuse = albedo * (1.0 / IBL_PI) * e;
    r.n_dot_l = nl;
    return r;
}

/* One light at point p of a surface (ibl_light_shade). */
ibl_light_result ibl_light_shade(ibl_light light, ibl_shade_desc desc, ibl_material m,
                                 ibl_surface s, vec3 p)
{
    return ibl_light_shade_incidence(ibl_light_incidence_at(light, p), desc, m, s);
}

/* The first count lights summed, each scaled by its visibility (e.g. 0 in its shadow).
 * Feed the result to the ambient compositions as the C's `ibl render` does:
 *   s.direct_specular = total.specular; colour = ibl_shade(...).color + total.diffuse */
ibl_light_result ibl_lights_shade(ibl_light lights[IBL_MAX_LIGHTS], int count,
                                  float visibility[IBL_MAX_LIGHTS], ibl_shade_desc desc,
                                  ibl_material m, ibl_surface s, vec3 p)
{
    ibl_light_result acc = ibl_light_result(vec3(0.0), vec3(0.0), 0.0, 0.0, 0.0);
    for (int i = 0; i < IBL_MAX_LIGHTS; i++) {
        if (i >= count) break;
        float vis = visibility[i];
        if (!(vis > 0.0)) continue;
        ibl_light_result one = ibl_light_shade(lights[i], desc, m, s, p);
        if (one.n_dot_l <= 0.0) continue;
        acc.diffuse += vis * one.diffuse;
        acc.specular += vis * one.specular;
        acc.n_dot_l = one.n_dot_l;
        acc.shininess = one.shininess;
        acc.alpha = one.alpha;
    }
    return acc;
}

/* The same with every light visible (the C's visibility = NULL). */
ibl_light_result ibl_lights_shade(ibl_light lights[IBL_MAX_LIGHTS], int count,
                                  ibl_shade_desc desc, ibl_material m, ibl_surface s, vec3 p)
{
    float visibility[IBL_MAX_LIGHTS];
    for (int i = 0; i < IBL_MAX_LIGHTS; i++) visibility[i] = 1.0;
    return ibl_lights_shade(lights, count, visibility, desc, m, s, p);
}

#endif /* IBL_GLSL */
