/* Maps baked from a mesh in its texture space: the stretch map (how long a step in U and in V is
 * on the surface, for the texture-space blur of scatter.c; d'Eon, Luebke and Enderton 2007,
 * "Efficient Rendering of Human Skin", section 4: texture-space diffusion needs the stretch to
 * turn millimetres into texels) and the thickness map (rays cast inward through the mesh with
 * Embree, for the translucency of thin regions; Jimenez et al. 2010 take the same distance from
 * a shadow map at run time).
 *
 * Both start from one rasterisation of the triangles in UV space into a map of triangle
 * indices; the per-texel values come from each texel's triangle, and empty texels next to the
 * charts are filled by dilation so that bilinear filtering and blurs near UV seams never read
 * an empty texel. */
#include "skin_internal.h"
#include "scene/scene_internal.h"
#include "core/context_internal.h"
#include "core/numeric.h"

#include <math.h>
#include <string.h>

/* ---- rasterisation in UV space ----------------------------------------------------------- */

/* The triangle's corners in texel units (x = u W, y = v H: texel (i, j) has its centre at
 * (i + 0.5, j + 0.5)). */
static void triangle_texels(const ibl_scene *m, int tri, int w, int h, double xy[3][2])
{
    for (int k = 0; k < 3; k++) {
        uint32_t v = m->indices[3 * tri + k];
        xy[k][0] = (double)m->uvs[2 * v] * w;
        xy[k][1] = (double)m->uvs[2 * v + 1] * h;
    }
}

/* Barycentric coordinates of point (px, py) in the triangle; 0 when the triangle has no area
 * in UV space. */
static int barycentric(const double xy[3][2], double px, double py, double b[3])
{
    double area = (xy[1][0] - xy[0][0]) * (xy[2][1] - xy[0][1]) -
                  (xy[2][0] - xy[0][0]) * (xy[1][1] - xy[0][1]);
    if (fabs(area) < 1e-12) return 0;
    b[0] = ((xy[1][0] - px) * (xy[2][1] - py) - (xy[2][0] - px) * (xy[1][1] - py)) / area;
    b[1] = ((xy[2][0] - px) * (xy[0][1] - py) - (xy[0][0] - px) * (xy[2][1] - py)) / area;
    b[2] = 1.0 - b[0] - b[1];
    return 1;
}

ibl_status ibl__skin_rasterize(ibl_context *ctx, const ibl_scene *mesh, int w, int h,
                               int32_t **out)
{
    int has_uv = 0;
    for (int i = 0; i < 2 * mesh->vertex_count && !has_uv; i++) has_uv = mesh->uvs[i] != 0.0f;
    if (!has_uv)
        return ibl__fail(ctx, IBL_ERR_FORMAT, "no texture coordinates (the skin maps are "
                         "baked in UV space)");
    int32_t *ids = ibl_alloc(ctx, (size_t)w * h * sizeof *ids);
    if (!ids) return ibl_context_status(ctx);
    for (size_t i = 0; i < (size_t)w * h; i++) ids[i] = -1;
    for (int t = 0; t < mesh->triangle_count; t++) {
        double xy[3][2], b[3];
        triangle_texels(mesh, t, w, h, xy);
        if (!barycentric(xy, 0.0, 0.0, b)) continue; /* no area in UV space */
        double x0 = fmin(xy[0][0], fmin(xy[1][0], xy[2][0])), x1 = fmax(xy[0][0], fmax(xy[1][0], xy[2][0]));
        double y0 = fmin(xy[0][1], fmin(xy[1][1], xy[2][1])), y1 = fmax(xy[0][1], fmax(xy[1][1], xy[2][1]));
        if (!(x0 < w && y0 < h && x1 >= 0 && y1 >= 0)) continue; /* off the texture, or NaN */
        int i0 = (int)fmax(0.0, ceil(x0 - 0.5)), i1 = (int)fmin(w - 1.0, floor(x1 - 0.5));
        int j0 = (int)fmax(0.0, ceil(y0 - 0.5)), j1 = (int)fmin(h - 1.0, floor(y1 - 0.5));
        for (int j = j0; j <= j1; j++)
            for (int i = i0; i <= i1; i++) {
                barycentric(xy, i + 0.5, j + 0.5, b);
                /* inclusive edges: a texel centre on a shared edge belongs to both (the later
                   triangle keeps it), none is lost between them */
                if (b[0] >= -1e-9 && b[1] >= -1e-9 && b[2] >= -1e-9) ids[(size_t)j * w + i] = t;
            }
    }
    *out = ids;
    return IBL_OK;
}

