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
    /* cmgen --deploy: 256..16 (IBL_DEFAULT_MIN_LOD_SIZE 16), R11F_G11F_B10F, its frame is ibl's
     * turned by 180 degrees about +Y (measured against cmgen-equivalent output in Filament's
     * own renderer, tests/viewer/filament_test.mjs) */
    [IBL_TARGET_FILAMENT] = {
        .target = IBL_TARGET_FILAMENT, .name = "filament", .engine = "Filament 1.53.4",
        .orientation = {.yaw_degrees = 180.0f},
        .filter = IBL_FILTER_GGX, .mapping = IBL_MAPPING_FILAMENT, .size = 256,
        .last_level_size = 16, .format = IBL_FORMAT_RG11B10F, .containers = IBL_BAKE_KTX2,
        .sh_form = IBL_TARGET_SH_FILAMENT, .files = IBL_TARGET_FILE_README | IBL_TARGET_FILE_FILAMENT},
    /* Unity, Unreal and Godot filter their own probes from an equirect: the chain is ibl's
     * default for their level mappings; what they take is engine_environment.exr */
    /* the picture turned so that the engine's import shows the input's (x, y, z) at Unity's
     * (x, y, -z) (the left-handed flip of z), at Unreal's (-z, x, y) (ibl's front on Unreal's
     * forward +X, +Z up; tests/test_engine_targets.c) and at Godot's (x, y, z) */
    [IBL_TARGET_UNITY] = {
        .target = IBL_TARGET_UNITY, .name = "unity", .engine = "Unity (2022.3 documentation)",
        .orientation = {.yaw_degrees = 90.0f},
        .filter = IBL_FILTER_GGX, .mapping = IBL_MAPPING_UNITY, .size = 256,
        .format = IBL_FORMAT_RGBA16F, .containers = IBL_BAKE_KTX2 | IBL_BAKE_DDS,
        .sh_form = IBL_TARGET_SH_UNITY, .files = IBL_TARGET_FILE_README | IBL_TARGET_FILE_EQUIRECT_EXR},
    [IBL_TARGET_UNREAL] = {
        .target = IBL_TARGET_UNREAL, .name = "unreal", .engine = "Unreal Engine 5 (documentation)",
        .orientation = {.yaw_degrees = -90.0f},
        .filter = IBL_FILTER_GGX, .mapping = IBL_MAPPING_UNREAL, .size = 256,
        .format = IBL_FORMAT_RGBA16F, .containers = IBL_BAKE_KTX2 | IBL_BAKE_DDS,
        .sh_form = IBL_TARGET_SH_RADIANCE,
        .files = IBL_TARGET_FILE_README | IBL_TARGET_FILE_EQUIRECT_EXR | IBL_TARGET_FILE_EQUIRECT_HDR},
    [IBL_TARGET_GODOT] = {
        .target = IBL_TARGET_GODOT, .name = "godot", .engine = "Godot 3.2.3 (rendered) and 4 (sky shader source)",
        .orientation = {.yaw_degrees = 180.0f},
        .filter = IBL_FILTER_GGX, .mapping = IBL_MAPPING_LINEAR, .size = 256,
        .format = IBL_FORMAT_RGBA16F, .containers = IBL_BAKE_KTX2 | IBL_BAKE_DDS,
        .sh_form = IBL_TARGET_SH_RADIANCE, .files = IBL_TARGET_FILE_README | IBL_TARGET_FILE_EQUIRECT_EXR},
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

/* The positive constants k_i of the real SH basis, Y_i = +-k_i P_i with P_i = 1, y, z, x, xy,
 * yz, 3z^2 - 1, xz, x^2 - y^2 (Sloan, "Stupid Spherical Harmonics (SH) Tricks", 2008). */
static const double sh_basis_constant[9] = {0.282094791773878143, 0.488602511902919921,
                                            0.488602511902919921, 0.488602511902919921,
                                            1.092548430592079070, 1.092548430592079070,
                                            0.315391565252520006, 1.092548430592079070,
                                            0.546274215296039535};

