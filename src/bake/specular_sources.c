/* A chain's narrow levels refined against the flat input image itself, next to its compact
 * bright sources (docs/SPECULAR.md "Accuracy against the input").
 *
 * The prefilter reads a working cube: every texel is the area mean of its footprint of the
 * input, and the filter treats it as uniform over the texel. Where a lobe is only a few
 * working texels wide, a sun a few input pixels across is then first-order misplaced (its
 * light is spread over the texel instead of sitting where its pixels are; the conversion's
 * linear reconstruction spreads it one more pixel): on city.exr, level 1 of the 256 chain is
 * 1.36% RMS off the exact integral over the input, while the filter's own share is ~0.1%. A
 * finer working cube cures it only slowly (the reconstruction stays) and costs the whole
 * plan; the input's own pixels cure it exactly, and only a few texels need them.
 *
 * So, for the levels whose lobe is narrower than NARROW_HALF_WIDTH_TEXELS working texels, a
 * region S of working texels is marked around the input's brightest compact pixels (those whose
 * power above their neighbours' adds at least BRIGHT_PEAK_SHARE of the mean radiance at such a
 * lobe's peak), and every output texel R within reach of S gets
 *     delta(R) = [ int_S f(R.l) L_input(l) dl - sum_{t in S} L_t int_t f(R.l) dl ] / int f dl
 * the integral over S of the input taken as constant per pixel (what the exact integral over
 * the input is) minus the same region as the filter saw it. Both sides are sums over small
 * cells: the input's pixels split k x k with their exact solid angles (2 pi / W)(cos theta0 -
 * cos theta1) / k, each kept where its centre falls in a texel of S, k the pixel's own (not
 * the texel's: a pixel two texels cut must be split the same way for both, or part of it is
 * counted twice or not at all); the texels of S split k x k with weights dA / |d|^3 scaled to
 * the texel's exact solid angle (Driscoll 2012). Both sides hold the same region's energy, so
 * far from S the difference fades (a group's cells are summed one by one within
 * NEAR_HALF_WIDTHS of the lobe's half width, as a monopole and a dipole, f and f' at the
 * group's centre, out to REACH_HALF_WIDTHS, not at all beyond).
 * The normaliser int f dl is the lobe's closed form over the sphere (GGX: Walter et al. 2007's
 * D with v = n, as in the fast method; Phong: 2 pi / (n + 1)).
 *
 * Near the poles (the conversion's directly integrated polar region, src/layout/equirect/
 * polar_texels.c, and the region's margin: the polar cap) a pixel is a thin wedge of a ring
 * round the pole, and a sun there is spread over many of them, none bright on its own: the
 * cap's sources are its working texels instead, by the same bar (find_polar_sources), with the
 * texels within the margin of any of their points. The conversion keeps a polar pixel's light
 * as compact as any other's (within 1.8 rows of its centre, measured with one lit pixel per
 * row), so the same region holds it; the cap's pixels are cut into cells of several columns
 * (cap_columns), a quarter of a texel or less both ways.
 *
 * delta is added to the chain by specular_sources_apply.c (a narrow Phong level's on a grid of
 * half the output's edge, interpolated). The whole-image scans run in row bands, and the groups
 * are made one per task, through the context's parallel-for; every output texel (or grid point)
 * is summed alone, in a fixed order of groups and cells, so the result does not depend on the
 * thread count. */
#include "specular_sources_internal.h"
#include "core/context_internal.h"
#include "core/cpu.h"
#include "core/numeric.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* A level is refined when its lobe's half width is under this many mean working texels: at
 * 9.1 (level 1 of the 1024 chain from a 4096x2048 input) the conversion's share was already
 * 0.27% RMS, at 5.6 (512) 0.57%, at 3.5 (256) 1.36% (docs/SPECULAR.md). */
#define NARROW_HALF_WIDTH_TEXELS 8.0
/* An input pixel is a source when its power in excess of its eight neighbours' mean (what a
 * texel can misplace to first order: a uniform patch is not misplaced) times the narrowest
 * refined lobe's peak over that lobe's normaliser, i.e. what the pixel alone adds to the level
 * where the lobe is centred on it, is at least the mean radiance; the brightest first, at most
 * MAX_SOURCE_PIXELS, until the region holds MAX_REGION_TEXELS. Measured on the six test HDRIs
 * at 256 (level 1 against the exact integral over the input, docs/SPECULAR.md): this setting
 * gives forest 0.09% RMS, studio 0.29%, interior 0.03%, night 0.09% (without the sources
 * 1.05%, 0.44%, 1.47%, 2.33%) for 11-15 ms of CPU; 0.1 of the mean with 2048 texels gave
 * 0.02%, 0.34%, 0.03%, 0.02% for 30-125 ms, and 0.1 with 512 texels left studio at 0.56% (the
 * region's edge then cuts through its bright panels). */
#define BRIGHT_PEAK_SHARE 1.0
#define MAX_SOURCE_PIXELS 2048
/* The region around a source pixel: the conversion spreads a pixel over the support of its
 * linear interpolation (one row and one column each way: within 1.42 rows of its centre, a
 * column being no wider than a row), and every texel that meets that disc holds some of its
 * light; S takes every texel that meets a disc of 1.5 rows (and one sampling step), so both
 * sides of delta hold all of it. */
#define MARGIN_PIXELS 1.5
/* Cells: at least 4 x 4 a pixel or texel, and at most a quarter of the other grid's spacing
 * (a boundary of the other grid then cuts a cell at most at quarter steps). */
#define MIN_CELLS 4
#define MAX_CELLS 32

static double texel_angle(int size)
{
    return sqrt(4.0 * IBL_PI / 6.0) / size;
}

/* The levels that are refined: a lobe (not a mirror) narrower than the bar. */
static int level_refined(const ibl_specular_info *info, int working_size, int level, ibl__lobe *lobe)
{
    *lobe = ibl__lobe_for_level(info, level);
    return lobe->kind != IBL__LOBE_MIRROR &&
           lobe->half_angle < NARROW_HALF_WIDTH_TEXELS * texel_angle(working_size);
}

