/* tri-Ace 2010's two fastest prefilter kernels ("Generate PMREM (1)" box, "Generate PMREM
 * (2)" Gaussian, "Mipmap LOD"). Internal: the prefilter (specular.c) calls them for --filter
 * box and --filter gauss. docs/EDGE_FIXUP.md ("The box and Gaussian kernels") documents the
 * fits and formulas. */
#ifndef IBL_BAKE_SPECULAR_KERNELS_H
#define IBL_BAKE_SPECULAR_KERNELS_H

#include "ibl/core.h"
#include "ibl/cubemap.h"

/* dst->size and dst->levels given; fills every level: level 0 = src resampled to dst->size
 * (the exact area mean of the covered source texels when src->size is a multiple of
 * dst->size, ibl_cubemap_resample otherwise), then the area-correct box mip chain. */
ibl_status ibl__specular_box(ibl_context *ctx, const ibl_cubemap *src, ibl_cubemap *dst);

/* A 2D Gaussian blur within each face of every level of the box chain (no filtering across
 * face edges, as in the tri-Ace talk), with sigma from the level's Phong kernel exponent
 * (ibl__gauss_sigma; 0 = a mirror level, left as the box chain has it). */
ibl_status ibl__specular_gauss(ibl_context *ctx, const ibl_cubemap *src, ibl_cubemap *dst,
                               const float *phong_exponent_per_level);

/* The Phong kernel exponent whose normalised lobe best matches, in least squares over the sphere,
 * the box chain's effective kernel at `level` of a chain whose level 0 has edge `size`
 * (area-mean texels read back with seamless bilinear filtering). */
float ibl__box_level_shininess(int size, int level);
/* The least-squares fit itself for a level of edge n (uncached: the yardstick of the table
 * ibl__box_level_shininess reads for power-of-two edges). */
float ibl__box_fit_shininess(int n);

/* The Gaussian profile's per-axis sigma, in texels of a face of edge n, for a Phong lobe of
 * the given exponent: sqrt(max(0, (n / 2)^2 / (shininess + 3) - 1/12)). */
double ibl__gauss_sigma(float shininess, int n);
/* How many times coarser than the level (edge n) a blur of sigma texels runs: 1 for the exact
 * blur, else a power of two (specular_gauss.c, "wide blurs through a Gaussian pyramid"). */
int ibl__gauss_coarse_factor(double sigma, int n);

#endif
