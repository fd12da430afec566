/*
 * ibl/sh.h - real spherical harmonics (SH) of radiance and irradiance, up to 5 bands.
 *
 * Basis (docs/DIFFUSE.md has the derivations and measured errors):
 *  - Real, orthonormal over the sphere, WITHOUT the Condon-Shortley phase: every constant is
 *    positive, Y(1,1) = +0.488603 x. The name of this convention is IBL_SH_BASIS_NAME.
 *  - Order: index l*l + l + m, i.e. (l,m) = (0,0), (1,-1), (1,0), (1,1), (2,-2), (2,-1), (2,0),
 *    (2,1), (2,2), (3,-3) ... (4,4). m < 0 are the sin(|m| phi) functions.
 *  - Band 0..2: 0.282095; 0.488603 (y, z, x); 1.092548 (xy, yz, xz); 0.315392 (3z^2 - 1);
 *    0.546274 (x^2 - y^2), as in Ramamoorthi & Hanrahan 2001 and Sloan's "Stupid SH tricks".
 *  - Axes: x, y, z of these formulas ARE the library's world axes (right-handed, +Y up). The
 *    formula's polar axis (the one the m = 0 functions are symmetric about) is therefore the
 *    horizontal world +Z, and "up" appears in the y terms (L1-1, L2-2, L2-1). This is also the
 *    frame of R&H's published light-probe tables (Y up), so those tables compare directly.
 *
 * Normalisations exported: radiance L_lm; irradiance E_lm = A_l L_lm (the clamped-cosine
 * convolution, A = pi, 2pi/3, pi/4, 0, -pi/24); irradiance / pi (the exitance of a white
 * Lambertian surface, ready for a shader); and the R&H 9-term quadratic form E(n) = n^T M n.
 */
#ifndef IBL_SH_H
#define IBL_SH_H

#include "core.h"

