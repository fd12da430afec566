/* tri-Ace 2010's two fastest dynamic profiles as a plan: the box chain ("Generate PMREM (1)":
 * the area-weighted mip chain) and the per-face Gaussian blur of each of its levels
 * ("Generate PMREM (2)"). The same chain is the source's mip pyramid of the lobe operator.
 *
 * The general code (specular_box.c, specular_gauss.c, and cubemap.c's block mean and mip
 * chain) computes its weights and normalisers as it goes and allocates its scratch; here they
 * are computed once, by the same expressions, and the run repeats the same operations in the
 * same order: every output value is (float)(sum_k w_k p_k / sum_k w_k) in double, with the taps
 * in the general code's order. So the plan's output is bit for bit the general code's (the
 * tests compare them), and a run allocates nothing. */
#include "bake/specular_dynamic/dynamic_internal.h"
#include "bake/specular_kernels.h"
#include "core/context_internal.h"

#include <math.h>
#include <string.h>

enum { MAX_BLUR_RADIUS = 1 << 14 }; /* specular_gauss.c's cap */

void ibl__dyn_box_chain_destroy(ibl_context *ctx, dyn_box_chain *c)
{
    if (!c) return;
    ibl_free(ctx, c->block_weights);
    ibl_free(ctx, c->block_sums);
    for (int l = 0; l < IBL_MAX_LEVELS; l++) {
        ibl_free(ctx, c->mip_weights[l]);
        ibl_free(ctx, c->mip_sums[l]);
        ibl_free(ctx, c->kernel[l]);
        ibl_free(ctx, c->line_sums[l]);
    }
    ibl_cubemap_free(ctx, &c->chain);
    ibl_free(ctx, c->blur_scratch);
    memset(c, 0, sizeof *c);
}

/* cubemap.c's block mean: the solid angle of source texel (i, j) as the difference of the
 * corner function atan(uv / sqrt(1 + u^2 + v^2)) on the source grid, the same expression */
static double grid_corner(int m, int i, int j)
{
    double v = 2.0 * (double)j / m - 1.0, u = 2.0 * (double)i / m - 1.0;
    return atan2(u * v, sqrt(u * u + v * v + 1.0));
}

static ibl_status block_tables(ibl_context *ctx, dyn_box_chain *c)
{
    int m = c->source_edge, n = c->edge, r = c->ratio;
    c->block_weights = ibl_alloc(ctx, (size_t)m * m * sizeof(double));
    c->block_sums = ibl_alloc(ctx, (size_t)n * n * sizeof(double));
    double *corner = ibl_alloc(ctx, (size_t)(m + 1) * (m + 1) * sizeof(double));
    if (!c->block_weights || !c->block_sums || !corner) {
        ibl_free(ctx, corner);
        return ibl_context_status(ctx);
    }
    size_t stride = (size_t)m + 1;
    for (int j = 0; j <= m; j++)
        for (int i = 0; i <= m; i++) corner[j * stride + i] = grid_corner(m, i, j);
    for (int j = 0; j < m; j++)
        for (int i = 0; i < m; i++)
            c->block_weights[(size_t)j * m + i] = corner[(j + 1) * stride + i + 1] - corner[(j + 1) * stride + i] -
                                                  corner[j * stride + i + 1] + corner[j * stride + i];
    ibl_free(ctx, corner);
    for (int y = 0; y < n; y++)
        for (int x = 0; x < n; x++) {
            double wsum = 0;
            for (int j = y * r; j < (y + 1) * r; j++)
                for (int i = x * r; i < (x + 1) * r; i++) wsum += c->block_weights[(size_t)j * m + i];
            c->block_sums[(size_t)y * n + x] = wsum;
        }
    return IBL_OK;
}

/* cubemap.c's mip chain: children weighted by ibl_cube_texel_solid_angle, (dy, dx) order */
static ibl_status mip_tables(ibl_context *ctx, dyn_box_chain *c, int level)
{
    int n = ibl_level_size(c->edge, level), cn = ibl_level_size(c->edge, level - 1);
    double *w = c->mip_weights[level] = ibl_alloc(ctx, (size_t)cn * cn * sizeof(double));
    double *s = c->mip_sums[level] = ibl_alloc(ctx, (size_t)n * n * sizeof(double));
    if (!w || !s) return ibl_context_status(ctx);
    for (int y = 0; y < cn; y++)
        for (int x = 0; x < cn; x++) w[(size_t)y * cn + x] = ibl_cube_texel_solid_angle(cn, x, y);
    for (int y = 0; y < n; y++)
        for (int x = 0; x < n; x++) {
            double wsum = 0;
            for (int dy = 0; dy < 2; dy++)
                for (int dx = 0; dx < 2; dx++) {
                    int cx = 2 * x + dx, cy = 2 * y + dy;
                    if (cx < cn && cy < cn) wsum += w[(size_t)cy * cn + cx];
                }
            s[(size_t)y * n + x] = wsum;
        }
    return IBL_OK;
}

