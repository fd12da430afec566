/* The specular prefilter's front: names, presets, the dispatcher (fast / reference / tri-Ace
 * kernels, mirror level, edge fixups) and the chain's description in KTX2 metadata. Design:
 * docs/SPECULAR.md; the bake folder's manifest is the bake module's (src/bake/bake*.c). */
#include "specular_internal.h"
#include "core/defaults.h"
#include "core/context_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *const filter_names[IBL_FILTER_COUNT] = {"ggx", "phong", "blinn", "box", "gauss"};
static const char *const mapping_names[IBL_MAPPING_COUNT] = {
    "default", "triace", "linear", "filament", "unreal", "unity", "babylon", "table"};

const char *ibl_specular_filter_name(ibl_specular_filter f)
{
    return (unsigned)f < IBL_FILTER_COUNT ? filter_names[f] : "unknown";
}

int ibl_specular_filter_from_name(const char *name, ibl_specular_filter *out)
{
    for (int i = 0; name && i < IBL_FILTER_COUNT; i++)
        if (strcmp(name, filter_names[i]) == 0) {
            *out = (ibl_specular_filter)i;
            return 1;
        }
    return 0;
}

const char *ibl_specular_mapping_name(ibl_specular_mapping m)
{
    return (unsigned)m < IBL_MAPPING_COUNT ? mapping_names[m] : "unknown";
}

int ibl_specular_mapping_from_name(const char *name, ibl_specular_mapping *out)
{
    for (int i = 0; name && i < IBL_MAPPING_COUNT; i++)
        if (strcmp(name, mapping_names[i]) == 0) {
            *out = (ibl_specular_mapping)i;
            return 1;
        }
    return 0;
}

/* tri-Ace 2010's "Implemented configurations", then the engines' defaults */
static const char *const preset_names[] = {
    "dynamic-box16", "dynamic-gauss32", "dynamic-phong16", "dynamic-phong32", "static-phong32",
    "static-phong64", "gltf", "filament", "unreal", "unity", NULL};

const char *const *ibl_specular_preset_names(void) { return preset_names; }

int ibl_specular_preset(const char *name, ibl_specular_desc *d)
{
    static const struct {
        ibl_specular_filter filter;
        int size;
        float smax;
        ibl_edge_fixup fixup;
        ibl_specular_mapping mapping;
    } table[] = {
        {IBL_FILTER_BOX, 16, 500, IBL_EDGE_FIXUP_OVERLAP, IBL_MAPPING_TRIACE},
        {IBL_FILTER_GAUSS, 32, 1000, IBL_EDGE_FIXUP_OVERLAP, IBL_MAPPING_TRIACE},
        /* the talk's ranges are the material's shininess, so its "Phong" chains are the
         * blinn filter (the Phong kernel of the Blinn-to-Phong fit, in material units) */
        {IBL_FILTER_BLINN, 16, 250, IBL_EDGE_FIXUP_BENT, IBL_MAPPING_TRIACE},
        {IBL_FILTER_BLINN, 32, 1000, IBL_EDGE_FIXUP_BENT, IBL_MAPPING_TRIACE},
        {IBL_FILTER_BLINN, 32, 1000, IBL_EDGE_FIXUP_BENT, IBL_MAPPING_TRIACE},
        {IBL_FILTER_BLINN, 64, 2000, IBL_EDGE_FIXUP_BENT, IBL_MAPPING_TRIACE},
        {IBL_FILTER_GGX, 256, 0, IBL_EDGE_FIXUP_NONE, IBL_MAPPING_LINEAR},
        {IBL_FILTER_GGX, 256, 0, IBL_EDGE_FIXUP_NONE, IBL_MAPPING_FILAMENT},
        {IBL_FILTER_GGX, 128, 0, IBL_EDGE_FIXUP_NONE, IBL_MAPPING_UNREAL},
        {IBL_FILTER_GGX, 128, 0, IBL_EDGE_FIXUP_NONE, IBL_MAPPING_UNITY},
    };
    for (int i = 0; name && preset_names[i]; i++) {
        if (strcmp(name, preset_names[i]) != 0) continue;
        memset(d, 0, sizeof *d);
        d->filter = table[i].filter;
        d->size = table[i].size;
        d->shininess_min = table[i].smax > 0 ? 1.0f : 0.0f;
        d->shininess_max = table[i].smax;
        d->edge_fixup = table[i].fixup;
        d->mapping = table[i].mapping;
        /* Filament's default chain stops at 16x16 (5 levels from 256), and so does the Khronos
         * glTF Sample Viewer's IBL sampler (lowestMipLevel 4: levels = log2(256) + 1 - 4,
         * roughness 1 on the 16x16 level); Unity's has 7 mips */
        if (table[i].mapping == IBL_MAPPING_FILAMENT || table[i].mapping == IBL_MAPPING_LINEAR)
            d->levels = 5;
        if (table[i].mapping == IBL_MAPPING_UNITY) d->levels = 7;
        /* the talk's dynamic configurations are refiltered every frame: the dynamic plan */
        d->dynamic = strncmp(name, "dynamic-", 8) == 0;
        return 1;
    }
    return 0;
}

