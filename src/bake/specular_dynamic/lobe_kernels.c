/* The products of the lobe operator (lobe_rows.c): one output texel is the sum over its chunks
 * of eight weights times eight consecutive floats of each of the three planes.
 *
 * Both paths add in the same order, so they give the same bits: lanes are summed apart, even
 * chunks into one set of accumulators and odd chunks into another (two sets hide the adds'
 * latency), each product rounded before it is added (no fused multiply-add: the library is
 * built as ISO C, which does not contract), then the sets are added and the eight lanes
 * reduced as (0+4, 1+5, 2+6, 3+7), then (0+2, 1+3), then 0+1. The AVX2 path needs the CPU and
 * the context's permission (core/cpu.h); the portable path is what a context created with
 * IBL_KERNELS_PORTABLE runs, and the tests compare the two. */
#include "bake/specular_dynamic/dynamic_internal.h"

static inline const float *chunk_weights(uint32_t code, const float *weights, const float *reversed,
                                         int chunk)
{
    return ((code & 1) ? reversed : weights) + (size_t)chunk * DYN_CHUNK;
}

static float reduce_lanes(const float a[DYN_CHUNK])
{
    float s[4], t[2];
    for (int j = 0; j < 4; j++) s[j] = a[j] + a[j + 4];
    for (int j = 0; j < 2; j++) t[j] = s[j] + s[j + 2];
    return t[0] + t[1];
}

void ibl__dyn_row_product_portable(const float *buffer, size_t plane, const uint32_t *codes,
                                   int count, const float *weights, const float *reversed,
                                   float out[3])
{
    float acc[2][3][DYN_CHUNK] = {{{0}}};
    for (int i = 0; i < count; i++) {
        const float *p = buffer + (codes[i] >> 1);
        const float *w = chunk_weights(codes[i], weights, reversed, i);
        float(*a)[DYN_CHUNK] = acc[i & 1];
        for (int k = 0; k < DYN_CHUNK; k++) {
            a[0][k] = a[0][k] + w[k] * p[k];
            a[1][k] = a[1][k] + w[k] * p[plane + k];
            a[2][k] = a[2][k] + w[k] * p[2 * plane + k];
        }
    }
    for (int c = 0; c < 3; c++) {
        float lanes[DYN_CHUNK];
        for (int k = 0; k < DYN_CHUNK; k++) lanes[k] = acc[0][c][k] + acc[1][c][k];
        out[c] = reduce_lanes(lanes);
    }
}

#if IBL_HAVE_X86_KERNELS
#include <immintrin.h>

IBL_TARGET_AVX2 static inline float reduce_vector(__m256 v)
{
    __m128 s = _mm_add_ps(_mm256_castps256_ps128(v), _mm256_extractf128_ps(v, 1)); /* 0+4 .. 3+7 */
    __m128 t = _mm_add_ps(s, _mm_movehl_ps(s, s));                               /* 0+2, 1+3 */
    return _mm_cvtss_f32(_mm_add_ss(t, _mm_shuffle_ps(t, t, 1)));               /* 0+1 */
}

IBL_TARGET_AVX2 void ibl__dyn_row_product_avx2(const float *buffer, size_t plane,
                                               const uint32_t *codes, int count,
                                               const float *weights, const float *reversed,
                                               float out[3])
{
    __m256 r0 = _mm256_setzero_ps(), g0 = r0, b0 = r0, r1 = r0, g1 = r0, b1 = r0;
    const float *wb[2] = {weights, reversed};
    int i = 0;
    for (; i + 1 < count; i += 2) {
        uint32_t c0 = codes[i], c1 = codes[i + 1];
        const float *p = buffer + (c0 >> 1), *q = buffer + (c1 >> 1);
        __m256 w = _mm256_loadu_ps(wb[c0 & 1] + (size_t)i * DYN_CHUNK);
        __m256 v = _mm256_loadu_ps(wb[c1 & 1] + (size_t)(i + 1) * DYN_CHUNK);
        r0 = _mm256_add_ps(r0, _mm256_mul_ps(w, _mm256_loadu_ps(p)));
        g0 = _mm256_add_ps(g0, _mm256_mul_ps(w, _mm256_loadu_ps(p + plane)));
        b0 = _mm256_add_ps(b0, _mm256_mul_ps(w, _mm256_loadu_ps(p + 2 * plane)));
        r1 = _mm256_add_ps(r1, _mm256_mul_ps(v, _mm256_loadu_ps(q)));
        g1 = _mm256_add_ps(g1, _mm256_mul_ps(v, _mm256_loadu_ps(q + plane)));
        b1 = _mm256_add_ps(b1, _mm256_mul_ps(v, _mm256_loadu_ps(q + 2 * plane)));
    }
    if (i < count) {
        uint32_t c0 = codes[i];
        const float *p = buffer + (c0 >> 1);
        __m256 w = _mm256_loadu_ps(wb[c0 & 1] + (size_t)i * DYN_CHUNK);
        r0 = _mm256_add_ps(r0, _mm256_mul_ps(w, _mm256_loadu_ps(p)));
        g0 = _mm256_add_ps(g0, _mm256_mul_ps(w, _mm256_loadu_ps(p + plane)));
        b0 = _mm256_add_ps(b0, _mm256_mul_ps(w, _mm256_loadu_ps(p + 2 * plane)));
    }
    out[0] = reduce_vector(_mm256_add_ps(r0, r1));
    out[1] = reduce_vector(_mm256_add_ps(g0, g1));
    out[2] = reduce_vector(_mm256_add_ps(b0, b1));
}
#endif
