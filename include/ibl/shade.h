/*
 * ibl/shade.h - runtime evaluation of baked image-based lighting on the CPU: what a shader
 * does with the bake, written in C so an engine's CPU code (and `ibl render`) can use it.
 *
 *   ibl_probe    the baked data of one environment: the prefiltered specular chain with its
 *                level <-> roughness/shininess mapping, the irradiance (cube or 9 SH
 *                coefficients) and the BRDF tables, all plain data (see docs/SHADING.md);
 *                bake.h makes and loads bakes and gives their probes. No file I/O here.
 *   ibl_shade    ambient diffuse + specular radiance at a surface point for a glTF
 *                metal/roughness (GGX) or tri-Ace's normalised Blinn-Phong material, with
 *                specular occlusion and tri-Ace's ambient-specular compositions.
 *   volumes      local probes: influence volumes with priority blending, parallax correction,
 *                the IBL offset, the shininess hack, the two-environment switch, tiled culling.
 *   atlas        Daqi 2016's 2D mip atlas of a prefiltered chain and material channel packing.
 *
 * Conventions: world frame right-handed, +Y up (docs/CONVENTIONS.md). V points from the
 * surface toward the eye; N is unit length. Roughness is the perceptual (glTF) roughness r,
 * alpha = r^2. Shininess is the exponent of tri-Ace 2010's normalised Blinn-Phong BRDF.
 * Radiances are linear RGB. The hot-path functions take validated data and never fail.
 */
#ifndef IBL_SHADE_H
#define IBL_SHADE_H

#include "core.h"
#include "cubemap.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ------------------------------------------------------------------------------------------ */
/* Plain tables                                                                               */

/* One axis of a lookup table: sample i holds the parameter value
 * first + (last - first) * i / (count - 1) (or the same in log(value) if logarithmic).
 * Lookups clamp to [first, last] and interpolate linearly between samples.
 * Texel-centred tables of n texels over [0, 1] have first = 0.5/n, last = 1 - 0.5/n. */
typedef struct ibl_table_axis {
    int count;
    float first, last;
    int logarithmic;
} ibl_table_axis;

/* The split-sum GGX table (Karis 2013): for n.v and roughness, A and B such that the
 * directional albedo of the specular lobe is F0 * A + B (single scattering). Laid out
 * [roughness][n_dot_v][channel]; channel 0 = A, channel 1 = B, further channels ignored. */
typedef struct ibl_splitsum_view {
    const float *data;
    int channels; /* floats per sample, >= 2; 0: 2 */
    ibl_table_axis n_dot_v, roughness;
} ibl_splitsum_view;

/* The AmbientBRDF volume (tri-Ace 2010, "AmbientBRDF texture usage"): the integral of
 * the normalised Blinn-Phong specular lobe times n.l for (n.v, shininess, F0). Laid out
 * [f0][shininess][n_dot_v][channel]; channel 0 is used. */
typedef struct ibl_ambient_brdf_view {
    const float *data;
    int channels; /* 0: 1 */
    ibl_table_axis n_dot_v, shininess, f0;
} ibl_ambient_brdf_view;

/* Interpolated lookups (clamped to the table's range). */
void ibl_splitsum_lookup(const ibl_splitsum_view *t, float n_dot_v, float roughness, float *a,
                         float *b);
float ibl_ambient_brdf_lookup(const ibl_ambient_brdf_view *t, float n_dot_v, float shininess,
                              float f0);
/* Value of sample i of an axis, and the fractional sample index of a value (clamped). */
float ibl_table_axis_value(const ibl_table_axis *axis, int i);
float ibl_table_axis_index(const ibl_table_axis *axis, float value);

/* ------------------------------------------------------------------------------------------ */
/* Roughness <-> shininess                                                                    */

/* Blinn-Phong exponent with the same lobe width as GGX alpha = r^2: n = 2 / alpha^2 - 2
 * (Walter et al. 2007; Karis 2013). Capped at 1e6. */
float ibl_shininess_from_roughness(float roughness);
float ibl_roughness_from_shininess(float shininess);

/* ------------------------------------------------------------------------------------------ */
/* The probe                                                                                  */

