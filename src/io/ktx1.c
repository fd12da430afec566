/* KTX 1.1 write and read (Khronos "KTX File Format Specification", version 1.1): the same six
 * storage formats as KTX2, described by OpenGL enums. Layout: identifier, 13 UInt32 header
 * fields, key/value data, then per mip level (base first) UInt32 imageSize followed by the
 * images. For a non-array cube map imageSize is the size of ONE face and each face is
 * followed by cubePadding; otherwise imageSize covers the whole level (all slices). Files
 * are written little-endian (endianness 0x04030201). */
#include <string.h>

#include "core/pixel_format.h"
#include "core/context_internal.h"
#include "io/container.h"

static const uint8_t KTX1_IDENTIFIER[12] = {0xAB, 0x4B, 0x54, 0x58, 0x20, 0x31,
                                            0x31, 0xBB, 0x0D, 0x0A, 0x1A, 0x0A};

enum {
    HEADER_BYTES = 64,
    ENDIAN_REF = 0x04030201,
    /* OpenGL 4.6 enums (glcorearb.h) */
    GL_FLOAT = 0x1406,
    GL_HALF_FLOAT = 0x140B,
    GL_RGB = 0x1907,
    GL_RGBA = 0x1908,
    GL_RG = 0x8227,
    GL_RG16F = 0x822F,
    GL_RG32F = 0x8230,
    GL_RGBA32F = 0x8814,
    GL_RGBA16F = 0x881A,
    GL_R11F_G11F_B10F = 0x8C3A,
    GL_UNSIGNED_INT_10F_11F_11F_REV = 0x8C3B,
    GL_RGB9_E5 = 0x8C3D,
    GL_UNSIGNED_INT_5_9_9_9_REV = 0x8C3E
};

typedef struct gl_map {
    ibl_format format;
    uint32_t type, type_size, gl_format, internal_format, base_internal_format;
} gl_map;

/* glTypeSize is 1 for compressed data, the component size for plain types and the size of
 * the packed word for packed types (GL_UNSIGNED_INT_*_REV: 4). */
static const gl_map GL_FORMATS[] = {
    {IBL_FORMAT_RGBA16F, GL_HALF_FLOAT, 2, GL_RGBA, GL_RGBA16F, GL_RGBA},
    {IBL_FORMAT_RGBA32F, GL_FLOAT, 4, GL_RGBA, GL_RGBA32F, GL_RGBA},
    {IBL_FORMAT_RG11B10F, GL_UNSIGNED_INT_10F_11F_11F_REV, 4, GL_RGB, GL_R11F_G11F_B10F, GL_RGB},
    {IBL_FORMAT_RGB9E5, GL_UNSIGNED_INT_5_9_9_9_REV, 4, GL_RGB, GL_RGB9_E5, GL_RGB},
    {IBL_FORMAT_RG16F, GL_HALF_FLOAT, 2, GL_RG, GL_RG16F, GL_RG},
    {IBL_FORMAT_RG32F, GL_FLOAT, 4, GL_RG, GL_RG32F, GL_RG},
};

static const gl_map *map_format(ibl_format f)
{
    for (size_t i = 0; i < sizeof GL_FORMATS / sizeof GL_FORMATS[0]; i++)
        if (GL_FORMATS[i].format == f) return &GL_FORMATS[i];
    return NULL;
}

static const gl_map *map_gl(uint32_t internal_format)
{
    for (size_t i = 0; i < sizeof GL_FORMATS / sizeof GL_FORMATS[0]; i++)
        if (GL_FORMATS[i].internal_format == internal_format) return &GL_FORMATS[i];
    return NULL;
}

static size_t pad4(size_t n)
{
    return (n + 3) & ~(size_t)3;
}

