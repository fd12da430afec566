/*
 * ibl_atlas.glsl - Daqi 2016 ("[PBR Series - 6] Improvement of PBR", 6.1) for devices short
 * of texture slots (OpenGL ES with 8): the prefiltered chain read from one 2D mip atlas, an
 * 8-bit RGBM atlas decoded before it is filtered, and the material texture whose R, G, B, A
 * hold metalness, roughness, AO and transmittance (`ibl pack`). Include after ibl.glsl (it
 * uses ibl_probe, ibl_atlas_layout, ibl_atlas_uv and ibl_atlas_sample from there).
 *
 * The coordinate table is the ibl_atlas_layout uniform block (ibl_shader_atlas_fill in
 * include/ibl/shader.h fills it from the table a bake's manifest.json "atlas", or the
 * atlas KTX2's key "ibl.atlas", holds: docs/ATLAS.md). The C twins: ibl_probe_sample_specular
 * with probe.use_atlas, ibl_atlas_sample, ibl_unpack_material_channels; tested against them
 * on llvmpipe in tests/test_shaders_atlas.c.
 *
 * The atlas texture: one level (no mipmaps: every level is in the image), clamp to edge, its
 * first row at v = 0; GL_LINEAR for a float atlas (RGBA16F), any filter for RGBM (RGBA8,
 * read with texelFetch).
 */
#ifndef IBL_ATLAS_GLSL
#define IBL_ATLAS_GLSL

/* Prefiltered radiance along dir from the atlas: ibl_probe_sample_specular's twin for a
 * chain stored as the atlas. lod is clamped to [0, levels - 1]: no mirror cube (the 8-slot
 * device has no slot for one), so a lod below 0 reads level 0. Bilinear in the two levels
 * around lod, then linear between them (ibl_atlas_sample). */
vec3 ibl_atlas_probe_specular(ibl_probe p, sampler2D atlas, ibl_atlas_layout l, float lod, vec3 dir)
{
    float top = float(min(p.levels, l.levels) - 1);
    return p.intensity * ibl_atlas_sample(atlas, l, clamp(lod, 0.0, top), dir).rgb;
}

/* RGBM texel -> radiance: rgb * a * range (ibl_rgbm_decode with codes normalised to [0, 1]). */
vec3 ibl_rgbm_decode(vec4 t, float range)
{
    return t.rgb * (t.a * range);
}

/* One level of an RGBM atlas at dir: the four texels around the point are decoded first and
 * then weighted. Hardware filtering of the stored bytes would blend rgb and the multiplier
 * separately (the product of the blends is not the blend of the products), so the bytes
 * are fetched whole. ibl_atlas_uv keeps the point inside the level's face cell, whose
 * 1-texel gutter holds the neighbouring faces: the four texels never leave the cell. */
vec3 ibli_atlas_rgbm_level(sampler2D atlas, ibl_atlas_layout l, int level, vec3 dir, float range)
{
    float u, v;
    ibl_atlas_uv(l, level, dir, u, v);
    vec2 p = vec2(u * float(l.width), v * float(l.height)) - 0.5;
    vec2 f = floor(p), w = p - f;
    ivec2 hi = ivec2(l.width - 1, l.height - 1);
    ivec2 a = clamp(ivec2(f), ivec2(0), hi), b = clamp(ivec2(f) + 1, ivec2(0), hi);
    vec3 t00 = ibl_rgbm_decode(texelFetch(atlas, ivec2(a.x, a.y), 0), range);
    vec3 t10 = ibl_rgbm_decode(texelFetch(atlas, ivec2(b.x, a.y), 0), range);
    vec3 t01 = ibl_rgbm_decode(texelFetch(atlas, ivec2(a.x, b.y), 0), range);
    vec3 t11 = ibl_rgbm_decode(texelFetch(atlas, ivec2(b.x, b.y), 0), range);
    return mix(mix(t00, t10, w.x), mix(t01, t11, w.x), w.y);
}

/* ibl_atlas_sample for an 8-bit RGBM atlas (specular_atlas.png, or a KTX2 in rgbm): the same
 * trilinear read, each level's bilinear on decoded texels. range: the file's (manifest
 * "rgbm_range", KTX2 key ibl.rgbm_range; 8 by default). */
vec3 ibl_atlas_sample_rgbm(sampler2D atlas, ibl_atlas_layout l, float range, float lod, vec3 dir)
{
    lod = clamp(lod, 0.0, float(l.levels - 1));
    int k = int(floor(lod));
    float w = lod - float(k);
    vec3 a = ibli_atlas_rgbm_level(atlas, l, k, dir, range);
    if (w == 0.0 || k + 1 >= l.levels) return a;
    return mix(a, ibli_atlas_rgbm_level(atlas, l, k + 1, dir, range), w);
}

/* ---- channel packing (Daqi 2016; `ibl pack`, ibl_pack_material_channels) ----------------- */

/* The four maps of a packed material texel: R metalness, G perceptual roughness, B ambient
 * occlusion, A transmittance. A packed PNG is linear data: sample it as a UNORM texture,
 * never as sRGB. */
struct ibl_packed_material {
    float metallic, roughness, ao, transmittance;
};

ibl_packed_material ibl_unpack_material(vec4 texel)
{
    return ibl_packed_material(texel.r, texel.g, texel.b, texel.a);
}

/* Puts a packed texel's maps into a material (GGX: metallic, roughness; every model: ao) and
 * returns the transmittance, which ibl_shade does not read (the translucency pass does). */
float ibl_material_apply_packed(inout ibl_material m, vec4 texel)
{
    ibl_packed_material p = ibl_unpack_material(texel);
    m.metallic = p.metallic;
    m.roughness = p.roughness;
    m.ao = p.ao;
    return p.transmittance;
}

#endif
