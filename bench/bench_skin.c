/* Skin bakes at texture sizes up to 4k (docs/SKIN.md "Speed"): the stretch map, the normal map
 * scattered by the six-Gaussian profile (1 and 2 threads, checked bit-identical) and the
 * thickness map, on a head-like blob (radius 0.1 m, 256 x 128 quads, glTF units: metres) with
 * a procedural pore normal map, both made here (tests/support/skin_data.c).
 *
 *   bench_skin [SIZE...]          sizes of the square maps (default 1024 2048 4096)
 *   bench_skin --write DIR [SIZE] writes DIR/head.obj, DIR/ear.obj (a thin flap) and
 *                                 DIR/pores.png (SIZE, default 1024)
 *                                 for `ibl sss` and `ibl render` (docs/SKIN.md) and exits
 * Wall-clock seconds, median of 3 runs; thickness: 16 rays per texel, at most 1024. */
#include "ibl/ibl.h"
#include "bench_timing.h"
#include "skin_data.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static double median_ms(double t[3]) { return bench_median(t, 3); }

/* CPU seconds of the process (all threads): the host is shared, wall time is noisy */
static double cpu_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int write_data(const char *dir, int size)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/head.obj", dir);
    if (skin_write_sphere_obj(path, 0.1, 256, 128, 0.25) != 0) return fprintf(stderr, "cannot write %s\n", path), 1;
    /* a thin flap for translucency: 60 x 80 mm, 5 mm thick at its centre */
    snprintf(path, sizeof path, "%s/ear.obj", dir);
    if (skin_write_ellipsoid_obj(path, 0.03, 0.04, 0.0025, 128, 64) != 0) return fprintf(stderr, "cannot write %s\n", path), 1;
    ibl_context *ctx;
    ibl_context_create(NULL, &ctx);
    ibl_image n;
    if (ibl_image_alloc(ctx, size, size, &n) != IBL_OK) return 1;
    skin_pores_normal_map(&n, size / 8, 1.0);
    snprintf(path, sizeof path, "%s/pores.png", dir);
    ibl_status st = ibl_write_image(ctx, path, &n, &(ibl_write_desc){.format = IBL_FORMAT_RGBA16_UNORM});
    if (st != IBL_OK) fprintf(stderr, "%s\n", ibl_context_message(ctx));
    ibl_image_free(ctx, &n);
    ibl_context_destroy(ctx);
    return st != IBL_OK;
}

static void run(const ibl_scene *mesh, ibl_context *c1, ibl_context *c2, int size)
{
    ibl_image normal, stretch, out1[3], out2[3], thick;
    if (ibl_image_alloc(c2, size, size, &normal) != IBL_OK) return;
    skin_pores_normal_map(&normal, size / 8, 1.0);
    ibl_skin_map_desc md = {size, size, 0};
    double ts[3], t1[3], t2[3], c1s[3], c2s[3], tt = 0, tc = 0;
    for (int r = 0; r < 3; r++) {
        double t0 = bench_now_ms();
        ibl_skin_stretch_map(c2, mesh, &md, &stretch);
        ts[r] = bench_now_ms() - t0;
        if (r < 2) ibl_image_free(c2, &stretch);
    }
    for (int r = 0; r < 3; r++) {
        double t0 = bench_now_ms(), p0 = cpu_s();
        ibl_skin_scatter_normals(c1, &normal, &stretch, NULL, out1);
        t1[r] = bench_now_ms() - t0;
        c1s[r] = cpu_s() - p0;
        t0 = bench_now_ms();
        p0 = cpu_s();
        ibl_skin_scatter_normals(c2, &normal, &stretch, NULL, out2);
        t2[r] = bench_now_ms() - t0;
        c2s[r] = cpu_s() - p0;
        int same = 1;
        for (int c = 0; c < 3; c++) {
            same &= memcmp(out1[c].pixels, out2[c].pixels, sizeof(float) * 4 * size * size) == 0;
            ibl_image_free(c1, &out1[c]);
            ibl_image_free(c2, &out2[c]);
        }
        if (!same) printf("  (1 and 2 threads differ!)\n");
    }
    if (size <= 1024 && !getenv("BENCH_SKIN_NO_THICKNESS")) {
        double t0 = bench_now_ms(), p0 = cpu_s();
        ibl_skin_thickness_map(c2, mesh, &(ibl_skin_thickness_desc){md, 16, 0, 0}, &thick);
        tt = bench_now_ms() - t0;
        tc = cpu_s() - p0;
        ibl_image_free(c2, &thick);
    }
    printf("| %5d | %7.2f | %7.2f (%.2f CPU) | %7.2f (%.2f CPU) | ", size, median_ms(ts) / 1e3,
           median_ms(t1) / 1e3, bench_median(c1s, 3), median_ms(t2) / 1e3, bench_median(c2s, 3));
    if (tt > 0) printf("%7.2f (%.2f CPU) |\n", tt / 1e3, tc);
    else printf("      - |\n");
    ibl_image_free(c2, &stretch);
    ibl_image_free(c2, &normal);
}

int main(int argc, char **argv)
{
    if (argc >= 3 && strcmp(argv[1], "--write") == 0) return write_data(argv[2], argc > 3 ? atoi(argv[3]) : 1024);
    ibl_context *c1, *c2;
    ibl_context_create(&(ibl_context_desc){.threads = 1}, &c1);
    ibl_context_create(&(ibl_context_desc){.threads = 2}, &c2);
    char dir[] = "/tmp/bench_skin_XXXXXX", path[64];
    if (!mkdtemp(dir)) return 1;
    snprintf(path, sizeof path, "%s/head.obj", dir);
    if (skin_write_sphere_obj(path, 0.1, 256, 128, 0.25) != 0) return 1;
    ibl_scene *mesh;
    if (ibl_scene_load(c2, path, &mesh) != IBL_OK) return fprintf(stderr, "%s\n", ibl_context_message(c2)), 1;
    printf("| size | stretch s (2 thr) | scatter s, 1 thread | scatter s, 2 threads | thickness s (2 thr, 16 rays) |\n");
    printf("|---|---|---|---|---|\n");
    int sizes[8] = {1024, 2048, 4096}, count = 3;
    if (argc > 1) {
        count = 0;
        for (int i = 1; i < argc && count < 8; i++) sizes[count++] = atoi(argv[i]);
    }
    for (int i = 0; i < count; i++) run(mesh, c1, c2, sizes[i]);
    ibl_scene_destroy(mesh);
    remove(path);
    remove(dir);
    ibl_context_destroy(c1);
    ibl_context_destroy(c2);
    return 0;
}
