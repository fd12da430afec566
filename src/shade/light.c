/* Punctual lights on the two material models, evaluated exactly as delta lights, with the
 * highlight widening each model's source gives a light of finite size.
 * Sources:
 *  - KHR_lights_punctual (Khronos glTF 2.0 extension): the three light types, their units
 *    (lux for directional lights, candela for point and spot lights), the recommended range
 *    window saturate(1 - (d/range)^4) over d^2, the cone falloff between the cosines of the
 *    inner and outer angles, squared.
 *  - tri-Ace 2010 (Gotanda & Shoji, "Real-time Physically Based Rendering - Implementation"):
 *    the normalised Blinn-Phong BRDF ("Equations") and the "Shininess hack".
 *  - glTF 2.0 specification, Appendix B (metal/roughness BRDF): GGX D (Walter et al. 2007),
 *    height-correlated Smith V (Heitz 2014), Schlick's Fresnel (Schlick 1994), Lambert.
 *  - Karis 2013 ("Real Shading in Unreal Engine 4", "Sphere Lights"): the widened roughness
 *    alpha' = saturate(alpha + radius / (2 distance)) of a sphere light. */
#include "ibl/light.h"
#include "core/context_internal.h"
#include "core/defaults.h"
#include "core/numeric.h"

#include <math.h>
#include <string.h>

/* KHR_lights_punctual's default outer cone angle, pi/4 */
#define DEFAULT_OUTER_CONE 0.78539816f
/* a point closer than this to a point light takes this distance: the inverse square stays
 * finite */
#define MIN_LIGHT_DISTANCE 1e-4f

static const char *const size_model_names[IBL_LIGHT_SIZE_COUNT] = {"widen", "ignore"};
static const char *const type_names[IBL_LIGHT_TYPE_COUNT] = {"directional", "point", "spot"};

const char *ibl_light_size_model_name(ibl_light_size_model m)
{
    return (unsigned)m < IBL_LIGHT_SIZE_COUNT ? size_model_names[m] : "unknown";
}

int ibl_light_size_model_from_name(const char *name, ibl_light_size_model *out)
{
    for (int i = 0; name && i < IBL_LIGHT_SIZE_COUNT; i++)
        if (strcmp(name, size_model_names[i]) == 0) {
            *out = (ibl_light_size_model)i;
            return 1;
        }
    return 0;
}

const char *ibl_light_type_name(ibl_light_type t)
{
    return (unsigned)t < IBL_LIGHT_TYPE_COUNT ? type_names[t] : "unknown";
}

static int finite_vec(ibl_vec3 v)
{
    return isfinite(v.x) && isfinite(v.y) && isfinite(v.z);
}

static int non_negative(float x)
{
    return isfinite(x) && x >= 0.0f;
}

static float outer_cone_of(const ibl_light *light)
{
    return light->outer_cone > 0.0f ? light->outer_cone : DEFAULT_OUTER_CONE;
}

ibl_status ibl_light_validate(ibl_context *ctx, const ibl_light *light, int index)
{
    if (!light) return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "light %d: missing", index);
    if ((unsigned)light->type >= IBL_LIGHT_TYPE_COUNT)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "light %d: unknown type %d", index,
                         (int)light->type);
    const char *type = type_names[light->type];
    for (int c = 0; c < 3; c++)
        if (!non_negative(light->color[c]))
            return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                             "light %d (%s): colour must be finite and >= 0", index, type);
    if (!non_negative(light->intensity) || !non_negative(light->range) ||
        !non_negative(light->size))
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                         "light %d (%s): intensity, range and size must be finite and >= 0",
                         index, type);
    if (light->type != IBL_LIGHT_DIRECTIONAL && !finite_vec(light->position))
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "light %d (%s): position not finite",
                         index, type);
    if (light->type != IBL_LIGHT_POINT &&
        (!finite_vec(light->direction) || ibl__dot(light->direction, light->direction) <= 0.0f))
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                         "light %d (%s): direction must be finite and non-zero", index, type);
    if (light->type == IBL_LIGHT_SPOT) {
        float inner = light->inner_cone, outer = outer_cone_of(light);
        /* glTF: 0 <= inner < outer <= pi/2 (the float nearest pi/2 is accepted) */
        if (!(inner >= 0.0f) || !(inner < outer) || !(outer <= 1.5707964f))
            return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                             "light %d (spot): cone angles need 0 <= inner < outer <= pi/2, "
                             "not %g and %g radians",
                             index, (double)inner, (double)outer);
    }
    return IBL_OK;
}

float ibl_light_range_window(float distance, float range)
{
    if (!(range > 0.0f)) return 1.0f;
    float x = distance / range, x2 = x * x;
    return ibl__saturate(1.0f - x2 * x2);
}

float ibl_light_distance_falloff(float distance, float range)
{
    float d = distance > MIN_LIGHT_DISTANCE ? distance : MIN_LIGHT_DISTANCE;
    return ibl_light_range_window(d, range) / (d * d);
}

float ibl_light_cone_falloff(float cos_angle, float inner_cone, float outer_cone)
{
    float cos_inner = cosf(inner_cone), cos_outer = cosf(outer_cone);
    float t = ibl__saturate((cos_angle - cos_outer) / fmaxf(1e-3f, cos_inner - cos_outer));
    return t * t;
}

float ibl_ggx_sphere_alpha(float alpha, float radius, float distance)
{
    if (!(radius > 0.0f) || !(distance > 0.0f)) return alpha;
    return ibl__saturate(alpha + radius / (2.0f * distance));
}

