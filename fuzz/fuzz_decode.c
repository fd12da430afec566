/* libFuzzer target for one reader: IBL_FUZZ_DECODER names an ibl__*_decode function, or
 * ibl_decode_any for the dispatcher (sniffing + pixel policy). Built by fuzz/CMakeLists.txt
 * once per reader; the same file replays the corpus in `make test` (replay.c). */
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "fuzz_common.h"
#include "io/io_internal.h"

__attribute__((unused)) static ibl_status ibl_decode_any(ibl_context *ctx, const uint8_t *bytes, size_t size,
                                 const char *name, ibl_texture *out, ibl_file_info *info)
{
    ibl_read_desc rd = {1, 0};
    return ibl_decode_texture(ctx, bytes, size, name, &rd, out, info);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    ibl_context *ctx = fuzz_context();
    if (!ctx) return 0;
    ibl_texture tex;
    ibl_file_info info;
    memset(&tex, 0, sizeof tex);
    ibl_status st = IBL_FUZZ_DECODER(ctx, data, size, "<fuzz>", &tex, &info);
    if (st == IBL_OK) {
        /* touch every texel so that short buffers show up under ASan */
        size_t n = ibl_texture_floats(tex.kind, tex.width, tex.height, tex.depth, tex.levels);
        volatile float sink = 0;
        for (size_t i = 0; i < n; i += 7) sink += tex.data[i];
        (void)sink;
        ibl_texture_free(ctx, &tex);
    } else {
        /* every failure has a message naming the input */
        const char *msg = ibl_context_message(ctx);
        if (strncmp(msg, "<fuzz>", 6) != 0 && st != IBL_ERR_TOO_LARGE && st != IBL_ERR_OUT_OF_MEMORY) {
            /* not a crash, but a contract violation worth finding */
            __builtin_trap();
        }
    }
    return 0;
}
