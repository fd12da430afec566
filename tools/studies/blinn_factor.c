/* Study 2: tri-Ace 2010's fit cos^n(theta) ~ cos^(4.2 n)(theta / 2) ("Fitting shininess"),
 * which lets a Phong-kernel chain stand for the Blinn-Phong material: the level of material
 * shininess s is filtered with the Phong exponent s / f, f = 4.2.
 *
 * At normal incidence (v = n, so R = n) the Blinn lobe (n.h)^s is cos^s(theta/2) of the angle
 * theta between l and R, over the whole sphere; the Phong lobe is max(cos theta, 0)^(s/f). Both
 * are normalised to integrate to 1 (a prefiltered map is a weighted mean) and compared:
 *   L1 = int |b - p| dw,   relative L2 = sqrt(int (b - p)^2 dw / int b^2 dw),
 * by composite Simpson quadrature in theta (float64, closed-form normalisations: the Blinn
 * lobe integrates to 8 pi / (s + 2), the Phong lobe to 2 pi / (n + 1)). The best factor
 * minimises the relative L2 (least squares), per shininess and over all of them.
 * Then the same on a real environment: the float64 convolution of forest.exr (32² faces) by
 * the exact Blinn lobe against the Phong lobe s / f, over 1536 directions. */
#include "studies.h"

#include <math.h>
#include <stdlib.h>

enum { SIMPSON = 8000 };

static const double shininess_list[] = {1, 2, 5, 10, 20, 50, 100, 200, 500, 1000, 2000, 10000};
enum { SHININESS_COUNT = sizeof shininess_list / sizeof shininess_list[0] };

typedef struct lobe_error {
    double l1, l2; /* L1 and relative L2 of the normalised lobes */
} lobe_error;

/* Both normalised lobes at angle theta (the Phong exponent n = s / f). */
static void lobes(double theta, double s, double n, double *b, double *p)
{
    double h = cos(0.5 * theta), c = cos(theta);
    *b = pow(h, s) * (s + 2.0) / (8.0 * M_PI);
    *p = c > 0.0 ? pow(c, n) * (n + 1.0) / (2.0 * M_PI) : 0.0;
}

static lobe_error lobe_compare(double s, double f)
{
    double n = s / f;
    /* both lobes are below e^-50 of their peak past 30 / sqrt(s) (Blinn ~ exp(-s t^2 / 8)) */
    double top = 30.0 / sqrt(s) < M_PI ? 30.0 / sqrt(s) : M_PI;
    double h = top / SIMPSON, l1 = 0.0, d2 = 0.0, b2 = 0.0;
    for (int i = 0; i <= SIMPSON; i++) {
        double t = i * h, b, p;
        lobes(t, s, n, &b, &p);
        double w = (i == 0 || i == SIMPSON) ? 1.0 : (i % 2 ? 4.0 : 2.0);
        w *= 2.0 * M_PI * sin(t) * h / 3.0; /* dw = 2 pi sin(theta) dtheta */
        l1 += w * fabs(b - p);
        d2 += w * (b - p) * (b - p);
        b2 += w * b * b;
    }
    return (lobe_error){l1, sqrt(d2 / b2)};
}

/* Golden-section search of the factor in [lo, hi] minimising cost(f). */
typedef double (*factor_cost)(double f, void *user);

static double golden_min(factor_cost cost, void *user, double lo, double hi)
{
    const double g = 0.5 * (sqrt(5.0) - 1.0);
    double a = lo, b = hi, c = b - g * (b - a), d = a + g * (b - a);
    double fc = cost(c, user), fd = cost(d, user);
    for (int it = 0; it < 60 && b - a > 1e-6; it++) {
        if (fc < fd) {
            b = d, d = c, fd = fc;
            c = b - g * (b - a), fc = cost(c, user);
        } else {
            a = c, c = d, fc = fd;
            d = a + g * (b - a), fd = cost(d, user);
        }
    }
    return 0.5 * (a + b);
}

static double cost_one(double f, void *user)
{
    double e = lobe_compare(*(const double *)user, f).l2;
    return e * e;
}

/* Sum of the squared relative L2 over shininess values spread evenly in log s over [lo, hi]. */
enum { FIT_POINTS = 32 };

static double cost_range(double f, void *user)
{
    const double *range = user;
    double sum = 0.0;
    for (int i = 0; i < FIT_POINTS; i++) {
        double s = range[0] * pow(range[1] / range[0], i / (FIT_POINTS - 1.0));
        double e = lobe_compare(s, f).l2;
        sum += e * e;
    }
    return sum / FIT_POINTS;
}

static void fit_line(FILE *md, double lo, double hi)
{
    double range[2] = {lo, hi};
    double f = golden_min(cost_range, range, 1.0, 100.0);
    fprintf(md, "| %g … %g | **%.3f** | %.2f%% | %.2f%% | %.2f%% |\n", lo, hi, f, 100 * sqrt(cost_range(f, range)),
            100 * sqrt(cost_range(4.2, range)), 100 * sqrt(cost_range(4.0, range)));
}

