/* Debevec's angular map (the "light probe" format of his HDR probes, Debevec 1998 / the
 * www.debevec.org probe pages): the whole sphere in the unit disk of a square picture.
 * With (a, b) = (2u - 1, 2v - 1) (b grows downward) and r = sqrt(a^2 + b^2):
 *   the angle from the view direction -Z is theta = pi r, i.e. r = acos(-z) / pi,
 *   d = (sin(theta) a / r, -sin(theta) b / r, -cos(theta)).
 * The centre looks toward -Z, right is +X, up is +Y (as seen from inside, like the equirect's
 * centre); the rim circle is the single direction +Z; the corners outside the disk are unused. */
#include "layout_internal.h"
#include "core/numeric.h"

#include <math.h>


int ibl__angular_dir(double u, double v, double d[3])
{
    double a = 2.0 * u - 1.0, b = 2.0 * v - 1.0;
    double r = sqrt(a * a + b * b);
    if (r > 1.0) return 0;
    if (r == 0.0) {
        d[0] = 0;
        d[1] = 0;
        d[2] = -1;
        return 1;
    }
    double theta = IBL_PI * r, s = sin(theta) / r;
    d[0] = s * a;
    d[1] = -s * b;
    d[2] = -cos(theta);
    return 1;
}

void ibl__angular_uv(const double d[3], double *u, double *v)
{
    double h = sqrt(d[0] * d[0] + d[1] * d[1]);
    double r = atan2(h, -d[2]) / IBL_PI;
    double a = r, b = 0.0; /* +Z itself: any point of the rim; take the right one */
    if (h > 0.0) {
        a = r * d[0] / h;
        b = -r * d[1] / h;
    }
    *u = 0.5 * (a + 1.0);
    *v = 0.5 * (b + 1.0);
}

/* d omega = sin(theta) d theta d psi with theta = pi r and the disk area element r dr dpsi:
 * d omega / dA = pi sin(pi r) / r. */
double ibl__angular_density(double u, double v)
{
    double a = 2.0 * u - 1.0, b = 2.0 * v - 1.0;
    double r = sqrt(a * a + b * b);
    if (r < 1e-9) return IBL_PI * IBL_PI;
    if (r >= 1.0) return 0.0;
    return IBL_PI * sin(IBL_PI * r) / r;
}
