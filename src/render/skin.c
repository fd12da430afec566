/* Skin in the preview renderer: rays against an ibl_scene (Embree) placed like the OBJ mesh of
 * `ibl render --scene` (centred, its largest extent 3.2 units), the normal maps read through the
 * triangle's tangent frame, and ibl_skin_shade for the diffuse (docs/SKIN.md). */
#include "render_internal.h"
#include "scene/scene_internal.h"

#include <string.h>

/* The mesh's placement: render space = (mesh space - centre) * scale. */
static void placement(const ibl_scene *m, float centre[3], float *scale)
{
    float extent = 0.0f;
    for (int k = 0; k < 3; k++) {
        centre[k] = 0.5f * (m->bounds_min[k] + m->bounds_max[k]);
        extent = fmaxf(extent, m->bounds_max[k] - m->bounds_min[k]);
    }
    *scale = extent > 0.0f ? 3.2f / extent : 1.0f;
}

/* Bilinear read of an image at texture coordinates (u, v), v = 0 at the top row, clamped. */
static void sample(const ibl_image *im, float u, float v, float out[3])
{
    float fx = u * (float)im->width - 0.5f, fy = v * (float)im->height - 0.5f;
    float x0f = floorf(fx), y0f = floorf(fy), tx = fx - x0f, ty = fy - y0f;
    int x0 = ibl__clampi((int)x0f, 0, im->width - 1), x1 = ibl__clampi((int)x0f + 1, 0, im->width - 1);
    int y0 = ibl__clampi((int)y0f, 0, im->height - 1), y1 = ibl__clampi((int)y0f + 1, 0, im->height - 1);
    const float *a = ibl_image_texel(im, x0, y0), *b = ibl_image_texel(im, x1, y0);
    const float *c = ibl_image_texel(im, x0, y1), *d = ibl_image_texel(im, x1, y1);
    for (int k = 0; k < 3; k++)
        out[k] = (1 - ty) * ((1 - tx) * a[k] + tx * b[k]) + ty * ((1 - tx) * c[k] + tx * d[k]);
}

/* The triangle's tangent (+u) and bitangent (image up, -v), orthonormalised about n. */
static void tangent_frame(const ibl_scene *m, int tri, ibl_vec3 n, ibl_vec3 *t, ibl_vec3 *b)
{
    const uint32_t *ix = m->indices + 3 * tri;
    const float *p0 = m->positions + 3 * ix[0], *p1 = m->positions + 3 * ix[1], *p2 = m->positions + 3 * ix[2];
    const float *t0 = m->uvs + 2 * ix[0], *t1 = m->uvs + 2 * ix[1], *t2 = m->uvs + 2 * ix[2];
    float du1 = t1[0] - t0[0], dv1 = t1[1] - t0[1], du2 = t2[0] - t0[0], dv2 = t2[1] - t0[1];
    float det = du1 * dv2 - du2 * dv1;
    ibl_vec3 e1 = ibl__v3(p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]);
    ibl_vec3 e2 = ibl__v3(p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]);
    ibl_vec3 dpdu = ibl__scale(ibl__sub(ibl__scale(e1, dv2), ibl__scale(e2, dv1)), 1.0f / det);
    ibl_vec3 dpdv = ibl__scale(ibl__sub(ibl__scale(e2, du1), ibl__scale(e1, du2)), 1.0f / det);
    ibl_vec3 tt = ibl__sub(dpdu, ibl__scale(n, ibl__dot(n, dpdu)));
    ibl_vec3 up = ibl__scale(dpdv, -1.0f);
    if (!(fabsf(det) > 1e-20f) || !(ibl__dot(tt, tt) > 1e-20f)) {
        ibl__frame(n, t, b);
        return;
    }
    *t = ibl__norm(tt);
    ibl_vec3 bb = ibl__cross(n, *t);
    *b = ibl__dot(bb, up) < 0.0f ? ibl__scale(bb, -1.0f) : bb; /* mirrored UVs */
}

static ibl_vec3 decode(const ibl_image *map, float u, float v, ibl_vec3 t, ibl_vec3 b, ibl_vec3 n)
{
    float c[3];
    sample(map, u, v, c);
    float x = 2.0f * c[0] - 1.0f, y = 2.0f * c[1] - 1.0f, z = 2.0f * c[2] - 1.0f;
    ibl_vec3 w = ibl__add(ibl__add(ibl__scale(t, x), ibl__scale(b, y)), ibl__scale(n, z));
    return ibl__dot(w, w) > 1e-12f ? ibl__norm(w) : n;
}

int ibl__skin_intersect(const ibl_render_skin *skin, ibl_vec3 o, ibl_vec3 d, float *t,
                        ibl__skin_hit *out)
{
    float centre[3], scale;
    placement(skin->mesh, centre, &scale);
    ibl_vec3 om = ibl__v3(o.x / scale + centre[0], o.y / scale + centre[1], o.z / scale + centre[2]);
    ibl_scene_hit h;
    if (!ibl_scene_intersect(skin->mesh, om, d, 0.0f, 1e30f, &h)) return 0;
    *t = h.t * scale;
    out->n = h.normal;
    out->geometric_normal = h.geometric_normal;
    out->triangle = h.triangle;
    out->uv[0] = h.uv[0];
    out->uv[1] = h.uv[1];
    return 1;
}

void ibl__skin_shade(const ibl_probe *probe, const ibl_render_desc *desc, const ibl__skin_hit *h,
                     ibl_vec3 v, float out[3])
{
    const ibl_render_skin *skin = desc->skin;
    ibl_vec3 t, b;
    tangent_frame(skin->mesh, h->triangle, h->n, &t, &b);
    float u = h->uv[0], w = h->uv[1];
    ibl_skin_surface s;
    memset(&s, 0, sizeof s);
    ibl_vec3 detail = decode(skin->normal, u, w, t, b, h->n);
    for (int c = 0; c < 3; c++)
        s.n[c] = desc->skin_off ? detail : decode(skin->scattered[c], u, w, t, b, h->n);
    s.geometric_normal = h->geometric_normal;
    static const float default_albedo[3] = {0.8f, 0.55f, 0.45f};
    int given = skin->albedo[0] > 0.0f || skin->albedo[1] > 0.0f || skin->albedo[2] > 0.0f;
    memcpy(s.albedo, given ? skin->albedo : default_albedo, sizeof s.albedo);
    if (skin->transmittance && !desc->skin_off) {
        float tr[3];
        sample(skin->transmittance, u, w, tr);
        s.transmittance = tr[0];
    }
    s.thickness_range_mm = skin->thickness_range_mm;
    ibl_skin_result r;
    ibl_skin_shade(probe, NULL, &s, &r);
    /* the specular: a glTF dielectric without its diffuse (the skin's is above) */
    static const float black[3] = {0.0f, 0.0f, 0.0f};
    ibl_material m = ibl_material_gltf(black, 0.0f, skin->roughness > 0.0f ? skin->roughness : 0.45f);
    ibl_surface surf;
    memset(&surf, 0, sizeof surf);
    surf.n = detail;
    surf.v = v;
    surf.geometric_normal = h->geometric_normal;
    ibl_shade_result sr;
    ibl_shade(probe, &desc->shade, &m, &surf, &sr);
    for (int c = 0; c < 3; c++) out[c] = r.color[c] + sr.color[c];
}
