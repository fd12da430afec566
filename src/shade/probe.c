/* The probe: validation of its plain parts, the level mapping (roughness/shininess <-> lod)
 * and the reads every shading model makes (prefiltered radiance, irradiance). */
#include "ibl/shade.h"
#include "core/context_internal.h"
#include "core/numeric.h"
#include "shade/probe_internal.h"

#include "ibl/io.h"
#include "ibl/layout.h"
#include "ibl/sh.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>


static int cube_ok(const ibl_cubemap *c)
{
    return c->data && c->size > 0 && c->levels > 0 && c->levels <= ibl_full_mip_count(c->size);
}

static int axis_ok(const ibl_table_axis *a)
{
    if (a->count < 1) return 0;
    if (!isfinite(a->first) || !isfinite(a->last)) return 0;
    if (a->logarithmic && (a->first <= 0.0f || a->last <= 0.0f)) return 0;
    return 1;
}

ibl_status ibl_probe_validate(ibl_context *ctx, ibl_probe *p)
{
    if (!p) return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "probe: NULL");
    if (!cube_ok(&p->specular))
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "probe: no prefiltered specular chain");
    ibl_level_mapping *m = &p->mapping;
    if (m->levels <= 0 || m->levels > p->specular.levels)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                        "probe: the level mapping describes %d levels, the chain has %d", m->levels,
                        p->specular.levels);
    int have_r = 0, have_s = 0;
    for (int k = 0; k < m->levels; k++) {
        if (m->roughness[k] != 0.0f) have_r = 1;
        if (m->shininess[k] != 0.0f) have_s = 1;
    }
    if (!have_r && have_s)
        for (int k = 0; k < m->levels; k++)
            m->roughness[k] = ibl_roughness_from_shininess(m->shininess[k]);
    /* floor at 1e-3: roughness 1 maps to shininess 0, and the lookup works in log2 */
    if (!have_s)
        for (int k = 0; k < m->levels; k++) {
            float s = ibl_shininess_from_roughness(m->roughness[k]);
            m->shininess[k] = s > 1e-3f ? s : 1e-3f;
        }
    for (int k = 0; k < m->levels; k++)
        if (!(m->shininess[k] > 0.0f))
            return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "probe: level %d has shininess %g", k,
                            (double)m->shininess[k]);
    for (int k = 1; k < m->levels; k++) {
        if (!(m->roughness[k] > m->roughness[k - 1]))
            return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                            "probe: level roughness must increase (level %d: %g after %g)", k,
                            (double)m->roughness[k], (double)m->roughness[k - 1]);
        if (!(m->shininess[k] < m->shininess[k - 1]))
            return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                            "probe: level shininess must decrease (level %d: %g after %g)", k,
                            (double)m->shininess[k], (double)m->shininess[k - 1]);
    }
    if (p->mirror.data && !cube_ok(&p->mirror))
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "probe: bad mirror cube");
    if (p->sh_kind == IBL_SH_NONE && !cube_ok(&p->irradiance))
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "probe: neither irradiance cube nor SH");
    const ibl_splitsum_view *ss = &p->splitsum;
    if (ss->data && (!axis_ok(&ss->n_dot_v) || !axis_ok(&ss->roughness) || ss->channels == 1 ||
                     ss->channels < 0))
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "probe: bad split-sum table");
    const ibl_ambient_brdf_view *ab = &p->ambient_brdf;
    if (ab->data && (!axis_ok(&ab->n_dot_v) || !axis_ok(&ab->shininess) || !axis_ok(&ab->f0) ||
                     ab->channels < 0))
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "probe: bad AmbientBRDF table");
    return IBL_OK;
}

void ibl_probe_free(ibl_context *ctx, ibl_probe *p)
{
    if (!p) return;
    for (int i = 0; i < p->owned_count; i++) ibl_free(ctx, p->owned[i]);
    for (int i = 0; i < 4; i++) ibl_cubemap_free(ctx, &p->owned_cubes[i]);
    memset(p, 0, sizeof *p);
}

