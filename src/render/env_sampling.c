/* Importance sampling of the environment for the Monte Carlo reference: texels are drawn in
 * proportion to luminance x solid angle, then a point uniformly in the texel's face
 * coordinates. HDR environments with a sun need this: a BRDF-sampled estimate hits a
 * 0.5-degree disk once in ~1e5 samples of a rough lobe, so its average over a sphere is wrong
 * by tens of percent at any practical sample count (Pharr, Jakob & Humphreys, PBRT 3rd ed.,
 * 14.2 "Infinite area lights", with cube faces instead of a lat-long map). */
#include "render_internal.h"

#include <stdlib.h>
#include <string.h>

typedef struct ibl__env_sampler {
    const ibl_cubemap *env;
    int n;
    double *cdf; /* 6 n^2 + 1 entries, cdf[0] = 0, last = 1 */
    float *prob; /* probability of each texel */
} ibl__env_sampler;

static float luminance(const float *t)
{
    return 0.2126f * t[0] + 0.7152f * t[1] + 0.0722f * t[2];
}

ibl__env_sampler *ibl__env_sampler_create(ibl_context *ctx, const ibl_cubemap *env)
{
    ibl__env_sampler *s = ibl_calloc(ctx, 1, sizeof *s);
    if (!s) return NULL;
    int n = env->size;
    size_t count = (size_t)6 * n * n;
    s->env = env;
    s->n = n;
    s->cdf = ibl_alloc(ctx, (count + 1) * sizeof(double));
    s->prob = ibl_alloc(ctx, count * sizeof(float));
    if (!s->cdf || !s->prob) {
        ibl__env_sampler_destroy(ctx, s);
        return NULL;
    }
    /* weight: the largest luminance of the 3x3 neighbourhood (bilinear lookups reach the
     * neighbours, so a dark texel next to the sun must not get a tiny probability), plus a
     * floor of 1e-3 of the mean so every direction stays reachable */
    double total = 0.0, mean = 0.0;
    for (int f = 0; f < 6; f++) {
        const float *face = ibl_cubemap_face(env, 0, f);
        for (int y = 0; y < n; y++)
            for (int x = 0; x < n; x++) {
                float m = 0.0f;
                for (int dy = -1; dy <= 1; dy++)
                    for (int dx = -1; dx <= 1; dx++) {
                        int xx = x + dx, yy = y + dy;
                        if (xx < 0 || yy < 0 || xx >= n || yy >= n) continue;
                        float l = luminance(face + ((size_t)yy * n + xx) * 4);
                        if (l > m) m = l;
                    }
                size_t i = ((size_t)f * n + y) * n + x;
                double w = (double)m * ibl_cube_texel_solid_angle(n, x, y);
                s->cdf[i + 1] = w;
                mean += w;
            }
    }
    mean /= 4.0 * 3.14159265358979;
    for (int f = 0; f < 6; f++)
        for (int y = 0; y < n; y++)
            for (int x = 0; x < n; x++) {
                size_t i = ((size_t)f * n + y) * n + x;
                s->cdf[i + 1] += 1e-3 * mean * ibl_cube_texel_solid_angle(n, x, y) + 1e-30;
                total += s->cdf[i + 1];
            }
    s->cdf[0] = 0.0;
    for (size_t i = 0; i < count; i++) {
        s->prob[i] = (float)(s->cdf[i + 1] / total);
        s->cdf[i + 1] = s->cdf[i] + s->cdf[i + 1] / total;
    }
    s->cdf[count] = 1.0;
    return s;
}

void ibl__env_sampler_destroy(ibl_context *ctx, ibl__env_sampler *s)
{
    if (!s) return;
    ibl_free(ctx, s->cdf);
    ibl_free(ctx, s->prob);
    ibl_free(ctx, s);
}

/* density over solid angle of a point (s, t) of a texel: P / (ds dt) * dA/dw, with
 * dw = 4 ds dt / (1 + sc^2 + tc^2)^(3/2) for face coordinates sc = 2s - 1, tc = 2t - 1 */
static float texel_pdf(const ibl__env_sampler *s, size_t i, float fs, float ft)
{
    float sc = 2.0f * fs - 1.0f, tc = 2.0f * ft - 1.0f;
    float q = 1.0f + sc * sc + tc * tc;
    return s->prob[i] * (float)s->n * (float)s->n * q * sqrtf(q) * 0.25f;
}

float ibl__env_sampler_pdf(const ibl__env_sampler *s, ibl_vec3 d)
{
    float fs, ft;
    int f = ibl_cube_face_st(d, &fs, &ft);
    int x = (int)(fs * s->n), y = (int)(ft * s->n);
    if (x >= s->n) x = s->n - 1;
    if (y >= s->n) y = s->n - 1;
    if (x < 0) x = 0;
    if (y < 0) y = 0;
    return texel_pdf(s, ((size_t)f * s->n + y) * s->n + x, fs, ft);
}

ibl_vec3 ibl__env_sampler_sample(const ibl__env_sampler *s, float u0, float u1, float *pdf)
{
    size_t count = (size_t)6 * s->n * s->n;
    size_t lo = 0, hi = count; /* find i with cdf[i] <= u0 < cdf[i + 1] */
    while (hi - lo > 1) {
        size_t mid = (lo + hi) / 2;
        if (s->cdf[mid] <= u0)
            lo = mid;
        else
            hi = mid;
    }
    size_t i = lo;
    double width = s->cdf[i + 1] - s->cdf[i];
    float jx = width > 0 ? (float)((u0 - s->cdf[i]) / width) : 0.5f;
    if (jx >= 1.0f) jx = 0.99999994f;
    int face = (int)(i / ((size_t)s->n * s->n));
    int rem = (int)(i % ((size_t)s->n * s->n));
    int y = rem / s->n, x = rem % s->n;
    float fs = ((float)x + jx) / (float)s->n, ft = ((float)y + u1) / (float)s->n;
    *pdf = texel_pdf(s, i, fs, ft);
    return ibl__norm(ibl_cube_direction(face, fs, ft));
}
