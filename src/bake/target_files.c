/* The files a target adds to a bake folder (ibl/target.h): README.txt with the engine's
 * loading code, and the engine's own containers: Babylon.js's .env (this file) and the glTF
 * lights (target_gltf.c). All are staged with the rest of the bake, in one transaction. */
#include "bake_internal.h"
#include "target_internal.h"
#include "core/context_internal.h"
#include "io/io_internal.h"
#include "io/json.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

int ibl__bake_target_entry(const char *name)
{
    return strcmp(name, "README.txt") == 0 || strcmp(name, "sh.txt") == 0 ||
           strncmp(name, "engine_", 7) == 0;
}

/* ---- README.txt ---------------------------------------------------------------------------- */

static const char three_readme[] =
    "three.js: a bake for three's physical materials (ibl bake --target three)\n"
    "\n"
    "specular.ktx2 is a cube of %d levels (%d..%d texels, rgba16f) in the form three's own\n"
    "PMREM path samples: Filament's level mapping, lod = (levels - 1) r (2 - r), the last level\n"
    "8x8, and the faces mirrored in x as three samples a cube that is not a render target. Load\n"
    "it with ktx-parse (npm) as a cube marked isPMREMTexture, so three uses it as it is:\n"
    "\n"
    "  import * as THREE from 'three';\n"
    "  import { read } from 'ktx-parse';\n"
    "  async function loadIblCube(url) {\n"
    "    const ktx = read(new Uint8Array(await (await fetch(url)).arrayBuffer()));\n"
    "    const faces = [];\n"
    "    for (let f = 0; f < 6; f++) {\n"
    "      const mipmaps = ktx.levels.map((level, l) => {\n"
    "        const s = Math.max(1, ktx.pixelWidth >> l), n = s * s * 4;\n"
    "        const o = level.levelData.byteOffset + f * n * 2;\n"
    "        return { data: new Uint16Array(level.levelData.buffer.slice(o, o + n * 2)),\n"
    "                 width: s, height: s };\n"
    "      });\n"
    "      faces.push({ width: ktx.pixelWidth, height: ktx.pixelHeight, mipmaps });\n"
    "    }\n"
    "    const cube = new THREE.CompressedCubeTexture(faces, THREE.RGBAFormat, THREE.HalfFloatType);\n"
    "    cube.isPMREMTexture = true;      // three takes the chain as prefiltered\n"
    "    cube.minFilter = THREE.LinearMipmapLinearFilter;\n"
    "    cube.magFilter = THREE.LinearFilter;\n"
    "    cube.generateMipmaps = false;\n"
    "    cube.colorSpace = THREE.LinearSRGBColorSpace;\n"
    "    cube.needsUpdate = true;\n"
    "    return cube;\n"
    "  }\n"
    "  scene.environment = await loadIblCube('specular.ktx2');\n"
    "\n"
    "For a LightProbe instead of the cube's diffuse term, take sh.json's engines.three.values\n"
    "(radiance SH in three's world frame):\n"
    "  const probe = new THREE.LightProbe();\n"
    "  probe.sh.fromArray(sh.engines.three.values.flat());\n";

static const char babylon_readme[] =
    "Babylon.js: a bake for PBRMaterial (ibl bake --target babylon)\n"
    "\n"
    "specular.dds (and .ktx2) hold a cube of %d levels (%d..%d texels, rgba16f) filtered with\n"
    "Babylon's own mapping, alphaG = 2^(lod / %g) / %d (HDRFiltering's lodGenerationScale),\n"
    "level 0 unfiltered, the faces in Babylon's left-handed frame. engine_babylon.env is the\n"
    "same chain as Babylon's .env: RGBD PNG faces per level and the SphericalPolynomial.\n"
    "\n"
    "  // the DDS (float, exact)\n"
    "  const env = BABYLON.CubeTexture.CreateFromPrefilteredData('specular.dds', scene);\n"
    "  env.gammaSpace = false;\n"
    "  env.lodGenerationScale = %g;\n"
    "  scene.environmentTexture = env;\n"
    "\n"
    "  // or the .env (8-bit RGBD, smaller)\n"
    "  scene.environmentTexture = new BABYLON.CubeTexture('engine_babylon.env', scene);\n"
    "\n"
    "The irradiance polynomial of the DDS is computed by Babylon from the cube; sh.json's\n"
    "engines.babylon holds the same polynomial (x y z xx yy zz yz zx xy) computed by ibl.\n";

