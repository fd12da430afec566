/* The specular prefilter's front: names, presets, the dispatcher (fast / reference / seed
 * kernels, mirror level, edge fixups) and what is written beside the result (KTX2 metadata,
 * manifest.json). Design: docs/SPECULAR.md. */
#include "specular_internal.h"
#include "core/context_internal.h"

#include <math.h>
#include <stdio.h>
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

/* seeds 000/001 "Implemented configurations", then the engines' defaults */
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
        {IBL_FILTER_PHONG, 16, 250, IBL_EDGE_FIXUP_BENT, IBL_MAPPING_TRIACE},
        {IBL_FILTER_PHONG, 32, 1000, IBL_EDGE_FIXUP_BENT, IBL_MAPPING_TRIACE},
        {IBL_FILTER_PHONG, 32, 1000, IBL_EDGE_FIXUP_BENT, IBL_MAPPING_TRIACE},
        {IBL_FILTER_PHONG, 64, 2000, IBL_EDGE_FIXUP_BENT, IBL_MAPPING_TRIACE},
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
        /* Filament's default chain stops at 16x16 (5 levels from 256); Unity's has 7 mips */
        if (table[i].mapping == IBL_MAPPING_FILAMENT) d->levels = 5;
        if (table[i].mapping == IBL_MAPPING_UNITY) d->levels = 7;
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

static int chain_levels(const ibl_specular_desc *desc, int size)
{
    int full = ibl_full_mip_count(size);
    int levels = desc->levels > 0 ? desc->levels : full;
    return levels > full ? full : levels;
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

/* Mirror levels of the reference and the seed kernels: the source area-resampled. */
static ibl_status mirror_level(ibl_context *ctx, const ibl_cubemap *src, ibl_cubemap *dst,
                               int level)
{
    int n = ibl_level_size(dst->size, level);
    if (n == src->size) {
        memcpy(ibl_cubemap_face(dst, level, 0), src->data, (size_t)6 * n * n * 4 * sizeof(float));
        return IBL_OK;
    }
    if (n < src->size && src->size % n == 0) {
        /* exact area average of the r x r source texels under each output texel */
        int r = src->size / n, m = src->size;
        for (int f = 0; f < 6; f++) {
            const float *sp = ibl_cubemap_face(src, 0, f);
            float *dp = ibl_cubemap_face(dst, level, f);
            for (int y = 0; y < n; y++)
                for (int x = 0; x < n; x++) {
                    double acc[4] = {0, 0, 0, 0}, w = 0;
                    for (int j = 0; j < r; j++)
                        for (int i = 0; i < r; i++) {
                            int sx = x * r + i, sy = y * r + j;
                            double o = ibl_cube_texel_solid_angle(m, sx, sy);
                            const float *q = sp + ((size_t)sy * m + sx) * 4;
                            for (int c = 0; c < 4; c++) acc[c] += o * q[c];
                            w += o;
                        }
                    for (int c = 0; c < 4; c++) dp[((size_t)y * n + x) * 4 + c] = (float)(acc[c] / w);
                }
        }
        return IBL_OK;
    }
    ibl_cubemap tmp;
    ibl_status st = ibl_cubemap_alloc(ctx, n, 1, &tmp);
    if (st != IBL_OK) return st;
    st = ibl_cubemap_resample(ctx, src, &tmp);
    if (st == IBL_OK)
        memcpy(ibl_cubemap_face(dst, level, 0), tmp.data, (size_t)6 * n * n * 4 * sizeof(float));
    ibl_cubemap_free(ctx, &tmp);
    return st;
}

ibl_status ibl_specular_prefilter(ibl_context *ctx, const ibl_cubemap *src,
                                  const ibl_specular_desc *desc_in, ibl_cubemap *out,
                                  ibl_specular_info *info_out)
{
    if (!ctx || !src || !src->data || !desc_in || !out) return IBL_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    ibl_specular_desc desc = *desc_in;
    int N = desc.size > 0 ? desc.size : src->size;
    if (N < 1 || N > 16384)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "prefilter: size %d out of range", N);
    desc.size = N;
    int L = chain_levels(&desc, N);
    desc.levels = L;
    ibl_specular_info info;
    ibl_status st = ibl__specular_mapping(ctx, &desc, N, L, &info);
    if (st != IBL_OK) return st;

    /* the working source: level 0 of src, resampled to a power of two if needed (the fast
     * method's quadtree needs one; the reference uses the same cube so both see one source) */
    ibl_cubemap work = {0};
    const ibl_cubemap *s = src;
    if (!is_pow2(src->size)) {
        int p = 1;
        while (p < src->size) p *= 2;
        st = ibl_cubemap_alloc(ctx, p, 1, &work);
        if (st != IBL_OK) return st;
        st = ibl_cubemap_resample(ctx, src, &work);
        if (st != IBL_OK) goto done;
        s = &work;
    } else if (src->levels > 1) {
        work = *src;
        work.levels = 1;
        work.owns_data = 0;
        s = &work;
    }
    st = ibl_cubemap_alloc(ctx, N, L, out);
    if (st != IBL_OK) goto done;

    if (desc.filter == IBL_FILTER_BOX || desc.filter == IBL_FILTER_GAUSS) {
        st = desc.filter == IBL_FILTER_BOX ? ibl__specular_box(ctx, s, out)
                                           : ibl__specular_gauss(ctx, s, out, info.shininess);
        if (st == IBL_OK && info.mirror) st = mirror_level(ctx, s, out, 0);
        for (int l = 0; st == IBL_OK && l < L; l++)
            st = ibl_edge_fixup_apply(ctx, desc.edge_fixup, out, l);
    } else if (desc.method == IBL_METHOD_REFERENCE) {
        st = ibl__specular_reference(ctx, s, &desc, &info, out);
        for (int l = 0; st == IBL_OK && l < L; l++) {
            ibl__lobe lobe = ibl__lobe_for_level(&info, l);
            if (lobe.kind == IBL__LOBE_MIRROR) st = mirror_level(ctx, s, out, l);
            if (st == IBL_OK) st = ibl_edge_fixup_apply(ctx, desc.edge_fixup, out, l);
        }
    } else {
        ibl_specular_plan *plan = NULL;
        desc.source_size = s->size;
        st = ibl_specular_plan_create(ctx, &desc, &plan);
        if (st == IBL_OK) st = ibl_specular_plan_run(plan, s, out);
        ibl_specular_plan_destroy(plan);
        /* a mirror level the plan could only point-sample (its size does not divide the
         * source's) is area-resampled here, as the reference does */
        for (int l = 0; st == IBL_OK && l < L; l++) {
            int n = ibl_level_size(N, l);
            if (ibl__lobe_for_level(&info, l).kind != IBL__LOBE_MIRROR || n >= s->size ||
                s->size % n == 0)
                continue;
            st = mirror_level(ctx, s, out, l);
            if (st == IBL_OK) st = ibl_edge_fixup_apply(ctx, desc.edge_fixup, out, l);
        }
    }
done:
    if (work.owns_data) ibl_cubemap_free(ctx, &work);
    if (st != IBL_OK) {
        ibl_cubemap_free(ctx, out);
        memset(out, 0, sizeof *out);
    } else if (info_out) {
        *info_out = info;
    }
    return st;
}

