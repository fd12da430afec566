/* Ambient (image-based) shading of one surface point for the two material models.
 *  - GGX (glTF 2.0 metal/roughness): the split-sum approximation (Karis 2013, "Real Shading in
 *    Unreal Engine 4"): prefiltered radiance at R times F0 A + B from the table, with optional
 *    multiple-scattering energy compensation (Fdez-Aguera 2019, "A Multiple-Scattering
 *    Microfacet Model for Real-Time Image-based Lighting"; Turquin 2019, "Practical
 *    multiple scattering compensation for microfacet models").
 *  - Blinn-Phong (tri-Ace 2010): PFREM at the shininess's level times the AmbientBRDF volume,
 *    diffuse Rd (1 - AmbientBRDF) ("AmbientBRDF texture usage").
 * Level selection goes through the probe's own mapping (probe.c). */
#include "ibl/shade.h"
#include "core/numeric.h"

#include <math.h>
#include <string.h>

float ibl_table_axis_value(const ibl_table_axis *a, int i)
{
    if (a->count <= 1) return a->first;
    float t = (float)i / (float)(a->count - 1);
    if (a->logarithmic) return expf(logf(a->first) + t * (logf(a->last) - logf(a->first)));
    return a->first + t * (a->last - a->first);
}

float ibl_table_axis_index(const ibl_table_axis *a, float value)
{
    if (a->count <= 1) return 0.0f;
    float t;
    if (a->logarithmic) {
        if (value <= 0.0f) return 0.0f;
        t = (logf(value) - logf(a->first)) / (logf(a->last) - logf(a->first));
    } else {
        t = (value - a->first) / (a->last - a->first);
    }
    if (!(t > 0.0f)) t = 0.0f; /* also NaN */
    if (t > 1.0f) t = 1.0f;
    return t * (float)(a->count - 1);
}

static void split_index(float f, int count, int *i0, float *w)
{
    int i = (int)f;
    if (i >= count - 1) i = count > 1 ? count - 2 : 0;
    *i0 = i;
    *w = count > 1 ? f - (float)i : 0.0f;
}

void ibl_splitsum_lookup(const ibl_splitsum_view *t, float n_dot_v, float roughness, float *a,
                         float *b)
{
    int ch = t->channels > 0 ? t->channels : 2;
    int nv = t->n_dot_v.count, nr = t->roughness.count;
    int i, j;
    float wi, wj;
    split_index(ibl_table_axis_index(&t->n_dot_v, n_dot_v), nv, &i, &wi);
    split_index(ibl_table_axis_index(&t->roughness, roughness), nr, &j, &wj);
    int i1 = nv > 1 ? i + 1 : i, j1 = nr > 1 ? j + 1 : j;
    const float *p00 = t->data + ((size_t)j * nv + i) * ch,
                *p01 = t->data + ((size_t)j * nv + i1) * ch;
    const float *p10 = t->data + ((size_t)j1 * nv + i) * ch,
                *p11 = t->data + ((size_t)j1 * nv + i1) * ch;
    for (int c = 0; c < 2; c++) {
        float lo = p00[c] + (p01[c] - p00[c]) * wi;
        float hi = p10[c] + (p11[c] - p10[c]) * wi;
        float v = lo + (hi - lo) * wj;
        if (c == 0)
            *a = v;
        else
            *b = v;
    }
}

float ibl_ambient_brdf_lookup(const ibl_ambient_brdf_view *t, float n_dot_v, float shininess,
                              float f0)
{
    int ch = t->channels > 0 ? t->channels : 1;
    int nv = t->n_dot_v.count, ns = t->shininess.count, nf = t->f0.count;
    int i, j, k;
    float wi, wj, wk;
    split_index(ibl_table_axis_index(&t->n_dot_v, n_dot_v), nv, &i, &wi);
    split_index(ibl_table_axis_index(&t->shininess, shininess), ns, &j, &wj);
    split_index(ibl_table_axis_index(&t->f0, f0), nf, &k, &wk);
    float acc = 0.0f;
    for (int dk = 0; dk < 2; dk++) {
        int kk = nf > 1 ? k + dk : k;
        float fk = dk ? wk : 1.0f - wk;
        for (int dj = 0; dj < 2; dj++) {
            int jj = ns > 1 ? j + dj : j;
            float fj = dj ? wj : 1.0f - wj;
            for (int di = 0; di < 2; di++) {
                int ii = nv > 1 ? i + di : i;
                float fi = di ? wi : 1.0f - wi;
                float w = fk * fj * fi;
                if (w != 0.0f) acc += w * t->data[(((size_t)kk * ns + jj) * nv + ii) * ch];
            }
        }
    }
    return acc;
}