typedef float (*ibl_lod_fn)(void *user, float value);

/* How the prefiltered levels relate to the material: what level k was filtered for. */
typedef struct ibl_level_mapping {
    int levels;                      /* levels described (<= the chain's levels)             */
    float roughness[IBL_MAX_LEVELS]; /* roughness of level k, strictly increasing             */
    float shininess[IBL_MAX_LEVELS]; /* shininess of level k, decreasing; an all-zero table
                                         is derived from roughness[]                          */
    ibl_lod_fn lod_from_roughness;   /* optional: overrides the table (e.g. a bake's formula) */
    ibl_lod_fn lod_from_shininess;   /* optional, likewise; e.g. tri-Ace's a - 0.5 log2 n     */
    void *user;                      /* passed to the two functions                           */
} ibl_level_mapping;

typedef enum ibl_sh_kind {
    IBL_SH_KIND_NONE = 0,  /* no SH: use the irradiance cube                                  */
    IBL_SH_KIND_RADIANCE,  /* projection of the radiance L (convolved with the cosine here)   */
    IBL_SH_KIND_IRRADIANCE /* already convolved: E(n) = sum c_i Y_i(n)                        */
} ibl_sh_kind;

/* Everything the runtime needs about one environment: plain data, never owning. Fill it by
 * hand from in-memory parts and call ibl_probe_validate once, or get it from a bake with
 * ibl_bake_probe (bake.h), which loads folders. The SH basis and axes are sh.h's
 * (IBL_SH_BASIS_NAME, world x y z, +Y up). */
struct ibl_atlas_layout;

typedef struct ibl_probe {
    ibl_cubemap specular; /* prefiltered chain, level 0 the sharpest                      */
    ibl_level_mapping mapping;
    ibl_cubemap mirror;     /* optional unfiltered, high-resolution environment (tri-Ace
                               2010 "Problems with large shininess": the mirror option)   */
    float mirror_shininess; /* shininess from which the mirror is used alone; 0: 10000    */
    ibl_cubemap irradiance; /* optional: IEM(n) = E(n) / pi, tri-Ace 2010's irradiance map */
    ibl_sh_kind sh_kind;    /* which diffuse source ibl_probe_irradiance reads            */
    float sh[9][3]; /* real SH, order (0,0) (1,-1) (1,0) (1,1) (2,-2) (2,-1) (2,0)
                                   (2,1) (2,2); basis 0.282095, 0.488603 (y, z, x), ...        */
    ibl_splitsum_view splitsum;
    ibl_ambient_brdf_view ambient_brdf;
    float intensity; /* scales every radiance read from the probe; 0: 1             */
    /* optional: the same chain as Daqi 2016's 2D mip atlas (ibl_atlas_pack; a bake made with
     * atlas = 1 offers it). With use_atlas, ibl_probe_sample_specular reads it as
     * shaders/ibl_atlas.glsl's ibl_atlas_probe_specular does (no mirror: an 8-slot device
     * holds no cube for it; lod < 0 reads level 0) */
    const ibl_image *atlas;
    const struct ibl_atlas_layout *atlas_layout;
    int use_atlas;
} ibl_probe;

/* Checks the probe's parts (sizes, a monotonic mapping, tables) and fills a missing
 * roughness or shininess table from the other; records the reason on failure. Levels may
 * repeat a value (engine mappings end in several levels of roughness 1): lookups then take
 * the sharpest level of the run. */
ibl_status ibl_probe_validate(ibl_context *ctx, ibl_probe *probe);

/* Fractional level for a roughness / shininess through the probe's own mapping (exact level
 * k at the value of level k). For shininess above level 0's, returns a negative lod whose
 * magnitude is the fraction toward the mirror (see ibl_probe_sample_specular). */
float ibl_probe_lod_from_roughness(const ibl_probe *probe, float roughness);
float ibl_probe_lod_from_shininess(const ibl_probe *probe, float shininess);
/* Prefiltered radiance along dir at a fractional lod: trilinear between the two levels;
 * lod in [-1, 0) blends level 0 with the mirror when one is present. RGB. */
