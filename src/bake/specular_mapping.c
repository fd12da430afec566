/* Level <-> roughness / shininess presets. Each formula cites where it comes from; the
 * inverse mappings (roughness of a level) are solved from the engines' lod-of-roughness. */
#include "specular_internal.h"
#include "core/defaults.h"
#include "core/context_internal.h"

#include <math.h>
#include <string.h>

/* GGX roughness of level l of a chain of L levels, edge `size`, for a roughness mapping. */
static double mapped_roughness(ibl_specular_mapping m, int l, int L, int size, double babylon_scale)
{
    double last = L > 1 ? L - 1 : 1;
    double lod = l / last, r;
    switch (m) {
    case IBL_MAPPING_FILAMENT:
        /* Filament IBLPrefilterContext / cmgen: lod / (levels - 1) = r (2 - r), inverted:
         * lodToPerceptualRoughness(lod) = 1 - sqrt(1 - lod) */
        r = 1.0 - sqrt(1.0 - (lod > 1 ? 1 : lod));
        break;
    case IBL_MAPPING_UNREAL: {
        /* UE4 ReflectionEnvironmentShared.usf: ComputeReflectionCaptureRoughnessFromMip,
         * LevelFrom1x1 = CubemapMaxMip - 1 - mip, r = 2^((1 - LevelFrom1x1) / 1.2) */
        double from1x1 = (L - 1) - l;
        r = pow(2.0, (1.0 - from1x1) / 1.2);
        break;
    }
    case IBL_MAPPING_UNITY:
        /* Unity ImageBasedLighting.hlsl: mip = r (1.7 - 0.7 r) * UNITY_SPECCUBE_LOD_STEPS (6),
         * solved for r */
        if (l >= 6) r = 1.0;
        else r = (1.7 - sqrt(1.7 * 1.7 - 2.8 * l / 6.0)) / 1.4;
        break;
    case IBL_MAPPING_BABYLON:
        /* Babylon.js HDRFiltering: alphaG = 2^(lod / lodGenerationScale) / width (the scale
         * is 0.8 unless the texture says otherwise), lod 0 unfiltered; alpha = r^2 */
        if (l == 0) r = 0.0;
        else r = sqrt(pow(2.0, l / babylon_scale) / size);
        break;
    case IBL_MAPPING_LINEAR:
    default:
        /* glTF-Sample-Viewer / KhronosGroup IBL-Sampler: roughness = lod / (levels - 1) */
        r = L > 1 ? lod : 0.0;
        break;
    }
    if (r > 1.0) r = 1.0;
    if (r < 0.0) r = 0.0;
    return r;
}

/* tri-Ace 2010's lod = a - 0.5 log2(shininess) with a = 0.5 log2(max): level 0 is the
 * sharpest lobe of the range, each level 4x less shiny, the last one at the minimum. */
static double triace_shininess(int l, double smin, double smax)
{
    double s = smax / pow(4.0, l);
    return s < smin ? smin : s;
}

/* ---- units ---- */

static int kernel_units(ibl_specular_filter filter) { return filter == IBL_FILTER_PHONG; }

static double factor_of(const ibl_specular_info *info)
{
    return info->blinn_factor > 0 ? info->blinn_factor : IBL_DEFAULT_BLINN_FACTOR;
}

static int phong_level(const ibl_specular_info *info, int level)
{
    return info && info->filter != IBL_FILTER_GGX && level >= 0 && level < info->levels &&
           info->shininess[level] > 0.0f;
}

double ibl__level_phong_exponent(const ibl_specular_info *info, int level)
{
    if (!phong_level(info, level)) return 0.0;
    double s = info->shininess[level];
    return kernel_units(info->filter) ? s : s / factor_of(info);
}

float ibl_specular_level_shininess(const ibl_specular_info *info, int level)
{
    if (!phong_level(info, level)) return 0.0f;
    double s = info->shininess[level];
    return (float)(kernel_units(info->filter) ? s * factor_of(info) : s);
}

