/* The split-sum GGX table (Karis 2013; the JAGE 2015 article's IntegrateEnvBRDF) with
 * optional multiple-scattering (Kulla & Conty 2017: E and E_avg) and Charlie sheen channels
 * (Estevez & Kulla 2017 distribution, Neubelt & Pettineo 2013 visibility), by the
 * deterministic quadrature of brdf_common.c. */
#include "ibl/brdf.h"
#include "core/context_internal.h"

#include <math.h>
#include <string.h>

#include "bake/brdf_common.h"

enum { DEFAULT_SIZE = 128 };

typedef struct rules {
    ibl__quadrature q; /* the albedo integral                                     */
    ibl__rule mu;      /* the cosine-weighted average over n.v (GGX)               */
    ibl__rule mu_sheen; /* the same for the sheen albedos, steeper at grazing n.v */
} rules;

static void make_rules(int order, rules *r)
{
    ibl__quadrature_init(&r->q, order);
    if (order <= 0) order = IBL__DEFAULT_ORDER;
    ibl__gauss_legendre(r->q.u_part.n, &r->mu);
    ibl__gauss_legendre(order, &r->mu_sheen);
}

static ibl__lobe_params ggx_params(double r, ibl_brdf_visibility vis)
{
    ibl__lobe_params p;
    memset(&p, 0, sizeof p);
    p.lobe = vis == IBL_VISIBILITY_SEPARABLE ? IBL__LOBE_GGX_SEPARABLE : IBL__LOBE_GGX_CORRELATED;
    p.alpha = r * r;
    return p;
}

static double clamp_mu(double mu)
{
    /* n.v = 0 is a limit the table never samples (texel centres); keep the maths finite. */
    if (!(mu > 1e-7)) return 1e-7;
    return mu > 1.0 ? 1.0 : mu;
}

static void splitsum_rules(double nv, double r, ibl_brdf_visibility vis, const rules *R,
                           double *a, double *b)
{
    double mu = clamp_mu(nv);
    if (!(r > 0)) {
        /* alpha -> 0: D becomes a delta at h = n, G -> 1, F evaluated at v.h = n.v. */
        double t = 1.0 - mu, fc = t * t * t * t * t;
        *a = 1.0 - fc;
        *b = fc;
        return;
    }
    ibl__lobe_params p = ggx_params(r > 1 ? 1 : r, vis);
    double m[2];
    ibl__albedo_moments(&p, mu, &R->q, m);
    *a = m[0];
    *b = m[1];
}

/* sheen: 1 the table's Charlie (alpha = r^2, Neubelt-Pettineo visibility), 2 the
 * KHR_materials_sheen form (alpha = r, the extension's Charlie visibility) */
static double sheen_rules(double nv, double r, const rules *R, int sheen)
{
    if (!(r > 0)) return 0; /* the Charlie lobe collapses onto the horizon: no valid l */
    ibl__lobe_params p;
    memset(&p, 0, sizeof p);
    p.lobe = sheen == 2 ? IBL__LOBE_CHARLIE_KHR : IBL__LOBE_CHARLIE;
    p.alpha = r > 1 ? 1 : sheen == 2 ? r : r * r;
    double m[2];
    ibl__albedo_moments(&p, clamp_mu(nv), &R->q, m);
    return m[0] + m[1];
}

/* E_avg = 2 integral_0^1 E(mu) mu dmu with mu = t^2 (4 integral E(t^2) t^3 dt), which
 * tames the mu log(mu) behaviour of E at grazing angles. The GGX albedo is smooth enough in t
 * for order / 2 Gauss-Legendre points (1.2e-6 at the default); the Charlie albedo, steep at
 * grazing n.v for small r, takes order points; the KHR sheen albedo has a kink at n.v = 0.5
 * (its Lambda(n.v) is mirrored there), so its integral is split at t = sqrt(0.5). */
