/* Capture of local probes by path tracing (docs/PROBES.md "Capture").
 *
 * Each texel of the probe's cube gets `samples` paths from the probe's position through
 * jittered points of the texel. Light: the emissive triangles (chosen in proportion to
 * power, then a uniform point; Shirley, Wang and Zimmerman, "Monte Carlo Techniques for
 * Direct Lighting Calculations", 1996) and the environment (importance-sampled by luminance x
 * solid angle, src/render/env_sampling.c), each combined with BRDF sampling by multiple
 * importance sampling with the power heuristic (Veach, "Robust Monte Carlo Methods for Light
 * Transport Simulation", 1997, ch. 9). Materials: the glTF 2.0 metal/roughness BRDF of the
 * specification's Appendix B (GGX D, height-correlated Smith V, Schlick F, the Fresnel mix of
 * a Lambertian base for dielectrics). The capture modes are the two methods of the JAGE 2015
 * article ("Rendering Environment Maps for Light Probes").
 *
 * Random numbers are counter-based: a SplitMix64 hash (Steele, Lea and Flood, "Fast
 * Splittable Pseudorandom Number Generators", OOPSLA 2014) of (seed, probe, face, texel,
 * sample, dimension), so a texel's value does not depend on the thread that computes it. */
#include "ibl/probes.h"
#include "core/context_internal.h"
#include "core/numeric.h"
#include "render/render_internal.h"
#include "scene/scene_internal.h"

#include <float.h>
#include <stdio.h>
#include <math.h>
#include <string.h>

enum { DEFAULT_BOUNCES = 2, DEFAULT_SAMPLES = 64, ROWS_PER_TASK = 1, PROGRESS_STEPS = 4 };

/* ---- counter-based random numbers ------------------------------------------------------- */

static uint64_t mix64(uint64_t z)
{
    z += 0x9e3779b97f4a7c15ull;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

typedef struct rng {
    uint64_t key;
    uint32_t dim;
} rng;

static float rnd(rng *r)
{
    uint64_t x = mix64(r->key ^ mix64((uint64_t)r->dim++));
    return (float)(x >> 40) * (1.0f / 16777216.0f); /* [0, 1) */
}

/* ---- lights ------------------------------------------------------------------------------ */

typedef struct emitters {
    int count;
    int *triangles;
    double *cdf;     /* count + 1 */
    double total;    /* sum of power proxies: luminance(emissive) x area */
} emitters;

static float luminance(const float *c)
{
    return 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2];
}

static ibl_status emitters_init(ibl_context *ctx, const ibl_scene *s, emitters *e)
{
    memset(e, 0, sizeof *e);
    if (s->emissive_count == 0) return IBL_OK;
    e->triangles = ibl_alloc(ctx, (size_t)s->emissive_count * sizeof(int));
    e->cdf = ibl_alloc(ctx, ((size_t)s->emissive_count + 1) * sizeof(double));
    if (!e->triangles || !e->cdf) return IBL_ERR_OUT_OF_MEMORY;
    e->cdf[0] = 0.0;
    for (int t = 0; t < s->triangle_count; t++) {
        const ibl_scene_material *m = &s->materials[s->material_ids[t]];
        double p = (double)luminance(m->emissive) * s->areas[t];
        if (!(p > 0.0)) continue;
        e->triangles[e->count] = t;
        e->total += p;
        e->cdf[++e->count] = e->total;
    }
    return IBL_OK;
}

static void emitters_free(ibl_context *ctx, emitters *e)
{
    ibl_free(ctx, e->triangles);
    ibl_free(ctx, e->cdf);
}

/* probability (over the triangle choice and its area) of the point's triangle */
static double emitter_area_pdf(const ibl_scene *s, const emitters *e, int triangle)
{
    const ibl_scene_material *m = &s->materials[s->material_ids[triangle]];
    double p = (double)luminance(m->emissive) * s->areas[triangle];
    return p > 0.0 && e->total > 0.0 ? p / e->total / s->areas[triangle] : 0.0;
}

