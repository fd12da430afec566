/* The bake in memory: every stage run on one environment (ibl_bake_compute), the runtime's
 * view of the result (ibl_bake_probe) and the table of the files a bake folder holds.
 * Writing and reading folders: bake_folder.c; the manifest: bake_manifest.c. */
#include "bake/bake_internal.h"
#include "bake/target_internal.h"
#include "core/context_internal.h"
#include "core/defaults.h"

#include "ibl/irradiance.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* ---- the folder's files ------------------------------------------------------------------ */

static const ibl__bake_file_info file_table[IBL__BAKE_FILE_COUNT] = {
    {"specular.ktx2", "specular", "cube, levels of the prefiltered chain"},
    {"specular.dds", "specular", "cube, levels of the prefiltered chain"},
    {"irradiance.ktx2", "irradiance", "cube, E/pi"},
    {"irradiance.dds", "irradiance", "cube, E/pi"},
    {"sh.json", "sh", "real SH, see its keys basis and axes"},
    {"brdf_lut.ktx2", "brdf_splitsum", "2d: x = n.v, y = roughness (texel centres)"},
    {"brdf_extra.ktx2", "brdf_multiscatter_sheen", "2d: x = n.v, y = roughness"},
    {"ambient_brdf.ktx2", "ambient_brdf", "3d: x = n.v, y = shininess (log), z = F0"},
    {"environment.png", "preview", "equirect, filmic tone map"},
    {"specular_atlas.ktx2", "specular_atlas", "2d: the chain's levels as a mip atlas (see atlas)"},
    {"specular_atlas.png", "specular_atlas", "2d: the same atlas, 8-bit RGBM (see atlas)"},
    {"manifest.json", "manifest", "this file"},
};

const ibl__bake_file_info *ibl__bake_file_info_of(ibl__bake_file file)
{
    return (unsigned)file < IBL__BAKE_FILE_COUNT ? &file_table[file] : NULL;
}

ibl__bake_file ibl__bake_file_named(const char *name)
{
    for (int i = 0; name && i < IBL__BAKE_FILE_COUNT; i++)
        if (strcmp(file_table[i].name, name) == 0) return (ibl__bake_file)i;
    return IBL__BAKE_FILE_COUNT;
}

int ibl__bake_has_file(const ibl_bake_data *b, ibl__bake_file file)
{
    switch (file) {
    case IBL__BAKE_SPECULAR_KTX2: return b->specular.data && (b->containers & IBL_BAKE_KTX2);
    case IBL__BAKE_SPECULAR_DDS: return b->specular.data && (b->containers & IBL_BAKE_DDS);
    case IBL__BAKE_IRRADIANCE_KTX2: return b->irradiance.data && (b->containers & IBL_BAKE_KTX2);
    case IBL__BAKE_IRRADIANCE_DDS: return b->irradiance.data && (b->containers & IBL_BAKE_DDS);
    case IBL__BAKE_SH_JSON: return b->sh.bands > 0;
    case IBL__BAKE_SPLITSUM: return b->splitsum.pixels != NULL;
    case IBL__BAKE_BRDF_EXTRA: return b->brdf_extra.pixels != NULL;
    case IBL__BAKE_AMBIENT_BRDF: return b->ambient_brdf.data != NULL;
    case IBL__BAKE_PREVIEW: return b->preview.pixels != NULL;
    case IBL__BAKE_ATLAS_KTX2: return b->atlas.pixels != NULL;
    case IBL__BAKE_ATLAS_PNG: return b->atlas.pixels != NULL;
    case IBL__BAKE_MANIFEST: return 1;
    case IBL__BAKE_FILE_COUNT: break;
    }
    return 0;
}

int ibl_bake_files(const ibl_bake_data *b, const char **names, int max)
{
    int n = 0;
    for (int i = 0; b && i < IBL__BAKE_FILE_COUNT; i++)
        if (ibl__bake_has_file(b, (ibl__bake_file)i)) {
            if (n < max) names[n] = file_table[i].name;
            n++;
        }
    return n;
}

/* ---- compute ------------------------------------------------------------------------------ */

static double now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

