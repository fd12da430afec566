/* BC6H tables, transcribed from the Khronos Data Format Specification 1.3, "BC6H":
 * "Endpoint and partition parameters for BPTC block modes" (mode parameters), "Block
 * descriptions for BC6H block modes (LSB..MSB)" (bit layouts), the first 32 entries of
 * "Partition table for 2-subset BPTC" and of "BPTC anchor index values for the second subset
 * of two-subset partitioning", and "BPTC interpolation factors". */
#include "compress/bc6h_internal.h"

#define ARRAY_COUNT(a) ((uint8_t)(sizeof(a) / sizeof((a)[0])))

enum { R0, G0, B0, R1, G1, B1, R2, G2, B2, R3, G3, B3, M = BC6H_FIELD_M, PB = BC6H_FIELD_PB };

/* Each list is one row of "Block descriptions for BC6H block modes", left (LSB) to right. */
static const bc6h_seg MODE_0[] = {
    {M, 1, 0},  {G2, 4, 4}, {B2, 4, 4}, {B3, 4, 4}, {R0, 9, 0}, {G0, 9, 0}, {B0, 9, 0},
    {R1, 4, 0}, {G3, 4, 4}, {G2, 3, 0}, {G1, 4, 0}, {B3, 0, 0}, {G3, 3, 0}, {B1, 4, 0},
    {B3, 1, 1}, {B2, 3, 0}, {R2, 4, 0}, {B3, 2, 2}, {R3, 4, 0}, {B3, 3, 3}, {PB, 4, 0}};
static const bc6h_seg MODE_1[] = {
    {M, 1, 0},  {G2, 5, 5}, {G3, 4, 4}, {G3, 5, 5}, {R0, 6, 0}, {B3, 0, 0}, {B3, 1, 1},
    {B2, 4, 4}, {G0, 6, 0}, {B2, 5, 5}, {B3, 2, 2}, {G2, 4, 4}, {B0, 6, 0}, {B3, 3, 3},
    {B3, 5, 5}, {B3, 4, 4}, {R1, 5, 0}, {G2, 3, 0}, {G1, 5, 0}, {G3, 3, 0}, {B1, 5, 0},
    {B2, 3, 0}, {R2, 5, 0}, {R3, 5, 0}, {PB, 4, 0}};
static const bc6h_seg MODE_2[] = {
    {M, 4, 0},  {R0, 9, 0}, {G0, 9, 0},   {B0, 9, 0}, {R1, 4, 0}, {R0, 10, 10}, {G2, 3, 0},
    {G1, 3, 0}, {G0, 10, 10}, {B3, 0, 0}, {G3, 3, 0}, {B1, 3, 0}, {B0, 10, 10}, {B3, 1, 1},
    {B2, 3, 0}, {R2, 4, 0}, {B3, 2, 2},   {R3, 4, 0}, {B3, 3, 3}, {PB, 4, 0}};
static const bc6h_seg MODE_6[] = {
    {M, 4, 0},   {R0, 9, 0}, {G0, 9, 0}, {B0, 9, 0}, {R1, 3, 0}, {R0, 10, 10}, {G3, 4, 4},
    {G2, 3, 0},  {G1, 4, 0}, {G0, 10, 10}, {G3, 3, 0}, {B1, 3, 0}, {B0, 10, 10}, {B3, 1, 1},
    {B2, 3, 0},  {R2, 3, 0}, {B3, 0, 0}, {B3, 2, 2}, {R3, 3, 0}, {G2, 4, 4}, {B3, 3, 3},
    {PB, 4, 0}};
static const bc6h_seg MODE_10[] = {
    {M, 4, 0},  {R0, 9, 0}, {G0, 9, 0}, {B0, 9, 0},   {R1, 3, 0}, {R0, 10, 10}, {B2, 4, 4},
    {G2, 3, 0}, {G1, 3, 0}, {G0, 10, 10}, {B3, 0, 0}, {G3, 3, 0}, {B1, 4, 0}, {B0, 10, 10},
    {B2, 3, 0}, {R2, 3, 0}, {B3, 1, 1}, {B3, 2, 2},   {R3, 3, 0}, {B3, 4, 4}, {B3, 3, 3},
    {PB, 4, 0}};
