/*
 * ibl/io.h - reading and writing images and textures.
 *
 * Flat images: Radiance .hdr, OpenEXR .exr, .pfm, .png, .jpg. Textures (2D, 3D, cube, mips,
 * metadata): .ktx2, .ktx (KTX 1.1), .dds (DX10 header). The container is chosen from the
 * path's extension when writing and from the file's magic bytes when reading.
 *
 * Every reader applies the pixel policy of ibl_sanitize_pixels (NaN and negatives become 0,
 * infinities are refused unless clamp_infinite) and reports what it changed in info->pixels.
 * Every writer encodes the whole file in memory, writes it under a temporary name in the same
 * folder and renames it over the target only when complete, so a failed or interrupted write
 * never leaves a partial file and never damages an existing one. Error messages name the file.
 */
#ifndef IBL_IO_H
#define IBL_IO_H

#include "compress.h"
#include "core.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum ibl_file_type {
    IBL_FILE_UNKNOWN = 0,
    IBL_FILE_HDR,
    IBL_FILE_EXR,
    IBL_FILE_PFM,
    IBL_FILE_PNG,
    IBL_FILE_JPEG,
    IBL_FILE_KTX2,
    IBL_FILE_KTX1,
    IBL_FILE_DDS
} ibl_file_type;

const char *ibl_file_type_name(ibl_file_type type); /* "hdr", "exr", ... */
/* From the extension (case-insensitive): .hdr .pic .exr .pfm .png .jpg .jpeg .ktx2 .ktx .dds */
ibl_file_type ibl_file_type_from_path(const char *path);
/* From the first bytes of a file (at least 16 bytes wanted). */
ibl_file_type ibl_file_type_sniff(const void *bytes, size_t size);
/* Non-zero if the type stores textures (ktx2, ktx1, dds) rather than one flat image. */
int ibl_file_type_is_container(ibl_file_type type);
/* Non-zero if a writer of the type stores that pixel format (IBL_FORMAT_DEFAULT: always), so
 * that a bad combination is refused before any work. */
int ibl_file_type_writes_format(ibl_file_type type, ibl_format format);

typedef struct ibl_read_desc {
    int clamp_infinite; /* accept +-Inf and clamp them (the CLI's --clamp)              */
    float clamp_value;  /* value for +Inf when clamping; 0: 65504 (largest half)        */
    int as_data;        /* PNG: samples as stored (code / 255 or / 65535) whatever the
                           file's sRGB or gAMA chunk: material maps are data, not colours
                           (`ibl pack`); RGBM files are not decoded                      */
} ibl_read_desc;

typedef struct ibl_file_info {
    ibl_file_type type;
    ibl_format format;        /* how the pixels were stored                          */
    ibl_texture_kind kind;    /* 2D for flat images                                  */
    int width, height, depth, levels;
    ibl_pixel_report pixels;  /* what the pixel policy found and changed             */
    int has_alpha;            /* the file had a real alpha channel                   */
} ibl_file_info;

/* Reads a flat image (for containers: level 0 of a 2D texture). desc and info may be NULL. */
ibl_status ibl_read_image(ibl_context *ctx, const char *path, const ibl_read_desc *desc,
                          ibl_image *out, ibl_file_info *info);
/* Reads any supported file as a texture (flat images become one-level 2D textures). */
ibl_status ibl_read_texture(ibl_context *ctx, const char *path, const ibl_read_desc *desc,
                            ibl_texture *out, ibl_file_info *info);
/* The same from memory; name is used in messages (e.g. the path, or "<memory>"). */
ibl_status ibl_decode_texture(ibl_context *ctx, const void *bytes, size_t size, const char *name,
                              const ibl_read_desc *desc, ibl_texture *out, ibl_file_info *info);
/* What the bytes hold, from the header alone, so that work depending only on the size can be
 * planned before (or beside) the decode: type, format, kind, width, height, depth, levels and
 * has_alpha, equal to the info ibl_decode_texture gives (with default read options) for every
 * file it accepts; info->pixels stays zero, as no pixel is looked at, decoded or allocated.
 * A malformed header fails as the full decode does, with a one-line message naming `name`.
 * Checks that need the pixel data are not made: a file whose header is sound but whose pixel
 * data is cut short or corrupt (an EXR's chunks, a PNG's IDAT, a container's level that runs
 * past the end) may succeed here and fail in ibl_decode_texture. Nor is the memory budget
 * consulted: nothing the size of the image is allocated. */
