/* The engine targets (ibl/target.h): ONE table, one row per engine, and the SH forms the
 * engines take. A row says everything that makes a bake loadable as is: the frame of the
 * cube (orientation applied when the input is read), the level mapping, the chain's last
 * level, the container and pixel format, the SH form and the extra files. Rows whose
 * `not_ready` is set are reserved: every use refuses with that message.
 *
 * Where each row's values come from (read in the engines' sources, then measured by
 * rendering the engine's own import next to the bake: tests/viewer/engines_test.mjs,
 * docs/ENGINES.md):
 *  - three.js r187: a cube marked isPMREMTexture is sampled at ENVMAP_MAX_LOD r (2 - r)
 *    (Filament's mapping), its last level times pi is the irradiance, PMREMGenerator's own
 *    chains end at 8x8 (LOD_MIN 3); a cube that is not a render target is sampled with x
 *    negated, and three's equirect import is a quarter turn from ibl's: mirror, yaw 90.
 *  - Babylon.js 9.35: HDRFiltering's alphaG = 2^(lod / lodGenerationScale) / width (0.8), a
 *    left-handed world (mirror, yaw 180), SphericalPolynomial, DDS and .env.
 *  - glTF: EXT_lights_image_based (Hsu, Bond; Khronos glTF vendor extension): mips spaced
 *    linearly in roughness down to 16x16, RGBD PNG faces, irradiance SH. */
#include "ibl/target.h"
#include "ibl/bake.h"
#include "core/context_internal.h"
#include "core/numeric.h"

#include <string.h>

#define NOT_YET(engine) "the " engine " target is not yet available in this build (its row is reserved)"

static const ibl_target_profile profiles[IBL_TARGET_COUNT] = {
    [IBL_TARGET_THREE] = {
        .target = IBL_TARGET_THREE, .name = "three", .engine = "three.js r187",
        .orientation = {.yaw_degrees = 90.0f, .mirror = 1},
        .filter = IBL_FILTER_GGX, .mapping = IBL_MAPPING_FILAMENT, .size = 256,
        .last_level_size = 8, .format = IBL_FORMAT_RGBA16F, .containers = IBL_BAKE_KTX2,
        .sh_form = IBL_TARGET_SH_THREE, .files = IBL_TARGET_FILE_README},
    [IBL_TARGET_BABYLON] = {
        .target = IBL_TARGET_BABYLON, .name = "babylon", .engine = "Babylon.js 9.35",
        .orientation = {.yaw_degrees = 180.0f, .mirror = 1},
        .filter = IBL_FILTER_GGX, .mapping = IBL_MAPPING_BABYLON, .babylon_lod_scale = 0.8f,
        .size = 256, .last_level_size = 0, .format = IBL_FORMAT_RGBA16F,
        .containers = IBL_BAKE_DDS | IBL_BAKE_KTX2, .sh_form = IBL_TARGET_SH_BABYLON,
        .files = IBL_TARGET_FILE_README | IBL_TARGET_FILE_BABYLON_ENV},
    [IBL_TARGET_FILAMENT] = {.target = IBL_TARGET_FILAMENT, .name = "filament", .engine = "Filament",
                             .not_ready = NOT_YET("filament")},
    [IBL_TARGET_UNITY] = {.target = IBL_TARGET_UNITY, .name = "unity", .engine = "Unity",
                          .not_ready = NOT_YET("unity")},
    [IBL_TARGET_UNREAL] = {.target = IBL_TARGET_UNREAL, .name = "unreal", .engine = "Unreal Engine",
                           .not_ready = NOT_YET("unreal")},
    [IBL_TARGET_GODOT] = {.target = IBL_TARGET_GODOT, .name = "godot", .engine = "Godot",
                          .not_ready = NOT_YET("godot")},
    [IBL_TARGET_GLTF] = {
        .target = IBL_TARGET_GLTF, .name = "gltf", .engine = "glTF 2.0 EXT_lights_image_based",
        .orientation = {0},
        .filter = IBL_FILTER_GGX, .mapping = IBL_MAPPING_LINEAR, .size = 256,
        .last_level_size = 16, .format = IBL_FORMAT_RGBA16F, .containers = IBL_BAKE_KTX2,
        .sh_form = IBL_TARGET_SH_GLTF_IRRADIANCE,
        .files = IBL_TARGET_FILE_README | IBL_TARGET_FILE_GLTF},
};

static const char *const names[] = {"three", "babylon", "filament", "unity", "unreal", "godot",
                                    "gltf", NULL};

const ibl_target_profile *ibl_target_profile_of(ibl_target target)
{
    if (target <= IBL_TARGET_NONE || target >= IBL_TARGET_COUNT) return NULL;
    return &profiles[target];
}

