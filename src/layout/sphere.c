/* Conversions shared by the sphere layouts: angular and octahedral pictures to a cube, and a
 * cube to any sphere layout (equirect, angular, octahedral). Both supersample each output
 * texel's footprint with enough samples that no input texel is skipped, weighting every sample
 * by the solid angle it stands for; a cube read at a coarser resolution than its own is first
 * reduced with the area-correct mip chain so that nothing aliases. */
#include "layout_internal.h"
#include "core/context_internal.h"
#include "core/numeric.h"

#include <math.h>
#include <string.h>


static int map_dir(ibl_layout layout, double u, double v, double d[3])
{
    switch (layout) {
    case IBL_LAYOUT_EQUIRECT: return ibl__equirect_dir(u, v, d);
    case IBL_LAYOUT_ANGULAR: return ibl__angular_dir(u, v, d);
    default: return ibl__octahedral_dir(u, v, d);
    }
}

static void map_uv(ibl_layout layout, const double d[3], double *u, double *v)
{
    switch (layout) {
    case IBL_LAYOUT_EQUIRECT: ibl__equirect_uv(d, u, v); break;
    case IBL_LAYOUT_ANGULAR: ibl__angular_uv(d, u, v); break;
    default: ibl__octahedral_uv(d, u, v); break;
    }
}

/* Relative solid angle per unit picture area at (u, v) with direction d. */
static double map_density(ibl_layout layout, double u, double v, const double d[3])
{
    switch (layout) {
    case IBL_LAYOUT_EQUIRECT: return sqrt(d[0] * d[0] + d[2] * d[2]); /* sin(theta) */
    case IBL_LAYOUT_ANGULAR: return ibl__angular_density(u, v);
    default: return ibl__octahedral_density(d);
    }
}

/* ---- angular / octahedral picture -> cube ---- */

typedef struct to_cube_job {
    ibl_layout layout;
    const ibl_image *im;
    double basis[6][3][3]; /* per face: major, s axis, t axis, in the picture frame */
    ibl_cubemap *out;
    int fixed_k;
} to_cube_job;

static const float *texel_addr(const to_cube_job *job, int x, int y)
{
    int W = job->im->width, H = job->im->height;
    if (job->layout == IBL_LAYOUT_OCTAHEDRAL) {
        /* across an edge the map continues mirrored (the fold): (-1, y) is (0, H-1-y) */
        if (x < 0) { x = -1 - x; y = H - 1 - y; }
        else if (x >= W) { x = 2 * W - 1 - x; y = H - 1 - y; }
        if (y < 0) { y = -1 - y; x = W - 1 - x; }
        else if (y >= H) { y = 2 * H - 1 - y; x = W - 1 - x; }
    }
    if (x < 0) x = 0;
    if (x >= W) x = W - 1;
    if (y < 0) y = 0;
    if (y >= H) y = H - 1;
    return job->im->pixels + ((size_t)y * W + x) * 4;
}

static void bilinear(const to_cube_job *job, double px, double py, float out[4])
{
    double x = px - 0.5, y = py - 0.5, fx0 = floor(x), fy0 = floor(y);
    int x0 = (int)fx0, y0 = (int)fy0;
    float fx = (float)(x - fx0), fy = (float)(y - fy0);
    const float *a = texel_addr(job, x0, y0), *b = texel_addr(job, x0 + 1, y0);
    const float *c = texel_addr(job, x0, y0 + 1), *e = texel_addr(job, x0 + 1, y0 + 1);
    for (int i = 0; i < 4; i++) {
        float top = a[i] + (b[i] - a[i]) * fx, bottom = c[i] + (e[i] - c[i]) * fx;
        out[i] = top + (bottom - top) * fy;
    }
}

static void face_point(const double (*basis)[3], double sc, double tc, double d[3])
{
    for (int i = 0; i < 3; i++) d[i] = basis[0][i] + sc * basis[1][i] + tc * basis[2][i];
}

