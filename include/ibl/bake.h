/*
 * ibl/bake.h - the bake: everything a renderer needs from one environment, in memory
 * (ibl_bake_data) and as a folder (manifest.json + textures). This module alone names the
 * folder's files and writes and reads its manifest; the CLI, the renderer and engines go
 * through it. docs/FORMATS.md ("Bake folder") has the manifest schema.
 *
 *   ibl_bake_desc d = {.specular = {.filter = IBL_FILTER_GGX, .size = 256}};
 *   ibl_bake_data bake;
 *   ibl_bake_compute(ctx, &environment, &d, &bake);   // every stage, in memory
 *   ibl_bake_write(ctx, &bake, "out/bake");             // the folder, all or nothing
 *   ibl_probe probe;
 *   ibl_bake_probe(ctx, &bake, &probe);                 // the runtime's view of it
 *   ...
 *   ibl_bake_free(ctx, &bake);
 *
 * and on the runtime side: ibl_bake_load(ctx, "out/bake", NULL, &bake) then ibl_bake_probe.
 *
 * Units. A level of a GGX chain is tied to a perceptual roughness r (alpha = r^2). A level of
 * a Phong-family chain (phong, blinn, box, gauss) is tied to the Blinn-Phong shininess of the
 * material that reads it (the exponent of the tri-Ace 2010 normalised Blinn-Phong BRDF, what
 * ibl_material.shininess holds); the Phong kernel the level was filtered with has exponent
 * shininess / blinn_factor (the tri-Ace fit cos^n(t) ~ cos^(4.2 n)(t/2)). The manifest
 * records both per level, whatever units the chain was specified in (a phong chain's
 * range is kernel exponents; specular.h).
 */
#ifndef IBL_BAKE_H
#define IBL_BAKE_H

#include "brdf.h"
#include "core.h"
#include "io.h"
#include "layout.h"
#include "sh.h"
#include "shade.h"
#include "sky.h"
#include "specular.h"
#include "target.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The manifest schema this library writes (and the newest it reads). */
enum { IBL_BAKE_MANIFEST_VERSION = 1 };

/* Containers the cube textures are written in. */
enum { IBL_BAKE_KTX2 = 1u << 0, IBL_BAKE_DDS = 1u << 1 };

/* Where the environment came from: recorded in the manifest so a bake can be reproduced. */
typedef struct ibl_bake_source {
    const char *name;            /* input path or name; NULL: "built-in sky" with sky set,
                                    else "environment"                                     */
    ibl_layout layout;           /* the layout it was read in (0: not recorded)             */
    ibl_orientation orientation; /* yaw, mirror, z-up applied when reading it               */
    const ibl_sky_desc *sky;     /* the built-in sky's parameters, when it is the sky       */
} ibl_bake_source;

typedef struct ibl_bake_desc {
    ibl_specular_desc specular; /* the chain (specular.h; zero: GGX at the source's size,
                                   linear mapping); ibl_specular_preset fills one          */
    const char *preset;         /* recorded only: the preset the chain's desc came from    */
    int irradiance_size;        /* irradiance map face edge; 0: 16                          */
    int sh_bands;               /* 1..5; 0: 3                                               */
    ibl_sh_window sh_window;    /* windowing of the SH (sh.h)                               */
    double sh_window_width;
    int lut_size;               /* split-sum and multiple-scattering tables; 0: 128        */
    int ambient_brdf;           /* the tri-Ace AmbientBRDF volume (Blinn-Phong materials read
                                   it on any chain): 0 or 1 written, -1 not                */
    ibl_ambient_brdf_desc ambient; /* its sizes, normalisation and the materials' shininess
                                   range (brdf.h; zero: 1..100000, any chain); the first and
                                   last rows are centred on the range's ends               */
    ibl_format format;          /* storage of the cube textures; 0: rgba16f                 */
    ibl_quality quality;        /* BC6H / ASTC encoder effort (ibl/compress.h)              */
    int zstd_level;             /* KTX2 files: Zstandard level 1..22; 0: none (DDS never)   */
    unsigned containers;        /* IBL_BAKE_KTX2 | IBL_BAKE_DDS; 0: both                    */
    ibl_dds_header dds_header;  /* the DDS files' header (io.h; 0: legacy where the format
                                   has a FourCC, else DX10)                                */
    int preview_width;          /* environment.png (equirect) width; 0: 1024; -1: none      */
    int keep_environment;       /* keep a copy of env in the bake (the probe's mirror and
                                   background, e.g. for `ibl render`); never written        */
    int atlas;                  /* 1: also the chain as Daqi 2016's 2D mip atlas
                                   (ibl_atlas_pack, 1-texel gutter): specular_atlas.ktx2 in
                                   `format` (2D, key "ibl.atlas" = the table) and
                                   specular_atlas.png (8-bit RGBM, range rgbm_range); the
                                   table in the manifest's "atlas" (docs/ATLAS.md)          */
    float rgbm_range;           /* RGBM's range (the atlas PNG, an rgbm format); 0: 8      */
    ibl_bake_source source;
    const char *units;          /* recorded only: what the radiance values are in, e.g.
                                   "cd/m^2" (NULL: not stated; the built-in sky is kcd/m^2);
                                   the caller scales the environment (`ibl bake --units`)   */
    ibl_target target;          /* the engine the bake is for (target.h): adds README.txt and
                                   the engine's files and records it; the chain, format and
                                   containers are the caller's (ibl_bake_desc_for_target)  */
    const ibl_specular_sources *specular_sources; /* optional: the sources of the flat image
                                   env was converted from (ibl_specular_sources_create with
                                   `specular` above), applied to the chain (specular.h) */
} ibl_bake_desc;

