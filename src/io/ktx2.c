/* KTX 2.0 read and write (Khronos KTX File Format Specification 2.0; the Data Format
 * Descriptor from the Khronos Data Format Specification 1.3, "Khronos Basic Data Format
 * Descriptor Block"). Uncompressed 2D, 3D and cube textures with full or partial mip chains,
 * no arrays and no supercompression. Layout of what we write:
 *   identifier, header, index, level index (levels[0] = base level), DFD (one basic block),
 *   key/value data (sorted by key), then the level images from the smallest level to the
 *   base level, each aligned to lcm(texel block size, 4) from the start of the file. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/pixel_format.h"
#include "core/context_internal.h"
#include "io/container.h"

static const uint8_t KTX2_IDENTIFIER[12] = {0xAB, 0x4B, 0x54, 0x58, 0x20, 0x32,
                                            0x30, 0xBB, 0x0D, 0x0A, 0x1A, 0x0A};

enum {
    SUPERCOMPRESSION_ZSTD = 2,
    HEADER_BYTES = 80, /* identifier 12 + 9 UInt32 + index (4 UInt32 + 2 UInt64) */
    LEVEL_ENTRY_BYTES = 24,
    /* VkFormat values (Vulkan 1.3 core, vulkan_core.h) */
    VK_R8G8B8A8_UNORM = 37,
    VK_R16G16_SFLOAT = 83,
    VK_R16G16B16A16_SFLOAT = 97,
    VK_R32G32_SFLOAT = 103,
    VK_R32G32B32A32_SFLOAT = 109,
    VK_B10G11R11_UFLOAT_PACK32 = 122,
    VK_E5B9G9R9_UFLOAT_PACK32 = 123,
    VK_BC6H_UFLOAT_BLOCK = 143,
    VK_BC6H_SFLOAT_BLOCK = 144,
    VK_ASTC_4x4_SFLOAT_BLOCK = 1000066000, /* VK_EXT_texture_compression_astc_hdr, Vulkan 1.3;
                                              4x4, 5x4, 5x5, 6x5, 6x6, 8x5, 8x6, 8x8 follow */
    /* Khronos Data Format Specification enumerants */
    KHR_DF_MODEL_RGBSDA = 1,
    KHR_DF_MODEL_BC6H = 133,
    KHR_DF_MODEL_ASTC = 162,
    KHR_DF_PRIMARIES_BT709 = 1,
    KHR_DF_TRANSFER_LINEAR = 1,
    KHR_DF_VERSION_1_3 = 2,
    KHR_DF_CHANNEL_R = 0,
    KHR_DF_CHANNEL_G = 1,
    KHR_DF_CHANNEL_B = 2,
    KHR_DF_CHANNEL_A = 15,
    KHR_DF_EXPONENT = 0x20, /* qualifier bits in the channelType byte */
    KHR_DF_SIGNED = 0x40,
    KHR_DF_FLOAT = 0x80
};

typedef struct vk_map {
    ibl_format format;
    uint32_t vk;
    uint32_t type_size; /* the spec's typeSize: component bytes, or xx/8 for _PACKxx */
} vk_map;

static const vk_map VK_FORMATS[] = {
    {IBL_FORMAT_RGBA16F, VK_R16G16B16A16_SFLOAT, 2}, {IBL_FORMAT_RGBA32F, VK_R32G32B32A32_SFLOAT, 4},
    {IBL_FORMAT_RG11B10F, VK_B10G11R11_UFLOAT_PACK32, 4},
    {IBL_FORMAT_RGB9E5, VK_E5B9G9R9_UFLOAT_PACK32, 4}, {IBL_FORMAT_RG16F, VK_R16G16_SFLOAT, 2},
    {IBL_FORMAT_RG32F, VK_R32G32_SFLOAT, 4},
    {IBL_FORMAT_BC6H, VK_BC6H_UFLOAT_BLOCK, 1}, {IBL_FORMAT_BC6H_SIGNED, VK_BC6H_SFLOAT_BLOCK, 1},
    /* the 8-bit HDR encodings share one vkFormat; the key ENCODING_KEY tells them apart */
    {IBL_FORMAT_RGBM, VK_R8G8B8A8_UNORM, 1}, {IBL_FORMAT_RGBD, VK_R8G8B8A8_UNORM, 1},
    {IBL_FORMAT_RGBE, VK_R8G8B8A8_UNORM, 1},
    {IBL_FORMAT_ASTC_4x4, VK_ASTC_4x4_SFLOAT_BLOCK + 0, 1}, {IBL_FORMAT_ASTC_5x4, VK_ASTC_4x4_SFLOAT_BLOCK + 1, 1},
    {IBL_FORMAT_ASTC_5x5, VK_ASTC_4x4_SFLOAT_BLOCK + 2, 1}, {IBL_FORMAT_ASTC_6x5, VK_ASTC_4x4_SFLOAT_BLOCK + 3, 1},
    {IBL_FORMAT_ASTC_6x6, VK_ASTC_4x4_SFLOAT_BLOCK + 4, 1}, {IBL_FORMAT_ASTC_8x5, VK_ASTC_4x4_SFLOAT_BLOCK + 5, 1},
    {IBL_FORMAT_ASTC_8x6, VK_ASTC_4x4_SFLOAT_BLOCK + 6, 1}, {IBL_FORMAT_ASTC_8x8, VK_ASTC_4x4_SFLOAT_BLOCK + 7, 1},
};

