/* Test vectors for an independent BC6H decoder (ibl_bc6h_test_vectors): blocks with random
 * fields for every mode in turn, and blocks this encoder makes from smooth HDR gradients,
 * each with the texels ibl_bc6h_decode_block returns. */
#include <math.h>
#include <string.h>

#include "ibl/compress.h"
#include "compress/bc6h_internal.h"

static uint64_t next(uint64_t *s) /* splitmix64 */
{
    uint64_t z = (*s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

static void random_block(uint64_t *s, int mode_index, uint8_t block[16])
{
    uint64_t a = next(s), b = next(s);
    for (int i = 0; i < 8; i++) block[i] = (uint8_t)(a >> (8 * i)), block[8 + i] = (uint8_t)(b >> (8 * i));
    int number = ibl__bc6h_modes[mode_index].number;
    if (number < 2) block[0] = (uint8_t)((block[0] & ~3u) | (unsigned)number);
    else block[0] = (uint8_t)((block[0] & ~31u) | (unsigned)number);
}

static void gradient_block(uint64_t *s, int is_signed, ibl_quality q, uint8_t block[16])
{
    float texels[64];
    float base = ldexpf(1.0f, (int)(next(s) % 40) - 20), c[3], d[3];
    for (int k = 0; k < 3; k++) {
        c[k] = base * (0.25f + (float)(next(s) % 1000) / 1000.0f);
        d[k] = base * ((float)(next(s) % 2000) / 1000.0f - 1.0f) * 0.5f;
    }
    for (int t = 0; t < 16; t++) {
        float u = (float)(t & 3) / 3.0f, v = (float)(t >> 2) / 3.0f;
        for (int k = 0; k < 3; k++) {
            float x = c[k] + d[k] * (u + v) * 0.5f;
            texels[4 * t + k] = is_signed ? x * ((t & 1) && k == 0 ? -1.0f : 1.0f) : fabsf(x);
        }
        texels[4 * t + 3] = 1.0f;
    }
    ibl_bc6h_desc desc = {is_signed, q};
    ibl_bc6h_encode_block(&desc, texels, block);
}

void ibl_bc6h_test_vectors(uint64_t seed, int count, int is_signed, uint8_t *blocks,
                           uint16_t *expected)
{
    uint64_t s = seed;
    for (int i = 0; i < count; i++) {
        uint8_t *b = blocks + (size_t)i * 16;
        if (i % 4 == 3) gradient_block(&s, is_signed, (ibl_quality)(i / 4 % 3), b);
        else random_block(&s, (i - i / 4) % BC6H_MODES, b);
        ibl_bc6h_decode_block(b, is_signed, expected + (size_t)i * 48);
    }
}
