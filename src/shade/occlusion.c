/* Specular occlusion and the ways ambient specular, ambient diffuse and direct specular are
 * put together. Sources: tri-Ace 2010 (Gotanda & Shoji, "Real-time Physically Based
 * Rendering - Implementation"), Lagarde & de Rousiers 2014 ("Moving Frostbite
 * to PBR", section 4.10.2), Jimenez et al. 2016 ("Practical Realtime Strategies for Accurate
 * Indirect Occlusion", section 6), Russell 2015 ("Horizon Occlusion for Normal Mapped
 * Reflections"). docs/SHADING.md discusses each. */
#include "ibl/shade.h"
#include "core/numeric.h"

#include <math.h>
#include <string.h>


static const char *const so_names[IBL_SO_COUNT] = {
    "none", "ao", "triace", "triace-shininess", "triace-fast", "frostbite", "cone"};
static const char *const mix_names[IBL_MIX_COUNT] = {"multiply",   "lerp-albedo", "lerp-ao",
                                                     "ao-lerp-ao", "lerp-ao2",    "entire"};

static const char *const energy_names[] = {"none", "fdez-aguera", "turquin"};

const char *ibl_energy_compensation_name(ibl_energy_compensation e)
{
    return (unsigned)e < sizeof energy_names / sizeof energy_names[0] ? energy_names[e] : "unknown";
}

int ibl_energy_compensation_from_name(const char *name, ibl_energy_compensation *out)
{
    for (unsigned i = 0; name && i < sizeof energy_names / sizeof energy_names[0]; i++)
        if (strcmp(name, energy_names[i]) == 0) {
            *out = (ibl_energy_compensation)i;
            return 1;
        }
    return 0;
}

const char *ibl_so_formula_name(ibl_so_formula f)
{
    return (unsigned)f < IBL_SO_COUNT ? so_names[f] : "unknown";
}

int ibl_so_formula_from_name(const char *name, ibl_so_formula *out)
{
    for (int i = 0; name && i < IBL_SO_COUNT; i++)
        if (strcmp(name, so_names[i]) == 0) {
            *out = (ibl_so_formula)i;
            return 1;
        }
    return 0;
}

const char *ibl_ambient_mix_name(ibl_ambient_mix m)
{
    return (unsigned)m < IBL_MIX_COUNT ? mix_names[m] : "unknown";
}

int ibl_ambient_mix_from_name(const char *name, ibl_ambient_mix *out)
{
    for (int i = 0; name && i < IBL_MIX_COUNT; i++)
        if (strcmp(name, mix_names[i]) == 0) {
            *out = (ibl_ambient_mix)i;
            return 1;
        }
    return 0;
}

/* Solid angle of the intersection of two spherical caps (half-angles r1, r2, axes d apart),
 * with the smoothstep blend of Oat & Sander 2007 ("Ambient aperture lighting") for the
 * partial overlap. */
static float cap_intersection(float r1, float r2, float d)
{
    float rmin = r1 < r2 ? r1 : r2, rmax = r1 < r2 ? r2 : r1;
    float h = sinf(0.5f * rmin); /* 1 - cos r = 2 sin^2(r/2): no cancellation for thin cones */
    float small_cap = 4.0f * IBL_PI_F * h * h;
    if (d <= rmax - rmin) return small_cap;
    if (d >= r1 + r2) return 0.0f;
    float x = 1.0f - ibl__saturate((d - (rmax - rmin)) / (2.0f * rmin));
    return small_cap * x * x * (3.0f - 2.0f * x);
}

/* Jimenez et al. 2016 (section 6): specular occlusion is the fraction of the specular cone
 * inside the visibility cone. The visibility cone has the aperture whose cosine-weighted
 * fraction is AO (AO = sin^2 of the half-angle, tri-Ace's isotropic occlusion); the
 * specular cone is where the equivalent Phong lobe cos^n falls to half (our choice, stated
 * in docs/SHADING.md). Both cones are centred on their axes: n and R. */
/* acos(1 - x) for x in [0, 2], written 2 asin(sqrt(x / 2)): acos loses the angle near 1
 * (one float step of c = 1 - 6e-8 is already 3.5e-4 rad), while 1 - c keeps its digits. */