/* Piecewise linear through the per-level values: level k exactly at value k. */
float ibl_probe_lod_from_roughness(const ibl_probe *p, float roughness)
{
    const ibl_level_mapping *m = &p->mapping;
    if (m->lod_from_roughness) return m->lod_from_roughness(m->user, roughness);
    int last = m->levels - 1;
    if (roughness <= m->roughness[0]) return 0.0f;
    if (roughness >= m->roughness[last]) return (float)last;
    int k = 0;
    while (k < last - 1 && roughness >= m->roughness[k + 1]) k++;
    return (float)k + (roughness - m->roughness[k]) / (m->roughness[k + 1] - m->roughness[k]);
}

/* Linear in log2(shininess) between levels: the seed's lod = a - 0.5 log2(n) is of this form,
 * so a Phong-kernel bake is reproduced exactly and any other is followed level by level. */
float ibl_probe_lod_from_shininess(const ibl_probe *p, float shininess)
{
    const ibl_level_mapping *m = &p->mapping;
    if (m->lod_from_shininess) return m->lod_from_shininess(m->user, shininess);
    int last = m->levels - 1;
    if (shininess < 1e-3f) shininess = 1e-3f;
    if (shininess >= m->shininess[0]) {
        float ms = p->mirror_shininess > 0.0f ? p->mirror_shininess : 10000.0f;
        if (!p->mirror.data || ms <= m->shininess[0]) return 0.0f;
        float t = logf(shininess / m->shininess[0]) / logf(ms / m->shininess[0]);
        return -(t > 1.0f ? 1.0f : t);
    }
    if (shininess <= m->shininess[last]) return (float)last;
    int k = 0;
    while (k < last - 1 && shininess <= m->shininess[k + 1]) k++;
    float l0 = log2f(m->shininess[k]), l1 = log2f(m->shininess[k + 1]);
    return (float)k + (log2f(shininess) - l0) / (l1 - l0);
}

void ibl_probe_sample_specular(const ibl_probe *p, float lod, ibl_vec3 dir, float out[3])
{
    float t[4];
    float scale = p->intensity > 0.0f ? p->intensity : 1.0f;
    float last = (float)(p->mapping.levels - 1);
    if (lod < 0.0f && p->mirror.data) {
        float a[4], b[4], f = -lod > 1.0f ? 1.0f : -lod;
        ibl_cubemap_sample_bilinear(&p->specular, 0, dir, a);
        ibl_cubemap_sample_bilinear(&p->mirror, 0, dir, b);
        for (int c = 0; c < 3; c++) out[c] = scale * (a[c] + (b[c] - a[c]) * f);
        return;
    }
    if (lod < 0.0f) lod = 0.0f;
    if (lod > last) lod = last;
    float fl = floorf(lod);
    if (lod == fl)
        ibl_cubemap_sample_bilinear(&p->specular, (int)fl, dir, t);
    else
        ibl_cubemap_sample_trilinear(&p->specular, lod, dir, t);
    for (int c = 0; c < 3; c++) out[c] = scale * t[c];
}

/* Ramamoorthi & Hanrahan 2001: E(n) = sum_l A_l sum_m L_lm Y_lm(n), A = (pi, 2pi/3, pi/4). */
void ibl_sh9_eval_irradiance(const float sh[9][3], ibl_sh_kind kind, ibl_vec3 n, float out[3])
{
    float x = n.x, y = n.y, z = n.z;
    float basis[9] = {0.282095f,
                      0.488603f * y,
                      0.488603f * z,
                      0.488603f * x,
                      1.092548f * x * y,
                      1.092548f * y * z,
                      0.315392f * (3.0f * z * z - 1.0f),
                      1.092548f * x * z,
                      0.546274f * (x * x - y * y)};
    static const float band[9] = {3.14159265f, 2.09439510f, 2.09439510f, 2.09439510f, 0.78539816f,
                                  0.78539816f, 0.78539816f, 0.78539816f, 0.78539816f};
    for (int c = 0; c < 3; c++) {
        float e = 0.0f;
        for (int i = 0; i < 9; i++)
            e += (kind == IBL_SH_RADIANCE ? band[i] : 1.0f) * sh[i][c] * basis[i];
        out[c] = e > 0.0f ? e : 0.0f;
    }
}