static int emitter_sample(const ibl_scene *s, const emitters *e, float u0, float u1, float u2,
                          ibl_vec3 *point, int *triangle)
{
    double target = (double)u0 * e->total;
    int lo = 0, hi = e->count; /* cdf[lo] <= target < cdf[lo + 1] */
    while (hi - lo > 1) {
        int mid = (lo + hi) / 2;
        if (e->cdf[mid] <= target) lo = mid;
        else hi = mid;
    }
    int t = e->triangles[lo];
    float su = sqrtf(u1), b0 = 1.0f - su, b1 = u2 * su; /* uniform on the triangle */
    const float *a = s->positions + 3 * s->indices[3 * t];
    const float *b = s->positions + 3 * s->indices[3 * t + 1];
    const float *c = s->positions + 3 * s->indices[3 * t + 2];
    float b2 = 1.0f - b0 - b1;
    *point = ibl__v3(b0 * a[0] + b1 * b[0] + b2 * c[0], b0 * a[1] + b1 * b[1] + b2 * c[1],
                     b0 * a[2] + b1 * b[2] + b2 * c[2]);
    *triangle = t;
    return 1;
}

/* ---- the glTF BRDF (specification, Appendix B) ---------------------------------------------- */

typedef struct brdf {
    ibl_vec3 n;          /* shading normal on the side of wo */
    float c_diff[3];     /* Lambert colour (base x (1 - metallic)) or the albedo when diffuse_only */
    float f0[3];
    float alpha;
    float p_spec;        /* probability of sampling the specular lobe */
    int diffuse_only;
} brdf;

static void brdf_init(const ibl_scene_surface *s, ibl_vec3 n, brdf *b)
{
    b->n = n;
    b->diffuse_only = s->diffuse_only;
    float m = ibl__saturate(s->metallic);
    for (int c = 0; c < 3; c++) {
        b->c_diff[c] = s->diffuse_only ? s->base_color[c] : s->base_color[c] * (1.0f - m);
        b->f0[c] = 0.04f * (1.0f - m) + s->base_color[c] * m;
    }
    float r = ibl__clampf(s->roughness, 0.0f, 1.0f);
    b->alpha = fmaxf(r * r, 1e-3f);
    b->p_spec = s->diffuse_only ? 0.0f : m + (1.0f - m) * 0.25f;
}

/* f(wo, wi) n.wi into f, and the sampling density of wi; 0 below the surface */
static float brdf_eval(const brdf *b, ibl_vec3 wo, ibl_vec3 wi, float f[3])
{
    float nl = ibl__dot(b->n, wi), nv = ibl__dot(b->n, wo);
    f[0] = f[1] = f[2] = 0.0f;
    if (nl <= 0.0f || nv <= 0.0f) return 0.0f;
    float pdf = (1.0f - b->p_spec) * nl * (float)IBL_INV_PI;
    if (b->diffuse_only) {
        for (int c = 0; c < 3; c++) f[c] = b->c_diff[c] * (float)IBL_INV_PI * nl;
        return pdf;
    }
    ibl_vec3 h = ibl__norm(ibl__add(wo, wi));
    float nh = fmaxf(ibl__dot(b->n, h), 0.0f), vh = fmaxf(ibl__dot(wo, h), 1e-6f);
    float d = ibl_ggx_d(b->alpha, nh), v = ibl_smith_ggx_v(b->alpha, nv, nl);
    float fc = powf(1.0f - vh, 5.0f);
    float fd = 0.04f + 0.96f * fc; /* the dielectric's Fresnel of the Lambertian mix */
    for (int c = 0; c < 3; c++) {
        float fs = b->f0[c] + (1.0f - b->f0[c]) * fc;
        f[c] = ((1.0f - fd) * b->c_diff[c] * (float)IBL_INV_PI + fs * d * v) * nl;
    }
    return pdf + b->p_spec * d * nh / (4.0f * vh);
}

static ibl_vec3 reflect(ibl_vec3 wo, ibl_vec3 h)
{
    return ibl__sub(ibl__scale(h, 2.0f * ibl__dot(wo, h)), wo);
}

static ibl_vec3 cosine_direction(ibl_vec3 n, float u0, float u1)
{
    ibl_vec3 t, b;
    ibl__frame(n, &t, &b);
    float r = sqrtf(u0), phi = 2.0f * IBL_PI_F * u1;
    float x = r * cosf(phi), y = r * sinf(phi), z = sqrtf(fmaxf(0.0f, 1.0f - u0));
    return ibl__norm(ibl__add(ibl__add(ibl__scale(t, x), ibl__scale(b, y)), ibl__scale(n, z)));
}

