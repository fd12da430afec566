/* Helpers shared by the texture containers: see container.h. */
#include "io/container.h"
#include "core/context_internal.h"

#include <math.h>
#include <sched.h>
#include <stdio.h>
#include <stdlib.h>
#include <stdatomic.h>
#include <string.h>

#include "core/pixel_format.h"
#include "ibl/compress.h"

ibl_format ibl__container_format(const ibl_texture *tex, const ibl_write_desc *desc)
{
    if (desc && desc->format != IBL_FORMAT_DEFAULT) return desc->format; /* asked for: exact */
    ibl_format f = tex ? tex->format : IBL_FORMAT_DEFAULT;
    switch (f) {
    case IBL_FORMAT_RGBA16F:
    case IBL_FORMAT_RGBA32F:
    case IBL_FORMAT_RG11B10F:
    case IBL_FORMAT_RGB9E5:
    case IBL_FORMAT_RG16F:
    case IBL_FORMAT_RG32F: return f; /* keep what the texture was read as */
    case IBL_FORMAT_RGB32F: return IBL_FORMAT_RGBA32F; /* e.g. from PFM or float EXR */
    default: return IBL_FORMAT_RGBA16F;
    }
}

uint64_t ibl__level_texels(ibl_texture_kind kind, int width, int height, int depth, int level)
{
    uint64_t w = (uint64_t)ibl_level_size(width, level);
    uint64_t h = (uint64_t)ibl_level_size(height, level);
    uint64_t d = kind == IBL_TEXTURE_3D ? (uint64_t)ibl_level_size(depth, level) : 1;
    return w * h * d;
}

ibl_status ibl__check_dimensions(ibl_context *ctx, const char *name, ibl_texture_kind kind,
                                 uint64_t width, uint64_t height, uint64_t depth,
                                 uint64_t levels)
{
    if (width == 0 || height == 0 || depth == 0)
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: texture size %llux%llux%llu has a zero edge",
                        name, (unsigned long long)width, (unsigned long long)height,
                        (unsigned long long)depth);
    if (width > IBL_MAX_DIMENSION || height > IBL_MAX_DIMENSION || depth > IBL_MAX_DIMENSION)
        return ibl__fail(ctx, IBL_ERR_TOO_LARGE,
                        "%s: texture size %llux%llux%llu exceeds the limit of %d texels per edge",
                        name, (unsigned long long)width, (unsigned long long)height,
                        (unsigned long long)depth, (int)IBL_MAX_DIMENSION);
    if ((kind == IBL_TEXTURE_CUBE || kind == IBL_TEXTURE_CUBE_ARRAY) && width != height)
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: cube map faces are %llux%llu, not square", name,
                        (unsigned long long)width, (unsigned long long)height);
    uint64_t max_dim = width > height ? width : height;
    if (kind == IBL_TEXTURE_3D && depth > max_dim) max_dim = depth;
    int full = ibl_full_mip_count((int)max_dim);
    if (levels == 0 || levels > (uint64_t)full)
        return ibl__fail(ctx, IBL_ERR_FORMAT,
                        "%s: %llu mip levels for a largest edge of %llu (at most %d possible)", name,
                        (unsigned long long)levels, (unsigned long long)max_dim, full);
    if (levels > IBL_MAX_LEVELS)
        return ibl__fail(ctx, IBL_ERR_UNSUPPORTED, "%s: %llu mip levels (at most %d supported)",
                        name, (unsigned long long)levels, (int)IBL_MAX_LEVELS);
    return IBL_OK;
}

ibl_status ibl__check_texture(ibl_context *ctx, const ibl_texture *tex, const char *name)
{
    if (!tex || !tex->data)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "%s: no texture data to write", name);
    if (tex->kind != IBL_TEXTURE_2D && tex->kind != IBL_TEXTURE_3D && tex->kind != IBL_TEXTURE_CUBE &&
        tex->kind != IBL_TEXTURE_CUBE_ARRAY)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "%s: unknown texture kind %d", name,
                        (int)tex->kind);
    if (tex->width <= 0 || tex->height <= 0 || tex->depth <= 0 || tex->levels <= 0 ||
        tex->width > IBL_MAX_DIMENSION || tex->height > IBL_MAX_DIMENSION ||
        tex->depth > IBL_MAX_DIMENSION ||
        ibl_texture_floats(tex->kind, tex->width, tex->height, tex->depth, tex->levels) == 0)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                        "%s: invalid texture dimensions %dx%dx%d with %d levels", name, tex->width,
                        tex->height, tex->depth, tex->levels);
    if (tex->metadata_count < 0 || (tex->metadata_count > 0 && !tex->metadata))
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "%s: invalid metadata list", name);
    return IBL_OK;
}

