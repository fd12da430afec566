/* The specular sources' refinement added to a chain (specular_sources.c makes the sources and
 * describes the method): every output texel of a refined level within reach of the region's
 * groups gets delta(R), each group's cells summed one by one near it and as a monopole and a
 * dipole farther out. A narrow Phong lobe (nil long before the horizon: close to a Gaussian) makes
 * delta as smooth as itself, so where a grid of half the output's edge is fine enough for it
 * (refinement_grid_edge) delta is summed at that grid's points and interpolated at the output
 * texels as the fast method reads its Phong cores (6-point Lagrange per axis, docs/SPECULAR.md
 * "The fast method", step 3): a quarter of the sums. Every output texel or grid point is summed
 * alone, in a fixed order of groups and cells, so the result does not depend on the thread
 * count. */
#include "specular_sources_internal.h"
#include "core/context_internal.h"
#include "core/cpu.h"
#include "core/numeric.h"

#include <math.h>
#include <stdint.h>
#include <string.h>

/* A group's cells are summed one by one where the output direction is within 2 half widths of
 * the group's cone, as a monopole and a dipole out to 16 (measured on city.exr, level 1 of the
 * 256 chain, against 4 and 32: within 0.11% of every texel; a reach of 8 half widths left a
 * 0.97% step where the correction ends, 4 a 3.2% step; a near field of 1 half width 0.028%
 * RMS against 0.022%). */
#define NEAR_HALF_WIDTHS 2.0
#define REACH_HALF_WIDTHS 16.0
/* Output texels are culled against the groups eight by eight. */
#define TILE 8
/* A Phong far field takes x^n by a series in u = 1 - x (phong_far) where every group's reach
 * is within u = 0.1 and the series' first dropped term is under 1e-10 of f there: the far
 * field is itself a dipole approximation good to ~1e-3 of the correction it carries. */
#define PHONG_FAR_SERIES_MAX_U 0.1
#define PHONG_FAR_SERIES_ERROR 1e-10
/* A narrow Phong level's delta is summed on a grid of half the output's edge and read by
 * GRID_TAPS-point Lagrange interpolation per axis (from GRID_TAP_OFFSET points before the one
 * under the texel) where the taps lie on the texel's own face, when the grid's mean spacing is
 * at most GRID_SPACING of the lobe's half width and the lobe is under GRID_PHONG_CULL of its
 * peak long before the horizon (see refinement_grid_edge). */
#define GRID_TAPS 6
#define GRID_TAP_OFFSET 2
#define GRID_BORDER 3
/* The grid's points are culled against the groups four by four (its tiles of eight covered
 * twice the output's area in reach). */
#define GRID_TILE 4
/* 0.6 half widths: a Gaussian (cos^n, sigma = 0.85 half widths) sampled 0.7 sigma apart is
 * interpolated within ~6e-3 of its peak per axis, and delta is a small part of the level: on
 * cmft's exponents at 256 from city.exr (grids 0.43 and 0.56 half widths apart) the chain moved
 * by at most 0.086% of a texel against delta summed at every output texel. */
#define GRID_SPACING 0.6
/* (as the fast method's Lagrange grids, pieces.c: x^n has a kink at the horizon) */
#define GRID_PHONG_CULL 1e-9

typedef struct apply_job {
    const ibl_specular_sources *s;
    ibl__lobe lobe;
    double inv_norm, near, reach;
    ibl_cubemap *chain;
    int level, n, tiles; /* tiles per face edge */
    /* per group, once per level: the cosines of its near and far bounds, and the cosine and
     * sine of its reach (radius + reach) for the tiles' test */
    double cos_near[MAX_REGION_TEXELS], cos_reach[MAX_REGION_TEXELS];
    double reach_angle[MAX_REGION_TEXELS], cos_tile[MAX_REGION_TEXELS], sin_tile[MAX_REGION_TEXELS];
    int phong_far_series; /* a Phong far field by phong_far (its reach is inside the series') */
    /* a Phong near field: phong_near or its AVX2 twin */
    int (*near_sum)(const source_group *g, const double R[3], double x0, double n, double out[3]);
    /* delta summed on a coarse grid of grid_edge points a face edge (refinement_grid_edge; 0:
     * at every output texel): 6 grid_edge^2 x rgb, interpolated at the output texels */
    int grid_edge;
    double *grid;
    /* the grid continued GRID_BORDER points beyond each face edge on the face's plane (so that
     * every output texel's taps are on its own face's grid: delta is a function of direction,
     * evaluated there as anywhere), grid_side = grid_edge + 2 GRID_BORDER points a face edge, in
     * GRID_TILE tiles (grid_tiles a face edge), each marked live when a group reaches it */
    int grid_side, grid_tiles;
    unsigned char *grid_live;
    /* every group's reach in one cone (unit centre, angle): a tile outside it is out of reach of
     * every group, found with one test */
    double all_centre[3], all_reach;
} apply_job;

