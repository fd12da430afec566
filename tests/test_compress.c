/* BC6H, the 8-bit HDR encodings and their containers.
 *
 * The decoder is checked against an independent reference written here: blocks are
 * assembled bit by bit from the Khronos Data Format Specification 1.3's per-bit tables
 * ("Interpretation of lower/upper bits for BC6H block modes", a different table from the
 * block descriptions the library transcribes), and decoded in float64 from the spec's
 * formulas (sign extension, transform inversion, unquantization, the weight formulas,
 * interpolation, final unquantization). The encoder is checked by round trips on synthetic
 * and real HDRIs (RMS of log2(1 + x), per channel), thread-count identity and padding of the
 * small mips; the containers by round trips, their header fields, Zstandard
 * supercompression and malformed files. */
#include "test_support.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/io_internal.h"

#include <unistd.h>

/* Acceptance bounds on the RMS of log2(1 + x) differences: the measured errors plus a
 * quarter (docs/FORMATS.md, "BC6H"), so that a change that makes the encoder worse fails. */
#define SYNTH_FAST_BOUND 0.0092
#define SYNTH_DEFAULT_BOUND 0.0092

/* ---- the spec's tables, as the test reads them ---- */

typedef struct spec_mode {
    int number, transformed, prec, delta[3], regions;
    const char *bits; /* bits 0..81: M<value>, P<bit>, <R|G|B><endpoint>.<bit>, or I (index) */
} spec_mode;

