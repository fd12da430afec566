/* The preview ray tracer: a pinhole camera looking down -Z at a grid of spheres (or a mesh)
 * in front of the environment. Runtime mode shades with ibl_shade (what an engine would do
 * with the bake); reference mode integrates the same BRDF against the unfiltered
 * environment by Monte Carlo (importance sampling of each lobe with a per-pixel rotated
 * Hammersley set), so the difference is the error of the whole baked pipeline. Punctual
 * lights: ibl_lights_shade in runtime mode; in reference mode each light as what it is, a
 * delta or a cone of uniform radiance (reference_light). */
#include "render_internal.h"
#include "core/context_internal.h"
#include "core/numeric.h"
#include "core/defaults.h"

#include "ibl/io.h"

#include <float.h>
#include <stdio.h>
#include <string.h>


enum { COLUMNS = 7, ROWS = 3, OBJECTS = COLUMNS * ROWS };
static const float SPACING = 1.1f, RADIUS = 0.48f, EYE_Z = 12.0f;

static const float gold[3] = {1.0f, 0.766f, 0.336f};
static const float white[3] = {0.8f, 0.8f, 0.8f};
static const float copper[3] = {0.955f, 0.638f, 0.538f};
static const float shininess_row[COLUMNS] = {1.0f,    10.0f,   50.0f,    200.0f,
                                             1000.0f, 5000.0f, 100000.0f};

int ibl_render_scene_objects(ibl_render_object *objects, int max_objects)
{
    int count = 0;
    for (int row = 0; row < ROWS; row++)
        for (int col = 0; col < COLUMNS && count < max_objects; col++, count++) {
            ibl_render_object *o = &objects[count];
            float r = (float)col / (float)(COLUMNS - 1);
            if (row < 2) {
                o->material = ibl_material_gltf(row == 0 ? gold : white, row == 0 ? 1.0f : 0.0f, r);
                snprintf(o->label, sizeof o->label, "%s r=%.2f", row == 0 ? "metal" : "dielectric",
                         (double)r);
            } else {
                static const float black[3] = {0.02f, 0.02f, 0.02f};
                o->material = ibl_material_blinn_phong(black, copper, shininess_row[col]);
                snprintf(o->label, sizeof o->label, "blinn-phong n=%g", (double)shininess_row[col]);
            }
        }
    return count;
}

static ibl_vec3 sphere_center(int index)
{
    int row = index / COLUMNS, col = index % COLUMNS;
    return ibl__v3(((float)col - 0.5f * (COLUMNS - 1)) * SPACING,
                   (0.5f * (ROWS - 1) - (float)row) * SPACING, 0.0f);
}

/* Nearest hit of the ray o + t d (|d| = 1) with the spheres; -1 if none. */
static int hit_spheres(ibl_vec3 o, ibl_vec3 d, float *t_out)
{
    int best = -1;
    float best_t = FLT_MAX;
    for (int i = 0; i < OBJECTS; i++) {
        ibl_vec3 c = sphere_center(i);
        ibl_vec3 oc = ibl__v3(o.x - c.x, o.y - c.y, o.z - c.z);
        float b = ibl__dot(oc, d);
        float q = ibl__dot(oc, oc) - RADIUS * RADIUS;
        float disc = b * b - q;
        if (disc < 0.0f) continue;
        float t = -b - sqrtf(disc);
        if (t > 1e-4f && t < best_t) {
            best_t = t;
            best = i;
        }
    }
    *t_out = best_t;
    return best;
}

/* mesh.c */
int ibl__mesh_intersect(const ibl_mesh *mesh, ibl_vec3 o, ibl_vec3 d, float *t, ibl_vec3 *n,
                        float *ao);

typedef struct render_job {
    const ibl_probe *probe;
    const ibl_render_desc *desc;
    const ibl_cubemap *env;
    ibl_render_object objects[OBJECTS];
    ibl_image *out;
    int *ids;
    float half_w, half_h;
    int samples;
    ibl__env_sampler *sampler;
} render_job;

static void env_radiance(const ibl_cubemap *env, float scale, ibl_vec3 d, float out[3])
{
    float c[4];
    ibl_cubemap_sample_bilinear(env, 0, d, c);
    for (int k = 0; k < 3; k++) out[k] = c[k] * scale;
}