static void to_cube_row(void *arg, int index)
{
    const to_cube_job *job = arg;
    int N = job->out->size, face = index / N, ty = index % N;
    int W = job->im->width, H = job->im->height;
    const double(*basis)[3] = job->basis[face];
    float *out = ibl_cubemap_face(job->out, 0, face) + (size_t)ty * N * 4;
    const double cell = 2.0 / N;
    double prev_u = 0, prev_v = 0, prev_u1 = 0, prev_v1 = 0;
    for (int tx = 0; tx < N; tx++) {
        int k = job->fixed_k;
        /* footprint: bounding box of the texel's corners in source pixels */
        double cu[2], cv[2], cu1[2], cv1[2];
        for (int side = 0; side < 2; side++) {
            if (side == 0 && tx > 0) {
                cu[0] = prev_u; cv[0] = prev_v; cu1[0] = prev_u1; cv1[0] = prev_v1;
                continue;
            }
            double d[3], len, n[3];
            double sc = -1.0 + (tx + side) * cell;
            face_point(basis, sc, -1.0 + ty * cell, d);
            len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            for (int i = 0; i < 3; i++) n[i] = d[i] / len;
            map_uv(job->layout, n, &cu[side], &cv[side]);
            face_point(basis, sc, -1.0 + (ty + 1) * cell, d);
            len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            for (int i = 0; i < 3; i++) n[i] = d[i] / len;
            map_uv(job->layout, n, &cu1[side], &cv1[side]);
        }
        prev_u = cu[1]; prev_v = cv[1]; prev_u1 = cu1[1]; prev_v1 = cv1[1];
        if (k == 0) {
            double umin = fmin(fmin(cu[0], cu[1]), fmin(cu1[0], cu1[1]));
            double umax = fmax(fmax(cu[0], cu[1]), fmax(cu1[0], cu1[1]));
            double vmin = fmin(fmin(cv[0], cv[1]), fmin(cv1[0], cv1[1]));
            double vmax = fmax(fmax(cv[0], cv[1]), fmax(cv1[0], cv1[1]));
            double ext = fmax((umax - umin) * W, (vmax - vmin) * H);
            /* samples at most half a source pixel apart; capped where the map is singular
             * (the rim of the angular map, the folds of the octahedron) */
            k = (int)ceil(2.0 * ext);
            if (k < 2) k = 2;
            if (k > 24) k = 24;
        }
        double acc[4] = {0, 0, 0, 0}, wsum = 0;
        const double sub = cell / k;
        for (int j = 0; j < k; j++) {
            double tc = -1.0 + ty * cell + (j + 0.5) * sub;
            for (int i = 0; i < k; i++) {
                double sc = -1.0 + tx * cell + (i + 0.5) * sub, d[3], u, v;
                face_point(basis, sc, tc, d);
                double r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2], len = sqrt(r2);
                double wt = 1.0 / (r2 * len);
                for (int c = 0; c < 3; c++) d[c] /= len;
                map_uv(job->layout, d, &u, &v);
                float val[4];
                bilinear(job, u * W, v * H, val);
                for (int c = 0; c < 4; c++) acc[c] += wt * val[c];
                wsum += wt;
            }
        }
        for (int c = 0; c < 4; c++) out[(size_t)tx * 4 + c] = (float)(acc[c] / wsum);
    }
}

void ibl__picture_basis(const ibl__frame *frame, double basis[6][3][3])
{
    for (int f = 0; f < 6; f++) {
        double o[3], sx[3], tx[3], axes[3][3];
        ibl_cube_direction_d(f, 0.5, 0.5, o);
        ibl_cube_direction_d(f, 1.0, 0.5, sx);
        ibl_cube_direction_d(f, 0.5, 1.0, tx);
        for (int i = 0; i < 3; i++) {
            axes[0][i] = o[i];
            axes[1][i] = sx[i] - o[i];
            axes[2][i] = tx[i] - o[i];
        }
        /* picture = M^T world */
        for (int r = 0; r < 3; r++)
            for (int i = 0; i < 3; i++)
                basis[f][r][i] = frame->m[0][i] * axes[r][0] + frame->m[1][i] * axes[r][1] +
                                 frame->m[2][i] * axes[r][2];
    }
}

