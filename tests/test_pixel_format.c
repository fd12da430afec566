/* Packed pixel formats against slow references written here from the specification text
 * (Vulkan 1.3 "16-bit / 11-bit / 10-bit floating-point numbers" and "Shared Exponent"):
 * half exhaustively, float->half rounding against a nearest-value search in double, RGB9E5
 * against the spec's formulas evaluated with pow/log2/floor, and B10G11R11 against a
 * nearest-value search over every code. */
#include "test_support.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/pixel_format.h"

static uint32_t fbits(float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    return u;
}

static float bitsf(uint32_t u)
{
    float f;
    memcpy(&f, &u, 4);
    return f;
}

static uint64_t rng_state = 0x9E3779B97F4A7C15ull;
static uint32_t rnd(void)
{
    /* xorshift64*: deterministic, independent of the C library */
    rng_state ^= rng_state >> 12;
    rng_state ^= rng_state << 25;
    rng_state ^= rng_state >> 27;
    return (uint32_t)((rng_state * 2685821657736338717ull) >> 32);
}

/* A random positive float with a log-uniform magnitude in [2^lo, 2^hi). */
static float rnd_magnitude(int lo, int hi)
{
    int e = lo + (int)(rnd() % (uint32_t)(hi - lo));
    float m = 1.0f + (float)(rnd() & 0x7fffff) * 0x1p-23f;
    return ldexpf(m, e);
}

/* ---- half ---- */

/* The value of a half from the format's definition: (-1)^s * 2^(e-15) * (1 + m/1024), or
 * 2^-14 * m/1024 for e = 0. */
static double half_value(uint16_t h)
{
    int s = h >> 15, e = (h >> 10) & 31, m = h & 1023;
    double v = e == 0 ? ldexp(m / 1024.0, -14) : ldexp(1.0 + m / 1024.0, e - 15);
    return s ? -v : v;
}

static void half_exhaustive(void **state)
{
    (void)state;
    for (uint32_t h = 0; h < 65536; h++) {
        float f = ibl_half_to_float((uint16_t)h);
        int e = (h >> 10) & 31, m = h & 1023;
        if (e == 31) {
            if (m == 0) {
                assert_true(isinf(f));
                assert_int_equal(signbit(f) != 0, (h >> 15) != 0);
                assert_int_equal(ibl_float_to_half(f), h);
            } else {
                assert_true(isnan(f));
                uint16_t back = ibl_float_to_half(f);
                assert_int_equal((back >> 10) & 31, 31); /* NaN stays NaN */
                assert_true((back & 1023) != 0);
            }
            continue;
        }
        assert_true((double)f == half_value((uint16_t)h));
        assert_int_equal(signbit(f) != 0, (h >> 15) != 0); /* -0 keeps its sign */
        assert_int_equal(ibl_float_to_half(f), h);         /* finite: exact round trip */
    }
}

/* Reference rounding: the nearest of all finite positive halves (a table in double), ties to
 * the even code; from 65520 = 65504 + half an ulp on, Inf (IEEE overflow rule). */
static double half_table[0x7c00];
static uint16_t ref_float_to_half(float f)
{
    uint16_t sign = signbit(f) ? 0x8000 : 0;
    double a = fabs((double)f);
    if (isnan(f)) return 0x7e00;
    if (a >= 65520.0) return sign | 0x7c00;
    int lo = 0, hi = 0x7bff; /* largest code with value <= a */
    while (lo < hi) {
        int mid = (lo + hi + 1) / 2;
        if (half_table[mid] <= a) lo = mid;
        else hi = mid - 1;
    }
    if (lo == 0x7bff) return sign | 0x7bff; /* a in [65504, 65520) */
    double dlo = a - half_table[lo], dhi = half_table[lo + 1] - a;
    int code = dlo < dhi ? lo : dhi < dlo ? lo + 1 : (lo % 2 == 0 ? lo : lo + 1);
    return (uint16_t)(sign | code);
}