ibl_material ibl_material_gltf(const float base_color[3], float metallic, float roughness)
{
    ibl_material m;
    memset(&m, 0, sizeof m);
    m.model = IBL_MATERIAL_GGX;
    for (int c = 0; c < 3; c++) m.base_color[c] = base_color[c];
    m.metallic = metallic;
    m.roughness = roughness;
    m.ao = 1.0f;
    return m;
}

ibl_material ibl_material_blinn_phong(const float rd[3], const float f0[3], float shininess)
{
    ibl_material m;
    memset(&m, 0, sizeof m);
    m.model = IBL_MATERIAL_BLINN_PHONG;
    for (int c = 0; c < 3; c++) {
        m.base_color[c] = rd[c];
        m.f0[c] = f0[c];
    }
    m.shininess = shininess;
    m.ao = 1.0f;
    return m;
}

float ibl_dominant_direction_lean(const ibl_material *m)
{
    if (m->model == IBL_MATERIAL_BLINN_PHONG) {
        /* tri-Ace 2010's normalised Blinn-Phong, (n.h)^s n.l / max(n.l, n.v): the factor that
         * points lerp(N, R, t) at the centroid of the lobe, averaged over n.v with the weight
         * of a sphere's projected area (sin cos), is t = g / (1 + g), g = 0.1785 s^0.9805
         * (fitted to a float64 integration, rms 0.0005 over s = 0.5..5000; tests/test_shade.c).
         * The GGX fit below leans too far for this lobe (0.87 instead of 0.99 at s = 1000). */
        float sh = m->shininess > 0.0f ? m->shininess : 0.0f;
        float g = 0.1785f * powf(sh, 0.9805f);
        return g / (1.0f + g);
    }
    /* Lagarde & de Rousiers 2014 ("Moving Frostbite to PBR", specular dominant direction)
     * for GGX: lerp(N, R, (1 - r)(sqrt(1 - r) + r)) */
    float rough = ibl__saturate(m->roughness);
    float smooth = 1.0f - rough;
    return smooth * (sqrtf(smooth) + rough);
}

void ibl_material_reflectances(const ibl_material *m, float f0[3], float diffuse_albedo[3])
{
    int dielectric_given = m->f0[0] != 0.0f || m->f0[1] != 0.0f || m->f0[2] != 0.0f;
    for (int c = 0; c < 3; c++) {
        if (m->model == IBL_MATERIAL_BLINN_PHONG) {
            f0[c] = m->f0[c];
            diffuse_albedo[c] = m->base_color[c] * (1.0f - m->f0[c]);
        } else {
            float fd = dielectric_given ? m->f0[c] : 0.04f;
            f0[c] = fd + (m->base_color[c] - fd) * m->metallic;
            diffuse_albedo[c] = m->base_color[c] * (1.0f - m->metallic);
        }
    }
}

ibl_vec3 ibl_shade_lookup_direction(const ibl_shade_desc *desc, const ibl_material *m,
                                    const ibl_surface *s)
{
    float nv = ibl__dot(s->n, s->v);
    ibl_vec3 r = {2.0f * nv * s->n.x - s->v.x, 2.0f * nv * s->n.y - s->v.y,
                  2.0f * nv * s->n.z - s->v.z};
    if (desc && desc->mirror_direction) return r;
    /* the n = v = r prefilter cannot express a lobe that leans from R toward N: look up along
     * lerp(N, R, t) instead (the lobe's dominant direction) */
    float t = ibl_dominant_direction_lean(m);
    ibl_vec3 d = {s->n.x + (r.x - s->n.x) * t, s->n.y + (r.y - s->n.y) * t,
                  s->n.z + (r.z - s->n.z) * t};
    float len = sqrtf(ibl__dot(d, d));
    return len > 0.0f ? ibl__v3(d.x / len, d.y / len, d.z / len) : r;
}

void ibl_shade(const ibl_probe *probe, const ibl_shade_desc *desc, const ibl_material *m,
               const ibl_surface *s, ibl_shade_result *out)
{
    ibl_shade_dir(probe, desc, m, s, ibl_shade_lookup_direction(desc, m, s), out);
}