/* "Endpoint and partition parameters for BPTC block modes" and the per-bit tables. */
static const spec_mode SPEC[14] = {
    {0, 1, 10, {5, 5, 5}, 2,
     "M0 M0 G2.4 B2.4 B3.4 R0.0 R0.1 R0.2 R0.3 R0.4 R0.5 R0.6 R0.7 R0.8 R0.9 G0.0 "
     "G0.1 G0.2 G0.3 G0.4 G0.5 G0.6 G0.7 G0.8 G0.9 B0.0 B0.1 B0.2 B0.3 B0.4 B0.5 "
     "B0.6 B0.7 B0.8 B0.9 R1.0 R1.1 R1.2 R1.3 R1.4 G3.4 G2.0 G2.1 G2.2 G2.3 G1.0 "
     "G1.1 G1.2 G1.3 G1.4 B3.0 G3.0 G3.1 G3.2 G3.3 B1.0 B1.1 B1.2 B1.3 B1.4 B3.1 "
     "B2.0 B2.1 B2.2 B2.3 R2.0 R2.1 R2.2 R2.3 R2.4 B3.2 R3.0 R3.1 R3.2 R3.3 R3.4 "
     "B3.3 P0 P1 P2 P3 P4"},
    {1, 1, 7, {6, 6, 6}, 2,
     "M1 M0 G2.5 G3.4 G3.5 R0.0 R0.1 R0.2 R0.3 R0.4 R0.5 R0.6 B3.0 B3.1 B2.4 G0.0 "
     "G0.1 G0.2 G0.3 G0.4 G0.5 G0.6 B2.5 B3.2 G2.4 B0.0 B0.1 B0.2 B0.3 B0.4 B0.5 "
     "B0.6 B3.3 B3.5 B3.4 R1.0 R1.1 R1.2 R1.3 R1.4 R1.5 G2.0 G2.1 G2.2 G2.3 G1.0 "
     "G1.1 G1.2 G1.3 G1.4 G1.5 G3.0 G3.1 G3.2 G3.3 B1.0 B1.1 B1.2 B1.3 B1.4 B1.5 "
     "B2.0 B2.1 B2.2 B2.3 R2.0 R2.1 R2.2 R2.3 R2.4 R2.5 R3.0 R3.1 R3.2 R3.3 R3.4 "
     "R3.5 P0 P1 P2 P3 P4"},
    {2, 1, 11, {5, 4, 4}, 2,
     "M0 M1 M0 M0 M0 R0.0 R0.1 R0.2 R0.3 R0.4 R0.5 R0.6 R0.7 R0.8 R0.9 G0.0 G0.1 "
     "G0.2 G0.3 G0.4 G0.5 G0.6 G0.7 G0.8 G0.9 B0.0 B0.1 B0.2 B0.3 B0.4 B0.5 B0.6 "
     "B0.7 B0.8 B0.9 R1.0 R1.1 R1.2 R1.3 R1.4 R0.10 G2.0 G2.1 G2.2 G2.3 G1.0 G1.1 "
     "G1.2 G1.3 G0.10 B3.0 G3.0 G3.1 G3.2 G3.3 B1.0 B1.1 B1.2 B1.3 B0.10 B3.1 B2.0 "
     "B2.1 B2.2 B2.3 R2.0 R2.1 R2.2 R2.3 R2.4 B3.2 R3.0 R3.1 R3.2 R3.3 R3.4 B3.3 P0 "
     "P1 P2 P3 P4"},
    {6, 1, 11, {4, 5, 4}, 2,
     "M0 M1 M1 M0 M0 R0.0 R0.1 R0.2 R0.3 R0.4 R0.5 R0.6 R0.7 R0.8 R0.9 G0.0 G0.1 "
     "G0.2 G0.3 G0.4 G0.5 G0.6 G0.7 G0.8 G0.9 B0.0 B0.1 B0.2 B0.3 B0.4 B0.5 B0.6 "
     "B0.7 B0.8 B0.9 R1.0 R1.1 R1.2 R1.3 R0.10 G3.4 G2.0 G2.1 G2.2 G2.3 G1.0 G1.1 "
     "G1.2 G1.3 G1.4 G0.10 G3.0 G3.1 G3.2 G3.3 B1.0 B1.1 B1.2 B1.3 B0.10 B3.1 B2.0 "
     "B2.1 B2.2 B2.3 R2.0 R2.1 R2.2 R2.3 B3.0 B3.2 R3.0 R3.1 R3.2 R3.3 G2.4 B3.3 P0 "
     "P1 P2 P3 P4"},
    {10, 1, 11, {4, 4, 5}, 2,
     "M0 M1 M0 M1 M0 R0.0 R0.1 R0.2 R0.3 R0.4 R0.5 R0.6 R0.7 R0.8 R0.9 G0.0 G0.1 "
     "G0.2 G0.3 G0.4 G0.5 G0.6 G0.7 G0.8 G0.9 B0.0 B0.1 B0.2 B0.3 B0.4 B0.5 B0.6 "
     "B0.7 B0.8 B0.9 R1.0 R1.1 R1.2 R1.3 R0.10 B2.4 G2.0 G2.1 G2.2 G2.3 G1.0 G1.1 "
     "G1.2 G1.3 G0.10 B3.0 G3.0 G3.1 G3.2 G3.3 B1.0 B1.1 B1.2 B1.3 B1.4 B0.10 B2.0 "
     "B2.1 B2.2 B2.3 R2.0 R2.1 R2.2 R2.3 B3.1 B3.2 R3.0 R3.1 R3.2 R3.3 B3.4 B3.3 P0 "
     "P1 P2 P3 P4"},
    {14, 1, 9, {5, 5, 5}, 2,
     "M0 M1 M1 M1 M0 R0.0 R0.1 R0.2 R0.3 R0.4 R0.5 R0.6 R0.7 R0.8 B2.4 G0.0 G0.1 "
     "G0.2 G0.3 G0.4 G0.5 G0.6 G0.7 G0.8 G2.4 B0.0 B0.1 B0.2 B0.3 B0.4 B0.5 B0.6 "
     "B0.7 B0.8 B3.4 R1.0 R1.1 R1.2 R1.3 R1.4 G3.4 G2.0 G2.1 G2.2 G2.3 G1.0 G1.1 "
     "G1.2 G1.3 G1.4 B3.0 G3.0 G3.1 G3.2 G3.3 B1.0 B1.1 B1.2 B1.3 B1.4 B3.1 B2.0 "
     "B2.1 B2.2 B2.3 R2.0 R2.1 R2.2 R2.3 R2.4 B3.2 R3.0 R3.1 R3.2 R3.3 R3.4 B3.3 P0 "
     "P1 P2 P3 P4"},
    {18, 1, 8, {6, 5, 5}, 2,
     "M0 M1 M0 M0 M1 R0.0 R0.1 R0.2 R0.3 R0.4 R0.5 R0.6 R0.7 G3.4 B2.4 G0.0 G0.1 "
     "G0.2 G0.3 G0.4 G0.5 G0.6 G0.7 B3.2 G2.4 B0.0 B0.1 B0.2 B0.3 B0.4 B0.5 B0.6 "
     "B0.7 B3.3 B3.4 R1.0 R1.1 R1.2 R1.3 R1.4 R1.5 G2.0 G2.1 G2.2 G2.3 G1.0 G1.1 "
     "G1.2 G1.3 G1.4 B3.0 G3.0 G3.1 G3.2 G3.3 B1.0 B1.1 B1.2 B1.3 B1.4 B3.1 B2.0 "
     "B2.1 B2.2 B2.3 R2.0 R2.1 R2.2 R2.3 R2.4 R2.5 R3.0 R3.1 R3.2 R3.3 R3.4 R3.5 P0 "
     "P1 P2 P3 P4"},
    {22, 1, 8, {5, 6, 5}, 2,
     "M0 M1 M1 M0 M1 R0.0 R0.1 R0.2 R0.3 R0.4 R0.5 R0.6 R0.7 B3.0 B2.4 G0.0 G0.1 "
     "G0.2 G0.3 G0.4 G0.5 G0.6 G0.7 G2.5 G2.4 B0.0 B0.1 B0.2 B0.3 B0.4 B0.5 B0.6 "
     "B0.7 G3.5 B3.4 R1.0 R1.1 R1.2 R1.3 R1.4 G3.4 G2.0 G2.1 G2.2 G2.3 G1.0 G1.1 "
     "G1.2 G1.3 G1.4 G1.5 G3.0 G3.1 G3.2 G3.3 B1.0 B1.1 B1.2 B1.3 B1.4 B3.1 B2.0 "
     "B2.1 B2.2 B2.3 R2.0 R2.1 R2.2 R2.3 R2.4 B3.2 R3.0 R3.1 R3.2 R3.3 R3.4 B3.3 P0 "
     "P1 P2 P3 P4"},
    {26, 1, 8, {5, 5, 6}, 2,
     "M0 M1 M0 M1 M1 R0.0 R0.1 R0.2 R0.3 R0.4 R0.5 R0.6 R0.7 B3.1 B2.4 G0.0 G0.1 "
     "G0.2 G0.3 G0.4 G0.5 G0.6 G0.7 B2.5 G2.4 B0.0 B0.1 B0.2 B0.3 B0.4 B0.5 B0.6 "
     "B0.7 B3.5 B3.4 R1.0 R1.1 R1.2 R1.3 R1.4 G3.4 G2.0 G2.1 G2.2 G2.3 G1.0 G1.1 "
     "G1.2 G1.3 G1.4 B3.0 G3.0 G3.1 G3.2 G3.3 B1.0 B1.1 B1.2 B1.3 B1.4 B1.5 B2.0 "
     "B2.1 B2.2 B2.3 R2.0 R2.1 R2.2 R2.3 R2.4 B3.2 R3.0 R3.1 R3.2 R3.3 R3.4 B3.3 P0 "
     "P1 P2 P3 P4"},
    {30, 0, 6, {6, 6, 6}, 2,
     "M0 M1 M1 M1 M1 R0.0 R0.1 R0.2 R0.3 R0.4 R0.5 G3.4 B3.0 B3.1 B2.4 G0.0 G0.1 "
     "G0.2 G0.3 G0.4 G0.5 G2.5 B2.5 B3.2 G2.4 B0.0 B0.1 B0.2 B0.3 B0.4 B0.5 G3.5 "
     "B3.3 B3.5 B3.4 R1.0 R1.1 R1.2 R1.3 R1.4 R1.5 G2.0 G2.1 G2.2 G2.3 G1.0 G1.1 "
     "G1.2 G1.3 G1.4 G1.5 G3.0 G3.1 G3.2 G3.3 B1.0 B1.1 B1.2 B1.3 B1.4 B1.5 B2.0 "
     "B2.1 B2.2 B2.3 R2.0 R2.1 R2.2 R2.3 R2.4 R2.5 R3.0 R3.1 R3.2 R3.3 R3.4 R3.5 P0 "
     "P1 P2 P3 P4"},
    {3, 0, 10, {10, 10, 10}, 1,
     "M1 M1 M0 M0 M0 R0.0 R0.1 R0.2 R0.3 R0.4 R0.5 R0.6 R0.7 R0.8 R0.9 G0.0 G0.1 "
     "G0.2 G0.3 G0.4 G0.5 G0.6 G0.7 G0.8 G0.9 B0.0 B0.1 B0.2 B0.3 B0.4 B0.5 B0.6 "
     "B0.7 B0.8 B0.9 R1.0 R1.1 R1.2 R1.3 R1.4 R1.5 R1.6 R1.7 R1.8 R1.9 G1.0 G1.1 "
     "G1.2 G1.3 G1.4 G1.5 G1.6 G1.7 G1.8 G1.9 B1.0 B1.1 B1.2 B1.3 B1.4 B1.5 B1.6 "
     "B1.7 B1.8 B1.9 I I I I I I I I I I I I I I I I I"},
    {7, 1, 11, {9, 9, 9}, 1,
     "M1 M1 M1 M0 M0 R0.0 R0.1 R0.2 R0.3 R0.4 R0.5 R0.6 R0.7 R0.8 R0.9 G0.0 G0.1 "
     "G0.2 G0.3 G0.4 G0.5 G0.6 G0.7 G0.8 G0.9 B0.0 B0.1 B0.2 B0.3 B0.4 B0.5 B0.6 "
     "B0.7 B0.8 B0.9 R1.0 R1.1 R1.2 R1.3 R1.4 R1.5 R1.6 R1.7 R1.8 R0.10 G1.0 G1.1 "
     "G1.2 G1.3 G1.4 G1.5 G1.6 G1.7 G1.8 G0.10 B1.0 B1.1 B1.2 B1.3 B1.4 B1.5 B1.6 "
     "B1.7 B1.8 B0.10 I I I I I I I I I I I I I I I I I"},
    {11, 1, 12, {8, 8, 8}, 1,
     "M1 M1 M0 M1 M0 R0.0 R0.1 R0.2 R0.3 R0.4 R0.5 R0.6 R0.7 R0.8 R0.9 G0.0 G0.1 "
     "G0.2 G0.3 G0.4 G0.5 G0.6 G0.7 G0.8 G0.9 B0.0 B0.1 B0.2 B0.3 B0.4 B0.5 B0.6 "
     "B0.7 B0.8 B0.9 R1.0 R1.1 R1.2 R1.3 R1.4 R1.5 R1.6 R1.7 R0.11 R0.10 G1.0 G1.1 "
     "G1.2 G1.3 G1.4 G1.5 G1.6 G1.7 G0.11 G0.10 B1.0 B1.1 B1.2 B1.3 B1.4 B1.5 B1.6 "
     "B1.7 B0.11 B0.10 I I I I I I I I I I I I I I I I I"},
    {15, 1, 16, {4, 4, 4}, 1,
     "M1 M1 M1 M1 M0 R0.0 R0.1 R0.2 R0.3 R0.4 R0.5 R0.6 R0.7 R0.8 R0.9 G0.0 G0.1 "
     "G0.2 G0.3 G0.4 G0.5 G0.6 G0.7 G0.8 G0.9 B0.0 B0.1 B0.2 B0.3 B0.4 B0.5 B0.6 "
     "B0.7 B0.8 B0.9 R1.0 R1.1 R1.2 R1.3 R0.15 R0.14 R0.13 R0.12 R0.11 R0.10 G1.0 "
     "G1.1 G1.2 G1.3 G0.15 G0.14 G0.13 G0.12 G0.11 G0.10 B1.0 B1.1 B1.2 B1.3 B0.15 "
     "B0.14 B0.13 B0.12 B0.11 B0.10 I I I I I I I I I I I I I I I I I"},
};

/* The first 32 partitions of "Partition table for 2-subset BPTC" (texel 4 y + x), and the
 * anchors of "BPTC anchor index values for the second subset of two-subset partitioning". */
static const char *const PARTITION[32] = {
    "0011001100110011", "0001000100010001", "0111011101110111", "0001001100110111",
    "0000000100010011", "0011011101111111", "0001001101111111", "0000000100110111",
    "0000000000010011", "0011011111111111", "0000000101111111", "0000000000010111",
    "0001011111111111", "0000000011111111", "0000111111111111", "0000000000001111",
    "0000100011101111", "0111000100000000", "0000000010001110", "0111001100010000",
    "0011000100000000", "0000100011001110", "0000000010001100", "0111001100110001",
    "0011000100010000", "0000100010001100", "0110011001100110", "0011011001101100",
    "0001011111101000", "0000111111110000", "0111000110001110", "0011100110011100",
};
static const int ANCHOR2[32] = {15, 15, 15, 15, 15, 15, 15, 15, 15, 15, 15, 15, 15, 15, 15, 15,
                                15, 2,  8,  2,  2,  8,  8,  15, 2,  8,  2,  2,  8,  8,  2,  2};

