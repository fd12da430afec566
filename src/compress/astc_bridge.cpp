// ASTC HDR through ARM's astcenc (Debian libastcenc-dev 4.2): the C++ half of the bridge in
// astc_bridge.h. Every context is single-threaded: the output depends only on the texels.
#include <astcenc.h>

#include <cstdio>
#include <new>

#include "compress/astc_bridge.h"

// The texels are RGBA; alpha is stored as LDR and read back as 1 (ASTC HDR probes carry RGB).
static const astcenc_swizzle rgb1 = {ASTCENC_SWZ_R, ASTCENC_SWZ_G, ASTCENC_SWZ_B, ASTCENC_SWZ_1};

static int report(astcenc_error e, char *err, size_t err_size)
{
    if (e == ASTCENC_SUCCESS) return 0;
    std::snprintf(err, err_size, "astcenc: %s", astcenc_get_error_string(e));
    return 1;
}

static astcenc_error make_context(int bw, int bh, float preset, unsigned flags, astcenc_context **out)
{
    astcenc_config config;
    *out = nullptr;
    astcenc_error e = astcenc_config_init(ASTCENC_PRF_HDR_RGB_LDR_A, (unsigned)bw, (unsigned)bh, 1,
                                          preset, flags, &config);
    if (e == ASTCENC_SUCCESS) e = astcenc_context_alloc(&config, 1, out);
    return e;
}

extern "C" int ibl__astc_encode_image(int bw, int bh, float preset, float *rgba, int w, int h,
                                      uint8_t *blocks, size_t bytes, char *err, size_t err_size)
{
    astcenc_context *context;
    astcenc_error e = make_context(bw, bh, preset, 0u, &context);
    if (e == ASTCENC_SUCCESS) {
        void *slices[1] = {rgba};
        astcenc_image image = {(unsigned)w, (unsigned)h, 1, ASTCENC_TYPE_F32, slices};
        e = astcenc_compress_image(context, &image, &rgb1, blocks, bytes, 0);
    }
    if (context) astcenc_context_free(context);
    return report(e, err, err_size);
}

// The decoder is astcenc's context itself; the struct name only gives C a distinct type.
struct ibl__astc_decoder {
    astcenc_context *context;
};

extern "C" ibl__astc_decoder *ibl__astc_decoder_create(int bw, int bh, char *err, size_t err_size)
{
    // The preset only steers compression; a decompress-only context ignores it.
    astcenc_context *context;
    astcenc_error e = make_context(bw, bh, 0.0f, ASTCENC_FLG_DECOMPRESS_ONLY, &context);
    if (e != ASTCENC_SUCCESS) {
        if (context) astcenc_context_free(context);
        report(e, err, err_size);
        return nullptr;
    }
    ibl__astc_decoder *decoder = new (std::nothrow) ibl__astc_decoder{context};
    if (!decoder) {
        astcenc_context_free(context);
        std::snprintf(err, err_size, "astcenc: out of memory");
    }
    return decoder;
}

extern "C" void ibl__astc_decoder_free(ibl__astc_decoder *decoder)
{
    if (!decoder) return;
    astcenc_context_free(decoder->context);
    delete decoder;
}

extern "C" int ibl__astc_decoder_run(ibl__astc_decoder *decoder, const uint8_t *blocks, size_t bytes,
                                     float *rgba, int w, int h, char *err, size_t err_size)
{
    void *slices[1] = {rgba};
    astcenc_image image = {(unsigned)w, (unsigned)h, 1, ASTCENC_TYPE_F32, slices};
    astcenc_error e = astcenc_decompress_image(decoder->context, blocks, bytes, &image, &rgb1, 0);
    // astcenc's work queue for the image is spent: reset it so the next image is decoded in
    // full (optional for one thread in astcenc 4.2, kept so that this holds whatever the version)
    astcenc_error r = astcenc_decompress_reset(decoder->context);
    return report(e != ASTCENC_SUCCESS ? e : r, err, err_size);
}
