/* The level both culling benchmarks use (bench_probes.c on the CPU, bench_probes_gpu.c on
 * llvmpipe): a floor and a back wall seen from eye height on a 1920x1080 screen, and 64
 * influence volumes (boxes and spheres) scattered over a 20 x 4 x 20 m level. */
#ifndef IBL_BENCH_PROBE_LEVEL_H
#define IBL_BENCH_PROBE_LEVEL_H

#include "ibl/probes.h"

#include <math.h>
#include <stdlib.h>

enum { LEVEL_W = 1920, LEVEL_H = 1080, LEVEL_PROBES = 64 };

static float level_rand(uint32_t *s)
{
    *s = *s * 1664525u + 1013904223u;
    return (float)(*s >> 8) / 16777216.0f;
}

static ibl_camera level_camera(void)
{
    ibl_camera cam = {.position = {0, 1.7f, 10}, .forward = {0, -0.15f, -1}, .up = {0, 1, 0},
                      .fov_y_degrees = 60, .width = LEVEL_W, .height = LEVEL_H};
    return cam;
}

/* view depths (malloc) of the floor and the wall at z = -10 */
static float *level_depth(const ibl_camera *cam)
{
    float *depth = malloc(sizeof(float) * LEVEL_W * LEVEL_H);
    for (int y = 0; depth && y < LEVEL_H; y++)
        for (int x = 0; x < LEVEL_W; x++) {
            ibl_vec3 r = ibl_camera_ray(cam, x + 0.5f, y + 0.5f);
            float t = 1e30f;
            if (r.y < 0) t = fminf(t, -cam->position.y / r.y);
            if (r.z < 0) t = fminf(t, (-10.0f - cam->position.z) / r.z);
            depth[(size_t)y * LEVEL_W + x] = t < 1e29f ? t : 0.0f;
        }
    return depth;
}

static void level_volumes(ibl_volume v[LEVEL_PROBES])
{
    uint32_t s = 1;
    for (int i = 0; i < LEVEL_PROBES; i++) {
        ibl_vec3 c = {-10 + 20 * level_rand(&s), 4 * level_rand(&s), -10 + 20 * level_rand(&s)};
        if (i % 2)
            v[i] = (ibl_volume){.shape = IBL_VOLUME_SPHERE, .center = c, .radius = 0.5f + 2.5f * level_rand(&s)};
        else
            v[i] = (ibl_volume){.shape = IBL_VOLUME_BOX, .center = c,
                                .half_extent = {0.5f + 2 * level_rand(&s), 0.5f + level_rand(&s),
                                                0.5f + 2 * level_rand(&s)}};
    }
}

#endif
