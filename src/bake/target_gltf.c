/* glTF 2.0 image-based lights of a bake (the gltf target):
 *  - EXT_lights_image_based (Gary Hsu, Mike Bond; Khronos glTF vendor extension): the chain as
 *    RGBD PNG faces per mip (specularImages[mip][face], faces +X -X +Y -Y +Z -Z),
 *    specularImageSize = the edge of mip 0, irradianceCoefficients = 9 RGB irradiance SH
 *    coefficients (E_lm, Condon-Shortley-signed, as Babylon.js's loader reads them through
 *    SphericalHarmonics.FromArray), a light referenced by the scene;
 *  - the KHR_lights_environment draft (Nopper, Sahlin, Hsu, Bond, Houston): the same light as
 *    a KTX2 cube (image/ktx2, specular.ktx2 of the bake) referenced by specularCubemaps, with
 *    the same SH. The draft is not ratified; the form written is the one whose lights hold
 *    "intensity", "irradianceCoefficients" and "specularCubemaps". */
#include "bake_internal.h"
#include "target_internal.h"
#include "core/context_internal.h"
#include "io/json.h"

#include <stdio.h>
#include <string.h>

static json_t *coefficients_json(const ibl_target_sh *sh)
{
    json_t *a = json_array();
    for (int i = 0; i < sh->count; i++) {
        json_t *rgb = json_array();
        for (int c = 0; c < 3; c++) ibl__json_append(rgb, ibl__json_number(sh->values[i][c]));
        ibl__json_append(a, rgb);
    }
    return a;
}

static json_t *asset_json(void)
{
    json_t *asset = json_object();
    ibl__json_set(asset, "version", ibl__json_string("2.0"));
    ibl__json_set(asset, "generator", ibl__json_string("ibl " IBL_VERSION_STRING " (ibl bake --target gltf)"));
    return asset;
}

/* A scene that references light 0 through the extension `ext` under the key `key`. */
static json_t *scenes_json(const char *ext, const char *key)
{
    json_t *ref = json_object();
    ibl__json_set(ref, key, ibl__json_number(0));
    json_t *exts = json_object();
    ibl__json_set(exts, ext, ref);
    json_t *scene = json_object();
    ibl__json_set(scene, "nodes", json_array());
    ibl__json_set(scene, "extensions", exts);
    json_t *scenes = json_array();
    ibl__json_append(scenes, scene);
    return scenes;
}

static json_t *used_json(const char *ext)
{
    json_t *used = json_array();
    ibl__json_append(used, ibl__json_string(ext));
    return used;
}

static void face_name(char *buf, size_t cap, int level, int face)
{
    snprintf(buf, cap, "engine_gltf_%d_%d.png", level, face);
}

static json_t *ext_lights_json(const ibl_bake_data *b, const ibl_target_sh *sh)
{
    json_t *root = json_object();
    ibl__json_set(root, "asset", asset_json());
    ibl__json_set(root, "extensionsUsed", used_json("EXT_lights_image_based"));
    json_t *images = json_array(), *mips = json_array();
    for (int l = 0; l < b->specular.levels; l++) {
        json_t *faces = json_array();
        for (int f = 0; f < 6; f++) {
            char name[64];
            face_name(name, sizeof name, l, f);
            json_t *img = json_object();
            ibl__json_set(img, "uri", ibl__json_string(name));
            ibl__json_set(img, "mimeType", ibl__json_string("image/png"));
            ibl__json_append(images, img);
            ibl__json_append(faces, ibl__json_number(l * 6 + f));
        }
        ibl__json_append(mips, faces);
    }
    ibl__json_set(root, "images", images);
    json_t *light = json_object();
    ibl__json_set(light, "name", ibl__json_string(b->source_name ? b->source_name : "environment"));
    ibl__json_set(light, "intensity", ibl__json_number(1.0));
    json_t *rotation = json_array();
    for (int i = 0; i < 4; i++) ibl__json_append(rotation, ibl__json_number(i == 3 ? 1.0 : 0.0));
    ibl__json_set(light, "rotation", rotation);
    ibl__json_set(light, "irradianceCoefficients", coefficients_json(sh));
    ibl__json_set(light, "specularImageSize", ibl__json_number(b->specular.size));
    ibl__json_set(light, "specularImages", mips);
    json_t *lights = json_array();
    ibl__json_append(lights, light);
    json_t *ext = json_object();
    ibl__json_set(ext, "lights", lights);
    json_t *exts = json_object();
    ibl__json_set(exts, "EXT_lights_image_based", ext);
    ibl__json_set(root, "extensions", exts);
    ibl__json_set(root, "scenes", scenes_json("EXT_lights_image_based", "light"));
    ibl__json_set(root, "scene", ibl__json_number(0));
    return root;
}

