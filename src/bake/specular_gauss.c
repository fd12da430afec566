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
    float *image;       /* 6 faces of n*n RGBA, blurred in place */
    float *scratch;     /* 6 faces of n*n RGBA: the rows' result */
    int n, radius;
    const double *kernel; /* kernel[0..radius], symmetric */
} blur_job;

/* One row (pass 0: horizontal, image -> scratch) or one column (pass 1: vertical, scratch ->
 * image). The kernel is cut at the face border and renormalised: nothing is read across an
 * edge, and a constant stays constant. */
static void blur_line(const blur_job *job, int index, int pass)
{
    int n = job->n, r = job->radius;
    int face = index / n, line = index % n;
    const float *src = (pass == 0 ? job->image : job->scratch) + (size_t)face * n * n * 4;
    float *dst = (pass == 0 ? job->scratch : job->image) + (size_t)face * n * n * 4;
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

/* The separable blur of 6 faces of edge n in place, sigma texels, cut at 4 sigma (the cut tail
 * is below 1e-4 of the weight; beyond n - 1 nothing is read). */
static ibl_status blur_faces(ibl_context *ctx, float *image, float *scratch, int n, double sigma)
{
    double reach = ceil(4.0 * sigma);
    int radius = reach > n - 1 ? n - 1 : (int)reach;
    if (radius > MAX_RADIUS) radius = MAX_RADIUS;
    double *kernel = ibl_alloc(ctx, (size_t)(radius + 1) * sizeof(double));
    if (!kernel) return ibl_context_status(ctx);
    for (int k = 0; k <= radius; k++) kernel[k] = exp(-0.5 * k * k / (sigma * sigma));
    blur_job job = {image, scratch, n, radius, kernel};
    ibl_parallel_for(ctx, 6 * n, rows_task, &job);
    ibl_parallel_for(ctx, 6 * n, columns_task, &job);
    ibl_free(ctx, kernel);
    return IBL_OK;
}

/* ---- wide blurs through a Gaussian pyramid ----
 *
 * The exact chain blurs level l (edge n) with a Gaussian of sigma_n texels: n^2 texels times
 * 8 sigma_n taps, and sigma_n grows with n, so a level costs n^3. A wide blur is instead
 * computed through a Gaussian pyramid (Burt & Adelson, "The Laplacian Pyramid as a Compact
 * Image Code", 1983), one line at a time (every step is separable, so rows then columns):
 * j times, a blur of PYRAMID_PREFILTER_SIGMA texels then the mean of texel pairs; then the
 * Gaussian of sigma_c texels of the grid k = 2^j times coarser; then linear interpolation
 * back to the level's texel centres.
 *
 * The face border: the exact blur cuts the kernel at the border and renormalises it, i.e.
 * it is (G * (f 1_face)) / (G * 1_face) with both convolutions over zero-extended lines, and
 * the window is a rectangle, so in 2D each axis divides by its own sum. So the pyramid runs
 * over the zero-extended line (the numerator) and the result is divided by the same operator
 * applied to the face's indicator (the denominator, once per level): a constant stays
 * constant and nothing crosses a face edge.
 *
 * Variances add. In level-l texels: each halving at step t costs 4^t (s_p^2 + 1/4) (the
 * prefilter and the pair mean), the coarse blur 4^j sigma_c^2, and linear interpolation at
 * fraction t acts on a smooth line as f + t(1-t)/2 f'', a variance t(1-t) coarse texels^2
 * whose mean over the level's texel centres (t = (q + 1/2)/k) is 1/6 + 1/(12 k^2). sigma_c
 * is set so the sum is sigma_n^2 (pyramid_coarse_sigma). What is left: aliasing at each
 * halving, which the prefilter damps by exp(-pi^2 s_p^2 / 2) = 3e-9 (s_p = 2); the phase-
 * dependent part of t(1-t) (at most 1/6 about its mean: <= f_peak / (12 sigma_c^2), 0.13%
 * at sigma_c = 8, for a Gaussian bump); and the higher cumulants of the pair means and the
 * tent (O(1/sigma_c^4)). The cut at 4 sigma of every kernel drops < 1e-4 of the weight. The
 * test gauss_pyramid_vs_float64 measures the whole against the exact chain in double. */
#define PYRAMID_MIN_SIGMA 8.0
#define PYRAMID_PREFILTER_SIGMA 2.0
enum { PREFILTER_RADIUS = 8, PYRAMID_CHUNKS = 32 };

/* sigma_c for k = 2^halvings (0 if the budget is spent) */
static double pyramid_coarse_sigma(double sigma_n, int halvings)
{
    double var = sigma_n * sigma_n, scale = 1.0;
    for (int t = 0; t < halvings; t++) {
        var -= scale * (PYRAMID_PREFILTER_SIGMA * PYRAMID_PREFILTER_SIGMA + 0.25);
        scale *= 4.0;
    }
    var = var / scale - (1.0 / 6.0 + 1.0 / (12.0 * scale));
    return var > 0 ? sqrt(var) : 0.0;
}

int ibl__gauss_coarse_factor(double sigma_n, int n)
{
    int halvings = 0;
    while (n % (2 << halvings) == 0 && n / (2 << halvings) >= 2 &&
           pyramid_coarse_sigma(sigma_n, halvings + 1) >= PYRAMID_MIN_SIGMA)
        halvings++;
    return 1 << halvings;
}

typedef struct pyramid_op {
    int n, halvings;
    double prefilter[PREFILTER_RADIUS + 1];
    const double *coarse_kernel; /* [0..coarse_radius] */
    int coarse_radius;
    const double *denominator; /* n values, or NULL while computing it */
    size_t line_doubles;       /* work per line */
} pyramid_op;

static int floor_half(int v) { return v >= 0 ? v / 2 : -((-v + 1) / 2); }

/* One line of 4 channels through the pyramid (header comment); in and out may alias. */
static void pyramid_line(const pyramid_op *op, const float *in, float *out, size_t stride, double *work)
{
    int n = op->n, lo = 0, len = n;
    double *a = work, *b = work + op->line_doubles / 3;
    for (int i = 0; i < n; i++)
        for (int c = 0; c < 4; c++) a[(size_t)i * 4 + c] = in[(size_t)i * stride + c];
    for (int t = 0; t < op->halvings; t++) {
        /* prefilter: support [lo - R, lo + len + R) */
        int R = PREFILTER_RADIUS, blen = len + 2 * R;
        for (int i = 0; i < blen; i++) {
            double acc[4] = {0, 0, 0, 0};
            for (int j = i - 2 * R < 0 ? 0 : i - 2 * R; j < len && j <= i; j++) {
                double w = op->prefilter[i - R - j < 0 ? j + R - i : i - R - j];
                for (int c = 0; c < 4; c++) acc[c] += w * a[(size_t)j * 4 + c];
            }
            for (int c = 0; c < 4; c++) b[(size_t)i * 4 + c] = acc[c];
        }
        /* pair means: coarse I holds fine 2I and 2I + 1 */
        int blo = lo - R, clo = floor_half(blo), chi = floor_half(blo + blen - 1) + 1;
        for (int I = clo; I < chi; I++)
            for (int c = 0; c < 4; c++) {
                double v = 0;
                for (int f = 2 * I; f <= 2 * I + 1; f++)
                    if (f >= blo && f < blo + blen) v += b[(size_t)(f - blo) * 4 + c];
                a[(size_t)(I - clo) * 4 + c] = 0.5 * v;
            }
        lo = clo, len = chi - clo;
    }
    /* the coarse blur at coarse texels -1..m, which the interpolation reads */
    int m = n >> op->halvings, r = op->coarse_radius;
    double *coarse = work + 2 * (op->line_doubles / 3);
    for (int I = -1; I <= m; I++) {
        double acc[4] = {0, 0, 0, 0};
        int j0 = I - r < lo ? lo : I - r, j1 = I + r >= lo + len ? lo + len - 1 : I + r;
        for (int j = j0; j <= j1; j++) {
            double w = op->coarse_kernel[j > I ? j - I : I - j];
            for (int c = 0; c < 4; c++) acc[c] += w * a[(size_t)(j - lo) * 4 + c];
        }
        for (int c = 0; c < 4; c++) coarse[(size_t)(I + 1) * 4 + c] = acc[c];
    }
    int k = 1 << op->halvings;
    for (int i = 0; i < n; i++) {
        double u = (i + 0.5) / k - 0.5;
        int base = (int)floor(u);
        double t = u - base, scale = op->denominator ? 1.0 / op->denominator[i] : 1.0;
        const double *p = coarse + (size_t)(base + 1) * 4;
        for (int c = 0; c < 4; c++) out[(size_t)i * stride + c] = (float)(((1.0 - t) * p[c] + t * p[c + 4]) * scale);
    }
}

typedef struct pyramid_job {
    const pyramid_op *op;
    float *image; /* 6 faces of n*n RGBA */
    int pass;     /* 0 rows, 1 columns */
    double *work; /* PYRAMID_CHUNKS lines of work */
} pyramid_job;

static void pyramid_chunk_task(void *arg, int chunk)
{
    const pyramid_job *job = arg;
    int n = job->op->n, lines = 6 * n;
    double *work = job->work + (size_t)chunk * job->op->line_doubles;
    for (int index = chunk * lines / PYRAMID_CHUNKS; index < (chunk + 1) * lines / PYRAMID_CHUNKS; index++) {
        int face = index / n, line = index % n;
        float *face_data = job->image + (size_t)face * n * n * 4;
        float *start = face_data + (job->pass == 0 ? (size_t)line * n * 4 : (size_t)line * 4);
        pyramid_line(job->op, start, start, job->pass == 0 ? 4 : (size_t)n * 4, work);
    }
}

static ibl_status pyramid_blur(ibl_context *ctx, float *image, int n, double sigma, int k)
{
    pyramid_op op = {.n = n};
    while ((1 << op.halvings) < k) op.halvings++;
    for (int d = 0; d <= PREFILTER_RADIUS; d++)
        op.prefilter[d] = exp(-0.5 * d * d / (PYRAMID_PREFILTER_SIGMA * PYRAMID_PREFILTER_SIGMA));
    double sigma_c = pyramid_coarse_sigma(sigma, op.halvings);
    op.coarse_radius = (int)ceil(4.0 * sigma_c);
    /* three buffers: the line and its prefiltered copy (n + 2 R at most), the coarse line */
    size_t third = (size_t)(n + 2 * PREFILTER_RADIUS + 4) * 4;
    op.line_doubles = 3 * third;
    double *kernel = ibl_alloc(ctx, (size_t)(op.coarse_radius + 1) * sizeof(double));
    double *denominator = ibl_alloc(ctx, (size_t)n * sizeof(double));
    double *work = ibl_alloc(ctx, PYRAMID_CHUNKS * op.line_doubles * sizeof(double));
    float *ones = ibl_alloc(ctx, (size_t)n * 4 * sizeof(float));
    ibl_status st = IBL_OK;
    if (!kernel || !denominator || !work || !ones) {
        st = ibl_context_status(ctx);
    } else {
        for (int d = 0; d <= op.coarse_radius; d++) kernel[d] = exp(-0.5 * d * d / (sigma_c * sigma_c));
        op.coarse_kernel = kernel;
        for (int i = 0; i < 4 * n; i++) ones[i] = 1.0f;
        pyramid_line(&op, ones, ones, 4, work);
        for (int i = 0; i < n; i++) denominator[i] = ones[(size_t)i * 4];
        op.denominator = denominator;
        int chunks = PYRAMID_CHUNKS;
        pyramid_job rows = {&op, image, 0, work}, columns = {&op, image, 1, work};
        ibl_parallel_for(ctx, chunks, pyramid_chunk_task, &rows);
        ibl_parallel_for(ctx, chunks, pyramid_chunk_task, &columns);
    }
    ibl_free(ctx, ones);
    ibl_free(ctx, work);
    ibl_free(ctx, denominator);
    ibl_free(ctx, kernel);
    return st;
}

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
    size_t scratch_floats = 0;
    for (int level = 0; level < dst->levels; level++) {
        int n = ibl_level_size(dst->size, level);
        double sigma = ibl__gauss_sigma(phong_exponent_per_level[level], n);
        if (sigma >= 1e-3 && n >= 2 && ibl__gauss_coarse_factor(sigma, n) == 1 &&
            6 * (size_t)n * n * 4 > scratch_floats)
            scratch_floats = 6 * (size_t)n * n * 4;
    }
    float *scratch = scratch_floats ? ibl_alloc(ctx, scratch_floats * sizeof(float)) : NULL;
    if (scratch_floats && !scratch) return ibl_context_status(ctx);
    for (int level = 0; level < dst->levels; level++) {
        int n = ibl_level_size(dst->size, level);
        double sigma = ibl__gauss_sigma(phong_exponent_per_level[level], n);
        if (sigma < 1e-3 || n < 2) continue;
        float *image = ibl_cubemap_face(dst, level, 0);
        int k = ibl__gauss_coarse_factor(sigma, n);
        st = k == 1 ? blur_faces(ctx, image, scratch, n, sigma) : pyramid_blur(ctx, image, n, sigma, k);
        if (st == IBL_OK) st = ibl__progress(ctx, "gauss prefilter", (double)(level + 1) / dst->levels);
        if (st != IBL_OK) break;
    }
    ibl_free(ctx, scratch);
    return st;
}
