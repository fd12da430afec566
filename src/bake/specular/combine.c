/* Combining the grids into an output level: every piece's numerator and normaliser were summed
 * on a grid (the output texels, or a coarser cube grid); the output texel is the sum over the
 * grids of their values at its direction, numerator over normaliser.
 *
 * A coarse grid is read by bilinear interpolation. When the output directions are the texel
 * centres and the grid's edge divides the level's, a texel centre's footprint on the grid is
 * fixed per row, so the grid gets a one-texel border taken across the face edges (at a cube
 * corner, where only three texels meet, the missing fourth is the mean of the three -- as the
 * library's seamless bilinear sampler reads them) and each output row reads two grid rows.
 * Otherwise (edge fixups bend the directions) the grid is sampled by direction with
 * ibl_cubemap_sample_bilinear. Interpolating the numerator and the normaliser alike keeps a
 * constant environment constant.
 *
 * A Phong core's grids (sum_grid.lagrange, always centred and dividing the level's edge) are read
 * by 6-point Lagrange interpolation per axis (the quintic through the 6 x 6 grid points around
 * the texel; its error on a smooth function goes as the spacing to the sixth power, where
 * bilinear's goes as its square), from a three-texel border resampled at the border points' own
 * directions (lagrange_border_task), the corner squares included. Its weights add up to 1, so a
 * constant environment stays constant too. */
#include "bake/specular/fast_internal.h"

#include <math.h>
#include <string.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

/* A lagrange grid is read over TAPS x TAPS points, from TAP_OFFSET before the point under the
 * texel (grid_border: TAPS / 2 texels of border). */
enum { TAPS = 6, TAP_OFFSET = TAPS / 2 - 1 };

typedef struct border_job {
    const ibl_specular_plan *p;
    sum_grid *grid;
} border_job;

/* Face f of a coarse grid's bordered copy. */
static void border_task(void *arg, int f)
{
    const border_job *j = arg;
    sum_grid *gr = j->grid;
    int n = gr->edge, B = grid_border(gr), m = n + 2 * B;
    float *out = gr->bordered + (size_t)f * m * m * 4;
    for (int Y = -B; Y < n + B; Y++)
        for (int X = -B; X < n + B; X++) {
            float *o = out + ((size_t)(Y + B) * m + X + B) * 4;
            int ox = X < 0 || X >= n, oy = Y < 0 || Y >= n;
            if (ox && oy) {
                /* a cube corner: the mean of the three texels around it (a bilinear read takes
                 * the cell next to the corner; a lagrange grid's corner square is resampled) */
                int cx = X < 0 ? 0 : n - 1, cy = Y < 0 ? 0 : n - 1;
                int32_t t[3] = {ibl__fast_unfolded_texel(j->p, n, f, cx, cy),
                                ibl__fast_unfolded_texel(j->p, n, f, X < 0 ? -1 : n, cy),
                                ibl__fast_unfolded_texel(j->p, n, f, cx, Y < 0 ? -1 : n)};
                for (int c = 0; c < 4; c++) {
                    float v = 0;
                    for (int k = 0; k < 3; k++) v += gr->sums[(size_t)t[k] * 4 + c] * (1.0f / 3.0f);
                    o[c] = v;
                }
                continue;
            }
            int32_t t = ibl__fast_unfolded_texel(j->p, n, f, X, Y);
            for (int c = 0; c < 4; c++) o[c] = gr->sums[(size_t)t * 4 + c];
        }
}

/* The interpolation weights of the TAPS points at -TAPS/2 + 1 .. TAPS/2 for a position t in
 * [0, 1) after point 0: Lagrange's polynomial through them. */
static void lagrange_weights(float t, float w[TAPS])
{
    for (int k = 0; k < TAPS; k++) {
        float wk = 1.0f;
        for (int j = 0; j < TAPS; j++)
            if (j != k) wk *= (t - (float)(j - TAP_OFFSET)) / (float)(k - j);
        w[k] = wk;
    }
}

