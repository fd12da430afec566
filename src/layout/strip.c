/* Strips: the six faces side by side (hstrip, 6:1) or stacked (vstrip, 1:6) in the order
 * +X -X +Y -Y +Z -Z, each stored exactly as in the cube (no rotation):
 *
 *   hstrip:  | +X | -X | +Y | -Y | +Z | -Z |        vstrip: the same cells top to bottom */
#include "layout_internal.h"

int ibl__strip_cell(ibl_layout layout, int face, int *col, int *row, int *rotation)
{
    if (face < 0 || face > 5) return 0;
    if (layout == IBL_LAYOUT_HSTRIP) {
        *col = face;
        *row = 0;
    } else if (layout == IBL_LAYOUT_VSTRIP) {
        *col = 0;
        *row = face;
    } else {
        return 0;
    }
    *rotation = 0;
    return 1;
}

int ibl__cube_layout_grid(ibl_layout layout, int *cols, int *rows)
{
    switch (layout) {
    case IBL_LAYOUT_HCROSS: *cols = 4; *rows = 3; return 1;
    case IBL_LAYOUT_VCROSS: *cols = 3; *rows = 4; return 1;
    case IBL_LAYOUT_HSTRIP: *cols = 6; *rows = 1; return 1;
    case IBL_LAYOUT_VSTRIP: *cols = 1; *rows = 6; return 1;
    default: return 0;
    }
}
