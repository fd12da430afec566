/* FALLBACK, slow and simple: builds a probe from an environment in memory so `ibl render`
 * works on a plain environment image before the bake stages (specular.h, sh.h, brdf.h) and
 * `ibl bake` exist in this build. Each piece is the textbook estimator, nothing tuned:
 *  - GGX prefilter with N = V = R (Karis 2013) by importance sampling with filtered lookups
 *    (Krivanek & Colbert 2008: lod from the ratio of sample and texel solid angles);
 *  - irradiance as 9 SH coefficients of the radiance (projection with exact texel solid
 *    angles; Ramamoorthi & Hanrahan 2001 convolve them at lookup);
 *  - the split-sum table (Karis 2013) and the seed's AmbientBRDF volume (tri-Ace 2010) by
 *    importance sampling.
 * When the bake stages land, this file is replaced by calls to them. */
#include "render_internal.h"

#include <stdlib.h>
#include <string.h>

static const float PI_F = 3.14159265358979f;

enum { PREFILTER_SAMPLES = 96, TABLE_SAMPLES = 256 };
enum { SS_NV = 32, SS_R = 32, AB_NV = 16, AB_S = 20, AB_F0 = 8 };

typedef struct prefilter_job {
    const ibl_cubemap *env; /* full mip chain */
    ibl_cubemap *out;
    float roughness[IBL_MAX_LEVELS];
} prefilter_job;

/* one task per (level >= 1, face) */
static void prefilter_task(void *arg, int index)
{
    prefilter_job *job = arg;
    int level = 1 + index / 6, face = index % 6;
    int n = ibl_level_size(job->out->size, level);
    float alpha = job->roughness[level] * job->roughness[level];
    if (alpha < 1e-3f) alpha = 1e-3f;
    float texel_sa = 4.0f * PI_F / (6.0f * (float)job->env->size * (float)job->env->size);
    float *dst = ibl_cubemap_face(job->out, level, face);
    for (int y = 0; y < n; y++)
        for (int x = 0; x < n; x++) {
            ibl_vec3 nrm = ibl_cube_texel_direction(face, n, x, y);
            float acc[3] = {0, 0, 0}, wsum = 0.0f;
            for (int i = 0; i < PREFILTER_SAMPLES; i++) {
                float u0, u1;
                ibl__hammersley((uint32_t)i, PREFILTER_SAMPLES, 0.0f, 0.0f, &u0, &u1);
                ibl_vec3 h = ibl__sample_ggx(nrm, alpha, u0, u1);
                float vh = ibl__dot(nrm, h);
                ibl_vec3 l = ibl__v3(2.0f * vh * h.x - nrm.x, 2.0f * vh * h.y - nrm.y,
                                     2.0f * vh * h.z - nrm.z);
                float nl = ibl__dot(nrm, l);
                if (nl <= 0.0f) continue;
                /* pdf of l with n = v: D(h) n.h / (4 v.h) = D / 4 */
                float pdf = ibl_ggx_d(alpha, vh) * 0.25f;
                float sample_sa = 1.0f / ((float)PREFILTER_SAMPLES * pdf + 1e-6f);
                float lod = 0.5f * log2f(sample_sa / texel_sa) + 1.0f;
                float c[4];
                ibl_cubemap_sample_trilinear(job->env, lod < 0.0f ? 0.0f : lod, l, c);
                for (int k = 0; k < 3; k++) acc[k] += c[k] * nl;
                wsum += nl;
            }
            float *t = dst + ((size_t)y * n + x) * 4;
            for (int k = 0; k < 3; k++) t[k] = wsum > 0.0f ? acc[k] / wsum : 0.0f;
            t[3] = 1.0f;
        }
}

