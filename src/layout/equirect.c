/* Equirectangular (latitude-longitude) images.
 *
 * Mapping (docs/CONVENTIONS.md): u in [0, 1] left to right, v in [0, 1] top to bottom,
 *   phi = 2 pi (u - 1/2), theta = pi v (angle from +Y),
 *   d = (sin theta sin phi, cos theta, -sin theta cos phi):
 * the centre column looks toward -Z, u = 3/4 toward +X, u = 0 and 1 toward +Z, the top row is +Y.
 *
 * To a cube: every cube texel is the solid-angle-weighted mean of k x k samples spread over
 * its footprint on the face plane (weights dA / |d|^3, the solid angle of each small cell).
 * k is chosen per texel so that consecutive samples are at most half a source row apart, so
 * every row contributes. Along a row each sample averages the source over the longitude
 * extent of its own cell (a box over whole and partial pixels), so near the poles, where a
 * texel spans many pixels of a row, every pixel is still reached; where the cell is narrower
 * than a pixel the row is interpolated linearly (wrapping around in longitude). Rows beyond
 * the poles continue on the opposite meridian (row -1 is row 0 shifted by half a turn). */
#include "layout_internal.h"

#include <math.h>
#include <string.h>

static const double PI = 3.14159265358979323846;

int ibl__equirect_dir(double u, double v, double d[3])
{
    double phi = 2.0 * PI * (u - 0.5), theta = PI * v;
    double st = sin(theta);
    d[0] = st * sin(phi);
    d[1] = cos(theta);
    d[2] = -st * cos(phi);
    return 1;
}

void ibl__equirect_uv(const double d[3], double *u, double *v)
{
    double rho = sqrt(d[0] * d[0] + d[2] * d[2]);
    *u = atan2(d[0], -d[2]) / (2.0 * PI) + 0.5;
    *v = atan2(rho, d[1]) / PI;
}

typedef struct eq_job {
    const ibl_image *im;
    double basis[6][3][3]; /* per face: major, s axis, t axis, in the picture frame */
    const float *row_mean; /* height x 4 */
    ibl_cubemap *out;
    int fixed_k;
} eq_job;

/* Row `r` (any integer: rows past a pole continue on the opposite meridian) at continuous
 * column px (pixel i covers [i, i+1)), averaged over a longitude window of w pixels. */
static void row_value(const eq_job *job, int r, double px, double w, float out[4])
{
    const ibl_image *im = job->im;
    int W = im->width, H = im->height;
    if (r < 0) {
        r = -1 - r;
        px += 0.5 * W;
    } else if (r >= H) {
        r = 2 * H - 1 - r;
        px += 0.5 * W;
    }
    if (r < 0) r = 0; /* only for absurdly thin images */
    if (r >= H) r = H - 1;
    const float *row = im->pixels + (size_t)r * W * 4;
    if (w >= W) {
        memcpy(out, job->row_mean + (size_t)r * 4, 4 * sizeof(float));
        return;
    }
    if (w <= 1.0) {
        double x = px - 0.5;
        double fl = floor(x);
        float f = (float)(x - fl);
        long i0 = (long)fl % W;
        if (i0 < 0) i0 += W;
        long i1 = i0 + 1 == W ? 0 : i0 + 1;
        const float *a = row + i0 * 4, *b = row + i1 * 4;
        for (int c = 0; c < 4; c++) out[c] = a[c] + (b[c] - a[c]) * f;
        return;
    }
    double a = px - 0.5 * w;
    a -= floor(a / W) * W;
    double b = a + w;
    long ia = (long)a, ib = (long)floor(b);
    if (ia >= W) ia = W - 1;
    if (ia == ib) {
        memcpy(out, row + ia * 4, 4 * sizeof(float));
        return;
    }
    float wa = (float)(ia + 1 - a), wb = (float)(b - ib);
    float acc[4];
    for (int c = 0; c < 4; c++) acc[c] = row[ia * 4 + c] * wa;
    long i = ia + 1 == W ? 0 : ia + 1;
    for (long n = ia + 1; n < ib; n++) {
        const float *p = row + i * 4;
        for (int c = 0; c < 4; c++) acc[c] += p[c];
        if (++i == W) i = 0;
    }
    const float *p = row + (ib % W) * 4;
    for (int c = 0; c < 4; c++) out[c] = (acc[c] + p[c] * wb) / (float)w;
}

