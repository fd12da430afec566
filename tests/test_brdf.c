/* BRDF tables (ibl/brdf.h) against independent references: closed forms at r = 0 and r = 1,
 * published split-sum values, slow float64 brute-force integrals over the hemisphere of
 * LIGHT directions (written here, separately from the library's half-vector quadrature),
 * convergence under doubling of the quadrature order, and bit-identity across threads. */
#include "test_support.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static const double PI = 3.14159265358979323846;

/* ---- brute force: midpoint rule over (theta_l, phi_l), the hemisphere of light directions.
 * The integrands are smooth except for the max() kink of tri-Ace 2010's denominator, so the midpoint rule's error
 * is O(h^2): with 1200 x 1200 cells and lobes no narrower than alpha = 0.09 it is below
 * 1e-5, an order under the tolerances used with it. ---- */

typedef double (*brdf_fn)(const double *l, const double *v, const double *h, const void *p);

static double brute_albedo(brdf_fn f, const void *p, double mu, int n)
{
    double v[3] = {sqrt(1 - mu * mu), 0, mu};
    double dt = 0.5 * PI / n, dp = PI / n, acc = 0;
    for (int a = 0; a < n; a++) {
        double t = (a + 0.5) * dt, st = sin(t), ct = cos(t);
        double row = 0;
        for (int b = 0; b < n; b++) {
            double ph = (b + 0.5) * dp;
            double l[3] = {st * cos(ph), st * sin(ph), ct};
            double h[3] = {l[0] + v[0], l[1] + v[1], l[2] + v[2]};
            double hl = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
            h[0] /= hl, h[1] /= hl, h[2] /= hl;
            row += f(l, v, h, p) * ct;
        }
        acc += row * st;
    }
    return 2.0 * acc * dt * dp; /* phi in [0, pi] covers half the symmetric hemisphere */
}

/* ---- a second brute force, accurate enough for the tolerances of 1e-5: composite
 * Gauss-Legendre over the same hemisphere of light directions, 8 points per panel and
 * `panels` panels on each axis, in (s, y) with n.l = s^3 and phi = pi (1 - y^3). A grazing
 * view puts a near-singularity (h undefined at l = -v) a distance ~n.v below the horizon
 * at phi = pi; the cubes move it ~n.v^(1/3) away from the panels' ends. The 8-point rule
 * is computed here by Newton's method on P_8, apart from the library's. Its own error is
 * measured by brute_force_self_convergence. ---- */

static void gauss8(double *x, double *w)
{
    for (int i = 0; i < 8; i++) {
        double z = cos(PI * (i + 0.75) / 8.5), dp = 1;
        for (int it = 0; it < 60; it++) {
            double p_prev = 1, p = z; /* P_0, P_1 */
            for (int k = 2; k <= 8; k++) {
                double next = ((2.0 * k - 1.0) * z * p - (k - 1.0) * p_prev) / k;
                p_prev = p;
                p = next;
            }
            dp = 8.0 * (z * p - p_prev) / (z * z - 1.0);
            double step = p / dp;
            z -= step;
            if (fabs(step) < 1e-15) break;
        }
        x[i] = 0.5 * (1.0 - z); /* on [0, 1] */
        w[i] = 1.0 / ((1.0 - z * z) * dp * dp);
    }
}

/* nl_kink in (0, 1): the s axis is split where n.l = nl_kink (an integrand with a kink
 * there, KHR sheen's Lambda at n.l = 0.5), `panels` panels on each side; 0: no split. */