/* The fields of a block as the reference sees them. */
typedef struct fields {
    const spec_mode *mode;
    unsigned e[4][3]; /* raw endpoint fields as stored */
    int partition;
    int index[16];
} fields;

static const spec_mode *spec_of(int number)
{
    for (int i = 0; i < 14; i++)
        if (SPEC[i].number == number) return &SPEC[i];
    return NULL;
}

/* Token k (0-based) of a mode's bit string, copied into tok. */
static void token(const spec_mode *m, int k, char tok[8])
{
    const char *p = m->bits;
    for (int i = 0; i < k; i++) p = strchr(p, ' ') + 1;
    size_t n = strcspn(p, " ");
    memcpy(tok, p, n);
    tok[n] = 0;
}

static int endpoint_bits(const spec_mode *m) { return m->regions == 2 ? 82 : 65; }

/* Bit offset and length of the index of texel i (the spec's formula). */
static void index_bits(const spec_mode *m, int partition, int i, int *pos, int *len)
{
    if (m->regions == 1) {
        *pos = i == 0 ? 65 : 65 + 4 * i - 1;
        *len = i == 0 ? 3 : 4;
        return;
    }
    int anchor = ANCHOR2[partition];
    *pos = i == 0 ? 82 : i <= anchor ? 82 + 3 * i - 1 : 82 + 3 * i - 2;
    *len = (i == 0 || i == anchor) ? 2 : 3;
}

static int get_bit(const uint8_t *b, int pos) { return (b[pos / 8] >> (pos % 8)) & 1; }
static void set_bit(uint8_t *b, int pos, int v)
{
    if (v) b[pos / 8] |= (uint8_t)(1 << (pos % 8));
}

static int channel_of(char c) { return c == 'R' ? 0 : c == 'G' ? 1 : 2; }

static void assemble(const fields *f, uint8_t block[16])
{
    memset(block, 0, 16);
    char tok[8];
    for (int k = 0; k < endpoint_bits(f->mode); k++) {
        token(f->mode, k, tok);
        if (tok[0] == 'M') set_bit(block, k, tok[1] == '1');
        else if (tok[0] == 'P') set_bit(block, k, (f->partition >> atoi(tok + 1)) & 1);
        else if (tok[0] != 'I')
            set_bit(block, k, (f->e[tok[1] - '0'][channel_of(tok[0])] >> atoi(tok + 3)) & 1);
    }
    for (int i = 0; i < 16; i++) {
        int pos, len;
        index_bits(f->mode, f->partition, i, &pos, &len);
        for (int b = 0; b < len; b++) set_bit(block, pos + b, (f->index[i] >> b) & 1);
    }
}

/* Parses a block with the per-bit table; NULL mode for the reserved modes. */
static void disassemble(const uint8_t block[16], fields *f)
{
    memset(f, 0, sizeof *f);
    int low2 = block[0] & 3;
    f->mode = spec_of(low2 < 2 ? low2 : block[0] & 31);
    if (!f->mode) return;
    char tok[8];
    for (int k = 0; k < endpoint_bits(f->mode); k++) {
        token(f->mode, k, tok);
        int v = get_bit(block, k);
        if (tok[0] == 'P') f->partition |= v << atoi(tok + 1);
        else if (tok[0] != 'M' && tok[0] != 'I')
            f->e[tok[1] - '0'][channel_of(tok[0])] |= (unsigned)v << atoi(tok + 3);
    }
    for (int i = 0; i < 16; i++) {
        int pos, len;
        index_bits(f->mode, f->partition, i, &pos, &len);
        for (int b = 0; b < len; b++) f->index[i] |= get_bit(block, pos + b) << b;
    }
}

/* ---- the float64 reference decoder ---- */

static double sext(double v, int bits)
{
    return v >= ldexp(1.0, bits - 1) ? v - ldexp(1.0, bits) : v;
}

static double unquantize_ref(double x, int prec, int is_signed)
{
    if (!is_signed) {
        if (prec >= 15) return x;
        if (x == 0.0) return 0.0;
        if (x == ldexp(1.0, prec) - 1.0) return 65535.0;
        return floor((x * 65536.0 + 32768.0) / ldexp(1.0, prec));
    }
    if (prec >= 16) return x;
    double m = fabs(x), u;
    if (m == 0.0) u = 0.0;
    else if (m >= ldexp(1.0, prec - 1) - 1.0) u = 32767.0;
    else u = floor((m * 32768.0 + 16384.0) / ldexp(1.0, prec - 1));
    return x < 0.0 ? -u : u;
}

static void reference_decode(const fields *f, int is_signed, uint16_t out[48])
{
    if (!f->mode) {
        memset(out, 0, 48 * sizeof *out);
        return;
    }
    const spec_mode *m = f->mode;
    double e[4][3];
    for (int c = 0; c < 3; c++) {
        e[0][c] = is_signed ? sext(f->e[0][c], m->prec) : f->e[0][c];
        for (int k = 1; k < 2 * m->regions; k++) {
            int bits = m->transformed ? m->delta[c] : m->prec;
            double v = (m->transformed || is_signed) ? sext(f->e[k][c], bits) : f->e[k][c];
            if (m->transformed) {
                v = fmod(e[0][c] + v + ldexp(1.0, 20), ldexp(1.0, m->prec)); /* wrap */
                if (is_signed) v = sext(v, m->prec);
            }
            e[k][c] = v;
        }
    }
    for (int i = 0; i < 16; i++) {
        int s = m->regions == 2 ? PARTITION[f->partition][i] - '0' : 0;
        int x = f->index[i];
        int w = m->regions == 2 ? x * 9 + (x >> 2) : (x << 2) + (x >> 2) + ((x >> 1) & 1);
        for (int c = 0; c < 3; c++) {
            double a = unquantize_ref(e[2 * s][c], m->prec, is_signed);
            double b = unquantize_ref(e[2 * s + 1][c], m->prec, is_signed);
            double v = floor((a * (64 - w) + b * w + 32.0) / 64.0);
            double h = is_signed ? (v < 0 ? 32768.0 + floor(-v * 31.0 / 32.0) : floor(v * 31.0 / 32.0))
                                 : floor(v * 31.0 / 64.0);
            out[3 * i + c] = (uint16_t)h;
        }
    }
}

static uint64_t rng_state = 0x1234567;
static uint32_t rnd(void)
{
    rng_state = rng_state * 6364136223846793005ull + 1442695040888963407ull;
    return (uint32_t)(rng_state >> 33);
}

/* Random fields for a mode: only the bits its layout stores. */
static void random_fields(const spec_mode *m, fields *f)
{
    memset(f, 0, sizeof *f);
    f->mode = m;
    uint8_t block[16];
    for (int i = 0; i < 16; i++) block[i] = (uint8_t)rnd();
    block[0] = (uint8_t)((block[0] & (m->number < 2 ? ~3u : ~31u)) | (unsigned)m->number);
    disassemble(block, f);
}

static const char *half_text(uint16_t h)
{
    static char buf[4][32];
    static int n;
    char *b = buf[n++ & 3];
    snprintf(b, 32, "0x%04x", h);
    return b;
}

/* Every mode: the per-bit table stores EPB bits of E0 and delta bits of the other endpoints,
 * and blocks assembled from random fields decode like the reference, signed and unsigned. */