/* What the reference needs of a material at one pixel. */
typedef struct lobe {
    int bp;
    float alpha, shininess, nv;
    float f0[3], kd[3];
} lobe;

static lobe make_lobe(const ibl_material *m, float nv)
{
    lobe b;
    b.bp = m->model == IBL_MATERIAL_BLINN_PHONG;
    b.alpha = fmaxf(m->roughness * m->roughness, IBL_MIN_GGX_ALPHA);
    b.shininess = m->shininess;
    b.nv = nv;
    ibl_material_reflectances(m, b.f0, b.kd);
    return b;
}

/* f(l) (RGB, diffuse + specular) and the densities of the two BRDF strategies at l. Returns
 * n.l (0 when l is under the surface, with f and the densities 0). */
static float eval_lobe(const lobe *b, ibl_vec3 n, ibl_vec3 v, ibl_vec3 l, float f[3],
                       float *pdf_spec, float *pdf_diff)
{
    float nl = ibl__dot(n, l);
    *pdf_spec = *pdf_diff = 0.0f;
    f[0] = f[1] = f[2] = 0.0f;
    if (nl <= 0.0f) return 0.0f;
    ibl_vec3 h = ibl__norm(ibl__v3(v.x + l.x, v.y + l.y, v.z + l.z));
    float nh = fmaxf(ibl__dot(n, h), 0.0f), vh = fmaxf(ibl__dot(v, h), 1e-6f);
    float spec, pdf;
    if (b->bp) {
        /* tri-Ace 2010: (c1 s + c2) F (n.h)^s / max(n.l, n.v) */
        float lobe_h = powf(nh, b->shininess);
        spec = ibl_blinn_phong_norm(b->shininess) * lobe_h / fmaxf(nl, b->nv);
        pdf = (b->shininess + 1.0f) / (2.0f * IBL_PI_F) * lobe_h / (4.0f * vh);
    } else {
        float d = ibl_ggx_d(b->alpha, nh);
        spec = d * ibl_smith_ggx_v(b->alpha, b->nv, nl);
        pdf = d * nh / (4.0f * vh);
    }
    for (int c = 0; c < 3; c++) f[c] = spec * ibl_fresnel_schlick(b->f0[c], vh) + b->kd[c] / IBL_PI_F;
    *pdf_spec = pdf;
    *pdf_diff = nl / IBL_PI_F;
    return nl;
}

/* The cone a light of finite size subtends at a point: its axis is in->l, its half-angle
 * theta with 1 - cos(theta) = *one_minus_cos (kept apart from cos: a sun's is ~1e-5, near
 * float's resolution of cos itself), and the uniform radiance that delivers the illuminance
 * of the delta light, E = L pi sin^2(theta) on a surface facing it. Returns 0 for a delta
 * light (or a point inside its own sphere, where the reference keeps the delta). */
static int light_cone(const ibl_light *light, const ibl_light_incidence *in, float *one_minus_cos,
                      float *radiance_scale)
{
    float sin2;
    if (!(in->size > 0.0f)) return 0;
    if (light->type == IBL_LIGHT_DIRECTIONAL) {
        sin2 = in->size * in->size / (1.0f + in->size * in->size); /* size = tan(theta) */
    } else {
        if (!(in->distance > in->size)) return 0;
        float s = in->size / in->distance; /* a sphere: sin(theta) = radius / distance */
        sin2 = s * s;
    }
    *one_minus_cos = sin2 / (1.0f + sqrtf(1.0f - sin2));
    *radiance_scale = 1.0f / (IBL_PI_F * sin2);
    return 1;
}

/* One light's share of one reference iteration. A delta light is exact: f(l) E n.l. A light
 * of finite size is a cone of uniform radiance, integrated with three strategies (a direction
 * uniform in the cone, and the BRDF's specular and cosine samples of this iteration, which
 * see the light when they fall in its cone), combined with the balance heuristic like the
 * environment: each adds f L n.l / (p_cone + p_spec + p_diff). */
