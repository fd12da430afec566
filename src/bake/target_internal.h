/* Internal contract of the target files (target_files.c, target_gltf.c). */
#ifndef IBL_TARGET_INTERNAL_H
#define IBL_TARGET_INTERNAL_H

#include "ibl/bake.h"

#include <stdint.h>

/* Babylon.js's RGBD (helperFunctions toRGBD / fromRGBD), which EXT_lights_image_based's PNGs
 * use: a = floor(max(255 / max(rgb), 1)) (at most 255), rgb8 = round(255 (rgb a / 255)^(1/2.2));
 * decoded as rgb = (rgb8 / 255)^2.2 / (a / 255). Not the library's linear RGBD of compress.h. */
void ibl__rgbd_babylon_encode(const float rgb[3], uint8_t out[4]);
void ibl__rgbd_babylon_decode(const uint8_t in[4], float rgb[3]);
/* One face of one level as an RGBD PNG (bytes freed with ibl_free), its rows in memory order
 * or, with flip_rows, bottom row first; errors name `name`. */
ibl_status ibl__rgbd_face_png(ibl_context *ctx, const ibl_cubemap *cube, int level, int face,
                              int flip_rows, const char *name, void **bytes, size_t *size);
/* Refuses, before any work, a target whose files this chain cannot make (reserved rows, a
 * .env without the whole chain, glTF images of a size that is not a power of two). */
ibl_status ibl__target_check(ibl_context *ctx, ibl_target target, const ibl_specular_desc *chain,
                             int source_size);
/* engine_gltf.gltf (EXT_lights_image_based), its PNG faces, and
 * engine_khr_lights_environment.gltf, into the staging folder. */
ibl_status ibl__stage_gltf_lights(ibl_context *ctx, const char *dir, const ibl_bake_data *bake);

/* target_engines.c: Filament's deploy set (engine_filament_*.ktx, sh.txt) and the equirect
 * picture of the engines that filter it themselves (engine_environment.exr, or .hdr when
 * kind is IBL_FILE_HDR), into the staging folder; both need the bake's environment (kept for
 * these targets). */
ibl_status ibl__stage_filament(ibl_context *ctx, const char *dir, const ibl_bake_data *bake);
ibl_status ibl__stage_equirect(ibl_context *ctx, const char *dir, const ibl_bake_data *bake,
                               ibl_file_type kind);
/* README.txt of the Filament, Unity, Unreal and Godot targets into text; units names the
 * bake's radiance units. Returns 0 for the other targets. */
int ibl__engine_readme(const ibl_bake_data *bake, const char *units, char *text, size_t cap);
/* target_sheen.c: engine_gltf_charlie.ktx2 (bake->sheen) and engine_gltf_sheen_lut.ktx2 (the
 * KHR_materials_sheen albedo table at the bake's table size). */
ibl_status ibl__stage_gltf_sheen(ibl_context *ctx, const char *dir, const ibl_bake_data *bake);

#endif
