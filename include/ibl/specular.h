/*
 * ibl/specular.h - the prefiltered (mipmapped) radiance environment map: every level of the
 * output cube is the source convolved with a lobe (Phong, Blinn, GGX, box or Gaussian) whose
 * width grows with the level, so that a shader reads a blurred reflection with
 * textureLod(cube, R, lod(roughness)). docs/SPECULAR.md has the design, algorithms, mapping
 * formulas with their sources and the manifest format.
 *
 *   ibl_specular_desc d = { .filter = IBL_FILTER_GGX, .size = 256 };
 *   ibl_cubemap out; ibl_specular_info info;
 *   ibl_specular_prefilter(ctx, &src, &d, &out, &info);   // out: 6 faces x levels
 *
 * Kernels (tri-Ace 2010 "Generate REM" .. "Spherical Phong kernel"; the JAGE 2015 article's
 * "Cubemap Convolution"):
 *   phong: P(R) = int L(l) max(R.l,0)^n dl / int max(R.l,0)^n dl, n = the level's value;
 *   blinn: the Blinn lobe (n.h)^s through tri-Ace's fit cos^n(t) ~ cos^(f n)(t/2): Phong with
 *          n = s / f (f = blinn_factor, default 4.2; cmft and CubeMapGen use 4);
 *   ggx:   P(n) = int L(l) D(h) max(n.l,0) dl / int D(h) max(n.l,0) dl, v = n, h = norm(n+l),
 *          alpha = roughness^2 (the split-sum prefilter without sampling noise);
 *   box:   the plain area-weighted mip chain (tri-Ace's fastest dynamic profile); a level's
 *          value is the material shininess f n of the Phong lobe n fitted to its kernel;
 *   gauss: a 2D Gaussian blur per face (tri-Ace's second dynamic profile), sigma from the
 *          Phong kernel n = s / f of the level's material shininess s.
 * Units: a phong chain's values are kernel exponents; blinn, box and gauss chains' values
 * are the shininess of the tri-Ace normalised Blinn-Phong material that reads the level
 * (ibl_specular_level_shininess / _phong_exponent convert; docs/SPECULAR.md "Units").
 *
 * Methods: IBL_METHOD_FAST (default; deterministic multilevel summation over the source's
 * moment pyramid, see docs/SPECULAR.md) and IBL_METHOD_REFERENCE (the exact integral of the
 * piecewise-constant source over every texel with exact solid angles, in double; slow).
 * Output is bit-identical for any thread count.
 */
#ifndef IBL_SPECULAR_H
#define IBL_SPECULAR_H

#include "core.h"
#include "cubemap.h"
#include "edge_fixup.h"
#include "layout.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum ibl_specular_filter {
    IBL_FILTER_GGX = 0, /* default */
    IBL_FILTER_PHONG,
    IBL_FILTER_BLINN,
    IBL_FILTER_BOX,
    IBL_FILTER_GAUSS,
    IBL_FILTER_COUNT
} ibl_specular_filter;

typedef enum ibl_specular_method {
    IBL_METHOD_FAST = 0,
    IBL_METHOD_REFERENCE
} ibl_specular_method;

/* How a level is tied to a roughness (GGX) or a shininess (Phong family). */
typedef enum ibl_specular_mapping {
    IBL_MAPPING_DEFAULT = 0, /* GGX: linear; phong/blinn/box/gauss: triace                    */
    IBL_MAPPING_TRIACE,        /* tri-Ace 2010: lod = a - 0.5 log2(shininess), a = 0.5 log2(max) */
    IBL_MAPPING_LINEAR,      /* glTF IBL-Sampler: roughness = lod / (levels - 1)             */
    IBL_MAPPING_FILAMENT,    /* Filament: lod/(levels-1) = r (2 - r)                          */
    IBL_MAPPING_UNREAL,      /* UE4: mip = levels - 1 - (1 - 1.2 log2 r)                      */
    IBL_MAPPING_UNITY,       /* Unity: mip = 6 r (1.7 - 0.7 r)                                */
    IBL_MAPPING_BABYLON,     /* Babylon.js: alpha = 2^(lod / scale) / size (scale 0.8), lod 0 mirror */
    IBL_MAPPING_TABLE,       /* the caller's table of roughness or shininess per level        */
    IBL_MAPPING_COUNT
} ibl_specular_mapping;

