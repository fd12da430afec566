/* The preview ray tracer: a pinhole camera looking down -Z at a grid of spheres (or a mesh)
 * in front of the environment. Runtime mode shades with ibl_shade (what an engine would do
 * with the bake); reference mode integrates the same BRDF against the unfiltered
 * environment by Monte Carlo (importance sampling of each lobe with a per-pixel rotated
 * Hammersley set), so the difference is the error of the whole baked pipeline. */
#include "render_internal.h"

#include "ibl/io.h"

#include <float.h>
#include <stdio.h>
#include <string.h>

static const float PI_F = 3.14159265358979f;

enum { COLUMNS = 7, ROWS = 3, OBJECTS = COLUMNS * ROWS };
static const float SPACING = 1.1f, RADIUS = 0.48f, EYE_Z = 12.0f;

static const float gold[3] = {1.0f, 0.766f, 0.336f};
static const float white[3] = {0.8f, 0.8f, 0.8f};
static const float copper[3] = {0.955f, 0.638f, 0.538f};
static const float shininess_row[COLUMNS] = {1.0f, 10.0f, 50.0f, 200.0f, 1000.0f, 5000.0f, 100000.0f};

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
    /* GGX at alpha = 0 is a delta; 1e-3 is far below what any cube level resolves */
    b.alpha = fmaxf(m->roughness * m->roughness, 1e-3f);
    b.shininess = m->shininess;
    b.nv = nv;
    int given = m->f0[0] != 0.0f || m->f0[1] != 0.0f || m->f0[2] != 0.0f;
    for (int c = 0; c < 3; c++) {
        if (b.bp) {
            b.f0[c] = m->f0[c];
            b.kd[c] = m->base_color[c] * (1.0f - m->f0[c]);
        } else {
            float fd = given ? m->f0[c] : 0.04f;
            b.f0[c] = fd + (m->base_color[c] - fd) * m->metallic;
            b.kd[c] = m->base_color[c] * (1.0f - m->metallic);
        }
    }
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
        pdf = (b->shininess + 1.0f) / (2.0f * PI_F) * lobe_h / (4.0f * vh);
    } else {
        float d = ibl_ggx_d(b->alpha, nh);
        spec = d * ibl_smith_ggx_v(b->alpha, b->nv, nl);
        pdf = d * nh / (4.0f * vh);
    }
    for (int c = 0; c < 3; c++) f[c] = spec * ibl_fresnel_schlick(b->f0[c], vh) + b->kd[c] / PI_F;
    *pdf_spec = pdf;
    *pdf_diff = nl / PI_F;
    return nl;
}

/* Monte Carlo estimate of the reflected radiance: three strategies (the specular lobe, the
 * cosine lobe, the environment's luminance), one sample of each per iteration, combined with
 * the balance heuristic (Veach 1997, multi-sample MIS): each adds f L n.l / sum of the three
 * densities. No split sum, no prefiltering. */
