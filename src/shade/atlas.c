/* Daqi 2016 ("[PBR Series - 6] Improvement of PBR", 6.1 "Re-arrangement of
 * Textures"): a prefiltered chain laid out in one 2D image, the small levels kept at level 2's
 * size in the otherwise unused space so UVs never fall outside a tiny level, and the
 * metalness/roughness/AO/transmittance channel packing of the same section. The article's
 * figure is not available; the arrangement below is ours and is described in shade.h. */
#include "ibl/shade.h"
#include "core/context_internal.h"

#include <math.h>
#include <string.h>

static int cell_size(const ibl_atlas_layout *l, int level)
{
    return l->face_size[level] + 2 * l->gutter;
}

ibl_status ibl_atlas_plan(int size, int levels, const ibl_atlas_desc *desc, ibl_atlas_layout *out)
{
    memset(out, 0, sizeof *out);
    if (size <= 0 || levels <= 0 || levels > IBL_MAX_LEVELS || levels > ibl_full_mip_count(size))
        return IBL_ERR_INVALID_ARGUMENT;
    int g = desc && desc->gutter ? desc->gutter : 1;
    if (g < 0) g = 0;
    out->levels = levels;
    out->gutter = g;
    for (int k = 0; k < levels; k++) out->face_size[k] = ibl_level_size(size, k < 2 ? k : 2);
    int w0 = 3 * cell_size(out, 0), h0 = 2 * cell_size(out, 0);
    out->width = w0;
    out->height = h0;
    if (levels == 1) return IBL_OK;
    int w1 = 3 * cell_size(out, 1), h1 = 2 * cell_size(out, 1);
    out->x[1] = 0;
    out->y[1] = h0;
    out->height = h0 + h1;
    if (levels == 2) return IBL_OK;
    int ws = 3 * cell_size(out, 2), hs = 2 * cell_size(out, 2);
    int k = 2;
    /* first the space right of level 1, column-major ... */
    for (int x = w1; x + ws <= w0 && k < levels; x += ws)
        for (int y = h0; y + hs <= h0 + h1 && k < levels; y += hs, k++) {
            out->x[k] = x;
            out->y[k] = y;
        }
    /* ... then rows below everything */
    int y = h0 + h1;
    while (k < levels) {
        for (int x = 0; x + ws <= w0 && k < levels; x += ws, k++) {
            out->x[k] = x;
            out->y[k] = y;
        }
        y += hs;
        out->height = y;
    }
    return IBL_OK;
}

static void face_origin(const ibl_atlas_layout *l, int level, int face, int *x, int *y)
{
    int c = cell_size(l, level);
    *x = l->x[level] + (face % 3) * c;
    *y = l->y[level] + (face / 3) * c;
}

ibl_status ibl_atlas_pack(ibl_context *ctx, const ibl_cubemap *chain, const ibl_atlas_desc *desc,
                          ibl_image *out, ibl_atlas_layout *layout)
{
    memset(out, 0, sizeof *out);
    if (!chain || !chain->data) return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "atlas: no chain");
    if (ibl_atlas_plan(chain->size, chain->levels, desc, layout) != IBL_OK)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "atlas: bad chain (size %d, %d levels)",
                        chain->size, chain->levels);
    ibl_status st = ibl_image_alloc(ctx, layout->width, layout->height, out);
    if (st != IBL_OK) return st;
    /* opaque black where no level is: no reader samples there, and pictures of it show the
     * arrangement (a zero alpha would let a viewer's background through) */
    size_t texels = (size_t)out->width * out->height;
    memset(out->pixels, 0, texels * 4 * sizeof(float));
    for (size_t i = 0; i < texels; i++) out->pixels[i * 4 + 3] = 1.0f;
    int nearest = desc && desc->filter == IBL_ATLAS_NEAREST;
    int g = layout->gutter;
    for (int k = 0; k < layout->levels; k++) {
        int n = layout->face_size[k], native = ibl_level_size(chain->size, k);
        for (int f = 0; f < 6; f++) {
            int ox, oy;
            face_origin(layout, k, f, &ox, &oy);
            const float *src = ibl_cubemap_face(chain, k, f);
            for (int cy = 0; cy < n + 2 * g; cy++)
                for (int cx = 0; cx < n + 2 * g; cx++) {
                    int x = cx - g, y = cy - g;
                    float *dst = ibl_image_texel(out, ox + cx, oy + cy);
                    int inside = x >= 0 && y >= 0 && x < n && y < n;
                    if (inside && (n == native || nearest)) {
                        /* exact copy (replicated when enlarged) keeps the round trip exact */
                        int sx = (int)((long)x * native / n), sy = (int)((long)y * native / n);
                        memcpy(dst, src + ((size_t)sy * native + sx) * 4, 4 * sizeof(float));
                        continue;
                    }
                    /* gutters and enlarged levels: the seamless sample along that direction */
                    ibl_vec3 d = ibl_cube_direction(f, ((float)x + 0.5f) / (float)n,
                                                    ((float)y + 0.5f) / (float)n);
                    if (nearest)
                        ibl_cubemap_sample_nearest(chain, k, d, dst);
                    else
                        ibl_cubemap_sample_bilinear(chain, k, d, dst);
                }
        }
    }
    return IBL_OK;
}

