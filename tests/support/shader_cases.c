/* The case table of tests/test_shaders.c: one entry per function of shaders/ibl.glsl, its
 * inputs (random plus the edge cases: grazing n.v, roughness 0 and 1, AO 0 and 1, directions
 * on cube edges and corners), its C twin and its tolerance with the reason.
 *
 * Tolerance classes:
 *  - ARITH: + - * / sqrt only: float rounding, a few ulps (fused multiply-adds in the JIT).
 *  - TRANSC: pow, exp, log, trig: GLSL allows ~3 ulp (exp2/log2) and more for pow, acos.
 *  - FILTER: a texture read: the GPU rounds the sub-texel weight to 8 bits (llvmpipe; the D3D
 *    and Vulkan minimum too), so a bilinear result may move by (texel step) / 512; and cube
 *    corners, where OpenGL leaves the missing fourth texel to the implementation. */
#include "shader_test.h"

#include <math.h>
#include <string.h>

#define ARITH 1e-6, 1e-5
#define TRANSC 1e-5, 2e-4

/* ---- generators ------------------------------------------------------------------------ */

float sc_rnd(uint64_t *s)
{
    *s ^= *s << 13; /* xorshift64 (Marsaglia 2003) */
    *s ^= *s >> 7;
    *s ^= *s << 17;
    return (float)((*s >> 40) * (1.0 / 16777216.0));
}

/* Every 4th sample cycles through the edge values, the others are uniform in [lo, hi]. */
float sc_pick(int i, uint64_t *s, const float *edges, int n, float lo, float hi)
{
    float r = sc_rnd(s);
    if (n > 0 && i % 4 == 0) return edges[(i / 4) % n];
    return lo + (hi - lo) * r;
}

float sc_pick_log(int i, uint64_t *s, const float *edges, int n, float lo, float hi)
{
    float r = sc_rnd(s);
    if (n > 0 && i % 4 == 0) return edges[(i / 4) % n];
    return expf(logf(lo) + (logf(hi) - logf(lo)) * r);
}

int sc_pick_int(uint64_t *s, int count)
{
    int k = (int)(sc_rnd(s) * (float)count);
    return k < count ? k : count - 1;
}

/* Unit direction; every 3rd sample lies on a cube edge or corner (or a face centre), some
 * of them nudged by 1e-6 off it. */