/* Key/value entries naming an 8-bit HDR encoding ("rgbm", "rgbd", "rgbe") and RGBM's range. */
static const char ENCODING_KEY[] = "ibl.encoding";
static const char RANGE_KEY[] = "ibl.rgbm_range";

static const vk_map *map_format(ibl_format f)
{
    for (size_t i = 0; i < sizeof VK_FORMATS / sizeof VK_FORMATS[0]; i++)
        if (VK_FORMATS[i].format == f) return &VK_FORMATS[i];
    return NULL;
}

static const vk_map *map_vk(uint32_t vk)
{
    for (size_t i = 0; i < sizeof VK_FORMATS / sizeof VK_FORMATS[0]; i++)
        if (VK_FORMATS[i].vk == vk) return &VK_FORMATS[i];
    return NULL;
}

/* ---- Data Format Descriptor ---- */

typedef struct dfd_sample {
    uint16_t bit_offset;
    uint16_t bit_length; /* the real length; stored minus one */
    uint8_t channel_type; /* channel id | qualifier bits */
    uint32_t lower, upper;
} dfd_sample;

/* IEEE bit patterns of -1.0f, 0.0f and 1.0f: the float samples' sampleLower/sampleUpper. */
enum { F32_MINUS_ONE = 0xBF800000u, F32_ZERO = 0u, F32_ONE = 0x3F800000u };

static int dfd_samples(ibl_format f, dfd_sample s[6])
{
    static const uint8_t rgba[4] = {KHR_DF_CHANNEL_R, KHR_DF_CHANNEL_G, KHR_DF_CHANNEL_B,
                                    KHR_DF_CHANNEL_A};
    switch (f) {
    case IBL_FORMAT_RGBA16F:
    case IBL_FORMAT_RGBA32F:
    case IBL_FORMAT_RG16F:
    case IBL_FORMAT_RG32F: {
        /* Signed floats: one sample per channel, FLOAT|SIGNED, range -1..1 as floats. */
        int n = ibl_format_channels(f);
        int bits = (f == IBL_FORMAT_RGBA16F || f == IBL_FORMAT_RG16F) ? 16 : 32;
        for (int i = 0; i < n; i++) {
            s[i].bit_offset = (uint16_t)(i * bits);
            s[i].bit_length = (uint8_t)bits;
            s[i].channel_type = (uint8_t)(rgba[i] | KHR_DF_FLOAT | KHR_DF_SIGNED);
            s[i].lower = F32_MINUS_ONE;
            s[i].upper = F32_ONE;
        }
        return n;
    }
    case IBL_FORMAT_RG11B10F: {
        /* Unsigned floats: R in bits 0-10, G 11-21, B 22-31; FLOAT without SIGNED, 0..1. */
        static const uint8_t off[3] = {0, 11, 22}, len[3] = {11, 11, 10};
        for (int i = 0; i < 3; i++) {
            s[i].bit_offset = off[i];
            s[i].bit_length = len[i];
            s[i].channel_type = (uint8_t)(rgba[i] | KHR_DF_FLOAT);
            s[i].lower = F32_ZERO;
            s[i].upper = F32_ONE;
        }
        return 3;
    }
    case IBL_FORMAT_RGB9E5:
        /* The Data Format specification's shared-exponent example: per channel a 9-bit
         * mantissa sample (lower 0, upper 8448) and an EXPONENT sample for the shared bits
         * 27-31 (lower = the bias 15, upper = the largest exponent 31). */
        for (int i = 0; i < 3; i++) {
            s[2 * i].bit_offset = (uint16_t)(9 * i);
            s[2 * i].bit_length = 9;
            s[2 * i].channel_type = rgba[i];
            s[2 * i].lower = 0;
            s[2 * i].upper = 8448;
            s[2 * i + 1].bit_offset = 27;
            s[2 * i + 1].bit_length = 5;
            s[2 * i + 1].channel_type = (uint8_t)(rgba[i] | KHR_DF_EXPONENT);
            s[2 * i + 1].lower = 15;
            s[2 * i + 1].upper = 31;
        }
        return 6;
    case IBL_FORMAT_BC6H:
    case IBL_FORMAT_BC6H_SIGNED:
        /* "Example BC6H signed/unsigned descriptor": one 128-bit COLOR sample (channel 0) */
        s[0].bit_offset = 0;
        s[0].bit_length = 128;
        s[0].channel_type = (uint8_t)(KHR_DF_FLOAT | (f == IBL_FORMAT_BC6H_SIGNED ? KHR_DF_SIGNED : 0));
        s[0].lower = f == IBL_FORMAT_BC6H_SIGNED ? F32_MINUS_ONE : F32_ZERO;
        s[0].upper = F32_ONE;
        return 1;
    case IBL_FORMAT_ASTC_4x4:
    case IBL_FORMAT_ASTC_5x4:
    case IBL_FORMAT_ASTC_5x5:
    case IBL_FORMAT_ASTC_6x5:
    case IBL_FORMAT_ASTC_6x6:
    case IBL_FORMAT_ASTC_8x5:
    case IBL_FORMAT_ASTC_8x6:
    case IBL_FORMAT_ASTC_8x8:
        /* KHR_DF_MODEL_ASTC: one 128-bit DATA sample; FLOAT marks blocks that may be HDR,
         * SIGNED the SFLOAT formats */
        s[0].bit_offset = 0;
        s[0].bit_length = 128;
        s[0].channel_type = (uint8_t)(KHR_DF_FLOAT | KHR_DF_SIGNED);
        s[0].lower = F32_MINUS_ONE;
        s[0].upper = F32_ONE;
        return 1;
    case IBL_FORMAT_RGBM:
    case IBL_FORMAT_RGBD:
    case IBL_FORMAT_RGBE:
        /* R8G8B8A8_UNORM: four 8-bit unsigned normalized samples, 0..255 */
        for (int i = 0; i < 4; i++) {
            s[i].bit_offset = (uint16_t)(8 * i);
            s[i].bit_length = 8;
            s[i].channel_type = rgba[i];
            s[i].lower = 0;
            s[i].upper = 255;
        }
        return 4;
    default: return 0;
    }
}

