/* The normal map scattered by a diffusion profile (Daqi 2016, "PBR Series 6.2: SSS based on
 * normal map": under light that arrives evenly from all directions, local subsurface
 * scattering is the normal map convolved with the profile, per colour channel). The profile
 * is a sum of Gaussians (d'Eon and Luebke, GPU Gems 3, ch. 14, 2007), so each term is a
 * separable blur, U then V, in texture space; its width in texels comes per texel from the
 * stretch map (d'Eon, Luebke and Enderton 2007, "Efficient Rendering of Human Skin": the
 * stretch-corrected texture-space blur).
 *
 * Speed: a Gaussian that is at least 2 texels wide everywhere runs on a copy of the map
 * averaged 2x2 L times (at most ~4 texels wide there), then is upsampled bilinearly. The box
 * averages and the bilinear upsampling blur too: a 2x2 average at level j adds 4^j / 4 texels^2
 * of variance (in level-0 texels), bilinear interpolation from level L adds 4^L / 6 on average
 * over the sample's phase, so the Gaussian at level L gets the variance that remains,
 * (sigma^2 - (4^L - 1) / 12 - 4^L / 6) / 4^L in its own texels. Kernels come from a table of
 * sampled, truncated (3 sigma) and renormalised Gaussians, 128 widths per octave. */
#include "skin_internal.h"
#include "core/context_internal.h"
#include "core/numeric.h"

#include <math.h>
#include <string.h>

enum { MAX_LEVELS = 12, BINS_PER_OCTAVE = 128, OCTAVE_MIN = -4, OCTAVE_MAX = 8, V_BAND_ROWS = 16 };
enum { BIN_COUNT = (OCTAVE_MAX - OCTAVE_MIN) * BINS_PER_OCTAVE + 1 };

/* ---- the kernel table ------------------------------------------------------------------------ */

typedef struct kernel_table {
    int stride;       /* 2 max_radius + 1 floats per kernel               */
    int *radius;      /* per bin                                          */
    float *weights;   /* per bin: taps -radius..radius at offset 0        */
} kernel_table;

static ibl_status kernels_create(ibl_context *ctx, int max_radius, kernel_table *k)
{
    k->stride = 2 * max_radius + 1;
    k->radius = ibl_alloc(ctx, BIN_COUNT * sizeof(int));
    k->weights = ibl_alloc(ctx, (size_t)BIN_COUNT * k->stride * sizeof(float));
    if (!k->radius || !k->weights) return ibl_context_status(ctx);
    for (int b = 0; b < BIN_COUNT; b++) {
        double sigma = exp2(OCTAVE_MIN + (double)b / BINS_PER_OCTAVE);
        int r = (int)ceil(3.0 * sigma);
        if (r > max_radius) r = max_radius;
        double w[2 * 1024 + 1], sum = 0;
        for (int i = -r; i <= r; i++) sum += w[i + r] = exp(-0.5 * i * i / (sigma * sigma));
        k->radius[b] = r;
        for (int i = 0; i <= 2 * r; i++) k->weights[(size_t)b * k->stride + i] = (float)(w[i] / sum);
    }
    return IBL_OK;
}

static void kernels_free(ibl_context *ctx, kernel_table *k)
{
    ibl_free(ctx, k->radius);
    ibl_free(ctx, k->weights);
}

/* The bin of a width in texels; -1: narrower than the table (the identity). */
static int kernel_bin(float sigma)
{
    if (!(sigma >= exp2f(OCTAVE_MIN))) return -1;
    if (!(sigma < exp2f(OCTAVE_MAX))) return BIN_COUNT - 1; /* also +inf (no stretch at all) */
    int b = (int)lrintf(log2f(sigma) * BINS_PER_OCTAVE) - OCTAVE_MIN * BINS_PER_OCTAVE;
    return b < BIN_COUNT ? b : BIN_COUNT - 1;
}

/* ---- the pyramid ------------------------------------------------------------------------------ */

typedef struct level {
    int w, h;
    float *normal; /* 3 per texel: the decoded normal map, 2x2-averaged                   */
    float *texels_per_mm; /* 2 per texel: U and V texels of this level per millimetre, 0
                             where there is no stretch                                 */
} level;

