/* Internal: the scene's storage, shared by scene.c (creation, Embree, queries), gltf.c (the
 * Assimp loader) and the probe capture (which samples the emissive triangles). */
#ifndef IBL_SCENE_INTERNAL_H
#define IBL_SCENE_INTERNAL_H

#include "ibl/scene.h"
#include "scene/libraries.h"

struct ibl_scene {
    ibl_context *ctx;
    int vertex_count, triangle_count, material_count, texture_count;
    float *positions;     /* 3 per vertex                          */
    float *normals;       /* 3 per vertex (unit)                   */
    float *uvs;           /* 2 per vertex (zeros without)          */
    uint32_t *indices;    /* 3 per triangle                        */
    int *material_ids;    /* 1 per triangle                        */
    float *face_normals;  /* 3 per triangle (unit; zero if degenerate) */
    float *areas;         /* 1 per triangle                        */
    ibl_scene_material *materials;
    ibl_image *textures;
    int emissive_count;   /* triangles whose material emits        */
    float bounds_min[3], bounds_max[3];
    ibl__embree embree; /* loaded for the scene (libraries.h) */
    RTCDevice device;
    RTCScene rtc;
};

#endif