static void decoder_matches_reference(void **state)
{
    (void)state;
    for (int mi = 0; mi < 14; mi++) {
        const spec_mode *m = &SPEC[mi];
        /* bits per field from the table */
        int count[4][3] = {{0}}, mode_bits = 0, pbits = 0, ibits = 0;
        char tok[8];
        for (int k = 0; k < 82; k++) {
            token(m, k, tok);
            if (tok[0] == 'M') mode_bits++;
            else if (tok[0] == 'P') pbits++;
            else if (tok[0] == 'I') ibits++;
            else count[tok[1] - '0'][channel_of(tok[0])]++;
        }
        assert_int_equal(mode_bits, m->number < 2 ? 2 : 5);
        assert_int_equal(pbits, m->regions == 2 ? 5 : 0);
        assert_int_equal(ibits, 82 - endpoint_bits(m));
        for (int k = 0; k < 2 * m->regions; k++)
            for (int c = 0; c < 3; c++)
                assert_int_equal(count[k][c], k == 0 || !m->transformed ? m->prec : m->delta[c]);
        for (int trial = 0; trial < 3000; trial++) {
            fields f, back;
            random_fields(m, &f);
            uint8_t block[16], again[16];
            assemble(&f, block);
            disassemble(block, &back);
            assemble(&back, again);
            assert_memory_equal(block, again, 16);
            for (int is_signed = 0; is_signed < 2; is_signed++) {
                uint16_t want[48], got[48];
                reference_decode(&f, is_signed, want);
                int number = ibl_bc6h_decode_block(block, is_signed, got);
                assert_int_equal(number, m->number);
                for (int i = 0; i < 48; i++)
                    if (want[i] != got[i])
                        fail_msg("mode %d (%s) texel %d channel %d: reference %s, library %s",
                                 m->number, is_signed ? "signed" : "unsigned", i / 3, i % 3,
                                 half_text(want[i]), half_text(got[i]));
            }
        }
    }
}

/* Hand-made blocks whose decoded values are worked out from the spec by hand. */
static void decoder_known_blocks(void **state)
{
    (void)state;
    /* mode 3 (one region, 10-bit endpoints, no transform): E0 = (0, 512, 1023),
     * E1 = (1023, 512, 0), every index 0 except texel 15 at index 15. Unsigned unquantize:
     * 0 -> 0, 1023 -> 0xFFFF, 512 -> ((512 << 16) + 0x8000) >> 10 = 32800; final: (x * 31) >> 6
     * -> 0, 15887, 31743 (0x7BFF = 65504.0). */
    fields f = {spec_of(3), {{0, 512, 1023}, {1023, 512, 0}}, 0, {0}};
    f.index[15] = 15;
    uint8_t block[16];
    assemble(&f, block);
    uint16_t h[48];
    assert_int_equal(ibl_bc6h_decode_block(block, 0, h), 3);
    assert_int_equal(h[0], 0);
    assert_int_equal(h[1], 15887);
    assert_int_equal(h[2], 0x7BFF);
    assert_int_equal(h[45], 0x7BFF);
    assert_int_equal(h[46], 15887);
    assert_int_equal(h[47], 0);
    /* signed: E0 G = 512 is -512 in 10 bits: magnitude >= 511 -> -0x7FFF -> 0x8000 |
     * ((0x7FFF * 31) >> 5) = 0xFBFF (-65504); B = 1023 is -1: unquantize
     * -(((1 << 15) + 0x4000) >> 9) = -96, final -((96 * 31) >> 5) = -93 -> 0x805D. */
    assert_int_equal(ibl_bc6h_decode_block(block, 1, h), 3);
    assert_int_equal(h[0], 0);
    assert_int_equal(h[1], 0xFBFF);
    assert_int_equal(h[2], 0x805D);
    /* the reserved modes 19, 23, 27, 31 decode to 0 */
    for (int r = 19; r <= 31; r += 4) {
        memset(block, 0xA5, 16);
        block[0] = (uint8_t)((block[0] & ~31u) | (unsigned)r);
        for (int s = 0; s < 2; s++) {
            assert_int_equal(ibl_bc6h_decode_block(block, s, h), -1);
            for (int i = 0; i < 48; i++) assert_int_equal(h[i], 0);
        }
    }
}

/* The test vectors left for an independent decoder: every mode appears, and the expected
 * texels are the reference's. */
static void test_vectors_hook(void **state)
{
    (void)state;
    enum { N = 560 };
    static uint8_t blocks[N * 16];
    static uint16_t expected[N * 48];
    for (int is_signed = 0; is_signed < 2; is_signed++) {
        ibl_bc6h_test_vectors(42, N, is_signed, blocks, expected);
        int seen[32] = {0};
        for (int i = 0; i < N; i++) {
            fields f;
            disassemble(blocks + i * 16, &f);
            assert_non_null(f.mode);
            seen[f.mode->number]++;
            uint16_t want[48];
            reference_decode(&f, is_signed, want);
            assert_memory_equal(want, expected + i * 48, sizeof want);
        }
        for (int mi = 0; mi < 14; mi++) assert_true(seen[SPEC[mi].number] >= 20);
    }
}

/* ---- the encoder ---- */

static double log_rms(const float *a, const float *b, size_t texels, int is_signed)
{
    double sum = 0.0;
    for (size_t i = 0; i < texels; i++)
        for (int c = 0; c < 3; c++) {
            double x = a[4 * i + c], y = b[4 * i + c];
            if (!is_signed && x < 0.0) x = 0.0;
            double d = copysign(log2(1.0 + fabs(x)), x) - copysign(log2(1.0 + fabs(y)), y);
            sum += d * d;
        }
    return sqrt(sum / (double)(texels * 3));
}

/* Encodes and decodes an image; returns the RMS log error. */
static double round_trip(ibl_context *ctx, const float *rgba, int w, int h, int is_signed,
                         ibl_quality q)
{
    size_t bytes = ibl_bc6h_bytes(w, h);
    uint8_t *blocks = malloc(bytes);
    float *back = malloc((size_t)w * (size_t)h * 16);
    assert_non_null(blocks);
    assert_non_null(back);
    ibl_bc6h_desc d = {is_signed, q};
    assert_int_equal(ibl_bc6h_encode(ctx, &d, rgba, w, h, blocks), IBL_OK);
    assert_int_equal(ibl_bc6h_decode(ctx, is_signed, blocks, w, h, back), IBL_OK);
    double e = log_rms(rgba, back, (size_t)w * (size_t)h, is_signed);
    free(blocks);
    free(back);
    return e;
}

/* A synthetic sky: a smooth blue gradient, a ground, and a sun disk of 50000 with a sharp
 * edge (the hardest case for BC6H's endpoint quantization). */
static float *sun_and_sky(int w, int h, int is_signed)
{
    float *p = malloc((size_t)w * (size_t)h * 16);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            float *t = p + ((size_t)y * (size_t)w + (size_t)x) * 4;
            float v = (float)y / (float)h, u = (float)x / (float)w;
            float sky = v < 0.5f ? 0.3f + 2.0f * v : 0.05f + 0.1f * u;
            t[0] = sky * 0.6f, t[1] = sky * 0.8f, t[2] = sky * 1.2f, t[3] = 1.0f;
            float dx = u - 0.3f, dy = v - 0.2f;
            if (dx * dx + dy * dy < 0.0004f) t[0] = 50000.0f, t[1] = 48000.0f, t[2] = 45000.0f;
            if (is_signed && v > 0.75f) t[0] = -t[0], t[2] = -0.5f * t[2];
        }
    return p;
}

static void encoder_synthetic(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(0);
    enum { W = 128, H = 128 };
    for (int is_signed = 0; is_signed < 2; is_signed++) {
        float *img = sun_and_sky(W, H, is_signed);
        double e[3];
        for (int q = 0; q < 3; q++) e[q] = round_trip(ctx, img, W, H, is_signed, (ibl_quality)q);
        print_message("sun and sky %s: RMS log2 error default %.5f fast %.5f thorough %.5f\n",
                      is_signed ? "signed" : "unsigned", e[0], e[1], e[2]);
        assert_true(e[1] < SYNTH_FAST_BOUND);
        assert_true(e[0] < SYNTH_DEFAULT_BOUND);
        assert_true(e[2] <= e[0] * 1.0001);
        assert_true(e[0] <= e[1] * 1.0001);
        free(img);
    }
    /* a constant block is exact to the half it rounds to; a smooth ramp within 1% */
    float block[64];
    for (int t = 0; t < 16; t++) block[4 * t] = 1.25f, block[4 * t + 1] = 3.0f, block[4 * t + 2] = 0.01f, block[4 * t + 3] = 1;
    uint8_t b[16];
    uint16_t hh[48];
    ibl_bc6h_encode_block(NULL, block, b);
    ibl_bc6h_decode_block(b, 0, hh);
    for (int t = 0; t < 16; t++) {
        float got[3];
        for (int c = 0; c < 3; c++) {
            uint16_t x = hh[3 * t + c];
            got[c] = ldexpf((float)((x & 1023) + ((x >> 10) ? 1024 : 0)), ((x >> 10) ? (x >> 10) : 1) - 25);
        }
        assert_near(got[0], 1.25f, 1.25f * 0.002f);
        assert_near(got[1], 3.0f, 3.0f * 0.002f);
        assert_near(got[2], 0.01f, 0.01f * 0.002f);
    }
    ibl_context_destroy(ctx);
}

