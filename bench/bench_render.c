/* Preview speed: `ibl render`'s 1024x512 runtime image (split-sum shading of the sphere grid
 * in front of the environment; median of 9 runs) and the probe building it needs when given a
 * plain environment (specular.h chain, sh.h, brdf.h tables; median of 3 runs).
 * Usage: bench_render [DATA_DIR]. */
#include "ibl/ibl.h"
#include "ibl/render.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

static int cmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* A sky-like synthetic environment with a small bright sun (the real HDRIs need the readers). */
static void synthetic(ibl_cubemap *c)
{
    for (int f = 0; f < 6; f++) {
        float *t = ibl_cubemap_face(c, 0, f);
        for (int y = 0; y < c->size; y++)
            for (int x = 0; x < c->size; x++) {
                ibl_vec3 d = ibl_cube_texel_direction(f, c->size, x, y);
                float sun = d.x * 0.5f + d.y * 0.6f - d.z * 0.62f > 0.995f ? 2000.0f : 0.0f;
                float *p = t + ((size_t)y * c->size + x) * 4;
                p[0] = 0.4f + 0.6f * fmaxf(d.y, 0.0f) + sun;
                p[1] = 0.5f + 0.7f * fmaxf(d.y, 0.0f) + sun;
                p[2] = 0.6f + 1.2f * fmaxf(d.y, 0.0f) + sun;
                p[3] = 1.0f;
            }
    }
}

int main(int argc, char **argv)
{
    (void)argc;
    (void)argv;
    ibl_context *ctx;
    if (ibl_context_create(NULL, &ctx) != IBL_OK) return 1;
    ibl_cubemap env;
    if (ibl_cubemap_alloc(ctx, 256, 1, &env) != IBL_OK) return 1;
    synthetic(&env);
    enum { RUNS = 9, PROBE_RUNS = 3 };
    double t_probe[PROBE_RUNS], t_render[RUNS];
    ibl_probe probe;
    ibl_bake_data bake;
    ibl_bake_desc bd;
    ibl_render_bake_desc(&env, 128, &bd);
    for (int r = 0; r < PROBE_RUNS; r++) {
        double t0 = now();
        if (ibl_bake_compute(ctx, &env, &bd, &bake) != IBL_OK) return 1;
        if (ibl_bake_probe(ctx, &bake, &probe) != IBL_OK) return 1;
        t_probe[r] = now() - t0;
        if (r + 1 < PROBE_RUNS) ibl_bake_free(ctx, &bake);
    }
    ibl_render_desc d = {.width = 1024, .height = 512, .environment = &env};
    for (int r = 0; r < RUNS; r++) {
        ibl_image im;
        double t0 = now();
        if (ibl_render(ctx, &probe, &d, &im, NULL) != IBL_OK) return 1;
        t_render[r] = now() - t0;
        ibl_image_free(ctx, &im);
    }
    qsort(t_probe, PROBE_RUNS, sizeof(double), cmp);
    qsort(t_render, RUNS, sizeof(double), cmp);
    printf("threads %d\n", ibl_context_threads(ctx));
    printf("render 1024x512 runtime (split-sum):   median %.3f s (min %.3f, max %.3f)\n",
           t_render[RUNS / 2], t_render[0], t_render[RUNS - 1]);
    printf("in-memory bake of a 256 cube (ibl_render_bake_desc: chain of 128, irradiance, SH, "
           "tables): median %.3f s\n",
           t_probe[PROBE_RUNS / 2]);
    ibl_bake_free(ctx, &bake);
    ibl_cubemap_free(ctx, &env);
    ibl_context_destroy(ctx);
    return 0;
}
