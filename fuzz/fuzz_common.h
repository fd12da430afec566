/* What every fuzz target shares: one single-threaded context with a small allocation limit, so
 * that huge declared sizes are refused instead of exhausting memory. */
#ifndef IBL_FUZZ_COMMON_H
#define IBL_FUZZ_COMMON_H

#include <string.h>

#include "ibl/ibl.h"

static inline ibl_context *fuzz_context(void)
{
    static ibl_context *ctx;
    if (!ctx) {
        ibl_context_desc d;
        memset(&d, 0, sizeof d);
        d.threads = 1;
        d.max_bytes = (uint64_t)256 << 20;
        if (ibl_context_create(&d, &ctx) != IBL_OK) return NULL;
    }
    return ctx;
}

#endif
