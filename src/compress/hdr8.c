/* The 8-bit HDR encodings (RGBM, RGBD, RGBE) and the quality names of ibl/compress.h. The
 * exact formulas are in docs/FORMATS.md ("8-bit HDR encodings"). */
#include <math.h>
#include <string.h>
#include <strings.h>

#include "ibl/compress.h"

static const char *const QUALITY_NAMES[] = {"default", "fast", "thorough"};

const char *ibl_quality_name(ibl_quality quality)
{
    return (unsigned)quality < 3 ? QUALITY_NAMES[quality] : "unknown";
}

int ibl_quality_from_name(const char *name, ibl_quality *out)
{
    for (int i = 0; name && i < 3; i++)
        if (strcasecmp(name, QUALITY_NAMES[i]) == 0) {
            *out = (ibl_quality)i;
            return 1;
        }
    return 0;
}

/* A channel made finite and non-negative (NaN and negatives: 0). */
static float clean(float v)
{
    return v > 0.0f ? v : 0.0f;
}

static uint8_t unorm8(float v)
{
    v = v < 0.0f ? 0.0f : v > 1.0f ? 1.0f : v;
    return (uint8_t)lrintf(v * 255.0f);
}

void ibl_rgbm_encode(const float rgb[3], float range, uint8_t out[4])
{
    if (!(range > 0.0f)) range = IBL_RGBM_DEFAULT_RANGE;
    float c[3] = {clean(rgb[0]), clean(rgb[1]), clean(rgb[2])};
    float m = fmaxf(c[0], fmaxf(c[1], c[2])) / range;
    if (!(m > 0.0f)) {
        memset(out, 0, 4);
        return;
    }
    if (m > 1.0f) m = 1.0f;
    int a = (int)ceilf(m * 255.0f);
    if (a < 1) a = 1;
    float scale = 1.0f / (range * (float)a / 255.0f);
    for (int i = 0; i < 3; i++) out[i] = unorm8(c[i] * scale);
    out[3] = (uint8_t)a;
}

/* The decodes use the operations of shaders/ibl_hdr8.glsl in the same order (products and
 * one division, each correctly rounded in C and GLSL), so a GPU decodes the same floats. */
void ibl_rgbm_decode(const uint8_t in[4], float range, float rgb[3])
{
    if (!(range > 0.0f)) range = IBL_RGBM_DEFAULT_RANGE;
    const float inv_65025 = 1.0f / 65025.0f; /* 1 / 255^2 */
    float s = (float)in[3] * (range * inv_65025);
    for (int i = 0; i < 3; i++) rgb[i] = (float)in[i] * s;
}

void ibl_rgbd_encode(const float rgb[3], uint8_t out[4])
{
    float c[3] = {clean(rgb[0]), clean(rgb[1]), clean(rgb[2])};
    float m = fmaxf(1.0f, fmaxf(c[0], fmaxf(c[1], c[2])));
    int a = (int)floorf(255.0f / m);
    if (a < 1) a = 1;
    float d = (float)a / 255.0f;
    for (int i = 0; i < 3; i++) out[i] = unorm8(c[i] * d);
    out[3] = (uint8_t)a;
}

void ibl_rgbd_decode(const uint8_t in[4], float rgb[3])
{
    float a = (float)(in[3] ? in[3] : 1);
    for (int i = 0; i < 3; i++) rgb[i] = (float)in[i] / a;
}

void ibl_rgbe_encode(const float rgb[3], uint8_t out[4])
{
    float c[3] = {clean(rgb[0]), clean(rgb[1]), clean(rgb[2])};
    float m = fmaxf(c[0], fmaxf(c[1], c[2]));
    if (!(m > 1e-38f)) {
        memset(out, 0, 4);
        return;
    }
    int e;
    if (isinf(m)) m = 1.7e38f, c[0] = fminf(c[0], m), c[1] = fminf(c[1], m), c[2] = fminf(c[2], m);
    (void)frexpf(m, &e); /* m = f 2^e, f in [0.5, 1) */
    if (e > 127) e = 127;
    float scale = ldexpf(1.0f, 8 - e);
    for (int i = 0; i < 3; i++) {
        float v = floorf(c[i] * scale);
        out[i] = (uint8_t)(v > 255.0f ? 255.0f : v);
    }
    out[3] = (uint8_t)(e + 128);
}

void ibl_rgbe_decode(const uint8_t in[4], float rgb[3])
{
    if (in[3] == 0) {
        rgb[0] = rgb[1] = rgb[2] = 0.0f;
        return;
    }
    /* 2^(A8 - 136) as two exact halves, as the shaders must (2^-135 alone is a denormal) */
    int e = (int)in[3] - 136, e_low = e >= 0 ? e / 2 : -((1 - e) / 2); /* floor(e / 2) */
    float s_low = ldexpf(1.0f, e_low), s_high = ldexpf(1.0f, e - e_low);
    for (int i = 0; i < 3; i++) rgb[i] = ((float)in[i] + 0.5f) * s_low * s_high;
}
