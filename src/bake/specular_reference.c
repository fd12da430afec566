/* The reference prefilter: for every output direction, the exact integral of the
 * piecewise-constant source against the lobe, sum_t L_t int_t f(R.l) dl / sum_t int_t f(R.l) dl,
 * over every source texel t, in double. int_t f is the exact texel solid angle times f at the
 * centre when f is smooth over the texel, and otherwise a k x k split of the texel into
 * sub-rectangles with exact solid angles (ibl_cube_rect_solid_angle), k chosen from the lobe's
 * variation (log slope) so that f changes by at most ~20% across a piece (midpoint error
 * <= ~0.2% of that piece, far less summed over the lobe). Blocks of
 * 8x8 texels whose nearest point is beyond the lobe's 1e-12 cut-off are skipped (their weight
 * is below 1e-12 of the peak). Slow by design: it is the yardstick. */
#include "specular_internal.h"
#include "core/context_internal.h"
#include "core/numeric.h"

#include <math.h>
#include <string.h>

enum { BLOCK = 8 };

static double angle_between(const double a[3], const double b[3])
{
    double c = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    if (c > 1.0) c = 1.0;
    if (c < -1.0) c = -1.0;
    return acos(c);
}

ibl_status ibl_specular_reference_create(ibl_context *ctx, const ibl_cubemap *src,
                                         ibl_specular_reference **out)
{
    if (!ctx || !src || !src->data || !out) return IBL_ERR_INVALID_ARGUMENT;
    *out = NULL;
    int n = src->size, nb = (n + BLOCK - 1) / BLOCK;
    ibl_specular_reference *r = ibl_calloc(ctx, 1, sizeof *r);
    if (!r) return ibl_context_status(ctx);
    r->ctx = ctx;
    r->src = src;
    r->n = n;
    r->blocks = nb;
    r->dir = ibl_alloc(ctx, (size_t)6 * n * n * 3 * sizeof(double));
    r->omega = ibl_alloc(ctx, (size_t)n * n * sizeof(double));
    r->radius = ibl_alloc(ctx, (size_t)n * n * sizeof(double));
    r->block = ibl_alloc(ctx, (size_t)6 * nb * nb * 4 * sizeof(double));
    r->max_radius = 0.0;
    if (!r->dir || !r->omega || !r->radius || !r->block) {
        ibl_specular_reference_destroy(r);
        return ibl_context_status(ctx);
    }
    double h = 2.0 / n;
    for (int y = 0; y < n; y++) {
        for (int x = 0; x < n; x++) {
            double c[3];
            r->omega[(size_t)y * n + x] = ibl_cube_texel_solid_angle(n, x, y);
            r->radius[(size_t)y * n + x] =
                ibl__rect_radius(0, x * h - 1, y * h - 1, (x + 1) * h - 1, (y + 1) * h - 1, c);
            if (r->radius[(size_t)y * n + x] > r->max_radius) r->max_radius = r->radius[(size_t)y * n + x];
        }
    }
    for (int f = 0; f < 6; f++) {
        for (int y = 0; y < n; y++) {
            for (int x = 0; x < n; x++) {
                ibl_vec3 d = ibl_cube_texel_direction(f, n, x, y);
                double dd[3];
                ibl_cube_direction_d(f, (x + 0.5) / n, (y + 0.5) / n, dd);
                double len = sqrt(dd[0] * dd[0] + dd[1] * dd[1] + dd[2] * dd[2]);
                double *o = r->dir + (((size_t)f * n + y) * n + x) * 3;
                (void)d;
                for (int i = 0; i < 3; i++) o[i] = dd[i] / len;
            }
        }
        for (int by = 0; by < nb; by++) {
            for (int bx = 0; bx < nb; bx++) {
                int x1 = (bx + 1) * BLOCK < n ? (bx + 1) * BLOCK : n;
                int y1 = (by + 1) * BLOCK < n ? (by + 1) * BLOCK : n;
                double *b = r->block + (((size_t)f * nb + by) * nb + bx) * 4;
                b[3] = ibl__rect_radius(f, bx * BLOCK * h - 1, by * BLOCK * h - 1, x1 * h - 1,
                                        y1 * h - 1, b);
            }
        }
    }
    *out = r;
    return IBL_OK;
}