/* Fills up to `rings` rings of empty texels around the filled ones with the mean of their
 * filled 8-neighbours (RGB; alpha stays 0). filled[] is 1 where the texel has a value. */
static ibl_status dilate(ibl_context *ctx, ibl_image *im, uint8_t *filled, int rings)
{
    int w = im->width, h = im->height;
    size_t n = (size_t)w * h;
    uint32_t *front = ibl_alloc(ctx, n * sizeof *front);
    float *values = ibl_alloc(ctx, n * 3 * sizeof *values);
    if (!front || !values) {
        ibl_free(ctx, front);
        ibl_free(ctx, values);
        return ibl_context_status(ctx);
    }
    for (int ring = 0; ring < rings; ring++) {
        size_t count = 0;
        for (int y = 0; y < h; y++)
            for (int x = 0; x < w; x++) {
                if (filled[(size_t)y * w + x]) continue;
                double sum[3] = {0, 0, 0};
                int k = 0;
                for (int dy = -1; dy <= 1; dy++)
                    for (int dx = -1; dx <= 1; dx++) {
                        int xx = x + dx, yy = y + dy;
                        if (xx < 0 || yy < 0 || xx >= w || yy >= h || !filled[(size_t)yy * w + xx]) continue;
                        const float *p = ibl_image_texel(im, xx, yy);
                        for (int c = 0; c < 3; c++) sum[c] += p[c];
                        k++;
                    }
                if (!k) continue;
                front[count] = (uint32_t)((size_t)y * w + x);
                for (int c = 0; c < 3; c++) values[3 * count + c] = (float)(sum[c] / k);
                count++;
            }
        if (!count) break;
        for (size_t i = 0; i < count; i++) {
            memcpy(im->pixels + (size_t)front[i] * 4, values + 3 * i, 3 * sizeof(float));
            filled[front[i]] = 1;
        }
    }
    ibl_free(ctx, front);
    ibl_free(ctx, values);
    return IBL_OK;
}

static ibl_status check_map_desc(ibl_context *ctx, const ibl_scene *mesh, const ibl_skin_map_desc *d)
{
    if (!mesh || !d) return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "skin map: missing argument");
    if (d->width <= 0 || d->height <= 0 || d->width > 65536 || d->height > 65536)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "skin map: size %dx%d", d->width, d->height);
    return IBL_OK;
}

/* Alpha from the id map, the dilation of RGB, and the clean-up on failure. */
static ibl_status finish_map(ibl_context *ctx, const int32_t *ids, int rings, ibl_image *out)
{
    size_t n = (size_t)out->width * out->height;
    uint8_t *filled = ibl_alloc(ctx, n);
    ibl_status st = filled ? IBL_OK : ibl_context_status(ctx);
    if (st == IBL_OK) {
        for (size_t i = 0; i < n; i++) {
            filled[i] = ids[i] >= 0;
            out->pixels[4 * i + 3] = filled[i] ? 1.0f : 0.0f;
        }
        st = dilate(ctx, out, filled, rings);
    }
    ibl_free(ctx, filled);
    if (st != IBL_OK) ibl_image_free(ctx, out);
    return st;
}

static int dilate_rings(const ibl_skin_map_desc *d)
{
    return d->dilate < 0 ? 0 : d->dilate == 0 ? 16 : d->dilate;
}

/* ---- the stretch map ------------------------------------------------------------------------- */

/* |dP/du| and |dP/dv| of a triangle: P is linear over it, so with the edges e1 = P1 - P0,
 * e2 = P2 - P0 and their UV deltas, dP/du = (e1 dv2 - e2 dv1) / det and
 * dP/dv = (e2 du1 - e1 du2) / det, det = du1 dv2 - du2 dv1. 0 if the UVs are degenerate. */