/* Writes dfdTotalSize and one basic descriptor block; returns the bytes written. */
static size_t write_dfd(ibl_format f, uint8_t *out)
{
    dfd_sample s[6];
    int n = dfd_samples(f, s);
    size_t block = 24 + 16 * (size_t)n;
    ibl__wr32(out, (uint32_t)(4 + block));
    uint8_t *b = out + 4;
    ibl__wr32(b + 0, 0); /* vendorId 0 (Khronos), descriptorType 0 (basic) */
    ibl__wr32(b + 4, (uint32_t)KHR_DF_VERSION_1_3 | ((uint32_t)block << 16));
    int bw, bh, is_block = ibl__format_block(f, &bw, &bh);
    int bc6h = f == IBL_FORMAT_BC6H || f == IBL_FORMAT_BC6H_SIGNED;
    b[8] = !is_block ? KHR_DF_MODEL_RGBSDA : bc6h ? KHR_DF_MODEL_BC6H : KHR_DF_MODEL_ASTC;
    b[9] = KHR_DF_PRIMARIES_BT709;
    b[10] = KHR_DF_TRANSFER_LINEAR;
    b[11] = 0;                          /* flags: KHR_DF_FLAG_ALPHA_STRAIGHT */
    memset(b + 12, 0, 12);              /* texelBlockDimension0-3 = 0 (1x1x1x1), bytesPlane */
    if (is_block) b[12] = (uint8_t)(bw - 1), b[13] = (uint8_t)(bh - 1); /* stored minus one */
    b[16] = (uint8_t)ibl__format_unit_bytes(f); /* bytesPlane0, also when supercompressed */
    for (int i = 0; i < n; i++) {
        uint8_t *p = b + 24 + 16 * (size_t)i;
        ibl__wr32(p, (uint32_t)s[i].bit_offset | ((uint32_t)(s[i].bit_length - 1) << 16) |
                         ((uint32_t)s[i].channel_type << 24));
        ibl__wr32(p + 4, 0); /* samplePosition0-3 */
        ibl__wr32(p + 8, s[i].lower);
        ibl__wr32(p + 12, s[i].upper);
    }
    return 4 + block;
}

static size_t lcm4(size_t texel)
{
    size_t a = texel, b = 4;
    while (b) {
        size_t t = a % b;
        a = b;
        b = t;
    }
    return texel / a * 4;
}

/* The key/value pairs the writer adds: orientation, writer, and for the 8-bit HDR encodings
 * the encoding (and RGBM's range). */
static int fixed_pairs(const ibl_texture *tex, ibl_format fmt, const ibl_write_desc *desc,
                       char range[32], ibl_key_value fixed[4])
{
    int n = 0;
    fixed[n++] = (ibl_key_value){(char *)"KTXorientation", (char *)(tex->kind == IBL_TEXTURE_3D ? "rdi" : "rd")};
    fixed[n++] = (ibl_key_value){(char *)"KTXwriter", (char *)("ibl " IBL_VERSION_STRING)};
    if (fmt == IBL_FORMAT_RGBM || fmt == IBL_FORMAT_RGBD || fmt == IBL_FORMAT_RGBE)
        fixed[n++] = (ibl_key_value){(char *)ENCODING_KEY, (char *)ibl_format_name(fmt)};
    if (fmt == IBL_FORMAT_RGBM) {
        float r = desc && desc->rgbm_range > 0.0f ? desc->rgbm_range : IBL_RGBM_DEFAULT_RANGE;
        snprintf(range, 32, "%.9g", (double)r);
        fixed[n++] = (ibl_key_value){(char *)RANGE_KEY, range};
    }
    return n;
}

/* Level images as stored: encoded (and Zstandard-compressed when zstd_level > 0) into new
 * buffers, or NULL buffers when the levels are encoded in place in the file. */
typedef struct level_data {
    uint8_t *bytes[IBL_MAX_LEVELS];
    size_t len[IBL_MAX_LEVELS], raw[IBL_MAX_LEVELS];
} level_data;

static void free_levels(ibl_context *ctx, level_data *ld)
{
    for (int l = 0; l < IBL_MAX_LEVELS; l++) ibl_free(ctx, ld->bytes[l]);
}

