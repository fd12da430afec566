/* Internal: the one place that decides which vector kernels run. Every module with an AVX2
 * path asks ibl__cpu_features(ctx) and takes the portable C path when its bits are missing;
 * a context created with IBL_KERNELS_PORTABLE reports none, which is how the tests compare
 * the two paths. */
#ifndef IBL_CORE_CPU_H
#define IBL_CORE_CPU_H

#include "ibl/core.h"

enum {
    IBL__CPU_AVX2_FMA = 1u << 0, /* AVX2 and FMA3 (and the OS saves the YMM registers) */
    IBL__CPU_F16C = 1u << 1      /* half <-> float conversion instructions             */
};

/* What this CPU offers, detected once per call (cheap; contexts cache it). */
unsigned ibl__cpu_detect(void);
/* The features the context lets kernels use: ibl__cpu_detect() unless the context asked for
 * IBL_KERNELS_PORTABLE (then 0). NULL: detected features. */
unsigned ibl__cpu_features(const ibl_context *ctx);
/* All of `wanted` available? */
static inline int ibl__cpu_has(const ibl_context *ctx, unsigned wanted)
{
    return (ibl__cpu_features(ctx) & wanted) == wanted;
}

/* The function attribute of AVX2 kernels (GCC and Clang on x86-64). */
#if defined(__GNUC__) && defined(__x86_64__)
#define IBL_HAVE_X86_KERNELS 1
#define IBL_TARGET_AVX2 __attribute__((target("avx2,fma,f16c")))
#else
#define IBL_HAVE_X86_KERNELS 0
#define IBL_TARGET_AVX2
#endif

#endif
