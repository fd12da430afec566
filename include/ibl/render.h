/*
 * ibl/render.h - the preview renderer behind `ibl render`: a small CPU ray tracer that shows
 * a probe on a grid of spheres (GGX roughness x metalness, and a row of Blinn-Phong
 * shininess values) or on an OBJ mesh with per-vertex AO, in front of the environment, using
 * the runtime shading of shade.h. A Monte Carlo reference of the same scene (the full BRDF
 * against the unfiltered environment, no split sum) measures the approximation error.
 * Punctual lights (light.h) may be added to both.
 *
 * Output images are linear radiance (RGBA float, alpha 1); ibl_render_tonemap turns them
 * into display values. Every pixel depends only on its own index, so the output is
 * bit-identical at any thread count.
 */
#ifndef IBL_RENDER_H
#define IBL_RENDER_H

#include "core.h"
#include "cubemap.h"
#include "bake.h"
#include "shade.h"
#include "light.h"
#include "scene.h"

#ifdef __cplusplus
extern "C" {
#endif

/* A triangle mesh with per-vertex normals and ambient occlusion. */
typedef struct ibl_mesh {
    int vertex_count, triangle_count;
    float *positions; /* 3 per vertex                                         */
    float *normals;   /* 3 per vertex                                         */
    float *ao;        /* 1 per vertex, in [0, 1]                              */
    int *indices;     /* 3 per triangle                                       */
    void *accel;      /* internal bounding volume hierarchy (built on load)   */
} ibl_mesh;

/* Reads a Wavefront OBJ (v, vn, f; polygons are fanned). Per-vertex AO comes from vertex
 * colours ("v x y z r g b": the red channel) when present, otherwise it is computed by ray
 * casting the mesh against itself (ao_rays rays per vertex; 0: 64). Missing normals are
 * computed from the faces. */
ibl_status ibl_mesh_load_obj(ibl_context *ctx, const char *path, int ao_rays, ibl_mesh *out);
void ibl_mesh_free(ibl_context *ctx, ibl_mesh *mesh);

/* Skin on a mesh with texture coordinates (skin.h; shade.h "Skin"): the diffuse term of each
 * colour channel lit along its own scattered normal plus the translucency, and a glTF
 * dielectric specular (F0 0.04) on the unscattered normal map. */
typedef struct ibl_render_skin {
    const ibl_scene *mesh;           /* drawn centred and scaled like ibl_render_desc.mesh    */
    const ibl_image *normal;         /* the tangent-space normal map (0.5 n + 0.5)             */
    const ibl_image *scattered[3];   /* its red, green, blue scatterings (ibl sss)            */
    const ibl_image *transmittance;  /* grey map of ibl_skin_transmittance_from_thickness, or
                                        NULL for no translucency                             */
    float albedo[3];                 /* diffuse albedo; all zero: (0.8, 0.55, 0.45)            */
    float roughness;                 /* of the specular; 0: 0.45                               */
    float thickness_range_mm;        /* of the transmittance map; 0: the default               */
} ibl_render_skin;

typedef struct ibl_render_desc {
    int width, height;              /* 0: 1024 x 512                                            */
    ibl_shade_desc shade;           /* specular occlusion, mix, energy compensation, ...         */
    const ibl_cubemap *environment; /* unfiltered environment: background and reference;
                                       NULL: the probe's mirror, else its level 0              */
    const ibl_mesh *mesh;           /* draw this mesh instead of the spheres                    */
    int reference;                  /* Monte Carlo reference instead of the runtime shading; its
                                    samples also spread over the pixel's footprint            */
    int supersample;                /* runtime shading: n x n rays per pixel; 0: 1               */
    int reference_samples;          /* per pixel and lobe; 0: 256                                */
    unsigned seed;                  /* of the per-pixel sample rotation                          */
    float sphere_ao_min;            /* > 0: synthetic AO on the spheres, from this value at the
                                    bottom to 1 at the top (to see specular occlusion)        */
    const ibl_light *lights;        /* punctual lights (light.h), unshadowed, not drawn; the
                                    runtime shades them with ibl_lights_shade (their specular is
                                    the compositions' s_d), the reference integrates each as
                                    what it is: a delta, or a sphere of radius `size` (a
                                    directional light: a disc of angular radius atan(size)) of
                                    uniform radiance, sampled over its solid angle            */
    int light_count;
    const ibl_render_skin *skin;    /* draw this skin instead of the spheres or the mesh (runtime
                                       shading only)                                          */
    int skin_off;                   /* the skin mesh with its unscattered normal map for all
                                       three channels and no translucency: the "before"       */
} ibl_render_desc;

/* One object of the scene, for per-object measurements. */
typedef struct ibl_render_object {
    ibl_material material;
    char label[32];
} ibl_render_object;

/* The objects of the sphere scene (at most 64): fills objects and returns their count. */
int ibl_render_scene_objects(ibl_render_object *objects, int max_objects);

/* Renders into a new linear image. ids (optional, width * height ints) receives the object
 * index hit by each pixel's centre ray, -1 for the background. */
ibl_status ibl_render(ibl_context *ctx, const ibl_probe *probe, const ibl_render_desc *desc,
                      ibl_image *out, int *ids);

/* In place: scale by 2^exposure_ev and apply the filmic curve of io.h (ibl_tonemap_apply);
 * the result is display-referred in [0, 1], before the sRGB transfer function. */
void ibl_render_tonemap(ibl_image *image, float exposure_ev);

/* A new image with a and b (same height) side by side, separated by a gap, each labelled. */
ibl_status ibl_render_side_by_side(ibl_context *ctx, const ibl_image *a, const char *label_a,
                                   const ibl_image *b, const char *label_b, ibl_image *out);

/* The bake `ibl render` makes of a plain environment (bake.h, ibl_bake_compute): a GGX chain
 * of edge specular_size (0: min(128, the environment's)) down to 4x4, the BRDF tables, the
 * AmbientBRDF for Blinn-Phong materials up to shininess 100000, no preview, and the
 * environment kept as the probe's mirror and background. */
void ibl_render_bake_desc(const ibl_cubemap *environment, int specular_size, ibl_bake_desc *out);

#ifdef __cplusplus
}
#endif
#endif