/* Box-downsampled by 4 (the test's speed): the six HDRIs at 256x128. */
static float *small_hdri(ibl_context *ctx, const char *name, int *w, int *h)
{
    ibl_image im;
    assert_int_equal(ibl_read_image(ctx, test_data(name), NULL, &im, NULL), IBL_OK);
    *w = im.width / 4;
    *h = im.height / 4;
    float *p = calloc((size_t)*w * (size_t)*h, 16);
    for (int y = 0; y < *h * 4; y++)
        for (int x = 0; x < *w * 4; x++)
            for (int c = 0; c < 4; c++)
                p[((size_t)(y / 4) * (size_t)*w + (size_t)(x / 4)) * 4 + (size_t)c] +=
                    ibl_image_texel(&im, x, y)[c] / 16.0f;
    ibl_image_free(ctx, &im);
    return p;
}

static const char *const HDRIS[] = {"city.exr", "forest.exr", "interior.exr",
                                    "night.exr", "studio.exr", "sunset.exr"};
/* measured at default quality: 0.0091 0.0243 0.0145 0.0150 0.0114 0.0081 */
static const double HDRI_BOUND[] = {0.0114, 0.0304, 0.0182, 0.0188, 0.0143, 0.0102};

static void encoder_real_hdris(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(0);
    for (size_t i = 0; i < sizeof HDRIS / sizeof HDRIS[0]; i++) {
        int w, h;
        float *img = small_hdri(ctx, HDRIS[i], &w, &h);
        double fast = round_trip(ctx, img, w, h, 0, IBL_QUALITY_FAST);
        double def = round_trip(ctx, img, w, h, 0, IBL_QUALITY_DEFAULT);
        print_message("%s %dx%d: RMS log2 error fast %.5f default %.5f\n", HDRIS[i], w, h, fast, def);
        assert_true(fast < HDRI_BOUND[i] * 1.05);
        assert_true(def < HDRI_BOUND[i]);
        assert_true(def <= fast * 1.0001);
        free(img);
    }
    ibl_context_destroy(ctx);
}

/* Bit-identical blocks at 1, 2 and 3 threads; and the small mips (1x1 .. 7x5) are padded. */
static void encoder_threads_and_padding(void **state)
{
    (void)state;
    ibl_context *c1 = test_context(1), *c2 = test_context(2), *c3 = test_context(3);
    int w, h;
    float *img = small_hdri(c1, "sunset.exr", &w, &h);
    size_t bytes = ibl_bc6h_bytes(w, h);
    uint8_t *a = malloc(bytes), *b = malloc(bytes);
    for (int q = 0; q < 3; q++) {
        ibl_bc6h_desc d = {0, (ibl_quality)q};
        assert_int_equal(ibl_bc6h_encode(c1, &d, img, w, h, a), IBL_OK);
        assert_int_equal(ibl_bc6h_encode(c2, &d, img, w, h, b), IBL_OK);
        assert_memory_equal(a, b, bytes);
        assert_int_equal(ibl_bc6h_encode(c3, &d, img, w, h, b), IBL_OK);
        assert_memory_equal(a, b, bytes);
    }
    static const int sizes[][2] = {{1, 1}, {2, 2}, {3, 3}, {7, 5}, {4, 1}, {1, 9}};
    for (size_t s = 0; s < sizeof sizes / sizeof sizes[0]; s++) {
        int sw = sizes[s][0], sh = sizes[s][1];
        assert_int_equal(ibl_bc6h_bytes(sw, sh), (size_t)((sw + 3) / 4 * ((sh + 3) / 4) * 16));
        double e = round_trip(c1, img, sw, sh, 0, IBL_QUALITY_DEFAULT);
        assert_true(e < 0.01);
    }
    assert_int_equal(ibl_bc6h_bytes(0, 4), 0);
    free(a);
    free(b);
    free(img);
    ibl_context_destroy(c1);
    ibl_context_destroy(c2);
    ibl_context_destroy(c3);
}

/* ---- containers ---- */

static ibl_texture smooth_cube(ibl_context *ctx, int size, int is_signed)
{
    ibl_texture t;
    assert_int_equal(ibl_texture_alloc(ctx, IBL_TEXTURE_CUBE, size, size, 1, ibl_full_mip_count(size), &t), IBL_OK);
    for (int l = 0; l < t.levels; l++)
        for (int f = 0; f < 6; f++) {
            int s = ibl_level_size(size, l);
            float *p = ibl_texture_level(&t, l, f);
            for (int i = 0; i < s * s; i++)
                for (int c = 0; c < 4; c++)
                    p[4 * i + c] = c == 3 ? 1.0f
                                          : (float)(0.1 + 4.0 * (f + 1) * (1 + (i % s)) * (1 + c) / (s * 6.0)) *
                                                (is_signed && c == 1 && (i & 1) ? -1.0f : 1.0f);
        }
    return t;
}

static uint32_t rd32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}
static uint64_t rd64(const uint8_t *p) { return (uint64_t)rd32(p) | ((uint64_t)rd32(p + 4) << 32); }

/* The texels a file must decode to: each face of each level through the block codec. */
static void assert_decodes_like_codec(ibl_context *ctx, const ibl_texture *src, const ibl_texture *got, int is_signed)
{
    ibl_bc6h_desc d = {is_signed, IBL_QUALITY_DEFAULT};
    for (int l = 0; l < src->levels; l++)
        for (int f = 0; f < 6; f++) {
            int s = ibl_level_size(src->width, l);
            uint8_t *blocks = malloc(ibl_bc6h_bytes(s, s));
            float *want = malloc((size_t)s * (size_t)s * 16);
            assert_int_equal(ibl_bc6h_encode(ctx, &d, ibl_texture_level(src, l, f), s, s, blocks), IBL_OK);
            assert_int_equal(ibl_bc6h_decode(ctx, is_signed, blocks, s, s, want), IBL_OK);
            assert_memory_equal(want, ibl_texture_level(got, l, f), (size_t)s * (size_t)s * 16);
            free(blocks);
            free(want);
        }
}

static void assert_one_line(ibl_context *ctx, const char *name, const char *needle)
{
    const char *m = ibl_context_message(ctx);
    if (!strstr(m, name) || strchr(m, '\n') || (needle && !strstr(m, needle)))
        fail_msg("unexpected message: \"%s\" (wanted %s and %s)", m, name, needle ? needle : "");
}