void ibl__output_direction(const ibl_specular_desc *desc, const ibl__lobe *lobe, int face, int n,
                           int x, int y, double dir[3])
{
    if (desc->edge_fixup == IBL_EDGE_FIXUP_BENT || desc->edge_fixup == IBL_EDGE_FIXUP_WARP) {
        ibl_vec3 v = ibl_edge_fixup_texel_direction(desc->edge_fixup, &desc->bent, face, n, x, y,
                                                    (float)lobe->half_angle);
        double len = sqrt((double)v.x * v.x + (double)v.y * v.y + (double)v.z * v.z);
        dir[0] = v.x / len;
        dir[1] = v.y / len;
        dir[2] = v.z / len;
        return;
    }
    ibl_cube_direction_d(face, (x + 0.5) / n, (y + 0.5) / n, dir);
    double len = sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
    for (int i = 0; i < 3; i++) dir[i] /= len;
}

/* The levels asked for, or the full chain down to 1x1 ended early where the mapping has no
 * more distinct levels (the triace mapping at the bottom of its range). */
static int chain_levels(const ibl_specular_desc *desc, int size)
{
    int full = ibl_full_mip_count(size);
    if (desc->levels > 0) return desc->levels > full ? full : desc->levels;
    int distinct = ibl__mapping_distinct_levels(desc);
    return distinct < full ? distinct : full;
}

ibl_status ibl_specular_levels(ibl_context *ctx, const ibl_specular_desc *desc, int source_size,
                               ibl_specular_info *info)
{
    if (!ctx || !desc || !info) return IBL_ERR_INVALID_ARGUMENT;
    int size = desc->size > 0 ? desc->size : source_size;
    if (size < 1) return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "prefilter: no size");
    return ibl__specular_mapping(ctx, desc, size, chain_levels(desc, size), info);
}

static int is_pow2(int n) { return n > 0 && (n & (n - 1)) == 0; }

/* A mirror level (the unfiltered source) of the reference and the box/Gaussian kernels: the
 * source resampled to the level's edge, area-correct (ibl_cubemap_resample). */
static ibl_status mirror_level(ibl_context *ctx, const ibl_cubemap *src, ibl_cubemap *dst,
                               int level)
{
    int n = ibl_level_size(dst->size, level);
    if (n == src->size) {
        memcpy(ibl_cubemap_face(dst, level, 0), src->data, (size_t)6 * n * n * 4 * sizeof(float));
        return IBL_OK;
    }
    ibl_cubemap view; /* the level as a one-level cube: resampled in place */
    ibl_status st = ibl_cubemap_wrap(n, 1, ibl_cubemap_face(dst, level, 0), &view);
    return st == IBL_OK ? ibl_cubemap_resample(ctx, src, &view) : st;
}

/* What ibl_specular_prepare resolves from the desc and the source's edge alone. */
struct ibl_specular_prepared {
    ibl_context *ctx;
    ibl_specular_desc desc; /* size, levels and dynamic resolved; source_size: the working edge */
    ibl_specular_info info;
    int source_size;         /* the edge of the cubes it takes */
    int edge;                /* the working source's: a power of two */
    ibl_specular_plan *plan; /* the fast method's, for one run; NULL for the other methods */
    int used;
};