static void triangle_stretch(const ibl_scene *m, int tri, float out[2])
{
    const uint32_t *ix = m->indices + 3 * tri;
    double p[3][3], uv[3][2];
    for (int k = 0; k < 3; k++) {
        for (int c = 0; c < 3; c++) p[k][c] = m->positions[3 * ix[k] + c];
        uv[k][0] = m->uvs[2 * ix[k]];
        uv[k][1] = m->uvs[2 * ix[k] + 1];
    }
    double du1 = uv[1][0] - uv[0][0], dv1 = uv[1][1] - uv[0][1];
    double du2 = uv[2][0] - uv[0][0], dv2 = uv[2][1] - uv[0][1];
    double det = du1 * dv2 - du2 * dv1;
    out[0] = out[1] = 0.0f;
    if (fabs(det) < 1e-20) return;
    double su = 0, sv = 0;
    for (int c = 0; c < 3; c++) {
        double e1 = p[1][c] - p[0][c], e2 = p[2][c] - p[0][c];
        double dpdu = (e1 * dv2 - e2 * dv1) / det, dpdv = (e2 * du1 - e1 * du2) / det;
        su += dpdu * dpdu;
        sv += dpdv * dpdv;
    }
    out[0] = (float)sqrt(su);
    out[1] = (float)sqrt(sv);
}

ibl_status ibl_skin_stretch_map(ibl_context *ctx, const ibl_scene *mesh,
                                const ibl_skin_map_desc *desc, ibl_image *out)
{
    ibl_status st = check_map_desc(ctx, mesh, desc);
    if (st != IBL_OK) return st;
    int w = desc->width, h = desc->height;
    int32_t *ids = NULL;
    float *per_triangle = ibl_alloc(ctx, (size_t)(mesh->triangle_count + 1) * 2 * sizeof(float));
    if (!per_triangle) return ibl_context_status(ctx);
    st = ibl__skin_rasterize(ctx, mesh, w, h, &ids);
    if (st == IBL_OK) st = ibl_image_alloc(ctx, w, h, out);
    if (st == IBL_OK) {
        for (int t = 0; t < mesh->triangle_count; t++) triangle_stretch(mesh, t, per_triangle + 2 * t);
        for (size_t i = 0; i < (size_t)w * h; i++) {
            float *p = out->pixels + 4 * i;
            p[0] = ids[i] >= 0 ? per_triangle[2 * ids[i]] : 0.0f;
            p[1] = ids[i] >= 0 ? per_triangle[2 * ids[i] + 1] : 0.0f;
            p[2] = 0.0f;
        }
        st = finish_map(ctx, ids, dilate_rings(desc), out);
    }
    ibl_free(ctx, ids);
    ibl_free(ctx, per_triangle);
    return st;
}

/* ---- the thickness map -------------------------------------------------------------------- */

typedef struct thickness_job {
    const ibl_scene *mesh;
    const int32_t *ids;
    ibl_image *out;
    const ibl_vec3 *cone; /* ray directions about +Z */
    int rays;
    float max_distance, offset;
} thickness_job;

/* The surface point and interpolated normal of texel (x, y) of triangle tri. */
static void texel_surface(const ibl_scene *m, int tri, int w, int h, int x, int y, ibl_vec3 *p,
                          ibl_vec3 *n)
{
    double xy[3][2], b[3] = {1.0 / 3, 1.0 / 3, 1.0 / 3};
    triangle_texels(m, tri, w, h, xy);
    barycentric(xy, x + 0.5, y + 0.5, b);
    float pp[3] = {0, 0, 0}, nn[3] = {0, 0, 0};
    for (int k = 0; k < 3; k++) {
        uint32_t v = m->indices[3 * tri + k];
        for (int c = 0; c < 3; c++) {
            pp[c] += (float)b[k] * m->positions[3 * v + c];
            nn[c] += (float)b[k] * m->normals[3 * v + c];
        }
    }
    *p = ibl__v3(pp[0], pp[1], pp[2]);
    ibl_vec3 nv = ibl__v3(nn[0], nn[1], nn[2]);
    if (ibl__dot(nv, nv) < 1e-12f) nv = ibl__v3(m->face_normals[3 * tri], m->face_normals[3 * tri + 1],
                                                m->face_normals[3 * tri + 2]);
    *n = ibl__norm(nv);
}

