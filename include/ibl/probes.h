/*
 * ibl/probes.h - probe sets: one global probe and local probes placed in a scene, and the
 * capture of each local probe's cube by path tracing the scene.
 *
 * After "Image Based Lighting", Just Another Game Engine blog, 2015: a global probe (the sky,
 * at infinity) and local probes with an influence volume (sphere or box, with a blend margin),
 * a parallax proxy (Lagarde and Zanuttini 2012) and a capture mode: the far plane at the
 * influence volume with alpha marking what was hit, or an infinite far plane that includes
 * the sky. The file format is docs/PROBES.md.
 */
#ifndef IBL_PROBES_H
#define IBL_PROBES_H

#include "core.h"
#include "cubemap.h"
#include "scene.h"
#include "shade.h"
#include "sky.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum ibl_capture_mode {
    IBL_CAPTURE_FAR_PLANE = 0, /* primary rays end at the influence volume; alpha = coverage  */
    IBL_CAPTURE_INFINITE       /* primary rays go on to the global environment; alpha = 1      */
} ibl_capture_mode;

const char *ibl_capture_mode_name(ibl_capture_mode mode); /* "far-plane", "infinite" */
int ibl_capture_mode_from_name(const char *name, ibl_capture_mode *out);

enum { IBL_PROBE_NAME_MAX = 64, IBL_PROBE_PRESET_MAX = 32 };

typedef struct ibl_local_probe {
    char name[IBL_PROBE_NAME_MAX]; /* unique in the set; [A-Za-z0-9_-] (names output files) */
    ibl_vec3 position;             /* where the cube is captured                             */
    ibl_volume influence;          /* blend_distance: the blend margin                       */
    ibl_volume proxy;              /* parallax proxy (blend_distance 0)                      */
    int priority;                  /* higher first in the blend order; default 0             */
    ibl_capture_mode capture;
    int size;                      /* capture cube edge                                      */
    char preset[IBL_PROBE_PRESET_MAX]; /* the specular chain preset (ibl_specular_preset)   */
} ibl_local_probe;

typedef struct ibl_global_probe {
    char *environment;             /* resolved path of an HDRI, or NULL for the built-in sky */
    ibl_sky_desc sky;              /* when environment is NULL                               */
    float yaw_degrees;             /* rotation of the HDRI about +Y                          */
    int size;                      /* cube edge the environment is resampled to              */
    char preset[IBL_PROBE_PRESET_MAX];
} ibl_global_probe;

typedef struct ibl_probe_set {
    ibl_global_probe global;
    ibl_local_probe *probes;
    int probe_count;
    char *path; /* the file it was read from (messages), or NULL */
} ibl_probe_set;

/* Reads a probe-set file (docs/PROBES.md). Every error is one line naming the file and the
 * field's JSON path ("rooms.json: probes[2].influence.radius: must be > 0"). Relative
 * environment paths are resolved against the file's folder. */
ibl_status ibl_probe_set_load(ibl_context *ctx, const char *path, ibl_probe_set *out);
/* The same from memory; name is used in messages and dir resolves relative paths (NULL: "."). */
ibl_status ibl_probe_set_parse(ibl_context *ctx, const void *bytes, size_t size,
                               const char *name, const char *dir, ibl_probe_set *out);
void ibl_probe_set_free(ibl_context *ctx, ibl_probe_set *set);

/* The blend order: higher priority first, then smaller influence volume (JAGE 2015), then
 * file order. order receives probe_count indices. */
void ibl_probe_set_order(const ibl_probe_set *set, int *order);

/* The global probe's environment as a one-level cube of edge set->global.size: the HDRI read
 * and rotated, or the built-in sky rendered. */
ibl_status ibl_probe_set_environment(ibl_context *ctx, const ibl_probe_set *set,
                                     ibl_cubemap *out);

/* ---- capture ---------------------------------------------------------------------------- */

enum { IBL_CAPTURE_NO_BOUNCE = -1 };

typedef struct ibl_capture_desc {
    int bounces;        /* surface reflections a path may take before it reaches the probe:
                           0: 2; IBL_CAPTURE_NO_BOUNCE: emitters and the sky as seen only     */
    int samples;        /* paths per texel; 0: 64                                             */
    uint32_t seed;      /* of the counter-based random numbers                                */
    int size;           /* cube edge; 0: each probe's own                                     */
    int no_light_sampling; /* validation: sample the BRDF only (no emitter or sky sampling)   */
} ibl_capture_desc;

/* Captures one local probe: a one-level RGBA cube (allocated into out) whose texels hold
 * premultiplied radiance and coverage. For each texel, `samples` paths start at the probe's
 * position through jittered points of the texel; a path's first hit must lie inside the
 * influence volume in far-plane mode (else it contributes nothing: alpha < 1), while later
 * bounces see the whole scene and the environment. RGB = sum of the covered paths' radiance /
 * samples, A = covered paths / samples (1 in infinite mode). Lighting: the environment
 * (importance-sampled), emissive triangles (sampled by power), multiple importance sampling
 * with the BRDF (glTF metal/roughness: Lambert + GGX, Smith height-correlated, Schlick).
 * Random numbers are a hash of (seed, probe_index, face, texel, sample, dimension): the
 * result is bit-identical for any thread count. Progress: stage "capture NAME". */
ibl_status ibl_capture_probe(ibl_context *ctx, const ibl_scene *scene,
                             const ibl_cubemap *environment, const ibl_local_probe *probe,
                             int probe_index, const ibl_capture_desc *desc, ibl_cubemap *out);

/* Captures every probe of the set and writes DIR/captures.json and DIR/NAME.ktx2 (cube,
 * RGBA32F) as one output set: the folder gets every file or none (docs/PROBES.md). The
 * folder is created when missing. */
ibl_status ibl_capture_set(ibl_context *ctx, const ibl_scene *scene,
                           const ibl_cubemap *environment, const ibl_probe_set *set,
                           const ibl_capture_desc *desc, const char *dir);

/* ---- coverage-aware filtering and blending ---------------------------------------------- */

/* Prefilters a capture (premultiplied RGB, coverage A; level 0) into a specular chain with a
 * preset's kernel (ibl_specular_preset; NULL: "gltf"), at the capture's size. RGB and A go
 * through the same linear filter, so every level stays premultiplied: a texel near uncovered
 * directions gets their share as alpha < 1 and no light for them, and the run time gives that
 * weight to the next probe (ibl_capture_blend). out: a new cube (ibl_cubemap_free). */
ibl_status ibl_capture_prefilter(ibl_context *ctx, const ibl_cubemap *capture,
                                 const char *preset, ibl_cubemap *out);

/* Front-to-back blend of premultiplied probe lookups (JAGE 2015's priority blend with its
 * alpha): probes in blend order (ibl_probe_set_order), each with its influence weight
 * (ibl_volume_weight) and looked-up premultiplied RGBA. With remaining = 1 at first, probe i
 * adds w_i remaining rgb_i and takes w_i remaining a_i of the remaining weight; the global
 * probe gets what is left. Returns that remaining weight; out receives RGB. With every alpha
 * 1 the weights are ibl_volume_blend's. */
float ibl_capture_blend(const float (*rgba)[4], const float *weights, int count,
                        const float global_rgb[3], float out[3]);

#ifdef __cplusplus
}
#endif
#endif
