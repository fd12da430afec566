/* DDS read and write (Microsoft "DDS Programming Guide": DDS_HEADER, DDS_PIXELFORMAT and
 * DDS_HEADER_DXT10). We write the legacy header with a Direct3D 9 FourCC where the format has
 * one (the form the most readers take) or the DX10 extended header with a DXGI format
 * (ibl_write_desc.dds_header); we read both: DX10 and the legacy float FourCCs (D3DFMT_A16B16G16R16F 113, A32B32G32R32F 116, G16R16F 112, G32R32F
 * 115). BC6H (DXGI 95 BC6H_UF16, 96 BC6H_SF16) is read (decoded) and written (encoded) in
 * 4x4 blocks, pitchOrLinearSize then being the top level's bytes. Data order differs from KTX: for each face (array slice), all its mip levels, each
 * level being all its depth slices, rows top first. DDS has no metadata. */
#include <string.h>

#include "core/pixel_format.h"
#include "core/context_internal.h"
#include "io/container.h"

enum {
    DDS_MAGIC = 0x20534444, /* "DDS " */
    HEADER_SIZE = 124,
    PIXELFORMAT_SIZE = 32,
    DX10_SIZE = 20,
    DATA_OFFSET_LEGACY = 4 + HEADER_SIZE,
    DATA_OFFSET_DX10 = 4 + HEADER_SIZE + DX10_SIZE,

    DDSD_CAPS = 0x1,
    DDSD_HEIGHT = 0x2,
    DDSD_WIDTH = 0x4,
    DDSD_PITCH = 0x8,
    DDSD_PIXELFORMAT = 0x1000,
    DDSD_MIPMAPCOUNT = 0x20000,
    DDSD_LINEARSIZE = 0x80000,
    DDSD_DEPTH = 0x800000,
    DDPF_FOURCC = 0x4,
    DDSCAPS_COMPLEX = 0x8,
    DDSCAPS_TEXTURE = 0x1000,
    DDSCAPS_MIPMAP = 0x400000,
    DDSCAPS2_CUBEMAP = 0x200,
    DDSCAPS2_CUBEMAP_ALLFACES = 0xFC00, /* POSITIVEX 0x400 ... NEGATIVEZ 0x8000 */
    DDSCAPS2_VOLUME = 0x200000,

    FOURCC_DX10 = 0x30315844, /* "DX10" */
    D3DFMT_G16R16F = 112,
    D3DFMT_A16B16G16R16F = 113,
    D3DFMT_G32R32F = 115,
    D3DFMT_A32B32G32R32F = 116,

    DIM_TEXTURE1D = 2,
    DIM_TEXTURE2D = 3,
    DIM_TEXTURE3D = 4,
    MISC_TEXTURECUBE = 0x4,
    ALPHA_MODE_UNKNOWN = 0,
    ALPHA_MODE_STRAIGHT = 1,

    /* DXGI_FORMAT values (dxgiformat.h) */
    DXGI_R32G32B32A32_FLOAT = 2,
    DXGI_R16G16B16A16_FLOAT = 10,
    DXGI_R32G32_FLOAT = 16,
    DXGI_R11G11B10_FLOAT = 26,
    DXGI_R16G16_FLOAT = 34,
    DXGI_R9G9B9E5_SHAREDEXP = 67,
    DXGI_BC6H_UF16 = 95,
    DXGI_BC6H_SF16 = 96
};

typedef struct dxgi_map {
    ibl_format format;
    uint32_t dxgi;
    uint32_t legacy_fourcc; /* 0: none */
} dxgi_map;

static const dxgi_map DXGI_FORMATS[] = {
    {IBL_FORMAT_RGBA16F, DXGI_R16G16B16A16_FLOAT, D3DFMT_A16B16G16R16F},
    {IBL_FORMAT_RGBA32F, DXGI_R32G32B32A32_FLOAT, D3DFMT_A32B32G32R32F},
    {IBL_FORMAT_RG11B10F, DXGI_R11G11B10_FLOAT, 0},
    {IBL_FORMAT_RGB9E5, DXGI_R9G9B9E5_SHAREDEXP, 0},
    {IBL_FORMAT_RG16F, DXGI_R16G16_FLOAT, D3DFMT_G16R16F},
    {IBL_FORMAT_RG32F, DXGI_R32G32_FLOAT, D3DFMT_G32R32F},
    {IBL_FORMAT_BC6H, DXGI_BC6H_UF16, 0},
    {IBL_FORMAT_BC6H_SIGNED, DXGI_BC6H_SF16, 0},
};

