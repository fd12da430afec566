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
/* PNG (libpng) and JPEG (stb_image): 8/16-bit, sRGB decoded to linear. */
ibl_status ibl__stb_decode(ibl_context *ctx, const uint8_t *bytes, size_t size, const char *name,
                           ibl_texture *out, ibl_file_info *info);
/* PNG: 8-bit sRGB with exposure and tone map, or 16-bit linear (IBL_FORMAT_RGBA16_UNORM). */
ibl_status ibl__png_encode(ibl_context *ctx, const ibl_image *image, const ibl_write_desc *desc,
                           const char *name, void **bytes, size_t *size);
ibl_status ibl__jpeg_encode(ibl_context *ctx, const ibl_image *image, const ibl_write_desc *desc,
                            const char *name, void **bytes, size_t *size);
/* OpenEXR (src/io/exr.c, with the C++ part in src/io/exr_cpp.cpp). */
ibl_status ibl__exr_decode(ibl_context *ctx, const uint8_t *bytes, size_t size, const char *name,
                           ibl_texture *out, ibl_file_info *info);
ibl_status ibl__exr_encode(ibl_context *ctx, const ibl_image *image, const ibl_write_desc *desc,
                           const char *name, void **bytes, size_t *size);

/* Containers: 2D, 3D, cube; every level; metadata. */
ibl_status ibl__ktx2_decode(ibl_context *ctx, const uint8_t *bytes, size_t size, const char *name,
                            ibl_texture *out, ibl_file_info *info);
ibl_status ibl__ktx2_encode(ibl_context *ctx, const ibl_texture *tex, const ibl_write_desc *desc,
                            const char *name, void **bytes, size_t *size);
ibl_status ibl__ktx1_decode(ibl_context *ctx, const uint8_t *bytes, size_t size, const char *name,
                            ibl_texture *out, ibl_file_info *info);
ibl_status ibl__ktx1_encode(ibl_context *ctx, const ibl_texture *tex, const ibl_write_desc *desc,
                            const char *name, void **bytes, size_t *size);
ibl_status ibl__dds_decode(ibl_context *ctx, const uint8_t *bytes, size_t size, const char *name,
                           ibl_texture *out, ibl_file_info *info);
ibl_status ibl__dds_encode(ibl_context *ctx, const ibl_texture *tex, const ibl_write_desc *desc,
                           const char *name, void **bytes, size_t *size);

/* Re-records the context's last message as "name: <message>" with status (for failures
 * reported by core calls such as ibl_alloc, whose messages do not name the file). */
ibl_status ibl__fail_named(ibl_context *ctx, ibl_status status, const char *name);

/* Encodes for the container path's extension names (what ibl_write_image/_texture write). */
ibl_status ibl__encode_image_for_path(ibl_context *ctx, const char *path, const ibl_image *image,
                                     const ibl_write_desc *desc, void **bytes, size_t *size);
ibl_status ibl__encode_texture_for_path(ibl_context *ctx, const char *path,
                                       const ibl_texture *texture, const ibl_write_desc *desc,
                                       void **bytes, size_t *size);

/* Largest edge any reader accepts before allocating (absurd sizes are refused). */
enum { IBL_MAX_DIMENSION = 65536 };

#endif