static ibl_vec3 brdf_sample(const brdf *b, ibl_vec3 wo, rng *r)
{
    float choose = rnd(r), u0 = rnd(r), u1 = rnd(r);
    if (choose < b->p_spec) return reflect(wo, ibl__sample_ggx(b->n, b->alpha, u0, u1));
    return cosine_direction(b->n, u0, u1);
}

static float power_heuristic(float a, float b)
{
    return a > 0.0f ? a * a / (a * a + b * b) : 0.0f;
}

/* ---- one path ------------------------------------------------------------------------------ */

typedef struct tracer {
    const ibl_scene *scene;
    const ibl_cubemap *env;
    const ibl__env_sampler *env_sampler;
    const emitters *lights;
    int bounces;   /* -1: emission only */
    int light_sampling;
    float eps;     /* ray offset */
} tracer;

static void env_radiance(const tracer *tr, ibl_vec3 d, float out[3])
{
    float t[4];
    ibl_cubemap_sample_nearest(tr->env, 0, d, t);
    out[0] = t[0], out[1] = t[1], out[2] = t[2];
}

static ibl_vec3 offset(const tracer *tr, const ibl_scene_hit *h, ibl_vec3 dir)
{
    float side = ibl__dot(h->geometric_normal, dir) >= 0.0f ? 1.0f : -1.0f;
    return ibl__add(h->position, ibl__scale(h->geometric_normal, side * tr->eps));
}

/* emission seen at a hit from direction d: only the front of an emitter (its wound normal) */
static int front_facing(const ibl_scene *s, const ibl_scene_hit *h, ibl_vec3 d)
{
    const float *fn = s->face_normals + 3 * h->triangle;
    return fn[0] * d.x + fn[1] * d.y + fn[2] * d.z < 0.0f;
}

static void add(float acc[3], const float thr[3], const float l[3], float w)
{
    for (int c = 0; c < 3; c++) acc[c] += thr[c] * l[c] * w;
}

/* Next-event estimation at a hit: one emitter sample and one environment sample. */
static void direct_light(const tracer *tr, const ibl_scene_hit *h, const brdf *b, ibl_vec3 wo,
                         const float thr[3], rng *r, float acc[3])
{
    const ibl_scene *s = tr->scene;
    float f[3];
    float u0 = rnd(r), u1 = rnd(r), u2 = rnd(r);
    if (tr->lights->count > 0) {
        ibl_vec3 q;
        int t;
        emitter_sample(s, tr->lights, u0, u1, u2, &q, &t);
        ibl_vec3 o = offset(tr, h, ibl__sub(q, h->position));
        ibl_vec3 to = ibl__sub(q, o);
        float dist2 = ibl__dot(to, to), dist = sqrtf(dist2);
        ibl_vec3 wi = ibl__scale(to, 1.0f / fmaxf(dist, 1e-20f));
        const float *fn = s->face_normals + 3 * t;
        float cos_l = -(fn[0] * wi.x + fn[1] * wi.y + fn[2] * wi.z); /* front faces emit */
        float bpdf = brdf_eval(b, wo, wi, f);
        if (cos_l > 0.0f && bpdf > 0.0f && !ibl_scene_occluded(s, o, wi, 0.0f, dist * (1.0f - 1e-4f) - tr->eps)) {
            float lpdf = (float)(emitter_area_pdf(s, tr->lights, t) * dist2 / cos_l);
            const float *le = s->materials[s->material_ids[t]].emissive;
            float w = power_heuristic(lpdf, bpdf) / lpdf;
            for (int c = 0; c < 3; c++) acc[c] += thr[c] * f[c] * le[c] * w;
        }
    }
    float epdf;
    ibl_vec3 wi = ibl__env_sampler_sample(tr->env_sampler, rnd(r), rnd(r), &epdf);
    float bpdf = brdf_eval(b, wo, wi, f);
    if (bpdf > 0.0f && epdf > 0.0f && !ibl_scene_occluded(s, offset(tr, h, wi), wi, 0.0f, FLT_MAX)) {
        float le[3];
        env_radiance(tr, wi, le);
        float w = power_heuristic(epdf, bpdf) / epdf;
        for (int c = 0; c < 3; c++) acc[c] += thr[c] * f[c] * le[c] * w;
    }
}

