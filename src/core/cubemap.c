/* Cube geometry, exact texel solid angles, seamless sampling and the area-correct mip chain.
 * Face orientation: OpenGL 4.6 / Vulkan "cube map face selection" table (docs/CONVENTIONS.md). */
#include "ibl/cubemap.h"

#include <math.h>
#include <string.h>

/* Per face: direction = major * axis + sc * s_axis + tc * t_axis, with sc, tc in [-1, 1]. */
static const double face_basis[6][3][3] = {
    /* major axis      s axis (sc)     t axis (tc) */
    {{+1, 0, 0}, {0, 0, -1}, {0, -1, 0}}, /* +X: sc = -rz, tc = -ry */
    {{-1, 0, 0}, {0, 0, +1}, {0, -1, 0}}, /* -X: sc = +rz, tc = -ry */
    {{0, +1, 0}, {+1, 0, 0}, {0, 0, +1}}, /* +Y: sc = +rx, tc = +rz */
    {{0, -1, 0}, {+1, 0, 0}, {0, 0, -1}}, /* -Y: sc = +rx, tc = -rz */
    {{0, 0, +1}, {+1, 0, 0}, {0, -1, 0}}, /* +Z: sc = +rx, tc = -ry */
    {{0, 0, -1}, {-1, 0, 0}, {0, -1, 0}}, /* -Z: sc = -rx, tc = -ry */
};

void ibl_cube_direction_d(int face, double s, double t, double dir[3])
{
    double sc = 2.0 * s - 1.0, tc = 2.0 * t - 1.0;
    const double(*b)[3] = face_basis[face];
    for (int i = 0; i < 3; i++) dir[i] = b[0][i] + sc * b[1][i] + tc * b[2][i];
}

ibl_vec3 ibl_cube_direction(int face, float s, float t)
{
    float sc = 2.0f * s - 1.0f, tc = 2.0f * t - 1.0f;
    const double(*b)[3] = face_basis[face];
    ibl_vec3 d = {(float)b[0][0] + sc * (float)b[1][0] + tc * (float)b[2][0],
                  (float)b[0][1] + sc * (float)b[1][1] + tc * (float)b[2][1],
                  (float)b[0][2] + sc * (float)b[1][2] + tc * (float)b[2][2]};
    return d;
}

int ibl_cube_face_st_d(const double d[3], double *s, double *t)
{
    double ax = fabs(d[0]), ay = fabs(d[1]), az = fabs(d[2]);
    int face;
    double ma, sc, tc;
    /* ties go to the lower axis: x before y before z, as the GL table is usually read */
    if (ax >= ay && ax >= az) {
        face = d[0] >= 0 ? IBL_FACE_POS_X : IBL_FACE_NEG_X;
        ma = ax;
        sc = d[0] >= 0 ? -d[2] : d[2];
        tc = -d[1];
    } else if (ay >= az) {
        face = d[1] >= 0 ? IBL_FACE_POS_Y : IBL_FACE_NEG_Y;
        ma = ay;
        sc = d[0];
        tc = d[1] >= 0 ? d[2] : -d[2];
    } else {
        face = d[2] >= 0 ? IBL_FACE_POS_Z : IBL_FACE_NEG_Z;
        ma = az;
        sc = d[2] >= 0 ? d[0] : -d[0];
        tc = -d[1];
    }
    if (ma == 0.0) ma = 1.0;
    *s = 0.5 * (sc / ma + 1.0);
    *t = 0.5 * (tc / ma + 1.0);
    return face;
}

