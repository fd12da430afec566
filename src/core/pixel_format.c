/* Conversions between float and the packed storage formats: IEEE 754 binary16 ("half"),
 * the shared-exponent E5B9G9R9 and the unsigned small floats of B10G11R11.
 * Vulkan 1.3 specification, "Fixed-Point Data Conversions" / "16-bit, 11-bit and 10-bit
 * Floating-Point Numbers" and "Shared Exponent" (the same text as OpenGL 4.6 sections 2.3.4
 * and 8.5.2 and EXT_texture_shared_exponent). All rounding is round-to-nearest-even and is
 * done on the bit patterns, so results do not depend on the FPU rounding mode. */
#include "core/pixel_format.h"

#include <float.h>
#include <math.h>
#include <string.h>

static uint32_t float_bits(float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    return u;
}

static float bits_float(uint32_t u)
{
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

/* Rounds `value >> shift` to nearest, ties to even (shift in 1..31). */
static uint32_t shift_round_even(uint32_t value, unsigned shift)
{
    uint32_t r = value >> shift;
    uint32_t rem = value & ((1u << shift) - 1u);
    uint32_t half = 1u << (shift - 1u);
    if (rem > half || (rem == half && (r & 1u))) r++;
    return r;
}

/* A positive finite float (bits x, sign clear) to a small float with a 5-bit exponent of
 * bias 15 and `mbits` mantissa bits, rounding to nearest even. The result may carry into
 * the next exponent; callers handle overflow. */
static uint32_t to_small_float(uint32_t x, unsigned mbits)
{
    unsigned drop = 23u - mbits;
    if (x < 0x38800000u) {
        /* Below 2^-14, the smallest normal: a denormal of unit 2^(-14 - mbits). The float
         * is mant * 2^(e - 150), so the count of units is mant >> (136 - mbits - e). */
        uint32_t e = x >> 23;
        if (e == 0) return 0; /* float denormals are far below half a unit */
        uint32_t mant = (x & 0x7fffffu) | 0x800000u;
        unsigned shift = 136u - mbits - e;
        if (shift >= 25u) return 0; /* below half of the smallest denormal (mant < 2^24) */
        return shift_round_even(mant, shift);
    }
    /* Re-bias the exponent from 127 to 15 (subtract 112 << 23) and round the mantissa. */
    return shift_round_even(x - (112u << 23), drop);
}

uint16_t ibl_float_to_half(float f)
{
    uint32_t x = float_bits(f);
    uint16_t sign = (uint16_t)((x >> 16) & 0x8000u);
    x &= 0x7fffffffu;
    if (x > 0x7f800000u) {
        /* NaN: keep the top payload bits (quiet bit included); never produce Inf. */
        uint16_t m = (uint16_t)((x >> 13) & 0x3ffu);
        return (uint16_t)(sign | 0x7c00u | (m ? m : 0x200u));
    }
    /* 65520 = 65504 + half an ulp: from there on the nearest is Inf (IEEE overflow). */
    if (x >= 0x477ff000u) return (uint16_t)(sign | 0x7c00u);
    return (uint16_t)(sign | to_small_float(x, 10));
}

/* Storage rounding that never makes a finite value infinite: past 65504 it is 65504. */
static uint16_t half_saturated(float v)
{
    if (v > 65504.0f) v = 65504.0f;
    else if (v < -65504.0f) v = -65504.0f;
    return ibl_float_to_half(v);
}

float ibl_half_to_float(uint16_t h)
{
    uint32_t sign = (uint32_t)(h & 0x8000u) << 16;
    uint32_t e = (h >> 10) & 0x1fu, m = h & 0x3ffu;
    if (e == 0) {
        /* zero or denormal m * 2^-24: exact in float */
        float v = (float)m * 0x1p-24f;
        return sign ? -v : v;
    }
    if (e == 31) return bits_float(sign | 0x7f800000u | (m << 13));
    return bits_float(sign | ((e + 112u) << 23) | (m << 13));
}

/* ---- B10G11R11_UFLOAT_PACK32 ---- */

/* Float to an unsigned 11-bit (mbits 6) or 10-bit (mbits 5) float. Negative values and -Inf
 * become 0 (the format has no sign), NaN stays NaN, +Inf stays +Inf, finite values above the
 * largest finite value saturate to it (65024 for 11 bits, 64512 for 10 bits) instead of
 * becoming Inf, so a very bright texel stays finite. */
static uint32_t pack_ufloat(float f, unsigned mbits)
{
    uint32_t x = float_bits(f);
    uint32_t inf = 31u << mbits;
    if ((x & 0x7fffffffu) > 0x7f800000u) return inf | (1u << (mbits - 1u));
    if (x & 0x80000000u) return 0;
    if (x == 0x7f800000u) return inf;
    uint32_t max_finite = inf - 1u;
    if (x >= 0x47800000u) return max_finite; /* >= 2^16: above every finite value */
    uint32_t r = to_small_float(x, mbits);
    return r > max_finite ? max_finite : r;
}

static float unpack_ufloat(uint32_t v, unsigned mbits)
{
    uint32_t e = v >> mbits, m = v & ((1u << mbits) - 1u);
    if (e == 0) return (float)m * ldexpf(1.0f, -14 - (int)mbits);
    if (e == 31) return bits_float(0x7f800000u | (m << (23u - mbits)));
    return bits_float(((e + 112u) << 23) | (m << (23u - mbits)));
}

uint32_t ibl_pack_rg11b10(const float rgb[3])
{
    return pack_ufloat(rgb[0], 6) | (pack_ufloat(rgb[1], 6) << 11) | (pack_ufloat(rgb[2], 5) << 22);
}

void ibl_unpack_rg11b10(uint32_t v, float rgb[3])
{
    rgb[0] = unpack_ufloat(v & 0x7ffu, 6);
    rgb[1] = unpack_ufloat((v >> 11) & 0x7ffu, 6);
    rgb[2] = unpack_ufloat(v >> 22, 5);
}

/* ---- E5B9G9R9_UFLOAT_PACK32 ---- */

enum { SE_N = 9, SE_B = 15, SE_EMAX = 31 };
/* sharedexp_max = (2^N - 1) / 2^N * 2^(Emax - B) = 65408 */
static const double SE_MAX = (double)((1 << SE_N) - 1) / (double)(1 << SE_N) * 65536.0;

static double se_clamp(float v)
{
    if (!(v > 0.0f)) return 0.0; /* negatives, zero and NaN */
    return (double)v > SE_MAX ? SE_MAX : (double)v;
}

/* Vulkan "Shared Exponent": exp' = max(-B - 1, floor(log2(max_c))) + 1 + B, then the
 * max-mantissa check bumps the exponent when max_c rounds up to 2^N. Every step below is
 * exact in double (scalings by powers of two of values with 24 significant bits). */
uint32_t ibl_pack_rgb9e5(const float rgb[3])
{
    double c[3] = {se_clamp(rgb[0]), se_clamp(rgb[1]), se_clamp(rgb[2])};
    double max_c = c[0] > c[1] ? c[0] : c[1];
    if (c[2] > max_c) max_c = c[2];
    int exp_p = 0;
    if (max_c > 0.0) {
        int e;
        frexp(max_c, &e); /* max_c = f * 2^e, f in [0.5, 1): floor(log2(max_c)) = e - 1 */
        int fl = e - 1;
        exp_p = (fl < -SE_B - 1 ? -SE_B - 1 : fl) + 1 + SE_B;
    }
    double scale = ldexp(1.0, -(exp_p - SE_B - SE_N)); /* 1 / 2^(exp' - B - N) */
    double max_s = floor(max_c * scale + 0.5);
    if (max_s >= (double)(1 << SE_N)) {
        exp_p++;
        scale *= 0.5;
    }
    uint32_t out = (uint32_t)exp_p << 27;
    for (int i = 0; i < 3; i++) {
        uint32_t s = (uint32_t)floor(c[i] * scale + 0.5);
        out |= s << (9 * i);
    }
    return out;
}

void ibl_unpack_rgb9e5(uint32_t v, float rgb[3])
{
    int e = (int)(v >> 27);
    float unit = ldexpf(1.0f, e - SE_B - SE_N);
    rgb[0] = (float)(v & 0x1ffu) * unit;
    rgb[1] = (float)((v >> 9) & 0x1ffu) * unit;
    rgb[2] = (float)((v >> 18) & 0x1ffu) * unit;
}

/* ---- whole-texel helpers ---- */

size_t ibl_format_texel_bytes(ibl_format format)
{
    switch (format) {
    case IBL_FORMAT_RGBA16F: return 8;
    case IBL_FORMAT_RGBA32F: return 16;
    case IBL_FORMAT_RG11B10F: return 4;
    case IBL_FORMAT_RGB9E5: return 4;
    case IBL_FORMAT_RG16F: return 4;
    case IBL_FORMAT_RG32F: return 8;
    case IBL_FORMAT_RGB32F: return 12;
    case IBL_FORMAT_RGB16F: return 6;
    default: return 0; /* 8/16-bit and RGBE encodings belong to the image writers */
    }
}

int ibl_format_channels(ibl_format format)
{
    switch (format) {
    case IBL_FORMAT_RG16F:
    case IBL_FORMAT_RG32F: return 2;
    case IBL_FORMAT_RG11B10F:
    case IBL_FORMAT_RGB9E5:
    case IBL_FORMAT_RGB32F:
    case IBL_FORMAT_RGB16F:
    case IBL_FORMAT_RGBE:
    case IBL_FORMAT_BC6H:
    case IBL_FORMAT_BC6H_SIGNED:
    case IBL_FORMAT_RGBM:
    case IBL_FORMAT_RGBD: return 3;
    default: return format >= IBL_FORMAT_ASTC_4x4 && format <= IBL_FORMAT_ASTC_8x8 ? 3 : 4;
    }
}

static void put32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
    p[2] = (uint8_t)(v >> 16);
    p[3] = (uint8_t)(v >> 24);
}