ibl_status ibl_atlas_unpack(ibl_context *ctx, const ibl_image *atlas,
                            const ibl_atlas_layout *layout, int size, ibl_cubemap *out)
{
    memset(out, 0, sizeof *out);
    ibl_atlas_layout check;
    ibl_atlas_desc d = {.gutter = layout->gutter ? layout->gutter : -1};
    if (ibl_atlas_plan(size, layout->levels, &d, &check) != IBL_OK || check.width != atlas->width ||
        check.height > atlas->height)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                        "atlas: a %dx%d image does not hold a %d-level chain of size %d",
                        atlas->width, atlas->height, layout->levels, size);
    ibl_status st = ibl_cubemap_alloc(ctx, size, layout->levels, out);
    if (st != IBL_OK) return st;
    int g = layout->gutter;
    int n0 = layout->face_size[0];
    float *tmp = ibl_alloc(ctx, (size_t)n0 * n0 * 4 * sizeof(float));
    if (!tmp) {
        ibl_cubemap_free(ctx, out);
        return ibl_context_status(ctx);
    }
    for (int k = 0; k < layout->levels; k++) {
        int n = layout->face_size[k], native = ibl_level_size(size, k);
        for (int f = 0; f < 6; f++) {
            int ox, oy;
            face_origin(layout, k, f, &ox, &oy);
            for (int y = 0; y < n; y++)
                memcpy(tmp + (size_t)y * n * 4, ibl_image_texel(atlas, ox + g, oy + g + y),
                       (size_t)n * 4 * sizeof(float));
            /* halve 2x2 at a time, summing in pairs: the box average of an enlarged level, and
             * exact for replicated texels (so a nearest-enlarged atlas round-trips bit for bit) */
            for (int m = n; m > native; m /= 2) {
                int h = m / 2;
                for (int y = 0; y < h; y++)
                    for (int x = 0; x < h; x++)
                        for (int c = 0; c < 4; c++) {
                            const float *r0 = tmp + ((size_t)(2 * y) * m + 2 * x) * 4 + c;
                            const float *r1 = r0 + (size_t)m * 4;
                            tmp[((size_t)y * h + x) * 4 + c] =
                                ((r0[0] + r0[4]) + (r1[0] + r1[4])) * 0.25f;
                        }
            }
            memcpy(ibl_cubemap_face(out, k, f), tmp, (size_t)native * native * 4 * sizeof(float));
        }
    }
    ibl_free(ctx, tmp);
    return IBL_OK;
}

static void atlas_pixel(const ibl_atlas_layout *l, int level, ibl_vec3 dir, float *px, float *py)
{
    float s, t;
    int f = ibl_cube_face_st(dir, &s, &t);
    /* Daqi 2016's edge problem (UVs falling outside a small level): s, t stay on the face,
     * the gutter holds the neighbours for the bilinear footprint at the edge */
    s = s < 0.0f ? 0.0f : s > 1.0f ? 1.0f : s;
    t = t < 0.0f ? 0.0f : t > 1.0f ? 1.0f : t;
    int ox, oy;
    face_origin(l, level, f, &ox, &oy);
    float n = (float)l->face_size[level];
    *px = (float)(ox + l->gutter) + s * n;
    *py = (float)(oy + l->gutter) + t * n;
}

