/* Internal: how library code reports failures and progress through the context. */
#ifndef IBL_CORE_CONTEXT_INTERNAL_H
#define IBL_CORE_CONTEXT_INTERNAL_H

#include "ibl/core.h"

/* Records a printf-style failure message in the context and returns status. */
ibl_status ibl__fail(ibl_context *ctx, ibl_status status, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
/* A copy of s allocated through the context (NULL for NULL s, or on failure with the
 * context's message set). */
char *ibl__strdup(ibl_context *ctx, const char *s);
/* Reports progress; returns IBL_ERR_CANCELLED (with a message) if the host asked to stop. */
ibl_status ibl__progress(ibl_context *ctx, const char *stage, double fraction);

#endif