static double brute_albedo_gl(brdf_fn f, const void *p, double mu, int panels, double nl_kink)
{
    double gx[8], gw[8];
    gauss8(gx, gw);
    double v[3] = {sqrt(1 - mu * mu), 0, mu}, acc = 0;
    double ends[3] = {0, 1, 1};
    int ranges = 1;
    if (nl_kink > 0 && nl_kink < 1) {
        ends[1] = cbrt(nl_kink);
        ranges = 2;
    }
    for (int r = 0; r < ranges; r++) {
        double s0 = ends[r], ds = (ends[r + 1] - s0) / panels;
        for (int a = 0; a < panels; a++)
            for (int i = 0; i < 8; i++) {
                double s = s0 + (a + gx[i]) * ds, ws = gw[i] * ds;
                double ct = s * s * s, st = sqrt(1 - ct * ct), row = 0;
                for (int b = 0; b < panels; b++)
                    for (int j = 0; j < 8; j++) {
                        double y = (b + gx[j]) / panels, ph = PI * (1.0 - y * y * y);
                        double l[3] = {st * cos(ph), st * sin(ph), ct};
                        double h[3] = {l[0] + v[0], l[1] + v[1], l[2] + v[2]};
                        double hl = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
                        h[0] /= hl, h[1] /= hl, h[2] /= hl;
                        /* dphi = 3 pi y^2 dy */
                        row += gw[j] * 3.0 * PI * y * y * f(l, v, h, p) * ct;
                    }
                acc += row / panels * 3.0 * s * s * ws; /* d(n.l) = 3 s^2 ds */
            }
    }
    return 2.0 * acc; /* phi in [0, pi] covers half the symmetric hemisphere */
}

