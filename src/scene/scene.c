/* Scenes for probe capture: the copy of the caller's triangles and materials, the Embree 3
 * acceleration structure (Intel Embree, "Embree: A Kernel Framework for Efficient CPU Ray
 * Tracing", Wald et al., SIGGRAPH 2014; Debian libembree-dev) and the per-hit queries.
 *
 * Embree runs on a device of its own configured with threads=1: the scenes are small, the
 * build then never competes with the library's pool, and it does not depend on the caller's
 * thread count. The scene is built with RTC_SCENE_FLAG_ROBUST (watertight triangle tests, so
 * rays do not leak through the shared edges of a closed room) and high build quality. */
#include "scene_internal.h"
#include "core/context_internal.h"
#include "core/numeric.h"

#include <float.h>
#include <math.h>
#include <string.h>

ibl_scene_material ibl_scene_material_default(void)
{
    ibl_scene_material m;
    memset(&m, 0, sizeof m);
    m.base_color[0] = m.base_color[1] = m.base_color[2] = 1.0f;
    m.metallic = 1.0f;
    m.roughness = 1.0f;
    m.base_color_texture = m.metallic_roughness_texture = m.emissive_texture = -1;
    return m;
}

static int emits(const ibl_scene_material *m)
{
    return m->emissive[0] > 0.0f || m->emissive[1] > 0.0f || m->emissive[2] > 0.0f;
}

static ibl_status check_desc(ibl_context *ctx, const ibl_scene_desc *d, const char *name)
{
    if (d->vertex_count <= 0 || d->triangle_count <= 0 || !d->positions || !d->indices)
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: the scene has no triangles", name);
    if (d->material_count <= 0 || !d->materials)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "%s: the scene has no material", name);
    for (int i = 0; i < 3 * d->triangle_count; i++)
        if (d->indices[i] >= (uint32_t)d->vertex_count)
            return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: triangle %d uses vertex %u of %d", name,
                             i / 3, d->indices[i], d->vertex_count);
    for (int i = 0; i < 3 * d->vertex_count; i++)
        if (!isfinite(d->positions[i]))
            return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: vertex %d is not finite", name, i / 3);
    for (int i = 0; d->material_ids && i < d->triangle_count; i++)
        if (d->material_ids[i] < 0 || d->material_ids[i] >= d->material_count)
            return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: triangle %d uses material %d of %d",
                             name, i, d->material_ids[i], d->material_count);
    for (int i = 0; i < d->material_count; i++) {
        const ibl_scene_material *m = &d->materials[i];
        const int tex[3] = {m->base_color_texture, m->metallic_roughness_texture,
                            m->emissive_texture};
        for (int k = 0; k < 3; k++)
            if (tex[k] < -1 || tex[k] >= d->texture_count)
                return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: material %d uses texture %d of %d",
                                 name, i, tex[k], d->texture_count);
    }
    return IBL_OK;
}

static ibl_status copy_textures(ibl_context *ctx, ibl_scene *s, const ibl_scene_desc *d)
{
    if (d->texture_count <= 0) return IBL_OK;
    s->textures = ibl_calloc(ctx, (size_t)d->texture_count, sizeof *s->textures);
    if (!s->textures) return IBL_ERR_OUT_OF_MEMORY;
    s->texture_count = d->texture_count;
    for (int i = 0; i < d->texture_count; i++) {
        const ibl_image *src = &d->textures[i];
        ibl_status st = ibl_image_alloc(ctx, src->width, src->height, &s->textures[i]);
        if (st != IBL_OK) return st;
        memcpy(s->textures[i].pixels, src->pixels, (size_t)src->width * src->height * 16);
    }
    return IBL_OK;
}

static void face_geometry(ibl_scene *s)
{
    for (int k = 0; k < 3; k++) {
        s->bounds_min[k] = FLT_MAX;
        s->bounds_max[k] = -FLT_MAX;
    }
    /* the bounds of what the triangles use (an unused vertex may hold anything) */
    for (int i = 0; i < 3 * s->triangle_count; i++)
        for (int k = 0; k < 3; k++) {
            s->bounds_min[k] = fminf(s->bounds_min[k], s->positions[3 * s->indices[i] + k]);
            s->bounds_max[k] = fmaxf(s->bounds_max[k], s->positions[3 * s->indices[i] + k]);
        }
    for (int t = 0; t < s->triangle_count; t++) {
        const float *a = s->positions + 3 * s->indices[3 * t];
        const float *b = s->positions + 3 * s->indices[3 * t + 1];
        const float *c = s->positions + 3 * s->indices[3 * t + 2];
        double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
        double e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]}, n[3];
        ibl__cross_d(e1, e2, n);
        double len = ibl__normalize_d(n);
        s->areas[t] = (float)(0.5 * len);
        for (int k = 0; k < 3; k++) s->face_normals[3 * t + k] = len > 0 ? (float)n[k] : 0.0f;
        if (emits(&s->materials[s->material_ids[t]]) && len > 0) s->emissive_count++;
    }
}