/* ---- key/value data ---- */

static int reserved_key(const char *key)
{
    return strncmp(key, "KTX", 3) == 0 || strncmp(key, "ktx", 3) == 0 ||
           strcmp(key, "ibl.encoding") == 0 || strcmp(key, "ibl.rgbm_range") == 0;
}

static int compare_pairs(const void *a, const void *b)
{
    const ibl_key_value *x = a, *y = b;
    return strcmp(x->key, y->key); /* strcmp compares as unsigned char: code point order */
}

ibl_status ibl__kv_build(ibl_context *ctx, const char *name, const ibl_key_value *fixed,
                         int fixed_count, const ibl_texture *tex, uint8_t **out, size_t *size)
{
    *out = NULL;
    *size = 0;
    int meta = tex ? tex->metadata_count : 0;
    size_t cap = (size_t)fixed_count + (size_t)(meta > 0 ? meta : 0);
    if (cap == 0) return IBL_OK;
    ibl_key_value *pairs = ibl_alloc(ctx, cap * sizeof *pairs);
    if (!pairs) return ibl__fail_named(ctx, ibl_context_status(ctx), name);
    size_t n = 0;
    for (int i = 0; i < fixed_count; i++) pairs[n++] = fixed[i];
    for (int i = 0; i < meta; i++) {
        const ibl_key_value *kv = &tex->metadata[i];
        if (!kv->key || !kv->value || !kv->key[0]) {
            ibl_free(ctx, pairs);
            return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "%s: metadata entry %d has no key",
                            name, i);
        }
        if (!reserved_key(kv->key)) pairs[n++] = *kv;
    }
    if (n > IBL__MAX_KEY_VALUES) {
        ibl_free(ctx, pairs);
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "%s: %zu metadata entries (at most %d)",
                        name, n, (int)IBL__MAX_KEY_VALUES);
    }
    qsort(pairs, n, sizeof *pairs, compare_pairs);
    size_t total = 0;
    for (size_t i = 0; i < n; i++) {
        if (i > 0 && strcmp(pairs[i - 1].key, pairs[i].key) == 0) {
            ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "%s: metadata key \"%s\" appears twice", name,
                     pairs[i].key);
            ibl_free(ctx, pairs);
            return IBL_ERR_INVALID_ARGUMENT;
        }
        size_t len = strlen(pairs[i].key) + 1 + strlen(pairs[i].value) + 1;
        if (len > 0x7fffffffu || total > (size_t)0x7fffffff) {
            ibl_free(ctx, pairs);
            return ibl__fail(ctx, IBL_ERR_TOO_LARGE, "%s: metadata is too large", name);
        }
        total += 4 + ((len + 3) & ~(size_t)3);
    }
    uint8_t *buf = total ? ibl_calloc(ctx, total, 1) : NULL;
    if (total && !buf) {
        ibl_free(ctx, pairs);
        return ibl__fail_named(ctx, ibl_context_status(ctx), name);
    }
    size_t at = 0;
    for (size_t i = 0; i < n; i++) {
        size_t klen = strlen(pairs[i].key) + 1, vlen = strlen(pairs[i].value) + 1;
        ibl__wr32(buf + at, (uint32_t)(klen + vlen));
        memcpy(buf + at + 4, pairs[i].key, klen);
        memcpy(buf + at + 4 + klen, pairs[i].value, vlen);
        at += 4 + ((klen + vlen + 3) & ~(size_t)3);
    }
    ibl_free(ctx, pairs);
    *out = buf;
    *size = total;
    return IBL_OK;
}

