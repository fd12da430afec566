/* Helpers shared by the texture containers (ktx2.c, ktx1.c, dds.c): little-endian fields,
 * level sizes, the choice of storage format, key/value blocks and reorientation. Internal. */
#ifndef IBL_IO_CONTAINER_H
#define IBL_IO_CONTAINER_H

#include "io/io_internal.h"

static inline uint32_t ibl__rd32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}
static inline uint64_t ibl__rd64(const uint8_t *p)
{
    return (uint64_t)ibl__rd32(p) | ((uint64_t)ibl__rd32(p + 4) << 32);
}
static inline void ibl__wr32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
    p[2] = (uint8_t)(v >> 16);
    p[3] = (uint8_t)(v >> 24);
}
static inline void ibl__wr64(uint8_t *p, uint64_t v)
{
    ibl__wr32(p, (uint32_t)v);
    ibl__wr32(p + 4, (uint32_t)(v >> 32));
}

/* ibl__fail_named is declared in io_internal.h (defined in file.c). */

/* The storage format an encoder writes: desc->format if set (refused later if the container
 * cannot store it); else tex->format if it is one of the six container formats; else
 * RGBA32F for RGB32F textures (keeps float precision) and RGBA16F for anything else. */
ibl_format ibl__container_format(const ibl_texture *tex, const ibl_write_desc *desc);

/* Validates a texture handed to an encoder (kind, dimensions, levels, data). */
ibl_status ibl__check_texture(ibl_context *ctx, const ibl_texture *tex, const char *name);

/* Texels of one face of one level (all slices of a 3D level). Dimensions must be at most
 * IBL_MAX_DIMENSION, so the product fits in 64 bits. */
uint64_t ibl__level_texels(ibl_texture_kind kind, int width, int height, int depth, int level);

/* Validates dimensions read from a file before anything is allocated: every edge in
 * 1..IBL_MAX_DIMENSION, cubes square, levels in 1..min(IBL_MAX_LEVELS, full chain). */
ibl_status ibl__check_dimensions(ibl_context *ctx, const char *name, ibl_texture_kind kind,
                                 uint64_t width, uint64_t height, uint64_t depth,
                                 uint64_t levels);

/* Most key/value pairs a container accepts (keeps metadata handling linear-ish for hostile
 * files: duplicate detection is quadratic in the count). */
enum { IBL__MAX_KEY_VALUES = 4096 };

/* Builds a key/value block (KTX 1 and KTX 2 share the layout): for each pair sorted by the
 * key's bytes (the Unicode code point order for UTF-8), UInt32 keyAndValueByteLength, the
 * key, NUL, the value, NUL, then zero padding to 4 bytes. The `fixed` pairs are the ones
 * the container itself writes (KTXorientation, KTXwriter, ibl.encoding, ibl.rgbm_range);
 * texture metadata whose key starts with "KTX" or "ktx" (reserved by the KTX
 * specifications) or is one of the two ibl keys the writer owns is not copied, the rest is.
 * *out is NULL when there are no pairs. */
ibl_status ibl__kv_build(ibl_context *ctx, const char *name, const ibl_key_value *fixed,
                         int fixed_count, const ibl_texture *tex, uint8_t **out, size_t *size);

/* Parses a key/value block into tex->metadata (values lose one trailing NUL). */
ibl_status ibl__kv_parse(ibl_context *ctx, const char *name, const uint8_t *bytes, size_t size,
                         ibl_texture *tex);

/* Mirrors every level/face of a texture along x, y and/or z (slices). */
void ibl__flip_texture(ibl_texture *tex, int flip_x, int flip_y, int flip_z);

/* ibl_pack_texels / ibl_unpack_texels split into fixed chunks of texels run through
 * ibl_parallel_for: the output does not depend on the thread count. ibl__pack returns the
 * texels clamped to the format's range. */
size_t ibl__pack(ibl_context *ctx, ibl_format format, const float *rgba, size_t count, uint8_t *dst);
void ibl__unpack(ibl_context *ctx, ibl_format format, const uint8_t *src, size_t count,
                 float *rgba);

/* ---- formats beyond fixed-size float texels: BC6H blocks and the 8-bit HDR encodings ---- */

/* Non-zero for block formats (BC6H 4x4, ASTC 4x4..8x8): their block footprint in
 * *block_width x *block_height (1x1 for texel formats; either pointer may be NULL). */
int ibl__format_block(ibl_format format, int *block_width, int *block_height);
int ibl__format_is_block(ibl_format format);
/* Bytes of one texel (4 for RGBM/RGBD/RGBE) or of one block (16 for BC6H and ASTC); 0 if
 * the containers cannot store the format. */
size_t ibl__format_unit_bytes(ibl_format format);
/* Bytes of one face of one level (all its slices; whole blocks per slice). */
uint64_t ibl__level_bytes(ibl_format format, ibl_texture_kind kind, int width, int height,
                          int depth, int level);
/* Stores one face of one level of tex in format (BC6H and ASTC encoded with desc->quality,
 * RGBM with desc->rgbm_range); returns the texels stored at the format's largest value.
 * *status is IBL_OK unless the ASTC encoder failed (then with the context's message). */
size_t ibl__encode_level(ibl_context *ctx, ibl_format format, const ibl_write_desc *desc,
                         const ibl_texture *tex, int level, int face, uint8_t *dst,
                         ibl_status *status);
/* ibl__encode_level for every face of every level; dst[l] receives level l's faces one after
 * another. Texel formats run as one parallel loop over the whole texture. */
size_t ibl__encode_levels(ibl_context *ctx, ibl_format format, const ibl_write_desc *desc,
                          const ibl_texture *tex, uint8_t *const dst[], ibl_status *status);
/* ibl__encode_levels of a texel format run beside the caller, which writes the bytes as they
 * are done (output.c): begin starts the loop on the pool's workers, its chunks in the order of
 * their place in memory, and returns at once (without a pool it encodes everything first);
 * NULL for block formats or without memory, with nothing started. wait returns once every
 * byte the encode writes below `end` is written, encoding chunks on the calling thread
 * meanwhile. end waits for the rest, frees the stream and returns the texels stored at the
 * format's largest value. The bytes are those of ibl__encode_levels. */
ibl__levels_stream *ibl__encode_levels_begin(ibl_context *ctx, ibl_format format,
                                             const ibl_write_desc *desc, const ibl_texture *tex,
                                             uint8_t *const dst[]);
void ibl__encode_levels_wait(ibl__levels_stream *s, const uint8_t *end);
size_t ibl__encode_levels_end(ibl__levels_stream *s);
/* The reverse of ibl__encode_level; rgbm_range as written (0: the default). */
ibl_status ibl__decode_level(ibl_context *ctx, ibl_format format, float rgbm_range,
                             const uint8_t *src, ibl_texture *tex, int level, int face);

/* Fills the file info of a decoded texture. */
void ibl__fill_info(ibl_file_info *info, ibl_file_type type, const ibl_texture *tex);
/* A texture without texels of what a container's header says: what ibl__fill_info reads, and
 * where its key/value data goes (free it with ibl_texture_free). */
ibl_texture ibl__header_texture(ibl_texture_kind kind, int width, int height, int depth, int levels,
                                ibl_format format);

#endif
