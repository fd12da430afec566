/* Tiled culling of 64 probe volumes over a 1920x1080 depth buffer (ibl_cull_probes), one
 * thread, for each of the write-up's three per-tile sorts, conservative and exact; thread CPU
 * time (the host is shared). The level (a floor and a back wall, 64 boxes and spheres) is
 * bench/probe_level.h; bench_probes_gpu.c runs the same on llvmpipe.
 *
 *   bench_probes [REPEATS]   (default 20) */
#include "ibl/ibl.h"
#include "ibl/probes.h"
#include "probe_level.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int main(int argc, char **argv)
{
    int repeats = argc > 1 ? atoi(argv[1]) : 20;
    enum { W = LEVEL_W, H = LEVEL_H, N = LEVEL_PROBES };
    ibl_context *ctx;
    ibl_context_create(&(ibl_context_desc){.threads = 1}, &ctx);
    ibl_camera cam = level_camera();
    float *depth = level_depth(&cam);
    ibl_volume v[N];
    level_volumes(v);
    static const char *names[3] = {"odd-even", "rank", "rank-copy"};
    printf("tiled culling, %d probes, %dx%d, 16x16 tiles, 1 thread, %d repeats\n", N, W, H, repeats);
    for (int exact = 0; exact < 2; exact++)
        for (int k = 0; k < 3; k++) {
            ibl_cull_desc d = {.tile_size = 16, .sort = (ibl_tile_sort)k, .exact = exact};
            ibl_tile_lists l;
            ibl_cull_stats st;
            double best = 1e30;
            for (int r = 0; r < repeats; r++) {
                double t0 = now();
                ibl_cull_probes(ctx, &cam, depth, v, N, &d, &l, &st);
                double t = now() - t0;
                best = t < best ? t : best;
                ibl_tile_lists_free(ctx, &l);
            }
            printf("  %-12s %-9s %8.2f ms  entries %lld  tests %lld  compares %lld\n",
                   exact ? "exact" : "conservative", names[k], best * 1e3, st.entries, st.tests,
                   st.compares);
        }
    free(depth);
    ibl_context_destroy(ctx);
    return 0;
}
