/*
 * ibl/core.h - status codes, the context (allocator, parallel-for, limits, progress),
 * float RGBA images, cubemaps and generic textures.
 *
 * Conventions used everywhere in the library:
 *  - Pixels are linear float RGBA (4 floats per texel), rows stored top row first.
 *  - Every fallible call returns an ibl_status; the human-readable reason of the last
 *    failure is kept in the context (ibl_context_message). The library never prints,
 *    never exits, and owns no global mutable state.
 *  - Structs named *_desc are descriptors: zero-initialise them and set only what you need;
 *    a zero field means "the documented default".
 */
#ifndef IBL_CORE_H
#define IBL_CORE_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define IBL_VERSION_MAJOR 0
#define IBL_VERSION_MINOR 1
#define IBL_VERSION_PATCH 0
#define IBL_VERSION_STRING "0.1.0"

/* ------------------------------------------------------------------------------------------ */
/* Status                                                                                     */

typedef enum ibl_status {
    IBL_OK = 0,
    IBL_ERR_INVALID_ARGUMENT, /* the caller passed something the API does not accept        */
    IBL_ERR_OUT_OF_MEMORY,    /* an allocation failed                                       */
    IBL_ERR_TOO_LARGE,        /* the request exceeds the memory budget or size_t            */
    IBL_ERR_IO,               /* the operating system refused a read, write or rename       */
    IBL_ERR_FORMAT,           /* the input is malformed, truncated or inconsistent          */
    IBL_ERR_UNSUPPORTED,      /* well-formed, but a feature this library does not handle    */
    IBL_ERR_BAD_PIXELS,       /* infinite pixels (or other values) refused by the policy    */
    IBL_ERR_CANCELLED         /* the progress callback asked to stop                        */
} ibl_status;

/* A fixed English name for the status ("invalid argument", "malformed input", ...). */
const char *ibl_status_name(ibl_status status);

/* ------------------------------------------------------------------------------------------ */
/* Context: the host's hooks. One context per thread of the host that calls the library.     */

typedef struct ibl_allocator {
    void *(*alloc)(size_t bytes, void *user); /* must return memory aligned to 16 bytes */
    void (*free)(void *ptr, void *user);
    void *user;
} ibl_allocator;

/* Runs task(task_arg, i) for every i in [0, count), in any order, possibly concurrently,
 * and returns when all are done. The library always splits work into the same chunks
 * regardless of how many threads run them, so results are bit-identical at any thread count. */
typedef void (*ibl_task_fn)(void *task_arg, int index);
typedef void (*ibl_parallel_for_fn)(void *host, int count, ibl_task_fn task, void *task_arg);

/* Called now and then during long work with fraction in [0, 1]; return non-zero to cancel. */
typedef int (*ibl_progress_fn)(void *user, const char *stage, double fraction);

/* Which kernels run where a vector version exists (AVX2, FMA, F16C on x86-64). */
typedef enum ibl_kernels {
    IBL_KERNELS_AUTO = 0,    /* the fastest the CPU supports                                   */
    IBL_KERNELS_PORTABLE     /* plain C only: results that do not depend on the CPU's extensions */
} ibl_kernels;

typedef struct ibl_context_desc {
    ibl_allocator allocator;         /* zero: malloc/free                                       */
    ibl_parallel_for_fn parallel_for; /* zero: the built-in thread pool                          */
    void *parallel_host;             /* passed to parallel_for                                  */
    int threads;                     /* built-in pool size; 0: every online core; 1: no threads.
                                      * With parallel_for: how many threads the host runs a loop
                                      * on (0: unknown, taken as 1), so that the library splits
                                      * the work whose split depends on it (file reads, EXR
                                      * decoding, ASTC encoders) for that many; more at once is
                                      * safe, only slower */
    uint64_t max_bytes;              /* the memory budget (below); 0: ibl_default_max_bytes()   */
    ibl_progress_fn progress;        /* optional                                                */
    void *progress_user;
    ibl_kernels kernels;             /* zero: IBL_KERNELS_AUTO                                  */
} ibl_context_desc;

