/* Internal hooks of src/bake/sh.c for the tests. */
#ifndef IBL_SH_INTERNAL_H
#define IBL_SH_INTERNAL_H

#include "ibl/sh.h"

/* Chooses the row-sum code of a plan: 0 the portable C loop, 1 AVX2 + FMA (only taken if the
 * CPU has them). Returns the path now in use. */
int ibl__sh_plan_use_simd(ibl_sh_plan *plan, int simd);

#endif