/* A lagrange grid's border, resampled: the unfolded neighbour texels of border_task lie where the
 * neighbour's grid has them, not where this face's grid continued across the edge would (the
 * face plane extended; laterally half a texel off at depth 1 near the corners, 1.5 at depth 2),
 * and the interpolation reads its taps as evenly spaced (read as they lie, they gave 0.5-1%
 * errors along the face edges of the 256 chain's level 0). So each border point takes the value
 * at its own direction -- this face's grid continued on its plane -- read from the face that
 * direction falls on by the same interpolation over that face's bordered copy (the point lies
 * within three texels of that face's edge, the border's own displacement entering only through
 * the outer taps). The corner squares, where no face's grid continues, get values the same way.
 * Reads the first copy, writes the second. */
static void lagrange_border_task(void *arg, int f)
{
    const border_job *j = arg;
    sum_grid *gr = j->grid;
    int n = gr->edge, B = grid_border(gr), m = n + 2 * B;
    const float *in = gr->bordered;
    float *out = gr->bordered + (size_t)6 * m * m * 4 + (size_t)f * m * m * 4;
    memcpy(out, in + (size_t)f * m * m * 4, (size_t)m * m * 4 * sizeof(float));
    for (int Y = -B; Y < n + B; Y++)
        for (int X = -B; X < n + B; X++) {
            if (X >= 0 && X < n && Y >= 0 && Y < n) continue;
            double d[3], s, t;
            ibl_cube_direction_d(f, (X + 0.5) / n, (Y + 0.5) / n, d);
            int g = ibl_cube_face_st_d(d, &s, &t);
            float gx = (float)(s * n - 0.5), gy = (float)(t * n - 0.5);
            int ix = (int)floorf(gx), iy = (int)floorf(gy);
            ix = ix < -1 ? -1 : ix > n - 1 ? n - 1 : ix;
            iy = iy < -1 ? -1 : iy > n - 1 ? n - 1 : iy;
            float wx[TAPS], wy[TAPS], v[4] = {0, 0, 0, 0};
            lagrange_weights(gx - ix, wx);
            lagrange_weights(gy - iy, wy);
            const float *origin = in + ((size_t)g * m * m + (size_t)B * m + B) * 4;
            for (int r = 0; r < TAPS; r++)
                for (int q = 0; q < TAPS; q++) {
                    const float *a = origin + ((ptrdiff_t)(iy - TAP_OFFSET + r) * m + ix - TAP_OFFSET + q) * 4;
                    for (int c = 0; c < 4; c++) v[c] += wy[r] * wx[q] * a[c];
                }
            float *o = out + ((size_t)(Y + B) * m + X + B) * 4;
            for (int c = 0; c < 4; c++) o[c] = v[c];
        }
}

typedef struct combine_job {
    const ibl_specular_plan *p;
    ibl_cubemap *dst;
    int level;
} combine_job;

/* How an output row reads the level's grids: the one at the output texels, the coarse grids
 * read by rows of their bordered copies (two rows bilinearly, TAPS for lagrange grids), and those
 * sampled by direction. */
/* A level has at most two lagrange grids (a Phong core's and its corrections', pieces.c); the
 * column weights of a lagrange grid are tabulated for up to 64 output texels a grid texel. */
enum { LAGRANGE_GRIDS = 2, LAGRANGE_PHASES = 64 };

typedef struct row_sources {
    const sum_grid *at_output;
    const float *rows[MAX_PIECES][2]; /* the two bordered rows under the output row        */
    float fy[MAX_PIECES], scale[MAX_PIECES];
    /* lagrange grids: the TAPS rows, their weights, and the column weights of each phase x % r
     * of the output column over the grid's (r = n / edge; computed per texel above
     * LAGRANGE_PHASES) */
    const float *lagrange_rows[LAGRANGE_GRIDS][TAPS];
    float lagrange_wy[LAGRANGE_GRIDS][TAPS], lagrange_scale[LAGRANGE_GRIDS];
    float lagrange_wx[LAGRANGE_GRIDS][LAGRANGE_PHASES][TAPS];
    int lagrange_ratio[LAGRANGE_GRIDS];
    int sampled[MAX_PIECES], row_count, lagrange_count, sampled_count;
} row_sources;

