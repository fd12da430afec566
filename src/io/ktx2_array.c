/* KTX 2.0 cube-map arrays from and to separate cubes (KTX File Format Specification 2.0,
 * section 3.4: layerCount > 0 and faceCount 6 make a cube-map array; a level's data is every
 * layer's six faces in order layer, face, row), for callers that hold one cube per layer (the
 * probe-array bake). Both directions go through the ordinary KTX2 encoder and decoder with an
 * IBL_TEXTURE_CUBE_ARRAY texture, so every storage format and Zstandard work for arrays as
 * for single cubes; the price is one float copy of the layers. */
#include <string.h>

#include "core/context_internal.h"
#include "io/container.h"
#include "io/io_internal.h"

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
    ibl_texture tex;
    ibl_status st = ibl_texture_alloc(ctx, IBL_TEXTURE_CUBE_ARRAY, layers[0].size, layers[0].size,
                                      count, layers[0].levels, &tex);
    if (st != IBL_OK) return st;
    for (int l = 0; l < tex.levels; l++) {
        size_t n = (size_t)ibl_level_size(tex.width, l);
        for (int i = 0; i < count; i++)
            memcpy(ibl_texture_level(&tex, l, 6 * i), ibl_cubemap_face(&layers[i], l, 0),
                   6 * n * n * 4 * sizeof(float));
    }
    tex.metadata = (ibl_key_value *)metadata;
    tex.metadata_count = metadata ? metadata_count : 0;
    st = ibl__ktx2_encode(ctx, &tex, desc, "cube array", bytes, size);
    tex.metadata = NULL;
    tex.metadata_count = 0;
    ibl_texture_free(ctx, &tex);
    return st;
}

ibl_status ibl_decode_cube_array(ibl_context *ctx, const void *bytes, size_t size, const char *name,
                                 ibl_cubemap **layers_out, int *count_out, ibl_texture *meta)
{
    *layers_out = NULL;
    *count_out = 0;
    ibl_texture tex;
    ibl_status st = ibl__ktx2_decode(ctx, bytes, size, name, &tex, NULL);
    if (st != IBL_OK) return st;
    if (tex.kind != IBL_TEXTURE_CUBE_ARRAY) {
        ibl_texture_free(ctx, &tex);
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: not a KTX2 cube-map array", name);
    }
    int count = tex.depth;
    ibl_cubemap *layers = ibl_calloc(ctx, (size_t)count, sizeof *layers);
    for (int i = 0; layers && i < count && st == IBL_OK; i++) {
        st = ibl_cubemap_alloc(ctx, tex.width, tex.levels, &layers[i]);
        /* a level holds every layer's six faces in turn; a cube, its own six */
        for (int l = 0; st == IBL_OK && l < tex.levels; l++) {
            size_t n = (size_t)ibl_level_size(tex.width, l);
            memcpy(ibl_cubemap_face(&layers[i], l, 0), ibl_texture_level(&tex, l, 6 * i),
                   6 * n * n * 4 * sizeof(float));
        }
    }
    if (!layers) st = ibl_context_status(ctx);
    if (st != IBL_OK) {
        for (int i = 0; layers && i < count; i++) ibl_cubemap_free(ctx, &layers[i]);
        ibl_free(ctx, layers);
        ibl_texture_free(ctx, &tex);
        return st;
    }
    if (meta) {
        *meta = tex; /* keeps the metadata; the texels go */
        if (meta->owns_data) ibl_free(ctx, meta->data);
        meta->data = NULL;
        meta->owns_data = 0;
    } else {
        ibl_texture_free(ctx, &tex);
    }
    *layers_out = layers;
    *count_out = count;
    return IBL_OK;
}