static void reference_light(const ibl_light *light, const lobe *b, ibl_vec3 n, ibl_vec3 v,
                            ibl_vec3 p, const ibl_vec3 brdf_dirs[2], float u0, float u1,
                            double acc[3])
{
    ibl_light_incidence in;
    ibl_light_incidence_at(light, p, &in);
    if (!(in.illuminance[0] > 0.0f || in.illuminance[1] > 0.0f || in.illuminance[2] > 0.0f))
        return;
    float one_minus_cos, radiance_scale, f[3], ps, pd;
    if (!light_cone(light, &in, &one_minus_cos, &radiance_scale)) {
        float nl = eval_lobe(b, n, v, in.l, f, &ps, &pd);
        for (int c = 0; c < 3 && nl > 0.0f; c++)
            acc[c] += (double)(f[c] * in.illuminance[c] * nl);
        return;
    }
    /* the cone sample, from its own rotation of this iteration's point */
    float w0 = u0 + 0.6180340f, w1 = u1 + 0.4142136f;
    w0 -= floorf(w0);
    w1 -= floorf(w1);
    float x = w1 * one_minus_cos; /* 1 - cos of the sampled angle */
    float sin_t = sqrtf(fmaxf(0.0f, x * (2.0f - x))), phi = 2.0f * IBL_PI_F * w0;
    ibl_vec3 t, bt;
    ibl__frame(in.l, &t, &bt);
    float a = sin_t * cosf(phi), c2 = sin_t * sinf(phi), z = 1.0f - x;
    ibl_vec3 dirs[3] = {ibl__v3(t.x * a + bt.x * c2 + in.l.x * z, t.y * a + bt.y * c2 + in.l.y * z,
                                t.z * a + bt.z * c2 + in.l.z * z),
                        brdf_dirs[0], brdf_dirs[1]};
    float cone_pdf = 1.0f / (2.0f * IBL_PI_F * one_minus_cos);
    for (int k = 0; k < 3; k++) {
        /* inside the cone: 1 - l.axis = |l - axis|^2 / 2 <= 1 - cos(theta), without the
         * cancellation of 1 - dot for small cones */
        ibl_vec3 d = ibl__sub(dirs[k], in.l);
        int inside = k == 0 || 0.5f * ibl__dot(d, d) <= one_minus_cos;
        if (k > 0 && !inside) continue;
        float nl = eval_lobe(b, n, v, dirs[k], f, &ps, &pd);
        if (nl <= 0.0f) continue;
        float sum = ps + pd + (inside ? cone_pdf : 0.0f);
        for (int c = 0; c < 3; c++)
            acc[c] += (double)(f[c] * in.illuminance[c] * radiance_scale * nl / sum);
    }
}

/* One iteration of the Monte Carlo estimate of the reflected radiance: three strategies (the
 * specular lobe, the cosine lobe, the environment's luminance), one sample of each, combined
 * with the balance heuristic (Veach 1997, multi-sample MIS): each adds f L n.l / the sum of
 * the three densities. No split sum, no prefiltering. */
static void reference_sample(const render_job *job, const lobe *b, ibl_vec3 n, ibl_vec3 v,
                             ibl_vec3 p, float u0, float u1, double acc[3])
{
    float scale = job->probe->intensity > 0.0f ? job->probe->intensity : 1.0f;
    ibl_vec3 t, bt;
    ibl__frame(n, &t, &bt);
    ibl_vec3 dirs[3];
    float env_pdf[3] = {-1.0f, -1.0f, 0.0f};
    /* specular lobe */
    ibl_vec3 h =
        b->bp ? ibl__sample_phong(n, b->shininess, u0, u1) : ibl__sample_ggx(n, b->alpha, u0, u1);
    float vh = ibl__dot(v, h);
    dirs[0] = ibl__v3(2.0f * vh * h.x - v.x, 2.0f * vh * h.y - v.y, 2.0f * vh * h.z - v.z);
    /* cosine lobe */
    float rr = sqrtf(u1), phi = 2.0f * IBL_PI_F * u0;
    float x = rr * cosf(phi), y = rr * sinf(phi), z = sqrtf(fmaxf(0.0f, 1.0f - u1));
    dirs[1] = ibl__v3(t.x * x + bt.x * y + n.x * z, t.y * x + bt.y * y + n.y * z,
                      t.z * x + bt.z * y + n.z * z);
    /* environment */
    dirs[2] = ibl__env_sampler_sample(job->sampler, u0, u1, &env_pdf[2]);
    for (int k = 0; k < 3; k++) {
        float f[3], ps, pd;
        float nl = eval_lobe(b, n, v, dirs[k], f, &ps, &pd);
        if (nl <= 0.0f) continue;
        float pe = env_pdf[k] >= 0.0f ? env_pdf[k] : ibl__env_sampler_pdf(job->sampler, dirs[k]);
        float sum = ps + pd + pe;
        if (!(sum > 0.0f)) continue;
        float l_rad[3];
        env_radiance(job->env, scale, dirs[k], l_rad);
        for (int c = 0; c < 3; c++) acc[c] += (double)(f[c] * l_rad[c] * nl / sum);
    }
    for (int i = 0; i < job->desc->light_count; i++)
        reference_light(&job->desc->lights[i], b, n, v, p, dirs, u0, u1, acc);
}