static void row_sources_of(const ibl_specular_plan *p, const level_plan *lv, int n, int face,
                           int y, row_sources *rs)
{
    int centred = centred_directions(p);
    rs->at_output = NULL;
    rs->row_count = rs->lagrange_count = rs->sampled_count = 0;
    for (int g = 0; g < lv->grid_count; g++) {
        const sum_grid *gr = &lv->grids[g];
        int gn = gr->edge;
        if (gr->at_output) {
            rs->at_output = gr;
        } else if (centred && n % gn == 0) {
            /* the texel centre's footprint on the bordered grid (it never leaves it: gx is in
             * [-1/2, gn - 1/2], and the border is three deep for the lagrange reads) */
            int B = grid_border(gr), m = gn + 2 * B;
            const float *copy = gr->bordered + (gr->lagrange ? (size_t)6 * m * m * 4 : 0);
            const float *face_origin = copy + ((size_t)face * m * m + (size_t)B * m + B) * 4;
            float gy = (y + 0.5f) * gn / n - 0.5f;
            int iy = (int)floorf(gy);
            if (gr->lagrange && rs->lagrange_count < LAGRANGE_GRIDS) {
                int k = rs->lagrange_count++;
                for (int r = 0; r < TAPS; r++)
                    rs->lagrange_rows[k][r] = face_origin + (ptrdiff_t)(iy - TAP_OFFSET + r) * m * 4;
                lagrange_weights(gy - iy, rs->lagrange_wy[k]);
                rs->lagrange_scale[k] = (float)gn / n;
                rs->lagrange_ratio[k] = n / gn;
                for (int x = 0; x < n / gn && x < LAGRANGE_PHASES; x++) {
                    float gx = (x + 0.5f) * rs->lagrange_scale[k] - 0.5f;
                    lagrange_weights(gx - floorf(gx), rs->lagrange_wx[k][x]);
                }
            } else {
                int k = rs->row_count++;
                rs->rows[k][0] = face_origin + (ptrdiff_t)iy * m * 4;
                rs->rows[k][1] = rs->rows[k][0] + (size_t)m * 4;
                rs->fy[k] = gy - iy;
                rs->scale[k] = (float)gn / n;
            }
        } else {
            rs->sampled[rs->sampled_count++] = g;
        }
    }
}

/* A Lagrange grid's y pass covers the grid columns under a span of at most LAGRANGE_SPAN output
 * texels at a time: its grid is at least twice as coarse as the output (it divides the output's
 * edge and is coarser), so a span reads at most LAGRANGE_SPAN / 2 + TAPS columns. */
enum { LAGRANGE_SPAN = 64, LAGRANGE_SPAN_COLUMNS = LAGRANGE_SPAN / 2 + TAPS };

/* Grid column c of Lagrange grid k interpolated along y at the row, into out. */
static void lagrange_column(const row_sources *rs, int k, int c, float out[4])
{
#if defined(__SSE2__)
    __m128 acc = _mm_setzero_ps();
    for (int r = 0; r < TAPS; r++)
        acc = _mm_add_ps(acc, _mm_mul_ps(_mm_set1_ps(rs->lagrange_wy[k][r]),
                                         _mm_loadu_ps(rs->lagrange_rows[k][r] + (ptrdiff_t)c * 4)));
    _mm_storeu_ps(out, acc);
#else
    for (int q = 0; q < 4; q++) out[q] = 0.0f;
    for (int r = 0; r < TAPS; r++)
        for (int q = 0; q < 4; q++)
            out[q] += rs->lagrange_wy[k][r] * rs->lagrange_rows[k][r][(ptrdiff_t)c * 4 + q];
#endif
}

/* floor(g) for g >= -1 (a texel centre's grid position is at least -1/2), without a call. */
static inline int floor_from_minus_one(float g) { return (int)(g + 1.0f) - 1; }

/* The first grid column Lagrange grid k reads at output column x, and the position gx. */
static int lagrange_first_column(const row_sources *rs, int k, int x, float *gx)
{
    *gx = (x + 0.5f) * rs->lagrange_scale[k] - 0.5f;
    return floor_from_minus_one(*gx) - TAP_OFFSET;
}