static uint32_t get32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

/* RGBA floats to halves, 8 values (two texels) at a time where SSE2 is: the values whose
 * halves are normal or zero are rounded on their bits exactly as ibl_float_to_half does
 * (re-bias, then round the 13 dropped bits to nearest even), and a group holding anything
 * else (a half denormal, an overflow, Inf or NaN) goes through ibl_float_to_half. Returns
 * the texels done. */
#if defined(__SSE2__)
#include <emmintrin.h>
static size_t pack_rgba16f_sse2(const float *rgba, size_t count, uint8_t *dst)
{
    const __m128i abs_mask = _mm_set1_epi32(0x7fffffff), rebias = _mm_set1_epi32(112 << 23);
    const __m128i min_normal = _mm_set1_epi32(0x38800000 - 1), overflow = _mm_set1_epi32(0x477ff000);
    const __m128i min_float_normal = _mm_set1_epi32(0x00800000), round = _mm_set1_epi32(0xfff);
    const __m128i one = _mm_set1_epi32(1), sign_bit = _mm_set1_epi32(0x8000);
    size_t i = 0;
    for (; i + 2 <= count; i += 2) {
        __m128i h[2];
        int fast = 1;
        for (int k = 0; k < 2 && fast; k++) {
            __m128i x = _mm_loadu_si128((const __m128i *)(const void *)(rgba + (i + (size_t)k) * 4));
            __m128i a = _mm_and_si128(x, abs_mask);
            /* (signed compares: a < 2^31) */
            __m128i normal = _mm_and_si128(_mm_cmpgt_epi32(a, min_normal), _mm_cmplt_epi32(a, overflow));
            __m128i zero = _mm_cmplt_epi32(a, min_float_normal);
            if (_mm_movemask_epi8(_mm_or_si128(normal, zero)) != 0xffff) {
                fast = 0;
                break;
            }
            __m128i v = _mm_sub_epi32(a, rebias);
            __m128i odd = _mm_and_si128(_mm_srli_epi32(v, 13), one);
            __m128i r = _mm_srli_epi32(_mm_add_epi32(_mm_add_epi32(v, round), odd), 13);
            r = _mm_and_si128(r, normal);
            r = _mm_or_si128(r, _mm_and_si128(_mm_srli_epi32(x, 16), sign_bit));
            /* sign-extend the 16 bits so that the signed pack keeps them as they are */
            h[k] = _mm_srai_epi32(_mm_slli_epi32(r, 16), 16);
        }
        if (fast) {
            _mm_storeu_si128((__m128i *)(void *)(dst + i * 8), _mm_packs_epi32(h[0], h[1]));
        } else {
            for (size_t j = 0; j < 8; j++) {
                uint16_t v = half_saturated(rgba[i * 4 + j]);
                dst[i * 8 + 2 * j] = (uint8_t)v;
                dst[i * 8 + 2 * j + 1] = (uint8_t)(v >> 8);
            }
        }
    }
    return i;
}

