/* A GGX chain's error against the exact integral over its INPUT image (docs/SPECULAR.md
 * "Accuracy against the input"), not over the working cube the prefilter converts it to: the
 * end-to-end error of `ibl prefilter`, conversion included.
 *
 *   bench_input_accuracy INPUT.exr CHAIN.ktx2 [--samples N] [--bright N] [--threads N]
 *                        [--max-level L] [--cube WORK.ktx2]
 *
 * INPUT is an equirect image (2:1); CHAIN is what `ibl prefilter INPUT -o CHAIN.ktx2
 * --format rgba32f` wrote (a GGX chain; its KTX2 metadata gives each level's roughness).
 * For every filtered level it samples the level's `--bright` brightest texels (default 50)
 * and `--samples` more at deterministic pseudo-random places (default 200), and evaluates at
 * each texel centre R, in double, the ratio
 *     sum_p L_p f(R . l_p) dw_p / sum_p f(R . l_p) dw_p
 * over every pixel p of the input: l_p its centre direction, dw_p its exact solid angle
 * (2 pi / W)(cos theta0 - cos theta1), f the GGX lobe of the level written out below. This is
 * the midpoint rule of the integral of the image taken as constant over each pixel; where the
 * lobe is narrower than 16 pixels, each pixel within 16 max(alpha, pixel) of R is split into
 * 8 x 8 sub-cells with their own centres and exact solid angles, so the lobe's core is
 * integrated to ~1e-4. Printed per level: the worst channel's relative RMS over the sampled
 * texels, sqrt(sum (chain - exact)^2 / sum exact^2), and the largest texel error relative to
 * max(exact, level mean), both for all samples and for the bright ones alone. With --cube (the
 * working cube the chain was filtered from, one level, rgba32f) the error over all samples is
 * split in two: the library's reference integral over that cube against the exact one over the
 * input (the conversion's share) and the chain against that cube integral (the filter's). */
#include "ibl/ibl.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const double PI = 3.14159265358979323846;
enum { SPLIT = 8 };

/* GGX as the prefilter's kernel (Walter et al. 2007, "Microfacet Models for Refraction through
 * Rough Surfaces"; the split-sum prefilter of Karis 2013 with n = v = R): with x = R . l and
 * (n.h)^2 = (1 + x)/2, f = x D(h)/D(n) = x alpha^4 / t^2, t = alpha^2 + (1 - x)(1 - alpha^2)/2;
 * 0 for x <= 0. */
static double ggx_lobe(double x, double alpha2)
{
    if (x <= 0) return 0;
    double t = alpha2 + (1.0 - x) * (1.0 - alpha2) * 0.5;
    return x * alpha2 * alpha2 / (t * t);
}

typedef struct equirect {
    int W, H;
    const float *pixels;
    double *cos_theta, *sin_theta; /* H + 1 row borders */
    double *sin_phi, *cos_phi;     /* W pixel centres   */
} equirect;

/* Direction of (theta from +Y, phi) in the library's equirect convention (docs/CONVENTIONS.md:
 * the centre column looks toward -Z, the right quarter toward +X, the top row is +Y). */
static void eq_direction(double st, double ct, double sp, double cp, double d[3])
{
    d[0] = st * sp;
    d[1] = ct;
    d[2] = -st * cp;
}