ibl_status ibl__kv_parse(ibl_context *ctx, const char *name, const uint8_t *bytes, size_t size,
                         ibl_texture *tex)
{
    size_t at = 0;
    int count = 0;
    while (at < size) {
        if (++count > IBL__MAX_KEY_VALUES)
            return ibl__fail(ctx, IBL_ERR_UNSUPPORTED, "%s: more than %d key/value entries", name,
                            (int)IBL__MAX_KEY_VALUES);
        if (size - at < 4)
            return ibl__fail(ctx, IBL_ERR_FORMAT,
                            "%s: key/value data ends inside an entry's length at byte %zu", name, at);
        uint32_t len = ibl__rd32(bytes + at);
        at += 4;
        if (len > size - at)
            return ibl__fail(ctx, IBL_ERR_FORMAT,
                            "%s: key/value entry of %u bytes runs past the key/value data", name,
                            len);
        const uint8_t *entry = bytes + at;
        const uint8_t *nul = memchr(entry, 0, len);
        if (!nul || nul == entry)
            return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: key/value entry at byte %zu has %s", name,
                            at - 4, nul ? "an empty key" : "no NUL after its key");
        size_t klen = (size_t)(nul - entry);
        size_t vlen = len - klen - 1;
        if (vlen > 0 && entry[klen + 1 + vlen - 1] == 0) vlen--; /* the string's own NUL */
        char *key = ibl_alloc(ctx, klen + 1 + vlen + 1);
        if (!key) return ibl__fail_named(ctx, ibl_context_status(ctx), name);
        memcpy(key, entry, klen + 1);
        char *value = key + klen + 1;
        memcpy(value, entry + klen + 1, vlen);
        value[vlen] = 0;
        ibl_status st = IBL_OK;
        if (ibl_texture_get_metadata(tex, key))
            st = ibl__fail(ctx, IBL_ERR_FORMAT, "%s: metadata key \"%s\" appears twice", name, key);
        else if (ibl_texture_set_metadata(ctx, tex, key, value) != IBL_OK)
            st = ibl__fail(ctx, IBL_ERR_OUT_OF_MEMORY, "%s: out of memory reading metadata", name);
        ibl_free(ctx, key);
        if (st != IBL_OK) return st;
        size_t padded = ((size_t)len + 3) & ~(size_t)3;
        if (padded > size - at)
            return ibl__fail(ctx, IBL_ERR_FORMAT,
                            "%s: key/value data ends inside the padding of an entry", name);
        at += padded;
    }
    return IBL_OK;
}

/* ---- reorientation ---- */

static void swap_texels(float *a, float *b)
{
    float t[4];
    memcpy(t, a, sizeof t);
    memcpy(a, b, sizeof t);
    memcpy(b, t, sizeof t);
}

void ibl__flip_texture(ibl_texture *tex, int flip_x, int flip_y, int flip_z)
{
    if (!flip_x && !flip_y && !flip_z) return;
    int faces = ibl_texture_faces(tex);
    for (int l = 0; l < tex->levels; l++) {
        size_t w = (size_t)ibl_level_size(tex->width, l), h = (size_t)ibl_level_size(tex->height, l);
        size_t d = tex->kind == IBL_TEXTURE_3D ? (size_t)ibl_level_size(tex->depth, l) : 1;
        for (int f = 0; f < faces; f++) {
            float *base = ibl_texture_level(tex, l, f);
            for (size_t z = 0; z < d; z++) {
                float *slice = base + z * w * h * 4;
                if (flip_y)
                    for (size_t y = 0; y < h / 2; y++)
                        for (size_t x = 0; x < w; x++)
                            swap_texels(slice + (y * w + x) * 4, slice + ((h - 1 - y) * w + x) * 4);
                if (flip_x)
                    for (size_t y = 0; y < h; y++)
                        for (size_t x = 0; x < w / 2; x++)
                            swap_texels(slice + (y * w + x) * 4, slice + (y * w + w - 1 - x) * 4);
            }
            if (flip_z)
                for (size_t z = 0; z < d / 2; z++)
                    for (size_t i = 0; i < w * h; i++)
                        swap_texels(base + (z * w * h + i) * 4, base + ((d - 1 - z) * w * h + i) * 4);
        }
    }
}

