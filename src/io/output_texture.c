/* A texture file of an output set written level by level (ibl_output_set_begin_texture): the
 * KTX2 is laid out from the texture's shape before any texel exists (ibl__ktx2_layout_make),
 * so each level's image has its place in the file from the start, and a level given early
 * -- a chain's mirror level, which is its source, while the other levels are still being
 * filtered -- is encoded and written, and on its way to the disk, before the rest exists.
 * The header comes last, with the flush. The file holds the bytes ibl_output_set_add_texture
 * writes for the same texture: the same head, the same encoders, zeros between the levels
 * (the file is sized first, so what no level covers reads as zeros). */
#define _GNU_SOURCE /* sync_file_range */
#include "io/io_internal.h"
#include "io/container.h"
#include "core/context_internal.h"

#include <errno.h>
#include <fcntl.h>
#include <stdatomic.h>
#include <string.h>
#include <unistd.h>

struct ibl_output_texture {
    ibl_output_set *set;
    ibl_context *ctx;
    char *path;
    int index, fd; /* the set's file */
    ibl_texture shape; /* kind, edges and levels (no data, no metadata) */
    ibl_write_desc desc;
    ibl_write_report *report; /* the caller's, filled at the finish */
    ibl__ktx2_layout layout;
    atomic_int given[IBL_MAX_LEVELS];
    atomic_size_t clamped; /* texels stored at the format's largest value: a sum, any order */
};

/* Bytes are handed to the disk (sync_file_range) a slice at a time as they are written, as
 * output.c does, so a large level's writeback runs beside its copy. */
#define WRITEBACK_SLICE ((size_t)1 << 20)

static int write_at(int fd, const uint8_t *p, size_t n, size_t offset)
{
    while (n > 0) {
        size_t chunk = n < WRITEBACK_SLICE ? n : WRITEBACK_SLICE;
        ssize_t w = pwrite(fd, p, chunk, (off_t)offset);
        if (w < 0 && errno == EINTR) continue;
        if (w <= 0) return w == 0 ? EIO : errno;
#ifdef SYNC_FILE_RANGE_WRITE
        (void)sync_file_range(fd, (off_t)offset, (off_t)w, SYNC_FILE_RANGE_WRITE); /* advice */
#endif
        p += w;
        n -= (size_t)w;
        offset += (size_t)w;
    }
    return 0;
}

static void free_writer(ibl_output_texture *w)
{
    ibl_context *ctx = w->ctx;
    ibl_free(ctx, w->layout.head);
    ibl_free(ctx, w->path);
    ibl_free(ctx, w);
}

ibl_status ibl_output_set_begin_texture(ibl_output_set *set, const char *path,
                                        const ibl_texture *shape, const ibl_write_desc *desc,
                                        ibl_output_texture **out)
{
    if (!out) return IBL_ERR_INVALID_ARGUMENT;
    *out = NULL;
    if (!set || !path || !shape) return IBL_ERR_INVALID_ARGUMENT;
    ibl_context *ctx = ibl__output_set_context(set);
    if (ibl_file_type_from_path(path) != IBL_FILE_KTX2)
        return ibl__fail(ctx, IBL_ERR_UNSUPPORTED,
                         "%s: only a .ktx2 is written level by level (its layout does not depend "
                         "on the texels)", path);
    ibl_output_texture *w = ibl_calloc(ctx, 1, sizeof *w);
    if (!w) return ibl__fail_named(ctx, ibl_context_status(ctx), path);
    w->set = set;
    w->ctx = ctx;
    w->fd = -1;
    w->path = ibl__strdup(ctx, path);
    if (!w->path) {
        free_writer(w);
        return ibl__fail_named(ctx, ibl_context_status(ctx), path);
    }
    if (desc) w->desc = *desc;
    w->report = w->desc.report;
    w->desc.report = NULL;
    ibl_status st = ibl__ktx2_layout_make(ctx, shape, desc, path, &w->layout);
    if (st != IBL_OK) {
        free_writer(w);
        return st;
    }
    w->shape = *shape;
    w->shape.data = NULL;
    w->shape.metadata = NULL;
    w->shape.metadata_count = 0;
    for (int l = 0; l < IBL_MAX_LEVELS; l++) atomic_init(&w->given[l], 0);
    atomic_init(&w->clamped, 0);
    st = ibl__output_set_open(set, path, &w->index, &w->fd);
    if (st != IBL_OK) {
        free_writer(w);
        return st;
    }
    if (ftruncate(w->fd, (off_t)w->layout.total) != 0) { /* the gaps between levels: zeros */
        int e = errno;
        ibl__output_set_close(set, w->index, 0);
        free_writer(w);
        return ibl__fail(ctx, IBL_ERR_IO, "%s: cannot size its temporary file: %s", path, strerror(e));
    }
    *out = w;
    return IBL_OK;
}