static double angle_between(const double a[3], const double b[3])
{
    double x = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    return acos(x > 1 ? 1 : x < -1 ? -1 : x);
}

/* A group's near field under a Phong lobe, sum_k w_k (x_k / x0)^n with x_k = R.d_k and x0 = R.c
 * (the caller multiplies by x0^n): (x_k / x0)^n = exp(n ln(1 + e)), e = R.(d_k - c) / x0, with
 * ln(1 + e) to its e^3 term and exp to its t^10 term (Estrin's scheme), in float over lanes of
 * cells the compiler vectorizes (a narrow lobe spent nearly all of its refinement in pow()
 * here). The offsets d_k - c keep e's relative precision in float; where every |e| <= 1e-3 and
 * |n e| <= 1 (a near field's cells: e is at most the near radius times the group's, ~3e-4 at
 * exponent 2049 on a 256 cube) the truncations are below 3e-8 relative. 0 when a cell is out
 * of that range: the caller sums the cells one by one. */
__attribute__((always_inline)) static inline int phong_near_lanes(const source_group *g,
                                                                  const double R[3], double x0,
                                                                  double n, double out[3])
{
    const size_t P = g->padded;
    const float *ox = g->lanes, *oy = ox + P, *oz = oy + P, *wr = oz + P, *wg = wr + P, *wb = wg + P;
    const float r0 = (float)R[0], r1 = (float)R[1], r2 = (float)R[2], inv = (float)(1.0 / x0);
    const float nf = (float)n;
    float ar[NEAR_LANES] = {0}, ag[NEAR_LANES] = {0}, ab[NEAR_LANES] = {0};
    float worst_e[NEAR_LANES] = {0}, worst_t[NEAR_LANES] = {0};
    for (size_t k = 0; k < P; k += NEAR_LANES)
        for (int l = 0; l < NEAR_LANES; l++) {
            size_t i = k + (size_t)l;
            float e = (r0 * ox[i] + r1 * oy[i] + r2 * oz[i]) * inv;
            float t = nf * (e * (1.0f + e * (-0.5f + e * (1.0f / 3.0f))));
            float ae = e < 0 ? -e : e, at = t < 0 ? -t : t;
            worst_e[l] = ae > worst_e[l] ? ae : worst_e[l];
            worst_t[l] = at > worst_t[l] ? at : worst_t[l];
            float t2 = t * t, t4 = t2 * t2, t8 = t4 * t4;
            float p01 = 1.0f + t, p23 = 0.5f + t * (1.0f / 6.0f);
            float p45 = 1.0f / 24.0f + t * (1.0f / 120.0f), p67 = 1.0f / 720.0f + t * (1.0f / 5040.0f);
            float p89 = 1.0f / 40320.0f + t * (1.0f / 362880.0f), p10 = 1.0f / 3628800.0f;
            float ex = (p01 + t2 * p23) + t4 * (p45 + t2 * p67) + t8 * (p89 + t2 * p10);
            ar[l] += ex * wr[i], ag[l] += ex * wg[i], ab[l] += ex * wb[i];
        }
    out[0] = out[1] = out[2] = 0.0;
    for (int l = 0; l < NEAR_LANES; l++) {
        if (!(worst_e[l] <= 1e-3f && worst_t[l] <= 1.0f)) return 0;
        out[0] += ar[l], out[1] += ag[l], out[2] += ab[l];
    }
    return 1;
}

/* phong_near_lanes compiled for the base instruction set and, where the context allows AVX2,
 * for it: the same lane arithmetic (no fused operations: C11 without contraction), eight lanes
 * in one vector instead of two, so the same bits at half the instructions. */
static int phong_near(const source_group *g, const double R[3], double x0, double n, double out[3])
{
    return phong_near_lanes(g, R, x0, n, out);
}
#if IBL_HAVE_X86_KERNELS
IBL_TARGET_AVX2 static int phong_near_avx2(const source_group *g, const double R[3], double x0,
                                           double n, double out[3])
{
    return phong_near_lanes(g, R, x0, n, out);
}
#endif