/* ---- chunked conversion ---- */

enum { CHUNK_TEXELS = 1 << 16 };

typedef struct convert_job {
    ibl_format format;
    size_t count, texel_bytes;
    const float *src_f;
    uint8_t *dst_b;
    const uint8_t *src_b;
    float *dst_f;
    atomic_size_t clamped; /* an integer sum: the same in any order */
} convert_job;

static void pack_chunk(void *arg, int index)
{
    convert_job *j = arg;
    size_t first = (size_t)index * CHUNK_TEXELS;
    size_t n = j->count - first < CHUNK_TEXELS ? j->count - first : CHUNK_TEXELS;
    size_t c = ibl_pack_texels(j->format, j->src_f + first * 4, n, j->dst_b + first * j->texel_bytes);
    if (c) atomic_fetch_add(&j->clamped, c);
}

static void unpack_chunk(void *arg, int index)
{
    const convert_job *j = arg;
    size_t first = (size_t)index * CHUNK_TEXELS;
    size_t n = j->count - first < CHUNK_TEXELS ? j->count - first : CHUNK_TEXELS;
    ibl_unpack_texels(j->format, j->src_b + first * j->texel_bytes, n, j->dst_f + first * 4);
}

static int chunk_count(size_t count)
{
    /* count <= 6 * 65536^3 would overflow int chunks only past 2^47 texels; files that large
     * are refused long before (memory limit). Fall back to one call if it ever happens. */
    size_t chunks = (count + CHUNK_TEXELS - 1) / CHUNK_TEXELS;
    return chunks > 0x7fffffff ? 0 : (int)chunks;
}

size_t ibl__pack(ibl_context *ctx, ibl_format format, const float *rgba, size_t count, uint8_t *dst)
{
    convert_job j = {format, count, ibl_format_texel_bytes(format), rgba, dst, NULL, NULL, 0};
    int chunks = chunk_count(count);
    if (chunks <= 1) return ibl_pack_texels(format, rgba, count, dst);
    ibl_parallel_for(ctx, chunks, pack_chunk, &j);
    return atomic_load(&j.clamped);
}

void ibl__unpack(ibl_context *ctx, ibl_format format, const uint8_t *src, size_t count,
                 float *rgba)
{
    convert_job j = {format, count, ibl_format_texel_bytes(format), NULL, NULL, src, rgba, 0};
    int chunks = chunk_count(count);
    if (chunks <= 1) ibl_unpack_texels(format, src, count, rgba);
    else ibl_parallel_for(ctx, chunks, unpack_chunk, &j);
}

/* ---- block formats and 8-bit encodings ---- */

int ibl__format_block(ibl_format format, int *block_width, int *block_height)
{
    static const uint8_t astc[8][2] = {{4, 4}, {5, 4}, {5, 5}, {6, 5}, {6, 6}, {8, 5}, {8, 6}, {8, 8}};
    int w = 1, h = 1;
    if (format == IBL_FORMAT_BC6H || format == IBL_FORMAT_BC6H_SIGNED) w = h = 4;
    if (format >= IBL_FORMAT_ASTC_4x4 && format <= IBL_FORMAT_ASTC_8x8) {
        w = astc[format - IBL_FORMAT_ASTC_4x4][0];
        h = astc[format - IBL_FORMAT_ASTC_4x4][1];
    }
    if (block_width) *block_width = w;
    if (block_height) *block_height = h;
    return w > 1;
}

int ibl__format_is_block(ibl_format format)
{
    return ibl__format_block(format, NULL, NULL);
}

int ibl_format_is_block(ibl_format format)
{
    return ibl__format_is_block(format);
}

size_t ibl__format_unit_bytes(ibl_format format)
{
    if (ibl__format_is_block(format)) return 16; /* BC6H and ASTC blocks */
    switch (format) {
    case IBL_FORMAT_RGBE:
    case IBL_FORMAT_RGBM:
    case IBL_FORMAT_RGBD: return 4;
    default: return ibl_format_texel_bytes(format);
    }
}

