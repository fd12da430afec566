/* The batch engine's float-lane kernels four lanes wide (batch_lanes.h): plain C vectors, SSE
 * where the target has it. Every CPU runs these unless src/core/cpu.h allows the eight-lane
 * AVX2 copy; a context created with IBL_KERNELS_PORTABLE always runs these. The four-lane
 * tent weights also serve the double path's tent windows (batch_double.c). */
#define LANES 4
#define LANE_TARGET
#define LANE_KERNELS ibl__eq_lanes_4
#include "batch_lanes.h"

void ibl__eq_tent_weights_4(v4f da, v4f e, v4f dy, v4f ey, v4f h, v4f s_c, v4f s_d, v4f wy[4],
                            v4f wx[4])
{
    lane_tent_weights(da, e, dy, ey, h, s_c, s_d, wy, wx);
}