static const bc6h_seg MODE_14[] = {
    {M, 4, 0},  {R0, 8, 0}, {B2, 4, 4}, {G0, 8, 0}, {G2, 4, 4}, {B0, 8, 0}, {B3, 4, 4},
    {R1, 4, 0}, {G3, 4, 4}, {G2, 3, 0}, {G1, 4, 0}, {B3, 0, 0}, {G3, 3, 0}, {B1, 4, 0},
    {B3, 1, 1}, {B2, 3, 0}, {R2, 4, 0}, {B3, 2, 2}, {R3, 4, 0}, {B3, 3, 3}, {PB, 4, 0}};
static const bc6h_seg MODE_18[] = {
    {M, 4, 0},  {R0, 7, 0}, {G3, 4, 4}, {B2, 4, 4}, {G0, 7, 0}, {B3, 2, 2}, {G2, 4, 4},
    {B0, 7, 0}, {B3, 3, 3}, {B3, 4, 4}, {R1, 5, 0}, {G2, 3, 0}, {G1, 4, 0}, {B3, 0, 0},
    {G3, 3, 0}, {B1, 4, 0}, {B3, 1, 1}, {B2, 3, 0}, {R2, 5, 0}, {R3, 5, 0}, {PB, 4, 0}};
static const bc6h_seg MODE_22[] = {
    {M, 4, 0},  {R0, 7, 0}, {B3, 0, 0}, {B2, 4, 4}, {G0, 7, 0}, {G2, 5, 5}, {G2, 4, 4},
    {B0, 7, 0}, {G3, 5, 5}, {B3, 4, 4}, {R1, 4, 0}, {G3, 4, 4}, {G2, 3, 0}, {G1, 5, 0},
    {G3, 3, 0}, {B1, 4, 0}, {B3, 1, 1}, {B2, 3, 0}, {R2, 4, 0}, {B3, 2, 2}, {R3, 4, 0},
    {B3, 3, 3}, {PB, 4, 0}};
static const bc6h_seg MODE_26[] = {
    {M, 4, 0},  {R0, 7, 0}, {B3, 1, 1}, {B2, 4, 4}, {G0, 7, 0}, {B2, 5, 5}, {G2, 4, 4},
    {B0, 7, 0}, {B3, 5, 5}, {B3, 4, 4}, {R1, 4, 0}, {G3, 4, 4}, {G2, 3, 0}, {G1, 4, 0},
    {B3, 0, 0}, {G3, 3, 0}, {B1, 5, 0}, {B2, 3, 0}, {R2, 4, 0}, {B3, 2, 2}, {R3, 4, 0},
    {B3, 3, 3}, {PB, 4, 0}};
static const bc6h_seg MODE_30[] = {
    {M, 4, 0},  {R0, 5, 0}, {G3, 4, 4}, {B3, 0, 0}, {B3, 1, 1}, {B2, 4, 4}, {G0, 5, 0},
    {G2, 5, 5}, {B2, 5, 5}, {B3, 2, 2}, {G2, 4, 4}, {B0, 5, 0}, {G3, 5, 5}, {B3, 3, 3},
    {B3, 5, 5}, {B3, 4, 4}, {R1, 5, 0}, {G2, 3, 0}, {G1, 5, 0}, {G3, 3, 0}, {B1, 5, 0},
    {B2, 3, 0}, {R2, 5, 0}, {R3, 5, 0}, {PB, 4, 0}};
static const bc6h_seg MODE_3[] = {{M, 4, 0},  {R0, 9, 0}, {G0, 9, 0}, {B0, 9, 0},
                                  {R1, 9, 0}, {G1, 9, 0}, {B1, 9, 0}};
