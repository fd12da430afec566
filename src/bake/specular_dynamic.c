/* The dynamic (per-frame) prefilter: the chain as one sparse linear operator, built once.
 *
 * tri-Ace 2010's dynamic configurations refilter a freshly rendered small cube every frame.
 * Each output texel becomes a row of weights over the texels of one box mip of the source
 * (the level whose texels are at most half the lobe's half width, so the lobe is resolved),
 * each weight the lobe integrated over that texel (k x k sub-points, k from the lobe's width),
 * rows normalised to sum 1 so that a constant cube stays constant. A run is then the source's
 * area-weighted box mips plus one sparse product: no allocation, time fixed by the plan.
 * Unlike the static method it does not move a coarse texel's weight to where its light is
 * (a box mip has no radiance centroid), so it is less exact next to small bright lights; the
 * chains it is meant for (16..64 texels) are coarse anyway. docs/SPECULAR.md "Dynamic path". */
#include "specular_internal.h"
#include "core/context_internal.h"
#include "core/numeric.h"

#include <math.h>
#include <string.h>

enum { MAX_ENTRIES = 1 << 25, DB = 8 };

typedef struct dyn_level {
    int n, mip;           /* output edge, source mip the rows read */
    size_t row_begin;     /* first row (output texel) of this level */
} dyn_level;

struct ibl__dynamic {
    ibl_context *ctx;
    int S, L, mips;
    dyn_level lv[IBL_MAX_LEVELS];
    size_t mip_offset[IBL_MAX_LEVELS + 1]; /* texel index of (mip, face 0, 0, 0)        */
    float *omega[IBL_MAX_LEVELS];          /* per mip: M M texel solid angles            */
    float *centre;                         /* 3 floats per texel of every mip: direction */
    float *cone;                           /* per DB x DB block of every mip: axis, radius */
    size_t cone_offset[IBL_MAX_LEVELS];
    float *mipdata;                        /* 3 floats per texel of every mip (scratch)  */
    uint32_t *row_start;                   /* rows + 1                                   */
    uint32_t *index;
    float *weight;
    size_t rows;
};


void ibl__dynamic_destroy(ibl__dynamic *d)
{
    if (!d) return;
    for (int m = 0; m < d->mips; m++) ibl_free(d->ctx, d->omega[m]);
    ibl_free(d->ctx, d->mipdata);
    ibl_free(d->ctx, d->centre);
    ibl_free(d->ctx, d->cone);
    ibl_free(d->ctx, d->row_start);
    ibl_free(d->ctx, d->index);
    ibl_free(d->ctx, d->weight);
    ibl_free(d->ctx, d);
}

/* The lobe around R integrated over texel (x, y) of face f (edge M) with k x k sub-points,
 * each weighted by its solid angle (the Jacobian of the face plane at its centre). */
static double texel_integral(const ibl__lobe *lobe, const double R[3], int f, int M, int x, int y,
                             int k)
{
    double h = 2.0 / M, hk = h / k, w = 0.0;
    for (int j = 0; j < k; j++)
        for (int i = 0; i < k; i++) {
            double u = -1.0 + x * h + (i + 0.5) * hk, v = -1.0 + y * h + (j + 0.5) * hk;
            double d[3];
            ibl_cube_direction_d(f, 0.5 * (u + 1.0), 0.5 * (v + 1.0), d);
            double r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2], r = sqrt(r2);
            double c = (R[0] * d[0] + R[1] * d[1] + R[2] * d[2]) / r;
            if (c <= 0) continue;
            w += ibl__lobe_f(lobe, c) * hk * hk / (r2 * r);
        }
    return w;
}