/* Defaults resolved once: a zero field of desc becomes its documented value. */
static ibl_bake_desc resolve_desc(const ibl_bake_desc *in)
{
    ibl_bake_desc d;
    if (in) d = *in;
    else memset(&d, 0, sizeof d);
    if (d.irradiance_size <= 0) d.irradiance_size = IBL_DEFAULT_IRRADIANCE_SIZE;
    if (d.sh_bands <= 0) d.sh_bands = IBL_DEFAULT_SH_BANDS;
    if (d.lut_size <= 0) d.lut_size = IBL_DEFAULT_LUT_SIZE;
    if (d.format == IBL_FORMAT_DEFAULT) d.format = IBL_FORMAT_RGBA16F;
    if (d.containers == 0) d.containers = IBL_BAKE_KTX2 | IBL_BAKE_DDS;
    if (d.preview_width == 0) d.preview_width = IBL_DEFAULT_PREVIEW_WIDTH;
    return d;
}

static ibl_status stage_specular(ibl_context *ctx, const ibl_cubemap *env, const ibl_bake_desc *d,
                                 ibl_bake_data *b)
{
    ibl_status st = ibl_specular_prefilter(ctx, env, &d->specular, &b->specular, &b->specular_info);
    if (st == IBL_OK && d->specular_sources) st = ibl_specular_sources_apply(d->specular_sources, &b->specular);
    if (st == IBL_OK && d->atlas) st = ibl_atlas_pack(ctx, &b->specular, NULL, &b->atlas, &b->atlas_layout);
    return st;
}

static ibl_status stage_diffuse(ibl_context *ctx, const ibl_cubemap *env, const ibl_bake_desc *d,
                                ibl_bake_data *b)
{
    ibl_irradiance_desc id = {.size = d->irradiance_size};
    ibl_status st = ibl_irradiance_cubemap(ctx, env, &id, &b->irradiance);
    if (st == IBL_OK) st = ibl_sh_project_cubemap(ctx, env, 0, d->sh_bands, &b->sh);
    if (st == IBL_OK) st = ibl_sh_apply_window(&b->sh, d->sh_window, d->sh_window_width, &b->sh_window);
    return st;
}

/* The AmbientBRDF's shininess axis [lo, hi] as the volume is computed: the materials it
 * serves are those of the caller's range, or 1..100000 (every Blinn-Phong material, whatever
 * the chain: a material of shininess 1 on a box chain whose widest level is 4 still needs the
 * albedo at 1). The range is widened by half a row at each end so that the first and last
 * row centres (where a lookup stops interpolating) fall on the materials' extremes. */
static void ambient_range(const ibl_bake_desc *d, int rows, double *lo, double *hi)
{
    double smin = d->ambient.shininess_min, smax = d->ambient.shininess_max;
    if (!(smin > 0)) smin = IBL_DEFAULT_AMBIENT_SHININESS_MIN;
    if (!(smax > smin)) smax = smin < IBL_DEFAULT_AMBIENT_SHININESS_MAX ? IBL_DEFAULT_AMBIENT_SHININESS_MAX : 2.0 * smin;
    double half = rows > 1 ? 0.5 / (rows - 1) : 0.0;
    if (d->ambient.spacing == IBL_SHININESS_LOG) {
        double ratio = pow(smax / smin, half);
        *lo = smin / ratio;
        *hi = smax * ratio;
    } else {
        double step = (smax - smin) * half;
        *lo = smin - step > 0 ? smin - step : smin;
        *hi = smax + step;
    }
}

/* An axis of n texel centres over [lo, hi] (linear) or log-spaced over [lo, hi]. */
static ibl_table_axis centred_axis(int n, double lo, double hi, int logarithmic)
{
    double t0 = 0.5 / n, t1 = 1.0 - 0.5 / n;
    ibl_table_axis a = {n, 0, 0, logarithmic};
    if (logarithmic) {
        a.first = (float)(lo * pow(hi / lo, t0));
        a.last = (float)(lo * pow(hi / lo, t1));
    } else {
        a.first = (float)(lo + (hi - lo) * t0);
        a.last = (float)(lo + (hi - lo) * t1);
    }
    return a;
}