static void check_half_rounding(float f)
{
    uint16_t got = ibl_float_to_half(f), want = ref_float_to_half(f);
    if (isnan(f)) {
        assert_true((got & 0x7c00) == 0x7c00 && (got & 1023) != 0);
        return;
    }
    if (got != want) fail_msg("float %a (0x%08x): half 0x%04x, reference 0x%04x", (double)f, fbits(f), got, want);
}

static void half_rounding(void **state)
{
    (void)state;
    for (int i = 0; i < 0x7c00; i++) half_table[i] = half_value((uint16_t)i);
    /* every float exponent that matters (2^-26 .. 2^17), mantissas around each tie point of
     * the normal (13 dropped bits) and denormal (more dropped bits) ranges */
    for (uint32_t e = 100; e <= 144; e++) {
        for (uint32_t k = 0; k < 600; k++) {
            uint32_t m = rnd() & 0x7fffff;
            uint32_t patterns[6] = {m, (m & ~0x1fffu) | 0x1000u, (m & ~0x1fffu) | 0x0fffu,
                                    (m & ~0x1fffu) | 0x1001u, (m & ~0x3fffu) | 0x3000u,
                                    m & ~((1u << (rnd() % 23)) - 1u)};
            for (int p = 0; p < 6; p++) {
                uint32_t x = (e << 23) | (patterns[p] & 0x7fffff);
                check_half_rounding(bitsf(x));
                check_half_rounding(bitsf(x | 0x80000000u));
            }
        }
    }
    /* a dense sweep of bit patterns from 2^-26 to 2^17 */
    for (uint32_t x = 0x32800000u; x < 0x48000000u; x += 97) check_half_rounding(bitsf(x));
    float edges[] = {0.0f, -0.0f, 65504.0f, 65519.996f, 65520.0f, 1e10f, INFINITY, -INFINITY,
                     NAN, 0x1p-24f, 0x1p-25f, 0x1.000002p-25f, 0x1.8p-24f, 0x1p-14f, 0x1.ffcp-15f,
                     1e-30f, 0x1p-149f};
    for (size_t i = 0; i < sizeof edges / sizeof edges[0]; i++) check_half_rounding(edges[i]);
    /* stated bound: normal range relative error <= 2^-11 (half an ulp of a 10-bit mantissa),
     * denormal range absolute error <= 2^-25 (half of the 2^-24 step) */
    for (int i = 0; i < 200000; i++) {
        float f = rnd_magnitude(-30, 15); /* below 2^15: no overflow to Inf */
        double back = (double)ibl_half_to_float(ibl_float_to_half(f));
        double err = fabs(back - (double)f);
        assert_true(err <= fmax((double)f * 0x1p-11, 0x1p-25));
    }
}

/* ---- RGB9E5 ---- */

/* Vulkan "Shared Exponent", transcribed formula by formula in double. */
static uint32_t ref_rgb9e5(const float in[3])
{
    const double N = 9, B = 15, Emax = 31;
    double sharedexp_max = (pow(2, N) - 1) / pow(2, N) * pow(2, Emax - B);
    double c[3];
    for (int i = 0; i < 3; i++) {
        double v = isnan(in[i]) ? 0.0 : (double)in[i];
        c[i] = fmax(0.0, fmin(sharedexp_max, v));
    }
    double max_c = fmax(c[0], fmax(c[1], c[2]));
    double exp_p = fmax(-B - 1, floor(log2(max_c))) + 1 + B; /* log2(0) = -inf */
    double max_s = floor(max_c / pow(2, exp_p - B - N) + 0.5);
    double exp_s = max_s < pow(2, N) ? exp_p : exp_p + 1;
    uint32_t out = (uint32_t)exp_s << 27;
    for (int i = 0; i < 3; i++) out |= (uint32_t)floor(c[i] / pow(2, exp_s - B - N) + 0.5) << (9 * i);
    return out;
}

