/* Layout conversion speed: equirect -> cube and cube -> equirect, plus the procedural sky.
 * Usage: bench_layout [width] [cube_size] [threads] [runs]   (defaults 1024 256 0 9)
 * Prints the median wall time of each stage in milliseconds. The input is a synthetic
 * equirect (smooth gradient plus a small sun), so no file is read. Equirect -> cube is also
 * timed with a context created with IBL_KERNELS_PORTABLE (no AVX2), which is what CPUs
 * without AVX2 run. */
#include "ibl/ibl.h"
#include "core/cpu.h"
#include "layout/layout_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static double clock_ms(clockid_t id)
{
    struct timespec ts;
    clock_gettime(id, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}
static double now_ms(void) { return clock_ms(CLOCK_MONOTONIC); }
/* CPU time of all threads: what the work costs, whatever else the machine is doing */
static double cpu_ms(void) { return clock_ms(CLOCK_PROCESS_CPUTIME_ID); }

static int cmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static double median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof v[0], cmp);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

int main(int argc, char **argv)
{
    int width = argc > 1 ? atoi(argv[1]) : 1024;
    int size = argc > 2 ? atoi(argv[2]) : 256;
    int threads = argc > 3 ? atoi(argv[3]) : 0;
    int runs = argc > 4 ? atoi(argv[4]) : 9;
    if (width < 8 || size < 1 || runs < 1 || runs > 100) {
        fprintf(stderr, "usage: bench_layout [width] [cube_size] [threads] [runs]\n");
        return 2;
    }
    ibl_context_desc cd = {0};
    cd.threads = threads;
    ibl_context *ctx, *portable;
    if (ibl_context_create(&cd, &ctx) != IBL_OK) return 1;
    cd.kernels = IBL_KERNELS_PORTABLE;
    if (ibl_context_create(&cd, &portable) != IBL_OK) return 1;
    ibl_image im;
    if (ibl_image_alloc(ctx, width, width / 2, &im) != IBL_OK) return 1;
    for (int y = 0; y < im.height; y++)
        for (int x = 0; x < im.width; x++) {
            float *p = ibl_image_texel(&im, x, y);
            p[0] = 1.0f + 0.5f * sinf(x * 0.01f);
            p[1] = 1.0f + 0.5f * cosf(y * 0.02f);
            p[2] = 0.5f;
            p[3] = 1.0f;
        }
    ibl_image_texel(&im, width / 3, width / 8)[0] = 1e5f;

    double t_to[100], t_from[100], t_sky[100], c_to[100], c_from[100], c_sky[100];
    double t_port[100], c_port[100];
    ibl__frame identity;
    ibl_orientation no_turn = {0, 0, 0};
    ibl__frame_from_orientation(&no_turn, &identity);
    for (int r = 0; r < runs; r++) {
        ibl_to_cube_desc td = {0};
        td.size = size;
        ibl_cubemap cube;
        double c0 = cpu_ms(), t0 = now_ms();
        if (ibl_image_to_cubemap(ctx, &im, &td, &cube) != IBL_OK) return 1;
        double c1 = cpu_ms(), t1 = now_ms();
        ibl_from_cube_desc fd = {0};
        fd.layout = IBL_LAYOUT_EQUIRECT;
        fd.width = width;
        ibl_image back;
        if (ibl_cubemap_to_image(ctx, &cube, &fd, &back) != IBL_OK) return 1;
        double c2 = cpu_ms(), t2 = now_ms();
        ibl_sky_desc sd = {0};
        sd.width = width;
        ibl_image sky;
        if (ibl_sky_render(ctx, &sd, &sky) != IBL_OK) return 1;
        double c3 = cpu_ms(), t3 = now_ms();
        ibl_cubemap port;
        if (ibl_cubemap_alloc(ctx, size, 1, &port) != IBL_OK) return 1;
        double c4 = cpu_ms(), t4 = now_ms();
        if (ibl__equirect_to_cube(portable, &im, &identity, 0, &port) != IBL_OK) return 1;
        double c5 = cpu_ms(), t5 = now_ms();
        ibl_cubemap_free(ctx, &port);
        c_port[r] = c5 - c4;
        t_port[r] = t5 - t4;
        c_to[r] = c1 - c0;
        c_from[r] = c2 - c1;
        c_sky[r] = c3 - c2;
        t_to[r] = t1 - t0;
        t_from[r] = t2 - t1;
        t_sky[r] = t3 - t2;
        ibl_image_free(ctx, &sky);
        ibl_image_free(ctx, &back);
        ibl_cubemap_free(ctx, &cube);
    }
    printf("threads %d, %d runs (medians: wall ms / CPU ms of all threads)\n",
           ibl_context_threads(ctx), runs);
    printf("equirect %dx%d -> cube %d: %.1f / %.1f\n", width, width / 2, size, median(t_to, runs),
           median(c_to, runs));
    printf("equirect %dx%d -> cube %d, portable code%s: %.1f / %.1f\n", width, width / 2, size,
           ibl__cpu_has(ctx, IBL__CPU_AVX2_FMA) ? "" : " (also above: no AVX2 here)",
           median(t_port, runs),
           median(c_port, runs));
    printf("cube %d -> equirect %dx%d: %.1f / %.1f\n", size, width, width / 2,
           median(t_from, runs), median(c_from, runs));
    printf("sky %dx%d: %.1f / %.1f\n", width, width / 2, median(t_sky, runs), median(c_sky, runs));
    ibl_image_free(ctx, &im);
    ibl_context_destroy(portable);
    ibl_context_destroy(ctx);
    return 0;
}
