/* A scene lit by its probe bake through a camera (`ibl render SCENE --probes DIR`): one
 * primary ray per pixel centre finds the visible surface, its view depth feeds the tiled
 * culling (ibl_cull_probes), and each surface point is shaded by ibl_probes_shade with its
 * tile's list, as a deferred renderer's lighting pass would; emitters add their own radiance
 * and rays that leave the scene show the global probe. The path-traced reference of the same
 * view is ibl_trace_view (capture.c). */
#include "ibl/probes.h"
#include "core/context_internal.h"
#include "core/numeric.h"
#include "scene/scene_internal.h"

#include <float.h>
#include <math.h>
#include <string.h>

typedef struct primary {
    int hit;
    ibl_scene_hit h;
    ibl_vec3 dir; /* unit */
} primary;

typedef struct render_job {
    const ibl_scene *scene;
    const ibl_probe_bake_data *bake;
    const ibl_probe *global;
    const ibl_probe *locals;
    const ibl_camera *cam;
    const ibl_probe_render_desc *desc;
    const ibl_tile_lists *lists;
    primary *rays;
    float *depth;
    ibl_image *out;
    int *regions;
} render_job;

static void trace_row(void *arg, int y)
{
    render_job *j = arg;
    const ibl_camera *cam = j->cam;
    ibl_vec3 r, u, f;
    ibl_camera_basis(cam, &r, &u, &f);
    for (int x = 0; x < cam->width; x++) {
        size_t i = (size_t)y * cam->width + x;
        primary *p = &j->rays[i];
        p->dir = ibl__norm(ibl_camera_ray(cam, (float)x + 0.5f, (float)y + 0.5f));
        p->hit = ibl_scene_intersect(j->scene, cam->position, p->dir, 0.0f, FLT_MAX, &p->h);
        /* view depth, not ray length: what a depth buffer holds */
        j->depth[i] = p->hit ? p->h.t * ibl__dot(p->dir, f) : 0.0f;
    }
}

/* glTF's emission is seen only from the front of the triangle as wound (capture.c's rule) */
static int emits_toward(const ibl_scene *s, const ibl_scene_hit *h, ibl_vec3 d)
{
    const float *fn = s->face_normals + 3 * h->triangle;
    return fn[0] * d.x + fn[1] * d.y + fn[2] * d.z < 0.0f;
}

static void shade_row(void *arg, int y)
{
    render_job *j = arg;
    const ibl_camera *cam = j->cam;
    const ibl_tile_lists *tl = j->lists;
    for (int x = 0; x < cam->width; x++) {
        size_t i = (size_t)y * cam->width + x;
        const primary *p = &j->rays[i];
        float *o = j->out->pixels + i * 4;
        o[3] = 1.0f;
        if (!p->hit) {
            float bg[4];
            ibl_cubemap_sample_bilinear(&j->global->specular, 0, p->dir, bg);
            for (int c = 0; c < 3; c++) o[c] = bg[c];
            if (j->regions) j->regions[i] = IBL_REGION_BACKGROUND;
            continue;
        }
        ibl_scene_surface sf;
        ibl_scene_surface_at(j->scene, &p->h, &sf);
        /* diffuse-only (validation scenes): Lambert of albedo base_color, whatever metallic says */
        ibl_material m = ibl_material_gltf(sf.base_color, sf.diffuse_only ? 0.0f : sf.metallic, sf.roughness);
        ibl_surface s;
        memset(&s, 0, sizeof s);
        s.v = ibl__scale(p->dir, -1.0f);
        s.n = p->h.normal;
        s.geometric_normal = p->h.geometric_normal;
        int t = (y / tl->tile_size) * tl->tiles_x + x / tl->tile_size;
        const int *list = tl->indices + tl->offsets[t];
        int count = tl->offsets[t + 1] - tl->offsets[t];
        ibl_shade_result res;
        ibl_probe_blend_info info;
        ibl_probes_shade(j->bake, j->global, j->locals, list, count, &j->desc->blend,
                         &j->desc->shade, &m, p->h.position, &s, &res, &info);
        int emits = emits_toward(j->scene, &p->h, p->dir);
        for (int c = 0; c < 3; c++) {
            /* a diffuse-only material (validation scenes) is Lambert alone: no specular lobe */
            float reflected = sf.diffuse_only ? res.diffuse[c] * m.ao : res.color[c];
            o[c] = reflected + (emits ? sf.emissive[c] : 0.0f);
        }
        if (j->regions) j->regions[i] = info.heaviest >= 0 ? info.heaviest : IBL_REGION_GLOBAL;
    }
}