/* Rows of one output level; count_only: only counts the entries. */
static size_t build_rows(ibl__dynamic *d, const ibl_specular_desc *desc, const ibl__lobe *lobe,
                         int level, int count_only, size_t entry)
{
    const dyn_level *lv = &d->lv[level];
    int n = lv->n, M = d->S >> lv->mip;
    size_t row = lv->row_begin, base = d->mip_offset[lv->mip];
    double texel = 2.0 / M, cull = lobe->cull_angle;
    /* the lobe below `floor` of its peak is dropped (the row is renormalised): a Phong lobe
     * falls like a Gaussian, GGX's tail (1 / angle^4) still holds ~1% of its weight below 1e-4 */
    double floor_value = lobe->kind == IBL__LOBE_GGX ? 1e-8 : 1e-4;
    double lo = 0.0, hi = 0.5 * IBL_PI;
    for (int i = 0; i < 60; i++) {
        double mid = 0.5 * (lo + hi);
        if (ibl__lobe_f(lobe, cos(mid)) > floor_value) lo = mid;
        else hi = mid;
    }
    if (hi < cull) cull = hi;
    int k = (int)ceil(3.0 * texel / (lobe->half_angle > 1e-9 ? lobe->half_angle : 1e-9));
    k = k < 1 ? 1 : k > 8 ? 8 : k;
    for (int f = 0; f < 6; f++)
        for (int y = 0; y < n; y++)
            for (int x = 0; x < n; x++, row++) {
                double R[3];
                ibl__output_direction(desc, lobe, f, n, x, y, R);
                if (!count_only) d->row_start[row] = (uint32_t)entry;
                size_t first = entry;
                double sum = 0.0;
                double reach = cos(cull + 0.75 * texel < IBL_PI ? cull + 0.75 * texel : IBL_PI);
                const float *cen = d->centre + base * 3;
                int nb = (M + DB - 1) / DB;
                const float *cone = d->cone + d->cone_offset[lv->mip] * 4;
                for (int sf = 0; sf < 6; sf++)
                    for (int by = 0; by < nb; by++)
                        for (int bx = 0; bx < nb; bx++) {
                            /* skip blocks of DB x DB texels beyond the reach */
                            const float *bc = cone + (((size_t)sf * nb + by) * nb + bx) * 4;
                            double ca = R[0] * bc[0] + R[1] * bc[1] + R[2] * bc[2];
                            double ang = acos(ca > 1 ? 1 : ca < -1 ? -1 : ca);
                            if (ang - bc[3] > cull + 0.75 * texel) continue;
                            int y1 = (by + 1) * DB < M ? (by + 1) * DB : M;
                            int x1 = (bx + 1) * DB < M ? (bx + 1) * DB : M;
                            for (int sy = by * DB; sy < y1; sy++)
                                for (int sx = bx * DB; sx < x1; sx++) {
                                    const float *c = cen + (((size_t)sf * M + sy) * M + sx) * 3;
                                    if (R[0] * c[0] + R[1] * c[1] + R[2] * c[2] < reach) continue;
                                    double w = texel_integral(lobe, R, sf, M, sx, sy, k);
                                    if (!(w > 0)) continue;
                                    if (!count_only) {
                                        d->index[entry] =
                                            (uint32_t)(base + ((size_t)sf * M + sy) * M + sx);
                                        d->weight[entry] = (float)w;
                                    }
                                    sum += w;
                                    entry++;
                                }
                        }
                if (!count_only && sum > 0)
                    for (size_t e = first; e < entry; e++)
                        d->weight[e] = (float)(d->weight[e] / sum);
            }
    return entry;
}

