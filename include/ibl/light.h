/*
 * ibl/light.h - punctual lights on the two material models of shade.h: directional, point and
 * spot lights as glTF's KHR_lights_punctual defines them, evaluated exactly as delta lights
 * on tri-Ace 2010's normalised Blinn-Phong BRDF and on glTF 2.0's GGX metal/roughness BRDF.
 *
 * A light may have a size (the radius of its emitter). The size only widens the specular
 * highlight the way each model's source does it: tri-Ace 2010's "shininess hack" for
 * Blinn-Phong, Karis 2013's widened roughness of a sphere light for GGX.
 *
 * The result keeps diffuse and specular apart: the specular is the direct specular s_d of
 * tri-Ace's compositions (shade.h, ibl_surface.direct_specular), so IBL_MIX_ENTIRE can apply
 * specular occlusion to it ("Applying to the entire specular term"). The diffuse is added by
 * the caller, unoccluded by AO (AO stands for ambient light only; a light's own shadow is the
 * caller's visibility). docs/SHADING.md "Punctual lights" gives every formula with its source.
 *
 * Units (KHR_lights_punctual): a directional light's intensity is an illuminance (lux), a
 * point or spot light's a luminous intensity (candela, illuminance intensity / d^2 at distance
 * d). The reflected radiance is f(l, v) E (n.l) with E the illuminance the light delivers on
 * a surface facing it. Every function here takes validated data and never fails.
 */
#ifndef IBL_LIGHT_H
#define IBL_LIGHT_H

#include "core.h"
#include "shade.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum ibl_light_type {
    IBL_LIGHT_DIRECTIONAL = 0, /* parallel light from infinitely far: no falloff                */
    IBL_LIGHT_POINT,           /* from a position in every direction: inverse-square falloff    */
    IBL_LIGHT_SPOT,            /* a point light limited to a cone, with a smooth edge           */
    IBL_LIGHT_TYPE_COUNT
} ibl_light_type;

typedef struct ibl_light {
    ibl_light_type type;
    float color[3];     /* linear RGB; all zero: white (glTF's default)                       */
    float intensity;    /* scales color: lux (directional) or candela (point, spot); 0: 1     */
    ibl_vec3 position;  /* point, spot                                                       */
    ibl_vec3 direction; /* directional, spot: the direction the light travels (glTF: the
                           node's -Z); any length but zero                                  */
    float range;        /* point, spot: the distance where it reaches zero; 0: infinite      */
    float inner_cone;   /* spot: half-angle in radians where the edge begins (glTF: 0)       */
    float outer_cone;   /* spot: half-angle where it ends; 0: pi/4 (glTF's default)          */
    float size;         /* radius of the emitter, in scene units; for a directional light the
                           tangent of its angular radius (the sun: 0.0047); 0: a true point  */
} ibl_light;

/* Checks one light (a known type, finite values, colour, intensity, range and size >= 0, a
 * non-zero direction where one is used, 0 <= inner < outer <= pi/2 for a spot); records the
 * reason, naming the light's index, on failure. */
ibl_status ibl_light_validate(ibl_context *ctx, const ibl_light *light, int index);

/* What a light delivers at a point, before the BRDF. */
typedef struct ibl_light_incidence {
    ibl_vec3 l;            /* unit direction from the point toward the light                  */
    float distance;        /* to the light; INFINITY for a directional light                  */
    float illuminance[3];  /* on a surface facing the light: colour x intensity x distance
                              falloff x cone falloff                                          */
    float size;            /* the light's size                                                */
    float attenuation;     /* tri-Ace 2010's "attenuation factor" for the shininess hack: the
                              range window, 1 at the light and 0 at its range; 0 for directional
                              lights and lights without a range (the distant-light limit)     */
} ibl_light_incidence;

void ibl_light_incidence_at(const ibl_light *light, ibl_vec3 p, ibl_light_incidence *out);

/* The falloffs, KHR_lights_punctual's recommended forms:
 *   range window        saturate(1 - (d / range)^4)  (1 when range <= 0: no range)
 *   distance falloff    window / d^2                  (d floored at 1e-4)
 *   cone falloff        saturate((cos - cos_outer) / max(1e-3, cos_inner - cos_outer))^2
 * where cos is the cosine between the spot's direction and the direction from the light. */
float ibl_light_range_window(float distance, float range);
float ibl_light_distance_falloff(float distance, float range);
float ibl_light_cone_falloff(float cos_angle, float inner_cone, float outer_cone);

/* Karis 2013 ("Real Shading in Unreal Engine 4", sphere lights): the GGX alpha widened by a
 * sphere light of radius `radius` at `distance`, saturate(alpha + radius / (2 distance)). */
float ibl_ggx_sphere_alpha(float alpha, float radius, float distance);

/* What a light's size does: ibl_light_size_model, in shade.h (ibl_shade_desc.light_size). */
const char *ibl_light_size_model_name(ibl_light_size_model m); /* "widen", "ignore" */
int ibl_light_size_model_from_name(const char *name, ibl_light_size_model *out); /* 0: unknown */
const char *ibl_light_type_name(ibl_light_type t); /* "directional", "point", "spot" */

typedef struct ibl_light_result {
    float diffuse[3];  /* radiance reflected by the diffuse lobe toward v                    */
    float specular[3]; /* by the specular lobe: s_d of the compositions                      */
    float n_dot_l;     /* 0 when the light is behind the surface (then all of it is 0)       */
    float shininess;   /* Blinn-Phong: the exponent used (after the hack)                    */
    float alpha;       /* GGX: the alpha of D (after widening; at least 1e-3)               */
} ibl_light_result;

/* One light at point p of a surface (s->n, s->v; direct_specular is ignored). desc may be
 * NULL (defaults); only desc->light_size is read.
 *   Blinn-Phong (tri-Ace 2010, "Equations"):
 *     f = Rd/pi (1 - F0) + (0.0397436 n + 0.0856832) F(F0, v.h) (n.h)^n / max(n.l, n.v)
 *   GGX (glTF 2.0 metal/roughness): f = F D V + diffuse colour / pi, D = GGX, V the
 *     height-correlated Smith visibility, F Schlick's. */
void ibl_light_shade(const ibl_light *light, const ibl_shade_desc *desc, const ibl_material *m,
                     const ibl_surface *s, ibl_vec3 p, ibl_light_result *out);
/* The same from an incidence already computed (ibl_light_incidence_at), e.g. after a shadow
 * test along in->l. */
void ibl_light_shade_incidence(const ibl_light_incidence *in, const ibl_shade_desc *desc,
                               const ibl_material *m, const ibl_surface *s,
                               ibl_light_result *out);

/* Several lights summed: visibility (optional, one factor per light) scales each light, e.g.
 * 0 in its shadow. out->n_dot_l, shininess and alpha are those of the last light that lit
 * the point. Putting it together with the ambient light (what `ibl render` does):
 *     s.direct_specular = total.specular;  ibl_shade(probe, desc, m, &s, &r);
 *     colour = r.color + total.diffuse  */
void ibl_lights_shade(const ibl_light *lights, int count, const float *visibility,
                      const ibl_shade_desc *desc, const ibl_material *m, const ibl_surface *s,
                      ibl_vec3 p, ibl_light_result *out);

#ifdef __cplusplus
}
#endif
#endif
