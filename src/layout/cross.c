/* Horizontal (4:3) and vertical (3:4) crosses, the arrangement of CubeMapGen and cmft.
 *
 *   hcross (4 x 3 cells)        vcross (3 x 4 cells)
 *        +Y                          +Y
 *    -X  +Z  +X  -Z              -X  +Z  +X
 *        -Y                          -Y
 *                                    -Z   (turned 180 degrees)
 *
 * Every face is stored as in the cube (texel (x, y) of the face is pixel (x, y) of its cell),
 * except -Z in the vertical cross, which is turned by 180 degrees so that its edge shared with
 * -Y touches -Y in the picture. With the OpenGL/KTX2 face orientation the cells then join
 * seamlessly across every edge drawn in the figures. */
#include "layout_internal.h"

int ibl__cross_cell(ibl_layout layout, int face, int *col, int *row, int *rotation)
{
    /* column, row of each face in the order +X -X +Y -Y +Z -Z */
    static const int h[6][2] = {{2, 1}, {0, 1}, {1, 0}, {1, 2}, {1, 1}, {3, 1}};
    static const int v[6][2] = {{2, 1}, {0, 1}, {1, 0}, {1, 2}, {1, 1}, {1, 3}};
    if (face < 0 || face > 5) return 0;
    if (layout == IBL_LAYOUT_HCROSS) {
        *col = h[face][0];
        *row = h[face][1];
        *rotation = 0;
        return 1;
    }
    if (layout == IBL_LAYOUT_VCROSS) {
        *col = v[face][0];
        *row = v[face][1];
        *rotation = face == IBL_FACE_NEG_Z ? 180 : 0;
        return 1;
    }
    return 0;
}
