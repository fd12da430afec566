/* The punctual lights of shaders/ibl.glsl (include/ibl/light.h's runtime) against the C, case
 * by case as in shader_cases.c: the three falloffs, Karis' sphere alpha, the incidence of
 * directional, point and spot lights, one light on both material models (the shininess hack
 * and the widened alpha, light_size widen and ignore), and several lights summed with and
 * without visibility.
 *
 * Inputs: edge cases every 4th sample (a point at the light itself, at its range, at the
 * 1e-4 distance floor; no range; cones with inner = outer - 1e-4 and the default outer; zero
 * colour and intensity, the glTF defaults; zero size; grazing n.v and n.l from gen_surface).
 *
 * Tolerances: the ARITH bound of shader_cases.c (1e-6 + 1e-5 |c|) plus, per sample, what
 * float conditioning allows two correct float evaluations to differ by (computed from the
 * input by the C):
 *  - cone falloff: the GPU's cos (llvmpipe ~1e-7 absolute) moves t = (cos - cos_o) / width by
 *    ~2e-7 / width (width >= 1e-3 by the clamp), t^2 by twice that;
 *  - the range window 1 - (d/r)^4 cancels near d = r: 4 ulps of 1, divided by d^2 in the
 *    falloff;
 *  - the half vector: n.h is rounded by ~4 ulps (normalize, dot, fused multiply-adds); the
 *    Blinn-Phong lobe (n.h)^s moves by s / (n.h) times that, relatively (s to 1e5 and more),
 *    GGX's D by 4 (n.h)(1 - a^2) / d times it near its peak (d = (n.h)^2 (a^2 - 1) + 1,
 *    which also cancels: ggx_cancellation of shader_cases.c). */
#include "shader_test.h"

#include <math.h>
#include <string.h>

#define EPS 1.1920929e-7
#define ARITH 1e-6, 1e-5

/* ---- inputs ---------------------------------------------------------------------------- */

/* x[0..14]: type, colour[3], intensity, position[3], direction[3], range, inner, outer, size
 * (the GLSL's L(k)); p[3] is the point the light is evaluated at (to aim spots and ranges). */
static void gen_light(int i, uint64_t *s, const float *p, float *x)
{
    static const float unit_edges[] = {0.0f, 1.0f};
    x[0] = (float)(i % 3);
    int white = sc_rnd(s) < 0.2f;
    for (int k = 1; k < 4; k++) x[k] = white ? 0.0f : 2.0f * sc_rnd(s);
    x[4] = sc_rnd(s) < 0.2f ? 0.0f : sc_pick_log(i / 3, s, unit_edges + 1, 1, 0.1f, 1000.0f);
    float d[3];
    sc_gen_dir(i / 3, s, d);
    float dist = sc_pick_log(i / 3 + 1, s, NULL, 0, 0.05f, 5.0f);
    int at = i % 97 == 0, floor_ = i % 89 == 0;
    if (floor_) dist = 5e-5f;
    for (int k = 0; k < 3; k++) x[5 + k] = at ? p[k] : p[k] + dist * d[k];
    /* the direction of travel: toward p (with a spread) for spots, any for directionals */
    float a[3];
    sc_gen_dir(i / 3 + 2, s, a);
    float spread = 0.6f * sc_rnd(s), scale = 0.5f + 2.0f * sc_rnd(s);
    for (int k = 0; k < 3; k++) x[8 + k] = scale * ((x[0] == 2.0f ? -d[k] : a[k]) + spread * a[k]);
    float r = sc_rnd(s);
    x[11] = r < 0.3f ? 0.0f : r < 0.4f ? dist : dist * (0.5f + 3.0f * sc_rnd(s));
    float inner = 1.2f * sc_rnd(s), outer = inner + (1.5707963f - inner) * sc_rnd(s) + 1e-4f;
    int kind = sc_pick_int(s, 5);
    if (kind == 0) outer = 0.0f, inner = 0.5f * sc_rnd(s);          /* default outer pi/4 */
    if (kind == 1) inner = 0.0f;                                    /* glTF's default inner */
    if (kind == 2) inner = fmaxf(outer - 1e-4f, 0.0f);              /* a hard edge */
    x[12] = inner;
    x[13] = fminf(outer, 1.5707963f);
    float sz = sc_rnd(s);
    x[14] = sz < 0.4f ? 0.0f : x[0] == 0.0f ? 0.05f * sc_rnd(s) : sc_pick_log(i, s, NULL, 0, 1e-3f, 2.0f);
}

