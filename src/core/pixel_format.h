/* Conversions between float and the packed storage formats (IEEE half, the shared-exponent
 * RGB9E5 and the unsigned-float B10G11R11 of the Vulkan/D3D specifications). Internal. */
#ifndef IBL_PIXEL_FORMAT_H
#define IBL_PIXEL_FORMAT_H

#include <stddef.h>
#include <stdint.h>

#include "ibl/core.h"

/* Round-to-nearest-even float -> half; NaN stays NaN, overflow becomes +-Inf. */
uint16_t ibl_float_to_half(float f);
float ibl_half_to_float(uint16_t h);
/* VK_FORMAT_E5B9G9R9_UFLOAT_PACK32 (negatives clamp to 0, too large to the maximum). */
uint32_t ibl_pack_rgb9e5(const float rgb[3]);
void ibl_unpack_rgb9e5(uint32_t v, float rgb[3]);
/* VK_FORMAT_B10G11R11_UFLOAT_PACK32 (R in bits 0-10, G 11-21, B 22-31). */
uint32_t ibl_pack_rg11b10(const float rgb[3]);
void ibl_unpack_rg11b10(uint32_t v, float rgb[3]);

/* Bytes per texel of a storage format (0 for formats that are not fixed-size texels). */
size_t ibl_format_texel_bytes(ibl_format format);
/* Channels a storage format keeps (4, 3 or 2). */
int ibl_format_channels(ibl_format format);
/* Packs `count` RGBA float texels into `dst` (little-endian) in a fixed-size format. Values
 * past the format's largest (ibl_format_max_value) are stored as that value, never as
 * infinity; returns how many texels had such a channel. */
size_t ibl_pack_texels(ibl_format format, const float *rgba, size_t count, uint8_t *dst);
/* Unpacks into RGBA float; missing channels become 0 (G, B) and 1 (A). */
void ibl_unpack_texels(ibl_format format, const uint8_t *src, size_t count, float *rgba);

#endif