static const char gltf_readme[] =
    "glTF 2.0: image-based light extensions (ibl bake --target gltf)\n"
    "\n"
    "engine_gltf.gltf declares EXT_lights_image_based: %d mips of the GGX chain (%d..%d texels,\n"
    "%s) as RGBD PNG faces engine_gltf_MIP_FACE.png (faces +X -X +Y\n"
    "-Y +Z -Z), the irradiance SH (irradianceCoefficients) and specularImageSize. Merge its\n"
    "\"extensions\", \"images\" and \"extensionsUsed\" into your asset, and reference the light\n"
    "from a scene:\n"
    "\n"
    "  \"scenes\": [{ \"nodes\": [...], \"extensions\": { \"EXT_lights_image_based\": { \"light\": 0 } } }]\n"
    "\n"
    "RGBD (Babylon.js's packing): rgb = pow(png.rgb, 2.2) / png.a.\n"
    "Babylon.js's glTF loader reads mip l as GGX alpha = 2^(l / s) / size, s = (mips - 1) /\n"
    "log2(size), not roughness = mip / (mips - 1): for Babylon bake with --mapping babylon\n"
    "--babylon-lod-scale s (0.5 for 5 mips at 256), and clear the loaded light's gammaSpace\n"
    "(scene.environmentTexture.gammaSpace = false; the loader leaves it true).\n"
    "engine_khr_lights_environment.gltf is the same light in the KHR_lights_environment draft's\n"
    "form (a KTX2 cube texture, specular.ktx2, and the SH), referenced as\n"
    "  \"scenes\": [{ \"extensions\": { \"KHR_lights_environment\": { \"environment\": 0 } } }]\n"
    "The draft is not ratified: its field names may still change.\n"
    "\n"
    "For KHR_materials_sheen: engine_gltf_charlie.ktx2 is the prefiltered Charlie chain (at most\n"
    "64 texels, the GGX chain's number of levels, sheenRoughness = lod / (levels - 1)), and\n"
    "engine_gltf_sheen_lut.ktx2 the sheen albedo E(n.v, sheenRoughness) with the extension's\n"
    "Charlie visibility (R = E, G = its average) for the albedo-scaling of the base layer.\n";

static char *readme_text(ibl_context *ctx, const ibl_bake_data *b)
{
    const ibl_specular_info *info = &b->specular_info;
    int first = info->size, last = ibl_level_size(info->size, info->levels - 1);
    char *text = ibl_alloc(ctx, 8192);
    if (!text) return NULL;
    switch (b->target) {
    case IBL_TARGET_THREE:
        snprintf(text, 8192, three_readme, info->levels, first, last);
        break;
    case IBL_TARGET_BABYLON:
        snprintf(text, 8192, babylon_readme, info->levels, first, last,
                 (double)info->babylon_lod_scale, info->size, (double)info->babylon_lod_scale);
        break;
    case IBL_TARGET_GLTF: {
        char mapping[96];
        if (info->mapping == IBL_MAPPING_BABYLON)
            snprintf(mapping, sizeof mapping, "alpha = 2^(mip / %g) / %d: Babylon's mapping",
                     (double)info->babylon_lod_scale, first);
        else if (info->mapping == IBL_MAPPING_LINEAR)
            snprintf(mapping, sizeof mapping, "roughness = mip / (mips - 1)");
        else
            snprintf(mapping, sizeof mapping, "the %s mapping", ibl_specular_mapping_name(info->mapping));
        snprintf(text, 8192, gltf_readme, info->levels, first, last, mapping);
        break;
    }
    default:
        if (!ibl__engine_readme(b, b->units ? b->units : "the input's units", text, 8192))
            snprintf(text, 8192, "%s\n", ibl_target_name(b->target));
        break;
    }
    return text;
}

