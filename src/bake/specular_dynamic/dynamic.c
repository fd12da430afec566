/* The dynamic (per-frame) plan: tri-Ace 2010's dynamic configurations ("Implemented
 * configurations": box 16x16x6 1-500, Gaussian 32x32x6 1-1000, Phong 16x16x6 1-250 and
 * 32x32x6 1-1000, each refiltered every frame from a freshly rendered cube, with its edge
 * fixup) as a plan whose run allocates nothing and costs the same every frame.
 *
 * Create: the engine by filter (box and gauss: the chain and its blur tables, box_chain.c;
 * phong, blinn, ggx: the source's box pyramid and one symmetric lobe operator per level,
 * lobe_rows.c), the edge fixup's groups per level (fixup_tables.c), and the weights of the SH
 * projection of the 8x8x6 box mip (below).
 * Run:    box pyramid or chain -> per level: the level (copy, blur, or row products; a mirror
 *         level is the box level of its size) -> its edge fixup -> the SH mip kept.
 * Export: the lobe engine's rows expanded to all six faces as CSR arrays
 *         (ibl_specular_plan_rows_info / _fill, at the end), what shaders/ibl_dynamic_phong.comp
 *         runs on the GPU.
 *
 * The diffuse SH. The talk computes the SH coefficients "from 6 texels at the center in each
 * face" of the small cube ("Optimize diffuse term"); ibl_sh_project_face_means does exactly
 * that from a 1x1 level. The plan offers more for the same price: the projection of the 8x8x6
 * area mean of the source with weights W_T = sum over the source texels t in T of
 * Omega_t Y(c_t), i.e. the exact projection (ibl_sh_project_cubemap) of the source with its
 * radiance replaced by its mean over each 8x8 block: the error is
 * sum_T sum_t Omega_t (L_t - mean_T L)(Y(c_t) - mean_T Y), second order in the block size
 * (the tests check it against that bound). */
#include "bake/specular_dynamic/dynamic_internal.h"
#include "bake/specular/fast_internal.h"
#include "core/context_internal.h"
#include "ibl/sh.h"

#include <math.h>
#include <string.h>

enum { ENGINE_BOX, ENGINE_GAUSS, ENGINE_LOBE };
enum { SH_EDGE = 8, SH_COEFFS = IBL_SH_MAX_COEFFS };

struct ibl__dynamic {
    ibl_context *ctx;
    ibl_specular_desc desc;
    ibl_specular_info info;
    int engine, S, N, L;
    dyn_box_chain chain;  /* box, gauss: the chain of edge N; lobe: the source's pyramid */
    int chain_levels;
    dyn_symmetries sym;
    dyn_lobe_level lobe[IBL_MAX_LEVELS]; /* lobe engine, filtered levels                   */
    int source_mip[IBL_MAX_LEVELS];      /* lobe engine: the pyramid level a level reads    */
    float *planar[IBL_MAX_LEVELS];       /* per pyramid level read by a lobe level           */
    float *planar_memory[IBL_MAX_LEVELS];
    dyn_row_product_fn product;
    dyn_fixup fixup[IBL_MAX_LEVELS];
    int sh_level, sh_edge;
    double *sh_weights; /* SH_COEFFS per texel of the SH mip (6 E E)                   */
    float *sh_texels;   /* the SH mip of the last run (RGBA)                           */
    int has_run;
    dyn_lobe_stats stats;
};

static int log2_int(int v)
{
    int l = 0;
    while ((1 << (l + 1)) <= v) l++;
    return l;
}

void ibl__dynamic_destroy(ibl__dynamic *d)
{
    if (!d) return;
    ibl_context *ctx = d->ctx;
    ibl__dyn_box_chain_destroy(ctx, &d->chain);
    for (int l = 0; l < IBL_MAX_LEVELS; l++) {
        ibl__dyn_lobe_level_destroy(ctx, &d->lobe[l]);
        ibl_free(ctx, d->planar_memory[l]);
        ibl__dyn_fixup_destroy(ctx, &d->fixup[l]);
    }
    ibl_free(ctx, d->sh_weights);
    ibl_free(ctx, d->sh_texels);
    ibl_free(ctx, d);
}

