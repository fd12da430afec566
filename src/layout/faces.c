/* Moving faces between cube-layout pictures (crosses, strips) and cubes, and re-orienting a
 * cube (used for --yaw / --mirror / --z-up on cube layouts). */
#include "layout_internal.h"

#include <math.h>
#include <string.h>

static int cell_of(ibl_layout layout, int face, int *col, int *row, int *rot)
{
    return ibl__cross_cell(layout, face, col, row, rot) || ibl__strip_cell(layout, face, col, row, rot);
}

/* Copies one n x n cell; rot 180 reverses both axes. to_cube selects the direction. */
static void copy_cell(float *cube_face, float *pic, size_t pic_stride, int n, int rot, int to_cube)
{
    for (int y = 0; y < n; y++) {
        for (int x = 0; x < n; x++) {
            int fx = rot ? n - 1 - x : x, fy = rot ? n - 1 - y : y;
            float *c = cube_face + ((size_t)fy * n + fx) * 4;
            float *p = pic + (size_t)y * pic_stride + (size_t)x * 4;
            if (to_cube) memcpy(c, p, 4 * sizeof(float));
            else memcpy(p, c, 4 * sizeof(float));
        }
    }
}

void ibl__cells_to_cube(ibl_layout layout, const ibl_image *image, ibl_cubemap *cube)
{
    int n = cube->size;
    size_t stride = (size_t)image->width * 4;
    for (int f = 0; f < 6; f++) {
        int col, row, rot;
        if (!cell_of(layout, f, &col, &row, &rot)) continue;
        float *origin = image->pixels + (size_t)row * n * stride + (size_t)col * n * 4;
        copy_cell(ibl_cubemap_face(cube, 0, f), origin, stride, n, rot, 1);
    }
}

void ibl__cube_to_cells(ibl_layout layout, const ibl_cubemap *cube, int level, ibl_image *image)
{
    int n = ibl_level_size(cube->size, level);
    size_t stride = (size_t)image->width * 4;
    /* cells no face occupies stay transparent black */
    memset(image->pixels, 0, (size_t)image->height * stride * sizeof(float));
    for (int f = 0; f < 6; f++) {
        int col, row, rot;
        if (!cell_of(layout, f, &col, &row, &rot)) continue;
        float *origin = image->pixels + (size_t)row * n * stride + (size_t)col * n * 4;
        copy_cell(ibl_cubemap_face(cube, level, f), origin, stride, n, rot, 0);
    }
}

typedef struct remap_job {
    const ibl_cubemap *src;
    int level;
    const ibl__frame *m;
    ibl_cubemap *dst;
    int k; /* samples per axis; 0: nearest at the texel centre */
} remap_job;

static void remap_row(void *arg, int index)
{
    const remap_job *job = arg;
    int n = job->dst->size, face = index / n, y = index % n, k = job->k;
    float *row = ibl_cubemap_face(job->dst, 0, face) + (size_t)y * n * 4;
    for (int x = 0; x < n; x++) {
        float *o = row + (size_t)x * 4;
        if (k == 0) {
            double d[3], w[3];
            ibl_cube_direction_d(face, (x + 0.5) / n, (y + 0.5) / n, d);
            ibl__mul3(job->m->m, d, w);
            ibl_vec3 v = {(float)w[0], (float)w[1], (float)w[2]};
            ibl_cubemap_sample_nearest(job->src, job->level, v, o);
            continue;
        }
        double acc[4] = {0, 0, 0, 0}, wsum = 0;
        for (int j = 0; j < k; j++) {
            for (int i = 0; i < k; i++) {
                double d[3], w[3];
                ibl_cube_direction_d(face, (x + (i + 0.5) / k) / n, (y + (j + 0.5) / k) / n, d);
                double r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
                /* solid angle of a small face-plane cell: dA / |d|^3 */
                double wt = 1.0 / (r2 * sqrt(r2));
                ibl__mul3(job->m->m, d, w);
                ibl_vec3 v = {(float)w[0], (float)w[1], (float)w[2]};
                float c[4];
                ibl_cubemap_sample_bilinear(job->src, job->level, v, c);
                for (int ch = 0; ch < 4; ch++) acc[ch] += wt * c[ch];
                wsum += wt;
            }
        }
        for (int ch = 0; ch < 4; ch++) o[ch] = (float)(acc[ch] / wsum);
    }
}

ibl_status ibl__cube_remap(ibl_context *ctx, const ibl_cubemap *src, int level,
                           const ibl__frame *m, ibl_cubemap *dst)
{
    int sn = ibl_level_size(src->size, level), n = dst->size;
    remap_job job = {src, level, m, dst, 0};
    if (!(m->permutation && sn == n)) {
        /* enough samples that every source texel is reached when shrinking */
        int ratio = (sn + n - 1) / n;
        job.k = 2 * ratio;
        if (job.k > 32) job.k = 32;
    }
    ibl_parallel_for(ctx, 6 * n, remap_row, &job);
    return IBL_OK;
}
