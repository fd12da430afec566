/* Capture and bake of the sample set (examples/rooms: 8 probes) at 128 texels a face: each
 * probe's capture (ibl_capture_probe, 2 bounces) and the probe-array bake from the captures in
 * memory (ibl_probe_bake into a temporary folder: 8 parts, the global probe, the array, the
 * buffer, the manifest), wall time and process CPU time.
 *
 *   bench_probe_bake [SAMPLES [THREADS]]   (default 16 paths per texel, every core) */
#include "ibl/ibl.h"
#include "ibl/probes.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static double clock_s(clockid_t id)
{
    struct timespec t;
    clock_gettime(id, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static void fail(ibl_context *ctx, const char *what)
{
    fprintf(stderr, "bench_probe_bake: %s: %s\n", what, ibl_context_message(ctx));
    exit(1);
}

int main(int argc, char **argv)
{
    int samples = argc > 1 ? atoi(argv[1]) : 16, threads = argc > 2 ? atoi(argv[2]) : 0;
    enum { SIZE = 128 };
    ibl_context *ctx;
    ibl_context_create(&(ibl_context_desc){.threads = threads}, &ctx);
    ibl_probe_set set;
    ibl_scene *scene;
    ibl_cubemap env;
    if (ibl_probe_set_load(ctx, IBL_SOURCE_DIR "/examples/rooms/probes.json", &set) != IBL_OK) fail(ctx, "set");
    if (ibl_scene_load_gltf(ctx, IBL_SOURCE_DIR "/examples/rooms/scene.gltf", &scene) != IBL_OK) fail(ctx, "scene");
    if (ibl_probe_set_environment(ctx, &set, &env) != IBL_OK) fail(ctx, "environment");
    ibl_cubemap *caps = calloc((size_t)set.probe_count, sizeof *caps);
    printf("capture + bake of examples/rooms: %d probes, %d texels a face, %d paths per texel, "
           "2 bounces, %d threads\n", set.probe_count, SIZE, samples, ibl_context_threads(ctx));
    double w0 = clock_s(CLOCK_MONOTONIC), c0 = clock_s(CLOCK_PROCESS_CPUTIME_ID);
    for (int i = 0; i < set.probe_count; i++) {
        double w = clock_s(CLOCK_MONOTONIC), c = clock_s(CLOCK_PROCESS_CPUTIME_ID);
        ibl_capture_desc d = {.samples = samples, .size = SIZE};
        if (ibl_capture_probe(ctx, scene, &env, &set.probes[i], i, &d, &caps[i]) != IBL_OK) fail(ctx, "capture");
        printf("  capture %-14s %-9s %7.2f s wall %7.2f s CPU\n", set.probes[i].name,
               ibl_capture_mode_name(set.probes[i].capture), clock_s(CLOCK_MONOTONIC) - w,
               clock_s(CLOCK_PROCESS_CPUTIME_ID) - c);
    }
    double w1 = clock_s(CLOCK_MONOTONIC), c1 = clock_s(CLOCK_PROCESS_CPUTIME_ID);
    char dir[] = "/tmp/ibl-bench-probes-XXXXXX";
    if (!mkdtemp(dir)) return 1;
    char out[sizeof dir + 8];
    snprintf(out, sizeof out, "%s/bake", dir);
    ibl_probe_bake_desc bd = {.cubes = caps};
    ibl_probe_bake_report rep;
    if (ibl_probe_bake(ctx, &set, &env, &bd, out, &rep) != IBL_OK) fail(ctx, "bake");
    double w2 = clock_s(CLOCK_MONOTONIC), c2 = clock_s(CLOCK_PROCESS_CPUTIME_ID);
    printf("  bake (%d parts filtered, global %d)          %7.2f s wall %7.2f s CPU\n", rep.computed,
           set.global.size, w2 - w1, c2 - c1);
    printf("  total                                  %7.2f s wall %7.2f s CPU (captures %.2f s wall)\n",
           w2 - w0, c2 - c0, w1 - w0);
    char cmd[sizeof dir + 16];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    if (system(cmd) != 0) fprintf(stderr, "bench_probe_bake: could not remove %s\n", dir);
    for (int i = 0; i < set.probe_count; i++) ibl_cubemap_free(ctx, &caps[i]);
    free(caps);
    ibl_cubemap_free(ctx, &env);
    ibl_scene_destroy(scene);
    ibl_probe_set_free(ctx, &set);
    ibl_context_destroy(ctx);
    return 0;
}