typedef struct ibl_specular_desc {
    ibl_specular_filter filter;
    ibl_specular_method method;
    int size;                    /* output face edge; 0: the source's                           */
    int levels;                  /* 0: full chain down to 1x1                                    */
    ibl_specular_mapping mapping;
    float shininess_min;         /* Phong family range; 0: 1                                     */
    float shininess_max;         /* 0: 1000 (tri-Ace's 32x32 configurations)                     */
    float blinn_factor;          /* 0: 4.2 (tri-Ace's fit); cmft/CubeMapGen use 4                */
    const float *table;          /* IBL_MAPPING_TABLE: roughness (GGX) or shininess per level   */
    int table_count;             /* must equal the number of levels                              */
    int mirror;                  /* level 0 is the unfiltered source (see docs/SPECULAR.md)      */
    ibl_edge_fixup edge_fixup;   /* 0: none                                                      */
    ibl_bent_desc bent;          /* parameters of IBL_EDGE_FIXUP_BENT                            */
    int source_size;             /* plans only: face edge of the cubes ibl_specular_plan_run gets     */
    float accuracy;              /* fast method: quadrature step scale; 0: 0.35 (smaller: more
                                    exact, slower)                                               */
    float babylon_lod_scale;     /* IBL_MAPPING_BABYLON: the engine's lodGenerationScale,
                                    alpha = 2^(lod / scale) / size; 0: 0.8 (Babylon's default)  */
    int dynamic;                 /* the per-frame path (the dynamic presets set it): a plan of
                                    precomputed tables for every filter, box and gauss included
                                    (Phong family: less exact next to small bright lights; see
                                    docs/SPECULAR.md "Dynamic path")                             */
} ibl_specular_desc;

/* What a prefilter produced: everything a renderer needs to pick the level. */
typedef struct ibl_specular_info {
    ibl_specular_filter filter;
    ibl_specular_mapping mapping;
    int size, levels, mirror;
    float blinn_factor;
    float shininess_min, shininess_max;
    float lod_offset;                     /* IBL_MAPPING_TRIACE: the fitted a                        */
    float babylon_lod_scale;              /* IBL_MAPPING_BABYLON: the lod scale used (else 0)        */
    float roughness[IBL_MAX_LEVELS];  /* GGX: perceptual roughness per level (alpha = r^2)     */
    float shininess[IBL_MAX_LEVELS];  /* Phong family, in the chain's units (see the top)      */
} ibl_specular_info;

const char *ibl_specular_filter_name(ibl_specular_filter filter);   /* "ggx", "phong", ...   */
int ibl_specular_filter_from_name(const char *name, ibl_specular_filter *out); /* 0: unknown */
const char *ibl_specular_mapping_name(ibl_specular_mapping mapping); /* "triace", "linear", ... */
int ibl_specular_mapping_from_name(const char *name, ibl_specular_mapping *out);

/* tri-Ace's configurations and the modern presets: "dynamic-box16", "dynamic-gauss32",
 * "dynamic-phong16", "dynamic-phong32", "static-phong32", "static-phong64", "gltf",
 * "filament", "unreal", "unity". Fills *desc (other fields zero); 0 for an unknown name. */
int ibl_specular_preset(const char *name, ibl_specular_desc *desc);
/* The preset names, NULL-terminated. */
const char *const *ibl_specular_preset_names(void);

/* Fills the per-level parameters (roughness or shininess) of the chain desc describes for a
 * source of face edge source_size, without filtering anything. */
ibl_status ibl_specular_levels(ibl_context *ctx, const ibl_specular_desc *desc, int source_size,
                               ibl_specular_info *info);

/* The face edge of the source cube the fast method works from for the chain desc describes
 * (desc->size 0: source_size) from a source of edge source_size: the source's edge rounded up
 * to a power of two, or, when that is larger, the smallest power of two that keeps the
 * chain's narrowest filtered lobe as exact as the full source does (at least the chain's
 * edge). ibl_specular_prefilter reduces a larger source to it by exact area means; a caller
 * that makes the source cube (from a flat image, say) can make it at this edge directly. */
ibl_status ibl_specular_source_size(ibl_context *ctx, const ibl_specular_desc *desc,
                                    int source_size, int *edge);

/* Prefilters src (level 0 is used) into a newly allocated cube (free with ibl_cubemap_free).
 * info may be NULL. */
ibl_status ibl_specular_prefilter(ibl_context *ctx, const ibl_cubemap *src,
                                  const ibl_specular_desc *desc, ibl_cubemap *out,
                                  ibl_specular_info *info);

/* ibl_specular_prefilter in two halves. Prepare does everything that depends only on the desc
 * and the source's face edge (the fast method's plan: about a sixth of a 256 chain's time),
 * so a host that learns the source's size before it has the source (from a file's header)
 * can prepare while it decodes and converts the input, e.g. as the two tasks of one
 * ibl_parallel_for on the same context (`ibl prefilter` does: ibl_read_info, then the read and
 * the conversion beside ibl_specular_prepare). The prepared chain then filters one source of
 * that edge, once, with the same result as ibl_specular_prefilter bit for bit. */