int ibl_target_from_name(const char *name, ibl_target *out)
{
    for (int t = 1; name && t < IBL_TARGET_COUNT; t++)
        if (strcmp(profiles[t].name, name) == 0) {
            if (out) *out = (ibl_target)t;
            return 1;
        }
    return 0;
}

const char *ibl_target_name(ibl_target target)
{
    const ibl_target_profile *p = ibl_target_profile_of(target);
    return p ? p->name : "none";
}

const char *const *ibl_target_names(void) { return names; }

int ibl_target_levels(int size, int last_level_size)
{
    if (last_level_size <= 0 || size <= last_level_size) return 0;
    int levels = 1;
    while (ibl_level_size(size, levels - 1) > last_level_size && levels < IBL_MAX_LEVELS) levels++;
    return levels;
}

ibl_status ibl__target_check(ibl_context *ctx, ibl_target target, const ibl_specular_desc *chain,
                             int source_size)
{
    const ibl_target_profile *p = ibl_target_profile_of(target);
    if (!p) return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "bake: unknown target %d", (int)target);
    if (p->not_ready) return ibl__fail(ctx, IBL_ERR_UNSUPPORTED, "bake: %s", p->not_ready);
    if (!(p->files & (IBL_TARGET_FILE_BABYLON_ENV | IBL_TARGET_FILE_GLTF))) return IBL_OK;
    ibl_specular_info info;
    ibl_status st = ibl_specular_levels(ctx, chain, source_size, &info);
    if (st != IBL_OK) return st;
    if (info.size & (info.size - 1))
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                         "bake: the %s target's images want power-of-two faces, the chain has %d "
                         "texels", p->name, info.size);
    int full = 1;
    while ((1 << (full - 1)) < info.size) full++;
    if ((p->files & IBL_TARGET_FILE_BABYLON_ENV) && info.levels != full)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                         "bake: Babylon's .env (engine_babylon.env) needs the whole chain, %d "
                         "levels for %d texels, not %d", full, info.size, info.levels);
    return IBL_OK;
}

void ibl_bake_desc_for_target(const ibl_target_profile *p, ibl_bake_desc *d)
{
    memset(d, 0, sizeof *d);
    if (!p) return;
    d->target = p->target;
    d->specular.filter = p->filter;
    d->specular.mapping = p->mapping;
    d->specular.babylon_lod_scale = p->babylon_lod_scale;
    d->specular.size = p->size;
    d->specular.levels = ibl_target_levels(p->size, p->last_level_size);
    d->format = p->format;
    d->containers = p->containers;
    d->source.orientation = p->orientation;
}

/* ---- SH forms ----------------------------------------------------------------------------- */

/* Babylon.js (Maths/sphericalPolynomial) and EXT_lights_image_based take the basis with the
 * Condon-Shortley phase: its Y(1,-1), Y(1,1), Y(2,-1), Y(2,1) are the negatives of ibl's. */
static double condon_shortley_sign(int index)
{
    return (index == 1 || index == 3 || index == 5 || index == 7) ? -1.0 : 1.0;
}

/* A_l, the clamped-cosine convolution (Ramamoorthi & Hanrahan 2001, eq. 8): pi, 2pi/3, pi/4 */
static double cosine_lobe(int index)
{
    return index == 0 ? IBL_PI : index < 4 ? 2.0 * IBL_PI / 3.0 : IBL_PI / 4.0;
}

static void three_form(const ibl_sh *r, ibl_target_sh *out)
{
    static const char *const basis_names[9] = {"Y00", "Y1-1 (y)", "Y10 (z)", "Y11 (x)", "Y2-2 (xy)",
                                               "Y2-1 (yz)", "Y20", "Y21 (xz)", "Y22"};
    out->engine = "three.js LightProbe.sh (SphericalHarmonics3.coefficients)";
    out->basis = "real orthonormal SH, three's order y z x, xy yz (3z^2-1) xz (x^2-y^2)";
    out->normalisation = "radiance L_lm (three's shader applies the cosine lobe: irradiance = "
                         "0.886227 c0 + 1.023328 (c1 y + c2 z + c3 x) + ...)";
    out->signs = "no Condon-Shortley phase (Y11 = +0.488603 x)";
    out->frame = "three's world frame: the bake's cube frame mirrored in x (three samples a "
                 "cube that is not a render target with x negated), so c3, c4, c7 change sign";
    for (int i = 0; i < 9; i++) {
        /* the x-odd functions (x, xy, xz) change sign under x -> -x */
        double s = (i == 3 || i == 4 || i == 7) ? -1.0 : 1.0;
        for (int c = 0; c < 3; c++) out->values[i][c] = s * r->c[i][c];
        out->names[i] = basis_names[i];
    }
    out->count = 9;
}