static void project_sh9(const ibl_cubemap *env, int level, float sh[9][3])
{
    int n = ibl_level_size(env->size, level);
    double acc[9][3];
    memset(acc, 0, sizeof acc);
    for (int f = 0; f < 6; f++) {
        const float *face = ibl_cubemap_face(env, level, f);
        for (int y = 0; y < n; y++)
            for (int x = 0; x < n; x++) {
                ibl_vec3 d = ibl_cube_texel_direction(f, n, x, y);
                double sa = ibl_cube_texel_solid_angle(n, x, y);
                double b[9] = {0.282095,
                               0.488603 * d.y,
                               0.488603 * d.z,
                               0.488603 * d.x,
                               1.092548 * d.x * d.y,
                               1.092548 * d.y * d.z,
                               0.315392 * (3.0 * d.z * d.z - 1.0),
                               1.092548 * d.x * d.z,
                               0.546274 * (d.x * d.x - d.y * d.y)};
                const float *t = face + ((size_t)y * n + x) * 4;
                for (int i = 0; i < 9; i++)
                    for (int c = 0; c < 3; c++) acc[i][c] += t[c] * b[i] * sa;
            }
    }
    for (int i = 0; i < 9; i++)
        for (int c = 0; c < 3; c++) sh[i][c] = (float)acc[i][c];
}

static void splitsum_entry(float nv, float roughness, float *a, float *b)
{
    float alpha = roughness * roughness;
    ibl_vec3 n = {0, 0, 1}, v = {sqrtf(1.0f - nv * nv), 0.0f, nv};
    double sa = 0.0, sb = 0.0;
    for (int i = 0; i < TABLE_SAMPLES; i++) {
        float u0, u1;
        ibl__hammersley((uint32_t)i, TABLE_SAMPLES, 0.0f, 0.0f, &u0, &u1);
        ibl_vec3 h = ibl__sample_ggx(n, alpha, u0, u1);
        float vh = ibl__dot(v, h);
        float nl = 2.0f * vh * h.z - v.z;
        if (nl <= 0.0f || vh <= 0.0f) continue;
        /* f n.l / pdf with pdf = D n.h / (4 v.h): V 4 v.h n.l / n.h */
        float w = ibl_smith_ggx_v(alpha, nv, nl) * 4.0f * vh * nl / h.z;
        float fc = powf(1.0f - vh, 5.0f);
        sa += (1.0f - fc) * w;
        sb += fc * w;
    }
    *a = (float)(sa / TABLE_SAMPLES);
    *b = (float)(sb / TABLE_SAMPLES);
}

/* White-environment albedo of the seed's specular term:
 * (c1 s + c2) F (n.h)^s n.l / max(n.l, n.v), sampled with pdf (s+1)/(2pi) (n.h)^s / (4 v.h). */
static float ambient_entry(float nv, float s, float f0)
{
    ibl_vec3 n = {0, 0, 1}, v = {sqrtf(1.0f - nv * nv), 0.0f, nv};
    double acc = 0.0;
    for (int i = 0; i < TABLE_SAMPLES; i++) {
        float u0, u1;
        ibl__hammersley((uint32_t)i, TABLE_SAMPLES, 0.0f, 0.0f, &u0, &u1);
        ibl_vec3 h = ibl__sample_phong(n, s, u0, u1);
        float vh = ibl__dot(v, h);
        float nl = 2.0f * vh * h.z - v.z;
        if (nl <= 0.0f || vh <= 0.0f) continue;
        float f = ibl_fresnel_schlick(f0, vh);
        acc += ibl_blinn_phong_norm(s) * f * nl / fmaxf(nl, nv) * 8.0f * PI_F * vh / (s + 1.0f);
    }
    return (float)(acc / TABLE_SAMPLES);
}

static float *own(ibl_probe *p, void *mem)
{
    if (mem) p->owned[p->owned_count++] = mem;
    return mem;
}

