/* Irradiance environment maps: direct convolution of a reduced cube with exact texel solid
 * angles (tri-Ace 2010, "Generate IEM (2)"), the full-resolution double reference and the SH
 * method. Normalisation and measured errors: docs/DIFFUSE.md. */
#include "ibl/irradiance.h"
#include "core/context_internal.h"
#include "core/numeric.h"

#include "ibl/cubemap.h"

#include <math.h>
#include <string.h>


enum { MAX_IEM_SIZE = 64 };

/* Unit centre direction of every texel of a cube of edge n, face-major (6 n^2 x 3 doubles),
 * and the exact solid angle of every texel of one face (n^2). */
static void texel_tables(int n, double *dirs, double *omega)
{
    for (int y = 0; y < n; y++)
        for (int x = 0; x < n; x++) omega[(size_t)y * n + x] = ibl_cube_texel_solid_angle(n, x, y);
    for (int f = 0; f < 6; f++) {
        for (int y = 0; y < n; y++) {
            for (int x = 0; x < n; x++) {
                double *d = dirs + (((size_t)f * n + y) * n + x) * 3;
                ibl_cube_direction_d(f, (x + 0.5) / n, (y + 0.5) / n, d);
                double len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
                d[0] /= len;
                d[1] /= len;
                d[2] /= len;
            }
        }
    }
}

/* ---- the plan ------------------------------------------------------------------------------- */

struct ibl_irradiance_plan {
    ibl_context *ctx;
    int src_n, dst_n;
    uint32_t *offset; /* 6 dst_n^2 + 1 */
    uint16_t *index;  /* source texel of each tap */
    float *weight;    /* normalised weight of each tap */
    size_t taps;
};

ibl_status ibl_irradiance_plan_create(ibl_context *ctx, const ibl_irradiance_plan_desc *desc,
                                      ibl_irradiance_plan **out)
{
    if (!out || !desc) return IBL_ERR_INVALID_ARGUMENT;
    *out = NULL;
    int source_size = desc->source_size, size = desc->size;
    ibl_irradiance_scale scale = desc->scale;
    if (source_size < 1 || source_size > MAX_IEM_SIZE || size < 1 || size > MAX_IEM_SIZE)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                        "irradiance: sizes %d -> %d out of range 1..%d", source_size, size,
                        MAX_IEM_SIZE);
    ibl_irradiance_plan *p = ibl_calloc(ctx, 1, sizeof *p);
    if (!p) return ibl_context_status(ctx);
    p->ctx = ctx;
    p->src_n = source_size;
    p->dst_n = size;
    size_t ns = 6 * (size_t)source_size * source_size, nd = 6 * (size_t)size * size;
    double *sdir = ibl_alloc(ctx, ns * 3 * sizeof(double));
    double *ddir = ibl_alloc(ctx, nd * 3 * sizeof(double));
    double *somega = ibl_alloc(ctx, (size_t)source_size * source_size * sizeof(double));
    double *domega = ibl_alloc(ctx, (size_t)size * size * sizeof(double));
    double *row = ibl_alloc(ctx, ns * sizeof(double));
    p->offset = ibl_alloc(ctx, (nd + 1) * sizeof(uint32_t));
    ibl_status st = IBL_OK;
    if (!sdir || !ddir || !somega || !domega || !row || !p->offset) {
        st = ibl_context_status(ctx);
        goto done;
    }
    texel_tables(source_size, sdir, somega);
    texel_tables(size, ddir, domega);
    /* first pass: count the taps with a positive cosine */
    size_t taps = 0;
    for (size_t i = 0; i < nd; i++) {
        p->offset[i] = (uint32_t)taps;
        const double *n = ddir + 3 * i;
        for (size_t j = 0; j < ns; j++) {
            const double *w = sdir + 3 * j;
            if (n[0] * w[0] + n[1] * w[1] + n[2] * w[2] > 0) taps++;
        }
        if (taps > UINT32_MAX) {
            st = ibl__fail(ctx, IBL_ERR_TOO_LARGE, "irradiance: plan too large");
            goto done;
        }
    }
    p->offset[nd] = (uint32_t)taps;
    p->taps = taps;
    p->index = ibl_alloc(ctx, (taps ? taps : 1) * sizeof(uint16_t));
    p->weight = ibl_alloc(ctx, (taps ? taps : 1) * sizeof(float));
    if (!p->index || !p->weight) {
        st = ibl_context_status(ctx);
        goto done;
    }
    /* second pass: weights dOmega * cos, normalised so each output texel's weights sum to 1
     * (the tri-Ace talk stores this normalising coefficient in its texture): a constant
     * environment stays exactly constant, and the discretisation error of the cosine lobe's
     * integral, which should be pi, does not show up as a brightness error */
    double target = scale == IBL_IRRADIANCE_SCALE_FULL ? IBL_PI : 1.0;
    for (size_t i = 0; i < nd; i++) {
        const double *n = ddir + 3 * i;
        double sum = 0;
        size_t k = p->offset[i];
        for (size_t j = 0; j < ns; j++) {
            const double *w = sdir + 3 * j;
            double c = n[0] * w[0] + n[1] * w[1] + n[2] * w[2];
            if (c > 0) {
                size_t in_face = j % ((size_t)source_size * source_size);
                row[k - p->offset[i]] = c * somega[in_face];
                sum += row[k - p->offset[i]];
                p->index[k++] = (uint16_t)j;
            }
        }
        for (size_t e = p->offset[i]; e < p->offset[i + 1]; e++)
            p->weight[e] = (float)(row[e - p->offset[i]] * target / sum);
    }