static ibl_status encode_faces(ibl_context *ctx, const ibl_texture *tex, ibl_format fmt,
                               const ibl_write_desc *desc, int level, uint8_t *dst, size_t *clamped)
{
    ibl_status st = IBL_OK;
    uint64_t face_bytes = ibl__level_bytes(fmt, tex->kind, tex->width, tex->height, tex->depth, level);
    for (int f = 0; f < ibl_texture_faces(tex) && st == IBL_OK; f++)
        *clamped += ibl__encode_level(ctx, fmt, desc, tex, level, f, dst + (size_t)face_bytes * (size_t)f, &st);
    return st;
}

/* Encodes and compresses every level (the supercompressed path). */
static ibl_status compress_levels(ibl_context *ctx, const char *name, const ibl_texture *tex,
                                  ibl_format fmt, const ibl_write_desc *desc, level_data *ld,
                                  size_t *clamped)
{
    for (int l = 0; l < tex->levels; l++) {
        size_t raw = ld->raw[l];
        uint8_t *tmp = ibl_alloc(ctx, raw ? raw : 1);
        if (!tmp) return ibl__fail_named(ctx, ibl_context_status(ctx), name);
        ibl_status st = encode_faces(ctx, tex, fmt, desc, l, tmp, clamped);
        if (st == IBL_OK)
            st = ibl__zstd_compress(ctx, name, tmp, raw, desc->zstd_level, &ld->bytes[l], &ld->len[l]);
        else
            st = ibl__fail_named(ctx, st, name);
        ibl_free(ctx, tmp);
        if (st != IBL_OK) return st;
    }
    return IBL_OK;
}

ibl_status ibl__ktx2_encode(ibl_context *ctx, const ibl_texture *tex, const ibl_write_desc *desc,
                            const char *name, void **bytes, size_t *size)
{
    return ibl__ktx2_encode_streamed(ctx, tex, desc, name, bytes, size, NULL);
}