/* Halves to floats, 8 at a time (two RGBA texels), exact for every code as ibl_half_to_float:
 * the exponent is re-biased in place (112 more; 112 more again for Inf and NaN, whose payload
 * is kept), and a zero or denormal half, m * 2^-24, is made as the float 2^-14 (1 + m/1024)
 * less 2^-14, a subtraction without rounding. Returns the texels done. */
static size_t unpack_rgba16f_sse2(const uint8_t *src, size_t count, float *rgba)
{
    const __m128i magnitude = _mm_set1_epi32(0x7fff), exponent = _mm_set1_epi32(0x0f800000);
    const __m128i rebias = _mm_set1_epi32(112 << 23), one_exponent = _mm_set1_epi32(1 << 23);
    const __m128 two_to_minus_14 = _mm_castsi128_ps(_mm_set1_epi32(113 << 23));
    const __m128i zero = _mm_setzero_si128();
    size_t i = 0;
    for (; i + 2 <= count; i += 2) {
        __m128i h8 = _mm_loadu_si128((const __m128i *)(const void *)(src + i * 8));
        __m128i halves[2] = {_mm_unpacklo_epi16(h8, zero), _mm_unpackhi_epi16(h8, zero)};
        for (int k = 0; k < 2; k++) {
            __m128i h = halves[k];
            __m128i o = _mm_slli_epi32(_mm_and_si128(h, magnitude), 13);
            __m128i e = _mm_and_si128(o, exponent);
            o = _mm_add_epi32(o, rebias);
            o = _mm_add_epi32(o, _mm_and_si128(_mm_cmpeq_epi32(e, exponent), rebias));
            __m128i small = _mm_cmpeq_epi32(e, zero);
            __m128 renormal = _mm_sub_ps(_mm_castsi128_ps(_mm_add_epi32(o, one_exponent)), two_to_minus_14);
            __m128i v = _mm_or_si128(_mm_andnot_si128(small, o),
                                     _mm_and_si128(small, _mm_castps_si128(renormal)));
            v = _mm_or_si128(v, _mm_slli_epi32(_mm_srli_epi32(h, 15), 31));
            _mm_storeu_ps(rgba + (i + (size_t)k) * 4, _mm_castsi128_ps(v));
        }
    }
    return i;
}
#endif

