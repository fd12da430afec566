/*
 * ibl/cubemap.h - cube geometry (direction <-> face texel), exact texel solid angles,
 * seamless bilinear / trilinear sampling and the area-correct mip chain.
 *
 * Face orientation follows the OpenGL / Vulkan / KTX2 cube convention (see
 * docs/CONVENTIONS.md): for direction r with major axis m,
 *   +X: sc=-rz tc=-ry   -X: sc=+rz tc=-ry   +Y: sc=+rx tc=+rz
 *   -Y: sc=+rx tc=-rz   +Z: sc=+rx tc=-ry   -Z: sc=-rx tc=-ry
 *   s = (sc/|m| + 1)/2, t = (tc/|m| + 1)/2, texel (x, y) covers s in [x/N, (x+1)/N],
 *   t in [y/N, (y+1)/N], and y = 0 is the first row in memory.
 */
#ifndef IBL_CUBEMAP_H
#define IBL_CUBEMAP_H

#include "core.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct ibl_vec3 {
    float x, y, z;
} ibl_vec3;

/* Unnormalised direction through face coordinates (s, t) in [0, 1]. */
ibl_vec3 ibl_cube_direction(int face, float s, float t);
void ibl_cube_direction_d(int face, double s, double t, double dir[3]);
/* Face and (s, t) in [0, 1] for any non-zero direction. */
int ibl_cube_face_st(ibl_vec3 dir, float *s, float *t);
int ibl_cube_face_st_d(const double dir[3], double *s, double *t);
/* Normalised direction through the centre of texel (x, y) of a face of edge n. */
ibl_vec3 ibl_cube_texel_direction(int face, int n, int x, int y);

/* Exact solid angle of texel (x, y) on a face of edge n (a spherical quadrilateral). */
double ibl_cube_texel_solid_angle(int n, int x, int y);
/* Solid angles of every texel of one face, row-major (n*n values; identical on all faces). */
void ibl_cube_solid_angle_table(int n, float *out);
/* Solid angle of the part of a face with face-plane coordinates u in [u0,u1], v in [v0,v1]
 * (each in [-1, 1]). */
double ibl_cube_rect_solid_angle(double u0, double v0, double u1, double v1);

/* Seamless bilinear sample of one level (filters across face edges; corners use the three
 * texels that meet there). dir need not be normalised. out: RGBA. */
void ibl_cubemap_sample_bilinear(const ibl_cubemap *cube, int level, ibl_vec3 dir, float out[4]);
/* Trilinear: linear between the two levels around lod (clamped to [0, levels-1]). */
void ibl_cubemap_sample_trilinear(const ibl_cubemap *cube, float lod, ibl_vec3 dir,
                                  float out[4]);
/* Nearest texel of a level. */
void ibl_cubemap_sample_nearest(const ibl_cubemap *cube, int level, ibl_vec3 dir, float out[4]);

/* Fills levels 1.. from level 0: each texel is the solid-angle-weighted mean of its 2x2
 * children, so a constant cube stays constant and sum(L * solid angle) is kept per level. */
ibl_status ibl_cubemap_build_mips(ibl_context *ctx, ibl_cubemap *cube);

/* Solid-angle-weighted mean of a level (RGBA, double). */
void ibl_cubemap_mean(const ibl_cubemap *cube, int level, double out[4]);

/* Resamples a cube to another edge size. Shrinking by an integer ratio gives each texel the
 * exact solid-angle-weighted mean of the source texels it covers (a power-of-two ratio takes
 * src's own area-correct mip level when it has one); any other size is a supersampled
 * bilinear box. Only level 0 of dst is written. */
ibl_status ibl_cubemap_resample(ibl_context *ctx, const ibl_cubemap *src, ibl_cubemap *dst);

#ifdef __cplusplus
}
#endif
#endif