ibl_status ibl__dynamic_create(ibl_context *ctx, const ibl_specular_desc *desc,
                               const ibl_specular_info *info, int source_size, ibl__dynamic **out)
{
    *out = NULL;
    ibl__dynamic *d = ibl_calloc(ctx, 1, sizeof *d);
    if (!d) return ibl_context_status(ctx);
    d->ctx = ctx;
    d->S = source_size;
    d->L = info->levels;
    d->mips = ibl_full_mip_count(source_size);
    size_t texels = 0;
    for (int m = 0; m < d->mips; m++) {
        int M = source_size >> m;
        d->mip_offset[m] = texels;
        texels += (size_t)6 * M * M;
        d->omega[m] = ibl_alloc(ctx, (size_t)M * M * sizeof(float));
        if (!d->omega[m]) goto oom;
        for (int y = 0; y < M; y++)
            for (int x = 0; x < M; x++)
                d->omega[m][(size_t)y * M + x] = (float)ibl_cube_texel_solid_angle(M, x, y);
    }
    d->mip_offset[d->mips] = texels;
    d->mipdata = ibl_alloc(ctx, texels * 3 * sizeof(float));
    d->centre = ibl_alloc(ctx, texels * 3 * sizeof(float));
    size_t cones = 0;
    for (int m = 0; m < d->mips; m++) {
        int nb = ((source_size >> m) + DB - 1) / DB;
        d->cone_offset[m] = cones;
        cones += (size_t)6 * nb * nb;
    }
    d->cone = ibl_alloc(ctx, cones * 4 * sizeof(float));
    if (!d->mipdata || !d->centre || !d->cone) goto oom;
    for (int m = 0; m < d->mips; m++) {
        int M = source_size >> m, nb = (M + DB - 1) / DB;
        double h = 2.0 / M;
        for (int f = 0; f < 6; f++)
            for (int by = 0; by < nb; by++)
                for (int bx = 0; bx < nb; bx++) {
                    int x1 = (bx + 1) * DB < M ? (bx + 1) * DB : M;
                    int y1 = (by + 1) * DB < M ? (by + 1) * DB : M;
                    double c[3];
                    double r = ibl__rect_radius(f, bx * DB * h - 1, by * DB * h - 1, x1 * h - 1,
                                                y1 * h - 1, c);
                    float *o = d->cone + (d->cone_offset[m] + ((size_t)f * nb + by) * nb + bx) * 4;
                    for (int i = 0; i < 3; i++) o[i] = (float)c[i];
                    o[3] = (float)(r + 1e-6);
                }
    }
    for (int m = 0; m < d->mips; m++) {
        int M = source_size >> m;
        for (int f = 0; f < 6; f++)
            for (int y = 0; y < M; y++)
                for (int x = 0; x < M; x++) {
                    double c[3];
                    ibl_cube_direction_d(f, (x + 0.5) / M, (y + 0.5) / M, c);
                    double len = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
                    float *o = d->centre + (d->mip_offset[m] + ((size_t)f * M + y) * M + x) * 3;
                    for (int i = 0; i < 3; i++) o[i] = (float)(c[i] / len);
                }
    }
    ibl__lobe lobes[IBL_MAX_LEVELS];
    for (int l = 0; l < d->L; l++) {
        lobes[l] = ibl__lobe_for_level(info, l);
        dyn_level *lv = &d->lv[l];
        lv->n = ibl_level_size(info->size, l);
        lv->row_begin = d->rows;
        d->rows += (size_t)6 * lv->n * lv->n;
        if (lobes[l].kind == IBL__LOBE_MIRROR) {
            lv->mip = 0;
            continue;
        }
        /* the coarsest mip with texels at most 0.8 of the lobe's half width (scaled by
         * desc.accuracy as in the static method) and at least 16 wide (wide lobes are cheap;
         * coarse texels at their horizon kink are not exact) */
        double ratio = 0.8 * (desc->accuracy > 0 ? desc->accuracy / 0.35 : 1.0);
        lv->mip = 0;
        for (int m = 0; m < d->mips; m++)
            if (2.0 / (source_size >> m) <= ratio * lobes[l].half_angle && (source_size >> m) >= 16)
                lv->mip = m;
    }
    size_t entries = 0;
    for (int l = 0; l < d->L; l++) {
        if (lobes[l].kind == IBL__LOBE_MIRROR) {
            entries += (size_t)6 * d->lv[l].n * d->lv[l].n * 4;
            continue;
        }
        entries = build_rows(d, desc, &lobes[l], l, 1, entries);
        if (entries > MAX_ENTRIES) {
            ibl__dynamic_destroy(d);
            return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                            "specular plan: a dynamic plan of %d -> %d needs over %d weights; "
                            "use the static plan for sizes this large",
                            source_size, info->size, (int)MAX_ENTRIES);
        }
    }
    d->row_start = ibl_alloc(ctx, (d->rows + 1) * sizeof(uint32_t));
    d->index = ibl_alloc(ctx, (entries ? entries : 1) * sizeof(uint32_t));
    d->weight = ibl_alloc(ctx, (entries ? entries : 1) * sizeof(float));
    if (!d->row_start || !d->index || !d->weight) goto oom;
    size_t e = 0;
    for (int l = 0; l < d->L; l++) {
        dyn_level *lv = &d->lv[l];
        if (lobes[l].kind != IBL__LOBE_MIRROR) {
            e = build_rows(d, desc, &lobes[l], l, 0, e);
            continue;
        }
        /* mirror: the area mean of the source texels under the texel (or bilinear when the
         * level is finer than the source) */
        int n = lv->n;
        for (int f = 0; f < 6; f++)
            for (int y = 0; y < n; y++)
                for (int x = 0; x < n; x++) {
                    size_t row = lv->row_begin + ((size_t)f * n + y) * n + x;
                    d->row_start[row] = (uint32_t)e;
                    int m = 0;
                    while ((source_size >> m) > n && m + 1 < d->mips) m++;
                    int M = source_size >> m;
                    if (M == n) {
                        d->index[e] = (uint32_t)(d->mip_offset[m] + ((size_t)f * M + y) * M + x);
                        d->weight[e++] = 1.0f;
                        continue;
                    }
                    /* finer than the source: bilinear within the face (clamped at its edge) */
                    double s = (x + 0.5) / n * M - 0.5, t = (y + 0.5) / n * M - 0.5;
                    s = s < 0 ? 0 : s > M - 1 ? M - 1 : s;
                    t = t < 0 ? 0 : t > M - 1 ? M - 1 : t;
                    int x0 = (int)s, y0 = (int)t;
                    int x1 = x0 + 1 < M ? x0 + 1 : x0, y1 = y0 + 1 < M ? y0 + 1 : y0;
                    double fx = s - x0, fy = t - y0;
                    int xs[4] = {x0, x1, x0, x1}, ys[4] = {y0, y0, y1, y1};
                    double ws[4] = {(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy};
                    for (int q = 0; q < 4; q++) {
                        d->index[e] = (uint32_t)(d->mip_offset[0] + ((size_t)f * M + ys[q]) * M + xs[q]);
                        d->weight[e++] = (float)ws[q];
                    }
                }
    }
    d->row_start[d->rows] = (uint32_t)e;
    *out = d;
    return IBL_OK;
oom:
    ibl__dynamic_destroy(d);
    return ibl_context_status(ctx);
}

