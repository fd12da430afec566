/*
 * ibl/skin.h - skin under image-based lighting, the offline half: the stretch map of a mesh's
 * texture space, the normal map scattered by the skin's diffusion profile, and the thickness
 * map for translucency. The runtime half (the diffuse term with three scattered normals and
 * the translucency) is in shade.h ("Skin"), and shaders/ibl_skin.glsl, ibl_skin.hlsl.
 *
 * The method (docs/SKIN.md): when light arrives evenly from all directions, as ambient light
 * roughly does, local subsurface scattering amounts to blurring the normal map with the skin's
 * diffusion profile, once per colour channel (Daqi 2016, "PBR Series 6.2: SSS based on normal
 * map"). The profile is d'Eon and Luebke's sum of six Gaussians (GPU Gems 3, ch. 14, 2007);
 * the blur runs in texture space, each Gaussian separable, its width in texels corrected per
 * texel by the stretch map (d'Eon, Luebke and Enderton 2007, "Efficient Rendering of Human
 * Skin", EGSR: texture-space diffusion with stretch correction).
 *
 * Meshes are ibl_scene (scene.h): glTF 2.0 or Wavefront OBJ with texture coordinates, read by
 * ibl_scene_load. Textures follow glTF: v = 0 at the image's top row; u, v in [0, 1] cover the
 * image (no wrapping).
 */
#ifndef IBL_SKIN_H
#define IBL_SKIN_H

#include "core.h"
#include "scene.h"
#include "shade.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Reads a table of Gaussians from JSON:
 *   {"gaussians": [{"variance_mm2": 0.0064, "weights": [0.233, 0.455, 0.649]}, ...]}
 * 1 to IBL_SKIN_MAX_GAUSSIANS entries, variances > 0, weights >= 0. Errors name the file and
 * the field. The weights are taken as they are (a profile need not integrate to 1). */
ibl_status ibl_skin_profile_load(ibl_context *ctx, const char *path, ibl_skin_profile *out);

/* The radially symmetric profile R_c(r) = sum_i w_ci G(v_i, r) at distance r (mm), with the
 * normalised 2D Gaussian G(v, r) = exp(-r^2 / (2 v)) / (2 pi v) (GPU Gems 3, ch. 14): its
 * integral over the plane is sum_i w_ci. */
float ibl_skin_profile_eval(const ibl_skin_profile *profile, int channel, float r_mm);

/* ---- the stretch map ------------------------------------------------------------------- */

typedef struct ibl_skin_map_desc {
    int width, height; /* the texture's size (the normal map's); both > 0                     */
    int dilate;        /* texels filled past the UV charts' edges; 0: 16; < 0: none            */
} ibl_skin_map_desc;

/* Rasterises the mesh in UV space (a texel belongs to the triangle that covers its centre;
 * the last such triangle in the file wins) and stores per texel the world-space length of a
 * unit step in U (R) and in V (G), in the mesh's units per whole texture (|dP/du|, |dP/dv|,
 * constant over each triangle), B = 0 and A = 1 where a triangle covers the texel. Empty
 * texels within `dilate` texels of a chart take the mean of their filled 8-neighbours, one
 * ring per pass, so that filtering near seams never reads a zero (their A stays 0). Triangles
 * with degenerate UVs are skipped. */
ibl_status ibl_skin_stretch_map(ibl_context *ctx, const ibl_scene *mesh,
                                const ibl_skin_map_desc *desc, ibl_image *out);

/* ---- scattering the normal map ---------------------------------------------------------- */

typedef struct ibl_skin_scatter_desc {
    const ibl_skin_profile *profile; /* NULL: ibl_skin_profile_deon()                           */
    float mm_per_unit;               /* millimetres per mesh unit; 0: 1000 (glTF: metres)       */
    int max_radius;                  /* taps each side of a Gaussian at its working resolution;
                                        0: 48. Wider kernels (where the stretch is tiny) are
                                        truncated and renormalised                            */
} ibl_skin_scatter_desc;

/* Convolves a tangent-space normal map (RGB = 0.5 n + 0.5, as stored in textures) with the
 * profile, once per colour channel: out[c] = normalize(sum_i w_ci (G_i * n)), written back as
 * 0.5 n + 0.5 with alpha 1. Each Gaussian is two passes (U, then V) with its standard deviation
 * in texels taken per texel from the stretch map (ibl_skin_stretch_map of the same size): in
 * U, sigma_texels = sqrt(v_i) / (mm_per_unit * stretch_u / width). A Gaussian wider than 2
 * texels everywhere runs on a 2x2-averaged copy of the map (repeatedly, keeping it >= 2 texels
 * wide) and is upsampled bilinearly, with its width reduced so that box, Gaussian and bilinear
 * together have the variance asked for (docs/SKIN.md). Texels with no stretch (never covered
 * nor dilated) keep their input normal. Rows run in parallel; bit-identical at any thread count.
 * out receives three new images (red, green, blue profile). */
ibl_status ibl_skin_scatter_normals(ibl_context *ctx, const ibl_image *normal_map,
                                    const ibl_image *stretch, const ibl_skin_scatter_desc *desc,
                                    ibl_image out[3]);

/* ---- thickness for translucency --------------------------------------------------------- */

typedef struct ibl_skin_thickness_desc {
    ibl_skin_map_desc map;
    int rays;           /* per texel; 0: 16. 1: along the inward normal only                     */
    float cone_degrees; /* half-angle of the cone of rays around the inward normal; 0: 30       */
    float max_distance; /* mesh units; rays that hit nothing count as this; 0: the bounding
                           box's diagonal                                                      */
} ibl_skin_thickness_desc;

/* Bakes the local thickness of a closed mesh: from each covered texel's surface point, rays go
 * inward (around the negated interpolated normal; `rays` directions spread evenly over a cone,
 * a Fibonacci spiral on its cap, the same for every texel) and the thickness is the mean
 * distance to the first surface they hit, in mesh units: R = G = B = thickness, A = coverage
 * (dilated like the stretch map). A sphere of radius R gives 2R cos(theta) along each ray
 * (the chord), a slab of depth d gives d / cos(theta). Bit-identical at any thread count. */
ibl_status ibl_skin_thickness_map(ibl_context *ctx, const ibl_scene *mesh,
                                  const ibl_skin_thickness_desc *desc, ibl_image *out);

/* In place: thickness in mesh units -> the grey transmittance map the runtime reads
 * (ibl_skin_surface.transmittance): t = saturate(1 - d mm_per_unit / range_mm), so that the
 * runtime recovers d = (1 - t) range_mm. range_mm <= 0: IBL_SKIN_THICKNESS_RANGE_MM.
 * RGB = t, alpha kept. */
void ibl_skin_transmittance_from_thickness(ibl_image *thickness, float mm_per_unit,
                                           float range_mm);

#ifdef __cplusplus
}
#endif
#endif