static ibl_status stage_brdf(ibl_context *ctx, const ibl_bake_desc *d, ibl_bake_data *b)
{
    ibl_brdf_lut_desc ld = {.size = d->lut_size};
    ibl_status st = ibl_brdf_lut(ctx, &ld, &b->splitsum);
    if (st != IBL_OK) return st;
    b->splitsum_n_dot_v = b->splitsum_roughness = centred_axis(d->lut_size, 0.0, 1.0, 0);
    /* the directional albedo E is A + B of the table just made (Karis 2013's split sum with
     * F = 1): summed here rather than integrated a second time, a third of the stage's cost */
    ld.channels[0] = IBL_BRDF_ZERO;
    ld.channels[1] = IBL_BRDF_ALBEDO_AVG;
    ld.channels[2] = IBL_BRDF_SHEEN;
    ld.channels[3] = IBL_BRDF_SHEEN_AVG;
    st = ibl_brdf_lut(ctx, &ld, &b->brdf_extra);
    if (st != IBL_OK) return st;
    size_t texels = (size_t)b->brdf_extra.width * b->brdf_extra.height;
    for (size_t i = 0; i < texels; i++)
        b->brdf_extra.pixels[i * 4] = b->splitsum.pixels[i * 4] + b->splitsum.pixels[i * 4 + 1];
    if (d->ambient_brdf < 0) return st;
    ibl_ambient_brdf_desc ad = d->ambient;
    if (ad.size_shininess == 0) ad.size_shininess = IBL_DEFAULT_AMBIENT_ROWS;
    double lo, hi;
    ambient_range(d, ad.size_shininess, &lo, &hi);
    ad.shininess_min = lo;
    ad.shininess_max = hi;
    st = ibl_ambient_brdf_volume(ctx, &ad, &b->ambient_brdf);
    if (st != IBL_OK) return st;
    /* the volume's own resolved sizes (ibl_ambient_brdf_volume's defaults) */
    b->ambient_n_dot_v = centred_axis(b->ambient_brdf.width, 0.0, 1.0, 0);
    b->ambient_shininess = centred_axis(b->ambient_brdf.height, lo, hi, ad.spacing == IBL_SHININESS_LOG);
    b->ambient_f0 = centred_axis(b->ambient_brdf.depth, 0.0, 1.0, 0);
    b->ambient_normalization = ad.normalization;
    return IBL_OK;
}

static ibl_status stage_preview(ibl_context *ctx, const ibl_cubemap *env, const ibl_bake_desc *d,
                                ibl_bake_data *b)
{
    if (d->preview_width < 0) return IBL_OK;
    ibl_from_cube_desc fd = {.layout = IBL_LAYOUT_EQUIRECT, .width = d->preview_width};
    return ibl_cubemap_to_image(ctx, env, &fd, &b->preview);
}

static ibl_status keep_environment(ibl_context *ctx, const ibl_cubemap *env, ibl_bake_data *b)
{
    ibl_status st = ibl_cubemap_alloc(ctx, env->size, 1, &b->environment);
    if (st == IBL_OK)
        memcpy(b->environment.data, env->data, ibl_cubemap_floats(env->size, 1) * sizeof(float));
    return st;
}

/* The provenance and the resolved parameters, copied into the bake. */
static ibl_status record_parameters(ibl_context *ctx, const ibl_cubemap *env,
                                    const ibl_bake_desc *d, ibl_bake_data *b)
{
    b->edge_fixup = d->specular.edge_fixup;
    b->irradiance_size = d->irradiance_size;
    b->sh_bands = d->sh_bands;
    b->lut_size = d->lut_size;
    b->working_size = env->size;
    b->sh_window_requested = d->sh_window;
    b->sh_window_width = d->sh_window_width;
    b->format = d->format;
    b->quality = d->quality;
    b->zstd_level = d->zstd_level;
    b->containers = d->containers;
    b->rgbm_range = d->rgbm_range > 0.0f ? d->rgbm_range : IBL_RGBM_DEFAULT_RANGE;
    b->dds_header = d->dds_header;
    b->source_layout = d->source.layout;
    b->source_orientation = d->source.orientation;
    b->target = d->target;
    if (d->source.sky) {
        ibl_sky_model model;
        ibl_status st = ibl_sky_model_init(ctx, d->source.sky, &model);
        if (st != IBL_OK) return st;
        b->has_sky = 1;
        b->sky = model.desc;
    }
    const char *name = d->source.name ? d->source.name : d->source.sky ? "built-in sky" : "environment";
    b->source_name = ibl__strdup(ctx, name);
    b->preset = ibl__strdup(ctx, d->preset);
    b->units = ibl__strdup(ctx, d->units);
    if (!b->source_name || (d->preset && !b->preset) || (d->units && !b->units))
        return ibl_context_status(ctx);
    return IBL_OK;
}