void ibl_shade_dir(const ibl_probe *probe, const ibl_shade_desc *desc, const ibl_material *m,
                   const ibl_surface *s, ibl_vec3 dir, ibl_shade_result *out)
{
    static const ibl_shade_desc defaults;
    if (!desc) desc = &defaults;
    /* n.v at exactly 0 makes the tables' edge column meaningless; 1e-4 is below their step */
    float nv = ibl__dot(s->n, s->v);
    if (nv < 1e-4f) nv = 1e-4f;
    float irr[3], pref[3], spec[3], diffuse_color[3];
    float roughness, shininess, lod;

    ibl_probe_irradiance(probe, s->n, irr);
    if (m->model == IBL_MATERIAL_BLINN_PHONG) {
        shininess = m->shininess;
        roughness = ibl_roughness_from_shininess(shininess);
        lod = ibl_probe_lod_from_shininess(probe, shininess);
        if (desc->no_mirror && lod < 0.0f) lod = 0.0f;
    } else {
        roughness = ibl__saturate(m->roughness);
        shininess = ibl_shininess_from_roughness(roughness);
        lod = ibl_probe_lod_from_roughness(probe, roughness);
    }
    if (desc->nearest_level && lod > 0.0f) lod = floorf(lod + 0.5f);
    ibl_probe_sample_specular(probe, lod, dir, pref);

    if (m->model == IBL_MATERIAL_BLINN_PHONG) {
        for (int c = 0; c < 3; c++) {
            float ab = probe->ambient_brdf.data
                           ? ibl_ambient_brdf_lookup(&probe->ambient_brdf, nv, shininess, m->f0[c])
                           : m->f0[c];
            spec[c] = pref[c] * ab;
            float kd = desc->bp_diffuse == IBL_BP_DIFFUSE_F0 ? 1.0f - m->f0[c] : 1.0f - ab;
            diffuse_color[c] = m->base_color[c] * ibl__saturate(kd);
        }
    } else {
        float a = 1.0f, b = 0.0f;
        if (probe->splitsum.data) ibl_splitsum_lookup(&probe->splitsum, nv, roughness, &a, &b);
        float ess = a + b;
        float f0s[3], albedo[3];
        ibl_material_reflectances(m, f0s, albedo);
        for (int c = 0; c < 3; c++) {
            float f0 = f0s[c];
            float fss_ess = f0 * a + b;
            spec[c] = pref[c] * fss_ess;
            if (desc->energy == IBL_ENERGY_FDEZ_AGUERA && ess > 0.0f) {
                /* Fdez-Aguera 2019, section 3: the multiply-scattered energy (1 - Ess) with the
                 * average Fresnel's geometric series, lit by the irradiance */
                float ems = 1.0f - ess;
                float favg = f0 + (1.0f - f0) / 21.0f;
                float fms = fss_ess * favg / (1.0f - ems * favg);
                spec[c] += fms * ems * irr[c];
            } else if (desc->energy == IBL_ENERGY_TURQUIN && ess > 0.0f) {
                /* Turquin 2019: E_ms lobe = F0 (1/E - 1) times the single-scattering lobe */
                spec[c] *= 1.0f + f0 * (1.0f / ess - 1.0f);
            }
            diffuse_color[c] = albedo[c];
        }
    }

    float so = ibl_specular_occlusion(desc->so, nv, m->ao, roughness, shininess);
    if (desc->horizon_occlusion) {
        ibl_vec3 ng = s->geometric_normal;
        if (ng.x == 0.0f && ng.y == 0.0f && ng.z == 0.0f) ng = s->n;
        so *= ibl_horizon_occlusion(dir, ng, desc->horizon_k);
    }
    float mixed[3];
    ibl_ambient_mix_apply(desc->mix, s->direct_specular, irr, spec, diffuse_color, m->ao, so,
                          mixed);
    for (int c = 0; c < 3; c++) {
        out->diffuse[c] = diffuse_color[c] * irr[c];
        out->specular[c] = spec[c];
        out->color[c] = out->diffuse[c] * m->ao + mixed[c];
    }
    out->so = so;
    out->lod = lod;
    out->r = dir;
}

void ibl_shade_blend(const ibl_probe *const *probes, const float *weights, int count,
                     const ibl_vec3 *lookup_dirs, const ibl_shade_desc *desc,
                     const ibl_material *m, const ibl_surface *s, ibl_shade_result *out)
{
    memset(out, 0, sizeof *out);
    float heaviest = -1.0f;
    for (int i = 0; i < count; i++) {
        if (weights[i] <= 0.0f) continue;
        ibl_shade_result r;
        if (lookup_dirs) ibl_shade_dir(probes[i], desc, m, s, lookup_dirs[i], &r);
        else ibl_shade(probes[i], desc, m, s, &r);
        for (int c = 0; c < 3; c++) {
            out->color[c] += weights[i] * r.color[c];
            out->diffuse[c] += weights[i] * r.diffuse[c];
            out->specular[c] += weights[i] * r.specular[c];
        }
        if (weights[i] > heaviest) {
            heaviest = weights[i];
            out->so = r.so;
            out->lod = r.lod;
            out->r = r.r;
        }
    }
}