typedef struct scatter_job {
    const ibl_image *normal_map, *stretch;
    level levels[MAX_LEVELS];
    int level_count;
    const kernel_table *kernels;
    const ibl_skin_profile *profile;
    float *tmp, *blurred;        /* scratch: one level's worth of float3                      */
    int *v_bins;                 /* scratch of the V pass: a row of kernel bins per band       */
    float *acc[3];               /* level-0 float3 sums per output channel                    */
    /* the Gaussian of the current pass */
    int gaussian, lvl;
    float variance_texels_extra, scale2; /* variance that box + bilinear add; 4^-L        */
    float sigma_mm2_factor;              /* variance in mm^2                               */
    float mm_per_unit;
    ibl_image *out;
} scatter_job;

static void decode_row(void *arg, int y)
{
    scatter_job *j = arg;
    level *l0 = &j->levels[0];
    float mm = j->mm_per_unit;
    for (int x = 0; x < l0->w; x++) {
        const float *n = ibl_image_texel(j->normal_map, x, y), *s = ibl_image_texel(j->stretch, x, y);
        size_t i = (size_t)y * l0->w + x;
        for (int c = 0; c < 3; c++) l0->normal[3 * i + c] = 2.0f * n[c] - 1.0f;
        /* |dP/du| mesh units per texture -> texels per millimetre along U */
        l0->texels_per_mm[2 * i] = s[0] > 0.0f ? (float)l0->w / (mm * s[0]) : 0.0f;
        l0->texels_per_mm[2 * i + 1] = s[1] > 0.0f ? (float)l0->h / (mm * s[1]) : 0.0f;
    }
}

static void downsample_row(void *arg, int y)
{
    scatter_job *j = arg;
    const level *a = &j->levels[j->lvl - 1];
    level *b = &j->levels[j->lvl];
    int y0 = 2 * y, y1 = 2 * y + 1 < a->h ? 2 * y + 1 : 2 * y;
    for (int x = 0; x < b->w; x++) {
        int x0 = 2 * x, x1 = 2 * x + 1 < a->w ? 2 * x + 1 : 2 * x;
        size_t s[4] = {(size_t)y0 * a->w + x0, (size_t)y0 * a->w + x1, (size_t)y1 * a->w + x0,
                       (size_t)y1 * a->w + x1};
        size_t d = (size_t)y * b->w + x;
        for (int c = 0; c < 3; c++)
            b->normal[3 * d + c] = 0.25f * (a->normal[3 * s[0] + c] + a->normal[3 * s[1] + c] +
                                            a->normal[3 * s[2] + c] + a->normal[3 * s[3] + c]);
        /* texels per mm halve with each level */
        for (int c = 0; c < 2; c++)
            b->texels_per_mm[2 * d + c] =
                0.125f * (a->texels_per_mm[2 * s[0] + c] + a->texels_per_mm[2 * s[1] + c] +
                          a->texels_per_mm[2 * s[2] + c] + a->texels_per_mm[2 * s[3] + c]);
    }
}

/* The current Gaussian's kernel bin at texel i of the current level, along axis (0 U, 1 V). */
static int texel_bin(const scatter_job *j, const level *l, size_t i, int axis)
{
    float k = l->texels_per_mm[2 * i + axis];
    if (k <= 0.0f) return -1;
    /* sigma^2 in this level's texels: the variance asked for, less what the box averages and the
       bilinear upsampling add (in level-0 texels, scaled by 4^-L) */
    float s2 = j->sigma_mm2_factor * k * k - j->variance_texels_extra * j->scale2;
    return s2 > 0.0f ? kernel_bin(sqrtf(s2)) : -1;
}

static void blur_u_row(void *arg, int y)
{
    scatter_job *j = arg;
    const level *l = &j->levels[j->lvl];
    const float *src = l->normal + (size_t)y * l->w * 3;
    float *dst = j->tmp + (size_t)y * l->w * 3;
    for (int x = 0; x < l->w; x++) {
        int b = texel_bin(j, l, (size_t)y * l->w + x, 0);
        if (b < 0) {
            memcpy(dst + 3 * x, src + 3 * x, 3 * sizeof(float));
            continue;
        }
        int r = j->kernels->radius[b];
        const float *w = j->kernels->weights + (size_t)b * j->kernels->stride + r; /* w[0]: centre */
        const float *c = src + 3 * x;
        float s0 = w[0] * c[0], s1 = w[0] * c[1], s2 = w[0] * c[2];
        if (x - r >= 0 && x + r < l->w) {
            /* inside the row: the kernel is symmetric, one weight per pair of taps */
            for (int k = 1; k <= r; k++) {
                const float *lo = c - 3 * k, *hi = c + 3 * k;
                s0 += w[k] * (lo[0] + hi[0]);
                s1 += w[k] * (lo[1] + hi[1]);
                s2 += w[k] * (lo[2] + hi[2]);
            }
        } else {
            for (int k = 1; k <= r; k++) {
                const float *lo = src + 3 * ibl__clampi(x - k, 0, l->w - 1);
                const float *hi = src + 3 * ibl__clampi(x + k, 0, l->w - 1);
                s0 += w[k] * (lo[0] + hi[0]);
                s1 += w[k] * (lo[1] + hi[1]);
                s2 += w[k] * (lo[2] + hi[2]);
            }
        }
        dst[3 * x] = s0, dst[3 * x + 1] = s1, dst[3 * x + 2] = s2;
    }
}