static double dot3(const double *a, const double *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

typedef struct ggx_p {
    double alpha, f0;
    int separable;
} ggx_p;

/* Walter 2007 GGX D; Heitz 2014 height-correlated G2 through Lambda; Schlick-GGX k = a/2. */
static double ggx_brdf(const double *l, const double *v, const double *h, const void *pp)
{
    const ggx_p *p = pp;
    double nl = l[2], nv = v[2], nh = h[2], vh = dot3(v, h), a2 = p->alpha * p->alpha;
    if (nl <= 0) return 0;
    double d = a2 / (PI * pow(nh * nh * (a2 - 1) + 1, 2));
    double g;
    if (p->separable) {
        double k = p->alpha / 2;
        g = nl / (nl * (1 - k) + k) * nv / (nv * (1 - k) + k);
    } else {
        double tl2 = (1 - nl * nl) / (nl * nl), tv2 = (1 - nv * nv) / (nv * nv);
        double ll = 0.5 * (sqrt(1 + a2 * tl2) - 1), lv = 0.5 * (sqrt(1 + a2 * tv2) - 1);
        g = 1 / (1 + ll + lv);
    }
    double f = p->f0 + (1 - p->f0) * pow(1 - vh, 5);
    return d * g * f / (4 * nl * nv);
}

/* Estevez-Kulla 2017 Charlie D, Neubelt-Pettineo 2013 visibility, F = 1. */
static double sheen_brdf(const double *l, const double *v, const double *h, const void *pp)
{
    double alpha = *(const double *)pp, nl = l[2], nv = v[2];
    if (nl <= 0) return 0;
    double sh = sqrt(fmax(0, 1 - h[2] * h[2]));
    double d = (2 + 1 / alpha) * pow(sh, 1 / alpha) / (2 * PI);
    return d / (4 * (nl + nv - nl * nv));
}

/* KHR_materials_sheen (its implementation notes, written here in float64): Charlie D with
 * alpha = sheenRoughness, the "Charlie" visibility 1 / ((1 + Lambda(v) + Lambda(l)) 4 nv nl)
 * with Conty Estevez & Kulla 2017's fitted Lambda, mirrored at cos = 0.5, F = 1. */
static double khr_fit(double x, double alpha)
{
    double t = (1 - alpha) * (1 - alpha);
    double a = (1 - t) * 21.5473 + t * 25.3245, b = (1 - t) * 3.82987 + t * 3.32435;
    double c = (1 - t) * 0.19823 + t * 0.16801, d = (1 - t) * -1.97760 + t * -1.27393;
    double e = (1 - t) * -4.32054 + t * -4.85967;
    return a / (1 + b * pow(x, c)) + d * x + e;
}

static double khr_lambda_of(double cos_theta, double alpha)
{
    if (cos_theta < 0.5) return exp(khr_fit(cos_theta, alpha));
    return exp(2 * khr_fit(0.5, alpha) - khr_fit(1 - cos_theta, alpha));
}

static double sheen_khr_brdf(const double *l, const double *v, const double *h, const void *pp)
{
    double alpha = *(const double *)pp, nl = l[2], nv = v[2];
    if (nl <= 0) return 0;
    double sh = sqrt(fmax(0, 1 - h[2] * h[2]));
    double d = (2 + 1 / alpha) * pow(sh, 1 / alpha) / (2 * PI);
    return d / ((1 + khr_lambda_of(nv, alpha) + khr_lambda_of(nl, alpha)) * 4 * nl * nv);
}

typedef struct blinn_p {
    double s, norm, f0;
    int literal; /* tri-Ace 2010's AmbientBRDF integrand read literally: (n.h)^s left out */
} blinn_p;

/* tri-Ace 2010's specular term: (c1 s + c2) F(w.h) (n.h)^s / max(n.w', n.w). */
static double blinn_brdf(const double *l, const double *v, const double *h, const void *pp)
{
    const blinn_p *p = pp;
    double nl = l[2], nv = v[2];
    if (nl <= 0) return 0;
    double f = p->f0 + (1 - p->f0) * pow(1 - dot3(v, h), 5);
    double lobe = p->literal ? 1.0 : pow(h[2], p->s);
    return p->norm * f * lobe / fmax(nl, nv);
}

/* (n.h)^s alone, per unit n.l (so brute_albedo integrates the prefilter's lobe weights). */
static double blinn_lobe(const double *l, const double *v, const double *h, const void *pp)
{
    (void)v;
    const blinn_p *p = pp;
    return l[2] > 0 ? pow(h[2], p->s) / l[2] : 0;
}

static double urand(void) { return rand() / (double)RAND_MAX; }

/* ---------------------------------------------------------------------------------------- */

/* r -> 0: A = 1 - (1 - mu)^5, B = (1 - mu)^5 (delta D, G = 1). At r = 1e-3 the true
 * height-correlated value departs from the limit by O(alpha^2 / mu^2) < 1e-6 for mu >= 0.01
 * and the quadrature's own error is below 5e-6: tolerance 1e-5. The separable G1(v) departs
 * by k / mu = alpha / (2 mu), 5e-5 at mu = 0.01: tolerance 1e-4 there. */
static void splitsum_smooth_limit(void **state)
{
    (void)state;
    const double mus[] = {0.01, 0.05, 0.2, 0.5, 0.8, 1.0};
    for (int vis = 0; vis < 2; vis++)
        for (size_t i = 0; i < sizeof mus / sizeof mus[0]; i++) {
            double a, b, fc = pow(1 - mus[i], 5);
            ibl_brdf_splitsum(mus[i], 1e-3, (ibl_brdf_visibility)vis, 0, &a, &b);
            double tol = vis == IBL_VISIBILITY_SEPARABLE ? 1e-4 : 1e-5;
            assert_near(a, 1 - fc, tol);
            assert_near(b, fc, tol);
            ibl_brdf_splitsum(mus[i], 0, (ibl_brdf_visibility)vis, 0, &a, &b);
            assert_near(a, 1 - fc, 1e-12);
        }
}

/* r = 1 (alpha = 1, D = 1/pi): E = 1 - mu ln(1 + 1/mu) (height-correlated) and
 * 2 (1 - ln 2) / (1 + mu) (separable, k = 1/2); both 1 - ln 2 at mu = 1. Averages:
 * 2 int E mu dmu = 4/3 (1 - ln 2) and 4 (1 - ln 2)^2 (integrated by hand). Measured worst
 * 6.5e-6 (height-correlated at mu = 0.002, below the table's first texel centre): 1e-5. */
static void splitsum_rough_closed_forms(void **state)
{
    (void)state;
    const double mus[] = {0.002, 0.01, 0.1, 0.3, 0.5, 0.9, 1.0};
    for (size_t i = 0; i < sizeof mus / sizeof mus[0]; i++) {
        double mu = mus[i], a, b;
        ibl_brdf_splitsum(mu, 1.0, IBL_VISIBILITY_HEIGHT_CORRELATED, 0, &a, &b);
        assert_near(a + b, 1 - mu * log(1 + 1 / mu), 1e-5);
        ibl_brdf_splitsum(mu, 1.0, IBL_VISIBILITY_SEPARABLE, 0, &a, &b);
        assert_near(a + b, 2 * (1 - log(2.0)) / (1 + mu), 1e-5);
    }
    double a, b;
    ibl_brdf_splitsum(1.0, 1.0, IBL_VISIBILITY_HEIGHT_CORRELATED, 0, &a, &b);
    assert_near(a + b, 1 - log(2.0), 1e-5);
    assert_near(ibl_brdf_albedo_average(1.0, IBL_VISIBILITY_HEIGHT_CORRELATED, 0),
                4.0 / 3.0 * (1 - log(2.0)), 1e-5);
    assert_near(ibl_brdf_albedo_average(1.0, IBL_VISIBILITY_SEPARABLE, 0),
                4 * pow(1 - log(2.0), 2), 1e-5);
}

/* Six-digit reference values at (n.v, r) = (0.5, 0.5) (docs/BRDF.md "Against closed forms"):
 * their rounding (5e-7) plus the quadrature's error there (4.2e-7): 2e-6. */
static void splitsum_published(void **state)
{
    (void)state;
    double a, b;
    ibl_brdf_splitsum(0.5, 0.5, IBL_VISIBILITY_HEIGHT_CORRELATED, 0, &a, &b);
    assert_near(a, 0.834916, 2e-6);
    assert_near(b, 0.022347, 2e-6);
    ibl_brdf_splitsum(0.5, 0.5, IBL_VISIBILITY_SEPARABLE, 0, &a, &b);
    assert_near(a, 0.728534, 2e-6);
    assert_near(b, 0.018546, 2e-6);
}

/* Random points against the light-direction brute force; tolerance 1e-4 (both errors are
 * near 1e-5). A is checked with F0 = 1 minus B, B from F0 = 0. */
static void splitsum_brute_force(void **state)
{
    (void)state;
    srand(4242);
    for (int k = 0; k < 3; k++) {
        double mu = 0.05 + 0.95 * urand(), r = 0.3 + 0.7 * urand();
        for (int vis = 0; vis < 2; vis++) {
            ggx_p p = {r * r, 0.0, vis};
            double b_ref = brute_albedo(ggx_brdf, &p, mu, 1200);
            p.f0 = 1.0;
            double e_ref = brute_albedo(ggx_brdf, &p, mu, 1200);
            double a, b;
            ibl_brdf_splitsum(mu, r, (ibl_brdf_visibility)vis, 0, &a, &b);
            assert_near(b, b_ref, 1e-4);
            assert_near(a, e_ref - b_ref, 1e-4);
        }
    }
}

static void sheen_brute_force(void **state)
{
    (void)state;
    const double pts[][2] = {{0.3, 0.6}, {0.8, 0.9}, {0.15, 0.75}};
    for (int k = 0; k < 3; k++) {
        double alpha = pts[k][1] * pts[k][1];
        double ref = brute_albedo(sheen_brdf, &alpha, pts[k][0], 1200);
        assert_near(ibl_brdf_sheen_albedo(pts[k][0], pts[k][1], 0), ref, 1e-4);
    }
    assert_near(ibl_brdf_sheen_albedo(0.5, 0, 0), 0, 0);
}

/* The sheen albedo's cosine-weighted average is 2 int_0^1 E(mu) mu dmu: a 400-point midpoint
 * rule over the point evaluations (its error ~1e-5 on this smooth integrand), 1e-4. */
static void sheen_average(void **state)
{
    (void)state;
    const double rs[] = {0.25, 0.5, 0.9};
    for (int k = 0; k < 3; k++) {
        double sum = 0;
        for (int i = 0; i < 400; i++) {
            double mu = (i + 0.5) / 400;
            sum += 2 * ibl_brdf_sheen_albedo(mu, rs[k], 0) * mu / 400;
        }
        assert_near(ibl_brdf_sheen_albedo_average(rs[k], 0), sum, 1e-4);
    }
}

/* Convergence: doubling the order changes no value by more than 2e-5 (measured: 1.0e-5),
 * over a coarse grid plus the grazing column and the smooth row of a 128 table, where the
 * integrands are hardest. */
static void convergence_by_doubling(void **state)
{
    (void)state;
    double worst = 0;
    for (int j = 0; j < 10; j++) {
        double r = j == 0 ? 0.5 / 128 : j == 9 ? 127.5 / 128 : (j + 0.5) / 10;
        for (int i = 0; i < 10; i++) {
            double mu = i == 0 ? 0.5 / 128 : i == 9 ? 127.5 / 128 : (i + 0.5) / 10;
            for (int vis = 0; vis < 2; vis++) {
                double a1, b1, a2, b2;
                ibl_brdf_splitsum(mu, r, (ibl_brdf_visibility)vis, 24, &a1, &b1);
                ibl_brdf_splitsum(mu, r, (ibl_brdf_visibility)vis, 48, &a2, &b2);
                worst = fmax(worst, fmax(fabs(a1 - a2), fabs(b1 - b2)));
            }
            worst = fmax(worst, fabs(ibl_brdf_sheen_albedo(mu, r, 24) - ibl_brdf_sheen_albedo(mu, r, 48)));
            double s = exp(log(2000.0) * r);
            worst = fmax(worst, fabs(ibl_ambient_brdf(mu, s, 0.04, IBL_BLINN_TRIACE_FIT, 24) -
                                     ibl_ambient_brdf(mu, s, 0.04, IBL_BLINN_TRIACE_FIT, 48)));
        }
    }
    print_message("max |order 24 - order 48| %.2e\n", worst);
    assert_true(worst < 2e-5);
}

/* The Gauss-Legendre brute force's own error: 32 panels (256 x 256 points) against 64, at
 * the hardest points used below (grazing and normal n.v, the narrowest lobes). Measured
 * 1e-12; asserted below 1e-7, two orders under the 1e-5 it is used to check. */
static void brute_force_self_convergence(void **state)
{
    (void)state;
    const double mus[] = {0.5 / 128, 127.5 / 128};
    double worst = 0;
    for (int i = 0; i < 2; i++) {
        ggx_p g = {1.0 / 6.0, 0.0, 0};
        worst = fmax(worst, fabs(brute_albedo_gl(ggx_brdf, &g, mus[i], 32, 0) -
                                 brute_albedo_gl(ggx_brdf, &g, mus[i], 64, 0)));
        double alpha = 1.0 / 6.0;
        worst = fmax(worst, fabs(brute_albedo_gl(sheen_brdf, &alpha, mus[i], 32, 0) -
                                 brute_albedo_gl(sheen_brdf, &alpha, mus[i], 64, 0)));
        worst = fmax(worst, fabs(brute_albedo_gl(sheen_khr_brdf, &alpha, mus[i], 32, 0.5) -
                                 brute_albedo_gl(sheen_khr_brdf, &alpha, mus[i], 64, 0.5)));
    }
    print_message("brute force: |32 - 64 panels| <= %.2e\n", worst);
    assert_true(worst < 1e-7);
}

/* The default quadrature against the Gauss-Legendre brute force from grazing to normal n.v
 * (the table's first and last texel centres included) and r = 0.41 .. 1, where the brute
 * force resolves the lobe: A, B for both visibilities, the sheen albedo and the KHR sheen
 * albedo (r chosen so that Charlie's sin^(1/alpha) is a polynomial in n.h and the brute force
 * converges geometrically). The quadrature's measured error here is 4.7e-6 (GGX), 2.2e-6
 * (sheen) and 1.1e-6 (KHR sheen); the tolerance 1e-5 is ten times tighter than the 1e-4 the
 * tables were first held to. */
static void albedo_against_gl_brute_force(void **state)
{
    (void)state;
    const double mus[] = {0.5 / 128, 0.03, 0.3, 0.7, 127.5 / 128};
    const double rs[] = {0.40824829046386302, 0.5, 0.70710678118654752, 1.0};
    double worst = 0, worst_sheen = 0, worst_khr = 0;
    for (size_t i = 0; i < sizeof mus / sizeof mus[0]; i++)
        for (size_t k = 0; k < sizeof rs / sizeof rs[0]; k++) {
            double mu = mus[i], r = rs[k];
            for (int vis = 0; vis < 2; vis++) {
                ggx_p g = {r * r, 0.0, vis};
                double b_ref = brute_albedo_gl(ggx_brdf, &g, mu, 32, 0);
                g.f0 = 1.0;
                double e_ref = brute_albedo_gl(ggx_brdf, &g, mu, 32, 0);
                double a, b;
                ibl_brdf_splitsum(mu, r, (ibl_brdf_visibility)vis, 0, &a, &b);
                worst = fmax(worst, fmax(fabs(b - b_ref), fabs(a - (e_ref - b_ref))));
            }
            if (k < 3) {
                double alpha = r * r;
                double ref = brute_albedo_gl(sheen_brdf, &alpha, mu, 32, 0);
                worst_sheen = fmax(worst_sheen, fabs(ibl_brdf_sheen_albedo(mu, r, 0) - ref));
                /* KHR: alpha = r, here 1/6, 1/4, 1/2 (again a polynomial sin^(1/alpha)) */
                double khr_r = alpha;
                ref = brute_albedo_gl(sheen_khr_brdf, &khr_r, mu, 32, 0.5);
                worst_khr = fmax(worst_khr, fabs(ibl_brdf_sheen_khr_albedo(mu, khr_r, 0) - ref));
            }
        }
    print_message("GGX A, B: max |quadrature - brute force| %.2e; sheen %.2e; KHR sheen %.2e\n",
                  worst, worst_sheen, worst_khr);
    assert_true(worst < 1e-5);
    assert_true(worst_sheen < 1e-5);
    assert_true(worst_khr < 1e-5);
}

/* Texel (i, j) holds the value at n.v = (i + 0.5)/N, r = (j + 0.5)/N; row 0 is r ~ 0. */
static void lut_layout_and_channels(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2);
    ibl_brdf_lut_desc d = {.size = 16,
                           .channels = {IBL_BRDF_SCALE, IBL_BRDF_BIAS, IBL_BRDF_ALBEDO,
                                        IBL_BRDF_ALBEDO_AVG}};
    ibl_image im;
    assert_int_equal(ibl_brdf_lut(ctx, &d, &im), IBL_OK);
    assert_int_equal(ibl_brdf_lut_channel_count(&d), 4);
    for (int j = 0; j < 16; j += 5)
        for (int i = 0; i < 16; i += 3) {
            double a, b, mu = (i + 0.5) / 16, r = (j + 0.5) / 16;
            ibl_brdf_splitsum(mu, r, IBL_VISIBILITY_HEIGHT_CORRELATED, 0, &a, &b);
            const float *px = ibl_image_texel(&im, i, j);
            assert_near(px[0], a, 1e-6); /* float rounding of the same computation */
            assert_near(px[1], b, 1e-6);
            assert_near(px[2], a + b, 1e-6);
            assert_near(px[3], ibl_brdf_albedo_average(r, IBL_VISIBILITY_HEIGHT_CORRELATED, 0), 1e-6);
        }
    /* top row is the smooth end: near the r = 0 closed form; alpha = 1e-3 at n.v = 0.03
     * departs from it by O(alpha / n.v) ~ 3e-3, the bottom row (r ~ 1) by ~0.8 */
    double fc = pow(1 - 0.5 / 16, 5);
    assert_near(ibl_image_texel(&im, 0, 0)[1], fc, 3e-3);
    assert_true(fabs(ibl_image_texel(&im, 0, 15)[1] - fc) > 0.3);
    ibl_image_free(ctx, &im);
    /* default channels: A, B, then 0 and alpha 1 */
    ibl_brdf_lut_desc d2 = {.size = 4};
    assert_int_equal(ibl_brdf_lut(ctx, &d2, &im), IBL_OK);
    assert_near(ibl_image_texel(&im, 2, 1)[2], 0, 0);
    assert_near(ibl_image_texel(&im, 2, 1)[3], 1, 0);
    ibl_image_free(ctx, &im);
    /* invalid descriptors are refused with a message */
    ibl_brdf_lut_desc bad = {.size = -3};
    assert_int_equal(ibl_brdf_lut(ctx, &bad, &im), IBL_ERR_INVALID_ARGUMENT);
    assert_non_null(strstr(ibl_context_message(ctx), "size"));
    ibl_brdf_lut_desc bad2 = {.size = 4, .channels = {IBL_BRDF_SCALE, IBL_BRDF_NONE, IBL_BRDF_BIAS}};
    assert_int_equal(ibl_brdf_lut(ctx, &bad2, &im), IBL_ERR_INVALID_ARGUMENT);
    ibl_context_destroy(ctx);
}

