/* Coverage-aware prefiltering and blending of captures (docs/PROBES.md "Premultiplied"). The
 * capture's RGB is premultiplied by its coverage, so any linear filter applied to RGB and A
 * alike keeps the pair consistent: prefiltering spreads uncovered directions' weight as
 * alpha < 1 without bleeding black into the light, and the run-time blend hands that weight
 * to the next probe (the JAGE 2015 article's alpha, used as a weight). The chain filter is the
 * library's (ibl_specular_prefilter); alpha is filtered in a second pass as a grey image, so
 * the result does not depend on what the prefilter does with its input's alpha channel. */
#include "ibl/probes.h"
#include "ibl/specular.h"
#include "core/context_internal.h"

#include <string.h>

ibl_status ibl_capture_prefilter(ibl_context *ctx, const ibl_cubemap *capture,
                                 const char *preset, ibl_cubemap *out)
{
    if (!ctx || !capture || !out) return IBL_ERR_INVALID_ARGUMENT;
    ibl_specular_desc d;
    memset(&d, 0, sizeof d);
    if (!ibl_specular_preset(preset ? preset : "gltf", &d))
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "unknown preset \"%s\"", preset);
    d.size = capture->size;
    ibl_cubemap grey;
    ibl_status st = ibl_cubemap_alloc(ctx, capture->size, 1, &grey);
    if (st != IBL_OK) return st;
    size_t n = (size_t)6 * capture->size * capture->size;
    for (size_t i = 0; i < n; i++) {
        float a = capture->data[4 * i + 3];
        grey.data[4 * i] = grey.data[4 * i + 1] = grey.data[4 * i + 2] = a;
        grey.data[4 * i + 3] = 1.0f;
    }
    ibl_cubemap alpha;
    st = ibl_specular_prefilter(ctx, capture, &d, out, NULL);
    if (st == IBL_OK) st = ibl_specular_prefilter(ctx, &grey, &d, &alpha, NULL);
    ibl_cubemap_free(ctx, &grey);
    if (st != IBL_OK) {
        ibl_cubemap_free(ctx, out);
        return st;
    }
    size_t total = ibl_cubemap_floats(out->size, out->levels) / 4;
    for (size_t i = 0; i < total; i++) out->data[4 * i + 3] = alpha.data[4 * i];
    ibl_cubemap_free(ctx, &alpha);
    return IBL_OK;
}

float ibl_capture_blend(const float (*rgba)[4], const float *weights, int count,
                        const float global_rgb[3], float out[3])
{
    float remaining = 1.0f;
    out[0] = out[1] = out[2] = 0.0f;
    for (int i = 0; i < count && remaining > 0.0f; i++) {
        float w = weights[i] < 0.0f ? 0.0f : (weights[i] > 1.0f ? 1.0f : weights[i]);
        float c = w * remaining;
        for (int k = 0; k < 3; k++) out[k] += c * rgba[i][k];
        float a = rgba[i][3] < 0.0f ? 0.0f : (rgba[i][3] > 1.0f ? 1.0f : rgba[i][3]);
        remaining -= c * a;
    }
    if (remaining < 0.0f) remaining = 0.0f;
    for (int k = 0; k < 3; k++) out[k] += remaining * global_rgb[k];
    return remaining;
}
