/* The tri-Ace AmbientBRDF (tri-Ace 2010 "Decompose integral", "Implement Ambient BRDF",
 * "AmbientBRDF texture usage"): the directional albedo of the talk's normalised Blinn-Phong
 * specular term over (n.v, shininess, F0), by the quadrature of brdf_common.c. The table is
 * the albedo of the whole term, (n.h)^s included; the prefiltered map it multiplies is
 * normalised by its lobe weights (docs/BRDF.md explains why the literal reading fails). */
#include "ibl/brdf.h"
#include "core/context_internal.h"
#include "core/numeric.h"
#include "core/defaults.h"

#include <math.h>
#include <string.h>

#include "bake/brdf_common.h"


double ibl_blinn_normalization_factor(ibl_blinn_normalization normalization, double s)
{
    if (normalization == IBL_BLINN_EXACT)
        /* Gotanda 2010: makes the F = 1 albedo exactly 1 at n.v = 1 (derived in docs/BRDF.md). */
        return (s + 2.0) * (s + 4.0) / (8.0 * IBL_PI * (exp2(-0.5 * s) + s));
    /* tri-Ace 2010 "Equations": the linear fit. */
    return 0.0397436 * s + 0.0856832;
}

typedef struct ambient_plan {
    ibl_ambient_brdf_desc d;
    ibl__quadrature q;
} ambient_plan;

static ibl__lobe_params blinn(double s, ibl_blinn_normalization n)
{
    ibl__lobe_params p;
    memset(&p, 0, sizeof p);
    p.lobe = IBL__LOBE_BLINN;
    p.shininess = s;
    p.norm = ibl_blinn_normalization_factor(n, s);
    return p;
}

static double clamp_mu(double mu)
{
    if (!(mu > 1e-7)) return 1e-7;
    return mu > 1.0 ? 1.0 : mu;
}

double ibl_ambient_brdf(double nv, double shininess, double f0,
                        ibl_blinn_normalization normalization, int order)
{
    ibl__quadrature q;
    ibl__quadrature_init(&q, order);
    if (!(shininess > 0)) shininess = 1e-6;
    ibl__lobe_params p = blinn(shininess, normalization);
    double out;
    ibl__albedo_f0(&p, clamp_mu(nv), &q, &f0, 1, &out);
    return out;
}

/* The desc with every zero field at its documented default. */
static ibl_ambient_brdf_desc resolve_desc(const ibl_ambient_brdf_desc *in)
{
    ibl_ambient_brdf_desc d;
    memset(&d, 0, sizeof d);
    if (in) d = *in;
    if (d.size_nv == 0) d.size_nv = 32;
    if (d.size_shininess == 0) d.size_shininess = IBL_DEFAULT_AMBIENT_ROWS;
    if (d.size_f0 == 0) d.size_f0 = 16;
    if (d.shininess_min == 0) d.shininess_min = IBL_DEFAULT_AMBIENT_TABLE_MIN;
    if (d.shininess_max == 0) d.shininess_max = IBL_DEFAULT_AMBIENT_TABLE_MAX;
    return d;
}

double ibl_ambient_brdf_row_shininess(const ibl_ambient_brdf_desc *desc, int j)
{
    ibl_ambient_brdf_desc d = resolve_desc(desc);
    double lo = d.shininess_min, hi = d.shininess_max;
    double v = (j + 0.5) / d.size_shininess;
    if (d.spacing == IBL_SHININESS_LINEAR) return lo + (hi - lo) * v;
    return lo * exp(log(hi / lo) * v);
}

static ibl_status check_desc(ibl_context *ctx, const ibl_ambient_brdf_desc *in,
                             ibl_ambient_brdf_desc *d)
{
    *d = resolve_desc(in);
    if (d->size_nv < 1 || d->size_nv > 4096 || d->size_shininess < 1 ||
        d->size_shininess > 4096 || d->size_f0 < 1 || d->size_f0 > 1024)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                        "ambient brdf: sizes %d x %d x %d out of range (1..4096, F0 1..1024)",
                        d->size_nv, d->size_shininess, d->size_f0);
    if (!(d->shininess_min > 0) || !(d->shininess_max > d->shininess_min) ||
        !(d->shininess_max <= 1e6))
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                        "ambient brdf: shininess range %g:%g must have 0 < min < max <= 1e6",
                        d->shininess_min, d->shininess_max);
    if (d->spacing != IBL_SHININESS_LOG && d->spacing != IBL_SHININESS_LINEAR)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "ambient brdf: unknown spacing %d",
                        (int)d->spacing);
    if (d->normalization != IBL_BLINN_TRIACE_FIT && d->normalization != IBL_BLINN_EXACT)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "ambient brdf: unknown normalization %d",
                        (int)d->normalization);
    if (d->order < 0 || d->order > IBL__GL_MAX)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "ambient brdf: order %d is not in 0..%d",
                        d->order, (int)IBL__GL_MAX);
    return IBL_OK;
}

