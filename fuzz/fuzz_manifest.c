/* libFuzzer target for the bake manifest reader (what ibl_bake_load parses). */
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "fuzz_common.h"
#include "bake/bake_internal.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    ibl_context *ctx = fuzz_context();
    if (!ctx) return 0;
    ibl_bake_data bake;
    ibl__bake_manifest_files files;
    void *root = NULL;
    ibl_status st = ibl__bake_manifest_parse(ctx, data, size, "<fuzz>", &bake, &files, &root);
    if (st == IBL_OK) {
        /* a chain was described: one to the maximum number of levels, a file to read it from */
        const ibl_specular_info *info = &bake.specular_info;
        if (info->levels < 1 || info->levels > IBL_MAX_LEVELS || !files.specular[0]) __builtin_trap();
        /* every file name is one of the bake's own (never a path) */
        const char *names[] = {files.specular[0], files.specular[1], files.irradiance[0],
                               files.irradiance[1], files.splitsum, files.ambient_brdf};
        for (size_t i = 0; i < sizeof names / sizeof names[0]; i++)
            if (names[i] && (strchr(names[i], '/') || ibl__bake_file_named(names[i]) == IBL__BAKE_FILE_COUNT))
                __builtin_trap();
        ibl__bake_manifest_release(root);
        ibl_bake_free(ctx, &bake);
    } else if (strncmp(ibl_context_message(ctx), "<fuzz>", 6) != 0) {
        __builtin_trap();
    }
    return 0;
}
