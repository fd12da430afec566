/*
 * ibl/layout.h - 2D layouts of a sphere of directions, and conversion to and from cubemaps.
 *
 * World frame: right-handed, +Y up. An equirectangular image's centre column looks toward
 * -Z, its right quarter toward +X, its top row is +Y (see docs/CONVENTIONS.md).
 */
#ifndef IBL_LAYOUT_H
#define IBL_LAYOUT_H

#include "core.h"
#include "cubemap.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum ibl_layout {
    IBL_LAYOUT_AUTO = 0,   /* detect from the aspect ratio                              */
    IBL_LAYOUT_EQUIRECT,   /* 2:1 latitude-longitude                                   */
    IBL_LAYOUT_HCROSS,     /* 4:3 horizontal cross                                      */
    IBL_LAYOUT_VCROSS,     /* 3:4 vertical cross                                        */
    IBL_LAYOUT_HSTRIP,     /* 6:1 faces left to right in the order +X -X +Y -Y +Z -Z    */
    IBL_LAYOUT_VSTRIP,     /* 1:6 faces top to bottom in the same order                 */
    IBL_LAYOUT_ANGULAR,    /* 1:1 Debevec angular map (light probe)                     */
    IBL_LAYOUT_OCTAHEDRAL, /* 1:1 octahedral map                                        */
    IBL_LAYOUT_FACES,      /* six separate face images                                  */
    IBL_LAYOUT_CUBE        /* already a cube texture                                    */
} ibl_layout;

const char *ibl_layout_name(ibl_layout layout); /* "equirect", "hcross", ... */
/* Case-insensitive; also "latlong", "equirectangular", "probe", "octahedron". 0 if unknown
 * (*out untouched). */
int ibl_layout_from_name(const char *name, ibl_layout *out);
/* The layout an image of this size most likely holds (IBL_LAYOUT_AUTO if none fits). 1:1
 * images are reported as angular; pass --layout octahedral to override. */
ibl_layout ibl_layout_detect(int width, int height);
/* The face edge ibl_image_to_cubemap gives a width x height picture in `layout` (AUTO: the
 * detected one) when its desc.size is 0; 0 when the layout does not fit that size. */
int ibl_layout_cube_size(ibl_layout layout, int width, int height);

/* How the picture's frame relates to the world frame:
 *   world = Yaw(yaw_degrees) * Mirror * ZUp * picture   (ZUp first, yaw last).
 * z_up maps (x, y, z) -> (x, z, -y); mirror maps x -> -x; yaw turns about +Y, right-handed, so
 * yaw 90 takes +X to -Z and slides an equirect's content left by a quarter. Quarter turns,
 * mirror and z_up move the texels of cube layouts exactly. See docs/CONVENTIONS.md. */
typedef struct ibl_orientation {
    float yaw_degrees; /* rotate the environment about the up axis (positive: counter-clockwise seen from above) */
    int mirror;        /* flip left-right (for images that look at the sphere from outside) */
    int z_up;          /* the picture was made with +Z up (converted to +Y up)              */
} ibl_orientation;

/* World direction for a direction of the picture's own frame, and back. */
ibl_vec3 ibl_orientation_apply(const ibl_orientation *o, ibl_vec3 picture_dir);
ibl_vec3 ibl_orientation_invert(const ibl_orientation *o, ibl_vec3 world_dir);

typedef struct ibl_to_cube_desc {
    ibl_layout layout;        /* 0: detect                                                 */
    int size;                 /* face edge; 0: chosen from the input's resolution          */
    ibl_orientation orientation;
    int samples_per_axis;     /* supersampling of each cube texel's footprint; 0: automatic */
} ibl_to_cube_desc;

/* Converts a flat image in any layout to a one-level cubemap (allocated into out). Each
 * texel is the solid-angle-weighted mean of the source over its footprint (an equirect's small
 * bright sources keep their energy at any cube size; docs/CONVENTIONS.md gives the measured
 * accuracy). Cube layouts at their own size are copied texel for texel. */
ibl_status ibl_image_to_cubemap(ibl_context *ctx, const ibl_image *image,
                                const ibl_to_cube_desc *desc, ibl_cubemap *out);
/* Six face images (+X -X +Y -Y +Z -Z), all square and of one size. */
ibl_status ibl_faces_to_cubemap(ibl_context *ctx, const ibl_image faces[6],
                                const ibl_to_cube_desc *desc, ibl_cubemap *out);

typedef struct ibl_from_cube_desc {
    ibl_layout layout;  /* required (not AUTO, not FACES)                                 */
    int level;          /* which mip level                                                 */
    int width;          /* output width; 0: natural for the layout and face size           */
    ibl_orientation orientation;
    int samples_per_axis; /* 0: automatic                                                  */
} ibl_from_cube_desc;

/* Converts one level of a cubemap to a flat image in a layout (allocated into out). Each
 * pixel averages its footprint (from the area-correct mip level matching its size), so
 * nothing aliases; pixels outside the angular map's disk and cells of a cross that hold no
 * face are transparent black. */
ibl_status ibl_cubemap_to_image(ibl_context *ctx, const ibl_cubemap *cube,
                                const ibl_from_cube_desc *desc, ibl_image *out);
/* Copies the six faces of one level into six new images. */
ibl_status ibl_cubemap_to_faces(ibl_context *ctx, const ibl_cubemap *cube, int level,
                                ibl_image faces[6]);

/* The solid-angle-weighted mean (RGBA) of a flat image in a layout (IBL_LAYOUT_AUTO: detected
 * from the aspect ratio): the mean radiance over the sphere, what a white diffuse sphere lit
 * by the image would average. An equirect's pixels are weighted by their exact solid angles,
 * (2 pi / W) (cos theta0 - cos theta1) for a row spanning theta0..theta1 from +Y. The other
 * layouts are converted by ibl_image_to_cubemap at their natural size and the cube texels
 * weighted by their exact solid angles (ibl_cubemap_mean): exact for crosses and strips,
 * whose cells are copied texel for texel; angular and octahedral maps are resampled first
 * (each texel the solid-angle-weighted mean of its footprint). */
ibl_status ibl_image_mean(ibl_context *ctx, const ibl_image *image, ibl_layout layout,
                          double out[4]);

/* Direction <-> normalised picture coordinates (u, v in [0, 1], v = 0 at the top) of the
 * sphere layouts (equirect, angular, octahedral); returns 0 where (u, v) is outside the map. */
int ibl_layout_direction(ibl_layout layout, float u, float v, ibl_vec3 *dir);
int ibl_layout_uv(ibl_layout layout, ibl_vec3 dir, float *u, float *v);

#ifdef __cplusplus
}
#endif
#endif
