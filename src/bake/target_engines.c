/* The files of the native-engine targets (ibl/target.h): Filament's deploy set, as Filament's
 * cmgen writes it with `--deploy DIR --format=ktx` (tools/cmgen/src/cmgen.cpp: DIR_ibl.ktx, the
 * GGX chain in KTX1 with the pre-scaled SH in its "sh" key; DIR_skybox.ktx; sh.txt), and the
 * equirect EXR that Unity, Unreal and Godot import and filter themselves. Staged with the rest
 * of the bake, in its one transaction. */
#include "bake_internal.h"
#include "target_internal.h"
#include "core/context_internal.h"

#include <stdio.h>
#include <string.h>

/* The KTX1 files are written in the bake's format when KTX1 holds it (cmgen's own choice is
 * rg11b10f), else rgba16f. */
static ibl_format filament_format(ibl_format bake_format)
{
    return ibl_file_type_writes_format(IBL_FILE_KTX1, bake_format) ? bake_format : IBL_FORMAT_RGBA16F;
}

static ibl_status stage_ktx1(ibl_context *ctx, const char *dir, const char *name, ibl_texture *tex,
                             ibl_format format)
{
    /* glType R11F_G11F_B10F for rg11b10f: the only form Filament's KTX1 reader maps */
    ibl_write_desc wd = {.format = format, .ktx1_cmgen_types = 1};
    void *bytes = NULL;
    size_t size = 0;
    ibl_status st = ibl_encode_texture(ctx, IBL_FILE_KTX1, tex, &wd, &bytes, &size);
    if (st == IBL_OK) st = ibl__bake_write_staged(ctx, dir, name, bytes, size);
    else st = ibl__fail(ctx, st, "%s/%s: %s", dir, name, ibl_context_message(ctx));
    ibl_free(ctx, bytes);
    return st;
}

/* cmgen's "sh" key: one line "r g b" per coefficient, L00 first. */
static void sh_key_text(const ibl_target_sh *sh, char *text, size_t cap)
{
    size_t at = 0;
    text[0] = 0;
    for (int i = 0; i < sh->count && at < cap; i++)
        at += (size_t)snprintf(text + at, cap - at, "%.9g %.9g %.9g\n", sh->values[i][0],
                               sh->values[i][1], sh->values[i][2]);
}

/* cmgen's sh.txt: "(r, g, b); // Llm, irradiance, pre-scaled base", 15 decimals. */
static void sh_txt_text(const ibl_target_sh *sh, char *text, size_t cap)
{
    static const char *const lm[9] = {"00", "1-1", "10", "11", "2-2", "2-1", "20", "21", "22"};
    size_t at = 0;
    text[0] = 0;
    for (int i = 0; i < sh->count && at < cap; i++)
        at += (size_t)snprintf(text + at, cap - at,
                               "(%18.15f, %18.15f, %18.15f); // L%s, irradiance, pre-scaled base\n",
                               sh->values[i][0], sh->values[i][1], sh->values[i][2], lm[i]);
}

ibl_status ibl__stage_filament(ibl_context *ctx, const char *dir, const ibl_bake_data *b)
{
    ibl_target_sh sh;
    ibl_status st = ibl_target_sh_form_of(ctx, IBL_TARGET_SH_FILAMENT, &b->sh, &sh);
    if (st != IBL_OK) return ibl__fail(ctx, st, "%s/sh.txt: %s", dir, ibl_context_message(ctx));
    if (!b->environment.data)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                         "%s/engine_filament_skybox.ktx: the bake kept no environment", dir);
    ibl_format format = filament_format(b->format);
    char text[2048];
    sh_key_text(&sh, text, sizeof text);
    ibl_texture chain = ibl_texture_from_cubemap(&b->specular);
    st = ibl_texture_set_metadata(ctx, &chain, "sh", text);
    if (st == IBL_OK) st = stage_ktx1(ctx, dir, "engine_filament_ibl.ktx", &chain, format);
    ibl_texture_free(ctx, &chain); /* the metadata; the texels stay with the bake */
    ibl_texture sky = ibl_texture_from_cubemap(&b->environment);
    if (st == IBL_OK) st = stage_ktx1(ctx, dir, "engine_filament_skybox.ktx", &sky, format);
    if (st == IBL_OK && b->irradiance.data) {
        ibl_texture irr = ibl_texture_from_cubemap(&b->irradiance);
        st = stage_ktx1(ctx, dir, "engine_filament_irradiance.ktx", &irr, format);
    }
    if (st == IBL_OK) {
        sh_txt_text(&sh, text, sizeof text);
        st = ibl__bake_write_staged(ctx, dir, "sh.txt", text, strlen(text));
    }
    return st;
}

