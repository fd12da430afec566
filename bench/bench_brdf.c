/* BRDF table timings (medians) and the numbers quoted in docs/BRDF.md.
 *   bench_brdf [DATA_DIR] [--accuracy] [--study]
 * DATA_DIR is ignored (the tables need no input). --accuracy prints the quadrature error of
 * the default order (against order 96); --study the tri-Ace BRDF's directional-albedo study and
 * the "Rd (1 - value)" shortcut error. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "ibl/ibl.h"

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

static double cpu_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

static int cmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

enum { RUNS = 15 };

/* Wall-clock median (what the budget, under 100 ms on 2 cores for the 128x128 split-sum table
 * and the 32x32x16 AmbientBRDF volume, is about) and the median CPU time summed over threads
 * (the work, less sensitive to other processes on the shared cores). */
static void report(const char *label, int threads, double *t, double *c)
{
    qsort(t, RUNS, sizeof t[0], cmp);
    qsort(c, RUNS, sizeof c[0], cmp);
    printf("%-38s threads %d  wall median %7.1f ms (min %6.1f)  cpu median %7.1f ms\n", label,
           threads, t[RUNS / 2] * 1e3, t[0] * 1e3, c[RUNS / 2] * 1e3);
}

static void bench_lut(int threads, const char *label, ibl_brdf_lut_desc d)
{
    ibl_context_desc cd = {.threads = threads};
    ibl_context *ctx;
    if (ibl_context_create(&cd, &ctx) != IBL_OK) exit(1);
    double t[RUNS], c[RUNS];
    for (int r = 0; r < RUNS; r++) {
        ibl_image im;
        double t0 = now(), c0 = cpu_now();
        if (ibl_brdf_lut(ctx, &d, &im) != IBL_OK) exit(1);
        t[r] = now() - t0;
        c[r] = cpu_now() - c0;
        ibl_image_free(ctx, &im);
    }
    report(label, threads, t, c);
    ibl_context_destroy(ctx);
}

static void bench_ambient(int threads, int volume)
{
    ibl_context_desc cd = {.threads = threads};
    ibl_context *ctx;
    if (ibl_context_create(&cd, &ctx) != IBL_OK) exit(1);
    ibl_ambient_brdf_desc d = {.size_nv = 32, .size_shininess = 32, .size_f0 = 16};
    double t[RUNS], c[RUNS];
    for (int r = 0; r < RUNS; r++) {
        double t0 = now(), c0 = cpu_now();
        if (volume) {
            ibl_texture tex;
            if (ibl_ambient_brdf_volume(ctx, &d, &tex) != IBL_OK) exit(1);
            t[r] = now() - t0;
            ibl_texture_free(ctx, &tex);
        } else {
            ibl_image im;
            if (ibl_ambient_brdf_table(ctx, &d, &im) != IBL_OK) exit(1);
            t[r] = now() - t0;
            ibl_image_free(ctx, &im);
        }
        c[r] = cpu_now() - c0;
    }
    report(volume ? "ambient-brdf volume 32x32x16" : "ambient-brdf 2D table 32x32 (X, Y)", threads,
           t, c);
    ibl_context_destroy(ctx);
}

/* The tables `ibl bake` computes in its "brdf" stage (src/bake/bake.c stage_brdf): the
 * 128x128 split-sum table, the 128x128 (E, E_avg, sheen, sheen_avg) table and the 32x32x16
 * AmbientBRDF volume (here over the volume's default shininess range; the bake widens it by
 * half a row at each end, which does not change the work). */