ibl_status ibl_render_probe_from_environment(ibl_context *ctx, const ibl_cubemap *env,
                                             int specular_size, ibl_probe *out)
{
    memset(out, 0, sizeof *out);
    if (!env || !env->data || env->size <= 0)
        return ibl_fail(ctx, IBL_ERR_INVALID_ARGUMENT, "render: no environment");
    int size = specular_size > 0 ? specular_size : (env->size < 128 ? env->size : 128);
    if (size > env->size) size = env->size;
    /* the environment with a full, area-correct mip chain for filtered lookups */
    ibl_cubemap *chain = &out->owned_cubes[0];
    ibl_status st = ibl_cubemap_alloc(ctx, env->size, ibl_full_mip_count(env->size), chain);
    if (st != IBL_OK) goto fail;
    memcpy(chain->data, env->data, ibl_cubemap_floats(env->size, 1) * sizeof(float));
    if ((st = ibl_cubemap_build_mips(ctx, chain)) != IBL_OK) goto fail;

    /* levels down to 4x4 (or 1x1 for tiny inputs): smaller levels add nothing for GGX */
    int levels = ibl_full_mip_count(size) - 2;
    if (levels < 1) levels = 1;
    ibl_cubemap *spec = &out->owned_cubes[1];
    if ((st = ibl_cubemap_alloc(ctx, size, levels, spec)) != IBL_OK) goto fail;
    {
        ibl_cubemap top;
        if ((st = ibl_cubemap_alloc(ctx, size, 1, &top)) != IBL_OK) goto fail;
        st = ibl_cubemap_resample(ctx, env, &top);
        if (st == IBL_OK) memcpy(spec->data, top.data, ibl_cubemap_floats(size, 1) * sizeof(float));
        ibl_cubemap_free(ctx, &top);
        if (st != IBL_OK) goto fail;
    }
    prefilter_job job = {chain, spec, {0}};
    for (int k = 0; k < levels; k++) {
        job.roughness[k] = levels > 1 ? (float)k / (float)(levels - 1) : 0.0f;
        out->mapping.roughness[k] = job.roughness[k];
    }
    out->mapping.levels = levels;
    if (levels > 1) ibl_parallel_for(ctx, (levels - 1) * 6, prefilter_task, &job);

    int sh_level = 0;
    while (ibl_level_size(env->size, sh_level) > 32) sh_level++;
    project_sh9(chain, sh_level, out->sh);
    out->sh_kind = IBL_SH_RADIANCE;

    float *ss = own(out, ibl_alloc(ctx, sizeof(float) * SS_NV * SS_R * 2));
    float *ab = own(out, ibl_alloc(ctx, sizeof(float) * AB_NV * AB_S * AB_F0));
    if (!ss || !ab) {
        st = ibl_context_status(ctx);
        goto fail;
    }
    ibl_table_axis nv_axis = {SS_NV, 0.5f / SS_NV, 1.0f - 0.5f / SS_NV, 0};
    ibl_table_axis r_axis = {SS_R, 0.0f, 1.0f, 0};
    for (int j = 0; j < SS_R; j++)
        for (int i = 0; i < SS_NV; i++)
            splitsum_entry(ibl_table_axis_value(&nv_axis, i), ibl_table_axis_value(&r_axis, j),
                           &ss[(j * SS_NV + i) * 2], &ss[(j * SS_NV + i) * 2 + 1]);
    out->splitsum = (ibl_splitsum_table){ss, 2, nv_axis, r_axis};
    ibl_table_axis abv = {AB_NV, 0.5f / AB_NV, 1.0f - 0.5f / AB_NV, 0};
    ibl_table_axis abs_ = {AB_S, 1.0f, 100000.0f, 1};
    ibl_table_axis abf = {AB_F0, 0.0f, 1.0f, 0};
    for (int k = 0; k < AB_F0; k++)
        for (int j = 0; j < AB_S; j++)
            for (int i = 0; i < AB_NV; i++)
                ab[(k * AB_S + j) * AB_NV + i] =
                    ambient_entry(ibl_table_axis_value(&abv, i), ibl_table_axis_value(&abs_, j),
                                  ibl_table_axis_value(&abf, k));
    out->ambient_brdf = (ibl_ambient_brdf_table){ab, 1, abv, abs_, abf};

    out->specular = *spec;
    out->specular.owns_data = 0;
    out->mirror = *chain;
    out->mirror.owns_data = 0;
    if ((st = ibl_probe_validate(ctx, out)) != IBL_OK) goto fail;
    return IBL_OK;
fail:
    ibl_probe_free(ctx, out);
    return st;
}