void ibl_probe_irradiance(const ibl_probe *p, ibl_vec3 n, float out[3])
{
    float scale = p->intensity > 0.0f ? p->intensity : 1.0f;
    if (p->sh_kind != IBL_SH_NONE) {
        ibl_sh9_eval_irradiance(p->sh, p->sh_kind, n, out);
        for (int c = 0; c < 3; c++) out[c] *= scale / IBL_PI_F;
        return;
    }
    float t[4];
    ibl_cubemap_sample_bilinear(&p->irradiance, 0, n, t);
    for (int c = 0; c < 3; c++) out[c] = scale * t[c];
}

/* The value after "key": within [p, end), or NULL. Enough for the manifest `ibl bake`
 * writes (cli/bake.c, ibl_specular_manifest_json); not a general JSON reader. */
static const char *json_value(const char *p, const char *end, const char *key)
{
    size_t n = strlen(key);
    for (const char *q = p; q && q < end; q = strchr(q + 1, '"')) {
        if (q + n + 2 <= end && q[0] == '"' && strncmp(q + 1, key, n) == 0 && q[n + 1] == '"') {
            const char *v = q + n + 2;
            while (v < end && (*v == ' ' || *v == ':')) v++;
            return v < end ? v : NULL;
        }
    }
    return NULL;
}

static int file_exists(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) return 0;
    fclose(f);
    return 1;
}

ibl_status ibl__probe_parse_manifest(ibl_context *ctx, const void *bytes, size_t size,
                                     const char *name, ibl_probe_files *files)
{
    memset(files, 0, sizeof *files);
    if (size > ((size_t)64 << 20))
        return ibl__fail(ctx, IBL_ERR_TOO_LARGE, "%s: a manifest of %zu bytes is too large", name, size);
    char *text = ibl_alloc(ctx, size + 1);
    if (!text) return ibl__fail(ctx, ibl_context_status(ctx), "%s: out of memory", name);
    memcpy(text, bytes, size);
    /* the parse below stops at the first NUL, so an embedded NUL only shortens the text */
    text[size] = 0;

    /* the level mapping: "specular": {..., "levels": [{"roughness": r} or {"shininess": s}]} */
    const char *end = text + strlen(text);
    const char *spec = json_value(text, end, "specular");
    const char *lv = spec ? strstr(spec, "\"levels\": [") : NULL;
    const char *range = spec ? json_value(spec, end, "shininess_range") : NULL;
    int k = 0, bad = !lv;
    for (const char *o = lv ? strchr(lv, '{') : NULL; o && k < IBL_MAX_LEVELS; k++) {
        const char *close = strchr(o, '}'), *stop = strchr(lv, ']');
        if (!close || (stop && o > stop)) break;
        const char *r = json_value(o, close, "roughness"), *sh = json_value(o, close, "shininess");
        if (r) files->mapping.roughness[k] = strtof(r, NULL);
        else if (sh && strncmp(sh, "null", 4) == 0) files->mapping.shininess[k] = 1e6f; /* mirror */
        else if (sh) files->mapping.shininess[k] = strtof(sh, NULL);
        else bad = 1;
        o = strchr(close, '{');
        if (stop && o > stop) o = NULL;
    }
    files->mapping.levels = k;
    /* the Phong-family chains (phong, box, gauss) are filtered with Phong lobes around R of
     * exponent n; the material's shininess is the Blinn-Phong exponent of the seed's BRDF, and
     * the seed's fit cos^n(t) ~ cos^(4.2 n)(t/2) makes that 4.2 n (a blinn chain is already
     * in Blinn exponents) */
    const char *filter = spec ? json_value(spec, end, "filter") : NULL;
    if (filter && strncmp(filter, "\"blinn\"", 7) != 0 && strncmp(filter, "\"ggx\"", 5) != 0) {
        const char *bf = json_value(spec, end, "blinn_factor");
        float f = bf ? strtof(bf, NULL) : 4.2f;
        if (!(f > 0.0f)) f = 4.2f;
        for (int i = 0; i < k; i++)
            if (files->mapping.shininess[i] < 1e6f) files->mapping.shininess[i] *= f;
    }
    if (range && *range == '[') {
        char *e = NULL;
        files->ambient_shininess_min = strtof(range + 1, &e);
        if (e && *e == ',') files->ambient_shininess_max = strtof(e + 1, NULL);
    }
    ibl_free(ctx, text);
    if (bad || k == 0) return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: no specular level mapping", name);
    return IBL_OK;
}

