/* Ray casting in the sample scene (examples/rooms): Embree 3 (src/scene, what `ibl capture`
 * uses) against the preview renderer's hand-written BVH (src/render/mesh.c, left as it is
 * for `ibl render --mesh`). The same rays through both, single-threaded: from each probe of
 * the sample set in directions of a fixed pseudo-random sequence, nearest hit with normal.
 * Both structures get the same triangles: the scene's are written to an OBJ (with vertex
 * colours, so that mesh.c computes no AO) and read back with ibl_mesh_load_obj.
 *
 *   bench_scene [RAYS]        (default 2,000,000; run from the build folder or anywhere) */
#include "ibl/ibl.h"
#include "scene/scene_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#ifndef IBL_SOURCE_DIR
#define IBL_SOURCE_DIR "."
#endif

/* the preview renderer's query (src/render/mesh.c; internal, declared there in render.c) */
int ibl__mesh_intersect(const ibl_mesh *m, ibl_vec3 o, ibl_vec3 d, float *t, ibl_vec3 *n,
                        float *ao);

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts); /* CPU time: the host is shared */
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static uint64_t next(uint64_t *s)
{
    uint64_t z = (*s += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

static int write_obj(const ibl_scene *s, const char *path)
{
    FILE *f = fopen(path, "w");
    if (!f) return 0;
    for (int v = 0; v < s->vertex_count; v++)
        fprintf(f, "v %.9g %.9g %.9g 1 1 1\n", s->positions[3 * v], s->positions[3 * v + 1],
                s->positions[3 * v + 2]);
    for (int t = 0; t < s->triangle_count; t++)
        fprintf(f, "f %u %u %u\n", s->indices[3 * t] + 1, s->indices[3 * t + 1] + 1,
                s->indices[3 * t + 2] + 1);
    return fclose(f) == 0;
}

int main(int argc, char **argv)
{
    long rays = argc > 1 ? atol(argv[1]) : 2000000;
    ibl_context *ctx;
    ibl_context_create(&(ibl_context_desc){.threads = 1}, &ctx);
    const char *gltf = IBL_SOURCE_DIR "/examples/rooms/scene.gltf";
    ibl_probe_set set;
    ibl_scene *scene;
    double t0 = now();
    if (ibl_scene_load_gltf(ctx, gltf, &scene) != IBL_OK ||
        ibl_probe_set_load(ctx, IBL_SOURCE_DIR "/examples/rooms/probes.json", &set) != IBL_OK) {
        fprintf(stderr, "%s\n", ibl_context_message(ctx));
        return 1;
    }
    double t_gltf = now() - t0;
    /* Embree's build alone: the same arrays again through ibl_scene_create */
    ibl_scene_material *mats = scene->materials;
    ibl_scene_desc d = {scene->vertex_count, scene->triangle_count, scene->positions,
                        scene->normals, scene->uvs, scene->indices, scene->material_ids, mats,
                        scene->material_count, scene->textures, scene->texture_count, "again"};
    ibl_scene *again;
    t0 = now();
    ibl_scene_create(ctx, &d, &again);
    double t_embree_build = now() - t0;
    ibl_scene_destroy(again);
    const char *obj = "bench_scene_rooms.obj";
    if (!write_obj(scene, obj)) return 1;
    ibl_mesh mesh;
    t0 = now();
    if (ibl_mesh_load_obj(ctx, obj, 0, &mesh) != IBL_OK) {
        fprintf(stderr, "%s\n", ibl_context_message(ctx));
        return 1;
    }
    double t_mesh_load = now() - t0;
    remove(obj);

    ibl_vec3 *o = malloc((size_t)rays * sizeof *o), *dir = malloc((size_t)rays * sizeof *dir);
    uint64_t seed = 1;
    for (long i = 0; i < rays; i++) {
        o[i] = set.probes[i % set.probe_count].position;
        double z = 2.0 * (next(&seed) >> 11) * 0x1p-53 - 1.0, phi = 6.283185307179586 * (next(&seed) >> 11) * 0x1p-53;
        double r = sqrt(fmax(0.0, 1.0 - z * z));
        dir[i] = (ibl_vec3){(float)(r * cos(phi)), (float)(r * sin(phi)), (float)z};
    }
    /* ibl_mesh_load_obj centres the mesh and scales it to a height of 3.2 (the preview's
     * frame): the rays go to that frame for mesh.c and its distances come back */
    float c[3], scale = 0.0f;
    for (int k = 0; k < 3; k++) {
        c[k] = 0.5f * (scene->bounds_min[k] + scene->bounds_max[k]);
        scale = fmaxf(scale, scene->bounds_max[k] - scene->bounds_min[k]);
    }
    scale = 3.2f / scale;
    double sum_e = 0, sum_m = 0;
    long hits_e = 0, hits_m = 0, agree = 0;
    float *te = malloc((size_t)rays * sizeof *te);
    t0 = now();
    for (long i = 0; i < rays; i++) {
        ibl_scene_hit h;
        te[i] = ibl_scene_intersect(scene, o[i], dir[i], 0.0f, INFINITY, &h) ? h.t : -1.0f;
        if (te[i] >= 0) hits_e++, sum_e += h.normal.y;
    }
    double t_embree = now() - t0;
    t0 = now();
    for (long i = 0; i < rays; i++) {
        float t, ao;
        ibl_vec3 n;
        ibl_vec3 om = {(o[i].x - c[0]) * scale, (o[i].y - c[1]) * scale, (o[i].z - c[2]) * scale};
        if (ibl__mesh_intersect(&mesh, om, dir[i], &t, &n, &ao)) {
            t /= scale;
            hits_m++, sum_m += n.y;
            if (te[i] >= 0 && fabsf(te[i] - t) <= 1e-4f * (1.0f + t)) agree++;
        }
    }
    double t_mesh = now() - t0;
    printf("scene: %s, %d triangles; %ld rays from the %d probes of probes.json, 1 thread\n",
           gltf, scene->triangle_count, rays, set.probe_count);
    printf("load: glTF through Assimp + Embree build %.1f ms (Embree build alone %.2f ms); "
           "OBJ parse + mesh.c BVH %.1f ms\n", 1e3 * t_gltf, 1e3 * t_embree_build, 1e3 * t_mesh_load);
    printf("%-24s %8.1f ms  %6.2f Mrays/s  hits %ld\n", "Embree 3 (src/scene)", 1e3 * t_embree,
           rays / t_embree / 1e6, hits_e);
    printf("%-24s %8.1f ms  %6.2f Mrays/s  hits %ld\n", "hand-written (mesh.c)", 1e3 * t_mesh,
           rays / t_mesh / 1e6, hits_m);
    printf("same nearest distance: %ld of %ld; Embree %.2fx as fast (sum of normal.y %.1f %.1f)\n",
           agree, hits_m, t_mesh / t_embree, sum_e, sum_m);
    free(o);
    free(dir);
    free(te);
    ibl_mesh_free(ctx, &mesh);
    ibl_probe_set_free(ctx, &set);
    ibl_scene_destroy(scene);
    ibl_context_destroy(ctx);
    return 0;
}