void ibl_probe_sample_specular(const ibl_probe *probe, float lod, ibl_vec3 dir, float out[3]);
/* The IEM (tri-Ace 2010): E(n)/pi, the radiance a white Lambertian surface reflects. RGB. */
void ibl_probe_irradiance(const ibl_probe *probe, ibl_vec3 n, float out[3]);
/* Irradiance E(n) from 9 SH coefficients of a kind (RGB). */
void ibl_sh9_eval_irradiance(const float sh[9][3], ibl_sh_kind kind, ibl_vec3 n, float out[3]);

/* ------------------------------------------------------------------------------------------ */
/* Materials and occlusion                                                                    */

typedef enum ibl_material_model {
    IBL_MATERIAL_GGX = 0,    /* glTF 2.0 metal/roughness: GGX + Smith + Schlick, Lambert     */
    IBL_MATERIAL_BLINN_PHONG /* tri-Ace 2010: Rd/pi (1 - F0) + normalised Blinn-Phong        */
} ibl_material_model;

typedef struct ibl_material {
    ibl_material_model model;
    float base_color[3]; /* GGX: glTF baseColor; Blinn-Phong: Rd                               */
    float metallic;      /* GGX                                                                */
    float roughness;     /* GGX perceptual roughness                                           */
    float f0[3];         /* Blinn-Phong F0 (GGX: dielectric F0, all-zero means 0.04)           */
    float shininess;     /* Blinn-Phong exponent                                               */
    float ao;            /* ambient occlusion in [0, 1] (set it: 1 means unoccluded)           */
} ibl_material;

/* Helpers that fill every field (ao = 1). */
ibl_material ibl_material_gltf(const float base_color[3], float metallic, float roughness);
ibl_material ibl_material_blinn_phong(const float rd[3], const float f0[3], float shininess);
/* The BRDF's own reflectances, per channel: F0 of the specular lobe and the albedo of the
 * Lambert lobe (the diffuse term is diffuse_albedo / pi).
 *   GGX: F0 = lerp(dielectric F0 (0.04 unless f0 is given), base_color, metallic),
 *        diffuse_albedo = base_color (1 - metallic)
 *   Blinn-Phong: F0 = f0, diffuse_albedo = Rd (1 - F0) (tri-Ace 2010, "Equations")
 * ibl_shade's ambient Blinn-Phong diffuse may weight Rd by 1 - AmbientBRDF instead
 * (ibl_bp_diffuse); punctual lights and the reference renderer use the BRDF as it is. */
void ibl_material_reflectances(const ibl_material *m, float f0[3], float diffuse_albedo[3]);

/* Specular occlusion from AO (docs/SHADING.md has every formula with its source). */
typedef enum ibl_so_formula {
    IBL_SO_NONE = 0,         /* SO = 1                                                          */
    IBL_SO_AO,               /* SO = AO: "generally multiply by the AO factor"                  */
    IBL_SO_TRIACE,           /* saturate((n.E)^2 + 2AO - 1)                    tri-Ace SO (1)   */
    IBL_SO_TRIACE_SHININESS, /* saturate(((n.E) + AO)^(0.01 shininess) - 1 + AO)  SO (2)      */
    IBL_SO_TRIACE_FAST,      /* saturate(((n.E) + AO)^2 - 1 + AO)              SO (3)           */
    IBL_SO_FROSTBITE,        /* saturate((n.v + AO)^exp2(-16 r - 1) - 1 + AO)  Lagarde 2014     */
    IBL_SO_CONE,             /* visibility cone / specular cone intersection  Jimenez 2016     */
    IBL_SO_COUNT
} ibl_so_formula;

/* tri-Ace's ways of putting ambient specular, ambient diffuse and direct specular together
 * (tri-Ace 2010 "Ambient specular term computation", "AS term computation (1)-(4)",
 * "Applying to the entire specular term"). s_d is the direct specular. */