done:
    ibl_free(ctx, sdir);
    ibl_free(ctx, ddir);
    ibl_free(ctx, somega);
    ibl_free(ctx, domega);
    ibl_free(ctx, row);
    if (st != IBL_OK) {
        ibl_irradiance_plan_destroy(p);
        return st;
    }
    *out = p;
    return IBL_OK;
}

void ibl_irradiance_plan_destroy(ibl_irradiance_plan *p)
{
    if (!p) return;
    ibl_free(p->ctx, p->offset);
    ibl_free(p->ctx, p->index);
    ibl_free(p->ctx, p->weight);
    ibl_free(p->ctx, p);
}

size_t ibl_irradiance_plan_taps(const ibl_irradiance_plan *p) { return p ? p->taps : 0; }

/* Four partial sums per output texel (taps e = 4k, 4k+1, 4k+2, 4k+3), added as
 * (s0 + s1) + (s2 + s3): four independent dependency chains instead of one, and the same
 * order on every path (the SSE2 version does the same per-channel operations as the portable
 * one, four channels at a time). */
#if defined(__SSE2__)
#include <emmintrin.h>
static void convolve(const ibl_irradiance_plan *p, const float *src, float *dst)
{
    size_t nd = 6 * (size_t)p->dst_n * p->dst_n;
    for (size_t i = 0; i < nd; i++) {
        __m128 a[4] = {_mm_setzero_ps(), _mm_setzero_ps(), _mm_setzero_ps(), _mm_setzero_ps()};
        uint32_t e = p->offset[i], end = p->offset[i + 1];
        for (; e + 4 <= end; e += 4)
            for (int k = 0; k < 4; k++)
                a[k] = _mm_add_ps(a[k], _mm_mul_ps(_mm_set1_ps(p->weight[e + k]),
                                                   _mm_loadu_ps(src + (size_t)p->index[e + k] * 4)));
        for (int k = 0; e < end; e++, k++)
            a[k] = _mm_add_ps(a[k], _mm_mul_ps(_mm_set1_ps(p->weight[e]),
                                               _mm_loadu_ps(src + (size_t)p->index[e] * 4)));
        __m128 sum = _mm_add_ps(_mm_add_ps(a[0], a[1]), _mm_add_ps(a[2], a[3]));
        float out[4];
        _mm_storeu_ps(out, sum);
        out[3] = 1.0f;
        memcpy(dst + i * 4, out, sizeof out);
    }
}
#else
static void convolve(const ibl_irradiance_plan *p, const float *src, float *dst)
{
    size_t nd = 6 * (size_t)p->dst_n * p->dst_n;
    for (size_t i = 0; i < nd; i++) {
        float a[4][3] = {{0}};
        uint32_t e = p->offset[i], end = p->offset[i + 1];
        for (; e + 4 <= end; e += 4)
            for (int k = 0; k < 4; k++)
                for (int c = 0; c < 3; c++)
                    a[k][c] += p->weight[e + k] * src[(size_t)p->index[e + k] * 4 + c];
        for (int k = 0; e < end; e++, k++)
            for (int c = 0; c < 3; c++) a[k][c] += p->weight[e] * src[(size_t)p->index[e] * 4 + c];
        float *o = dst + i * 4;
        for (int c = 0; c < 3; c++) o[c] = (a[0][c] + a[1][c]) + (a[2][c] + a[3][c]);
        o[3] = 1.0f;
    }
}
#endif

