/* Deterministic quadrature shared by the BRDF tables (split-sum GGX, Charlie sheen, the
 * tri-Ace AmbientBRDF). Every table is a directional albedo
 *     E(mu) = integral over the hemisphere of f(l, v) (n.l) dl,   n.v = mu,
 * computed in half-vector coordinates (theta_h, phi) with the lobe's exact importance map
 * u -> theta_h, Gauss-Legendre in a per-lobe variable of u and in phi, and the integration
 * domain cut exactly where the integrand has kinks (n.l = 0; n.l = n.v for tri-Ace's
 * max(n.l, n.v); n.l = 0.5 for KHR_materials_sheen's Lambda) so that each piece is smooth
 * and Gauss-Legendre converges fast. docs/BRDF.md has the derivation. */
#ifndef IBL_BRDF_COMMON_H
#define IBL_BRDF_COMMON_H

#include "ibl/core.h"

enum { IBL__GL_MAX = 192 };

/* Gauss-Legendre rule on [0, 1]. */
typedef struct ibl__rule {
    int n;
    double x[IBL__GL_MAX];
    double w[IBL__GL_MAX];
} ibl__rule;

/* Fills a rule of n points (1 <= n <= IBL__GL_MAX); nodes by Newton iteration, float64. */
void ibl__gauss_legendre(int n, ibl__rule *rule);

/* The rules one albedo integral uses, all derived from one "order": order / 2 points on the
 * theta_h pieces where the phi circle is cut (5/6 order at grazing n.v) and on the
 * whole-circle piece, order / 3 per phi interval and order / 3 midpoints on a whole half
 * circle. */
typedef struct ibl__quadrature {
    ibl__rule u_part, u_graze, u_full, phi;
    int circle;
    double circle_cos[IBL__GL_MAX]; /* cos of the circle's midpoints on [0, pi] */
} ibl__quadrature;

enum { IBL__DEFAULT_ORDER = 24 };

/* order 0: IBL__DEFAULT_ORDER; clamped to [4, IBL__GL_MAX]. */
void ibl__quadrature_init(ibl__quadrature *q, int order);

typedef enum ibl__lobe {
    IBL__LOBE_GGX_CORRELATED, /* GGX D, height-correlated Smith G2                     */
    IBL__LOBE_GGX_SEPARABLE,  /* GGX D, Schlick-GGX G1(l) G1(v) with k = alpha / 2        */
    IBL__LOBE_CHARLIE,        /* Charlie D (Estevez-Kulla), Neubelt-Pettineo visibility */
    IBL__LOBE_CHARLIE_KHR,    /* Charlie D, KHR_materials_sheen's Charlie visibility (Conty &
                                 Kulla 2017's fitted Lambda)                             */
    IBL__LOBE_BLINN           /* tri-Ace's (c1 s + c2) (n.h)^s / max(n.l, n.v)           */
} ibl__lobe;

typedef struct ibl__lobe_params {
    ibl__lobe lobe;
    double alpha;     /* GGX / Charlie roughness alpha = r^2 (> 0)              */
    double shininess; /* Blinn exponent s (> 0)                                 */
    double norm;      /* Blinn normalisation factor (c1 s + c2, or the exact)   */
} ibl__lobe_params;

/* The two Schlick moments of the directional albedo at n.v = mu (0 < mu <= 1):
 *   out[0] = integral f/F (1 - (1 - v.h)^5) (n.l) dl,  out[1] = integral f/F (1 - v.h)^5 (n.l) dl
 * so that with F = F0 + (F90 - F0)(1 - v.h)^5 the albedo is F0 out[0] + F90 out[1].
 * q: the rules applied to every smooth piece. */
void ibl__albedo_moments(const ibl__lobe_params *p, double mu, const ibl__quadrature *q,
                         double out[2]);

/* The same with Schlick F evaluated for nf0 values of F0 at every node (so the sum follows
 * the integrand, not the affine shortcut): out[k] = integral f(F0 = f0[k]) (n.l) dl. */
void ibl__albedo_f0(const ibl__lobe_params *p, double mu, const ibl__quadrature *q,
                    const double *f0, int nf0, double *out);

#endif