/* int f dl over the sphere. GGX: f = x a4 / t^2, t = 1 + (1 + x) k; with t as the variable,
 * int_0^1 f dx = a4 / k^2 [ln t + (1 + k) / t] from t0 = 1 + k to t1 = alpha^2. */
double ibl__sources_lobe_normaliser(const ibl__lobe *lobe)
{
    if (lobe->kind == IBL__LOBE_PHONG) return IBL_TWO_PI / (lobe->n + 1.0);
    double k = lobe->k, t0 = 1.0 + k, t1 = 1.0 + 2.0 * k;
    return IBL_TWO_PI * lobe->a4 / (k * k) * (log(t1 / t0) + (1.0 + k) * (1.0 / t1 - 1.0 / t0));
}

/* The cells of a group being made, on the thread that makes it (then copied to the group's
 * own block: every block the sources keep while the chain is filtered stays small, so an
 * allocator that keeps freed large blocks for reuse, as the CLI's, is not made to grow past
 * them). */
typedef struct cell_list {
    ibl_context *ctx;
    double *dir; /* 3 per cell, unit            */
    double *w;   /* 3 per cell: solid angle x radiance (negative for the working cube) */
    size_t count, capacity;
} cell_list;

static ibl_status add_cell(cell_list *s, const double d[3], const double w[3])
{
    if (s->count == s->capacity) {
        size_t cap = s->capacity ? 2 * s->capacity : 1024;
        double *dir = ibl_alloc(s->ctx, cap * 3 * sizeof(double));
        double *wt = dir ? ibl_alloc(s->ctx, cap * 3 * sizeof(double)) : NULL;
        if (!wt) {
            ibl_free(s->ctx, dir);
            return ibl_context_status(s->ctx);
        }
        if (s->count) {
            memcpy(dir, s->dir, s->count * 3 * sizeof(double));
            memcpy(wt, s->w, s->count * 3 * sizeof(double));
        }
        ibl_free(s->ctx, s->dir);
        ibl_free(s->ctx, s->w);
        s->dir = dir, s->w = wt, s->capacity = cap;
    }
    memcpy(s->dir + s->count * 3, d, 3 * sizeof(double));
    memcpy(s->w + s->count * 3, w, 3 * sizeof(double));
    s->count++;
    return IBL_OK;
}

/* The picture's frame in the world's (ibl_orientation_apply on the axes: exact for quarter
 * turns, mirror and z-up; yaw in float, as the conversion applies it). */
typedef struct frame {
    double m[3][3]; /* world = m picture, column j the image of axis j */
} frame;