static void thickness_row(void *arg, int y)
{
    const thickness_job *j = arg;
    int w = j->out->width, h = j->out->height;
    for (int x = 0; x < w; x++) {
        int32_t tri = j->ids[(size_t)y * w + x];
        float *px = ibl_image_texel(j->out, x, y);
        if (tri < 0) { /* empty (until dilated): as thick as nothing goes through */
            px[0] = px[1] = px[2] = j->max_distance;
            continue;
        }
        ibl_vec3 p, n;
        texel_surface(j->mesh, tri, w, h, x, y, &p, &n);
        ibl_vec3 in = ibl__scale(n, -1.0f), t, b;
        /* a frame about the inward normal (Frisvad 2012's branch on the sign of z) */
        if (in.z < -0.9999999f) {
            t = ibl__v3(0.0f, -1.0f, 0.0f);
            b = ibl__v3(-1.0f, 0.0f, 0.0f);
        } else {
            float a = 1.0f / (1.0f + in.z), c = -in.x * in.y * a;
            t = ibl__v3(1.0f - in.x * in.x * a, c, -in.x);
            b = ibl__v3(c, 1.0f - in.y * in.y * a, -in.y);
        }
        double sum = 0;
        for (int r = 0; r < j->rays; r++) {
            ibl_vec3 c = j->cone[r];
            ibl_vec3 d = ibl__norm(ibl__add(ibl__add(ibl__scale(t, c.x), ibl__scale(b, c.y)), ibl__scale(in, c.z)));
            ibl_scene_hit hit;
            sum += ibl_scene_intersect(j->mesh, p, d, j->offset, j->max_distance, &hit) ? hit.t
                                                                                    : j->max_distance;
        }
        px[0] = px[1] = px[2] = (float)(sum / j->rays);
    }
}

ibl_status ibl_skin_thickness_map(ibl_context *ctx, const ibl_scene *mesh,
                                  const ibl_skin_thickness_desc *desc, ibl_image *out)
{
    ibl_status st = check_map_desc(ctx, mesh, desc ? &desc->map : NULL);
    if (st != IBL_OK) return st;
    int rays = desc->rays > 0 ? desc->rays : 16;
    if (rays > 4096) return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "thickness: %d rays", rays);
    double cone = (desc->cone_degrees > 0.0f ? desc->cone_degrees : 30.0) * IBL_PI / 180.0;
    if (!(cone < IBL_PI / 2))
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "thickness: cone of %g degrees (< 90)",
                         (double)desc->cone_degrees);
    ibl_vec3 *dirs = ibl_alloc(ctx, (size_t)rays * sizeof *dirs);
    if (!dirs) return ibl_context_status(ctx);
    /* a Fibonacci spiral over the cap: equal solid angle per ray (cos theta uniform) */
    for (int r = 0; r < rays; r++) {
        double ct = rays == 1 ? 1.0 : 1.0 - (1.0 - cos(cone)) * (r + 0.5) / rays;
        double st_ = sqrt(fmax(0.0, 1.0 - ct * ct)), phi = r * IBL_PI * (3.0 - sqrt(5.0));
        dirs[r] = ibl__v3((float)(st_ * cos(phi)), (float)(st_ * sin(phi)), (float)ct);
    }
    double dx = mesh->bounds_max[0] - mesh->bounds_min[0], dy = mesh->bounds_max[1] - mesh->bounds_min[1],
           dz = mesh->bounds_max[2] - mesh->bounds_min[2];
    float diagonal = (float)sqrt(dx * dx + dy * dy + dz * dz);
    int32_t *ids = NULL;
    st = ibl__skin_rasterize(ctx, mesh, desc->map.width, desc->map.height, &ids);
    if (st == IBL_OK) st = ibl_image_alloc(ctx, desc->map.width, desc->map.height, out);
    if (st == IBL_OK) {
        /* the offset skips the ray's own triangle: a millionth of the mesh's size */
        thickness_job job = {mesh, ids, out, dirs, rays,
                             desc->max_distance > 0.0f ? desc->max_distance : diagonal,
                             1e-6f * diagonal};
        ibl_parallel_for(ctx, out->height, thickness_row, &job);
        st = finish_map(ctx, ids, dilate_rings(&desc->map), out);
    }
    ibl_free(ctx, ids);
    ibl_free(ctx, dirs);
    return st;
}

void ibl_skin_transmittance_from_thickness(ibl_image *thickness, float mm_per_unit, float range_mm)
{
    float scale = (mm_per_unit > 0.0f ? mm_per_unit : 1000.0f) /
                  (range_mm > 0.0f ? range_mm : IBL_SKIN_THICKNESS_RANGE_MM);
    for (size_t i = 0; i < (size_t)thickness->width * thickness->height; i++) {
        float *p = thickness->pixels + 4 * i;
        p[0] = p[1] = p[2] = ibl__saturate(1.0f - p[0] * scale);
    }
}