static ibl_light light_of(const float *x)
{
    ibl_light l;
    memset(&l, 0, sizeof l);
    l.type = (ibl_light_type)(int)x[0];
    for (int c = 0; c < 3; c++) l.color[c] = x[1 + c];
    l.intensity = x[4];
    l.position = sc_v3(x + 5);
    l.direction = sc_v3(x + 8);
    l.range = x[11];
    l.inner_cone = x[12];
    l.outer_cone = x[13];
    l.size = x[14];
    return l;
}

/* material [0, 11), surface [11, 23), point [23, 26), light_size 26, lights from 27 (15 each),
 * visibility after NL lights */
enum { P = 23, LSIZE = 26, LIGHTS = 27, NL = 3, VIS = LIGHTS + 15 * NL, N_IN = VIS + NL };

static void gen_shade_case(const fixture *f, int i, uint64_t *s, float *x)
{
    (void)f;
    sc_gen_material(i, s, x);
    sc_gen_surface(i, s, x + 11);
    for (int k = 0; k < 3; k++) x[P + k] = 2.0f * sc_rnd(s) - 1.0f;
    x[LSIZE] = (float)(sc_rnd(s) < 0.25f);
    for (int k = 0; k < NL; k++) gen_light(i + k, s, x + P, x + LIGHTS + 15 * k);
    static const float vis_edges[] = {0.0f, 1.0f, -0.5f};
    for (int k = 0; k < NL; k++) x[VIS + k] = sc_pick(i / 2 + k, s, vis_edges, 3, 0.0f, 1.0f);
}

static ibl_shade_desc desc_of(const float *x)
{
    ibl_shade_desc d;
    memset(&d, 0, sizeof d);
    d.light_size = (ibl_light_size_model)(int)x[LSIZE];
    return d;
}

static void put_result(float *y, const ibl_light_result *r)
{
    for (int c = 0; c < 3; c++) {
        y[c] = r->diffuse[c];
        y[3 + c] = r->specular[c];
    }
    y[6] = r->n_dot_l;
    y[7] = r->shininess;
    y[8] = r->alpha;
}

/* ---- slack from float conditioning ---------------------------------------------------- */

static double max3(const float *v) { return fmax(fabs(v[0]), fmax(fabs(v[1]), fabs(v[2]))); }

static double cone_slack(float cos_angle, float inner, float outer)
{
    (void)cos_angle;
    double width = fmax(1e-3, cos((double)inner) - cos((double)outer));
    return 2.0 * 4e-7 / width;
}

/* absolute slack of a light's illuminance at p: the range window's cancellation (4 ulps of
 * 1, over d^2) and the cone's edge (t moved by dt = 4e-7 / width: t^2 by 2 t dt + dt^2) */
