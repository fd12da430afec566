/*
 * ibl_probes.hlsl - the run time of a probe bake in HLSL (Shader Model 5.0 and later): the
 * twin of shaders/ibl_probes.glsl, function for function, with the same names, parameters and
 * conventions. Include after ibl.hlsl. The records are a StructuredBuffer<ibl_local_probe>
 * (probes.bin, 240-byte stride), the chains a TextureCubeArray whose slice i is record i, read
 * through ibl.hlsl's one SamplerState `smp`. tests/test_shaders_probes.c compiles it to
 * SPIR-V; the GLSL twin is the one run against the C.
 */
#ifndef IBL_PROBES_HLSL
#define IBL_PROBES_HLSL

#ifndef IBL_HLSL
#error "include ibl.hlsl before ibl_probes.hlsl"
#endif

/* One record of probes.bin (std430, 240 bytes; ibl_probe_record in C). */
struct ibl_local_probe {
    float4 position_size;               /* xyz capture position, w influence volume (m^3)    */
    float4 influence_center_radius;     /* w: sphere radius (0 for a box)                     */
    float4 influence_half_extent_blend; /* xyz: box half extent, w: blend margin              */
    float4 proxy_center_radius;
    float4 proxy_half_extent_coverage;  /* w: mean coverage of level 0                        */
    int4 shapes_layer_priority;      /* influence shape, proxy shape, layer, priority      */
    float4 sh[9];                       /* rgb: SH of premultiplied radiance, a: of coverage  */
};

ibl_volume ibl_local_probe_influence(ibl_local_probe r)
{
    ibl_volume v;
    v.shape = r.shapes_layer_priority.x;
    v.center = r.influence_center_radius.xyz;
    v.radius = r.influence_center_radius.w;
    v.half_extent = r.influence_half_extent_blend.xyz;
    v.blend_distance = r.influence_half_extent_blend.w;
    return v;
}

ibl_volume ibl_local_probe_proxy(ibl_local_probe r)
{
    ibl_volume v;
    v.shape = r.shapes_layer_priority.y;
    v.center = r.proxy_center_radius.xyz;
    v.radius = r.proxy_center_radius.w;
    v.half_extent = r.proxy_half_extent_coverage.xyz;
    v.blend_distance = 0.0;
    return v;
}

/* The diffuse alpha at normal n: the cosine-convolved coverage, E_a(n) / pi of the coverage
 * SH (the records' .a), clamped to [0, 1]. */
float ibl_local_probe_diffuse_alpha(ibl_local_probe r, float3 n)
{
    float4 sh[9];
    for (int k = 0; k < 9; k++) sh[k] = float4(r.sh[k].aaa, 0.0);
    return clamp(ibl_sh9_eval_irradiance(sh, IBL_SH_KIND_RADIANCE, n).r / IBL_PI, 0.0, 1.0);
}

/* A local probe as ibl.glsl's ibl_probe: `layers` is the block every layer shares (the
 * bake's level mapping and the BRDF tables: ibl_shader_probe_fill of any probe
 * ibl_probe_bake_locals returns), given the record's radiance SH here. */
ibl_probe ibl_local_probe_view(ibl_probe layers, ibl_local_probe r)
{
    ibl_probe p = layers;
    for (int k = 0; k < 9; k++) p.sh[k] = float4(r.sh[k].rgb, 0.0);
    p.sh_kind = IBL_SH_KIND_RADIANCE;
    p.has_mirror = 0;
    p.intensity = 1.0;
    return p;
}

/* ---- the front-to-back priority blend (JAGE 2015, with its alpha) ---------------------- */

struct ibl_probe_blend {
    float3 specular, diffuse;
    float rs, rd;  /* what is left for the probes after, and at last the global probe       */
    float best;    /* the largest specular share so far                                       */
    int heaviest;  /* its layer, -1: none                                                     */
};

ibl_probe_blend ibl_probe_blend_begin()
{
    ibl_probe_blend b;
    b.specular = float3(0.0, 0.0, 0.0);
    b.diffuse = float3(0.0, 0.0, 0.0);
    b.rs = 1.0;
    b.rd = 1.0;
    b.best = 0.0;
    b.heaviest = -1;
    return b;
}

/* Adds layer k's premultiplied specular S and diffuse D with influence weight w and alphas
 * a_s (the chain's alpha along the lookup direction) and a_d (ibl_local_probe_diffuse_alpha):
 * S += w rs S, rs -= w rs a_s, and the same for D with rd. */
void ibl_probe_blend_add(inout ibl_probe_blend b, int k, float w, float3 s, float3 d, float a_s,
                         float a_d)
{
    float cs = w * b.rs, cd = w * b.rd;
    b.specular += cs * s;
    b.diffuse += cd * d;
    if (cs * a_s > b.best) {
        b.best = cs * a_s;
        b.heaviest = k;
    }
    b.rs = max(b.rs - cs * a_s, 0.0);
    b.rd = max(b.rd - cd * a_d, 0.0);
}