static void check_rgb9e5(const float in[3])
{
    uint32_t got = ibl_pack_rgb9e5(in), want = ref_rgb9e5(in);
    if (got != want)
        fail_msg("rgb9e5(%a, %a, %a) = 0x%08x, reference 0x%08x", (double)in[0], (double)in[1],
                 (double)in[2], got, want);
    /* Stated bound: each channel is within half a step of its clamped input; the step is at
     * most 2^-8 of the largest channel (2^-8 * 512/511.5 after the max-mantissa bump), so the
     * error is <= 2^-9 * max * 512/511.5, and <= 2^-25 absolute below 2^-15 where the exponent
     * bottoms out. */
    float out[3];
    ibl_unpack_rgb9e5(got, out);
    double c[3], max_c = 0;
    for (int i = 0; i < 3; i++) {
        c[i] = !(in[i] > 0) ? 0.0 : fmin((double)in[i], 65408.0);
        max_c = fmax(max_c, c[i]);
    }
    for (int i = 0; i < 3; i++)
        assert_true(fabs((double)out[i] - c[i]) <= fmax(max_c * 0x1p-9 * 512.0 / 511.5, 0x1p-25));
}

static void rgb9e5_reference(void **state)
{
    (void)state;
    float edges[][3] = {
        {0, 0, 0}, {65408, 65408, 65408}, {65408, 1, 0}, {1e6f, 2, 3}, {INFINITY, 1, 1},
        {-1, -INFINITY, 5}, {NAN, 1, 2}, {NAN, NAN, NAN}, {0x1p-24f, 0, 0}, {0x1p-25f, 0x1p-26f, 0},
        {0x1.8p-25f, 0, 0}, {1e-30f, 1e-38f, 0}, {0x1p-149f, 0, 0}, {1, 1, 1}, {0.999f, 0.5f, 0},
        {0x1.ffp0f, 0, 0}, {0x1.ff8p0f, 1, 1}, {0x1.ffcp0f, 0, 1e-9f}, {65407.9f, 0, 0},
        {65472, 0, 0}, {-0.0f, 0.0f, -0.0f}, {1e-5f, 1e3f, 1e-8f}, {511.5f, 511.25f, 0.5f}};
    for (size_t i = 0; i < sizeof edges / sizeof edges[0]; i++) check_rgb9e5(edges[i]);
    for (int i = 0; i < 300000; i++) {
        float v[3];
        int base = -30 + (int)(rnd() % 48);
        for (int c = 0; c < 3; c++) {
            uint32_t kind = rnd() % 16;
            if (kind == 0) v[c] = 0;
            else if (kind == 1) v[c] = -rnd_magnitude(-10, 10);
            else if (kind < 8) v[c] = rnd_magnitude(base - 12, base + 1);
            else v[c] = rnd_magnitude(base, base + 1); /* same octave: the bump case */
        }
        check_rgb9e5(v);
    }
    /* every mantissa/exponent combination decodes to m * 2^(e - 24) */
    for (uint32_t e = 0; e < 32; e++)
        for (uint32_t m = 0; m < 512; m += 7) {
            float out[3];
            ibl_unpack_rgb9e5(m | (m << 9) | ((511 - m) << 18) | (e << 27), out);
            assert_true((double)out[0] == ldexp(m, (int)e - 24));
            assert_true((double)out[2] == ldexp(511 - m, (int)e - 24));
        }
}

/* ---- B10G11R11 ---- */

/* Value of an unsigned small float code from the spec: E = 0: 2^-14 * M / 2^mbits;
 * 0 < E < 31: 2^(E-15) * (1 + M / 2^mbits); E = 31: Inf (M = 0) or NaN. */
static double uf_value(uint32_t code, int mbits)
{
    uint32_t e = code >> mbits, m = code & ((1u << mbits) - 1);
    if (e == 31) return m ? NAN : INFINITY;
    if (e == 0) return ldexp((double)m / (1 << mbits), -14);
    return ldexp(1.0 + (double)m / (1 << mbits), (int)e - 15);
}

/* Reference: negatives -> 0, NaN -> a NaN code, +Inf -> Inf, above the largest finite value
 * -> the largest finite value, else the nearest code (ties to the even code). */
