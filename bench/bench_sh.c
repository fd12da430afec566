/* Diffuse benchmarks (docs/PERFORMANCE.md): SH projection of a 256-face cube and the dynamic
 * IEM 8x8x6 -> 16x16x6, both on one core, medians over many runs; then, given the test data
 * folder, the accuracy table of docs/DIFFUSE.md on the real HDRIs (face-centre SH vs exact,
 * IEM methods vs the full-resolution reference, windowing).
 * usage: bench_sh [TESTDATA_DIR] */
#include "ibl/ibl.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* CPU time of this thread: every timed call runs on the calling thread (threads = 1), and on
 * a machine shared with other work the thread's CPU time is far steadier than wall time. */
static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
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

/* Max |a - b| over directions (E/pi from SH) relative to the mean of b. */
static double sh_irradiance_error(const ibl_sh *a, const ibl_sh *b)
{
    ibl_sh ea, eb;
    ibl_sh_radiance_to_irradiance(a, &ea);
    ibl_sh_radiance_to_irradiance(b, &eb);
    double worst = 0, mean = (eb.c[0][0] + eb.c[0][1] + eb.c[0][2]) / 3 * 0.28209479177387814;
    for (int i = 0; i < 4096; i++) {
        double z = 1.0 - (2.0 * i + 1.0) / 4096, r = sqrt(1 - z * z), ph = i * 2.39996322972865332;
        double d[3] = {r * cos(ph), r * sin(ph), z}, va[3], vb[3];
        ibl_sh_eval(&ea, d, va);
        ibl_sh_eval(&eb, d, vb);
        for (int c = 0; c < 3; c++) {
            double e = fabs(va[c] - vb[c]) / mean;
            if (e > worst) worst = e;
        }
    }
    return worst;
}

static double cube_error(const ibl_cubemap *a, const ibl_cubemap *b)
{
    double mean[4], worst = 0;
    ibl_cubemap_mean(b, 0, mean);
    double m = (mean[0] + mean[1] + mean[2]) / 3;
    for (size_t i = 0; i < 6 * (size_t)a->size * a->size * 4; i++) {
        if (i % 4 == 3) continue;
        double e = fabs((double)a->data[i] - b->data[i]) / m;
        if (e > worst) worst = e;
    }
    return worst;
}