static double incidence_slack(const ibl_light *l, ibl_vec3 p)
{
    if (l->type == IBL_LIGHT_DIRECTIONAL) return 0.0;
    ibl_vec3 t = {l->position.x - p.x, l->position.y - p.y, l->position.z - p.z};
    double d = sqrt((double)t.x * t.x + (double)t.y * t.y + (double)t.z * t.z);
    if (!(d > 0.0)) return 0.0;
    int white = l->color[0] == 0.0f && l->color[1] == 0.0f && l->color[2] == 0.0f;
    double e0 = (white ? 1.0 : max3(l->color)) * (l->intensity > 0.0f ? l->intensity : 1.0);
    double dd = fmax(d, 1e-4), falloff = ibl_light_distance_falloff((float)d, l->range);
    double cone = 1.0, cone_slack_abs = 0.0;
    if (l->type == IBL_LIGHT_SPOT) {
        float outer = l->outer_cone > 0.0f ? l->outer_cone : 0.78539816f;
        ibl_vec3 axis = l->direction;
        double len = sqrt((double)axis.x * axis.x + (double)axis.y * axis.y + (double)axis.z * axis.z);
        double c = -((double)axis.x * t.x + (double)axis.y * t.y + (double)axis.z * t.z) / (len * d);
        cone = ibl_light_cone_falloff((float)c, l->inner_cone, outer);
        double dt = cone_slack(0.0f, l->inner_cone, outer) / 2.0;
        cone_slack_abs = 2.0 * sqrt(cone) * dt + dt * dt;
    }
    double window = l->range > 0.0f ? 8.0 * EPS / (dd * dd) : 0.0;
    return e0 * (window * cone + falloff * cone_slack_abs);
}

/* the lobe's n.h dependence: (n.h)^s or GGX's D(alpha', n.h) */
static double lobe_of(const ibl_material *m, const ibl_light_result *r, double nh)
{
    if (nh <= 0.0) return 0.0;
    if (m->model == IBL_MATERIAL_BLINN_PHONG) return pow(fmin(nh, 1.0), r->shininess);
    double a2 = (double)r->alpha * r->alpha, d = nh * nh * (a2 - 1.0) + 1.0;
    return a2 / (d * d);
}

/* relative slack of one light's specular from n.h's rounding: the lobe's largest relative
 * change for n.h moved by 8 ulps (not its derivative: a near-mirror GGX lobe is as narrow
 * as that), and for GGX the cancellation of d in float (ggx_cancellation in shader_cases.c) */
static double lobe_slack(const ibl_material *m, const ibl_light_result *r, const ibl_surface *s,
                         ibl_vec3 l)
{
    ibl_vec3 h = {s->v.x + l.x, s->v.y + l.y, s->v.z + l.z};
    double len = sqrt((double)h.x * h.x + (double)h.y * h.y + (double)h.z * h.z);
    if (len <= 0.0) return 0.0;
    double nh = ((double)s->n.x * h.x + (double)s->n.y * h.y + (double)s->n.z * h.z) / len;
    double f = lobe_of(m, r, nh), worst = 0.0;
    if (!(f > 0.0)) return 0.0;
    for (int k = -8; k <= 8; k++) {
        double g = lobe_of(m, r, nh + k * EPS);
        worst = fmax(worst, fabs(g - f) / f);
    }
    if (m->model == IBL_MATERIAL_BLINN_PHONG) return worst;
    double a2 = (double)r->alpha * r->alpha, d = nh * nh * (a2 - 1.0) + 1.0;
    return worst + 8.0 * EPS * fmax(1.0, nh * nh) / d;
}

/* absolute slack from n.l's rounding (~8 ulps: l = (position - p) / d, a dot product): the
 * result is E n.l times the lobe and the albedo, and near n.l = 0 (a light along the
 * horizon; the tests' edge directions make it exactly 0 in exact arithmetic) n.l has no
 * correct digits left, nor its sign (then one side returns 0). The lobe is bounded at n.l
 * -> 0 (Blinn-Phong divides by max(n.l, n.v), GGX's V -> 0.5 / (n.v alpha)). */