static uint32_t ref_uf(float f, int mbits)
{
    uint32_t inf = 31u << mbits, max_code = inf - 1;
    if (isnan(f)) return inf | 1; /* any NaN code: compared loosely */
    if (f <= 0) return 0;
    if (isinf(f)) return inf;
    double a = f;
    if (a >= uf_value(max_code, mbits)) return max_code;
    uint32_t lo = 0, hi = max_code;
    while (lo < hi) {
        uint32_t mid = (lo + hi + 1) / 2;
        if (uf_value(mid, mbits) <= a) lo = mid;
        else hi = mid - 1;
    }
    double dlo = a - uf_value(lo, mbits), dhi = uf_value(lo + 1, mbits) - a;
    return dlo < dhi ? lo : dhi < dlo ? lo + 1 : (lo % 2 == 0 ? lo : lo + 1);
}

static void check_rg11b10(const float in[3])
{
    uint32_t got = ibl_pack_rg11b10(in);
    uint32_t parts[3] = {got & 0x7ff, (got >> 11) & 0x7ff, got >> 22};
    int mb[3] = {6, 6, 5};
    for (int c = 0; c < 3; c++) {
        uint32_t want = ref_uf(in[c], mb[c]);
        if (isnan(in[c])) {
            assert_true((parts[c] >> mb[c]) == 31 && (parts[c] & ((1u << mb[c]) - 1)) != 0);
            continue;
        }
        if (parts[c] != want)
            fail_msg("channel %d of %a: code 0x%03x, reference 0x%03x", c, (double)in[c], parts[c], want);
        /* Stated bound within range: half an ulp, <= 2^-(mbits+1) relative in the normal range
         * and 2^(-15-mbits) absolute in the denormal range. */
        double maxv = uf_value((31u << mb[c]) - 1, mb[c]);
        if (in[c] > 0 && (double)in[c] <= maxv) {
            float out[3];
            ibl_unpack_rg11b10(got, out);
            double err = fabs((double)out[c] - (double)in[c]);
            assert_true(err <= fmax((double)in[c] * ldexp(1, -(mb[c] + 1)), ldexp(1, -15 - mb[c])));
        }
    }
}

static void rg11b10_reference(void **state)
{
    (void)state;
    /* every code of each field decodes to its spec value and re-encodes to itself */
    for (int field = 0; field < 3; field++) {
        int mb = field == 2 ? 5 : 6, shift = field * 11;
        for (uint32_t code = 0; code < (32u << mb); code++) {
            float out[3];
            ibl_unpack_rg11b10(code << shift, out);
            double v = uf_value(code, mb);
            if (isnan(v)) {
                assert_true(isnan(out[field]));
                continue;
            }
            assert_true((double)out[field] == v);
            float in[3] = {0, 0, 0};
            in[field] = out[field];
            assert_int_equal((ibl_pack_rg11b10(in) >> shift) & ((32u << mb) - 1), code);
        }
    }
    float edges[][3] = {{0, 0, 0}, {-1, -0.0f, -INFINITY}, {INFINITY, NAN, 1}, {65024, 64512, 64512},
                        {65535, 1e9f, 64600}, {0x1p-20f, 0x1p-21f, 0x1p-19f}, {0x1.8p-21f, 0x1p-22f, 0x1p-20f},
                        {1, 0.5f, 0.25f}, {0x1.02p0f, 0x1.06p0f, 0x1.04p0f}, {1e-30f, 0x1p-149f, 1e-38f}};
    for (size_t i = 0; i < sizeof edges / sizeof edges[0]; i++) check_rg11b10(edges[i]);
    for (int i = 0; i < 300000; i++) {
        float v[3];
        for (int c = 0; c < 3; c++) {
            uint32_t kind = rnd() % 16;
            v[c] = kind == 0 ? -rnd_magnitude(-5, 5) : rnd_magnitude(-24, 17);
        }
        check_rg11b10(v);
    }
}

/* ---- texel helpers ---- */

/* ibl_pack_texels to RGBA16F converts most texels several at a time: every value must still
 * be the nearest half of the reference, whatever else shares its group (denormal halves,
 * overflow, Inf and NaN fall back to the one-value path) and at every count and offset;
 * storage saturates: a value past 65504 (infinity included) is stored as 65504 and counted,
 * never as infinity (ibl would not read it back). */