static void containers_bc6h(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2);
    for (int is_signed = 0; is_signed < 2; is_signed++) {
        ibl_texture t = smooth_cube(ctx, 16, is_signed);
        ibl_write_desc wd = {0};
        wd.format = is_signed ? IBL_FORMAT_BC6H_SIGNED : IBL_FORMAT_BC6H;
        void *bytes;
        size_t size;
        /* KTX2: vkFormat 143/144, typeSize 1, 16-byte blocks down to the 1x1 level, the DFD of
         * the Data Format Specification's BC6H examples */
        assert_int_equal(ibl__ktx2_encode(ctx, &t, &wd, "b.ktx2", &bytes, &size), IBL_OK);
        const uint8_t *b = bytes;
        assert_int_equal(rd32(b + 12), is_signed ? 144 : 143);
        assert_int_equal(rd32(b + 16), 1);
        for (int l = 0; l < t.levels; l++) {
            int blocks = (ibl_level_size(16, l) + 3) / 4;
            assert_int_equal(rd64(b + 80 + 24 * l + 8), (uint64_t)blocks * blocks * 16 * 6);
            assert_int_equal(rd64(b + 80 + 24 * l) % 16, 0);
        }
        const uint8_t *dfd = b + rd32(b + 48);
        assert_int_equal(rd32(dfd), 44);
        assert_int_equal(dfd[4 + 8], 133);
        assert_int_equal(dfd[4 + 12], 3);
        assert_int_equal(dfd[4 + 13], 3);
        assert_int_equal(dfd[4 + 16], 16);
        assert_int_equal(rd32(dfd + 4 + 24), (127u << 16) | ((is_signed ? 0xC0u : 0x80u) << 24));
        assert_int_equal(rd32(dfd + 4 + 32), is_signed ? 0xBF800000u : 0u);
        ibl_texture back;
        ibl_file_info info;
        assert_int_equal(ibl__ktx2_decode(ctx, bytes, size, "b.ktx2", &back, &info), IBL_OK);
        assert_int_equal(info.format, wd.format);
        assert_int_equal(info.has_alpha, 0);
        assert_decodes_like_codec(ctx, &t, &back, is_signed);
        ibl_texture_free(ctx, &back);
        /* a level shorter than its blocks, and a file cut short */
        uint8_t *bad = malloc(size);
        memcpy(bad, bytes, size);
        bad[80 + 8] ^= 16;
        assert_int_equal(ibl__ktx2_decode(ctx, bad, size, "bad.ktx2", &back, NULL), IBL_ERR_FORMAT);
        assert_one_line(ctx, "bad.ktx2", "level 0");
        assert_int_equal(ibl__ktx2_decode(ctx, bytes, size - 40, "cut.ktx2", &back, NULL), IBL_ERR_FORMAT);
        assert_one_line(ctx, "cut.ktx2", "past the end");
        memcpy(bad, bytes, size);
        bad[rd32(b + 48) + 4 + 12] = 0; /* DFD says 1x4 blocks */
        assert_int_equal(ibl__ktx2_decode(ctx, bad, size, "dfd.ktx2", &back, NULL), IBL_ERR_FORMAT);
        assert_one_line(ctx, "dfd.ktx2", "4x4");
        free(bad);
        ibl_free(ctx, bytes);

        /* DDS: DX10 header with DXGI 95/96, linear size of the top level */
        assert_int_equal(ibl__dds_encode(ctx, &t, &wd, "b.dds", &bytes, &size), IBL_OK);
        b = bytes;
        assert_int_equal(rd32(b + 128), is_signed ? 96 : 95);
        assert_true(rd32(b + 8) & 0x80000);
        assert_int_equal(rd32(b + 20), 16 * 16);
        assert_int_equal(ibl__dds_decode(ctx, bytes, size, "b.dds", &back, &info), IBL_OK);
        assert_int_equal(info.format, wd.format);
        assert_decodes_like_codec(ctx, &t, &back, is_signed);
        ibl_texture_free(ctx, &back);
        assert_int_equal(ibl__dds_decode(ctx, bytes, size - 1, "cut.dds", &back, NULL), IBL_ERR_FORMAT);
        assert_one_line(ctx, "cut.dds", "truncated");
        ibl_free(ctx, bytes);
        /* KTX1 has no BC6H here */
        assert_false(ibl_file_type_writes_format(IBL_FILE_KTX1, wd.format));
        assert_int_equal(ibl__ktx1_encode(ctx, &t, &wd, "b.ktx", &bytes, &size), IBL_ERR_UNSUPPORTED);
        ibl_texture_free(ctx, &t);
    }
    ibl_context_destroy(ctx);
}

static void containers_zstd(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2);
    static const ibl_format formats[] = {IBL_FORMAT_RGBA16F, IBL_FORMAT_RGB9E5, IBL_FORMAT_BC6H, IBL_FORMAT_RGBM};
    for (size_t i = 0; i < sizeof formats / sizeof formats[0]; i++) {
        ibl_texture t = smooth_cube(ctx, 32, 0);
        ibl_write_desc plain = {0}, packed = {0};
        plain.format = packed.format = formats[i];
        packed.zstd_level = 3;
        void *a, *z;
        size_t an, zn;
        assert_int_equal(ibl__ktx2_encode(ctx, &t, &plain, "p.ktx2", &a, &an), IBL_OK);
        assert_int_equal(ibl__ktx2_encode(ctx, &t, &packed, "z.ktx2", &z, &zn), IBL_OK);
        const uint8_t *zb = z;
        assert_int_equal(rd32(zb + 44), 2);
        assert_true(zn < an);
        ibl_texture ta, tz;
        assert_int_equal(ibl__ktx2_decode(ctx, a, an, "p.ktx2", &ta, NULL), IBL_OK);
        assert_int_equal(ibl__ktx2_decode(ctx, z, zn, "z.ktx2", &tz, NULL), IBL_OK);
        assert_int_equal(tz.format, formats[i]);
        assert_memory_equal(ta.data, tz.data, ibl_texture_floats(ta.kind, 32, 32, 1, ta.levels) * 4);
        ibl_texture_free(ctx, &ta);
        ibl_texture_free(ctx, &tz);
        /* a corrupt payload: one line naming the file, the level and Zstandard */
        uint8_t *bad = malloc(zn);
        memcpy(bad, z, zn);
        uint64_t off = rd64(zb + 80), len = rd64(zb + 88);
        for (uint64_t k = off + len / 3; k < off + len / 3 + 8 && k < off + len; k++) bad[k] ^= 0x5A;
        ibl_status st = ibl__ktx2_decode(ctx, bad, zn, "bad.ktx2", &tz, NULL);
        assert_int_equal(st, IBL_ERR_FORMAT);
        assert_one_line(ctx, "bad.ktx2", "level 0");
        assert_one_line(ctx, "bad.ktx2", "Zstandard");
        /* an uncompressed length that does not match the level */
        memcpy(bad, z, zn);
        bad[80 + 16] ^= 1;
        assert_int_equal(ibl__ktx2_decode(ctx, bad, zn, "len.ktx2", &tz, NULL), IBL_ERR_FORMAT);
        assert_one_line(ctx, "len.ktx2", "level 0");
        free(bad);
        ibl_free(ctx, a);
        ibl_free(ctx, z);
        packed.zstd_level = 23;
        assert_int_equal(ibl__ktx2_encode(ctx, &t, &packed, "z.ktx2", &z, &zn), IBL_ERR_INVALID_ARGUMENT);
        ibl_texture_free(ctx, &t);
    }
    ibl_context_destroy(ctx);
}

/* ---- ASTC HDR through astcenc ---- */

static void astc_codec(void **state)
{
    (void)state;
    ibl_context *c1 = test_context(1), *c3 = test_context(3);
    int w, h;
    float *img = small_hdri(c1, "forest.exr", &w, &h);
    static const int sizes[][2] = {{4, 4}, {5, 4}, {5, 5}, {6, 5}, {6, 6}, {8, 5}, {8, 6}, {8, 8}};
    double prev = 0.0;
    for (size_t i = 0; i < 8; i++) {
        ibl_astc_desc d = {sizes[i][0], sizes[i][1], IBL_QUALITY_FAST};
        size_t bytes = ibl_astc_bytes(d.block_width, d.block_height, w, h);
        assert_int_equal(bytes, (size_t)((w + d.block_width - 1) / d.block_width) *
                                    (size_t)((h + d.block_height - 1) / d.block_height) * 16);
        uint8_t *a = malloc(bytes), *b = malloc(bytes);
        float *back = malloc((size_t)w * (size_t)h * 16);
        assert_int_equal(ibl_astc_encode(c1, &d, img, w, h, a), IBL_OK);
        assert_int_equal(ibl_astc_encode(c3, &d, img, w, h, b), IBL_OK);
        assert_memory_equal(a, b, bytes); /* any thread count */
        assert_int_equal(ibl_astc_decode(c3, &d, a, w, h, back), IBL_OK);
        double e = log_rms(img, back, (size_t)w * (size_t)h, 0);
        print_message("astc %dx%d fast on forest 256x128: RMS log2 error %.5f\n", d.block_width, d.block_height, e);
        assert_true(e < 0.12);
        assert_true(e >= prev * 0.9); /* fewer bits per texel, more error (roughly) */
        prev = e;
        free(a);
        free(b);
        free(back);
    }
    ibl_astc_desc bad = {7, 7, IBL_QUALITY_DEFAULT};
    uint8_t block[16];
    assert_int_equal(ibl_astc_bytes(7, 7, 4, 4), 0);
    assert_int_equal(ibl_astc_encode(c1, &bad, img, 4, 4, block), IBL_ERR_INVALID_ARGUMENT);
    /* KTX2: vkFormat 1000066000 + n, a KHR_DF_MODEL_ASTC descriptor with the footprint */
    ibl_texture t = smooth_cube(c1, 16, 0);
    ibl_write_desc wd = {0};
    wd.format = IBL_FORMAT_ASTC_6x5;
    void *bytes;
    size_t size;
    assert_int_equal(ibl__ktx2_encode(c1, &t, &wd, "a.ktx2", &bytes, &size), IBL_OK);
    const uint8_t *kb = bytes;
    assert_int_equal(rd32(kb + 12), 1000066003u);
    const uint8_t *dfd = kb + rd32(kb + 48);
    assert_int_equal(dfd[4 + 8], 162);
    assert_int_equal(dfd[4 + 12], 5);
    assert_int_equal(dfd[4 + 13], 4);
    assert_int_equal(rd64(kb + 80 + 8), (uint64_t)3 * 4 * 16 * 6); /* 16x16: 3x4 blocks */
    ibl_texture back;
    assert_int_equal(ibl__ktx2_decode(c1, bytes, size, "a.ktx2", &back, NULL), IBL_OK);
    assert_int_equal(back.format, IBL_FORMAT_ASTC_6x5);
    ibl_astc_desc d65 = {6, 5, IBL_QUALITY_DEFAULT};
    uint8_t *blocks = malloc(ibl_astc_bytes(6, 5, 16, 16));
    float *want = malloc(16 * 16 * 16);
    assert_int_equal(ibl_astc_encode(c1, &d65, ibl_texture_level(&t, 0, 2), 16, 16, blocks), IBL_OK);
    assert_int_equal(ibl_astc_decode(c1, &d65, blocks, 16, 16, want), IBL_OK);
    assert_memory_equal(want, ibl_texture_level(&back, 0, 2), 16 * 16 * 16);
    free(blocks);
    free(want);
    ibl_texture_free(c1, &back);
    ibl_free(c1, bytes);
    assert_false(ibl_file_type_writes_format(IBL_FILE_DDS, IBL_FORMAT_ASTC_4x4));
    assert_int_equal(ibl__dds_encode(c1, &t, &wd, "a.dds", &bytes, &size), IBL_ERR_UNSUPPORTED);
    ibl_texture_free(c1, &t);
    free(img);
    ibl_context_destroy(c1);
    ibl_context_destroy(c3);
}