static void accuracy(ibl_context *ctx, const char *dir)
{
    static const char *const names[] = {"city", "forest", "interior", "night", "studio", "sunset"};
    printf("\naccuracy on %s (errors: max over directions / texels, relative to the mean E)\n", dir);
    printf("%-9s %6s %9s | %10s %10s %10s | %9s %9s %9s %9s %9s | %10s %8s\n", "hdri", "cube",
           "max L", "eq-vs-cube", "centres0", "centres1x1", "conv8", "conv16", "conv32", "sh3",
           "sh3-auto", "min E(sh3)", "auto W");
    for (size_t k = 0; k < sizeof names / sizeof names[0]; k++) {
        char path[1024];
        snprintf(path, sizeof path, "%s/%s.exr", dir, names[k]);
        ibl_image im;
        if (ibl_read_image(ctx, path, NULL, &im, NULL) != IBL_OK) {
            printf("%-9s (not readable: %s)\n", names[k], ibl_context_message(ctx));
            continue;
        }
        double maxl = 0;
        for (size_t i = 0; i < (size_t)im.width * im.height * 4; i++)
            if (i % 4 != 3 && im.pixels[i] > maxl) maxl = im.pixels[i];
        ibl_cubemap cube;
        ibl_to_cube_desc cd = {0};
        cd.layout = IBL_LAYOUT_EQUIRECT;
        if (ibl_image_to_cubemap(ctx, &im, &cd, &cube) != IBL_OK) return;
        ibl_sh exact, eq, c0, c1, win;
        ibl_sh_project_cubemap(ctx, &cube, 0, 3, &exact);
        ibl_sh_project_equirect(ctx, &im, 3, &eq);
        ibl_sh_project_face_centres(&cube, 0, 3, &c0);
        ibl_cubemap chain;
        ibl_cubemap_alloc(ctx, cube.size, ibl_full_mip_count(cube.size), &chain);
        memcpy(chain.data, cube.data, 6 * (size_t)cube.size * cube.size * 4 * sizeof(float));
        ibl_cubemap_build_mips(ctx, &chain);
        ibl_sh_project_face_centres(&chain, chain.levels - 1, 3, &c1);
        ibl_cubemap_free(ctx, &chain);
        win = exact;
        ibl_sh_window_report rep;
        ibl_sh_apply_window(&win, IBL_SH_WINDOW_AUTO, 0, &rep);
        ibl_cubemap ref, conv, conv16, conv32, sh3, sha;
        ibl_irradiance_desc d = {0};
        d.method = IBL_IRRADIANCE_REFERENCE;
        ibl_irradiance_cubemap(ctx, &cube, &d, &ref);
        d.method = IBL_IRRADIANCE_CONVOLVE;
        ibl_irradiance_cubemap(ctx, &cube, &d, &conv);
        d.source_size = 16;
        ibl_irradiance_cubemap(ctx, &cube, &d, &conv16);
        d.source_size = 32;
        ibl_irradiance_cubemap(ctx, &cube, &d, &conv32);
        d.source_size = 0;
        d.method = IBL_IRRADIANCE_SH;
        ibl_irradiance_cubemap(ctx, &cube, &d, &sh3);
        d.sh_window = IBL_SH_WINDOW_AUTO;
        ibl_irradiance_cubemap(ctx, &cube, &d, &sha);
        double mean = (exact.c[0][0] + exact.c[0][1] + exact.c[0][2]) / 3 * 0.28209479177387814 * 3.14159265358979;
        printf("%-9s %6d %9.4g | %10.2e %10.4f %10.4f | %9.4f %9.4f %9.4f %9.4f %9.4f | %10.4f %8.3g\n",
               names[k], cube.size, maxl, sh_irradiance_error(&eq, &exact),
               sh_irradiance_error(&c0, &exact), sh_irradiance_error(&c1, &exact),
               cube_error(&conv, &ref), cube_error(&conv16, &ref), cube_error(&conv32, &ref),
               cube_error(&sh3, &ref),
               cube_error(&sha, &ref), rep.min_irradiance_before / mean,
               rep.applied == IBL_SH_WINDOW_HANNING ? rep.width : 0.0);
        ibl_cubemap_free(ctx, &ref);
        ibl_cubemap_free(ctx, &conv);
        ibl_cubemap_free(ctx, &conv16);
        ibl_cubemap_free(ctx, &conv32);
        ibl_cubemap_free(ctx, &sh3);
        ibl_cubemap_free(ctx, &sha);
        ibl_cubemap_free(ctx, &cube);
        ibl_image_free(ctx, &im);
    }
}

int main(int argc, char **argv)
{
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
        ibl_sh_plan_desc pd = {.face_size = 256, .bands = bands};
        if (ibl_sh_plan_create(ctx, &pd, &plan) != IBL_OK) return 1;
        enum { RUNS = 101 };
        double t[RUNS], t2[RUNS];
        ibl_sh sh;
        for (int r = 0; r < RUNS; r++) {
            double t0 = now();
            ibl_sh_plan_run(plan, &cube, &sh);
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
        ibl_irradiance_plan *plan;
        double t0 = now();
        ibl_irradiance_plan_desc pd = {.source_size = 8, .size = 16};
        if (ibl_irradiance_plan_create(ctx, &pd, &plan) != IBL_OK) return 1;
        double create = now() - t0;
        float src[6 * 8 * 8 * 4], dst[6 * 16 * 16 * 4];
        fill(src, 6 * 8 * 8);
        ibl_cubemap src_cube, dst_cube;
        ibl_cubemap_wrap(8, 1, src, &src_cube);
        ibl_cubemap_wrap(16, 1, dst, &dst_cube);
        enum { RUNS = 2001 };
        static double t[RUNS];
        for (int r = 0; r < RUNS; r++) {
            double a = now();
            ibl_irradiance_plan_run(plan, &src_cube, &dst_cube);
            t[r] = now() - a;
            sink += dst[0];
        }
        printf("dynamic IEM 8x8x6 -> 16x16x6, 1 thread: run median %.4f ms (%zu taps), "
               "plan creation %.3f ms\n",
               median(t, RUNS) * 1e3, ibl_irradiance_plan_taps(plan), create * 1e3);
        ibl_irradiance_plan_destroy(plan);
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
    if (argc > 1) {
        ibl_context *all;
        if (ibl_context_create(NULL, &all) != IBL_OK) return 1;
        accuracy(all, argv[1]);
        ibl_context_destroy(all);
    }
    return sink == 12345.0;
}
