/* The fast prefilter: a deterministic hierarchical quadrature ("Barnes-Hut" over the source).
 *
 * The source's area-weighted quadtree (one per face, down from 1x1) stores per cell the
 * moments of its radiance: per channel the integral M0 = int L dl, the first moment about the
 * cell's radiance centroid m, D = int L (l - m) dl, and the shared normalised covariance C.
 * For every tile of 8x8 output texels a cut through the tree is chosen once (the plan): a cell
 * is split while it is wider than `accuracy` times the lobe's local length scale
 * 1 / |d log f / d angle| over the tile (or straddles the horizon), unless the lobe is below
 * 1e-4 of its peak there; cells beyond the lobe's 1e-12 cut-off are dropped. Each leaf then
 * contributes the second-order Taylor expansion of f(R.l) about x = R.m:
 *     sum_c = M0_c (f(x) + f''(x) R^T C R / 2) + f'(x) R.D_c,
 * exact for a point light in the cell (its centroid is the light) and to second order for
 * smooth light. Where even a source texel is too wide, it is split into k x k sub-texels
 * (points with exact solid angles), as the reference does. The result is divided by the same
 * sum for L = 1, so a constant environment stays constant. Cost per output texel depends only
 * on the lobe and the accuracy, not on the source size beyond a log factor.
 * Deterministic: tiles are independent, reductions run in a fixed order. */
#include "specular_internal.h"

#include <math.h>
#include <string.h>

enum { REC = 32, TILE = 8, CHUNK = 64, NCH = 5 };

/* record fields */
enum { R_M = 0, R_E = 3, R_M0 = 4, R_D = 9, R_C = 24 };

typedef struct subleaf {
    uint32_t texel;
    float d[3], e, omega;
} subleaf;

typedef struct tile {
    int face, x0, y0, w, h;
    size_t cell_begin, cell_count;   /* indices into plan->cells   */
    size_t point_begin, point_count; /* level-0 texel indices       */
    size_t sub_begin, sub_count;     /* subleaves                   */
} tile;

struct ibl_specular_plan {
    ibl_context *ctx;
    ibl_specular_desc desc;
    ibl_specular_info info;
    int S, SL;        /* source edge (power of two) and its level count */
    int N, L;         /* output edge and levels                         */
    ibl__lobe lobes[IBL_MAX_LEVELS];
    float *pyramid;   /* records of source levels 1..SL-1               */
    size_t level_offset[IBL_MAX_LEVELS + 1]; /* record index of (level, face 0, 0, 0) */
    double *radius[IBL_MAX_LEVELS];          /* per source level: n x n angular radii  */
    float *texel;     /* 6 S S x 4: direction, 1 - |d|^2 (double-accurate) */
    float *omega;     /* S S */
    float *outdir;    /* per output level: 6 n n x 4 (direction, 1 - |R|^2) */
    size_t outdir_offset[IBL_MAX_LEVELS];
    tile *tiles;
    int tile_count, level_tile_begin[IBL_MAX_LEVELS + 1];
    uint32_t *cells;
    uint32_t *points;
    subleaf *subs;
    size_t cell_total, point_total, sub_total;
    const ibl_cubemap *run_src;
    ibl_cubemap *run_dst;
    int run_level;
};

/* ------------------------------------------------------------------------------------------ */
/* Geometry                                                                                   */

static void cell_centre(int face, int n, int x, int y, double c[3])
{
    ibl_cube_direction_d(face, (x + 0.5) / n, (y + 0.5) / n, c);
    double len = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    for (int i = 0; i < 3; i++) c[i] /= len;
}

static double angle_between(const double a[3], const double b[3])
{
    double c = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    if (c > 1.0) c = 1.0;
    if (c < -1.0) c = -1.0;
    return acos(c);
}

/* ------------------------------------------------------------------------------------------ */
/* The cut: which cells of the source tree serve a tile                                       */

typedef struct cut_params {
    const ibl_specular_plan *p;
    const ibl__lobe *lobe;
    double axis[3], beta; /* the tile's cone */
    double kappa;
} cut_params;

typedef struct cut_out {
    uint32_t *cells, *points;
    subleaf *subs;
    size_t ncell, npoint, nsub;
} cut_out;

