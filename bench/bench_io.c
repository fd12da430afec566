/* Flat image decode/encode speed: bench_io DATA_DIR
 * DATA_DIR holds hdri/NAME.exr and probes/uffizi_latlong_256x128.hdr (../shared/testdata), or
 * tests/data (studio.exr, uffizi_latlong_256x128.hdr). Prints the median of 11 runs.
 * First every codec on one thread, in memory; then the I/O around `ibl prefilter` at 1 and 2
 * threads: EXR decode (city.exr, and a 2048x1024 ZIP file made from it, float and half),
 * the decode + equirect-to-cube read of both, and the KTX2 encode and the atomic write
 * (to a temporary folder: page cache and fsync) of a 256 and a 512 chain. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

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

/* ---- the I/O around ibl prefilter, at 1 and 2 threads ---- */

static ibl_context *context(int threads)
{
    ibl_context_desc d = {0};
    d.threads = threads;
    ibl_context *ctx = NULL;
    if (ibl_context_create(&d, &ctx) != IBL_OK) exit(1);
    return ctx;
}

/* ms median of RUNS decodes of an in-memory file, and of decode + equirect -> cube */
static void bench_read(int threads, const char *label, const void *bytes, size_t size, int cube)
{
    ibl_context *ctx = context(threads);
    double td[RUNS], tc[RUNS];
    for (int r = 0; r < RUNS; r++) {
        ibl_texture tex;
        double t0 = now_ms();
        if (ibl_decode_texture(ctx, bytes, size, label, NULL, &tex, NULL) != IBL_OK) {
            fprintf(stderr, "%s\n", ibl_context_message(ctx));
            exit(1);
        }
        double t1 = now_ms();
        ibl_image im = {tex.width, tex.height, tex.data};
        ibl_to_cube_desc d = {0};
        d.size = cube;
        ibl_cubemap c;
        if (ibl_image_to_cubemap(ctx, &im, &d, &c) != IBL_OK) exit(1);
        double t2 = now_ms();
        td[r] = t1 - t0;
        tc[r] = t2 - t0;
        ibl_cubemap_free(ctx, &c);
        ibl_texture_free(ctx, &tex);
    }
    printf("read   %-34s %d thr  decode %7.2f ms  + cube %d: %7.2f ms\n", label, threads,
           median(td), cube, median(tc));
    ibl_context_destroy(ctx);
}

/* A chain of `size` with every level: level 0 from the picture, the rest 2x2 means. */
static ibl_cubemap make_chain(ibl_context *ctx, const ibl_image *im, int size)
{
    ibl_to_cube_desc d = {0};
    d.size = size;
    ibl_cubemap one, chain;
    if (ibl_image_to_cubemap(ctx, im, &d, &one) != IBL_OK) exit(1);
    if (ibl_cubemap_alloc(ctx, size, ibl_full_mip_count(size), &chain) != IBL_OK) exit(1);
    memcpy(chain.data, one.data, ibl_cubemap_floats(size, 1) * sizeof(float));
    for (int l = 1; l < chain.levels; l++) {
        int n = size >> l;
        for (int f = 0; f < 6; f++) {
            const float *src = ibl_cubemap_face(&chain, l - 1, f);
            float *dst = ibl_cubemap_face(&chain, l, f);
            for (int y = 0; y < n; y++)
                for (int x = 0; x < n; x++)
                    for (int c = 0; c < 4; c++)
                        dst[(y * n + x) * 4 + c] =
                            0.25f * (src[((2 * y) * 2 * n + 2 * x) * 4 + c] + src[((2 * y) * 2 * n + 2 * x + 1) * 4 + c] +
                                     src[((2 * y + 1) * 2 * n + 2 * x) * 4 + c] +
                                     src[((2 * y + 1) * 2 * n + 2 * x + 1) * 4 + c]);
        }
    }
    ibl_cubemap_free(ctx, &one);
    return chain;
}