void ibl_atlas_uv(const ibl_atlas_layout *l, int level, ibl_vec3 dir, float *u, float *v)
{
    float px, py;
    atlas_pixel(l, level, dir, &px, &py);
    *u = px / (float)l->width;
    *v = py / (float)l->height;
}

static void bilinear_2d(const ibl_image *im, float px, float py, float out[4])
{
    float fx = px - 0.5f, fy = py - 0.5f;
    int x0 = (int)floorf(fx), y0 = (int)floorf(fy);
    float wx = fx - (float)x0, wy = fy - (float)y0;
    for (int c = 0; c < 4; c++) out[c] = 0.0f;
    for (int j = 0; j < 2; j++)
        for (int i = 0; i < 2; i++) {
            int x = x0 + i, y = y0 + j;
            if (x < 0) x = 0;
            if (y < 0) y = 0;
            if (x >= im->width) x = im->width - 1;
            if (y >= im->height) y = im->height - 1;
            float w = (i ? wx : 1.0f - wx) * (j ? wy : 1.0f - wy);
            const float *t = ibl_image_texel(im, x, y);
            for (int c = 0; c < 4; c++) out[c] += w * t[c];
        }
}

void ibl_atlas_sample(const ibl_image *atlas, const ibl_atlas_layout *l, float lod, ibl_vec3 dir,
                      float out[4])
{
    if (lod < 0.0f) lod = 0.0f;
    if (lod > (float)(l->levels - 1)) lod = (float)(l->levels - 1);
    int k = (int)floorf(lod);
    float w = lod - (float)k;
    float px, py, a[4], b[4];
    atlas_pixel(l, k, dir, &px, &py);
    bilinear_2d(atlas, px, py, a);
    if (w == 0.0f || k + 1 >= l->levels) {
        memcpy(out, a, sizeof a);
        return;
    }
    atlas_pixel(l, k + 1, dir, &px, &py);
    bilinear_2d(atlas, px, py, b);
    for (int c = 0; c < 4; c++) out[c] = a[c] + (b[c] - a[c]) * w;
}

ibl_status ibl_pack_material_channels(ibl_context *ctx, const ibl_image *metalness,
                                      const ibl_image *roughness, const ibl_image *ao,
                                      const ibl_image *transmittance, ibl_image *out)
{
    const ibl_image *in[4] = {metalness, roughness, ao, transmittance};
    static const float fallback[4] = {0.0f, 1.0f, 1.0f, 0.0f};
    int w = 0, h = 0;
    memset(out, 0, sizeof *out);
    for (int i = 0; i < 4; i++) {
        if (!in[i]) continue;
        if (w == 0) {
            w = in[i]->width;
            h = in[i]->height;
        } else if (in[i]->width != w || in[i]->height != h) {
            return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                            "pack channels: inputs differ in size (%dx%d and %dx%d)", w, h,
                            in[i]->width, in[i]->height);
        }
    }
    if (w == 0) return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "pack channels: no input");
    ibl_status st = ibl_image_alloc(ctx, w, h, out);
    if (st != IBL_OK) return st;
    size_t count = (size_t)w * h;
    for (size_t p = 0; p < count; p++)
        for (int i = 0; i < 4; i++)
            out->pixels[p * 4 + i] = in[i] ? in[i]->pixels[p * 4] : fallback[i];
    return IBL_OK;
}

ibl_status ibl_unpack_material_channels(ibl_context *ctx, const ibl_image *packed, ibl_image out[4])
{
    memset(out, 0, 4 * sizeof *out);
    for (int i = 0; i < 4; i++) {
        ibl_status st = ibl_image_alloc(ctx, packed->width, packed->height, &out[i]);
        if (st != IBL_OK) {
            for (int j = 0; j < i; j++) ibl_image_free(ctx, &out[j]);
            return st;
        }
        size_t count = (size_t)packed->width * packed->height;
        for (size_t p = 0; p < count; p++) {
            float v = packed->pixels[p * 4 + i];
            float *t = out[i].pixels + p * 4;
            t[0] = t[1] = t[2] = v;
            t[3] = 1.0f;
        }
    }
    return IBL_OK;
}