ibl_status ibl__ktx2_encode_streamed(ibl_context *ctx, const ibl_texture *tex,
                                     const ibl_write_desc *desc, const char *name, void **bytes,
                                     size_t *size, ibl__levels_stream **stream)
{
    if (stream) *stream = NULL;
    size_t clamped = 0; /* texels stored at the format's largest value */
    if (!name) name = "<ktx2>";
    if (!bytes || !size) return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "%s: no output", name);
    *bytes = NULL;
    *size = 0;
    ibl_status st = ibl__check_texture(ctx, tex, name);
    if (st != IBL_OK) return st;
    ibl_format fmt = ibl__container_format(tex, desc);
    const vk_map *vk = map_format(fmt);
    if (!vk)
        return ibl__fail(ctx, IBL_ERR_UNSUPPORTED,
                        "%s: KTX2 output does not support pixel format %s (use rgba16f, rgba32f, "
                        "rg11b10f, rgb9e5, rg16f, rg32f, bc6h, bc6h-signed, astc4x4..astc8x8, "
                        "rgbm, rgbd or rgbe)",
                        name, ibl_format_name(fmt));
    int zstd = desc && desc->zstd_level > 0;
    if (zstd && desc->zstd_level > 22)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "%s: Zstandard level %d (1..22)", name,
                        desc->zstd_level);
    size_t align = zstd ? 1 : lcm4(ibl__format_unit_bytes(fmt));
    int faces = ibl_texture_faces(tex);

    char range[32];
    ibl_key_value fixed[4];
    int nfixed = fixed_pairs(tex, fmt, desc, range, fixed);
    uint8_t *kvd = NULL;
    size_t kvd_len = 0;
    st = ibl__kv_build(ctx, name, fixed, nfixed, tex, &kvd, &kvd_len);
    if (st != IBL_OK) return st;

    level_data ld;
    memset(&ld, 0, sizeof ld);
    /* ibl__check_texture bounded every edge by IBL_MAX_DIMENSION: no 64-bit overflow. */
    for (int l = 0; l < tex->levels; l++) {
        uint64_t n = ibl__level_bytes(fmt, tex->kind, tex->width, tex->height, tex->depth, l) * (uint64_t)faces;
        if (n > SIZE_MAX / 2) {
            ibl_free(ctx, kvd);
            return ibl__fail(ctx, IBL_ERR_TOO_LARGE, "%s: texture is too large to encode", name);
        }
        ld.raw[l] = ld.len[l] = (size_t)n;
    }
    if (zstd && (st = compress_levels(ctx, name, tex, fmt, desc, &ld, &clamped)) != IBL_OK) {
        free_levels(ctx, &ld);
        ibl_free(ctx, kvd);
        return st;
    }

    size_t level_off[IBL_MAX_LEVELS];
    size_t dfd_off = HEADER_BYTES + LEVEL_ENTRY_BYTES * (size_t)tex->levels;
    uint8_t dfd[4 + 24 + 16 * 6];
    size_t dfd_len = write_dfd(fmt, dfd);
    size_t kvd_off = dfd_off + dfd_len;
    uint64_t total = kvd_off + kvd_len;
    for (int l = tex->levels - 1; l >= 0; l--) {
        total = (total + align - 1) / align * align;
        if (total > SIZE_MAX - ld.len[l]) {
            free_levels(ctx, &ld);
            ibl_free(ctx, kvd);
            return ibl__fail(ctx, IBL_ERR_TOO_LARGE, "%s: texture is too large to encode", name);
        }
        level_off[l] = (size_t)total;
        total += ld.len[l];
    }
    /* Only the bytes outside the levels are zeroed here: the level images are written in full
     * by the encoders, whose threads then also take the buffer's first-touch page faults. */
    uint8_t *buf = ibl_alloc(ctx, (size_t)total);
    if (!buf) {
        free_levels(ctx, &ld);
        ibl_free(ctx, kvd);
        return ibl__fail_named(ctx, ibl_context_status(ctx), name);
    }
    memset(buf, 0, level_off[tex->levels - 1]);
    for (int l = tex->levels - 1; l > 0; l--) /* the alignment padding after each level */
        memset(buf + level_off[l] + ld.len[l], 0, level_off[l - 1] - (level_off[l] + ld.len[l]));
    memset(buf + level_off[0] + ld.len[0], 0, (size_t)total - (level_off[0] + ld.len[0]));
    memcpy(buf, KTX2_IDENTIFIER, 12);
    ibl__wr32(buf + 12, vk->vk);
    ibl__wr32(buf + 16, vk->type_size);
    ibl__wr32(buf + 20, (uint32_t)tex->width);
    ibl__wr32(buf + 24, (uint32_t)tex->height);
    ibl__wr32(buf + 28, tex->kind == IBL_TEXTURE_3D ? (uint32_t)tex->depth : 0);
    int array = tex->kind == IBL_TEXTURE_CUBE_ARRAY;
    ibl__wr32(buf + 32, array ? (uint32_t)tex->depth : 0); /* layerCount: 0 unless an array */
    ibl__wr32(buf + 36, array ? 6u : (uint32_t)faces);
    ibl__wr32(buf + 40, (uint32_t)tex->levels);
    ibl__wr32(buf + 44, zstd ? SUPERCOMPRESSION_ZSTD : 0);
    ibl__wr32(buf + 48, (uint32_t)dfd_off);
    ibl__wr32(buf + 52, (uint32_t)dfd_len);
    ibl__wr32(buf + 56, kvd_len ? (uint32_t)kvd_off : 0);
    ibl__wr32(buf + 60, (uint32_t)kvd_len);
    ibl__wr64(buf + 64, 0); /* sgdByteOffset */
    ibl__wr64(buf + 72, 0); /* sgdByteLength */
    for (int l = 0; l < tex->levels; l++) {
        uint8_t *e = buf + HEADER_BYTES + LEVEL_ENTRY_BYTES * (size_t)l;
        ibl__wr64(e, level_off[l]);
        ibl__wr64(e + 8, ld.len[l]);
        ibl__wr64(e + 16, ld.raw[l]);
    }
    memcpy(buf + dfd_off, dfd, dfd_len);
    if (kvd_len) memcpy(buf + kvd_off, kvd, kvd_len);
    ibl_free(ctx, kvd);
    /* A level's images are layer, face, slice, row: exactly our in-memory level block. */
    if (zstd) {
        for (int l = 0; l < tex->levels; l++) memcpy(buf + level_off[l], ld.bytes[l], ld.len[l]);
    } else {
        uint8_t *dst[IBL_MAX_LEVELS];
        for (int l = 0; l < tex->levels; l++) dst[l] = buf + level_off[l];
        ibl__levels_stream *s = stream ? ibl__encode_levels_begin(ctx, fmt, desc, tex, dst) : NULL;
        if (s) *stream = s;
        else clamped += ibl__encode_levels(ctx, fmt, desc, tex, dst, &st);
    }
    free_levels(ctx, &ld);
    if (st != IBL_OK) {
        ibl_free(ctx, buf);
        return ibl__fail_named(ctx, st, name);
    }
    *bytes = buf;
    *size = (size_t)total;
    if (desc && desc->report) desc->report->clamped_texels += clamped;
    return IBL_OK;
}

/* ---- reading ---- */

/* Is [offset, offset + length) inside a file of `size` bytes? (overflow-safe) */
static int in_file(uint64_t offset, uint64_t length, size_t size)
{
    return offset <= (uint64_t)size && length <= (uint64_t)size - offset;
}

static ibl_status check_dfd(ibl_context *ctx, const char *name, const uint8_t *dfd, uint32_t len,
                            ibl_format fmt)
{
    if (len < 4 + 24)
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: data format descriptor of %u bytes is too short",
                        name, len);
    if (ibl__rd32(dfd) != len)
        return ibl__fail(ctx, IBL_ERR_FORMAT,
                        "%s: dfdTotalSize %u differs from dfdByteLength %u", name, ibl__rd32(dfd),
                        len);
    const uint8_t *b = dfd + 4;
    uint32_t w0 = ibl__rd32(b), block = ibl__rd32(b + 4) >> 16;
    if ((w0 & 0x1ffffu) != 0 || (w0 >> 17) != 0)
        return ibl__fail(ctx, IBL_ERR_FORMAT,
                        "%s: the first descriptor block is not a Khronos basic descriptor block",
                        name);
    if (block < 24 || block > len - 4 || (block - 24) % 16 != 0)
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: descriptor block size %u is inconsistent", name,
                        block);
    int bw, bh;
    ibl__format_block(fmt, &bw, &bh); /* stored minus one */
    if (b[12] != bw - 1 || b[13] != bh - 1 || b[14] | b[15])
        return ibl__fail(ctx, IBL_ERR_FORMAT,
                        "%s: texel block dimensions in the descriptor are not %dx%dx1x1", name, bw,
                        bh);
    if ((size_t)b[16] != ibl__format_unit_bytes(fmt) && b[16] != 0)
        return ibl__fail(ctx, IBL_ERR_FORMAT,
                        "%s: descriptor says %u bytes per texel block, the vkFormat has %zu", name,
                        b[16], ibl__format_unit_bytes(fmt));
    return IBL_OK;
}

