/* Tiled culling of 64 probe volumes over a 1920x1080 depth buffer (ibl_cull_probes), one
 * thread, for each of the write-up's three per-tile sorts, conservative and exact; thread CPU
 * time (the host is shared). The scene: a floor and a back wall seen from eye height, the
 * volumes (boxes and spheres) scattered over a 20 x 4 x 20 m level.
 *
 *   bench_probes [REPEATS]   (default 20) */
#include "ibl/ibl.h"
#include "ibl/probes.h"

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

static float frand(uint32_t *s)
{
    *s = *s * 1664525u + 1013904223u;
    return (float)(*s >> 8) / 16777216.0f;
}

int main(int argc, char **argv)
{
    int repeats = argc > 1 ? atoi(argv[1]) : 20;
    enum { W = 1920, H = 1080, N = 64 };
    ibl_context *ctx;
    ibl_context_create(&(ibl_context_desc){.threads = 1}, &ctx);
    ibl_camera cam = {.position = {0, 1.7f, 10}, .forward = {0, -0.15f, -1}, .up = {0, 1, 0},
                      .fov_y_degrees = 60, .width = W, .height = H};
    float *depth = malloc(sizeof(float) * W * H);
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            ibl_vec3 r = ibl_camera_ray(&cam, x + 0.5f, y + 0.5f);
            float t = 1e30f;
            if (r.y < 0) t = fminf(t, -cam.position.y / r.y);
            if (r.z < 0) t = fminf(t, (-10.0f - cam.position.z) / r.z);
            depth[(size_t)y * W + x] = t < 1e29f ? t : 0.0f;
        }
    ibl_volume v[N];
    uint32_t s = 1;
    for (int i = 0; i < N; i++) {
        ibl_vec3 c = {-10 + 20 * frand(&s), 4 * frand(&s), -10 + 20 * frand(&s)};
        if (i % 2) v[i] = (ibl_volume){.shape = IBL_VOLUME_SPHERE, .center = c, .radius = 0.5f + 2.5f * frand(&s)};
        else v[i] = (ibl_volume){.shape = IBL_VOLUME_BOX, .center = c,
                                 .half_extent = {0.5f + 2 * frand(&s), 0.5f + frand(&s), 0.5f + 2 * frand(&s)}};
    }
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