void sc_gen_dir(int i, uint64_t *s, float *d)
{
    if (i % 3 == 0) {
        int code = sc_pick_int(s, 26);
        code += code >= 13; /* skip (0, 0, 0) */
        float v[3] = {(float)(code % 3) - 1.0f, (float)(code / 3 % 3) - 1.0f,
                      (float)(code / 9) - 1.0f};
        if (sc_rnd(s) < 0.3f) v[sc_pick_int(s, 3)] += sc_rnd(s) < 0.5f ? 1e-6f : -1e-6f;
        float len = sqrtf(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        for (int k = 0; k < 3; k++) d[k] = v[k] / len;
        return;
    }
    float v[3], len;
    do {
        for (int k = 0; k < 3; k++) v[k] = 2.0f * sc_rnd(s) - 1.0f;
        len = sqrtf(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    } while (len < 0.1f || len > 1.0f);
    for (int k = 0; k < 3; k++) d[k] = v[k] / len;
}

/* A surface: n a unit direction, v at a polar cosine that is often grazing. */
static void gen_nv(int i, uint64_t *s, float *n, float *v)
{
    static const float grazing[] = {0.0f, 1e-4f, 1e-3f, 0.02f, 1.0f, -0.05f};
    sc_gen_dir(i / 2, s, n);
    float c = sc_pick(i / 2 + 1, s, grazing, 6, 0.0f, 1.0f);
    float t[3], len;
    do {
        sc_gen_dir(1, s, t);
        float d = t[0] * n[0] + t[1] * n[1] + t[2] * n[2];
        for (int k = 0; k < 3; k++) t[k] -= d * n[k];
        len = sqrtf(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
    } while (len < 1e-3f);
    float sn = sqrtf(fmaxf(0.0f, 1.0f - c * c));
    for (int k = 0; k < 3; k++) v[k] = n[k] * c + t[k] / len * sn;
}

ibl_vec3 sc_v3(const float *x) { return (ibl_vec3){x[0], x[1], x[2]}; }
void sc_put3(float *y, ibl_vec3 v)
{
    y[0] = v.x;
    y[1] = v.y;
    y[2] = v.z;
}

/* x[0..10]: model, base colour, metallic, roughness, f0, shininess, ao */
void sc_gen_material(int i, uint64_t *s, float *x)
{
    static const float r_edges[] = {0.0f, 1.0f, 0.5f, 0.0376f};
    static const float s_edges[] = {1.0f, 100000.0f, 1e6f, 0.5f};
    static const float unit_edges[] = {0.0f, 1.0f};
    x[0] = (float)(i % 2);
    for (int k = 1; k < 4; k++) x[k] = sc_rnd(s);
    x[4] = sc_pick(i / 2, s, unit_edges, 2, 0.0f, 1.0f);
    x[5] = sc_pick(i / 2 + 1, s, r_edges, 4, 0.0f, 1.0f);
    int f0_given = x[0] == 1.0f || sc_rnd(s) < 0.3f;
    for (int k = 6; k < 9; k++) x[k] = f0_given ? 0.02f + 0.98f * sc_rnd(s) : 0.0f;
    x[9] = sc_pick_log(i / 2 + 2, s, s_edges, 4, 0.5f, 2e5f);
    x[10] = sc_pick(i / 2 + 3, s, unit_edges, 2, 0.0f, 1.0f);
}

ibl_material sc_material_of(const float *x)
{
    ibl_material m;
    memset(&m, 0, sizeof m);
    m.model = (ibl_material_model)(int)x[0];
    for (int c = 0; c < 3; c++) {
        m.base_color[c] = x[1 + c];
        m.f0[c] = x[6 + c];
    }
    m.metallic = x[4];
    m.roughness = x[5];
    m.shininess = x[9];
    m.ao = x[10];
    return m;
}

/* x[0..11]: n, v, geometric normal (zero half the time), direct specular */
void sc_gen_surface(int i, uint64_t *s, float *x)
{
    gen_nv(i, s, x, x + 3);
    if (sc_rnd(s) < 0.5f) {
        x[6] = x[7] = x[8] = 0.0f;
    } else {
        float g[3], len;
        sc_gen_dir(1, s, g);
        for (int k = 0; k < 3; k++) g[k] = x[k] + 0.5f * g[k];
        len = sqrtf(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
        for (int k = 0; k < 3; k++) x[6 + k] = len > 0.0f ? g[k] / len : x[k];
    }
    int sd = sc_rnd(s) < 0.5f;
    for (int k = 9; k < 12; k++) x[k] = sd ? sc_rnd(s) : 0.0f;
}

ibl_surface sc_surface_of(const float *x)
{
    ibl_surface s;
    memset(&s, 0, sizeof s);
    s.n = sc_v3(x);
    s.v = sc_v3(x + 3);
    s.geometric_normal = sc_v3(x + 6);
    for (int c = 0; c < 3; c++) s.direct_specular[c] = x[9 + c];
    return s;
}

/* x[0..8]: energy, so, mix, horizon, horizon_k, bp_diffuse, no_mirror, nearest, mirror_dir */
static void gen_desc(uint64_t *s, float *x)
{
    static const float ks[] = {0.0f, 1.3f, 2.0f};
    x[0] = (float)sc_pick_int(s, 3);
    x[1] = (float)sc_pick_int(s, IBL_SO_COUNT);
    x[2] = (float)sc_pick_int(s, IBL_MIX_COUNT);
    x[3] = (float)(sc_rnd(s) < 0.5f);
    x[4] = ks[sc_pick_int(s, 3)];
    x[5] = (float)(sc_rnd(s) < 0.5f);
    x[6] = (float)(sc_rnd(s) < 0.3f);
    x[7] = (float)(sc_rnd(s) < 0.2f);
    x[8] = (float)(sc_rnd(s) < 0.3f);
}

static ibl_shade_desc desc_of(const float *x)
{
    ibl_shade_desc d;
    memset(&d, 0, sizeof d);
    d.energy = (ibl_energy_compensation)(int)x[0];
    d.so = (ibl_so_formula)(int)x[1];
    d.mix = (ibl_ambient_mix)(int)x[2];
    d.horizon_occlusion = (int)x[3];
    d.horizon_k = x[4];
    d.bp_diffuse = (ibl_bp_diffuse)(int)x[5];
    d.no_mirror = (int)x[6];
    d.nearest_level = (int)x[7];
    d.mirror_direction = (int)x[8];
    d.light_size = IBL_LIGHT_SIZE_WIDEN; /* D(k) in the GLSL: only the lights read it */
    return d;
}

/* x[0..8]: shape, centre, half extent, radius, blend distance */
static void gen_volume(uint64_t *s, float *x)
{
    x[0] = (float)(sc_rnd(s) < 0.5f);
    for (int k = 1; k < 4; k++) x[k] = 2.0f * sc_rnd(s) - 1.0f;
    for (int k = 4; k < 7; k++) x[k] = 0.3f + 2.0f * sc_rnd(s);
    x[7] = 0.3f + 2.0f * sc_rnd(s);
    x[8] = sc_rnd(s) < 0.2f ? 0.0f : sc_rnd(s);
}

static ibl_volume volume_of(const float *x)
{
    ibl_volume v;
    memset(&v, 0, sizeof v);
    v.shape = (ibl_volume_shape)(int)x[0];
    v.center = sc_v3(x + 1);
    v.half_extent = sc_v3(x + 4);
    v.radius = x[7];
    v.blend_distance = x[8];
    return v;
}

static void put_result(float *y, const ibl_shade_result *r)
{
    for (int c = 0; c < 3; c++) {
        y[c] = r->color[c];
        y[3 + c] = r->diffuse[c];
        y[6 + c] = r->specular[c];
    }
    y[9] = r->so;
    y[10] = r->lod;
    sc_put3(y + 11, r->r);
}

static const float unit_edges[] = {0.0f, 1.0f};
static const float nv_edges[] = {0.0f, 1e-4f, 1.0f, -0.1f, 1.1f};

/* ---- tables ---------------------------------------------------------------------------- */

static void gen_axis(const fixture *f, int i, uint64_t *s, float *x)
{
    (void)f;
    static const int counts[] = {1, 2, 16, 64};
    x[0] = (float)counts[sc_pick_int(s, 4)];
    x[3] = (float)(sc_rnd(s) < 0.5f);
    x[1] = 0.01f + sc_rnd(s);
    x[2] = x[1] + 100.0f * sc_rnd(s) + 0.01f;
    x[4] = (float)sc_pick_int(s, (int)x[0]);
    static const float rel[] = {0.0f, 1.0f, -0.5f};
    float t = sc_pick(i, s, rel, 3, -0.2f, 1.2f);
    x[5] = x[1] + (x[2] - x[1]) * t;
}

static ibl_table_axis axis_of(const float *x)
{
    ibl_table_axis a = {(int)x[0], x[1], x[2], (int)x[3]};
    return a;
}

static void ref_axis_value(const fixture *f, const float *x, float *y)
{
    (void)f;
    ibl_table_axis a = axis_of(x);
    y[0] = ibl_table_axis_value(&a, (int)x[4]);
}

static void ref_axis_index(const fixture *f, const float *x, float *y)
{
    (void)f;
    ibl_table_axis a = axis_of(x);
    y[0] = ibl_table_axis_index(&a, x[5]);
}

static void gen_splitsum(const fixture *f, int i, uint64_t *s, float *x)
{
    (void)f;
    x[0] = sc_pick(i, s, nv_edges, 5, 0.0f, 1.0f);
    x[1] = sc_pick(i / 2, s, unit_edges, 2, 0.0f, 1.0f);
}

static void ref_splitsum(const fixture *f, const float *x, float *y)
{
    ibl_splitsum_lookup(&f->probe.splitsum, x[0], x[1], &y[0], &y[1]);
}

static void gen_ambient(const fixture *f, int i, uint64_t *s, float *x)
{
    (void)f;
    static const float s_edges[] = {1.0f, 100000.0f, 0.5f, 1e6f};
    x[0] = sc_pick(i, s, nv_edges, 5, 0.0f, 1.0f);
    x[1] = sc_pick_log(i / 2, s, s_edges, 4, 0.5f, 2e5f);
    x[2] = sc_pick(i / 3, s, unit_edges, 2, 0.0f, 1.0f);
}

static void ref_ambient(const fixture *f, const float *x, float *y)
{
    y[0] = ibl_ambient_brdf_lookup(&f->probe.ambient_brdf, x[0], x[1], x[2]);
}

/* ---- BRDF pieces ----------------------------------------------------------------------- */

static void gen_two_unit(const fixture *f, int i, uint64_t *s, float *x)
{
    (void)f;
    static const float a_edges[] = {1e-3f, 1.0f, 0.02f};
    x[0] = sc_pick(i, s, a_edges, 3, 1e-3f, 1.0f);
    x[1] = sc_pick(i / 2, s, nv_edges, 5, -0.1f, 1.0f);
    x[2] = sc_pick(i / 3, s, nv_edges, 5, -0.1f, 1.0f);
}

static void ref_fresnel(const fixture *f, const float *x, float *y)
{
    (void)f;
    y[0] = ibl_fresnel_schlick(x[0], x[1]);
}

/* d = (n.h)^2 (a^2 - 1) + 1 cancels near n.h = 1 (and past it): its rounding error, an ulp
 * of max(1, (n.h)^2), is relative eps max(1, (n.h)^2) / |d| of d and doubled in D = a^2 /
 * (pi d^2); the GPU fuses the multiply-add, the C does not, so float D is only that good */
static double ggx_cancellation(const float *x)
{
    double a2 = (double)x[0] * x[0], nh2 = (double)x[1] * x[1];
    double d = nh2 * (a2 - 1.0) + 1.0;
    if (x[1] <= 0.0f || d == 0.0) return 0.0;
    return 8.0 * 1.1920929e-7 * fmax(1.0, nh2) / fabs(d) * (a2 / (3.14159265358979 * d * d));
}

static void ref_ggx_d(const fixture *f, const float *x, float *y)
{
    (void)f;
    y[0] = ibl_ggx_d(x[0], x[1]);
}

static void ref_smith(const fixture *f, const float *x, float *y)
{
    (void)f;
    y[0] = ibl_smith_ggx_v(x[0], x[1], x[2]);
}

static void gen_shininess(const fixture *f, int i, uint64_t *s, float *x)
{
    static const float edges[] = {0.0f, -1.0f, 1e6f, 1.0f, 100000.0f, 1e-3f};
    x[0] = sc_pick_log(i, s, edges, 6, 1e-4f, 2e6f);
    /* every 4th of the rest: exactly a level's shininess */
    if (i % 8 == 2) x[0] = f->probe.mapping.shininess[(i / 8) % f->probe.mapping.levels];
}

static void gen_roughness(const fixture *f, int i, uint64_t *s, float *x)
{
    static const float edges[] = {0.0f, 1.0f, -0.1f, 1.1f, 0.0376f, 0.03759f};
    x[0] = sc_pick(i, s, edges, 6, 0.0f, 1.0f);
    if (i % 8 == 2) x[0] = f->probe.mapping.roughness[(i / 8) % f->probe.mapping.levels];
}

static void ref_norm(const fixture *f, const float *x, float *y)
{
    (void)f;
    y[0] = ibl_blinn_phong_norm(x[0]);
}

static void ref_s_from_r(const fixture *f, const float *x, float *y)
{
    (void)f;
    y[0] = ibl_shininess_from_roughness(x[0]);
}

static void ref_r_from_s(const fixture *f, const float *x, float *y)
{
    (void)f;
    y[0] = ibl_roughness_from_shininess(x[0]);
}

/* ---- the probe ------------------------------------------------------------------------- */

static void ref_lod_r(const fixture *f, const float *x, float *y)
{
    y[0] = ibl_probe_lod_from_roughness(&f->probe, x[0]);
}

static void ref_lod_s(const fixture *f, const float *x, float *y)
{
    y[0] = ibl_probe_lod_from_shininess(&f->probe, x[0]);
}

static void gen_lod_dir(const fixture *f, int i, uint64_t *s, float *x)
{
    float last = (float)(f->probe.mapping.levels - 1);
    const float edges[] = {0.0f, -1.0f, -0.5f, 1.0f, last, last + 0.5f, -1.5f, 0.25f};
    x[0] = sc_pick(i, s, edges, 8, -1.2f, last + 0.2f);
    sc_gen_dir(i / 2, s, x + 1);
    float scale = 0.5f + 2.0f * sc_rnd(s); /* directions need not be unit */
    for (int k = 1; k < 4; k++) x[k] *= scale;
}

static void ref_sample_specular(const fixture *f, const float *x, float *y)
{
    ibl_probe_sample_specular(&f->probe, x[0], sc_v3(x + 1), y);
}

static void gen_kind_dir(const fixture *f, int i, uint64_t *s, float *x)
{
    (void)f;
    x[0] = (float)(1 + i % 2);
    sc_gen_dir(i / 2, s, x + 1);
    x[4] = (float)(i % 3); /* the probe's own kind for ibl_probe_irradiance: NONE reads the cube */
}

static void ref_sh9(const fixture *f, const float *x, float *y)
{
    ibl_sh9_eval_irradiance(f->probe.sh, (ibl_sh_kind)(int)x[0], sc_v3(x + 1), y);
}

static void ref_irradiance(const fixture *f, const float *x, float *y)
{
    ibl_probe p = f->probe;
    p.sh_kind = (ibl_sh_kind)(int)x[4];
    ibl_probe_irradiance(&p, sc_v3(x + 1), y);
}

/* ---- materials, occlusion, compositions ---------------------------------------------- */

static void gen_material_only(const fixture *f, int i, uint64_t *s, float *x)
{
    (void)f;
    sc_gen_material(i, s, x);
}

static void ref_lean(const fixture *f, const float *x, float *y)
{
    (void)f;
    ibl_material m = sc_material_of(x);
    y[0] = ibl_dominant_direction_lean(&m);
}

static void ref_constructors(const fixture *f, const float *x, float *y)
{
    (void)f;
    ibl_material m = x[0] == 1.0f ? ibl_material_blinn_phong(x + 1, x + 6, x[9])
                                  : ibl_material_gltf(x + 1, x[4], x[5]);
    y[0] = (float)m.model;
    for (int c = 0; c < 3; c++) {
        y[1 + c] = m.base_color[c];
        y[6 + c] = m.f0[c];
    }
    y[4] = m.metallic;
    y[5] = m.roughness;
    y[9] = m.shininess;
    y[10] = m.ao;
}

static void ref_reflectances(const fixture *f, const float *x, float *y)
{
    (void)f;
    ibl_material m = sc_material_of(x);
    ibl_material_reflectances(&m, y, y + 3);
}

static void ref_lookup_direction(const fixture *f, const float *x, float *y)
{
    (void)f;
    ibl_material m = sc_material_of(x);
    ibl_surface s = sc_surface_of(x + 11);
    ibl_shade_desc d = desc_of(x + 23);
    sc_put3(y, ibl_shade_lookup_direction(&d, &m, &s));
}

static void gen_so(const fixture *f, int i, uint64_t *s, float *x)
{
    (void)f;
    static const float r_edges[] = {0.0f, 1.0f, 0.1f, 0.5f};
    static const float s_edges[] = {0.0f, 10.0f, 100.0f, 1000.0f, 1e6f};
    x[0] = (float)(i % (IBL_SO_COUNT + 1)); /* and one unknown formula: SO = 1 */
    x[1] = sc_pick(i / 8, s, nv_edges, 5, -0.1f, 1.0f);
    x[2] = sc_pick(i / 8 + 1, s, unit_edges, 2, 0.0f, 1.0f);
    x[3] = sc_pick(i / 8 + 2, s, r_edges, 4, 0.0f, 1.0f);
    x[4] = sc_pick_log(i / 8 + 3, s, s_edges, 5, 1.0f, 1e5f);
}

/* The cone formula's smoothstep spans 2 spec (the specular cone's half-angle, 1e-3 rad for a
 * mirror): an angle error delta (GLSL's atan: ~3e-6 rad on llvmpipe; the C's asinf: 6e-8)
 * moves SO by up to 1.5 delta / (2 spec); delta = 2e-5 bounds it with room (atan near pi/2). */
static double cone_sensitivity(int formula, float roughness)
{
    if (formula != IBL_SO_CONE) return 0.0;
    float n = ibl_shininess_from_roughness(roughness);
    double spec = 2.0 * asin(sqrt(0.5 * -expm1(-0.69314718 / (n + 1.0))));
    return 1.5 * 2e-5 / (2.0 * fmax(spec, 1e-4));
}

static double so_tolerance(const float *x)
{
    return cone_sensitivity((int)x[0], x[3]);
}

/* in a shaded colour SO multiplies radiances of up to ~4 here */
static double shade_tolerance(const float *x)
{
    float r = x[0] == 1.0f ? ibl_roughness_from_shininess(x[9]) : fminf(fmaxf(x[5], 0.0f), 1.0f);
    return 4.0 * cone_sensitivity((int)x[24], r);
}

static void ref_so(const fixture *f, const float *x, float *y)
{
    (void)f;
    y[0] = ibl_specular_occlusion((ibl_so_formula)(int)x[0], x[1], x[2], x[3], x[4]);
}

static void gen_horizon(const fixture *f, int i, uint64_t *s, float *x)
{
    (void)f;
    static const float k_edges[] = {0.0f, -1.0f, 1.3f, 5.0f};
    sc_gen_dir(i, s, x);
    sc_gen_dir(i / 3, s, x + 3);
    x[6] = sc_pick(i / 2, s, k_edges, 4, 0.0f, 3.0f);
}

static void ref_horizon(const fixture *f, const float *x, float *y)
{
    (void)f;
    y[0] = ibl_horizon_occlusion(sc_v3(x), sc_v3(x + 3), x[6]);
}

static void gen_mix(const fixture *f, int i, uint64_t *s, float *x)
{
    (void)f;
    x[0] = (float)(i % (IBL_MIX_COUNT + 1));
    for (int k = 1; k < 13; k++) x[k] = 2.0f * sc_rnd(s);
    x[13] = sc_pick(i / 7, s, unit_edges, 2, 0.0f, 1.0f);
    x[14] = sc_pick(i / 7 + 1, s, unit_edges, 2, 0.0f, 1.0f);
}

static void ref_mix(const fixture *f, const float *x, float *y)
{
    (void)f;
    ibl_ambient_mix_apply((ibl_ambient_mix)(int)x[0], x + 1, x + 4, x + 7, x + 10, x[13], x[14], y);
}

/* ---- shading --------------------------------------------------------------------------- */

/* x: material [0, 11), surface [11, 23), desc [23, 32), lookup dir 32..34, weights 35, 36,
 * second lookup dir 37..39 */
static void gen_shade(const fixture *f, int i, uint64_t *s, float *x)
{
    (void)f;
    sc_gen_material(i, s, x);
    sc_gen_surface(i, s, x + 11);
    gen_desc(s, x + 23);
    sc_gen_dir(i / 2, s, x + 32);
    static const float w_edges[] = {0.0f, 1.0f, 0.5f};
    x[35] = sc_pick(i / 3, s, w_edges, 3, 0.0f, 1.0f);
    x[36] = sc_pick(i / 3 + 1, s, w_edges, 3, 0.0f, 1.0f);
    sc_gen_dir(i / 5, s, x + 37);
}

static void ref_shade(const fixture *f, const float *x, float *y)
{
    ibl_material m = sc_material_of(x);
    ibl_surface s = sc_surface_of(x + 11);
    ibl_shade_desc d = desc_of(x + 23);
    ibl_shade_result r;
    ibl_shade(&f->probe, &d, &m, &s, &r);
    put_result(y, &r);
}

static void ref_shade_dir(const fixture *f, const float *x, float *y)
{
    ibl_material m = sc_material_of(x);
    ibl_surface s = sc_surface_of(x + 11);
    ibl_shade_desc d = desc_of(x + 23);
    ibl_shade_result r;
    ibl_shade_dir(&f->probe, &d, &m, &s, sc_v3(x + 32), &r);
    put_result(y, &r);
}

static void ref_shade_blend(const fixture *f, const float *x, float *y)
{
    ibl_material m = sc_material_of(x);
    ibl_surface s = sc_surface_of(x + 11);
    ibl_shade_desc d = desc_of(x + 23);
    const ibl_probe *probes[2] = {&f->probe, &f->probe};
    const float w[2] = {x[35], x[36]};
    const ibl_vec3 dirs[2] = {sc_v3(x + 32), sc_v3(x + 37)};
    ibl_shade_result r;
    ibl_shade_blend(probes, w, 2, dirs, &d, &m, &s, &r);
    put_result(y, &r);
}

/* ---- local probes ---------------------------------------------------------------------- */

/* x: count, order[4], 4 volumes, p, probe position, r */
static void gen_volumes(const fixture *f, int i, uint64_t *s, float *x)
{
    (void)f;
    ibl_volume v[4];
    int order[4];
    x[0] = (float)(i % 5);
    for (int k = 0; k < 4; k++) {
        gen_volume(s, x + 5 + 9 * k);
        v[k] = volume_of(x + 5 + 9 * k);
    }
    ibl_volume_sort(v, 4, order);
    for (int k = 0; k < 4; k++) x[1 + k] = (float)order[k];
    for (int k = 41; k < 47; k++) x[k] = 3.0f * sc_rnd(s) - 1.5f;
    if (i % 7 == 0) { /* a point on a volume's surface, and the capture point itself */
        ibl_volume a = v[0];
        x[41] = a.center.x + (a.shape == IBL_VOLUME_BOX ? a.half_extent.x : a.radius);
        x[42] = a.center.y;
        x[43] = a.center.z;
    }
    if (i % 11 == 0)
        for (int k = 0; k < 3; k++) x[44 + k] = x[41 + k];
    sc_gen_dir(i / 2, s, x + 47);
}

static void ref_volume_size(const fixture *f, const float *x, float *y)
{
    (void)f;
    ibl_volume v = volume_of(x + 5);
    y[0] = ibl_volume_size(&v);
}

static void ref_volume_weight(const fixture *f, const float *x, float *y)
{
    (void)f;
    ibl_volume v = volume_of(x + 5);
    y[0] = ibl_volume_weight(&v, sc_v3(x + 41));
}

static void ref_volume_blend(const fixture *f, const float *x, float *y)
{
    (void)f;
    memset(y, 0, 4 * sizeof(float)); /* the C writes only the first `count` weights */
    ibl_volume v[4];
    int order[4];
    for (int k = 0; k < 4; k++) {
        v[k] = volume_of(x + 5 + 9 * k);
        order[k] = (int)x[1 + k];
    }
    y[4] = ibl_volume_blend(v, order, (int)x[0], sc_v3(x + 41), y);
}

static void ref_parallax(const fixture *f, const float *x, float *y)
{
    (void)f;
    ibl_volume v = volume_of(x + 5);
    sc_put3(y, ibl_parallax_correct(&v, sc_v3(x + 44), sc_v3(x + 41), sc_v3(x + 47)));
}

static void gen_offset(const fixture *f, int i, uint64_t *s, float *x)
{
    (void)f;
    sc_gen_dir(i, s, x);
    for (int k = 3; k < 9; k++) x[k] = 4.0f * sc_rnd(s) - 2.0f;
    static const float c_edges[] = {0.0f, 1.0f, -0.2f};
    x[9] = sc_pick(i / 2, s, c_edges, 3, -0.5f, 0.5f);
}

static void ref_offset(const fixture *f, const float *x, float *y)
{
    (void)f;
    sc_put3(y, ibl_offset_reflection(sc_v3(x), sc_v3(x + 3), sc_v3(x + 6), x[9]));
}

static void gen_three(const fixture *f, int i, uint64_t *s, float *x)
{
    (void)f;
    static const float size_edges[] = {0.0f, -1.0f, 60.0f, 1.0f};
    x[0] = sc_pick_log(i, s, NULL, 0, 1.0f, 1e5f);
    x[1] = sc_pick(i, s, size_edges, 4, 0.1f, 200.0f);
    x[2] = sc_pick(i / 2, s, unit_edges, 2, -0.5f, 1.5f);
}

static void ref_hack(const fixture *f, const float *x, float *y)
{
    (void)f;
    y[0] = ibl_shininess_hack(x[0], x[1], x[2]);
}

static void ref_offset_coefficient(const fixture *f, const float *x, float *y)
{
    (void)f;
    y[0] = ibl_offset_coefficient(x[1] - 20.0f, x[2]);
}

static void ref_switch(const fixture *f, const float *x, float *y)
{
    (void)f;
    y[0] = ibl_environment_switch(x[2] * 10.0f, x[0] * 1e-4f, x[1] * 0.05f - 2.0f);
}

/* ---- atlas, warp, cube geometry ------------------------------------------------------- */

static void gen_level_dir(const fixture *f, int i, uint64_t *s, float *x)
{
    int levels = f->atlas_layout.levels;
    x[0] = (float)(i % levels);
    sc_gen_dir(i / levels, s, x + 1);
    static const int ns[] = {1, 2, 3, 4, 8, 32, 256};
    x[4] = (float)ns[i % 7];
    const float edges[] = {0.0f, 0.5f, (float)(levels - 1), (float)levels};
    x[5] = sc_pick(i / 3, s, edges, 4, -0.3f, (float)levels - 0.7f);
    x[6] = (float)(i % 6);
    x[7] = sc_pick(i / 6, s, unit_edges, 2, 0.0f, 1.0f);
    x[8] = sc_pick(i / 12, s, unit_edges, 2, 0.0f, 1.0f);
}

static void ref_atlas_uv(const fixture *f, const float *x, float *y)
{
    ibl_atlas_uv(&f->atlas_layout, (int)x[0], sc_v3(x + 1), &y[0], &y[1]);
}

static void ref_atlas_sample(const fixture *f, const float *x, float *y)
{
    ibl_atlas_sample(&f->atlas, &f->atlas_layout, x[5], sc_v3(x + 1), y);
}

static void ref_warp(const fixture *f, const float *x, float *y)
{
    (void)f;
    sc_put3(y, ibl_edge_fixup_warp_lookup(sc_v3(x + 1), (int)x[4]));
}

static void ref_face_st(const fixture *f, const float *x, float *y)
{
    (void)f;
    y[0] = (float)ibl_cube_face_st(sc_v3(x + 1), &y[1], &y[2]);
}

static void ref_cube_direction(const fixture *f, const float *x, float *y)
{
    (void)f;
    sc_put3(y, ibl_cube_direction((int)x[6], x[7], x[8]));
}

/* ---- the table --------------------------------------------------------------------------- */

#define SHADE_CALL(fn, extra)                                                                  \
    "Yr(0, " fn "(probe, u_specular, u_mirror, u_irradiance, u_splitsum, u_ambient, D(23), "  \
    "M(0), S(11)" extra "));"

/* Texture reads: llvmpipe filters in float (measured: 1e-7 against the C's bilinear, at cube
 * edges and corners too, where its seamless filter also takes the mean of the three texels);
 * hardware rounds the sub-texel weight to 8 bits (the Direct3D and Vulkan minimum), which
 * would move a bilinear result by up to a texel-to-texel step / 512: these bounds hold for
 * llvmpipe only, and the full-frame bounds below are the ones an engine can expect. */
#define FILTER_TABLE 1e-5, 1e-5
#define FILTER_CUBE 1e-5, 1e-5
#define FILTER_SHADE 1e-5, 1e-4

const shader_case shader_cases[] = {
    {"ibl_table_axis_value", 6, 1,
     "Y(0, ibl_table_axis_value(ibl_table_axis(I(0), X(1), X(2), I(3)), I(4)));", gen_axis,
     ref_axis_value, TRANSC, "exp/log of a log axis", NULL},
    {"ibl_table_axis_index", 6, 1,
     "Y(0, ibl_table_axis_index(ibl_table_axis(I(0), X(1), X(2), I(3)), X(5)));", gen_axis,
     ref_axis_index, 1e-4, 1e-5, "log of a log axis, times count - 1 (<= 63)", NULL},
    {"ibl_splitsum_lookup", 2, 2,
     "float a, b; ibl_splitsum_lookup(u_splitsum, probe, X(0), X(1), a, b); Y(0, a); Y(1, b);",
     gen_splitsum, ref_splitsum, FILTER_TABLE, "bilinear in float (llvmpipe)", NULL},
    {"ibl_ambient_brdf_lookup", 3, 1,
     "Y(0, ibl_ambient_brdf_lookup(u_ambient, probe, X(0), X(1), X(2)));", gen_ambient,
     ref_ambient, FILTER_TABLE, "trilinear in float (llvmpipe)", NULL},
    {"ibl_fresnel_schlick", 3, 1, "Y(0, ibl_fresnel_schlick(X(0), X(1)));", gen_two_unit,
     ref_fresnel, ARITH, "arithmetic", NULL},
    {"ibl_ggx_d", 3, 1, "Y(0, ibl_ggx_d(X(0), X(1)));", gen_two_unit, ref_ggx_d, ARITH,
     "arithmetic; + 8 eps / |d| D: d cancels at n.h = 1", ggx_cancellation},
    {"ibl_smith_ggx_v", 3, 1, "Y(0, ibl_smith_ggx_v(X(0), X(1), X(2)));", gen_two_unit,
     ref_smith, ARITH, "arithmetic, sqrt", NULL},
    {"ibl_blinn_phong_norm", 1, 1, "Y(0, ibl_blinn_phong_norm(X(0)));", gen_shininess,
     ref_norm, ARITH, "arithmetic", NULL},
    {"ibl_shininess_from_roughness", 1, 1, "Y(0, ibl_shininess_from_roughness(X(0)));",
     gen_roughness, ref_s_from_r, ARITH, "arithmetic", NULL},
    {"ibl_roughness_from_shininess", 1, 1, "Y(0, ibl_roughness_from_shininess(X(0)));",
     gen_shininess, ref_r_from_s, ARITH, "arithmetic, sqrt", NULL},
    {"ibl_probe_lod_from_roughness", 1, 1, "Y(0, ibl_probe_lod_from_roughness(probe, X(0)));",
     gen_roughness, ref_lod_r, ARITH, "arithmetic", NULL},
    {"ibl_probe_lod_from_shininess", 1, 1, "Y(0, ibl_probe_lod_from_shininess(probe, X(0)));",
     gen_shininess, ref_lod_s, TRANSC, "log2 of the shininess", NULL},
    {"ibl_probe_sample_specular", 4, 3,
     "Y3(0, ibl_probe_sample_specular(probe, u_specular, u_mirror, X(0), V(1)));", gen_lod_dir,
     ref_sample_specular, FILTER_CUBE, "seamless trilinear, corners too", NULL},
    {"ibl_sh9_eval_irradiance", 5, 3, "Y3(0, ibl_sh9_eval_irradiance(probe.sh, I(0), V(1)));",
     gen_kind_dir, ref_sh9, ARITH, "arithmetic", NULL},
    {"ibl_probe_irradiance", 5, 3,
     "ibl_probe p = probe; p.sh_kind = I(4); Y3(0, ibl_probe_irradiance(p, u_irradiance, V(1)));",
     gen_kind_dir, ref_irradiance, FILTER_CUBE, "SH arithmetic or a bilinear cube read", NULL},
    {"ibl_dominant_direction_lean", 11, 1, "Y(0, ibl_dominant_direction_lean(M(0)));",
     gen_material_only, ref_lean, TRANSC, "pow(s, 0.9805)", NULL},
    {"ibl_material_gltf/blinn_phong", 11, 11,
     "ibl_material m = I(0) == 1 ? ibl_material_blinn_phong(V(1), V(6), X(9))\n"
     "    : ibl_material_gltf(V(1), X(4), X(5));\n"
     "  Y(0, float(m.model)); Y3(1, m.base_color); Y(4, m.metallic); Y(5, m.roughness);\n"
     "  Y3(6, m.f0); Y(9, m.shininess); Y(10, m.ao);",
     gen_material_only, ref_constructors, 0.0, 0.0, "copies", NULL},
    {"ibl_material_reflectances", 11, 6,
     "vec3 f0, albedo; ibl_material_reflectances(M(0), f0, albedo); Y3(0, f0); Y3(3, albedo);",
     gen_material_only, ref_reflectances, ARITH, "arithmetic", NULL},
    {"ibl_shade_lookup_direction", 40, 3,
     "Y3(0, ibl_shade_lookup_direction(D(23), M(0), S(11)));", gen_shade, ref_lookup_direction,
     TRANSC, "the lean's pow, a normalisation", NULL},
    {"ibl_specular_occlusion", 5, 1,
     "Y(0, ibl_specular_occlusion(I(0), X(1), X(2), X(3), X(4)));", gen_so, ref_so, 1e-5, 1e-5,
     "pow; + the cone's angle error / its width", so_tolerance},
    {"ibl_horizon_occlusion", 7, 1, "Y(0, ibl_horizon_occlusion(V(0), V(3), X(6)));",
     gen_horizon, ref_horizon, ARITH, "arithmetic", NULL},
    {"ibl_ambient_mix_apply", 15, 3,
     "Y3(0, ibl_ambient_mix_apply(I(0), V(1), V(4), V(7), V(10), X(13), X(14)));", gen_mix,
     ref_mix, ARITH, "arithmetic", NULL},
    {"ibl_shade", 40, 14, SHADE_CALL("ibl_shade", ""), gen_shade, ref_shade, FILTER_SHADE,
     "cube, table reads; + cone SO as above", shade_tolerance},
    {"ibl_shade_dir", 40, 14, SHADE_CALL("ibl_shade_dir", ", normalize(V(32))"), gen_shade,
     ref_shade_dir, FILTER_SHADE, "cube, table reads; + cone SO as above", shade_tolerance},
    {"ibl_shade_blend (blend_add)", 40, 14,
     "ibl_shade_result acc = ibl_shade_result(vec3(0.0), vec3(0.0), vec3(0.0), 0.0, 0.0,\n"
     "      vec3(0.0)); float h = -1.0;\n"
     "  ibl_shade_blend_add(acc, h, X(35), ibl_shade_dir(probe, u_specular, u_mirror,\n"
     "      u_irradiance, u_splitsum, u_ambient, D(23), M(0), S(11), V(32)));\n"
     "  ibl_shade_blend_add(acc, h, X(36), ibl_shade_dir(probe, u_specular, u_mirror,\n"
     "      u_irradiance, u_splitsum, u_ambient, D(23), M(0), S(11), V(37)));\n"
     "  Yr(0, acc);",
     gen_shade, ref_shade_blend, FILTER_SHADE, "cube, table reads; + cone SO as above", shade_tolerance},
    {"ibl_volume_size", 50, 1, "Y(0, ibl_volume_size(VOL(5)));", gen_volumes, ref_volume_size,
     ARITH, "arithmetic", NULL},
    {"ibl_volume_weight", 50, 1, "Y(0, ibl_volume_weight(VOL(5), V(41)));", gen_volumes,
     ref_volume_weight, ARITH, "arithmetic, sqrt", NULL},
    {"ibl_volume_blend", 50, 5,
     "ibl_volume v[IBL_MAX_VOLUMES]; int o[IBL_MAX_VOLUMES]; float w[IBL_MAX_VOLUMES];\n"
     "  for (int k = 0; k < IBL_MAX_VOLUMES; k++) { v[k] = VOL(5 + 9 * min(k, 3));\n"
     "    o[k] = k < 4 ? I(1 + k) : 0; }\n"
     "  float rest = ibl_volume_blend(v, o, I(0), V(41), w);\n"
     "  for (int k = 0; k < 4; k++) Y(k, w[k]);\n"
     "  Y(4, rest);",
     gen_volumes, ref_volume_blend, 1e-5, 1e-5, "1 - (sum before) cancels as the sum nears 1", NULL},
    {"ibl_parallax_correct", 50, 3, "Y3(0, ibl_parallax_correct(VOL(5), V(44), V(41), V(47)));",
     gen_volumes, ref_parallax, 2e-5, 1e-4, "a division by a small ray component", NULL},
    {"ibl_offset_reflection", 10, 3, "Y3(0, ibl_offset_reflection(V(0), V(3), V(6), X(9)));",
     gen_offset, ref_offset, ARITH, "arithmetic", NULL},
    {"ibl_shininess_hack", 3, 1, "Y(0, ibl_shininess_hack(X(0), X(1), X(2)));", gen_three,
     ref_hack, ARITH, "arithmetic", NULL},
    {"ibl_offset_coefficient", 3, 1, "Y(0, ibl_offset_coefficient(X(1) - 20.0, X(2)));",
     gen_three, ref_offset_coefficient, ARITH, "a division", NULL},
    {"ibl_environment_switch", 3, 1,
     "Y(0, ibl_environment_switch(X(2) * 10.0, X(0) * 1e-4, X(1) * 0.05 - 2.0));", gen_three,
     ref_switch, ARITH, "arithmetic", NULL},
    {"ibl_atlas_uv", 9, 2, "float u, v; ibl_atlas_uv(atlas_layout, I(0), V(1), u, v); Y(0, u); Y(1, v);",
     gen_level_dir, ref_atlas_uv, ARITH, "arithmetic", NULL},
    {"ibl_atlas_sample", 9, 4, "vec4 c = ibl_atlas_sample(u_atlas, atlas_layout, X(5), V(1));\n"
     "  Y3(0, c.rgb); Y(3, c.a);",
     gen_level_dir, ref_atlas_sample, FILTER_TABLE, "bilinear in float (llvmpipe)", NULL},
    {"ibl_edge_fixup_warp_lookup", 9, 3, "Y3(0, ibl_edge_fixup_warp_lookup(V(1), I(4)));",
     gen_level_dir, ref_warp, 2e-6, 2e-5, "float sinh/asinh against the C's double", NULL},
    {"ibl_cube_face_st", 9, 3, "float s, t; Y(0, float(ibl_cube_face_st(V(1), s, t))); Y(1, s); Y(2, t);",
     gen_level_dir, ref_face_st, ARITH, "arithmetic", NULL},
    {"ibl_cube_direction", 9, 3, "Y3(0, ibl_cube_direction(I(6), X(7), X(8)));", gen_level_dir,
     ref_cube_direction, ARITH, "arithmetic", NULL},
};

const int shader_case_count = (int)(sizeof shader_cases / sizeof shader_cases[0]);
