/*
 * ibl/scene.h - triangle scenes for probe capture: glTF 2.0 loading and ray casting.
 *
 * A scene is triangles with per-vertex normals and texture coordinates and glTF
 * metal/roughness materials (base colour, metallic, roughness, emissive; each factor may be
 * multiplied by a texture). Files are read with Assimp (Debian libassimp-dev, through its C
 * API); rays are cast with Intel Embree 3 (libembree-dev; robust, watertight triangle tests).
 * The scene is immutable once created and may be queried from any number of threads.
 *
 * Units: positions in the file's units (glTF: metres); emissive radiance is
 * emissiveFactor x KHR_materials_emissive_strength (x the emissive texture), in the units of the
 * environment it is lit with (the built-in sky's: kcd/m^2, include/ibl/sky.h).
 */
#ifndef IBL_SCENE_H
#define IBL_SCENE_H

#include "core.h"
#include "cubemap.h"

#ifdef __cplusplus
extern "C" {
#endif

/* A glTF metal/roughness material. Texture fields are indices into the scene's textures, or
 * -1 for none (ibl_scene_material_default fills the glTF defaults). */
typedef struct ibl_scene_material {
    float base_color[3];        /* linear RGB                                                   */
    float metallic, roughness;  /* perceptual roughness (alpha = roughness^2)                    */
    float emissive[3];          /* linear RGB radiance                                          */
    int base_color_texture;     /* sRGB-decoded RGB multiplies base_color                       */
    int metallic_roughness_texture; /* glTF: B = metallic, G = roughness (linear)              */
    int emissive_texture;       /* sRGB-decoded RGB multiplies emissive                         */
    int diffuse_only;           /* non-zero: a pure Lambertian reflector of albedo base_color,
                                   no specular lobe (validation scenes: the furnace)           */
    char name[64];
} ibl_scene_material;

/* White dielectric, roughness 1, metallic 1 as glTF's defaults say, no emission, no textures. */
ibl_scene_material ibl_scene_material_default(void);

/* Geometry and materials, copied by ibl_scene_create. */
typedef struct ibl_scene_desc {
    int vertex_count, triangle_count;
    const float *positions;     /* 3 per vertex                                                 */
    const float *normals;       /* 3 per vertex; NULL: each triangle's own (flat)               */
    const float *uvs;           /* 2 per vertex (glTF: v = 0 at the image's top); NULL: none    */
    const uint32_t *indices;    /* 3 per triangle, counter-clockwise seen from the front        */
    const int *material_ids;    /* 1 per triangle; NULL: material 0                             */
    const ibl_scene_material *materials; /* material_count >= 1                                */
    int material_count;
    const ibl_image *textures;  /* linear RGBA (as ibl_read_image returns them); copied         */
    int texture_count;
    const char *name;           /* for messages; NULL: "scene"                                  */
} ibl_scene_desc;

typedef struct ibl_scene ibl_scene;

ibl_status ibl_scene_create(ibl_context *ctx, const ibl_scene_desc *desc, ibl_scene **out);
/* Reads a glTF 2.0 file (.gltf with its .bin and images, or .glb). Every node's transform is
 * applied; polygons are triangulated; missing normals are computed. Errors name the file. */
ibl_status ibl_scene_load_gltf(ibl_context *ctx, const char *path, ibl_scene **out);
/* The same, or a Wavefront OBJ (.obj, by the extension; Assimp's reader, its .mtl colours as
 * base colours; v flipped so that v = 0 is the image's top, as in glTF). */
ibl_status ibl_scene_load(ibl_context *ctx, const char *path, ibl_scene **out);
void ibl_scene_destroy(ibl_scene *scene);

typedef struct ibl_scene_info {
    int vertex_count, triangle_count, material_count, texture_count;
    int emissive_triangle_count;
    float bounds_min[3], bounds_max[3];
} ibl_scene_info;
void ibl_scene_get_info(const ibl_scene *scene, ibl_scene_info *out);
const ibl_scene_material *ibl_scene_get_material(const ibl_scene *scene, int index);

typedef struct ibl_scene_hit {
    float t;                  /* distance along the (unit) direction                            */
    ibl_vec3 position;
    ibl_vec3 normal;          /* interpolated shading normal, on the side the ray came from      */
    ibl_vec3 geometric_normal; /* the triangle's, on the side the ray came from                 */
    float uv[2];              /* texture coordinates (0 without)                                */
    int triangle, material;
} ibl_scene_hit;

/* Nearest hit of the ray o + t d, t in (tmin, tmax); d must be unit length. 1 on a hit. */
int ibl_scene_intersect(const ibl_scene *scene, ibl_vec3 o, ibl_vec3 d, float tmin, float tmax,
                        ibl_scene_hit *hit);
/* 1 if anything lies on the ray between tmin and tmax. */
int ibl_scene_occluded(const ibl_scene *scene, ibl_vec3 o, ibl_vec3 d, float tmin, float tmax);

/* The material at a hit with its textures applied (bilinear, repeat). */
typedef struct ibl_scene_surface {
    float base_color[3];
    float metallic, roughness;
    float emissive[3];
    int diffuse_only;
} ibl_scene_surface;
void ibl_scene_surface_at(const ibl_scene *scene, const ibl_scene_hit *hit,
                          ibl_scene_surface *out);

#ifdef __cplusplus
}
#endif
#endif
