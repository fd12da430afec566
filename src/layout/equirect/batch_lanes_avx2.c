/* The batch engine's float-lane kernels eight lanes wide in AVX2 registers (batch_lanes.h),
 * chosen at run time by to_cube.c where src/core/cpu.h reports AVX2 and FMA. They give the
 * same bits as the four-lane copy: the same float operations in the same order, and no fused
 * multiply-adds although the target allows them (GCC does not contract in ISO C mode, the
 * build's -std=c11; Clang is told so below). */
#include "equirect_internal.h"

#if EQ_HAVE_LANES_8
#if defined(__clang__)
#pragma STDC FP_CONTRACT OFF
#endif
#define LANES 8
#define LANE_TARGET IBL_TARGET_AVX2
#define LANE_KERNELS ibl__eq_lanes_8
#include "batch_lanes.h"
#else
/* (no eight-lane code on this compiler or target: an empty unit needs a declaration) */
typedef int eq_no_eight_lanes;
#endif