static const double HALF_PI = 1.57079632679489661923;
/* refinement is pointless where the lobe is this far below its peak */
static const double SMALL_WEIGHT = 1e-6;
/* largest cell allowed across the horizon (radians): the lobe has a kink there */
static const double HORIZON_CELL = 0.05;
/* a source texel is used as a point until it would need more than this many pieces a side */
enum { LEVEL0_POINT_MAX = 1 };

/* 0: drop, 1: leaf, k >= 2: wants splitting (k: pieces per edge a level-0 texel would need) */
static int classify(const cut_params *cp, const double c[3], double gamma)
{
    double theta = angle_between(cp->axis, c);
    double t0 = theta - cp->beta - gamma, t1 = theta + cp->beta + gamma;
    if (t0 >= cp->lobe->cull_angle || t0 >= HALF_PI) return 0;
    if (t0 < 0) t0 = 0;
    double need = 1.0;
    if (t1 > HALF_PI && cp->lobe->horizon > 0.05) need = 2.0 * gamma / HORIZON_CELL;
    if (ibl__lobe_table_f(cp->lobe, t0) > SMALL_WEIGHT) {
        /* the last 0.05 rad above the horizon belong to the horizon rule: lobes with
         * n < 1 (Blinn 1 / 4.2) have an unbounded slope there that does not matter */
        double te = t1 < HALF_PI - 0.05 ? t1 : HALF_PI - 0.05;
        double g = t0 < te ? ibl__lobe_table_max_variation(cp->lobe, t0, te) : 0.0;
        double k = 2.0 * gamma * g / cp->kappa;
        if (k > need) need = k;
    }
    if (need <= 1.0) return 1;
    double k = ceil(need);
    return k > 16 ? 16 : (int)k;
}

static void cut_tile(const cut_params *cp, cut_out *o, int write)
{
    const ibl_specular_plan *p = cp->p;
    int top = p->SL - 1;
    struct item {
        int8_t level, face;
        int x, y;
    } stack[256];
    int sp = 0;
    for (int f = 5; f >= 0; f--) stack[sp++] = (struct item){(int8_t)top, (int8_t)f, 0, 0};
    while (sp > 0) {
        struct item it = stack[--sp];
        int n = p->S >> it.level;
        double c[3];
        cell_centre(it.face, n, it.x, it.y, c);
        double gamma = p->radius[it.level][(size_t)it.y * n + it.x];
        int k = classify(cp, c, gamma);
        if (k == 0) continue;
        if (k >= 2 && it.level > 0) {
            /* children pushed so that they pop in row-major order */
            for (int j = 1; j >= 0; j--)
                for (int i = 1; i >= 0; i--)
                    stack[sp++] = (struct item){(int8_t)(it.level - 1), it.face, 2 * it.x + i,
                                                2 * it.y + j};
            continue;
        }
        uint32_t texel_index = (uint32_t)(((size_t)it.face * n + it.y) * n + it.x);
        if (it.level > 0) {
            if (write)
                o->cells[o->ncell] = (uint32_t)(p->level_offset[it.level] + texel_index);
            o->ncell++;
        } else if (k <= LEVEL0_POINT_MAX) {
            if (write) o->points[o->npoint] = texel_index;
            o->npoint++;
        } else {
            if (write) {
                double h = 2.0 / n, hk = h / k;
                for (int j = 0; j < k; j++) {
                    for (int i = 0; i < k; i++) {
                        double u0 = it.x * h - 1 + i * hk, v0 = it.y * h - 1 + j * hk, d[3];
                        ibl_cube_direction_d(it.face, 0.5 * (u0 + 0.5 * hk + 1.0),
                                             0.5 * (v0 + 0.5 * hk + 1.0), d);
                        double len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
                        subleaf *s = &o->subs[o->nsub + (size_t)j * k + i];
                        s->texel = texel_index;
                        for (int q = 0; q < 3; q++) s->d[q] = (float)(d[q] / len);
                        double m2 = (double)s->d[0] * s->d[0] + (double)s->d[1] * s->d[1] +
                                    (double)s->d[2] * s->d[2];
                        s->e = (float)(1.0 - m2);
                        /* the solid-angle density 1 / (1 + u^2 + v^2)^(3/2) at the piece's
                         * centre: relative error O(hk^2) ~ 1e-6, without four atan2 */
                        double uc = u0 + 0.5 * hk, vc = v0 + 0.5 * hk, q = 1.0 + uc * uc + vc * vc;
                        s->omega = (float)(hk * hk / (q * sqrt(q)));
                    }
                }
            }
            o->nsub += (size_t)k * k;
        }
    }
}

