/* Images, cubemaps and textures: allocation, views, metadata and the pixel policy. */
#include "ibl/core.h"
#include "core/context_internal.h"

#include <math.h>
#include <string.h>
#include <strings.h>

static const char *const format_names[IBL_FORMAT_COUNT] = {
    "default", "rgba16f", "rgba32f", "rg11b10f", "rgb9e5", "rg16f", "rg32f",
    "rgb32f", "rgb16f", "rgba8", "rgba16", "rgbe", "bc6h", "bc6h-signed", "rgbm", "rgbd",
    "astc4x4", "astc5x4", "astc5x5", "astc6x5", "astc6x6", "astc8x5", "astc8x6", "astc8x8",
    "rgba8-linear",
};

const char *ibl_format_name(ibl_format format)
{
    if ((int)format < 0 || format >= IBL_FORMAT_COUNT) return "unknown";
    return format_names[format];
}

int ibl_format_from_name(const char *name, ibl_format *out)
{
    if (!name) return 0;
    for (int i = 1; i < IBL_FORMAT_COUNT; i++)
        if (strcasecmp(name, format_names[i]) == 0) {
            *out = (ibl_format)i;
            return 1;
        }
    if (strcasecmp(name, "b10g11r11") == 0 || strcasecmp(name, "r11g11b10f") == 0) {
        *out = IBL_FORMAT_RG11B10F;
        return 1;
    }
    if (strcasecmp(name, "e5b9g9r9") == 0) {
        *out = IBL_FORMAT_RGB9E5;
        return 1;
    }
    return 0;
}

/* ---- zeroed pixel memory ---- */

/* Large pixel blocks are zeroed in fixed 1 MiB chunks through ibl_parallel_for: zeroing a
 * fresh block is mostly the kernel faulting its pages in and clearing them, and one thread
 * doing it for a whole cube (the 512 chain: 33 MiB) is a serial stretch of every command.
 * Below ZERO_PARALLEL_BYTES one memset is cheaper than waking the workers. */
#define ZERO_CHUNK_BYTES ((size_t)1 << 20)
#define ZERO_PARALLEL_BYTES ((size_t)4 << 20)

typedef struct zero_job {
    unsigned char *bytes;
    size_t size;
} zero_job;

static void zero_chunk(void *arg, int index)
{
    const zero_job *j = arg;
    size_t first = (size_t)index * ZERO_CHUNK_BYTES;
    memset(j->bytes + first, 0, j->size - first < ZERO_CHUNK_BYTES ? j->size - first : ZERO_CHUNK_BYTES);
}

/* ibl_calloc(ctx, count, sizeof(float)), zeroed in parallel when large. */
static float *zeroed_floats(ibl_context *ctx, size_t count)
{
    if (count > SIZE_MAX / sizeof(float) || count * sizeof(float) < ZERO_PARALLEL_BYTES)
        return ibl_calloc(ctx, count, sizeof(float));
    size_t size = count * sizeof(float);
    float *p = ibl_alloc(ctx, size);
    if (!p) return NULL;
    zero_job j = {(unsigned char *)p, size};
    ibl_parallel_for(ctx, (int)((size + ZERO_CHUNK_BYTES - 1) / ZERO_CHUNK_BYTES), zero_chunk, &j);
    return p;
}

/* ---- images ---- */

ibl_status ibl_image_alloc(ibl_context *ctx, int width, int height, ibl_image *out)
{
    if (!out) return IBL_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    if (width <= 0 || height <= 0)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "image size %dx%d is not positive", width,
                        height);
    size_t texels = (size_t)width * (size_t)height;
    if (texels > SIZE_MAX / (4 * sizeof(float)))
        return ibl__fail(ctx, IBL_ERR_TOO_LARGE, "image size %dx%d overflows", width, height);
    out->pixels = zeroed_floats(ctx, texels * 4);
    if (!out->pixels) return ibl_context_status(ctx);
    out->width = width;
    out->height = height;
    return IBL_OK;
}

void ibl_image_free(ibl_context *ctx, ibl_image *image)
{
    if (!image) return;
    ibl_free(ctx, image->pixels);
    memset(image, 0, sizeof *image);
}