/* The V pass, a band of rows per task: each row is summed tap by tap over whole rows (k outer,
 * x inner), so that it reads rows y - k and y + k contiguously instead of a column per texel;
 * each texel keeps its own kernel (bin and radius) and stops at its radius. The sums are the
 * same in the same order whatever the band, so the output does not depend on the threads. */
static void blur_v_band(void *arg, int band)
{
    scatter_job *j = arg;
    const level *l = &j->levels[j->lvl];
    int w = l->w, y0 = band * V_BAND_ROWS, y1 = y0 + V_BAND_ROWS < l->h ? y0 + V_BAND_ROWS : l->h;
    int *bins = j->v_bins + (size_t)band * j->levels[0].w;
    const float *table = j->kernels->weights;
    for (int y = y0; y < y1; y++) {
        float *dst = j->blurred + (size_t)y * w * 3;
        const float *centre = j->tmp + (size_t)y * w * 3;
        int rmax = 0;
        for (int x = 0; x < w; x++) {
            int b = texel_bin(j, l, (size_t)y * w + x, 1);
            bins[x] = b;
            float c = b < 0 ? 1.0f : table[(size_t)b * j->kernels->stride + j->kernels->radius[b]];
            for (int k = 0; k < 3; k++) dst[3 * x + k] = c * centre[3 * x + k];
            if (b >= 0 && j->kernels->radius[b] > rmax) rmax = j->kernels->radius[b];
        }
        for (int k = 1; k <= rmax; k++) {
            const float *lo = j->tmp + (size_t)ibl__clampi(y - k, 0, l->h - 1) * w * 3;
            const float *hi = j->tmp + (size_t)ibl__clampi(y + k, 0, l->h - 1) * w * 3;
            for (int x = 0; x < w; x++) {
                int b = bins[x];
                if (b < 0 || k > j->kernels->radius[b]) continue;
                float wk = table[(size_t)b * j->kernels->stride + j->kernels->radius[b] + k];
                dst[3 * x] += wk * (lo[3 * x] + hi[3 * x]);
                dst[3 * x + 1] += wk * (lo[3 * x + 1] + hi[3 * x + 1]);
                dst[3 * x + 2] += wk * (lo[3 * x + 2] + hi[3 * x + 2]);
            }
        }
    }
}

/* Adds the blurred level, upsampled bilinearly to level 0 (texel centres aligned), times the
 * Gaussian's weight per channel into the three sums. */
static void accumulate_row(void *arg, int y)
{
    scatter_job *j = arg;
    const level *l0 = &j->levels[0], *l = &j->levels[j->lvl];
    const float *wt = j->profile->weight[j->gaussian];
    float scale = 1.0f / (float)(1 << j->lvl);
    float fy = ((float)y + 0.5f) * scale - 0.5f;
    int y0 = (int)floorf(fy);
    float ty = fy - (float)y0;
    int ya = ibl__clampi(y0, 0, l->h - 1), yb = ibl__clampi(y0 + 1, 0, l->h - 1);
    for (int x = 0; x < l0->w; x++) {
        float v[3];
        if (j->lvl == 0) {
            memcpy(v, j->blurred + 3 * ((size_t)y * l0->w + x), sizeof v);
        } else {
            float fx = ((float)x + 0.5f) * scale - 0.5f;
            int x0 = (int)floorf(fx);
            float tx = fx - (float)x0;
            int xa = ibl__clampi(x0, 0, l->w - 1), xb = ibl__clampi(x0 + 1, 0, l->w - 1);
            const float *p00 = j->blurred + 3 * ((size_t)ya * l->w + xa), *p01 = j->blurred + 3 * ((size_t)ya * l->w + xb);
            const float *p10 = j->blurred + 3 * ((size_t)yb * l->w + xa), *p11 = j->blurred + 3 * ((size_t)yb * l->w + xb);
            for (int c = 0; c < 3; c++)
                v[c] = (1 - ty) * ((1 - tx) * p00[c] + tx * p01[c]) + ty * ((1 - tx) * p10[c] + tx * p11[c]);
        }
        size_t i = 3 * ((size_t)y * l0->w + x);
        for (int ch = 0; ch < 3; ch++)
            if (wt[ch] != 0.0f)
                for (int c = 0; c < 3; c++) j->acc[ch][i + c] += wt[ch] * v[c];
    }
}