/* A Phong far field's f = x^n and f' = n x^(n-1) at x = 1 - u, with -ln x = u + u^2/2 + ... +
 * u^8/8 by Horner and one exp(): pow() was a third of a narrow level's refinement (every output
 * texel within the cull angle of every group). The first dropped term moves f by n u^9 / 9 of
 * itself, under PHONG_FAR_SERIES_ERROR wherever the series is used (apply_job.phong_far_series:
 * cmft's exponents 2049 and 862 at 256 reach u = 0.016 and 0.035). */
static void phong_far(double n, double x, double f[2])
{
    double u = 1.0 - x;
    double s = 1.0 / 7.0 + u * (1.0 / 8.0);
    s = 1.0 / 6.0 + u * s;
    s = 1.0 / 5.0 + u * s;
    s = 1.0 / 4.0 + u * s;
    s = 1.0 / 3.0 + u * s;
    s = 1.0 / 2.0 + u * s;
    s = 1.0 + u * s;
    f[0] = exp(-n * u * s);
    f[1] = n * f[0] / x;
}

/* The groups in reach of the tile [x0, x1) x [y0, y1) of face `face` of an n-texel face (list,
 * with the cosines of their near and far bounds); their count. */
static int tile_groups(const apply_job *job, int face, int n, int x0, int y0, int x1, int y1,
                       int *list, double *cos_near, double *cos_reach)
{
    const ibl_specular_sources *s = job->s;
    /* the tile's cone: its centre direction and the farthest corner */
    double c[3], q[3], radius = 0;
    ibl_cube_direction_d(face, 0.5 * (x0 + x1) / n, 0.5 * (y0 + y1) / n, c);
    double cl = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    for (int m = 0; m < 3; m++) c[m] /= cl;
    /* out of every group's reach at once, before the corners' angles: the tile's radius is at
     * most its half diagonal on the face plane (2 / n a texel), the plane being at least 1 from
     * the centre (a margin of 1e-6 radians above the test below) */
    double bound = sqrt((double)(x1 - x0) * (x1 - x0) + (double)(y1 - y0) * (y1 - y0)) / n;
    double xa = c[0] * job->all_centre[0] + c[1] * job->all_centre[1] + c[2] * job->all_centre[2];
    if (job->all_reach + bound + 1e-6 < IBL_PI && xa < cos(job->all_reach + bound + 1e-6)) return 0;
    for (int k = 0; k < 4; k++) {
        ibl_cube_direction_d(face, (double)(k & 1 ? x1 : x0) / n, (double)(k & 2 ? y1 : y0) / n, q);
        double ql = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
        for (int m = 0; m < 3; m++) q[m] /= ql;
        radius = fmax(radius, angle_between(c, q));
    }
    /* a group is out of reach when the angle to it exceeds its reach angle plus the tile's
     * radius, i.e. when c.centre < cos(reach angle + radius) (by the angle-sum rule, a little
     * lower to stay conservative: the texels' own test decides) */
    int count = 0;
    double cos_radius = cos(radius), sin_radius = sin(radius);
    for (int g = 0; g < s->groups; g++) {
        const source_group *gr = &s->group[g];
        double xc = c[0] * gr->centre[0] + c[1] * gr->centre[1] + c[2] * gr->centre[2];
        if (job->reach_angle[g] + radius < IBL_PI &&
            xc < job->cos_tile[g] * cos_radius - job->sin_tile[g] * sin_radius - 1e-9)
            continue;
        cos_near[count] = job->cos_near[g];
        cos_reach[count] = job->cos_reach[g];
        list[count++] = g;
    }
    return count;
}

/* delta(R) at the unit direction R from the tile's groups (times the normaliser: acc is the
 * sum of f times the cells' weights). */
