/* The edge fixups of the dynamic plan as precomputed tables (tri-Ace 2010 "Edge overlapping"
 * (1) and (2); the 1x1 rule "the color becomes the average of all faces").
 *
 * ibl_edge_fixup_apply (edge_fixup.c) finds the partner of each edge texel across the seam
 * by unfolding geometry every time it runs: correct, but for a 16x16x6 chain that costs more
 * than the filtering. Here the groups (two texels across a seam, three at a cube corner; for
 * overlap2 also the pairs and triples one texel deep) are found once, by the same unfolding,
 * and a run only blends them: the same weights, the members in the same canonical order
 * (face, y, x), the same double accumulation, so the same bits as ibl_edge_fixup_apply (the
 * tests compare them). */
#include "bake/specular_dynamic/dynamic_internal.h"
#include "core/context_internal.h"

#include <math.h>
#include <string.h>

/* The texel index (face, y, x) of the texel across edge `edge` (0: x = 0, 1: x = n-1,
 * 2: y = 0, 3: y = n-1) at `depth` texels from the seam, beside texel (x, y) of `face`: the
 * point sign A + along B + (1 - (2 depth + 1) / n) M of the face's frame projects onto the
 * neighbour's texel centre. */
static uint32_t partner(int face, int n, int x, int y, int edge, int depth)
{
    dyn_face_frame f;
    ibl__dyn_face_frame(face, &f);
    double sign = (edge & 1) ? 1.0 : -1.0, major = 1.0 - (2.0 * depth + 1.0) / n;
    double sc = edge < 2 ? sign : (2.0 * x + 1.0) / n - 1.0;
    double tc = edge < 2 ? (2.0 * y + 1.0) / n - 1.0 : sign;
    double p[3], s, t;
    for (int i = 0; i < 3; i++) p[i] = major * f.m[i] + sc * f.s[i] + tc * f.t[i];
    int pf = ibl_cube_face_st_d(p, &s, &t);
    int px = (int)floor(s * n), py = (int)floor(t * n);
    px = px < 0 ? 0 : px >= n ? n - 1 : px;
    py = py < 0 ? 0 : py >= n ? n - 1 : py;
    return (uint32_t)(((size_t)pf * n + py) * n + px);
}

/* The group of texel (face, x, y) at edge n, or 0 when it has none or is not its first
 * member. */
static int group_of(int face, int n, int x, int y, int two_deep, dyn_fixup_group *g)
{
    int depth[4] = {x, n - 1 - x, y, n - 1 - y}, zero[2], one[2], nz = 0, n1 = 0, inner = 1;
    for (int e = 0; e < 4; e++) {
        if (depth[e] == 0) zero[nz++] = e;
        else if (depth[e] == 1 && n1 < 2) one[n1++] = e;
        if (depth[e] < 2) inner = 0;
    }
    if (inner) return 0;
    const int *edges;
    int d;
    if (nz > 0) {
        g->count = (uint8_t)(nz + 1), edges = zero, d = 0;
        g->kind = DYN_FIXUP_MEAN;
    } else if (two_deep && n1 > 0) {
        g->count = (uint8_t)(n1 + 1), edges = one, d = 1;
        g->kind = DYN_FIXUP_DEEP;
    } else {
        return 0;
    }
    g->texel[0] = (uint32_t)(((size_t)face * n + y) * n + x);
    for (int k = 0; k + 1 < g->count; k++) g->texel[k + 1] = partner(face, n, x, y, edges[k], d);
    for (int k = 1; k < g->count; k++)
        if (g->texel[k] < g->texel[0]) return 0;
    /* canonical order: by (face, y, x), i.e. by index */
    for (int i = 1; i < g->count; i++)
        for (int j = i; j > 0 && g->texel[j] < g->texel[j - 1]; j--) {
            uint32_t tmp = g->texel[j];
            g->texel[j] = g->texel[j - 1];
            g->texel[j - 1] = tmp;
        }
    return 1;
}

ibl_status ibl__dyn_fixup_create(ibl_context *ctx, ibl_edge_fixup fixup, int n, dyn_fixup *out)
{
    memset(out, 0, sizeof *out);
    out->edge = n;
    out->method = fixup;
    if (fixup != IBL_EDGE_FIXUP_OVERLAP && fixup != IBL_EDGE_FIXUP_OVERLAP2) return IBL_OK;
    if (n < 2) return IBL_OK;
    int two_deep = fixup == IBL_EDGE_FIXUP_OVERLAP2 && n >= 4;
    /* at most every texel of the four borders two deep, one group each */
    size_t capacity = (size_t)6 * 8 * n;
    out->group = ibl_alloc(ctx, capacity * sizeof *out->group);
    if (!out->group) return ibl_context_status(ctx);
    for (int face = 0; face < 6; face++)
        for (int y = 0; y < n; y++)
            for (int x = 0; x < n; x++) {
                dyn_fixup_group g;
                memset(&g, 0, sizeof g);
                if (group_of(face, n, x, y, two_deep, &g) && (size_t)out->groups < capacity)
                    out->group[out->groups++] = g;
            }
    return IBL_OK;
}

void ibl__dyn_fixup_destroy(ibl_context *ctx, dyn_fixup *f)
{
    ibl_free(ctx, f->group);
    memset(f, 0, sizeof *f);
}

/* edge_fixup.c's rule for a 1x1 level: every face becomes the mean of the six */
static void average_faces(float *level)
{
    double acc[4] = {0, 0, 0, 0};
    for (int f = 0; f < 6; f++)
        for (int c = 0; c < 4; c++) acc[c] += level[f * 4 + c];
    for (int f = 0; f < 6; f++)
        for (int c = 0; c < 4; c++) level[f * 4 + c] = (float)(acc[c] / 6.0);
}

void ibl__dyn_fixup_apply(const dyn_fixup *f, float *level)
{
    if (f->method == IBL_EDGE_FIXUP_NONE) return;
    if (f->edge == 1) {
        average_faces(level);
        return;
    }
    for (int i = 0; i < f->groups; i++) {
        const dyn_fixup_group *g = &f->group[i];
        int count = g->count;
        double w_self, w_other;
        if (g->kind == DYN_FIXUP_MEAN) {
            w_self = w_other = 1.0 / count;
        } else {
            w_self = count == 2 ? 0.75 : 0.5;
            w_other = 0.25;
        }
        float orig[3][4];
        for (int k = 0; k < count; k++) memcpy(orig[k], level + (size_t)g->texel[k] * 4, sizeof orig[k]);
        for (int k = 0; k < count; k++) {
            float *dst = level + (size_t)g->texel[k] * 4;
            for (int c = 0; c < 4; c++) {
                double acc = 0;
                for (int j = 0; j < count; j++) acc += (k == j ? w_self : w_other) * (double)orig[j][c];
                dst[c] = (float)acc;
            }
        }
    }
}