/* The level a Gaussian of variance v (mm^2) runs at: the coarsest whose width stays >= 2 texels
 * at the texel that needs the narrowest (the fewest texels per mm), after the box and bilinear
 * variances. */
static int gaussian_level(const scatter_job *j, float variance_mm2, float min_texels_per_mm)
{
    double s2 = variance_mm2 * (double)min_texels_per_mm * min_texels_per_mm; /* level-0 texels^2 */
    int lvl = 0;
    while (lvl + 1 < j->level_count) {
        double f = ldexp(1.0, 2 * (lvl + 1)); /* 4^(L+1) */
        if ((s2 - (f - 1) / 12 - f / 6) / f < 4.0) break;
        lvl++;
    }
    return lvl;
}

static void finish_row(void *arg, int y)
{
    scatter_job *j = arg;
    const level *l0 = &j->levels[0];
    for (int x = 0; x < l0->w; x++) {
        size_t i = (size_t)y * l0->w + x;
        int unstretched = l0->texels_per_mm[2 * i] <= 0.0f && l0->texels_per_mm[2 * i + 1] <= 0.0f;
        for (int ch = 0; ch < 3; ch++) {
            /* texels with no stretch keep their own normal */
            const float *a = unstretched ? l0->normal + 3 * i : j->acc[ch] + 3 * i;
            float len = sqrtf(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
            float n[3] = {0.0f, 0.0f, 1.0f};
            if (len > 1e-12f)
                for (int c = 0; c < 3; c++) n[c] = a[c] / len;
            float *px = ibl_image_texel(&j->out[ch], x, y);
            for (int c = 0; c < 3; c++) px[c] = 0.5f * n[c] + 0.5f;
            px[3] = 1.0f;
        }
    }
}

static ibl_status check_inputs(ibl_context *ctx, const ibl_image *n, const ibl_image *s,
                               const ibl_skin_profile *p, float mm_per_unit, int max_radius)
{
    if (!n || !s || !n->pixels || !s->pixels)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "scatter: missing normal or stretch map");
    if (n->width != s->width || n->height != s->height)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                         "scatter: the normal map is %dx%d, the stretch map %dx%d", n->width,
                         n->height, s->width, s->height);
    if (p->count < 1 || p->count > IBL_SKIN_MAX_GAUSSIANS)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "scatter: profile of %d Gaussians", p->count);
    for (int i = 0; i < p->count; i++)
        if (!(p->variance_mm2[i] > 0.0f))
            return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "scatter: Gaussian %d has variance %g", i,
                             (double)p->variance_mm2[i]);
    if (!(mm_per_unit > 0.0f && mm_per_unit < 1e9f))
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "scatter: %g mm per unit", (double)mm_per_unit);
    if (max_radius < 1 || max_radius > 1024)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "scatter: max radius %d (1 to 1024)", max_radius);
    return IBL_OK;
}

/* The pyramid's levels, each half the one above (rounded up), down to min_size texels. */
static ibl_status build_levels(ibl_context *ctx, scatter_job *j, int w, int h)
{
    for (int l = 0; l < MAX_LEVELS; l++) {
        level *lv = &j->levels[l];
        lv->w = l == 0 ? w : (j->levels[l - 1].w + 1) / 2;
        lv->h = l == 0 ? h : (j->levels[l - 1].h + 1) / 2;
        if (l > 0 && (lv->w < 8 || lv->h < 8)) break;
        lv->normal = ibl_alloc(ctx, (size_t)lv->w * lv->h * 3 * sizeof(float));
        lv->texels_per_mm = ibl_alloc(ctx, (size_t)lv->w * lv->h * 2 * sizeof(float));
        if (!lv->normal || !lv->texels_per_mm) return ibl_context_status(ctx);
        j->level_count = l + 1;
        j->lvl = l;
        if (l == 0) ibl_parallel_for(ctx, h, decode_row, j);
        else ibl_parallel_for(ctx, lv->h, downsample_row, j);
    }
    return IBL_OK;
}