ibl_status ibl__stage_equirect(ibl_context *ctx, const char *dir, const ibl_bake_data *b,
                               ibl_file_type kind)
{
    const char *name = kind == IBL_FILE_HDR ? "engine_environment.hdr" : "engine_environment.exr";
    if (!b->environment.data)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "%s/%s: the bake kept no environment", dir, name);
    /* 4 pixels per cube texel around the horizon: the cube's detail, no more */
    ibl_from_cube_desc fd = {.layout = IBL_LAYOUT_EQUIRECT, .width = 4 * b->environment.size};
    ibl_image image;
    ibl_status st = ibl_cubemap_to_image(ctx, &b->environment, &fd, &image);
    if (st != IBL_OK) return ibl__fail(ctx, st, "%s/%s: %s", dir, name, ibl_context_message(ctx));
    /* EXR in 32-bit float: a sun in cd/m^2 is far past half's 65504 (RGBE's shared exponent
     * reaches 2^127 with an 8-bit mantissa) */
    ibl_write_desc wd = {.format = kind == IBL_FILE_HDR ? IBL_FORMAT_DEFAULT : IBL_FORMAT_RGB32F};
    void *bytes = NULL;
    size_t size = 0;
    st = ibl_encode_image(ctx, kind, &image, &wd, &bytes, &size);
    if (st == IBL_OK) st = ibl__bake_write_staged(ctx, dir, name, bytes, size);
    else st = ibl__fail(ctx, st, "%s/%s: %s", dir, name, ibl_context_message(ctx));
    ibl_free(ctx, bytes);
    ibl_image_free(ctx, &image);
    return st;
}

/* ---- README.txt of the native-engine targets ------------------------------------------------ */

static const char filament_readme[] =
    "Filament: a bake in cmgen's deploy form (ibl bake --target filament)\n"
    "\n"
    "engine_filament_ibl.ktx is the GGX chain of %d levels (%d..%d texels, %s) with Filament's\n"
    "level mapping (lod = (levels - 1) r (2 - r)), as `cmgen --deploy DIR --format=ktx` writes\n"
    "it: KTX1, cube, R11F_G11F_B10F stored with cmgen's glType 0x8C3A (Filament's KTX1 reader\n"
    "knows no other), and the irradiance SH in the KTX \"sh\" key. The environment is turned\n"
    "by 180 degrees about +Y to match cmgen's frame. engine_filament_skybox.ktx is the\n"
    "unfiltered environment, engine_filament_irradiance.ktx the irradiance cube (E/pi) and\n"
    "sh.txt the SH as cmgen prints it: sh[i] = c_i (E/pi)_i, the form\n"
    "IndirectLight::Builder::irradiance takes.\n"
    "\n"
    "C++ (libs/ktxreader):\n"
    "  auto* iblKtx = new image::Ktx1Bundle(iblBytes, iblSize);\n"
    "  filament::math::float3 sh[9];\n"
    "  iblKtx->getSphericalHarmonics(sh);\n"
    "  Texture* ibl = ktxreader::Ktx1Reader::createTexture(engine, iblKtx, false);\n"
    "  Texture* sky = ktxreader::Ktx1Reader::createTexture(engine, skyKtx, false);\n"
    "  IndirectLight* light = IndirectLight::Builder()\n"
    "      .reflections(ibl)\n"
    "      .irradiance(3, sh)\n"
    "      .intensity(30000.0f)          // your exposure: the bake is in %s\n"
    "      .build(*engine);\n"
    "  scene->setIndirectLight(light);\n"
    "  scene->setSkybox(Skybox::Builder().environment(sky).build(*engine));\n"
    "\n"
    "JavaScript (the filament npm package; the files preloaded by Filament.init):\n"
    "  const bytes = Filament.assets['engine_filament_ibl.ktx'];\n"
    "  const sh = new Filament.Ktx1Bundle(Filament.Buffer(bytes)).getMetadata('sh')\n"
    "      .split(/\\s/, 27).map(parseFloat);\n"
    "  const light = Filament.IndirectLight.Builder()\n"
    "      .reflections(engine.createTextureFromKtx1(bytes))\n"
    "      .irradianceSh(3, sh).intensity(30000).build(engine);\n"
    "  scene.setIndirectLight(light);\n"
    "  scene.setSkybox(engine.createSkyFromKtx1('engine_filament_skybox.ktx'));\n"
    "\n"
    "sh.json's engines.filament holds the same nine values with their labels.\n";

