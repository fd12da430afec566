/* Test data for the skin bakes, made here (no assets): a UV sphere or a head-like blob as a
 * Wavefront OBJ, a closed slab, and a procedural normal map of pores. */
#ifndef IBL_TEST_SKIN_DATA_H
#define IBL_TEST_SKIN_DATA_H

#include "ibl/core.h"

/* A UV sphere of radius r centred at the origin, seg_u x seg_v quads: vertex (i, j) at
 * u = i / seg_u, image v = j / seg_v (v = 0 at the top: +Y), theta = pi v, phi = 2 pi u,
 * P = r (sin theta cos phi, cos theta, -sin theta sin phi), normals radial. blob > 0 makes a
 * head-like shape instead (stretched along Y, a nose and brow bumps of that relative height;
 * normals from the faces then). Returns 0 on success. */
int skin_write_sphere_obj(const char *path, double r, int seg_u, int seg_v, double blob);
/* An ellipsoid of radii (rx, ry, rz) with the sphere's UVs and its true normals: with a small
 * rz, a thin flap (an ear) whose thickness falls to 0 at the rim. */
int skin_write_ellipsoid_obj(const char *path, double rx, double ry, double rz, int seg_u, int seg_v);
/* A closed box [-sx/2, sx/2] x [-depth, 0] x [-sz/2, sz/2]: its top face (y = 0) carries the
 * whole texture (u along +x, image v along +z), the other faces have no texture area. */
int skin_write_slab_obj(const char *path, double sx, double sz, double depth);
/* A tangent-space normal map (RGB = 0.5 n + 0.5) of a skin-like height field: pores (small
 * round dimples on a jittered grid, `pores` per row) and fine creases. */
void skin_pores_normal_map(ibl_image *im, int pores, double depth);

#endif