typedef enum ibl_ambient_mix {
    IBL_MIX_MULTIPLY = 0, /* s_d + specular_ambient * SO                                      */
    IBL_MIX_LERP_ALBEDO,  /* s_d + lerp(diffuse_ambient * albedo, specular_ambient, SO)   (1) */
    IBL_MIX_LERP_AO,      /* s_d + lerp(diffuse_ambient * AO, specular_ambient, SO)       (2) */
    IBL_MIX_AO_LERP_AO,   /* s_d + AO lerp(diffuse_ambient * AO, specular_ambient, SO)    (3) */
    IBL_MIX_LERP_AO2,     /* s_d + lerp(diffuse_ambient * AO^2, specular_ambient, SO)     (4) */
    IBL_MIX_ENTIRE,       /* s_d SO + AO lerp(diffuse_ambient * AO, specular_ambient, SO)     */
    IBL_MIX_COUNT
} ibl_ambient_mix;

typedef enum ibl_energy_compensation {
    IBL_ENERGY_NONE = 0,    /* single scattering only (the split-sum as is)                  */
    IBL_ENERGY_FDEZ_AGUERA, /* Fdez-Aguera 2019: multiple-scattering lobe lit by irradiance  */
    IBL_ENERGY_TURQUIN      /* Turquin 2019: scale the lobe by 1 + F0 (1/E - 1)              */
} ibl_energy_compensation;

typedef enum ibl_bp_diffuse {
    IBL_BP_DIFFUSE_AMBIENT_BRDF = 0, /* Rd (1 - AmbientBRDF): tri-Ace's optimisation                  */
    IBL_BP_DIFFUSE_F0        /* Rd (1 - F0): the BRDF's own diffuse weight                    */
} ibl_bp_diffuse;

const char *ibl_so_formula_name(ibl_so_formula f); /* "none", "ao", "triace", ...   */
int ibl_so_formula_from_name(const char *name, ibl_so_formula *out); /* 0 if unknown  */
const char *ibl_ambient_mix_name(ibl_ambient_mix m); /* "multiply", "lerp-albedo", ...  */
int ibl_ambient_mix_from_name(const char *name, ibl_ambient_mix *out);
const char *ibl_energy_compensation_name(ibl_energy_compensation e); /* "none", "fdez-aguera", "turquin" */
int ibl_energy_compensation_from_name(const char *name, ibl_energy_compensation *out);

/* SO for one formula. n_dot_e: n.E (E toward the eye); roughness for FROSTBITE/CONE,
 * shininess for TRIACE_SHININESS (the other is ignored). */
float ibl_specular_occlusion(ibl_so_formula f, float n_dot_e, float ao, float roughness,
                             float shininess);
/* Horizon fade of reflections that point below the geometric surface (Russell 2015,
 * "Horizon occlusion for normal mapped reflections", Marmoset): saturate(1 + k R.Ng)^2. */
float ibl_horizon_occlusion(ibl_vec3 r, ibl_vec3 geometric_normal, float k);
/* tri-Ace's compositions, per channel. Returns the specular total (what "final" is in
 * the talk); the diffuse term (diffuse_ambient * albedo * AO) is added by the caller. */
void ibl_ambient_mix_apply(ibl_ambient_mix mix, const float s_d[3], const float diffuse_ambient[3],
                           const float specular_ambient[3], const float albedo[3], float ao,
                           float so, float out[3]);

/* What a punctual light's size does (light.h, ibl_light.size). */
typedef enum ibl_light_size_model {
    IBL_LIGHT_SIZE_WIDEN = 0, /* Blinn-Phong: tri-Ace 2010's shininess hack,
                                 n' = n saturate(60 / size (1 - attenuation))^2;
                                 GGX: D with Karis 2013's alpha' (V keeps alpha)          */
    IBL_LIGHT_SIZE_IGNORE,    /* every light is a true point: the exact delta light         */
    IBL_LIGHT_SIZE_COUNT
} ibl_light_size_model;