static void frame_make(const ibl_orientation *o, frame *fr)
{
    static const ibl_vec3 axes[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    for (int j = 0; j < 3; j++) {
        ibl_vec3 w = ibl_orientation_apply(o, axes[j]);
        fr->m[0][j] = w.x, fr->m[1][j] = w.y, fr->m[2][j] = w.z;
    }
}

/* World direction of picture angles (theta from +Y, phi; docs/CONVENTIONS.md: the centre
 * column looks toward -Z, the right quarter toward +X). */
static void picture_direction_sc(const frame *fr, double st, double ct, double sp, double cp,
                                 double out[3])
{
    double p[3] = {st * sp, ct, -st * cp};
    for (int i = 0; i < 3; i++) out[i] = fr->m[i][0] * p[0] + fr->m[i][1] * p[1] + fr->m[i][2] * p[2];
}

static void picture_direction(const frame *fr, double theta, double phi, double out[3])
{
    picture_direction_sc(fr, sin(theta), cos(theta), sin(phi), cos(phi), out);
}

/* Picture angles of a world direction (the inverse: m is orthogonal). */
static void picture_angles(const frame *fr, const double d[3], double *theta, double *phi)
{
    double p[3];
    for (int j = 0; j < 3; j++) p[j] = fr->m[0][j] * d[0] + fr->m[1][j] * d[1] + fr->m[2][j] * d[2];
    double len = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    double y = p[1] / len;
    *theta = acos(y < -1 ? -1 : y > 1 ? 1 : y);
    *phi = atan2(p[0], -p[2]);
}

static size_t texel_index(int size, const double d[3])
{
    double s, t;
    int f = ibl_cube_face_st_d(d, &s, &t);
    int x = (int)(s * size), y = (int)(t * size);
    x = x < 0 ? 0 : x >= size ? size - 1 : x;
    y = y < 0 ? 0 : y >= size ? size - 1 : y;
    return ((size_t)f * size + y) * size + x;
}

static double luminance(const float *p)
{
    return 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
}

/* The whole-image scans (the mean luminance, the source pixels) run in SCAN_BANDS bands of
 * rows through the context's parallel-for: a fixed split, and each band's results are merged
 * in band order, so the result does not depend on the thread count. */
#define SCAN_BANDS 16

static int band_row(int H, int band)
{
    return (int)((long long)H * band / SCAN_BANDS);
}

typedef struct mean_job {
    const ibl_image *im;
    double *row_term; /* per row: its luminance sum times one pixel's exact solid angle */
} mean_job;

static void mean_band(void *arg, int band)
{
    const mean_job *j = arg;
    int W = j->im->width, H = j->im->height;
    for (int y = band_row(H, band); y < band_row(H, band + 1); y++) {
        double row = 0;
        const float *p = j->im->pixels + (size_t)y * W * 4;
        for (int x = 0; x < W; x++) row += luminance(p + (size_t)x * 4);
        j->row_term[y] = row * (IBL_TWO_PI / W) * (cos(IBL_PI * y / H) - cos(IBL_PI * (y + 1) / H));
    }
}

/* The solid-angle-weighted mean luminance of the image (rows weighted by their exact solid
 * angles; the working cube's would cost a texel solid angle each); the rows' terms added in
 * row order. */
static ibl_status image_mean_luminance(ibl_context *ctx, const ibl_image *im, double *mean)
{
    mean_job job = {im, ibl_alloc(ctx, (size_t)im->height * sizeof(double))};
    if (!job.row_term) return ibl_context_status(ctx);
    ibl_parallel_for(ctx, SCAN_BANDS, mean_band, &job);
    double sum = 0;
    for (int y = 0; y < im->height; y++) sum += job.row_term[y];
    ibl_free(ctx, job.row_term);
    *mean = sum / (4.0 * IBL_PI);
    return IBL_OK;
}

/* A source: an input pixel (index y W + x), or in the polar caps a working texel (index
 * (face M + y) M + x). */
typedef struct candidate {
    float power;
    uint32_t index;
} candidate;

static int better(const candidate *a, const candidate *b)
{
    return a->power > b->power || (a->power == b->power && a->index < b->index);
}

static int by_power(const void *a, const void *b)
{
    return better(a, b) ? -1 : better(b, a) ? 1 : 0;
}

/* Keeps the MAX_SOURCE_PIXELS best candidates in a heap whose root is the worst of them. */
static void heap_offer(candidate *h, int *n, candidate c)
{
    int i;
    if (*n < MAX_SOURCE_PIXELS) {
        for (i = (*n)++; i > 0 && better(&h[(i - 1) / 2], &c); i = (i - 1) / 2) h[i] = h[(i - 1) / 2];
        h[i] = c;
        return;
    }
    if (!better(&c, &h[0])) return;
    for (i = 0;;) {
        int k = 2 * i + 1;
        if (k >= *n) break;
        if (k + 1 < *n && better(&h[k], &h[k + 1])) k++;
        if (!better(&c, &h[k])) break;
        h[i] = h[k], i = k;
    }
    h[i] = c;
}

/* The polar cap of the pixel scan: the conversion's directly integrated polar region (3
 * texels or 4 rows, src/layout/equirect/to_cube.c) and the region's margin. */
static double polar_cap(int working_size, int H, double margin)
{
    return fmax(atan(3.0 * 2.0 / working_size), 4.0 * IBL_PI / H) + margin;
}

typedef struct scan_job {
    const ibl_image *im;
    double bar, polar;
    candidate *best; /* SCAN_BANDS heaps of MAX_SOURCE_PIXELS */
    int count[SCAN_BANDS];
} scan_job;

/* One band's source pixels, away from the polar caps (find_polar_sources takes those). */
static void scan_band(void *arg, int band)
{
    scan_job *job = arg;
    const ibl_image *im = job->im;
    int W = im->width, H = im->height, n = 0;
    candidate *heap = job->best + (size_t)band * MAX_SOURCE_PIXELS;
    int y0 = band_row(H, band), y1 = band_row(H, band + 1);
    for (int y = y0 < 1 ? 1 : y0; y < y1 && y + 1 < H; y++) {
        double t0 = IBL_PI * y / H, t1 = IBL_PI * (y + 1) / H;
        if (t0 < job->polar || t1 > IBL_PI - job->polar) continue;
        double dw = IBL_TWO_PI / W * (cos(t0) - cos(t1));
        const float *row = im->pixels + (size_t)y * W * 4;
        for (int x = 0; x < W; x++) {
            double lum = luminance(row + (size_t)x * 4);
            if (!(lum * dw >= job->bar) || !isfinite(lum)) continue;
            /* only its excess over its eight neighbours' mean is misplaced to first order */
            double around = 0;
            for (int j = -1; j <= 1; j++)
                for (int i = -1; i <= 1; i++) {
                    int xx = x + i < 0 ? x + i + W : x + i >= W ? x + i - W : x + i;
                    if (i || j) around += luminance(im->pixels + ((size_t)(y + j) * W + xx) * 4);
                }
            double power = (lum - around / 8.0) * dw;
            if (power >= job->bar)
                heap_offer(heap, &n, (candidate){(float)power, (uint32_t)((size_t)y * W + x)});
        }
    }
    job->count[band] = n;
}

/* The source pixels, brightest first (at most MAX_SOURCE_PIXELS): each band keeps its best
 * MAX_SOURCE_PIXELS, and the best of their union are the image's (better() is a total order,
 * so the set and its order are the same however the rows are split). */
static ibl_status find_sources(ibl_context *ctx, const ibl_image *im, double bar, double polar,
                               candidate *c, int *count)
{
    scan_job *job = ibl_alloc(ctx, sizeof *job);
    candidate *best = ibl_alloc(ctx, (size_t)SCAN_BANDS * MAX_SOURCE_PIXELS * sizeof *best);
    if (!job || !best) {
        ibl_free(ctx, job);
        ibl_free(ctx, best);
        return ibl_context_status(ctx);
    }
    job->im = im, job->bar = bar, job->polar = polar, job->best = best;
    ibl_parallel_for(ctx, SCAN_BANDS, scan_band, job);
    size_t n = 0;
    for (int b = 0; b < SCAN_BANDS; b++) {
        memmove(best + n, best + (size_t)b * MAX_SOURCE_PIXELS, (size_t)job->count[b] * sizeof *best);
        n += (size_t)job->count[b];
    }
    qsort(best, n, sizeof *best, by_power);
    *count = n < MAX_SOURCE_PIXELS ? (int)n : MAX_SOURCE_PIXELS;
    memcpy(c, best, (size_t)*count * sizeof *c);
    ibl_free(ctx, best);
    ibl_free(ctx, job);
    return IBL_OK;
}

/* The angle from a pole within which a texel meets the cap (a texel's corner is at most
 * sqrt 2 / M from its centre), and the half side in texels of the square round the pole on
 * its face that holds those texels. */
static double polar_reach(int M, int H, double polar)
{
    return polar + IBL_PI / H + sqrt(2.0) / M;
}

static int polar_square(int M, double reach)
{
    return (int)ceil(tan(fmin(reach, 1.0)) * M / 2.0) + 1;
}

static void unit(double d[3])
{
    double l = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (int m = 0; m < 3; m++) d[m] /= l;
}

/* The sources in the polar caps. There a pixel is a thin wedge (a row of them, a ring round
 * the pole) holding a tiny part of a sun, so pixels are not compared with their neighbours:
 * working texels are, with the same bar, a texel's power (its luminance times its solid angle)
 * in excess of its eight neighbours' mean. The texels taken are those meeting the cap (the
 * caps' rows reach a row past it). The pole is at a face's centre for every orientation
 * (quarter turns, mirror, z-up, yaw about the pole); where the cap does not fit on one face,
 * there are none. Brightest first, at most `capacity`. */
static int find_polar_sources(const ibl_cubemap *working, const frame *fr, int H, double bar,
                              double polar, candidate *out, int capacity)
{
    int M = working->size, n = 0;
    double reach = polar_reach(M, H, polar);
    int R = polar_square(M, reach);
    for (int pole = 0; pole < 2; pole++) {
        double p[3], s, t;
        picture_direction(fr, pole ? IBL_PI : 0.0, 0.0, p);
        int f = ibl_cube_face_st_d(p, &s, &t), ci = (int)(s * M), cj = (int)(t * M);
        if (ci - R - 1 < 0 || ci + R + 1 >= M || cj - R - 1 < 0 || cj + R + 1 >= M) continue;
        const float *face = ibl_cubemap_face(working, 0, f);
        for (int y = cj - R; y <= cj + R; y++)
            for (int x = ci - R; x <= ci + R; x++) {
                double c[3];
                ibl_cube_direction_d(f, (x + 0.5) / M, (y + 0.5) / M, c);
                unit(c);
                if (c[0] * p[0] + c[1] * p[1] + c[2] * p[2] < cos(reach)) continue;
                double lum = luminance(face + ((size_t)y * M + x) * 4), around = 0;
                if (!isfinite(lum)) continue;
                for (int j = -1; j <= 1; j++)
                    for (int i = -1; i <= 1; i++)
                        if (i || j) around += luminance(face + ((size_t)(y + j) * M + x + i) * 4);
                double power = (lum - around / 8.0) * ibl_cube_texel_solid_angle(M, x, y);
                if (power >= bar && n < capacity)
                    out[n++] = (candidate){(float)power, (uint32_t)(((size_t)f * M + y) * M + x)};
            }
    }
    qsort(out, (size_t)n, sizeof *out, by_power);
    return n;
}

/* The set of region texels: open addressing over REGION_HASH slots (twice the most texels a
 * region holds with one source's disc on top). */
#define REGION_HASH 8192
static int region_insert(uint32_t *table, uint32_t key)
{
    uint32_t i = (uint32_t)((key * 0x9E3779B97F4A7C15ull) >> 51) & (REGION_HASH - 1);
    for (;; i = (i + 1) & (REGION_HASH - 1)) {
        if (table[i] == key) return 0;
        if (table[i] == UINT32_MAX) {
            table[i] = key;
            return 1;
        }
    }
}

/* Points of a disc sampled on the tangent plane at `step` out to `radius`: (2 half + 1)^2 at
 * most. */
static int disc_half(double radius, double step)
{
    return (int)ceil(radius / step);
}

/* Adds to out[] the texels not yet in the table that meet the disc of `radius` radians round
 * unit direction d (sampled on its tangent plane at `step`); returns how many. */
static int mark_disc(int M, const double d[3], double radius, double step, uint32_t *table,
                     uint32_t *out)
{
    int half = disc_half(radius, step), added = 0;
    /* a tangent basis: u orthogonal to d and to its smallest axis, v = d x u */
    double u[3], v[3];
    int a = fabs(d[0]) < fabs(d[1]) ? (fabs(d[0]) < fabs(d[2]) ? 0 : 2) : (fabs(d[1]) < fabs(d[2]) ? 1 : 2);
    double e[3] = {0, 0, 0};
    e[a] = 1;
    u[0] = d[1] * e[2] - d[2] * e[1], u[1] = d[2] * e[0] - d[0] * e[2], u[2] = d[0] * e[1] - d[1] * e[0];
    double ul = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    for (int k = 0; k < 3; k++) u[k] /= ul;
    v[0] = d[1] * u[2] - d[2] * u[1], v[1] = d[2] * u[0] - d[0] * u[2], v[2] = d[0] * u[1] - d[1] * u[0];
    for (int j = -half; j <= half; j++)
        for (int k = -half; k <= half; k++) {
            if (j * j + k * k > half * half) continue;
            double q[3];
            for (int m = 0; m < 3; m++) q[m] = d[m] + step * (k * u[m] + j * v[m]);
            uint32_t t = (uint32_t)texel_index(M, q);
            if (region_insert(table, t)) out[added++] = t;
        }
    return added;
}

/* The sources, pixels and polar texels, brightest first. */
typedef struct source_list {
    const candidate *pixel, *texel;
    int pixels, texels;
} source_list;

/* Marks the texels round each source, the brightest first, until MAX_REGION_TEXELS would be
 * passed; region[] receives them (the last source's past the count returned are not part of
 * it). Round a source pixel: within `margin` of its centre. Round a polar texel: within
 * `margin` of any of its points (sqrt 2 / M past its centre: a corner on a face's middle). */
static int mark_region(const ibl_image *im, const frame *fr, int M, const source_list *src,
                       double margin, double step, uint32_t *table, uint32_t *region)
{
    int W = im->width, H = im->height, marked = 0;
    for (int i = 0, k = 0; i < src->pixels || k < src->texels;) {
        int texel = k < src->texels && (i == src->pixels || better(&src->texel[k], &src->pixel[i]));
        double d[3];
        int added;
        if (texel) {
            uint32_t t = src->texel[k++].index;
            ibl_cube_direction_d((int)(t / ((uint32_t)M * M)), (t % M + 0.5) / M, (t / M % M + 0.5) / M, d);
            unit(d);
            added = mark_disc(M, d, margin + sqrt(2.0) / M, step, table, region + marked);
        } else {
            uint32_t p = src->pixel[i++].index;
            int px = (int)(p % W), py = (int)(p / W);
            picture_direction(fr, IBL_PI * (py + 0.5) / H, IBL_TWO_PI * ((px + 0.5) / W - 0.5), d);
            added = mark_disc(M, d, margin, step, table, region + marked);
        }
        if (marked + added > MAX_REGION_TEXELS) break; /* not this source, nor later ones */
        marked += added;
    }
    return marked;
}

static int by_index(const void *a, const void *b)
{
    uint32_t p = *(const uint32_t *)a, q = *(const uint32_t *)b;
    return p < q ? -1 : p > q;
}

/* A pixel's cells per axis: a quarter of the texel spacing at its centre or less (the texel
 * spacing at unit direction d is 2 / M times the square of d's largest coordinate). It depends
 * on the pixel alone, so that the texels cutting a pixel keep disjoint cells that add up to
 * the whole pixel. Chosen per texel, a pixel cut by texels on either side of a change of k
 * (4 to 5 where the face-plane radius passes 0.52 for a 512x256 image on 128 texels) would lose
 * or double part of its light: 5% of interior.exr's brightest pixel, level 1 of its 256 chain
 * then 0.5-1.2% low around that lamp (tests/test_specular_input.c keeps the case). */
static int pixel_cells(const frame *fr, int M, int W, int H, int x, int y)
{
    double d[3];
    picture_direction(fr, IBL_PI * (y + 0.5) / H, IBL_TWO_PI * ((x + 0.5) / W - 0.5), d);
    double big = fmax(fabs(d[0]), fmax(fabs(d[1]), fabs(d[2])));
    int k = (int)ceil(4.0 * (IBL_PI / H) / (2.0 / M * big * big));
    return k < MIN_CELLS ? MIN_CELLS : k > MAX_CELLS ? MAX_CELLS : k;
}

/* The columns one cell spans in row y: 1 outside the polar caps; in a cap, where a pixel is
 * a wedge much narrower than tall, as many as make a cell about as wide as a k-th of a row
 * (k the row's split in latitude, kp), so that a cell stays within a quarter of a texel both
 * ways without a ring of thousands of cells round the pole. Whole groups of columns from
 * column 0, the last one shorter: the split depends on the row alone, so the texels cutting a
 * group share it (as pixel_cells' k). */
static int cap_columns(int W, int H, int y, double polar, int kp)
{
    double t0 = IBL_PI * y / H, t1 = IBL_PI * (y + 1) / H;
    if (!(t0 < polar || t1 > IBL_PI - polar)) return 1;
    double wide = IBL_TWO_PI / W * fmax(sin(t0), sin(t1)), g = floor(IBL_PI / H / (kp * wide));
    return g < 2 ? 1 : g > W ? W : (int)g;
}

/* The cells of one region texel's input pixels, row y, columns [x0, x1] (past the seam where
 * needed), in a polar cap where `group` columns make a cell: kp rows of cells, each cell the
 * group's pixels' light at its centre. */
static ibl_status cap_row_cells(cell_list *s, const ibl_image *im, const frame *fr, int M,
                                size_t self, int y, int x0, int x1, int group, int kp)
{
    int W = im->width, H = im->height, groups = (W + group - 1) / group;
    double pixel = IBL_PI / H, t0 = pixel * y, t1 = pixel * (y + 1);
    int all = x1 - x0 + 1 + 2 * group >= W; /* (then no group is met twice across the seam) */
    for (int xx = all ? 0 : x0; xx <= (all ? groups - 1 : x1); xx++) {
        int x = ((xx % W) + W) % W, g = all ? xx : x / group;
        if (!all && xx != x0 && x % group) continue; /* the group was taken at its first column */
        int gx0 = g * group, gx1 = gx0 + group < W ? gx0 + group : W;
        double sum[3] = {0, 0, 0};
        for (int c = gx0; c < gx1; c++) {
            const float *p = im->pixels + ((size_t)y * W + c) * 4;
            if (!isfinite(p[0]) || !isfinite(p[1]) || !isfinite(p[2])) continue;
            for (int m = 0; m < 3; m++) sum[m] += p[m];
        }
        double phi = IBL_TWO_PI * (0.5 * (gx0 + gx1) / W - 0.5);
        for (int j = 0; j < kp; j++) {
            double a0 = t0 + (t1 - t0) * j / kp, a1 = t0 + (t1 - t0) * (j + 1) / kp;
            double dw = IBL_TWO_PI / W * (cos(a0) - cos(a1)), q[3];
            picture_direction(fr, 0.5 * (a0 + a1), phi, q);
            if (texel_index(M, q) != self) continue;
            double w[3] = {dw * sum[0], dw * sum[1], dw * sum[2]};
            ibl_status st = add_cell(s, q, w);
            if (st != IBL_OK) return st;
        }
    }
    return IBL_OK;
}

/* The columns [x0, x1] (past the seam where needed) of row y whose pixel centres are within
 * `radius` of the direction at picture angles (tc, pc): by the spherical law of cosines,
 * |phi - pc| <= acos((cos radius - cos theta cos tc) / (sin theta sin tc)), theta the row's
 * centre's (one column more each way). 0 if there are none. */
static int pole_row_columns(int W, int H, int y, double tc, double pc, double radius, int *x0,
                            int *x1)
{
    double th = IBL_PI * (y + 0.5) / H, den = sin(th) * sin(tc), col = IBL_TWO_PI / W;
    double rhs = den > 1e-12 ? (cos(radius) - cos(th) * cos(tc)) / den : (fabs(th - tc) <= radius ? -2.0 : 2.0);
    if (rhs > 1.0) return 0;
    if (rhs <= -1.0) {
        *x0 = 0, *x1 = W - 1;
        return 1;
    }
    double half = acos(rhs);
    *x0 = (int)floor((pc + IBL_PI - half) / col - 0.5) - 1;
    *x1 = (int)floor((pc + IBL_PI + half) / col - 0.5) + 1;
    if (*x1 - *x0 + 1 >= W) *x0 = 0, *x1 = W - 1;
    return 1;
}

/* The cells of one region texel: its own k x k (negative: the working cube's radiance), then
 * those of the input pixels around it whose centres fall in it. */
static ibl_status texel_cells(cell_list *s, const ibl_image *im, const frame *fr,
                              const ibl_cubemap *working, double polar, int face, int tx, int ty)
{
    int M = working->size, W = im->width, H = im->height;
    size_t self = ((size_t)face * M + ty) * M + tx;
    const float *L = ibl_cubemap_face(working, 0, face) + ((size_t)ty * M + tx) * 4;
    double pixel = IBL_PI / H, c[3];
    ibl_cube_direction_d(face, (tx + 0.5) / M, (ty + 0.5) / M, c);
    double c2 = c[0] * c[0] + c[1] * c[1] + c[2] * c[2], texel = 2.0 / M / c2;
    int kt = (int)ceil(4.0 * texel / pixel);
    kt = kt < MIN_CELLS ? MIN_CELLS : kt > MAX_CELLS ? MAX_CELLS : kt;
    double omega = ibl_cube_texel_solid_angle(M, tx, ty), wsum = 0;
    size_t first = 0;
    s->count = 0;
    for (int j = 0; j < kt; j++)
        for (int i = 0; i < kt; i++) {
            double q[3], w[3];
            ibl_cube_direction_d(face, (tx + (i + 0.5) / kt) / M, (ty + (j + 0.5) / kt) / M, q);
            double l2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2], l = sqrt(l2), a = 1.0 / (l2 * l);
            for (int m = 0; m < 3; m++) q[m] /= l, w[m] = -a * L[m];
            wsum += a;
            ibl_status st = add_cell(s, q, w);
            if (st != IBL_OK) return st;
        }
    for (size_t n = first; n < s->count; n++)
        for (int m = 0; m < 3; m++) s->w[n * 3 + m] *= omega / wsum;
    /* the pixels the texel can touch: the picture-angle box of its corners, edge midpoints
     * and centre, one pixel wider (a texel edge bulges in theta between its corners) */
    double tmin = 1e9, tmax = -1e9, pc, tc, pmin = 1e9, pmax = -1e9, cu[3] = {c[0], c[1], c[2]};
    double cos_circ = 1; /* of the largest angle from the centre to the nine points */
    picture_angles(fr, c, &tc, &pc);
    unit(cu);
    for (int j = 0; j <= 2; j++)
        for (int i = 0; i <= 2; i++) {
            double q[3], t, p;
            ibl_cube_direction_d(face, (tx + 0.5 * i) / M, (ty + 0.5 * j) / M, q);
            picture_angles(fr, q, &t, &p);
            unit(q);
            cos_circ = fmin(cos_circ, cu[0] * q[0] + cu[1] * q[1] + cu[2] * q[2]);
            p -= pc;
            p = p > IBL_PI ? p - IBL_TWO_PI : p < -IBL_PI ? p + IBL_TWO_PI : p;
            tmin = fmin(tmin, t), tmax = fmax(tmax, t), pmin = fmin(pmin, p), pmax = fmax(pmax, p);
        }
    int y0 = (int)floor(tmin / pixel) - 1, y1 = (int)floor(tmax / pixel) + 1;
    double col = IBL_TWO_PI / W, base = pc + IBL_PI; /* phi + pi = column units x col */
    int x0 = (int)floor((base + pmin) / col) - 1, x1 = (int)floor((base + pmax) / col) + 1;
    /* a texel on a pole, or close to it, has no box in longitude: from the pole's row (one of
     * its 9 points is within 0.75 texel of any point of it), each row's columns whose pixel
     * centres are near enough its centre for a cell of theirs to be in it */
    int pole = tmin < 2.0 * pixel + 1.5 * 2.0 / M || tmax > IBL_PI - 2.0 * pixel - 1.5 * 2.0 / M;
    double near_pole = acos(fmin(cos_circ, 1.0)) + 0.5 * (pixel + col) + 1e-9;
    if (pole && tmin < IBL_HALF_PI) y0 = 0;
    if (pole && tmax > IBL_HALF_PI) y1 = H - 1;
    y0 = y0 < 0 ? 0 : y0, y1 = y1 >= H ? H - 1 : y1;
    for (int y = y0; y <= y1; y++) {
        double t0 = pixel * y, t1 = pixel * (y + 1);
        if (pole && !pole_row_columns(W, H, y, tc, pc, near_pole, &x0, &x1)) continue;
        int row_k = pixel_cells(fr, M, W, H, 0, y), group = cap_columns(W, H, y, polar, row_k);
        if (group > 1) {
            ibl_status st = cap_row_cells(s, im, fr, M, self, y, x0, x1, group, row_k);
            if (st != IBL_OK) return st;
            continue;
        }
        /* the sines and cosines of the cells' latitudes (for the row's last k) and of the
         * pixel's cells' longitudes: 2 k per pixel, not 2 k^2 */
        int row_kp = 0;
        double sub_st[MAX_CELLS], sub_ct[MAX_CELLS], sub_dw[MAX_CELLS], sp[MAX_CELLS], cp[MAX_CELLS];
        for (int xx = x0; xx <= x1; xx++) {
            int x = ((xx % W) + W) % W;
            const float *p = im->pixels + ((size_t)y * W + x) * 4;
            if (!isfinite(p[0]) || !isfinite(p[1]) || !isfinite(p[2])) continue;
            int kp = pixel_cells(fr, M, W, H, x, y);
            for (int j = 0; kp != row_kp && j < kp; j++) {
                double a0 = t0 + (t1 - t0) * j / kp, a1 = t0 + (t1 - t0) * (j + 1) / kp;
                double am = 0.5 * (a0 + a1);
                sub_dw[j] = IBL_TWO_PI / W / kp * (cos(a0) - cos(a1));
                sub_st[j] = sin(am), sub_ct[j] = cos(am);
            }
            row_kp = kp;
            for (int i = 0; i < kp; i++) {
                double phi = IBL_TWO_PI * ((xx + (i + 0.5) / kp) / W - 0.5);
                sp[i] = sin(phi), cp[i] = cos(phi);
            }
            for (int j = 0; j < kp; j++) {
                double dw = sub_dw[j];
                for (int i = 0; i < kp; i++) {
                    double q[3], w[3] = {dw * p[0], dw * p[1], dw * p[2]};
                    picture_direction_sc(fr, sub_st[j], sub_ct[j], sp[i], cp[i], q);
                    if (texel_index(M, q) != self) continue;
                    ibl_status st = add_cell(s, q, w);
                    if (st != IBL_OK) return st;
                }
            }
        }
    }
    return IBL_OK;
}