/* W_T = sum over the source texels t of T of Omega_t Y(c_t), Y the 25 functions of 5 bands. */
static ibl_status sh_tables(ibl__dynamic *d)
{
    int E = d->sh_edge, S = d->S, r = S / E;
    size_t texels = (size_t)6 * E * E;
    d->sh_weights = ibl_calloc(d->ctx, texels * SH_COEFFS, sizeof(double));
    d->sh_texels = ibl_calloc(d->ctx, texels * 4, sizeof(float));
    if (!d->sh_weights || !d->sh_texels) return ibl_context_status(d->ctx);
    for (int f = 0; f < 6; f++)
        for (int y = 0; y < S; y++)
            for (int x = 0; x < S; x++) {
                double c[3], basis[SH_COEFFS];
                ibl_cube_direction_d(f, (x + 0.5) / S, (y + 0.5) / S, c);
                double len = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
                for (int i = 0; i < 3; i++) c[i] /= len;
                ibl_sh_eval_basis(IBL_SH_MAX_BANDS, c, basis);
                double omega = ibl_cube_texel_solid_angle(S, x, y);
                double *w = d->sh_weights + (((size_t)f * E + y / r) * E + x / r) * SH_COEFFS;
                for (int k = 0; k < SH_COEFFS; k++) w[k] += omega * basis[k];
            }
    return IBL_OK;
}

/* The lobe engine: which pyramid level each level reads, its operator, the planar buffers. */
static ibl_status lobe_plan(ibl__dynamic *d)
{
    ibl_context *ctx = d->ctx;
    int mips = ibl_full_mip_count(d->S);
    ibl__dyn_symmetries(&d->sym);
    for (int l = 0; l < d->L; l++) {
        ibl__lobe lobe = ibl__lobe_for_level(&d->info, l);
        int n = ibl_level_size(d->N, l);
        if (lobe.kind == IBL__LOBE_MIRROR) {
            /* the unfiltered source: the box level of the same edge */
            d->source_mip[l] = log2_int(d->S / n);
            continue;
        }
        /* the coarsest mip with texels at most 0.8 of the lobe's half width (scaled by
         * desc.accuracy as in the static method) and at least 16 wide (wide lobes are cheap;
         * coarse texels at their horizon kink are not exact) */
        double ratio = 0.8 * (d->desc.accuracy > 0 ? d->desc.accuracy / 0.35 : 1.0);
        int mip = 0;
        for (int m = 0; m < mips; m++)
            if (2.0 / (d->S >> m) <= ratio * lobe.half_angle && (d->S >> m) >= 16) mip = m;
        d->source_mip[l] = mip;
        /* the lobe below 1e-4 of its peak is dropped (the row is renormalised): a Phong lobe
         * falls like a Gaussian; GGX's tail (1 / angle^4) still holds ~1% of its weight there */
        double floor_value = lobe.kind == IBL__LOBE_GGX ? 1e-8 : 1e-4;
        ibl_status st = ibl__dyn_lobe_level_create(ctx, &d->desc, &lobe, &d->sym, n, mip, d->S >> mip,
                                                   floor_value, &d->lobe[l], &d->stats);
        if (st != IBL_OK) return st;
        if (!d->planar[mip]) {
            int M = d->S >> mip;
            /* 32-byte aligned (the chunks are aligned to eight floats) */
            d->planar_memory[mip] = ibl_calloc(ctx, (size_t)36 * M * M + 2 * DYN_GUARD + 8, sizeof(float));
            if (!d->planar_memory[mip]) return ibl_context_status(ctx);
            uintptr_t a = (uintptr_t)d->planar_memory[mip];
            d->planar[mip] = d->planar_memory[mip] + ((32 - a % 32) % 32) / sizeof(float);
        }
    }
    for (int l = 0; l < d->L; l++)
        if (d->source_mip[l] + 1 > d->chain_levels) d->chain_levels = d->source_mip[l] + 1;
#if IBL_HAVE_X86_KERNELS
    d->product = ibl__cpu_has(ctx, IBL__CPU_AVX2_FMA) ? ibl__dyn_row_product_avx2
                                                      : ibl__dyn_row_product_portable;
#else
    d->product = ibl__dyn_row_product_portable;
#endif
    return IBL_OK;
}