static const char unity_readme[] =
    "Unity: an environment for Unity to filter (ibl bake --target unity)\n"
    "\n"
    "Unity filters reflection probes and the ambient probe itself: what it needs is the\n"
    "unfiltered environment, engine_environment.exr (equirect, 32-bit float RGB, %s).\n"
    "\n"
    "Import settings: Texture Shape Cube, Mapping Latitude-Longitude Layout (Cylindrical),\n"
    "sRGB off, Convolution Type None (HDRP/URP convolve at run time), Compression None or\n"
    "BC6H, Max Size at least %d. Then Lighting > Environment > Skybox Material: a\n"
    "Skybox/Cubemap material with it (or the HDRP Sky and Fog Volume's HDRI Sky). Unity's\n"
    "frame is left-handed, +Y up; its latitude-longitude import puts a picture's centre on +X,\n"
    "so the environment was turned by 90 degrees about +Y first: a direction (x, y, z) of the\n"
    "input is (x, y, -z) in Unity (its front, ibl's -Z, is Unity's forward +Z).\n"
    "\n"
    "sh.json's engines.unity is the SphericalHarmonicsL2 of the same light (E/pi,\n"
    "Condon-Shortley signs, Unity's frame), for RenderSettings.ambientProbe or a light probe:\n"
    "  var sh = new SphericalHarmonicsL2();\n"
    "  for (int i = 0; i < 9; i++) for (int c = 0; c < 3; c++) sh[c, i] = values[i][c];\n"
    "  RenderSettings.ambientMode = AmbientMode.Custom; RenderSettings.ambientProbe = sh;\n";

static const char unreal_readme[] =
    "Unreal Engine: an environment for Unreal to filter (ibl bake --target unreal)\n"
    "\n"
    "Unreal builds its reflection captures and sky light from the unfiltered environment:\n"
    "engine_environment.hdr (equirect, Radiance RGBE, %s; engine_environment.exr is the same\n"
    "picture in 32-bit float for tools that take EXR).\n"
    "\n"
    "Import settings: drag the .hdr into the Content Browser: Unreal makes a 2:1 Radiance file\n"
    "a TextureCube (long-lat source) by itself; an EXR panorama comes in as a 2D texture.\n"
    "Compression Settings HDR (RGBA16F) or HDRCompressed (BC6H), sRGB off,\n"
    "Maximum Texture Size at least %d. Use it as a Sky Light with Source Type SLS Specified\n"
    "Cubemap (or the HDRI Backdrop actor). Units: with physical units (cd/m^2) bake with\n"
    "--units nits and leave the Sky Light's intensity at 1. Unreal's frame is left-handed, +Z\n"
    "up, and its long-lat import puts a picture's centre on -Y and its right quarter on +X, so\n"
    "the environment was turned by -90 degrees about +Y first: a direction (x, y, z) of the\n"
    "input shows at Unreal's (-z, x, y), the input's front (-Z) on Unreal's forward (+X).\n";