static void group_stats(source_group *g)
{
    double c[3] = {0, 0, 0};
    for (size_t n = 0; n < g->count; n++)
        for (int m = 0; m < 3; m++) c[m] += g->cell[n * 6 + m];
    double len = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    for (int m = 0; m < 3; m++) g->centre[m] = c[m] / len;
    double min_cos = 1;
    memset(g->energy, 0, sizeof g->energy);
    memset(g->moment, 0, sizeof g->moment);
    for (size_t n = 0; n < g->count; n++) {
        const double *d = g->cell + n * 6, *w = d + 3;
        double x = d[0] * g->centre[0] + d[1] * g->centre[1] + d[2] * g->centre[2];
        if (x < min_cos) min_cos = x;
        for (int ch = 0; ch < 3; ch++) {
            g->energy[ch] += w[ch];
            for (int m = 0; m < 3; m++) g->moment[ch][m] += w[ch] * (d[m] - g->centre[m]);
        }
    }
    g->radius = acos(min_cos > 1 ? 1 : min_cos) + 1e-9;
}


/* Each region texel's group is made alone (its cells, then their sums), one task each. */
typedef struct group_job {
    ibl_specular_sources *s;
    const ibl_image *image;
    const frame *fr;
    const ibl_cubemap *working;
    const uint32_t *region;
    double polar;
    ibl_status *status; /* per group */
} group_job;