/* Radiance along a path that starts with the hit h (seen along d); adds to acc. */
static void trace_path(const tracer *tr, ibl_scene_hit h, ibl_vec3 d, rng *r, float acc[3])
{
    const ibl_scene *s = tr->scene;
    float thr[3] = {1.0f, 1.0f, 1.0f};
    float prev_pdf = 0.0f; /* density of the BRDF sample that found h (0: camera ray) */
    for (int depth = 0;; depth++) {
        ibl_scene_surface surf;
        ibl_scene_surface_at(s, &h, &surf);
        if (luminance(surf.emissive) > 0.0f && front_facing(s, &h, d)) {
            float w = 1.0f;
            if (prev_pdf > 0.0f && tr->light_sampling) {
                float cos_l = fabsf(ibl__dot(h.geometric_normal, d));
                float lpdf = (float)(emitter_area_pdf(s, tr->lights, h.triangle) * h.t * h.t /
                                     fmaxf(cos_l, 1e-8f));
                w = power_heuristic(prev_pdf, lpdf);
            }
            add(acc, thr, surf.emissive, w);
        }
        if (depth >= tr->bounces) return;
        ibl_vec3 wo = ibl__scale(d, -1.0f);
        ibl_vec3 n = ibl__dot(h.normal, wo) > 0.0f ? h.normal : h.geometric_normal;
        brdf b;
        brdf_init(&surf, n, &b);
        if (tr->light_sampling) direct_light(tr, &h, &b, wo, thr, r, acc);
        ibl_vec3 wi = brdf_sample(&b, wo, r);
        float f[3];
        float pdf = brdf_eval(&b, wo, wi, f);
        if (!(pdf > 0.0f) || ibl__dot(wi, h.geometric_normal) <= 0.0f) return;
        for (int c = 0; c < 3; c++) thr[c] *= f[c] / pdf;
        ibl_scene_hit next;
        if (!ibl_scene_intersect(s, offset(tr, &h, wi), wi, 0.0f, FLT_MAX, &next)) {
            float le[3];
            env_radiance(tr, wi, le);
            float w = tr->light_sampling
                          ? power_heuristic(pdf, ibl__env_sampler_pdf(tr->env_sampler, wi)) : 1.0f;
            add(acc, thr, le, w);
            return;
        }
        h = next;
        d = wi;
        prev_pdf = pdf;
    }
}

/* ---- the cube -------------------------------------------------------------------------------- */

/* distance from p (inside) to the surface of the volume along the unit direction d */
static float exit_distance(const ibl_volume *v, ibl_vec3 p, ibl_vec3 d)
{
    double o[3] = {p.x - v->center.x, p.y - v->center.y, p.z - v->center.z};
    double dd[3] = {d.x, d.y, d.z};
    if (v->shape == IBL_VOLUME_SPHERE) {
        double b = ibl__dot_d(o, dd), c = ibl__dot_d(o, o) - (double)v->radius * v->radius;
        double disc = b * b - c;
        return disc > 0.0 ? (float)fmax(0.0, -b + sqrt(disc)) : 0.0f;
    }
    const double h[3] = {v->half_extent.x, v->half_extent.y, v->half_extent.z};
    double t = DBL_MAX;
    for (int k = 0; k < 3; k++)
        if (dd[k] != 0.0) t = fmin(t, ((dd[k] > 0 ? h[k] : -h[k]) - o[k]) / dd[k]);
    return (float)fmax(0.0, t);
}

typedef struct capture_job {
    tracer tr;
    const ibl_local_probe *probe;
    uint64_t probe_key;
    int size, samples, face, row0;
    ibl_cubemap *out;
} capture_job;