/* Stored as the format's largest value instead of infinity (or its own clamp): counts the
 * texels with a channel above it, for the writer's report. */
static size_t count_over(const float *rgba, size_t count, int channels, float max)
{
    size_t n = 0;
    for (size_t i = 0; i < count; i++) {
        int over = 0;
        for (int c = 0; c < channels; c++) over |= fabsf(rgba[i * 4 + (size_t)c]) > max;
        n += (size_t)over;
    }
    return n;
}

float ibl_format_max_value(ibl_format format)
{
    switch (format) {
    case IBL_FORMAT_RGBA16F:
    case IBL_FORMAT_RGB16F:
    case IBL_FORMAT_RG16F:
    case IBL_FORMAT_BC6H:
    case IBL_FORMAT_BC6H_SIGNED: return 65504.0f;
    case IBL_FORMAT_RGBD: return 255.0f;
    case IBL_FORMAT_RG11B10F: return 65024.0f; /* 6-bit mantissa, exponent 30 */
    case IBL_FORMAT_RGB9E5: return 65408.0f;   /* (511/512) 2^16 */
    case IBL_FORMAT_RGBA8_SRGB:
    case IBL_FORMAT_RGBA8_UNORM:
    case IBL_FORMAT_RGBA16_UNORM: return 1.0f;
    default: return FLT_MAX;
    }
}

