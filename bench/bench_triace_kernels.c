/* tri-Ace 2010's dynamic profiles (box 16x16x6, gauss 32x32x6, refiltered from a freshly
 * rendered 64x64x6 cube) and the edge fixups' per-texel and per-level costs. Synthetic input:
 * the figures do not depend on the content. Usage: bench_triace_kernels [ignored data dir] */
#include "bake/specular_kernels.h"
#include "ibl/ibl.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "bench_timing.h"



enum { RUNS = 51 };


static void fill(ibl_cubemap *c)
{
    int n = c->size;
    for (int f = 0; f < 6; f++) {
        float *p = ibl_cubemap_face(c, 0, f);
        for (int y = 0; y < n; y++)
            for (int x = 0; x < n; x++, p += 4) {
                ibl_vec3 d = ibl_cube_texel_direction(f, n, x, y);
                p[0] = 1.0f + d.x, p[1] = expf(4.0f * d.y), p[2] = 0.5f + d.z * d.z, p[3] = 1.0f;
            }
    }
}

int main(int argc, char **argv)
{
    (void)argc, (void)argv;
    for (int threads = 1; threads <= 2; threads++) {
        ibl_context *ctx;
        ibl_context_desc desc = {0};
        desc.threads = threads;
        if (ibl_context_create(&desc, &ctx) != IBL_OK) return 1;
        ibl_cubemap src, box, gauss;
        if (ibl_cubemap_alloc(ctx, 64, 1, &src) != IBL_OK || ibl_cubemap_alloc(ctx, 16, 5, &box) != IBL_OK ||
            ibl_cubemap_alloc(ctx, 32, 6, &gauss) != IBL_OK)
            return 1;
        fill(&src);
        /* the talk's gauss configuration: shininess 1..1000 over 6 levels, lod = a - 0.5 log2 s */
        float shininess[6];
        for (int l = 0; l < 6; l++) shininess[l] = (float)(1000.0 * pow(1000.0, -l / 5.0));
        double t_box[RUNS], t_gauss[RUNS], t_overlap[RUNS], t_overlap2[RUNS];
        for (int r = 0; r < RUNS; r++) {
            double t0 = bench_now_ms();
            ibl__specular_box(ctx, &src, &box);
            double t1 = bench_now_ms();
            ibl__specular_gauss(ctx, &src, &gauss, shininess);
            double t2 = bench_now_ms();
            for (int l = 0; l < gauss.levels; l++) ibl_edge_fixup_apply(ctx, IBL_EDGE_FIXUP_OVERLAP, &gauss, l);
            double t3 = bench_now_ms();
            for (int l = 0; l < gauss.levels; l++) ibl_edge_fixup_apply(ctx, IBL_EDGE_FIXUP_OVERLAP2, &gauss, l);
            double t4 = bench_now_ms();
            t_box[r] = t1 - t0, t_gauss[r] = t2 - t1, t_overlap[r] = t3 - t2, t_overlap2[r] = t4 - t3;
        }
        printf("threads %d, median of %d runs (ms):\n", threads, RUNS);
        printf("  box   16x16x6, 5 levels, from 64x64x6:   %.3f\n", bench_median(t_box, RUNS));
        printf("  gauss 32x32x6, 6 levels, from 64x64x6:   %.3f\n", bench_median(t_gauss, RUNS));
        printf("  overlap  on the 6 levels of 32x32x6:     %.3f\n", bench_median(t_overlap, RUNS));
        printf("  overlap2 on the 6 levels of 32x32x6:     %.3f\n", bench_median(t_overlap2, RUNS));
        ibl_cubemap_free(ctx, &src);
        ibl_cubemap_free(ctx, &box);
        ibl_cubemap_free(ctx, &gauss);
        ibl_context_destroy(ctx);
    }
    /* per-texel direction cost, as the prefilter pays it for every output texel */
    ibl_edge_fixup kinds[3] = {IBL_EDGE_FIXUP_NONE, IBL_EDGE_FIXUP_BENT, IBL_EDGE_FIXUP_WARP};
    for (int k = 0; k < 3; k++) {
        double t[RUNS];
        volatile float sink = 0;
        for (int r = 0; r < RUNS; r++) {
            double t0 = bench_now_ms();
            for (int f = 0; f < 6; f++)
                for (int y = 0; y < 32; y++)
                    for (int x = 0; x < 32; x++)
                        sink += ibl_edge_fixup_texel_direction(kinds[k], NULL, f, 32, x, y, 0.1f).x;
            t[r] = bench_now_ms() - t0;
        }
        printf("texel_direction %-5s: %.1f ns per texel (32x32x6)\n", ibl_edge_fixup_name(kinds[k]),
               bench_median(t, RUNS) * 1e6 / (6 * 32 * 32));
    }
    double t[RUNS];
    for (int r = 0; r < RUNS; r++) {
        double t0 = bench_now_ms();
        volatile float s = ibl__box_level_shininess(256, r % 9);
        (void)s;
        t[r] = bench_now_ms() - t0;
    }
    printf("box_level_shininess: %.2f ms per level\n", bench_median(t, RUNS));
    return 0;
}