/* Adds Lagrange grid k at output columns x0 .. x1 - 1 of the row to sums (4 floats a column):
 * the grid columns under the span interpolated along y once (a column serves every output
 * column over it), then TAPS taps along x per output column, with the column weights of its
 * phase x % ratio. The same products, added in the same order, as a texel-by-texel 6 x 6 read
 * of the y-interpolated columns. */
static void add_lagrange_span(const row_sources *rs, int k, int x0, int x1, float (*sums)[4])
{
    float columns[LAGRANGE_SPAN_COLUMNS][4], gx;
    int first = lagrange_first_column(rs, k, x0, &gx);
    int last = lagrange_first_column(rs, k, x1 - 1, &gx) + TAPS - 1;
    for (int c = first; c <= last; c++) lagrange_column(rs, k, c, columns[c - first]);
    int ratio = rs->lagrange_ratio[k], phase = x0 % ratio;
    for (int x = x0; x < x1; x++, phase = phase + 1 == ratio ? 0 : phase + 1) {
        int ix = lagrange_first_column(rs, k, x, &gx) - first;
        float computed[TAPS];
        const float *wx = computed;
        if (ratio <= LAGRANGE_PHASES) wx = rs->lagrange_wx[k][phase];
        else lagrange_weights(gx - floorf(gx), computed);
        float *v = sums[x - x0];
#if defined(__SSE2__)
        __m128 acc = _mm_loadu_ps(v);
        for (int q = 0; q < TAPS; q++)
            acc = _mm_add_ps(acc, _mm_mul_ps(_mm_set1_ps(wx[q]), _mm_loadu_ps(columns[ix + q])));
        _mm_storeu_ps(v, acc);
#else
        for (int q = 0; q < TAPS; q++)
            for (int c = 0; c < 4; c++) v[c] += wx[q] * columns[ix + q][c];
#endif
    }
}

/* The sums of the grids at output column x of the row, added to v: the grid at the output
 * texels and the bilinear grids read by rows. */
static void add_texel_grids(const row_sources *rs, int n, int face, int y, int x, float v[4])
{
    if (rs->at_output) {
        const float *a = rs->at_output->sums + (((size_t)face * n + y) * n + x) * 4;
        for (int c = 0; c < 4; c++) v[c] = a[c];
    }
#if defined(__SSE2__)
    __m128 acc = _mm_loadu_ps(v);
    for (int k = 0; k < rs->row_count; k++) {
        float gx = (x + 0.5f) * rs->scale[k] - 0.5f;
        int ix = floor_from_minus_one(gx);
        const float *a = rs->rows[k][0] + (ptrdiff_t)ix * 4, *b = rs->rows[k][1] + (ptrdiff_t)ix * 4;
        __m128 fx = _mm_set1_ps(gx - ix), a0 = _mm_loadu_ps(a), b0 = _mm_loadu_ps(b);
        __m128 top = _mm_add_ps(a0, _mm_mul_ps(fx, _mm_sub_ps(_mm_loadu_ps(a + 4), a0)));
        __m128 bot = _mm_add_ps(b0, _mm_mul_ps(fx, _mm_sub_ps(_mm_loadu_ps(b + 4), b0)));
        acc = _mm_add_ps(acc, _mm_add_ps(top, _mm_mul_ps(_mm_set1_ps(rs->fy[k]), _mm_sub_ps(bot, top))));
    }
    _mm_storeu_ps(v, acc);
#else
    for (int k = 0; k < rs->row_count; k++) {
        float gx = (x + 0.5f) * rs->scale[k] - 0.5f;
        int ix = floor_from_minus_one(gx);
        float fx = gx - ix;
        const float *a = rs->rows[k][0] + (ptrdiff_t)ix * 4, *b = rs->rows[k][1] + (ptrdiff_t)ix * 4;
        for (int c = 0; c < 4; c++) {
            float top = a[c] + fx * (a[4 + c] - a[c]);
            float bot = b[c] + fx * (b[4 + c] - b[c]);
            v[c] += top + rs->fy[k] * (bot - top);
        }
    }
#endif
}