#ifdef __cplusplus
extern "C" {
#endif

enum { IBL_SH_MAX_BANDS = 5, IBL_SH_MAX_COEFFS = 25 };

#define IBL_SH_BASIS_NAME "real orthonormal SH without Condon-Shortley phase (R&H / Sloan order)"

/* A set of RGB SH coefficients. c[l*l + l + m][channel]. Coefficients of bands >= `bands`
 * are zero. */
typedef struct ibl_sh {
    int bands; /* 1 .. IBL_SH_MAX_BANDS */
    double c[IBL_SH_MAX_COEFFS][3];
} ibl_sh;

static inline int ibl_sh_index(int l, int m) { return l * l + l + m; }

/* The basis functions of bands 0 .. bands-1 at a unit direction (bands*bands values). */
void ibl_sh_eval_basis(int bands, const double dir[3], double *out);
/* Sum of c_lm Y_lm(dir) for a unit direction: the reconstructed function. */
void ibl_sh_eval(const ibl_sh *sh, const double dir[3], double rgb[3]);

/* ---- projection ------------------------------------------------------------------------ */

/* Projects level `level` of a cubemap: every texel, weighted by its exact solid angle,
 * evaluated at its centre direction; double accumulation in a fixed order (bit-identical at
 * any thread count). bands: 1..5 (0: 3). */
ibl_status ibl_sh_project_cubemap(ibl_context *ctx, const ibl_cubemap *cube, int level, int bands,
                                  ibl_sh *out);
/* Projects an equirectangular image in the library's layout (centre column toward -Z, right
 * quarter toward +X, top row +Y) with the exact pixel solid angle of each row,
 * 2 pi / W (cos theta0 - cos theta1). */
ibl_status ibl_sh_project_equirect(ibl_context *ctx, const ibl_image *image, int bands,
                                   ibl_sh *out);
/* Projects arbitrary samples: unit directions (3 doubles each), solid-angle weights and RGB(A)
 * values (`stride` floats apart). For layouts the library does not know. */
ibl_status ibl_sh_project_samples(int bands, size_t count, const double *dirs,
                                  const double *weights, const float *rgb, size_t stride,
                                  ibl_sh *out);
/* tri-Ace's cheap dynamic path: SH from six values only, the face-centre samples of one level
 * (bilinear at each face centre). On a 1x1 level they are the face means, on larger levels
 * point values at the axes; either way each band is corrected so that a radiance in
 * span{Y00, Y1m, Y20, Y22} is recovered exactly. The xy, yz, xz terms and bands >= 3 cannot
 * be seen by six values and are zero. Errors on real HDRIs: docs/DIFFUSE.md. */
ibl_status ibl_sh_project_face_centres(const ibl_cubemap *cube, int level, int bands,
                                       ibl_sh *out);
/* The same estimator from the six exact face means (solid-angle-weighted, in double) of one
 * level: what the 1x1 level of an area-correct mip chain holds. */
ibl_status ibl_sh_project_face_means(const ibl_cubemap *cube, int level, int bands, ibl_sh *out);

/* A reusable projection of cubes of one face size: tables made once, then every run
 * allocates nothing (the per-frame path). */
typedef struct ibl_sh_plan_desc {
    int face_size; /* edge of the cubes run gets (required)  */
    int bands;     /* 1..5; 0: 3                              */
} ibl_sh_plan_desc;

typedef struct ibl_sh_plan ibl_sh_plan;
ibl_status ibl_sh_plan_create(ibl_context *ctx, const ibl_sh_plan_desc *desc, ibl_sh_plan **out);
/* Projects level 0 of cube (edge face_size). One run at a time per plan (the plan holds the
 * per-chunk partial sums); make one plan per thread. */
ibl_status ibl_sh_plan_run(ibl_sh_plan *plan, const ibl_cubemap *cube, ibl_sh *out);
void ibl_sh_plan_destroy(ibl_sh_plan *plan);

/* ---- convolution and forms ---------------------------------------------------------------- */

/* A_l: SH coefficient of the clamped cosine max(0, cos) times sqrt(4 pi / (2l + 1)), i.e. the
 * factor turning radiance into irradiance: pi, 2pi/3, pi/4, 0, -pi/24 for l = 0..4. */
double ibl_sh_cosine_factor(int l);
/* E_lm = A_l L_lm. */
void ibl_sh_radiance_to_irradiance(const ibl_sh *radiance, ibl_sh *irradiance);
/* Multiplies every coefficient by s (e.g. 1/pi for irradiance / pi). */
void ibl_sh_scale(ibl_sh *sh, double s);

/* R&H 2001 constants of the 9-term quadratic form. */
#define IBL_SH_RH_C1 0.429043
#define IBL_SH_RH_C2 0.511664
#define IBL_SH_RH_C3 0.743125
#define IBL_SH_RH_C4 0.886227
#define IBL_SH_RH_C5 0.247708
/* Irradiance of the first 9 radiance coefficients as E(n) = (n,1)^T M (n,1) with n = (x,y,z),
 * one symmetric 4x4 matrix per channel (R&H 2001, eq. 12). Uses the published 6-digit
 * constants; ibl_sh_radiance_to_irradiance uses the exact A_l. */
void ibl_sh_polynomial(const ibl_sh *radiance, double m[3][4][4]);

/* ---- windowing against ringing -------------------------------------------------------------- */

typedef enum ibl_sh_window {
    IBL_SH_WINDOW_NONE = 0,
    IBL_SH_WINDOW_HANNING, /* h_l = (1 + cos(pi l / W)) / 2 for l < W, else 0 (W > 0)   */
    IBL_SH_WINDOW_AUTO     /* the weakest Hanning window (largest W) whose irradiance is
                              non-negative on a dense direction set; none if not needed  */
} ibl_sh_window;

typedef struct ibl_sh_window_report {
    ibl_sh_window applied;  /* NONE or HANNING (what auto chose)                          */
    double width;           /* W of the Hanning window applied (0 if none)                */
    double factors[IBL_SH_MAX_BANDS]; /* h_l per band (1 if none)                         */
    double min_irradiance_before; /* smallest irradiance channel over the direction set   */
    double min_irradiance_after;
} ibl_sh_window_report;

/* Windows radiance coefficients in place (everything derived from them follows). width is
 * W for HANNING and ignored otherwise. report may be NULL. */
ibl_status ibl_sh_apply_window(ibl_sh *radiance, ibl_sh_window window, double width,
                               ibl_sh_window_report *report);
/* Smallest irradiance value (any channel) of radiance SH over the dense direction set used by
 * the automatic window (4096 Fibonacci-sphere directions). */
double ibl_sh_min_irradiance(const ibl_sh *radiance);

/* ---- the JSON form -------------------------------------------------------------------------- */

/* The JSON object of an SH set (what `ibl sh --json` prints and a bake's sh.json holds): the
 * basis and axes, the window, radiance, irradiance and irradiance/pi coefficients, and the
 * Ramamoorthi-Hanrahan matrices. input and projection are recorded when not NULL. The text
 * is NUL-terminated, ends with a newline and is freed with ibl_free. */
ibl_status ibl_sh_json(ibl_context *ctx, const ibl_sh *radiance, ibl_sh_window requested,
                       const ibl_sh_window_report *window, const char *input,
                       const char *projection, char **json);
/* "none", "auto", "hanning" */
const char *ibl_sh_window_name(ibl_sh_window window);

#ifdef __cplusplus
}
#endif
#endif
