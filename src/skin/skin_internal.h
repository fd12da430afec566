/* Internal: pieces shared by the skin bakes (src/skin/). */
#ifndef IBL_SKIN_INTERNAL_H
#define IBL_SKIN_INTERNAL_H

#include "ibl/skin.h"

/* The mesh rasterised in UV space: per texel of a w x h map, the index of the triangle whose
 * UV footprint covers the texel's centre, or -1. Fails with a message when the mesh has no
 * texture coordinates. *out is freed with ibl_free. */
ibl_status ibl__skin_rasterize(ibl_context *ctx, const ibl_scene *mesh, int w, int h,
                               int32_t **out);

#endif
