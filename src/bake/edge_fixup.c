/* Cube edge fixups for hardware without seamless cube filtering.
 * Gotanda and Shoji (tri-Ace), "Real-time Physically Based Rendering - Implementation", 2010:
 * "Edge overlapping" (1)-(2) and "Bent Phong filter kernel"; the warp of NVTT's CubeSurface as
 * used by cmft (texel centre coordinate u -> u + a*u^3, a = n^2/(n-1)^3) with its lookup
 * re-derived here as the exact inverse. docs/EDGE_FIXUP.md defines every method precisely
 * and gives the shader code each one needs. */
#include "core/numeric.h"
#include "core/context_internal.h"
#include "ibl/edge_fixup.h"

#include <ctype.h>
#include <math.h>
#include <string.h>

static const char *const fixup_names[] = {"none", "overlap", "overlap2", "bent", "warp"};
enum { FIXUP_COUNT = (int)(sizeof fixup_names / sizeof fixup_names[0]) };

const char *ibl_edge_fixup_name(ibl_edge_fixup fixup)
{
    if ((int)fixup < 0 || (int)fixup >= FIXUP_COUNT) return "unknown";
    return fixup_names[fixup];
}

int ibl_edge_fixup_from_name(const char *name, ibl_edge_fixup *out)
{
    if (!name || !out) return 0;
    for (int i = 0; i < FIXUP_COUNT; i++) {
        const char *a = name, *b = fixup_names[i];
        while (*a && *b && tolower((unsigned char)*a) == *b) a++, b++;
        if (!*a && !*b) {
            *out = (ibl_edge_fixup)i;
            return 1;
        }
    }
    return 0;
}

static ibl_vec3 to_vec3(ibl__dvec3 a)
{
    ibl_vec3 v = {(float)a.x, (float)a.y, (float)a.z};
    return v;
}

/* The face frame: direction = M + sc*S + tc*T for face-plane coordinates sc, tc in [-1, 1]. */
typedef struct face_frame {
    ibl__dvec3 m, s, t;
} face_frame;

static face_frame frame_of(int face)
{
    double c[3], sx[3], ty[3];
    ibl_cube_direction_d(face, 0.5, 0.5, c);
    ibl_cube_direction_d(face, 1.0, 0.5, sx);
    ibl_cube_direction_d(face, 0.5, 1.0, ty);
    face_frame f;
    f.m = ibl__dv(c[0], c[1], c[2]);
    f.s = ibl__dv(sx[0] - c[0], sx[1] - c[1], sx[2] - c[2]);
    f.t = ibl__dv(ty[0] - c[0], ty[1] - c[1], ty[2] - c[2]);
    return f;
}

static ibl__dvec3 frame_point(const face_frame *f, double m, double sc, double tc)
{
    return ibl__dadd(ibl__dadd(ibl__dscale(f->m, m), ibl__dscale(f->s, sc)), ibl__dscale(f->t, tc));
}

/* Texel centre in face-plane coordinates: (2x + 1)/n - 1. */
static double centre_coord(int i, int n) { return (2.0 * i + 1.0) / n - 1.0; }

/* ---- bent: tri-Ace "Bent Phong filter kernel" ---- */

/* Fraction of the target angle used: linear in the blur radius from the small-radius
 * fraction at 0 to the large-radius fraction at large_radius (tri-Ace: 50% small, 100% large). */
static double bent_fraction(const ibl_bent_desc *desc, float blur_radius)
{
    double small = 0.5, large = 1.0, at = 0.5;
    if (desc) {
        if (desc->small_radius_fraction > 0) small = desc->small_radius_fraction;
        if (desc->large_radius_fraction > 0) large = desc->large_radius_fraction;
        if (desc->large_radius > 0) at = desc->large_radius;
    }
    double r = blur_radius > 0 ? blur_radius / at : 0.0;
    if (r > 1.0) r = 1.0;
    double fraction = small + (large - small) * r;
    /* beyond 1 an edge texel would pass its partner (and at 1 + alpha_e/target, infinity) */
    return fraction > 1.0 ? 1.0 : fraction;
}

/* Angles on a face: a direction M + u*S + v*T is at angle alpha = atan(u) from the face
 * centre in the plane spanned by M and S (the plane perpendicular to the u-edges), beta =
 * atan(v) likewise. Seen in that plane, the normals of the two edge texels facing each other
 * across a u-edge (centres at alpha_e = atan(1 - 1/n) on each side, the edge at pi/4) are
 * target = 2 (pi/4 - alpha_e) apart; that is the angle between them at the middle of the
 * edge, and its projection perpendicular to the edge elsewhere. The bend offsets alpha by
 * fraction * target * |alpha| / alpha_e toward the edge (zero at the centre, the target share
 * at the edge texel), and beta likewise: alpha' = k alpha, k = 1 + fraction * target /
 * alpha_e. At fraction 1/2 every edge texel lands on the face edge at the same point as its
 * partner (corner texels on the cube corner), at 1 on its partner's original direction. */