static double nl_slack(const ibl_material *m, const ibl_light_result *r, const ibl_surface *s,
                       const ibl_light_incidence *in)
{
    double nl = fabs((double)s->n.x * in->l.x + (double)s->n.y * in->l.y + (double)s->n.z * in->l.z);
    double nv = fmax((double)s->n.x * s->v.x + (double)s->n.y * s->v.y + (double)s->n.z * s->v.z, 1e-4);
    ibl_vec3 h = {s->v.x + in->l.x, s->v.y + in->l.y, s->v.z + in->l.z};
    double len = sqrt((double)h.x * h.x + (double)h.y * h.y + (double)h.z * h.z);
    double nh = len > 0.0 ? ((double)s->n.x * h.x + (double)s->n.y * h.y + (double)s->n.z * h.z) / len : 0.0;
    nh = fmax(nh, 0.0);
    float f0[3], albedo[3];
    ibl_material_reflectances(m, f0, albedo);
    double lobe;
    if (m->model == IBL_MATERIAL_BLINN_PHONG) {
        lobe = ibl_blinn_phong_norm(r->shininess) * pow(nh, r->shininess) / fmax(nl, nv);
    } else {
        float alpha = fmaxf(m->roughness * m->roughness, 1e-3f);
        float a = r->alpha > 0.0f ? r->alpha : alpha;
        lobe = ibl_ggx_d(a, (float)nh) * ibl_smith_ggx_v(alpha, (float)nv, (float)fmax(nl, 1e-7));
    }
    return (lobe + max3(albedo) / 3.14159265) * max3(in->illuminance) * 8.0 * EPS;
}

/* the slack of lights [first, first + count) summed at the sample's point: the lobe's
 * relative slack on the specular, the illuminance's absolute slack through the BRDF (the C
 * result for a unit illuminance) */
static double lights_slack(const float *x, int first, int count, int use_visibility)
{
    ibl_material m = sc_material_of(x);
    ibl_surface s = sc_surface_of(x + 11);
    ibl_shade_desc d = desc_of(x);
    double slack = 0.0;
    for (int k = first; k < first + count; k++) {
        ibl_light l = light_of(x + LIGHTS + 15 * k);
        ibl_light_incidence in;
        ibl_light_incidence_at(&l, sc_v3(x + P), &in);
        /* several lights: n_dot_l, shininess and alpha are the last lit light's, and which
         * one that is has no answer in float when one has n.l ~ 0 */
        double nl = (double)s.n.x * in.l.x + (double)s.n.y * in.l.y + (double)s.n.z * in.l.z;
        if (count > 1 && fabs(nl) < 1e-5) slack += fmax(1.0, m.shininess);
        ibl_light_result r, unit;
        ibl_light_shade_incidence(&in, &d, &m, &s, &r);
        ibl_light_incidence unit_in = in;
        for (int c = 0; c < 3; c++) unit_in.illuminance[c] = 1.0f;
        ibl_light_shade_incidence(&unit_in, &d, &m, &s, &unit);
        double vis = use_visibility ? fmax(x[VIS + k], 0.0) : 1.0;
        slack += vis * (max3(r.specular) * lobe_slack(&m, &r, &s, in.l) + nl_slack(&m, &r, &s, &in) +
                        (max3(unit.specular) + max3(unit.diffuse)) *
                            incidence_slack(&l, sc_v3(x + P)));
    }
    return slack;
}

static double one_light_slack(const float *x) { return lights_slack(x, 0, 1, 0); }
static double visible_lights_slack(const float *x) { return lights_slack(x, 0, NL, 1); }
static double all_lights_slack(const float *x) { return lights_slack(x, 0, NL, 0); }

/* ---- the falloffs ---------------------------------------------------------------------- */

static void gen_falloff(const fixture *f, int i, uint64_t *s, float *x)
{
    (void)f;
    static const float d_edges[] = {0.0f, 1e-5f, 1e-4f, 1.0f, 2.0f};
    x[0] = sc_pick(i, s, d_edges, 5, 0.0f, 4.0f);
    float r = sc_rnd(s);
    x[1] = r < 0.2f ? 0.0f : r < 0.3f ? x[0] : 0.1f + 4.0f * sc_rnd(s);
    float inner = 1.4f * sc_rnd(s), outer = inner + (1.5707963f - inner) * sc_rnd(s);
    if (i % 8 == 1) inner = outer - 1e-4f;
    x[3] = inner;
    x[4] = outer;
    x[2] = cosf(inner + (outer - inner) * (1.4f * sc_rnd(s) - 0.2f)); /* across the edge */
    if (i % 8 == 3) x[2] = cosf(outer);
    x[5] = sc_pick(i / 2, s, d_edges + 2, 2, 1e-3f, 1.0f); /* alpha */
    x[6] = sc_rnd(s) < 0.2f ? 0.0f : 2.0f * sc_rnd(s);     /* radius */
}