typedef struct hit {
    int id;
    ibl_vec3 d, n, p; /* ray direction, normal and position of the hit */
    ibl_material mat;
    ibl__skin_hit skin; /* with desc->skin */
} hit;

/* The primary ray through the continuous pixel position (fx, fy) (pixel x covers [x, x+1)). */
static void trace_primary(const render_job *job, float fx, float fy, hit *h)
{
    const ibl_render_desc *desc = job->desc;
    const ibl_image *im = job->out;
    ibl_vec3 eye = {0.0f, 0.0f, EYE_Z};
    float px = fx / (float)im->width * 2.0f - 1.0f;
    float py = 1.0f - fy / (float)im->height * 2.0f;
    h->d = ibl__norm(ibl__v3(px * job->half_w, py * job->half_h, -EYE_Z));
    float t = 0.0f, ao = 1.0f;
    if (desc->skin) {
        h->id = ibl__skin_intersect(desc->skin, eye, h->d, &t, &h->skin) ? 0 : -1;
        h->n = h->skin.n;
        memset(&h->mat, 0, sizeof h->mat);
    } else if (desc->mesh) {
        h->id = ibl__mesh_intersect(desc->mesh, eye, h->d, &t, &h->n, &ao) ? 0 : -1;
        static const float grey[3] = {0.9f, 0.9f, 0.9f};
        h->mat = ibl_material_gltf(grey, 1.0f, 0.3f);
    } else {
        h->id = hit_spheres(eye, h->d, &t);
        if (h->id >= 0) {
            ibl_vec3 c = sphere_center(h->id);
            h->n = ibl__norm(ibl__v3(eye.x + t * h->d.x - c.x, eye.y + t * h->d.y - c.y,
                                     eye.z + t * h->d.z - c.z));
            h->mat = job->objects[h->id].material;
            if (desc->sphere_ao_min > 0.0f)
                ao = desc->sphere_ao_min + (1.0f - desc->sphere_ao_min) * 0.5f * (h->n.y + 1.0f);
        }
    }
    h->mat.ao = ao;
    h->p = ibl__v3(eye.x + t * h->d.x, eye.y + t * h->d.y, eye.z + t * h->d.z);
}

/* Runtime shading of a hit: the probe through ibl_shade, the lights through
 * ibl_lights_shade, their specular the compositions' s_d (so "entire" occludes it) and their
 * diffuse added unoccluded (light.h). */
static void runtime_shade(const render_job *job, const hit *h, float out[3])
{
    const ibl_render_desc *desc = job->desc;
    if (desc->skin) {
        ibl__skin_shade(job->probe, desc, &h->skin, ibl__v3(-h->d.x, -h->d.y, -h->d.z), out);
        return;
    }
    ibl_surface surf;
    memset(&surf, 0, sizeof surf);
    surf.n = h->n;
    surf.v = ibl__v3(-h->d.x, -h->d.y, -h->d.z);
    ibl_light_result direct;
    memset(&direct, 0, sizeof direct);
    if (desc->light_count > 0) {
        ibl_lights_shade(desc->lights, desc->light_count, NULL, &desc->shade, &h->mat, &surf, h->p,
                         &direct);
        memcpy(surf.direct_specular, direct.specular, sizeof surf.direct_specular);
    }
    ibl_shade_result r;
    ibl_shade(job->probe, &desc->shade, &h->mat, &surf, &r);
    for (int c = 0; c < 3; c++) out[c] = r.color[c] + direct.diffuse[c];
}