static ibl__dvec3 bent_direction(const ibl_bent_desc *desc, int face, int n, int x, int y,
                           float blur_radius)
{
    face_frame f = frame_of(face);
    double u = centre_coord(x, n), v = centre_coord(y, n);
    if (n >= 2) {
        double fraction = bent_fraction(desc, blur_radius);
        double alpha_e = atan(1.0 - 1.0 / n);
        double target = 2.0 * (atan(1.0) - alpha_e);
        double k = 1.0 + fraction * target / alpha_e;
        u = tan(k * atan(u));
        v = tan(k * atan(v));
    }
    return ibl__dnorm(frame_point(&f, 1.0, u, v));
}

/* ---- warp: NVTT / cmft ---- */

/* a such that the edge texel centre (n-1)/n lands on the face edge: (n-1)/n + a((n-1)/n)^3 = 1. */
static double warp_factor(int n) { return (double)n * n / ((double)(n - 1) * (n - 1) * (n - 1)); }

/* The inverse of w = u + a*u^3 (monotonic, one real root): the hyperbolic form of Cardano's
 * solution for t^3 + p t + q = 0 with p = 1/a > 0, q = -w/a, stable for every a > 0. */
static double warp_inverse(double w, double a)
{
    double k = sqrt(3.0 * a);
    return 2.0 / k * sinh(asinh(1.5 * k * w) / 3.0);
}

ibl_vec3 ibl_edge_fixup_texel_direction(ibl_edge_fixup fixup, const ibl_bent_desc *bent, int face,
                                        int n, int x, int y, float blur_radius)
{
    if (face < 0 || face >= 6 || n < 1 || x < 0 || y < 0 || x >= n || y >= n) return to_vec3(ibl__dv(0, 0, 0));
    if (fixup == IBL_EDGE_FIXUP_BENT) return to_vec3(bent_direction(bent, face, n, x, y, blur_radius));
    if (fixup == IBL_EDGE_FIXUP_WARP && n >= 2) {
        double a = warp_factor(n);
        double u = centre_coord(x, n), v = centre_coord(y, n);
        u += a * u * u * u;
        v += a * v * v * v;
        face_frame f = frame_of(face);
        return to_vec3(ibl__dnorm(frame_point(&f, 1.0, u, v)));
    }
    return ibl_cube_texel_direction(face, n, x, y);
}

ibl_vec3 ibl_edge_fixup_warp_lookup(ibl_vec3 dir, int n)
{
    double d[3] = {dir.x, dir.y, dir.z}, s, t;
    if (n < 2) return to_vec3(ibl__dnorm(ibl__dv(d[0], d[1], d[2])));
    int face = ibl_cube_face_st_d(d, &s, &t);
    double a = warp_factor(n);
    double u = warp_inverse(2.0 * s - 1.0, a), v = warp_inverse(2.0 * t - 1.0, a);
    face_frame f = frame_of(face);
    return to_vec3(ibl__dnorm(frame_point(&f, 1.0, u, v)));
}

/* ---- overlap, overlap2: post-processes of a level ---- */

typedef struct texel_ref {
    int face, x, y;
} texel_ref;

/* The texel of the neighbouring face across edge `edge` (0: x = 0, 1: x = n-1, 2: y = 0,
 * 3: y = n-1) at `depth` texels from the seam, with the same along-edge position as (x, y).
 * Found by unfolding: in this face's frame the neighbour's texel centre is
 * sign*A + along*B + (1 - (2 depth + 1)/n) * M, which projects exactly onto its centre. */
static texel_ref partner_across(int face, int n, int x, int y, int edge, int depth)
{
    face_frame f = frame_of(face);
    double sign = (edge & 1) ? 1.0 : -1.0;
    double m = 1.0 - (2.0 * depth + 1.0) / n;
    ibl__dvec3 p = edge < 2 ? frame_point(&f, m, sign, centre_coord(y, n))
                      : frame_point(&f, m, centre_coord(x, n), sign);
    double d[3] = {p.x, p.y, p.z}, s, t;
    texel_ref r;
    r.face = ibl_cube_face_st_d(d, &s, &t);
    r.x = (int)floor(s * n);
    r.y = (int)floor(t * n);
    if (r.x < 0) r.x = 0;
    if (r.x >= n) r.x = n - 1;
    if (r.y < 0) r.y = 0;
    if (r.y >= n) r.y = n - 1;
    return r;
}

static int ref_less(texel_ref a, texel_ref b)
{
    if (a.face != b.face) return a.face < b.face;
    if (a.y != b.y) return a.y < b.y;
    return a.x < b.x;
}

static float *texel_ptr(ibl_cubemap *cube, int level, int n, texel_ref r)
{
    return ibl_cubemap_face(cube, level, r.face) + ((size_t)r.y * n + r.x) * 4;
}

/* Depth of (x, y) from each edge: x, n-1-x, y, n-1-y. */
static void edge_depths(int n, int x, int y, int depth[4])
{
    depth[0] = x;
    depth[1] = n - 1 - x;
    depth[2] = y;
    depth[3] = n - 1 - y;
}