typedef struct ibl_shade_desc {
    ibl_energy_compensation energy;
    ibl_so_formula so;
    ibl_ambient_mix mix;
    int horizon_occlusion; /* apply the horizon fade (needs the geometric normal)       */
    float horizon_k;       /* 0: 1.3                                                    */
    ibl_bp_diffuse bp_diffuse;
    int no_mirror;        /* never use the mirror cube                                 */
    int nearest_level;    /* round the lod (no trilinear): to see the level steps      */
    int mirror_direction; /* ibl_shade: look up along R itself instead of the lobe's
                                   dominant direction, which leans from R toward N as the
                                   lobe widens (ibl_dominant_direction_lean; the default)      */
    ibl_light_size_model light_size; /* punctual lights (light.h): what their size does      */
} ibl_shade_desc;

typedef struct ibl_surface {
    ibl_vec3 n;                /* shading normal (unit)                                         */
    ibl_vec3 v;                /* toward the eye (unit)                                         */
    ibl_vec3 geometric_normal; /* zero: same as n                                              */
    float direct_specular[3];  /* s_d for the compositions (0 if none)                          */
} ibl_surface;

typedef struct ibl_shade_result {
    float color[3];    /* diffuse * AO + composed specular: the ambient result         */
    float diffuse[3];  /* ambient diffuse radiance (albedo applied, no AO)             */
    float specular[3]; /* ambient specular radiance (BRDF scale applied, no SO)        */
    float so;          /* specular occlusion used (horizon fade included)              */
    float lod;         /* level sampled                                                */
    ibl_vec3 r;        /* reflection direction sampled                                 */
} ibl_shade_result;

/* How far the lookup direction leans from N toward R, t in [0, 1] for lerp(N, R, t): the
 * lobe's dominant direction, which the n = v = r prefilter cannot express. GGX: Lagarde & de
 * Rousiers 2014, (1 - r)(sqrt(1 - r) + r); tri-Ace's normalised Blinn-Phong: the lobe's
 * centroid, t = g / (1 + g), g = 0.1785 s^0.9805 (docs/SHADING.md "Dominant direction"). */
float ibl_dominant_direction_lean(const ibl_material *material);

/* Ambient lighting of one surface point. desc may be NULL (defaults). The reflection vector
 * is R = 2 (n.v) n - v; pass a corrected direction through ibl_shade_dir for local probes. */
void ibl_shade(const ibl_probe *probe, const ibl_shade_desc *desc, const ibl_material *m,
               const ibl_surface *s, ibl_shade_result *out);
/* The direction ibl_shade looks the prefiltered chain up along: the lobe's dominant
 * direction, lerp(N, R, ibl_dominant_direction_lean(m)) normalised, or R itself with
 * desc->mirror_direction. Start from it to correct it (IBL offset, parallax). */
ibl_vec3 ibl_shade_lookup_direction(const ibl_shade_desc *desc, const ibl_material *m,
                                    const ibl_surface *s);
/* The same with the specular lookup direction given (parallax-corrected, offset, ...). */
void ibl_shade_dir(const ibl_probe *probe, const ibl_shade_desc *desc, const ibl_material *m,
                   const ibl_surface *s, ibl_vec3 lookup_dir, ibl_shade_result *out);

/* Several probes at one point, summed by weight (tri-Ace 2010 "IBL Blending": each radiance
 * map fetched once; JAGE 2015: weights from ibl_volume_blend, its remainder for the global
 * probe). lookup_dirs: one direction per probe (e.g. parallax-corrected), or NULL for the
 * dominant direction / R of ibl_shade. so and lod in out are those of the heaviest probe. */
void ibl_shade_blend(const ibl_probe *const *probes, const float *weights, int count,
                     const ibl_vec3 *lookup_dirs, const ibl_shade_desc *desc,
                     const ibl_material *m, const ibl_surface *s, ibl_shade_result *out);

/* ------------------------------------------------------------------------------------------ */
/* Analytic BRDF pieces (src/shade/brdf_eval.c), shared by the reference renderer.           */

float ibl_fresnel_schlick(float f0, float v_dot_h);
float ibl_ggx_d(float alpha, float n_dot_h);
/* Height-correlated Smith visibility V = G / (4 n.l n.v) (Heitz 2014). */
float ibl_smith_ggx_v(float alpha, float n_dot_v, float n_dot_l);
/* The tri-Ace normalisation, 0.0397436 n + 0.0856832 (tri-Ace 2010). */
float ibl_blinn_phong_norm(float shininess);

