/* The probe: validation of its plain parts, the level mapping (roughness/shininess <-> lod)
 * and the reads every shading model makes (prefiltered radiance, irradiance). Plain data in,
 * no file I/O (bake.h loads bakes). */
#include "ibl/shade.h"
#include "core/context_internal.h"
#include "core/numeric.h"


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
        if (!(m->roughness[k] >= m->roughness[k - 1]))
            return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                             "probe: level roughness must not decrease (level %d: %g after %g)", k,
                             (double)m->roughness[k], (double)m->roughness[k - 1]);
        if (!(m->shininess[k] <= m->shininess[k - 1]))
            return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                             "probe: level shininess must not increase (level %d: %g after %g)", k,
                             (double)m->shininess[k], (double)m->shininess[k - 1]);
    }
    if (p->mirror.data && !cube_ok(&p->mirror))
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "probe: bad mirror cube");
    if (p->use_atlas && (!p->atlas || !p->atlas->pixels || !p->atlas_layout ||
                         p->atlas_layout->levels < m->levels ||
                         p->atlas_layout->width != p->atlas->width ||
                         p->atlas_layout->height != p->atlas->height))
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                         "probe: use_atlas without an atlas of the chain's %d levels", m->levels);
    if (p->sh_kind == IBL_SH_KIND_NONE && !cube_ok(&p->irradiance))
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

/* Piecewise linear through the per-level values: level k exactly at value k. */
float ibl_probe_lod_from_roughness(const ibl_probe *p, float roughness)
{
    const ibl_level_mapping *m = &p->mapping;
    if (m->lod_from_roughness) return m->lod_from_roughness(m->user, roughness);
    int last = m->levels - 1;
    if (roughness <= m->roughness[0]) return 0.0f;
    /* past the end, or on a run of equal values at the end: the run's sharpest level */
    int top = last;
    while (top > 0 && m->roughness[top - 1] == m->roughness[top]) top--;
    if (roughness >= m->roughness[top]) return (float)top;
    int k = 0;
    while (k < top - 1 && roughness >= m->roughness[k + 1]) k++;
    float span = m->roughness[k + 1] - m->roughness[k];
    return span > 0.0f ? (float)k + (roughness - m->roughness[k]) / span : (float)k;
}

/* Linear in log2(shininess) between levels: tri-Ace's lod = a - 0.5 log2(n) is of this form,
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
    int top = last;
    while (top > 0 && m->shininess[top - 1] == m->shininess[top]) top--;
    if (shininess <= m->shininess[top]) return (float)top;
    int k = 0;
    while (k < top - 1 && shininess <= m->shininess[k + 1]) k++;
    float l0 = log2f(m->shininess[k]), l1 = log2f(m->shininess[k + 1]);
    return l1 < l0 ? (float)k + (log2f(shininess) - l0) / (l1 - l0) : (float)k;
}

void ibl_probe_sample_specular(const ibl_probe *p, float lod, ibl_vec3 dir, float out[3])
{
    float t[4];
    float scale = p->intensity > 0.0f ? p->intensity : 1.0f;
    float last = (float)(p->mapping.levels - 1);
    if (p->use_atlas) {
        ibl_atlas_sample(p->atlas, p->atlas_layout, lod < 0.0f ? 0.0f : lod > last ? last : lod,
                         dir, t);
        for (int c = 0; c < 3; c++) out[c] = scale * t[c];
        return;
    }
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
            e += (kind == IBL_SH_KIND_RADIANCE ? band[i] : 1.0f) * sh[i][c] * basis[i];
        out[c] = e > 0.0f ? e : 0.0f;
    }
}

void ibl_probe_irradiance(const ibl_probe *p, ibl_vec3 n, float out[3])
{
    float scale = p->intensity > 0.0f ? p->intensity : 1.0f;
    if (p->sh_kind != IBL_SH_KIND_NONE) {
        ibl_sh9_eval_irradiance(p->sh, p->sh_kind, n, out);
        for (int c = 0; c < 3; c++) out[c] *= scale / IBL_PI_F;
        return;
    }
    float t[4];
    ibl_cubemap_sample_bilinear(&p->irradiance, 0, n, t);
    for (int c = 0; c < 3; c++) out[c] = scale * t[c];
}