ibl_status ibl__dynamic_create(ibl_context *ctx, const ibl_specular_desc *desc,
                               const ibl_specular_info *info, int source_size, ibl__dynamic **out)
{
    *out = NULL;
    int N = info->size, S = source_size;
    int box = desc->filter == IBL_FILTER_BOX || desc->filter == IBL_FILTER_GAUSS;
    if (N > S || (N & (N - 1)) != 0)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                         "specular plan: a dynamic plan needs an output edge that is a power of two "
                         "no larger than the source's (%d from %d)", N, S);
    if (box && desc->edge_fixup != IBL_EDGE_FIXUP_NONE && desc->edge_fixup != IBL_EDGE_FIXUP_OVERLAP &&
        desc->edge_fixup != IBL_EDGE_FIXUP_OVERLAP2)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                         "specular plan: the %s chain takes no %s fixup (its texels have no "
                         "direction to bend; use overlap or overlap2)",
                         ibl_specular_filter_name(desc->filter), ibl_edge_fixup_name(desc->edge_fixup));
    ibl__dynamic *d = ibl_calloc(ctx, 1, sizeof *d);
    if (!d) return ibl_context_status(ctx);
    d->ctx = ctx;
    d->desc = *desc;
    d->info = *info;
    d->S = S, d->N = N, d->L = info->levels;
    d->engine = desc->filter == IBL_FILTER_BOX ? ENGINE_BOX : desc->filter == IBL_FILTER_GAUSS ? ENGINE_GAUSS : ENGINE_LOBE;
    int chain_edge = box ? N : S;
    d->sh_edge = chain_edge < SH_EDGE ? chain_edge : SH_EDGE;
    d->sh_level = log2_int(chain_edge / d->sh_edge);
    d->chain_levels = box ? d->L : 1;
    if (d->sh_level + 1 > d->chain_levels) d->chain_levels = d->sh_level + 1;
    ibl_status st = IBL_OK;
    if (d->engine == ENGINE_LOBE) st = lobe_plan(d);
    if (st == IBL_OK) {
        float blur[IBL_MAX_LEVELS];
        for (int l = 0; l < IBL_MAX_LEVELS; l++) {
            /* the Phong kernel exponent of each level; none past the output's levels and on a
             * mirror level (infinite: sigma 0) */
            float e = l < d->L ? ibl_specular_level_phong_exponent(info, l) : 0.0f;
            blur[l] = e > 0 ? e : INFINITY;
        }
        st = ibl__dyn_box_chain_create(ctx, S, chain_edge, d->chain_levels,
                                       d->engine == ENGINE_GAUSS ? blur : NULL, &d->chain);
    }
    for (int l = 0; st == IBL_OK && l < d->L; l++)
        st = ibl__dyn_fixup_create(ctx, desc->edge_fixup, ibl_level_size(N, l), &d->fixup[l]);
    if (st == IBL_OK) st = sh_tables(d);
    if (st != IBL_OK) {
        ibl__dynamic_destroy(d);
        return st;
    }
    *out = d;
    return IBL_OK;
}

/* ---- the run ---- */

typedef struct run_job {
    ibl__dynamic *d;
    const ibl_cubemap *src;
    ibl_cubemap *dst;
    int level;
} run_job;

/* Pyramid level m as the products read it: R, G, B planes of the six faces, then the same
 * planes with every face transposed (T[x M + y] = F[y M + x]). One task per face. */
static void planar_task(void *arg, int face)
{
    const run_job *job = arg;
    ibl__dynamic *d = job->d;
    int m = job->level, M = d->S >> m;
    size_t plane = (size_t)6 * M * M, base = (size_t)face * M * M;
    const float *src = ibl__dyn_box_chain_face(&d->chain, job->src, m, face);
    float *p = d->planar[m] + DYN_GUARD;
    for (int y = 0; y < M; y++)
        for (int x = 0; x < M; x++) {
            const float *t = src + ((size_t)y * M + x) * 4;
            size_t i = base + (size_t)y * M + x, j = base + (size_t)x * M + y;
            for (int c = 0; c < 3; c++) {
                p[c * plane + i] = t[c];
                p[(3 + c) * plane + j] = t[c];
            }
        }
}

/* One face row of a filtered level: every texel the product of its chunks. */
static void row_task(void *arg, int index)
{
    const run_job *job = arg;
    const ibl__dynamic *d = job->d;
    const dyn_lobe_level *lv = &d->lobe[job->level];
    int n = lv->edge, f = index / n, y = index % n, M = d->S >> lv->mip;
    const float *buffer = d->planar[lv->mip];
    size_t plane = (size_t)6 * M * M;
    float *out = ibl_cubemap_face(job->dst, job->level, f) + (size_t)y * n * 4;
    size_t i = ((size_t)f * n + y) * n;
    for (int x = 0; x < n; x++, i++) {
        uint32_t rep = lv->row_rep[i], first = lv->row_codes[i];
        size_t w = (size_t)lv->rep_chunks[rep] * DYN_CHUNK;
        float rgb[3];
        d->product(buffer, plane, lv->codes + first, (int)(lv->row_codes[i + 1] - first), lv->weights + w,
                   lv->reversed + w, rgb);
        out[4 * x + 0] = rgb[0], out[4 * x + 1] = rgb[1], out[4 * x + 2] = rgb[2], out[4 * x + 3] = 1.0f;
    }
}

