/* Builds a probe from an environment in memory, so `ibl render` works on a plain environment
 * image: the irradiance SH (sh.h) and the BRDF tables (brdf.h) come from the library's bake
 * stages; the GGX prefilter is a FALLBACK, slow and simple, until specular.h exists in this
 * build: N = V = R (Karis 2013) by importance sampling with filtered lookups (Krivanek &
 * Colbert 2008: lod from the ratio of sample and texel solid angles). */
#include "render_internal.h"

#include "ibl/brdf.h"
#include "ibl/sh.h"

#include <stdlib.h>
#include <string.h>

static const float PI_F = 3.14159265358979f;

enum { PREFILTER_SAMPLES = 96 };
enum { AB_NV = 16, AB_S = 24, AB_F0 = 8 };

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

static float *own(ibl_probe *p, void *mem)
{
    if (mem) p->owned[p->owned_count++] = mem;
    return mem;
}

ibl_status ibl_render_probe_from_environment(ibl_context *ctx, const ibl_cubemap *env,
                                             const ibl_render_probe_desc *desc, ibl_probe *out)
{
    int specular_size = desc ? desc->specular_size : 0;
    int table_size = desc && desc->table_size > 0 ? desc->table_size : 128;
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
    ibl_sh sh;
    if ((st = ibl_sh_project_cubemap(ctx, chain, sh_level, 3, &sh)) != IBL_OK) goto fail;
    for (int i = 0; i < 9; i++)
        for (int c = 0; c < 3; c++) out->sh[i][c] = (float)sh.c[i][c];
    out->sh_kind = IBL_SH_RADIANCE;

    /* brdf.h tables, texel-centred on every axis (docs/BRDF.md): [r][n.v] RGBA with A, B */
    ibl_image lut;
    ibl_brdf_lut_desc ld = {.size = table_size};
    if ((st = ibl_brdf_lut(ctx, &ld, &lut)) != IBL_OK) goto fail;
    own(out, lut.pixels);
    float ts = (float)table_size;
    ibl_table_axis centred = {table_size, 0.5f / ts, 1.0f - 0.5f / ts, 0};
    out->splitsum = (ibl_splitsum_view){lut.pixels, 4, centred, centred};
    /* the AmbientBRDF volume [F0][shininess][n.v] RGBA, R the albedo; shininess rows at
     * min (max/min)^((j + 0.5)/n), i.e. a log axis from row 0's value to the last row's */
    ibl_ambient_brdf_desc ad = {.size_nv = AB_NV,
                                .size_shininess = AB_S,
                                .size_f0 = AB_F0,
                                .shininess_min = 1.0,
                                .shininess_max = 100000.0};
    ibl_texture vol;
    if ((st = ibl_ambient_brdf_volume(ctx, &ad, &vol)) != IBL_OK) goto fail;
    float *vol_data = own(out, vol.data);
    vol.owns_data = 0;
    ibl_texture_free(ctx, &vol); /* its metadata, if any */
    ibl_table_axis abv = {AB_NV, 0.5f / AB_NV, 1.0f - 0.5f / AB_NV, 0};
    ibl_table_axis abs_ = {AB_S, (float)ibl_ambient_brdf_row_shininess(&ad, 0),
                           (float)ibl_ambient_brdf_row_shininess(&ad, AB_S - 1), 1};
    ibl_table_axis abf = {AB_F0, 0.5f / AB_F0, 1.0f - 0.5f / AB_F0, 0};
    out->ambient_brdf = (ibl_ambient_brdf_view){vol_data, 4, abv, abs_, abf};

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