ibl_status ibl_irradiance_plan_run(const ibl_irradiance_plan *p, const ibl_cubemap *src,
                                   ibl_cubemap *dst)
{
    if (!p || !src || !dst || !src->data || !dst->data) return IBL_ERR_INVALID_ARGUMENT;
    if (src->size != p->src_n || dst->size != p->dst_n)
        return ibl__fail(p->ctx, IBL_ERR_INVALID_ARGUMENT,
                         "irradiance: the plan is for %d -> %d texels, not %d -> %d", p->src_n,
                         p->dst_n, src->size, dst->size);
    convolve(p, src->data, dst->data);
    return IBL_OK;
}

/* ---- reduction -------------------------------------------------------------------------------- */

/* Level 0 of src reduced area-correctly to a new cube of edge size (ibl_cubemap_resample). */
static ibl_status reduce(ibl_context *ctx, const ibl_cubemap *src, int size, ibl_cubemap *out)
{
    if (!src || !src->data || !out || size < 1)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "irradiance: bad source or size %d", size);
    ibl_status st = ibl_cubemap_alloc(ctx, size, 1, out);
    if (st == IBL_OK) st = ibl_cubemap_resample(ctx, src, out);
    if (st != IBL_OK) ibl_cubemap_free(ctx, out);
    return st;
}

/* ---- reference ----------------------------------------------------------------------------------- */

typedef struct reference_job {
    const ibl_cubemap *src;
    const double *canon; /* per face texel: a = sc/r, b = tc/r, c = 1/r, omega */
    const double *ddir;  /* output texel directions */
    ibl_cubemap *dst;
    double target;
    int face; /* the face being written */
} reference_job;

/* Face frames of cubemap.h: direction = major + sc s_axis + tc t_axis. */
static const double face_frame[6][3][3] = {
    {{0, 0, -1}, {0, -1, 0}, {1, 0, 0}},  {{0, 0, 1}, {0, -1, 0}, {-1, 0, 0}},
    {{1, 0, 0}, {0, 0, 1}, {0, 1, 0}},    {{1, 0, 0}, {0, 0, -1}, {0, -1, 0}},
    {{1, 0, 0}, {0, -1, 0}, {0, 0, 1}},   {{-1, 0, 0}, {0, -1, 0}, {0, 0, -1}},
};

static void reference_task(void *arg, int index)
{
    const reference_job *job = arg;
    int n = job->src->size, m = job->dst->size;
    size_t nn = (size_t)n * n;
    int face = job->face, y = index;
    for (int x = 0; x < m; x++) {
        const double *nrm = job->ddir + (((size_t)face * m + y) * m + x) * 3;
        double acc[3] = {0, 0, 0}, sum = 0;
        for (int f = 0; f < 6; f++) {
            double ps = 0, pt = 0, pm = 0;
            for (int i = 0; i < 3; i++) {
                ps += nrm[i] * face_frame[f][0][i];
                pt += nrm[i] * face_frame[f][1][i];
                pm += nrm[i] * face_frame[f][2][i];
            }
            const float *px = ibl_cubemap_face(job->src, 0, f);
            for (size_t j = 0; j < nn; j++) {
                const double *c = job->canon + 4 * j;
                double cosine = c[0] * ps + c[1] * pt + c[2] * pm;
                if (cosine <= 0) continue;
                double w = cosine * c[3];
                acc[0] += w * px[4 * j];
                acc[1] += w * px[4 * j + 1];
                acc[2] += w * px[4 * j + 2];
                sum += w;
            }
        }
        float *o = ibl_cubemap_face(job->dst, 0, face) + ((size_t)y * m + x) * 4;
        for (int c = 0; c < 3; c++) o[c] = (float)(acc[c] * job->target / sum);
        o[3] = 1.0f;
    }
}

static ibl_status reference_iem(ibl_context *ctx, const ibl_cubemap *src, int size, double target,
                                ibl_cubemap *out)
{
    int n = src->size;
    size_t nn = (size_t)n * n;
    double *canon = ibl_alloc(ctx, nn * 4 * sizeof(double));
    double *ddir = ibl_alloc(ctx, 6 * (size_t)size * size * 3 * sizeof(double));
    double *domega = ibl_alloc(ctx, (size_t)size * size * sizeof(double));
    ibl_status st = IBL_OK;
    if (!canon || !ddir || !domega) {
        st = ibl_context_status(ctx);
        goto done;
    }
    for (int y = 0; y < n; y++) {
        for (int x = 0; x < n; x++) {
            double sc = (2.0 * x + 1.0) / n - 1.0, tc = (2.0 * y + 1.0) / n - 1.0;
            double inv_r = 1.0 / sqrt(1.0 + sc * sc + tc * tc);
            double *c = canon + ((size_t)y * n + x) * 4;
            c[0] = sc * inv_r;
            c[1] = tc * inv_r;
            c[2] = inv_r;
            c[3] = ibl_cube_texel_solid_angle(n, x, y);
        }
    }
    texel_tables(size, ddir, domega);
    st = ibl_cubemap_alloc(ctx, size, 1, out);
    if (st != IBL_OK) goto done;
    reference_job job = {src, canon, ddir, out, target, 0};
    /* one face at a time so that a long run reports progress and can be cancelled */
    for (int f = 0; f < 6 && st == IBL_OK; f++) {
        job.face = f;
        ibl_parallel_for(ctx, size, reference_task, &job);
        st = ibl__progress(ctx, "irradiance reference", (f + 1) / 6.0);
    }
    if (st != IBL_OK) ibl_cubemap_free(ctx, out);
done:
    ibl_free(ctx, canon);
    ibl_free(ctx, ddir);
    ibl_free(ctx, domega);
    return st;
}