static ibl_status make_group(const group_job *job, int index)
{
    ibl_context *ctx = job->s->ctx;
    int M = job->working->size;
    size_t t = job->region[index];
    source_group *g = &job->s->group[index];
    cell_list cells = {ctx, NULL, NULL, 0, 0};
    ibl_status st = texel_cells(&cells, job->image, job->fr, job->working, job->polar,
                                (int)(t / ((size_t)M * M)), (int)(t % M), (int)(t / M % M));
    if (st == IBL_OK) {
        g->count = cells.count;
        g->cell = ibl_alloc(ctx, (g->count ? g->count : 1) * 6 * sizeof(double));
        if (!g->cell) st = ibl_context_status(ctx);
    }
    if (st == IBL_OK) {
        for (size_t n = 0; n < g->count; n++) {
            memcpy(g->cell + n * 6, cells.dir + n * 3, 3 * sizeof(double));
            memcpy(g->cell + n * 6 + 3, cells.w + n * 3, 3 * sizeof(double));
        }
        group_stats(g);
        g->padded = (g->count + NEAR_LANES - 1) / NEAR_LANES * NEAR_LANES;
        g->lanes = ibl_calloc(ctx, (g->padded ? g->padded : 1) * 6, sizeof(float));
        if (!g->lanes) st = ibl_context_status(ctx);
    }
    if (st == IBL_OK)
        for (size_t n = 0; n < g->count; n++)
            for (int m = 0; m < 3; m++) {
                g->lanes[m * g->padded + n] = (float)(g->cell[n * 6 + m] - g->centre[m]);
                g->lanes[(3 + m) * g->padded + n] = (float)g->cell[n * 6 + 3 + m];
            }
    ibl_free(ctx, cells.dir);
    ibl_free(ctx, cells.w);
    return st;
}