/* The grids sampled by direction (edge fixups, or grids that do not divide the level's edge) at
 * output column x of the row, added to v. */
static void add_sampled_grids(const ibl_specular_plan *p, const level_plan *lv,
                              const row_sources *rs, int n, int face, int y, int x, float v[4])
{
    double d[3];
    ibl__output_direction(&p->desc, &lv->lobe, face, n, x, y, d);
    ibl_vec3 dv = {(float)d[0], (float)d[1], (float)d[2]};
    for (int k = 0; k < rs->sampled_count; k++) {
        const sum_grid *gr = &lv->grids[rs->sampled[k]];
        ibl_cubemap cube = {gr->edge, 1, gr->sums, 0};
        float s4[4];
        ibl_cubemap_sample_bilinear(&cube, 0, dv, s4);
        for (int c = 0; c < 4; c++) v[c] += s4[c];
    }
}

/* Row `index` (face n + y) of the output level, LAGRANGE_SPAN texels at a time: the grids read
 * by rows, then the Lagrange grids over the span, then the grids sampled by direction (every
 * texel adds them in that order). */
static void combine_task(void *arg, int index)
{
    const combine_job *job = arg;
    const ibl_specular_plan *p = job->p;
    const level_plan *lv = &p->levels[job->level];
    int n = ibl_level_size(p->output_edge, job->level), face = index / n, y = index % n;
    float *row = ibl_cubemap_face(job->dst, job->level, face) + (size_t)y * n * 4;
    row_sources rs;
    row_sources_of(p, lv, n, face, y, &rs);
    for (int x0 = 0; x0 < n; x0 += LAGRANGE_SPAN) {
        int x1 = x0 + LAGRANGE_SPAN < n ? x0 + LAGRANGE_SPAN : n;
        float sums[LAGRANGE_SPAN][4];
        for (int x = x0; x < x1; x++) {
            float *v = sums[x - x0];
            v[0] = v[1] = v[2] = v[3] = 0.0f;
            add_texel_grids(&rs, n, face, y, x, v);
        }
        for (int k = 0; k < rs.lagrange_count; k++) add_lagrange_span(&rs, k, x0, x1, sums);
        for (int x = x0; x < x1; x++) {
            float *v = sums[x - x0];
            if (rs.sampled_count) add_sampled_grids(p, lv, &rs, n, face, y, x, v);
            float *o = row + x * 4;
            float inv = v[3] > 0 ? 1.0f / v[3] : 0.0f;
            for (int c = 0; c < 3; c++) {
                float r = v[c] * inv;
                o[c] = r > 0 ? r : 0.0f;
            }
            o[3] = 1.0f;
        }
    }
}

ibl_status ibl__fast_combine(ibl_specular_plan *p, ibl_cubemap *dst, int level)
{
    level_plan *lv = &p->levels[level];
    int made[MAX_PIECES] = {0};
    ibl_status st = IBL_OK;
    for (int g = 0; g < lv->grid_count; g++) {
        sum_grid *gr = &lv->grids[g];
        if (!gr->bordered_floats) continue;
        /* a one-shot plan's bordered copies are made here and freed after the level */
        if (!gr->bordered) {
            gr->bordered = ibl_alloc(p->ctx, gr->bordered_floats * sizeof(float));
            if (!gr->bordered) {
                st = ibl_context_status(p->ctx);
                break;
            }
            made[g] = 1;
        }
        border_job bj = {p, gr};
        ibl_parallel_for(p->ctx, 6, border_task, &bj);
        if (gr->lagrange) ibl_parallel_for(p->ctx, 6, lagrange_border_task, &bj);
    }
    if (st == IBL_OK) {
        combine_job job = {p, dst, level};
        ibl_parallel_for(p->ctx, 6 * ibl_level_size(p->output_edge, level), combine_task, &job);
    }
    for (int g = 0; g < lv->grid_count; g++)
        if (made[g]) {
            ibl_free(p->ctx, lv->grids[g].bordered);
            lv->grids[g].bordered = NULL;
        }
    return st;
}