size_t ibl_pack_texels(ibl_format format, const float *rgba, size_t count, uint8_t *dst)
{
    int channels = ibl_format_channels(format);
    float max = ibl_format_max_value(format);
    size_t clamped = max < FLT_MAX ? count_over(rgba, count, channels, max) : 0;
    switch (format) {
    case IBL_FORMAT_RGBA16F:
#if defined(__SSE2__)
    {
        size_t done = pack_rgba16f_sse2(rgba, count, dst);
        rgba += done * 4;
        dst += done * 8;
        count -= done;
    }
#endif
        /* fall through */
    case IBL_FORMAT_RG16F:
    case IBL_FORMAT_RGB16F:
        for (size_t i = 0; i < count; i++) {
            for (int c = 0; c < channels; c++) {
                uint16_t h = half_saturated(rgba[i * 4 + (size_t)c]);
                dst[0] = (uint8_t)h;
                dst[1] = (uint8_t)(h >> 8);
                dst += 2;
            }
        }
        break;
    case IBL_FORMAT_RGBA32F:
    case IBL_FORMAT_RG32F:
    case IBL_FORMAT_RGB32F:
        for (size_t i = 0; i < count; i++) {
            for (int c = 0; c < channels; c++) {
                put32(dst, float_bits(rgba[i * 4 + (size_t)c]));
                dst += 4;
            }
        }
        break;
    case IBL_FORMAT_RG11B10F:
        for (size_t i = 0; i < count; i++, dst += 4) put32(dst, ibl_pack_rg11b10(rgba + i * 4));
        break;
    case IBL_FORMAT_RGB9E5:
        for (size_t i = 0; i < count; i++, dst += 4) put32(dst, ibl_pack_rgb9e5(rgba + i * 4));
        break;
    default: break; /* ibl_format_texel_bytes is 0: nothing to write */
    }
    return clamped;
}

void ibl_unpack_texels(ibl_format format, const uint8_t *src, size_t count, float *rgba)
{
    int channels = ibl_format_channels(format);
    switch (format) {
    case IBL_FORMAT_RGBA16F:
    case IBL_FORMAT_RG16F:
    case IBL_FORMAT_RGB16F: {
        size_t i = 0;
#if defined(__SSE2__)
        if (format == IBL_FORMAT_RGBA16F) {
            i = unpack_rgba16f_sse2(src, count, rgba);
            src += i * 8;
        }
#endif
        for (; i < count; i++) {
            float *p = rgba + i * 4;
            p[1] = p[2] = 0.0f;
            p[3] = 1.0f;
            for (int c = 0; c < channels; c++, src += 2)
                p[c] = ibl_half_to_float((uint16_t)(src[0] | (src[1] << 8)));
        }
        break;
    }
    case IBL_FORMAT_RGBA32F:
    case IBL_FORMAT_RG32F:
    case IBL_FORMAT_RGB32F:
        for (size_t i = 0; i < count; i++) {
            float *p = rgba + i * 4;
            p[1] = p[2] = 0.0f;
            p[3] = 1.0f;
            for (int c = 0; c < channels; c++, src += 4) p[c] = bits_float(get32(src));
        }
        break;
    case IBL_FORMAT_RG11B10F:
        for (size_t i = 0; i < count; i++, src += 4) {
            ibl_unpack_rg11b10(get32(src), rgba + i * 4);
            rgba[i * 4 + 3] = 1.0f;
        }
        break;
    case IBL_FORMAT_RGB9E5:
        for (size_t i = 0; i < count; i++, src += 4) {
            ibl_unpack_rgb9e5(get32(src), rgba + i * 4);
            rgba[i * 4 + 3] = 1.0f;
        }
        break;
    default: break;
    }
}
