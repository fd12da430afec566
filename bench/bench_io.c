/* Flat image decode/encode speed (in memory, no disk): bench_io DATA_DIR
 * DATA_DIR holds hdri/NAME.exr and probes/uffizi_latlong_256x128.hdr (../shared/testdata), or
 * tests/data (studio.exr, uffizi_latlong_256x128.hdr). Prints the median of 11 runs. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "ibl/ibl.h"

enum { RUNS = 11 };

static double now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec / 1e6;
}

static int cmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static double median(double *t)
{
    qsort(t, RUNS, sizeof *t, cmp);
    return t[RUNS / 2];
}

static int bench_decode(ibl_context *ctx, const char *path, ibl_texture *keep)
{
    void *bytes;
    size_t size;
    if (ibl_read_file(ctx, path, &bytes, &size) != IBL_OK) return 0;
    double t[RUNS];
    ibl_texture tex;
    int w = 0, h = 0;
    for (int r = 0; r < RUNS; r++) {
        double t0 = now_ms();
        if (ibl_decode_texture(ctx, bytes, size, path, NULL, &tex, NULL) != IBL_OK) {
            fprintf(stderr, "%s\n", ibl_context_message(ctx));
            ibl_free(ctx, bytes);
            return 0;
        }
        t[r] = now_ms() - t0;
        w = tex.width;
        h = tex.height;
        if (r == RUNS - 1 && keep) *keep = tex;
        else ibl_texture_free(ctx, &tex);
    }
    double ms = median(t);
    printf("decode %-40s %5dx%-5d %8.2f ms  %7.1f Mpixel/s\n", strrchr(path, '/') + 1, w, h, ms,
           (double)w * h / 1e6 / (ms / 1e3));
    ibl_free(ctx, bytes);
    return 1;
}

static void bench_encode(ibl_context *ctx, const ibl_texture *tex, ibl_file_type type,
                         const char *label, ibl_write_desc wd)
{
    double t[RUNS];
    size_t size = 0;
    for (int r = 0; r < RUNS; r++) {
        void *bytes;
        double t0 = now_ms();
        if (ibl_encode_texture(ctx, type, tex, &wd, &bytes, &size) != IBL_OK) {
            fprintf(stderr, "%s\n", ibl_context_message(ctx));
            return;
        }
        t[r] = now_ms() - t0;
        ibl_free(ctx, bytes);
    }
    double mpix = (double)tex->width * tex->height / 1e6;
    printf("encode %-40s %5dx%-5d %8.2f ms  %7.1f Mpixel/s  %9zu bytes\n", label, tex->width,
           tex->height, median(t), mpix / (median(t) / 1e3), size);
}

int main(int argc, char **argv)
{
    const char *dir = argc > 1 ? argv[1] : "tests/data";
    ibl_context *ctx;
    if (ibl_context_create(NULL, &ctx) != IBL_OK) return 1;
    char path[1024];
    ibl_texture big = {0};
    const char *exrs[] = {"hdri/forest.exr", "hdri/studio.exr", "studio.exr"};
    int have_exr = 0;
    for (int i = 0; i < 3 && !have_exr; i++) {
        snprintf(path, sizeof path, "%s/%s", dir, exrs[i]);
        have_exr = bench_decode(ctx, path, &big);
    }
    const char *hdrs[] = {"probes/uffizi_latlong_256x128.hdr", "uffizi_latlong_256x128.hdr"};
    for (int i = 0; i < 2; i++) {
        snprintf(path, sizeof path, "%s/%s", dir, hdrs[i]);
        if (bench_decode(ctx, path, NULL)) break;
    }
    if (!have_exr) {
        fprintf(stderr, "bench_io: no EXR found under %s\n", dir);
        ibl_context_destroy(ctx);
        return 1;
    }
    ibl_write_desc wd = {0};
    wd.format = IBL_FORMAT_RGB32F;
    bench_encode(ctx, &big, IBL_FILE_EXR, "exr rgb32f zip", wd);
    wd.format = IBL_FORMAT_RGB16F;
    wd.exr_compression = IBL_EXR_PIZ;
    bench_encode(ctx, &big, IBL_FILE_EXR, "exr rgb16f piz", wd);
    memset(&wd, 0, sizeof wd);
    bench_encode(ctx, &big, IBL_FILE_HDR, "hdr rle", wd);
    bench_encode(ctx, &big, IBL_FILE_PFM, "pfm", wd);
    bench_encode(ctx, &big, IBL_FILE_PNG, "png rgba8 filmic", wd);
    wd.format = IBL_FORMAT_RGBA16_UNORM;
    bench_encode(ctx, &big, IBL_FILE_PNG, "png rgba16 linear", wd);
    /* Round trips through memory to time the decoders of our own outputs too. */
    const struct {
        ibl_file_type type;
        const char *label;
    } rt[] = {{IBL_FILE_HDR, "hdr rle (own output)"}, {IBL_FILE_EXR, "exr rgb32f zip (own output)"},
              {IBL_FILE_PNG, "png rgba8 (own output)"}};
    for (int i = 0; i < 3; i++) {
        memset(&wd, 0, sizeof wd);
        void *bytes;
        size_t size;
        if (ibl_encode_texture(ctx, rt[i].type, &big, &wd, &bytes, &size) != IBL_OK) continue;
        double t[RUNS];
        for (int r = 0; r < RUNS; r++) {
            ibl_texture tex;
            double t0 = now_ms();
            if (ibl_decode_texture(ctx, bytes, size, "mem", NULL, &tex, NULL) != IBL_OK) break;
            t[r] = now_ms() - t0;
            ibl_texture_free(ctx, &tex);
        }
        double mpix = (double)big.width * big.height / 1e6;
        printf("decode %-40s %5dx%-5d %8.2f ms  %7.1f Mpixel/s\n", rt[i].label, big.width,
               big.height, median(t), mpix / (median(t) / 1e3));
        ibl_free(ctx, bytes);
    }
    ibl_texture_free(ctx, &big);
    ibl_context_destroy(ctx);
    return 0;
}