/* A desc with a target row's chain, pixel format, containers, target and (in source) its
 * orientation, everything else zero (default). NULL: all zero. */
void ibl_bake_desc_for_target(const ibl_target_profile *profile, ibl_bake_desc *desc);

/* Wall time of each stage of ibl_bake_compute, milliseconds (also in the manifest). */
typedef struct ibl_bake_timing {
    double specular, diffuse, brdf, preview, total;
} ibl_bake_timing;

/* One bake, owned (ibl_bake_free). Parts a folder did not hold are left empty (data NULL). */
typedef struct ibl_bake_data {
    /* what was baked, every default resolved */
    ibl_specular_info specular_info;
    ibl_edge_fixup edge_fixup;
    int irradiance_size, sh_bands, lut_size, working_size;
    ibl_sh_window sh_window_requested;
    double sh_window_width;
    ibl_format format;
    ibl_quality quality;
    int zstd_level;
    unsigned containers;
    ibl_dds_header dds_header;
    char *source_name;   /* owned */
    char *preset;        /* owned; NULL when none was recorded */
    ibl_layout source_layout;
    ibl_orientation source_orientation;
    int has_sky;
    ibl_sky_desc sky;    /* defaults resolved */
    ibl_target target;   /* the engine the folder is for (IBL_TARGET_NONE: none)          */
    char *units;         /* owned; the stated units of the radiance, NULL when not stated */

    ibl_cubemap specular;    /* the prefiltered chain, level 0 the sharpest               */
    ibl_cubemap irradiance;  /* E/pi per texel (one level)                                 */
    ibl_sh sh;               /* radiance SH, windowed as asked                            */
    ibl_sh_window_report sh_window;
    ibl_image splitsum;      /* [roughness][n.v] RGBA: R = A, G = B (brdf.h)               */
    ibl_table_axis splitsum_n_dot_v, splitsum_roughness;
    ibl_image brdf_extra;    /* R = E, G = E_avg, B = sheen albedo, A = its average         */
    ibl_texture ambient_brdf; /* 3D [F0][shininess][n.v], R = AmbientBRDF (kind 3D)          */
    ibl_table_axis ambient_n_dot_v, ambient_shininess, ambient_f0;
    ibl_blinn_normalization ambient_normalization;
    ibl_cubemap sheen;       /* the glTF target: the prefiltered Charlie (sheen) chain, at
                                most 64 texels, the specular chain's number of levels
                                (target.h ibl_charlie_prefilter); not read back by load     */
    ibl_cubemap environment; /* with keep_environment: the unfiltered working cube, the
                                probe's mirror and background; never written whole       */
    ibl_image preview;       /* linear equirect preview (environment.png), if asked        */
    ibl_image atlas;         /* with desc.atlas: the chain as a 2D atlas (linear float)     */
    ibl_atlas_layout atlas_layout; /* its coordinate table                                  */
    float rgbm_range;        /* the range of the RGBM files (resolved, never 0)             */
    ibl_bake_timing timing_ms;
    uint64_t clamped_texels; /* cube texels past the storage format's largest value (e.g. a
                                sun above 65504 in rgba16f), stored as that value          */
} ibl_bake_data;

/* Runs every stage on level 0 of env: the specular chain, the irradiance map, the SH, the
 * BRDF tables and the preview. desc may be NULL for every default. Bit-identical at any
 * thread count. On failure *out is empty. */
