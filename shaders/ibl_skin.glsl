/*
 * ibl_skin.glsl - skin under image-based lighting at run time, the twin of the "Skin" part of
 * include/ibl/shade.h (src/shade/skin.c), tested against the C on Mesa's llvmpipe
 * (tests/test_shaders_skin.c). Include after ibl.glsl; same dialects (GLSL 4.50, ES 3.00,
 * Vulkan). docs/SKIN.md has the method and the maps.
 *
 * Inputs per pixel: three normals from the scattered normal maps that `ibl sss` bakes (one per
 * colour channel, Daqi 2016 "PBR Series 6.2: SSS based on normal map"), taken to world space
 * with the mesh's tangent frame as any normal map; the geometric normal; the albedo; the grey
 * transmittance map t (the alpha of the packed material map), which stands for the thickness
 * d = (1 - t) range_mm.
 *
 * Profile: d'Eon and Luebke's six Gaussians (GPU Gems 3, ch. 14, 2007): variances in mm^2,
 * RGB weights (each channel sums to 1).
 */
#ifndef IBL_SKIN_GLSL
#define IBL_SKIN_GLSL

#define IBL_SKIN_THICKNESS_RANGE_MM 8.0

const float IBL_SKIN_VARIANCE_MM2[6] = float[6](0.0064, 0.0484, 0.187, 0.567, 1.99, 7.41);
const vec3 IBL_SKIN_WEIGHT[6] = vec3[6](vec3(0.233, 0.455, 0.649), vec3(0.100, 0.336, 0.344),
                                        vec3(0.118, 0.198, 0.0), vec3(0.113, 0.007, 0.007),
                                        vec3(0.358, 0.004, 0.0), vec3(0.078, 0.0, 0.0));

struct ibl_skin_surface {
    vec3 n_r, n_g, n_b;         /* world normals of the red, green, blue scattered maps (unit) */
    vec3 geometric_normal;      /* unit: translucency arrives from -N                         */
    vec3 albedo;
    float transmittance;        /* the map's t in [0, 1]; 0: no translucency                  */
    float thickness_range_mm;   /* what t = 0 stands for; 0: IBL_SKIN_THICKNESS_RANGE_MM      */
    float translucency;         /* scale of the translucent term; 0: 1                        */
};

struct ibl_skin_result {
    vec3 diffuse;     /* albedo_c IEM_c(n_c)                */
    vec3 translucent; /* albedo_c T_c(d) IEM_c(-N) scale     */
    vec3 color;       /* the sum                             */
};

/* T_c(d) = sum_i w_ci exp(-d^2 / v_i), d in mm (Jimenez, Whelan, Sundstedt and Gutierrez
 * 2010, "Real-Time Realistic Skin Translucency"). */
vec3 ibl_skin_transmittance(float thickness_mm)
{
    float d2 = thickness_mm * thickness_mm;
    vec3 t = vec3(0.0);
    for (int i = 0; i < 6; i++) t += IBL_SKIN_WEIGHT[i] * exp(-d2 / IBL_SKIN_VARIANCE_MM2[i]);
    return t;
}

/* Each colour channel lit along its own scattered normal, plus light from behind through thin
 * regions: the irradiance about -N times the transmittance (ibl_skin_shade in C). */
ibl_skin_result ibl_skin_shade(ibl_probe p, samplerCube irradiance, ibl_skin_surface s)
{
    ibl_skin_result r;
    r.diffuse = s.albedo * vec3(ibl_probe_irradiance(p, irradiance, s.n_r).r,
                                ibl_probe_irradiance(p, irradiance, s.n_g).g,
                                ibl_probe_irradiance(p, irradiance, s.n_b).b);
    r.translucent = vec3(0.0);
    if (s.transmittance > 0.0) {
        float range = s.thickness_range_mm > 0.0 ? s.thickness_range_mm : IBL_SKIN_THICKNESS_RANGE_MM;
        float scale = s.translucency > 0.0 ? s.translucency : 1.0;
        float d = (1.0 - clamp(s.transmittance, 0.0, 1.0)) * range;
        r.translucent = s.albedo * ibl_skin_transmittance(d) *
                        ibl_probe_irradiance(p, irradiance, -s.geometric_normal) * scale;
    }
    r.color = r.diffuse + r.translucent;
    return r;
}

#endif