/* Van der Corput radical inverse in a prime base (the pixel-footprint dimensions). */
static float radical_inverse(uint32_t i, uint32_t base)
{
    float inv = 1.0f / (float)base, f = inv, r = 0.0f;
    while (i > 0) {
        r += f * (float)(i % base);
        i /= base;
        f *= inv;
    }
    return r;
}

static float frac(float x)
{
    return x - floorf(x);
}

static void render_row(void *arg, int y)
{
    render_job *job = arg;
    const ibl_render_desc *desc = job->desc;
    ibl_image *im = job->out;
    float scale = job->probe->intensity > 0.0f ? job->probe->intensity : 1.0f;
    int ss = desc->supersample > 0 ? desc->supersample : 1;
    for (int x = 0; x < im->width; x++) {
        float *dst = ibl_image_texel(im, x, y);
        uint32_t pixel = (uint32_t)((size_t)y * im->width + x);
        hit h;
        trace_primary(job, (float)x + 0.5f, (float)y + 0.5f, &h);
        if (job->ids) job->ids[pixel] = h.id;
        double acc[3] = {0, 0, 0};
        int count;
        if (desc->reference) {
            /* each sample its own point of the pixel: the reference integrates the footprint */
            uint32_t h0 = ibl__hash(pixel * 2654435761u ^ desc->seed);
            uint32_t h1 = ibl__hash(h0 + 0x68bc21ebu), h2 = ibl__hash(h1 + 0x02e5be93u);
            uint32_t h3 = ibl__hash(h2 + 0x967a889bu);
            float r[4] = {(float)(h0 >> 8), (float)(h1 >> 8), (float)(h2 >> 8), (float)(h3 >> 8)};
            for (int k = 0; k < 4; k++) r[k] *= 1.0f / 16777216.0f;
            count = job->samples;
            int last_id = -2;
            lobe b;
            memset(&b, 0, sizeof b);
            for (int i = 0; i < count; i++) {
                float jx = frac(radical_inverse((uint32_t)i + 1, 3) + r[2]);
                float jy = frac(radical_inverse((uint32_t)i + 1, 5) + r[3]);
                hit s;
                trace_primary(job, (float)x + jx, (float)y + jy, &s);
                if (s.id < 0) {
                    float bg[3];
                    env_radiance(job->env, scale, s.d, bg);
                    for (int c = 0; c < 3; c++) acc[c] += bg[c];
                    continue;
                }
                ibl_vec3 v = ibl__v3(-s.d.x, -s.d.y, -s.d.z);
                float nv = fmaxf(ibl__dot(s.n, v), 1e-4f);
                if (s.id != last_id || desc->mesh) {
                    b = make_lobe(&s.mat, nv);
                    last_id = s.id;
                }
                b.nv = nv;
                float u0, u1;
                ibl__hammersley((uint32_t)i, (uint32_t)count, r[0], r[1], &u0, &u1);
                reference_sample(job, &b, s.n, v, s.p, u0, u1, acc);
            }
        } else {
            count = ss * ss;
            for (int sy = 0; sy < ss; sy++)
                for (int sx = 0; sx < ss; sx++) {
                    hit s = h;
                    if (ss > 1)
                        trace_primary(job, (float)x + ((float)sx + 0.5f) / (float)ss,
                                      (float)y + ((float)sy + 0.5f) / (float)ss, &s);
                    float c3[3];
                    if (s.id < 0) {
                        env_radiance(job->env, scale, s.d, c3);
                    } else {
                        runtime_shade(job, &s, c3);
                    }
                    for (int c = 0; c < 3; c++) acc[c] += c3[c];
                }
        }
        for (int c = 0; c < 3; c++) dst[c] = (float)(acc[c] / count);
        dst[3] = 1.0f;
    }
}