ibl_status ibl_probe_load(ibl_context *ctx, const char *dir, ibl_probe *out)
{
    if (out) memset(out, 0, sizeof *out);
    if (!dir || !out) return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "probe: no directory");
    char path[4][1024], manifest_path[1024];
    snprintf(manifest_path, sizeof manifest_path, "%s/manifest.json", dir);
    void *bytes = NULL;
    size_t size = 0;
    ibl_status st = ibl_read_file(ctx, manifest_path, &bytes, &size);
    if (st != IBL_OK) return st;
    ibl_probe_files files;
    st = ibl__probe_parse_manifest(ctx, bytes, size, manifest_path, &files);
    ibl_free(ctx, bytes);
    if (st != IBL_OK) return st;

    const char *names[4] = {"specular.ktx2", "irradiance.ktx2", "brdf_lut.ktx2", "ambient_brdf.ktx2"};
    for (int i = 0; i < 4; i++) snprintf(path[i], sizeof path[i], "%s/%s", dir, names[i]);
    if (!file_exists(path[0])) snprintf(path[0], sizeof path[0], "%s/specular.dds", dir);
    if (!file_exists(path[1])) snprintf(path[1], sizeof path[1], "%s/irradiance.dds", dir);
    files.specular = path[0];
    files.irradiance = file_exists(path[1]) ? path[1] : NULL;
    files.splitsum = file_exists(path[2]) ? path[2] : NULL;
    files.ambient_brdf = file_exists(path[3]) ? path[3] : NULL;
    return ibl_probe_load_files(ctx, &files, out);
}

/* Reads a cube (a cube texture, or a flat image in a layout) into out, owning its texels. */
static ibl_status read_cube(ibl_context *ctx, const char *path, const ibl_read_desc *rd,
                            int allow_image, ibl_cubemap *out)
{
    ibl_texture tex;
    ibl_file_info info;
    ibl_status st = ibl_read_texture(ctx, path, rd, &tex, &info);
    if (st != IBL_OK) return st;
    if (tex.kind == IBL_TEXTURE_CUBE) {
        out->size = tex.width;
        out->levels = tex.levels;
        out->data = tex.data;
        out->owns_data = tex.owns_data;
        tex.owns_data = 0;
    } else if (allow_image && tex.kind == IBL_TEXTURE_2D) {
        ibl_image im = {tex.width, tex.height, tex.data};
        st = ibl_image_to_cubemap(ctx, &im, NULL, out);
    } else {
        st = ibl__fail(ctx, IBL_ERR_FORMAT, "%s: not a cube texture", path);
    }
    ibl_texture_free(ctx, &tex);
    return st;
}

/* Reads a 2D or 3D table and keeps its texels (RGBA float, level 0). */
static ibl_status read_table(ibl_context *ctx, ibl_probe *p, const char *path,
                             const ibl_read_desc *rd, ibl_texture_kind kind, ibl_texture *shape,
                             float **data)
{
    ibl_texture tex;
    ibl_status st = ibl_read_texture(ctx, path, rd, &tex, NULL);
    if (st != IBL_OK) return st;
    if (tex.kind != kind || !tex.owns_data) {
        ibl_texture_free(ctx, &tex);
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: expected a %s table", path,
                        kind == IBL_TEXTURE_3D ? "3D" : "2D");
    }
    *shape = tex;
    shape->data = NULL;
    shape->metadata = NULL;
    shape->metadata_count = 0;
    *data = tex.data;
    p->owned[p->owned_count++] = tex.data;
    tex.owns_data = 0;
    ibl_texture_free(ctx, &tex);
    return IBL_OK;
}