/* Filament's cmgen (tools/cmgen: CubemapSH::computeSH with irradiance, then
 * preprocessSHForShader) stores sh[i] = c_i E_i / pi, with E_i the irradiance coefficient in
 * its Condon-Shortley-signed basis Y_i = c_i P_i; its shader then evaluates sum sh[i] P_i(n).
 * c_i E_i = c_i^2 A_l int L P_i = k_i A_l L_i for ibl's unsigned coefficients L_i = k_i int L P_i,
 * so the sign convention drops out: sh[i] = k_i (A_l / pi) L_i, in the cube's own frame. */
static void filament_form(const ibl_sh *r, ibl_target_sh *out)
{
    static const char *const poly_names[9] = {"1", "y", "z", "x", "yx", "yz", "3z^2-1", "zx",
                                              "x^2-y^2"};
    out->engine = "Filament IndirectLight::Builder::irradiance(3, sh) (cmgen's sh.txt and the "
                  "KTX1 \"sh\" key)";
    out->basis = "polynomial E(n)/pi = sum sh[i] P_i(n), P = 1, y, z, x, yx, yz, 3z^2-1, zx, "
                 "x^2-y^2 (cmgen's pre-scaled SH, renderPreScaledSH3Bands)";
    out->normalisation = "sh[i] = c_i (E/pi)_i: the irradiance coefficient over pi times its "
                         "basis constant, so sh[0] is the mean of E/pi";
    out->signs = "none left: the product c_i E_i is the same with or without the "
                 "Condon-Shortley phase";
    out->frame = "the cube's own frame: the faces of engine_filament_ibl.ktx as stored";
    for (int i = 0; i < 9; i++) {
        for (int c = 0; c < 3; c++)
            out->values[i][c] = sh_basis_constant[i] * cosine_lobe(i) / IBL_PI * r->c[i][c];
        out->names[i] = poly_names[i];
    }
    out->count = 9;
}

/* Unity's SphericalHarmonicsL2 as RenderSettings.ambientProbe holds it and the render
 * pipelines read it (SphericalHarmonicMath.PremultiplyCoefficients multiplies by k0, -k1, k1,
 * -k1, k2, -k2, k3, -k2, k4 and the shader adds the polynomial terms): coefficients of E/pi
 * in the Condon-Shortley-signed real basis, index l(l+1)+m, in Unity's world frame. Unity is
 * left-handed, +Y up; its panoramic import (Skybox/Panoramic, ToRadialCoords: u = 0.5 -
 * atan2(z, x) / 2pi) puts an equirect's centre on +X and its right quarter on -Z, where ibl
 * puts them on -Z and +X: a direction (x, y, z) of the cube is (-z, y, -x) in Unity. */
