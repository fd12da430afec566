/* Encode/decode speed of the texture containers and the packed pixel formats: a 256-texel
 * cube with its full mip chain (9 levels, 393,216 + ... texels), every container x format.
 * Prints the median of 15 runs in milliseconds and the float-RGBA throughput. Usage:
 *   build/bench/bench_containers [ignored data folder] */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "core/pixel_format.h"
#include "io/io_internal.h"

enum { RUNS = 15 };

typedef ibl_status (*encode_fn)(ibl_context *, const ibl_texture *, const ibl_write_desc *,
                                const char *, void **, size_t *);
typedef ibl_status (*decode_fn)(ibl_context *, const uint8_t *, size_t, const char *,
                                ibl_texture *, ibl_file_info *);

static double now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double median(double *v)
{
    qsort(v, RUNS, sizeof *v, cmp_double);
    return v[RUNS / 2];
}

int main(int argc, char **argv)
{
    ibl_context_desc cd = {0};
    cd.threads = argc > 2 ? atoi(argv[2]) : 0;
    ibl_context *ctx = NULL;
    if (ibl_context_create(&cd, &ctx) != IBL_OK) return 1;
    ibl_texture tex;
    if (ibl_texture_alloc(ctx, IBL_TEXTURE_CUBE, 256, 256, 1, 9, &tex) != IBL_OK) return 1;
    size_t floats = ibl_texture_floats(IBL_TEXTURE_CUBE, 256, 256, 1, 9);
    uint32_t s = 1;
    for (size_t i = 0; i < floats; i++) {
        s = s * 1664525u + 1013904223u;
        tex.data[i] = (float)(s >> 8) * 0x1p-14f; /* 0 .. 1024 */
    }
    double mib = (double)floats * 4.0 / 1048576.0;
    struct { const char *name; encode_fn enc; decode_fn dec; } cs[] = {
        {"ktx2", ibl__ktx2_encode, ibl__ktx2_decode},
        {"ktx1", ibl__ktx1_encode, ibl__ktx1_decode},
        {"dds", ibl__dds_encode, ibl__dds_decode},
    };
    static const ibl_format fmts[] = {IBL_FORMAT_RGBA16F, IBL_FORMAT_RGBA32F, IBL_FORMAT_RG11B10F,
                                      IBL_FORMAT_RGB9E5, IBL_FORMAT_RG16F, IBL_FORMAT_RG32F};
    printf("cube 256, 9 levels, %.1f MiB of float RGBA; %d threads; median of %d runs\n", mib,
           ibl_context_threads(ctx), RUNS);
    printf("%-5s %-9s %10s %10s %12s %12s\n", "cont", "format", "enc ms", "dec ms", "enc MiB/s",
           "dec MiB/s");
    for (size_t c = 0; c < sizeof cs / sizeof cs[0]; c++) {
        for (size_t f = 0; f < sizeof fmts / sizeof fmts[0]; f++) {
            double te[RUNS], td[RUNS];
            ibl_write_desc d = {.format = fmts[f]};
            for (int r = 0; r < RUNS; r++) {
                void *bytes;
                size_t size;
                double t0 = now_ms();
                if (cs[c].enc(ctx, &tex, &d, "bench", &bytes, &size) != IBL_OK) return 1;
                double t1 = now_ms();
                ibl_texture out;
                if (cs[c].dec(ctx, bytes, size, "bench", &out, NULL) != IBL_OK) return 1;
                double t2 = now_ms();
                te[r] = t1 - t0;
                td[r] = t2 - t1;
                ibl_texture_free(ctx, &out);
                ibl_free(ctx, bytes);
            }
            double me = median(te), md = median(td);
            printf("%-5s %-9s %10.2f %10.2f %12.0f %12.0f\n", cs[c].name, ibl_format_name(fmts[f]),
                   me, md, mib / (me * 1e-3), mib / (md * 1e-3));
        }
    }
    ibl_texture_free(ctx, &tex);
    ibl_context_destroy(ctx);
    return 0;
}
