/* Local probes: influence volumes and their priority blend, parallax correction, tri-Ace's
 * IBL offset and shininess hack, the two-environment switch, and tiled probe culling.
 * Sources: the JAGE 2015 article ("Image Based Lighting", Just Another Game Engine blog:
 * influence volumes, smallest first, box/sphere parallax proxies, tiled culling with sorted
 * per-tile lists), Lagarde 2012 ("Image-based Lighting approaches and parallax-corrected
 * cubemap"), tri-Ace 2010 ("IBL Offset", "Shininess hack"), Daqi 2016 ("[PBR Series - 6]
 * Improvement of PBR": "Environment Switch"). */
#include "ibl/shade.h"
#include "core/context_internal.h"
#include "core/numeric.h"

#include <float.h>
#include <math.h>
#include <string.h>

float ibl_volume_size(const ibl_volume *v)
{
    if (v->shape == IBL_VOLUME_BOX)
        return 8.0f * v->half_extent.x * v->half_extent.y * v->half_extent.z;
    return 4.18879020f * v->radius * v->radius * v->radius;
}

/* Distance from p to the volume's surface, positive inside. */
static float inside_distance(const ibl_volume *v, ibl_vec3 p)
{
    float dx = p.x - v->center.x, dy = p.y - v->center.y, dz = p.z - v->center.z;
    if (v->shape == IBL_VOLUME_BOX) {
        float a = v->half_extent.x - fabsf(dx), b = v->half_extent.y - fabsf(dy),
              c = v->half_extent.z - fabsf(dz);
        float m = a < b ? a : b;
        return m < c ? m : c;
    }
    return v->radius - sqrtf(dx * dx + dy * dy + dz * dz);
}

float ibl_volume_weight(const ibl_volume *v, ibl_vec3 p)
{
    float d = inside_distance(v, p);
    if (d < 0.0f) return 0.0f;
    if (v->blend_distance <= 0.0f) return 1.0f;
    return ibl__saturate(d / v->blend_distance);
}

void ibl_volume_sort(const ibl_volume *volumes, int count, int *order)
{
    for (int i = 0; i < count; i++) order[i] = i;
    /* insertion sort, as the JAGE 2015 article does on the CPU: stable, so equal sizes keep
     * index order */
    for (int i = 1; i < count; i++) {
        int key = order[i];
        float ks = ibl_volume_size(&volumes[key]);
        int j = i - 1;
        while (j >= 0 && ibl_volume_size(&volumes[order[j]]) > ks) {
            order[j + 1] = order[j];
            j--;
        }
        order[j + 1] = key;
    }
}

float ibl_volume_blend(const ibl_volume *volumes, const int *order, int count, ibl_vec3 p,
                       float *weights)
{
    float used = 0.0f;
    for (int i = 0; i < count; i++) weights[i] = 0.0f;
    for (int i = 0; i < count; i++) {
        int k = order ? order[i] : i;
        float w = ibl_volume_weight(&volumes[k], p) * (1.0f - used);
        weights[k] = w;
        used += w;
        if (used >= 1.0f) {
            used = 1.0f;
            break;
        }
    }
    return 1.0f - used;
}