typedef struct volume_job {
    ambient_plan plan;
    ibl_texture *tex;
    ibl_image *img;
} volume_job;

/* One shininess row per task (fixed chunks: bit-identical at any thread count). Every F0
 * slice is accumulated from the full Schlick factor at each node, not from the 2D form. */
static void volume_row(void *arg, int j)
{
    const volume_job *job = arg;
    const ibl_ambient_brdf_desc *d = &job->plan.d;
    int w = d->size_nv, h = d->size_shininess, depth = d->size_f0;
    ibl__lobe_params p = blinn(ibl_ambient_brdf_row_shininess(d, j), d->normalization);
    double f0[1024], val[1024];
    for (int k = 0; k < depth; k++) f0[k] = (k + 0.5) / depth;
    for (int i = 0; i < w; i++) {
        ibl__albedo_f0(&p, (i + 0.5) / w, &job->plan.q, f0, depth, val);
        for (int k = 0; k < depth; k++) {
            float *px = job->tex->data + (((size_t)k * h + j) * w + i) * 4u;
            px[0] = (float)val[k];
            px[1] = (float)(1.0 - f0[k]);
            px[2] = 0;
            px[3] = 1;
        }
    }
}

static void table_row(void *arg, int j)
{
    const volume_job *job = arg;
    const ibl_ambient_brdf_desc *d = &job->plan.d;
    ibl__lobe_params p = blinn(ibl_ambient_brdf_row_shininess(d, j), d->normalization);
    for (int i = 0; i < d->size_nv; i++) {
        double m[2];
        ibl__albedo_moments(&p, (i + 0.5) / d->size_nv, &job->plan.q, m);
        float *px = ibl_image_texel(job->img, i, j);
        px[0] = (float)m[0];
        px[1] = (float)m[1];
        px[2] = 0;
        px[3] = 1;
    }
}

/* The part both table shapes share: the checked descriptor, the quadrature, the first
 * progress report. */
static ibl_status job_init(ibl_context *ctx, const ibl_ambient_brdf_desc *desc, volume_job *job)
{
    memset(job, 0, sizeof *job);
    ibl_status st = check_desc(ctx, desc, &job->plan.d);
    if (st != IBL_OK) return st;
    ibl__quadrature_init(&job->plan.q, job->plan.d.order);
    return ibl__progress(ctx, "ambient brdf", 0.0);
}

ibl_status ibl_ambient_brdf_volume(ibl_context *ctx, const ibl_ambient_brdf_desc *desc,
                                   ibl_texture *out)
{
    if (!out) return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "ambient brdf: no output texture");
    memset(out, 0, sizeof *out);
    volume_job job;
    ibl_status st = job_init(ctx, desc, &job);
    if (st != IBL_OK) return st;
    st = ibl_texture_alloc(ctx, IBL_TEXTURE_3D, job.plan.d.size_nv, job.plan.d.size_shininess,
                           job.plan.d.size_f0, 1, out);
    if (st != IBL_OK) return st;
    job.tex = out;
    ibl_parallel_for(ctx, job.plan.d.size_shininess, volume_row, &job);
    st = ibl__progress(ctx, "ambient brdf", 1.0);
    if (st != IBL_OK) ibl_texture_free(ctx, out);
    return st;
}

ibl_status ibl_ambient_brdf_table(ibl_context *ctx, const ibl_ambient_brdf_desc *desc,
                                  ibl_image *out)
{
    if (!out) return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "ambient brdf: no output image");
    memset(out, 0, sizeof *out);
    volume_job job;
    ibl_status st = job_init(ctx, desc, &job);
    if (st != IBL_OK) return st;
    st = ibl_image_alloc(ctx, job.plan.d.size_nv, job.plan.d.size_shininess, out);
    if (st != IBL_OK) return st;
    job.img = out;
    ibl_parallel_for(ctx, job.plan.d.size_shininess, table_row, &job);
    st = ibl__progress(ctx, "ambient brdf", 1.0);
    if (st != IBL_OK) ibl_image_free(ctx, out);
    return st;
}
