/*
 * ibl/brdf.h - BRDF lookup tables for image-based lighting.
 *
 * 1. The split-sum GGX table (Karis 2013, "Real Shading in Unreal Engine 4"; the JAGE 2015
 *    article's IntegrateEnvBRDF): ambient specular = prefiltered(R, r) * (F0 * A + F90 * B),
 *    with A, B the directional albedo of the GGX specular lobe split by Schlick's Fresnel, over
 *    x = n.v and y = perceptual roughness r (alpha = r^2). Optional extra channels: the
 *    directional albedo E = A + B and its cosine-weighted average E_avg for multiple-scattering
 *    energy compensation, and the Charlie sheen albedo (Estevez & Kulla 2017 distribution,
 *    Neubelt & Pettineo 2013 visibility).
 *
 * 2. The tri-Ace AmbientBRDF (the tri-Ace talk's "Implement Ambient BRDF"): a 3D table over
 *    U = n.v, V = shininess, W = F0 of the directional albedo of tri-Ace's normalised
 *    Blinn-Phong specular (c1 s + c2) F(w.h) (n.h)^s / max(n.w', n.w), to be multiplied by a
 *    prefiltered map normalised by its lobe weights; and the compact 2D two-channel form
 *    (Schlick is affine in F0: value = F0 * X + Y).
 *
 * Every value is a deterministic quadrature (Gauss-Legendre on the half-vector sphere with
 * the lobe's exact importance map, cut at the integrand's kinks), accurate to 2e-5 absolute
 * or better everywhere including grazing n.v (measured in docs/BRDF.md); output is
 * bit-identical at any thread count.
 *
 * Texel centres: texel (i, j) of an N-texel axis holds the value at (i + 0.5) / N, so a GPU's
 * bilinear lookup at the normalised coordinate is right. Rows are stored top first: row 0,
 * the top of the image, is r ~ 0 (smooth) for the split-sum table and the smallest
 * shininess for the AmbientBRDF. docs/BRDF.md has the derivations and the
 * measurements.
 */
#ifndef IBL_BRDF_H
#define IBL_BRDF_H

#include "core.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ------------------------------------------------------------------------------------------ */
/* Split-sum GGX table                                                                        */

typedef enum ibl_brdf_visibility {
    IBL_VISIBILITY_HEIGHT_CORRELATED = 0, /* Heitz 2014 height-correlated Smith (default)    */
    IBL_VISIBILITY_SEPARABLE              /* Schlick-GGX G1(l) G1(v), k = alpha/2 (UE4, LearnOpenGL) */
} ibl_brdf_visibility;

typedef enum ibl_brdf_channel {
    IBL_BRDF_NONE = 0,       /* ends the channel list                                     */
    IBL_BRDF_SCALE,          /* A: multiplies F0                                          */
    IBL_BRDF_BIAS,           /* B: multiplies F90                                         */
    IBL_BRDF_ALBEDO,         /* E(mu, r) = A + B, the directional albedo with F = 1       */
    IBL_BRDF_ALBEDO_AVG,     /* E_avg(r) = 2 * integral E(mu) mu dmu (same along a row)   */
    IBL_BRDF_SHEEN,          /* Charlie sheen directional albedo (F = 1)                  */
    IBL_BRDF_SHEEN_AVG,      /* its cosine-weighted average (same along a row)            */
    IBL_BRDF_SHEEN_KHR,      /* KHR_materials_sheen's E(x): Charlie D with alpha = the
                                table's y (sheenRoughness, not squared), the extension's
                                Charlie visibility (Conty Estevez & Kulla 2017), F = 1      */
    IBL_BRDF_SHEEN_KHR_AVG,  /* its cosine-weighted average (same along a row)            */
    IBL_BRDF_ZERO,           /* constant 0                                                */
    IBL_BRDF_ONE             /* constant 1                                                */
} ibl_brdf_channel;

typedef struct ibl_brdf_lut_desc {
    int size;                     /* edge in texels (n.v and r axes); 0: 128               */
    ibl_brdf_visibility visibility;
    ibl_brdf_channel channels[4]; /* R, G, B, A sources up to the first NONE; all zero:
                                     {SCALE, BIAS}                                        */
    int order;                    /* quadrature size: order / 2 Gauss-Legendre points per
                                     theta_h piece, order / 3 per phi interval (docs/BRDF.md);
                                     0: 24. Raise to check convergence                    */
} ibl_brdf_lut_desc;

/* Number of channels the descriptor asks for (1..4). */
int ibl_brdf_lut_channel_count(const ibl_brdf_lut_desc *desc);
/* Computes the table into a new size x size RGBA image (free with ibl_image_free). Texel
 * (i, j): n.v = (i + 0.5) / size, r = (j + 0.5) / size; row 0 (top) is r ~ 0. Channels past
 * the requested count are 0, except alpha, which is 1. */