static void exact_at(const equirect *e, const double R[3], double alpha2, double out[3])
{
    int W = e->W, H = e->H;
    double alpha = sqrt(alpha2), pixel = PI / H;
    /* a lobe 16 pixels wide or more is smooth on a pixel: the midpoint rule's error of the
     * integral is then O((pixel / alpha)^2 / 24) at most, far below the bars */
    double window = alpha < 16.0 * pixel ? 16.0 * (alpha > pixel ? alpha : pixel) : 0.0;
    double cos_window = window > 0 ? cos(window) : 2.0;
    double num[3] = {0, 0, 0}, den = 0;
    for (int y = 0; y < H; y++) {
        double t0 = PI * y / H, t1 = PI * (y + 1) / H, tc = 0.5 * (t0 + t1);
        double st = sin(tc), ct = cos(tc);
        double dw = 2.0 * PI / W * (e->cos_theta[y] - e->cos_theta[y + 1]);
        const float *row = e->pixels + (size_t)y * W * 4;
        for (int x = 0; x < W; x++) {
            double d[3];
            eq_direction(st, ct, e->sin_phi[x], e->cos_phi[x], d);
            double c = R[0] * d[0] + R[1] * d[1] + R[2] * d[2];
            double w;
            if (c > cos_window - 2 * pixel) {
                /* the lobe's core: SPLIT x SPLIT sub-cells, each at its own centre */
                w = 0;
                for (int sy = 0; sy < SPLIT; sy++) {
                    double a0 = t0 + (t1 - t0) * sy / SPLIT, a1 = t0 + (t1 - t0) * (sy + 1) / SPLIT;
                    double am = 0.5 * (a0 + a1), sdw = 2.0 * PI / W / SPLIT * (cos(a0) - cos(a1));
                    for (int sx = 0; sx < SPLIT; sx++) {
                        double phi = 2.0 * PI * ((x + (sx + 0.5) / SPLIT) / W - 0.5), sd[3];
                        eq_direction(sin(am), cos(am), sin(phi), cos(phi), sd);
                        w += sdw * ggx_lobe(R[0] * sd[0] + R[1] * sd[1] + R[2] * sd[2], alpha2);
                    }
                }
            } else {
                w = dw * ggx_lobe(c, alpha2);
            }
            if (w == 0) continue;
            for (int k = 0; k < 3; k++) num[k] += w * row[(size_t)x * 4 + k];
            den += w;
        }
    }
    for (int k = 0; k < 3; k++) out[k] = num[k] / den;
}

typedef struct job {
    const equirect *e;
    double alpha2;
    const double (*dirs)[3];
    double (*out)[3];
    /* with --cube: the library's reference integral over the working cube at the same texels */
    const ibl_specular_reference *cube_ref;
    const ibl_specular_info *info;
    int level;
    double (*cube_out)[3];
} job;

static void exact_task(void *arg, int index)
{
    const job *j = arg;
    exact_at(j->e, j->dirs[index], j->alpha2, j->out[index]);
    if (j->cube_ref) {
        const double *d = j->dirs[index];
        double v[4];
        ibl_specular_reference_eval(j->cube_ref, j->info, j->level,
                                    (ibl_vec3){(float)d[0], (float)d[1], (float)d[2]}, v);
        for (int k = 0; k < 3; k++) j->cube_out[index][k] = v[k];
    }
}

/* the indices of the `count` largest values, largest first (insertion into a short list) */
static void brightest(const double *lum, size_t total, size_t count, size_t *out)
{
    size_t have = 0;
    if (count == 0) return;
    for (size_t i = 0; i < total; i++) {
        if (have == count && lum[i] <= lum[out[have - 1]]) continue;
        size_t at = have < count ? have++ : count - 1;
        while (at > 0 && lum[out[at - 1]] < lum[i]) {
            out[at] = out[at - 1];
            at--;
        }
        out[at] = i;
    }
}

/* Worst channel's relative RMS and largest relative error of got against want over the first
 * `end` samples, relative to max(want, mean). */
static void error_stats(const double (*got)[3], const double (*want)[3], int end, double mean,
                        double *worst_rms, double *worst_max)
{
    *worst_rms = 0, *worst_max = 0;
    for (int k = 0; k < 3; k++) {
        double e2 = 0, r2 = 0;
        for (int s = 0; s < end; s++) {
            double err = fabs(got[s][k] - want[s][k]);
            e2 += err * err, r2 += want[s][k] * want[s][k];
            double rel = err / (want[s][k] > mean ? want[s][k] : mean);
            if (rel > *worst_max) *worst_max = rel;
        }
        double rms = r2 > 0 ? sqrt(e2 / r2) : 0;
        if (rms > *worst_rms) *worst_rms = rms;
    }
}