ibl_status ibl_bake_compute(ibl_context *ctx, const ibl_cubemap *env, const ibl_bake_desc *desc,
                            ibl_bake_data *out);

/* Writes the bake into folder dir as one transaction: the files are built in a staging
 * folder beside dir and swapped in, so dir always holds one complete bake (the old one or
 * the new one) even if the process is killed; a second writer of the same folder at the same
 * time is refused (IBL_ERR_IO, "... is being written by another process"); stale staging
 * folders of killed runs are removed. A dir that exists must be a bake folder (it holds a
 * manifest.json written by ibl) or empty: other files are never deleted. */
ibl_status ibl_bake_write(ibl_context *ctx, const ibl_bake_data *bake, const char *dir);

/* ibl_bake_compute then ibl_bake_write, with the folder locked first (a second writer is
 * refused before any work is done). result (may be NULL) receives the bake; the caller frees
 * it. Every failure message names dir. */
ibl_status ibl_bake(ibl_context *ctx, const ibl_cubemap *env, const ibl_bake_desc *desc,
                    const char *dir, ibl_bake_data *result);

/* The names of the files a bake's folder holds (manifest.json last); returns their count
 * (at most max are stored). */
int ibl_bake_files(const ibl_bake_data *bake, const char **names, int max);

/* Reads a bake folder (or the manifest.json path itself): the manifest, then the files it
 * lists. desc (may be NULL) applies to every texture read (e.g. clamp_infinite). Errors name
 * the file and, for the manifest, the field. */
ibl_status ibl_bake_load(ibl_context *ctx, const char *path, const ibl_read_desc *desc,
                         ibl_bake_data *out);

/* A bake put together from separate files (e.g. a chain made by another tool). */
typedef struct ibl_bake_parts {
    const char *specular;      /* required: a cube texture with its chain (.ktx2 .dds .ktx);
                                  a chain ibl wrote describes its own levels (KTX2 metadata) */
    ibl_level_mapping mapping; /* when the chain does not describe itself: what each level
                                  was filtered for; levels 0: roughness k / (levels - 1)    */
    const char *environment;   /* optional: the unfiltered environment (cube texture, or an
                                  image in any layout ibl_image_to_cubemap detects)         */
    const char *irradiance;    /* optional: E/pi as a cube texture or image; without it the
                                  SH is projected from the environment (or the chain)       */
    const char *splitsum;      /* optional: a split-sum table as brdf.h and `ibl lut` write */
    const char *ambient_brdf;  /* optional: an AmbientBRDF volume as `ibl lut` writes it     */
    float ambient_shininess_min, ambient_shininess_max; /* its shininess range; 0: 1, 2000 */
    int ambient_linear;        /* its shininess rows are linearly spaced (default: log)     */
} ibl_bake_parts;

ibl_status ibl_bake_load_parts(ibl_context *ctx, const ibl_bake_parts *parts,
                               const ibl_read_desc *desc, ibl_bake_data *out);

/* The runtime's view of a bake: pointers into it (the bake must outlive the probe), the level
 * mapping, the SH or irradiance map, the tables; validated. */
ibl_status ibl_bake_probe(ibl_context *ctx, const ibl_bake_data *bake, ibl_probe *out);

void ibl_bake_free(ibl_context *ctx, ibl_bake_data *bake);

/* The manifest.json text of a bake (NUL-terminated, freed with ibl_free). */
ibl_status ibl_bake_manifest(ibl_context *ctx, const ibl_bake_data *bake, char **json);

/* The manifest of a lone chain (what `ibl prefilter` writes beside it): "format":
 * "ibl-chain" and the "specular" object of a bake manifest, its "files" naming the given
 * files (for a chain in flat images, one per face and level, in level-major order
 * +X -X +Y -Y +Z -Z). */
ibl_status ibl_chain_manifest(ibl_context *ctx, const ibl_specular_info *info,
                              ibl_edge_fixup edge_fixup, ibl_format format,
                              const char *const *files, int file_count, char **json);
/* The same for a chain written as one 2D mip atlas (`ibl prefilter --out-layout atlas`),
 * with "atlas": the coordinate table (ibl_atlas_layout_to_json's keys) and its "files". */
ibl_status ibl_atlas_chain_manifest(ibl_context *ctx, const ibl_specular_info *info,
                                    ibl_edge_fixup edge_fixup, ibl_format format,
                                    const ibl_atlas_layout *layout, const char *const *files,
                                    int file_count, char **json);

#ifdef __cplusplus
}
#endif
#endif