/* Texels of a cube with a colour channel past max (what the writer will clamp). */
static uint64_t count_over(const ibl_cubemap *c, float max)
{
    uint64_t n = 0;
    size_t texels = c->data ? ibl_cubemap_floats(c->size, c->levels) / 4 : 0;
    for (size_t i = 0; i < texels; i++) {
        const float *p = c->data + i * 4;
        n += (uint64_t)(p[0] > max || p[1] > max || p[2] > max);
    }
    return n;
}

ibl_status ibl_bake_compute(ibl_context *ctx, const ibl_cubemap *env, const ibl_bake_desc *desc,
                            ibl_bake_data *out)
{
    if (!out) return IBL_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    if (!env || !env->data || env->size < 1)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "bake: no environment");
    ibl_bake_desc d = resolve_desc(desc);
    if (d.containers & ~(unsigned)(IBL_BAKE_KTX2 | IBL_BAKE_DDS))
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "bake: unknown containers 0x%x", d.containers);
    if (d.target != IBL_TARGET_NONE) {
        ibl_status st = ibl__target_check(ctx, d.target, &d.specular, env->size);
        if (st != IBL_OK) return st;
        /* the skybox and the equirect EXR are made from the unfiltered environment */
        if (ibl_target_profile_of(d.target)->files & (IBL_TARGET_FILE_FILAMENT | IBL_TARGET_FILE_EQUIRECT_EXR))
            d.keep_environment = 1;
    }
    /* the storage settings are checked before any work, not when the files are written */
    if (!ibl_file_type_writes_format(IBL_FILE_KTX2, d.format) ||
        ((d.containers & IBL_BAKE_DDS) && !ibl_file_type_writes_format(IBL_FILE_DDS, d.format)))
        return ibl__fail(ctx, IBL_ERR_UNSUPPORTED, "bake: %s cubes cannot be stored in %s (DDS "
                         "holds neither ASTC nor the 8-bit encodings: bake KTX2 only)",
                         ibl_format_name(d.format), (d.containers & IBL_BAKE_DDS) ? "DDS" : "KTX2");
    if ((unsigned)d.quality > IBL_QUALITY_THOROUGH || d.zstd_level < 0 || d.zstd_level > 22 ||
        !(d.rgbm_range >= 0.0f && d.rgbm_range <= 65504.0f))
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                         "bake: invalid storage settings (quality %d, zstd level %d, RGBM range %g)",
                         (int)d.quality, d.zstd_level, (double)d.rgbm_range);
    double t0 = now_ms(), t = t0;
    ibl_status st = record_parameters(ctx, env, &d, out);
    if (st == IBL_OK) st = stage_specular(ctx, env, &d, out);
    /* the glTF target's sheen chain (target_sheen.c): at most 64 texels, the chain's levels */
    if (st == IBL_OK && d.target != IBL_TARGET_NONE &&
        (ibl_target_profile_of(d.target)->files & IBL_TARGET_FILE_GLTF))
        st = ibl_charlie_prefilter(ctx, env, out->specular.size < 64 ? out->specular.size : 64,
                                   out->specular.levels, &out->sheen);
    if (st == IBL_OK) out->timing_ms.specular = now_ms() - t, t = now_ms();
    if (st == IBL_OK) st = ibl__progress(ctx, "bake", 0.7);
    if (st == IBL_OK) st = stage_diffuse(ctx, env, &d, out);
    if (st == IBL_OK) out->timing_ms.diffuse = now_ms() - t, t = now_ms();
    if (st == IBL_OK) st = ibl__progress(ctx, "bake", 0.8);
    if (st == IBL_OK) st = stage_brdf(ctx, &d, out);
    if (st == IBL_OK) out->timing_ms.brdf = now_ms() - t, t = now_ms();
    if (st == IBL_OK) st = ibl__progress(ctx, "bake", 0.9);
    if (st == IBL_OK) st = stage_preview(ctx, env, &d, out);
    if (st == IBL_OK && d.keep_environment) st = keep_environment(ctx, env, out);
    if (st == IBL_OK) out->timing_ms.preview = now_ms() - t;
    if (st == IBL_OK) {
        float max = ibl_format_max_value(d.format);
        out->clamped_texels = count_over(&out->specular, max) + count_over(&out->irradiance, max);
    }
    out->timing_ms.total = now_ms() - t0;
    if (st != IBL_OK) ibl_bake_free(ctx, out);
    return st;
}