uint64_t ibl__level_bytes(ibl_format format, ibl_texture_kind kind, int width, int height,
                          int depth, int level)
{
    int bw, bh;
    if (!ibl__format_block(format, &bw, &bh))
        return ibl__level_texels(kind, width, height, depth, level) * ibl__format_unit_bytes(format);
    uint64_t bx = ((uint64_t)ibl_level_size(width, level) + (uint64_t)bw - 1) / (uint64_t)bw;
    uint64_t by = ((uint64_t)ibl_level_size(height, level) + (uint64_t)bh - 1) / (uint64_t)bh;
    uint64_t d = kind == IBL_TEXTURE_3D ? (uint64_t)ibl_level_size(depth, level) : 1;
    return bx * by * d * 16;
}

typedef struct hdr8_job {
    ibl_format format;
    float range;
    size_t count;
    const float *src_f;
    uint8_t *dst_b;
    const uint8_t *src_b;
    float *dst_f;
} hdr8_job;

static void hdr8_chunk(void *arg, int index)
{
    const hdr8_job *j = arg;
    size_t first = (size_t)index * CHUNK_TEXELS;
    size_t end = j->count - first < CHUNK_TEXELS ? j->count : first + CHUNK_TEXELS;
    for (size_t i = first; i < end; i++) {
        if (j->src_f) {
            const float *c = j->src_f + i * 4;
            uint8_t *o = j->dst_b + i * 4;
            if (j->format == IBL_FORMAT_RGBM) ibl_rgbm_encode(c, j->range, o);
            else if (j->format == IBL_FORMAT_RGBD) ibl_rgbd_encode(c, o);
            else ibl_rgbe_encode(c, o);
        } else {
            const uint8_t *b = j->src_b + i * 4;
            float *o = j->dst_f + i * 4;
            if (j->format == IBL_FORMAT_RGBM) ibl_rgbm_decode(b, j->range, o);
            else if (j->format == IBL_FORMAT_RGBD) ibl_rgbd_decode(b, o);
            else ibl_rgbe_decode(b, o);
            o[3] = 1.0f;
        }
    }
}

static void run_hdr8(ibl_context *ctx, hdr8_job *j)
{
    int chunks = chunk_count(j->count);
    if (chunks == 1) hdr8_chunk(j, 0);
    else if (chunks > 1) ibl_parallel_for(ctx, chunks, hdr8_chunk, j);
}

size_t ibl__encode_level(ibl_context *ctx, ibl_format format, const ibl_write_desc *desc,
                         const ibl_texture *tex, int level, int face, uint8_t *dst,
                         ibl_status *status)
{
    *status = IBL_OK;
    int w = ibl_level_size(tex->width, level), h = ibl_level_size(tex->height, level);
    int d = tex->kind == IBL_TEXTURE_3D ? ibl_level_size(tex->depth, level) : 1;
    const float *src = ibl_texture_level(tex, level, face);
    size_t count = (size_t)w * (size_t)h * (size_t)d;
    int bw, bh;
    if (ibl__format_block(format, &bw, &bh)) {
        ibl_bc6h_desc bd = {format == IBL_FORMAT_BC6H_SIGNED, desc ? desc->quality : IBL_QUALITY_DEFAULT};
        ibl_astc_desc ad = {bw, bh, bd.quality};
        int astc = bw != 4 || bh != 4 || (format != IBL_FORMAT_BC6H && format != IBL_FORMAT_BC6H_SIGNED);
        size_t slice = astc ? ibl_astc_bytes(bw, bh, w, h) : ibl_bc6h_bytes(w, h), clamped = 0;
        for (int z = 0; z < d; z++) {
            const float *texels = src + (size_t)z * (size_t)w * (size_t)h * 4;
            if (astc) *status = ibl_astc_encode(ctx, &ad, texels, w, h, dst + (size_t)z * slice);
            else *status = ibl_bc6h_encode(ctx, &bd, texels, w, h, dst + (size_t)z * slice);
            if (*status != IBL_OK) return 0;
        }
        for (size_t i = 0; i < count; i++) {
            int over = 0;
            for (int c = 0; c < 3; c++) over |= fabsf(src[i * 4 + (size_t)c]) > 65504.0f;
            clamped += (size_t)over;
        }
        return clamped;
    }
    if (format == IBL_FORMAT_RGBM || format == IBL_FORMAT_RGBD || format == IBL_FORMAT_RGBE) {
        float range = desc && desc->rgbm_range > 0.0f ? desc->rgbm_range : IBL_RGBM_DEFAULT_RANGE;
        hdr8_job j = {format, range, count, src, dst, NULL, NULL};
        run_hdr8(ctx, &j);
        float max = format == IBL_FORMAT_RGBM ? range : ibl_format_max_value(format);
        size_t clamped = 0;
        for (size_t i = 0; i < count; i++) {
            int over = 0;
            for (int c = 0; c < 3; c++) over |= src[i * 4 + (size_t)c] > max;
            clamped += (size_t)over;
        }
        return clamped;
    }
    return ibl__pack(ctx, format, src, count, dst);
}