static void texel(const capture_job *j, int face, int x, int y, float out[4])
{
    const tracer *tr = &j->tr;
    double sum[3] = {0, 0, 0};
    int covered = 0;
    uint64_t texel_key = mix64(j->probe_key ^ mix64(((uint64_t)face << 48) ^
                                                   ((uint64_t)y << 24) ^ (uint64_t)x));
    for (int i = 0; i < j->samples; i++) {
        rng r = {mix64(texel_key ^ (uint64_t)i), 0};
        float s = ((float)x + rnd(&r)) / (float)j->size, t = ((float)y + rnd(&r)) / (float)j->size;
        ibl_vec3 d = ibl__norm(ibl_cube_direction(face, s, t));
        /* geometry on the volume's surface (a room's walls on its box) counts as inside */
        float tmax = j->probe->capture == IBL_CAPTURE_FAR_PLANE
                         ? exit_distance(&j->probe->influence, j->probe->position, d) * 1.001f +
                               4.0f * tr->eps
                         : FLT_MAX;
        ibl_scene_hit h;
        float acc[3] = {0, 0, 0};
        if (ibl_scene_intersect(tr->scene, j->probe->position, d, 0.0f, tmax, &h)) {
            trace_path(tr, h, d, &r, acc);
            covered++;
        } else if (j->probe->capture == IBL_CAPTURE_INFINITE) {
            env_radiance(tr, d, acc);
            covered++;
        }
        if (isfinite(acc[0]) && isfinite(acc[1]) && isfinite(acc[2]))
            for (int c = 0; c < 3; c++) sum[c] += acc[c];
    }
    for (int c = 0; c < 3; c++) out[c] = (float)(sum[c] / j->samples);
    out[3] = (float)covered / (float)j->samples;
}

static void capture_task(void *arg, int index)
{
    const capture_job *j = arg;
    int y0 = j->row0 + index * ROWS_PER_TASK;
    float *face = ibl_cubemap_face(j->out, 0, j->face);
    for (int y = y0; y < y0 + ROWS_PER_TASK && y < j->size; y++)
        for (int x = 0; x < j->size; x++)
            texel(j, j->face, x, y, face + ((size_t)y * j->size + x) * 4);
}

static ibl_status run_faces(ibl_context *ctx, capture_job *j)
{
    char stage[96];
    snprintf(stage, sizeof stage, "capture %s", j->probe->name);
    int rows_per_step = (j->size + PROGRESS_STEPS - 1) / PROGRESS_STEPS;
    for (int f = 0; f < 6; f++)
        for (int row0 = 0; row0 < j->size; row0 += rows_per_step) {
            ibl_status st = ibl__progress(ctx, stage, (f * j->size + row0) / (6.0 * j->size));
            if (st != IBL_OK) return st;
            int rows = j->size - row0 < rows_per_step ? j->size - row0 : rows_per_step;
            j->face = f;
            j->row0 = row0;
            ibl_parallel_for(ctx, (rows + ROWS_PER_TASK - 1) / ROWS_PER_TASK, capture_task, j);
        }
    return ibl__progress(ctx, stage, 1.0);
}

ibl_status ibl_capture_probe(ibl_context *ctx, const ibl_scene *scene,
                             const ibl_cubemap *environment, const ibl_local_probe *probe,
                             int probe_index, const ibl_capture_desc *desc, ibl_cubemap *out)
{
    if (!ctx || !scene || !environment || !probe || !out) return IBL_ERR_INVALID_ARGUMENT;
    ibl_capture_desc d;
    memset(&d, 0, sizeof d);
    if (desc) d = *desc;
    int bounces = d.bounces == IBL_CAPTURE_NO_BOUNCE ? 0 : d.bounces ? d.bounces : DEFAULT_BOUNCES;
    int samples = d.samples ? d.samples : DEFAULT_SAMPLES;
    int size = d.size ? d.size : probe->size;
    if (bounces < 0 || bounces > 64 || samples < 1 || samples > (1 << 20) || size < 1 || size > 4096)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "capture %s: bounces must be 0..64, "
                         "samples 1..1048576, size 1..4096", probe->name);
    emitters lights;
    ibl_status st = emitters_init(ctx, scene, &lights);
    ibl__env_sampler *es = st == IBL_OK ? ibl__env_sampler_create(ctx, environment) : NULL;
    if (st == IBL_OK && !es) st = IBL_ERR_OUT_OF_MEMORY;
    if (st == IBL_OK) st = ibl_cubemap_alloc(ctx, size, 1, out);
    if (st == IBL_OK) {
        float extent = 0.0f;
        for (int k = 0; k < 3; k++)
            extent = fmaxf(extent, fmaxf(fabsf(scene->bounds_min[k]), fabsf(scene->bounds_max[k])));
        capture_job j;
        memset(&j, 0, sizeof j);
        j.tr = (tracer){scene, environment, es, &lights, bounces, !d.no_light_sampling,
                        1e-4f * (1.0f + extent)};
        j.probe = probe;
        j.probe_key = mix64(mix64((uint64_t)d.seed) ^ (uint64_t)(uint32_t)probe_index);
        j.size = size;
        j.samples = samples;
        j.out = out;
        st = run_faces(ctx, &j);
        if (st != IBL_OK) ibl_cubemap_free(ctx, out);
    }
    ibl__env_sampler_destroy(ctx, es);
    emitters_free(ctx, &lights);
    return st;
}

