/*
 * ibl/target.h - engine targets: what a bake must look like for one engine to take it as is.
 *
 * Each engine reads a prefiltered chain its own way: the frame its cube faces are sampled in,
 * the level <-> roughness mapping of its shader, the number of levels it expects, the
 * container it loads, the form its spherical harmonics take. One table (src/bake/target.c,
 * one row per engine) holds all of it; `ibl bake --target NAME` starts from a row and explicit
 * options override it. A bake made for a target also holds README.txt (the engine's loading
 * code) and the engine's own files (target_files below).
 *
 *   const ibl_target_profile *p = ibl_target_profile_of(IBL_TARGET_THREE);
 *   ibl_bake_desc d;
 *   ibl_bake_desc_for_target(p, &d);      // bake.h: the row's chain, format, containers
 *   // read the environment with p->orientation, then ibl_bake(ctx, &env, &d, dir, NULL)
 *
 * The engines' conventions, with the sources they were read from: docs/ENGINES.md.
 */
#ifndef IBL_TARGET_H
#define IBL_TARGET_H

#include "core.h"
#include "layout.h"
#include "sh.h"
#include "specular.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum ibl_target {
    IBL_TARGET_NONE = 0,
    IBL_TARGET_THREE,    /* three.js (r150+): a PMREM-like cube read through a KTX2 loader  */
    IBL_TARGET_BABYLON,  /* Babylon.js: DDS / .env with CreateFromPrefilteredData           */
    IBL_TARGET_FILAMENT, /* Filament (cmgen's output)                                        */
    IBL_TARGET_UNITY,    /* Unity (HDRP / URP reflection probes)                             */
    IBL_TARGET_UNREAL,   /* Unreal Engine (reflection captures)                              */
    IBL_TARGET_GODOT,    /* Godot (radiance maps)                                            */
    IBL_TARGET_GLTF,     /* glTF 2.0: EXT_lights_image_based, the KHR_lights_environment draft */
    IBL_TARGET_COUNT
} ibl_target;

/* The SH form an engine takes (every form also goes into sh.json, labelled). */
typedef enum ibl_target_sh_form {
    IBL_TARGET_SH_RADIANCE = 0,      /* ibl's own: radiance, orthonormal, ibl frame            */
    IBL_TARGET_SH_THREE,             /* three.js LightProbe / SphericalHarmonics3: radiance in
                                        three's world frame                                     */
    IBL_TARGET_SH_BABYLON,           /* Babylon.js SphericalPolynomial (x, y, z, xx, ...)       */
    IBL_TARGET_SH_GLTF_IRRADIANCE,   /* EXT_lights_image_based irradianceCoefficients: E_lm    */
    IBL_TARGET_SH_FILAMENT,          /* Filament IndirectLight irradiance(3, sh): cmgen's
                                        pre-scaled form sh[i] = c_i (E / pi)_i                 */
    IBL_TARGET_SH_UNITY              /* Unity SphericalHarmonicsL2 (RenderSettings.ambientProbe):
                                        E / pi, Condon-Shortley signed, Unity's frame          */
} ibl_target_sh_form;

/* Files a target adds to the bake folder. */
enum {
    IBL_TARGET_FILE_README = 1u << 0,       /* README.txt: the loading code                  */
    IBL_TARGET_FILE_BABYLON_ENV = 1u << 1,  /* engine_babylon.env                             */
    IBL_TARGET_FILE_GLTF = 1u << 2,         /* engine_gltf.gltf (EXT_lights_image_based),
                                               engine_khr_lights_environment.gltf and the RGBD
                                               faces engine_gltf_L_F.png                     */
    IBL_TARGET_FILE_FILAMENT = 1u << 3,     /* what `cmgen --deploy --format=ktx` writes:
                                               engine_filament_ibl.ktx (the chain, KTX1 with
                                               the "sh" key), engine_filament_skybox.ktx,
                                               engine_filament_irradiance.ktx and sh.txt     */
    IBL_TARGET_FILE_EQUIRECT_EXR = 1u << 4, /* engine_environment.exr: the unfiltered
                                               environment as an equirect float EXR, for the
                                               engines that filter it themselves             */
    IBL_TARGET_FILE_EQUIRECT_HDR = 1u << 5  /* engine_environment.hdr: the same picture as
                                               Radiance RGBE, the form Unreal's importer turns
                                               into a TextureCube by itself                  */
};

typedef struct ibl_target_profile {
    ibl_target target;
    const char *name;             /* the --target value: "three", "babylon", ...            */
    const char *engine;           /* the engine and version the row was measured with       */
    const char *not_ready;        /* non-NULL: the row is reserved and refuses with this     */
    ibl_orientation orientation;  /* applied when the environment is read: the engine's
                                     cube frame relative to its own equirect import          */
    ibl_specular_filter filter;
    ibl_specular_mapping mapping;
    float babylon_lod_scale;      /* IBL_MAPPING_BABYLON's lod scale (0: 0.8)                */
    int size;                     /* chain face edge                                         */
    int last_level_size;          /* the chain ends at this edge (0: the mapping's default)  */
    ibl_format format;            /* cube texture pixel format                               */
    unsigned containers;          /* IBL_BAKE_KTX2 | IBL_BAKE_DDS                             */
    ibl_target_sh_form sh_form;
    unsigned files;               /* IBL_TARGET_FILE_* */
} ibl_target_profile;

/* The row of a target (NULL for IBL_TARGET_NONE or out of range). */
const ibl_target_profile *ibl_target_profile_of(ibl_target target);
/* "three", "babylon", ... ; 0 for an unknown name. */
int ibl_target_from_name(const char *name, ibl_target *out);
const char *ibl_target_name(ibl_target target);
/* The names of every row, NULL-terminated. */
const char *const *ibl_target_names(void);

/* The number of levels a chain of face edge `size` has when it ends at last_level_size
 * (log2(size / last) + 1; 0 when last is 0 or not smaller than size). */
int ibl_target_levels(int size, int last_level_size);

/* One SH set in an engine's form, for sh.json and the engines' files. radiance is the bake's
 * (ibl frame: the frame the bake's cube textures are stored in). values holds count RGB
 * triples, named by names[] (for the Babylon polynomial x y z xx yy zz yz zx xy). */
typedef struct ibl_target_sh {
    ibl_target_sh_form form;
    const char *engine;          /* "three.js", ...                                         */
    const char *basis;           /* the basis or polynomial, in words                       */
    const char *normalisation;   /* radiance, irradiance E, E / pi ...                      */
    const char *signs;           /* sign convention                                         */
    const char *frame;           /* the frame the directions are taken in                   */
    const char *names[9];        /* the name of each value (polynomial terms), or NULL      */
    int count;
    double values[9][3];
} ibl_target_sh;

ibl_status ibl_target_sh_form_of(ibl_context *ctx, ibl_target_sh_form form, const ibl_sh *radiance,
                                 ibl_target_sh *out);

/* The prefiltered Charlie (sheen) chain of KHR_materials_sheen (src/bake/target_sheen.c has
 * the definition): level l of `levels` levels of edge size >> l, for sheenRoughness
 * ibl_charlie_level_roughness(l, levels) = l / (levels - 1), at least 1/64. out is allocated. */
ibl_status ibl_charlie_prefilter(ibl_context *ctx, const ibl_cubemap *env, int size, int levels,
                                 ibl_cubemap *out);
float ibl_charlie_level_roughness(int level, int levels);

#ifdef __cplusplus
}
#endif
#endif