/* The layer with the largest specular share, or -1 when the global probe's share is larger
 * (ibl_probe_blend_info.heaviest). */
int ibl_probe_blend_heaviest(ibl_probe_blend b) { return b.rs > b.best ? -1 : b.heaviest; }

/* Is anything left for the probes after? (the loop may stop when not) */
bool ibl_probe_blend_open(ibl_probe_blend b) { return b.rs > 0.0 || b.rd > 0.0; }

/* The global probe takes what is left: color = D ao + S so, with so that of the global
 * probe's result (ibl_probes_shade). */
ibl_shade_result ibl_probe_blend_end(ibl_probe_blend b, ibl_shade_result global, float ao)
{
    ibl_shade_result r = global;
    r.specular = b.specular + b.rs * global.specular;
    r.diffuse = b.diffuse + b.rd * global.diffuse;
    r.color = r.diffuse * ao + r.specular * global.so;
    return r;
}

/* ---- shading from the cube-map array -------------------------------------------------- */

/* A layer's premultiplied specular and diffuse for a GGX material along dir (ibl_shade_dir
 * of a local probe: split-sum specular, SH diffuse; energy compensation as desc says), and
 * the chain's alpha there. */
ibl_shade_result ibl_local_shade_dir(ibl_probe p, TextureCubeArray chains, int layer,
                                     Texture2D splitsum, SamplerState smp, ibl_shade_desc desc, ibl_material m,
                                     ibl_surface s, float3 dir, out float alpha)
{
    float nv = max(dot(s.n, s.v), 1e-4);
    float3 irr = ibl_sh9_eval_irradiance(p.sh, IBL_SH_KIND_RADIANCE, s.n) * (p.intensity / IBL_PI);
    float roughness = clamp(m.roughness, 0.0, 1.0);
    float lod = ibl_probe_lod_from_roughness(p, roughness);
    if (desc.nearest_level != 0 && lod > 0.0) lod = floor(lod + 0.5);
    lod = clamp(lod, 0.0, float(p.levels - 1));
    float4 t = chains.SampleLevel(smp, float4(dir, float(layer)), lod);
    alpha = clamp(t.a, 0.0, 1.0);
    float a = 1.0, b = 0.0;
    if (p.has_splitsum != 0) ibl_splitsum_lookup(splitsum, smp, p, nv, roughness, a, b);
    float ess = a + b;
    float3 fd = any(m.f0 != float3(0.0, 0.0, 0.0)) ? m.f0 : float3(0.04, 0.04, 0.04);
    float3 f0 = fd + (m.base_color - fd) * m.metallic;
    float3 fss_ess = f0 * a + b;
    float3 spec = t.rgb * fss_ess;
    if (desc.energy == IBL_ENERGY_FDEZ_AGUERA && ess > 0.0) {
        float ems = 1.0 - ess; /* Fdez-Aguera 2019 section 3 */
        float3 favg = f0 + (1.0 - f0) / 21.0;
        spec += fss_ess * favg / (1.0 - ems * favg) * ems * irr;
    } else if (desc.energy == IBL_ENERGY_TURQUIN && ess > 0.0) {
        spec *= 1.0 + f0 * (1.0 / ess - 1.0); /* Turquin 2019 */
    }
    ibl_shade_result r;
    r.diffuse = m.base_color * (1.0 - m.metallic) * irr;
    r.specular = spec;
    r.color = r.diffuse * m.ao + spec;
    r.so = 1.0;
    r.lod = lod;
    r.r = dir;
    return r;
}

/* What the comparisons switch off (ibl_probe_blend_desc) */
#define IBL_PROBE_NO_PARALLAX 1
#define IBL_PROBE_NO_BLEND 2
#define IBL_PROBE_NO_ALPHA 4

/* One listed layer k of the blend at world point p: its influence weight (skipped at 0), the
 * lookup direction corrected on its proxy, its shading and alphas, added front to back. The
 * caller loops over the tile's list in ascending order (ibl_probe_cull.comp's lists):
 *
 *   ibl_probe_blend b = ibl_probe_blend_begin();
 *   float3 dir = ibl_shade_lookup_direction(desc, m, s);
 *   for (int i = 0; i < count && ibl_probe_blend_open(b); i++)
 *       ibl_probe_blend_layer(b, layers, records[list[i]], list[i], chains, splitsum,
 *                             desc, m, p, s, dir, 0);
 *   ibl_shade_result g = ibl_shade_dir(global, ..., dir);
 *   ibl_shade_result r = ibl_probe_blend_end(b, g, m.ao);  */