ibl_status ibl__ktx1_encode(ibl_context *ctx, const ibl_texture *tex, const ibl_write_desc *desc,
                            const char *name, void **bytes, size_t *size)
{
    size_t clamped = 0; /* texels stored at the format's largest value */
    if (!name) name = "<ktx>";
    if (!bytes || !size) return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "%s: no output", name);
    *bytes = NULL;
    *size = 0;
    ibl_status st = ibl__check_texture(ctx, tex, name);
    if (st != IBL_OK) return st;
    if (tex->kind == IBL_TEXTURE_CUBE_ARRAY)
        return ibl__fail(ctx, IBL_ERR_UNSUPPORTED,
                        "%s: KTX1 output does not store cube-map arrays (use .ktx2 or .dds)", name);
    ibl_format fmt = ibl__container_format(tex, desc);
    const gl_map *gl = map_format(fmt);
    if (!gl)
        return ibl__fail(ctx, IBL_ERR_UNSUPPORTED,
                        "%s: KTX1 output does not support pixel format %s (use rgba16f, rgba32f, "
                        "rg11b10f, rgb9e5, rg16f or rg32f)",
                        name, ibl_format_name(fmt));
    size_t texel = ibl_format_texel_bytes(fmt);
    int faces = ibl_texture_faces(tex);
    int cube = tex->kind == IBL_TEXTURE_CUBE;

    /* KTX 1.1 defines one key, KTXorientation, as "S=r,T=d[,R=i]". */
    ibl_key_value fixed[1] = {
        {(char *)"KTXorientation", (char *)(tex->kind == IBL_TEXTURE_3D ? "S=r,T=d,R=i" : "S=r,T=d")},
    };
    uint8_t *kvd = NULL;
    size_t kvd_len = 0;
    st = ibl__kv_build(ctx, name, fixed, 1, tex, &kvd, &kvd_len);
    if (st != IBL_OK) return st;
    if (kvd_len > UINT32_MAX) {
        ibl_free(ctx, kvd);
        return ibl__fail(ctx, IBL_ERR_TOO_LARGE, "%s: metadata is too large", name);
    }

    uint64_t total = HEADER_BYTES + kvd_len;
    for (int l = 0; l < tex->levels; l++) {
        uint64_t face = ibl__level_texels(tex->kind, tex->width, tex->height, tex->depth, l) * texel;
        uint64_t image = cube ? face : face * (uint64_t)faces;
        if (image > UINT32_MAX) {
            ibl_free(ctx, kvd);
            return ibl__fail(ctx, IBL_ERR_TOO_LARGE,
                            "%s: level %d needs %llu bytes, over KTX1's 4 GiB imageSize", name, l,
                            (unsigned long long)image);
        }
        total += 4 + (uint64_t)faces * pad4((size_t)face); /* faces, cube padding, mip padding */
    }
    if (total > SIZE_MAX) {
        ibl_free(ctx, kvd);
        return ibl__fail(ctx, IBL_ERR_TOO_LARGE, "%s: texture is too large to encode", name);
    }
    uint8_t *buf = ibl_calloc(ctx, (size_t)total, 1);
    if (!buf) {
        ibl_free(ctx, kvd);
        return ibl__fail_named(ctx, ibl_context_status(ctx), name);
    }
    memcpy(buf, KTX1_IDENTIFIER, 12);
    ibl__wr32(buf + 12, ENDIAN_REF);
    /* Filament's cmgen writes R11F_G11F_B10F into glType (and glFormat) and Filament's KTX1
     * reader maps only that glType to these texels; on request we write its form, else the
     * spec's packed type, which every other reader (libktx, our own) expects. */
    int cmgen = desc && desc->ktx1_cmgen_types && fmt == IBL_FORMAT_RG11B10F;
    ibl__wr32(buf + 16, cmgen ? GL_R11F_G11F_B10F : gl->type);
    ibl__wr32(buf + 20, gl->type_size);
    ibl__wr32(buf + 24, gl->gl_format);
    ibl__wr32(buf + 28, gl->internal_format);
    ibl__wr32(buf + 32, gl->base_internal_format);
    ibl__wr32(buf + 36, (uint32_t)tex->width);
    ibl__wr32(buf + 40, (uint32_t)tex->height);
    ibl__wr32(buf + 44, tex->kind == IBL_TEXTURE_3D ? (uint32_t)tex->depth : 0);
    ibl__wr32(buf + 48, 0); /* numberOfArrayElements */
    ibl__wr32(buf + 52, (uint32_t)faces);
    ibl__wr32(buf + 56, (uint32_t)tex->levels);
    ibl__wr32(buf + 60, (uint32_t)kvd_len);
    if (kvd_len) memcpy(buf + HEADER_BYTES, kvd, kvd_len);
    ibl_free(ctx, kvd);
    size_t at = HEADER_BYTES + kvd_len;
    for (int l = 0; l < tex->levels; l++) {
        size_t count = (size_t)ibl__level_texels(tex->kind, tex->width, tex->height, tex->depth, l);
        size_t face = count * texel;
        ibl__wr32(buf + at, (uint32_t)(cube ? face : face * (size_t)faces));
        at += 4;
        for (int f = 0; f < faces; f++) {
            clamped += ibl__pack(ctx, fmt, ibl_texture_level(tex, l, f), count, buf + at);
            at += pad4(face);
        }
    }
    *bytes = buf;
    *size = (size_t)total;
    if (desc && desc->report) desc->report->clamped_texels += clamped;
    return IBL_OK;
}