ibl_status ibl_sanitize_pixels(ibl_context *ctx, float *rgba, size_t texel_count,
                               int clamp_infinite, float clamp_value, ibl_pixel_report *report)
{
    ibl_pixel_report r = {0, 0, 0, texel_count};
    if (clamp_value <= 0.0f) clamp_value = 65504.0f;
    for (size_t i = 0; i < texel_count; i++) {
        float *p = rgba + i * 4;
        int has_nan = 0, has_inf = 0, has_neg = 0;
        for (int c = 0; c < 3; c++) {
            float v = p[c];
            if (isnan(v)) {
                has_nan = 1;
                p[c] = 0.0f;
            } else if (isinf(v)) {
                has_inf = 1;
                if (clamp_infinite) p[c] = v > 0 ? clamp_value : 0.0f;
            } else if (v < 0.0f) {
                has_neg = 1;
                p[c] = 0.0f;
            }
        }
        if (!isfinite(p[3])) p[3] = isnan(p[3]) ? 1.0f : (p[3] > 0 ? 1.0f : 0.0f);
        r.nan_count += (uint64_t)has_nan;
        r.inf_count += (uint64_t)has_inf;
        r.negative_count += (uint64_t)has_neg;
    }
    if (report) *report = r;
    if (r.inf_count && !clamp_infinite)
        return ibl__fail(ctx, IBL_ERR_BAD_PIXELS,
                        "%llu texels are infinite (use --clamp to clamp them)",
                        (unsigned long long)r.inf_count);
    return IBL_OK;
}

/* ---- cubemaps ---- */

int ibl_full_mip_count(int size)
{
    int levels = 1;
    while (size > 1) {
        size >>= 1;
        levels++;
    }
    return levels;
}

size_t ibl_cubemap_floats(int size, int levels)
{
    return ibl_texture_floats(IBL_TEXTURE_CUBE, size, size, 1, levels);
}

ibl_status ibl_cubemap_wrap(int size, int levels, float *memory, ibl_cubemap *out)
{
    if (!out) return IBL_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    if (!memory || ibl_cubemap_floats(size, levels) == 0) return IBL_ERR_INVALID_ARGUMENT;
    out->size = size;
    out->levels = levels;
    out->data = memory;
    return IBL_OK;
}

ibl_status ibl_cubemap_alloc(ibl_context *ctx, int size, int levels, ibl_cubemap *out)
{
    if (!out) return IBL_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    size_t n = ibl_cubemap_floats(size, levels);
    if (n == 0)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "invalid cubemap size %d with %d levels",
                        size, levels);
    float *data = zeroed_floats(ctx, n);
    if (!data) return ibl_context_status(ctx);
    out->size = size;
    out->levels = levels;
    out->data = data;
    out->owns_data = 1;
    return IBL_OK;
}

void ibl_cubemap_free(ibl_context *ctx, ibl_cubemap *cube)
{
    if (!cube) return;
    if (cube->owns_data) ibl_free(ctx, cube->data);
    memset(cube, 0, sizeof *cube);
}

float *ibl_cubemap_face(const ibl_cubemap *cube, int level, int face)
{
    size_t offset = 0;
    for (int l = 0; l < level; l++) {
        size_t s = (size_t)ibl_level_size(cube->size, l);
        offset += 6 * s * s * 4;
    }
    size_t s = (size_t)ibl_level_size(cube->size, level);
    return cube->data + offset + (size_t)face * s * s * 4;
}

/* ---- textures ---- */

static int level_depth(const ibl_texture *t, int level)
{
    return t->kind == IBL_TEXTURE_3D ? ibl_level_size(t->depth, level) : 1;
}

size_t ibl_texture_floats(ibl_texture_kind kind, int width, int height, int depth, int levels)
{
    if (width <= 0 || height <= 0 || depth <= 0 || levels <= 0 || levels > IBL_MAX_LEVELS)
        return 0;
    if ((kind == IBL_TEXTURE_CUBE || kind == IBL_TEXTURE_CUBE_ARRAY) && width != height) return 0;
    if (kind != IBL_TEXTURE_3D && kind != IBL_TEXTURE_CUBE_ARRAY && depth != 1) return 0;
    int max_dim = width > height ? width : height;
    if (kind == IBL_TEXTURE_3D && depth > max_dim) max_dim = depth;
    if (levels > ibl_full_mip_count(max_dim)) return 0;
    size_t faces = kind == IBL_TEXTURE_CUBE ? 6 : kind == IBL_TEXTURE_CUBE_ARRAY ? 6 * (size_t)depth : 1;
    size_t total = 0;
    for (int l = 0; l < levels; l++) {
        size_t w = (size_t)ibl_level_size(width, l), h = (size_t)ibl_level_size(height, l);
        size_t d = kind == IBL_TEXTURE_3D ? (size_t)ibl_level_size(depth, l) : 1;
        /* each factor is below 2^31; guard the products against size_t overflow */
        if (w > SIZE_MAX / h) return 0;
        size_t n = w * h;
        if (n > SIZE_MAX / d) return 0;
        n *= d;
        if (n > SIZE_MAX / (faces * 4 * sizeof(float))) return 0;
        n *= faces * 4;
        if (total > SIZE_MAX / sizeof(float) - n) return 0;
        total += n;
    }
    return total;
}