ibl_vec3 ibl_parallax_correct(const ibl_volume *proxy, ibl_vec3 probe_position, ibl_vec3 p,
                              ibl_vec3 r)
{
    if (inside_distance(proxy, p) < 0.0f) return r;
    float t;
    if (proxy->shape == IBL_VOLUME_BOX) {
        /* exit distance of the ray through the axis-aligned box: the nearest of the far planes */
        const float pc[3] = {p.x, p.y, p.z}, rc[3] = {r.x, r.y, r.z};
        const float cc[3] = {proxy->center.x, proxy->center.y, proxy->center.z};
        const float hc[3] = {proxy->half_extent.x, proxy->half_extent.y, proxy->half_extent.z};
        t = FLT_MAX;
        for (int i = 0; i < 3; i++) {
            if (rc[i] == 0.0f) continue;
            float plane = rc[i] > 0.0f ? cc[i] + hc[i] : cc[i] - hc[i];
            float ti = (plane - pc[i]) / rc[i];
            if (ti < t) t = ti;
        }
        if (t == FLT_MAX) return r;
    } else {
        /* |o + t r|^2 = R^2 with |r| = 1 in general: solve the quadratic with a = r.r */
        ibl_vec3 o = ibl__v3(p.x - proxy->center.x, p.y - proxy->center.y, p.z - proxy->center.z);
        float a = r.x * r.x + r.y * r.y + r.z * r.z;
        float b = o.x * r.x + o.y * r.y + o.z * r.z;
        float c = o.x * o.x + o.y * o.y + o.z * o.z - proxy->radius * proxy->radius;
        if (a <= 0.0f) return r;
        float disc = b * b - a * c;
        t = (-b + sqrtf(disc > 0.0f ? disc : 0.0f)) / a;
    }
    ibl_vec3 hit = ibl__v3(p.x + t * r.x, p.y + t * r.y, p.z + t * r.z);
    return ibl__norm(
        ibl__v3(hit.x - probe_position.x, hit.y - probe_position.y, hit.z - probe_position.z));
}

ibl_vec3 ibl_offset_reflection(ibl_vec3 r, ibl_vec3 p_obj, ibl_vec3 p_ibl, float c)
{
    return ibl__norm(ibl__v3(c * (p_obj.x - p_ibl.x) + r.x, c * (p_obj.y - p_ibl.y) + r.y,
                         c * (p_obj.z - p_ibl.z) + r.z));
}

/* tri-Ace 2010 ("IBL Offset") computes c "from the IBL size, the object size and another
 * coefficient which is adjusted by hand" and gives no formula. Take the surroundings as a
 * sphere of radius S around the capture point and a reflection ray x + t R from a point x of
 * the object: it meets the sphere at x + t R with |x + t R| = S, seen from the capture point
 * along (x_perp + sqrt(S^2 - |x_perp|^2) R) / S, x_perp the part of x across R. To first order
 * in |x| / S that is normalize(x / S + R): the offset with c = 1/S. Taking the object's
 * position for x (one offset per object) drops the shaded point's offset from it, a term of
 * size object_radius / S that no constant c can restore, so the object's size does not enter
 * c; k is the talk's hand-tuned coefficient. */
float ibl_offset_coefficient(float environment_radius, float k)
{
    if (!(environment_radius > 0.0f)) return 0.0f;
    return (k > 0.0f ? k : 1.0f) / environment_radius;
}

float ibl_shininess_hack(float shininess, float light_size, float attenuation)
{
    if (light_size <= 0.0f) return shininess;
    float s = ibl__saturate(60.0f / light_size * (1.0f - attenuation));
    return shininess * s * s;
}

/* Daqi 2016 gives the formula as a picture; it uses "the position of the adjacent border and
 * the scale and position of the shaded object", projected on the border's normal. We read it
 * as the fraction of the object's extent that has crossed the border. */
float ibl_environment_switch(float position, float border, float size)
{
    if (size <= 0.0f) return position >= border ? 1.0f : 0.0f;
    return ibl__saturate((position - border) / size + 0.5f);
}

