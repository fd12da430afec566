/* OpenEXR: the decoding and encoding are OpenEXR's own (C++ API, in exr_cpp.cpp); this file
 * checks the file's structure first (headers, windows, chunk offset table) so hostile sizes
 * are refused before OpenEXR or we allocate, then places the pixels.
 *
 * Read: half, float (and uint) channels, scanline or tiled (level 0 of mip/rip-mapped files),
 * every compression of OpenEXR 3.1 (NONE, RLE, ZIPS, ZIP, PIZ, PXR24, B44, B44A, DWAA, DWAB),
 * part 0 of multi-part files. Channels: R,G,B(,A); else Y(,A) as grey; else Y,RY,BY
 * (luminance/chroma, converted by OpenEXR); else the alphabetically first layer that has
 * .R, .G and .B. Deep files are refused. The result covers the display window: pixels of the
 * data window outside it are cropped, display pixels without data are 0 (alpha 0). Zeros are
 * not data, so they are bounded: a display window larger than EXR_FREE_FILL texels must be at
 * least 1/EXR_MAX_FILL_RATIO covered by the data window (a 335-byte file declaring a 1x1 data
 * window in a 16000x8000 display window would otherwise cost 2 GiB of zeros).
 * Write: R,G,B(,A) as half or float, scanline, with the chosen lossless compression. */
#include "io/exr_bridge.h"
#include "core/context_internal.h"
#include "io/io_internal.h"

#include <stdatomic.h>
#include <stdio.h>
#include <math.h>
#include <string.h>
#include <libdeflate.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "core/pixel_format.h"

/* ---- structural check ---------------------------------------------------------------- */

/* Largest buffer OpenEXR may be led to allocate for one tile, tile row or scanline block
 * (legitimate files need a few MiB; 65536 wide x 256 lines of 4 float channels is 256 MiB). */
#define EXR_MAX_BUFFER ((uint64_t)256 << 20)

typedef struct exr_shape {
    int32_t data[4], display[4]; /* xmin ymin xmax ymax */
    int has_data, has_display, has_tiles;
    int compression;
    uint32_t tile_w, tile_h;
    int tiled, multipart, deep;
    int channels;          /* in part 0's channel list            */
    uint64_t pixel_bytes;  /* bytes of one pixel of all channels  */
    int subsampled;        /* some channel has x or y sampling > 1 */
    const uint8_t *chlist; /* part 0's channel list (checked)     */
    size_t chlist_len;
    size_t table;          /* the chunk offset table's position   */
    uint64_t chunks;       /* level 0's chunks                    */
} exr_shape;

/* Scanlines per chunk of each compression (OpenEXR file layout). */
static const int lines_per_chunk[10] = {1, 1, 1, 16, 32, 16, 32, 32, 32, 256};

/* The most a chunk's pixels can outnumber its stored bytes, per compression, for the codecs
 * where that is bounded (0: not bounded, left to the memory budget): NONE stores them;
 * RLE codes at most 128 equal bytes in 2; ZIPS, ZIP are zlib (at most 1032 to 1, see
 * DEFLATE_MAX_RATIO in stb.c); PXR24 is zlib over 24 of each float's 32 bits; B44 and B44A store
 * a 4x4 block of halves (32 bytes) in at least 3 bytes and other channels as they are. PIZ
 * (Huffman with run codes) and DWAA/DWAB (zlib over run-length codes) have no useful bound. */
static const uint32_t max_expansion[10] = {1, 64, 1032, 1032, 0, 1376, 11, 11, 0, 0};

/* Zeros that the display window may add around the data window: any amount up to
 * EXR_FREE_FILL texels (16 MiB of floats), beyond that at most EXR_MAX_FILL_RATIO - 1 texels
 * of zeros for each texel of data. */
#define EXR_FREE_FILL ((uint64_t)1 << 20)
enum { EXR_MAX_FILL_RATIO = 16 };