ibl_status ibl_specular_prepare(ibl_context *ctx, const ibl_specular_desc *desc_in,
                                int source_size, ibl_specular_prepared **out)
{
    if (!ctx || !desc_in || !out) return IBL_ERR_INVALID_ARGUMENT;
    *out = NULL;
    if (source_size < 1 || source_size > 16384)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "prefilter: source size %d out of range",
                         source_size);
    ibl_specular_desc desc = *desc_in;
    int N = desc.size > 0 ? desc.size : source_size;
    if (N < 1 || N > 16384)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "prefilter: size %d out of range", N);
    desc.size = N;
    desc.levels = chain_levels(&desc, N);
    ibl_specular_info info;
    ibl_status st = ibl__specular_mapping(ctx, &desc, N, desc.levels, &info);
    if (st != IBL_OK) return st;

    /* the dynamic plan (the dynamic presets) wants a power-of-two chain no larger than the
     * source; other sizes take the general code */
    int pow2 = 1;
    while (pow2 < source_size) pow2 *= 2;
    if (desc.dynamic && (desc.method == IBL_METHOD_REFERENCE || !is_pow2(N) || N > pow2)) desc.dynamic = 0;
    int box_or_gauss = desc.filter == IBL_FILTER_BOX || desc.filter == IBL_FILTER_GAUSS;
    int fast_plan = desc.method != IBL_METHOD_REFERENCE && !desc.dynamic && !box_or_gauss;
    /* the working source: level 0 of src at a power of two (the fast method's quadtree needs
     * one; the reference uses the same cube so both see one source). The fast plan's is the
     * edge the chain needs (ibl_specular_source_size): a larger source is reduced to it by
     * exact area means, so the plan, whose memory and time grow with its source's texels,
     * is built at that edge and not at the source's. */
    int edge = pow2;
    if (fast_plan) st = ibl_specular_source_size(ctx, &desc, source_size, &edge);
    if (st != IBL_OK) return st;
    ibl_specular_prepared *p = ibl_calloc(ctx, 1, sizeof *p);
    if (!p) return ibl_context_status(ctx);
    p->ctx = ctx;
    desc.source_size = edge;
    p->desc = desc;
    p->info = info;
    p->source_size = source_size;
    p->edge = edge;
    int plan_path = !(box_or_gauss && !desc.dynamic) && desc.method != IBL_METHOD_REFERENCE;
    if (plan_path) st = ibl__specular_plan_create(ctx, &p->desc, !desc.dynamic, &p->plan);
    if (st != IBL_OK) {
        ibl_specular_prepared_destroy(p);
        return st;
    }
    *out = p;
    return IBL_OK;
}

ibl_specular_plan *ibl__specular_prepared_plan(const ibl_specular_prepared *p, int *edge)
{
    *edge = p->edge;
    return p->plan;
}

void ibl_specular_prepared_destroy(ibl_specular_prepared *p)
{
    if (!p) return;
    ibl_specular_plan_destroy(p->plan);
    ibl_free(p->ctx, p);
}

/* The filtering itself, from the working source s (level 0 of edge p->edge) into out. */
static ibl_status filter_working(ibl_specular_prepared *p, const ibl_cubemap *s, ibl_cubemap *out)
{
    ibl_context *ctx = p->ctx;
    const ibl_specular_desc *desc = &p->desc;
    const ibl_specular_info *info = &p->info;
    int N = desc->size, L = desc->levels;
    ibl_status st = IBL_OK;
    if ((desc->filter == IBL_FILTER_BOX || desc->filter == IBL_FILTER_GAUSS) && !desc->dynamic) {
        float kernel_exponents[IBL_MAX_LEVELS];
        for (int l = 0; l < L; l++) kernel_exponents[l] = ibl_specular_level_phong_exponent(info, l);
        st = ibl_cubemap_alloc(ctx, N, L, out);
        if (st == IBL_OK)
            st = desc->filter == IBL_FILTER_BOX ? ibl__specular_box(ctx, s, out)
                                                : ibl__specular_gauss(ctx, s, out, kernel_exponents);
        if (st == IBL_OK && info->mirror) st = mirror_level(ctx, s, out, 0);
        for (int l = 0; st == IBL_OK && l < L; l++)
            st = ibl_edge_fixup_apply(ctx, desc->edge_fixup, out, l);
        return st;
    }
    if (desc->method == IBL_METHOD_REFERENCE) {
        st = ibl_cubemap_alloc(ctx, N, L, out);
        if (st == IBL_OK) st = ibl__specular_reference(ctx, s, desc, info, out);
        for (int l = 0; st == IBL_OK && l < L; l++) {
            if (ibl__level_is_mirror(info, l)) st = mirror_level(ctx, s, out, l);
            if (st == IBL_OK) st = ibl_edge_fixup_apply(ctx, desc->edge_fixup, out, l);
        }
        return st;
    }
    /* a plan's chain is allocated once its grids are summed: the pyramid's records and the
     * precomputed weights are freed by then and the chain takes their memory */
    st = ibl__specular_plan_run_grids(p->plan, s);
    if (st == IBL_OK) st = ibl_cubemap_alloc(ctx, N, L, out);
    if (st == IBL_OK) st = ibl__specular_plan_run_output(p->plan, s, out);
    ibl_specular_plan_destroy(p->plan);
    p->plan = NULL;
    /* a mirror level the plan could only point-sample (its size does not divide the
     * source's) is area-resampled here, as the reference does */
    for (int l = 0; st == IBL_OK && l < L; l++) {
        int n = ibl_level_size(N, l);
        if (!ibl__level_is_mirror(info, l) || n >= s->size || s->size % n == 0) continue;
        st = mirror_level(ctx, s, out, l);
        if (st == IBL_OK) st = ibl_edge_fixup_apply(ctx, desc->edge_fixup, out, l);
    }
    return st;
}