static const dxgi_map *map_format(ibl_format f)
{
    for (size_t i = 0; i < sizeof DXGI_FORMATS / sizeof DXGI_FORMATS[0]; i++)
        if (DXGI_FORMATS[i].format == f) return &DXGI_FORMATS[i];
    return NULL;
}

static const dxgi_map *map_dxgi(uint32_t dxgi)
{
    for (size_t i = 0; i < sizeof DXGI_FORMATS / sizeof DXGI_FORMATS[0]; i++)
        if (DXGI_FORMATS[i].dxgi == dxgi) return &DXGI_FORMATS[i];
    return NULL;
}

static const dxgi_map *map_fourcc(uint32_t fourcc)
{
    for (size_t i = 0; i < sizeof DXGI_FORMATS / sizeof DXGI_FORMATS[0]; i++)
        if (DXGI_FORMATS[i].legacy_fourcc && DXGI_FORMATS[i].legacy_fourcc == fourcc)
            return &DXGI_FORMATS[i];
    return NULL;
}

ibl_status ibl__dds_encode(ibl_context *ctx, const ibl_texture *tex, const ibl_write_desc *desc,
                           const char *name, void **bytes, size_t *size)
{
    size_t clamped = 0; /* texels stored at the format's largest value */
    if (!name) name = "<dds>";
    if (!bytes || !size) return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "%s: no output", name);
    *bytes = NULL;
    *size = 0;
    ibl_status st = ibl__check_texture(ctx, tex, name);
    if (st != IBL_OK) return st;
    ibl_format fmt = ibl__container_format(tex, desc);
    const dxgi_map *dx = map_format(fmt);
    if (!dx)
        return ibl__fail(ctx, IBL_ERR_UNSUPPORTED,
                        "%s: DDS output does not support pixel format %s (use rgba16f, rgba32f, "
                        "rg11b10f, rgb9e5, rg16f, rg32f, bc6h or bc6h-signed)",
                        name, ibl_format_name(fmt));
    ibl_dds_header header = desc ? desc->dds_header : IBL_DDS_HEADER_AUTO;
    if (header == IBL_DDS_HEADER_LEGACY && !dx->legacy_fourcc)
        return ibl__fail(ctx, IBL_ERR_UNSUPPORTED,
                        "%s: %s has no legacy DDS FourCC (only rgba16f, rgba32f, rg16f and rg32f "
                        "do); it needs the DX10 header", name, ibl_format_name(fmt));
    /* the legacy header has no array size: a cube-map array always takes the DX10 header */
    int is_array = tex->kind == IBL_TEXTURE_CUBE_ARRAY;
    if (header == IBL_DDS_HEADER_LEGACY && is_array)
        return ibl__fail(ctx, IBL_ERR_UNSUPPORTED,
                        "%s: a cube-map array needs the DX10 header (the legacy one has no array size)",
                        name);
    int legacy = header != IBL_DDS_HEADER_DX10 && dx->legacy_fourcc && !is_array;
    size_t data_offset = legacy ? DATA_OFFSET_LEGACY : DATA_OFFSET_DX10;
    int faces = ibl_texture_faces(tex);
    int is3d = tex->kind == IBL_TEXTURE_3D, block = ibl__format_is_block(fmt);

    uint64_t total = data_offset;
    for (int l = 0; l < tex->levels; l++)
        total += ibl__level_bytes(fmt, tex->kind, tex->width, tex->height, tex->depth, l) *
                 (uint64_t)faces;
    if (total > SIZE_MAX)
        return ibl__fail(ctx, IBL_ERR_TOO_LARGE, "%s: texture is too large to encode", name);
    /* only the header is zeroed: the encoders write every byte of the levels (a calloc would
     * also fault in and clear the whole buffer on this thread first) */
    uint8_t *buf = ibl_alloc(ctx, (size_t)total);
    if (!buf) return ibl__fail_named(ctx, ibl_context_status(ctx), name);
    memset(buf, 0, data_offset);

    uint32_t flags = DDSD_CAPS | DDSD_HEIGHT | DDSD_WIDTH | DDSD_PIXELFORMAT |
                     (block ? DDSD_LINEARSIZE : DDSD_PITCH) | DDSD_MIPMAPCOUNT;
    if (is3d) flags |= DDSD_DEPTH;
    uint32_t caps = DDSCAPS_TEXTURE, caps2 = 0;
    if (tex->levels > 1) caps |= DDSCAPS_COMPLEX | DDSCAPS_MIPMAP;
    int cube = tex->kind == IBL_TEXTURE_CUBE || tex->kind == IBL_TEXTURE_CUBE_ARRAY;
    if (cube) {
        caps |= DDSCAPS_COMPLEX;
        caps2 |= DDSCAPS2_CUBEMAP | DDSCAPS2_CUBEMAP_ALLFACES;
    }
    /* COMPLEX marks files with more than one surface: mips or cube faces (a volume without
     * mips is one surface) */
    if (is3d) caps2 |= DDSCAPS2_VOLUME;
    uint8_t *h = buf + 4;
    ibl__wr32(buf, DDS_MAGIC);
    ibl__wr32(h + 0, HEADER_SIZE);
    ibl__wr32(h + 4, flags);
    ibl__wr32(h + 8, (uint32_t)tex->height);
    ibl__wr32(h + 12, (uint32_t)tex->width);
    /* pitch: bytes per row; for block formats the linear size: bytes of the top level */
    ibl__wr32(h + 16, block ? (uint32_t)ibl__level_bytes(fmt, tex->kind, tex->width, tex->height,
                                                          tex->depth, 0)
                            : (uint32_t)((size_t)tex->width * ibl__format_unit_bytes(fmt)));
    ibl__wr32(h + 20, is3d ? (uint32_t)tex->depth : 0);
    ibl__wr32(h + 24, (uint32_t)tex->levels);
    /* dwReserved1[11] stays zero; DDS_PIXELFORMAT at 72 */
    ibl__wr32(h + 72, PIXELFORMAT_SIZE);
    ibl__wr32(h + 76, DDPF_FOURCC);
    ibl__wr32(h + 80, legacy ? dx->legacy_fourcc : FOURCC_DX10);
    ibl__wr32(h + 104, caps);
    ibl__wr32(h + 108, caps2);
    if (!legacy) {
        uint8_t *x = buf + 4 + HEADER_SIZE;
        ibl__wr32(x + 0, dx->dxgi);
        ibl__wr32(x + 4, is3d ? DIM_TEXTURE3D : DIM_TEXTURE2D);
        ibl__wr32(x + 8, cube ? MISC_TEXTURECUBE : 0);
        /* arraySize: one texture, one cube, or the cubes of a cube-map array (Microsoft's
         * DDS_HEADER_DXT10: "For a 2D texture that is also a cube-map texture, this number
         * represents the number of cubes") */
        ibl__wr32(x + 12, tex->kind == IBL_TEXTURE_CUBE_ARRAY ? (uint32_t)tex->depth : 1);
        ibl__wr32(x + 16, ibl_format_channels(fmt) == 4 ? ALPHA_MODE_STRAIGHT : ALPHA_MODE_UNKNOWN);
    }

    size_t at = data_offset;
    for (int f = 0; f < faces; f++) {
        for (int l = 0; l < tex->levels; l++) {
            clamped += ibl__encode_level(ctx, fmt, desc, tex, l, f, buf + at, &st);
            if (st != IBL_OK) {
                ibl_free(ctx, buf);
                return ibl__fail_named(ctx, st, name);
            }
            at += (size_t)ibl__level_bytes(fmt, tex->kind, tex->width, tex->height, tex->depth, l);
        }
    }
    *bytes = buf;
    *size = (size_t)total;
    if (desc && desc->report) desc->report->clamped_texels += clamped;
    return IBL_OK;
}

