/* Internal contract between the I/O dispatcher (src/io/file.c) and the per-format modules.
 * Decoders take the whole file in memory and a name for messages; they allocate `out`
 * through the context, fill `info`, and never apply the pixel policy themselves (file.c
 * runs ibl_sanitize_pixels on the result). Encoders produce a whole file in a new buffer
 * (ibl_alloc) that file.c writes atomically. Every failure message starts with the name. */
#ifndef IBL_IO_INTERNAL_H
#define IBL_IO_INTERNAL_H

#include "ibl/io.h"

/* Flat images (out->kind = 2D, one level). */
ibl_status ibl__hdr_decode(ibl_context *ctx, const uint8_t *bytes, size_t size, const char *name,
                           ibl_texture *out, ibl_file_info *info);
ibl_status ibl__hdr_encode(ibl_context *ctx, const ibl_image *image, const ibl_write_desc *desc,
                           const char *name, void **bytes, size_t *size);
ibl_status ibl__pfm_decode(ibl_context *ctx, const uint8_t *bytes, size_t size, const char *name,
                           ibl_texture *out, ibl_file_info *info);
ibl_status ibl__pfm_encode(ibl_context *ctx, const ibl_image *image, const ibl_write_desc *desc,
                           const char *name, void **bytes, size_t *size);
/* PNG (src/io/png.c, libpng): 8/16-bit read, sRGB or gAMA decoded to linear (RGBM files, tEXt
 * ibl.encoding = rgbm, decoded); written as 8-bit sRGB with exposure and tone map, 8-bit or
 * 16-bit linear (IBL_FORMAT_RGBA8_UNORM, IBL_FORMAT_RGBA16_UNORM) or 8-bit RGBM. */
ibl_status ibl__png_decode(ibl_context *ctx, const uint8_t *bytes, size_t size, const char *name,
                           ibl_texture *out, ibl_file_info *info);
/* as_data: samples as stored (code / max) whatever the transfer function (ibl_read_desc). */
ibl_status ibl__png_decode_as(ibl_context *ctx, const uint8_t *bytes, size_t size, const char *name,
                              int as_data, ibl_texture *out, ibl_file_info *info);
ibl_status ibl__png_encode(ibl_context *ctx, const ibl_image *image, const ibl_write_desc *desc,
                           const char *name, void **bytes, size_t *size);
/* Stores 8-bit RGBA bytes as they are (no colour chunk, no curve): packed data such as RGBD. */
ibl_status ibl__png_encode_rgba8(ibl_context *ctx, const uint8_t *rgba, int width, int height,
                                 const char *name, void **bytes, size_t *size);
/* JPEG (src/io/jpeg.c, libjpeg-turbo): 8-bit grey, YCbCr or RGB, baseline or progressive,
 * read as sRGB; written as 8-bit sRGB previews like PNG's. */
ibl_status ibl__jpeg_decode(ibl_context *ctx, const uint8_t *bytes, size_t size, const char *name,
                            ibl_texture *out, ibl_file_info *info);
ibl_status ibl__jpeg_encode(ibl_context *ctx, const ibl_image *image, const ibl_write_desc *desc,
                            const char *name, void **bytes, size_t *size);

/* Shared by the PNG and JPEG readers (png.c): RGBA samples (8-bit, or 16-bit big-endian as
 * PNG stores them) to linear float, through the sRGB curve (power 0) or the power law
 * v^power (1 = linear). The samples may lie in the tail of dst itself (both readers decode
 * there): texel i is read whole before it is written, and its float lands at or before
 * samples not yet read. Fails only when the 16-bit table cannot be allocated. */
ibl_status ibl__rgba_samples_to_linear(ibl_context *ctx, const uint8_t *samples, int is16,
                                      double power, size_t texels, float *dst, const char *name);