static double average_rules(double r, int sheen, ibl_brdf_visibility vis, const rules *R)
{
    const ibl__rule *rule = sheen == 1 ? &R->mu_sheen : &R->mu;
    double split = sqrt(0.5), ends[3] = {0, sheen == 2 ? split : 1, 1};
    int pieces = sheen == 2 ? 2 : 1;
    double acc = 0;
    for (int piece = 0; piece < pieces; piece++) {
        double t0 = ends[piece], dt = ends[piece + 1] - t0;
        for (int k = 0; k < rule->n; k++) {
            double t = t0 + dt * rule->x[k], mu = t * t, e;
            if (sheen) {
                e = sheen_rules(mu, r, R, sheen);
            } else {
                double a, b;
                splitsum_rules(mu, r, vis, R, &a, &b);
                e = a + b;
            }
            acc += dt * rule->w[k] * 4.0 * e * t * t * t;
        }
    }
    return acc;
}

void ibl_brdf_splitsum(double nv, double r, ibl_brdf_visibility visibility, int order,
                       double *scale, double *bias)
{
    rules R;
    make_rules(order, &R);
    double a, b;
    splitsum_rules(nv, r, visibility, &R, &a, &b);
    if (scale) *scale = a;
    if (bias) *bias = b;
}

double ibl_brdf_albedo_average(double r, ibl_brdf_visibility visibility, int order)
{
    rules R;
    make_rules(order, &R);
    return average_rules(r, 0, visibility, &R);
}

double ibl_brdf_sheen_albedo(double nv, double r, int order)
{
    rules R;
    make_rules(order, &R);
    return sheen_rules(nv, r, &R, 1);
}

double ibl_brdf_sheen_khr_albedo(double nv, double r, int order)
{
    rules R;
    make_rules(order, &R);
    return sheen_rules(nv, r, &R, 2);
}

double ibl_brdf_sheen_khr_albedo_average(double r, int order)
{
    rules R;
    make_rules(order, &R);
    return average_rules(r, 2, IBL_VISIBILITY_HEIGHT_CORRELATED, &R);
}

double ibl_brdf_sheen_albedo_average(double r, int order)
{
    rules R;
    make_rules(order, &R);
    return average_rules(r, 1, IBL_VISIBILITY_HEIGHT_CORRELATED, &R);
}

/* ------------------------------------------------------------------------------------------ */

static const ibl_brdf_channel default_channels[4] = {IBL_BRDF_SCALE, IBL_BRDF_BIAS,
                                                     IBL_BRDF_NONE, IBL_BRDF_NONE};

static const ibl_brdf_channel *channel_list(const ibl_brdf_lut_desc *d)
{
    return d->channels[0] == IBL_BRDF_NONE ? default_channels : d->channels;
}

int ibl_brdf_lut_channel_count(const ibl_brdf_lut_desc *desc)
{
    if (!desc) return 2;
    const ibl_brdf_channel *c = channel_list(desc);
    int n = 0;
    while (n < 4 && c[n] != IBL_BRDF_NONE) n++;
    return n;
}

typedef struct lut_job {
    const ibl_brdf_lut_desc *desc;
    const ibl_brdf_channel *channels;
    int nchannels, size;
    rules R;
    int need_ab, need_sheen, need_avg, need_sheen_avg, need_khr, need_khr_avg;
    ibl_image *out;
} lut_job;

