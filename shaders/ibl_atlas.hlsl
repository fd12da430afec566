/*
 * ibl_atlas.hlsl - the twin of shaders/ibl_atlas.glsl (Daqi 2016's 2D mip atlas and channel
 * packing), function for function; include after ibl.hlsl. Textures are Texture2D with the
 * SamplerState `smp` of ibl.hlsl (bilinear, clamp) for a float atlas; an RGBM atlas is read
 * with Load. docs/ATLAS.md.
 */
#ifndef IBL_ATLAS_HLSL
#define IBL_ATLAS_HLSL

/* Prefiltered radiance from the atlas (ibl_probe_sample_specular's twin, no mirror). */
float3 ibl_atlas_probe_specular(ibl_probe p, Texture2D atlas, SamplerState smp,
                                ibl_atlas_layout l, float lod, float3 dir)
{
    float top = float(min(p.levels, l.levels) - 1);
    return p.intensity * ibl_atlas_sample(atlas, smp, l, clamp(lod, 0.0, top), dir).rgb;
}

/* RGBM texel -> radiance: rgb * a * range. */
float3 ibl_rgbm_decode(float4 t, float range)
{
    return t.rgb * (t.a * range);
}

/* One level of an RGBM atlas: four texels decoded, then weighted (see the GLSL). */
float3 ibli_atlas_rgbm_level(Texture2D atlas, ibl_atlas_layout l, int level, float3 dir, float range)
{
    float u, v;
    ibl_atlas_uv(l, level, dir, u, v);
    float2 p = float2(u * float(l.width), v * float(l.height)) - 0.5;
    float2 f = floor(p), w = p - f;
    int2 hi = int2(l.width - 1, l.height - 1);
    int2 a = clamp(int2(f), int2(0, 0), hi), b = clamp(int2(f) + 1, int2(0, 0), hi);
    float3 t00 = ibl_rgbm_decode(atlas.Load(int3(a.x, a.y, 0)), range);
    float3 t10 = ibl_rgbm_decode(atlas.Load(int3(b.x, a.y, 0)), range);
    float3 t01 = ibl_rgbm_decode(atlas.Load(int3(a.x, b.y, 0)), range);
    float3 t11 = ibl_rgbm_decode(atlas.Load(int3(b.x, b.y, 0)), range);
    return lerp(lerp(t00, t10, w.x), lerp(t01, t11, w.x), w.y);
}

/* ibl_atlas_sample for an 8-bit RGBM atlas. */
float3 ibl_atlas_sample_rgbm(Texture2D atlas, ibl_atlas_layout l, float range, float lod, float3 dir)
{
    lod = clamp(lod, 0.0, float(l.levels - 1));
    int k = int(floor(lod));
    float w = lod - float(k);
    float3 a = ibli_atlas_rgbm_level(atlas, l, k, dir, range);
    if (w == 0.0 || k + 1 >= l.levels) return a;
    return lerp(a, ibli_atlas_rgbm_level(atlas, l, k + 1, dir, range), w);
}

/* ---- channel packing (Daqi 2016; `ibl pack`) -------------------------------------------- */

struct ibl_packed_material {
    float metallic, roughness, ao, transmittance;
};

ibl_packed_material ibl_unpack_material(float4 texel)
{
    ibl_packed_material p;
    p.metallic = texel.r;
    p.roughness = texel.g;
    p.ao = texel.b;
    p.transmittance = texel.a;
    return p;
}

float ibl_material_apply_packed(inout ibl_material m, float4 texel)
{
    ibl_packed_material p = ibl_unpack_material(texel);
    m.metallic = p.metallic;
    m.roughness = p.roughness;
    m.ao = p.ao;
    return p.transmittance;
}

#endif