static void unity_form(const ibl_sh *r, ibl_target_sh *out)
{
    static const char *const basis_names[9] = {"sh[c,0] Y00", "sh[c,1] Y1-1 (y)", "sh[c,2] Y10 (z)",
                                               "sh[c,3] Y11 (x)", "sh[c,4] Y2-2 (xy)",
                                               "sh[c,5] Y2-1 (yz)", "sh[c,6] Y20 (3z^2-1)",
                                               "sh[c,7] Y21 (xz)", "sh[c,8] Y22 (x^2-y^2)"};
    out->engine = "Unity SphericalHarmonicsL2 (RenderSettings.ambientProbe, LightProbes): "
                  "values[i] = {sh[0,i], sh[1,i], sh[2,i]}";
    out->basis = "real orthonormal SH, index l(l+1)+m: 1, y, z, x, xy, yz, 3z^2-1, xz, x^2-y^2";
    out->normalisation = "irradiance / pi: (A_l / pi) L_lm (A = pi, 2pi/3, pi/4), so that "
                         "sum sh_i Y_i(n) is the diffuse light of albedo 1";
    out->signs = "Condon-Shortley: Y1-1 = -0.488603 y, Y11 = -0.488603 x, Y2-1 = -1.092548 yz, "
                 "Y21 = -1.092548 xz";
    out->frame = "Unity's world frame (left-handed, +Y up) with engine_environment.exr imported "
                 "as a latitude-longitude cubemap: the cube's (x, y, z) is Unity's (-z, y, -x) "
                 "(with --target unity's turn, the input's (x, y, z) is Unity's (x, y, -z))";
    /* ibl's unsigned L_i in the cube frame, re-projected into Unity's frame: the substitution
     * x_u = -z, y_u = y, z_u = -x maps the basis polynomials onto each other:
     *   y_u = y, z_u = -x, x_u = -z, x_u y_u = -zy, y_u z_u = -xy, 3 z_u^2 - 1 = 3x^2 - 1,
     *   x_u z_u = xz, x_u^2 - y_u^2 = z^2 - y^2.
     * The quadratic terms mix: 3x^2 - 1 and z^2 - y^2 are combinations of the cube frame's
     * (3z^2 - 1) and (x^2 - y^2) (with x^2 + y^2 + z^2 = 1), computed below in P-space. */
    for (int c = 0; c < 3; c++) {
        double p[9]; /* coefficients of the polynomials P_i in the cube frame: f = sum p_i P_i */
        for (int i = 0; i < 9; i++) p[i] = sh_basis_constant[i] * cosine_lobe(i) / IBL_PI * r->c[i][c];
        /* f(n) = p0 + p1 y + p2 z + p3 x + p4 xy + p5 yz + p6 (3z^2-1) + p7 xz + p8 (x^2-y^2);
         * write it with x = -z_u, y = y_u, z = -x_u, then read Unity's P coefficients q_i */
        double q[9];
        q[1] = p[1];          /* y       -> y_u             */
        q[3] = -p[2];         /* z       -> -x_u            */
        q[2] = -p[3];         /* x       -> -z_u            */
        q[5] = -p[4];         /* xy      -> -z_u y_u        */
        q[4] = -p[5];         /* yz      -> -y_u x_u        */
        q[7] = p[7];          /* xz      -> z_u x_u         */
        /* p6 (3 x_u^2 - 1) + p8 (z_u^2 - y_u^2) in the basis 1, (3z_u^2-1), (x_u^2-y_u^2): on
         * the sphere x^2 = 1/3 - (3z^2-1)/6 + (x^2-y^2)/2, y^2 = 1/3 - (3z^2-1)/6 - (x^2-y^2)/2,
         * z^2 = 1/3 + (3z^2-1)/3, so 3 x_u^2 - 1 = -(3z_u^2-1)/2 + 3 (x_u^2-y_u^2)/2 and
         * z_u^2 - y_u^2 = (3z_u^2-1)/2 + (x_u^2-y_u^2)/2 (no constant term in either) */
        double a = p[6], b = p[8];
        q[0] = p[0];
        q[6] = -a / 2.0 + b / 2.0;
        q[8] = 3.0 * a / 2.0 + b / 2.0;
        for (int i = 0; i < 9; i++) {
            /* back from P-space to Unity's signed orthonormal coefficients: f = sum q_i P_i
             * = sum u_i Y_i with Y_i = s_i k_i P_i, so u_i = q_i / (s_i k_i) */
            out->values[i][c] = q[i] / (condon_shortley_sign(i) * sh_basis_constant[i]);
        }
    }
    for (int i = 0; i < 9; i++) out->names[i] = basis_names[i];
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
    case IBL_TARGET_SH_FILAMENT: filament_form(radiance, out); break;
    case IBL_TARGET_SH_UNITY: unity_form(radiance, out); break;
    case IBL_TARGET_SH_RADIANCE:
    default:
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "sh form: %d is not an engine form", (int)form);
    }
    return IBL_OK;
}