/* The memory budget. max_bytes caps the total of the blocks the library holds at any one
 * time: every allocation through the context (ibl_alloc, ibl_calloc; images, cubemaps,
 * textures, file buffers, scratch memory of every stage, on every thread), plus an estimate of
 * what the decoders it calls (OpenEXR, stb_image) allocate by themselves while they run. An
 * allocation that would take the total over it fails with IBL_ERR_TOO_LARGE and a one-line
 * message saying how much was asked, how much is in use and the budget; ibl_free gives the
 * bytes back. Readers check an input's declared size against the budget before decoding it.
 * Not counted: the context itself, its threads and their stacks, and the host's memory.
 *
 * The default (max_bytes = 0) is ibl_default_max_bytes(): half of the smallest of the
 * machine's physical memory, the process's address-space and data limits (setrlimit
 * RLIMIT_AS, RLIMIT_DATA) and its container's memory limit (Linux cgroup v2 memory.max or v1
 * memory.limit_in_bytes). The other half is left to what the budget does not count. */

typedef struct ibl_context ibl_context;

/* Creates a context; desc may be NULL for every default. */
ibl_status ibl_context_create(const ibl_context_desc *desc, ibl_context **out);
void ibl_context_destroy(ibl_context *ctx);
/* The message of the last failure in this context ("" if none). Valid until the next call. */
const char *ibl_context_message(const ibl_context *ctx);
/* The status of the last recorded failure. */
ibl_status ibl_context_status(const ibl_context *ctx);
/* Number of threads the context runs work on (with a host parallel_for: desc.threads, or 1). */
int ibl_context_threads(const ibl_context *ctx);
/* The memory budget in bytes: desc.max_bytes, or the default it resolved to. */
uint64_t ibl_context_max_bytes(const ibl_context *ctx);
/* Bytes the budget counts now, and the most it has counted since the context was created. */
uint64_t ibl_context_current_bytes(const ibl_context *ctx);
uint64_t ibl_context_peak_bytes(const ibl_context *ctx);
/* The budget a context gets when desc.max_bytes is 0, on this machine and in this process. */
uint64_t ibl_default_max_bytes(void);

/* Allocation through the context: counted against the memory budget, a message recorded on
 * failure. Blocks are aligned as the allocator's, and are freed with ibl_free: through the
 * context that allocated them, which gets the bytes back (through another context with the
 * same allocator they are freed but stay counted in the first), or NULL for both. */
void *ibl_alloc(ibl_context *ctx, size_t bytes);
void *ibl_calloc(ibl_context *ctx, size_t count, size_t size);
void ibl_free(ibl_context *ctx, void *ptr);
/* Runs task over [0, count) with the context's parallel-for. A task may start loops of its
 * own: on the built-in pool they run beside the outer loop, on every thread (a host's
 * parallel-for gets them as calls from inside its tasks). */
void ibl_parallel_for(ibl_context *ctx, int count, ibl_task_fn task, void *task_arg);

/* ------------------------------------------------------------------------------------------ */
/* Pixel formats (how texels are stored in a file; in memory they are always float RGBA).   */

typedef enum ibl_format {
    IBL_FORMAT_DEFAULT = 0,  /* the container's natural choice (RGBA16F for KTX2/DDS)     */
    IBL_FORMAT_RGBA16F,      /* VK_FORMAT_R16G16B16A16_SFLOAT / DXGI 10                  */
    IBL_FORMAT_RGBA32F,      /* VK_FORMAT_R32G32B32A32_SFLOAT / DXGI 2                   */
    IBL_FORMAT_RG11B10F,     /* VK_FORMAT_B10G11R11_UFLOAT_PACK32 / DXGI 26              */
    IBL_FORMAT_RGB9E5,       /* VK_FORMAT_E5B9G9R9_UFLOAT_PACK32 / DXGI 67               */
    IBL_FORMAT_RG16F,        /* VK_FORMAT_R16G16_SFLOAT / DXGI 34                        */
    IBL_FORMAT_RG32F,        /* VK_FORMAT_R32G32_SFLOAT / DXGI 16                        */
    IBL_FORMAT_RGB32F,       /* 3 x float (PFM, EXR, Radiance in-memory meaning)          */
    IBL_FORMAT_RGB16F,       /* 3 x half (EXR)                                            */
    IBL_FORMAT_RGBA8_SRGB,   /* 8-bit sRGB (PNG/JPEG previews)                            */
    IBL_FORMAT_RGBA16_UNORM, /* 16-bit linear (PNG tables)                                */
    IBL_FORMAT_RGBE,         /* shared exponent in 8-bit RGBA (Radiance; KTX2 R8G8B8A8)    */
    IBL_FORMAT_BC6H,         /* BC6H unsigned float: VK_FORMAT_BC6H_UFLOAT_BLOCK / DXGI 95 */
    IBL_FORMAT_BC6H_SIGNED,  /* BC6H signed float: VK_FORMAT_BC6H_SFLOAT_BLOCK / DXGI 96   */
    IBL_FORMAT_RGBM,         /* 8-bit RGBM (KTX2 R8G8B8A8_UNORM; ibl/compress.h)          */
    IBL_FORMAT_RGBD,         /* 8-bit RGBD (KTX2 R8G8B8A8_UNORM; ibl/compress.h)          */
    IBL_FORMAT_ASTC_4x4,     /* ASTC HDR, VK_FORMAT_ASTC_4x4_SFLOAT_BLOCK (KTX2 only)      */
    IBL_FORMAT_ASTC_5x4,
    IBL_FORMAT_ASTC_5x5,
    IBL_FORMAT_ASTC_6x5,
    IBL_FORMAT_ASTC_6x6,
    IBL_FORMAT_ASTC_8x5,
    IBL_FORMAT_ASTC_8x6,
    IBL_FORMAT_ASTC_8x8,
    IBL_FORMAT_RGBA8_UNORM,  /* 8-bit linear data (PNG: packed material channels)           */
    IBL_FORMAT_COUNT
} ibl_format;