/* ---- 8-bit HDR encodings ---- */

static void hdr8_round_trips(void **state)
{
    (void)state;
    for (int i = 0; i < 200000; i++) {
        float c[3], back[3];
        uint8_t e[4];
        double scale = ldexp(1.0, (int)(rnd() % 40) - 24);
        for (int k = 0; k < 3; k++) c[k] = (float)(scale * (rnd() % 10000) / 10000.0);
        float m = fmaxf(c[0], fmaxf(c[1], c[2]));
        /* RGBM, range 8: |error| <= (max + range / 255) / 510 below the range */
        ibl_rgbm_encode(c, 8.0f, e);
        ibl_rgbm_decode(e, 8.0f, back);
        for (int k = 0; k < 3; k++)
            if (m <= 8.0f) assert_true(fabsf(back[k] - c[k]) <= (m + 8.0f / 255.0f) / 510.0f * 1.0001f + 1e-7f);
            else assert_true(back[k] <= 8.0f * 1.0001f);
        /* RGBD: |error| <= 1 / (510 d) with d = alpha / 255, up to 255 */
        ibl_rgbd_encode(c, e);
        ibl_rgbd_decode(e, back);
        for (int k = 0; k < 3; k++)
            if (m <= 255.0f) assert_true(fabsf(back[k] - c[k]) <= 0.5f / (float)e[3] * 1.0001f + 1e-6f);
        /* RGBE: |error| <= max / 256 */
        ibl_rgbe_encode(c, e);
        ibl_rgbe_decode(e, back);
        for (int k = 0; k < 3; k++) assert_true(fabsf(back[k] - c[k]) <= m / 256.0f * 1.0001f + 1e-30f);
    }
    /* fixed values worked out by hand */
    float one[3] = {1.0f, 0.5f, 0.0f}, back[3];
    uint8_t e[4];
    ibl_rgbm_encode(one, 8.0f, e); /* m = 1/8 -> a = ceil(31.875) = 32; rgb / (8 * 32 / 255) */
    assert_int_equal(e[3], 32);
    assert_int_equal(e[0], 254); /* round(255 / 256 * 255) = 254 */
    ibl_rgbm_decode(e, 8.0f, back);
    assert_near(back[0], 254.0 * 32.0 * 8.0 / (255.0 * 255.0), 1e-6);
    ibl_rgbd_encode(one, e); /* max 1 -> alpha 255 */
    assert_int_equal(e[3], 255);
    assert_int_equal(e[0], 255);
    assert_int_equal(e[1], 128);
    ibl_rgbe_encode(one, e); /* 1 = 0.5 2^1: exponent 129, mantissas 128, 64, 0 */
    assert_int_equal(e[0], 128);
    assert_int_equal(e[1], 64);
    assert_int_equal(e[3], 129);
    float black[3] = {0, 0, 0};
    ibl_rgbe_encode(black, e);
    assert_int_equal(e[3], 0);
}

static void hdr8_containers(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_texture t = smooth_cube(ctx, 8, 0);
    static const ibl_format formats[] = {IBL_FORMAT_RGBM, IBL_FORMAT_RGBD, IBL_FORMAT_RGBE};
    for (int i = 0; i < 3; i++) {
        ibl_write_desc wd = {0};
        wd.format = formats[i];
        wd.rgbm_range = 16.0f;
        void *bytes;
        size_t size;
        assert_int_equal(ibl__ktx2_encode(ctx, &t, &wd, "h.ktx2", &bytes, &size), IBL_OK);
        assert_int_equal(rd32((const uint8_t *)bytes + 12), 37); /* R8G8B8A8_UNORM */
        ibl_texture back;
        assert_int_equal(ibl__ktx2_decode(ctx, bytes, size, "h.ktx2", &back, NULL), IBL_OK);
        assert_int_equal(back.format, formats[i]);
        assert_string_equal(ibl_texture_get_metadata(&back, "ibl.encoding"), ibl_format_name(formats[i]));
        for (size_t k = 0; k < ibl_texture_floats(t.kind, 8, 8, 1, t.levels) / 4; k++) {
            uint8_t e[4];
            float want[3];
            const float *c = t.data + 4 * k;
            if (i == 0) ibl_rgbm_encode(c, 16.0f, e), ibl_rgbm_decode(e, 16.0f, want);
            else if (i == 1) ibl_rgbd_encode(c, e), ibl_rgbd_decode(e, want);
            else ibl_rgbe_encode(c, e), ibl_rgbe_decode(e, want);
            assert_memory_equal(want, back.data + 4 * k, sizeof want);
        }
        /* re-written as another encoding: the writer's keys are its own */
        void *again;
        size_t again_size;
        wd.format = IBL_FORMAT_RGBD;
        assert_int_equal(ibl__ktx2_encode(ctx, &back, &wd, "h2.ktx2", &again, &again_size), IBL_OK);
        ibl_free(ctx, again);
        wd.format = formats[i];
        ibl_texture_free(ctx, &back);
        /* without the key the file is refused */
        uint8_t *bad = malloc(size);
        memcpy(bad, bytes, size);
        uint8_t *k = NULL;
        for (size_t at = 0; at + 12 <= size && !k; at++)
            if (memcmp(bad + at, "ibl.encoding", 12) == 0) k = bad + at;
        assert_non_null(k);
        k[0] = 'x';
        assert_int_equal(ibl__ktx2_decode(ctx, bad, size, "nokey.ktx2", &back, NULL), IBL_ERR_UNSUPPORTED);
        assert_one_line(ctx, "nokey.ktx2", "ibl.encoding");
        free(bad);
        ibl_free(ctx, bytes);
        assert_false(ibl_file_type_writes_format(IBL_FILE_DDS, formats[i]));
        assert_int_equal(ibl__dds_encode(ctx, &t, &wd, "h.dds", &bytes, &size), IBL_ERR_UNSUPPORTED);
    }
    ibl_texture_free(ctx, &t);
    ibl_context_destroy(ctx);
}

/* ---- the command line ---- */