/* The 8-bit HDR encoding named by the key/value data of an R8G8B8A8_UNORM file, and RGBM's
 * range. */
static ibl_status hdr8_encoding(ibl_context *ctx, const char *name, const ibl_texture *tex,
                                ibl_format *fmt, float *range)
{
    const char *e = ibl_texture_get_metadata(tex, ENCODING_KEY);
    *range = 0.0f;
    if (!e || !ibl_format_from_name(e, fmt) ||
        (*fmt != IBL_FORMAT_RGBM && *fmt != IBL_FORMAT_RGBD && *fmt != IBL_FORMAT_RGBE))
        return ibl__fail(ctx, IBL_ERR_UNSUPPORTED,
                        "%s: R8G8B8A8_UNORM without an %s key of rgbm, rgbd or rgbe is not an HDR "
                        "texture", name, ENCODING_KEY);
    if (*fmt == IBL_FORMAT_RGBM) {
        const char *r = ibl_texture_get_metadata(tex, RANGE_KEY);
        char *end = NULL;
        double v = r ? strtod(r, &end) : IBL_RGBM_DEFAULT_RANGE;
        if (r && (end == r || *end || !(v > 0.0 && v < 1e30)))
            return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: invalid %s \"%s\"", name, RANGE_KEY, r);
        *range = (float)v;
    }
    return IBL_OK;
}

/* Parses KTXorientation ("rd", "ru", "ld", "rdi", ...) into flips to our layout (rows top
 * first, columns left first, slices in increasing R "into the screen"). */
static ibl_status orientation(ibl_context *ctx, const char *name, const ibl_texture *tex,
                              int one_d, int flips[3])
{
    flips[0] = flips[1] = flips[2] = 0;
    const char *o = ibl_texture_get_metadata(tex, "KTXorientation");
    if (!o) return IBL_OK;
    size_t want = one_d ? 1 : tex->kind == IBL_TEXTURE_3D ? 3 : 2;
    int ok = strlen(o) == want && (o[0] == 'r' || o[0] == 'l');
    if (ok && want >= 2) ok = o[1] == 'd' || o[1] == 'u';
    if (ok && want == 3) ok = o[2] == 'i' || o[2] == 'o';
    if (!ok)
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: invalid KTXorientation \"%s\" for this texture",
                        name, o);
    if ((tex->kind == IBL_TEXTURE_CUBE || tex->kind == IBL_TEXTURE_CUBE_ARRAY) && strcmp(o, "rd") != 0)
        return ibl__fail(ctx, IBL_ERR_FORMAT,
                        "%s: cube map orientation must be \"rd\", the file says \"%s\"", name, o);
    flips[0] = o[0] == 'l';
    flips[1] = want >= 2 && o[1] == 'u';
    flips[2] = want == 3 && o[2] == 'o';
    return IBL_OK;
}

/* Decodes every level into out (inflating Zstandard levels first). */
static ibl_status decode_levels(ibl_context *ctx, const char *name, const uint8_t *bytes,
                                uint32_t scheme, const uint64_t *offset, const uint64_t *len,
                                const uint64_t *raw, float range, ibl_texture *out)
{
    int faces = ibl_texture_faces(out);
    for (int l = 0; l < out->levels; l++) {
        const uint8_t *src = bytes + offset[l];
        uint8_t *tmp = NULL;
        if (scheme == SUPERCOMPRESSION_ZSTD) {
            if (raw[l] > SIZE_MAX) return ibl__fail(ctx, IBL_ERR_TOO_LARGE, "%s: level too large", name);
            tmp = ibl_alloc(ctx, (size_t)raw[l]);
            if (!tmp) return ibl__fail_named(ctx, ibl_context_status(ctx), name);
            ibl_status st = ibl__zstd_decompress(ctx, name, l, src, (size_t)len[l], tmp, (size_t)raw[l]);
            if (st != IBL_OK) {
                ibl_free(ctx, tmp);
                return st;
            }
            src = tmp;
        }
        uint64_t face_bytes = raw[l] / (uint64_t)faces;
        ibl_status st = IBL_OK;
        for (int f = 0; f < faces && st == IBL_OK; f++)
            st = ibl__decode_level(ctx, out->format, range, src + (size_t)face_bytes * (size_t)f, out, l, f);
        ibl_free(ctx, tmp);
        if (st != IBL_OK) return ibl__fail_named(ctx, st, name);
    }
    return IBL_OK;
}

/* What the header, the level index, the DFD and the key/value data's place say. */
typedef struct ktx2_header {
    const vk_map *vk;
    ibl_texture_kind kind;
    int width, height, depth, levels; /* as the texture's (depth: slices or cube layers) */
    int one_d;                        /* pixelHeight 0                                   */
    uint32_t scheme, faces, layers;
    uint32_t kvd_off, kvd_len;
    uint64_t level_bytes[IBL_MAX_LEVELS], level_offset[IBL_MAX_LEVELS], level_raw[IBL_MAX_LEVELS];
} ktx2_header;