int ibl_cube_face_st(ibl_vec3 d, float *s, float *t)
{
    float ax = fabsf(d.x), ay = fabsf(d.y), az = fabsf(d.z);
    int face;
    float ma, sc, tc;
    if (ax >= ay && ax >= az) {
        face = d.x >= 0 ? IBL_FACE_POS_X : IBL_FACE_NEG_X;
        ma = ax;
        sc = d.x >= 0 ? -d.z : d.z;
        tc = -d.y;
    } else if (ay >= az) {
        face = d.y >= 0 ? IBL_FACE_POS_Y : IBL_FACE_NEG_Y;
        ma = ay;
        sc = d.x;
        tc = d.y >= 0 ? d.z : -d.z;
    } else {
        face = d.z >= 0 ? IBL_FACE_POS_Z : IBL_FACE_NEG_Z;
        ma = az;
        sc = d.z >= 0 ? d.x : -d.x;
        tc = -d.y;
    }
    if (ma == 0.0f) ma = 1.0f;
    float inv = 0.5f / ma;
    *s = sc * inv + 0.5f;
    *t = tc * inv + 0.5f;
    return face;
}

ibl_vec3 ibl_cube_texel_direction(int face, int n, int x, int y)
{
    double d[3];
    ibl_cube_direction_d(face, (x + 0.5) / n, (y + 0.5) / n, d);
    double len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    ibl_vec3 v = {(float)(d[0] / len), (float)(d[1] / len), (float)(d[2] / len)};
    return v;
}

/* Solid angle of the face-plane rectangle [0,u] x [0,v] at unit distance: atan(uv / sqrt(1 +
 * u^2 + v^2)) (the spherical-quadrilateral area; Driscoll 2012, "Cubemap texel solid angle"). */
static double corner_area(double u, double v)
{
    return atan2(u * v, sqrt(u * u + v * v + 1.0));
}

double ibl_cube_rect_solid_angle(double u0, double v0, double u1, double v1)
{
    return corner_area(u1, v1) - corner_area(u0, v1) - corner_area(u1, v0) + corner_area(u0, v0);
}

double ibl_cube_texel_solid_angle(int n, int x, int y)
{
    double inv = 2.0 / n;
    double u0 = x * inv - 1.0, v0 = y * inv - 1.0;
    /* the far edge from the integer grid too, so that neighbours share their edges exactly */
    double u1 = (x + 1) * inv - 1.0, v1 = (y + 1) * inv - 1.0;
    return ibl_cube_rect_solid_angle(u0, v0, u1, v1);
}

void ibl_cube_solid_angle_table(int n, float *out)
{
    for (int y = 0; y < n; y++)
        for (int x = 0; x < n; x++) out[(size_t)y * n + x] = (float)ibl_cube_texel_solid_angle(n, x, y);
}

/* ---- sampling ---- */

static const float *texel_at(const ibl_cubemap *cube, int level, int face, int x, int y)
{
    int n = ibl_level_size(cube->size, level);
    return ibl_cubemap_face(cube, level, face) + ((size_t)y * n + x) * 4;
}

/* The texel that continues face `face` past its edge at integer coordinates (x, y) just
 * outside [0, n): found by projecting that texel's centre onto the cube. */
static const float *texel_across_edge(const ibl_cubemap *cube, int level, int face, int n, int x,
                                      int y)
{
    double d[3], s, t;
    ibl_cube_direction_d(face, (x + 0.5) / n, (y + 0.5) / n, d);
    int f = ibl_cube_face_st_d(d, &s, &t);
    int xi = (int)floor(s * n), yi = (int)floor(t * n);
    if (xi < 0) xi = 0;
    if (xi >= n) xi = n - 1;
    if (yi < 0) yi = 0;
    if (yi >= n) yi = n - 1;
    return texel_at(cube, level, f, xi, yi);
}

