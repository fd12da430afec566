/* Octahedral map (Praun & Hoppe 2003, "Spherical parametrization and remeshing"; the encoding
 * surveyed by Cigolle et al. 2014, "A Survey of Efficient Representations for Independent Unit
 * Vectors"), with the octahedron's axis along +Y (up):
 *   (a, b) = (2u - 1, 2v - 1); y = 1 - |a| - |b|; where y < 0 (the lower half, folded into the
 *   corners) (a, b) = ((1 - |b|) sgn a, (1 - |a|) sgn b); d = normalize(a, y, b).
 * The centre is +Y (zenith), the four corners are -Y, the middle of the right edge is +X, of the
 * bottom edge +Z, of the top edge -Z, of the left edge -X: a map of the sky seen from above
 * with -Z at the top. Opposite halves of each edge are the same directions (the fold). */
#include "layout_internal.h"

#include <math.h>

static double sgn(double x) { return x < 0.0 ? -1.0 : 1.0; }

int ibl__octahedral_dir(double u, double v, double d[3])
{
    double a = 2.0 * u - 1.0, b = 2.0 * v - 1.0;
    double y = 1.0 - fabs(a) - fabs(b);
    if (y < 0.0) {
        double na = (1.0 - fabs(b)) * sgn(a), nb = (1.0 - fabs(a)) * sgn(b);
        a = na;
        b = nb;
    }
    double len = sqrt(a * a + y * y + b * b);
    d[0] = a / len;
    d[1] = y / len;
    d[2] = b / len;
    return 1;
}

void ibl__octahedral_uv(const double d[3], double *u, double *v)
{
    double s = fabs(d[0]) + fabs(d[1]) + fabs(d[2]);
    if (!(s > 0.0)) s = 1.0;
    double a = d[0] / s, b = d[2] / s;
    if (d[1] < 0.0) {
        double na = (1.0 - fabs(b)) * sgn(a), nb = (1.0 - fabs(a)) * sgn(b);
        a = na;
        b = nb;
    }
    *u = 0.5 * (a + 1.0);
    *v = 0.5 * (b + 1.0);
}

/* A point q on the octahedron |x|+|y|+|z| = 1 seen from the centre: d omega = (q.n) dA_q / |q|^3
 * with q.n = 1/sqrt(3) and dA_q = sqrt(3) dA_ab, so d omega / dA_ab = 1/|q|^3 = |d|_1^3 for a
 * unit d (the fold is an isometry, so the lower half follows the same rule). */
double ibl__octahedral_density(const double d[3])
{
    double s = fabs(d[0]) + fabs(d[1]) + fabs(d[2]);
    return s * s * s;
}
