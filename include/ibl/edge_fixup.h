/*
 * ibl/edge_fixup.h - cube edge fixups for hardware without seamless cube filtering
 * (the tri-Ace talk's "Edge overlapping" (1)-(2), "Bent Phong filter kernel"; the
 * NVTT/cmft "warp" with its shader-side lookup). shaders/ibl.glsl and ibl.hlsl have the shader side.
 *
 * Two kinds of fixup:
 *  - post-processes of a filtered level (overlap, overlap2): ibl_edge_fixup_apply;
 *  - changes of the direction a texel is filtered around (bent, warp):
 *    ibl_edge_fixup_texel_direction, called by the prefilter for every output texel.
 */
#ifndef IBL_EDGE_FIXUP_H
#define IBL_EDGE_FIXUP_H

#include "core.h"
#include "cubemap.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum ibl_edge_fixup {
    IBL_EDGE_FIXUP_NONE = 0, /* modern APIs filter across faces: nothing to do          */
    IBL_EDGE_FIXUP_OVERLAP,  /* blend the two edge texels 50%: equal across the edge    */
    IBL_EDGE_FIXUP_OVERLAP2, /* blend two texels deep with 1/4 and 3/4                  */
    IBL_EDGE_FIXUP_BENT,     /* bent Phong kernel: bend the filter direction            */
    IBL_EDGE_FIXUP_WARP      /* stretch texel directions so edge texels coincide        */
} ibl_edge_fixup;

const char *ibl_edge_fixup_name(ibl_edge_fixup fixup); /* "none", "overlap", ... */
/* Returns 0 and leaves *out unchanged for unknown names. */
int ibl_edge_fixup_from_name(const char *name, ibl_edge_fixup *out);

typedef struct ibl_bent_desc {
    float small_radius_fraction; /* fraction of the target angle for small blur radii; 0: 0.5 */
    float large_radius_fraction; /* ... for large blur radii; 0: 1.0                          */
    float large_radius;          /* blur radius (radians) where the large fraction is reached; 0: 0.5 */
} ibl_bent_desc;

/* The (normalised) direction the prefilter should centre its kernel on for texel (x, y) of a
 * face of edge n, for a kernel of angular radius blur_radius (radians, e.g. the angle where
 * the lobe falls to half). NONE, OVERLAP and OVERLAP2 return the texel centre direction.
 * Returns (0, 0, 0) for a face, n or texel out of range. */
ibl_vec3 ibl_edge_fixup_texel_direction(ibl_edge_fixup fixup, const ibl_bent_desc *bent, int face,
                                        int n, int x, int y, float blur_radius);

/* Post-process of one level in place (OVERLAP, OVERLAP2). For every method but NONE a 1x1
 * level becomes the mean of its six faces (a 1x1 face has no direction to bend or warp);
 * BENT and WARP change nothing on larger levels. Call it on every level after filtering. */
ibl_status ibl_edge_fixup_apply(ibl_context *ctx, ibl_edge_fixup fixup, ibl_cubemap *cube,
                                int level);

/* The warp's lookup: maps a direction to the one a shader must sample on a level of edge n
 * so that texel centres of warped levels are hit (shaders/ibl.glsl: its GLSL twin). */
ibl_vec3 ibl_edge_fixup_warp_lookup(ibl_vec3 dir, int n);

#ifdef __cplusplus
}
#endif
#endif