static void direction_delta(const apply_job *job, const int *list, const double *cos_near,
                            const double *cos_reach, int count, const double R[3], double acc[3])
{
    const ibl_specular_sources *s = job->s;
    acc[0] = acc[1] = acc[2] = 0.0;
    for (int i = 0; i < count; i++) {
        const source_group *gr = &s->group[list[i]];
        double xc = R[0] * gr->centre[0] + R[1] * gr->centre[1] + R[2] * gr->centre[2];
        if (xc < cos_reach[i]) continue;
        if (xc >= cos_near[i]) {
            double near[3];
            if (job->lobe.kind == IBL__LOBE_PHONG && xc > 0 && job->near_sum(gr, R, xc, job->lobe.n, near)) {
                double fc = ibl__lobe_f(&job->lobe, xc);
                for (int ch = 0; ch < 3; ch++) acc[ch] += fc * near[ch];
                continue;
            }
            for (size_t k = 0; k < gr->count; k++) {
                const double *d = gr->cell + k * 6, *w = d + 3;
                double f = ibl__lobe_f(&job->lobe, R[0] * d[0] + R[1] * d[1] + R[2] * d[2]);
                for (int ch = 0; ch < 3; ch++) acc[ch] += f * w[ch];
            }
            continue;
        }
        /* f(R.l) ~ f(x) + f'(x) R.(l - centre), x = R.centre */
        double f[3];
        if (job->phong_far_series) phong_far(job->lobe.n, xc, f);
        else ibl__lobe_f012(&job->lobe, xc, f);
        for (int ch = 0; ch < 3; ch++)
            acc[ch] += f[0] * gr->energy[ch] +
                       f[1] * (R[0] * gr->moment[ch][0] + R[1] * gr->moment[ch][1] + R[2] * gr->moment[ch][2]);
    }
}

/* The unit direction of texel (x, y) of face `face` of an n-texel face. */
static void texel_direction(int face, int n, int x, int y, double R[3])
{
    ibl_cube_direction_d(face, (x + 0.5) / n, (y + 0.5) / n, R);
    double rl = sqrt(R[0] * R[0] + R[1] * R[1] + R[2] * R[2]);
    for (int m = 0; m < 3; m++) R[m] /= rl;
}

/* The weights of the GRID_TAPS points at -GRID_TAP_OFFSET .. GRID_TAPS - 1 - GRID_TAP_OFFSET
 * around a position t in [0, 1) after point 0: Lagrange's polynomial through them. The same
 * taps as the fast filter's lagrange grids (specular/combine.c), in double here: those are
 * summed in float, and their weights' float bits are part of every chain's output. */
static void lagrange_weights(double t, double w[GRID_TAPS])
{
    for (int k = 0; k < GRID_TAPS; k++) {
        double wk = 1.0;
        for (int j = 0; j < GRID_TAPS; j++)
            if (j != k) wk *= (t - (double)(j - GRID_TAP_OFFSET)) / (double)(k - j);
        w[k] = wk;
    }
}

/* A tile of the level's coarse grid (job->grid_edge points a face edge, continued beyond the
 * face's edges on its plane): delta at its points, into job->grid (zero where no group
 * reaches). */
static void grid_tile(void *arg, int index)
{
    const apply_job *job = arg;
    int m = job->grid_edge, side = job->grid_side, T = job->grid_tiles;
    int face = index / (T * T), tx = index % T, ty = index / T % T;
    int X0 = tx * GRID_TILE, Y0 = ty * GRID_TILE;
    int X1 = X0 + GRID_TILE < side ? X0 + GRID_TILE : side, Y1 = Y0 + GRID_TILE < side ? Y0 + GRID_TILE : side;
    int list[MAX_REGION_TEXELS];
    double cos_near[MAX_REGION_TEXELS], cos_reach[MAX_REGION_TEXELS];
    int count = tile_groups(job, face, m, X0 - GRID_BORDER, Y0 - GRID_BORDER, X1 - GRID_BORDER,
                            Y1 - GRID_BORDER, list, cos_near, cos_reach);
    job->grid_live[index] = count > 0;
    for (int Y = Y0; Y < Y1; Y++)
        for (int X = X0; X < X1; X++) {
            double R[3], acc[3] = {0, 0, 0};
            if (count) {
                texel_direction(face, m, X - GRID_BORDER, Y - GRID_BORDER, R);
                direction_delta(job, list, cos_near, cos_reach, count, R, acc);
            }
            double *o = job->grid + (((size_t)face * side + Y) * side + X) * 3;
            for (int ch = 0; ch < 3; ch++) o[ch] = acc[ch];
        }
}

/* The first grid point (bordered coordinates) output texel x (of job->n) reads, and its
 * position t after the point under it. */
static int grid_first_tap(const apply_job *job, int x, double *t)
{
    double g = (x + 0.5) * job->grid_edge / job->n - 0.5;
    int i = (int)floor(g);
    *t = g - i;
    return i - GRID_TAP_OFFSET + GRID_BORDER;
}