/* "S=r,T=d" style orientation (any order, optional R) into flips to our layout. */
static ibl_status orientation(ibl_context *ctx, const char *name, const ibl_texture *tex,
                              int flips[3])
{
    flips[0] = flips[1] = flips[2] = 0;
    const char *o = ibl_texture_get_metadata(tex, "KTXorientation");
    if (!o) return IBL_OK;
    for (const char *p = o; *p;) {
        if (!p[0] || !p[1] || p[1] != '=' || !p[2])
            return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: invalid KTXorientation \"%s\"", name, o);
        char axis = p[0], dir = p[2];
        if (axis == 'S' && (dir == 'r' || dir == 'l')) flips[0] = dir == 'l';
        else if (axis == 'T' && (dir == 'd' || dir == 'u')) flips[1] = dir == 'u';
        else if (axis == 'R' && (dir == 'i' || dir == 'o')) flips[2] = dir == 'o';
        else return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: invalid KTXorientation \"%s\"", name, o);
        p += 3;
        if (*p == ',') p++;
        else if (*p) return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: invalid KTXorientation \"%s\"", name, o);
    }
    if (tex->kind == IBL_TEXTURE_CUBE && (flips[0] || flips[1]))
        return ibl__fail(ctx, IBL_ERR_FORMAT,
                        "%s: cube map faces must be stored S=r,T=d, the file says \"%s\"", name, o);
    if (tex->kind != IBL_TEXTURE_3D) flips[2] = 0;
    return IBL_OK;
}

/* What the header says, and where the key/value data ends. */
typedef struct ktx1_header {
    const gl_map *gl;
    ibl_texture_kind kind;
    int width, height, depth, levels;
    uint32_t faces, kvd_len;
} ktx1_header;