/* The largest magnitude a format stores (65504 for half floats, 1 for 8/16-bit unorm,
 * FLT_MAX for 32-bit floats); writers store larger values as this one. */
float ibl_format_max_value(ibl_format format);
/* "rgba16f", "rgba32f", "rg11b10f", "rgb9e5", "rg16f", "rg32f", ... */
const char *ibl_format_name(ibl_format format);
/* Parses a name as above (case-insensitive; also "b10g11r11", "e5b9g9r9"); 0 if unknown
 * (*out untouched). */
int ibl_format_from_name(const char *name, ibl_format *out);
/* Non-zero for the block-compressed formats (BC6H, ASTC): the ones an encoder quality
 * (ibl_write_desc.quality) applies to. */
int ibl_format_is_block(ibl_format format);

/* ------------------------------------------------------------------------------------------ */
/* Images: one 2D float RGBA picture (a reader's output, a layout's input).                 */

typedef struct ibl_image {
    int width, height;
    float *pixels; /* width * height * 4 floats, top row first; owned by whoever allocated it */
} ibl_image;

ibl_status ibl_image_alloc(ibl_context *ctx, int width, int height, ibl_image *out);
void ibl_image_free(ibl_context *ctx, ibl_image *image);
static inline float *ibl_image_texel(const ibl_image *im, int x, int y)
{
    return im->pixels + ((size_t)y * (size_t)im->width + (size_t)x) * 4u;
}

/* Counts of non-finite and negative values found (and fixed) by ibl_sanitize_pixels. */
typedef struct ibl_pixel_report {
    uint64_t nan_count, inf_count, negative_count; /* texels with at least one such channel */
    uint64_t texel_count;
} ibl_pixel_report;

/* The policy all readers follow: NaN and negatives become 0; +-Inf is refused with
 * IBL_ERR_BAD_PIXELS unless clamp_infinite, in which case +Inf becomes clamp_value (or
 * 65504 if clamp_value <= 0) and -Inf 0. The report is filled either way. Alpha is kept. */
ibl_status ibl_sanitize_pixels(ibl_context *ctx, float *rgba, size_t texel_count,
                               int clamp_infinite, float clamp_value, ibl_pixel_report *report);

/* ------------------------------------------------------------------------------------------ */
/* Cubemaps: 6 square faces per level, a full or partial mip chain.                          */

enum { IBL_MAX_LEVELS = 16 };

typedef enum ibl_cube_face {
    IBL_FACE_POS_X = 0,
    IBL_FACE_NEG_X,
    IBL_FACE_POS_Y,
    IBL_FACE_NEG_Y,
    IBL_FACE_POS_Z,
    IBL_FACE_NEG_Z
} ibl_cube_face;

/* Memory layout (identical to a KTX2 cubemap's level images): for each level, faces in the
 * order +X -X +Y -Y +Z -Z, each face max(1, size >> level) squared texels, RGBA float,
 * row-major, row 0 at t = 0. One contiguous block. */