/* Every texel of every face and level in one parallel loop: a level's faces are contiguous in
 * memory and in the file, so the texture is a few runs of texels (one a level), cut into
 * LEVELS_CHUNK-texel chunks that never straddle two levels. One loop instead of one a face
 * keeps both threads busy at 256 (a face of 65536 texels was a single chunk, encoded on one
 * thread) and through the small levels. */
enum { LEVELS_CHUNK = 1 << 14 };

typedef struct levels_job {
    ibl_format format;
    float hdr8_range, hdr8_max; /* RGBM/RGBD/RGBE: the range encoded, the largest value kept */
    /* the loop's runs of texels, one a level, in the order the loop's indices take them */
    const float *src[IBL_MAX_LEVELS];
    uint8_t *dst[IBL_MAX_LEVELS];
    size_t texels[IBL_MAX_LEVELS];
    int first_chunk[IBL_MAX_LEVELS + 1];
    size_t unit; /* bytes a texel */
    atomic_size_t clamped; /* an integer sum: the same in any order */
    atomic_uchar *done;    /* a streamed encode's: chunk i's bytes are written (else NULL) */
} levels_job;

/* The run and the first texel of chunk `index`, and its texel count. */
static int chunk_place(const levels_job *j, int index, size_t *first, size_t *n)
{
    int r = 0;
    while (index >= j->first_chunk[r + 1]) r++;
    *first = (size_t)(index - j->first_chunk[r]) * LEVELS_CHUNK;
    *n = j->texels[r] - *first < LEVELS_CHUNK ? j->texels[r] - *first : LEVELS_CHUNK;
    return r;
}

static void levels_chunk(void *arg, int index)
{
    levels_job *j = arg;
    size_t first, n;
    int l = chunk_place(j, index, &first, &n);
    const float *src = j->src[l] + first * 4;
    uint8_t *dst = j->dst[l] + first * j->unit;
    size_t clamped = 0;
    if (j->hdr8_max > 0.0f) {
        hdr8_job h = {j->format, j->hdr8_range, n, src, dst, NULL, NULL};
        hdr8_chunk(&h, 0);
        for (size_t i = 0; i < n; i++) {
            int over = 0;
            for (int c = 0; c < 3; c++) over |= src[i * 4 + (size_t)c] > j->hdr8_max;
            clamped += (size_t)over;
        }
    } else {
        clamped = ibl_pack_texels(j->format, src, n, dst);
    }
    if (clamped) atomic_fetch_add(&j->clamped, clamped);
    if (j->done) atomic_store_explicit(&j->done[index], 1, memory_order_release);
}

/* Face by face (the block formats, whose encoders split their own work). */
static size_t encode_levels_by_face(ibl_context *ctx, ibl_format format, const ibl_write_desc *desc,
                                    const ibl_texture *tex, uint8_t *const dst[], ibl_status *status)
{
    size_t clamped = 0;
    for (int l = 0; l < tex->levels && *status == IBL_OK; l++) {
        uint64_t face_bytes = ibl__level_bytes(format, tex->kind, tex->width, tex->height,
                                               tex->depth, l);
        for (int f = 0; f < ibl_texture_faces(tex) && *status == IBL_OK; f++)
            clamped += ibl__encode_level(ctx, format, desc, tex, l, f,
                                         dst[l] + (size_t)face_bytes * (size_t)f, status);
    }
    return clamped;
}