ibl_status ibl_probe_load_files(ibl_context *ctx, const ibl_probe_files *f, ibl_probe *out)
{
    memset(out, 0, sizeof *out);
    if (!f || !f->specular)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "probe: no specular chain file");
    ibl_read_desc rd = {.clamp_infinite = f->clamp_infinite};
    ibl_status st = read_cube(ctx, f->specular, &rd, 0, &out->owned_cubes[0]);
    if (st != IBL_OK) goto fail;
    out->specular = out->owned_cubes[0];
    out->specular.owns_data = 0;
    out->mapping = f->mapping;
    if (out->mapping.levels <= 0) {
        int n = out->specular.levels;
        memset(&out->mapping, 0, sizeof out->mapping);
        out->mapping.levels = n;
        for (int k = 0; k < n; k++)
            out->mapping.roughness[k] = n > 1 ? (float)k / (float)(n - 1) : 0.0f;
    }
    if (f->mirror) {
        if ((st = read_cube(ctx, f->mirror, &rd, 1, &out->owned_cubes[1])) != IBL_OK) goto fail;
        out->mirror = out->owned_cubes[1];
        out->mirror.owns_data = 0;
    }
    if (f->irradiance) {
        if ((st = read_cube(ctx, f->irradiance, &rd, 1, &out->owned_cubes[2])) != IBL_OK) goto fail;
        out->irradiance = out->owned_cubes[2];
        out->irradiance.owns_data = 0;
    } else {
        /* SH9 of the sharpest radiance at hand, at a level of at most 32 texels */
        const ibl_cubemap *src = out->mirror.data ? &out->mirror : &out->specular;
        int level = 0; /* a one-level mirror is projected whole */
        while (level + 1 < src->levels && ibl_level_size(src->size, level) > 32) level++;
        ibl_sh sh;
        if ((st = ibl_sh_project_cubemap(ctx, src, level, 3, &sh)) != IBL_OK) goto fail;
        for (int i = 0; i < 9; i++)
            for (int c = 0; c < 3; c++) out->sh[i][c] = (float)sh.c[i][c];
        out->sh_kind = IBL_SH_RADIANCE;
    }
    if (f->splitsum) {
        ibl_texture shape;
        float *data;
        if ((st = read_table(ctx, out, f->splitsum, &rd, IBL_TEXTURE_2D, &shape, &data)) != IBL_OK)
            goto fail;
        float w = (float)shape.width, h = (float)shape.height;
        out->splitsum = (ibl_splitsum_view){data,
                                            4,
                                            {shape.width, 0.5f / w, 1.0f - 0.5f / w, 0},
                                            {shape.height, 0.5f / h, 1.0f - 0.5f / h, 0}};
    }
    if (f->ambient_brdf) {
        ibl_texture shape;
        float *data;
        if ((st = read_table(ctx, out, f->ambient_brdf, &rd, IBL_TEXTURE_3D, &shape, &data)) !=
            IBL_OK)
            goto fail;
        double lo = f->ambient_shininess_min > 0 ? f->ambient_shininess_min : 1.0;
        double hi = f->ambient_shininess_max > 0 ? f->ambient_shininess_max : 2000.0;
        int n = shape.height;
        double t0 = 0.5 / n, t1 = 1.0 - 0.5 / n;
        ibl_table_axis s_axis;
        if (f->ambient_linear)
            s_axis =
                (ibl_table_axis){n, (float)(lo + (hi - lo) * t0), (float)(lo + (hi - lo) * t1), 0};
        else
            s_axis = (ibl_table_axis){n, (float)(lo * pow(hi / lo, t0)),
                                      (float)(lo * pow(hi / lo, t1)), 1};
        float w = (float)shape.width, d = (float)shape.depth;
        out->ambient_brdf = (ibl_ambient_brdf_view){data,
                                                    4,
                                                    {shape.width, 0.5f / w, 1.0f - 0.5f / w, 0},
                                                    s_axis,
                                                    {shape.depth, 0.5f / d, 1.0f - 0.5f / d, 0}};
    }
    if ((st = ibl_probe_validate(ctx, out)) != IBL_OK) goto fail;
    return IBL_OK;
fail:
    ibl_probe_free(ctx, out);
    return st;
}