static void bench_bake_stage(int threads)
{
    ibl_context_desc cd = {.threads = threads};
    ibl_context *ctx;
    if (ibl_context_create(&cd, &ctx) != IBL_OK) exit(1);
    ibl_brdf_lut_desc split = {.size = 128};
    ibl_brdf_lut_desc extra = {.size = 128,
                               .channels = {IBL_BRDF_ALBEDO, IBL_BRDF_ALBEDO_AVG, IBL_BRDF_SHEEN,
                                            IBL_BRDF_SHEEN_AVG}};
    ibl_ambient_brdf_desc ad = {.size_shininess = 32};
    double t[RUNS], c[RUNS];
    for (int r = 0; r < RUNS; r++) {
        ibl_image a, b;
        ibl_texture v;
        double t0 = now(), c0 = cpu_now();
        if (ibl_brdf_lut(ctx, &split, &a) != IBL_OK || ibl_brdf_lut(ctx, &extra, &b) != IBL_OK ||
            ibl_ambient_brdf_volume(ctx, &ad, &v) != IBL_OK)
            exit(1);
        t[r] = now() - t0;
        c[r] = cpu_now() - c0;
        ibl_image_free(ctx, &a);
        ibl_image_free(ctx, &b);
        ibl_texture_free(ctx, &v);
    }
    report("bake table stage (the three above)", threads, t, c);
    ibl_context_destroy(ctx);
}

/* Directional albedo (F = 1) of the tri-Ace specular term under both normalisations, and
 * the diffuse shortcut error, on a few rows. */
static void study(void)
{
    const double mus[] = {0.02, 0.1, 0.25, 0.5, 0.75, 1.0};
    const double ss[] = {1, 2, 5, 10, 30, 100, 300, 1000, 2000};
    for (int n = 0; n < 2; n++) {
        printf("\nspecular albedo, F = 1, %s normalisation\n  s \\ n.v",
               n ? "exact (s+2)(s+4)/(8pi(2^-s/2+s))" : "triace 0.0397436 s + 0.0856832");
        for (int i = 0; i < 6; i++) printf("  %6.2f", mus[i]);
        printf("   norm\n");
        for (int k = 0; k < 9; k++) {
            printf("  %6g ", ss[k]);
            for (int i = 0; i < 6; i++)
                printf("  %6.3f", ibl_ambient_brdf(mus[i], ss[k], 1.0, (ibl_blinn_normalization)n, 48));
            printf("   %.4f\n", ibl_blinn_normalization_factor((ibl_blinn_normalization)n, ss[k]));
        }
    }
    /* where does each normalisation exceed 1 (energy gain) on a fine grid */
    for (int n = 0; n < 2; n++) {
        double worst = 0, wm = 0, ws = 0;
        int over = 0, total = 0;
        for (int k = 0; k <= 40; k++) {
            double s = exp(log(2000.0) * k / 40.0);
            for (int i = 1; i <= 40; i++) {
                double mu = i / 40.0, e = ibl_ambient_brdf(mu, s, 1.0, (ibl_blinn_normalization)n, 0);
                total++;
                if (e > 1) over++;
                if (e > worst) worst = e, wm = mu, ws = s;
            }
        }
        printf("\n%s: albedo > 1 at %d of %d grid points (s log 1..2000, n.v 0.025..1); max %.4f at n.v %.3f s %.1f\n",
               n ? "exact" : "triace", over, total, worst, wm, ws);
    }
    /* diffuse: exact factor (1 - F0) vs the shortcut 1 - AmbientBRDF */
    const double f0s[] = {0.02, 0.04, 0.1, 0.5, 0.9};
    printf("\ndiffuse shortcut (1 - AmbientBRDF) minus exact (1 - F0), triace normalisation\n");
    for (int f = 0; f < 5; f++) {
        double lo = 1e9, hi = -1e9, lm = 0, ls = 0, hm = 0, hs = 0;
        for (int k = 0; k <= 20; k++) {
            double s = exp(log(2000.0) * k / 20.0);
            for (int i = 1; i <= 20; i++) {
                double mu = i / 20.0;
                double diff = (1 - ibl_ambient_brdf(mu, s, f0s[f], IBL_BLINN_TRIACE_FIT, 0)) - (1 - f0s[f]);
                if (diff < lo) lo = diff, lm = mu, ls = s;
                if (diff > hi) hi = diff, hm = mu, hs = s;
            }
        }
        printf("  F0 %.2f: min %+.4f (n.v %.2f, s %.0f)  max %+.4f (n.v %.2f, s %.0f)\n", f0s[f], lo,
               lm, ls, hi, hm, hs);
    }
}