static void half_bulk_packing(void **state)
{
    (void)state;
    for (int i = 0; i < 0x7c00; i++) half_table[i] = half_value((uint16_t)i);
    enum { N = 67 };
    float src[N * 4];
    uint8_t buf[N * 8 + 8];
    for (int round = 0; round < 400; round++) {
        for (int i = 0; i < N * 4; i++) {
            uint32_t kind = rnd() % 16;
            float v;
            if (kind == 0) v = rnd_magnitude(-40, -14);      /* half denormals, float tiny */
            else if (kind == 1) v = rnd_magnitude(15, 20);   /* overflow region */
            else if (kind == 2) v = (rnd() & 1) ? INFINITY : NAN;
            else if (kind == 3) v = bitsf(rnd() & 0x007fffffu); /* float denormals and 0 */
            else if (kind == 4) v = bitsf((rnd() % 45 + 100) << 23 | 0x1000u); /* a tie */
            else v = rnd_magnitude(-14, 16);
            src[i] = (rnd() & 1) ? -v : v;
        }
        /* mostly-ordinary rounds too: whole groups on the fast path */
        if (round % 2)
            for (int i = 0; i < N * 4; i++) src[i] = rnd_magnitude(-14, 16);
        size_t count = 1 + rnd() % N, first = rnd() % (N - count + 1);
        memset(buf, 0xAA, sizeof buf);
        size_t clamped = ibl_pack_texels(IBL_FORMAT_RGBA16F, src + first * 4, count, buf);
        assert_int_equal(buf[count * 8], 0xAA);
        size_t over = 0;
        for (size_t t = 0; t < count; t++) {
            int o = 0;
            for (int c = 0; c < 4; c++) o |= fabsf(src[(first + t) * 4 + (size_t)c]) > 65504.0f;
            over += (size_t)o;
        }
        assert_int_equal(clamped, over);
        for (size_t i = 0; i < count * 4; i++) {
            float f = src[first * 4 + i];
            uint16_t got = (uint16_t)(buf[2 * i] | buf[2 * i + 1] << 8);
            if (isnan(f)) {
                assert_int_equal(got, ibl_float_to_half(f)); /* NaN stays NaN */
                continue;
            }
            float stored = fabsf(f) > 65504.0f ? copysignf(65504.0f, f) : f;
            if (got != ref_float_to_half(stored))
                fail_msg("float %a: half 0x%04x, reference 0x%04x", (double)f, got, ref_float_to_half(stored));
        }
    }
}

/* ibl_unpack_texels from RGBA16F converts two texels at a time: every one of the 65,536 codes
 * (as 16,384 texels, each code once in each channel) must give the bits of ibl_half_to_float,
 * itself checked against the codes' values in double above (denormals, signed zeros, Inf and
 * NaN payloads included), and so must every count and start, odd ones ending on the one-texel
 * path. */
static void half_bulk_unpacking(void **state)
{
    (void)state;
    enum { TEXELS = 16384 };
    uint8_t *buf = malloc(TEXELS * 8);
    float *out = malloc((TEXELS + 1) * 4 * sizeof(float));
    assert_non_null(buf);
    assert_non_null(out);
    for (int shift = 0; shift < 4; shift++) {
        for (uint32_t t = 0; t < TEXELS; t++)
            for (uint32_t c = 0; c < 4; c++) {
                uint16_t h = (uint16_t)(t * 4 + (c + (uint32_t)shift) % 4);
                buf[t * 8 + c * 2] = (uint8_t)h;
                buf[t * 8 + c * 2 + 1] = (uint8_t)(h >> 8);
            }
        size_t first = (size_t)shift, count = TEXELS - (size_t)shift * 3;
        out[count * 4] = 12345.0f;
        ibl_unpack_texels(IBL_FORMAT_RGBA16F, buf + first * 8, count, out);
        assert_true(out[count * 4] == 12345.0f); /* nothing written past the texels */
        for (size_t i = 0; i < count * 4; i++) {
            uint16_t h = (uint16_t)(buf[first * 8 + 2 * i] | buf[first * 8 + 2 * i + 1] << 8);
            if (fbits(out[i]) != fbits(ibl_half_to_float(h)))
                fail_msg("half 0x%04x: 0x%08x, one at a time 0x%08x", h, fbits(out[i]),
                         fbits(ibl_half_to_float(h)));
        }
    }
    free(out);
    free(buf);
}