static void group_task(void *arg, int index)
{
    const group_job *job = arg;
    job->status[index] = make_group(job, index);
}

static ibl_status build(ibl_specular_sources *s, const ibl_image *image, const frame *fr,
                        const ibl_cubemap *working, double lobe_normaliser_min)
{
    ibl_context *ctx = s->ctx;
    int M = working->size, H = image->height;
    double mean_lum = 0;
    ibl_status st = image_mean_luminance(ctx, image, &mean_lum);
    if (st != IBL_OK) return st;
    if (!(mean_lum > 0) || !isfinite(mean_lum)) return IBL_OK;
    double step = fmin(IBL_PI / H, 2.0 / (3.0 * M)) / 2.0;
    double margin = MARGIN_PIXELS * IBL_PI / H + step, polar = polar_cap(M, H, margin);
    double bar = BRIGHT_PEAK_SHARE * mean_lum * lobe_normaliser_min;
    /* one source's disc adds at most (2 half + 1)^2 texels past MAX_REGION_TEXELS; the polar
     * texels' discs are wider, and left out where they would not fit */
    int half = disc_half(margin, step), polar_half = disc_half(margin + sqrt(2.0) / M, step);
    size_t disc = (size_t)(2 * half + 1) * (2 * half + 1);
    size_t polar_disc = (size_t)(2 * polar_half + 1) * (2 * polar_half + 1);
    if (MAX_REGION_TEXELS + disc > REGION_HASH / 2) return IBL_OK; /* a step far below a texel */
    int polar_sources = MAX_REGION_TEXELS + polar_disc <= REGION_HASH / 2;
    if (polar_sources) disc = polar_disc;
    int square = 2 * polar_square(M, polar_reach(M, H, polar)) + 1;
    int polar_capacity = polar_sources ? 2 * square * square : 0;
    candidate *c = ibl_alloc(ctx, MAX_SOURCE_PIXELS * sizeof *c);
    candidate *pc = ibl_alloc(ctx, (size_t)(polar_capacity ? polar_capacity : 1) * sizeof *pc);
    uint32_t *table = ibl_alloc(ctx, REGION_HASH * sizeof(uint32_t));
    uint32_t *region = ibl_alloc(ctx, (MAX_REGION_TEXELS + disc) * sizeof(uint32_t));
    ibl_status *status = NULL;
    source_list src = {c, pc, 0, 0};
    if (!c || !pc || !table || !region) {
        st = ibl_context_status(ctx);
        goto done;
    }
    st = find_sources(ctx, image, bar, polar, c, &src.pixels);
    if (st != IBL_OK) goto done;
    if (polar_sources) src.texels = find_polar_sources(working, fr, H, bar, polar, pc, polar_capacity);
    memset(table, 0xff, REGION_HASH * sizeof(uint32_t));
    int marked = mark_region(image, fr, M, &src, margin, step, table, region);
    qsort(region, (size_t)marked, sizeof *region, by_index); /* groups in (face, y, x) order */
    s->group = ibl_calloc(ctx, (size_t)(marked ? marked : 1), sizeof *s->group);
    status = ibl_alloc(ctx, (size_t)(marked ? marked : 1) * sizeof *status);
    if (!s->group || !status) {
        st = ibl_context_status(ctx);
        goto done;
    }
    s->groups = marked; /* (every group is freed by destroy, made or not) */
    group_job job = {s, image, fr, working, region, polar, status};
    ibl_parallel_for(ctx, marked, group_task, &job);
    for (int i = 0; i < marked && st == IBL_OK; i++) st = status[i];
done:
    ibl_free(ctx, status);
    ibl_free(ctx, region);
    ibl_free(ctx, table);
    ibl_free(ctx, pc);
    ibl_free(ctx, c);
    return st;
}