static int images_equal(const ibl_image *a, const ibl_image *b)
{
    return a->width == b->width && a->height == b->height &&
           memcmp(a->pixels, b->pixels, (size_t)a->width * a->height * 16) == 0;
}

static void identical_at_any_thread_count(void **state)
{
    (void)state;
    ibl_brdf_lut_desc d = {.size = 20,
                           .channels = {IBL_BRDF_SCALE, IBL_BRDF_BIAS, IBL_BRDF_SHEEN,
                                        IBL_BRDF_ALBEDO_AVG}};
    ibl_ambient_brdf_desc ad = {.size_nv = 8, .size_shininess = 9, .size_f0 = 4};
    ibl_image ref, ref2;
    ibl_texture vref;
    ibl_context *ctx0 = test_context(1);
    assert_int_equal(ibl_brdf_lut(ctx0, &d, &ref), IBL_OK);
    assert_int_equal(ibl_ambient_brdf_table(ctx0, &ad, &ref2), IBL_OK);
    assert_int_equal(ibl_ambient_brdf_volume(ctx0, &ad, &vref), IBL_OK);
    const int threads[] = {2, 8};
    for (int t = 0; t < 2; t++) {
        ibl_context *ctx = test_context(threads[t]);
        ibl_image im, im2;
        ibl_texture vol;
        assert_int_equal(ibl_brdf_lut(ctx, &d, &im), IBL_OK);
        assert_int_equal(ibl_ambient_brdf_table(ctx, &ad, &im2), IBL_OK);
        assert_int_equal(ibl_ambient_brdf_volume(ctx, &ad, &vol), IBL_OK);
        assert_true(images_equal(&ref, &im));
        assert_true(images_equal(&ref2, &im2));
        assert_memory_equal(vref.data, vol.data, (size_t)8 * 9 * 4 * 16);
        ibl_image_free(ctx, &im);
        ibl_image_free(ctx, &im2);
        ibl_texture_free(ctx, &vol);
        ibl_context_destroy(ctx);
    }
    ibl_image_free(ctx0, &ref);
    ibl_image_free(ctx0, &ref2);
    ibl_texture_free(ctx0, &vref);
    ibl_context_destroy(ctx0);
}