/* The loop's job for a texel format, its runs in the order of `order` (level numbers); the
 * chunk count, or 0 past what one loop can count (2^45 texels, refused long before by the
 * memory limit). */
static size_t levels_setup(levels_job *j, ibl_format format, const ibl_write_desc *desc,
                           const ibl_texture *tex, uint8_t *const dst[], const int order[])
{
    memset(j, 0, sizeof *j);
    j->format = format;
    j->unit = ibl__format_unit_bytes(format);
    if (format == IBL_FORMAT_RGBM || format == IBL_FORMAT_RGBD || format == IBL_FORMAT_RGBE) {
        j->hdr8_range = desc && desc->rgbm_range > 0.0f ? desc->rgbm_range : IBL_RGBM_DEFAULT_RANGE;
        j->hdr8_max = format == IBL_FORMAT_RGBM ? j->hdr8_range : ibl_format_max_value(format);
    }
    size_t chunks = 0;
    for (int r = 0; r < tex->levels; r++) {
        int l = order[r];
        j->src[r] = ibl_texture_level(tex, l, 0);
        j->dst[r] = dst[l];
        j->texels[r] = (size_t)ibl__level_texels(tex->kind, tex->width, tex->height, tex->depth, l) *
                       (size_t)ibl_texture_faces(tex);
        j->first_chunk[r] = (int)chunks;
        chunks += (j->texels[r] + LEVELS_CHUNK - 1) / LEVELS_CHUNK;
        if (chunks > 0x7fffffff) return 0;
    }
    j->first_chunk[tex->levels] = (int)chunks;
    return chunks;
}

size_t ibl__encode_levels(ibl_context *ctx, ibl_format format, const ibl_write_desc *desc,
                          const ibl_texture *tex, uint8_t *const dst[], ibl_status *status)
{
    *status = IBL_OK;
    if (ibl__format_is_block(format)) return encode_levels_by_face(ctx, format, desc, tex, dst, status);
    int order[IBL_MAX_LEVELS];
    for (int l = 0; l < tex->levels; l++) order[l] = l;
    levels_job j;
    size_t chunks = levels_setup(&j, format, desc, tex, dst, order);
    if (!chunks) return encode_levels_by_face(ctx, format, desc, tex, dst, status);
    ibl_parallel_for(ctx, (int)chunks, levels_chunk, &j);
    return atomic_load(&j.clamped);
}

struct ibl__levels_stream {
    ibl_context *ctx;
    levels_job job;
    int chunks;
    int next;   /* every chunk before it is written */
    int posted; /* the loop runs on the pool (ibl__parallel_begin) until the end */
};

ibl__levels_stream *ibl__encode_levels_begin(ibl_context *ctx, ibl_format format,
                                             const ibl_write_desc *desc, const ibl_texture *tex,
                                             uint8_t *const dst[])
{
    if (ibl__format_is_block(format) || tex->levels < 1) return NULL;
    /* the runs in the order of their place in memory (a KTX2 file holds the smallest level
     * first), so that the chunks are done front to back as the writer wants them */
    int order[IBL_MAX_LEVELS];
    for (int r = 0; r < tex->levels; r++) {
        int k = r;
        while (k > 0 && dst[order[k - 1]] > dst[r]) order[k] = order[k - 1], k--;
        order[k] = r;
    }
    ibl__levels_stream *s = ibl_alloc(ctx, sizeof *s);
    if (!s) return NULL;
    size_t chunks = levels_setup(&s->job, format, desc, tex, dst, order);
    s->job.done = chunks ? ibl_calloc(ctx, chunks, sizeof *s->job.done) : NULL;
    if (!s->job.done) {
        ibl_free(ctx, s);
        return NULL;
    }
    s->ctx = ctx;
    s->chunks = (int)chunks;
    s->next = 0;
    s->posted = ibl__parallel_begin(ctx, s->chunks, levels_chunk, &s->job);
    if (!s->posted) { /* no pool to run it beside the caller: the whole encode now */
        ibl_parallel_for(ctx, s->chunks, levels_chunk, &s->job);
        s->next = s->chunks;
    }
    return s;
}