typedef struct ibl_cubemap {
    int size;    /* edge of a level-0 face in texels */
    int levels;  /* 1 .. log2(size) + 1             */
    float *data; /* ibl_cubemap_floats(size, levels) floats */
    int owns_data;
} ibl_cubemap;

static inline int ibl_level_size(int size, int level)
{
    int s = size >> level;
    return s < 1 ? 1 : s;
}
/* Number of levels of a full chain down to 1x1. */
int ibl_full_mip_count(int size);
/* Floats needed for a cubemap (0 if the arguments are invalid or overflow). */
size_t ibl_cubemap_floats(int size, int levels);
/* Allocates (zeroed). */
ibl_status ibl_cubemap_alloc(ibl_context *ctx, int size, int levels, ibl_cubemap *out);
/* Wraps caller-owned memory of ibl_cubemap_floats(size, levels) floats: no allocation. */
ibl_status ibl_cubemap_wrap(int size, int levels, float *memory, ibl_cubemap *out);
void ibl_cubemap_free(ibl_context *ctx, ibl_cubemap *cube);
/* Pointer to texel (0,0) of a face of a level. */
float *ibl_cubemap_face(const ibl_cubemap *cube, int level, int face);

/* ------------------------------------------------------------------------------------------ */
/* Textures: what containers (KTX2, KTX1, DDS) hold. 2D, 3D or cube, with mips and metadata. */

typedef enum ibl_texture_kind {
    IBL_TEXTURE_2D = 0,
    IBL_TEXTURE_3D,
    IBL_TEXTURE_CUBE,
    IBL_TEXTURE_CUBE_ARRAY /* depth cubes of one size (KTX2 layerCount, DDS arraySize) */
} ibl_texture_kind;

typedef struct ibl_key_value {
    char *key;   /* NUL-terminated UTF-8                     */
    char *value; /* NUL-terminated (KTX2 values are written with their NUL) */
} ibl_key_value;

/* Memory layout: for each level, for each face (1, 6 for cubes, 6 x layers for cube-map
 * arrays: layer by layer, each +X -X +Y -Y +Z -Z, as a KTX2 level), for each slice z (depth >>
 * level, at least 1, 3D only), rows top first, RGBA float. Cubes have width == height and are
 * laid out exactly like ibl_cubemap; layer i of a cube-map array is a cube at
 * ibl_texture_level(tex, level, 6 i). */
typedef struct ibl_texture {
    ibl_texture_kind kind;
    int width, height, depth; /* 3D: depth; cube-map array: the number of layers; else 1  */
    int levels;
    ibl_format format;        /* storage format read from / to write to a file */
    float *data;
    int owns_data;
    ibl_key_value *metadata;  /* owned by the texture when read from a file */
    int metadata_count;
    int owns_metadata;
} ibl_texture;

size_t ibl_texture_floats(ibl_texture_kind kind, int width, int height, int depth, int levels);
ibl_status ibl_texture_alloc(ibl_context *ctx, ibl_texture_kind kind, int width, int height,
                             int depth, int levels, ibl_texture *out);
void ibl_texture_free(ibl_context *ctx, ibl_texture *tex);
/* Texels of one level/face (face 0 for non-cubes; 6 layer + face for cube-map arrays); the
 * slices of a 3D level follow each other. */
float *ibl_texture_level(const ibl_texture *tex, int level, int face);
/* Faces per level: 1, 6 (cube) or 6 x layers (cube-map array). */
int ibl_texture_faces(const ibl_texture *tex);
/* A non-owning texture view of a cubemap (no copy). */
ibl_texture ibl_texture_from_cubemap(const ibl_cubemap *cube);
/* A non-owning cubemap view of a cube texture; IBL_ERR_INVALID_ARGUMENT if not a cube. */
ibl_status ibl_cubemap_from_texture(const ibl_texture *tex, ibl_cubemap *out);
/* Adds (copies) a key/value pair to a texture's metadata. */
ibl_status ibl_texture_set_metadata(ibl_context *ctx, ibl_texture *tex, const char *key,
                                    const char *value);
/* The value for key, or NULL. */
const char *ibl_texture_get_metadata(const ibl_texture *tex, const char *key);

#ifdef __cplusplus
}
#endif
#endif
