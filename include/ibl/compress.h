/*
 * ibl/compress.h - GPU block compression and 8-bit HDR encodings.
 *
 * BC6H (Khronos Data Format Specification 1.3, "BPTC Compressed Texture Image Formats",
 * section BC6H; Microsoft, "BC6H Format"): 4x4 texel blocks of 16 bytes holding RGB half
 * floats, unsigned (VK_FORMAT_BC6H_UFLOAT_BLOCK, DXGI_FORMAT_BC6H_UF16) or signed
 * (VK_FORMAT_BC6H_SFLOAT_BLOCK, DXGI_FORMAT_BC6H_SF16). The encoder tries the one- and
 * two-region modes (all 14 modes, the 32 two-region partitions) and refines the endpoints by
 * least squares; the error it minimises is the squared difference of the half-float bit
 * patterns (close to a relative, logarithmic error). Blocks are independent and encoded
 * through the context's parallel-for in fixed rows, so the output is bit-identical at any
 * thread count. The decoder is bit-exact to the specification. Images whose sides are not
 * multiples of 4 (the small mips) are padded by repeating their last row and column: the
 * texels outside the image are "irrelevant and undefined" for the formats.
 *
 * ASTC HDR (block sizes 4x4 to 8x8) goes through ARM's astcenc (ibl_astc_*).
 *
 * 8-bit HDR encodings (exact formulas in docs/FORMATS.md): RGBM (rgb = m.rgb * m.a * range),
 * RGBD (rgb = d.rgb / d.a, a shade over [1/255, 1]) and the shared-exponent RGBE of Radiance
 * files. Stored as R8G8B8A8_UNORM with a key naming the encoding in KTX2.
 */
#ifndef IBL_COMPRESS_H
#define IBL_COMPRESS_H

#include "core.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Encoder effort. */
typedef enum ibl_quality {
    IBL_QUALITY_DEFAULT = 0, /* two partitions, the best fitting mode, two refinements     */
    IBL_QUALITY_FAST,        /* one partition, the best fitting mode, one refinement       */
    IBL_QUALITY_THOROUGH     /* 8 partitions, every mode, 4 refinements, endpoint search    */
} ibl_quality;

/* "default", "fast", "thorough". */
const char *ibl_quality_name(ibl_quality quality);
/* Parses a name as above (case-insensitive); 0 if unknown (*out untouched). */
int ibl_quality_from_name(const char *name, ibl_quality *out);

/* ------------------------------------------------------------------------------------------ */
/* BC6H                                                                                       */

enum { IBL_BC6H_BLOCK_BYTES = 16 };

typedef struct ibl_bc6h_desc {
    int is_signed;       /* 0: unsigned float (negatives encode as 0); 1: signed float */
    ibl_quality quality;
} ibl_bc6h_desc;

/* Bytes of the blocks of a width x height image (0 if either is not positive). */
size_t ibl_bc6h_bytes(int width, int height);

/* One block from 16 RGBA float texels, rows top first (alpha is ignored; NaN becomes 0,
 * values beyond the half range the largest half). desc may be NULL (unsigned, default). */
void ibl_bc6h_encode_block(const ibl_bc6h_desc *desc, const float rgba[64], uint8_t block[16]);

/* The 16 texels of a block as half-float bit patterns, RGB per texel, rows top first.
 * Returns the block's mode number (0, 1, 2, 3, 6, 7, 10, 11, 14, 15, 18, 22, 26, 30; the
 * value of the mode bits), or -1 for the reserved modes, which decode to 0. */
int ibl_bc6h_decode_block(const uint8_t block[16], int is_signed, uint16_t half_rgb[48]);

/* A whole image: rgba has width * height texels, blocks ibl_bc6h_bytes(width, height)
 * bytes (block rows top first). Runs on the context's parallel-for. */
ibl_status ibl_bc6h_encode(ibl_context *ctx, const ibl_bc6h_desc *desc, const float *rgba,
                           int width, int height, void *blocks);
/* Decodes into width * height RGBA float texels (alpha 1). */
ibl_status ibl_bc6h_decode(ibl_context *ctx, int is_signed, const void *blocks, int width,
                           int height, float *rgba);

/* Test vectors for an independent decoder (e.g. a GL driver decoding BPTC): `count` blocks
 * from `seed`, covering every mode in turn with random fields (and every partition), each
 * with the half-float RGB texels this library decodes from it. blocks holds count * 16
 * bytes, expected count * 48 halves (texel order as ibl_bc6h_decode_block). Reserved modes
 * are not included (drivers need not agree on them). Deterministic for a seed. */
void ibl_bc6h_test_vectors(uint64_t seed, int count, int is_signed, uint8_t *blocks,
                           uint16_t *expected);

/* ------------------------------------------------------------------------------------------ */
/* ASTC HDR (VK_FORMAT_ASTC_<w>x<h>_SFLOAT_BLOCK) through ARM's astcenc                       */

typedef struct ibl_astc_desc {
    int block_width, block_height; /* 4x4, 5x4, 5x5, 6x5, 6x6, 8x5, 8x6 or 8x8; 0: 4x4      */
    ibl_quality quality;           /* astcenc's presets: fast, medium (default), thorough    */
} ibl_astc_desc;

/* Bytes of the 16-byte blocks of an image (0 for an invalid block size or image). */
size_t ibl_astc_bytes(int block_width, int block_height, int width, int height);
/* Encodes width * height RGBA float texels (alpha stored as 1) with the HDR RGB profile; the
 * image is split into bands of block rows, each encoded by its own single-threaded astcenc
 * context on the context's parallel-for (output identical at any thread count). */
ibl_status ibl_astc_encode(ibl_context *ctx, const ibl_astc_desc *desc, const float *rgba,
                           int width, int height, void *blocks);
/* Decodes the same way, band by band. The context keeps astcenc's decoders from one call to
 * the next (building one costs 4-14 ms): at most one per footprint and band decoded at once,
 * about 10 MiB each counted in the memory budget, freed by ibl_context_destroy. */
ibl_status ibl_astc_decode(ibl_context *ctx, const ibl_astc_desc *desc, const void *blocks,
                           int width, int height, float *rgba);

/* ------------------------------------------------------------------------------------------ */
/* 8-bit HDR encodings                                                                        */

/* The RGBM range used when the caller gives 0. */
#define IBL_RGBM_DEFAULT_RANGE 8.0f

/* RGBM: m = max(r, g, b) / range, a = ceil(255 m) / 255, rgb = c / (range a) (8-bit,
 * rounded); decode: c = rgb * a * range. Values above range clip. */
void ibl_rgbm_encode(const float rgb[3], float range, uint8_t out[4]);
void ibl_rgbm_decode(const uint8_t in[4], float range, float rgb[3]);
/* RGBD: d = 1 / max(1, max(r, g, b)), a = floor(255 d) / 255 (at least 1/255),
 * rgb = c a (8-bit, rounded); decode: c = rgb / a. Range [0, 255]. */
void ibl_rgbd_encode(const float rgb[3], uint8_t out[4]);
void ibl_rgbd_decode(const uint8_t in[4], float rgb[3]);
/* RGBE (Ward): e = ceil-exponent of max(r, g, b), rgb = floor(c 256 / 2^e), a = e + 128;
 * decode: c = (rgb + 0.5) 2^(a - 136), black when a = 0. */
void ibl_rgbe_encode(const float rgb[3], uint8_t out[4]);
void ibl_rgbe_decode(const uint8_t in[4], float rgb[3]);

#ifdef __cplusplus
}
#endif
#endif