void ibl__encode_levels_wait(ibl__levels_stream *s, const uint8_t *end)
{
    while (s->next < s->chunks) {
        size_t first, n;
        int r = chunk_place(&s->job, s->next, &first, &n);
        if (s->job.dst[r] + first * s->job.unit >= end) return;
        if (atomic_load_explicit(&s->job.done[s->next], memory_order_acquire)) {
            s->next++;
            continue;
        }
        /* a chunk still being encoded: take one of those not started meanwhile, else wait for
         * it (a worker has it: ~0.1 ms; on a loaded host the worker may have lost its CPU, so
         * after a while the wait gives its own up) */
        if (!ibl__parallel_help(s->ctx))
            for (int spins = 1; !atomic_load_explicit(&s->job.done[s->next], memory_order_acquire); spins++) {
                if (spins % 4096 == 0) sched_yield();
                else ibl__cpu_relax();
            }
    }
}

size_t ibl__encode_levels_end(ibl__levels_stream *s)
{
    if (!s) return 0;
    if (s->posted) ibl__parallel_end(s->ctx);
    size_t clamped = atomic_load(&s->job.clamped);
    ibl_free(s->ctx, s->job.done);
    ibl_free(s->ctx, s);
    return clamped;
}

ibl_status ibl__decode_level(ibl_context *ctx, ibl_format format, float rgbm_range,
                             const uint8_t *src, ibl_texture *tex, int level, int face)
{
    int w = ibl_level_size(tex->width, level), h = ibl_level_size(tex->height, level);
    int d = tex->kind == IBL_TEXTURE_3D ? ibl_level_size(tex->depth, level) : 1;
    float *dst = ibl_texture_level(tex, level, face);
    size_t count = (size_t)w * (size_t)h * (size_t)d;
    int bw, bh;
    if (ibl__format_block(format, &bw, &bh)) {
        int bc6h = format == IBL_FORMAT_BC6H || format == IBL_FORMAT_BC6H_SIGNED;
        ibl_astc_desc ad = {bw, bh, IBL_QUALITY_DEFAULT};
        size_t slice = bc6h ? ibl_bc6h_bytes(w, h) : ibl_astc_bytes(bw, bh, w, h);
        for (int z = 0; z < d; z++) {
            float *texels = dst + (size_t)z * (size_t)w * (size_t)h * 4;
            ibl_status st = bc6h ? ibl_bc6h_decode(ctx, format == IBL_FORMAT_BC6H_SIGNED, src + (size_t)z * slice, w, h, texels)
                                 : ibl_astc_decode(ctx, &ad, src + (size_t)z * slice, w, h, texels);
            if (st != IBL_OK) return st;
        }
    } else if (format == IBL_FORMAT_RGBM || format == IBL_FORMAT_RGBD || format == IBL_FORMAT_RGBE) {
        hdr8_job j = {format, rgbm_range > 0.0f ? rgbm_range : IBL_RGBM_DEFAULT_RANGE, count, NULL, NULL, src, dst};
        run_hdr8(ctx, &j);
    } else {
        ibl__unpack(ctx, format, src, count, dst);
    }
    return IBL_OK;
}

ibl_texture ibl__header_texture(ibl_texture_kind kind, int width, int height, int depth, int levels,
                                ibl_format format)
{
    ibl_texture tex;
    memset(&tex, 0, sizeof tex);
    tex.kind = kind;
    tex.width = width;
    tex.height = height;
    tex.depth = depth;
    tex.levels = levels;
    tex.format = format;
    return tex;
}

void ibl__fill_info(ibl_file_info *info, ibl_file_type type, const ibl_texture *tex)
{
    if (!info) return;
    memset(info, 0, sizeof *info);
    info->type = type;
    info->format = tex->format;
    info->kind = tex->kind;
    info->width = tex->width;
    info->height = tex->height;
    info->depth = tex->depth;
    info->levels = tex->levels;
    info->has_alpha = ibl_format_channels(tex->format) == 4;
}