void ibl_specular_reference_destroy(ibl_specular_reference *r)
{
    if (!r) return;
    ibl_free(r->ctx, r->dir);
    ibl_free(r->ctx, r->omega);
    ibl_free(r->ctx, r->radius);
    ibl_free(r->ctx, r->block);
    ibl_free(r->ctx, r);
}

/* int over texel (x, y) of face f of the lobe around R, split k x k. */
static double texel_weight_split(const ibl__lobe *lobe, const double R[3], int f, int n, int x,
                                 int y, int k)
{
    double w = 0.0, h = 2.0 / n, hk = h / k;
    for (int j = 0; j < k; j++) {
        for (int i = 0; i < k; i++) {
            double u0 = x * h - 1 + i * hk, v0 = y * h - 1 + j * hk;
            double d[3];
            ibl_cube_direction_d(f, 0.5 * (u0 + 0.5 * hk + 1.0), 0.5 * (v0 + 0.5 * hk + 1.0), d);
            double len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            double c = (R[0] * d[0] + R[1] * d[1] + R[2] * d[2]) / len;
            if (c <= 0) continue;
            w += ibl__lobe_f(lobe, c) * ibl_cube_rect_solid_angle(u0, v0, u0 + hk, v0 + hk);
        }
    }
    return w;
}

void ibl__reference_eval_lobe(const ibl_specular_reference *r, const ibl__lobe *lobe,
                              const double R[3], double out[4])
{
    int n = r->n, nb = r->blocks;
    const ibl_cubemap *src = r->src;
    if (lobe->kind == IBL__LOBE_MIRROR) {
        double s, t;
        int f = ibl_cube_face_st_d(R, &s, &t);
        int x = (int)floor(s * n), y = (int)floor(t * n);
        x = x < 0 ? 0 : x >= n ? n - 1 : x;
        y = y < 0 ? 0 : y >= n ? n - 1 : y;
        const float *p = ibl_cubemap_face(src, 0, f) + ((size_t)y * n + x) * 4;
        for (int i = 0; i < 4; i++) out[i] = p[i];
        return;
    }
    double acc[4] = {0, 0, 0, 0}, wsum = 0.0;
    /* a lobe that varies slowly enough everywhere never splits a texel away from the horizon:
     * those texels take the centre value without the angle and slope work (same result) */
    double gmax = ibl__lobe_max_log_slope(lobe, 0.0, IBL_HALF_PI - 0.05);
    int smooth = ceil(2.0 * r->max_radius * gmax / 0.2) <= 1.0;
    double sin_max_radius = sin(r->max_radius);
    for (int f = 0; f < 6; f++) {
        const float *face = ibl_cubemap_face(src, 0, f);
        for (int by = 0; by < nb; by++) {
            for (int bx = 0; bx < nb; bx++) {
                const double *b = r->block + (((size_t)f * nb + by) * nb + bx) * 4;
                double tmin = angle_between(R, b) - b[3];
                if (tmin >= lobe->cull_angle || tmin >= IBL_HALF_PI) continue;
                double skip_angle = (lobe->cull_angle < IBL_HALF_PI ? lobe->cull_angle : IBL_HALF_PI) + b[3];
                double cos_skip = skip_angle >= 3.14159265358979 ? -2.0 : cos(skip_angle);
                int x1 = (bx + 1) * BLOCK < n ? (bx + 1) * BLOCK : n;
                int y1 = (by + 1) * BLOCK < n ? (by + 1) * BLOCK : n;
                for (int y = by * BLOCK; y < y1; y++) {
                    for (int x = bx * BLOCK; x < x1; x++) {
                        const double *d = r->dir + (((size_t)f * n + y) * n + x) * 3;
                        double gamma = r->radius[(size_t)y * n + x];
                        /* cheap rejection before the acos: beyond the cut-off plus the block's
                         * radius (which bounds every texel's radius in it) */
                        double cd = R[0] * d[0] + R[1] * d[1] + R[2] * d[2];
                        if (cd < cos_skip) continue;
                        if (smooth && cd > sin_max_radius) {
                            double w = ibl__lobe_f(lobe, cd) * r->omega[(size_t)y * n + x];
                            if (w == 0.0) continue;
                            const float *p = face + ((size_t)y * n + x) * 4;
                            for (int i = 0; i < 4; i++) acc[i] += w * p[i];
                            wsum += w;
                            continue;
                        }
                        double theta = angle_between(R, d);
                        double t0 = theta - gamma, t1 = theta + gamma;
                        if (t0 >= lobe->cull_angle || t0 >= IBL_HALF_PI) continue;
                        if (t0 < 0) t0 = 0;
                        double te = t1 < IBL_HALF_PI - 0.05 ? t1 : IBL_HALF_PI - 0.05;
                        double g = t0 < te ? ibl__lobe_max_log_slope(lobe, t0, te) : 0.0;
                        double kk = ceil(2.0 * gamma * g / 0.2);
                        if (t1 > IBL_HALF_PI && lobe->horizon > 1e-3) {
                            /* the lobe's kink at the horizon: pieces of at most 0.01 rad where the lobe is
                             * still above 1e-3 of its peak 0.1 rad above the horizon */
                            double kh = ceil(2.0 * gamma / 0.01);
                            if (kh > kk) kk = kh;
                        }
                        int k = kk < 1 ? 1 : kk > 32 ? 32 : (int)kk;
                        double w;
                        if (k == 1) {
                            double c = R[0] * d[0] + R[1] * d[1] + R[2] * d[2];
                            w = ibl__lobe_f(lobe, c) * r->omega[(size_t)y * n + x];
                        } else {
                            w = texel_weight_split(lobe, R, f, n, x, y, k);
                        }
                        if (w == 0.0) continue;
                        const float *p = face + ((size_t)y * n + x) * 4;
                        for (int i = 0; i < 4; i++) acc[i] += w * p[i];
                        wsum += w;
                    }
                }
            }
        }
    }
    for (int i = 0; i < 4; i++) out[i] = wsum > 0 ? acc[i] / wsum : 0.0;
}