static void reference_shade(const render_job *job, const ibl_material *m, ibl_vec3 n, ibl_vec3 v,
                            uint32_t pixel, float out[3])
{
    float scale = job->probe->intensity > 0.0f ? job->probe->intensity : 1.0f;
    int ns = job->samples;
    lobe b = make_lobe(m, fmaxf(ibl__dot(n, v), 1e-4f));
    uint32_t h0 = ibl__hash(pixel * 2654435761u ^ job->desc->seed);
    uint32_t h1 = ibl__hash(h0 + 0x68bc21ebu);
    float r0 = (float)(h0 >> 8) * (1.0f / 16777216.0f), r1 = (float)(h1 >> 8) * (1.0f / 16777216.0f);
    double acc[3] = {0, 0, 0};
    ibl_vec3 t, bt;
    ibl__frame(n, &t, &bt);
    for (int i = 0; i < ns; i++) {
        float u0, u1;
        ibl__hammersley((uint32_t)i, (uint32_t)ns, r0, r1, &u0, &u1);
        ibl_vec3 dirs[3];
        float env_pdf[3];
        /* specular lobe */
        ibl_vec3 h = b.bp ? ibl__sample_phong(n, b.shininess, u0, u1) : ibl__sample_ggx(n, b.alpha, u0, u1);
        float vh = ibl__dot(v, h);
        dirs[0] = ibl__v3(2.0f * vh * h.x - v.x, 2.0f * vh * h.y - v.y, 2.0f * vh * h.z - v.z);
        env_pdf[0] = -1.0f;
        /* cosine lobe */
        float rr = sqrtf(u1), phi = 2.0f * PI_F * u0;
        float x = rr * cosf(phi), y = rr * sinf(phi), z = sqrtf(fmaxf(0.0f, 1.0f - u1));
        dirs[1] = ibl__v3(t.x * x + bt.x * y + n.x * z, t.y * x + bt.y * y + n.y * z,
                          t.z * x + bt.z * y + n.z * z);
        env_pdf[1] = -1.0f;
        /* environment */
        dirs[2] = ibl__env_sampler_sample(job->sampler, u0, u1, &env_pdf[2]);
        for (int k = 0; k < 3; k++) {
            float f[3], ps, pd;
            float nl = eval_lobe(&b, n, v, dirs[k], f, &ps, &pd);
            if (nl <= 0.0f) continue;
            float pe = env_pdf[k] >= 0.0f ? env_pdf[k] : ibl__env_sampler_pdf(job->sampler, dirs[k]);
            float sum = ps + pd + pe;
            if (!(sum > 0.0f)) continue;
            float l_rad[3];
            env_radiance(job->env, scale, dirs[k], l_rad);
            for (int c = 0; c < 3; c++) acc[c] += (double)(f[c] * l_rad[c] * nl / sum);
        }
    }
    for (int c = 0; c < 3; c++) out[c] = (float)(acc[c] / ns);
}

static void render_row(void *arg, int y)
{
    render_job *job = arg;
    const ibl_render_desc *desc = job->desc;
    ibl_image *im = job->out;
    ibl_vec3 eye = {0.0f, 0.0f, EYE_Z};
    float scale = job->probe->intensity > 0.0f ? job->probe->intensity : 1.0f;
    for (int x = 0; x < im->width; x++) {
        float px = ((float)x + 0.5f) / (float)im->width * 2.0f - 1.0f;
        float py = 1.0f - ((float)y + 0.5f) / (float)im->height * 2.0f;
        ibl_vec3 d = ibl__norm(ibl__v3(px * job->half_w, py * job->half_h, -EYE_Z));
        float *dst = ibl_image_texel(im, x, y);
        float t, ao = 1.0f;
        ibl_vec3 n;
        int id;
        ibl_material mat;
        if (desc->mesh) {
            id = ibl__mesh_intersect(desc->mesh, eye, d, &t, &n, &ao) ? 0 : -1;
            static const float grey[3] = {0.9f, 0.9f, 0.9f};
            mat = ibl_material_gltf(grey, 1.0f, 0.3f);
        } else {
            id = hit_spheres(eye, d, &t);
            if (id >= 0) {
                ibl_vec3 c = sphere_center(id);
                n = ibl__norm(ibl__v3(eye.x + t * d.x - c.x, eye.y + t * d.y - c.y, eye.z + t * d.z - c.z));
                mat = job->objects[id].material;
                if (desc->sphere_ao_min > 0.0f)
                    ao = desc->sphere_ao_min + (1.0f - desc->sphere_ao_min) * 0.5f * (n.y + 1.0f);
            }
        }
        if (job->ids) job->ids[(size_t)y * im->width + x] = id;
        if (id < 0) {
            env_radiance(job->env, scale, d, dst);
            dst[3] = 1.0f;
            continue;
        }
        ibl_vec3 v = ibl__v3(-d.x, -d.y, -d.z);
        mat.ao = ao;
        if (desc->reference) {
            reference_shade(job, &mat, n, v, (uint32_t)((size_t)y * im->width + x), dst);
        } else {
            ibl_surface s;
            memset(&s, 0, sizeof s);
            s.n = n;
            s.v = v;
            ibl_shade_result r;
            ibl_shade(job->probe, &desc->shade, &mat, &s, &r);
            memcpy(dst, r.color, 3 * sizeof(float));
        }
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
        return ibl_fail(ctx, IBL_ERR_INVALID_ARGUMENT, "render: no probe");
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
            im->pixels[i * 4 + c] = ibl_tonemap_apply(IBL_TONEMAP_FILMIC, im->pixels[i * 4 + c] * s);
}