static void tile_cone(const ibl_specular_plan *p, int level, const tile *t, double axis[3],
                      double *beta)
{
    int n = ibl_level_size(p->N, level);
    const float *dirs = p->outdir + p->outdir_offset[level];
    double a[3] = {0, 0, 0};
    for (int y = t->y0; y < t->y0 + t->h; y++)
        for (int x = t->x0; x < t->x0 + t->w; x++) {
            const float *d = dirs + (((size_t)t->face * n + y) * n + x) * 4;
            for (int i = 0; i < 3; i++) a[i] += d[i];
        }
    double len = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    for (int i = 0; i < 3; i++) axis[i] = a[i] / len;
    double b = 0;
    for (int y = t->y0; y < t->y0 + t->h; y++)
        for (int x = t->x0; x < t->x0 + t->w; x++) {
            const float *d = dirs + (((size_t)t->face * n + y) * n + x) * 4;
            double dd[3] = {d[0], d[1], d[2]};
            double ang = angle_between(axis, dd);
            if (ang > b) b = ang;
        }
    *beta = b * 1.0001 + 1e-9;
}

typedef struct plan_job {
    ibl_specular_plan *p;
    int write;
} plan_job;

static int tile_level(const ibl_specular_plan *p, int index)
{
    int level = 0;
    while (level + 1 <= p->L && p->level_tile_begin[level + 1] <= index) level++;
    return level;
}

static void plan_tile_task(void *arg, int index)
{
    plan_job *job = arg;
    ibl_specular_plan *p = job->p;
    tile *t = &p->tiles[index];
    int level = tile_level(p, index);
    cut_params cp;
    cp.p = p;
    cp.lobe = &p->lobes[level];
    cp.kappa = p->desc.accuracy > 0 ? p->desc.accuracy : 0.35;
    tile_cone(p, level, t, cp.axis, &cp.beta);
    cut_out o = {0};
    if (job->write) {
        o.cells = p->cells + t->cell_begin;
        o.points = p->points + t->point_begin;
        o.subs = p->subs + t->sub_begin;
    }
    cut_tile(&cp, &o, job->write);
    if (!job->write) {
        t->cell_count = o.ncell;
        t->point_count = o.npoint;
        t->sub_count = o.nsub;
    }
}

/* ------------------------------------------------------------------------------------------ */
/* Plan                                                                                       */

static int is_pow2(int n) { return n > 0 && (n & (n - 1)) == 0; }

/* Tiles share one cut, refined for the whole tile's cone: keep them within about two lobe
 * half-widths so the cut stays as coarse as a single texel's would be. */
static int tile_width(const ibl__lobe *lobe, int n)
{
    double texel = HALF_PI / n;
    int w = (int)(2.0 * lobe->half_angle / texel);
    if (w < 1) w = 1;
    if (w > TILE) w = TILE;
    return w > n ? n : w;
}

void ibl_specular_plan_destroy(ibl_specular_plan *p)
{
    if (!p) return;
    ibl_context *ctx = p->ctx;
    ibl_free(ctx, p->pyramid);
    for (int i = 0; i < IBL_MAX_LEVELS; i++) ibl_free(ctx, p->radius[i]);
    ibl_free(ctx, p->texel);
    ibl_free(ctx, p->omega);
    ibl_free(ctx, p->outdir);
    ibl_free(ctx, p->tiles);
    ibl_free(ctx, p->cells);
    ibl_free(ctx, p->points);
    ibl_free(ctx, p->subs);
    ibl_free(ctx, p);
}

const ibl_specular_info *ibl_specular_plan_info(const ibl_specular_plan *plan)
{
    return plan ? &plan->info : NULL;
}