typedef struct ibl_specular_prepared ibl_specular_prepared;
ibl_status ibl_specular_prepare(ibl_context *ctx, const ibl_specular_desc *desc, int source_size,
                                ibl_specular_prepared **out);
ibl_status ibl_specular_prefilter_prepared(ibl_specular_prepared *prepared,
                                           const ibl_cubemap *src, ibl_cubemap *out,
                                           ibl_specular_info *info);
void ibl_specular_prepared_destroy(ibl_specular_prepared *prepared);

/* ---- accuracy against a flat input (docs/SPECULAR.md "Accuracy against the input") ----
 *
 * The prefilter reads a cube; an image in another layout is converted first to a working cube
 * whose texels are area means of the image. Where a level's lobe is only a few working texels
 * wide (half width under 8), a sun a few pixels across is then misplaced inside its texels by
 * up to a texel. The sources of an image fix that: made from the image and the working cube
 * before the prefilter, they hold the image's own pixels (split into small cells with exact
 * solid angles) and the working texels around its brightest pixels, and applied to the chain
 * after it they replace, at every output texel of those narrow levels within reach, the
 * region's integral as the working cube gave it by the integral over the image's pixels.
 * Equirect images only (other layouts, box and Gaussian chains, edge fixups and the dynamic
 * path: no sources, apply does nothing); sources near the poles are left out (the conversion
 * integrates whole rows there). The image may be freed after create. */
typedef struct ibl_specular_sources ibl_specular_sources;
/* conversion: the desc the working cube was made with (layout, orientation; NULL: detected,
 * none); desc: the chain that will be filtered from working. */
ibl_status ibl_specular_sources_create(ibl_context *ctx, const ibl_image *image,
                                       const ibl_to_cube_desc *conversion,
                                       const ibl_cubemap *working, const ibl_specular_desc *desc,
                                       ibl_specular_sources **out);
/* Refines the chain ibl_specular_prefilter made from the working cube with the same desc. */
ibl_status ibl_specular_sources_apply(const ibl_specular_sources *sources, ibl_cubemap *chain);
/* Working texels whose light is replaced by the image's (0: apply does nothing). */
int ibl_specular_sources_count(const ibl_specular_sources *sources);
void ibl_specular_sources_destroy(ibl_specular_sources *sources);

/* A chain straight from an image in any layout: ibl_image_to_cubemap (conversion; NULL: the
 * layout detected, the image's own size), the sources, ibl_specular_prefilter, apply. What
 * `ibl prefilter` and `ibl bake` do with a flat input. */
ibl_status ibl_specular_prefilter_image(ibl_context *ctx, const ibl_image *image,
                                        const ibl_to_cube_desc *conversion,
                                        const ibl_specular_desc *desc, ibl_cubemap *out,
                                        ibl_specular_info *info);

/* The reference integral (double, every source texel, exact solid angles) for single
 * directions: the yardstick the benchmarks and tests compare the fast method against. */
typedef struct ibl_specular_reference ibl_specular_reference;
/* Precomputes texel directions and solid angles of src level 0 (src must outlive it). */
ibl_status ibl_specular_reference_create(ibl_context *ctx, const ibl_cubemap *src,
                                         ibl_specular_reference **out);
/* The filtered value (RGBA) of level `level` of the chain info describes, in direction dir.
 * A mirror level (roughness 0) gives the nearest source texel. */
void ibl_specular_reference_eval(const ibl_specular_reference *ref, const ibl_specular_info *info,
                                 int level, ibl_vec3 dir, double out[4]);
void ibl_specular_reference_destroy(ibl_specular_reference *ref);

/* The two units of a Phong-family level (docs/SPECULAR.md "Units"): the shininess of the
 * tri-Ace normalised Blinn-Phong material that reads it, and the exponent of the Phong kernel
 * it was filtered with, material = blinn_factor x kernel (tri-Ace 2010's fit). A phong chain's
 * levels and range are kernel exponents (the Phong material's own, as cmft's phong); blinn,
 * box and gauss chains speak the material's shininess. 0 for a mirror level and for GGX. */
float ibl_specular_level_shininess(const ibl_specular_info *info, int level);
float ibl_specular_level_phong_exponent(const ibl_specular_info *info, int level);

/* Describes the chain in a texture's KTX2 key/values, "ibl.specular.*": filter, mapping,
 * mirror, blinn_factor, lod_offset (tri-Ace mapping), and per level (space-separated,
 * 0 = mirror level) "roughness" for GGX, or "shininess" (the material's Blinn-Phong
 * exponent) and "phong_exponent" (the kernel's) for the Phong family. docs/FORMATS.md. */
ibl_status ibl_specular_set_metadata(ibl_context *ctx, const ibl_specular_info *info,
                                     ibl_texture *tex);