ibl_status ibl_render(ibl_context *ctx, const ibl_probe *probe, const ibl_render_desc *desc,
                      ibl_image *out, int *ids)
{
    static const ibl_render_desc defaults;
    if (!desc) desc = &defaults;
    memset(out, 0, sizeof *out);
    if (!probe || !probe->specular.data)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "render: no probe");
    if (desc->light_count < 0 || (desc->light_count > 0 && !desc->lights))
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "render: %d lights and no array",
                         desc->light_count);
    for (int i = 0; i < desc->light_count; i++) {
        ibl_status ls = ibl_light_validate(ctx, &desc->lights[i], i);
        if (ls != IBL_OK) return ls;
    }
    const ibl_render_skin *skin = desc->skin;
    if (skin && (!skin->mesh || !skin->normal || !skin->scattered[0] || !skin->scattered[1] ||
                 !skin->scattered[2]))
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "render: skin without its mesh or maps");
    if (skin && (desc->reference || desc->light_count > 0))
        return ibl__fail(ctx, IBL_ERR_UNSUPPORTED, "render: skin is drawn by the runtime shading "
                         "of the probe only (no reference, no punctual lights)");
    int w = desc->width > 0 ? desc->width : 1024;
    int h = desc->height > 0 ? desc->height : (desc->width > 0 ? (w + 1) / 2 : 512);
    render_job *job = ibl_calloc(ctx, 1, sizeof *job);
    if (!job) return ibl_context_status(ctx);
    job->probe = probe;
    job->desc = desc;
    job->env = desc->environment ? desc->environment
                                 : (probe->mirror.data ? &probe->mirror : &probe->specular);
    ibl_render_scene_objects(job->objects, OBJECTS);
    job->ids = ids;
    job->samples = desc->reference_samples > 0 ? desc->reference_samples : 256;
    float aspect = (float)w / (float)h;
    /* frame the grid: at least 2 units above and below, at least 4.3 to each side */
    float half_h = 2.0f;
    if (half_h * aspect < 4.3f) half_h = 4.3f / aspect;
    job->half_h = half_h;
    job->half_w = half_h * aspect;
    ibl_status st = IBL_OK;
    if (desc->reference) {
        job->sampler = ibl__env_sampler_create(ctx, job->env);
        if (!job->sampler) st = ibl_context_status(ctx);
    }
    if (st == IBL_OK) st = ibl_image_alloc(ctx, w, h, out);
    if (st == IBL_OK) {
        job->out = out;
        ibl_parallel_for(ctx, h, render_row, job);
    }
    ibl__env_sampler_destroy(ctx, job->sampler);
    ibl_free(ctx, job);
    return st;
}

/* The library's filmic curve (io.h: Narkowicz's ACES fit), so a tone-mapped preview and a
 * PNG written from the linear image look the same. */
void ibl_render_tonemap(ibl_image *im, float exposure_ev)
{
    float s = exp2f(exposure_ev);
    size_t n = (size_t)im->width * im->height;
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < 3; c++)
            im->pixels[i * 4 + c] =
                ibl_tonemap_apply(IBL_TONEMAP_FILMIC, im->pixels[i * 4 + c] * s);
}

void ibl_render_bake_desc(const ibl_cubemap *env, int specular_size, ibl_bake_desc *out)
{
    memset(out, 0, sizeof *out);
    int env_size = env ? env->size : 128;
    int size = specular_size > 0 ? specular_size : (env_size < 128 ? env_size : 128);
    if (size > env_size) size = env_size;
    /* levels down to 4x4 (or 1x1 for tiny inputs): smaller levels add nothing for GGX */
    int levels = ibl_full_mip_count(size) - 2;
    out->specular.filter = IBL_FILTER_GGX;
    out->specular.size = size;
    out->specular.levels = levels < 1 ? 1 : levels;
    out->preview_width = -1;
    out->keep_environment = 1;
    /* the Blinn-Phong row reads the AmbientBRDF even on a GGX chain; a small volume is
     * enough for a preview (it is interpolated in log shininess) */
    out->ambient_brdf = 1;
    out->ambient.size_nv = 16;
    out->ambient.size_shininess = 24;
    out->ambient.size_f0 = 8;
    out->source.name = "environment";
}
