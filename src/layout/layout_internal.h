/* Shared by the files of src/layout: the orientation as a matrix, the sphere layouts' mappings
 * in double precision, and the conversions each file implements. */
#ifndef IBL_LAYOUT_INTERNAL_H
#define IBL_LAYOUT_INTERNAL_H

#include "ibl/layout.h"

/* world = m * picture. An orthogonal matrix (rotation, or rotation times a mirror). */
typedef struct ibl__frame {
    double m[3][3];
    int identity;    /* m is exactly the identity                               */
    int permutation; /* m is a signed permutation (maps cube texels onto texels) */
} ibl__frame;

void ibl__frame_from_orientation(const ibl_orientation *o, ibl__frame *f);
/* A frame from an explicit matrix (classifies identity / permutation). */
void ibl__frame_from_matrix(const double m[3][3], ibl__frame *f);
/* The transpose (the inverse of an orthogonal matrix). */
void ibl__frame_transpose(const ibl__frame *f, ibl__frame *out);
/* Each cube face's centre, s and t axes (rows 0, 1, 2) expressed in the picture's frame. */
void ibl__picture_basis(const ibl__frame *frame, double basis[6][3][3]);

static inline void ibl__mul3(const double m[3][3], const double p[3], double out[3])
{
    double x = p[0], y = p[1], z = p[2];
    out[0] = m[0][0] * x + m[0][1] * y + m[0][2] * z;
    out[1] = m[1][0] * x + m[1][1] * y + m[1][2] * z;
    out[2] = m[2][0] * x + m[2][1] * y + m[2][2] * z;
}

/* Sphere layouts (equirect, angular, octahedral), (u, v) in [0, 1], v = 0 at the top.
 * dir: unit direction; returns 0 outside the map (the corners of the angular map). */
int ibl__equirect_dir(double u, double v, double d[3]);
void ibl__equirect_uv(const double d[3], double *u, double *v);
int ibl__angular_dir(double u, double v, double d[3]);
void ibl__angular_uv(const double d[3], double *u, double *v);
int ibl__octahedral_dir(double u, double v, double d[3]);
void ibl__octahedral_uv(const double d[3], double *u, double *v);
/* Solid angle per unit (u, v) area at a point of the map, up to a constant factor per layout
 * (only ratios within one output pixel are used). d is the unit direction of (u, v). */
double ibl__angular_density(double u, double v);
double ibl__octahedral_density(const double d[3]);

/* Natural sizes: the cube face a layout image holds (or resolves to), and back. */
int ibl__natural_cube_size(ibl_layout layout, int width, int height);

/* equirect/: the exact solid angle of each pixel of row `row` (0 at the top) of a width x height
 * equirect, (2 pi / width) (cos theta0 - cos theta1) with theta0 = pi row / height and
 * theta1 = pi (row + 1) / height; the solid-angle-weighted mean of an equirect (RGBA) with
 * those weights */
double ibl__equirect_row_solid_angle(int width, int height, int row);
void ibl__equirect_mean(const ibl_image *image, double out[4]);
/* equirect/to_cube.c (out: a cube already allocated, level 0 written). The vector kernels
 * follow the context (ibl__cpu_has); every choice gives the same bits. */
ibl_status ibl__equirect_to_cube(ibl_context *ctx, const ibl_image *image, const ibl__frame *frame,
                                 int samples_per_axis, ibl_cubemap *out);
/* sphere.c: angular and octahedral to cube; any sphere layout from a cube */
ibl_status ibl__sphere_to_cube(ibl_context *ctx, ibl_layout layout, const ibl_image *image,
                               const ibl__frame *frame, int samples_per_axis, ibl_cubemap *out);
ibl_status ibl__cube_to_sphere(ibl_context *ctx, const ibl_cubemap *cube, int level,
                               ibl_layout layout, const ibl__frame *frame, int samples_per_axis,
                               ibl_image *out);
/* cross.c / strip.c: where a face sits in a cube layout. cols x rows cells; rotation 0 or 180
 * (degrees, clockwise as seen in the picture). Returns 0 if the layout is not a cube layout. */
int ibl__cross_cell(ibl_layout layout, int face, int *col, int *row, int *rotation);
int ibl__strip_cell(ibl_layout layout, int face, int *col, int *row, int *rotation);
int ibl__cube_layout_grid(ibl_layout layout, int *cols, int *rows);
/* faces.c: copy the cells of a cube-layout picture into a cube's level 0, and back */
void ibl__cells_to_cube(ibl_layout layout, const ibl_image *image, ibl_cubemap *cube);
void ibl__cube_to_cells(ibl_layout layout, const ibl_cubemap *cube, int level, ibl_image *image);
/* faces.c: dst level 0 (any size) = src level `level` seen through m: dst(d) = src(m d),
 * supersampled; exact (nearest) when m is a signed permutation and the sizes agree. */
ibl_status ibl__cube_remap(ibl_context *ctx, const ibl_cubemap *src, int level,
                           const ibl__frame *m, ibl_cubemap *dst);

#endif