/* vertex normals: the caller's (normalised), or each triangle's own where there are none */
static void vertex_attributes(ibl_scene *s, const ibl_scene_desc *d)
{
    for (int v = 0; v < s->vertex_count; v++) {
        if (d->normals) {
            ibl_vec3 n = ibl__norm(ibl__v3(d->normals[3 * v], d->normals[3 * v + 1],
                                           d->normals[3 * v + 2]));
            s->normals[3 * v] = n.x, s->normals[3 * v + 1] = n.y, s->normals[3 * v + 2] = n.z;
        }
        if (d->uvs) s->uvs[2 * v] = d->uvs[2 * v], s->uvs[2 * v + 1] = d->uvs[2 * v + 1];
    }
}

static ibl_status build_embree(ibl_context *ctx, ibl_scene *s, const char *name)
{
    ibl_status st = ibl__embree_load(ctx, name, &s->embree);
    if (st != IBL_OK) return st;
    const ibl__embree *rtc = &s->embree;
    s->device = rtc->rtcNewDevice("threads=1,set_affinity=0,verbose=0");
    if (!s->device)
        return ibl__fail(ctx, IBL_ERR_UNSUPPORTED, "%s: Embree could not create a device (%d)",
                         name, (int)rtc->rtcGetDeviceError(NULL));
    s->rtc = rtc->rtcNewScene(s->device);
    rtc->rtcSetSceneFlags(s->rtc, RTC_SCENE_FLAG_ROBUST);
    rtc->rtcSetSceneBuildQuality(s->rtc, RTC_BUILD_QUALITY_HIGH);
    RTCGeometry g = rtc->rtcNewGeometry(s->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    float *v = rtc->rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                            3 * sizeof(float), (size_t)s->vertex_count);
    unsigned *ix = rtc->rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                3 * sizeof(unsigned), (size_t)s->triangle_count);
    if (v && ix) {
        memcpy(v, s->positions, (size_t)s->vertex_count * 3 * sizeof(float));
        memcpy(ix, s->indices, (size_t)s->triangle_count * 3 * sizeof(unsigned));
        rtc->rtcCommitGeometry(g);
        rtc->rtcAttachGeometry(s->rtc, g);
    }
    rtc->rtcReleaseGeometry(g);
    if (v && ix) rtc->rtcCommitScene(s->rtc);
    enum RTCError e = rtc->rtcGetDeviceError(s->device);
    if (!v || !ix || e != RTC_ERROR_NONE)
        return ibl__fail(ctx, e == RTC_ERROR_OUT_OF_MEMORY ? IBL_ERR_OUT_OF_MEMORY : IBL_ERR_FORMAT,
                         "%s: Embree could not build the scene (error %d)", name, (int)e);
    return IBL_OK;
}