/* The 8-bit display encoding shared by the PNG and JPEG writers (initialised in png.c):
 * exposure, tone map (IBL_TONEMAP_DEFAULT = filmic) and sRGB encoding to the nearest code,
 * without a pow per channel. The code is the number of decision levels (the linear values
 * whose sRGB encoding is k + 0.5 codes) at or below the value, i.e. round(oetf(t) * 255). A
 * 4096-bucket table gives the count at each bucket's lower edge; levels are at least
 * 1 / (255 * 12.92) = 3.0e-4 apart (the steepest, linear part of the curve) and buckets
 * 2.4e-4 wide, so at most one more level can lie inside a bucket: one comparison finishes. */
enum { IBL_DISPLAY_BUCKETS = 4096 };

typedef struct ibl__display_encoder {
    float scale;
    ibl_tonemap tonemap;
    float level[256];                       /* level[k]: smallest value encoding to k + 1 */
    uint8_t base[IBL_DISPLAY_BUCKETS + 1];  /* levels <= bucket / IBL_DISPLAY_BUCKETS */
} ibl__display_encoder;

void ibl__display_encoder_init(ibl__display_encoder *d, const ibl_write_desc *desc);

static inline uint8_t ibl__display_code(const ibl__display_encoder *d, float linear)
{
    float t = ibl_tonemap_apply(d->tonemap, linear * d->scale); /* in [0, 1] */
    int code = d->base[(int)(t * IBL_DISPLAY_BUCKETS)];
    return (uint8_t)(code + (d->level[code] <= t));
}
/* The pixel policy of ibl_decode_texture (ibl_sanitize_pixels) for a decoder that applies it
 * itself, band by band inside its own parallel loop while the rows are still in cache: one
 * loop and one wait fewer, and a thread that finishes its band early sanitizes it while the
 * other still decodes. `done` is set when every texel of the result went through it; then
 * `report` is the whole image's, in the same integers ibl_sanitize_pixels counts. */
typedef struct ibl__pixel_policy {
    int clamp_infinite;
    float clamp_value;
    int done;
    ibl_pixel_report report;
} ibl__pixel_policy;

/* OpenEXR (src/io/exr.c, with the C++ part in src/io/exr_cpp.cpp). The second applies policy
 * as it decodes where it can (policy->done tells). */
ibl_status ibl__exr_decode(ibl_context *ctx, const uint8_t *bytes, size_t size, const char *name,
                           ibl_texture *out, ibl_file_info *info);
ibl_status ibl__exr_decode_sanitized(ibl_context *ctx, const uint8_t *bytes, size_t size,
                                     const char *name, ibl_texture *out, ibl_file_info *info,
                                     ibl__pixel_policy *policy);
ibl_status ibl__exr_encode(ibl_context *ctx, const ibl_image *image, const ibl_write_desc *desc,
                           const char *name, void **bytes, size_t *size);

/* The header-only halves of the decoders (ibl_decode_info): each parses the header through
 * the code its decoder runs first and fills what it knows of info (flat formats: width,
 * height, format, has_alpha; containers: everything but pixels; file.c sets the rest). They
 * read nothing past the header and check nothing that needs the pixel data. */
ibl_status ibl__hdr_info(ibl_context *ctx, const uint8_t *bytes, size_t size, const char *name,
                         ibl_file_info *info);
ibl_status ibl__pfm_info(ibl_context *ctx, const uint8_t *bytes, size_t size, const char *name,
                         ibl_file_info *info);
ibl_status ibl__png_info(ibl_context *ctx, const uint8_t *bytes, size_t size, const char *name,
                         ibl_file_info *info);
ibl_status ibl__jpeg_info(ibl_context *ctx, const uint8_t *bytes, size_t size, const char *name,
                          ibl_file_info *info);
ibl_status ibl__exr_info(ibl_context *ctx, const uint8_t *bytes, size_t size, const char *name,
                         ibl_file_info *info);
ibl_status ibl__ktx2_info(ibl_context *ctx, const uint8_t *bytes, size_t size, const char *name,
                          ibl_file_info *info);