static void run_lobe(ibl__dynamic *d, const ibl_cubemap *src, ibl_cubemap *dst)
{
    ibl_context *ctx = d->ctx;
    ibl__dyn_box_chain_build(&d->chain, ctx, src, d->chain_levels);
    for (int m = 0; m < d->chain_levels; m++) {
        if (!d->planar[m]) continue;
        run_job job = {d, src, dst, m};
        ibl_parallel_for(ctx, 6, planar_task, &job);
    }
    for (int l = 0; l < d->L; l++) {
        int n = ibl_level_size(d->N, l);
        if (d->lobe[l].edge == 0) {
            memcpy(ibl_cubemap_face(dst, l, 0), ibl__dyn_box_chain_face(&d->chain, src, d->source_mip[l], 0),
                   (size_t)6 * n * n * 4 * sizeof(float));
        } else {
            run_job job = {d, src, dst, l};
            ibl_parallel_for(ctx, 6 * n, row_task, &job);
        }
        ibl__dyn_fixup_apply(&d->fixup[l], ibl_cubemap_face(dst, l, 0));
    }
}

ibl_status ibl__dynamic_run(ibl__dynamic *d, const ibl_cubemap *src, ibl_cubemap *dst)
{
    if (d->engine == ENGINE_LOBE) {
        run_lobe(d, src, dst);
    } else {
        ibl__dyn_box_chain_build(&d->chain, d->ctx, src, d->chain_levels);
        for (int l = 0; l < d->L; l++) {
            ibl__dyn_box_chain_output(&d->chain, d->ctx, src, dst, l);
            ibl__dyn_fixup_apply(&d->fixup[l], ibl_cubemap_face(dst, l, 0));
        }
    }
    int E = d->sh_edge;
    memcpy(d->sh_texels, ibl__dyn_box_chain_face(&d->chain, src, d->sh_level, 0),
           (size_t)6 * E * E * 4 * sizeof(float));
    d->has_run = 1;
    return IBL_OK;
}

void ibl__dynamic_stats(const ibl__dynamic *d, size_t *taps, size_t *row_chunks)
{
    if (taps) *taps = d ? d->stats.taps : 0;
    if (row_chunks) *row_chunks = d ? d->stats.row_chunks : 0;
}

ibl_status ibl_specular_plan_sh(const ibl_specular_plan *plan, int bands, ibl_sh *out)
{
    if (!plan || !out) return IBL_ERR_INVALID_ARGUMENT;
    if (bands == 0) bands = 3;
    const ibl__dynamic *d = plan->dynamic;
    if (!d || !d->has_run || bands < 1 || bands > IBL_SH_MAX_BANDS)
        return ibl__fail(plan->ctx, IBL_ERR_INVALID_ARGUMENT,
                         "specular plan: %s", !d ? "the SH needs a dynamic plan"
                                              : !d->has_run ? "the SH needs a run first"
                                                            : "bands out of range 1..5");
    memset(out, 0, sizeof *out);
    out->bands = bands;
    int count = bands * bands, E = d->sh_edge;
    for (size_t t = 0; t < (size_t)6 * E * E; t++) {
        const double *w = d->sh_weights + t * SH_COEFFS;
        const float *p = d->sh_texels + t * 4;
        for (int k = 0; k < count; k++)
            for (int c = 0; c < 3; c++) out->c[k][c] += w[k] * p[c];
    }
    return IBL_OK;
}

/* ---- the lobe operator exported as CSR rows (ibl/specular.h) ---- */

/* The level's operator, or NULL (with the reason in the context) when there is none. */
static const ibl__dynamic *rows_plan(const ibl_specular_plan *plan, int level)
{
    if (!plan) return NULL;
    const ibl__dynamic *d = plan->dynamic;
    if (!d || d->engine != ENGINE_LOBE || level < 0 || level >= d->L) {
        ibl__fail(plan->ctx, IBL_ERR_INVALID_ARGUMENT, "specular plan: %s",
                  !d || d->engine != ENGINE_LOBE
                      ? "rows need a dynamic plan of the phong, blinn or ggx filter"
                      : "rows: level out of range");
        return NULL;
    }
    return d;
}