void ibl_bake_free(ibl_context *ctx, ibl_bake_data *b)
{
    if (!b) return;
    ibl_cubemap_free(ctx, &b->specular);
    ibl_cubemap_free(ctx, &b->sheen);
    ibl_cubemap_free(ctx, &b->irradiance);
    ibl_cubemap_free(ctx, &b->environment);
    ibl_image_free(ctx, &b->splitsum);
    ibl_image_free(ctx, &b->brdf_extra);
    ibl_image_free(ctx, &b->preview);
    ibl_image_free(ctx, &b->atlas);
    ibl_texture_free(ctx, &b->ambient_brdf);
    ibl_free(ctx, b->source_name);
    ibl_free(ctx, b->preset);
    ibl_free(ctx, b->units);
    memset(b, 0, sizeof *b);
}

/* ---- the runtime's view ------------------------------------------------------------------- */

ibl_status ibl_bake_probe(ibl_context *ctx, const ibl_bake_data *b, ibl_probe *p)
{
    if (!p) return IBL_ERR_INVALID_ARGUMENT;
    memset(p, 0, sizeof *p);
    if (!b || !b->specular.data)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "bake: no prefiltered chain");
    const ibl_specular_info *info = &b->specular_info;
    p->specular = b->specular;
    p->specular.owns_data = 0;
    p->mapping.levels = info->levels < b->specular.levels ? info->levels : b->specular.levels;
    for (int k = 0; k < p->mapping.levels; k++) {
        if (info->filter == IBL_FILTER_GGX) {
            p->mapping.roughness[k] = info->roughness[k];
        } else {
            float s = ibl_specular_level_shininess(info, k);
            p->mapping.shininess[k] = s > 0.0f ? s : IBL_MIRROR_SHININESS;
        }
    }
    if (b->environment.data) {
        p->mirror = b->environment;
        p->mirror.owns_data = 0;
    }
    for (int i = 0; i < 9; i++)
        for (int c = 0; c < 3; c++) p->sh[i][c] = i < b->sh.bands * b->sh.bands ? (float)b->sh.c[i][c] : 0.0f;
    if (b->irradiance.data) {
        p->irradiance = b->irradiance;
        p->irradiance.owns_data = 0;
        p->sh_kind = IBL_SH_KIND_NONE;
    } else {
        p->sh_kind = b->sh.bands > 0 ? IBL_SH_KIND_RADIANCE : IBL_SH_KIND_NONE;
    }
    if (b->splitsum.pixels)
        p->splitsum = (ibl_splitsum_view){b->splitsum.pixels, 4, b->splitsum_n_dot_v, b->splitsum_roughness};
    if (b->ambient_brdf.data)
        p->ambient_brdf = (ibl_ambient_brdf_view){b->ambient_brdf.data, 4, b->ambient_n_dot_v,
                                                  b->ambient_shininess, b->ambient_f0};
    if (b->atlas.pixels) { /* offered, not used: the caller sets probe.use_atlas */
        p->atlas = &b->atlas;
        p->atlas_layout = &b->atlas_layout;
    }
    return ibl_probe_validate(ctx, p);
}