/* ------------------------------------------------------------------------------------------ */
/* Local probes (src/shade/volumes.c)                                                        */

typedef enum ibl_volume_shape { IBL_VOLUME_SPHERE = 0, IBL_VOLUME_BOX } ibl_volume_shape;

/* An axis-aligned box or a sphere. Influence: weight 1 deeper than blend_distance inside,
 * falling linearly to 0 at the surface (JAGE 2015 / Lagarde 2012 influence volumes). */
typedef struct ibl_volume {
    ibl_volume_shape shape;
    ibl_vec3 center;
    ibl_vec3 half_extent; /* box                       */
    float radius;         /* sphere                    */
    float blend_distance; /* width of the fade region  */
} ibl_volume;

float ibl_volume_size(const ibl_volume *v); /* its volume (for the priority order) */
float ibl_volume_weight(const ibl_volume *v, ibl_vec3 p);

/* Priority blending (the JAGE 2015 article's "Influence Volume"): in the order given
 * (smallest volume first, from ibl_volume_sort) each volume takes
 * weight_i * (1 - sum of the weights before it). weights[i] receives the final weight of
 * volumes[i]; their sum is <= 1 and the rest, returned, belongs to the global (sky) probe. */
float ibl_volume_blend(const ibl_volume *volumes, const int *order, int count, ibl_vec3 p,
                       float *weights);
/* Sorts indices by increasing volume size, ties by index (insertion sort, as the JAGE 2015
 * article does). */
void ibl_volume_sort(const ibl_volume *volumes, int count, int *order);

/* Parallax correction (Lagarde 2012; the JAGE 2015 article): intersect the ray p + t r with
 * the proxy (box or sphere, p inside it) and return the normalised direction from the probe's
 * capture position to the hit. Returns r unchanged when p is outside the proxy. */
ibl_vec3 ibl_parallax_correct(const ibl_volume *proxy, ibl_vec3 probe_position, ibl_vec3 p,
                              ibl_vec3 r);
/* The IBL offset: R' = normalize(c (P_obj - P_IBL) + R) (tri-Ace 2010). */
ibl_vec3 ibl_offset_reflection(ibl_vec3 r, ibl_vec3 p_obj, ibl_vec3 p_ibl, float c);
/* Its coefficient for surroundings at distance environment_radius from the capture point:
 * c = k / environment_radius (k <= 0: 1), the first-order parallax of a sphere of that radius
 * (docs/SHADING.md derives it; tri-Ace 2010 names the IBL's size, the object's size and a
 * hand-tuned coefficient as its inputs without giving the formula, and the object's size drops
 * out of the first order). 0 when environment_radius <= 0. */
float ibl_offset_coefficient(float environment_radius, float k);
/* The shininess hack for punctual lights:
 * shininess' = shininess * saturate(60 / light_size * (1 - attenuation))^2 (tri-Ace 2010). */
float ibl_shininess_hack(float shininess, float light_size, float attenuation);

/* The environment switch (Daqi 2016): weight of the NEW environment for an object of extent
 * `size` centred at `position` crossing the border at `border`, all projected on the line
 * perpendicular to the border and measured toward the new environment:
 * saturate((position - border) / size + 0.5). */
float ibl_environment_switch(float position, float border, float size);

/* Tiled probe culling (the JAGE 2015 article's "Tiled Probe Culling"), on the CPU. */
typedef struct ibl_screen_rect {
    int x0, y0, x1, y1; /* pixels [x0, x1) x [y0, y1); empty if x0 >= x1 or y0 >= y1 */
} ibl_screen_rect;

/* Conservative pixel rectangle of a volume's bounding box under a column-major 4x4
 * view-projection matrix (OpenGL clip space); the whole screen when a corner is behind the
 * eye, empty when the box is outside the frustum. */
ibl_screen_rect ibl_volume_screen_rect(const ibl_volume *v, const float view_proj[16], int width,
                                       int height);