static int measure_level(ibl_context *ctx, const equirect *e, const ibl_cubemap *chain, int level,
                         const ibl_specular_info *info, const ibl_specular_reference *cube_ref,
                         int bright, int samples)
{
    double roughness = info->roughness[level];
    int n = ibl_level_size(chain->size, level);
    size_t total = 6 * (size_t)n * n;
    double *lum = malloc(total * sizeof(double)), mean = 0;
    const float *base = ibl_cubemap_face(chain, level, 0);
    for (size_t i = 0; i < total; i++) {
        lum[i] = 0.2126 * base[i * 4] + 0.7152 * base[i * 4 + 1] + 0.0722 * base[i * 4 + 2];
        mean += (base[i * 4] + base[i * 4 + 1] + base[i * 4 + 2]) / 3.0;
    }
    mean /= (double)total;
    if ((size_t)bright > total) bright = (int)total;
    int count = bright + samples;
    size_t *idx = malloc((size_t)count * sizeof(size_t));
    brightest(lum, total, (size_t)bright, idx);
    unsigned long long state = 0x9E3779B97F4A7C15ull ^ (unsigned long long)(level * 7919 + n);
    for (int s = bright; s < count; s++) {
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        idx[s] = (size_t)((state >> 33) % total);
    }
    double (*dirs)[3] = malloc((size_t)count * sizeof *dirs), (*ref)[3] = malloc((size_t)count * sizeof *ref);
    double (*got)[3] = malloc((size_t)count * sizeof *got), (*cube)[3] = malloc((size_t)count * sizeof *cube);
    for (int s = 0; s < count; s++) {
        size_t t = idx[s];
        int f = (int)(t / ((size_t)n * n)), y = (int)(t / n % n), x = (int)(t % n);
        ibl_vec3 d = ibl_cube_texel_direction(f, n, x, y);
        double len = sqrt((double)d.x * d.x + (double)d.y * d.y + (double)d.z * d.z);
        dirs[s][0] = d.x / len, dirs[s][1] = d.y / len, dirs[s][2] = d.z / len;
        for (int k = 0; k < 3; k++) got[s][k] = base[t * 4 + k];
    }
    double a = roughness * roughness;
    job j = {e, a * a, (const double(*)[3])dirs, ref, cube_ref, info, level, cube};
    ibl_parallel_for(ctx, count, exact_task, &j);
    double rms[2], max[2];
    for (int set = 0; set < 2; set++)
        error_stats((const double(*)[3])got, (const double(*)[3])ref, set == 0 ? count : bright, mean,
                    &rms[set], &max[set]);
    printf("| %d | %d | %.3f | %.3f%% | %.2f%% | %.3f%% | %.2f%% |", chain->size, level, roughness,
           100 * rms[0], 100 * max[0], 100 * rms[1], 100 * max[1]);
    if (cube_ref) {
        double conv_rms, conv_max, filt_rms, filt_max;
        error_stats((const double(*)[3])cube, (const double(*)[3])ref, count, mean, &conv_rms, &conv_max);
        error_stats((const double(*)[3])got, (const double(*)[3])cube, count, mean, &filt_rms, &filt_max);
        printf(" %.3f%% / %.2f%% | %.3f%% / %.2f%% |", 100 * conv_rms, 100 * conv_max, 100 * filt_rms,
               100 * filt_max);
    }
    printf("\n");
    fflush(stdout);
    free(lum);
    free(idx);
    free(dirs);
    free(ref);
    free(got);
    free(cube);
    return 0;
}

