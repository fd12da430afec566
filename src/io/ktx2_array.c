/* KTX 2.0 cube-map arrays (KTX File Format Specification 2.0, section 3.4: layerCount > 0 and
 * faceCount 6 make a cube-map array; a level's data is every layer's six faces in order
 * layer, face, row). Kept apart from ktx2.c on purpose: both directions go through the one-cube
 * encoder and decoder there and only splice bytes, so the single-texture code path is
 * untouched. Writing: each layer is encoded as a cube, then the files' level images are
 * concatenated per level (smallest level first, each level aligned as ktx2.c aligns it) under
 * the first layer's header, DFD and key/value data, with layerCount = N. Reading: for each
 * layer a copy of the file whose header says "not an array" and whose level index points at
 * that layer's slice of each level goes through the ordinary decoder (which checks it). */
#include <string.h>

#include "core/context_internal.h"
#include "core/pixel_format.h"
#include "io/container.h"
#include "io/io_internal.h"

enum { A_HEADER = 80, A_ENTRY = 24, A_LAYERS = 32, A_FACES = 36, A_LEVELS = 40 };

static size_t align_of(size_t texel)
{
    size_t a = texel, b = 4; /* lcm(texel, 4), as ktx2.c */
    while (b) {
        size_t t = a % b;
        a = b;
        b = t;
    }
    return texel / a * 4;
}

ibl_status ibl_encode_cube_array(ibl_context *ctx, const ibl_cubemap *layers, int count,
                                 const ibl_key_value *metadata, int metadata_count,
                                 const ibl_write_desc *desc, void **bytes, size_t *size)
{
    *bytes = NULL;
    *size = 0;
    if (count < 1 || !layers) return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "cube array: no layers");
    for (int i = 1; i < count; i++)
        if (layers[i].size != layers[0].size || layers[i].levels != layers[0].levels)
            return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                             "cube array: layer %d is %dx%d with %d levels, layer 0 %dx%d with %d",
                             i, layers[i].size, layers[i].size, layers[i].levels, layers[0].size,
                             layers[0].size, layers[0].levels);
    uint8_t **enc = ibl_alloc(ctx, sizeof *enc * (size_t)count);
    size_t *enc_size = ibl_alloc(ctx, sizeof *enc_size * (size_t)count);
    if (!enc || !enc_size) {
        ibl_free(ctx, enc);
        ibl_free(ctx, enc_size);
        return ibl_context_status(ctx);
    }
    memset(enc, 0, sizeof *enc * (size_t)count);
    ibl_status st = IBL_OK;
    for (int i = 0; i < count && st == IBL_OK; i++) {
        ibl_texture tex = ibl_texture_from_cubemap(&layers[i]);
        tex.metadata = (ibl_key_value *)metadata;
        tex.metadata_count = i == 0 ? metadata_count : 0;
        void *b = NULL;
        st = ibl__ktx2_encode(ctx, &tex, desc, "cube array", &b, &enc_size[i]);
        enc[i] = b;
    }
    if (st == IBL_OK) {
        const uint8_t *h = enc[0];
        int levels = (int)ibl__rd32(h + A_LEVELS);
        size_t texel = ibl_format_texel_bytes(desc && desc->format ? desc->format : IBL_FORMAT_RGBA16F);
        size_t align = align_of(texel);
        /* the head: everything before the smallest level's image in layer 0's file */
        size_t head = (size_t)ibl__rd64(h + A_HEADER + A_ENTRY * (size_t)(levels - 1));
        size_t off[IBL_MAX_LEVELS], len[IBL_MAX_LEVELS], total = head;
        for (int l = levels - 1; l >= 0; l--) {
            total = (total + align - 1) / align * align;
            off[l] = total;
            len[l] = (size_t)ibl__rd64(h + A_HEADER + A_ENTRY * (size_t)l + 8) * (size_t)count;
            total += len[l];
        }
        uint8_t *out = ibl_alloc(ctx, total);
        if (!out) {
            st = ibl_context_status(ctx);
        } else {
            memset(out, 0, total);
            memcpy(out, h, head);
            ibl__wr32(out + A_LAYERS, (uint32_t)count);
            for (int l = 0; l < levels; l++) {
                uint8_t *e = out + A_HEADER + A_ENTRY * (size_t)l;
                ibl__wr64(e, off[l]);
                ibl__wr64(e + 8, len[l]);
                ibl__wr64(e + 16, len[l]);
                size_t one = len[l] / (size_t)count;
                for (int i = 0; i < count; i++) {
                    size_t src = (size_t)ibl__rd64(enc[i] + A_HEADER + A_ENTRY * (size_t)l);
                    memcpy(out + off[l] + one * (size_t)i, enc[i] + src, one);
                }
            }
            *bytes = out;
            *size = total;
        }
    }
    for (int i = 0; i < count; i++) ibl_free(ctx, enc[i]);
    ibl_free(ctx, enc);
    ibl_free(ctx, enc_size);
    return st;
}

