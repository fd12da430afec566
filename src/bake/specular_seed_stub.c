/* delete when specular_box.c lands: temporary stubs for the seed kernels of the edge-fixup
 * helper's branch, so that this branch links. */
#include "specular_internal.h"

ibl_status ibl__specular_box(ibl_context *ctx, const ibl_cubemap *src, ibl_cubemap *dst)
{
    (void)src;
    (void)dst;
    return ibl_fail(ctx, IBL_ERR_UNSUPPORTED, "prefilter: the box kernel is not built in yet");
}

ibl_status ibl__specular_gauss(ibl_context *ctx, const ibl_cubemap *src, ibl_cubemap *dst,
                               const float *shininess_per_level)
{
    (void)src;
    (void)dst;
    (void)shininess_per_level;
    return ibl_fail(ctx, IBL_ERR_UNSUPPORTED, "prefilter: the gauss kernel is not built in yet");
}