/* ---- a camera's view (ibl render --reference) ---------------------------------------------- */

typedef struct view_job {
    tracer tr;
    const ibl_camera *cam;
    uint64_t key;
    int samples;
    ibl_image *out;
    int row0;
} view_job;

static void view_row(void *arg, int index)
{
    const view_job *j = arg;
    int y = j->row0 + index;
    const ibl_camera *cam = j->cam;
    for (int x = 0; x < cam->width; x++) {
        uint64_t pk = mix64(j->key ^ mix64(((uint64_t)y << 24) ^ (uint64_t)x));
        double sum[3] = {0, 0, 0};
        for (int i = 0; i < j->samples; i++) {
            rng r = {mix64(pk ^ (uint64_t)i), 0};
            float px = (float)x + rnd(&r), py = (float)y + rnd(&r);
            ibl_vec3 d = ibl__norm(ibl_camera_ray(cam, px, py));
            float acc[3] = {0, 0, 0};
            ibl_scene_hit h;
            if (ibl_scene_intersect(j->tr.scene, cam->position, d, 0.0f, FLT_MAX, &h))
                trace_path(&j->tr, h, d, &r, acc);
            else
                env_radiance(&j->tr, d, acc);
            if (isfinite(acc[0]) && isfinite(acc[1]) && isfinite(acc[2]))
                for (int c = 0; c < 3; c++) sum[c] += acc[c];
        }
        float *o = j->out->pixels + ((size_t)y * cam->width + x) * 4;
        for (int c = 0; c < 3; c++) o[c] = (float)(sum[c] / j->samples);
        o[3] = 1.0f;
    }
}

ibl_status ibl_trace_view(ibl_context *ctx, const ibl_scene *scene, const ibl_cubemap *environment,
                          const ibl_camera *cam, const ibl_trace_desc *desc, ibl_image *out)
{
    if (!ctx || !scene || !environment || !cam || !out || cam->width < 1 || cam->height < 1)
        return IBL_ERR_INVALID_ARGUMENT;
    ibl_trace_desc d;
    memset(&d, 0, sizeof d);
    if (desc) d = *desc;
    int bounces = d.bounces == IBL_CAPTURE_NO_BOUNCE ? 0 : d.bounces ? d.bounces : DEFAULT_BOUNCES;
    int samples = d.samples ? d.samples : DEFAULT_SAMPLES;
    emitters lights;
    ibl_status st = emitters_init(ctx, scene, &lights);
    ibl__env_sampler *es = st == IBL_OK ? ibl__env_sampler_create(ctx, environment) : NULL;
    if (st == IBL_OK && !es) st = IBL_ERR_OUT_OF_MEMORY;
    if (st == IBL_OK) st = ibl_image_alloc(ctx, cam->width, cam->height, out);
    if (st == IBL_OK) {
        float extent = 0.0f;
        for (int k = 0; k < 3; k++)
            extent = fmaxf(extent, fmaxf(fabsf(scene->bounds_min[k]), fabsf(scene->bounds_max[k])));
        view_job j = {{scene, environment, es, &lights, bounces, 1, 1e-4f * (1.0f + extent)},
                      cam, mix64(mix64((uint64_t)d.seed) ^ 0x7669657775ull), samples, out, 0};
        int step = cam->height / 8 > 0 ? cam->height / 8 : 1;
        for (int y0 = 0; y0 < cam->height && st == IBL_OK; y0 += step) {
            st = ibl__progress(ctx, "reference", (double)y0 / cam->height);
            if (st != IBL_OK) break;
            int rows = cam->height - y0 < step ? cam->height - y0 : step;
            j.row0 = y0;
            ibl_parallel_for(ctx, rows, view_row, &j);
        }
        if (st != IBL_OK) ibl_image_free(ctx, out);
    }
    ibl__env_sampler_destroy(ctx, es);
    emitters_free(ctx, &lights);
    return st;
}