ibl_status ibl_decode_info(ibl_context *ctx, const void *bytes, size_t size, const char *name,
                           ibl_file_info *info);
/* ibl_decode_info for a file: reads only its head (the first 64 KiB; more, up to the whole
 * file, when a header runs past that, e.g. an EXR with large attributes), so that a 100 MB
 * EXR costs a few page reads. Pipes and devices are read whole. Errors name the path. */
ibl_status ibl_read_info(ibl_context *ctx, const char *path, ibl_file_info *info);

typedef enum ibl_tonemap {
    IBL_TONEMAP_DEFAULT = 0, /* filmic for 8-bit outputs, none otherwise */
    IBL_TONEMAP_NONE,        /* clamp to [0, 1]                          */
    IBL_TONEMAP_FILMIC       /* ACES fitted curve (Narkowicz 2016)        */
} ibl_tonemap;

typedef enum ibl_exr_compression {
    IBL_EXR_DEFAULT = 0, /* ZIP */
    IBL_EXR_NONE,
    IBL_EXR_RLE,
    IBL_EXR_ZIPS,
    IBL_EXR_ZIP,
    IBL_EXR_PIZ
} ibl_exr_compression;

/* The header a DDS file is written with. The legacy header names the pixel format by a
 * Direct3D 9 FourCC (113 D3DFMT_A16B16G16R16F, 116 A32B32G32R32F, 112 G16R16F, 115
 * G32R32F); the DX10 extension by a DXGI format. Every DDS reader that knows DX10 also knows
 * these FourCCs, while several (OpenImageIO 2.4, Pillow, three.js) read half and float
 * texels only through the FourCC: AUTO writes the legacy header where the format has a
 * FourCC and DX10 where it has none (rg11b10f, rgb9e5, BC6H). docs/FORMATS.md "DDS". */
typedef enum ibl_dds_header {
    IBL_DDS_HEADER_AUTO = 0,
    IBL_DDS_HEADER_LEGACY, /* refused for formats without a FourCC */
    IBL_DDS_HEADER_DX10
} ibl_dds_header;

/* What a writer changed to fit the file's format. */
typedef struct ibl_write_report {
    uint64_t clamped_texels; /* texels with a value past the format's largest, stored as it
                                (ibl_format_max_value; e.g. a sun above 65504 in rgba16f) */
} ibl_write_report;

typedef struct ibl_write_desc {
    ibl_format format;        /* 0: the container's default (see docs/FORMATS.md)      */
    float exposure_ev;        /* 8-bit outputs: scale by 2^exposure_ev before tonemap  */
    ibl_tonemap tonemap;
    ibl_exr_compression exr_compression;
    int hdr_no_rle;           /* Radiance: write flat scanlines                        */
    ibl_write_report *report; /* optional: receives what was changed (added to)        */
    ibl_quality quality;      /* BC6H: encoder effort (ibl/compress.h)                  */
    float rgbm_range;         /* RGBM: the range (0: IBL_RGBM_DEFAULT_RANGE)            */
    int zstd_level;           /* KTX2: Zstandard supercompression level 1..22 (0: none) */
    ibl_dds_header dds_header; /* DDS: legacy FourCC or DX10 header (0: AUTO, see above)  */
    int ktx1_cmgen_types;     /* KTX1 rg11b10f: glType = glFormat = R11F_G11F_B10F (0x8C3A),
                                 as Filament's cmgen writes and Filament's KTX1 reader needs
                                 (it knows no other glType for these texels); 0: the KTX
                                 1.1 spec's glType UNSIGNED_INT_10F_11F_11F_REV (0x8C3B)
                                 with glFormat RGB, which every other reader expects     */
} ibl_write_desc;

/* Writes one flat image; the container follows the extension (.hdr .exr .pfm .png .jpg, or
 * .ktx2/.ktx/.dds as a one-level 2D texture). desc may be NULL. */