ibl_status ibl__sphere_to_cube(ibl_context *ctx, ibl_layout layout, const ibl_image *image,
                               const ibl__frame *frame, int samples_per_axis, ibl_cubemap *out)
{
    to_cube_job job;
    memset(&job, 0, sizeof job);
    job.layout = layout;
    job.im = image;
    ibl_image padded = {0, 0, NULL};
    if (layout == IBL_LAYOUT_ANGULAR) {
        /* bilinear taps at the rim must not read the unused corners: continue the disk
         * outward (each outside pixel takes the nearest pixel inside along its radius) */
        int W = image->width, H = image->height;
        ibl_status st = ibl_image_alloc(ctx, W, H, &padded);
        if (st != IBL_OK) return st;
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++) {
                double a = 2.0 * (x + 0.5) / W - 1.0, b = 2.0 * (y + 0.5) / H - 1.0;
                double r = sqrt(a * a + b * b);
                int sx = x, sy = y;
                for (double rr = 1.0 - 1.0 / W; r > 1.0 && rr > 0.0; rr -= 1.0 / W) {
                    sx = (int)floor((a / r * rr + 1.0) * 0.5 * W);
                    sy = (int)floor((b / r * rr + 1.0) * 0.5 * H);
                    double ca = 2.0 * (sx + 0.5) / W - 1.0, cb = 2.0 * (sy + 0.5) / H - 1.0;
                    if (ca * ca + cb * cb <= 1.0) break;
                }
                memcpy(ibl_image_texel(&padded, x, y), ibl_image_texel(image, sx, sy),
                       4 * sizeof(float));
            }
        job.im = &padded;
    }
    job.out = out;
    job.fixed_k = samples_per_axis;
    ibl__picture_basis(frame, job.basis);
    ibl_parallel_for(ctx, 6 * out->size, to_cube_row, &job);
    ibl_image_free(ctx, &padded);
    return IBL_OK;
}

/* ---- cube -> sphere layout ---- */

typedef struct from_cube_job {
    ibl_layout layout;
    const ibl_cubemap *cube; /* level 0 is the source; more levels when reducing */
    const ibl__frame *frame; /* world = M picture */
    ibl_image *out;
    int fixed_k;
} from_cube_job;

static void unit_dir_clamped(ibl_layout layout, double u, double v, double d[3])
{
    if (layout == IBL_LAYOUT_ANGULAR) {
        double a = 2.0 * u - 1.0, b = 2.0 * v - 1.0, r = sqrt(a * a + b * b);
        if (r > 1.0) {
            u = 0.5 * (a / r + 1.0);
            v = 0.5 * (b / r + 1.0);
        }
    }
    if (!map_dir(layout, u, v, d)) {
        d[0] = 0;
        d[1] = 0;
        d[2] = 1;
    }
}

static double chord(const double a[3], const double b[3])
{
    double x = a[0] - b[0], y = a[1] - b[1], z = a[2] - b[2];
    return sqrt(x * x + y * y + z * z);
}