ibl_status ibl_specular_plan_create(ibl_context *ctx, const ibl_specular_desc *desc,
                                    ibl_specular_plan **out)
{
    if (!ctx || !desc || !out) return IBL_ERR_INVALID_ARGUMENT;
    *out = NULL;
    int S = desc->source_size > 0 ? desc->source_size : desc->size;
    int N = desc->size;
    if (N < 1 || N > 16384)
        return ibl_fail(ctx, IBL_ERR_INVALID_ARGUMENT, "specular plan: size %d out of range", N);
    if (!is_pow2(S) || S > 16384)
        return ibl_fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                        "specular plan: source size %d must be a power of two", S);
    if (desc->filter != IBL_FILTER_GGX && desc->filter != IBL_FILTER_PHONG &&
        desc->filter != IBL_FILTER_BLINN)
        return ibl_fail(ctx, IBL_ERR_UNSUPPORTED,
                        "specular plan: the %s filter has no plan (phong, blinn, ggx only)",
                        ibl_specular_filter_name(desc->filter));
    ibl_specular_plan *p = ibl_calloc(ctx, 1, sizeof *p);
    if (!p) return ibl_context_status(ctx);
    p->ctx = ctx;
    p->desc = *desc;
    p->S = S;
    p->SL = ibl_full_mip_count(S);
    p->N = N;
    int levels = desc->levels > 0 ? desc->levels : ibl_full_mip_count(N);
    if (levels > ibl_full_mip_count(N)) levels = ibl_full_mip_count(N);
    p->L = levels;
    ibl_status st = ibl__specular_mapping(ctx, desc, N, levels, &p->info);
    if (st != IBL_OK) goto fail;
    for (int l = 0; l < levels; l++) p->lobes[l] = ibl__lobe_for_level(&p->info, l);

    /* source geometry */
    size_t off = 0;
    for (int l = 1; l < p->SL; l++) {
        int n = S >> l;
        p->level_offset[l] = off;
        off += (size_t)6 * n * n;
    }
    p->level_offset[p->SL] = off;
    p->pyramid = ibl_alloc(ctx, (off ? off : 1) * REC * sizeof(float));
    p->texel = ibl_alloc(ctx, (size_t)6 * S * S * 4 * sizeof(float));
    p->omega = ibl_alloc(ctx, (size_t)S * S * sizeof(float));
    if (!p->pyramid || !p->texel || !p->omega) goto oom;
    for (int l = 0; l < p->SL; l++) {
        int n = S >> l;
        double h = 2.0 / n, c[3];
        p->radius[l] = ibl_alloc(ctx, (size_t)n * n * sizeof(double));
        if (!p->radius[l]) goto oom;
        for (int y = 0; y < n; y++)
            for (int x = 0; x < n; x++)
                p->radius[l][(size_t)y * n + x] =
                    ibl__rect_radius(0, x * h - 1, y * h - 1, (x + 1) * h - 1, (y + 1) * h - 1, c);
    }
    for (int y = 0; y < S; y++)
        for (int x = 0; x < S; x++)
            p->omega[(size_t)y * S + x] = (float)ibl_cube_texel_solid_angle(S, x, y);
    for (int f = 0; f < 6; f++)
        for (int y = 0; y < S; y++)
            for (int x = 0; x < S; x++) {
                double c[3];
                cell_centre(f, S, x, y, c);
                float *t = p->texel + (((size_t)f * S + y) * S + x) * 4;
                for (int i = 0; i < 3; i++) t[i] = (float)c[i];
                t[3] = (float)(1.0 - ((double)t[0] * t[0] + (double)t[1] * t[1] +
                                      (double)t[2] * t[2]));
            }

    /* output directions and tiles */
    size_t dir_floats = 0;
    int tiles = 0;
    for (int l = 0; l < levels; l++) {
        int n = ibl_level_size(N, l), tw = tile_width(&p->lobes[l], n);
        p->outdir_offset[l] = dir_floats;
        dir_floats += (size_t)6 * n * n * 4;
        p->level_tile_begin[l] = tiles;
        if (p->lobes[l].kind != IBL__LOBE_MIRROR) tiles += 6 * ((n + tw - 1) / tw) * ((n + tw - 1) / tw);
    }
    p->level_tile_begin[levels] = tiles;
    p->tile_count = tiles;
    p->outdir = ibl_alloc(ctx, dir_floats * sizeof(float));
    p->tiles = ibl_calloc(ctx, tiles ? (size_t)tiles : 1, sizeof(tile));
    if (!p->outdir || !p->tiles) goto oom;
    for (int l = 0; l < levels; l++) {
        int n = ibl_level_size(N, l), tw = tile_width(&p->lobes[l], n);
        float *dirs = p->outdir + p->outdir_offset[l];
        for (int f = 0; f < 6; f++)
            for (int y = 0; y < n; y++)
                for (int x = 0; x < n; x++) {
                    double R[3];
                    ibl__output_direction(desc, &p->lobes[l], f, n, x, y, R);
                    float *d = dirs + (((size_t)f * n + y) * n + x) * 4;
                    for (int i = 0; i < 3; i++) d[i] = (float)R[i];
                    d[3] = (float)(1.0 - ((double)d[0] * d[0] + (double)d[1] * d[1] +
                                          (double)d[2] * d[2]));
                }
        if (p->lobes[l].kind == IBL__LOBE_MIRROR) continue;
        int ti = p->level_tile_begin[l];
        for (int f = 0; f < 6; f++)
            for (int ty = 0; ty < n; ty += tw)
                for (int tx = 0; tx < n; tx += tw) {
                    tile *t = &p->tiles[ti++];
                    t->face = f;
                    t->x0 = tx;
                    t->y0 = ty;
                    t->w = tx + tw <= n ? tw : n - tx;
                    t->h = ty + tw <= n ? tw : n - ty;
                }
    }
    plan_job job = {p, 0};
    if (tiles) ibl_parallel_for(ctx, tiles, plan_tile_task, &job);
    for (int i = 0; i < tiles; i++) {
        tile *t = &p->tiles[i];
        t->cell_begin = p->cell_total;
        t->point_begin = p->point_total;
        t->sub_begin = p->sub_total;
        p->cell_total += t->cell_count;
        p->point_total += t->point_count;
        p->sub_total += t->sub_count;
    }
    p->cells = ibl_alloc(ctx, (p->cell_total + 1) * sizeof(uint32_t));
    p->points = ibl_alloc(ctx, (p->point_total + 1) * sizeof(uint32_t));
    p->subs = ibl_alloc(ctx, (p->sub_total + 1) * sizeof(subleaf));
    if (!p->cells || !p->points || !p->subs) goto oom;
    job.write = 1;
    if (tiles) ibl_parallel_for(ctx, tiles, plan_tile_task, &job);
    *out = p;
    return IBL_OK;