/* Largest |order 24 - order 96| over every texel of 128x128 tables (and 128x128 AmbientBRDF
 * 2D tables over log 1..2000), i.e. the quadrature error of the defaults. */
static double max_diff(const ibl_image *a, const ibl_image *b, int channels)
{
    double m = 0;
    for (size_t i = 0; i < (size_t)a->width * a->height; i++)
        for (int c = 0; c < channels; c++) {
            double d = fabs((double)a->pixels[i * 4 + c] - b->pixels[i * 4 + c]);
            if (d > m) m = d;
        }
    return m;
}

static void accuracy(void)
{
    ibl_context *ctx;
    if (ibl_context_create(NULL, &ctx) != IBL_OK) exit(1);
    struct {
        const char *label;
        ibl_brdf_lut_desc d;
    } cases[] = {
        {"splitsum (A, B)", {.size = 128}},
        {"splitsum-separable (A, B)", {.size = 128, .visibility = IBL_VISIBILITY_SEPARABLE}},
        {"multiscatter (E, E_avg)", {.size = 128, .channels = {IBL_BRDF_ALBEDO, IBL_BRDF_ALBEDO_AVG}}},
        {"sheen (E, E_avg)", {.size = 128, .channels = {IBL_BRDF_SHEEN, IBL_BRDF_SHEEN_AVG}}},
    };
    printf("\nquadrature error: max |order 24 - order 96| over every texel\n");
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        ibl_image lo, hi;
        ibl_brdf_lut_desc d = cases[c].d;
        d.order = 24;
        if (ibl_brdf_lut(ctx, &d, &lo) != IBL_OK) exit(1);
        d.order = 96;
        if (ibl_brdf_lut(ctx, &d, &hi) != IBL_OK) exit(1);
        printf("  %-36s 128x128   %.2e\n", cases[c].label, max_diff(&lo, &hi, 2));
        ibl_image_free(ctx, &lo);
        ibl_image_free(ctx, &hi);
    }
    for (int n = 0; n < 2; n++) {
        ibl_ambient_brdf_desc ad = {.size_nv = 128, .size_shininess = 128,
                                    .normalization = (ibl_blinn_normalization)n, .order = 24};
        ibl_image lo, hi;
        if (ibl_ambient_brdf_table(ctx, &ad, &lo) != IBL_OK) exit(1);
        ad.order = 96;
        if (ibl_ambient_brdf_table(ctx, &ad, &hi) != IBL_OK) exit(1);
        printf("  ambient-brdf (X, Y), %-15s 128x128   %.2e\n", n ? "exact norm" : "triace norm",
               max_diff(&lo, &hi, 2));
        ibl_image_free(ctx, &lo);
        ibl_image_free(ctx, &hi);
    }
    ibl_context_destroy(ctx);
}

int main(int argc, char **argv)
{
    int do_study = 0, do_accuracy = 0;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--study") == 0) do_study = 1;
        if (strcmp(argv[i], "--accuracy") == 0) do_accuracy = 1;
    }
    ibl_brdf_lut_desc split = {.size = 128};
    ibl_brdf_lut_desc sep = {.size = 128, .visibility = IBL_VISIBILITY_SEPARABLE};
    ibl_brdf_lut_desc ms = {.size = 128, .channels = {IBL_BRDF_ALBEDO, IBL_BRDF_ALBEDO_AVG}};
    ibl_brdf_lut_desc sheen = {.size = 128, .channels = {IBL_BRDF_SHEEN, IBL_BRDF_SHEEN_AVG}};
    for (int t = 2; t >= 1; t--) {
        bench_lut(t, "splitsum 128x128 (A, B)", split);
        bench_lut(t, "splitsum-separable 128x128", sep);
        bench_lut(t, "multiscatter 128x128 (E, E_avg)", ms);
        bench_lut(t, "sheen 128x128 (E, E_avg)", sheen);
        bench_ambient(t, 1);
        bench_ambient(t, 0);
        bench_bake_stage(t);
    }
    if (do_accuracy) accuracy();
    if (do_study) study();
    return 0;
}
