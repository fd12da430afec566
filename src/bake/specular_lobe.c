/* The lobes of the Phong family and of GGX as functions of x = cos(angle to the lobe axis),
 * with the derivatives the fast method's second-order leaves need and the log slope the
 * reference uses to split texels. Phong: Phong 1975 / tri-Ace 2010 "Spherical Phong kernel";
 * Blinn through tri-Ace's fit cos^n(t) ~ cos^(4.2 n)(t/2); GGX: Walter et al. 2007 with v = n
 * (Karis 2013 split sum). */
#include "specular_internal.h"
#include "core/numeric.h"
#include "core/defaults.h"

#include <math.h>


double ibl__lobe_f(const ibl__lobe *lobe, double x)
{
    if (x <= 0.0) return 0.0;
    if (x > 1.0) x = 1.0;
    if (lobe->kind == IBL__LOBE_PHONG) return pow(x, lobe->n);
    /* D(h) / D(n) with (n.h)^2 = (1 + x) / 2: alpha^4 / t^2, t = 1 + (1 + x) k */
    double t = 1.0 + (1.0 + x) * lobe->k;
    return x * lobe->a4 / (t * t);
}

void ibl__lobe_f012(const ibl__lobe *lobe, double x, double out[3])
{
    if (x <= 0.0) {
        out[0] = out[1] = out[2] = 0.0;
        return;
    }
    if (lobe->kind == IBL__LOBE_PHONG) {
        double n = lobe->n, f = pow(x, n);
        out[0] = f;
        out[1] = n * f / x;
        out[2] = n * (n - 1.0) * f / (x * x);
        return;
    }
    double k = lobe->k, t = 1.0 + (1.0 + x) * k, it = 1.0 / t;
    double it2 = it * it, it3 = it2 * it;
    out[0] = lobe->a4 * x * it2;
    out[1] = lobe->a4 * it3 * (t - 2.0 * k * x);
    out[2] = lobe->a4 * it3 * it * (-4.0 * k * t + 6.0 * k * k * x);
}

double ibl__lobe_log_slope(const ibl__lobe *lobe, double theta)
{
    if (theta <= 0.0) return 0.0;
    if (theta >= 0.5 * IBL_PI) theta = 0.5 * IBL_PI - 1e-9;
    double x = cos(theta), s = sin(theta);
    if (lobe->kind == IBL__LOBE_PHONG) return lobe->n * s / x;
    double t = 1.0 + (1.0 + x) * lobe->k;
    return s * (1.0 / x - 2.0 * lobe->k / t);
}

/* The relative variation rate of the lobe, |df/dtheta| / max(f, 0.02): the log slope where
 * the lobe matters, the plain slope (in units of 2% of the peak) in its tail and at the
 * horizon, where f goes to zero and the log slope to infinity without mattering. Sampled at
 * the candidates below. */
static double variation(const ibl__lobe *lobe, double theta)
{
    if (theta <= 0.0) return 0.0;
    if (theta > 0.5 * IBL_PI) theta = 0.5 * IBL_PI;
    double f[3];
    ibl__lobe_f012(lobe, cos(theta), f);
    double floor_value = 0.1;
    return fabs(f[1]) * sin(theta) / (f[0] > floor_value ? f[0] : floor_value);
}

double ibl__lobe_max_log_slope(const ibl__lobe *lobe, double t0, double t1)
{
    /* the variation rises to the lobe's log-slope peak (GGX) and to where f meets the floor,
     * and falls after: its maximum over [t0, t1] is at one of these points or an end */
    double cand[4] = {t0, t1, lobe->floor_angle, lobe->peak_angle};
    double g = 0;
    for (int i = 0; i < 4; i++) {
        if (cand[i] < t0 || cand[i] > t1) continue;
        double v = variation(lobe, cand[i]);
        if (v > g) g = v;
    }
    return g;
}

/* The angle in [0, pi/2] where f falls to `value` (f decreases with the angle). */
static double angle_where(const ibl__lobe *lobe, double value)
{
    double lo = 0.0, hi = 0.5 * IBL_PI;
    for (int i = 0; i < 100; i++) {
        double mid = 0.5 * (lo + hi);
        if (ibl__lobe_f(lobe, cos(mid)) > value) lo = mid;
        else hi = mid;
    }
    return hi;
}