oom:
    st = ibl_context_status(ctx);
    if (st == IBL_OK) st = IBL_ERR_OUT_OF_MEMORY;
fail:
    ibl_specular_plan_destroy(p);
    return st;
}

/* ------------------------------------------------------------------------------------------ */
/* Run: moments of the source, then every tile                                                */

typedef struct pyr_job {
    ibl_specular_plan *p;
    const ibl_cubemap *src;
    int level;
} pyr_job;

/* Combines weighted points / child records into one record (double). */
typedef struct accum {
    double rho, m[3], M0[NCH];
} accum;

static void pyramid_task(void *arg, int index)
{
    const pyr_job *job = arg;
    const ibl_specular_plan *p = job->p;
    int level = job->level, n = p->S >> level, face = index / n, y = index % n;
    int cn = n * 2;
    for (int x = 0; x < n; x++) {
        float *rec = p->pyramid + (p->level_offset[level] + ((size_t)face * n + y) * n + x) * REC;
        /* the four children: position, moments, covariance */
        double cm[4][3], cM0[4][NCH], cD[4][NCH][3], cC[4][6];
        for (int k = 0; k < 4; k++) {
            int cx = 2 * x + (k & 1), cy = 2 * y + (k >> 1);
            if (level == 1) {
                const float *t = p->texel + (((size_t)face * cn + cy) * cn + cx) * 4;
                const float *L = ibl_cubemap_face(job->src, 0, face) + ((size_t)cy * cn + cx) * 4;
                double om = p->omega[(size_t)cy * cn + cx];
                for (int i = 0; i < 3; i++) cm[k][i] = t[i];
                for (int c = 0; c < 4; c++) cM0[k][c] = om * L[c];
                cM0[k][4] = om;
                memset(cD[k], 0, sizeof cD[k]);
                memset(cC[k], 0, sizeof cC[k]);
            } else {
                const float *r = p->pyramid +
                                 (p->level_offset[level - 1] + ((size_t)face * cn + cy) * cn + cx) * REC;
                for (int i = 0; i < 3; i++) cm[k][i] = r[R_M + i];
                for (int c = 0; c < NCH; c++) {
                    cM0[k][c] = r[R_M0 + c];
                    for (int i = 0; i < 3; i++) cD[k][c][i] = r[R_D + 3 * c + i];
                }
                for (int i = 0; i < 6; i++) cC[k][i] = r[R_C + i];
            }
        }
        double rho[4], rs = 0;
        for (int k = 0; k < 4; k++) rs += rho[k] = cM0[k][0] + cM0[k][1] + cM0[k][2];
        if (!(rs > 0)) {
            rs = 0;
            for (int k = 0; k < 4; k++) rs += rho[k] = cM0[k][4];
        }
        double m[3] = {0, 0, 0};
        for (int k = 0; k < 4; k++)
            for (int i = 0; i < 3; i++) m[i] += rho[k] * cm[k][i];
        for (int i = 0; i < 3; i++) {
            m[i] /= rs;
            rec[R_M + i] = (float)m[i];
        }
        double mf[3] = {rec[R_M], rec[R_M + 1], rec[R_M + 2]};
        rec[R_E] = (float)(1.0 - (mf[0] * mf[0] + mf[1] * mf[1] + mf[2] * mf[2]));
        for (int c = 0; c < NCH; c++) {
            double M0 = 0, D[3] = {0, 0, 0};
            for (int k = 0; k < 4; k++) {
                M0 += cM0[k][c];
                for (int i = 0; i < 3; i++) D[i] += cD[k][c][i] + cM0[k][c] * (cm[k][i] - mf[i]);
            }
            rec[R_M0 + c] = (float)M0;
            for (int i = 0; i < 3; i++) rec[R_D + 3 * c + i] = (float)D[i];
        }
        double C[6] = {0, 0, 0, 0, 0, 0};
        for (int k = 0; k < 4; k++) {
            double d[3] = {cm[k][0] - mf[0], cm[k][1] - mf[1], cm[k][2] - mf[2]};
            C[0] += rho[k] * (cC[k][0] + d[0] * d[0]);
            C[1] += rho[k] * (cC[k][1] + d[0] * d[1]);
            C[2] += rho[k] * (cC[k][2] + d[0] * d[2]);
            C[3] += rho[k] * (cC[k][3] + d[1] * d[1]);
            C[4] += rho[k] * (cC[k][4] + d[1] * d[2]);
            C[5] += rho[k] * (cC[k][5] + d[2] * d[2]);
        }
        for (int i = 0; i < 6; i++) rec[R_C + i] = (float)(C[i] / rs);
        rec[30] = rec[31] = 0.0f;
    }
}