void ibl_specular_reference_eval(const ibl_specular_reference *ref, const ibl_specular_info *info,
                                 int level, ibl_vec3 dir, double out[4])
{
    ibl__lobe lobe = ibl__lobe_for_level(info, level);
    double len = sqrt((double)dir.x * dir.x + (double)dir.y * dir.y + (double)dir.z * dir.z);
    double R[3] = {dir.x / len, dir.y / len, dir.z / len};
    ibl__reference_eval_lobe(ref, &lobe, R, out);
}

typedef struct ref_job {
    const ibl_specular_reference *ref;
    const ibl_specular_desc *desc;
    ibl__lobe lobe;
    ibl_cubemap *dst;
    int level, n;
} ref_job;

static void ref_row_task(void *arg, int index)
{
    const ref_job *job = arg;
    int n = job->n, face = index / n, y = index % n;
    float *row = ibl_cubemap_face(job->dst, job->level, face) + (size_t)y * n * 4;
    for (int x = 0; x < n; x++) {
        double R[3], v[4];
        ibl__output_direction(job->desc, &job->lobe, face, n, x, y, R);
        ibl__reference_eval_lobe(job->ref, &job->lobe, R, v);
        for (int i = 0; i < 4; i++) row[x * 4 + i] = (float)v[i];
    }
}

ibl_status ibl__specular_reference(ibl_context *ctx, const ibl_cubemap *src,
                                   const ibl_specular_desc *desc, const ibl_specular_info *info,
                                   ibl_cubemap *dst)
{
    ibl_specular_reference *ref = NULL;
    ibl_status st = ibl_specular_reference_create(ctx, src, &ref);
    if (st != IBL_OK) return st;
    for (int level = 0; level < dst->levels; level++) {
        ref_job job = {ref, desc, ibl__lobe_for_level(info, level), dst, level,
                       ibl_level_size(dst->size, level)};
        ibl_parallel_for(ctx, 6 * job.n, ref_row_task, &job);
        st = ibl__progress(ctx, "prefilter (reference)", (level + 1.0) / dst->levels);
        if (st != IBL_OK) break;
    }
    ibl_specular_reference_destroy(ref);
    return st;
}
