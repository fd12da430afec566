/* The C side of the astcenc bridge (src/compress/astc_bridge.cpp): astcenc's header is C++
 * only, so the one call into it lives in a small C++ file. Internal. */
#ifndef IBL_COMPRESS_ASTC_BRIDGE_H
#define IBL_COMPRESS_ASTC_BRIDGE_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Encodes (encode = 1) rgba (w x h RGBA floats) into blocks, or decodes blocks into rgba, in
 * the HDR RGB + LDR alpha profile with bw x bh blocks, at astcenc's effort `preset` (0..100),
 * on one thread with its own context. Returns 0, or 1 with a message in err. */
int ibl__astc_codec(int encode, int bw, int bh, float preset, float *rgba, int w, int h,
                    uint8_t *blocks, size_t bytes, char *err, size_t err_size);

#ifdef __cplusplus
}
#endif
#endif