static void eq_row_task(void *arg, int index)
{
    const eq_job *job = arg;
    int N = job->out->size, face = index / N, ty = index % N;
    int W = job->im->width, H = job->im->height;
    const double *m = job->basis[face][0], *a = job->basis[face][1], *b = job->basis[face][2];
    float *out = ibl_cubemap_face(job->out, 0, face) + (size_t)ty * N * 4;
    const double cell = 2.0 / N;            /* texel edge on the face plane */
    const double px_per_rad_u = W / (2.0 * PI), px_per_rad_v = H / PI;

    for (int tx = 0; tx < N; tx++) {
        int k = job->fixed_k;
        if (k == 0) {
            /* latitude extent of the texel in source rows, from the gradient of theta */
            double sc = -1.0 + (tx + 0.5) * cell, tc = -1.0 + (ty + 0.5) * cell;
            double d[3] = {m[0] + sc * a[0] + tc * b[0], m[1] + sc * a[1] + tc * b[1],
                           m[2] + sc * a[2] + tc * b[2]};
            double rho2 = d[0] * d[0] + d[2] * d[2], r2 = rho2 + d[1] * d[1];
            double rho = sqrt(rho2), len = sqrt(r2), ext;
            if (rho < 2.0 * cell * len) {
                /* at a pole theta is a cone: bound its change by the full gradient 1/|d| */
                ext = 2.0 / len;
            } else {
                double g[3] = {d[1] * d[0] / rho / r2, -rho / r2, d[1] * d[2] / rho / r2};
                ext = fabs(g[0] * a[0] + g[1] * a[1] + g[2] * a[2]) +
                      fabs(g[0] * b[0] + g[1] * b[1] + g[2] * b[2]);
            }
            double rows = ext * cell * px_per_rad_v;
            k = (int)ceil(2.0 * rows);
            if (k < 2) k = 2;
            if (k > 64) k = 64;
        }
        double acc[4] = {0, 0, 0, 0}, wsum = 0;
        const double sub = cell / k;
        for (int j = 0; j < k; j++) {
            double tc = -1.0 + ty * cell + (j + 0.5) * sub;
            double e[3] = {m[0] + tc * b[0], m[1] + tc * b[1], m[2] + tc * b[2]};
            for (int i = 0; i < k; i++) {
                double sc = -1.0 + tx * cell + (i + 0.5) * sub;
                double x = e[0] + sc * a[0], y = e[1] + sc * a[1], z = e[2] + sc * a[2];
                double rho2 = x * x + z * z, r2 = rho2 + y * y;
                double wt = 1.0 / (r2 * sqrt(r2));
                double rho = sqrt(rho2);
                double px = (atan2(x, -z) / (2.0 * PI) + 0.5) * W;
                double py = atan2(rho, y) / PI * H;
                /* longitude extent of this sample's cell: |grad phi . axis| * sub, both axes */
                double wpx;
                if (rho2 > 1e-300) {
                    double ga = fabs(x * a[2] - z * a[0]), gb = fabs(x * b[2] - z * b[0]);
                    wpx = (ga + gb) / rho2 * sub * px_per_rad_u;
                    if (!(wpx < W)) wpx = W;
                } else {
                    wpx = W;
                }
                double yy = py - 0.5, fl = floor(yy);
                int r0 = (int)fl;
                float f = (float)(yy - fl), v0[4], v1[4];
                row_value(job, r0, px, wpx, v0);
                row_value(job, r0 + 1, px, wpx, v1);
                for (int c = 0; c < 4; c++) acc[c] += wt * (v0[c] + (v1[c] - v0[c]) * f);
                wsum += wt;
            }
        }
        for (int c = 0; c < 4; c++) out[(size_t)tx * 4 + c] = (float)(acc[c] / wsum);
    }
}

ibl_status ibl__equirect_to_cube(ibl_context *ctx, const ibl_image *image, const ibl__frame *frame,
                                 int samples_per_axis, ibl_cubemap *out)
{
    int W = image->width, H = image->height;
    float *mean = ibl_alloc(ctx, (size_t)H * 4 * sizeof(float));
    if (!mean) return ibl_context_status(ctx);
    for (int r = 0; r < H; r++) {
        double s[4] = {0, 0, 0, 0};
        const float *p = image->pixels + (size_t)r * W * 4;
        for (int x = 0; x < W; x++)
            for (int c = 0; c < 4; c++) s[c] += p[(size_t)x * 4 + c];
        for (int c = 0; c < 4; c++) mean[(size_t)r * 4 + c] = (float)(s[c] / W);
    }
    eq_job job;
    memset(&job, 0, sizeof job);
    job.im = image;
    job.row_mean = mean;
    job.out = out;
    job.fixed_k = samples_per_axis;
    /* face axes in the picture frame: picture = M^T world */
    for (int f = 0; f < 6; f++) {
        double o[3], sx[3], tx[3];
        ibl_cube_direction_d(f, 0.5, 0.5, o);
        ibl_cube_direction_d(f, 1.0, 0.5, sx);
        ibl_cube_direction_d(f, 0.5, 1.0, tx);
        double axes[3][3];
        for (int i = 0; i < 3; i++) {
            axes[0][i] = o[i];
            axes[1][i] = sx[i] - o[i];
            axes[2][i] = tx[i] - o[i];
        }
        for (int r = 0; r < 3; r++)
            for (int i = 0; i < 3; i++)
                job.basis[f][r][i] = frame->m[0][i] * axes[r][0] + frame->m[1][i] * axes[r][1] +
                                     frame->m[2][i] * axes[r][2];
    }
    ibl_parallel_for(ctx, 6 * out->size, eq_row_task, &job);
    ibl_free(ctx, mean);
    return IBL_OK;
}