float ibl_specular_level_phong_exponent(const ibl_specular_info *info, int level)
{
    return (float)ibl__level_phong_exponent(info, level);
}

int ibl__mapping_distinct_levels(const ibl_specular_desc *desc)
{
    ibl_specular_mapping m = desc->mapping;
    if (m == IBL_MAPPING_DEFAULT) m = desc->filter == IBL_FILTER_GGX ? IBL_MAPPING_LINEAR : IBL_MAPPING_TRIACE;
    /* the box chain's levels carry their own fitted shininess: every level is distinct */
    if (m != IBL_MAPPING_TRIACE || desc->filter == IBL_FILTER_BOX) return IBL_MAX_LEVELS;
    double smin = desc->shininess_min > 0 ? desc->shininess_min : IBL_DEFAULT_SHININESS_MIN;
    double smax = desc->shininess_max > 0 ? desc->shininess_max : IBL_DEFAULT_SHININESS_MAX;
    /* level l has max / 4^l until that reaches the minimum: the level that reaches it is the
     * last distinct one (tri-Ace 2010 ties the chain's end to the range's end) */
    int n = 1;
    while (n < IBL_MAX_LEVELS && smax / pow(4.0, n - 1) > smin) n++;
    return n + (desc->mirror ? 1 : 0);
}

/* a of tri-Ace 2010's lod = a - 0.5 log2(s), s in the chain's units. For the levels the
 * mapping makes it is exact: a = 0.5 log2(max), one more when a mirror level comes first. The
 * box chain's levels are fitted rather than chosen, so its a is the least-squares fit over
 * its levels, a = mean(l + 0.5 log2 s_l), as the talk fits a per size and kernel. */
static float triace_lod_offset(const ibl_specular_info *info, int shift)
{
    if (info->filter != IBL_FILTER_BOX) return (float)(0.5 * log2(info->shininess_max) + shift);
    double sum = 0;
    int count = 0;
    for (int l = 0; l < info->levels; l++)
        if (info->shininess[l] > 0) sum += l + 0.5 * log2(info->shininess[l]), count++;
    return count ? (float)(sum / count) : 0.0f;
}