/* What the header (and its DX10 extension) says. */
typedef struct dds_header {
    const dxgi_map *dx;
    ibl_texture_kind kind;
    int width, height, depth, levels; /* depth: slices, or a cube-map array's layers */
    size_t data_at;                   /* the first texel block                       */
} dds_header;

static ibl_status parse_header(ibl_context *ctx, const uint8_t *bytes, size_t size,
                               const char *name, dds_header *hd)
{
    memset(hd, 0, sizeof *hd);
    if (size < 4 || ibl__rd32(bytes) != DDS_MAGIC)
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: not a DDS file (wrong magic)", name);
    if (size < DATA_OFFSET_LEGACY)
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: truncated DDS header (%zu of %d bytes)", name,
                        size, DATA_OFFSET_LEGACY);
    const uint8_t *h = bytes + 4;
    if (ibl__rd32(h) != HEADER_SIZE || ibl__rd32(h + 72) != PIXELFORMAT_SIZE)
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: DDS header size %u / pixel format size %u "
                        "(must be 124 / 32)", name, ibl__rd32(h), ibl__rd32(h + 72));
    uint32_t height = ibl__rd32(h + 8), width = ibl__rd32(h + 12), depth = ibl__rd32(h + 20);
    uint32_t mips = ibl__rd32(h + 24), pf_flags = ibl__rd32(h + 76), fourcc = ibl__rd32(h + 80);
    uint32_t caps2 = ibl__rd32(h + 108);
    if (!(pf_flags & DDPF_FOURCC))
        return ibl__fail(ctx, IBL_ERR_UNSUPPORTED,
                        "%s: DDS with an RGB bit-mask pixel format is not supported (only float "
                        "formats)", name);

    const dxgi_map *dx;
    ibl_texture_kind kind = IBL_TEXTURE_2D;
    size_t data_at;
    if (fourcc == FOURCC_DX10) {
        if (size < DATA_OFFSET_DX10)
            return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: truncated DX10 header", name);
        const uint8_t *x = bytes + 4 + HEADER_SIZE;
        uint32_t dxgi = ibl__rd32(x), dim = ibl__rd32(x + 4), misc = ibl__rd32(x + 8);
        uint32_t array = ibl__rd32(x + 12);
        dx = map_dxgi(dxgi);
        if (!dx)
            return ibl__fail(ctx, IBL_ERR_UNSUPPORTED,
                            "%s: unsupported DXGI format %u (supported: 10 R16G16B16A16_FLOAT, 2 "
                            "R32G32B32A32_FLOAT, 26 R11G11B10_FLOAT, 67 R9G9B9E5_SHAREDEXP, 34 "
                            "R16G16_FLOAT, 16 R32G32_FLOAT, 95 BC6H_UF16, 96 BC6H_SF16)",
                            name, dxgi);
        if (array == 0) return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: arraySize 0", name);
        if (array > 1 && !(dim == DIM_TEXTURE2D && (misc & MISC_TEXTURECUBE)))
            return ibl__fail(ctx, IBL_ERR_UNSUPPORTED,
                            "%s: arraySize %u (of arrays only cube-map arrays are supported)", name,
                            array);
        if (dim == DIM_TEXTURE3D) {
            kind = IBL_TEXTURE_3D;
        } else if (dim == DIM_TEXTURE2D || dim == DIM_TEXTURE1D) {
            if (misc & MISC_TEXTURECUBE) {
                if (dim != DIM_TEXTURE2D)
                    return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: a 1D texture flagged as a cube", name);
                kind = array > 1 ? IBL_TEXTURE_CUBE_ARRAY : IBL_TEXTURE_CUBE;
                depth = array; /* a cube-map array's "depth" is its layer count */
            }
            if (dim == DIM_TEXTURE1D && height > 1)
                return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: a 1D texture with height %u", name,
                                height);
        } else {
            return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: invalid resourceDimension %u", name, dim);
        }
        data_at = DATA_OFFSET_DX10;
    } else {
        dx = map_fourcc(fourcc);
        if (!dx)
            return ibl__fail(ctx, IBL_ERR_UNSUPPORTED,
                            "%s: unsupported DDS FourCC 0x%08x (supported: DX10, 112, 113, 115, 116)",
                            name, fourcc);
        if (caps2 & DDSCAPS2_CUBEMAP) {
            if ((caps2 & DDSCAPS2_CUBEMAP_ALLFACES) != DDSCAPS2_CUBEMAP_ALLFACES)
                return ibl__fail(ctx, IBL_ERR_UNSUPPORTED,
                                "%s: cube map with missing faces is not supported", name);
            kind = IBL_TEXTURE_CUBE;
        } else if (caps2 & DDSCAPS2_VOLUME) {
            kind = IBL_TEXTURE_3D;
        }
        data_at = DATA_OFFSET_LEGACY;
    }
    if (kind == IBL_TEXTURE_3D && depth == 0)
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: volume texture with depth 0", name);
    if (kind != IBL_TEXTURE_3D && kind != IBL_TEXTURE_CUBE_ARRAY) depth = 1;
    uint64_t levels = mips ? mips : 1;
    ibl_status st = ibl__check_dimensions(ctx, name, kind, width, height, depth, levels);
    if (st != IBL_OK) return st;
    hd->dx = dx;
    hd->kind = kind;
    hd->width = (int)width;
    hd->height = (int)height;
    hd->depth = (int)depth;
    hd->levels = (int)levels;
    hd->data_at = data_at;
    return IBL_OK;
}