/* ---- RGBD, Babylon.js's packing ------------------------------------------------------------ */

void ibl__rgbd_babylon_encode(const float rgb[3], uint8_t out[4])
{
    /* Babylon.js helperFunctions toRGBD: D = saturate(floor(max(255 / max(rgb), 1)) / 255),
     * rgb' = saturate(gamma(rgb * D)) with gamma = pow(x, 1 / 2.2); the 8-bit store rounds */
    float m = rgb[0] > rgb[1] ? rgb[0] : rgb[1];
    if (rgb[2] > m) m = rgb[2];
    if (!(m > 1e-7f)) m = 1e-7f;
    double d = floor(fmax(255.0 / m, 1.0));
    if (d > 255.0) d = 255.0;
    double scale = d / 255.0;
    for (int c = 0; c < 3; c++) {
        double v = rgb[c] > 0 ? rgb[c] * scale : 0.0;
        v = pow(v > 1.0 ? 1.0 : v, 1.0 / 2.2);
        out[c] = (uint8_t)(v * 255.0 + 0.5);
    }
    out[3] = (uint8_t)d;
}

void ibl__rgbd_babylon_decode(const uint8_t in[4], float rgb[3])
{
    double d = in[3] / 255.0;
    for (int c = 0; c < 3; c++) rgb[c] = d > 0 ? (float)(pow(in[c] / 255.0, 2.2) / d) : 0.0f;
}

ibl_status ibl__rgbd_face_png(ibl_context *ctx, const ibl_cubemap *cube, int level, int face,
                              int flip_rows, const char *name, void **bytes, size_t *size)
{
    int s = ibl_level_size(cube->size, level);
    uint8_t *rgba = ibl_alloc(ctx, (size_t)s * (size_t)s * 4);
    if (!rgba) return ibl__fail_named(ctx, ibl_context_status(ctx), name);
    const float *src = ibl_cubemap_face(cube, level, face);
    for (int y = 0; y < s; y++) {
        const float *row = src + (size_t)(flip_rows ? s - 1 - y : y) * (size_t)s * 4;
        for (int x = 0; x < s; x++)
            ibl__rgbd_babylon_encode(row + (size_t)x * 4, rgba + ((size_t)y * (size_t)s + (size_t)x) * 4);
    }
    ibl_status st = ibl__png_encode_rgba8(ctx, rgba, s, s, name, bytes, size);
    ibl_free(ctx, rgba);
    return st;
}

/* ---- Babylon.js .env ----------------------------------------------------------------------
 * Babylon's environmentTextureTools (version 2): 8 magic bytes, a NUL-terminated JSON
 * manifest, then the images, each at manifest.specular.mipmaps[level * 6 + face].position
 * bytes after the NUL. The chain must run down to 1x1 (log2(width) + 1 levels). */

static const uint8_t env_magic[8] = {0x86, 0x16, 0x87, 0x96, 0xf6, 0xd6, 0x96, 0x36};

static json_t *env_manifest(const ibl_bake_data *b, const size_t *lengths, int images,
                            const ibl_target_sh *poly)
{
    json_t *o = json_object();
    ibl__json_set(o, "version", ibl__json_number(2));
    ibl__json_set(o, "width", ibl__json_number(b->specular.size));
    ibl__json_set(o, "imageType", ibl__json_string("image/png"));
    json_t *irr = json_object();
    for (int i = 0; i < poly->count; i++) {
        json_t *rgb = json_array();
        for (int c = 0; c < 3; c++) ibl__json_append(rgb, ibl__json_number(poly->values[i][c]));
        ibl__json_set(irr, poly->names[i], rgb);
    }
    ibl__json_set(o, "irradiance", irr);
    json_t *spec = json_object();
    json_t *mips = json_array();
    size_t position = 0;
    for (int i = 0; i < images; i++) {
        json_t *m = json_object();
        ibl__json_set(m, "length", ibl__json_number((double)lengths[i]));
        ibl__json_set(m, "position", ibl__json_number((double)position));
        ibl__json_append(mips, m);
        position += lengths[i];
    }
    ibl__json_set(spec, "mipmaps", mips);
    ibl__json_set(spec, "lodGenerationScale", ibl__json_float(b->specular_info.babylon_lod_scale));
    ibl__json_set(o, "specular", spec);
    return o;
}