/* specular_gauss.c's kernel of a level: radius and weights from ibl__gauss_sigma, cut at the
 * face border and renormalised there (the sums per position along a line) */
static ibl_status blur_tables(ibl_context *ctx, dyn_box_chain *c, int level, float phong_exponent)
{
    int n = ibl_level_size(c->edge, level);
    double sigma = ibl__gauss_sigma(phong_exponent, n);
    if (sigma < 1e-3 || n < 2) return IBL_OK;
    double reach = ceil(4.0 * sigma);
    int radius = reach > n - 1 ? n - 1 : (int)reach;
    if (radius > MAX_BLUR_RADIUS) radius = MAX_BLUR_RADIUS;
    double *k = c->kernel[level] = ibl_alloc(ctx, (size_t)(radius + 1) * sizeof(double));
    double *s = c->line_sums[level] = ibl_alloc(ctx, (size_t)n * sizeof(double));
    if (!k || !s) return ibl_context_status(ctx);
    for (int i = 0; i <= radius; i++) k[i] = exp(-0.5 * i * i / (sigma * sigma));
    for (int i = 0; i < n; i++) {
        int a = i - radius < 0 ? 0 : i - radius, b = i + radius > n - 1 ? n - 1 : i + radius;
        double wsum = 0;
        for (int j = a; j <= b; j++) wsum += k[j > i ? j - i : i - j];
        s[i] = wsum;
    }
    c->radius[level] = radius;
    return IBL_OK;
}

ibl_status ibl__dyn_box_chain_create(ibl_context *ctx, int source_edge, int edge, int levels,
                                     const float *blur_phong_exponents, dyn_box_chain *c)
{
    memset(c, 0, sizeof *c);
    c->source_edge = source_edge;
    c->edge = edge;
    c->levels = levels;
    c->ratio = source_edge / edge;
    ibl_status st = ibl_cubemap_alloc(ctx, edge, levels, &c->chain);
    if (st == IBL_OK && c->ratio > 1) st = block_tables(ctx, c);
    for (int l = 1; st == IBL_OK && l < levels; l++) st = mip_tables(ctx, c, l);
    for (int l = 0; st == IBL_OK && blur_phong_exponents && l < levels; l++)
        st = blur_tables(ctx, c, l, blur_phong_exponents[l]);
    if (st == IBL_OK && blur_phong_exponents &&
        !(c->blur_scratch = ibl_alloc(ctx, (size_t)6 * edge * edge * 4 * sizeof(float))))
        st = ibl_context_status(ctx);
    if (st != IBL_OK) ibl__dyn_box_chain_destroy(ctx, c);
    return st;
}

/* level 0 of the chain (or the source itself when no block mean is needed) */
static const float *chain_face(const dyn_box_chain *c, const ibl_cubemap *src, int level, int face)
{
    if (level == 0 && c->ratio == 1) return ibl_cubemap_face(src, 0, face);
    return ibl_cubemap_face(&c->chain, level, face);
}

typedef struct chain_job {
    dyn_box_chain *c;
    const ibl_cubemap *src;
    ibl_cubemap *dst;
    int level;
} chain_job;

/* one row of level 0: cubemap.c's block_row_task */
static void block_row_task(void *arg, int index)
{
    const chain_job *job = arg;
    const dyn_box_chain *c = job->c;
    int n = c->edge, m = c->source_edge, r = c->ratio, face = index / n, y = index % n;
    const float *src = ibl_cubemap_face(job->src, 0, face);
    float *row = ibl_cubemap_face(&c->chain, 0, face) + (size_t)y * n * 4;
    for (int x = 0; x < n; x++) {
        double acc[4] = {0, 0, 0, 0};
        for (int j = y * r; j < (y + 1) * r; j++) {
            const double *w = c->block_weights + (size_t)j * m;
            const float *p = src + (size_t)j * m * 4;
            for (int i = x * r; i < (x + 1) * r; i++)
                for (int k = 0; k < 4; k++) acc[k] += w[i] * p[(size_t)i * 4 + k];
        }
        double wsum = c->block_sums[(size_t)y * n + x];
        for (int k = 0; k < 4; k++) row[(size_t)x * 4 + k] = (float)(acc[k] / wsum);
    }
}

