/* Internal contract of the bake module (bake.c computes, bake_manifest.c writes and reads
 * the manifest, bake_folder.c owns the folder): the one table of the folder's files. */
#ifndef IBL_BAKE_INTERNAL_H
#define IBL_BAKE_INTERNAL_H

#include "ibl/bake.h"

/* Every file a bake folder can hold. Nothing else names them. */
typedef enum ibl__bake_file {
    IBL__BAKE_SPECULAR_KTX2 = 0,
    IBL__BAKE_SPECULAR_DDS,
    IBL__BAKE_IRRADIANCE_KTX2,
    IBL__BAKE_IRRADIANCE_DDS,
    IBL__BAKE_SH_JSON,
    IBL__BAKE_SPLITSUM,
    IBL__BAKE_BRDF_EXTRA,
    IBL__BAKE_AMBIENT_BRDF,
    IBL__BAKE_PREVIEW,
    IBL__BAKE_ATLAS_KTX2,
    IBL__BAKE_ATLAS_PNG,
    IBL__BAKE_MANIFEST,
    IBL__BAKE_FILE_COUNT
} ibl__bake_file;

typedef struct ibl__bake_file_info {
    const char *name;   /* in the folder                                       */
    const char *kind;   /* the manifest's "kind" of the file                   */
    const char *layout; /* what its texels are, for people reading the manifest */
} ibl__bake_file_info;

const ibl__bake_file_info *ibl__bake_file_info_of(ibl__bake_file file);
/* The file of that name, or IBL__BAKE_FILE_COUNT. */
ibl__bake_file ibl__bake_file_named(const char *name);
/* Is the file part of this bake (which containers, which optional parts)? */
int ibl__bake_has_file(const ibl_bake_data *bake, ibl__bake_file file);

/* What a manifest says besides the numbers it fills into an ibl_bake_data: the file each part is
 * read from (NULL: the part is absent). */
typedef struct ibl__bake_manifest_files {
    const char *specular[2];   /* the containers listed, KTX2 first when both     */
    const char *irradiance[2];
    const char *splitsum;
    const char *ambient_brdf;
    const char *atlas;         /* the atlas KTX2 (the PNG is its 8-bit twin)            */
} ibl__bake_manifest_files;

/* Parses manifest bytes into *bake (every number; no textures) and *files (pointers into
 * *root, which the caller releases with json_decref through ibl__bake_manifest_release). */
ibl_status ibl__bake_manifest_parse(ibl_context *ctx, const void *bytes, size_t size,
                                    const char *name, ibl_bake_data *bake,
                                    ibl__bake_manifest_files *files, void **root);
void ibl__bake_manifest_release(void *root);

/* Extra files of a bake folder (the probe array, src/bake/bake_probes.c): stage writes them
 * into the staging folder before the manifest; manifest rewrites the manifest's text (it may
 * replace *text, freeing the old one with ibl_free). */
typedef struct ibl__bake_extra {
    ibl_status (*stage)(ibl_context *ctx, const char *staging, void *user);
    ibl_status (*manifest)(ibl_context *ctx, char **text, void *user);
    void *user;
} ibl__bake_extra;

/* ibl_bake_write with extra files (extra may be NULL), the same transaction. */
ibl_status ibl__bake_write_extra(ibl_context *ctx, const ibl_bake_data *bake, const char *dir,
                                 const ibl__bake_extra *extra);
/* Writes and flushes a new file in a folder (O_EXCL); errors name the file. */
ibl_status ibl__bake_write_staged(ibl_context *ctx, const char *dir, const char *name,
                                  const void *bytes, size_t size);
/* May the bake module delete this entry of a bake folder (its files and their temporaries)? */
int ibl__bake_is_entry(const char *name);
/* bake_probes.c: is name one of the probe array's files (probes.ktx2, probes.bin,
 * probes.json, probe-HASH.ktx2)? */
int ibl__bake_probe_entry(const char *name);
/* target_files.c: is name one of the files a target adds (README.txt, engine_*)? */
int ibl__bake_target_entry(const char *name);
/* target_files.c: writes the target's files (README.txt, the engine's own) of bake into the
 * staging folder; nothing when the bake has no target. */
ibl_status ibl__bake_stage_target(ibl_context *ctx, const char *staging, const ibl_bake_data *bake);

#endif
