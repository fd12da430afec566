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
 * constant environment constant. */
#include "bake/specular/fast_internal.h"

#include <math.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

typedef struct border_job {
    const ibl_specular_plan *p;
    sum_grid *grid;
} border_job;

/* Face f of a coarse grid's bordered copy. */
static void border_task(void *arg, int f)
{
    const border_job *j = arg;
    sum_grid *gr = j->grid;
    int n = gr->edge, m = n + 2;
    float *out = gr->bordered + (size_t)f * m * m * 4;
    for (int Y = -1; Y <= n; Y++)
        for (int X = -1; X <= n; X++) {
            float *o = out + ((size_t)(Y + 1) * m + X + 1) * 4;
            int ox = X < 0 || X >= n, oy = Y < 0 || Y >= n;
            if (ox && oy) { /* a cube corner: the mean of the three texels around it */
                int cx = X < 0 ? 0 : n - 1, cy = Y < 0 ? 0 : n - 1;
                int32_t t[3] = {ibl__fast_unfolded_texel(j->p, n, f, cx, cy),
                                ibl__fast_unfolded_texel(j->p, n, f, X, cy),
                                ibl__fast_unfolded_texel(j->p, n, f, cx, Y)};
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

typedef struct combine_job {
    const ibl_specular_plan *p;
    ibl_cubemap *dst;
    int level;
} combine_job;

/* How an output row reads the level's grids: the one at the output texels, the coarse grids
 * read by rows of their bordered copies, and those sampled by direction. */
typedef struct row_sources {
    const sum_grid *at_output;
    const float *rows[MAX_PIECES][2]; /* the two bordered rows under the output row        */
    float fy[MAX_PIECES], scale[MAX_PIECES];
    int sampled[MAX_PIECES], row_count, sampled_count;
} row_sources;

static void row_sources_of(const ibl_specular_plan *p, const level_plan *lv, int n, int face,
                           int y, row_sources *rs)
{
    int centred = centred_directions(p);
    rs->at_output = NULL;
    rs->row_count = rs->sampled_count = 0;
    for (int g = 0; g < lv->grid_count; g++) {
        const sum_grid *gr = &lv->grids[g];
        int gn = gr->edge;
        if (gr->at_output) {
            rs->at_output = gr;
        } else if (centred && n % gn == 0) {
            /* the texel centre's bilinear footprint on the bordered grid (it never leaves it:
             * gx is in [-1/2, gn - 1/2]) */
            float gy = (y + 0.5f) * gn / n - 0.5f;
            int iy = (int)floorf(gy), k = rs->row_count++;
            rs->rows[k][0] = gr->bordered + (((size_t)face * (gn + 2) + iy + 1) * (gn + 2) + 1) * 4;
            rs->rows[k][1] = rs->rows[k][0] + (size_t)(gn + 2) * 4;
            rs->fy[k] = gy - iy;
            rs->scale[k] = (float)gn / n;
        } else {
            rs->sampled[rs->sampled_count++] = g;
        }
    }
}

/* Row `index` (face n + y) of the output level. */
static void combine_task(void *arg, int index)
{
    const combine_job *job = arg;
    const ibl_specular_plan *p = job->p;
    const level_plan *lv = &p->levels[job->level];
    int n = ibl_level_size(p->output_edge, job->level), face = index / n, y = index % n;
    float *row = ibl_cubemap_face(job->dst, job->level, face) + (size_t)y * n * 4;
    row_sources rs;
    row_sources_of(p, lv, n, face, y, &rs);
    for (int x = 0; x < n; x++) {
        float v[4] = {0, 0, 0, 0};
        if (rs.at_output) {
            const float *a = rs.at_output->sums + (((size_t)face * n + y) * n + x) * 4;
            for (int c = 0; c < 4; c++) v[c] = a[c];
        }
#if defined(__SSE2__)
        __m128 acc = _mm_loadu_ps(v);
        for (int k = 0; k < rs.row_count; k++) {
            float gx = (x + 0.5f) * rs.scale[k] - 0.5f;
            int ix = (int)floorf(gx);
            const float *a = rs.rows[k][0] + (ptrdiff_t)ix * 4, *b = rs.rows[k][1] + (ptrdiff_t)ix * 4;
            __m128 fx = _mm_set1_ps(gx - ix), a0 = _mm_loadu_ps(a), b0 = _mm_loadu_ps(b);
            __m128 top = _mm_add_ps(a0, _mm_mul_ps(fx, _mm_sub_ps(_mm_loadu_ps(a + 4), a0)));
            __m128 bot = _mm_add_ps(b0, _mm_mul_ps(fx, _mm_sub_ps(_mm_loadu_ps(b + 4), b0)));
            acc = _mm_add_ps(acc, _mm_add_ps(top, _mm_mul_ps(_mm_set1_ps(rs.fy[k]), _mm_sub_ps(bot, top))));
        }
        _mm_storeu_ps(v, acc);
#else
        for (int k = 0; k < rs.row_count; k++) {
            float gx = (x + 0.5f) * rs.scale[k] - 0.5f;
            int ix = (int)floorf(gx);
            float fx = gx - ix;
            const float *a = rs.rows[k][0] + (ptrdiff_t)ix * 4, *b = rs.rows[k][1] + (ptrdiff_t)ix * 4;
            for (int c = 0; c < 4; c++) {
                float top = a[c] + fx * (a[4 + c] - a[c]);
                float bot = b[c] + fx * (b[4 + c] - b[c]);
                v[c] += top + rs.fy[k] * (bot - top);
            }
        }
#endif
        if (rs.sampled_count) {
            double d[3];
            ibl__output_direction(&p->desc, &lv->lobe, face, n, x, y, d);
            ibl_vec3 dv = {(float)d[0], (float)d[1], (float)d[2]};
            for (int k = 0; k < rs.sampled_count; k++) {
                const sum_grid *gr = &lv->grids[rs.sampled[k]];
                ibl_cubemap cube = {gr->edge, 1, gr->sums, 0};
                float s4[4];
                ibl_cubemap_sample_bilinear(&cube, 0, dv, s4);
                for (int c = 0; c < 4; c++) v[c] += s4[c];
            }
        }
        float *o = row + x * 4;
        float inv = v[3] > 0 ? 1.0f / v[3] : 0.0f;
        for (int c = 0; c < 3; c++) {
            float r = v[c] * inv;
            o[c] = r > 0 ? r : 0.0f;
        }
        o[3] = 1.0f;
    }
}

void ibl__fast_combine(ibl_specular_plan *p, ibl_cubemap *dst, int level)
{
    level_plan *lv = &p->levels[level];
    for (int g = 0; g < lv->grid_count; g++) {
        if (!lv->grids[g].bordered) continue;
        border_job bj = {p, &lv->grids[g]};
        ibl_parallel_for(p->ctx, 6, border_task, &bj);
    }
    combine_job job = {p, dst, level};
    ibl_parallel_for(p->ctx, 6 * ibl_level_size(p->output_edge, level), combine_task, &job);
}