ibl_status ibl_scene_create(ibl_context *ctx, const ibl_scene_desc *d, ibl_scene **out)
{
    if (!ctx || !d || !out) return IBL_ERR_INVALID_ARGUMENT;
    *out = NULL;
    const char *name = d->name ? d->name : "scene";
    ibl_status st = check_desc(ctx, d, name);
    if (st != IBL_OK) return st;
    ibl_scene *s = ibl_calloc(ctx, 1, sizeof *s);
    if (!s) return IBL_ERR_OUT_OF_MEMORY;
    s->ctx = ctx;
    size_t nv = (size_t)d->vertex_count, nt = (size_t)d->triangle_count;
    s->vertex_count = d->vertex_count;
    s->triangle_count = d->triangle_count;
    s->material_count = d->material_count;
    s->positions = ibl_alloc(ctx, nv * 3 * sizeof(float));
    s->normals = ibl_calloc(ctx, nv * 3, sizeof(float));
    s->uvs = ibl_calloc(ctx, nv * 2, sizeof(float));
    s->indices = ibl_alloc(ctx, nt * 3 * sizeof(uint32_t));
    s->material_ids = ibl_calloc(ctx, nt, sizeof(int));
    s->face_normals = ibl_alloc(ctx, nt * 3 * sizeof(float));
    s->areas = ibl_alloc(ctx, nt * sizeof(float));
    s->materials = ibl_alloc(ctx, (size_t)d->material_count * sizeof *s->materials);
    if (!s->positions || !s->normals || !s->uvs || !s->indices || !s->material_ids ||
        !s->face_normals || !s->areas || !s->materials) {
        ibl_scene_destroy(s);
        return IBL_ERR_OUT_OF_MEMORY;
    }
    memcpy(s->positions, d->positions, nv * 3 * sizeof(float));
    memcpy(s->indices, d->indices, nt * 3 * sizeof(uint32_t));
    if (d->material_ids) memcpy(s->material_ids, d->material_ids, nt * sizeof(int));
    memcpy(s->materials, d->materials, (size_t)d->material_count * sizeof *s->materials);
    vertex_attributes(s, d);
    face_geometry(s);
    st = copy_textures(ctx, s, d);
    if (st == IBL_OK) st = build_embree(ctx, s, name);
    if (st != IBL_OK) {
        ibl_scene_destroy(s);
        return st;
    }
    *out = s;
    return IBL_OK;
}

void ibl_scene_destroy(ibl_scene *s)
{
    if (!s) return;
    ibl_context *ctx = s->ctx;
    if (s->rtc) s->embree.rtcReleaseScene(s->rtc);
    if (s->device) s->embree.rtcReleaseDevice(s->device);
    ibl__embree_unload(&s->embree);
    for (int i = 0; i < s->texture_count; i++) ibl_image_free(ctx, &s->textures[i]);
    ibl_free(ctx, s->textures);
    ibl_free(ctx, s->positions);
    ibl_free(ctx, s->normals);
    ibl_free(ctx, s->uvs);
    ibl_free(ctx, s->indices);
    ibl_free(ctx, s->material_ids);
    ibl_free(ctx, s->face_normals);
    ibl_free(ctx, s->areas);
    ibl_free(ctx, s->materials);
    ibl_free(ctx, s);
}

void ibl_scene_get_info(const ibl_scene *s, ibl_scene_info *out)
{
    memset(out, 0, sizeof *out);
    out->vertex_count = s->vertex_count;
    out->triangle_count = s->triangle_count;
    out->material_count = s->material_count;
    out->texture_count = s->texture_count;
    out->emissive_triangle_count = s->emissive_count;
    memcpy(out->bounds_min, s->bounds_min, sizeof out->bounds_min);
    memcpy(out->bounds_max, s->bounds_max, sizeof out->bounds_max);
}

const ibl_scene_material *ibl_scene_get_material(const ibl_scene *s, int index)
{
    return index >= 0 && index < s->material_count ? &s->materials[index] : NULL;
}

static void init_ray(struct RTCRay *r, ibl_vec3 o, ibl_vec3 d, float tmin, float tmax)
{
    r->org_x = o.x, r->org_y = o.y, r->org_z = o.z;
    r->dir_x = d.x, r->dir_y = d.y, r->dir_z = d.z;
    r->tnear = tmin;
    r->tfar = tmax;
    r->time = 0.0f;
    r->mask = 0xFFFFFFFFu;
    r->id = 0;
    r->flags = 0;
}