void ibl_specular_sources_destroy(ibl_specular_sources *s)
{
    if (!s) return;
    for (int g = 0; g < s->groups; g++) {
        ibl_free(s->ctx, s->group[g].cell);
        ibl_free(s->ctx, s->group[g].lanes);
    }
    ibl_free(s->ctx, s->group);
    ibl_free(s->ctx, s);
}

static void lobe_task(void *arg, int level)
{
    ibl_specular_sources *s = arg;
    s->refined[level] = level_refined(&s->info, s->working_size, level, &s->lobe[level]);
}

ibl_status ibl_specular_sources_create(ibl_context *ctx, const ibl_image *image,
                                       const ibl_to_cube_desc *conversion,
                                       const ibl_cubemap *working, const ibl_specular_desc *desc,
                                       ibl_specular_sources **out)
{
    if (!out) return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "specular sources: no output");
    *out = NULL;
    if (!image || !image->pixels || !working || !working->data || !desc)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "specular sources: missing image, cube or desc");
    ibl_specular_sources *s = ibl_alloc(ctx, sizeof *s);
    if (!s) return ibl_context_status(ctx);
    memset(s, 0, sizeof *s);
    s->ctx = ctx;
    s->working_size = working->size;
    ibl_layout layout = conversion && conversion->layout ? conversion->layout
                                                         : ibl_layout_detect(image->width, image->height);
    int lobes = desc->filter == IBL_FILTER_GGX || desc->filter == IBL_FILTER_PHONG ||
                desc->filter == IBL_FILTER_BLINN;
    ibl_status st = IBL_OK;
    if (layout == IBL_LAYOUT_EQUIRECT && lobes && desc->edge_fixup == IBL_EDGE_FIXUP_NONE &&
        !desc->dynamic && image->width >= 8 && image->height >= 4 &&
        (size_t)image->width * image->height <= UINT32_MAX) {
        st = ibl_specular_levels(ctx, desc, working->size, &s->info);
        if (st == IBL_OK) ibl_parallel_for(ctx, s->info.levels, lobe_task, s);
        double narrowest = 0;
        for (int l = 0; st == IBL_OK && l < s->info.levels; l++) {
            if (!s->refined[l]) continue;
            double n = ibl__sources_lobe_normaliser(&s->lobe[l]);
            if (narrowest == 0 || n < narrowest) narrowest = n;
        }
        if (st == IBL_OK && narrowest > 0) {
            frame fr;
            ibl_orientation o = {0};
            if (conversion) o = conversion->orientation;
            frame_make(&o, &fr);
            st = build(s, image, &fr, working, narrowest);
        }
    }
    if (st != IBL_OK) {
        ibl_specular_sources_destroy(s);
        return st;
    }
    *out = s;
    return IBL_OK;
}

