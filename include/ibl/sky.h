/*
 * ibl/sky.h - a physically based procedural clear sky, the built-in default environment.
 *
 * The sky is the Preetham, Shirley & Smits 1999 model ("A Practical Analytic Model for
 * Daylight", SIGGRAPH 99): the Perez luminance distribution with turbidity-dependent
 * coefficients and the paper's zenith luminance and chromaticity, converted from xyY to linear
 * Rec.709 RGB. A sun disk of 0.53 degrees is added, whose radiance is the extraterrestrial
 * sun (127.5 klux over the disk) dimmed by Rayleigh and aerosol extinction along the air mass
 * (the transmittance formulas of the paper's appendix, evaluated at one wavelength per RGB
 * channel). Below the horizon is a Lambertian ground lit by the sun and the sky.
 *
 * Units: every value is luminance-scaled radiance in kcd/m^2 (cd/m^2 divided by 1000), i.e.
 * the Rec.709 luminance 0.2126 R + 0.7152 G + 0.0722 B of a texel is its luminance in kcd/m^2,
 * and integrating L cos(theta) d(omega) gives illuminance in klux. A clear noon sun is about
 * 1.5e6 (1.5e9 cd/m^2), the blue sky a few units.
 *
 * Directions (docs/CONVENTIONS.md): +Y up; the sun azimuth is measured from -Z (the centre of
 * an equirect image) toward +X (its right quarter), so the sun appears at u = 0.5 + azimuth/360,
 * v = 0.5 - elevation/180 of the rendered equirect image.
 */
#ifndef IBL_SKY_H
#define IBL_SKY_H

#include "core.h"
#include "cubemap.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct ibl_sky_desc {
    float sun_elevation_deg; /* degrees above the horizon, (0, 90]; 0: 35                        */
    float sun_azimuth_deg;   /* degrees from -Z toward +X (any value, taken modulo 360)           */
    float turbidity;         /* Preetham turbidity in [2, 10] (2: very clear, 10: hazy); 0: 3     */
    int width;               /* equirect width (height = width / 2), even, >= 8; 0: 1024          */
    float ground_albedo;     /* Lambertian albedo of the ground in [0, 1]; 0: 0.3; < 0: black     */
    int no_sun_disk;         /* non-zero: leave the disk out (sky and ground are still sunlit),
                                for engines that draw the sun as a separate directional light   */
} ibl_sky_desc;

typedef struct ibl_sky_sun {
    ibl_vec3 direction;    /* unit vector toward the centre of the sun                        */
    float radiance[3];     /* linear Rec.709 RGB of the (uniform) disk, kcd/m^2                */
    double angular_radius; /* radians (0.265 degrees)                                          */
    double solid_angle;    /* of the disk, sr: 2 pi (1 - cos(angular_radius))                   */
    double air_mass;       /* relative optical air mass along the sun's path                   */
} ibl_sky_sun;

/* Everything the sky needs, computed once from a descriptor (plain data, no allocation). */
typedef struct ibl_sky_model {
    ibl_sky_desc desc;     /* with the defaults filled in                                      */
    ibl_sky_sun sun;
    double perez[3][5];    /* Perez A..E for Y, x, y at this turbidity                         */
    double zenith[3];      /* zenith luminance Y_z (kcd/m^2) and chromaticity x_z, y_z         */
    double norm[3];        /* 1 / F(0, theta_sun) for Y, x, y                                  */
    float sky_illuminance[3]; /* horizontal illuminance from the sky alone (klux, RGB)         */
    float sun_illuminance[3]; /* horizontal illuminance from the sun disk (klux, RGB)          */
    float ground[3];       /* radiance of the ground: albedo / pi * (sky + sun) illuminance     */
} ibl_sky_model;

/* Unit vector toward the sun for a descriptor (defaults applied; NULL: all defaults). */
ibl_vec3 ibl_sky_sun_direction(const ibl_sky_desc *desc);
/* Fills a model; IBL_ERR_INVALID_ARGUMENT for parameters out of range. */
ibl_status ibl_sky_model_init(ibl_context *ctx, const ibl_sky_desc *desc, ibl_sky_model *out);
/* Radiance of the sky (above the horizon) or the ground (below), without the sun disk. */
void ibl_sky_model_radiance(const ibl_sky_model *model, ibl_vec3 dir, float rgb[3]);
/* Renders the sky into a new equirect image of width x width/2 (alpha 1). The disk is
 * integrated over each pixel, so its energy (radiance x solid angle) is exact at any width. */
ibl_status ibl_sky_render(ibl_context *ctx, const ibl_sky_desc *desc, ibl_image *out);

#ifdef __cplusplus
}
#endif
#endif