int ibl_scene_intersect(const ibl_scene *s, ibl_vec3 o, ibl_vec3 d, float tmin, float tmax,
                        ibl_scene_hit *hit)
{
    struct RTCIntersectContext ic;
    rtcInitIntersectContext(&ic);
    struct RTCRayHit rh;
    init_ray(&rh.ray, o, d, tmin, tmax);
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    s->embree.rtcIntersect1(s->rtc, &ic, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return 0;
    int t = (int)rh.hit.primID;
    float w[3] = {1.0f - rh.hit.u - rh.hit.v, rh.hit.u, rh.hit.v};
    ibl_vec3 n = {0, 0, 0};
    float uv[2] = {0, 0};
    for (int c = 0; c < 3; c++) {
        uint32_t v = s->indices[3 * t + c];
        n = ibl__add(n, ibl__scale(ibl__v3(s->normals[3 * v], s->normals[3 * v + 1],
                                           s->normals[3 * v + 2]), w[c]));
        uv[0] += w[c] * s->uvs[2 * v];
        uv[1] += w[c] * s->uvs[2 * v + 1];
    }
    ibl_vec3 ng = ibl__v3(s->face_normals[3 * t], s->face_normals[3 * t + 1],
                          s->face_normals[3 * t + 2]);
    if (ibl__dot(ng, d) > 0.0f) ng = ibl__scale(ng, -1.0f); /* two-sided: face the ray */
    n = ibl__dot(n, n) > 0.0f ? ibl__norm(n) : ng;
    if (ibl__dot(n, ng) < 0.0f) n = ibl__scale(n, -1.0f);
    hit->t = rh.ray.tfar;
    hit->position = ibl__add(o, ibl__scale(d, rh.ray.tfar));
    hit->normal = n;
    hit->geometric_normal = ng;
    hit->uv[0] = uv[0];
    hit->uv[1] = uv[1];
    hit->triangle = t;
    hit->material = s->material_ids[t];
    return 1;
}

int ibl_scene_occluded(const ibl_scene *s, ibl_vec3 o, ibl_vec3 d, float tmin, float tmax)
{
    struct RTCIntersectContext ic;
    rtcInitIntersectContext(&ic);
    struct RTCRay r;
    init_ray(&r, o, d, tmin, tmax);
    s->embree.rtcOccluded1(s->rtc, &ic, &r);
    return r.tfar < 0.0f; /* Embree sets tfar to -inf on a hit */
}

/* bilinear, repeat; uv (0, 0) is the top-left corner of the image */
static void texture_rgb(const ibl_image *im, const float uv[2], float out[3])
{
    float x = uv[0] * (float)im->width - 0.5f, y = uv[1] * (float)im->height - 0.5f;
    float fx = floorf(x), fy = floorf(y), ax = x - fx, ay = y - fy;
    int x0 = (int)fmodf(fx, (float)im->width), y0 = (int)fmodf(fy, (float)im->height);
    if (x0 < 0) x0 += im->width;
    if (y0 < 0) y0 += im->height;
    int x1 = (x0 + 1) % im->width, y1 = (y0 + 1) % im->height;
    const float *p00 = ibl_image_texel(im, x0, y0), *p10 = ibl_image_texel(im, x1, y0);
    const float *p01 = ibl_image_texel(im, x0, y1), *p11 = ibl_image_texel(im, x1, y1);
    for (int c = 0; c < 3; c++)
        out[c] = (1 - ay) * ((1 - ax) * p00[c] + ax * p10[c]) + ay * ((1 - ax) * p01[c] + ax * p11[c]);
}

/* the texture's stored (sRGB-decoded) value back to the file's linear data value */
static float srgb_encode(float v)
{
    v = ibl__saturate(v);
    return v <= 0.0031308f ? 12.92f * v : 1.055f * powf(v, 1.0f / 2.4f) - 0.055f;
}

void ibl_scene_surface_at(const ibl_scene *s, const ibl_scene_hit *hit, ibl_scene_surface *out)
{
    const ibl_scene_material *m = &s->materials[hit->material];
    float t[3];
    for (int c = 0; c < 3; c++) out->base_color[c] = m->base_color[c];
    for (int c = 0; c < 3; c++) out->emissive[c] = m->emissive[c];
    out->metallic = m->metallic;
    out->roughness = m->roughness;
    out->diffuse_only = m->diffuse_only;
    if (m->base_color_texture >= 0) {
        texture_rgb(&s->textures[m->base_color_texture], hit->uv, t);
        for (int c = 0; c < 3; c++) out->base_color[c] *= t[c];
    }
    if (m->emissive_texture >= 0) {
        texture_rgb(&s->textures[m->emissive_texture], hit->uv, t);
        for (int c = 0; c < 3; c++) out->emissive[c] *= t[c];
    }
    if (m->metallic_roughness_texture >= 0) {
        /* PNG/JPEG readers decode 8-bit data as sRGB; this texture holds linear values */
        texture_rgb(&s->textures[m->metallic_roughness_texture], hit->uv, t);
        out->roughness *= srgb_encode(t[1]);
        out->metallic *= srgb_encode(t[2]);
    }
}