int main(int argc, char **argv)
{
    const char *in = NULL, *chain_path = NULL, *cube_path = NULL;
    int samples = 200, bright = 50, threads = 0, max_level = 1 << 20;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--samples") && i + 1 < argc) samples = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--bright") && i + 1 < argc) bright = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--threads") && i + 1 < argc) threads = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--max-level") && i + 1 < argc) max_level = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--cube") && i + 1 < argc) cube_path = argv[++i];
        else if (!in) in = argv[i];
        else chain_path = argv[i];
    }
    if (!in || !chain_path) {
        fprintf(stderr, "usage: bench_input_accuracy INPUT.exr CHAIN.ktx2 [--samples N] [--bright N] [--threads N] [--max-level L]\n");
        return 2;
    }
    ibl_context_desc cd = {.threads = threads};
    ibl_context *ctx = NULL;
    if (ibl_context_create(&cd, &ctx) != IBL_OK) return 1;
    ibl_image img;
    ibl_texture tex;
    ibl_cubemap chain;
    ibl_specular_info info;
    if (ibl_read_image(ctx, in, NULL, &img, NULL) != IBL_OK || ibl_read_texture(ctx, chain_path, NULL, &tex, NULL) != IBL_OK ||
        ibl_cubemap_from_texture(&tex, &chain) != IBL_OK ||
        ibl_specular_info_from_metadata(ctx, &tex, chain_path, &info) != IBL_OK) {
        fprintf(stderr, "bench_input_accuracy: %s\n", ibl_context_message(ctx));
        return 1;
    }
    if (img.width != 2 * img.height || info.filter != IBL_FILTER_GGX) {
        fprintf(stderr, "bench_input_accuracy: needs a 2:1 equirect and a GGX chain\n");
        return 1;
    }
    equirect e = {img.width, img.height, img.pixels, NULL, NULL, NULL, NULL};
    e.cos_theta = malloc((size_t)(e.H + 1) * sizeof(double));
    e.sin_theta = malloc((size_t)(e.H + 1) * sizeof(double));
    e.sin_phi = malloc((size_t)e.W * sizeof(double));
    e.cos_phi = malloc((size_t)e.W * sizeof(double));
    for (int y = 0; y <= e.H; y++) e.cos_theta[y] = cos(PI * y / e.H), e.sin_theta[y] = sin(PI * y / e.H);
    for (int x = 0; x < e.W; x++) {
        double phi = 2.0 * PI * ((x + 0.5) / e.W - 0.5);
        e.sin_phi[x] = sin(phi), e.cos_phi[x] = cos(phi);
    }
    /* the convention above against the library's own, at a few pixel centres */
    for (int probe = 0; probe < 4; probe++) {
        int x = (probe * 911 + 17) % e.W, y = (probe * 373 + 5) % e.H;
        double tc = PI * (y + 0.5) / e.H, d[3];
        eq_direction(sin(tc), cos(tc), e.sin_phi[x], e.cos_phi[x], d);
        ibl_vec3 lib;
        ibl_layout_direction(IBL_LAYOUT_EQUIRECT, (float)((x + 0.5) / e.W), (float)((y + 0.5) / e.H), &lib);
        if (fabs(d[0] - lib.x) + fabs(d[1] - lib.y) + fabs(d[2] - lib.z) > 1e-4) {
            fprintf(stderr, "bench_input_accuracy: equirect convention mismatch\n");
            return 1;
        }
    }
    printf("%s against %s (%dx%d): %d brightest + %d sampled texels a level\n\n", chain_path, in, e.W, e.H,
           bright, samples);
    /* --cube WORK.ktx2: the working cube the chain was filtered from (one level); the error
     * is then split into the conversion's share (the reference integral over the cube against
     * the exact one over the input) and the filter's (the chain against the cube's integral) */
    ibl_texture cube_tex = {0};
    ibl_cubemap cube;
    ibl_specular_reference *cube_ref = NULL;
    if (cube_path && (ibl_read_texture(ctx, cube_path, NULL, &cube_tex, NULL) != IBL_OK ||
                      ibl_cubemap_from_texture(&cube_tex, &cube) != IBL_OK ||
                      ibl_specular_reference_create(ctx, &cube, &cube_ref) != IBL_OK)) {
        fprintf(stderr, "bench_input_accuracy: %s\n", ibl_context_message(ctx));
        return 1;
    }
    printf("| size | level | roughness | RMS (all) | max (all) | RMS (bright) | max (bright) |%s\n",
           cube_ref ? " conversion RMS / max | filter RMS / max |" : "");
    printf("|---|---|---|---|---|---|---|%s\n", cube_ref ? "---|---|" : "");
    for (int l = 0; l < chain.levels && l <= max_level; l++) {
        if (!(info.roughness[l] > 0)) continue;
        measure_level(ctx, &e, &chain, l, &info, cube_ref, bright, samples);
    }
    if (cube_ref) ibl_specular_reference_destroy(cube_ref);
    if (cube_path) ibl_texture_free(ctx, &cube_tex);
    free(e.cos_theta);
    free(e.sin_theta);
    free(e.sin_phi);
    free(e.cos_phi);
    ibl_texture_free(ctx, &tex);
    ibl_image_free(ctx, &img);
    ibl_context_destroy(ctx);
    return 0;
}