/* Godot 3's settings and levels as measured by rendering this file in Godot 3.2.3
 * (tests/godot/test_godot.c): the sky, the reflections and the diffuse light all come from the
 * panorama; Background Energy scales all three and Ambient Light Energy the diffuse light. */
static const char godot_readme[] =
    "Godot: an environment for Godot to filter (ibl bake --target godot)\n"
    "\n"
    "Godot filters its radiance and irradiance maps itself from the sky: engine_environment.exr\n"
    "(equirect, 32-bit float RGB, %s).\n"
    "\n"
    "Godot 3 (rendered in Godot 3.2.3, GLES3): import the EXR as a Texture with Filter on,\n"
    "Mipmaps off, HDR as sRGB off, Compress Mode Lossless; WorldEnvironment > Environment:\n"
    "Background Mode Sky, Sky a new PanoramaSky whose Panorama is the EXR, Radiance Size 256\n"
    "or more, Ambient Light Sky Contribution 1. Or at run time, without the import:\n"
    "  var image = Image.new()\n"
    "  image.load(ProjectSettings.globalize_path(\"res://engine_environment.exr\"))\n"
    "  var panorama = ImageTexture.new()\n"
    "  panorama.create_from_image(image, Texture.FLAG_FILTER)\n"
    "  var sky = PanoramaSky.new()\n"
    "  sky.radiance_size = Sky.RADIANCE_SIZE_256\n"
    "  sky.panorama = panorama\n"
    "  var environment = Environment.new()\n"
    "  environment.background_mode = Environment.BG_SKY\n"
    "  environment.background_sky = sky\n"
    "  environment.ambient_light_sky_contribution = 1.0\n"
    "  $WorldEnvironment.environment = environment\n"
    "Godot 4: Background Mode Sky, Sky > Sky Material a PanoramaSkyMaterial whose Panorama is\n"
    "the EXR.\n"
    "\n"
    "Levels: Godot 3 has no light units. A value V of the EXR reaches the tone mapper as\n"
    "V x Background Energy (the sky and the reflections; Godot 4: Background Energy\n"
    "Multiplier) and V x Background Energy x Ambient Light Energy (the diffuse light of a\n"
    "white surface), then Tonemap Exposure multiplies it. Keep both energies at 1 to keep the\n"
    "bake's levels, and set the exposure with Tonemap Exposure (or the camera's).\n"
    "\n"
    "Frame: Godot is right-handed, +Y up, -Z forward, like ibl, but its panorama puts a\n"
    "picture's centre on +Z, so the environment was turned by 180 degrees about +Y first: a\n"
    "direction (x, y, z) of the input is (x, y, z) in Godot.\n";

int ibl__engine_readme(const ibl_bake_data *b, const char *units, char *text, size_t cap)
{
    const ibl_specular_info *info = &b->specular_info;
    int width = b->environment.data ? 4 * b->environment.size : 0;
    switch (b->target) {
    case IBL_TARGET_FILAMENT:
        snprintf(text, cap, filament_readme, info->levels, info->size,
                 ibl_level_size(info->size, info->levels - 1),
                 ibl_format_name(filament_format(b->format)), units);
        return 1;
    case IBL_TARGET_UNITY: snprintf(text, cap, unity_readme, units, width); return 1;
    case IBL_TARGET_UNREAL: snprintf(text, cap, unreal_readme, units, width); return 1;
    case IBL_TARGET_GODOT: snprintf(text, cap, godot_readme, units); return 1;
    default: return 0;
    }
}
