/* BC6H tables and bit helpers shared by the encoder and the decoder. Every layout below is
 * the Khronos Data Format Specification 1.3, section "BC6H" (within "BPTC Compressed Texture
 * Image Formats"), cross-checked with Microsoft's "BC6H Format". Internal. */
#ifndef IBL_COMPRESS_BC6H_INTERNAL_H
#define IBL_COMPRESS_BC6H_INTERNAL_H

#include <stdint.h>

/* Fields of a block description: the endpoint channels R0 G0 B0 R1 ... B3 (field 3 k + c
 * for endpoint E_k, channel c), the mode bits and the partition bits. */
enum { BC6H_FIELD_M = 12, BC6H_FIELD_PB = 13, BC6H_MODES = 14, BC6H_PARTITIONS = 32 };

/* One element v^{a..b} of the spec's "Block descriptions for BC6H block modes": the next
 * |a - b| + 1 bits of the block go to bits b, b+1, ..., a of v when a >= b, and to bits
 * b, b-1, ..., a (reversed) when a < b. */
typedef struct bc6h_seg {
    uint8_t field, a, b;
} bc6h_seg;

typedef struct bc6h_mode {
    uint8_t number;      /* value of the mode bits (M): 0, 1, 2, 6, ..., 30, 3, 7, 11, 15 */
    uint8_t regions;     /* 2: partition bits and 3-bit indices; 1: 4-bit indices         */
    uint8_t transformed; /* endpoints other than E0 are deltas from E0                     */
    uint8_t prec;        /* endpoint bits (EPB)                                            */
    uint8_t delta[3];    /* delta bits per channel (= prec when not transformed)           */
    uint8_t seg_count;
    const bc6h_seg *segs;
} bc6h_mode;

/* The 14 modes: the ten two-region modes in precision order of the spec's table
 * (0, 1, 2, 6, 10, 14, 18, 22, 26, 30), then the one-region modes (3, 7, 11, 15). */
extern const bc6h_mode ibl__bc6h_modes[BC6H_MODES];
/* Subset of texel i (bit i) for each of the first 32 two-subset BPTC partitions. */
extern const uint16_t ibl__bc6h_partitions[BC6H_PARTITIONS];
/* Anchor texel of the second subset ("BPTC anchor index values for the second subset of
 * two-subset partitioning", first 32 entries). */
extern const uint8_t ibl__bc6h_anchor2[BC6H_PARTITIONS];
/* "BPTC interpolation factors" for 3- and 4-bit indices. */
extern const uint8_t ibl__bc6h_weights3[8];
extern const uint8_t ibl__bc6h_weights4[16];

/* Index into ibl__bc6h_modes of the block's mode, or -1 for a reserved mode (19, 23, 27,
 * 31): the low two bits are the mode when below 2, else the low five bits. */
int ibl__bc6h_mode_index(const uint8_t block[16]);

/* The unquantization of an endpoint of `prec` bits (sign-extended when is_signed). */
static inline int ibl__bc6h_unquantize(int x, int prec, int is_signed)
{
    if (!is_signed) {
        if (prec >= 15) return x;
        if (x == 0) return 0;
        if (x == (1 << prec) - 1) return 0xFFFF;
        return ((x << 15) + 0x4000) >> (prec - 1);
    }
    if (prec >= 16) return x;
    int s = x < 0;
    if (s) x = -x;
    int unq;
    if (x == 0) unq = 0;
    else if (x >= (1 << (prec - 1)) - 1) unq = 0x7FFF;
    else unq = ((x << 15) + 0x4000) >> (prec - 1);
    return s ? -unq : unq;
}

/* The interpolation of two unquantized endpoints with a 6-bit weight. */
static inline int ibl__bc6h_interpolate(int a, int b, int w)
{
    return (a * (64 - w) + b * w + 32) >> 6;
}

/* The final unquantization to a half-float bit pattern. */
static inline uint16_t ibl__bc6h_finish(int i, int is_signed)
{
    if (!is_signed) return (uint16_t)((i * 31) >> 6);
    return (uint16_t)(i < 0 ? (((-i) * 31) >> 5) | 0x8000 : (i * 31) >> 5);
}

static inline int ibl__bc6h_sign_extend(int v, int bits)
{
    int m = 1 << (bits - 1);
    v &= (1 << bits) - 1;
    return (v ^ m) - m;
}

/* Little-endian bit access to a 128-bit block. */
static inline unsigned ibl__bc6h_get_bits(const uint8_t *block, int pos, int n)
{
    unsigned v = 0;
    for (int i = 0; i < n; i++, pos++) v |= (unsigned)((block[pos >> 3] >> (pos & 7)) & 1) << i;
    return v;
}

static inline void ibl__bc6h_put_bits(uint8_t *block, int pos, int n, unsigned v)
{
    for (int i = 0; i < n; i++, pos++)
        if ((v >> i) & 1) block[pos >> 3] |= (uint8_t)(1u << (pos & 7));
}

#endif