static void ref_window(const fixture *f, const float *x, float *y)
{
    (void)f;
    y[0] = ibl_light_range_window(x[0], x[1]);
}

static double window_slack(const float *x)
{
    return 8.0 * EPS / fmax((double)x[0] * x[0], 1e-8);
}

static void ref_falloff(const fixture *f, const float *x, float *y)
{
    (void)f;
    y[0] = ibl_light_distance_falloff(x[0], x[1]);
}

static void ref_cone(const fixture *f, const float *x, float *y)
{
    (void)f;
    y[0] = ibl_light_cone_falloff(x[2], x[3], x[4]);
}

static double cone_case_slack(const float *x) { return cone_slack(x[2], x[3], x[4]); }

static void ref_sphere_alpha(const fixture *f, const float *x, float *y)
{
    (void)f;
    y[0] = ibl_ggx_sphere_alpha(x[5], x[6], x[0]);
}

/* ---- incidence and shading ------------------------------------------------------------- */

static void ref_incidence(const fixture *f, const float *x, float *y)
{
    (void)f;
    ibl_light l = light_of(x + LIGHTS);
    ibl_light_incidence in;
    ibl_light_incidence_at(&l, sc_v3(x + P), &in);
    sc_put3(y, in.l);
    y[3] = isinf(in.distance) ? 3.402823466e38f : in.distance; /* the GLSL's IBL_FLT_MAX */
    for (int c = 0; c < 3; c++) y[4 + c] = in.illuminance[c];
    y[7] = in.size;
    y[8] = in.attenuation;
}

static double incidence_case_slack(const float *x)
{
    ibl_light l = light_of(x + LIGHTS);
    return incidence_slack(&l, sc_v3(x + P));
}

static void ref_shade_incidence(const fixture *f, const float *x, float *y)
{
    (void)f;
    ibl_material m = sc_material_of(x);
    ibl_surface s = sc_surface_of(x + 11);
    ibl_shade_desc d = desc_of(x);
    ibl_light l = light_of(x + LIGHTS);
    ibl_light_incidence in;
    ibl_light_incidence_at(&l, sc_v3(x + P), &in);
    ibl_light_result r;
    ibl_light_shade_incidence(&in, &d, &m, &s, &r);
    put_result(y, &r);
}

static void ref_light_shade(const fixture *f, const float *x, float *y)
{
    (void)f;
    ibl_material m = sc_material_of(x);
    ibl_surface s = sc_surface_of(x + 11);
    ibl_shade_desc d = desc_of(x);
    ibl_light l = light_of(x + LIGHTS);
    ibl_light_result r;
    ibl_light_shade(&l, &d, &m, &s, sc_v3(x + P), &r);
    put_result(y, &r);
}

static void ref_lights_shade(const fixture *f, const float *x, float *y)
{
    (void)f;
    ibl_material m = sc_material_of(x);
    ibl_surface s = sc_surface_of(x + 11);
    ibl_shade_desc d = desc_of(x);
    ibl_light l[NL];
    for (int k = 0; k < NL; k++) l[k] = light_of(x + LIGHTS + 15 * k);
    ibl_light_result r;
    ibl_lights_shade(l, NL, x + VIS, &d, &m, &s, sc_v3(x + P), &r);
    put_result(y, &r);
}