/* f, f', f'' (d/dx) from u = 1 - x, in float. */
static inline void lobe_eval(const ibl__lobe *lobe, float nn, float a2, float a4, float u,
                             float *f0, float *f1, float *f2)
{
    float x = 1.0f - u;
    if (!(x > 0.0f)) {
        *f0 = *f1 = *f2 = 0.0f;
        return;
    }
    if (lobe->kind == IBL__LOBE_PHONG) {
        float f = expf(nn * log1pf(-u));
        float ix = 1.0f / x;
        *f0 = f;
        *f1 = nn * f * ix;
        *f2 = nn * (nn - 1.0f) * f * ix * ix;
        return;
    }
    /* t = alpha^2 + u (1 - alpha^2) / 2, k = (alpha^2 - 1) / 2 */
    float k = 0.5f * (a2 - 1.0f);
    float t = a2 - u * k;
    float it = 1.0f / t, it2 = it * it, it3 = it2 * it;
    *f0 = a4 * x * it2;
    *f1 = a4 * it3 * (t - 2.0f * k * x);
    *f2 = a4 * it3 * it * (-4.0f * k * t + 6.0f * k * k * x);
}

static inline float lobe_f(const ibl__lobe *lobe, float nn, float a2, float a4, float u)
{
    float x = 1.0f - u;
    if (!(x > 0.0f)) return 0.0f;
    if (lobe->kind == IBL__LOBE_PHONG) return expf(nn * log1pf(-u));
    float t = a2 + u * 0.5f * (1.0f - a2);
    float q = 1.0f / t;
    return a4 * x * q * q;
}