typedef struct dyn_job {
    ibl__dynamic *d;
    const ibl_cubemap *src;
    ibl_cubemap *dst;
    int level;
} dyn_job;

static void mip_task(void *arg, int index)
{
    const dyn_job *job = arg;
    ibl__dynamic *d = job->d;
    int m = job->level, M = d->S >> m, f = index / M, y = index % M;
    float *o = d->mipdata + (d->mip_offset[m] + ((size_t)f * M + y) * M) * 3;
    if (m == 0) {
        const float *row = ibl_cubemap_face(job->src, 0, f) + (size_t)y * M * 4;
        for (int x = 0; x < M; x++)
            for (int c = 0; c < 3; c++) o[x * 3 + c] = row[x * 4 + c];
        return;
    }
    int C = 2 * M;
    const float *om = d->omega[m - 1];
    const float *ch = d->mipdata + d->mip_offset[m - 1] * 3 + (size_t)f * C * C * 3;
    for (int x = 0; x < M; x++) {
        float acc[3] = {0, 0, 0}, w = 0;
        for (int k = 0; k < 4; k++) {
            size_t i = (size_t)(2 * y + (k >> 1)) * C + 2 * x + (k & 1);
            for (int c = 0; c < 3; c++) acc[c] += om[i] * ch[i * 3 + c];
            w += om[i];
        }
        for (int c = 0; c < 3; c++) o[x * 3 + c] = acc[c] / w;
    }
}

static void row_task(void *arg, int index)
{
    const dyn_job *job = arg;
    const ibl__dynamic *d = job->d;
    const dyn_level *lv = &d->lv[job->level];
    int n = lv->n, f = index / n, y = index % n;
    float *out = ibl_cubemap_face(job->dst, job->level, f) + (size_t)y * n * 4;
    size_t row = lv->row_begin + ((size_t)f * n + y) * n;
    for (int x = 0; x < n; x++, row++) {
        float r = 0, g = 0, b = 0;
        for (uint32_t e = d->row_start[row]; e < d->row_start[row + 1]; e++) {
            const float *p = d->mipdata + (size_t)d->index[e] * 3;
            float w = d->weight[e];
            r += w * p[0], g += w * p[1], b += w * p[2];
        }
        out[x * 4 + 0] = r, out[x * 4 + 1] = g, out[x * 4 + 2] = b, out[x * 4 + 3] = 1.0f;
    }
}

void ibl__dynamic_mips(ibl__dynamic *d, const ibl_cubemap *src)
{
    for (int m = 0; m < d->mips; m++) {
        dyn_job job = {d, src, NULL, m};
        ibl_parallel_for(d->ctx, 6 * (d->S >> m), mip_task, &job);
    }
}

void ibl__dynamic_level(ibl__dynamic *d, ibl_cubemap *dst, int level)
{
    dyn_job job = {d, NULL, dst, level};
    ibl_parallel_for(d->ctx, 6 * d->lv[level].n, row_task, &job);
}