static void texel_packing(void **state)
{
    (void)state;
    struct { ibl_format f; size_t bytes; int channels; } table[] = {
        {IBL_FORMAT_RGBA16F, 8, 4}, {IBL_FORMAT_RGBA32F, 16, 4}, {IBL_FORMAT_RG11B10F, 4, 3},
        {IBL_FORMAT_RGB9E5, 4, 3},  {IBL_FORMAT_RG16F, 4, 2},    {IBL_FORMAT_RG32F, 8, 2},
        {IBL_FORMAT_RGB32F, 12, 3}, {IBL_FORMAT_RGB16F, 6, 3}};
    float src[3 * 4] = {1.0f, -2.0f, 0.5f, 0.25f, 3.0f, 0.0f, 65504.0f, 1.0f, 0.125f, 7.0f, 1e-3f, 0.0f};
    for (size_t i = 0; i < sizeof table / sizeof table[0]; i++) {
        ibl_format f = table[i].f;
        assert_int_equal(ibl_format_texel_bytes(f), table[i].bytes);
        assert_int_equal(ibl_format_channels(f), table[i].channels);
        uint8_t buf[3 * 16 + 1];
        memset(buf, 0xAA, sizeof buf);
        ibl_pack_texels(f, src, 3, buf);
        assert_int_equal(buf[3 * table[i].bytes], 0xAA); /* writes exactly 3 texels */
        float out[12];
        ibl_unpack_texels(f, buf, 3, out);
        for (int t = 0; t < 3; t++) {
            for (int c = table[i].channels; c < 4; c++)
                assert_true(out[t * 4 + c] == (c == 3 ? 1.0f : 0.0f)); /* missing: 0, 0, 1 */
            if (f == IBL_FORMAT_RGBA32F || f == IBL_FORMAT_RG32F || f == IBL_FORMAT_RGB32F)
                for (int c = 0; c < table[i].channels; c++)
                    assert_true(fbits(out[t * 4 + c]) == fbits(src[t * 4 + c]));
        }
    }
    /* little-endian byte order, checked on known encodings */
    uint8_t b[16];
    float one[4] = {1.0f, 2.0f, 0.0f, 1.0f};
    ibl_pack_texels(IBL_FORMAT_RGBA16F, one, 1, b);
    const uint8_t want16[8] = {0x00, 0x3C, 0x00, 0x40, 0x00, 0x00, 0x00, 0x3C};
    assert_memory_equal(b, want16, 8);
    ibl_pack_texels(IBL_FORMAT_RGB9E5, one, 1, b);
    /* 2.0 is the max: exp' = 1 + 16 = 17, 2 / 2^(17-24) = 256; 1.0 -> 128;
     * word = 128 | 256 << 9 | 17 << 27 = 0x88020080 */
    const uint8_t want9e5[4] = {0x80, 0x00, 0x02, 0x88};
    assert_memory_equal(b, want9e5, 4);
    ibl_pack_texels(IBL_FORMAT_RG11B10F, one, 1, b);
    /* R 1.0 = E15 M0 = 0x3C0; G 2.0 = E16 = 0x400 at bit 11; B 0 */
    uint32_t w = 0x3C0u | (0x400u << 11);
    const uint8_t want11[4] = {(uint8_t)w, (uint8_t)(w >> 8), (uint8_t)(w >> 16), (uint8_t)(w >> 24)};
    assert_memory_equal(b, want11, 4);
    /* formats whose encoding is an image writer's business report 0 bytes */
    assert_int_equal(ibl_format_texel_bytes(IBL_FORMAT_RGBE), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(half_exhaustive),
        cmocka_unit_test(half_rounding),
        cmocka_unit_test(rgb9e5_reference),
        cmocka_unit_test(rg11b10_reference),
        cmocka_unit_test(texel_packing),
        cmocka_unit_test(half_bulk_packing),
        cmocka_unit_test(half_bulk_unpacking),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