static void tile_run_task(void *arg, int index)
{
    ibl_specular_plan *p = arg;
    int level = p->run_level;
    const tile *t = &p->tiles[p->level_tile_begin[level] + index];
    const ibl__lobe *lobe = &p->lobes[level];
    float nn = (float)lobe->n, a2 = (float)(lobe->alpha * lobe->alpha), a4 = a2 * a2;
    int bounded = lobe->kind == IBL__LOBE_PHONG && lobe->n < 2.0;
    int n = ibl_level_size(p->N, level), S = p->S;
    const float *dirs = p->outdir + p->outdir_offset[level];
    const float *src = p->run_src->data; /* level 0: 6 faces contiguous */
    int count = t->w * t->h;
    float R[TILE * TILE][4];
    double acc[TILE * TILE][NCH];
    memset(acc, 0, sizeof acc);
    for (int j = 0; j < t->h; j++)
        for (int i = 0; i < t->w; i++)
            memcpy(R[j * t->w + i],
                   dirs + (((size_t)t->face * n + t->y0 + j) * n + t->x0 + i) * 4, 4 * sizeof(float));

    /* full cells: Taylor leaves */
    const uint32_t *cells = p->cells + t->cell_begin;
    for (size_t c0 = 0; c0 < t->cell_count; c0 += CHUNK) {
        size_t cn = t->cell_count - c0 < CHUNK ? t->cell_count - c0 : CHUNK;
        float part[TILE * TILE][NCH];
        memset(part, 0, sizeof part);
        for (size_t c = 0; c < cn; c++) {
            const float *rec = p->pyramid + (size_t)cells[c0 + c] * REC;
            for (int q = 0; q < count; q++) {
                const float *r = R[q];
                float dx = r[0] - rec[0], dy = r[1] - rec[1], dz = r[2] - rec[2];
                float u = 0.5f * (dx * dx + dy * dy + dz * dz + rec[R_E] + r[3]);
                float f0, f1, f2;
                lobe_eval(lobe, nn, a2, a4, u, &f0, &f1, &f2);
                if (f0 == 0.0f && f1 == 0.0f) continue;
                /* the second-order term f'' R^T C R / 2 with the radiance's covariance
                 * (docs/SPECULAR.md: variants that bound it measured worse on real HDRIs) */
                const float *C = rec + R_C;
                float var = r[0] * (r[0] * C[0] + 2.0f * (r[1] * C[1] + r[2] * C[2])) +
                            r[1] * (r[1] * C[3] + 2.0f * r[2] * C[4]) + r[2] * r[2] * C[5];
                float corr = 0.5f * f2 * var;
                /* Phong with n < 2 has f'' = n (n - 1) x^(n-2) unbounded at the horizon
                 * (Blinn shininess 1 is n = 0.24): there the expansion is bounded to
                 * [-f/2, +f] (measured: 37% RMS at a 2x2 level without it) */
                if (bounded) corr = corr > f0 ? f0 : corr < -0.5f * f0 ? -0.5f * f0 : corr;
                float w0 = f0 + corr;
                for (int ch = 0; ch < NCH; ch++) {
                    const float *D = rec + R_D + 3 * ch;
                    part[q][ch] += rec[R_M0 + ch] * w0 + f1 * (r[0] * D[0] + r[1] * D[1] + r[2] * D[2]);
                }
            }
        }
        for (int q = 0; q < count; q++)
            for (int ch = 0; ch < NCH; ch++) acc[q][ch] += part[q][ch];
    }
    /* source texels: points */
    const uint32_t *points = p->points + t->point_begin;
    for (size_t c0 = 0; c0 < t->point_count; c0 += CHUNK) {
        size_t cn = t->point_count - c0 < CHUNK ? t->point_count - c0 : CHUNK;
        float part[TILE * TILE][NCH];
        memset(part, 0, sizeof part);
        for (size_t c = 0; c < cn; c++) {
            uint32_t ti = points[c0 + c];
            const float *d = p->texel + (size_t)ti * 4;
            const float *L = src + (size_t)ti * 4;
            float om = p->omega[ti % ((uint32_t)S * S)];
            for (int q = 0; q < count; q++) {
                const float *r = R[q];
                float dx = r[0] - d[0], dy = r[1] - d[1], dz = r[2] - d[2];
                float u = 0.5f * (dx * dx + dy * dy + dz * dz + d[3] + r[3]);
                float w = lobe_f(lobe, nn, a2, a4, u) * om;
                for (int ch = 0; ch < 4; ch++) part[q][ch] += w * L[ch];
                part[q][4] += w;
            }
        }
        for (int q = 0; q < count; q++)
            for (int ch = 0; ch < NCH; ch++) acc[q][ch] += part[q][ch];
    }
    /* split source texels */
    const subleaf *subs = p->subs + t->sub_begin;
    for (size_t c0 = 0; c0 < t->sub_count; c0 += CHUNK) {
        size_t cn = t->sub_count - c0 < CHUNK ? t->sub_count - c0 : CHUNK;
        float part[TILE * TILE][NCH];
        memset(part, 0, sizeof part);
        for (size_t c = 0; c < cn; c++) {
            const subleaf *s = &subs[c0 + c];
            const float *L = src + (size_t)s->texel * 4;
            for (int q = 0; q < count; q++) {
                const float *r = R[q];
                float dx = r[0] - s->d[0], dy = r[1] - s->d[1], dz = r[2] - s->d[2];
                float u = 0.5f * (dx * dx + dy * dy + dz * dz + s->e + r[3]);
                float w = lobe_f(lobe, nn, a2, a4, u) * s->omega;
                for (int ch = 0; ch < 4; ch++) part[q][ch] += w * L[ch];
                part[q][4] += w;
            }
        }
        for (int q = 0; q < count; q++)
            for (int ch = 0; ch < NCH; ch++) acc[q][ch] += part[q][ch];
    }
    float *face = ibl_cubemap_face(p->run_dst, level, t->face);
    for (int j = 0; j < t->h; j++)
        for (int i = 0; i < t->w; i++) {
            const double *a = acc[j * t->w + i];
            float *o = face + ((size_t)(t->y0 + j) * n + t->x0 + i) * 4;
            for (int ch = 0; ch < 4; ch++) {
                double v = a[4] > 0 ? a[ch] / a[4] : 0.0;
                o[ch] = v > 0 ? (float)v : 0.0f;
            }
        }
}