/* ---- AmbientBRDF ---- */

/* F0 = 1 gives the specular directional albedo (F = 1), against the brute force; and the
 * exact normalisation gives albedo 1 at n.v = 1 (its derivation in docs/BRDF.md). 1e-4. */
static void ambient_albedo(void **state)
{
    (void)state;
    const double pts[][2] = {{0.9, 4}, {0.4, 20}, {0.12, 10}};
    for (int k = 0; k < 3; k++) {
        double s = pts[k][1];
        blinn_p p = {s, ibl_blinn_normalization_factor(IBL_BLINN_TRIACE_FIT, s), 1.0, 0};
        double ref = brute_albedo(blinn_brdf, &p, pts[k][0], 1200);
        assert_near(ibl_ambient_brdf(pts[k][0], s, 1.0, IBL_BLINN_TRIACE_FIT, 0), ref, 1e-4);
        p.f0 = 0.04;
        ref = brute_albedo(blinn_brdf, &p, pts[k][0], 1200);
        assert_near(ibl_ambient_brdf(pts[k][0], s, 0.04, IBL_BLINN_TRIACE_FIT, 0), ref, 1e-4);
    }
    const double ss[] = {0.5, 1, 10, 100, 2000};
    for (int k = 0; k < 5; k++)
        assert_near(ibl_ambient_brdf(1.0, ss[k], 1.0, IBL_BLINN_EXACT, 0), 1.0, 1e-4);
    /* tri-Ace's linear fit is the exact factor's asymptote 1/(8 pi): within 0.2% at s = 2000 */
    assert_near(ibl_blinn_normalization_factor(IBL_BLINN_TRIACE_FIT, 2000) /
                    ibl_blinn_normalization_factor(IBL_BLINN_EXACT, 2000), 1.0, 4e-3);
}

