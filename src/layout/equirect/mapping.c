/* The equirectangular (latitude-longitude) mapping itself: direction <-> picture coordinates,
 * the exact solid angle of a row of pixels, and the exact solid-angle-weighted mean of a
 * picture. Everything else in this folder builds on these.
 *
 * Mapping (docs/CONVENTIONS.md): u in [0, 1] left to right, v in [0, 1] top to bottom,
 *   phi = 2 pi (u - 1/2), theta = pi v (angle from +Y),
 *   d = (sin theta sin phi, cos theta, -sin theta cos phi):
 * the centre column looks toward -Z, u = 3/4 toward +X, u = 0 and 1 toward +Z, the top row is
 * +Y.
 *
 * Solid angle: dOmega = sin(theta) dtheta dphi, so the band theta0 <= theta <= theta1 holds
 * 2 pi (cos theta0 - cos theta1) (the area of a spherical zone, Archimedes' hat-box theorem),
 * shared equally by the W pixels of a row. Summed over the rows the cosines telescope to
 * 2 - (-2) = 4, so the weights add up to the whole sphere up to rounding. */
#include "equirect_internal.h"

#include <math.h>

int ibl__equirect_dir(double u, double v, double d[3])
{
    double phi = IBL_TWO_PI * (u - 0.5), theta = IBL_PI * v;
    double st = sin(theta);
    d[0] = st * sin(phi);
    d[1] = cos(theta);
    d[2] = -st * cos(phi);
    return 1;
}

void ibl__equirect_uv(const double d[3], double *u, double *v)
{
    double rho = sqrt(d[0] * d[0] + d[2] * d[2]);
    *u = atan2(d[0], -d[2]) / IBL_TWO_PI + 0.5;
    *v = atan2(rho, d[1]) / IBL_PI;
}

double ibl__equirect_row_solid_angle(int width, int height, int row)
{
    double theta0 = IBL_PI * row / height, theta1 = IBL_PI * (row + 1) / height;
    return IBL_TWO_PI / width * (cos(theta0) - cos(theta1));
}

void ibl__equirect_mean(const ibl_image *image, double out[4])
{
    /* each row summed in double, then weighted by its pixels' solid angle */
    double acc[4] = {0, 0, 0, 0}, wsum = 0.0;
    for (int y = 0; y < image->height; y++) {
        double w = ibl__equirect_row_solid_angle(image->width, image->height, y);
        const float *p = image->pixels + (size_t)y * image->width * 4;
        double row[4] = {0, 0, 0, 0};
        for (int x = 0; x < image->width; x++, p += 4)
            for (int c = 0; c < 4; c++) row[c] += p[c];
        for (int c = 0; c < 4; c++) acc[c] += w * row[c];
        wsum += w * image->width;
    }
    for (int c = 0; c < 4; c++) out[c] = acc[c] / wsum;
}