ibl_status ibl_decode_cube_array(ibl_context *ctx, const void *bytes, size_t size, const char *name,
                                 ibl_cubemap **layers_out, int *count_out, ibl_texture *meta)
{
    *layers_out = NULL;
    *count_out = 0;
    const uint8_t *b = bytes;
    if (size < A_HEADER || ibl__rd32(b + A_FACES) != 6)
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: not a KTX2 cube-map array", name);
    uint32_t count = ibl__rd32(b + A_LAYERS), levels = ibl__rd32(b + A_LEVELS);
    if (levels == 0) levels = 1;
    if (count == 0 || count > 65536 || levels > IBL_MAX_LEVELS ||
        size < A_HEADER + (size_t)A_ENTRY * levels)
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: layerCount %u, levelCount %u: not a cube-map array "
                         "this reader takes", name, count, levels);
    for (uint32_t l = 0; l < levels; l++)
        if (ibl__rd64(b + A_HEADER + A_ENTRY * l + 8) % count != 0)
            return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: level %u's length is not a multiple of %u "
                             "layers", name, l, count);
    uint8_t *copy = ibl_alloc(ctx, size);
    ibl_cubemap *layers = ibl_alloc(ctx, sizeof *layers * count);
    if (!copy || !layers) {
        ibl_free(ctx, copy);
        ibl_free(ctx, layers);
        return ibl_context_status(ctx);
    }
    memset(layers, 0, sizeof *layers * count);
    memcpy(copy, b, size);
    ibl__wr32(copy + A_LAYERS, 0);
    ibl_status st = IBL_OK;
    for (uint32_t i = 0; i < count && st == IBL_OK; i++) {
        for (uint32_t l = 0; l < levels; l++) {
            const uint8_t *e = b + A_HEADER + A_ENTRY * l;
            uint64_t one = ibl__rd64(e + 8) / count;
            uint8_t *c = copy + A_HEADER + A_ENTRY * l;
            ibl__wr64(c, ibl__rd64(e) + one * i);
            ibl__wr64(c + 8, one);
            ibl__wr64(c + 16, one);
        }
        ibl_texture tex;
        st = ibl__ktx2_decode(ctx, copy, size, name, &tex, NULL);
        if (st != IBL_OK) break;
        ibl_cubemap view;
        st = ibl_cubemap_from_texture(&tex, &view);
        if (st == IBL_OK) st = ibl_cubemap_alloc(ctx, view.size, view.levels, &layers[i]);
        if (st == IBL_OK)
            memcpy(layers[i].data, view.data, ibl_cubemap_floats(view.size, view.levels) * sizeof(float));
        if (st == IBL_OK && i == 0 && meta) {
            *meta = tex; /* keeps the metadata; the texels go */
            if (meta->owns_data) ibl_free(ctx, meta->data);
            meta->data = NULL;
            meta->owns_data = 0;
        } else {
            ibl_texture_free(ctx, &tex);
        }
    }
    ibl_free(ctx, copy);
    if (st != IBL_OK) {
        for (uint32_t i = 0; i < count; i++) ibl_cubemap_free(ctx, &layers[i]);
        ibl_free(ctx, layers);
        if (meta && meta->metadata) ibl_texture_free(ctx, meta);
        return st;
    }
    *layers_out = layers;
    *count_out = (int)count;
    return IBL_OK;
}