/* One row (one roughness) per task: the chunks do not depend on the thread count. */
static void lut_row(void *arg, int j)
{
    const lut_job *job = arg;
    int n = job->size;
    double r = (j + 0.5) / n;
    double avg = 0, sheen_avg = 0, khr_avg = 0;
    if (job->need_avg) avg = average_rules(r, 0, job->desc->visibility, &job->R);
    if (job->need_sheen_avg) sheen_avg = average_rules(r, 1, job->desc->visibility, &job->R);
    if (job->need_khr_avg) khr_avg = average_rules(r, 2, job->desc->visibility, &job->R);
    for (int i = 0; i < n; i++) {
        double mu = (i + 0.5) / n, a = 0, b = 0, sheen = 0, khr = 0;
        if (job->need_ab) splitsum_rules(mu, r, job->desc->visibility, &job->R, &a, &b);
        if (job->need_sheen) sheen = sheen_rules(mu, r, &job->R, 1);
        if (job->need_khr) khr = sheen_rules(mu, r, &job->R, 2);
        float *px = ibl_image_texel(job->out, i, j);
        px[0] = px[1] = px[2] = 0;
        px[3] = 1;
        for (int c = 0; c < job->nchannels; c++) {
            double v = 0;
            switch (job->channels[c]) {
            case IBL_BRDF_SCALE: v = a; break;
            case IBL_BRDF_BIAS: v = b; break;
            case IBL_BRDF_ALBEDO: v = a + b; break;
            case IBL_BRDF_ALBEDO_AVG: v = avg; break;
            case IBL_BRDF_SHEEN: v = sheen; break;
            case IBL_BRDF_SHEEN_AVG: v = sheen_avg; break;
            case IBL_BRDF_SHEEN_KHR: v = khr; break;
            case IBL_BRDF_SHEEN_KHR_AVG: v = khr_avg; break;
            case IBL_BRDF_ONE: v = 1; break;
            default: v = 0; break;
            }
            px[c] = (float)v;
        }
    }
}

ibl_status ibl_brdf_lut(ibl_context *ctx, const ibl_brdf_lut_desc *desc, ibl_image *out)
{
    if (!out) return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "brdf lut: no output image");
    memset(out, 0, sizeof *out);
    ibl_brdf_lut_desc d;
    memset(&d, 0, sizeof d);
    if (desc) d = *desc;
    if (d.size == 0) d.size = DEFAULT_SIZE;
    if (d.size < 1 || d.size > 16384)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "brdf lut: size %d is not in 1..16384", d.size);
    if (d.visibility != IBL_VISIBILITY_HEIGHT_CORRELATED && d.visibility != IBL_VISIBILITY_SEPARABLE)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "brdf lut: unknown visibility %d",
                        (int)d.visibility);
    if (d.order < 0 || d.order > IBL__GL_MAX)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "brdf lut: order %d is not in 0..%d",
                        d.order, (int)IBL__GL_MAX);
    lut_job job;
    memset(&job, 0, sizeof job);
    job.desc = &d;
    job.channels = channel_list(&d);
    job.nchannels = ibl_brdf_lut_channel_count(&d);
    job.size = d.size;
    for (int c = 0; c < job.nchannels; c++) {
        switch (job.channels[c]) {
        case IBL_BRDF_SCALE:
        case IBL_BRDF_BIAS:
        case IBL_BRDF_ALBEDO: job.need_ab = 1; break;
        case IBL_BRDF_ALBEDO_AVG: job.need_avg = 1; break;
        case IBL_BRDF_SHEEN: job.need_sheen = 1; break;
        case IBL_BRDF_SHEEN_AVG: job.need_sheen_avg = 1; break;
        case IBL_BRDF_SHEEN_KHR: job.need_khr = 1; break;
        case IBL_BRDF_SHEEN_KHR_AVG: job.need_khr_avg = 1; break;
        case IBL_BRDF_ZERO:
        case IBL_BRDF_ONE: break;
        default:
            return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "brdf lut: unknown channel %d",
                            (int)job.channels[c]);
        }
    }
    for (int c = job.nchannels; c < 4; c++)
        if (d.channels[c] != IBL_BRDF_NONE && d.channels[0] != IBL_BRDF_NONE)
            return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                            "brdf lut: channel %d follows an empty channel", c);
    make_rules(d.order, &job.R);
    ibl_status st = ibl__progress(ctx, "brdf lut", 0.0);
    if (st != IBL_OK) return st;
    st = ibl_image_alloc(ctx, d.size, d.size, out);
    if (st != IBL_OK) return st;
    job.out = out;
    ibl_parallel_for(ctx, d.size, lut_row, &job);
    st = ibl__progress(ctx, "brdf lut", 1.0);
    if (st != IBL_OK) {
        ibl_image_free(ctx, out);
        return st;
    }
    return IBL_OK;
}