ibl_status ibl_brdf_lut(ibl_context *ctx, const ibl_brdf_lut_desc *desc, ibl_image *out);

/* Point evaluations in float64 (order 0: default). nv in (0, 1], r in [0, 1]; r = 0 is the
 * closed form A = 1 - (1 - nv)^5, B = (1 - nv)^5. */
void ibl_brdf_splitsum(double nv, double r, ibl_brdf_visibility visibility, int order,
                       double *scale, double *bias);
double ibl_brdf_albedo_average(double r, ibl_brdf_visibility visibility, int order);
double ibl_brdf_sheen_albedo(double nv, double r, int order);
double ibl_brdf_sheen_albedo_average(double r, int order);
/* KHR_materials_sheen's albedo E(nv) at sheenRoughness r (alpha = r), and its average */
double ibl_brdf_sheen_khr_albedo(double nv, double r, int order);
double ibl_brdf_sheen_khr_albedo_average(double r, int order);

/* ------------------------------------------------------------------------------------------ */
/* tri-Ace AmbientBRDF                                                                        */

typedef enum ibl_shininess_spacing {
    IBL_SHININESS_LOG = 0, /* shininess = min * (max/min)^v  (default)  */
    IBL_SHININESS_LINEAR   /* shininess = min + (max - min) * v         */
} ibl_shininess_spacing;

typedef enum ibl_blinn_normalization {
    IBL_BLINN_TRIACE_FIT = 0, /* tri-Ace's linear fit 0.0397436 s + 0.0856832                        */
    IBL_BLINN_EXACT     /* (s + 2)(s + 4) / (8 pi (2^(-s/2) + s)): albedo 1 at n.v = 1, F = 1 */
} ibl_blinn_normalization;

typedef struct ibl_ambient_brdf_desc {
    int size_nv;                   /* U texels; 0: 32                                       */
    int size_shininess;            /* V texels; 0: 32                                       */
    int size_f0;                   /* W texels (3D volume only); 0: 16                      */
    double shininess_min;          /* 0: 1                                                  */
    double shininess_max;          /* 0: 2000                                               */
    ibl_shininess_spacing spacing;
    ibl_blinn_normalization normalization;
    int order;                     /* as in ibl_brdf_lut_desc; 0: 24                        */
} ibl_ambient_brdf_desc;

/* Shininess at the centre of row j, (j + 0.5) / size_shininess along the spacing. A shader
 * maps shininess s back to v = log(s / min) / log(max / min) (log spacing). */
double ibl_ambient_brdf_row_shininess(const ibl_ambient_brdf_desc *desc, int j);
/* The normalisation factor of the tri-Ace specular term at shininess s. */
double ibl_blinn_normalization_factor(ibl_blinn_normalization normalization, double s);

/* The 3D volume: width U = n.v, height V = shininess, depth W = F0 (slice k at
 * F0 = (k + 0.5) / size_f0). R = the AmbientBRDF (directional albedo of the specular term),
 * G = the exact diffuse factor of the tri-Ace BRDF, 1 - F0 (the diffuse term
 * Rd/pi (1 - F0) integrates to Rd (1 - F0) IEM; see docs/BRDF.md), B = 0, A = 1. */
ibl_status ibl_ambient_brdf_volume(ibl_context *ctx, const ibl_ambient_brdf_desc *desc,
                                   ibl_texture *out);
/* The compact 2D form: width U, height V; R = X, G = Y with AmbientBRDF = F0 * X + Y. */
ibl_status ibl_ambient_brdf_table(ibl_context *ctx, const ibl_ambient_brdf_desc *desc,
                                  ibl_image *out);
/* One value in float64: directional albedo of the tri-Ace specular term. */
double ibl_ambient_brdf(double nv, double shininess, double f0,
                        ibl_blinn_normalization normalization, int order);

/* ------------------------------------------------------------------------------------------ */
/* Text outputs                                                                               */

/* Writes the first `channels` channels of a 2D or 3D texture (level 0) as a C header when the
 * path ends in .h (a `static const float NAME[depth][height][width][channels]` array, depth
 * omitted for 2D, with the axes in a comment), or else as a text table: '#' comment lines,
 * then one line per texel "x y [z] c0 c1 ...". Values are printed with 9 significant digits
 * (exact for float). symbol: the array name (0: "ibl_brdf_table"); comment: a free text
 * written at the top (may be NULL). Written atomically. */
ibl_status ibl_write_table(ibl_context *ctx, const char *path, const ibl_texture *table,
                           int channels, const char *symbol, const char *comment);

#ifdef __cplusplus
}
#endif
#endif