/* The header and the key/value data's extent: everything before the first imageSize. */
static ibl_status parse_header(ibl_context *ctx, const uint8_t *bytes, size_t size,
                               const char *name, ktx1_header *hd)
{
    memset(hd, 0, sizeof *hd);
    if (size < 12 || memcmp(bytes, KTX1_IDENTIFIER, 12) != 0)
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: not a KTX 1 file (wrong identifier)", name);
    if (size < HEADER_BYTES)
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: truncated KTX header (%zu of %d bytes)", name,
                        size, HEADER_BYTES);
    uint32_t endian = ibl__rd32(bytes + 12);
    if (endian == 0x01020304u)
        return ibl__fail(ctx, IBL_ERR_UNSUPPORTED, "%s: big-endian KTX files are not supported",
                        name);
    if (endian != ENDIAN_REF)
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: invalid endianness field 0x%08x", name, endian);
    uint32_t type = ibl__rd32(bytes + 16), gl_format = ibl__rd32(bytes + 24);
    uint32_t internal = ibl__rd32(bytes + 28);
    uint32_t width = ibl__rd32(bytes + 36), height = ibl__rd32(bytes + 40);
    uint32_t depth = ibl__rd32(bytes + 44), elements = ibl__rd32(bytes + 48);
    uint32_t faces = ibl__rd32(bytes + 52), level_count = ibl__rd32(bytes + 56);
    uint32_t kvd_len = ibl__rd32(bytes + 60);

    const gl_map *gl = map_gl(internal);
    /* Filament's cmgen stores R11F_G11F_B10F as glType, and as glFormat up to Filament
     * 1.8: read that form too */
    if (gl && gl->format == IBL_FORMAT_RG11B10F && type == GL_R11F_G11F_B10F) type = gl->type;
    if (gl && gl->format == IBL_FORMAT_RG11B10F && gl_format == GL_R11F_G11F_B10F) gl_format = gl->gl_format;
    if (!gl || gl->type != type || gl->gl_format != gl_format)
        return ibl__fail(ctx, IBL_ERR_UNSUPPORTED,
                        "%s: unsupported GL format (glInternalFormat 0x%04x, glFormat 0x%04x, "
                        "glType 0x%04x); supported: RGBA16F, RGBA32F, R11F_G11F_B10F, RGB9_E5, "
                        "RG16F, RG32F",
                        name, internal, gl_format, type);
    if (elements != 0)
        return ibl__fail(ctx, IBL_ERR_UNSUPPORTED, "%s: array textures (%u elements) are not supported",
                        name, elements);
    if (faces != 1 && faces != 6)
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: numberOfFaces %u (must be 1 or 6)", name, faces);
    if (width == 0) return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: pixelWidth is 0", name);
    ibl_texture_kind kind = faces == 6 ? IBL_TEXTURE_CUBE : depth ? IBL_TEXTURE_3D : IBL_TEXTURE_2D;
    if ((faces == 6 && depth != 0) || (depth != 0 && height == 0))
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: pixelDepth %u with %u faces and height %u", name,
                        depth, faces, height);
    uint64_t levels = level_count ? level_count : 1;
    ibl_status st = ibl__check_dimensions(ctx, name, kind, width, height ? height : 1,
                                          depth ? depth : 1, levels);
    if (st != IBL_OK) return st;
    if (kvd_len > size - HEADER_BYTES)
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: key/value data (%u bytes) runs past the end of "
                        "the file", name, kvd_len);
    hd->gl = gl;
    hd->kind = kind;
    hd->width = (int)width;
    hd->height = height ? (int)height : 1;
    hd->depth = depth ? (int)depth : 1;
    hd->levels = (int)levels;
    hd->faces = faces;
    hd->kvd_len = kvd_len;
    return IBL_OK;
}

/* The key/value data into tex (kind and format set) and the flips of its KTXorientation. */
static ibl_status read_metadata(ibl_context *ctx, const char *name, const uint8_t *bytes,
                                const ktx1_header *hd, ibl_texture *tex, int flips[3])
{
    ibl_status st = ibl__kv_parse(ctx, name, bytes + HEADER_BYTES, hd->kvd_len, tex);
    if (st == IBL_OK) st = orientation(ctx, name, tex, flips);
    return st;
}

ibl_status ibl__ktx1_info(ibl_context *ctx, const uint8_t *bytes, size_t size, const char *name,
                          ibl_file_info *info)
{
    ktx1_header hd;
    ibl_status st = parse_header(ctx, bytes, size, name, &hd);
    if (st != IBL_OK) return st;
    ibl_texture tex = ibl__header_texture(hd.kind, hd.width, hd.height, hd.depth, hd.levels,
                                          hd.gl->format);
    int flips[3];
    st = read_metadata(ctx, name, bytes, &hd, &tex, flips);
    if (st == IBL_OK) ibl__fill_info(info, IBL_FILE_KTX1, &tex);
    ibl_texture_free(ctx, &tex);
    return st;
}