void ibl_cubemap_sample_bilinear(const ibl_cubemap *cube, int level, ibl_vec3 dir, float out[4])
{
    if (level < 0) level = 0;
    if (level >= cube->levels) level = cube->levels - 1;
    float s, t;
    int face = ibl_cube_face_st(dir, &s, &t);
    int n = ibl_level_size(cube->size, level);
    float px = s * n - 0.5f, py = t * n - 0.5f;
    float fx0 = floorf(px), fy0 = floorf(py);
    float fx = px - fx0, fy = py - fy0;
    int x0 = (int)fx0, y0 = (int)fy0;
    if (x0 >= 0 && y0 >= 0 && x0 + 1 < n && y0 + 1 < n) {
        const float *a = texel_at(cube, level, face, x0, y0);
        const float *b = a + 4;
        const float *c = a + (size_t)n * 4;
        const float *e = c + 4;
        for (int i = 0; i < 4; i++) {
            float top = a[i] + (b[i] - a[i]) * fx;
            float bottom = c[i] + (e[i] - c[i]) * fx;
            out[i] = top + (bottom - top) * fy;
        }
        return;
    }
    const float *tap[4];
    int outside[4];
    for (int k = 0; k < 4; k++) {
        int x = x0 + (k & 1), y = y0 + (k >> 1);
        int ox = x < 0 || x >= n, oy = y < 0 || y >= n;
        outside[k] = ox && oy;
        if (!ox && !oy) tap[k] = texel_at(cube, level, face, x, y);
        else if (ox != oy) tap[k] = texel_across_edge(cube, level, face, n, x, y);
        else tap[k] = NULL; /* beyond a cube corner: no such texel */
    }
    float w[4] = {(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy};
    float corner[4] = {0, 0, 0, 0};
    for (int k = 0; k < 4; k++) {
        if (!outside[k]) continue;
        /* three texels meet at a cube corner: the missing fourth is their mean */
        for (int j = 0; j < 4; j++)
            if (j != k)
                for (int i = 0; i < 4; i++) corner[i] += tap[j][i] * (1.0f / 3.0f);
    }
    for (int i = 0; i < 4; i++) {
        float v = 0;
        for (int k = 0; k < 4; k++) v += w[k] * (outside[k] ? corner[i] : tap[k][i]);
        out[i] = v;
    }
}

void ibl_cubemap_sample_nearest(const ibl_cubemap *cube, int level, ibl_vec3 dir, float out[4])
{
    if (level < 0) level = 0;
    if (level >= cube->levels) level = cube->levels - 1;
    float s, t;
    int face = ibl_cube_face_st(dir, &s, &t);
    int n = ibl_level_size(cube->size, level);
    int x = (int)(s * n), y = (int)(t * n);
    if (x < 0) x = 0;
    if (x >= n) x = n - 1;
    if (y < 0) y = 0;
    if (y >= n) y = n - 1;
    memcpy(out, texel_at(cube, level, face, x, y), 4 * sizeof(float));
}

void ibl_cubemap_sample_trilinear(const ibl_cubemap *cube, float lod, ibl_vec3 dir, float out[4])
{
    float max_lod = (float)(cube->levels - 1);
    if (!(lod > 0.0f)) lod = 0.0f;
    if (lod > max_lod) lod = max_lod;
    int l0 = (int)lod;
    float f = lod - (float)l0;
    ibl_cubemap_sample_bilinear(cube, l0, dir, out);
    if (f > 0.0f && l0 + 1 < cube->levels) {
        float hi[4];
        ibl_cubemap_sample_bilinear(cube, l0 + 1, dir, hi);
        for (int i = 0; i < 4; i++) out[i] += (hi[i] - out[i]) * f;
    }
}

/* ---- mip chain ---- */

typedef struct mip_job {
    const ibl_cubemap *cube;
    int level; /* the level being written */
    const double *child_weights; /* solid angles of the child level's texels (one face) */
} mip_job;

static void mip_face_task(void *arg, int face)
{
    const mip_job *job = arg;
    int n = ibl_level_size(job->cube->size, job->level);
    int cn = ibl_level_size(job->cube->size, job->level - 1);
    const float *src = ibl_cubemap_face(job->cube, job->level - 1, face);
    float *dst = ibl_cubemap_face(job->cube, job->level, face);
    for (int y = 0; y < n; y++) {
        for (int x = 0; x < n; x++) {
            double acc[4] = {0, 0, 0, 0}, wsum = 0;
            for (int dy = 0; dy < 2; dy++) {
                for (int dx = 0; dx < 2; dx++) {
                    int cx = 2 * x + dx, cy = 2 * y + dy;
                    if (cx >= cn || cy >= cn) continue;
                    double w = job->child_weights[(size_t)cy * cn + cx];
                    const float *p = src + ((size_t)cy * cn + cx) * 4;
                    for (int i = 0; i < 4; i++) acc[i] += w * p[i];
                    wsum += w;
                }
            }
            float *o = dst + ((size_t)y * n + x) * 4;
            for (int i = 0; i < 4; i++) o[i] = (float)(acc[i] / wsum);
        }
    }
}

ibl_status ibl_cubemap_build_mips(ibl_context *ctx, ibl_cubemap *cube)
{
    if (!cube || !cube->data) return IBL_ERR_INVALID_ARGUMENT;
    if (cube->levels < 2) return IBL_OK;
    size_t n0 = (size_t)cube->size;
    double *weights = ibl_alloc(ctx, n0 * n0 * sizeof(double));
    if (!weights) return ibl_context_status(ctx);
    for (int level = 1; level < cube->levels; level++) {
        int cn = ibl_level_size(cube->size, level - 1);
        for (int y = 0; y < cn; y++)
            for (int x = 0; x < cn; x++)
                weights[(size_t)y * cn + x] = ibl_cube_texel_solid_angle(cn, x, y);
        mip_job job = {cube, level, weights};
        ibl_parallel_for(ctx, 6, mip_face_task, &job);
    }
    ibl_free(ctx, weights);
    return IBL_OK;
}

void ibl_cubemap_mean(const ibl_cubemap *cube, int level, double out[4])
{
    int n = ibl_level_size(cube->size, level);
    double acc[4] = {0, 0, 0, 0}, wsum = 0;
    for (int face = 0; face < 6; face++) {
        const float *p = ibl_cubemap_face(cube, level, face);
        for (int y = 0; y < n; y++) {
            for (int x = 0; x < n; x++, p += 4) {
                double w = ibl_cube_texel_solid_angle(n, x, y);
                for (int i = 0; i < 4; i++) acc[i] += w * p[i];
                wsum += w;
            }
        }
    }
    for (int i = 0; i < 4; i++) out[i] = acc[i] / wsum;
}

/* ---- resampling ---- */

/* When the source edge is an integer multiple r of the destination's: each texel is
 * the exact area mean of the r x r source texels it covers, weighted by their solid angles
 * (differences of the corner function atan(uv / sqrt(1 + u^2 + v^2)) on the source grid). */
typedef struct block_job {
    const ibl_cubemap *src;
    ibl_cubemap *dst;
    int ratio;
    const double *corner; /* (m + 1)^2 corner values of the source grid, m = source edge */
} block_job;

static void block_row_task(void *arg, int index)
{
    const block_job *job = arg;
    int n = job->dst->size, m = job->src->size, r = job->ratio;
    int face = index / n, y = index % n;
    const float *src = ibl_cubemap_face(job->src, 0, face);
    float *row = ibl_cubemap_face(job->dst, 0, face) + (size_t)y * n * 4;
    const double *c = job->corner;
    size_t stride = (size_t)m + 1;
    for (int x = 0; x < n; x++) {
        double acc[4] = {0, 0, 0, 0}, wsum = 0;
        for (int j = y * r; j < (y + 1) * r; j++) {
            for (int i = x * r; i < (x + 1) * r; i++) {
                double w = c[(j + 1) * stride + i + 1] - c[(j + 1) * stride + i] - c[j * stride + i + 1] +
                           c[j * stride + i];
                const float *p = src + ((size_t)j * m + i) * 4;
                for (int k = 0; k < 4; k++) acc[k] += w * p[k];
                wsum += w;
            }
        }
        for (int k = 0; k < 4; k++) row[(size_t)x * 4 + k] = (float)(acc[k] / wsum);
    }
}

static ibl_status block_mean(ibl_context *ctx, const ibl_cubemap *src, ibl_cubemap *dst)
{
    int m = src->size, n = dst->size;
    size_t stride = (size_t)m + 1;
    double *corner = ibl_alloc(ctx, stride * stride * sizeof(double));
    if (!corner) return ibl_context_status(ctx);
    for (size_t j = 0; j < stride; j++) {
        double v = 2.0 * (double)j / m - 1.0;
        for (size_t i = 0; i < stride; i++) {
            double u = 2.0 * (double)i / m - 1.0;
            corner[j * stride + i] = atan2(u * v, sqrt(u * u + v * v + 1.0));
        }
    }
    block_job job = {src, dst, m / n, corner};
    ibl_parallel_for(ctx, 6 * n, block_row_task, &job);
    ibl_free(ctx, corner);
    return IBL_OK;
}


typedef struct resample_job {
    const ibl_cubemap *src;
    int src_level;
    ibl_cubemap *dst;
    int samples;
} resample_job;

static void resample_task(void *arg, int index)
{
    const resample_job *job = arg;
    int n = job->dst->size;
    int face = index / n, y = index % n;
    float *row = ibl_cubemap_face(job->dst, 0, face) + (size_t)y * n * 4;
    int k = job->samples;
    for (int x = 0; x < n; x++) {
        double acc[4] = {0, 0, 0, 0}, wsum = 0;
        for (int sy = 0; sy < k; sy++) {
            for (int sx = 0; sx < k; sx++) {
                double u0 = 2.0 * (x + (double)sx / k) / n - 1.0;
                double v0 = 2.0 * (y + (double)sy / k) / n - 1.0;
                double u1 = 2.0 * (x + (double)(sx + 1) / k) / n - 1.0;
                double v1 = 2.0 * (y + (double)(sy + 1) / k) / n - 1.0;
                double w = ibl_cube_rect_solid_angle(u0, v0, u1, v1);
                double d[3];
                ibl_cube_direction_d(face, (x + (sx + 0.5) / k) / n, (y + (sy + 0.5) / k) / n, d);
                ibl_vec3 dir = {(float)d[0], (float)d[1], (float)d[2]};
                float c[4];
                ibl_cubemap_sample_bilinear(job->src, job->src_level, dir, c);
                for (int i = 0; i < 4; i++) acc[i] += w * c[i];
                wsum += w;
            }
        }
        for (int i = 0; i < 4; i++) row[(size_t)x * 4 + i] = (float)(acc[i] / wsum);
    }
}

ibl_status ibl_cubemap_resample(ibl_context *ctx, const ibl_cubemap *src, ibl_cubemap *dst)
{
    if (!src || !dst || !src->data || !dst->data) return IBL_ERR_INVALID_ARGUMENT;
    int n = dst->size;
    /* exact power-of-two shrink of a full chain: take the area-correct level directly */
    for (int l = 0; l < src->levels; l++) {
        if (ibl_level_size(src->size, l) == n && (src->size >> l) == n) {
            memcpy(dst->data, ibl_cubemap_face(src, l, 0), (size_t)6 * n * n * 4 * sizeof(float));
            return IBL_OK;
        }
    }
    /* an integer ratio: the exact area mean of the covered level-0 texels */
    if (src->size > n && src->size % n == 0) return block_mean(ctx, src, dst);
    /* otherwise: the finest level not more than 2x larger, then a supersampled box */
    int level = 0;
    while (level + 1 < src->levels && ibl_level_size(src->size, level + 1) >= n) level++;
    int ratio = (ibl_level_size(src->size, level) + n - 1) / n;
    resample_job job = {src, level, dst, ratio < 1 ? 2 : 2 * ratio};
    ibl_parallel_for(ctx, 6 * n, resample_task, &job);
    return IBL_OK;
}