ibl_status ibl_texture_alloc(ibl_context *ctx, ibl_texture_kind kind, int width, int height,
                             int depth, int levels, ibl_texture *out)
{
    if (!out) return IBL_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    size_t n = ibl_texture_floats(kind, width, height, depth, levels);
    if (n == 0)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                        "invalid texture dimensions %dx%dx%d with %d levels", width, height,
                        depth, levels);
    float *data = zeroed_floats(ctx, n);
    if (!data) return ibl_context_status(ctx);
    out->kind = kind;
    out->width = width;
    out->height = height;
    out->depth = depth;
    out->levels = levels;
    out->data = data;
    out->owns_data = 1;
    return IBL_OK;
}

void ibl_texture_free(ibl_context *ctx, ibl_texture *tex)
{
    if (!tex) return;
    if (tex->owns_data) ibl_free(ctx, tex->data);
    if (tex->owns_metadata) {
        for (int i = 0; i < tex->metadata_count; i++) {
            ibl_free(ctx, tex->metadata[i].key);
            ibl_free(ctx, tex->metadata[i].value);
        }
        ibl_free(ctx, tex->metadata);
    }
    memset(tex, 0, sizeof *tex);
}

int ibl_texture_faces(const ibl_texture *tex)
{
    return tex->kind == IBL_TEXTURE_CUBE ? 6 : tex->kind == IBL_TEXTURE_CUBE_ARRAY ? 6 * tex->depth : 1;
}

float *ibl_texture_level(const ibl_texture *tex, int level, int face)
{
    size_t offset = 0;
    size_t faces = (size_t)ibl_texture_faces(tex);
    for (int l = 0; l <= level; l++) {
        size_t n = (size_t)ibl_level_size(tex->width, l) * (size_t)ibl_level_size(tex->height, l) *
                   (size_t)level_depth(tex, l) * 4;
        if (l == level) return tex->data + offset + (size_t)face * n;
        offset += faces * n;
    }
    return tex->data;
}

ibl_texture ibl_texture_from_cubemap(const ibl_cubemap *cube)
{
    ibl_texture t;
    memset(&t, 0, sizeof t);
    t.kind = IBL_TEXTURE_CUBE;
    t.width = t.height = cube->size;
    t.depth = 1;
    t.levels = cube->levels;
    t.data = cube->data;
    return t;
}

ibl_status ibl_cubemap_from_texture(const ibl_texture *tex, ibl_cubemap *out)
{
    if (!tex || !out || tex->kind != IBL_TEXTURE_CUBE || tex->width != tex->height)
        return IBL_ERR_INVALID_ARGUMENT;
    return ibl_cubemap_wrap(tex->width, tex->levels, tex->data, out);
}

static char *dup_string(ibl_context *ctx, const char *s)
{
    size_t n = strlen(s) + 1;
    char *d = ibl_alloc(ctx, n);
    if (d) memcpy(d, s, n);
    return d;
}

ibl_status ibl_texture_set_metadata(ibl_context *ctx, ibl_texture *tex, const char *key,
                                    const char *value)
{
    if (!tex || !key || !value || !key[0]) return IBL_ERR_INVALID_ARGUMENT;
    if (tex->metadata_count > 0 && !tex->owns_metadata) return IBL_ERR_INVALID_ARGUMENT;
    for (int i = 0; i < tex->metadata_count; i++) {
        if (strcmp(tex->metadata[i].key, key) == 0) {
            char *v = dup_string(ctx, value);
            if (!v) return IBL_ERR_OUT_OF_MEMORY;
            ibl_free(ctx, tex->metadata[i].value);
            tex->metadata[i].value = v;
            return IBL_OK;
        }
    }
    ibl_key_value *grown = ibl_alloc(ctx, sizeof *grown * (size_t)(tex->metadata_count + 1));
    if (!grown) return IBL_ERR_OUT_OF_MEMORY;
    if (tex->metadata_count) memcpy(grown, tex->metadata, sizeof *grown * (size_t)tex->metadata_count);
    grown[tex->metadata_count].key = dup_string(ctx, key);
    grown[tex->metadata_count].value = dup_string(ctx, value);
    if (!grown[tex->metadata_count].key || !grown[tex->metadata_count].value) {
        ibl_free(ctx, grown[tex->metadata_count].key);
        ibl_free(ctx, grown[tex->metadata_count].value);
        ibl_free(ctx, grown);
        return IBL_ERR_OUT_OF_MEMORY;
    }
    ibl_free(ctx, tex->metadata);
    tex->metadata = grown;
    tex->metadata_count++;
    tex->owns_metadata = 1;
    return IBL_OK;
}

const char *ibl_texture_get_metadata(const ibl_texture *tex, const char *key)
{
    for (int i = 0; i < tex->metadata_count; i++)
        if (strcmp(tex->metadata[i].key, key) == 0) return tex->metadata[i].value;
    return NULL;
}