static const bc6h_seg MODE_7[] = {{M, 4, 0},  {R0, 9, 0},   {G0, 9, 0}, {B0, 9, 0},
                                  {R1, 8, 0}, {R0, 10, 10}, {G1, 8, 0}, {G0, 10, 10},
                                  {B1, 8, 0}, {B0, 10, 10}};
static const bc6h_seg MODE_11[] = {{M, 4, 0},  {R0, 9, 0},   {G0, 9, 0}, {B0, 9, 0},
                                   {R1, 7, 0}, {R0, 10, 11}, {G1, 7, 0}, {G0, 10, 11},
                                   {B1, 7, 0}, {B0, 10, 11}};
static const bc6h_seg MODE_15[] = {{M, 4, 0},  {R0, 9, 0},   {G0, 9, 0}, {B0, 9, 0},
                                   {R1, 3, 0}, {R0, 10, 15}, {G1, 3, 0}, {G0, 10, 15},
                                   {B1, 3, 0}, {B0, 10, 15}};

#define MODE(n, r, t, p, dr, dg, db, segs) {n, r, t, p, {dr, dg, db}, ARRAY_COUNT(segs), segs}
const bc6h_mode ibl__bc6h_modes[BC6H_MODES] = {
    MODE(0, 2, 1, 10, 5, 5, 5, MODE_0),    MODE(1, 2, 1, 7, 6, 6, 6, MODE_1),
    MODE(2, 2, 1, 11, 5, 4, 4, MODE_2),    MODE(6, 2, 1, 11, 4, 5, 4, MODE_6),
    MODE(10, 2, 1, 11, 4, 4, 5, MODE_10),  MODE(14, 2, 1, 9, 5, 5, 5, MODE_14),
    MODE(18, 2, 1, 8, 6, 5, 5, MODE_18),   MODE(22, 2, 1, 8, 5, 6, 5, MODE_22),
    MODE(26, 2, 1, 8, 5, 5, 6, MODE_26),   MODE(30, 2, 0, 6, 6, 6, 6, MODE_30),
    MODE(3, 1, 0, 10, 10, 10, 10, MODE_3), MODE(7, 1, 1, 11, 9, 9, 9, MODE_7),
    MODE(11, 1, 1, 12, 8, 8, 8, MODE_11),  MODE(15, 1, 1, 16, 4, 4, 4, MODE_15),
};

/* Bit 4 y + x is the subset of texel (x, y). */
const uint16_t ibl__bc6h_partitions[BC6H_PARTITIONS] = {
    0xcccc, 0x8888, 0xeeee, 0xecc8, 0xc880, 0xfeec, 0xfec8, 0xec80, 0xc800, 0xffec, 0xfe80,
    0xe800, 0xffe8, 0xff00, 0xfff0, 0xf000, 0xf710, 0x008e, 0x7100, 0x08ce, 0x008c, 0x7310,
    0x3100, 0x8cce, 0x088c, 0x3110, 0x6666, 0x366c, 0x17e8, 0x0ff0, 0x718e, 0x399c};

const uint8_t ibl__bc6h_anchor2[BC6H_PARTITIONS] = {
    15, 15, 15, 15, 15, 15, 15, 15, 15, 15, 15, 15, 15, 15, 15, 15,
    15, 2,  8,  2,  2,  8,  8,  15, 2,  8,  2,  2,  8,  8,  2,  2};

const uint8_t ibl__bc6h_weights3[8] = {0, 9, 18, 27, 37, 46, 55, 64};
const uint8_t ibl__bc6h_weights4[16] = {0, 4, 9, 13, 17, 21, 26, 30, 34, 38, 43, 47, 51, 55, 60, 64};

int ibl__bc6h_mode_index(const uint8_t block[16])
{
    int low2 = block[0] & 3;
    int number = low2 < 2 ? low2 : block[0] & 31;
    for (int i = 0; i < BC6H_MODES; i++)
        if (ibl__bc6h_modes[i].number == number) return i;
    return -1; /* 19, 23, 27, 31 */
}