ibl_status ibl__ktx1_info(ibl_context *ctx, const uint8_t *bytes, size_t size, const char *name,
                          ibl_file_info *info);
ibl_status ibl__dds_info(ibl_context *ctx, const uint8_t *bytes, size_t size, const char *name,
                         ibl_file_info *info);

/* Containers: 2D, 3D, cube; every level; metadata. */
ibl_status ibl__ktx2_decode(ibl_context *ctx, const uint8_t *bytes, size_t size, const char *name,
                            ibl_texture *out, ibl_file_info *info);
ibl_status ibl__ktx2_encode(ibl_context *ctx, const ibl_texture *tex, const ibl_write_desc *desc,
                            const char *name, void **bytes, size_t *size);
/* ibl__ktx2_encode whose level images may still be being encoded when it returns: with
 * `stream` non-NULL and a texel format without supercompression, the header and everything
 * outside the levels are in *bytes and the levels are encoded beside the caller (*stream: see
 * ibl__encode_levels_begin in container.h; the caller waits for the bytes it reads and ends the
 * stream, which also adds its clamped texels to desc->report); otherwise *stream is NULL. */
typedef struct ibl__levels_stream ibl__levels_stream;
ibl_status ibl__ktx2_encode_streamed(ibl_context *ctx, const ibl_texture *tex,
                                     const ibl_write_desc *desc, const char *name, void **bytes,
                                     size_t *size, ibl__levels_stream **stream);
ibl_status ibl__ktx1_decode(ibl_context *ctx, const uint8_t *bytes, size_t size, const char *name,
                            ibl_texture *out, ibl_file_info *info);
ibl_status ibl__ktx1_encode(ibl_context *ctx, const ibl_texture *tex, const ibl_write_desc *desc,
                            const char *name, void **bytes, size_t *size);
ibl_status ibl__dds_decode(ibl_context *ctx, const uint8_t *bytes, size_t size, const char *name,
                           ibl_texture *out, ibl_file_info *info);
ibl_status ibl__dds_encode(ibl_context *ctx, const ibl_texture *tex, const ibl_write_desc *desc,
                           const char *name, void **bytes, size_t *size);

/* Zstandard (src/io/zstd.c): one frame of `size` bytes compressed at `level` (1..22) into a
 * new buffer (ibl_free); and a frame inflated into exactly `expect` bytes (anything else,
 * or corrupt data, fails with IBL_ERR_FORMAT naming the level). */
ibl_status ibl__zstd_compress(ibl_context *ctx, const char *name, const void *src, size_t size,
                              int level, uint8_t **out, size_t *out_size);
ibl_status ibl__zstd_decompress(ibl_context *ctx, const char *name, int level, const void *src,
                                size_t size, void *dst, size_t expect);

/* Re-records the context's last message as "name: <message>" with status (for failures
 * reported by core calls such as ibl_alloc, whose messages do not name the file). */
ibl_status ibl__fail_named(ibl_context *ctx, ibl_status status, const char *name);

/* Encodes for the container path's extension names (what ibl_write_image/_texture write). */
ibl_status ibl__encode_image_for_path(ibl_context *ctx, const char *path, const ibl_image *image,
                                     const ibl_write_desc *desc, void **bytes, size_t *size);
ibl_status ibl__encode_texture_for_path(ibl_context *ctx, const char *path,
                                       const ibl_texture *texture, const ibl_write_desc *desc,
                                       void **bytes, size_t *size);
/* The same, a KTX2's levels streamed where ibl__ktx2_encode_streamed can (*stream). */
ibl_status ibl__encode_texture_streamed(ibl_context *ctx, const char *path,
                                        const ibl_texture *texture, const ibl_write_desc *desc,
                                        void **bytes, size_t *size, ibl__levels_stream **stream);

/* Largest edge any reader accepts before allocating (absurd sizes are refused). */
enum { IBL_MAX_DIMENSION = 65536 };

#endif