void ibl_light_incidence_at(const ibl_light *light, ibl_vec3 p, ibl_light_incidence *out)
{
    float scale = light->intensity > 0.0f ? light->intensity : 1.0f;
    int white = light->color[0] == 0.0f && light->color[1] == 0.0f && light->color[2] == 0.0f;
    float falloff = 1.0f;
    out->size = light->size > 0.0f ? light->size : 0.0f;
    out->attenuation = 0.0f;
    if (light->type == IBL_LIGHT_DIRECTIONAL) {
        out->l = ibl__norm(ibl__scale(light->direction, -1.0f));
        out->distance = INFINITY;
    } else {
        ibl_vec3 to_light = ibl__sub(light->position, p);
        float d = sqrtf(ibl__dot(to_light, to_light));
        out->distance = d;
        if (d > 0.0f) {
            out->l = ibl__scale(to_light, 1.0f / d);
            falloff = ibl_light_distance_falloff(d, light->range);
        } else {
            /* at the light itself there is no direction to light from */
            out->l = ibl__v3(0.0f, 1.0f, 0.0f);
            falloff = 0.0f;
        }
        /* the talk's attenuation factor is 1 at the light and 0 where the light ends: the
         * range window is that factor of an inverse-square light (the 1/d^2 part carries the
         * scene's unit of length and is not in [0, 1]) */
        if (light->range > 0.0f) out->attenuation = ibl_light_range_window(d, light->range);
        if (light->type == IBL_LIGHT_SPOT) {
            ibl_vec3 axis = ibl__norm(light->direction);
            /* the cone is measured from the light toward the point: -l */
            falloff *= ibl_light_cone_falloff(-ibl__dot(axis, out->l), light->inner_cone,
                                              outer_cone_of(light));
        }
    }
    for (int c = 0; c < 3; c++)
        out->illuminance[c] = (white ? 1.0f : light->color[c]) * scale * falloff;
}

void ibl_light_shade_incidence(const ibl_light_incidence *in, const ibl_shade_desc *desc,
                               const ibl_material *m, const ibl_surface *s,
                               ibl_light_result *out)
{
    memset(out, 0, sizeof *out);
    int widen = !desc || desc->light_size == IBL_LIGHT_SIZE_WIDEN;
    int bp = m->model == IBL_MATERIAL_BLINN_PHONG;
    float alpha = fmaxf(m->roughness * m->roughness, IBL_MIN_GGX_ALPHA);
    if (bp) {
        out->shininess = widen ? ibl_shininess_hack(m->shininess, in->size, in->attenuation)
                               : m->shininess;
    } else {
        /* a directional light's size is already the ratio radius / distance */
        float distance = isinf(in->distance) ? 1.0f : in->distance;
        out->alpha = widen ? ibl_ggx_sphere_alpha(alpha, in->size, distance) : alpha;
    }
    float nl = ibl__dot(s->n, in->l);
    if (nl <= 0.0f) return;
    /* n.v at 0 (silhouettes, bent normals): the floor ibl_shade uses */
    float nv = fmaxf(ibl__dot(s->n, s->v), 1e-4f);
    ibl_vec3 h = ibl__norm(ibl__add(s->v, in->l));
    float nh = fmaxf(ibl__dot(s->n, h), 0.0f), vh = fmaxf(ibl__dot(s->v, h), 0.0f);
    float lobe;
    if (bp) /* tri-Ace 2010: (c1 n + c2) (n.h)^n / max(n.l, n.v), times F below */
        lobe = ibl_blinn_phong_norm(out->shininess) * powf(nh, out->shininess) / fmaxf(nl, nv);
    else /* Karis 2013 widens the distribution only; the visibility keeps the material's alpha */
        lobe = ibl_ggx_d(out->alpha, nh) * ibl_smith_ggx_v(alpha, nv, nl);
    float f0[3], albedo[3];
    ibl_material_reflectances(m, f0, albedo);
    for (int c = 0; c < 3; c++) {
        float e = in->illuminance[c] * nl;
        out->specular[c] = lobe * ibl_fresnel_schlick(f0[c], vh) * e;
        out->diffuse[c] = albedo[c] * (1.0f / IBL_PI_F) * e;
    }
    out->n_dot_l = nl;
}

void ibl_light_shade(const ibl_light *light, const ibl_shade_desc *desc, const ibl_material *m,
                     const ibl_surface *s, ibl_vec3 p, ibl_light_result *out)
{
    ibl_light_incidence in;
    ibl_light_incidence_at(light, p, &in);
    ibl_light_shade_incidence(&in, desc, m, s, out);
}

void ibl_lights_shade(const ibl_light *lights, int count, const float *visibility,
                      const ibl_shade_desc *desc, const ibl_material *m, const ibl_surface *s,
                      ibl_vec3 p, ibl_light_result *out)
{
    memset(out, 0, sizeof *out);
    for (int i = 0; i < count; i++) {
        float vis = visibility ? visibility[i] : 1.0f;
        if (!(vis > 0.0f)) continue;
        ibl_light_result one;
        ibl_light_shade(&lights[i], desc, m, s, p, &one);
        if (one.n_dot_l <= 0.0f) continue;
        for (int c = 0; c < 3; c++) {
            out->diffuse[c] += vis * one.diffuse[c];
            out->specular[c] += vis * one.specular[c];
        }
        out->n_dot_l = one.n_dot_l;
        out->shininess = one.shininess;
        out->alpha = one.alpha;
    }
}