/* Writes to every member of a group of 2 or 3 texels the weighted sum w_self * own +
 * w_other * each other member, computed from the originals in canonical member order (so
 * equal weights give bit-equal results whichever member is processed). */
static void blend_group(ibl_cubemap *cube, int level, int n, texel_ref *g, int count,
                        double w_self, double w_other)
{
    /* canonical order: sorted by (face, y, x) */
    for (int i = 1; i < count; i++)
        for (int j = i; j > 0 && ref_less(g[j], g[j - 1]); j--) {
            texel_ref tmp = g[j];
            g[j] = g[j - 1];
            g[j - 1] = tmp;
        }
    float orig[3][4];
    for (int i = 0; i < count; i++) memcpy(orig[i], texel_ptr(cube, level, n, g[i]), sizeof orig[i]);
    for (int i = 0; i < count; i++) {
        float *dst = texel_ptr(cube, level, n, g[i]);
        for (int c = 0; c < 4; c++) {
            double acc = 0;
            for (int j = 0; j < count; j++) acc += (i == j ? w_self : w_other) * (double)orig[j][c];
            dst[c] = (float)acc;
        }
    }
}

static void average_all_faces(ibl_cubemap *cube, int level)
{
    double acc[4] = {0, 0, 0, 0};
    for (int f = 0; f < 6; f++)
        for (int c = 0; c < 4; c++) acc[c] += ibl_cubemap_face(cube, level, f)[c];
    for (int f = 0; f < 6; f++)
        for (int c = 0; c < 4; c++) ibl_cubemap_face(cube, level, f)[c] = (float)(acc[c] / 6.0);
}

/* Every texel belongs to at most one group; a group is processed from its first member in
 * (face, y, x) order, so the result does not depend on the visiting order. Groups:
 *  - corner texels (depth 0 from two edges): the three meeting at a cube corner -> their mean;
 *  - other edge texels (depth 0 from one edge): the pair across the seam -> their mean;
 *  - overlap2, n >= 4: texels at depth 1 from one edge and >= 2 from the others: the pair at
 *    depth 1 across the seam -> 3/4 own + 1/4 partner; texels at depth 1 from two edges: the
 *    three at (1, 1) around a cube corner -> 1/2 own + 1/4 each of the other two. */
static void overlap_level(ibl_cubemap *cube, int level, int two_deep)
{
    int n = ibl_level_size(cube->size, level);
    if (n == 1) {
        average_all_faces(cube, level);
        return;
    }
    if (n < 4) two_deep = 0;
    for (int face = 0; face < 6; face++) {
        for (int y = 0; y < n; y++) {
            for (int x = 0; x < n; x++) {
                int depth[4], zero[2], one[2], nz = 0, n1 = 0, inner = 1;
                edge_depths(n, x, y, depth);
                for (int e = 0; e < 4; e++) {
                    if (depth[e] == 0) zero[nz++] = e;
                    else if (depth[e] == 1 && n1 < 2) one[n1++] = e;
                    if (depth[e] < 2) inner = 0;
                }
                if (inner) continue;
                texel_ref g[3] = {{face, x, y}, {0, 0, 0}, {0, 0, 0}};
                int count = 0, d;
                double w_self, w_other;
                const int *edges;
                if (nz > 0) {
                    count = nz + 1;
                    edges = zero;
                    d = 0;
                    w_self = w_other = 1.0 / count;
                } else if (two_deep && n1 > 0) {
                    count = n1 + 1;
                    edges = one;
                    d = 1;
                    w_self = count == 2 ? 0.75 : 0.5;
                    w_other = 0.25;
                } else {
                    continue;
                }
                for (int k = 0; k + 1 < count; k++) g[k + 1] = partner_across(face, n, x, y, edges[k], d);
                int first = 1;
                for (int k = 1; k < count; k++)
                    if (ref_less(g[k], g[0])) first = 0;
                if (first) blend_group(cube, level, n, g, count, w_self, w_other);
            }
        }
    }
}

ibl_status ibl_edge_fixup_apply(ibl_context *ctx, ibl_edge_fixup fixup, ibl_cubemap *cube,
                                int level)
{
    if (!cube || !cube->data)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "edge fixup: no cubemap");
    if (level < 0 || level >= cube->levels)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "edge fixup: level %d out of range 0..%d",
                        level, cube->levels - 1);
    switch (fixup) {
    case IBL_EDGE_FIXUP_NONE:
        return IBL_OK;
    case IBL_EDGE_FIXUP_OVERLAP:
    case IBL_EDGE_FIXUP_OVERLAP2:
        overlap_level(cube, level, fixup == IBL_EDGE_FIXUP_OVERLAP2);
        return IBL_OK;
    case IBL_EDGE_FIXUP_BENT:
    case IBL_EDGE_FIXUP_WARP:
        /* a 1x1 face has no direction to bend or warp: like CubeMapGen, average the faces */
        if (ibl_level_size(cube->size, level) == 1) average_all_faces(cube, level);
        return IBL_OK;
    }
    return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "edge fixup: unknown method %d", (int)fixup);
}