static float min_texels_per_mm(const level *l0)
{
    float m = 0.0f;
    for (size_t i = 0; i < (size_t)l0->w * l0->h * 2; i++) {
        float k = l0->texels_per_mm[i];
        if (k > 0.0f && (m == 0.0f || k < m)) m = k;
    }
    return m;
}

static void run_gaussians(ibl_context *ctx, scatter_job *j)
{
    float kmin = min_texels_per_mm(&j->levels[0]);
    for (int g = 0; g < j->profile->count; g++) {
        j->gaussian = g;
        j->sigma_mm2_factor = j->profile->variance_mm2[g];
        j->lvl = kmin > 0.0f ? gaussian_level(j, j->profile->variance_mm2[g], kmin) : 0;
        double f = ldexp(1.0, 2 * j->lvl);
        j->variance_texels_extra = j->lvl ? (float)((f - 1) / 12 + f / 6) : 0.0f;
        j->scale2 = (float)(1.0 / f);
        const level *l = &j->levels[j->lvl];
        ibl_parallel_for(ctx, l->h, blur_u_row, j);
        ibl_parallel_for(ctx, (l->h + V_BAND_ROWS - 1) / V_BAND_ROWS, blur_v_band, j);
        ibl_parallel_for(ctx, j->levels[0].h, accumulate_row, j);
    }
}

ibl_status ibl_skin_scatter_normals(ibl_context *ctx, const ibl_image *normal_map,
                                    const ibl_image *stretch, const ibl_skin_scatter_desc *desc,
                                    ibl_image out[3])
{
    ibl_skin_scatter_desc d = {0};
    if (desc) d = *desc;
    ibl_skin_profile deon = ibl_skin_profile_deon();
    const ibl_skin_profile *profile = d.profile ? d.profile : &deon;
    float mm = d.mm_per_unit != 0.0f ? d.mm_per_unit : 1000.0f;
    int max_radius = d.max_radius ? d.max_radius : 48;
    if (!out) return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "scatter: missing output");
    ibl_status st = check_inputs(ctx, normal_map, stretch, profile, mm, max_radius);
    if (st != IBL_OK) return st;
    int w = normal_map->width, h = normal_map->height;
    size_t n3 = (size_t)w * h * 3;
    scatter_job j;
    memset(&j, 0, sizeof j);
    memset(out, 0, 3 * sizeof *out);
    j.normal_map = normal_map;
    j.stretch = stretch;
    j.profile = profile;
    j.mm_per_unit = mm;
    kernel_table kernels = {0};
    j.kernels = &kernels;
    st = kernels_create(ctx, max_radius, &kernels);
    if (st == IBL_OK) st = build_levels(ctx, &j, w, h);
    if (st == IBL_OK) {
        j.tmp = ibl_alloc(ctx, n3 * sizeof(float));
        j.blurred = ibl_alloc(ctx, n3 * sizeof(float));
        j.v_bins = ibl_alloc(ctx, (size_t)((h + V_BAND_ROWS - 1) / V_BAND_ROWS) * w * sizeof(int));
        for (int c = 0; c < 3; c++) j.acc[c] = ibl_calloc(ctx, n3, sizeof(float));
        if (!j.tmp || !j.blurred || !j.v_bins || !j.acc[0] || !j.acc[1] || !j.acc[2])
            st = ibl_context_status(ctx);
    }
    if (st == IBL_OK) run_gaussians(ctx, &j);
    for (int c = 0; c < 3 && st == IBL_OK; c++) st = ibl_image_alloc(ctx, w, h, &out[c]);
    if (st == IBL_OK) {
        j.out = out;
        ibl_parallel_for(ctx, h, finish_row, &j);
    } else {
        for (int c = 0; c < 3; c++) ibl_image_free(ctx, &out[c]);
    }
    for (int c = 0; c < 3; c++) ibl_free(ctx, j.acc[c]);
    ibl_free(ctx, j.tmp);
    ibl_free(ctx, j.blurred);
    ibl_free(ctx, j.v_bins);
    for (int l = 0; l < MAX_LEVELS; l++) {
        ibl_free(ctx, j.levels[l].normal);
        ibl_free(ctx, j.levels[l].texels_per_mm);
    }
    kernels_free(ctx, &kernels);
    return st;
}