/* Everything before the level images: the header, the level index (each level's sizes agree
 * with its dimensions), the DFD and where the key/value data lies. Reads only those bytes;
 * with check_levels, each level must also lie inside the `size` bytes (the decoder's check;
 * ibl__ktx2_info may hold only the head of the file). */
static ibl_status parse_header(ibl_context *ctx, const uint8_t *bytes, size_t size,
                               const char *name, int check_levels, ktx2_header *hd)
{
    memset(hd, 0, sizeof *hd);
    if (size < 12 || memcmp(bytes, KTX2_IDENTIFIER, 12) != 0)
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: not a KTX 2.0 file (wrong identifier)", name);
    if (size < HEADER_BYTES)
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: truncated KTX2 header (%zu of %d bytes)", name,
                        size, HEADER_BYTES);
    uint32_t vkformat = ibl__rd32(bytes + 12), type_size = ibl__rd32(bytes + 16);
    uint32_t width = ibl__rd32(bytes + 20), height = ibl__rd32(bytes + 24);
    uint32_t depth = ibl__rd32(bytes + 28), layers = ibl__rd32(bytes + 32);
    uint32_t faces = ibl__rd32(bytes + 36), level_count = ibl__rd32(bytes + 40);
    uint32_t scheme = ibl__rd32(bytes + 44);
    uint32_t dfd_off = ibl__rd32(bytes + 48), dfd_len = ibl__rd32(bytes + 52);
    uint32_t kvd_off = ibl__rd32(bytes + 56), kvd_len = ibl__rd32(bytes + 60);
    uint64_t sgd_len = ibl__rd64(bytes + 72);

    const vk_map *vk = map_vk(vkformat);
    if (!vk)
        return ibl__fail(ctx, IBL_ERR_UNSUPPORTED,
                        "%s: unsupported vkFormat %u (supported: 97 R16G16B16A16_SFLOAT, 109 "
                        "R32G32B32A32_SFLOAT, 122 B10G11R11_UFLOAT_PACK32, 123 "
                        "E5B9G9R9_UFLOAT_PACK32, 83 R16G16_SFLOAT, 103 R32G32_SFLOAT, 143 "
                        "BC6H_UFLOAT_BLOCK, 144 BC6H_SFLOAT_BLOCK, 1000066000-7 ASTC 4x4..8x8 "
                        "SFLOAT_BLOCK, 37 R8G8B8A8_UNORM with an ibl.encoding key)",
                        name, vkformat);
    if (type_size != vk->type_size)
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: typeSize %u, the vkFormat requires %u", name,
                        type_size, vk->type_size);
    if (scheme != 0 && scheme != SUPERCOMPRESSION_ZSTD)
        return ibl__fail(ctx, IBL_ERR_UNSUPPORTED,
                        "%s: supercompression scheme %u is not supported (only none and 2, "
                        "Zstandard)", name, scheme);
    if (sgd_len != 0)
        return ibl__fail(ctx, IBL_ERR_FORMAT,
                        "%s: supercompression global data present (none is defined for %s)", name,
                        scheme ? "Zstandard" : "uncompressed files");
    if (layers != 0 && faces != 6)
        return ibl__fail(ctx, IBL_ERR_UNSUPPORTED,
                        "%s: 2D array textures (%u layers) are not supported (cube-map arrays are)",
                        name, layers);
    if (faces != 1 && faces != 6)
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: faceCount %u (must be 1 or 6)", name, faces);
    if (width == 0) return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: pixelWidth is 0", name);
    ibl_texture_kind kind = IBL_TEXTURE_2D;
    int one_d = height == 0;
    if (faces == 6) {
        if (depth != 0)
            return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: a cube map with pixelDepth %u", name, depth);
        kind = layers ? IBL_TEXTURE_CUBE_ARRAY : IBL_TEXTURE_CUBE;
    } else if (depth > 0) {
        if (one_d)
            return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: pixelDepth %u with pixelHeight 0", name,
                            depth);
        kind = IBL_TEXTURE_3D;
    }
    uint64_t levels = level_count ? level_count : 1; /* 0: base level only */
    /* a cube-map array's "depth" is its layer count (ibl_texture) */
    uint64_t depth_or_layers = layers ? layers : depth ? depth : 1;
    ibl_status st = ibl__check_dimensions(ctx, name, kind, width, one_d ? 1 : height,
                                          depth_or_layers, levels);
    if (st != IBL_OK) return st;
    int w = (int)width, h = one_d ? 1 : (int)height, d = (int)depth_or_layers;
    if (size < HEADER_BYTES + LEVEL_ENTRY_BYTES * levels)
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: truncated level index", name);

    if (!in_file(dfd_off, dfd_len, size))
        return ibl__fail(ctx, IBL_ERR_FORMAT,
                        "%s: data format descriptor (%u bytes at %u) lies outside the file", name,
                        dfd_len, dfd_off);
    st = check_dfd(ctx, name, bytes + dfd_off, dfd_len, vk->format);
    if (st != IBL_OK) return st;
    if (!in_file(kvd_off, kvd_len, size))
        return ibl__fail(ctx, IBL_ERR_FORMAT,
                        "%s: key/value data (%u bytes at %u) lies outside the file", name, kvd_len,
                        kvd_off);
    if (kvd_len && (uint64_t)kvd_off != (uint64_t)dfd_off + dfd_len)
        return ibl__fail(ctx, IBL_ERR_FORMAT,
                        "%s: dfdTotalSize %u differs from kvdByteOffset - dfdByteOffset", name,
                        dfd_len);

    for (uint64_t l = 0; l < levels; l++) {
        const uint8_t *e = bytes + HEADER_BYTES + LEVEL_ENTRY_BYTES * l;
        uint64_t off = ibl__rd64(e), len = ibl__rd64(e + 8), raw = ibl__rd64(e + 16);
        /* at most 65536^3 texels (a 3D level, or a face of 65536 layers) * 6 faces * 16 bytes < 2^64 */
        uint64_t expect = ibl__level_bytes(vk->format, kind, w, h, d, (int)l) * faces * (layers ? layers : 1);
        if (raw != expect || (scheme == 0 && len != expect) || (scheme != 0 && len == 0))
            return ibl__fail(ctx, IBL_ERR_FORMAT,
                            "%s: level %llu holds %llu bytes (uncompressed %llu), its dimensions "
                            "need %llu",
                            name, (unsigned long long)l, (unsigned long long)len,
                            (unsigned long long)raw, (unsigned long long)expect);
        if (check_levels && !in_file(off, len, size))
            return ibl__fail(ctx, IBL_ERR_FORMAT,
                            "%s: level %llu (%llu bytes at offset %llu) runs past the end of the "
                            "file (%zu bytes)",
                            name, (unsigned long long)l, (unsigned long long)len,
                            (unsigned long long)off, size);
        hd->level_bytes[l] = len;
        hd->level_offset[l] = off;
        hd->level_raw[l] = raw;
    }
    hd->vk = vk;
    hd->kind = kind;
    hd->width = w;
    hd->height = h;
    hd->depth = d;
    hd->levels = (int)levels;
    hd->one_d = one_d;
    hd->scheme = scheme;
    hd->faces = faces;
    hd->layers = layers;
    hd->kvd_off = kvd_off;
    hd->kvd_len = kvd_len;
    return IBL_OK;
}