/* Reads that description back (size from the texture; the mapping's shininess range is not
 * stored and set to the defaults). name is used in messages. IBL_ERR_FORMAT if absent. */
ibl_status ibl_specular_info_from_metadata(ibl_context *ctx, const ibl_texture *tex,
                                           const char *name, ibl_specular_info *info);

/* ---- the dynamic (per-frame) path: plan once, refilter many times ---- */

typedef struct ibl_specular_plan ibl_specular_plan;
struct ibl_sh; /* ibl/sh.h */

/* Plans for source cubes of face edge desc->source_size (0: desc->size) and output desc->size
 * (required). All tables and scratch memory are allocated here. The context is kept and used
 * by ibl_specular_plan_run (its parallel-for). */
ibl_status ibl_specular_plan_create(ibl_context *ctx, const ibl_specular_desc *desc,
                                    ibl_specular_plan **out);
/* Refilters: src must have level 0 of edge source_size; dst must have edge size and the
 * planned number of levels (e.g. caller-owned memory through ibl_cubemap_wrap). Allocates
 * nothing; time depends only on the sizes. */
ibl_status ibl_specular_plan_run(ibl_specular_plan *plan, const ibl_cubemap *src, ibl_cubemap *dst);
const ibl_specular_info *ibl_specular_plan_info(const ibl_specular_plan *plan);
/* The diffuse SH of the dynamic path (a plan with .dynamic, after a run): the radiance SH
 * (bands 1..5, 0: 3) of the last run's source, projected from its 8x8x6 box mip with
 * precomputed weights (docs/SPECULAR.md "Dynamic path"). Allocates nothing. */
ibl_status ibl_specular_plan_sh(const ibl_specular_plan *plan, int bands, struct ibl_sh *out);
void ibl_specular_plan_destroy(ibl_specular_plan *plan);

/* The lobe operator of a dynamic Phong-family plan (filter phong, blinn or ggx with .dynamic;
 * the presets dynamic-phong16/32) in a form a GPU can run: one output level is a sparse
 * matrix in CSR form, one row per output texel, over the texels of one box mip of the source
 * (the area-weighted chain of ibl_cubemap_build_mips / shaders/ibl_box_mip.comp; mip m has
 * edge source_size >> m). The plan stores only 1/48 of the rows (the cube's symmetries);
 * here they are expanded to all six faces. docs/SHADERS.md "the Phong presets".
 *
 *   level[i] = sum over k in [row_offsets[r], row_offsets[r+1]) of weight[k] mip[column[k]]
 *   r = (face n + y) n + x (output texel), column = (face M + y) M + x (mip texel, M its edge)
 *
 * The rows are normalised when the plan is made (each sums to 1 in double before the cast to
 * float): there is no normalisation left to apply. Taps of weight 0 (the plan's eight-wide
 * padding) are left out; the taps of a row come in the order the C sums them. A mirror level
 * (filter's roughness 0) is the box mip of its own edge: rows of one tap of weight 1. After
 * the rows the C applies `fixup` to the level: IBL_EDGE_FIXUP_NONE (nothing), or
 * IBL_EDGE_FIXUP_OVERLAP / OVERLAP2 (tri-Ace's edge overlapping; on a 1x1 level any fixup
 * but none is the mean of the six faces, reported as OVERLAP). The bent and warp fixups live
 * in the rows' directions: a dynamic-phong level reports NONE except at 1x1. */
typedef struct ibl_specular_plan_rows {
    int size;          /* output edge n of the level                                         */
    int source_mip;    /* the box mip of the source the rows read                            */
    int source_size;   /* its edge M = source_size >> source_mip                             */
    int mirror;        /* 1: a copy of the box mip (one tap of weight 1 per row)             */
    ibl_edge_fixup fixup; /* applied by the C after the rows (see above)                     */
    size_t rows;       /* 6 n^2: row_offsets has rows + 1 entries                             */
    size_t taps;       /* entries of columns and weights                                      */
} ibl_specular_plan_rows;

/* The sizes of level `level` (and where it reads). IBL_ERR_INVALID_ARGUMENT for a plan without
 * a lobe operator (not dynamic, or box/gauss) or a level out of range. Allocates nothing. */
ibl_status ibl_specular_plan_rows_info(const ibl_specular_plan *plan, int level,
                                       ibl_specular_plan_rows *out);
/* Fills the caller's arrays of the sizes rows_info gave: row_offsets (rows + 1, from 0 to
 * taps), columns and weights (taps each). Allocates nothing. */
ibl_status ibl_specular_plan_rows_fill(const ibl_specular_plan *plan, int level,
                                       uint32_t *row_offsets, uint32_t *columns, float *weights);

#ifdef __cplusplus
}
#endif
#endif