ibl_status ibl_specular_prefilter_prepared(ibl_specular_prepared *p, const ibl_cubemap *src,
                                           ibl_cubemap *out, ibl_specular_info *info_out)
{
    if (!p || !src || !src->data || !out) return IBL_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    ibl_context *ctx = p->ctx;
    if (p->used)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "prefilter: a prepared chain runs once");
    if (src->size != p->source_size)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                         "prefilter: prepared for a source of edge %d, given one of %d",
                         p->source_size, src->size);
    p->used = 1;
    ibl_cubemap work = {0};
    const ibl_cubemap *s = src;
    ibl_status st = IBL_OK;
    if (p->edge != src->size) {
        st = ibl_cubemap_alloc(ctx, p->edge, 1, &work);
        if (st == IBL_OK) st = ibl_cubemap_resample(ctx, src, &work);
        s = &work;
    } else if (src->levels > 1) {
        work = *src;
        work.levels = 1;
        work.owns_data = 0;
        s = &work;
    }
    if (st == IBL_OK) st = filter_working(p, s, out);
    if (work.owns_data) ibl_cubemap_free(ctx, &work);
    if (st != IBL_OK) {
        ibl_cubemap_free(ctx, out);
        memset(out, 0, sizeof *out);
    } else if (info_out) {
        *info_out = p->info;
    }
    return st;
}

ibl_status ibl_specular_prefilter(ibl_context *ctx, const ibl_cubemap *src,
                                  const ibl_specular_desc *desc, ibl_cubemap *out,
                                  ibl_specular_info *info)
{
    if (!ctx || !src || !src->data || !desc || !out) return IBL_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    ibl_specular_prepared *p = NULL;
    ibl_status st = ibl_specular_prepare(ctx, desc, src->size, &p);
    if (st == IBL_OK) st = ibl_specular_prefilter_prepared(p, src, out, info);
    ibl_specular_prepared_destroy(p);
    return st;
}

/* ---- metadata: a chain that describes itself ---- */

/* KTX2 key/values (specular.h): the filter, the mapping, the mirror flag, the Blinn factor,
 * the tri-Ace lod offset, and per level the GGX roughness or, for the Phong family, both the
 * material shininess and the Phong kernel exponent (0 marks a mirror level). */

static int is_phong_family(const ibl_specular_info *info) { return info->filter != IBL_FILTER_GGX; }

static double material_shininess(const ibl_specular_info *info, int l)
{
    return ibl_specular_level_shininess(info, l);
}

static double kernel_exponent(const ibl_specular_info *info, int l)
{
    return ibl_specular_level_phong_exponent(info, l);
}

typedef double (*level_value_fn)(const ibl_specular_info *info, int l);

static double roughness_of(const ibl_specular_info *info, int l) { return info->roughness[l]; }

static ibl_status set_level_list(ibl_context *ctx, ibl_texture *tex, const char *key,
                                 const ibl_specular_info *info, level_value_fn value)
{
    char buf[24 * IBL_MAX_LEVELS + 8];
    size_t pos = 0;
    for (int l = 0; l < info->levels; l++)
        pos += (size_t)snprintf(buf + pos, sizeof buf - pos, "%s%.9g", l ? " " : "", value(info, l));
    return ibl_texture_set_metadata(ctx, tex, key, buf);
}

