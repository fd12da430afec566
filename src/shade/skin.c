/* Skin at run time: the ambient diffuse term lit along three scattered normals (one per colour
 * channel, Daqi 2016 "PBR Series 6.2": the normal map blurred offline by the diffusion profile,
 * skin.h) and the translucency of thin regions lit from behind by the irradiance (Jimenez,
 * Whelan, Sundstedt and Gutierrez 2010, "Real-Time Realistic Skin Translucency"). The profile
 * is d'Eon and Luebke's six Gaussians (GPU Gems 3, ch. 14, 2007). shaders/ibl_skin.glsl and
 * ibl_skin.hlsl are the twins of this file. */
#include "ibl/shade.h"
#include "core/numeric.h"

#include <math.h>

ibl_skin_profile ibl_skin_profile_deon(void)
{
    /* GPU Gems 3, ch. 14, "sum-of-Gaussians parameters for a three-layer skin model":
     * variance (mm^2) and the red, green, blue weights of each Gaussian */
    static const float table[6][4] = {
        {0.0064f, 0.233f, 0.455f, 0.649f}, {0.0484f, 0.100f, 0.336f, 0.344f},
        {0.187f, 0.118f, 0.198f, 0.0f},    {0.567f, 0.113f, 0.007f, 0.007f},
        {1.99f, 0.358f, 0.004f, 0.0f},     {7.41f, 0.078f, 0.0f, 0.0f},
    };
    ibl_skin_profile p = {0};
    p.count = 6;
    for (int i = 0; i < 6; i++) {
        p.variance_mm2[i] = table[i][0];
        for (int c = 0; c < 3; c++) p.weight[i][c] = table[i][1 + c];
    }
    return p;
}

void ibl_skin_transmittance(const ibl_skin_profile *profile, float thickness_mm, float out[3])
{
    ibl_skin_profile deon;
    if (!profile) {
        deon = ibl_skin_profile_deon();
        profile = &deon;
    }
    float d2 = thickness_mm * thickness_mm;
    out[0] = out[1] = out[2] = 0.0f;
    for (int i = 0; i < profile->count; i++) {
        float g = expf(-d2 / profile->variance_mm2[i]);
        for (int c = 0; c < 3; c++) out[c] += profile->weight[i][c] * g;
    }
}

void ibl_skin_shade(const ibl_probe *probe, const ibl_skin_profile *profile,
                    const ibl_skin_surface *s, ibl_skin_result *out)
{
    for (int c = 0; c < 3; c++) {
        float e[3];
        ibl_probe_irradiance(probe, s->n[c], e);
        out->diffuse[c] = s->albedo[c] * e[c];
        out->translucent[c] = 0.0f;
    }
    if (s->transmittance > 0.0f) {
        float range = s->thickness_range_mm > 0.0f ? s->thickness_range_mm : IBL_SKIN_THICKNESS_RANGE_MM;
        float scale = s->translucency > 0.0f ? s->translucency : 1.0f;
        float d = (1.0f - ibl__saturate(s->transmittance)) * range, t[3], back[3];
        ibl_skin_transmittance(profile, d, t);
        ibl_probe_irradiance(probe, ibl__scale(s->geometric_normal, -1.0f), back);
        for (int c = 0; c < 3; c++) out->translucent[c] = s->albedo[c] * t[c] * back[c] * scale;
    }
    for (int c = 0; c < 3; c++) out->color[c] = out->diffuse[c] + out->translucent[c];
}