/* The 3D volume (accumulated per F0 at every node) and the 2D form F0 X + Y agree; slices
 * sit at texel centres; G is the exact diffuse factor 1 - F0. Tolerance 1e-5: the same
 * integrals summed in a different order, stored as float. */
static void ambient_volume_vs_table(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2);
    ibl_ambient_brdf_desc d = {.size_nv = 12, .size_shininess = 10, .size_f0 = 6};
    ibl_texture vol;
    ibl_image tab;
    assert_int_equal(ibl_ambient_brdf_volume(ctx, &d, &vol), IBL_OK);
    assert_int_equal(ibl_ambient_brdf_table(ctx, &d, &tab), IBL_OK);
    assert_int_equal(vol.kind, IBL_TEXTURE_3D);
    assert_int_equal(vol.depth, 6);
    double worst = 0;
    for (int k = 0; k < 6; k++)
        for (int j = 0; j < 10; j++)
            for (int i = 0; i < 12; i++) {
                const float *v = vol.data + (((size_t)k * 10 + j) * 12 + i) * 4;
                const float *t = ibl_image_texel(&tab, i, j);
                double f0 = (k + 0.5) / 6;
                worst = fmax(worst, fabs(v[0] - (f0 * t[0] + t[1])));
                assert_near(v[1], 1 - f0, 1e-7);
            }
    assert_true(worst < 1e-5);
    /* a texel against the point evaluation at its centre */
    double s = ibl_ambient_brdf_row_shininess(&d, 7);
    assert_near(s, exp(log(2000.0) * 7.5 / 10), 1e-9 * s);
    const float *v = vol.data + (((size_t)2 * 10 + 7) * 12 + 3) * 4;
    assert_near(v[0], ibl_ambient_brdf(3.5 / 12, s, 2.5 / 6, IBL_BLINN_TRIACE_FIT, 0), 1e-5);
    ibl_texture_free(ctx, &vol);
    ibl_image_free(ctx, &tab);
    ibl_ambient_brdf_desc bad = {.shininess_min = 10, .shininess_max = 5};
    assert_int_equal(ibl_ambient_brdf_table(ctx, &bad, &tab), IBL_ERR_INVALID_ARGUMENT);
    ibl_context_destroy(ctx);
}

