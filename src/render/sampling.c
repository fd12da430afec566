/* Low-discrepancy sequences and lobe sampling for the reference renderer and the in-memory
 * probe builder. */
#include "render_internal.h"
#include "core/numeric.h"


void ibl__frame(ibl_vec3 n, ibl_vec3 *t, ibl_vec3 *b)
{
    float sign = n.z >= 0.0f ? 1.0f : -1.0f;
    float a = -1.0f / (sign + n.z);
    float c = n.x * n.y * a;
    *t = ibl__v3(1.0f + sign * n.x * n.x * a, sign * c, -sign * n.x);
    *b = ibl__v3(c, sign + n.y * n.y * a, -n.y);
}

void ibl__hammersley(uint32_t i, uint32_t n, float r0, float r1, float *u0, float *u1)
{
    uint32_t bits = i;
    bits = (bits << 16) | (bits >> 16);
    bits = ((bits & 0x55555555u) << 1) | ((bits & 0xAAAAAAAAu) >> 1);
    bits = ((bits & 0x33333333u) << 2) | ((bits & 0xCCCCCCCCu) >> 2);
    bits = ((bits & 0x0F0F0F0Fu) << 4) | ((bits & 0xF0F0F0F0u) >> 4);
    bits = ((bits & 0x00FF00FFu) << 8) | ((bits & 0xFF00FF00u) >> 8);
    float a = ((float)i + 0.5f) / (float)n + r0;
    float b = (float)bits * 2.3283064365386963e-10f + r1;
    *u0 = a - floorf(a);
    *u1 = b - floorf(b);
}

uint32_t ibl__hash(uint32_t x)
{
    /* integer finaliser with good avalanche (the constants of the "lowbias32" mix) */
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

static ibl_vec3 from_frame(ibl_vec3 n, float cos_t, float phi)
{
    ibl_vec3 t, b;
    ibl__frame(n, &t, &b);
    float sin_t = sqrtf(fmaxf(0.0f, 1.0f - cos_t * cos_t));
    float x = sin_t * cosf(phi), y = sin_t * sinf(phi);
    return ibl__v3(t.x * x + b.x * y + n.x * cos_t, t.y * x + b.y * y + n.y * cos_t,
                   t.z * x + b.z * y + n.z * cos_t);
}

/* Inverting the GGX cdf of cos(theta_h) (Walter et al. 2007). */
ibl_vec3 ibl__sample_ggx(ibl_vec3 n, float alpha, float u0, float u1)
{
    float a2 = alpha * alpha;
    float cos_t = sqrtf((1.0f - u1) / (1.0f + (a2 - 1.0f) * u1));
    return from_frame(n, cos_t, 2.0f * IBL_PI_F * u0);
}

ibl_vec3 ibl__sample_phong(ibl_vec3 n, float s, float u0, float u1)
{
    float cos_t = powf(1.0f - u1, 1.0f / (s + 1.0f));
    return from_frame(n, cos_t, 2.0f * IBL_PI_F * u0);
}