ibl_status ibl__dds_info(ibl_context *ctx, const uint8_t *bytes, size_t size, const char *name,
                         ibl_file_info *info)
{
    dds_header hd;
    ibl_status st = parse_header(ctx, bytes, size, name, &hd);
    if (st != IBL_OK) return st;
    ibl_texture tex = ibl__header_texture(hd.kind, hd.width, hd.height, hd.depth, hd.levels,
                                          hd.dx->format);
    ibl__fill_info(info, IBL_FILE_DDS, &tex);
    return IBL_OK;
}

ibl_status ibl__dds_decode(ibl_context *ctx, const uint8_t *bytes, size_t size, const char *name,
                           ibl_texture *out, ibl_file_info *info)
{
    if (!name) name = "<dds>";
    if (!out) return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "%s: no output texture", name);
    memset(out, 0, sizeof *out);
    if (!bytes && size) return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "%s: no input", name);
    dds_header hd;
    ibl_status st = parse_header(ctx, bytes, size, name, &hd);
    if (st != IBL_OK) return st;
    const dxgi_map *dx = hd.dx;
    ibl_texture_kind kind = hd.kind;
    size_t data_at = hd.data_at;
    uint64_t levels = (uint64_t)hd.levels;
    int w = hd.width, hh = hd.height, d = hd.depth;
    int faces = kind == IBL_TEXTURE_CUBE ? 6 : kind == IBL_TEXTURE_CUBE_ARRAY ? 6 * d : 1;
    /* at most 17 levels * 6 * 2^48 * 16 (faces * 2^32 texels when 2^16 layers): fits in 64 bits */
    uint64_t need = 0;
    for (int l = 0; l < (int)levels; l++)
        need += ibl__level_bytes(dx->format, kind, w, hh, d, l) * (uint64_t)faces;
    if (need > size - data_at)
        return ibl__fail(ctx, IBL_ERR_FORMAT,
                        "%s: truncated: the texture needs %llu bytes of data, the file has %zu",
                        name, (unsigned long long)need, size - data_at);

    st = ibl_texture_alloc(ctx, kind, w, hh, d, (int)levels, out);
    if (st != IBL_OK) return ibl__fail_named(ctx, st, name);
    out->format = dx->format;
    const uint8_t *p = bytes + data_at;
    for (int f = 0; f < faces; f++) {
        for (int l = 0; l < (int)levels; l++) {
            st = ibl__decode_level(ctx, dx->format, 0.0f, p, out, l, f);
            if (st != IBL_OK) {
                ibl_texture_free(ctx, out);
                return ibl__fail_named(ctx, st, name);
            }
            p += (size_t)ibl__level_bytes(dx->format, kind, w, hh, d, l);
        }
    }
    ibl__fill_info(info, IBL_FILE_DDS, out);
    return IBL_OK;
}