ibl_status ibl_specular_set_metadata(ibl_context *ctx, const ibl_specular_info *info,
                                     ibl_texture *tex)
{
    if (!ctx || !info || !tex) return IBL_ERR_INVALID_ARGUMENT;
    char buf[64];
    ibl_status st = ibl_texture_set_metadata(ctx, tex, "ibl.specular.filter",
                                             ibl_specular_filter_name(info->filter));
    if (st == IBL_OK)
        st = ibl_texture_set_metadata(ctx, tex, "ibl.specular.mapping",
                                      ibl_specular_mapping_name(info->mapping));
    if (st == IBL_OK)
        st = ibl_texture_set_metadata(ctx, tex, "ibl.specular.mirror", info->mirror ? "1" : "0");
    if (st == IBL_OK) {
        snprintf(buf, sizeof buf, "%.9g", info->blinn_factor);
        st = ibl_texture_set_metadata(ctx, tex, "ibl.specular.blinn_factor", buf);
    }
    if (st == IBL_OK && info->mapping == IBL_MAPPING_TRIACE) {
        snprintf(buf, sizeof buf, "%.9g", info->lod_offset);
        st = ibl_texture_set_metadata(ctx, tex, "ibl.specular.lod_offset", buf);
    }
    if (st != IBL_OK) return st;
    if (!is_phong_family(info))
        return set_level_list(ctx, tex, "ibl.specular.roughness", info, roughness_of);
    st = set_level_list(ctx, tex, "ibl.specular.shininess", info, material_shininess);
    if (st == IBL_OK) st = set_level_list(ctx, tex, "ibl.specular.phong_exponent", info, kernel_exponent);
    return st;
}

/* Parses "v v v ..." into out (at most IBL_MAX_LEVELS); the count, or -1 if malformed. */
static int parse_level_list(const char *text, float *out)
{
    int n = 0;
    const char *p = text;
    while (*p) {
        while (*p == ' ') p++;
        if (!*p) break;
        char *end = NULL;
        double v = strtod(p, &end);
        if (end == p || n == IBL_MAX_LEVELS || !(v >= 0) || isinf(v)) return -1;
        out[n++] = (float)v;
        p = end;
    }
    return n;
}

ibl_status ibl_specular_info_from_metadata(ibl_context *ctx, const ibl_texture *tex,
                                           const char *name, ibl_specular_info *info)
{
    if (!tex || !info) return IBL_ERR_INVALID_ARGUMENT;
    if (!name) name = "chain";
    memset(info, 0, sizeof *info);
    const char *filter = ibl_texture_get_metadata(tex, "ibl.specular.filter");
    if (!filter) return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: no ibl.specular metadata", name);
    if (!ibl_specular_filter_from_name(filter, &info->filter))
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: ibl.specular.filter: unknown filter '%s'", name, filter);
    const char *mapping = ibl_texture_get_metadata(tex, "ibl.specular.mapping");
    if (!mapping || !ibl_specular_mapping_from_name(mapping, &info->mapping))
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: ibl.specular.mapping: missing or unknown", name);
    const char *mirror = ibl_texture_get_metadata(tex, "ibl.specular.mirror");
    info->mirror = mirror && strcmp(mirror, "1") == 0;
    const char *bf = ibl_texture_get_metadata(tex, "ibl.specular.blinn_factor");
    info->blinn_factor = bf ? strtof(bf, NULL) : IBL_DEFAULT_BLINN_FACTOR;
    if (!(info->blinn_factor > 0 && info->blinn_factor < 1e3f))
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: ibl.specular.blinn_factor: not a positive number", name);
    const char *a = ibl_texture_get_metadata(tex, "ibl.specular.lod_offset");
    if (a) info->lod_offset = strtof(a, NULL);
    /* the chain's own units (ibl_specular_level_shininess) */
    const char *key = info->filter == IBL_FILTER_GGX     ? "ibl.specular.roughness"
                      : info->filter == IBL_FILTER_PHONG ? "ibl.specular.phong_exponent"
                                                          : "ibl.specular.shininess";
    const char *list = ibl_texture_get_metadata(tex, key);
    float *values = info->filter == IBL_FILTER_GGX ? info->roughness : info->shininess;
    int n = list ? parse_level_list(list, values) : -1;
    if (n < 1 || n > tex->levels)
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: %s: %s", name, key,
                         n < 0 ? "missing or malformed" : "more values than the texture has levels");
    for (int l = 0; info->filter == IBL_FILTER_GGX && l < n; l++)
        if (info->roughness[l] > 1.0f)
            return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: %s: roughness %g above 1", name, key, info->roughness[l]);
    info->levels = n;
    info->size = tex->width;
    info->shininess_min = IBL_DEFAULT_SHININESS_MIN;
    info->shininess_max = IBL_DEFAULT_SHININESS_MAX;
    return IBL_OK;
}