/* ---- SH method ------------------------------------------------------------------------------- */

static ibl_status sh_iem(ibl_context *ctx, const ibl_cubemap *src, const ibl_irradiance_desc *d,
                         double target, ibl_cubemap *out)
{
    ibl_sh sh;
    ibl_status st = ibl_sh_project_cubemap(ctx, src, 0, d->sh_bands, &sh);
    if (st != IBL_OK) return st;
    if (d->sh_window != IBL_SH_WINDOW_NONE) {
        st = ibl_sh_apply_window(&sh, d->sh_window, d->sh_window_width, NULL);
        if (st != IBL_OK) return ibl__fail(ctx, st, "irradiance: bad SH window");
    }
    ibl_sh e;
    ibl_sh_radiance_to_irradiance(&sh, &e);
    ibl_sh_scale(&e, target / IBL_PI);
    int m = d->size;
    st = ibl_cubemap_alloc(ctx, m, 1, out);
    if (st != IBL_OK) return st;
    for (int f = 0; f < 6; f++) {
        float *o = ibl_cubemap_face(out, 0, f);
        for (int y = 0; y < m; y++) {
            for (int x = 0; x < m; x++, o += 4) {
                double dir[3], v[3];
                ibl_cube_direction_d(f, (x + 0.5) / m, (y + 0.5) / m, dir);
                double len = sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
                for (int i = 0; i < 3; i++) dir[i] /= len;
                ibl_sh_eval(&e, dir, v);
                for (int c = 0; c < 3; c++) o[c] = (float)v[c];
                o[3] = 1.0f;
            }
        }
    }
    return IBL_OK;
}

/* ---- entry point ------------------------------------------------------------------------------- */

ibl_status ibl_irradiance_cubemap(ibl_context *ctx, const ibl_cubemap *src,
                                  const ibl_irradiance_desc *desc, ibl_cubemap *out)
{
    if (!src || !src->data || !out)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "irradiance: no source cubemap");
    memset(out, 0, sizeof *out);
    ibl_irradiance_desc d;
    if (desc) d = *desc;
    else memset(&d, 0, sizeof d);
    if (d.size == 0) d.size = 16;
    if (d.source_size == 0) d.source_size = 8;
    if (d.sh_bands == 0) d.sh_bands = 3;
    if (d.size < 1 || d.size > MAX_IEM_SIZE || d.source_size < 1 || d.source_size > MAX_IEM_SIZE)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                        "irradiance: size %d / source size %d out of range 1..%d", d.size,
                        d.source_size, MAX_IEM_SIZE);
    if (d.sh_bands < 1 || d.sh_bands > IBL_SH_MAX_BANDS)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "irradiance: SH bands %d out of range 1..5",
                        d.sh_bands);
    double target = d.scale == IBL_IRRADIANCE_SCALE_FULL ? IBL_PI : 1.0;
    switch (d.method) {
    case IBL_IRRADIANCE_REFERENCE: return reference_iem(ctx, src, d.size, target, out);
    case IBL_IRRADIANCE_SH: return sh_iem(ctx, src, &d, target, out);
    case IBL_IRRADIANCE_CONVOLVE: break;
    default: return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "irradiance: unknown method");
    }
    ibl_cubemap small;
    ibl_status st = reduce(ctx, src, d.source_size, &small);
    if (st != IBL_OK) return st;
    ibl_irradiance_plan *plan;
    ibl_irradiance_plan_desc pd = {.source_size = d.source_size, .size = d.size, .scale = d.scale};
    st = ibl_irradiance_plan_create(ctx, &pd, &plan);
    if (st == IBL_OK) {
        st = ibl_cubemap_alloc(ctx, d.size, 1, out);
        if (st == IBL_OK) st = ibl_irradiance_plan_run(plan, &small, out);
        ibl_irradiance_plan_destroy(plan);
    }
    ibl_cubemap_free(ctx, &small);
    return st;
}