static void gltf_form(const ibl_sh *r, ibl_target_sh *out)
{
    static const char *const basis_names[9] = {"l00", "l1-1", "l10", "l11", "l2-2",
                                               "l2-1", "l20", "l21", "l22"};
    out->engine = "glTF EXT_lights_image_based irradianceCoefficients (Babylon.js's loader: "
                  "SphericalHarmonics.FromArray)";
    out->basis = "real orthonormal SH with the Condon-Shortley phase, order l00 l1-1 l10 l11 "
                 "l2-2 l2-1 l20 l21 l22";
    out->normalisation = "irradiance E_lm = A_l L_lm (A = pi, 2pi/3, pi/4)";
    out->signs = "Condon-Shortley: Y1-1 = -0.488603 y, Y11 = -0.488603 x, Y2-1 = -1.092548 yz, "
                 "Y21 = -1.092548 xz, so l1-1, l11, l2-1, l21 are negated against ibl's";
    out->frame = "the cube's own frame (the glTF cube faces as stored)";
    for (int i = 0; i < 9; i++) {
        for (int c = 0; c < 3; c++)
            out->values[i][c] = condon_shortley_sign(i) * cosine_lobe(i) * r->c[i][c];
        out->names[i] = basis_names[i];
    }
    out->count = 9;
}

/* Babylon's SphericalPolynomial.updateFromHarmonics with its own constants (0.886277 is
 * Babylon's spelling of sqrt(pi)/2 = 0.886227; kept so that the numbers equal the engine's)
 * applied to the harmonics ConvertCubeMapToSphericalPolynomial builds: Condon-Shortley-signed
 * radiance SH, times A_l / pi (irradiance / pi). updateFromHarmonics scales band l by A_l / pi
 * once more; FromPolynomial undoes it. */
static void babylon_form(const ibl_sh *r, ibl_target_sh *out)
{
    static const char *const poly_names[9] = {"x", "y", "z", "xx", "yy", "zz", "yz", "zx", "xy"};
    out->engine = "Babylon.js SphericalPolynomial (.env \"irradiance\", "
                  "CubeTexture.sphericalPolynomial)";
    out->basis = "SphericalPolynomial.FromHarmonics of the harmonics h_lm = E_lm / pi: x y z "
                 "xx yy zz yz zx xy; Babylon turns it back into h (FromPolynomial) for its "
                 "shader, which sums h_lm Y_lm(n) = E(n) / pi";
    out->normalisation = "h = irradiance / pi (Lambertian radiance for albedo 1); the "
                         "polynomial's terms carry one more A_l / pi, as Babylon writes them";
    out->signs = "made from Condon-Shortley-signed harmonics, as Babylon makes them";
    out->frame = "the cube texture's own frame (Babylon projects the cube as stored)";
    for (int c = 0; c < 3; c++) {
        double h[9];
        for (int i = 0; i < 9; i++)
            h[i] = condon_shortley_sign(i) * r->c[i][c] * cosine_lobe(i) / IBL_PI;
        double v[9];
        v[0] = -1.02333 * h[3];
        v[1] = -1.02333 * h[1];
        v[2] = 1.02333 * h[2];
        v[3] = 0.886277 * h[0] - 0.247708 * h[6] + 0.429043 * h[8];
        v[4] = 0.886277 * h[0] - 0.247708 * h[6] - 0.429043 * h[8];
        v[5] = 0.886277 * h[0] + 0.495417 * h[6];
        v[6] = -0.858086 * h[5];
        v[7] = -0.858086 * h[7];
        v[8] = 0.858086 * h[4];
        for (int i = 0; i < 9; i++) out->values[i][c] = v[i] / IBL_PI;
    }
    for (int i = 0; i < 9; i++) out->names[i] = poly_names[i];
    out->count = 9;
}

ibl_status ibl_target_sh_form_of(ibl_context *ctx, ibl_target_sh_form form, const ibl_sh *radiance,
                                 ibl_target_sh *out)
{
    if (!out || !radiance) return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "sh form: no coefficients");
    memset(out, 0, sizeof *out);
    out->form = form;
    if (radiance->bands < 3 && form != IBL_TARGET_SH_RADIANCE)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                         "sh form: the engines take 3 bands, the bake has %d", radiance->bands);
    switch (form) {
    case IBL_TARGET_SH_THREE: three_form(radiance, out); break;
    case IBL_TARGET_SH_GLTF_IRRADIANCE: gltf_form(radiance, out); break;
    case IBL_TARGET_SH_BABYLON: babylon_form(radiance, out); break;
    case IBL_TARGET_SH_RADIANCE:
    default:
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "sh form: %d is not an engine form", (int)form);
    }
    return IBL_OK;
}