ibl_status ibl__specular_mapping(ibl_context *ctx, const ibl_specular_desc *desc, int size,
                                 int levels, ibl_specular_info *info)
{
    memset(info, 0, sizeof *info);
    if (levels < 1 || levels > IBL_MAX_LEVELS)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "prefilter: %d levels out of range", levels);
    if ((unsigned)desc->filter >= IBL_FILTER_COUNT)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "prefilter: unknown filter %d", desc->filter);
    info->filter = desc->filter;
    info->size = size;
    info->levels = levels;
    info->mirror = desc->mirror != 0;
    info->blinn_factor = desc->blinn_factor > 0 ? desc->blinn_factor : IBL_DEFAULT_BLINN_FACTOR;
    info->shininess_min = desc->shininess_min > 0 ? desc->shininess_min : IBL_DEFAULT_SHININESS_MIN;
    info->shininess_max = desc->shininess_max > 0 ? desc->shininess_max : IBL_DEFAULT_SHININESS_MAX;
    if (info->shininess_max < info->shininess_min)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "prefilter: shininess range %g-%g is empty",
                        info->shininess_min, info->shininess_max);
    ibl_specular_mapping m = desc->mapping;
    if ((unsigned)m >= IBL_MAPPING_COUNT)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "prefilter: unknown mapping %d", m);
    if (m == IBL_MAPPING_DEFAULT) m = desc->filter == IBL_FILTER_GGX ? IBL_MAPPING_LINEAR : IBL_MAPPING_TRIACE;
    info->mapping = m;
    if (m == IBL_MAPPING_BABYLON) {
        if (desc->babylon_lod_scale < 0 || !(desc->babylon_lod_scale < 100.0f))
            return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                             "prefilter: the babylon lod scale %g is not in (0, 100)",
                             (double)desc->babylon_lod_scale);
        info->babylon_lod_scale = desc->babylon_lod_scale > 0 ? desc->babylon_lod_scale : 0.8f;
    }
    int distinct = ibl__mapping_distinct_levels(desc);
    if (levels > distinct)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                         "prefilter: the triace mapping over shininess %g-%g has %d distinct "
                         "levels%s; %d levels would repeat the last (ask for at most %d, or widen "
                         "the range)", info->shininess_min, info->shininess_max, distinct,
                         info->mirror ? " with the mirror level" : "", levels, distinct);
    if (m == IBL_MAPPING_TABLE) {
        if (!desc->table || desc->table_count != levels)
            return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                            "prefilter: the mapping table has %d values for %d levels",
                            desc->table ? desc->table_count : 0, levels);
        for (int l = 0; l < levels; l++)
            if (!(desc->table[l] >= 0) || isinf(desc->table[l]))
                return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                                "prefilter: mapping table value %d (%g) is not a finite value >= 0",
                                l, desc->table[l]);
    }
    /* --mirror: level 0 is the unfiltered source. The tri-Ace shininess chain then starts at
     * level 1 (the talk's "mirror reflection option" adds the sharp end); the roughness
     * mappings keep their levels and only level 0 becomes the mirror (most already put
     * roughness 0 there). */
    int first = info->mirror ? 1 : 0;
    int shift = info->mirror && m == IBL_MAPPING_TRIACE;
    int L = levels - shift; /* levels the mapping spreads over */
    int ggx = desc->filter == IBL_FILTER_GGX;
    for (int l = 0; l < levels; l++) {
        if (l < first) {
            info->roughness[l] = 0.0f;
            info->shininess[l] = 0.0f; /* 0: mirror (unfiltered) */
            continue;
        }
        int ml = l - shift;
        if (m == IBL_MAPPING_TABLE) {
            if (ggx) info->roughness[l] = desc->table[l] > 1 ? 1.0f : desc->table[l];
            else info->shininess[l] = desc->table[l];
            continue;
        }
        if (desc->filter == IBL_FILTER_BOX && m == IBL_MAPPING_TRIACE) {
            /* box: what the level really holds, the Phong lobe fitted by least squares to the
             * box-plus-bilinear kernel (specular_box.c), as the material's shininess */
            info->shininess[l] = info->blinn_factor * ibl__box_level_shininess(size, l);
            continue;
        }
        if (m == IBL_MAPPING_TRIACE) {
            double s = triace_shininess(ml, info->shininess_min, info->shininess_max);
            if (ggx) info->roughness[l] = (float)pow(2.0 / (s + 2.0), 0.25);
            else info->shininess[l] = (float)s;
            continue;
        }
        double r = mapped_roughness(m, ml, L, size, info->babylon_lod_scale > 0 ? info->babylon_lod_scale : 0.8);
        if (ggx) {
            info->roughness[l] = (float)r;
        } else {
            /* roughness presets for the Phong family: the Blinn-Phong exponent equivalent to
             * Beckmann/GGX alpha, s = 2 / alpha^2 - 2 (Walter et al. 2007, eq. 33), in the
             * chain's units (a phong chain's are kernel exponents, s / blinn_factor) */
            double a = r * r;
            double sh = a > 0 ? 2.0 / (a * a) - 2.0 : 0.0;
            if (kernel_units(desc->filter)) sh /= info->blinn_factor;
            info->shininess[l] = a > 0 ? (float)sh : 0.0f;
            if (a > 0 && info->shininess[l] < 1e-3f) info->shininess[l] = 1e-3f;
        }
    }
    if (m == IBL_MAPPING_TRIACE) info->lod_offset = triace_lod_offset(info, shift);
    return IBL_OK;
}