/* Constant environment L: the table value times the normalised prefiltered value (lobe-
 * weighted average of L = L) reproduces the full integral of f_spec L (n.w'), computed by
 * brute force. The talk's literal reading (table without (n.h)^s, times the unnormalised
 * prefiltered integral) does not, and its table grows without bound with shininess. */
static void ambient_constant_environment(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2);
    const double L = 2.5;
    ibl_ambient_brdf_desc d = {.size_nv = 8, .size_shininess = 8, .size_f0 = 4,
                               .shininess_min = 2, .shininess_max = 60};
    ibl_texture vol;
    assert_int_equal(ibl_ambient_brdf_volume(ctx, &d, &vol), IBL_OK);
    const int cells[][3] = {{5, 2, 1}, {2, 5, 3}};
    for (int c = 0; c < 2; c++) {
        int i = cells[c][0], j = cells[c][1], k = cells[c][2];
        double mu = (i + 0.5) / 8, s = ibl_ambient_brdf_row_shininess(&d, j), f0 = (k + 0.5) / 4;
        blinn_p p = {s, ibl_blinn_normalization_factor(IBL_BLINN_TRIACE_FIT, s), f0, 0};
        double full = L * brute_albedo(blinn_brdf, &p, mu, 1200);
        /* normalised prefilter of a constant environment: sum w L / sum w */
        double wsum = brute_albedo(blinn_lobe, &p, mu, 600);
        double prefiltered = L * wsum / wsum;
        double table = vol.data[(((size_t)k * 8 + j) * 8 + i) * 4];
        assert_near(table * prefiltered, full, 1e-4 * L);
        /* literal reading */
        p.literal = 1;
        double literal = brute_albedo(blinn_brdf, &p, mu, 600) * (L * wsum);
        assert_true(fabs(literal - full) > 0.05 * full);
    }
    blinn_p big = {1000, ibl_blinn_normalization_factor(IBL_BLINN_TRIACE_FIT, 1000), 1.0, 1};
    assert_true(brute_albedo(blinn_brdf, &big, 0.5, 200) > 20.0);
    ibl_texture_free(ctx, &vol);
    ibl_context_destroy(ctx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(splitsum_smooth_limit),
        cmocka_unit_test(splitsum_rough_closed_forms),
        cmocka_unit_test(splitsum_published),
        cmocka_unit_test(splitsum_brute_force),
        cmocka_unit_test(sheen_brute_force),
        cmocka_unit_test(sheen_average),
        cmocka_unit_test(convergence_by_doubling),
        cmocka_unit_test(brute_force_self_convergence),
        cmocka_unit_test(albedo_against_gl_brute_force),
        cmocka_unit_test(lut_layout_and_channels),
        cmocka_unit_test(identical_at_any_thread_count),
        cmocka_unit_test(ambient_albedo),
        cmocka_unit_test(ambient_volume_vs_table),
        cmocka_unit_test(ambient_constant_environment),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