/* Whether any grid tile under the taps of the output tile [x0, x1) x [y0, y1) of `face` is
 * live. */
static int grid_tiles_live(const apply_job *job, int face, int x0, int y0, int x1, int y1)
{
    double t;
    int T = job->grid_tiles;
    int gx0 = grid_first_tap(job, x0, &t) / GRID_TILE, gx1 = (grid_first_tap(job, x1 - 1, &t) + GRID_TAPS - 1) / GRID_TILE;
    int gy0 = grid_first_tap(job, y0, &t) / GRID_TILE, gy1 = (grid_first_tap(job, y1 - 1, &t) + GRID_TAPS - 1) / GRID_TILE;
    for (int gy = gy0; gy <= gy1; gy++)
        for (int gx = gx0; gx <= gx1; gx++)
            if (job->grid_live[((size_t)face * T + gy) * T + gx]) return 1;
    return 0;
}

/* delta at output texel (x, y) of `face` from the coarse grid, by GRID_TAPS-point Lagrange
 * interpolation per axis on the face's own (bordered) grid. */
static void grid_delta(const apply_job *job, int face, int x, int y, double acc[3])
{
    int side = job->grid_side;
    double tx, ty, wx[GRID_TAPS], wy[GRID_TAPS];
    int ix = grid_first_tap(job, x, &tx), iy = grid_first_tap(job, y, &ty);
    lagrange_weights(tx, wx);
    lagrange_weights(ty, wy);
    acc[0] = acc[1] = acc[2] = 0.0;
    for (int r = 0; r < GRID_TAPS; r++) {
        const double *row = job->grid + (((size_t)face * side + iy + r) * side + ix) * 3;
        double v[3] = {0, 0, 0};
        for (int q = 0; q < GRID_TAPS; q++)
            for (int ch = 0; ch < 3; ch++) v[ch] += wx[q] * row[3 * q + ch];
        for (int ch = 0; ch < 3; ch++) acc[ch] += wy[r] * v[ch];
    }
}

static void apply_tile(void *arg, int index)
{
    const apply_job *job = arg;
    int n = job->n, T = job->tiles, face = index / (T * T), tx = index % T, ty = index / T % T;
    int x0 = tx * TILE, y0 = ty * TILE, x1 = x0 + TILE < n ? x0 + TILE : n, y1 = y0 + TILE < n ? y0 + TILE : n;
    int list[MAX_REGION_TEXELS], count = 0;
    double cos_near[MAX_REGION_TEXELS], cos_reach[MAX_REGION_TEXELS];
    if (job->grid ? !grid_tiles_live(job, face, x0, y0, x1, y1)
                  : !(count = tile_groups(job, face, n, x0, y0, x1, y1, list, cos_near, cos_reach)))
        return;
    for (int y = y0; y < y1; y++)
        for (int x = x0; x < x1; x++) {
            double acc[3];
            if (job->grid) {
                grid_delta(job, face, x, y, acc);
            } else {
                double R[3];
                texel_direction(face, n, x, y, R);
                direction_delta(job, list, cos_near, cos_reach, count, R, acc);
            }
            float *p = ibl_cubemap_face(job->chain, job->level, face) + ((size_t)y * n + x) * 4;
            for (int ch = 0; ch < 3; ch++) {
                float v = p[ch] + (float)(acc[ch] * job->inv_norm);
                p[ch] = v > 0.0f ? v : 0.0f;
            }
        }
}

/* The edge of the coarse grid a level's delta is summed on (0: at the output texels): half the
 * output's, for a Phong lobe nil before the horizon (delta is then a sum of cos^n lobes, as
 * smooth as a Gaussian) whose half width is at least 1 / GRID_SPACING of the grid's mean
 * spacing. */
static int refinement_grid_edge(const ibl__lobe *lobe, int n)
{
    int m = n / 2;
    if (lobe->kind != IBL__LOBE_PHONG || !(lobe->horizon < GRID_PHONG_CULL) || n % 2 || m < 2 * GRID_TAPS)
        return 0;
    return sqrt(4.0 * IBL_PI / 6.0) / m <= GRID_SPACING * lobe->half_angle ? m : 0;
}