ibl_status ibl_write_image(ibl_context *ctx, const char *path, const ibl_image *image,
                           const ibl_write_desc *desc);
/* Writes a texture to .ktx2, .ktx or .dds (all levels, faces, slices, metadata). */
ibl_status ibl_write_texture(ibl_context *ctx, const char *path, const ibl_texture *texture,
                             const ibl_write_desc *desc);
/* Encodes a texture into a new buffer (freed with ibl_free). type: KTX2, KTX1 or DDS. */
ibl_status ibl_encode_texture(ibl_context *ctx, ibl_file_type type, const ibl_texture *texture,
                              const ibl_write_desc *desc, void **bytes, size_t *size);

/* Encodes an image into a new buffer (freed with ibl_free), as ibl_write_image would. */
ibl_status ibl_encode_image(ibl_context *ctx, ibl_file_type type, const ibl_image *image,
                            const ibl_write_desc *desc, void **bytes, size_t *size);

/* Writes bytes to path atomically (a set of one file, below). */
ibl_status ibl_write_file_atomic(ibl_context *ctx, const char *path, const void *bytes,
                                 size_t size);

/* A set of output files that appear together or not at all (src/io/output.c): each file is
 * written and flushed under a temporary name beside its path, and only the commit renames
 * them into place (after a last cancellation check), so a failure, a full disk or a Ctrl-C
 * leaves every target untouched. Destroying an uncommitted set removes its temporaries. New
 * files get mode 0666 minus the umask; a replaced file keeps its mode. */
typedef struct ibl_output_set ibl_output_set;
ibl_status ibl_output_set_create(ibl_context *ctx, ibl_output_set **out);
/* An input no output of the set may replace (refused with IBL_ERR_INVALID_ARGUMENT). */
ibl_status ibl_output_set_protect(ibl_output_set *set, const char *input_path);
ibl_status ibl_output_set_add(ibl_output_set *set, const char *path, const void *bytes,
                              size_t size);
ibl_status ibl_output_set_add_image(ibl_output_set *set, const char *path,
                                    const ibl_image *image, const ibl_write_desc *desc);
ibl_status ibl_output_set_add_texture(ibl_output_set *set, const char *path,
                                      const ibl_texture *texture, const ibl_write_desc *desc);
ibl_status ibl_output_set_commit(ibl_output_set *set);
void ibl_output_set_destroy(ibl_output_set *set);
/* Reads a whole file into a new buffer (freed with ibl_free); refuses files over max_bytes. */
ibl_status ibl_read_file(ibl_context *ctx, const char *path, void **bytes, size_t *size);

/* Tone mapping used by 8-bit writers: linear value -> display value in [0, 1] (before sRGB). */
float ibl_tonemap_apply(ibl_tonemap tonemap, float linear);
/* The exposure (EV) that maps the image's mean Rec.709 luminance to middle grey (0.18): the
 * default of 8-bit previews. 0 for a black image. */
float ibl_image_auto_exposure(const ibl_image *image);

/* KTX2 cube-map arrays (layerCount N, faceCount 6) from and to separate cubes
 * (src/io/ktx2_array.c; ibl_read_texture / ibl_write_texture take them whole as
 * IBL_TEXTURE_CUBE_ARRAY textures, in DDS too): count cubes of one size and level count,
 * layer i = layers[i]; metadata (may be NULL) goes into the file's key/value data. Encodes
 * into a new buffer (ibl_free). */
ibl_status ibl_encode_cube_array(ibl_context *ctx, const ibl_cubemap *layers, int count,
                                 const ibl_key_value *metadata, int metadata_count,
                                 const ibl_write_desc *desc, void **bytes, size_t *size);
/* Decodes one: *layers_out receives count new cubes (free each, then the array with ibl_free);
 * meta (may be NULL) receives a texture without texels holding the file's metadata
 * (ibl_texture_free). */
ibl_status ibl_decode_cube_array(ibl_context *ctx, const void *bytes, size_t size, const char *name,
                                 ibl_cubemap **layers_out, int *count_out, ibl_texture *meta);

#ifdef __cplusplus
}
#endif
#endif