typedef struct ibl_tile_lists {
    int tiles_x, tiles_y, tile_size;
    int *offsets; /* tiles_x * tiles_y + 1 entries: tile t's list is
                     indices[offsets[t] .. offsets[t + 1])                                   */
    int *indices; /* probe indices, each list in priority order (smallest volume first) */
} ibl_tile_lists;

/* Per-tile lists of the probes whose rectangle touches the tile, sorted by `order` (from
 * ibl_volume_sort). Allocates out's arrays (ibl_tile_lists_free). */
ibl_status ibl_tile_probes(ibl_context *ctx, const ibl_screen_rect *rects, const int *order,
                           int count, int width, int height, int tile_size, ibl_tile_lists *out);
void ibl_tile_lists_free(ibl_context *ctx, ibl_tile_lists *lists);

/* ------------------------------------------------------------------------------------------ */
/* Skin (src/shade/skin.c; the offline half is skin.h)                                       */

enum { IBL_SKIN_MAX_GAUSSIANS = 16 };
/* Thickness (mm) that a transmittance map value of 0 stands for (skin.h). */
#define IBL_SKIN_THICKNESS_RANGE_MM 8.0f

/* A diffusion profile as a sum of 2D Gaussians: variance v_i (mm^2) and an RGB weight each. */
typedef struct ibl_skin_profile {
    int count;
    float variance_mm2[IBL_SKIN_MAX_GAUSSIANS];
    float weight[IBL_SKIN_MAX_GAUSSIANS][3];
} ibl_skin_profile;

/* d'Eon and Luebke's six-Gaussian fit of the three-layer skin profile (Donner and Jensen
 * 2005), GPU Gems 3, ch. 14 "Advanced Techniques for Realistic Real-Time Skin Rendering"
 * (2007), its table "sum-of-Gaussians parameters for a three-layer skin model": variances
 * 0.0064, 0.0484, 0.187, 0.567, 1.99, 7.41 mm^2; each channel's weights sum to 1. */
ibl_skin_profile ibl_skin_profile_deon(void);

/* Transmittance through skin of thickness d (mm): T_c(d) = sum_i w_ci exp(-d^2 / v_i), the
 * profile's Gaussians without their normalisation (Jimenez, Whelan, Sundstedt and Gutierrez
 * 2010, "Real-Time Realistic Skin Translucency", IEEE CG&A 30(4)). T(0) = the
 * weights' sums. profile NULL: ibl_skin_profile_deon(). */
void ibl_skin_transmittance(const ibl_skin_profile *profile, float thickness_mm, float out[3]);

typedef struct ibl_skin_surface {
    ibl_vec3 n[3];             /* world-space normals from the red, green and blue scattered
                                  normal maps (unit)                                        */
    ibl_vec3 geometric_normal; /* the surface's own (unit): translucency arrives from -N       */
    float albedo[3];           /* diffuse albedo                                             */
    float transmittance;       /* the map's value t in [0, 1] (skin.h); 0: no translucency   */
    float thickness_range_mm;  /* what t = 0 stands for; 0: IBL_SKIN_THICKNESS_RANGE_MM      */
    float translucency;        /* scale of the translucent term; 0: 1                        */
} ibl_skin_surface;

typedef struct ibl_skin_result {
    float diffuse[3];      /* albedo_c IEM_c(n_c): each channel lit along its own normal      */
    float translucent[3];  /* albedo_c T_c(d) IEM_c(-N) scale                                 */
    float color[3];        /* the sum                                                         */
} ibl_skin_result;

/* Ambient diffuse of skin: channel c of the irradiance (ibl_probe_irradiance, E/pi) read along
 * normal n[c] (Daqi 2016's scattered normals), plus light from behind through a thin region:
 * the irradiance about -N times the profile's transmittance at d = (1 - t) range_mm
 * (Jimenez et al. 2010, with the ambient irradiance E(-N) in place of their punctual light's
 * E_L saturate(0.3 + dot(-N, L)); docs/SKIN.md). profile NULL: d'Eon's. */
void ibl_skin_shade(const ibl_probe *probe, const ibl_skin_profile *profile,
                    const ibl_skin_surface *s, ibl_skin_result *out);