/* Texel index (face M + y) M + x of lane k of a chunk code, and whether the reversed weights
 * apply: the code's offset points into the planar buffer (dynamic_internal.h), the faces'
 * R plane or their transposed R plane. */
static uint32_t code_texel(uint32_t code, int k, int M)
{
    size_t plane = (size_t)6 * M * M, offset = (code >> 1) - DYN_GUARD;
    if (offset < plane) return (uint32_t)(offset + (size_t)k);
    size_t rest = offset - 3 * plane, face = rest / ((size_t)M * M);
    size_t p = rest % ((size_t)M * M) + (size_t)k; /* transposed: p = x M + y */
    return (uint32_t)((face * M + p % M) * M + p / M);
}

/* The eight weights of chunk c of a row whose representative's weights start at w. */
static const float *chunk_weights(const dyn_lobe_level *lv, uint32_t code, size_t w, uint32_t c)
{
    return ((code & 1) ? lv->reversed : lv->weights) + w + (size_t)c * DYN_CHUNK;
}

ibl_status ibl_specular_plan_rows_info(const ibl_specular_plan *plan, int level,
                                       ibl_specular_plan_rows *out)
{
    if (!plan || !out) return IBL_ERR_INVALID_ARGUMENT;
    const ibl__dynamic *d = rows_plan(plan, level);
    if (!d) return IBL_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    const dyn_lobe_level *lv = &d->lobe[level];
    int n = ibl_level_size(d->N, level);
    out->size = n;
    out->source_mip = d->source_mip[level];
    out->source_size = d->S >> d->source_mip[level];
    out->mirror = lv->edge == 0;
    const dyn_fixup *fx = &d->fixup[level];
    out->fixup = fx->method == IBL_EDGE_FIXUP_NONE ? IBL_EDGE_FIXUP_NONE
                 : n == 1                          ? IBL_EDGE_FIXUP_OVERLAP
                 : fx->method == IBL_EDGE_FIXUP_OVERLAP || fx->method == IBL_EDGE_FIXUP_OVERLAP2
                     ? fx->method
                     : IBL_EDGE_FIXUP_NONE;
    out->rows = (size_t)6 * n * n;
    if (out->mirror) {
        out->taps = out->rows;
        return IBL_OK;
    }
    size_t taps = 0;
    for (size_t i = 0; i < out->rows; i++) {
        uint32_t rep = lv->row_rep[i], first = lv->row_codes[i];
        size_t w = (size_t)lv->rep_chunks[rep] * DYN_CHUNK;
        for (uint32_t c = 0; c < lv->row_codes[i + 1] - first; c++) {
            const float *cw = chunk_weights(lv, lv->codes[first + c], w, c);
            for (int k = 0; k < DYN_CHUNK; k++) taps += cw[k] != 0.0f;
        }
    }
    out->taps = taps;
    return IBL_OK;
}

ibl_status ibl_specular_plan_rows_fill(const ibl_specular_plan *plan, int level,
                                       uint32_t *row_offsets, uint32_t *columns, float *weights)
{
    ibl_specular_plan_rows info;
    ibl_status st = ibl_specular_plan_rows_info(plan, level, &info);
    if (st != IBL_OK) return st;
    if (!row_offsets || (info.taps && (!columns || !weights))) return IBL_ERR_INVALID_ARGUMENT;
    if (info.taps > UINT32_MAX)
        return ibl__fail(plan->ctx, IBL_ERR_INVALID_ARGUMENT, "specular plan: rows: too many taps");
    const ibl__dynamic *d = plan->dynamic;
    const dyn_lobe_level *lv = &d->lobe[level];
    int M = info.source_size;
    size_t t = 0;
    for (size_t i = 0; i < info.rows; i++) {
        row_offsets[i] = (uint32_t)t;
        if (info.mirror) {
            columns[t] = (uint32_t)i, weights[t] = 1.0f, t++;
            continue;
        }
        uint32_t rep = lv->row_rep[i], first = lv->row_codes[i];
        size_t w = (size_t)lv->rep_chunks[rep] * DYN_CHUNK;
        for (uint32_t c = 0; c < lv->row_codes[i + 1] - first; c++) {
            uint32_t code = lv->codes[first + c];
            const float *cw = chunk_weights(lv, code, w, c);
            for (int k = 0; k < DYN_CHUNK; k++)
                if (cw[k] != 0.0f) columns[t] = code_texel(code, k, M), weights[t] = cw[k], t++;
        }
    }
    row_offsets[info.rows] = (uint32_t)t;
    return IBL_OK;
}