static void cli_formats(void **state)
{
    (void)state;
    const char *out;
    const char *exr = test_data("forest_128x64.exr");
    assert_int_equal(test_run_cli(&out, "convert -q '%s' -o '%s' --size 32 --mips --format bc6h --quality fast",
                                  exr, test_path("f.dds")), 0);
    assert_int_equal(test_run_cli(&out, "info '%s'", test_path("f.dds")), 0);
    assert_non_null(strstr(out, "bc6h"));
    /* a BC6H DDS back to EXR: decoded */
    assert_int_equal(test_run_cli(&out, "convert -q '%s' -o '%s'", test_path("f.dds"), test_path("f.exr")), 0);
    assert_int_equal(test_run_cli(&out, "convert -q '%s' -o '%s' --size 32 --format bc6h-signed --zstd 5",
                                  exr, test_path("s.ktx2")), 0);
    assert_int_equal(test_run_cli(&out, "info '%s'", test_path("s.ktx2")), 0);
    assert_non_null(strstr(out, "bc6h-signed"));
    assert_int_equal(test_run_cli(&out, "convert -q '%s' -o '%s' --size 32 --format rgbm --rgbm-range 16 --zstd",
                                  exr, test_path("m.ktx2")), 0);
    assert_int_equal(test_run_cli(&out, "info '%s'", test_path("m.ktx2")), 0);
    assert_non_null(strstr(out, "rgbm"));
    assert_non_null(strstr(out, "ibl.rgbm_range = 16"));
    assert_int_equal(test_run_cli(&out, "convert -q '%s' -o '%s' --size 16 --mips --format astc5x5 --quality fast",
                                  exr, test_path("a.ktx2")), 0);
    assert_int_equal(test_run_cli(&out, "info '%s'", test_path("a.ktx2")), 0);
    assert_non_null(strstr(out, "astc5x5"));
    /* usage errors: exit 2 */
    assert_int_equal(test_run_cli(&out, "convert '%s' -o '%s' --format rgbm", exr, test_path("m.dds")), 2);
    assert_int_equal(test_run_cli(&out, "convert '%s' -o '%s' --zstd", exr, test_path("z.dds")), 2);
    assert_int_equal(test_run_cli(&out, "convert '%s' -o '%s' --quality best", exr, test_path("z.ktx2")), 2);
    /* a broken BC6H file: exit 1, one line naming it */
    FILE *f = fopen(test_path("f.dds"), "r+b");
    assert_non_null(f);
    assert_int_equal(fseek(f, 0, SEEK_END), 0);
    long n = ftell(f);
    fclose(f);
    assert_int_equal(truncate(test_path("f.dds"), n - 5), 0);
    assert_int_equal(test_run_cli(&out, "convert -q '%s' -o '%s'", test_path("f.dds"), test_path("g.exr")), 1);
    assert_non_null(strstr(out, "f.dds"));
    assert_ptr_equal(strchr(out, '\n'), out + strlen(out) - 1);
}

/* ibl bake with the storage options: the same chain in BC6H at each quality is the float
 * bake's chain put through the encoder at that quality (bit for bit), Zstandard on the KTX2
 * files only, ASTC and RGBM bakes without DDS, the manifest's "storage", refusals. */
static void cli_bake_formats(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(0);
    const char *out, *exr = test_data("forest_128x64.exr");
    const char *common = "bake -q --size 16 --irradiance-size 4 --lut-size 8 --preview-width 0";
    assert_int_equal(test_run_cli(&out, "%s '%s' -o '%s' --format rgba32f", common, exr, test_path("bf")), 0);
    ibl_texture ref;
    char path[1200];
    snprintf(path, sizeof path, "%s/specular.ktx2", test_path("bf"));
    assert_int_equal(ibl_read_texture(ctx, path, NULL, &ref, NULL), IBL_OK);
    static const char *const qualities[] = {"fast", "thorough"};
    for (int q = 0; q < 2; q++) {
        const char *dir = test_path(q ? "bt" : "bq");
        assert_int_equal(test_run_cli(&out, "%s '%s' -o '%s' --format bc6h --quality %s --zstd 5", common,
                                      exr, dir, qualities[q]), 0);
        ibl_texture got, want;
        snprintf(path, sizeof path, "%s/specular.ktx2", dir);
        assert_int_equal(ibl_read_texture(ctx, path, NULL, &got, NULL), IBL_OK);
        FILE *f = fopen(path, "rb");
        unsigned char head[48];
        assert_non_null(f);
        assert_int_equal(fread(head, 1, 48, f), 48);
        fclose(f);
        assert_int_equal(head[44], 2); /* supercompressionScheme: Zstandard */
        ibl_write_desc wd = {.format = IBL_FORMAT_BC6H, .quality = q ? IBL_QUALITY_THOROUGH : IBL_QUALITY_FAST};
        void *bytes;
        size_t size;
        assert_int_equal(ibl_encode_texture(ctx, IBL_FILE_KTX2, &ref, &wd, &bytes, &size), IBL_OK);
        assert_int_equal(ibl_decode_texture(ctx, bytes, size, "want.ktx2", NULL, &want, NULL), IBL_OK);
        assert_memory_equal(got.data, want.data,
                            ibl_texture_floats(got.kind, got.width, got.height, 1, got.levels) * sizeof(float));
        ibl_free(ctx, bytes);
        ibl_texture_free(ctx, &got);
        ibl_texture_free(ctx, &want);
        /* the DDS has no supercompression but the same blocks */
        snprintf(path, sizeof path, "%s/specular.dds", dir);
        assert_true(test_file_exists(path));
        assert_int_equal(test_run_cli(&out, "info '%s/specular.dds'", dir), 0);
        assert_non_null(strstr(out, "bc6h"));
    }
    ibl_texture_free(ctx, &ref);
    /* the manifest says how the cubes are stored */
    snprintf(path, sizeof path, "%s/manifest.json", test_path("bt"));
    FILE *mf = fopen(path, "rb");
    char *manifest = calloc(1, 1 << 20);
    assert_true(mf && manifest);
    assert_true(fread(manifest, 1, (1 << 20) - 1, mf) > 0);
    fclose(mf);
    assert_non_null(strstr(manifest, "\"storage\": {\n    \"quality\": \"thorough\",\n    \"zstd_level\": 5"));
    free(manifest);
    /* KTX2-only formats: no DDS */
    assert_int_equal(test_run_cli(&out, "%s '%s' -o '%s' --format astc4x4 --quality fast", common, exr,
                                  test_path("ba")), 0);
    snprintf(path, sizeof path, "%s/specular.dds", test_path("ba"));
    assert_false(test_file_exists(path));
    assert_int_equal(test_run_cli(&out, "%s '%s' -o '%s' --format rgbm --rgbm-range 16", common, exr,
                                  test_path("bm")), 0);
    assert_int_equal(test_run_cli(&out, "info '%s/specular.ktx2'", test_path("bm")), 0);
    assert_non_null(strstr(out, "ibl.rgbm_range = 16"));
    /* refused before any work, nothing written: exit 2 */
    assert_int_equal(test_run_cli(&out, "%s '%s' -o '%s' --format rgbm --quality fast", common, exr, test_path("bx")), 2);
    assert_non_null(strstr(out, "--quality applies to the block formats"));
    assert_int_equal(test_run_cli(&out, "%s '%s' -o '%s' --format bc6h --rgbm-range 4", common, exr, test_path("bx")), 2);
    assert_int_equal(test_run_cli(&out, "prefilter '%s' -o '%s' --quality thorough", exr, test_path("bx.ktx2")), 2);
    assert_int_equal(test_run_cli(&out, "convert '%s' -o '%s' --format rgba16f --quality fast", exr,
                                  test_path("bx.ktx2")), 2);
    assert_false(test_file_exists(test_path("bx")));
    assert_false(test_file_exists(test_path("bx.ktx2")));
    /* the library checks the combination itself before baking */
    ibl_cubemap env;
    assert_int_equal(ibl_cubemap_alloc(ctx, 8, 1, &env), IBL_OK);
    test_fill_cube(&env, 1, 1, 1);
    ibl_bake_data b;
    ibl_bake_desc d = {.format = IBL_FORMAT_RGBM}; /* containers 0: KTX2 and DDS */
    assert_int_equal(ibl_bake_compute(ctx, &env, &d, &b), IBL_ERR_UNSUPPORTED);
    assert_non_null(strstr(ibl_context_message(ctx), "rgbm cubes cannot be stored in DDS"));
    ibl_cubemap_free(ctx, &env);
    ibl_context_destroy(ctx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(decoder_matches_reference),
        cmocka_unit_test(decoder_known_blocks),
        cmocka_unit_test(test_vectors_hook),
        cmocka_unit_test(encoder_synthetic),
        cmocka_unit_test(encoder_real_hdris),
        cmocka_unit_test(encoder_threads_and_padding),
        cmocka_unit_test(containers_bc6h),
        cmocka_unit_test(containers_zstd),
        cmocka_unit_test(astc_codec),
        cmocka_unit_test(hdr8_round_trips),
        cmocka_unit_test(hdr8_containers),
        cmocka_unit_test(cli_formats),
        cmocka_unit_test(cli_bake_formats),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
