/* The dynamic (per-frame) specular plans of tri-Ace 2010's dynamic configurations
 * (docs/PERFORMANCE.md "The dynamic path"): for each preset, the median plan creation and the
 * median run (refiltering a freshly rendered 64x64x6 cube, edge fixup included) on one
 * thread, and the plan's SH (ibl_specular_plan_sh). The input is synthetic (a smooth sky with
 * a small bright sun): the run's cost does not depend on the content.
 * Usage: bench_dynamic [source edge, default 64] [runs, default 201] [threads, default 1] */
#include "ibl/ibl.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "bench_timing.h"




static void fill(ibl_cubemap *c)
{
    int n = c->size;
    for (int f = 0; f < 6; f++) {
        float *p = ibl_cubemap_face(c, 0, f);
        for (int y = 0; y < n; y++)
            for (int x = 0; x < n; x++, p += 4) {
                ibl_vec3 d = ibl_cube_texel_direction(f, n, x, y);
                float sun = d.x * 0.6f + d.y * 0.8f > 0.995f ? 500.0f : 0.0f;
                p[0] = 1.0f + d.x + sun, p[1] = expf(2.0f * d.y) + sun, p[2] = 0.5f + d.z * d.z, p[3] = 1.0f;
            }
    }
}

int main(int argc, char **argv)
{
    int source = argc > 1 ? atoi(argv[1]) : 64, runs = argc > 2 ? atoi(argv[2]) : 201;
    int threads = argc > 3 ? atoi(argv[3]) : 1, creations = 11;
    if (source < 1 || runs < 1 || threads < 1) return 2;
    static const char *const presets[] = {"dynamic-box16", "dynamic-gauss32", "dynamic-phong16",
                                          "dynamic-phong32"};
    ibl_context *ctx;
    ibl_context_desc cd = {0};
    cd.threads = threads;
    if (ibl_context_create(&cd, &ctx) != IBL_OK) return 1;
    ibl_cubemap src;
    if (ibl_cubemap_alloc(ctx, source, 1, &src) != IBL_OK) return 1;
    fill(&src);
    double *t = malloc((size_t)(runs > creations ? runs : creations) * sizeof *t);
    if (!t) return 1;
    printf("dynamic plans from a %dx%dx6 cube, %d thread%s; medians of %d creations and %d runs\n",
           source, source, threads, threads > 1 ? "s" : "", creations, runs);
    printf("| preset | output | plan creation | run | SH (3 bands) |\n|---|---|---|---|---|\n");
    for (int i = 0; i < 4; i++) {
        ibl_specular_desc d;
        ibl_specular_preset(presets[i], &d);
        d.source_size = source;
        ibl_specular_plan *plan = NULL;
        for (int r = 0; r < creations; r++) {
            double t0 = bench_now_ms();
            if (ibl_specular_plan_create(ctx, &d, &plan) != IBL_OK) {
                fprintf(stderr, "%s: %s\n", presets[i], ibl_context_message(ctx));
                return 1;
            }
            t[r] = bench_now_ms() - t0;
            if (r + 1 < creations) ibl_specular_plan_destroy(plan);
        }
        double create = bench_median(t, creations);
        const ibl_specular_info *info = ibl_specular_plan_info(plan);
        ibl_cubemap dst;
        if (ibl_cubemap_alloc(ctx, info->size, info->levels, &dst) != IBL_OK) return 1;
        for (int r = 0; r < runs; r++) {
            double t0 = bench_now_ms();
            ibl_specular_plan_run(plan, &src, &dst);
            t[r] = bench_now_ms() - t0;
        }
        double run = bench_median(t, runs);
        ibl_sh sh;
        for (int r = 0; r < runs; r++) {
            double t0 = bench_now_ms();
            ibl_specular_plan_sh(plan, 3, &sh);
            t[r] = bench_now_ms() - t0;
        }
        printf("| %s | %dx%dx6, %d levels | %.2f ms | %.4f ms | %.4f ms |\n", presets[i], info->size,
               info->size, info->levels, create, run, bench_median(t, runs));
        ibl_cubemap_free(ctx, &dst);
        ibl_specular_plan_destroy(plan);
    }
    free(t);
    ibl_cubemap_free(ctx, &src);
    ibl_context_destroy(ctx);
    return 0;
}