static json_t *khr_environment_json(const ibl_bake_data *b, const ibl_target_sh *sh)
{
    json_t *root = json_object();
    ibl__json_set(root, "asset", asset_json());
    ibl__json_set(root, "extensionsUsed", used_json("KHR_lights_environment"));
    json_t *img = json_object();
    ibl__json_set(img, "name", ibl__json_string("specular radiance cubemap"));
    ibl__json_set(img, "uri", ibl__json_string(ibl__bake_file_info_of(IBL__BAKE_SPECULAR_KTX2)->name));
    ibl__json_set(img, "mimeType", ibl__json_string("image/ktx2"));
    json_t *images = json_array();
    ibl__json_append(images, img);
    ibl__json_set(root, "images", images);
    json_t *tex = json_object();
    ibl__json_set(tex, "source", ibl__json_number(0));
    json_t *textures = json_array();
    ibl__json_append(textures, tex);
    ibl__json_set(root, "textures", textures);
    json_t *light = json_object();
    ibl__json_set(light, "name", ibl__json_string(b->source_name ? b->source_name : "environment"));
    ibl__json_set(light, "intensity", ibl__json_number(1.0));
    ibl__json_set(light, "irradianceCoefficients", coefficients_json(sh));
    json_t *cubes = json_array();
    ibl__json_append(cubes, ibl__json_number(0));
    ibl__json_set(light, "specularCubemaps", cubes);
    json_t *lights = json_array();
    ibl__json_append(lights, light);
    json_t *ext = json_object();
    ibl__json_set(ext, "lights", lights);
    json_t *exts = json_object();
    ibl__json_set(exts, "KHR_lights_environment", ext);
    ibl__json_set(root, "extensions", exts);
    ibl__json_set(root, "scenes", scenes_json("KHR_lights_environment", "environment"));
    ibl__json_set(root, "scene", ibl__json_number(0));
    return root;
}

static ibl_status stage_json(ibl_context *ctx, const char *dir, const char *name, json_t *root)
{
    char *text = NULL;
    ibl_status st = ibl__json_text(ctx, root, name, &text);
    if (st == IBL_OK) st = ibl__bake_write_staged(ctx, dir, name, text, strlen(text));
    ibl_free(ctx, text);
    return st;
}

ibl_status ibl__stage_gltf_lights(ibl_context *ctx, const char *dir, const ibl_bake_data *b)
{
    const ibl_cubemap *c = &b->specular;
    if (c->size & (c->size - 1))
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                         "engine_gltf.gltf: EXT_lights_image_based wants power-of-two faces, "
                         "the chain is %d texels", c->size);
    ibl_target_sh sh;
    ibl_status st = ibl_target_sh_form_of(ctx, IBL_TARGET_SH_GLTF_IRRADIANCE, &b->sh, &sh);
    if (st != IBL_OK)
        return ibl__fail(ctx, st, "engine_gltf.gltf: %s", ibl_context_message(ctx));
    for (int l = 0; st == IBL_OK && l < c->levels; l++)
        for (int f = 0; st == IBL_OK && f < 6; f++) {
            char name[64];
            face_name(name, sizeof name, l, f);
            void *png = NULL;
            size_t size = 0;
            st = ibl__rgbd_face_png(ctx, c, l, f, 1, name, &png, &size);
            if (st == IBL_OK) st = ibl__bake_write_staged(ctx, dir, name, png, size);
            ibl_free(ctx, png);
        }
    if (st == IBL_OK) st = stage_json(ctx, dir, "engine_gltf.gltf", ext_lights_json(b, &sh));
    if (st == IBL_OK && (b->containers & IBL_BAKE_KTX2))
        st = stage_json(ctx, dir, "engine_khr_lights_environment.gltf", khr_environment_json(b, &sh));
    if (st == IBL_OK) st = ibl__stage_gltf_sheen(ctx, dir, b);
    return st;
}