ibl_status ibl_output_texture_level(ibl_output_texture *w, int level, const float *texels)
{
    if (!w || !texels) return IBL_ERR_INVALID_ARGUMENT;
    ibl_context *ctx = w->ctx;
    if (level < 0 || level >= w->shape.levels)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "%s: level %d of a texture of %d levels",
                         w->path, level, w->shape.levels);
    if (atomic_exchange(&w->given[level], 1))
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "%s: level %d written twice", w->path, level);
    ibl_status st = IBL_OK;
    int e = 0;
    size_t clamped = 0, size = w->layout.level_size[level], offset = w->layout.level_offset[level];
    if (ibl__format_is_block(w->layout.format)) {
        /* the level as a texture of its own, for the encoders the whole-texture writer uses */
        ibl_texture view = w->shape;
        view.width = ibl_level_size(w->shape.width, level);
        view.height = ibl_level_size(w->shape.height, level);
        if (view.kind == IBL_TEXTURE_3D) view.depth = ibl_level_size(w->shape.depth, level);
        view.levels = 1;
        view.data = (float *)texels;
        uint8_t *bytes = ibl_alloc(ctx, size ? size : 1);
        uint8_t *dst[1] = {bytes};
        if (!bytes) st = ibl_context_status(ctx);
        else clamped = ibl__encode_levels(ctx, w->layout.format, &w->desc, &view, dst, &st);
        if (st == IBL_OK) e = write_at(w->fd, bytes, size, offset);
        ibl_free(ctx, bytes);
    } else {
        /* a texel format encodes texels one by one: the level goes a slice at a time through
         * one small buffer (as a row of texels), so a large level takes no buffer of its size
         * -- and no fresh pages while a filter beside it wants them */
        size_t unit = ibl__format_unit_bytes(w->layout.format), texels_left = size / unit;
        size_t slice = WRITEBACK_SLICE / unit;
        uint8_t *bytes = ibl_alloc(ctx, (texels_left < slice ? texels_left : slice) * unit + 1);
        if (!bytes) st = ibl_context_status(ctx);
        for (size_t done = 0; st == IBL_OK && !e && texels_left > 0;) {
            size_t n = texels_left < slice ? texels_left : slice;
            ibl_texture row = {.kind = IBL_TEXTURE_2D, .width = (int)n, .height = 1, .depth = 1,
                               .levels = 1, .data = (float *)texels + done * 4};
            uint8_t *dst[1] = {bytes};
            clamped += ibl__encode_levels(ctx, w->layout.format, &w->desc, &row, dst, &st);
            if (st == IBL_OK) e = write_at(w->fd, bytes, n * unit, offset + done * unit);
            done += n;
            texels_left -= n;
        }
        ibl_free(ctx, bytes);
    }
    if (st != IBL_OK || e) {
        atomic_store(&w->given[level], 0);
        if (e) return ibl__fail(ctx, IBL_ERR_IO, "%s: cannot write it: %s", w->path, strerror(e));
        return ibl__fail_named(ctx, st, w->path);
    }
    atomic_fetch_add(&w->clamped, clamped);
    return IBL_OK;
}

ibl_status ibl_output_texture_finish(ibl_output_texture *w)
{
    if (!w) return IBL_ERR_INVALID_ARGUMENT;
    ibl_context *ctx = w->ctx;
    ibl_status st = IBL_OK;
    for (int l = 0; l < w->shape.levels && st == IBL_OK; l++)
        if (!atomic_load(&w->given[l]))
            st = ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "%s: level %d was never written", w->path, l);
    int e = st == IBL_OK ? write_at(w->fd, w->layout.head, w->layout.head_size, 0) : 0;
    if (e) st = ibl__fail(ctx, IBL_ERR_IO, "%s: cannot write it: %s", w->path, strerror(e));
    ibl_status closed = ibl__output_set_close(w->set, w->index, st == IBL_OK);
    if (st == IBL_OK) st = closed;
    if (st == IBL_OK && w->report) w->report->clamped_texels += atomic_load(&w->clamped);
    free_writer(w);
    return st;
}

void ibl_output_texture_cancel(ibl_output_texture *w)
{
    if (!w) return;
    ibl__output_set_close(w->set, w->index, 0);
    free_writer(w);
}
