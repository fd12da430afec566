/* libFuzzer target for the bake manifest reader (what ibl_probe_load parses). */
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "fuzz_common.h"
#include "shade/probe_internal.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    ibl_context *ctx = fuzz_context();
    if (!ctx) return 0;
    ibl_probe_files files;
    ibl_status st = ibl__probe_parse_manifest(ctx, data, size, "<fuzz>", &files);
    if (st == IBL_OK) {
        /* a mapping was found: it has at least one level and at most the maximum */
        if (files.mapping.levels < 1 || files.mapping.levels > IBL_MAX_LEVELS) __builtin_trap();
    } else if (strncmp(ibl_context_message(ctx), "<fuzz>", 6) != 0) {
        __builtin_trap();
    }
    return 0;
}