static ibl_status stage_babylon_env(ibl_context *ctx, const char *dir, const ibl_bake_data *b)
{
    static const char name[] = "engine_babylon.env";
    const ibl_cubemap *c = &b->specular;
    int full = 1;
    while ((1 << (full - 1)) < c->size) full++;
    if (c->levels != full || (c->size & (c->size - 1)))
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                         "%s: Babylon's .env needs the whole chain of a power-of-two cube "
                         "(%d levels for %d texels), the bake has %d levels", name, full,
                         c->size, c->levels);
    ibl_target_sh poly;
    ibl_status st = ibl_target_sh_form_of(ctx, IBL_TARGET_SH_BABYLON, &b->sh, &poly);
    if (st != IBL_OK) return ibl__fail(ctx, st, "%s: %s", name, ibl_context_message(ctx));
    int images = c->levels * 6;
    void *png[6 * IBL_MAX_LEVELS] = {0};
    size_t lengths[6 * IBL_MAX_LEVELS] = {0};
    for (int i = 0; st == IBL_OK && i < images; i++)
        st = ibl__rgbd_face_png(ctx, c, i / 6, i % 6, 1, name, &png[i], &lengths[i]);
    char *manifest = NULL;
    if (st == IBL_OK) st = ibl__json_text(ctx, env_manifest(b, lengths, images, &poly), name, &manifest);
    uint8_t *file = NULL;
    size_t total = 0;
    if (st == IBL_OK) {
        size_t mlen = strlen(manifest) + 1;
        total = sizeof env_magic + mlen;
        for (int i = 0; i < images; i++) total += lengths[i];
        file = ibl_alloc(ctx, total);
        if (!file) st = ibl__fail_named(ctx, ibl_context_status(ctx), name);
        else {
            uint8_t *p = file;
            memcpy(p, env_magic, sizeof env_magic), p += sizeof env_magic;
            memcpy(p, manifest, mlen), p += mlen;
            for (int i = 0; i < images; i++) memcpy(p, png[i], lengths[i]), p += lengths[i];
        }
    }
    if (st == IBL_OK) st = ibl__bake_write_staged(ctx, dir, name, file, total);
    ibl_free(ctx, file);
    ibl_free(ctx, manifest);
    for (int i = 0; i < images; i++) ibl_free(ctx, png[i]);
    return st;
}

ibl_status ibl__bake_stage_target(ibl_context *ctx, const char *dir, const ibl_bake_data *b)
{
    const ibl_target_profile *p = ibl_target_profile_of(b->target);
    if (!p) return IBL_OK;
    ibl_status st = IBL_OK;
    if (p->files & IBL_TARGET_FILE_README) {
        char *text = readme_text(ctx, b);
        if (!text) return ibl__fail(ctx, ibl_context_status(ctx), "%s/README.txt: out of memory", dir);
        st = ibl__bake_write_staged(ctx, dir, "README.txt", text, strlen(text));
        ibl_free(ctx, text);
    }
    if (st == IBL_OK && (p->files & IBL_TARGET_FILE_BABYLON_ENV)) st = stage_babylon_env(ctx, dir, b);
    if (st == IBL_OK && (p->files & IBL_TARGET_FILE_GLTF)) st = ibl__stage_gltf_lights(ctx, dir, b);
    if (st == IBL_OK && (p->files & IBL_TARGET_FILE_FILAMENT)) st = ibl__stage_filament(ctx, dir, b);
    if (st == IBL_OK && (p->files & IBL_TARGET_FILE_EQUIRECT_EXR))
        st = ibl__stage_equirect(ctx, dir, b, IBL_FILE_EXR);
    if (st == IBL_OK && (p->files & IBL_TARGET_FILE_EQUIRECT_HDR))
        st = ibl__stage_equirect(ctx, dir, b, IBL_FILE_HDR);
    return st;
}
