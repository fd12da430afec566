/* Diffuse benchmarks (docs/PERFORMANCE.md): SH projection of a 256-face cube and the dynamic
 * IEM 8x8x6 -> 16x16x6, both on one core, medians over many runs.
 * usage: bench_sh [TESTDATA_DIR]   (the directory is not needed: inputs are synthetic) */
#include "ibl/ibl.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + ts.tv_nsec * 1e-9;
}

static int cmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static double median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, cmp);
    return v[n / 2];
}

static void fill(float *p, size_t texels)
{
    uint32_t s = 12345;
    for (size_t i = 0; i < texels * 4; i++) {
        s = s * 1664525u + 1013904223u;
        p[i] = (float)(s >> 8) / 16777216.0f * 4.0f;
    }
}

int main(int argc, char **argv)
{
    (void)argc;
    (void)argv;
    ibl_context *ctx;
    ibl_context_desc cd = {0};
    cd.threads = 1;
    if (ibl_context_create(&cd, &ctx) != IBL_OK) return 1;
    volatile double sink = 0;

    /* SH projection, 256 faces, 1 core */
    ibl_cubemap cube;
    if (ibl_cubemap_alloc(ctx, 256, 1, &cube) != IBL_OK) return 1;
    fill(cube.data, 6 * 256 * 256);
    for (int bands = 3; bands <= 5; bands += 2) {
        ibl_sh_plan *plan;
        if (ibl_sh_plan_create(ctx, 256, bands, &plan) != IBL_OK) return 1;
        enum { RUNS = 101 };
        double t[RUNS], t2[RUNS];
        ibl_sh sh;
        for (int r = 0; r < RUNS; r++) {
            double t0 = now();
            ibl_sh_plan_run(plan, cube.data, &sh);
            t[r] = now() - t0;
            sink += sh.c[0][0];
        }
        for (int r = 0; r < 21; r++) {
            double t0 = now();
            ibl_sh_project_cubemap(ctx, &cube, 0, bands, &sh);
            t2[r] = now() - t0;
            sink += sh.c[0][0];
        }
        printf("sh projection 256x256x6, %d bands, 1 thread: plan run median %.3f ms, "
               "one-shot (with tables) median %.3f ms\n",
               bands, median(t, RUNS) * 1e3, median(t2, 21) * 1e3);
        ibl_sh_plan_destroy(plan);
    }

    /* equirect projection 1024x512 */
    ibl_image im;
    if (ibl_image_alloc(ctx, 1024, 512, &im) != IBL_OK) return 1;
    fill(im.pixels, 1024 * 512);
    {
        double t[21];
        for (int r = 0; r < 21; r++) {
            ibl_sh sh;
            double t0 = now();
            ibl_sh_project_equirect(ctx, &im, 3, &sh);
            t[r] = now() - t0;
            sink += sh.c[0][0];
        }
        printf("sh projection equirect 1024x512, 3 bands, 1 thread: median %.3f ms\n",
               median(t, 21) * 1e3);
    }

    /* dynamic IEM 8x8x6 -> 16x16x6 */
    {
        ibl_iem_plan *plan;
        double t0 = now();
        if (ibl_iem_plan_create(ctx, 8, 16, IBL_IRRADIANCE_OVER_PI, &plan) != IBL_OK) return 1;
        double create = now() - t0;
        float src[6 * 8 * 8 * 4], dst[6 * 16 * 16 * 4];
        fill(src, 6 * 8 * 8);
        enum { RUNS = 2001 };
        static double t[RUNS];
        for (int r = 0; r < RUNS; r++) {
            double a = now();
            ibl_iem_plan_run(plan, src, dst);
            t[r] = now() - a;
            sink += dst[0];
        }
        printf("dynamic IEM 8x8x6 -> 16x16x6, 1 thread: run median %.4f ms (%zu taps), "
               "plan creation %.3f ms\n",
               median(t, RUNS) * 1e3, ibl_iem_plan_taps(plan), create * 1e3);
        ibl_iem_plan_destroy(plan);
    }

    /* whole irradiance cubemaps from the 256 cube */
    static const struct {
        ibl_irradiance_method m;
        const char *name;
        int runs;
    } methods[] = {{IBL_IRRADIANCE_CONVOLVE, "convolve", 11},
                   {IBL_IRRADIANCE_SH, "sh", 11},
                   {IBL_IRRADIANCE_REFERENCE, "reference", 1}};
    for (int k = 0; k < 3; k++) {
        double t[11];
        for (int r = 0; r < methods[k].runs; r++) {
            ibl_irradiance_desc d = {0};
            d.method = methods[k].m;
            ibl_cubemap out;
            double a = now();
            if (ibl_irradiance_cubemap(ctx, &cube, &d, &out) != IBL_OK) return 1;
            t[r] = now() - a;
            sink += out.data[0];
            ibl_cubemap_free(ctx, &out);
        }
        printf("irradiance cubemap 256 -> 16, method %s, 1 thread: median %.3f ms\n",
               methods[k].name, median(t, methods[k].runs) * 1e3);
    }
    ibl_image_free(ctx, &im);
    ibl_cubemap_free(ctx, &cube);
    ibl_context_destroy(ctx);
    return sink == 12345.0;
}
