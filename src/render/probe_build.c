/* Builds a probe from an environment in memory, so `ibl render` works on a plain environment
 * image: what `ibl bake` would write, from the library's bake stages — the GGX chain
 * (specular.h, its own level mapping), the irradiance SH (sh.h) and the BRDF tables (brdf.h). */
#include "render_internal.h"
#include "core/context_internal.h"

#include "ibl/brdf.h"
#include "ibl/sh.h"
#include "ibl/specular.h"

#include <string.h>

enum { AB_NV = 16, AB_S = 24, AB_F0 = 8 };

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
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "render: no environment");
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
    ibl_specular_desc sd = {.filter = IBL_FILTER_GGX, .size = size, .levels = levels};
    ibl_specular_info info;
    if ((st = ibl_specular_prefilter(ctx, env, &sd, spec, &info)) != IBL_OK) goto fail;
    /* the bake's own mapping: level k was filtered for info.roughness[k] */
    out->mapping.levels = info.levels;
    for (int k = 0; k < info.levels; k++) out->mapping.roughness[k] = info.roughness[k];

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
