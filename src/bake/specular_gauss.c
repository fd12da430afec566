/* tri-Ace's second dynamic profile: a 2D Gaussian blur of each face (tri-Ace 2010
 * "Generate PMREM (2)"). Not physically based on purpose: it works in texel space, ignores
 * the texels' solid angles, and never filters across a face edge (the talk's point: edges
 * band; pair it with an edge fixup). Each level starts from the area-correct box chain.
 *
 * Sigma (docs/EDGE_FIXUP.md, "Gaussian sigma"): a normalised Phong lobe cos^s(theta) has
 * E[sin^2 theta] = 2/(s+3), i.e. a per-axis angular deviation 1/sqrt(s+3) on the tangent
 * plane; a texel of a face of edge n spans 2/n radians at the face centre; the level's
 * texels are already area means (a box of variance 1/12 texel^2), so the blur adds
 * sigma^2 = (n/2)^2 / (s+3) - 1/12 texels^2 (0 if negative). */
#include "bake/specular_kernels.h"
#include "core/context_internal.h"

#include <math.h>
#include <string.h>

double ibl__gauss_sigma(float shininess, int n)
{
    if (!(shininess >= 0) || n < 1) return 0.0;
    if (isinf(shininess)) return 0.0;
    double half = 0.5 * n;
    double var = half * half / ((double)shininess + 3.0) - 1.0 / 12.0;
    return var > 0 ? sqrt(var) : 0.0;
}

enum { MAX_RADIUS = 1 << 14 };

typedef struct blur_job {
    ibl_cubemap *cube;
    int level, n, radius;
    const double *kernel; /* kernel[0..radius], symmetric */
    float *scratch;       /* one level: 6 faces of n*n RGBA */
} blur_job;

/* One row (pass 0: horizontal, dst = scratch) or one column (pass 1: vertical, src =
 * scratch, dst = level). The kernel is cut at the face border and renormalised: nothing is
 * read across an edge, and a constant stays constant. */
static void blur_line(const blur_job *job, int index, int pass)
{
    int n = job->n, r = job->radius;
    int face = index / n, line = index % n;
    const float *src = pass == 0 ? ibl_cubemap_face(job->cube, job->level, face)
                                 : job->scratch + (size_t)face * n * n * 4;
    float *dst = pass == 0 ? job->scratch + (size_t)face * n * n * 4
                           : ibl_cubemap_face(job->cube, job->level, face);
    size_t stride = pass == 0 ? 4 : (size_t)n * 4;
    size_t start = pass == 0 ? (size_t)line * n * 4 : (size_t)line * 4;
    for (int i = 0; i < n; i++) {
        int a = i - r < 0 ? 0 : i - r, b = i + r > n - 1 ? n - 1 : i + r;
        double acc[4] = {0, 0, 0, 0}, wsum = 0;
        for (int k = a; k <= b; k++) {
            double w = job->kernel[k > i ? k - i : i - k];
            const float *p = src + start + (size_t)k * stride;
            for (int c = 0; c < 4; c++) acc[c] += w * p[c];
            wsum += w;
        }
        float *o = dst + start + (size_t)i * stride;
        for (int c = 0; c < 4; c++) o[c] = (float)(acc[c] / wsum);
    }
}

static void rows_task(void *arg, int index) { blur_line(arg, index, 0); }
static void columns_task(void *arg, int index) { blur_line(arg, index, 1); }

ibl_status ibl__specular_gauss(ibl_context *ctx, const ibl_cubemap *src, ibl_cubemap *dst,
                               const float *phong_exponent_per_level)
{
    if (!phong_exponent_per_level)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "gauss prefilter: no shininess per level");
    for (int l = 0; dst && l < dst->levels; l++)
        if (!(phong_exponent_per_level[l] >= 0))
            return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                            "gauss prefilter: shininess of level %d is %g", l,
                            (double)phong_exponent_per_level[l]);
    ibl_status st = ibl__specular_box(ctx, src, dst);
    if (st != IBL_OK) return st;
    size_t n0 = (size_t)dst->size;
    float *scratch = ibl_alloc(ctx, 6 * n0 * n0 * 4 * sizeof(float));
    double *kernel = NULL;
    if (!scratch) return ibl_context_status(ctx);
    for (int level = 0; level < dst->levels; level++) {
        int n = ibl_level_size(dst->size, level);
        double sigma = ibl__gauss_sigma(phong_exponent_per_level[level], n);
        if (sigma < 1e-3 || n < 2) continue;
        /* 4 sigma keeps the cut tail below 1e-4 of the weight; beyond n - 1 nothing is read */
        double reach = ceil(4.0 * sigma);
        int radius = reach > n - 1 ? n - 1 : (int)reach;
        if (radius > MAX_RADIUS) radius = MAX_RADIUS;
        ibl_free(ctx, kernel);
        kernel = ibl_alloc(ctx, (size_t)(radius + 1) * sizeof(double));
        if (!kernel) {
            st = ibl_context_status(ctx);
            break;
        }
        for (int k = 0; k <= radius; k++) kernel[k] = exp(-0.5 * k * k / (sigma * sigma));
        blur_job job = {dst, level, n, radius, kernel, scratch};
        ibl_parallel_for(ctx, 6 * n, rows_task, &job);
        ibl_parallel_for(ctx, 6 * n, columns_task, &job);
        st = ibl__progress(ctx, "gauss prefilter", (double)(level + 1) / dst->levels);
        if (st != IBL_OK) break;
    }
    ibl_free(ctx, kernel);
    ibl_free(ctx, scratch);
    return st;
}
