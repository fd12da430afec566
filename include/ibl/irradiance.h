/*
 * ibl/irradiance.h - irradiance environment maps (IEM): the diffuse cubemap.
 *
 * A texel of the result holds, for the normal n through the texel centre,
 *   E(n) / pi = (1/pi) * integral of L(w) max(0, n.w) dw        (default, IBL_IRRADIANCE_SCALE_OVER_PI)
 * i.e. the radiance reflected by a white Lambertian surface, or E(n) itself
 * (IBL_IRRADIANCE_SCALE_FULL). Alpha is 1. docs/DIFFUSE.md has the design and measured errors.
 *
 * Methods:
 *  - CONVOLVE (default; tri-Ace 2010 "Generate IEM (2)"): the radiance is reduced area-correctly
 *    to a small cube (8x8x6 by default) and convolved directly with exact texel solid angles.
 *    Each output texel's weights are normalised to sum to 1 (times pi for FULL), so a constant
 *    environment gives exactly that constant.
 *  - REFERENCE: the same sum over every texel of the full-resolution source, in double.
 *  - SH: project on SH (3 bands by default), convolve with the clamped cosine, evaluate.
 */
#ifndef IBL_IRRADIANCE_H
#define IBL_IRRADIANCE_H

#include "core.h"
#include "sh.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum ibl_irradiance_method {
    IBL_IRRADIANCE_CONVOLVE = 0,
    IBL_IRRADIANCE_SH,
    IBL_IRRADIANCE_REFERENCE
} ibl_irradiance_method;

typedef enum ibl_irradiance_scale {
    IBL_IRRADIANCE_SCALE_OVER_PI = 0, /* E / pi: multiply by albedo in the shader */
    IBL_IRRADIANCE_SCALE_FULL         /* E                                        */
} ibl_irradiance_scale;

typedef struct ibl_irradiance_desc {
    int size;                    /* output face edge; 0: 16; at most 64                    */
    ibl_irradiance_method method;
    ibl_irradiance_scale scale;
    int source_size;             /* CONVOLVE: reduced radiance edge; 0: 8; at most 64     */
    int sh_bands;                /* SH: 1..5; 0: 3                                         */
    ibl_sh_window sh_window;     /* SH: windowing of the radiance coefficients             */
    double sh_window_width;      /* SH: W of a Hanning window                              */
} ibl_irradiance_desc;

/* Makes the irradiance cubemap of level 0 of src (allocated into out, one level). desc may be
 * NULL for every default. Bit-identical at any thread count. */
ibl_status ibl_irradiance_cubemap(ibl_context *ctx, const ibl_cubemap *src,
                                  const ibl_irradiance_desc *desc, ibl_cubemap *out);


/* The dynamic path: plan once for (source edge, output edge, scale), then convolve a small
 * radiance cube every frame with no allocation and no threads (it is a few hundred
 * microseconds; run several plans on your own threads if needed). */
typedef struct ibl_irradiance_plan_desc {
    int source_size;            /* edge of the radiance cubes run gets; 1..64 (required)  */
    int size;                   /* output face edge; 1..64 (required)                     */
    ibl_irradiance_scale scale;
} ibl_irradiance_plan_desc;

typedef struct ibl_irradiance_plan ibl_irradiance_plan;
ibl_status ibl_irradiance_plan_create(ibl_context *ctx, const ibl_irradiance_plan_desc *desc,
                                      ibl_irradiance_plan **out);
/* Level 0 of src (edge source_size) into level 0 of dst (edge size); allocates nothing. */
ibl_status ibl_irradiance_plan_run(const ibl_irradiance_plan *plan, const ibl_cubemap *src,
                                   ibl_cubemap *dst);
/* Number of non-zero weights the plan holds (taps per frame = this many). */
size_t ibl_irradiance_plan_taps(const ibl_irradiance_plan *plan);
void ibl_irradiance_plan_destroy(ibl_irradiance_plan *plan);

#ifdef __cplusplus
}
#endif
#endif