static void bench_write(int threads, const ibl_cubemap *chain)
{
    ibl_context *ctx = context(threads);
    ibl_texture t = ibl_texture_from_cubemap(chain);
    t.format = IBL_FORMAT_RGBA16F;
    char dir[] = "/tmp/bench_io_XXXXXX", path[64];
    if (!mkdtemp(dir)) exit(1);
    snprintf(path, sizeof path, "%s/p.ktx2", dir);
    double te[RUNS], tw[RUNS];
    size_t size = 0;
    for (int r = 0; r < RUNS; r++) {
        void *bytes;
        double t0 = now_ms();
        if (ibl_encode_texture(ctx, IBL_FILE_KTX2, &t, NULL, &bytes, &size) != IBL_OK) exit(1);
        te[r] = now_ms() - t0;
        ibl_free(ctx, bytes);
        t0 = now_ms();
        if (ibl_write_texture(ctx, path, &t, NULL) != IBL_OK) exit(1);
        tw[r] = now_ms() - t0;
    }
    printf("write  ktx2 rgba16f chain %-4d (%8zu B) %d thr  encode %7.2f ms  encode + file %7.2f ms\n",
           chain->size, size, threads, median(te), median(tw));
    unlink(path);
    rmdir(dir);
    ibl_context_destroy(ctx);
}

static void bench_prefilter_io(const char *city_path)
{
    ibl_context *ctx = context(2);
    void *bytes;
    size_t size;
    ibl_texture city;
    if (ibl_read_file(ctx, city_path, &bytes, &size) != IBL_OK ||
        ibl_decode_texture(ctx, bytes, size, city_path, NULL, &city, NULL) != IBL_OK) {
        fprintf(stderr, "%s\n", ibl_context_message(ctx));
        exit(1);
    }
    /* the 2048x1024 input: each pixel of city doubled (the bench/run.sh file is resampled) */
    ibl_image big;
    if (ibl_image_alloc(ctx, 2 * city.width, 2 * city.height, &big) != IBL_OK) exit(1);
    for (int y = 0; y < big.height; y++)
        for (int x = 0; x < big.width; x++)
            memcpy(big.pixels + ((size_t)y * big.width + x) * 4,
                   city.data + ((size_t)(y / 2) * city.width + x / 2) * 4, 4 * sizeof(float));
    ibl_texture bt = {0};
    bt.kind = IBL_TEXTURE_2D;
    bt.width = big.width;
    bt.height = big.height;
    bt.depth = bt.levels = 1;
    bt.data = big.pixels;
    ibl_write_desc wd = {0};
    void *zip32, *zip16;
    size_t zip32_size, zip16_size;
    wd.format = IBL_FORMAT_RGB32F;
    if (ibl_encode_texture(ctx, IBL_FILE_EXR, &bt, &wd, &zip32, &zip32_size) != IBL_OK) exit(1);
    wd.format = IBL_FORMAT_RGB16F;
    if (ibl_encode_texture(ctx, IBL_FILE_EXR, &bt, &wd, &zip16, &zip16_size) != IBL_OK) exit(1);
    ibl_image city_im = {city.width, city.height, city.data};
    ibl_cubemap chain256 = make_chain(ctx, &city_im, 256), chain512 = make_chain(ctx, &big, 512);
    for (int threads = 1; threads <= 2; threads++) {
        bench_read(threads, "city.exr (DWAB float, 1024x512)", bytes, size, 256);
        bench_read(threads, "2048x1024 ZIP float RGB", zip32, zip32_size, 512);
        bench_read(threads, "2048x1024 ZIP half RGB", zip16, zip16_size, 512);
        bench_write(threads, &chain256);
        bench_write(threads, &chain512);
    }
    ibl_cubemap_free(ctx, &chain256);
    ibl_cubemap_free(ctx, &chain512);
    ibl_free(ctx, zip32);
    ibl_free(ctx, zip16);
    ibl_image_free(ctx, &big);
    ibl_texture_free(ctx, &city);
    ibl_free(ctx, bytes);
    ibl_context_destroy(ctx);
}

int main(int argc, char **argv)
{
    const char *dir = argc > 1 ? argv[1] : "tests/data";
    char city_path[1024];
    snprintf(city_path, sizeof city_path, "%s/hdri/city.exr", dir);
    if (access(city_path, R_OK) != 0) snprintf(city_path, sizeof city_path, "%s/city.exr", dir);
    if (argc > 2 && strcmp(argv[2], "prefilter") == 0) {
        bench_prefilter_io(city_path);
        return 0;
    }
    ibl_context *ctx = context(1);
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
    if (access(city_path, R_OK) == 0) bench_prefilter_io(city_path);
    return 0;
}