static ibl__lobe make_phong(double n)
{
    ibl__lobe l = {0};
    l.kind = IBL__LOBE_PHONG;
    l.n = n;
    l.cull_angle = angle_where(&l, 1e-12);
    l.half_angle = angle_where(&l, 0.5);
    l.horizon = ibl__lobe_f(&l, sin(0.1));
    l.floor_angle = angle_where(&l, 0.1);
    return l;
}

static ibl__lobe make_ggx(double roughness)
{
    ibl__lobe l = {0};
    l.kind = IBL__LOBE_GGX;
    l.alpha = roughness * roughness;
    double a2 = l.alpha * l.alpha;
    l.k = 0.5 * (a2 - 1.0);
    l.a4 = a2 * a2;
    l.cull_angle = angle_where(&l, 1e-12);
    l.half_angle = angle_where(&l, 0.5);
    /* the D part of the log slope peaks near 2 alpha; find it on a fine scan */
    double best = 0, best_t = 0;
    for (int i = 1; i < 4000; i++) {
        double t = 0.5 * IBL_PI * i / 4000.0;
        double g = ibl__lobe_log_slope(&l, t) - tan(t);
        if (g > best) best = g, best_t = t;
    }
    l.peak_angle = best_t;
    l.horizon = ibl__lobe_f(&l, sin(0.1));
    l.floor_angle = angle_where(&l, 0.1);
    return l;
}

/* A GGX level whose roughness is at most this is a mirror: its lobe is far narrower than any
 * texel we handle. */
#define GGX_MIRROR_ROUGHNESS 1e-3

int ibl__level_is_mirror(const ibl_specular_info *info, int level)
{
    if (info->filter == IBL_FILTER_GGX) return !(info->roughness[level] > GGX_MIRROR_ROUGHNESS);
    double n = ibl__level_phong_exponent(info, level);
    return !(n > 0.0) || isinf(n) || n > 1e7;
}

ibl__lobe ibl__lobe_for_level(const ibl_specular_info *info, int level)
{
    if (ibl__level_is_mirror(info, level)) {
        ibl__lobe mirror = {0};
        mirror.kind = IBL__LOBE_MIRROR;
        return mirror;
    }
    if (info->filter == IBL_FILTER_GGX) {
        double r = info->roughness[level];
        return make_ggx(r > 1.0 ? 1.0 : r);
    }
    return make_phong(ibl__level_phong_exponent(info, level));
}

typedef struct lobes_job {
    const ibl_specular_info *info;
    ibl__lobe *out;
} lobes_job;

static void lobe_task(void *arg, int level)
{
    lobes_job *j = arg;
    j->out[level] = ibl__lobe_for_level(j->info, level);
}

void ibl__lobes_for_levels(ibl_context *ctx, const ibl_specular_info *info, int levels, ibl__lobe *out)
{
    lobes_job job = {info, out};
    ibl_parallel_for(ctx, levels, lobe_task, &job);
}

double ibl__rect_radius(int face, double u0, double v0, double u1, double v1, double centre[3])
{
    ibl_cube_direction_d(face, 0.5 * (0.5 * (u0 + u1) + 1.0), 0.5 * (0.5 * (v0 + v1) + 1.0),
                         centre);
    double len = sqrt(centre[0] * centre[0] + centre[1] * centre[1] + centre[2] * centre[2]);
    for (int i = 0; i < 3; i++) centre[i] /= len;
    double min_dot = 1.0;
    for (int k = 0; k < 4; k++) {
        double u = (k & 1) ? u1 : u0, v = (k & 2) ? v1 : v0, d[3];
        ibl_cube_direction_d(face, 0.5 * (u + 1.0), 0.5 * (v + 1.0), d);
        double l = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        double c = (d[0] * centre[0] + d[1] * centre[1] + d[2] * centre[2]) / l;
        if (c < min_dot) min_dot = c;
    }
    if (min_dot > 1.0) min_dot = 1.0;
    return acos(min_dot);
}