/* ibl_parallel_for numbers its tasks from 0: a band of rows starting at y0 */
typedef struct band {
    render_job *job;
    void (*row)(void *, int);
    int y0;
} band;

static void band_task(void *arg, int index)
{
    band *b = arg;
    b->row(b->job, b->y0 + index);
}

static ibl_status run_rows(ibl_context *ctx, const char *stage, void (*row)(void *, int),
                           render_job *j)
{
    int rows = j->cam->height, step = rows / 8 > 0 ? rows / 8 : 1;
    for (int y0 = 0; y0 < rows; y0 += step) {
        ibl_status st = ibl__progress(ctx, stage, (double)y0 / rows);
        if (st != IBL_OK) return st;
        band b = {j, row, y0};
        ibl_parallel_for(ctx, rows - y0 < step ? rows - y0 : step, band_task, &b);
    }
    return ibl__progress(ctx, stage, 1.0);
}

ibl_status ibl_probe_render(ibl_context *ctx, const ibl_scene *scene,
                            const ibl_probe_bake_data *bake, const ibl_camera *cam,
                            const ibl_probe_render_desc *desc, ibl_image *out, int *regions)
{
    if (out) memset(out, 0, sizeof *out);
    if (!ctx || !scene || !bake || !cam || !out || cam->width < 1 || cam->height < 1 ||
        bake->count < 0 || bake->count > 1024)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "probe render: bad arguments");
    ibl_probe_render_desc d;
    memset(&d, 0, sizeof d);
    if (desc) d = *desc;
    size_t pixels = (size_t)cam->width * (size_t)cam->height;
    render_job j;
    memset(&j, 0, sizeof j);
    j.scene = scene;
    j.bake = bake;
    j.cam = cam;
    j.desc = &d;
    j.regions = regions;
    j.out = out;
    ibl_probe global;
    ibl_tile_lists lists;
    memset(&lists, 0, sizeof lists);
    ibl_probe *locals = ibl_alloc(ctx, sizeof *locals * (size_t)(bake->count > 0 ? bake->count : 1));
    ibl_volume *influences = ibl_alloc(ctx, sizeof *influences * (size_t)(bake->count > 0 ? bake->count : 1));
    j.rays = ibl_alloc(ctx, sizeof *j.rays * pixels);
    j.depth = ibl_alloc(ctx, sizeof *j.depth * pixels);
    ibl_status st = locals && influences && j.rays && j.depth ? IBL_OK : ibl_context_status(ctx);
    if (st == IBL_OK) st = ibl_bake_probe(ctx, &bake->global, &global);
    if (st == IBL_OK) st = ibl_probe_bake_locals(ctx, bake, &global, locals);
    if (st == IBL_OK) st = ibl_image_alloc(ctx, cam->width, cam->height, out);
    j.global = &global;
    j.locals = locals;
    j.lists = &lists;
    if (st == IBL_OK) st = run_rows(ctx, "primary rays", trace_row, &j);
    for (int i = 0; st == IBL_OK && i < bake->count; i++) influences[i] = bake->records[i].influence;
    if (st == IBL_OK)
        st = ibl_cull_probes(ctx, cam, j.depth, influences, bake->count, &d.cull, &lists, NULL);
    if (st == IBL_OK) st = run_rows(ctx, "probe shading", shade_row, &j);
    if (st != IBL_OK) ibl_image_free(ctx, out);
    ibl_tile_lists_free(ctx, &lists);
    ibl_free(ctx, locals);
    ibl_free(ctx, influences);
    ibl_free(ctx, j.rays);
    ibl_free(ctx, j.depth);
    return st;
}