/* RMS relative luminance error of the Phong s/f convolution against the exact Blinn lobe's,
 * over the directions; blinn_ref caches the Blinn values. */
static double hdri_error(const ibl_cubemap *src, double s, double f, int count, double (*dirs)[3],
                         double *blinn_ref, int have_ref)
{
    double n = s / f, sum2 = 0.0;
    /* resolve the narrower lobe: a few sub-texels across its half-width */
    double half = acos(pow(0.5, 1.0 / (n > 1.0 ? n : 1.0)));
    int k = (int)ceil(4.0 * (M_PI / 2.0 / src->size) / half);
    study_quad q;
    if (study_quad_build(src, k < 1 ? 1 : k > 16 ? 16 : k, &q)) return -1.0;
    double bcut = 2.0 * exp(log(1e-16) * 2.0 / s) - 1.0;
    for (int i = 0; i < count; i++) {
        double out[3];
        if (!have_ref) {
            study_convolve(&q, dirs[i], study_kernel_blinn_n1, s, bcut, out);
            blinn_ref[i] = study_luminance_d(out);
        }
        study_convolve(&q, dirs[i], study_kernel_phong, n, study_phong_cut(n), out);
        double rel = (study_luminance_d(out) - blinn_ref[i]) / blinn_ref[i];
        sum2 += rel * rel;
    }
    study_quad_free(&q);
    return sqrt(sum2 / count);
}

static int hdri_table(const study_env *env, FILE *md, const double *best)
{
    ibl_cubemap src;
    if (study_load_cube(env, "forest.exr", 32, &src)) return 1;
    int count = env->quick ? 256 : 1024;
    double(*dirs)[3] = malloc((size_t)count * sizeof *dirs);
    double *ref = malloc((size_t)count * sizeof *ref);
    int rc = dirs && ref ? 0 : 1;
    if (!rc) study_sphere_points(count, dirs);
    fprintf(md, "\n| shininess s | RMS error, f = 4.2 | f = 4 | f = best of the lobe fit |\n");
    fprintf(md, "|---|---|---|---|\n");
    for (int i = 0; i < SHININESS_COUNT && !rc; i++) {
        double s = shininess_list[i], e[3];
        const double f[3] = {4.2, 4.0, best[i]};
        for (int j = 0; j < 3 && !rc; j++) {
            e[j] = hdri_error(&src, s, f[j], count, dirs, ref, j > 0);
            if (e[j] < 0) rc = 1;
        }
        if (!rc)
            fprintf(md, "| %g | %.2f%% | %.2f%% | %.2f%% (f = %.3f) |\n", s, 100 * e[0], 100 * e[1],
                    100 * e[2], best[i]);
    }
    free(dirs);
    free(ref);
    ibl_cubemap_free(env->ctx, &src);
    return rc;
}

int study_blinn_factor(const study_env *env)
{
    FILE *md = study_fragment(env, "blinn");
    if (!md) return 1;
    double best[SHININESS_COUNT];
    fprintf(md, "| shininess s | L1, f = 4.2 | rel. L2, f = 4.2 | L1, f = 4 | rel. L2, f = 4 | best f | rel. L2 at best f |\n");
    fprintf(md, "|---|---|---|---|---|---|---|\n");
    for (int i = 0; i < SHININESS_COUNT; i++) {
        double s = shininess_list[i];
        lobe_error a = lobe_compare(s, 4.2), b = lobe_compare(s, 4.0);
        best[i] = golden_min(cost_one, &s, 1.0, 100.0);
        lobe_error c = lobe_compare(s, best[i]);
        fprintf(md, "| %g | %.4f | %.2f%% | %.4f | %.2f%% | %.3f | %.2f%% |\n", s, a.l1, 100 * a.l2, b.l1,
                100 * b.l2, best[i], 100 * c.l2);
    }
    fprintf(md, "\nLeast-squares factor over a shininess range (%d values evenly spaced in log s, each "
                "weighted equally; the RMS of the relative L2 at the best factor, at 4.2 and at 4):\n\n",
            FIT_POINTS);
    fprintf(md, "| range of s | best f | RMS rel. L2 | at f = 4.2 | at f = 4 |\n|---|---|---|---|---|\n");
    fit_line(md, 1, 2000);
    fit_line(md, 10, 2000);
    fit_line(md, 1, 250);
    fit_line(md, 10, 1000);
    fprintf(md, "\nOn forest.exr (32² faces, 1024 directions): RMS relative error of the luminance "
                "of the Phong-kernel convolution against the exact Blinn-lobe convolution:\n");
    int rc = hdri_table(env, md, best);
    if (rc) {
        fclose(md);
        return rc;
    }
    return study_fragment_close(env, md, "blinn");
}