/* The key/value data into tex (whose kind and format are the header's), the 8-bit HDR
 * encoding it names (tex->format, *range) and the flips its KTXorientation asks for. */
static ibl_status read_metadata(ibl_context *ctx, const char *name, const uint8_t *bytes,
                                const ktx2_header *hd, ibl_texture *tex, float *range, int flips[3])
{
    *range = 0.0f;
    ibl_status st = ibl__kv_parse(ctx, name, bytes + hd->kvd_off, hd->kvd_len, tex);
    if (st == IBL_OK && hd->vk->vk == VK_R8G8B8A8_UNORM)
        st = hdr8_encoding(ctx, name, tex, &tex->format, range);
    if (st == IBL_OK) st = orientation(ctx, name, tex, hd->one_d, flips);
    return st;
}

ibl_status ibl__ktx2_info(ibl_context *ctx, const uint8_t *bytes, size_t size, const char *name,
                          ibl_file_info *info)
{
    ktx2_header hd;
    ibl_status st = parse_header(ctx, bytes, size, name, 0, &hd);
    if (st != IBL_OK) return st;
    ibl_texture tex = ibl__header_texture(hd.kind, hd.width, hd.height, hd.depth, hd.levels,
                                          hd.vk->format);
    float range;
    int flips[3];
    st = read_metadata(ctx, name, bytes, &hd, &tex, &range, flips);
    if (st == IBL_OK) ibl__fill_info(info, IBL_FILE_KTX2, &tex);
    ibl_texture_free(ctx, &tex);
    return st;
}

ibl_status ibl__ktx2_decode(ibl_context *ctx, const uint8_t *bytes, size_t size, const char *name,
                            ibl_texture *out, ibl_file_info *info)
{
    if (!name) name = "<ktx2>";
    if (!out) return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "%s: no output texture", name);
    memset(out, 0, sizeof *out);
    if (!bytes && size) return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "%s: no input", name);
    ktx2_header hd;
    ibl_status st = parse_header(ctx, bytes, size, name, 1, &hd);
    if (st != IBL_OK) return st;

    st = ibl_texture_alloc(ctx, hd.kind, hd.width, hd.height, hd.depth, hd.levels, out);
    if (st != IBL_OK) return ibl__fail_named(ctx, st, name);
    out->format = hd.vk->format;
    int flips[3];
    float range = 0.0f;
    st = read_metadata(ctx, name, bytes, &hd, out, &range, flips);
    if (st == IBL_OK) st = decode_levels(ctx, name, bytes, hd.scheme, hd.level_offset, hd.level_bytes, hd.level_raw, range, out);
    if (st != IBL_OK) {
        ibl_texture_free(ctx, out);
        return st;
    }
    ibl__flip_texture(out, flips[0], flips[1], flips[2]);
    if (flips[0] || flips[1] || flips[2]) {
        /* the texels now follow our layout; say so */
        st = ibl_texture_set_metadata(ctx, out, "KTXorientation",
                                      hd.kind == IBL_TEXTURE_3D ? "rdi" : hd.one_d ? "r" : "rd");
        if (st != IBL_OK) {
            ibl_texture_free(ctx, out);
            return ibl__fail_named(ctx, st, name);
        }
    }
    ibl__fill_info(info, IBL_FILE_KTX2, out);
    return IBL_OK;
}