void ibl_probe_blend_layer(inout ibl_probe_blend b, ibl_probe layers, ibl_local_probe rec, int k,
                           TextureCubeArray chains, Texture2D splitsum, SamplerState smp, ibl_shade_desc desc,
                           ibl_material m, float3 p, ibl_surface s, float3 dir, int flags)
{
    float w = ibl_volume_weight(ibl_local_probe_influence(rec), p);
    if (!(w > 0.0)) return;
    if ((flags & IBL_PROBE_NO_BLEND) != 0) w = 1.0;
    float3 d = (flags & IBL_PROBE_NO_PARALLAX) != 0
                 ? dir
                 : ibl_parallax_correct(ibl_local_probe_proxy(rec), rec.position_size.xyz, p, dir);
    float a_s;
    ibl_shade_result r = ibl_local_shade_dir(ibl_local_probe_view(layers, rec), chains, k, splitsum, smp,
                                             desc, m, s, d, a_s);
    float a_d = ibl_local_probe_diffuse_alpha(rec, s.n);
    if ((flags & IBL_PROBE_NO_ALPHA) != 0) a_s = a_d = 1.0;
    ibl_probe_blend_add(b, k, w, r.specular, r.diffuse, a_s, a_d);
}

/* ---- tri-Ace 2010 "IBL Blending" -------------------------------------------------------- */

/* The blend factor across the attenuation zone [zone_start, zone_end] of a distance (e.g.
 * from the first probe's centre): 0 before it, 1 after, linear inside. */
float ibl_attenuation_zone(float distance, float zone_start, float zone_end)
{
    if (!(zone_end > zone_start)) return distance >= zone_end ? 1.0 : 0.0;
    return clamp((distance - zone_start) / (zone_end - zone_start), 0.0, 1.0);
}

/* Two layers blended by t the talk's way: outside the attenuation zone (t 0 or 1) one
 * radiance fetch; inside it two, and the diffuse from the two SH sets blended coefficient by
 * coefficient (one evaluation). Layers a and b of the array, their records ra and rb. */
ibl_shade_result ibl_triace_blend(ibl_probe layers, ibl_local_probe ra, int a, ibl_local_probe rb,
                                  int b, float t, TextureCubeArray chains, Texture2D splitsum, SamplerState smp,
                                  ibl_shade_desc desc, ibl_material m, ibl_surface s, float3 dir)
{
    ibl_local_probe first = t >= 1.0 ? rb : ra;
    for (int k = 0; k < 9; k++) first.sh[k].rgb = lerp(ra.sh[k].rgb, rb.sh[k].rgb, clamp(t, 0.0, 1.0));
    float alpha;
    ibl_shade_result r = ibl_local_shade_dir(ibl_local_probe_view(layers, first), chains,
                                             t >= 1.0 ? b : a, splitsum, smp, desc, m, s, dir, alpha);
    if (t > 0.0 && t < 1.0) { /* the second fetch, only in the zone */
        ibl_shade_result r2 = ibl_local_shade_dir(ibl_local_probe_view(layers, rb), chains, b,
                                                  splitsum, smp, desc, m, s, dir, alpha);
        r.specular = lerp(r.specular, r2.specular, t);
    }
    r.color = r.diffuse * m.ao + r.specular;
    return r;
}

/* ---- the environment switch (Daqi 2016, "PBR Series 6", 6.3) ---------------------------- */

/* Two sets of environment slots, the older (where the object comes from) and the newer
 * (where it goes): here two layers of the array. On touching a new environment its layer
 * goes to the newer set; once the object is wholly inside (t = 1) the newer set becomes the
 * older one (ibl_environment_slots_update on the CPU, or in a shader per object). */
struct ibl_environment_slots {
    int older, newer;
};

/* The switch factor of an object of extent `size` at p walking across the border plane
 * through border_point with unit normal border_normal (pointing into the newer
 * environment): ibl.glsl's ibl_environment_switch on the positions projected onto the
 * normal, saturate(x / size + 0.5). */
float ibl_environment_switch_at(float3 p, float3 border_point, float3 border_normal, float size)
{
    return ibl_environment_switch(dot(p - border_point, border_normal), 0.0, size);
}

/* The slots after the object stands in environment `here` with switch factor t. */
ibl_environment_slots ibl_environment_slots_update(ibl_environment_slots slots, int here, float t)
{
    if (here != slots.older && here != slots.newer) slots.newer = here;
    if (t >= 1.0 && slots.newer == here) slots.older = here;
    return slots;
}

/* The shading across the switch: the older set's result, the newer's, mixed by t. */
ibl_shade_result ibl_environment_switch_shade(ibl_probe layers, ibl_environment_slots slots,
                                              ibl_local_probe older, ibl_local_probe newer,
                                              float t, TextureCubeArray chains,
                                              Texture2D splitsum, SamplerState smp, ibl_shade_desc desc,
                                              ibl_material m, ibl_surface s, float3 dir)
{
    float alpha;
    ibl_shade_result r = ibl_local_shade_dir(ibl_local_probe_view(layers, older), chains,
                                             slots.older, splitsum, smp, desc, m, s, dir, alpha);
    if (slots.newer != slots.older && t > 0.0) {
        ibl_shade_result n = ibl_local_shade_dir(ibl_local_probe_view(layers, newer), chains,
                                                 slots.newer, splitsum, smp, desc, m, s, dir, alpha);
        r.diffuse = lerp(r.diffuse, n.diffuse, t);
        r.specular = lerp(r.specular, n.specular, t);
        r.color = lerp(r.color, n.color, t);
    }
    return r;
}

#endif
