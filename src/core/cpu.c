/* CPU feature detection for the vector kernels (see cpu.h). */
#include "core/cpu.h"

#if IBL_HAVE_X86_KERNELS
#include <cpuid.h>
#endif

unsigned ibl__cpu_detect(void)
{
    unsigned features = 0;
#if IBL_HAVE_X86_KERNELS
    /* __builtin_cpu_supports checks the OS's XSAVE support of YMM state for "avx2"; F16C is
     * read from CPUID leaf 1 (ECX bit 29) because clang's builtin has no "f16c" */
    if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma"))
        features |= IBL__CPU_AVX2_FMA;
    unsigned a, b, c, d;
    if (__get_cpuid(1, &a, &b, &c, &d) && (c & (1u << 29))) features |= IBL__CPU_F16C;
#endif
    return features;
}
