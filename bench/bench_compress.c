/* BC6H encoding: speed and quality on cube chains (KTX2 files of float texels, e.g. written
 * by `ibl prefilter X.exr -o X.ktx2 --format rgba32f --size 256`).
 *   build/bench/bench_compress [-j THREADS] [--runs N] CHAIN.ktx2 ...
 * For each file and quality: the median encode time of the whole chain (all levels and
 * faces, through the context's parallel-for), then per level the RMS of log2(1 + x)
 * differences (RGB) and the mPSNR (Munkberg et al. 2006: exposures c = -8..+4 stops,
 * T(x) = clamp(255 (2^c x)^(1/2.2), 0, 255), mPSNR = 10 log10(3 255^2 / MSE), MSE summed over
 * RGB and averaged over texels and exposures) of the decoded chain against the float chain.
 * With --astc, the same for astcenc 4x4 at -medium and -thorough (the anchor). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "ibl/ibl.h"
#include "bench_timing.h"


/* CPU time of every thread of the process: on a loaded machine, what the encode costs. */
static double cpu_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}


typedef struct metrics {
    double log_rms, mpsnr;
} metrics;

static metrics measure(const float *ref, const float *got, size_t texels)
{
    double sum = 0.0, mse = 0.0;
    int exposures = 0;
    for (size_t i = 0; i < texels; i++)
        for (int c = 0; c < 3; c++) {
            double d = log2(1.0 + ref[4 * i + c]) - log2(1.0 + got[4 * i + c]);
            sum += d * d;
        }
    for (int e = -8; e <= 4; e++, exposures++) {
        double s = ldexp(1.0, e);
        for (size_t i = 0; i < texels; i++)
            for (int c = 0; c < 3; c++) {
                double a = fmin(255.0, fmax(0.0, 255.0 * pow(s * ref[4 * i + c], 1.0 / 2.2)));
                double b = fmin(255.0, fmax(0.0, 255.0 * pow(s * got[4 * i + c], 1.0 / 2.2)));
                mse += (a - b) * (a - b);
            }
    }
    mse /= (double)texels * exposures;
    metrics m = {sqrt(sum / (double)(texels * 3)), mse > 0 ? 10.0 * log10(3.0 * 255.0 * 255.0 / mse) : 99.0};
    return m;
}

typedef ibl_status (*codec_fn)(ibl_context *ctx, int variant, const float *rgba, int w, int h,
                               float *decoded, double ms[2]);

static ibl_status bc6h_codec(ibl_context *ctx, int quality, const float *rgba, int w, int h,
                             float *decoded, double ms[2])
{
    uint8_t *blocks = malloc(ibl_bc6h_bytes(w, h));
    ibl_bc6h_desc d = {0, (ibl_quality)quality};
    double t0 = bench_now_ms(), c0 = cpu_ms();
    ibl_status st = ibl_bc6h_encode(ctx, &d, rgba, w, h, blocks);
    ms[0] += bench_now_ms() - t0;
    ms[1] += cpu_ms() - c0;
    if (st == IBL_OK) st = ibl_bc6h_decode(ctx, 0, blocks, w, h, decoded);
    free(blocks);
    return st;
}

static ibl_status astc_codec(ibl_context *ctx, int quality, const float *rgba, int w, int h,
                             float *decoded, double ms[2])
{
    ibl_astc_desc d = {4, 4, (ibl_quality)quality};
    uint8_t *blocks = malloc(ibl_astc_bytes(4, 4, w, h));
    double t0 = bench_now_ms(), c0 = cpu_ms();
    ibl_status st = ibl_astc_encode(ctx, &d, rgba, w, h, blocks);
    ms[0] += bench_now_ms() - t0;
    ms[1] += cpu_ms() - c0;
    if (st == IBL_OK) st = ibl_astc_decode(ctx, &d, blocks, w, h, decoded);
    free(blocks);
    return st;
}

static void run(ibl_context *ctx, const char *path, const ibl_texture *t, const char *name,
                codec_fn codec, int variant, int runs)
{
    size_t floats = ibl_texture_floats(t->kind, t->width, t->height, t->depth, t->levels);
    float *decoded = malloc(floats * sizeof *decoded);
    double times[64], cpu[64];
    for (int r = 0; r < runs; r++) {
        double ms[2] = {0.0, 0.0};
        for (int l = 0; l < t->levels; l++)
            for (int f = 0; f < 6; f++) {
                int s = ibl_level_size(t->width, l);
                float *src = ibl_texture_level(t, l, f);
                if (codec(ctx, variant, src, s, s, decoded + (src - t->data), ms) != IBL_OK) {
                    fprintf(stderr, "%s: %s\n", path, ibl_context_message(ctx));
                    exit(1);
                }
            }
        times[r] = ms[0];
        cpu[r] = ms[1];
    }
    qsort(times, (size_t)runs, sizeof *times, bench_cmp_double);
    qsort(cpu, (size_t)runs, sizeof *cpu, bench_cmp_double);
    printf("%s %s: encode %.1f ms wall, %.1f ms CPU (medians of %d)\n", path, name,
           times[runs / 2], cpu[runs / 2], runs);
    printf("  level  size  log2-RMS  mPSNR\n");
    for (int l = 0; l < t->levels; l++) {
        int s = ibl_level_size(t->width, l);
        size_t off = (size_t)(ibl_texture_level(t, l, 0) - t->data);
        metrics m = measure(t->data + off, decoded + off, (size_t)s * (size_t)s * 6);
        printf("  %5d %5d  %.5f  %6.2f\n", l, s, m.log_rms, m.mpsnr);
    }
    metrics all = measure(t->data, decoded, floats / 4);
    printf("  all        %.5f  %6.2f\n", all.log_rms, all.mpsnr);
    free(decoded);
}

int main(int argc, char **argv)
{
    int threads = 2, runs = 5, astc = 0;
    ibl_context_desc cd = {0};
    ibl_context *ctx = NULL;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "-j") == 0 && i + 1 < argc) threads = atoi(argv[++i]);
        else if (strcmp(argv[i], "--runs") == 0 && i + 1 < argc) runs = atoi(argv[++i]);
        else if (strcmp(argv[i], "--astc") == 0) astc = 1;
    }
    if (runs < 1 || runs > 64) runs = 5;
    cd.threads = threads;
    if (ibl_context_create(&cd, &ctx) != IBL_OK) return 1;
    for (int i = 1; i < argc; i++) {
        if (argv[i][0] == '-') {
            if (strcmp(argv[i], "-j") == 0 || strcmp(argv[i], "--runs") == 0) i++;
            continue;
        }
        ibl_texture t;
        if (ibl_read_texture(ctx, argv[i], NULL, &t, NULL) != IBL_OK || t.kind != IBL_TEXTURE_CUBE) {
            fprintf(stderr, "%s: %s\n", argv[i], t.kind != IBL_TEXTURE_CUBE ? "not a cube" : ibl_context_message(ctx));
            return 1;
        }
        static const char *const names[] = {"bc6h default", "bc6h fast", "bc6h thorough"};
        for (int q = 0; q < 3; q++) run(ctx, argv[i], &t, names[q], bc6h_codec, q, q == 2 ? 1 : runs);
        if (astc) {
            run(ctx, argv[i], &t, "astcenc 4x4 -medium", astc_codec, IBL_QUALITY_DEFAULT, 1);
            run(ctx, argv[i], &t, "astcenc 4x4 -thorough", astc_codec, IBL_QUALITY_THOROUGH, 1);
        }
        ibl_texture_free(ctx, &t);
    }
    ibl_context_destroy(ctx);
    return 0;
}
