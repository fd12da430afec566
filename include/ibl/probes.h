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
#include "bake.h"

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

/* A default view of the scene (the set's optional "view"): camera position, the point it
 * looks at, vertical field of view. */
typedef struct ibl_probe_view {
    ibl_vec3 position, target;
    float fov_y_degrees;
} ibl_probe_view;

typedef struct ibl_probe_set {
    ibl_global_probe global;
    ibl_local_probe *probes;
    int probe_count;
    char *path; /* the file it was read from (messages), or NULL */
    int has_view;
    ibl_probe_view view;
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


/* ---- the probe-array bake (src/bake/bake_probes.c; docs/PROBES.md "The probe bake") ------ */

/* Bytes of one probe's record in the std430 property buffer (probes.bin). */
enum { IBL_PROBE_RECORD_BYTES = 240 };

typedef struct ibl_probe_bake_desc {
    const char *captures;        /* the captures folder (ibl_capture_set): CAPTURES/NAME.ktx2   */
    const ibl_cubemap *cubes;    /* or the captures in memory, one per probe in set order      */
    int shard, shards;           /* shards > 0: only the probes whose set index i has
                                    i % shards == shard - 1, as parts in dir (no merge)         */
    int merge;                   /* assemble from the parts already in dir (compute none)      */
    ibl_format format;           /* storage of the local chains; 0: rgba16f                     */
    const ibl_bake_desc *global; /* the global probe's bake; NULL: the set's global preset and
                                    size, no preview                                           */
    int lut_size;                /* with global NULL: the split-sum table's edge; 0: 128        */
} ibl_probe_bake_desc;

typedef struct ibl_probe_bake_report {
    int computed, reused; /* parts filtered by this run / found in dir (content-addressed)  */
} ibl_probe_bake_report;

/* Bakes a probe set into the bake folder dir: the global probe as ibl_bake does (from
 * environment), every local capture through ibl_capture_prefilter with its SH (premultiplied
 * RGB and coverage), one KTX2 cube-map array (probes.ktx2) with the chains in blend order
 * (ibl_probe_set_order), the std430 property buffer (probes.bin) and its JSON twin
 * (probes.json), and the manifest with a "probes" section. Every local probe needs the same
 * preset and capture size. Each filtered chain is first written as a content-addressed part
 * (probe-HASH.ktx2): with desc->shards only the shard's parts are made (environment may be
 * NULL); with desc->merge none are made; a part already in dir is reused. The folder is
 * written as one transaction (ibl_bake_write); a shard writes only whole parts. The result is
 * byte-identical however the probes were split into shards. */
ibl_status ibl_probe_bake(ibl_context *ctx, const ibl_probe_set *set, const ibl_cubemap *environment,
                          const ibl_probe_bake_desc *desc, const char *dir,
                          ibl_probe_bake_report *report);

/* One local probe of a probe bake, as its record in the property buffer. */
typedef struct ibl_probe_record {
    char name[IBL_PROBE_NAME_MAX];
    ibl_vec3 position;
    ibl_volume influence, proxy;
    int priority, layer;
    float influence_size; /* ibl_volume_size(influence): the sort key after priority           */
    float coverage;       /* mean alpha of level 0                                             */
    float sh[9][4];       /* rgb: SH of the premultiplied radiance; a: of the coverage         */
} ibl_probe_record;

/* A probe bake in memory (ibl_probe_bake_load). records[i] and chains[i] are layer i; the
 * layers are in blend order. */
typedef struct ibl_probe_bake_data {
    ibl_bake_data global;
    int count;
    ibl_probe_record *records;
    ibl_cubemap *chains;         /* premultiplied RGB + coverage A, every level                */
    ibl_level_mapping mapping;   /* roughness of each level of the chains                      */
} ibl_probe_bake_data;

/* Reads a probe bake folder: the global bake (ibl_bake_load), probes.ktx2 and probes.bin
 * (the records are decoded from the binary buffer; names from the manifest). */
ibl_status ibl_probe_bake_load(ibl_context *ctx, const char *dir, ibl_probe_bake_data *out);
void ibl_probe_bake_free(ibl_context *ctx, ibl_probe_bake_data *bake);

/* ---- run time: tiled culling and blending (src/probes/probe_runtime.c; docs/PROBES.md
 * "Run time", whose exact statements the shaders mirror) ------------------------------------ */

/* A pinhole camera: pixel (x, y) (y down) looks along
 * forward + sx right + sy up, sx = (2 (x + 0.5) / width - 1) tan(fov_y / 2) width / height,
 * sy = (1 - 2 (y + 0.5) / height) tan(fov_y / 2); right = normalize(forward x up), up
 * re-orthogonalised. A depth is the distance along forward (view depth, not ray length). */
typedef struct ibl_camera {
    ibl_vec3 position, forward, up; /* forward and up need not be unit or orthogonal          */
    float fov_y_degrees;            /* 0: 60                                                   */
    int width, height;
} ibl_camera;

/* The camera's unit basis and the unnormalised ray of pixel (px, py) in pixel coordinates
 * (the centre of pixel x is x + 0.5): the point at view depth d is position + d * ray. */
void ibl_camera_basis(const ibl_camera *cam, ibl_vec3 *right, ibl_vec3 *up, ibl_vec3 *forward);
ibl_vec3 ibl_camera_ray(const ibl_camera *cam, float px, float py);

typedef enum ibl_tile_sort {
    IBL_TILE_SORT_ODD_EVEN = 0, /* the write-up's first: odd-even transposition on one thread  */
    IBL_TILE_SORT_RANK,         /* its second: each entry counts the smaller ones, then a
                                   barrier and a write in place (two barriers on a GPU)       */
    IBL_TILE_SORT_RANK_COPY     /* its third: the same rank written to a second array (one)    */
} ibl_tile_sort;

typedef struct ibl_cull_desc {
    int tile_size;        /* pixels; 0: 16                                                     */
    ibl_tile_sort sort;   /* how each tile's list is put in blend order                         */
    int exact;            /* keep a probe only if some pixel of the tile lies inside its
                             influence volume (per-pixel test): the lists then equal the
                             brute force; 0: the frustum test only (conservative)            */
} ibl_cull_desc;

typedef struct ibl_cull_stats {
    long long tests;       /* volume x tile frustum tests                                      */
    long long compares;    /* comparisons made by the sorts                                    */
    long long entries;     /* total list entries                                               */
} ibl_cull_stats;

/* Tiled culling (JAGE 2015 "Tiled Probe Culling"): for each tile of tile_size pixels, the
 * depth bounds are the least and greatest depth[] of its pixels (depths <= 0 or not finite
 * are background and ignored; a tile of background only gets an empty list); a probe is
 * listed if its influence volume (sphere, or the box's 8 corners) is not wholly outside one
 * of the tile frustum's 6 planes (4 sides through the tile's pixel edges, near = the least
 * depth, far = the greatest). Probe indices are appended in a scrambled order (as a GPU's
 * atomic adds give them) and sorted into ascending index order with desc->sort: the probes
 * must be given in blend order (a probe bake's layer order). Lists are in out (freed with
 * ibl_tile_lists_free). depth: width x height floats, row 0 at the top. stats may be NULL. */
ibl_status ibl_cull_probes(ibl_context *ctx, const ibl_camera *cam, const float *depth,
                           const ibl_volume *influences, int count, const ibl_cull_desc *desc,
                           ibl_tile_lists *out, ibl_cull_stats *stats);

/* One of the three sorts on n distinct indices (scratch: n ints for RANK_COPY); returns the
 * comparisons it made. */
long long ibl_tile_sort_run(ibl_tile_sort sort, int *indices, int n, int *scratch);

typedef struct ibl_probe_blend_desc {
    int no_parallax;  /* look each probe up along the uncorrected direction                  */
    int no_blend;     /* the first probe with weight > 0 takes all (weight 1), no margins     */
    int no_alpha;     /* treat every probe's alpha as 1 (the uncovered directions show black) */
} ibl_probe_blend_desc;

/* What the blend gave each probe at a point (for tests and pictures). */
typedef struct ibl_probe_blend_info {
    float specular_global, diffuse_global; /* the global probe's share of each term           */
    int heaviest;                          /* layer with the largest specular share, -1: none */
} ibl_probe_blend_info;

/* Ambient lighting at world point p with the probes of list (layer indices of bake, in
 * ascending order: blend order): for each listed probe k in order, w_k =
 * ibl_volume_weight(influence, p) (no_blend: 1 if > 0); probes with w_k = 0 are skipped; the
 * lookup direction is ibl_parallax_correct(proxy, position, p, d) of the shading direction d
 * (ibl_shade_lookup_direction); ibl_shade_dir on the layer gives premultiplied diffuse D_k and
 * specular S_k; the specular alpha a_k is the chain's alpha at that direction and lod, the
 * diffuse alpha the cosine-convolved coverage (SH .a, irradiance / pi, clamped to 0..1).
 * Front to back, with remaining weights rs = rd = 1: S += w_k rs S_k, rs -= w_k rs a_k (and
 * the same for D with rd); the global probe adds rs S_g + rd D_g at the uncorrected
 * direction. color = D (x AO) + S x SO, as ibl_shade composes with IBL_MIX_MULTIPLY. */
void ibl_probes_shade(const ibl_probe_bake_data *bake, const ibl_probe *global,
                      const ibl_probe *locals, const int *list, int list_count,
                      const ibl_probe_blend_desc *blend, const ibl_shade_desc *desc,
                      const ibl_material *m, ibl_vec3 p, const ibl_surface *s,
                      ibl_shade_result *out, ibl_probe_blend_info *info);

/* The runtime views of a probe bake's layers: locals[i] reads chains[i] with the bake's
 * mapping, SH (rgb) and the global probe's BRDF tables. locals: bake->count entries. */
ibl_status ibl_probe_bake_locals(ibl_context *ctx, const ibl_probe_bake_data *bake,
                                 const ibl_probe *global, ibl_probe *locals);

/* ---- path-traced views (src/probes/capture.c's tracer; `ibl render --reference`) -------- */

typedef struct ibl_trace_desc {
    int bounces;     /* as ibl_capture_desc: 0: 2, IBL_CAPTURE_NO_BOUNCE: emission only        */
    int samples;     /* paths per pixel; 0: 64                                                  */
    uint32_t seed;
} ibl_trace_desc;

/* Path-traces the camera's view: each pixel the mean of `samples` paths through jittered
 * points of the pixel, with the capture's light transport (radiance, RGBA with A = 1; rays
 * that leave the scene see the environment). Deterministic for any thread count. out: a new image of cam->width x cam->height. */
ibl_status ibl_trace_view(ibl_context *ctx, const ibl_scene *scene, const ibl_cubemap *environment,
                          const ibl_camera *cam, const ibl_trace_desc *desc, ibl_image *out);

/* ---- the scene lit by its probes (src/probes/probe_render.c; `ibl render SCENE --probes`) -- */

enum {
    IBL_REGION_GLOBAL = -1,     /* a surface lit by the global probe mostly (no local share)   */
    IBL_REGION_BACKGROUND = -2  /* no surface: the ray left the scene                          */
};

typedef struct ibl_probe_render_desc {
    ibl_probe_blend_desc blend; /* what to switch off (the comparisons of `ibl render`)        */
    ibl_shade_desc shade;       /* the runtime shading; zero: defaults                          */
    ibl_cull_desc cull;         /* the tiled culling; zero: 16x16 tiles, conservative           */
} ibl_probe_render_desc;

/* Renders the scene lit by a probe bake as a deferred renderer would: the camera's primary
 * ray through each pixel centre finds the visible surface (its glTF material becomes an
 * ibl_material_gltf; a diffuse-only material keeps only the diffuse term), the view depths feed
 * ibl_cull_probes with the layers' influence volumes, and each point is shaded by
 * ibl_probes_shade with its tile's list (weights, parallax, alpha-aware priority blend, the
 * global probe last), plus the emission of front-facing emitters; a ray that leaves the scene
 * shows the global probe's sharpest level. out: a new linear image. regions (optional, one
 * int per pixel) receives the layer with the largest specular share (ibl_probe_blend_info's
 * heaviest), IBL_REGION_GLOBAL or IBL_REGION_BACKGROUND. Bit-identical for any thread count. */
ibl_status ibl_probe_render(ibl_context *ctx, const ibl_scene *scene,
                            const ibl_probe_bake_data *bake, const ibl_camera *cam,
                            const ibl_probe_render_desc *desc, ibl_image *out, int *regions);

#ifdef __cplusplus
}
#endif
#endif