static int32_t le32(const uint8_t *p)
{
    return (int32_t)((uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24);
}

static uint64_t le64(const uint8_t *p)
{
    return (uint64_t)(uint32_t)le32(p) | (uint64_t)(uint32_t)le32(p + 4) << 32;
}

/* Checks a channel list (name, pixel type, pLinear + 3 reserved, x/y sampling; an empty name
 * ends it exactly at the attribute's end: OpenEXR reads it by structure, not by size) and,
 * for part 0, counts channels and bytes per pixel (OpenEXR sizes its buffers by them). */
static const char *scan_chlist(const uint8_t *v, size_t len, exr_shape *sh, int record)
{
    size_t pos = 0;
    while (pos < len && v[pos] != 0) {
        const uint8_t *nul = memchr(v + pos, 0, len - pos);
        if (!nul || (size_t)(nul - v) + 1 + 16 > len) return "malformed channel list";
        pos = (size_t)(nul - v) + 1;
        int32_t type = le32(v + pos), xs = le32(v + pos + 8), ys = le32(v + pos + 12);
        if (type < 0 || type > 2 || xs < 1 || ys < 1) return "malformed channel list";
        if (record) {
            sh->pixel_bytes += type == 1 ? 2 : 4; /* HALF, else UINT/FLOAT */
            sh->channels++;
            if (xs != 1 || ys != 1) sh->subsampled = 1;
        }
        pos += 16;
    }
    if (pos + 1 != len) return "malformed channel list";
    return NULL;
}

/* OpenEXR 3.1 reads typed attributes by their type, not by the declared size, so a size that
 * disagrees with the type desynchronises its header parser from ours: refuse those. */
static const char *check_value(const char *type, const uint8_t *v, size_t len)
{
    static const struct {
        const char *type;
        size_t size;
    } fixed[] = {
        {"box2i", 16}, {"box2f", 16}, {"v2i", 8}, {"v2f", 8}, {"v2d", 16}, {"v3i", 12},
        {"v3f", 12}, {"v3d", 24}, {"int", 4}, {"float", 4}, {"double", 8}, {"rational", 8},
        {"timecode", 8}, {"keycode", 28}, {"chromaticities", 32}, {"m33f", 36}, {"m33d", 72},
        {"m44f", 64}, {"m44d", 128}, {"compression", 1}, {"lineOrder", 1}, {"envmap", 1},
        {"deepImageState", 1}, {"tiledesc", 9},
    };
    for (size_t i = 0; i < sizeof fixed / sizeof fixed[0]; i++)
        if (strcmp(type, fixed[i].type) == 0)
            return len == fixed[i].size ? NULL : "attribute size does not match its type";
    if (strcmp(type, "stringvector") == 0) { /* (int32 length, bytes)... filling the value */
        size_t pos = 0;
        while (pos < len) {
            if (len - pos < 4) return "malformed string vector";
            int32_t n = le32(v + pos);
            pos += 4;
            if (n < 0 || (size_t)n > len - pos) return "malformed string vector";
            pos += (size_t)n;
        }
    } else if (strcmp(type, "preview") == 0) { /* width, height, then RGBA8 pixels */
        if (len < 8) return "malformed preview";
        uint64_t pw = (uint32_t)le32(v), ph = (uint32_t)le32(v + 4);
        if (pw * ph * 4 != len - 8) return "malformed preview";
    } else if (strcmp(type, "floatvector") == 0 && len % 4 != 0) {
        return "malformed float vector";
    }
    return NULL;
}

/* A NUL-terminated string of at most max_len characters at b[*pos]; NULL if malformed. */
static const char *read_name(const uint8_t *b, size_t size, size_t *pos, size_t max_len)
{
    const uint8_t *start = b + *pos;
    size_t avail = size - *pos;
    const uint8_t *nul = memchr(start, 0, avail < max_len + 1 ? avail : max_len + 1);
    if (!nul) return NULL;
    *pos += (size_t)(nul - start) + 1;
    return (const char *)start;
}

/* Walks one header's attributes; records part 0's. Returns NULL or the problem. */
static const char *walk_header(const uint8_t *b, size_t size, size_t *pos, size_t max_name,
                               exr_shape *sh, int record)
{
    for (;;) {
        if (*pos >= size) return "truncated header";
        if (b[*pos] == 0) {
            (*pos)++;
            return NULL;
        }
        const char *name = read_name(b, size, pos, max_name);
        if (!name) return "bad attribute name";
        const char *type = read_name(b, size, pos, max_name);
        if (!type) return "bad attribute type";
        if (size - *pos < 4) return "truncated header";
        int32_t len = le32(b + *pos);
        *pos += 4;
        if (len < 0 || (size_t)len > size - *pos) return "attribute size beyond the end of the file";
        const uint8_t *v = b + *pos;
        int channels = record && strcmp(name, "channels") == 0;
        const char *bad = strcmp(type, "chlist") == 0 ? scan_chlist(v, (size_t)len, sh, channels)
                                                      : check_value(type, v, (size_t)len);
        if (bad) return bad;
        if (channels && strcmp(type, "chlist") == 0) {
            sh->chlist = v;
            sh->chlist_len = (size_t)len;
        }
        if (record) {
            if (strcmp(type, "box2i") == 0 && len == 16 &&
                (strcmp(name, "dataWindow") == 0 || strcmp(name, "displayWindow") == 0)) {
                int32_t *box = name[1] == 'a' ? sh->data : sh->display;
                for (int i = 0; i < 4; i++) box[i] = le32(v + 4 * i);
                if (name[1] == 'a') sh->has_data = 1;
                else sh->has_display = 1;
            } else if (strcmp(name, "compression") == 0 && len == 1) {
                sh->compression = v[0];
            } else if (strcmp(name, "tiles") == 0 && strcmp(type, "tiledesc") == 0 && len == 9) {
                sh->tile_w = (uint32_t)le32(v);
                sh->tile_h = (uint32_t)le32(v + 4);
                sh->has_tiles = 1;
            } else if (strcmp(name, "type") == 0) {
                if (len >= 4 && memcmp(v, "deep", 4) == 0) sh->deep = 1;
                if (len == 10 && memcmp(v, "tiledimage", 10) == 0) sh->tiled = 1;
            }
        }
        *pos += (size_t)len;
    }
}

static int64_t box_extent(const int32_t *box, int axis)
{
    return (int64_t)box[2 + axis] - (int64_t)box[axis] + 1;
}

/* The headers (up to the chunk offset table): what ibl__exr_info checks of the structure. */
static ibl_status check_headers(ibl_context *ctx, const uint8_t *b, size_t size, const char *name,
                                exr_shape *sh)
{
    memset(sh, 0, sizeof *sh);
    if (size < 8 || le32(b) != 20000630)
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: not an OpenEXR file", name);
    uint32_t version = (uint32_t)le32(b + 4);
    if ((version & 0xFF) != 2)
        return ibl__fail(ctx, IBL_ERR_UNSUPPORTED, "%s: OpenEXR version %u is not supported", name,
                        version & 0xFF);
    if (version & ~(uint32_t)0x1EFF)
        return ibl__fail(ctx, IBL_ERR_UNSUPPORTED, "%s: unknown OpenEXR feature flags 0x%x", name,
                        version);
    sh->tiled = (version & 0x200) != 0;
    sh->multipart = (version & 0x1000) != 0;
    sh->deep = (version & 0x800) != 0;
    size_t max_name = (version & 0x400) ? 255 : 31;
    size_t pos = 8;
    const char *problem = walk_header(b, size, &pos, max_name, sh, 1);
    /* Multi-part: more headers follow, the list ends with an empty header. */
    while (!problem && sh->multipart) {
        if (pos >= size) {
            problem = "truncated header list";
            break;
        }
        if (b[pos] == 0) {
            pos++;
            break;
        }
        problem = walk_header(b, size, &pos, max_name, sh, 0);
    }
    if (problem) return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: malformed OpenEXR: %s", name, problem);
    if (sh->deep)
        return ibl__fail(ctx, IBL_ERR_UNSUPPORTED, "%s: deep OpenEXR data is not supported", name);
    if (sh->channels == 0) return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: malformed OpenEXR: no channels", name);
    if (!sh->has_data || !sh->has_display)
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: malformed OpenEXR: no data or display window", name);
    for (int axis = 0; axis < 2; axis++) {
        int64_t d = box_extent(sh->data, axis), v = box_extent(sh->display, axis);
        if (d <= 0 || v <= 0 || d > IBL_MAX_DIMENSION || v > IBL_MAX_DIMENSION)
            return ibl__fail(ctx, IBL_ERR_FORMAT,
                            "%s: absurd OpenEXR window (data %lldx%lld, display %lldx%lld)", name,
                            (long long)box_extent(sh->data, 0), (long long)box_extent(sh->data, 1),
                            (long long)box_extent(sh->display, 0), (long long)box_extent(sh->display, 1));
    }
    if (sh->compression < 0 || sh->compression > 9)
        return ibl__fail(ctx, IBL_ERR_UNSUPPORTED, "%s: unknown OpenEXR compression %d", name,
                        sh->compression);
    uint64_t w = (uint64_t)box_extent(sh->data, 0), h = (uint64_t)box_extent(sh->data, 1);
    uint64_t chunks;
    if (sh->tiled) {
        if (!sh->has_tiles || sh->tile_w == 0 || sh->tile_h == 0 || sh->tile_w > 0x7FFFFFFFu ||
            sh->tile_h > 0x7FFFFFFFu)
            return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: malformed OpenEXR tile description", name);
        /* OpenEXR allocates a tile (tile_w x tile_h pixels) per buffer and, reading through
         * InputFile, a row of tiles (width x tile_h of every channel): keep both sane. */
        uint64_t th = sh->tile_h;
        if (sh->tile_w > IBL_MAX_DIMENSION || th > IBL_MAX_DIMENSION ||
            (uint64_t)sh->tile_w * th * sh->pixel_bytes > EXR_MAX_BUFFER ||
            w * th * 4 * (uint64_t)(sh->channels < 4 ? sh->channels : 4) > EXR_MAX_BUFFER)
            return ibl__fail(ctx, IBL_ERR_UNSUPPORTED, "%s: OpenEXR tiles of %ux%u are too large",
                            name, sh->tile_w, sh->tile_h);
        /* Level 0 comes first in the offset table; only its tiles are read. */
        chunks = ((w + sh->tile_w - 1) / sh->tile_w) * ((h + sh->tile_h - 1) / sh->tile_h);
    } else {
        uint64_t lpc = (uint64_t)lines_per_chunk[sh->compression];
        chunks = (h + lpc - 1) / lpc;
        if (w * lpc * sh->pixel_bytes > EXR_MAX_BUFFER)
            return ibl__fail(ctx, IBL_ERR_UNSUPPORTED, "%s: OpenEXR scanline blocks are too large", name);
    }
    sh->table = pos;
    sh->chunks = chunks;
    return IBL_OK;
}

/* The headers, then every chunk of level 0 must exist: offset in the file, its header and
 * data inside, and enough stored bytes for its pixels at the compression's best ratio. */
static ibl_status check_structure(ibl_context *ctx, const uint8_t *b, size_t size, const char *name,
                                  exr_shape *sh)
{
    ibl_status s = check_headers(ctx, b, size, name, sh);
    if (s != IBL_OK) return s;
    size_t pos = sh->table;
    uint64_t chunks = sh->chunks;
    uint64_t w = (uint64_t)box_extent(sh->data, 0), h = (uint64_t)box_extent(sh->data, 1);
    if (chunks > (size - pos) / 8)
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: truncated OpenEXR (offset table)", name);
    size_t table_end = pos + (size_t)chunks * 8;
    size_t chunk_header = (sh->multipart ? 4u : 0u) + (sh->tiled ? 16u : 4u);
    uint64_t ratio = sh->subsampled ? 0 : max_expansion[sh->compression];
    uint64_t across = sh->tiled ? (w + sh->tile_w - 1) / sh->tile_w : 1;
    for (uint64_t i = 0; i < chunks; i++) {
        uint64_t off = le64(b + pos + i * 8);
        if (off < table_end || off > size || size - off < chunk_header + 4)
            return ibl__fail(ctx, IBL_ERR_FORMAT,
                            "%s: truncated or incomplete OpenEXR (chunk %llu of %llu missing)", name,
                            (unsigned long long)i, (unsigned long long)chunks);
        int32_t packed = le32(b + off + chunk_header);
        if (packed < 0 || (uint64_t)packed > size - off - chunk_header - 4)
            return ibl__fail(ctx, IBL_ERR_FORMAT,
                            "%s: truncated OpenEXR (chunk %llu of %llu cut short)", name,
                            (unsigned long long)i, (unsigned long long)chunks);
        if (!ratio) continue;
        uint64_t cw, ch; /* the chunk's pixels: a tile, or a block of scanlines */
        if (sh->tiled) {
            uint64_t x0 = (i % across) * sh->tile_w, y0 = (i / across) * sh->tile_h;
            cw = w - x0 < sh->tile_w ? w - x0 : sh->tile_w;
            ch = h - y0 < sh->tile_h ? h - y0 : sh->tile_h;
        } else {
            uint64_t lpc = (uint64_t)lines_per_chunk[sh->compression], y0 = i * lpc;
            cw = w;
            ch = h - y0 < lpc ? h - y0 : lpc;
        }
        uint64_t raw = cw * ch * sh->pixel_bytes; /* <= EXR_MAX_BUFFER (checked above) */
        if ((uint64_t)packed * ratio < raw)
            return ibl__fail(ctx, IBL_ERR_FORMAT,
                             "%s: OpenEXR chunk %llu of %llu stores %d bytes, too few for its "
                             "%llux%llu pixels (truncated, or a forged size)",
                             name, (unsigned long long)i, (unsigned long long)chunks, packed,
                             (unsigned long long)cw, (unsigned long long)ch);
    }
    return IBL_OK;
}

/* Texels of the display window that the data window covers. */
static uint64_t window_overlap(const exr_shape *sh)
{
    int64_t x0 = sh->data[0] > sh->display[0] ? sh->data[0] : sh->display[0];
    int64_t x1 = sh->data[2] < sh->display[2] ? sh->data[2] : sh->display[2];
    int64_t y0 = sh->data[1] > sh->display[1] ? sh->data[1] : sh->display[1];
    int64_t y1 = sh->data[3] < sh->display[3] ? sh->data[3] : sh->display[3];
    if (x1 < x0 || y1 < y0) return 0;
    return (uint64_t)(x1 - x0 + 1) * (uint64_t)(y1 - y0 + 1);
}

/* ---- decode -------------------------------------------------------------------------- */

/* Pixels are decoded in bands of whole chunks (scanline blocks or tile rows), each band by
 * its own OpenEXR file object through ibl_parallel_for: a chunk decodes to the same pixels
 * whichever band or thread reads it, so the image does not depend on the thread count. */
enum { EXR_MAX_BANDS = 16 };
/* Above this many bytes per chunk buffer a file is read as one band (each band's reader holds
 * its own buffers). */
#define EXR_BAND_BUFFER ((uint64_t)16 << 20)

typedef struct exr_bands {
    const uint8_t *bytes;
    size_t size;
    const ibl__exr_header *hd;
    float *rgba;
    int width, lines, count;
    const ibl__pixel_policy *policy; /* NULL: the caller sanitizes the image */
    ibl_pixel_report reports[EXR_MAX_BANDS];
    int rc[EXR_MAX_BANDS];
    char err[EXR_MAX_BANDS][256];
} exr_bands;

/* Applies the pixel policy to `rows` decoded rows of `width` texels from row `row` on. */
static void sanitize_rows(const ibl__pixel_policy *policy, float *rgba, int width, int row, int rows,
                          ibl_pixel_report *report)
{
    size_t first = (size_t)row * (size_t)width, count = (size_t)rows * (size_t)width;
    (void)ibl_sanitize_pixels(NULL, rgba + first * 4, count, policy->clamp_infinite,
                              policy->clamp_value, report);
}

/* The bands' reports summed (integers: the same in any order) into the policy's. */
static void policy_done(ibl__pixel_policy *policy, const ibl_pixel_report *reports, int count,
                        uint64_t texels)
{
    ibl_pixel_report r = {0, 0, 0, texels};
    for (int i = 0; i < count; i++) {
        r.nan_count += reports[i].nan_count;
        r.inf_count += reports[i].inf_count;
        r.negative_count += reports[i].negative_count;
    }
    policy->report = r;
    policy->done = 1;
}

static void band_task(void *arg, int index)
{
    exr_bands *b = arg;
    int y0 = b->hd->data_min_y + index * b->lines;
    int y1 = index == b->count - 1 ? b->hd->data_max_y : y0 + b->lines - 1;
    b->rc[index] = ibl__exr_read_rows(b->bytes, b->size, b->hd, b->rgba, y0, y1, b->err[index],
                                      sizeof b->err[index]);
    if (b->rc[index] == 0 && b->policy)
        sanitize_rows(b->policy, b->rgba, b->width, y0 - b->hd->data_min_y, y1 - y0 + 1,
                      &b->reports[index]);
}

/* ---- fast path: scanline files without compression or with ZIP / ZIPS ----------------- *
 * These are decoded here, chunk by chunk, as OpenEXR does (a zlib stream, inflated by
 * libdeflate: 2-3x faster than zlib on whole buffers, and the 512 chain's input is 22 MB of
 * it; then the predictor and the byte interleaving of OpenEXR's Zip codec, then each
 * channel's samples into its slot), for lack of per-chunk parallelism and speed in OpenEXR's own path. Any
 * chunk this path does not find exactly as expected (sizes, y coordinates, zlib errors)
 * sends the whole file back to OpenEXR, whose result and messages are then the answer. The
 * samples are copied (float) or converted exactly (half), so both paths give the same bits
 * (tests/test_io.c compares them). */
enum { EXR_NONE = 0, EXR_ZIPS = 2, EXR_ZIP = 3, EXR_MAX_SLOTS = 64 };

typedef struct exr_fast {
    const uint8_t *bytes;
    size_t size;
    const exr_shape *sh;
    const ibl__exr_header *hd;
    float *rgba;
    const float *half_table; /* 65536 entries, or NULL when no half channel is read */
    int w, h, lines, chunks_per_band, bands;
    size_t line_bytes;
    /* per slot (R, G, B, A): the channel's type (1 HALF, 2 FLOAT, 0 absent) and its offset
     * in a line (bytes) */
    int type[4];
    size_t offset[4];
    /* work buffers: slot_count pairs of chunk buffers, claimed by running bands */
    uint8_t *work;
    size_t work_bytes;
    int slot_count;
    atomic_int busy[EXR_MAX_SLOTS];
    int failed[EXR_MAX_BANDS];
    const ibl__pixel_policy *policy; /* NULL: the caller sanitizes the image */
    ibl_pixel_report reports[EXR_MAX_BANDS];
} exr_fast;

/* Finds the channels the reader wants (the names OpenEXR is asked for in exr_cpp.cpp) in the
 * checked channel list; 0 when the file does not suit the fast path. */
static int fast_channels(exr_fast *f)
{
    const exr_shape *sh = f->sh;
    const ibl__exr_header *hd = f->hd;
    char want[4][160];
    const char *layer = hd->layer;
    if (hd->layout == IBL__EXR_RGB) {
        static const char *rgba = "RGBA";
        for (int c = 0; c < 4; c++)
            snprintf(want[c], sizeof want[c], "%s%s%c", layer, layer[0] ? "." : "", rgba[c]);
    } else if (hd->layout == IBL__EXR_GREY) {
        snprintf(want[0], sizeof want[0], "Y");
        want[1][0] = want[2][0] = 0;
        snprintf(want[3], sizeof want[3], "%s%sA", layer, layer[0] ? "." : "");
    } else {
        return 0;
    }
    int found[4] = {0, 0, 0, 0};
    for (int c = 0; c < 4; c++) f->type[c] = 0;
    const uint8_t *v = sh->chlist;
    size_t pos = 0, offset = 0;
    while (pos < sh->chlist_len && v[pos] != 0) {
        const char *name = (const char *)v + pos;
        pos += strlen(name) + 1; /* scan_chlist checked the NUL and the 16 bytes after it */
        int32_t type = le32(v + pos);
        pos += 16;
        for (int c = 0; c < 4; c++)
            if (want[c][0] && strcmp(name, want[c]) == 0) {
                f->type[c] = type;
                f->offset[c] = offset;
                found[c] = 1;
            }
        offset += type == 1 ? 2 : 4;
    }
    if (offset != sh->pixel_bytes) return 0; /* (more than one channel list) */
    for (int c = 0; c < 4; c++) {
        if (found[c] && f->type[c] != 1 && f->type[c] != 2) return 0; /* UINT: OpenEXR's path */
        if (!found[c] && want[c][0] && c != 3) return 0;
    }
    if (!found[3]) f->type[3] = -1; /* no alpha: 1 */
    for (int c = 0; c < 4; c++) f->offset[c] *= (size_t)f->w;
    return 1;
}

/* OpenEXR's Zip codec stores the bytes b[0], b[2], ... then b[1], b[3], ..., each as the
 * difference to the previous stored byte plus 128: undo the differences (a running sum, 16
 * bytes at a time with SSE2) and the interleaving. */
static void zip_unpredict(uint8_t *t, size_t n, uint8_t *out)
{
    size_t i = 0;
    uint8_t prev = 128; /* the first byte is stored as is: 128 + (t[0] - 128) */
#if defined(__SSE2__)
    const __m128i bias = _mm_set1_epi8((char)-128);
    __m128i carry = _mm_set1_epi8((char)prev);
    for (; i + 16 <= n; i += 16) {
        __m128i x = _mm_add_epi8(_mm_loadu_si128((const __m128i *)(const void *)(t + i)), bias);
        x = _mm_add_epi8(x, _mm_slli_si128(x, 1));
        x = _mm_add_epi8(x, _mm_slli_si128(x, 2));
        x = _mm_add_epi8(x, _mm_slli_si128(x, 4));
        x = _mm_add_epi8(x, _mm_slli_si128(x, 8));
        x = _mm_add_epi8(x, carry);
        _mm_storeu_si128((__m128i *)(void *)(t + i), x);
        carry = _mm_set1_epi8((char)t[i + 15]);
    }
    if (i) prev = t[i - 1];
#endif
    for (; i < n; i++) prev = t[i] = (uint8_t)(prev + t[i] - 128);
    const uint8_t *t1 = t, *t2 = t + (n + 1) / 2;
    size_t k = 0;
#if defined(__SSE2__)
    for (; 2 * k + 32 <= n; k += 16) {
        __m128i a = _mm_loadu_si128((const __m128i *)(const void *)(t1 + k));
        __m128i b = _mm_loadu_si128((const __m128i *)(const void *)(t2 + k));
        _mm_storeu_si128((__m128i *)(void *)(out + 2 * k), _mm_unpacklo_epi8(a, b));
        _mm_storeu_si128((__m128i *)(void *)(out + 2 * k + 16), _mm_unpackhi_epi8(a, b));
    }
#endif
    for (; 2 * k < n; k++) {
        out[2 * k] = t1[k];
        if (2 * k + 1 < n) out[2 * k + 1] = t2[k];
    }
}

/* Decodes the chunks of one band; returns 0 on success, 1 when OpenEXR must do the file. */
static int fast_band_with(exr_fast *f, int band, uint8_t *buf, uint8_t *raw, struct libdeflate_decompressor *inflater);

static int fast_band(exr_fast *f, int band, uint8_t *buf, uint8_t *raw)
{
    /* libdeflate's state (~32 KB) for this band: it allocates with malloc, as zlib did */
    struct libdeflate_decompressor *inflater = libdeflate_alloc_decompressor();
    if (!inflater) return 1;
    int rc = fast_band_with(f, band, buf, raw, inflater);
    libdeflate_free_decompressor(inflater);
    if (rc == 0 && f->policy) {
        int row0 = band * f->chunks_per_band * f->lines;
        int row1 = row0 + f->chunks_per_band * f->lines < f->h ? row0 + f->chunks_per_band * f->lines : f->h;
        sanitize_rows(f->policy, f->rgba, f->w, row0, row1 - row0, &f->reports[band]);
    }
    return rc;
}

static int fast_band_with(exr_fast *f, int band, uint8_t *buf, uint8_t *raw, struct libdeflate_decompressor *inflater)
{
    const exr_shape *sh = f->sh;
    int first = band * f->chunks_per_band, chunks = (f->h + f->lines - 1) / f->lines;
    int last = first + f->chunks_per_band < chunks ? first + f->chunks_per_band : chunks;
    size_t w = (size_t)f->w;
    for (int i = first; i < last; i++) {
        uint64_t off = le64(f->bytes + sh->table + (size_t)i * 8); /* checked in range */
        int32_t y = le32(f->bytes + off), packed = le32(f->bytes + off + 4);
        const uint8_t *data = f->bytes + off + 8;
        int row0 = i * f->lines;
        int n_lines = f->h - row0 < f->lines ? f->h - row0 : f->lines;
        size_t expect = (size_t)n_lines * f->line_bytes;
        if ((int64_t)y != (int64_t)sh->data[1] + row0) return 1;
        const uint8_t *lines;
        if ((size_t)packed == expect) {
            lines = data; /* stored: compression did not pay */
        } else if (sh->compression == EXR_NONE || (size_t)packed > expect) {
            return 1;
        } else {
            size_t got = 0;
            if (libdeflate_zlib_decompress(inflater, data, (size_t)packed, buf, expect, &got) != LIBDEFLATE_SUCCESS ||
                got != expect)
                return 1;
            zip_unpredict(buf, expect, raw);
            lines = raw;
        }
        for (int j = 0; j < n_lines; j++) {
            const uint8_t *line = lines + (size_t)j * f->line_bytes;
            float *dst = f->rgba + (size_t)(row0 + j) * w * 4;
            for (int c = 0; c < 4; c++) {
                float *d = dst + c;
                if (f->type[c] == 2) {
                    const uint8_t *src = line + f->offset[c];
                    for (size_t x = 0; x < w; x++) {
                        uint32_t u = (uint32_t)le32(src + 4 * x);
                        memcpy(d + 4 * x, &u, sizeof u);
                    }
                } else if (f->type[c] == 1) {
                    const uint8_t *src = line + f->offset[c];
                    for (size_t x = 0; x < w; x++)
                        d[4 * x] = f->half_table[src[2 * x] | src[2 * x + 1] << 8];
                } else if (f->type[c] == -1) {
                    for (size_t x = 0; x < w; x++) d[4 * x] = 1.0f;
                }
            }
            if (f->hd->layout == IBL__EXR_GREY)
                for (size_t x = 0; x < w; x++) dst[4 * x + 1] = dst[4 * x + 2] = dst[4 * x];
        }
    }
    return 0;
}

static void fast_task(void *arg, int band)
{
    exr_fast *f = arg;
    /* at most slot_count bands run at once (one per thread): one of the slots is free */
    int slot = band % f->slot_count;
    for (;;) {
        int expected = 0;
        if (atomic_compare_exchange_strong(&f->busy[slot], &expected, 1)) break;
        slot = (slot + 1) % f->slot_count;
    }
    uint8_t *buf = f->work + (size_t)slot * 2 * f->work_bytes;
    f->failed[band] = fast_band(f, band, buf, buf + f->work_bytes);
    atomic_store(&f->busy[slot], 0);
}

/* 1: decoded; 0: not a file for this path, it found something unexpected or its buffers
 * could not be allocated (OpenEXR reads the file then, with its own buffers as before). */
static int read_fast(ibl_context *ctx, const uint8_t *bytes, size_t size, const exr_shape *sh,
                     const ibl__exr_header *hd, float *rgba, ibl__pixel_policy *policy)
{
    int comp = sh->compression;
    if (sh->tiled || sh->multipart || sh->subsampled || !sh->chlist ||
        (comp != EXR_NONE && comp != EXR_ZIPS && comp != EXR_ZIP))
        return 0;
    exr_fast *f = ibl_alloc(ctx, sizeof *f);
    if (!f) return 0;
    memset(f, 0, sizeof *f);
    f->bytes = bytes;
    f->size = size;
    f->sh = sh;
    f->hd = hd;
    f->rgba = rgba;
    f->policy = policy;
    f->w = (int)box_extent(sh->data, 0);
    f->h = (int)box_extent(sh->data, 1);
    f->lines = lines_per_chunk[comp];
    f->line_bytes = (size_t)f->w * (size_t)sh->pixel_bytes;
    int ok = fast_channels(f);
    int chunks = (f->h + f->lines - 1) / f->lines;
    f->chunks_per_band = (chunks + EXR_MAX_BANDS - 1) / EXR_MAX_BANDS;
    f->bands = (chunks + f->chunks_per_band - 1) / f->chunks_per_band;
    int threads = ibl_context_threads(ctx);
    f->slot_count = threads < f->bands ? threads : f->bands;
    if (f->slot_count > EXR_MAX_SLOTS) f->slot_count = EXR_MAX_SLOTS;
    if (f->slot_count < 1) f->slot_count = 1;
    f->work_bytes = (size_t)f->lines * f->line_bytes; /* <= EXR_MAX_BUFFER (checked) */
    /* huge chunks (a very wide or many-channel file): one band at a time */
    if ((uint64_t)f->work_bytes * 2 * (uint64_t)f->slot_count > 4 * EXR_BAND_BUFFER) threads = f->slot_count = 1;
    float *table = NULL;
    int rc = ok ? 1 : 0;
    if (ok && (f->type[0] == 1 || f->type[1] == 1 || f->type[2] == 1 || f->type[3] == 1)) {
        table = ibl_alloc(ctx, 65536 * sizeof(float));
        if (!table) rc = 0;
        else
            for (uint32_t i = 0; i < 65536; i++) table[i] = ibl_half_to_float((uint16_t)i);
        f->half_table = table;
    }
    if (rc == 1) {
        f->work = ibl_alloc(ctx, (size_t)f->slot_count * 2 * f->work_bytes);
        if (!f->work) rc = 0;
    }
    if (rc == 1) {
        for (int i = 0; i < EXR_MAX_SLOTS; i++) atomic_init(&f->busy[i], 0);
        /* one thread (or a host's parallel_for, whose concurrency is unknown): in order here */
        if (threads > 1) ibl_parallel_for(ctx, f->bands, fast_task, f);
        else
            for (int b = 0; b < f->bands; b++) f->failed[b] = fast_band(f, b, f->work, f->work + f->work_bytes);
        for (int b = 0; b < f->bands; b++)
            if (f->failed[b]) rc = 0;
        if (rc == 1 && policy) policy_done(policy, f->reports, f->bands, (uint64_t)f->w * (uint64_t)f->h);
    }
    ibl_free(ctx, f->work);
    ibl_free(ctx, table);
    ibl_free(ctx, f);
    return rc;
}

/* What OpenEXR allocates by itself to read the file: per reader (one, or one per band that
 * runs at the same time) about three buffers of a chunk (the stored bytes, the decompressed
 * ones, the codec's scratch), where a chunk read through InputFile is a whole row of tiles;
 * luminance/chroma files are first decoded into a whole data window of half RGBA. An
 * estimate: it is reserved in the budget while OpenEXR runs. */
static uint64_t openexr_bytes(const exr_shape *sh, const ibl__exr_header *hd, uint64_t readers)
{
    uint64_t w = (uint64_t)box_extent(sh->data, 0), h = (uint64_t)box_extent(sh->data, 1);
    uint64_t lines = sh->tiled ? sh->tile_h : (uint64_t)lines_per_chunk[sh->compression];
    uint64_t bytes = readers * 3 * w * lines * sh->pixel_bytes;
    if (hd->layout == IBL__EXR_LUMA_CHROMA) bytes += w * h * 4 * 2;
    return bytes;
}

static int read_pixels(ibl_context *ctx, const uint8_t *bytes, size_t size, const exr_shape *sh,
                       ibl__exr_reader *reader, const ibl__exr_header *hd, float *rgba,
                       ibl__pixel_policy *policy, char *err, size_t err_size)
{
    uint64_t w = (uint64_t)box_extent(sh->data, 0), h = (uint64_t)box_extent(sh->data, 1);
    uint64_t lines = sh->tiled ? sh->tile_h : (uint64_t)lines_per_chunk[sh->compression];
    uint64_t chunks = (h + lines - 1) / lines;
    uint64_t per_band = (chunks + EXR_MAX_BANDS - 1) / EXR_MAX_BANDS;
    if (read_fast(ctx, bytes, size, sh, hd, rgba, policy)) return 0;
    exr_bands *b = NULL;
    if (hd->layout != IBL__EXR_LUMA_CHROMA && chunks >= 2 &&
        w * lines * (sh->pixel_bytes > 16 ? sh->pixel_bytes : 16) <= EXR_BAND_BUFFER)
        b = ibl_alloc(ctx, sizeof *b); /* if this fails: one band, as before */
    int bands = b ? (int)((h + per_band * lines - 1) / (per_band * lines)) : 1;
    int threads = ibl_context_threads(ctx);
    uint64_t reserved = openexr_bytes(sh, hd, (uint64_t)(bands < threads ? bands : threads));
    if (ibl__budget_reserve(ctx, reserved) != IBL_OK) {
        snprintf(err, err_size, "decoding: %s", ibl_context_message(ctx));
        ibl_free(ctx, b);
        return IBL_ERR_TOO_LARGE;
    }
    int rc = 0;
    if (!b) {
        rc = ibl__exr_read(reader, rgba, err, err_size);
    } else {
        b->bytes = bytes;
        b->size = size;
        b->hd = hd;
        b->rgba = rgba;
        b->width = (int)w;
        b->lines = (int)(per_band * lines);
        b->count = bands;
        b->policy = policy;
        ibl_parallel_for(ctx, b->count, band_task, b);
        /* the first failing band's message: the one a reader going down the image meets first */
        for (int i = 0; i < b->count && !rc; i++)
            if (b->rc[i]) {
                rc = b->rc[i];
                snprintf(err, err_size, "%s", b->err[i]);
            }
        if (!rc && policy) policy_done(policy, b->reports, b->count, w * h);
        ibl_free(ctx, b);
    }
    ibl__budget_release(ctx, reserved);
    return rc;
}

/* The windows OpenEXR parsed must be those check_headers read (trust only what was checked),
 * and the display window must be covered enough by the data window (EXR_MAX_FILL_RATIO). */
static ibl_status check_windows(ibl_context *ctx, const char *name, const exr_shape *sh,
                                const ibl__exr_header *hd)
{
    if (hd->data_min_x != sh->data[0] || hd->data_min_y != sh->data[1] ||
        hd->data_max_x != sh->data[2] || hd->data_max_y != sh->data[3] ||
        hd->display_min_x != sh->display[0] || hd->display_min_y != sh->display[1] ||
        hd->display_max_x != sh->display[2] || hd->display_max_y != sh->display[3])
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: inconsistent OpenEXR windows", name);
    int dw = (int)box_extent(sh->data, 0), dh = (int)box_extent(sh->data, 1);
    int vw = (int)box_extent(sh->display, 0), vh = (int)box_extent(sh->display, 1);
    uint64_t display = (uint64_t)vw * (uint64_t)vh, covered = window_overlap(sh);
    if (display > EXR_FREE_FILL && covered < display / EXR_MAX_FILL_RATIO)
        return ibl__fail(ctx, IBL_ERR_UNSUPPORTED,
                         "%s: the data window (%dx%d) covers %llu of the %dx%d texels of the "
                         "display window; ibl fills at most %d/%d of an image with zeros",
                         name, dw, dh, (unsigned long long)covered, vw, vh, EXR_MAX_FILL_RATIO - 1,
                         EXR_MAX_FILL_RATIO);
    return IBL_OK;
}

/* The format a decode reports: half when every channel read is half, alpha when A exists. */
static ibl_format exr_format(const ibl__exr_header *hd)
{
    return hd->all_half ? (hd->has_alpha ? IBL_FORMAT_RGBA16F : IBL_FORMAT_RGB16F)
                        : (hd->has_alpha ? IBL_FORMAT_RGBA32F : IBL_FORMAT_RGB32F);
}

ibl_status ibl__exr_info(ibl_context *ctx, const uint8_t *bytes, size_t size, const char *name,
                         ibl_file_info *info)
{
    exr_shape sh;
    ibl_status s = check_headers(ctx, bytes, size, name, &sh);
    if (s != IBL_OK) return s;
    char err[256] = "";
    ibl__exr_header hd;
    int rc = ibl__exr_read_header(bytes, size, &hd, err, sizeof err);
    if (rc) return ibl__fail(ctx, (ibl_status)rc, "%s: %s", name, err);
    s = check_windows(ctx, name, &sh, &hd);
    if (s != IBL_OK) return s;
    info->width = (int)box_extent(sh.display, 0); /* the decode's image is the display window */
    info->height = (int)box_extent(sh.display, 1);
    info->format = exr_format(&hd);
    info->has_alpha = hd.has_alpha;
    return IBL_OK;
}

ibl_status ibl__exr_decode(ibl_context *ctx, const uint8_t *bytes, size_t size, const char *name,
                           ibl_texture *out, ibl_file_info *info)
{
    return ibl__exr_decode_sanitized(ctx, bytes, size, name, out, info, NULL);
}

ibl_status ibl__exr_decode_sanitized(ibl_context *ctx, const uint8_t *bytes, size_t size,
                                     const char *name, ibl_texture *out, ibl_file_info *info,
                                     ibl__pixel_policy *policy)
{
    /* the header is parsed and the image allocated before the first band: wake the pool now */
    ibl__parallel_warm(ctx);
    exr_shape sh;
    ibl_status s = check_structure(ctx, bytes, size, name, &sh);
    if (s != IBL_OK) return s;
    char err[256] = "";
    ibl__exr_reader *reader = NULL;
    ibl__exr_header hd;
    int rc = ibl__exr_open(bytes, size, &reader, &hd, err, sizeof err);
    if (rc) return ibl__fail(ctx, (ibl_status)rc, "%s: %s", name, err);
    s = check_windows(ctx, name, &sh, &hd);
    if (s != IBL_OK) {
        ibl__exr_close(reader);
        return s;
    }
    int dw = (int)box_extent(sh.data, 0), dh = (int)box_extent(sh.data, 1);
    int vw = (int)box_extent(sh.display, 0), vh = (int)box_extent(sh.display, 1);
    int same = memcmp(sh.data, sh.display, sizeof sh.data) == 0;
    uint64_t display = (uint64_t)vw * (uint64_t)vh;
    uint64_t texel = 4 * sizeof(float);
    s = ibl__budget_check(ctx, display * texel + (same ? 0 : (uint64_t)dw * (uint64_t)dh * texel));
    if (s != IBL_OK) {
        ibl__exr_close(reader);
        return ibl__fail_named(ctx, s, name);
    }
    if (same) {
        /* every texel is decoded into it: not zeroed first (a serial pass that would also
         * take all the page faults on one thread; the decoding bands take them instead) */
        memset(out, 0, sizeof *out);
        out->data = ibl_alloc(ctx, (size_t)vw * (size_t)vh * 4 * sizeof(float));
        s = out->data ? IBL_OK : ibl_context_status(ctx);
        out->kind = IBL_TEXTURE_2D;
        out->width = vw;
        out->height = vh;
        out->depth = out->levels = 1;
        out->owns_data = 1;
    } else {
        s = ibl_texture_alloc(ctx, IBL_TEXTURE_2D, vw, vh, 1, 1, out);
    }
    if (s != IBL_OK) {
        ibl__exr_close(reader);
        memset(out, 0, sizeof *out);
        return ibl__fail_named(ctx, s, name);
    }
    float *target = out->data;
    if (!same) {
        target = ibl_alloc(ctx, (size_t)dw * (size_t)dh * 4 * sizeof(float));
        if (!target) {
            s = ibl_context_status(ctx);
            ibl__exr_close(reader);
            ibl_texture_free(ctx, out);
            return ibl__fail_named(ctx, s, name);
        }
    }
    /* the bands sanitize their rows only where they are the image's (no window to copy) */
    if (policy) policy->done = 0;
    rc = read_pixels(ctx, bytes, size, &sh, reader, &hd, target, same ? policy : NULL, err, sizeof err);
    ibl__exr_close(reader);
    if (rc) {
        if (!same) ibl_free(ctx, target);
        ibl_texture_free(ctx, out);
        return ibl__fail(ctx, (ibl_status)rc, "%s: %s", name, err);
    }
    if (!same) {
        /* Copy the overlap of the data window into the display window. */
        int64_t x0 = sh.data[0] > sh.display[0] ? sh.data[0] : sh.display[0];
        int64_t x1 = sh.data[2] < sh.display[2] ? sh.data[2] : sh.display[2];
        int64_t y0 = sh.data[1] > sh.display[1] ? sh.data[1] : sh.display[1];
        int64_t y1 = sh.data[3] < sh.display[3] ? sh.data[3] : sh.display[3];
        for (int64_t y = y0; y <= y1 && x0 <= x1; y++) {
            const float *src = target + ((size_t)(y - sh.data[1]) * (size_t)dw + (size_t)(x0 - sh.data[0])) * 4;
            float *dst = out->data + ((size_t)(y - sh.display[1]) * (size_t)vw + (size_t)(x0 - sh.display[0])) * 4;
            memcpy(dst, src, (size_t)(x1 - x0 + 1) * 4 * sizeof(float));
        }
        ibl_free(ctx, target);
    }
    out->format = exr_format(&hd);
    info->format = out->format;
    info->has_alpha = hd.has_alpha;
    return IBL_OK;
}

/* ---- encode -------------------------------------------------------------------------- */

static void *exr_alloc(void *user, size_t bytes)
{
    return ibl_alloc(user, bytes);
}

ibl_status ibl__exr_encode(ibl_context *ctx, const ibl_image *image, const ibl_write_desc *desc,
                           const char *name, void **bytes, size_t *size)
{
    int channels, half;
    switch (desc->format) {
    case IBL_FORMAT_DEFAULT: {
        /* float (half would turn a bright sun infinite); RGB unless the alpha says something */
        size_t n = (size_t)image->width * (size_t)image->height;
        channels = 3;
        for (size_t i = 0; i < n; i++)
            if (image->pixels[i * 4 + 3] != 1.0f) {
                channels = 4;
                break;
            }
        half = 0;
        break;
    }
    case IBL_FORMAT_RGBA16F: channels = 4; half = 1; break;
    case IBL_FORMAT_RGB16F: channels = 3; half = 1; break;
    case IBL_FORMAT_RGBA32F: channels = 4; half = 0; break;
    case IBL_FORMAT_RGB32F: channels = 3; half = 0; break;
    default:
        return ibl__fail(ctx, IBL_ERR_UNSUPPORTED,
                        "%s: OpenEXR output stores rgba16f, rgb16f, rgba32f or rgb32f, not %s", name,
                        ibl_format_name(desc->format));
    }
    int compression;
    switch (desc->exr_compression) {
    case IBL_EXR_NONE: compression = 0; break;
    case IBL_EXR_RLE: compression = 1; break;
    case IBL_EXR_ZIPS: compression = 2; break;
    case IBL_EXR_PIZ: compression = 4; break;
    case IBL_EXR_DEFAULT:
    case IBL_EXR_ZIP: compression = 3; break;
    default:
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "%s: unknown OpenEXR compression %d", name,
                        (int)desc->exr_compression);
    }
    char err[256] = "";
    int rc = ibl__exr_write(image->pixels, image->width, image->height, channels, half, compression,
                            exr_alloc, ctx, bytes, size, err, sizeof err);
    if (rc) return ibl__fail(ctx, (ibl_status)rc, "%s: cannot encode OpenEXR: %s", name, err);
    if (half && desc->report) {
        /* the C++ side stores values past 65504 as 65504; count them as the containers do */
        size_t n = (size_t)image->width * (size_t)image->height, over = 0;
        for (size_t i = 0; i < n; i++) {
            int o = 0;
            for (int c = 0; c < channels; c++) o |= fabsf(image->pixels[i * 4 + (size_t)c]) > 65504.0f;
            over += (size_t)o;
        }
        desc->report->clamped_texels += over;
    }
    return IBL_OK;
}