static void from_cube_row(void *arg, int y)
{
    const from_cube_job *job = arg;
    int W = job->out->width, H = job->out->height;
    const ibl_cubemap *cube = job->cube;
    float *row = job->out->pixels + (size_t)y * W * 4;
    double v0 = (double)y / H, v1 = (double)(y + 1) / H;
    double top[3], bottom[3], next_top[3], next_bottom[3];
    unit_dir_clamped(job->layout, 0.0, v0, top);
    unit_dir_clamped(job->layout, 0.0, v1, bottom);
    for (int x = 0; x < W; x++, row += 4) {
        double u0 = (double)x / W, u1 = (double)(x + 1) / W, centre[3];
        unit_dir_clamped(job->layout, u1, v0, next_top);
        unit_dir_clamped(job->layout, u1, v1, next_bottom);
        int kx = job->fixed_k, ky = job->fixed_k, level = 0;
        if (kx == 0) {
            /* angular size of the pixel along each axis (chords of its edges) */
            double ex = fmax(chord(top, next_top), chord(bottom, next_bottom));
            double ey = fmax(chord(top, bottom), chord(next_top, next_bottom));
            double big = fmax(ex, ey);
            /* the coarsest level whose texels (about pi/2/n radians) are no wider than the
             * pixel's long side, then samples half a texel apart along each axis */
            while (level + 1 < cube->levels &&
                   IBL_PI / 2.0 / ibl_level_size(cube->size, level + 1) <= big)
                level++;
            double texel = IBL_PI / 2.0 / ibl_level_size(cube->size, level);
            kx = (int)ceil(2.0 * ex / texel);
            ky = (int)ceil(2.0 * ey / texel);
            if (kx < 1) kx = 1;
            if (ky < 1) ky = 1;
            if (kx > 16) kx = 16;
            if (ky > 16) ky = 16;
        }
        memcpy(top, next_top, sizeof top);
        memcpy(bottom, next_bottom, sizeof bottom);
        double acc[4] = {0, 0, 0, 0}, wsum = 0;
        for (int j = 0; j < ky; j++) {
            double v = v0 + (v1 - v0) * (j + 0.5) / ky;
            for (int i = 0; i < kx; i++) {
                double u = u0 + (u1 - u0) * (i + 0.5) / kx, p[3], w[3];
                if (!map_dir(job->layout, u, v, p)) continue;
                double wt = map_density(job->layout, u, v, p);
                if (!(wt > 0.0)) continue;
                ibl__mul3(job->frame->m, p, w);
                ibl_vec3 dir = {(float)w[0], (float)w[1], (float)w[2]};
                float c[4];
                ibl_cubemap_sample_bilinear(cube, level, dir, c);
                for (int ch = 0; ch < 4; ch++) acc[ch] += wt * c[ch];
                wsum += wt;
            }
        }
        if (wsum > 0.0) {
            for (int ch = 0; ch < 4; ch++) row[ch] = (float)(acc[ch] / wsum);
        } else if (map_dir(job->layout, 0.5 * (u0 + u1), 0.5 * (v0 + v1), centre)) {
            double w[3];
            ibl__mul3(job->frame->m, centre, w);
            ibl_vec3 dir = {(float)w[0], (float)w[1], (float)w[2]};
            ibl_cubemap_sample_bilinear(cube, level, dir, row);
        } else {
            /* outside the angular map's disk: transparent black */
            memset(row, 0, 4 * sizeof(float));
        }
    }
}

ibl_status ibl__cube_to_sphere(ibl_context *ctx, const ibl_cubemap *cube, int level,
                               ibl_layout layout, const ibl__frame *frame, int samples_per_axis,
                               ibl_image *out)
{
    int n = ibl_level_size(cube->size, level);
    /* the output's pixel pitch in radians, roughly, against the cube's texel pitch */
    double pitch = layout == IBL_LAYOUT_EQUIRECT ? IBL_PI / out->height
                 : layout == IBL_LAYOUT_ANGULAR ? 2.0 * IBL_PI / out->width
                                                : IBL_PI / out->width;
    ibl_cubemap chain;
    memset(&chain, 0, sizeof chain);
    ibl_status st;
    int levels = 1;
    if (samples_per_axis == 0) {
        while (levels < ibl_full_mip_count(n) && IBL_PI / 2.0 / ibl_level_size(n, levels) <= pitch)
            levels++;
    }
    if (levels > 1) {
        st = ibl_cubemap_alloc(ctx, n, levels, &chain);
        if (st != IBL_OK) return st;
        memcpy(chain.data, ibl_cubemap_face(cube, level, 0), (size_t)6 * n * n * 4 * sizeof(float));
        st = ibl_cubemap_build_mips(ctx, &chain);
        if (st != IBL_OK) {
            ibl_cubemap_free(ctx, &chain);
            return st;
        }
    } else {
        st = ibl_cubemap_wrap(n, 1, ibl_cubemap_face(cube, level, 0), &chain);
        if (st != IBL_OK) return ibl__fail(ctx, st, "layout: bad cubemap level");
    }
    from_cube_job job = {layout, &chain, frame, out, samples_per_axis};
    ibl_parallel_for(ctx, out->height, from_cube_row, &job);
    ibl_cubemap_free(ctx, &chain);
    return IBL_OK;
}