int ibl_specular_sources_count(const ibl_specular_sources *s)
{
    return s ? s->groups : 0;
}

ibl_status ibl_specular_prefilter_image(ibl_context *ctx, const ibl_image *image,
                                        const ibl_to_cube_desc *conversion,
                                        const ibl_specular_desc *desc, ibl_cubemap *out,
                                        ibl_specular_info *info)
{
    ibl_specular_desc zero = {0};
    ibl_cubemap working;
    memset(&working, 0, sizeof working);
    if (out) memset(out, 0, sizeof *out);
    if (!desc) desc = &zero;
    ibl_to_cube_desc cd = {0};
    if (conversion) cd = *conversion;
    ibl_status st = ibl_image_to_cubemap(ctx, image, &cd, &working);
    if (st != IBL_OK) return st;
    ibl_specular_sources *sources = NULL;
    st = ibl_specular_sources_create(ctx, image, &cd, &working, desc, &sources);
    if (st == IBL_OK) st = ibl_specular_prefilter(ctx, &working, desc, out, info);
    if (st == IBL_OK) st = ibl_specular_sources_apply(sources, out);
    ibl_specular_sources_destroy(sources);
    ibl_cubemap_free(ctx, &working);
    if (st != IBL_OK && out) ibl_cubemap_free(ctx, out);
    return st;
}
