// ASTC HDR through ARM's astcenc (Debian libastcenc-dev 4.2): the C++ half of the bridge in
// astc_bridge.h. One single-threaded context per call: the output depends only on the texels.
#include <astcenc.h>

#include <cstdio>

#include "compress/astc_bridge.h"

extern "C" int ibl__astc_codec(int encode, int bw, int bh, float preset, float *rgba, int w,
                               int h, uint8_t *blocks, size_t bytes, char *err, size_t err_size)
{
    astcenc_config config;
    unsigned flags = encode ? 0u : ASTCENC_FLG_DECOMPRESS_ONLY;
    astcenc_error e = astcenc_config_init(ASTCENC_PRF_HDR_RGB_LDR_A, (unsigned)bw, (unsigned)bh,
                                          1, preset, flags, &config);
    astcenc_context *context = nullptr;
    if (e == ASTCENC_SUCCESS) e = astcenc_context_alloc(&config, 1, &context);
    if (e == ASTCENC_SUCCESS) {
        const astcenc_swizzle swizzle = {ASTCENC_SWZ_R, ASTCENC_SWZ_G, ASTCENC_SWZ_B, ASTCENC_SWZ_1};
        void *slices[1] = {rgba};
        astcenc_image image = {(unsigned)w, (unsigned)h, 1, ASTCENC_TYPE_F32, slices};
        e = encode ? astcenc_compress_image(context, &image, &swizzle, blocks, bytes, 0)
                   : astcenc_decompress_image(context, blocks, bytes, &image, &swizzle, 0);
    }
    if (context) astcenc_context_free(context);
    if (e == ASTCENC_SUCCESS) return 0;
    std::snprintf(err, err_size, "astcenc: %s", astcenc_get_error_string(e));
    return 1;
}