ibl_status ibl_specular_sources_apply(const ibl_specular_sources *s, ibl_cubemap *chain)
{
    if (!s || !s->groups) return IBL_OK; /* no sources: nothing to refine */
    if (!chain || !chain->data)
        return ibl__fail(s->ctx, IBL_ERR_INVALID_ARGUMENT, "specular sources: no chain");
    if (chain->size != s->info.size || chain->levels != s->info.levels)
        return ibl__fail(s->ctx, IBL_ERR_INVALID_ARGUMENT,
                         "specular sources: the chain is %d texels and %d levels, the sources were "
                         "made for %d and %d", chain->size, chain->levels, s->info.size, s->info.levels);
    for (int l = 0; l < chain->levels; l++) {
        apply_job job;
        memset(&job, 0, sizeof job);
        if (!s->refined[l]) continue;
        job.lobe = s->lobe[l];
        job.s = s;
        job.inv_norm = 1.0 / ibl__sources_lobe_normaliser(&job.lobe);
        job.near = NEAR_HALF_WIDTHS * job.lobe.half_angle;
        job.reach = REACH_HALF_WIDTHS * job.lobe.half_angle;
        /* a Phong lobe is under 1e-12 of its peak beyond its cull angle (GGX's tail is not) */
        if (job.lobe.kind == IBL__LOBE_PHONG && job.lobe.cull_angle < job.reach)
            job.reach = job.lobe.cull_angle;
        double widest = 0;
        for (int g = 0; g < s->groups; g++) {
            const source_group *gr = &s->group[g];
            widest = fmax(widest, gr->radius + job.reach);
            job.cos_near[g] = cos(fmin(gr->radius + job.near, IBL_PI));
            job.cos_reach[g] = cos(fmin(gr->radius + job.reach, IBL_PI));
            job.reach_angle[g] = gr->radius + job.reach;
            job.cos_tile[g] = cos(job.reach_angle[g]), job.sin_tile[g] = sin(job.reach_angle[g]);
        }
        /* the cone of every group's reach: about their mean centre */
        for (int g = 0; g < s->groups; g++)
            for (int m = 0; m < 3; m++) job.all_centre[m] += s->group[g].centre[m];
        double cl = sqrt(job.all_centre[0] * job.all_centre[0] + job.all_centre[1] * job.all_centre[1] +
                         job.all_centre[2] * job.all_centre[2]);
        job.all_reach = IBL_PI;
        if (cl > 1e-6) {
            job.all_reach = 0;
            for (int m = 0; m < 3; m++) job.all_centre[m] /= cl;
            for (int g = 0; g < s->groups; g++)
                job.all_reach = fmax(job.all_reach, angle_between(job.all_centre, s->group[g].centre) + job.reach_angle[g]);
        }
        double u_far = 1.0 - cos(fmin(widest, IBL_PI));
        job.phong_far_series = job.lobe.kind == IBL__LOBE_PHONG && u_far <= PHONG_FAR_SERIES_MAX_U &&
                               job.lobe.n * pow(u_far, 9.0) / 9.0 <= PHONG_FAR_SERIES_ERROR;
        job.near_sum = phong_near;
#if IBL_HAVE_X86_KERNELS
        if (ibl__cpu_has(s->ctx, IBL__CPU_AVX2_FMA)) job.near_sum = phong_near_avx2;
#endif
        job.chain = chain;
        job.level = l;
        job.n = ibl_level_size(chain->size, l);
        job.tiles = (job.n + TILE - 1) / TILE;
        job.grid_edge = refinement_grid_edge(&job.lobe, job.n);
        if (job.grid_edge) {
            job.grid_side = job.grid_edge + 2 * GRID_BORDER;
            job.grid_tiles = (job.grid_side + GRID_TILE - 1) / GRID_TILE;
            size_t points = (size_t)6 * job.grid_side * job.grid_side;
            job.grid = ibl_alloc(s->ctx, points * 3 * sizeof(double));
            job.grid_live = ibl_alloc(s->ctx, (size_t)6 * job.grid_tiles * job.grid_tiles);
            if (!job.grid || !job.grid_live) {
                ibl_free(s->ctx, job.grid);
                ibl_free(s->ctx, job.grid_live);
                return ibl_context_status(s->ctx);
            }
            ibl_parallel_for(s->ctx, 6 * job.grid_tiles * job.grid_tiles, grid_tile, &job);
        }
        ibl_parallel_for(s->ctx, 6 * job.tiles * job.tiles, apply_tile, &job);
        ibl_free(s->ctx, job.grid);
        ibl_free(s->ctx, job.grid_live);
    }
    return IBL_OK;
}