/* ------------------------------------------------------------------------------------------ */
/* The mip atlas of Daqi 2016 (src/shade/atlas.c)                                             */

/* A prefiltered chain in one 2D image: every level as a 3x2 grid of its faces
 * (+X -X +Y / -Y +Z -Z), each face cell with a gutter of `gutter` texels filled from the
 * neighbouring faces; level 0 on top, level 1 below it on the left, and every level >= 2
 * kept at level 2's face size in slots to the right of level 1 and then in rows below
 * (Daqi 2016, 6.1: no level smaller than level 2, so UVs never fall outside a tiny level). */
typedef struct ibl_atlas_layout {
    int width, height;
    int levels;
    int gutter;
    int face_size[IBL_MAX_LEVELS];            /* stored face edge (level 2's for levels >= 2) */
    int x[IBL_MAX_LEVELS], y[IBL_MAX_LEVELS]; /* top-left of each level's 3x2 block   */
} ibl_atlas_layout;

typedef enum ibl_atlas_filter {
    IBL_ATLAS_BILINEAR = 0, /* levels > 2 enlarged by seamless bilinear sampling          */
    IBL_ATLAS_NEAREST       /* enlarged by replication (unpack restores them exactly)     */
} ibl_atlas_filter;

typedef struct ibl_atlas_desc {
    int gutter; /* 0: 1 texel (use -1 for none)                               */
    ibl_atlas_filter filter;
} ibl_atlas_desc;

ibl_status ibl_atlas_plan(int size, int levels, const ibl_atlas_desc *desc, ibl_atlas_layout *out);
/* Packs a chain into a new image (opaque black where no level is). */
ibl_status ibl_atlas_pack(ibl_context *ctx, const ibl_cubemap *chain, const ibl_atlas_desc *desc,
                          ibl_image *out, ibl_atlas_layout *layout);
/* Reads the chain back (levels > 2 box-averaged down to their own size) into a new cube. */
ibl_status ibl_atlas_unpack(ibl_context *ctx, const ibl_image *atlas,
                            const ibl_atlas_layout *layout, int size, ibl_cubemap *out);
/* The coordinate table as one line of JSON (NUL-terminated, ibl_free): {"width", "height",
 * "levels", "gutter", "face_order", "rects": [[x, y, face_size] per level]}, what a bake's
 * manifest.json ("atlas") and the atlas KTX2's key "ibl.atlas" hold (docs/ATLAS.md). */
ibl_status ibl_atlas_layout_to_json(ibl_context *ctx, const ibl_atlas_layout *layout, char **text);
/* Reads one back, refusing a table that is not ibl_atlas_plan's arrangement for its level-0
 * face size, level count and gutter; messages name `name` and the field. */
ibl_status ibl_atlas_layout_from_json(ibl_context *ctx, const char *text, const char *name,
                                      ibl_atlas_layout *out);
/* Atlas UV (u right, v down, in [0, 1]) of a direction on a level: what a shader computes.
 * The face coordinates are clamped to the face, so rounding never reads another cell. */
void ibl_atlas_uv(const ibl_atlas_layout *layout, int level, ibl_vec3 dir, float *u, float *v);
/* Emulates the shader: bilinear in the atlas at the two levels around lod, then linear. */
void ibl_atlas_sample(const ibl_image *atlas, const ibl_atlas_layout *layout, float lod,
                      ibl_vec3 dir, float out[4]);

/* Channel packing (Daqi 2016): metalness R, roughness G, AO B, transmittance A. Missing inputs
 * (NULL) give 0, 1, 1, 0 respectively; present inputs must share one size and their channel 0
 * (red) is used. */
ibl_status ibl_pack_material_channels(ibl_context *ctx, const ibl_image *metalness,
                                      const ibl_image *roughness, const ibl_image *ao,
                                      const ibl_image *transmittance, ibl_image *out);
/* Splits a packed image back into four one-channel images (value in R, G = B = R, A = 1). */
ibl_status ibl_unpack_material_channels(ibl_context *ctx, const ibl_image *packed,
                                        ibl_image out[4]);

#ifdef __cplusplus
}
#endif
#endif
