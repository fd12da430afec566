/* delete when edge_fixup.c lands: temporary stubs of the edge-fixup interface (the texel
 * centre direction, no post-process), so that this branch links. */
#include "ibl/edge_fixup.h"

#include <string.h>

static const char *const names[] = {"none", "overlap", "overlap2", "bent", "warp"};

const char *ibl_edge_fixup_name(ibl_edge_fixup fixup)
{
    return (unsigned)fixup < 5 ? names[fixup] : "unknown";
}

int ibl_edge_fixup_from_name(const char *name, ibl_edge_fixup *out)
{
    for (int i = 0; name && i < 5; i++)
        if (strcmp(name, names[i]) == 0) {
            *out = (ibl_edge_fixup)i;
            return 1;
        }
    return 0;
}

ibl_vec3 ibl_edge_fixup_texel_direction(ibl_edge_fixup fixup, const ibl_bent_desc *bent, int face,
                                        int n, int x, int y, float blur_radius)
{
    (void)fixup;
    (void)bent;
    (void)blur_radius;
    return ibl_cube_texel_direction(face, n, x, y);
}

ibl_status ibl_edge_fixup_apply(ibl_context *ctx, ibl_edge_fixup fixup, ibl_cubemap *cube,
                                int level)
{
    (void)ctx;
    (void)fixup;
    (void)cube;
    (void)level;
    return IBL_OK;
}

ibl_vec3 ibl_edge_fixup_warp_lookup(ibl_vec3 dir, int n)
{
    (void)n;
    return dir;
}