typedef struct mirror_job {
    const ibl_specular_plan *p;
    const ibl_cubemap *src;
    ibl_cubemap *dst;
    int level;
} mirror_job;

static void mirror_row_task(void *arg, int index)
{
    const mirror_job *job = arg;
    const ibl_specular_plan *p = job->p;
    int n = ibl_level_size(p->N, job->level), face = index / n, y = index % n;
    float *row = ibl_cubemap_face(job->dst, job->level, face) + (size_t)y * n * 4;
    if (n == p->S) {
        memcpy(row, ibl_cubemap_face(job->src, 0, face) + (size_t)y * n * 4, (size_t)n * 4 * sizeof(float));
        return;
    }
    if (n < p->S) {
        int sl = 0;
        while ((p->S >> sl) > n) sl++;
        for (int x = 0; x < n; x++) {
            const float *rec = p->pyramid + (p->level_offset[sl] + ((size_t)face * n + y) * n + x) * REC;
            for (int ch = 0; ch < 4; ch++) row[x * 4 + ch] = rec[R_M0 + ch] / rec[R_M0 + 4];
        }
        return;
    }
    const float *dirs = p->outdir + p->outdir_offset[job->level];
    for (int x = 0; x < n; x++) {
        const float *d = dirs + (((size_t)face * n + y) * n + x) * 4;
        ibl_vec3 v = {d[0], d[1], d[2]};
        ibl_cubemap_sample_bilinear(job->src, 0, v, row + x * 4);
    }
}

ibl_status ibl_specular_run(ibl_specular_plan *p, const ibl_cubemap *src, ibl_cubemap *dst)
{
    if (!p || !src || !dst || !src->data || !dst->data) return IBL_ERR_INVALID_ARGUMENT;
    ibl_context *ctx = p->ctx;
    if (src->size != p->S || dst->size != p->N || dst->levels != p->L)
        return ibl_fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                        "specular run: planned source %d -> %d x %d levels, got %d -> %d x %d",
                        p->S, p->N, p->L, src->size, dst->size, dst->levels);
    for (int l = 1; l < p->SL; l++) {
        pyr_job job = {p, src, l};
        ibl_parallel_for(ctx, 6 * (p->S >> l), pyramid_task, &job);
    }
    p->run_src = src;
    p->run_dst = dst;
    for (int l = 0; l < p->L; l++) {
        int count = p->level_tile_begin[l + 1] - p->level_tile_begin[l];
        if (p->lobes[l].kind == IBL__LOBE_MIRROR) {
            mirror_job job = {p, src, dst, l};
            ibl_parallel_for(ctx, 6 * ibl_level_size(p->N, l), mirror_row_task, &job);
        } else {
            p->run_level = l;
            ibl_parallel_for(ctx, count, tile_run_task, p);
        }
        ibl_status st = ibl_edge_fixup_apply(ctx, p->desc.edge_fixup, dst, l);
        if (st != IBL_OK) return st;
        st = ibl_progress(ctx, "prefilter", (l + 1.0) / p->L);
        if (st != IBL_OK) return st;
    }
    return IBL_OK;
}