/* one row of a mip level: cubemap.c's mip_face_task */
static void mip_row_task(void *arg, int index)
{
    const chain_job *job = arg;
    const dyn_box_chain *c = job->c;
    int l = job->level, n = ibl_level_size(c->edge, l), cn = ibl_level_size(c->edge, l - 1);
    int face = index / n, y = index % n;
    const float *src = chain_face(c, job->src, l - 1, face);
    float *row = ibl_cubemap_face(&c->chain, l, face) + (size_t)y * n * 4;
    const double *w = c->mip_weights[l];
    for (int x = 0; x < n; x++) {
        double acc[4] = {0, 0, 0, 0};
        for (int dy = 0; dy < 2; dy++)
            for (int dx = 0; dx < 2; dx++) {
                int cx = 2 * x + dx, cy = 2 * y + dy;
                if (cx >= cn || cy >= cn) continue;
                double wk = w[(size_t)cy * cn + cx];
                const float *p = src + ((size_t)cy * cn + cx) * 4;
                for (int k = 0; k < 4; k++) acc[k] += wk * p[k];
            }
        double wsum = c->mip_sums[l][(size_t)y * n + x];
        for (int k = 0; k < 4; k++) row[(size_t)x * 4 + k] = (float)(acc[k] / wsum);
    }
}

void ibl__dyn_box_chain_build(dyn_box_chain *c, ibl_context *ctx, const ibl_cubemap *src, int levels)
{
    chain_job job = {c, src, NULL, 0};
    if (c->ratio > 1) ibl_parallel_for(ctx, 6 * c->edge, block_row_task, &job);
    for (int l = 1; l < levels && l < c->levels; l++) {
        job.level = l;
        ibl_parallel_for(ctx, 6 * ibl_level_size(c->edge, l), mip_row_task, &job);
    }
}

const float *ibl__dyn_box_chain_face(const dyn_box_chain *c, const ibl_cubemap *src, int level,
                                     int face)
{
    return chain_face(c, src, level, face);
}

/* specular_gauss.c's blur_line: pass 0 a row of the chain into the scratch, pass 1 a column of
 * the scratch into the output level */
static void blur_line(const chain_job *job, int index, int pass)
{
    const dyn_box_chain *c = job->c;
    int l = job->level, n = ibl_level_size(c->edge, l), r = c->radius[l];
    int face = index / n, line = index % n;
    const float *src = pass == 0 ? chain_face(c, job->src, l, face) : c->blur_scratch + (size_t)face * n * n * 4;
    float *dst = pass == 0 ? c->blur_scratch + (size_t)face * n * n * 4 : ibl_cubemap_face(job->dst, l, face);
    size_t stride = pass == 0 ? 4 : (size_t)n * 4;
    size_t start = pass == 0 ? (size_t)line * n * 4 : (size_t)line * 4;
    const double *kernel = c->kernel[l];
    for (int i = 0; i < n; i++) {
        int a = i - r < 0 ? 0 : i - r, b = i + r > n - 1 ? n - 1 : i + r;
        double acc[4] = {0, 0, 0, 0};
        for (int k = a; k <= b; k++) {
            double w = kernel[k > i ? k - i : i - k];
            const float *p = src + start + (size_t)k * stride;
            for (int ch = 0; ch < 4; ch++) acc[ch] += w * p[ch];
        }
        float *o = dst + start + (size_t)i * stride;
        double wsum = c->line_sums[l][i];
        for (int ch = 0; ch < 4; ch++) o[ch] = (float)(acc[ch] / wsum);
    }
}

static void blur_rows_task(void *arg, int index) { blur_line(arg, index, 0); }
static void blur_columns_task(void *arg, int index) { blur_line(arg, index, 1); }

void ibl__dyn_box_chain_output(dyn_box_chain *c, ibl_context *ctx, const ibl_cubemap *src,
                               ibl_cubemap *dst, int level)
{
    int n = ibl_level_size(c->edge, level);
    if (c->radius[level] == 0) {
        memcpy(ibl_cubemap_face(dst, level, 0), chain_face(c, src, level, 0),
               (size_t)6 * n * n * 4 * sizeof(float));
        return;
    }
    chain_job job = {c, src, dst, level};
    ibl_parallel_for(ctx, 6 * n, blur_rows_task, &job);
    ibl_parallel_for(ctx, 6 * n, blur_columns_task, &job);
}