static float acos_one_minus(float x)
{
    return 2.0f * asinf(sqrtf(ibl__saturate(0.5f * x)));
}

static float cone_so(float n_dot_e, float ao, float roughness)
{
    float vis = asinf(sqrtf(ibl__saturate(ao)));
    float n = ibl_shininess_from_roughness(roughness);
    /* half-angle where cos^n falls to 1/2: c = 2^(-1/(n+1)), 1 - c = -expm1(-ln2 / (n+1)) */
    float spec = acos_one_minus(-expm1f(-0.69314718f / (n + 1.0f)));
    if (spec < 1e-4f) spec = 1e-4f;
    /* R is E mirrored about n: both make the same angle with n */
    float d = acos_one_minus(1.0f - ibl__saturate(n_dot_e));
    float h = sinf(0.5f * spec);
    float cap = 4.0f * IBL_PI_F * h * h;
    return ibl__saturate(cap_intersection(vis, spec, d) / cap);
}

float ibl_specular_occlusion(ibl_so_formula f, float n_dot_e, float ao, float roughness,
                             float shininess)
{
    float ne = ibl__saturate(n_dot_e);
    ao = ibl__saturate(ao);
    switch (f) {
    case IBL_SO_NONE: return 1.0f;
    case IBL_SO_AO: return ao;
    /* tri-Ace 2010, "SO implementation (1)" */
    case IBL_SO_TRIACE: return ibl__saturate(ne * ne + 2.0f * ao - 1.0f);
    /* tri-Ace 2010, "SO implementation (2)" */
    case IBL_SO_TRIACE_SHININESS: return ibl__saturate(powf(ne + ao, 0.01f * shininess) - 1.0f + ao);
    /* tri-Ace 2010, "SO implementation (3)" */
    case IBL_SO_TRIACE_FAST: {
        float s = ne + ao;
        return ibl__saturate(s * s - 1.0f + ao);
    }
    /* Lagarde & de Rousiers 2014, "Moving Frostbite to PBR", specular occlusion */
    case IBL_SO_FROSTBITE:
        return ibl__saturate(powf(ne + ao, exp2f(-16.0f * roughness - 1.0f)) - 1.0f + ao);
    case IBL_SO_CONE: return cone_so(ne, ao, roughness);
    default: return 1.0f;
    }
}

/* Russell 2015: reflections of normal-mapped surfaces that point under the geometric horizon
 * are faded out: ibl__saturate(1 + k R.Ng)^2, k = 1.3 in Marmoset Toolbag. */
float ibl_horizon_occlusion(ibl_vec3 r, ibl_vec3 ng, float k)
{
    if (k <= 0.0f) k = 1.3f;
    float h = ibl__saturate(1.0f + k * (r.x * ng.x + r.y * ng.y + r.z * ng.z));
    return h * h;
}

/* tri-Ace 2010, "Ambient specular term computation" .. "Applying to the entire specular term". */
void ibl_ambient_mix_apply(ibl_ambient_mix mix, const float s_d[3], const float diffuse_ambient[3],
                           const float specular_ambient[3], const float albedo[3], float ao,
                           float so, float out[3])
{
    for (int c = 0; c < 3; c++) {
        float sd = s_d ? s_d[c] : 0.0f, da = diffuse_ambient[c], sa = specular_ambient[c];
        switch (mix) {
        case IBL_MIX_LERP_ALBEDO: out[c] = sd + ibl__lerpf(da * albedo[c], sa, so); break;
        case IBL_MIX_LERP_AO: out[c] = sd + ibl__lerpf(da * ao, sa, so); break;
        case IBL_MIX_AO_LERP_AO: out[c] = sd + ao * ibl__lerpf(da * ao, sa, so); break;
        case IBL_MIX_LERP_AO2: out[c] = sd + ibl__lerpf(da * ao * ao, sa, so); break;
        case IBL_MIX_ENTIRE: out[c] = sd * so + ao * ibl__lerpf(da * ao, sa, so); break;
        case IBL_MIX_MULTIPLY:
        default: out[c] = sd + sa * so; break;
        }
    }
}