static void ref_lights_shade_all(const fixture *f, const float *x, float *y)
{
    (void)f;
    ibl_material m = sc_material_of(x);
    ibl_surface s = sc_surface_of(x + 11);
    ibl_shade_desc d = desc_of(x);
    ibl_light l[NL];
    for (int k = 0; k < NL; k++) l[k] = light_of(x + LIGHTS + 15 * k);
    ibl_light_result r;
    ibl_lights_shade(l, NL, NULL, &d, &m, &s, sc_v3(x + P), &r);
    put_result(y, &r);
}

/* GLSL: L(k) builds an ibl_light from the 15 inputs at k, DL the desc with light_size */
#define LIGHT_HEAD                                                                             \
    "ibl_shade_desc d = ibl_shade_desc(0, 0, 0, 0, 0.0, 0, 0, 0, 0, I(26));\n"                                         \
    "  ibl_light ls[IBL_MAX_LIGHTS]; float vis[IBL_MAX_LIGHTS];\n"                             \
    "  for (int k = 0; k < IBL_MAX_LIGHTS; k++) { ls[k] = L(27 + 15 * min(k, 2));\n"            \
    "    vis[k] = k < 3 ? X(72 + k) : 0.0; }\n  "

#define YL(expr) "ibl_light_result r = " expr "; Y3(0, r.diffuse); Y3(3, r.specular);\n"      \
                 "  Y(6, r.n_dot_l); Y(7, r.shininess); Y(8, r.alpha);"

const shader_case shader_light_cases[] = {
    {"ibl_light_range_window", 7, 1, "Y(0, ibl_light_range_window(X(0), X(1)));", gen_falloff,
     ref_window, ARITH, "arithmetic", NULL},
    {"ibl_light_distance_falloff", 7, 1, "Y(0, ibl_light_distance_falloff(X(0), X(1)));",
     gen_falloff, ref_falloff, ARITH, "arithmetic; + 8 eps / d^2: the window cancels",
     window_slack},
    {"ibl_light_cone_falloff", 7, 1, "Y(0, ibl_light_cone_falloff(X(2), X(3), X(4)));",
     gen_falloff, ref_cone, ARITH, "cos; + 8e-7 / (cos_i - cos_o)", cone_case_slack},
    {"ibl_ggx_sphere_alpha", 7, 1, "Y(0, ibl_ggx_sphere_alpha(X(5), X(6), X(0)));",
     gen_falloff, ref_sphere_alpha, ARITH, "arithmetic", NULL},
    {"ibl_light_incidence_at", N_IN, 9,
     LIGHT_HEAD "ibl_light_incidence r = ibl_light_incidence_at(ls[0], V(23));\n"
     "  Y3(0, r.l); Y(3, r.distance); Y3(4, r.illuminance); Y(7, r.size); Y(8, r.attenuation);",
     gen_shade_case, ref_incidence, ARITH, "sqrt, cos; + cone and window slack",
     incidence_case_slack},
    {"ibl_light_shade_incidence", N_IN, 9,
     LIGHT_HEAD YL("ibl_light_shade_incidence(ibl_light_incidence_at(ls[0], V(23)), d, M(0), S(11))"),
     gen_shade_case, ref_shade_incidence, ARITH, "pow; + n.h's rounding through the lobe",
     one_light_slack},
    {"ibl_light_shade", N_IN, 9, LIGHT_HEAD YL("ibl_light_shade(ls[0], d, M(0), S(11), V(23))"),
     gen_shade_case, ref_light_shade, ARITH, "as above", one_light_slack},
    {"ibl_lights_shade (visibility)", N_IN, 9,
     LIGHT_HEAD YL("ibl_lights_shade(ls, 3, vis, d, M(0), S(11), V(23))"), gen_shade_case,
     ref_lights_shade, ARITH, "as above, summed", visible_lights_slack},
    {"ibl_lights_shade", N_IN, 9, LIGHT_HEAD YL("ibl_lights_shade(ls, 3, d, M(0), S(11), V(23))"),
     gen_shade_case, ref_lights_shade_all, ARITH, "as above, summed", all_lights_slack},
};

const int shader_light_case_count = (int)(sizeof shader_light_cases / sizeof shader_light_cases[0]);
