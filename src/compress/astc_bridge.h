/* The C side of the astcenc bridge (src/compress/astc_bridge.cpp): astcenc's header is C++
 * only, so the calls into it live in a small C++ file. Internal. */
#ifndef IBL_COMPRESS_ASTC_BRIDGE_H
#define IBL_COMPRESS_ASTC_BRIDGE_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Encodes rgba (w x h RGBA floats) into blocks in the HDR RGB + LDR alpha profile with
 * bw x bh blocks, at astcenc's effort `preset` (0..100), on one thread with its own context.
 * Returns 0, or 1 with a message in err. */
int ibl__astc_encode_image(int bw, int bh, float preset, float *rgba, int w, int h,
                           uint8_t *blocks, size_t bytes, char *err, size_t err_size);

/* A decompress-only astcenc context for bw x bh blocks in the same profile, for one thread at
 * a time; it may decode any number of images one after another. NULL with a message in err. */
typedef struct ibl__astc_decoder ibl__astc_decoder;
ibl__astc_decoder *ibl__astc_decoder_create(int bw, int bh, char *err, size_t err_size);
void ibl__astc_decoder_free(ibl__astc_decoder *decoder);
/* Decodes blocks into rgba (w x h RGBA floats). Returns 0, or 1 with a message in err. */
int ibl__astc_decoder_run(ibl__astc_decoder *decoder, const uint8_t *blocks, size_t bytes,
                          float *rgba, int w, int h, char *err, size_t err_size);

#ifdef __cplusplus
}
#endif
#endif
