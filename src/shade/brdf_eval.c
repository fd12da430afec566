/* The analytic BRDF pieces the runtime and the reference renderer share, written once. */
#include "ibl/shade.h"
#include "core/numeric.h"
#include "core/defaults.h"

#include <math.h>


/* Schlick 1994: F = F0 + (1 - F0)(1 - v.h)^5. */
float ibl_fresnel_schlick(float f0, float v_dot_h)
{
    float c = 1.0f - (v_dot_h < 0.0f ? 0.0f : v_dot_h);
    float c2 = c * c;
    return f0 + (1.0f - f0) * c2 * c2 * c;
}

/* Trowbridge-Reitz / GGX (Walter et al. 2007): a^2 / (pi ((n.h)^2 (a^2 - 1) + 1)^2). */
float ibl_ggx_d(float alpha, float n_dot_h)
{
    if (n_dot_h <= 0.0f) return 0.0f;
    float a2 = alpha * alpha;
    float d = n_dot_h * n_dot_h * (a2 - 1.0f) + 1.0f;
    return a2 / (IBL_PI_F * d * d);
}

/* Height-correlated Smith for GGX divided by 4 (n.l)(n.v) (Heitz 2014, "Understanding the
 * Masking-Shadowing Function in Microfacet-Based BRDFs"). */
float ibl_smith_ggx_v(float alpha, float n_dot_v, float n_dot_l)
{
    if (n_dot_v <= 0.0f || n_dot_l <= 0.0f) return 0.0f;
    float a2 = alpha * alpha;
    float gv = n_dot_l * sqrtf(n_dot_v * n_dot_v * (1.0f - a2) + a2);
    float gl = n_dot_v * sqrtf(n_dot_l * n_dot_l * (1.0f - a2) + a2);
    return 0.5f / (gv + gl);
}

/* tri-Ace 2010 ("Equations"): the fitted normalisation of their Blinn-Phong lobe. */
float ibl_blinn_phong_norm(float shininess)
{
    return 0.0397436f * shininess + 0.0856832f;
}

/* Walter et al. 2007 relate Phong exponent and Beckmann width by n = 2 / alpha^2 - 2; GGX and
 * Beckmann agree in the lobe core, which is what prefiltered levels care about. */
float ibl_shininess_from_roughness(float roughness)
{
    float a = roughness * roughness;
    if (a * a < 2e-6f) return IBL_MIRROR_SHININESS;
    float n = 2.0f / (a * a) - 2.0f;
    return n < 0.0f ? 0.0f : n;
}

float ibl_roughness_from_shininess(float shininess)
{
    if (shininess < 0.0f) shininess = 0.0f;
    float a = sqrtf(2.0f / (shininess + 2.0f));
    return sqrtf(a);
}