ibl_status ibl__ktx1_decode(ibl_context *ctx, const uint8_t *bytes, size_t size, const char *name,
                            ibl_texture *out, ibl_file_info *info)
{
    if (!name) name = "<ktx>";
    if (!out) return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "%s: no output texture", name);
    memset(out, 0, sizeof *out);
    if (!bytes && size) return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "%s: no input", name);
    ktx1_header hd;
    ibl_status st = parse_header(ctx, bytes, size, name, &hd);
    if (st != IBL_OK) return st;
    const gl_map *gl = hd.gl;
    ibl_texture_kind kind = hd.kind;
    int w = hd.width, h = hd.height, d = hd.depth;
    uint64_t levels = (uint64_t)hd.levels;
    uint32_t faces = hd.faces, kvd_len = hd.kvd_len;

    /* Walk the levels once to validate every imageSize before allocating. */
    size_t texel = ibl_format_texel_bytes(gl->format);
    size_t level_at[IBL_MAX_LEVELS];
    size_t at = HEADER_BYTES + kvd_len;
    for (uint64_t l = 0; l < levels; l++) {
        uint64_t face = ibl__level_texels(kind, w, h, d, (int)l) * texel;
        uint64_t expect = kind == IBL_TEXTURE_CUBE ? face : face * faces;
        if (size - at < 4)
            return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: file ends before the imageSize of level %llu",
                            name, (unsigned long long)l);
        uint32_t image = ibl__rd32(bytes + at);
        if (image != expect)
            return ibl__fail(ctx, IBL_ERR_FORMAT,
                            "%s: level %llu imageSize is %u bytes, its dimensions need %llu", name,
                            (unsigned long long)l, image, (unsigned long long)expect);
        at += 4;
        level_at[l] = at;
        /* faces (each padded to 4 for cubes) then mip padding to 4; face < 2^32 here */
        uint64_t span = (uint64_t)faces * ((face + 3) & ~(uint64_t)3);
        if (span > size - at)
            return ibl__fail(ctx, IBL_ERR_FORMAT,
                            "%s: level %llu (%llu bytes) runs past the end of the file (%zu bytes)",
                            name, (unsigned long long)l, (unsigned long long)span, size);
        at += (size_t)span;
    }

    st = ibl_texture_alloc(ctx, kind, w, h, d, (int)levels, out);
    if (st != IBL_OK) return ibl__fail_named(ctx, st, name);
    out->format = gl->format;
    int flips[3];
    st = read_metadata(ctx, name, bytes, &hd, out, flips);
    if (st != IBL_OK) {
        ibl_texture_free(ctx, out);
        return st;
    }
    for (uint64_t l = 0; l < levels; l++) {
        size_t count = (size_t)ibl__level_texels(kind, w, h, d, (int)l);
        size_t face = pad4(count * texel);
        for (uint32_t f = 0; f < faces; f++)
            ibl__unpack(ctx, gl->format, bytes + level_at[l] + f * face, count,
                              ibl_texture_level(out, (int)l, (int)f));
    }
    ibl__flip_texture(out, flips[0], flips[1], flips[2]);
    if (flips[0] || flips[1] || flips[2]) {
        st = ibl_texture_set_metadata(ctx, out, "KTXorientation",
                                      kind == IBL_TEXTURE_3D ? "S=r,T=d,R=i" : "S=r,T=d");
        if (st != IBL_OK) {
            ibl_texture_free(ctx, out);
            return ibl__fail_named(ctx, st, name);
        }
    }
    ibl__fill_info(info, IBL_FILE_KTX1, out);
    return IBL_OK;
}