/* ---- metadata and manifest ---- */

static int is_phong_family(const ibl_specular_info *info) { return info->filter != IBL_FILTER_GGX; }

ibl_status ibl_specular_set_metadata(ibl_context *ctx, const ibl_specular_info *info,
                                     ibl_texture *tex)
{
    if (!ctx || !info || !tex) return IBL_ERR_INVALID_ARGUMENT;
    char buf[64 * IBL_MAX_LEVELS + 64];
    ibl_status st = ibl_texture_set_metadata(ctx, tex, "ibl.specular.filter",
                                             ibl_specular_filter_name(info->filter));
    if (st == IBL_OK)
        st = ibl_texture_set_metadata(ctx, tex, "ibl.specular.mapping",
                                      ibl_specular_mapping_name(info->mapping));
    if (st == IBL_OK)
        st = ibl_texture_set_metadata(ctx, tex, "ibl.specular.mirror", info->mirror ? "1" : "0");
    if (st == IBL_OK && info->filter == IBL_FILTER_BLINN) {
        snprintf(buf, sizeof buf, "%.9g", info->blinn_factor);
        st = ibl_texture_set_metadata(ctx, tex, "ibl.specular.blinn_factor", buf);
    }
    if (st == IBL_OK && info->mapping == IBL_MAPPING_TRIACE) {
        snprintf(buf, sizeof buf, "%.9g", info->lod_offset);
        st = ibl_texture_set_metadata(ctx, tex, "ibl.specular.lod_offset", buf);
    }
    if (st != IBL_OK) return st;
    size_t pos = 0;
    for (int l = 0; l < info->levels; l++) {
        float v = is_phong_family(info) ? info->shininess[l] : info->roughness[l];
        pos += (size_t)snprintf(buf + pos, sizeof buf - pos, "%s%.9g", l ? " " : "", v);
    }
    return ibl_texture_set_metadata(ctx, tex,
                                    is_phong_family(info) ? "ibl.specular.shininess"
                                                          : "ibl.specular.roughness",
                                    buf);
}

ibl_status ibl_specular_manifest_json(ibl_context *ctx, const ibl_specular_info *info, char **json)
{
    if (!ctx || !info || !json) return IBL_ERR_INVALID_ARGUMENT;
    size_t cap = 1024 + (size_t)info->levels * 160;
    char *b = ibl_alloc(ctx, cap);
    if (!b) return ibl_context_status(ctx);
    size_t n = 0;
#define PUT(...) n += (size_t)snprintf(b + n, cap - n, __VA_ARGS__)
    PUT("{\n  \"filter\": \"%s\",\n  \"mapping\": \"%s\",\n", ibl_specular_filter_name(info->filter),
        ibl_specular_mapping_name(info->mapping));
    PUT("  \"size\": %d,\n  \"mirror\": %s,\n", info->size, info->mirror ? "true" : "false");
    if (info->filter == IBL_FILTER_BLINN) PUT("  \"blinn_factor\": %.9g,\n", info->blinn_factor);
    if (is_phong_family(info))
        PUT("  \"shininess_range\": [%.9g, %.9g],\n", info->shininess_min, info->shininess_max);
    if (info->mapping == IBL_MAPPING_TRIACE)
        PUT("  \"seed_lod\": \"lod = a - 0.5 * log2(shininess)\",\n  \"lod_offset\": %.9g,\n", info->lod_offset);
    PUT("  \"levels\": [\n");
    for (int l = 0; l < info->levels; l++) {
        PUT("    {\"level\": %d, \"size\": %d, ", l, ibl_level_size(info->size, l));
        int mirror = is_phong_family(info) ? !(info->shininess[l] > 0) : !(info->roughness[l] > 0);
        if (is_phong_family(info)) {
            if (mirror) PUT("\"shininess\": null, \"mirror\": true}");
            else PUT("\"shininess\": %.9g}", info->shininess[l]);
        } else {
            PUT("\"roughness\": %.9g%s}", info->roughness[l], mirror ? ", \"mirror\": true" : "");
        }
        PUT("%s\n", l + 1 < info->levels ? "," : "");
    }
    PUT("  ]\n}\n");
#undef PUT
    *json = b;
    return IBL_OK;
}