ibl_screen_rect ibl_volume_screen_rect(const ibl_volume *v, const float m[16], int width,
                                       int height)
{
    ibl_screen_rect full = {0, 0, width, height}, empty = {0, 0, 0, 0};
    ibl_vec3 h = v->shape == IBL_VOLUME_BOX ? v->half_extent : ibl__v3(v->radius, v->radius, v->radius);
    float xmin = FLT_MAX, xmax = -FLT_MAX, ymin = FLT_MAX, ymax = -FLT_MAX;
    int all_far = 1;
    for (int i = 0; i < 8; i++) {
        float p[4] = {v->center.x + ((i & 1) ? h.x : -h.x), v->center.y + ((i & 2) ? h.y : -h.y),
                      v->center.z + ((i & 4) ? h.z : -h.z), 1.0f};
        float c[4];
        for (int r = 0; r < 4; r++)
            c[r] = m[r] * p[0] + m[4 + r] * p[1] + m[8 + r] * p[2] + m[12 + r] * p[3];
        /* a corner at or behind the eye plane: projecting it is meaningless, stay conservative */
        if (c[3] <= 1e-6f) return full;
        float x = c[0] / c[3], y = c[1] / c[3], z = c[2] / c[3];
        if (z <= 1.0f) all_far = 0;
        if (x < xmin) xmin = x;
        if (x > xmax) xmax = x;
        if (y < ymin) ymin = y;
        if (y > ymax) ymax = y;
    }
    if (all_far || xmax < -1.0f || xmin > 1.0f || ymax < -1.0f || ymin > 1.0f) return empty;
    ibl_screen_rect r;
    r.x0 = (int)floorf((xmin * 0.5f + 0.5f) * (float)width);
    r.x1 = (int)ceilf((xmax * 0.5f + 0.5f) * (float)width);
    r.y0 = (int)floorf((0.5f - ymax * 0.5f) * (float)height);
    r.y1 = (int)ceilf((0.5f - ymin * 0.5f) * (float)height);
    if (r.x0 < 0) r.x0 = 0;
    if (r.y0 < 0) r.y0 = 0;
    if (r.x1 > width) r.x1 = width;
    if (r.y1 > height) r.y1 = height;
    return r;
}

ibl_status ibl_tile_probes(ibl_context *ctx, const ibl_screen_rect *rects, const int *order,
                           int count, int width, int height, int tile_size, ibl_tile_lists *out)
{
    memset(out, 0, sizeof *out);
    if (count < 0 || width <= 0 || height <= 0 || tile_size <= 0 || (count > 0 && !rects))
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "tile probes: bad arguments");
    int tx = (width + tile_size - 1) / tile_size, ty = (height + tile_size - 1) / tile_size;
    size_t tiles = (size_t)tx * (size_t)ty;
    int *offsets = ibl_calloc(ctx, tiles + 1, sizeof(int));
    if (!offsets) return ibl_context_status(ctx);
    /* two passes (count, then fill in priority order) give sorted lists with no per-tile sort */
    size_t total = 0;
    for (int pass = 0; pass < 2; pass++) {
        for (int i = 0; i < count; i++) {
            int k = order ? order[i] : i;
            const ibl_screen_rect *r = &rects[k];
            if (r->x0 >= r->x1 || r->y0 >= r->y1) continue;
            int bx0 = r->x0 / tile_size, bx1 = (r->x1 - 1) / tile_size;
            int by0 = r->y0 / tile_size, by1 = (r->y1 - 1) / tile_size;
            for (int y = by0; y <= by1 && y < ty; y++)
                for (int x = bx0; x <= bx1 && x < tx; x++) {
                    size_t t = (size_t)y * tx + x;
                    if (pass == 0)
                        offsets[t + 1]++;
                    else
                        out->indices[offsets[t]++] = k;
                }
        }
        if (pass == 0) {
            for (size_t t = 0; t < tiles; t++) offsets[t + 1] += offsets[t];
            total = (size_t)offsets[tiles];
            out->indices = ibl_alloc(ctx, (total ? total : 1) * sizeof(int));
            if (!out->indices) {
                ibl_free(ctx, offsets);
                return ibl_context_status(ctx);
            }
        }
    }
    /* after filling, offsets[t] is the end of list t = the start of list t + 1 */
    for (size_t t = tiles; t > 0; t--) offsets[t] = offsets[t - 1];
    offsets[0] = 0;
    (void)total;
    out->offsets = offsets;
    out->tiles_x = tx;
    out->tiles_y = ty;
    out->tile_size = tile_size;
    return IBL_OK;
}

void ibl_tile_lists_free(ibl_context *ctx, ibl_tile_lists *l)
{
    if (!l) return;
    ibl_free(ctx, l->offsets);
    ibl_free(ctx, l->indices);
    memset(l, 0, sizeof *l);
}
