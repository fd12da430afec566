/* Files and dispatch: type detection, whole-file reads, atomic writes, the readers'
 * pixel policy and the writers' choice of container. The per-format code lives in
 * hdr.c, exr.c, pfm.c, png.c, jpeg.c and the container files; see io_internal.h for the
 * contract. */
#include "io/io_internal.h"
#include "core/context_internal.h"

#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

/* ---- file types ---------------------------------------------------------------------- */

const char *ibl_file_type_name(ibl_file_type type)
{
    switch (type) {
    case IBL_FILE_HDR: return "hdr";
    case IBL_FILE_EXR: return "exr";
    case IBL_FILE_PFM: return "pfm";
    case IBL_FILE_PNG: return "png";
    case IBL_FILE_JPEG: return "jpeg";
    case IBL_FILE_KTX2: return "ktx2";
    case IBL_FILE_KTX1: return "ktx";
    case IBL_FILE_DDS: return "dds";
    case IBL_FILE_UNKNOWN: break;
    }
    return "unknown";
}

ibl_file_type ibl_file_type_from_path(const char *path)
{
    static const struct {
        const char *ext;
        ibl_file_type type;
    } table[] = {
        {"hdr", IBL_FILE_HDR},   {"pic", IBL_FILE_HDR},   {"exr", IBL_FILE_EXR},
        {"pfm", IBL_FILE_PFM},   {"png", IBL_FILE_PNG},   {"jpg", IBL_FILE_JPEG},
        {"jpeg", IBL_FILE_JPEG}, {"ktx2", IBL_FILE_KTX2}, {"ktx", IBL_FILE_KTX1},
        {"dds", IBL_FILE_DDS},
    };
    if (!path) return IBL_FILE_UNKNOWN;
    const char *slash = strrchr(path, '/');
    const char *base = slash ? slash + 1 : path;
    const char *dot = strrchr(base, '.');
    if (!dot || dot == base) return IBL_FILE_UNKNOWN;
    for (size_t i = 0; i < sizeof table / sizeof table[0]; i++)
        if (strcasecmp(dot + 1, table[i].ext) == 0) return table[i].type;
    return IBL_FILE_UNKNOWN;
}

static int starts_with(const uint8_t *b, size_t size, const void *magic, size_t n)
{
    return size >= n && memcmp(b, magic, n) == 0;
}

ibl_file_type ibl_file_type_sniff(const void *bytes, size_t size)
{
    const uint8_t *b = bytes;
    if (!b) return IBL_FILE_UNKNOWN;
    static const uint8_t ktx2[12] = {0xAB, 'K', 'T', 'X', ' ', '2', '0', 0xBB, '\r', '\n', 0x1A, '\n'};
    static const uint8_t ktx1[12] = {0xAB, 'K', 'T', 'X', ' ', '1', '1', 0xBB, '\r', '\n', 0x1A, '\n'};
    static const uint8_t png[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
    static const uint8_t exr[4] = {0x76, 0x2F, 0x31, 0x01};
    static const uint8_t jpeg[3] = {0xFF, 0xD8, 0xFF};
    if (starts_with(b, size, ktx2, sizeof ktx2)) return IBL_FILE_KTX2;
    if (starts_with(b, size, ktx1, sizeof ktx1)) return IBL_FILE_KTX1;
    if (starts_with(b, size, png, sizeof png)) return IBL_FILE_PNG;
    if (starts_with(b, size, exr, sizeof exr)) return IBL_FILE_EXR;
    if (starts_with(b, size, jpeg, sizeof jpeg)) return IBL_FILE_JPEG;
    if (starts_with(b, size, "DDS ", 4)) return IBL_FILE_DDS;
    /* Radiance files start with "#?" and the program name ("#?RADIANCE", "#?RGBE"). */
    if (starts_with(b, size, "#?", 2)) return IBL_FILE_HDR;
    /* PFM: "PF" (colour) or "Pf" (grey) followed by white space. */
    if (size >= 3 && b[0] == 'P' && (b[1] == 'F' || b[1] == 'f') &&
        (b[2] == '\n' || b[2] == '\r' || b[2] == ' ' || b[2] == '\t'))
        return IBL_FILE_PFM;
    return IBL_FILE_UNKNOWN;
}

int ibl_file_type_is_container(ibl_file_type type)
{
    return type == IBL_FILE_KTX2 || type == IBL_FILE_KTX1 || type == IBL_FILE_DDS;
}

int ibl_file_type_writes_format(ibl_file_type type, ibl_format f)
{
    if (f == IBL_FORMAT_DEFAULT) return type != IBL_FILE_UNKNOWN;
    switch (type) {
    case IBL_FILE_KTX2:
        if (f == IBL_FORMAT_RGBE || f == IBL_FORMAT_RGBM || f == IBL_FORMAT_RGBD ||
            (f >= IBL_FORMAT_ASTC_4x4 && f <= IBL_FORMAT_ASTC_8x8))
            return 1;
        /* fall through */
    case IBL_FILE_DDS:
        if (f == IBL_FORMAT_BC6H || f == IBL_FORMAT_BC6H_SIGNED) return type != IBL_FILE_KTX1;
        /* fall through */
    case IBL_FILE_KTX1:
        return f == IBL_FORMAT_RGBA16F || f == IBL_FORMAT_RGBA32F || f == IBL_FORMAT_RG11B10F ||
               f == IBL_FORMAT_RGB9E5 || f == IBL_FORMAT_RG16F || f == IBL_FORMAT_RG32F;
    case IBL_FILE_EXR:
        return f == IBL_FORMAT_RGBA16F || f == IBL_FORMAT_RGB16F || f == IBL_FORMAT_RGBA32F ||
               f == IBL_FORMAT_RGB32F;
    case IBL_FILE_PNG:
        return f == IBL_FORMAT_RGBA8_SRGB || f == IBL_FORMAT_RGBA8_UNORM ||
               f == IBL_FORMAT_RGBA16_UNORM || f == IBL_FORMAT_RGBM;
    case IBL_FILE_JPEG: return f == IBL_FORMAT_RGBA8_SRGB;
    case IBL_FILE_HDR: return f == IBL_FORMAT_RGBE;
    case IBL_FILE_PFM: return f == IBL_FORMAT_RGB32F;
    case IBL_FILE_UNKNOWN: break;
    }
    return 0;
}

/* ---- whole-file read ----------------------------------------------------------------- */

ibl_status ibl__fail_named(ibl_context *ctx, ibl_status status, const char *name)
{
    char saved[400];
    const char *m = ibl_context_message(ctx);
    snprintf(saved, sizeof saved, "%s", m && m[0] ? m : ibl_status_name(status));
    return ibl__fail(ctx, status, "%s: %s", name, saved);
}

static ibl_status read_all(ibl_context *ctx, int fd, const char *path, uint8_t *dst, size_t size,
                           size_t *got)
{
    size_t done = 0;
    while (done < size) {
        ssize_t n = read(fd, dst + done, size - done);
        if (n < 0) {
            if (errno == EINTR) continue;
            return ibl__fail(ctx, IBL_ERR_IO, "%s: cannot read: %s", path, strerror(errno));
        }
        if (n == 0) break;
        done += (size_t)n;
    }
    *got = done;
    return IBL_OK;
}

/* A large regular file is read in fixed pieces by pread through ibl_parallel_for: the kernel's
 * copy (and the faults on the fresh buffer) then run on every thread. */
enum { READ_CHUNK = 4 << 20 };

typedef struct read_job {
    int fd;
    uint8_t *dst;
    size_t size;
    size_t got[256];
    int err[256];
    size_t chunk;
} read_job;

static void read_task(void *arg, int index)
{
    read_job *j = arg;
    size_t first = (size_t)index * j->chunk;
    size_t n = j->size - first < j->chunk ? j->size - first : j->chunk, done = 0;
    while (done < n) {
        ssize_t r = pread(j->fd, j->dst + first + done, n - done, (off_t)(first + done));
        if (r < 0) {
            if (errno == EINTR) continue;
            j->err[index] = errno;
            break;
        }
        if (r == 0) break;
        done += (size_t)r;
    }
    j->got[index] = done;
}

static ibl_status read_parallel(ibl_context *ctx, int fd, const char *path, uint8_t *dst,
                                size_t size, size_t *got)
{
    read_job *j = ibl_alloc(ctx, sizeof *j);
    if (!j) return read_all(ctx, fd, path, dst, size, got); /* as without threads */
    memset(j, 0, sizeof *j);
    j->fd = fd;
    j->dst = dst;
    j->size = size;
    j->chunk = READ_CHUNK;
    while ((size + j->chunk - 1) / j->chunk > 256) j->chunk *= 2;
    int chunks = (int)((size + j->chunk - 1) / j->chunk);
    ibl_parallel_for(ctx, chunks, read_task, j);
    /* as a sequential read: the bytes up to the first error or short piece */
    size_t done = 0;
    ibl_status s = IBL_OK;
    for (int i = 0; i < chunks; i++) {
        done += j->got[i];
        if (j->err[i]) {
            s = ibl__fail(ctx, IBL_ERR_IO, "%s: cannot read: %s", path, strerror(j->err[i]));
            break;
        }
        if (j->got[i] < (i == chunks - 1 ? size - (size_t)i * j->chunk : j->chunk)) break;
    }
    ibl_free(ctx, j);
    *got = done;
    return s;
}

/* The message for bytes that are none of the supported formats. */
static ibl_status unknown_type(ibl_context *ctx, const char *name, size_t size)
{
    return ibl__fail(ctx, IBL_ERR_FORMAT,
                     "%s: not a supported image file (%s; expected Radiance HDR, OpenEXR, PFM, PNG, "
                     "JPEG, KTX2, KTX or DDS)",
                     name, size < 4 ? "too short to identify" : "unknown magic bytes");
}

/* Bytes that tell the formats apart (ibl_file_type_sniff reads at most 12). */
enum { SNIFF_BYTES = 16 };

/* Pipes and devices have no size: they are read in pieces, each twice the last up to
 * STREAM_PIECE_MAX, then joined; and at most STREAM_READ_CAP bytes, so that an endless
 * source (/dev/zero, `yes`) fails within seconds instead of filling the budget. The cap is
 * above any environment a pipe is likely to carry (a 16384x8192 float EXR is 1.3 GB). */
#define STREAM_PIECE_MIN ((size_t)64 << 10)
#define STREAM_PIECE_MAX ((size_t)64 << 20)
#define STREAM_READ_CAP ((uint64_t)2 << 30)
enum { STREAM_MAX_PIECES = 64 };

static ibl_status read_stream(ibl_context *ctx, int fd, const char *path, int sniff, uint8_t **out,
                              size_t *out_size)
{
    uint8_t *piece[STREAM_MAX_PIECES];
    size_t used[STREAM_MAX_PIECES];
    int count = 0;
    size_t total = 0, next = STREAM_PIECE_MIN;
    ibl_status s = IBL_OK;
    for (;;) {
        if ((uint64_t)total >= STREAM_READ_CAP || count == STREAM_MAX_PIECES) {
            s = ibl__fail(ctx, IBL_ERR_TOO_LARGE,
                          "%s: more than %llu MiB from a pipe or device, the most ibl reads from "
                          "anything but a regular file (save it to a file first)",
                          path, (unsigned long long)(STREAM_READ_CAP >> 20));
            break;
        }
        piece[count] = ibl_alloc(ctx, next);
        if (!piece[count]) {
            s = ibl__fail_named(ctx, ibl_context_status(ctx), path);
            break;
        }
        s = read_all(ctx, fd, path, piece[count], next, &used[count]);
        total += used[count++];
        if (s != IBL_OK) break;
        /* the first bytes say whether this can be an image at all: /dev/zero cannot */
        if (sniff && count == 1 && ibl_file_type_sniff(piece[0], used[0]) == IBL_FILE_UNKNOWN) {
            s = unknown_type(ctx, path, used[0]);
            break;
        }
        if (used[count - 1] < next) break; /* end of stream */
        if (next < STREAM_PIECE_MAX) next *= 2;
    }
    uint8_t *joined = NULL;
    if (s == IBL_OK && count == 1) {
        joined = piece[0]; /* small enough for one piece: no copy */
        count = 0;
    } else if (s == IBL_OK) {
        joined = ibl_alloc(ctx, total ? total : 1);
        if (!joined) s = ibl__fail_named(ctx, ibl_context_status(ctx), path);
        if (joined) {
            size_t at = 0;
            for (int i = 0; i < count; i++) {
                memcpy(joined + at, piece[i], used[i]);
                at += used[i];
            }
        }
    }
    for (int i = 0; i < count; i++) ibl_free(ctx, piece[i]);
    *out = joined;
    *out_size = s == IBL_OK ? total : 0;
    return s;
}

/* A named FIFO that nobody writes would be waited for forever: wait a while for a writer's
 * first bytes, then say so. (Anonymous pipes, e.g. a shell's <(...), always have a writer.) */
enum { FIFO_WAIT_MS = 10000 };

static ibl_status wait_for_fifo_writer(ibl_context *ctx, int fd, const char *path)
{
    struct stat link;
    if (lstat(path, &link) != 0 || !S_ISFIFO(link.st_mode)) return IBL_OK;
    struct pollfd p = {fd, POLLIN, 0};
    int r;
    do r = poll(&p, 1, FIFO_WAIT_MS);
    while (r < 0 && errno == EINTR);
    if (r == 0)
        return ibl__fail(ctx, IBL_ERR_IO, "%s: a FIFO that nothing wrote to in %d s", path,
                         FIFO_WAIT_MS / 1000);
    return IBL_OK;
}

/* Opens path for reading (a FIFO once a writer came) and stats it; directories are refused. */
static ibl_status open_input(ibl_context *ctx, const char *path, int *fd_out, struct stat *st)
{
    int fd;
    /* O_NONBLOCK: opening a FIFO that no process writes would otherwise wait forever; reads
     * block again below, and a FIFO without a writer then reads as empty */
    do fd = open(path, O_RDONLY | O_CLOEXEC | O_NONBLOCK);
    while (fd < 0 && errno == EINTR);
    if (fd < 0) return ibl__fail(ctx, IBL_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
    ibl_status waited = wait_for_fifo_writer(ctx, fd, path);
    if (waited != IBL_OK) {
        close(fd);
        return waited;
    }
    int flags = fcntl(fd, F_GETFL);
    if (flags >= 0) fcntl(fd, F_SETFL, flags & ~O_NONBLOCK);
    if (fstat(fd, st) != 0) {
        int e = errno;
        close(fd);
        return ibl__fail(ctx, IBL_ERR_IO, "%s: cannot open: %s", path, strerror(e));
    }
    if (S_ISDIR(st->st_mode)) {
        close(fd);
        return ibl__fail(ctx, IBL_ERR_IO, "%s: cannot open: %s", path, strerror(EISDIR));
    }
    *fd_out = fd;
    return IBL_OK;
}

/* A regular file is read into one buffer of its size (which the budget may refuse); with
 * `sniff`, its first bytes must look like an image before anything is allocated. */
static ibl_status read_file(ibl_context *ctx, const char *path, int sniff, void **bytes, size_t *size)
{
    if (!path || !bytes || !size)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "ibl_read_file: missing argument");
    *bytes = NULL;
    *size = 0;
    int fd = -1;
    struct stat st;
    ibl_status s = open_input(ctx, path, &fd, &st);
    if (s != IBL_OK) return s;
    uint8_t *buf = NULL;
    size_t used = 0;
    if (!S_ISREG(st.st_mode)) {
        s = read_stream(ctx, fd, path, sniff, &buf, &used);
        close(fd);
        if (s != IBL_OK) return s;
        *bytes = buf;
        *size = used;
        return IBL_OK;
    }
    if ((uint64_t)st.st_size > (uint64_t)SIZE_MAX) {
        close(fd);
        return ibl__fail(ctx, IBL_ERR_TOO_LARGE, "%s: file too large", path);
    }
    size_t want = (size_t)st.st_size;
    if (sniff) {
        uint8_t head[SNIFF_BYTES];
        size_t n = 0;
        ssize_t r;
        do r = pread(fd, head, want < sizeof head ? want : sizeof head, 0);
        while (r < 0 && errno == EINTR);
        if (r < 0) {
            int e = errno;
            close(fd);
            return ibl__fail(ctx, IBL_ERR_IO, "%s: cannot read: %s", path, strerror(e));
        }
        n = (size_t)r;
        if (ibl_file_type_sniff(head, n) == IBL_FILE_UNKNOWN) {
            close(fd);
            return unknown_type(ctx, path, n);
        }
    }
    /* The size is known: one allocation, which the context's memory budget may refuse. */
    buf = ibl_alloc(ctx, want ? want : 1);
    if (!buf) {
        s = ibl__fail_named(ctx, ibl_context_status(ctx), path);
        close(fd);
        return s;
    }
    s = want >= 2 * (size_t)READ_CHUNK && ibl_context_threads(ctx) > 1
            ? read_parallel(ctx, fd, path, buf, want, &used)
            : read_all(ctx, fd, path, buf, want, &used);
    if (s == IBL_OK && used != want)
        s = ibl__fail(ctx, IBL_ERR_IO, "%s: file shrank while being read", path);
    close(fd);
    if (s != IBL_OK) {
        ibl_free(ctx, buf);
        return s;
    }
    *bytes = buf;
    *size = used;
    return IBL_OK;
}

ibl_status ibl_read_file(ibl_context *ctx, const char *path, void **bytes, size_t *size)
{
    return read_file(ctx, path, 0, bytes, size);
}

/* ---- reading: dispatch and pixel policy ---------------------------------------------- */

/* ibl_sanitize_pixels over fixed chunks of texels through ibl_parallel_for; the counts are
 * added in chunk order (integers: any order gives the same sums). 16384 texels (256 KiB, ~0.1
 * ms) a chunk: the last chunk runs on one thread while the other waits, 0.4 ms of the 256
 * chain's two-thread run with chunks of 65536. */
enum { SANITIZE_CHUNK = 1 << 14, SANITIZE_MAX_CHUNKS = 4096 };

typedef struct sanitize_job {
    float *rgba;
    size_t count, chunk;
    int clamp_infinite;
    float clamp_value;
    ibl_pixel_report report[SANITIZE_MAX_CHUNKS];
} sanitize_job;

static void sanitize_task(void *arg, int index)
{
    sanitize_job *j = arg;
    size_t first = (size_t)index * j->chunk;
    size_t n = j->count - first < j->chunk ? j->count - first : j->chunk;
    /* no context: a chunk's infinities are reported by the caller, for the whole image */
    (void)ibl_sanitize_pixels(NULL, j->rgba + first * 4, n, j->clamp_infinite, j->clamp_value,
                              &j->report[index]);
}

/* The message of ibl_sanitize_pixels for a whole image sanitized in parts. */
static ibl_status pixel_verdict(ibl_context *ctx, const ibl_pixel_report *r, int clamp_infinite)
{
    if (r->inf_count && !clamp_infinite)
        return ibl__fail(ctx, IBL_ERR_BAD_PIXELS, "%llu texels are infinite (use --clamp to clamp them)",
                        (unsigned long long)r->inf_count);
    return IBL_OK;
}

static ibl_status sanitize(ibl_context *ctx, float *rgba, size_t count, int clamp_infinite,
                           float clamp_value, ibl_pixel_report *report)
{
    if (count <= 2 * (size_t)SANITIZE_CHUNK || ibl_context_threads(ctx) < 2)
        return ibl_sanitize_pixels(ctx, rgba, count, clamp_infinite, clamp_value, report);
    sanitize_job *j = ibl_alloc(ctx, sizeof *j);
    if (!j) return ibl_sanitize_pixels(ctx, rgba, count, clamp_infinite, clamp_value, report);
    j->rgba = rgba;
    j->count = count;
    j->chunk = SANITIZE_CHUNK;
    while ((count + j->chunk - 1) / j->chunk > SANITIZE_MAX_CHUNKS) j->chunk *= 2;
    j->clamp_infinite = clamp_infinite;
    j->clamp_value = clamp_value;
    int chunks = (int)((count + j->chunk - 1) / j->chunk);
    ibl_parallel_for(ctx, chunks, sanitize_task, j);
    ibl_pixel_report r = {0, 0, 0, count};
    for (int i = 0; i < chunks; i++) {
        r.nan_count += j->report[i].nan_count;
        r.inf_count += j->report[i].inf_count;
        r.negative_count += j->report[i].negative_count;
    }
    ibl_free(ctx, j);
    if (report) *report = r;
    return pixel_verdict(ctx, &r, clamp_infinite);
}

ibl_status ibl_decode_texture(ibl_context *ctx, const void *bytes, size_t size, const char *name,
                              const ibl_read_desc *desc, ibl_texture *out, ibl_file_info *info)
{
    if (!name) name = "<memory>";
    if (!out || (!bytes && size))
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "%s: missing argument", name);
    memset(out, 0, sizeof *out);
    ibl_read_desc rd;
    memset(&rd, 0, sizeof rd);
    if (desc) rd = *desc;
    ibl_file_info fi;
    memset(&fi, 0, sizeof fi);
    const uint8_t *b = bytes;
    ibl__pixel_policy policy = {rd.clamp_infinite, rd.clamp_value, 0, {0, 0, 0, 0}};
    fi.type = ibl_file_type_sniff(b, size);
    ibl_status s;
    switch (fi.type) {
    case IBL_FILE_HDR: s = ibl__hdr_decode(ctx, b, size, name, out, &fi); break;
    case IBL_FILE_EXR: s = ibl__exr_decode_sanitized(ctx, b, size, name, out, &fi, &policy); break;
    case IBL_FILE_PFM: s = ibl__pfm_decode(ctx, b, size, name, out, &fi); break;
    case IBL_FILE_PNG: s = ibl__png_decode_as(ctx, b, size, name, rd.as_data, out, &fi); break;
    case IBL_FILE_JPEG: s = ibl__jpeg_decode(ctx, b, size, name, out, &fi); break;
    case IBL_FILE_KTX2: s = ibl__ktx2_decode(ctx, b, size, name, out, &fi); break;
    case IBL_FILE_KTX1: s = ibl__ktx1_decode(ctx, b, size, name, out, &fi); break;
    case IBL_FILE_DDS: s = ibl__dds_decode(ctx, b, size, name, out, &fi); break;
    default: return unknown_type(ctx, name, size);
    }
    if (s != IBL_OK) {
        ibl_texture_free(ctx, out);
        return s;
    }
    fi.type = ibl_file_type_sniff(b, size);
    fi.kind = out->kind;
    fi.width = out->width;
    fi.height = out->height;
    fi.depth = out->depth;
    fi.levels = out->levels;
    if (fi.format == IBL_FORMAT_DEFAULT) fi.format = out->format;
    if (out->format == IBL_FORMAT_DEFAULT) out->format = fi.format;
    size_t texels = ibl_texture_floats(out->kind, out->width, out->height, out->depth, out->levels) / 4;
    if (policy.done) {
        fi.pixels = policy.report;
        s = pixel_verdict(ctx, &policy.report, rd.clamp_infinite);
    } else {
        s = sanitize(ctx, out->data, texels, rd.clamp_infinite, rd.clamp_value, &fi.pixels);
    }
    if (info) *info = fi;
    if (s != IBL_OK) {
        ibl_texture_free(ctx, out);
        return ibl__fail_named(ctx, s, name);
    }
    return IBL_OK;
}

ibl_status ibl_read_texture(ibl_context *ctx, const char *path, const ibl_read_desc *desc,
                            ibl_texture *out, ibl_file_info *info)
{
    if (!out || !path)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "ibl_read_texture: missing argument");
    memset(out, 0, sizeof *out);
    void *bytes = NULL;
    size_t size = 0;
    ibl_status s = read_file(ctx, path, 1, &bytes, &size);
    if (s != IBL_OK) return s;
    s = ibl_decode_texture(ctx, bytes, size, path, desc, out, info);
    ibl_free(ctx, bytes);
    return s;
}

ibl_status ibl_decode_info(ibl_context *ctx, const void *bytes, size_t size, const char *name,
                           ibl_file_info *info)
{
    if (!name) name = "<memory>";
    if (!info || (!bytes && size))
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "%s: missing argument", name);
    memset(info, 0, sizeof *info);
    ibl_file_info fi;
    memset(&fi, 0, sizeof fi);
    const uint8_t *b = bytes;
    ibl_file_type type = ibl_file_type_sniff(b, size);
    /* a flat image is one level of one 2D image (the containers' parsers say all of it) */
    fi.kind = IBL_TEXTURE_2D;
    fi.depth = fi.levels = 1;
    ibl_status s;
    switch (type) {
    case IBL_FILE_HDR: s = ibl__hdr_info(ctx, b, size, name, &fi); break;
    case IBL_FILE_EXR: s = ibl__exr_info(ctx, b, size, name, &fi); break;
    case IBL_FILE_PFM: s = ibl__pfm_info(ctx, b, size, name, &fi); break;
    case IBL_FILE_PNG: s = ibl__png_info(ctx, b, size, name, &fi); break;
    case IBL_FILE_JPEG: s = ibl__jpeg_info(ctx, b, size, name, &fi); break;
    case IBL_FILE_KTX2: s = ibl__ktx2_info(ctx, b, size, name, &fi); break;
    case IBL_FILE_KTX1: s = ibl__ktx1_info(ctx, b, size, name, &fi); break;
    case IBL_FILE_DDS: s = ibl__dds_info(ctx, b, size, name, &fi); break;
    default: return unknown_type(ctx, name, size);
    }
    if (s != IBL_OK) return s;
    fi.type = type;
    *info = fi;
    return IBL_OK;
}

/* ibl_read_info reads the head of a regular file, and as many times more each time the
 * header did not parse from what was read, up to the whole file (whose failure is then the
 * one reported: that of a header that is malformed, not merely cut by the read). 64 KiB
 * holds the header of every file ibl writes and of the usual EXR (a few hundred bytes of
 * attributes and the chunk offsets after them are not read). */
#define INFO_HEAD_BYTES ((size_t)64 << 10)
enum { INFO_HEAD_GROWTH = 16 };

static ibl_status read_info_regular(ibl_context *ctx, int fd, const char *path, size_t file_size,
                                    ibl_file_info *info)
{
    uint8_t *buf = NULL;
    size_t have = 0, want = file_size < INFO_HEAD_BYTES ? file_size : INFO_HEAD_BYTES;
    for (;;) {
        uint8_t *grown = ibl_alloc(ctx, want ? want : 1);
        if (!grown) {
            ibl_free(ctx, buf);
            return ibl__fail_named(ctx, ibl_context_status(ctx), path);
        }
        if (have) memcpy(grown, buf, have);
        ibl_free(ctx, buf);
        buf = grown;
        size_t got = 0; /* the reads go on from where the last stopped */
        ibl_status s = read_all(ctx, fd, path, buf + have, want - have, &got);
        if (s != IBL_OK) {
            ibl_free(ctx, buf);
            return s;
        }
        got += have;
        int whole = got < want || got >= file_size; /* the end (a file that shrank ends early) */
        have = got;
        s = ibl_decode_info(ctx, buf, have, path, info);
        if (s == IBL_OK || whole) {
            ibl_free(ctx, buf);
            return s;
        }
        want = file_size / INFO_HEAD_GROWTH < have ? file_size : have * INFO_HEAD_GROWTH;
    }
}

ibl_status ibl_read_info(ibl_context *ctx, const char *path, ibl_file_info *info)
{
    if (!path || !info)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "ibl_read_info: missing argument");
    memset(info, 0, sizeof *info);
    int fd = -1;
    struct stat st;
    ibl_status s = open_input(ctx, path, &fd, &st);
    if (s != IBL_OK) return s;
    if (S_ISREG(st.st_mode)) {
        s = (uint64_t)st.st_size > (uint64_t)SIZE_MAX
                ? ibl__fail(ctx, IBL_ERR_TOO_LARGE, "%s: file too large", path)
                : read_info_regular(ctx, fd, path, (size_t)st.st_size, info);
        close(fd);
        return s;
    }
    /* a pipe or device cannot be read again: all of it, as ibl_read_texture would */
    uint8_t *bytes = NULL;
    size_t size = 0;
    s = read_stream(ctx, fd, path, 1, &bytes, &size);
    close(fd);
    if (s == IBL_OK) s = ibl_decode_info(ctx, bytes, size, path, info);
    ibl_free(ctx, bytes);
    return s;
}

ibl_status ibl_read_image(ibl_context *ctx, const char *path, const ibl_read_desc *desc,
                          ibl_image *out, ibl_file_info *info)
{
    if (!out || !path)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "ibl_read_image: missing argument");
    memset(out, 0, sizeof *out);
    ibl_texture tex;
    ibl_status s = ibl_read_texture(ctx, path, desc, &tex, info);
    if (s != IBL_OK) return s;
    if (tex.kind != IBL_TEXTURE_2D) {
        ibl_texture_free(ctx, &tex);
        return ibl__fail(ctx, IBL_ERR_UNSUPPORTED, "%s: holds a %s texture, not a flat image",
                        path, tex.kind == IBL_TEXTURE_CUBE         ? "cube"
                              : tex.kind == IBL_TEXTURE_CUBE_ARRAY ? "cube-map array"
                                                                   : "3D");
    }
    if (tex.levels == 1 && tex.owns_data) {
        /* Level 0 is the whole block: hand it over without a copy. */
        out->width = tex.width;
        out->height = tex.height;
        out->pixels = tex.data;
        tex.owns_data = 0;
    } else {
        s = ibl_image_alloc(ctx, tex.width, tex.height, out);
        if (s != IBL_OK) {
            ibl_texture_free(ctx, &tex);
            return ibl__fail_named(ctx, s, path);
        }
        memcpy(out->pixels, tex.data, (size_t)tex.width * (size_t)tex.height * 4 * sizeof(float));
    }
    ibl_texture_free(ctx, &tex);
    return IBL_OK;
}

/* ---- writing ------------------------------------------------------------------------- */

static ibl_status check_image(ibl_context *ctx, const char *name, const ibl_image *image)
{
    if (!image || !image->pixels || image->width <= 0 || image->height <= 0)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "%s: empty image", name);
    return IBL_OK;
}

/* A non-owning one-level 2D texture view of an image. */
static ibl_texture texture_view(const ibl_image *image, const ibl_write_desc *desc)
{
    ibl_texture t;
    memset(&t, 0, sizeof t);
    t.kind = IBL_TEXTURE_2D;
    t.width = image->width;
    t.height = image->height;
    t.depth = 1;
    t.levels = 1;
    t.format = desc ? desc->format : IBL_FORMAT_DEFAULT;
    t.data = image->pixels;
    return t;
}

static ibl_status encode_flat(ibl_context *ctx, ibl_file_type type, const ibl_image *image,
                              const ibl_write_desc *desc, const char *name, void **bytes,
                              size_t *size)
{
    switch (type) {
    case IBL_FILE_HDR: return ibl__hdr_encode(ctx, image, desc, name, bytes, size);
    case IBL_FILE_EXR: return ibl__exr_encode(ctx, image, desc, name, bytes, size);
    case IBL_FILE_PFM: return ibl__pfm_encode(ctx, image, desc, name, bytes, size);
    case IBL_FILE_PNG: return ibl__png_encode(ctx, image, desc, name, bytes, size);
    case IBL_FILE_JPEG: return ibl__jpeg_encode(ctx, image, desc, name, bytes, size);
    default: break;
    }
    return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "%s: not a flat image type", name);
}

static ibl_status encode_container(ibl_context *ctx, ibl_file_type type, const ibl_texture *tex,
                                   const ibl_write_desc *desc, const char *name, void **bytes,
                                   size_t *size)
{
    switch (type) {
    case IBL_FILE_KTX2: return ibl__ktx2_encode(ctx, tex, desc, name, bytes, size);
    case IBL_FILE_KTX1: return ibl__ktx1_encode(ctx, tex, desc, name, bytes, size);
    case IBL_FILE_DDS: return ibl__dds_encode(ctx, tex, desc, name, bytes, size);
    default: break;
    }
    return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "%s: not a texture container type", name);
}

static ibl_status unknown_extension(ibl_context *ctx, const char *path)
{
    return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                    "%s: unknown output extension (use .hdr .exr .pfm .png .jpg .ktx2 .ktx .dds)",
                    path);
}

ibl_status ibl__encode_image_for_path(ibl_context *ctx, const char *path, const ibl_image *image,
                                     const ibl_write_desc *desc, void **bytes, size_t *size)
{
    *bytes = NULL;
    *size = 0;
    if (!path) return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "ibl_write_image: missing path");
    ibl_status s = check_image(ctx, path, image);
    if (s != IBL_OK) return s;
    ibl_write_desc wd;
    memset(&wd, 0, sizeof wd);
    if (desc) wd = *desc;
    ibl_file_type type = ibl_file_type_from_path(path);
    if (type == IBL_FILE_UNKNOWN) return unknown_extension(ctx, path);
    if (ibl_file_type_is_container(type)) {
        ibl_texture view = texture_view(image, &wd);
        return encode_container(ctx, type, &view, &wd, path, bytes, size);
    }
    return encode_flat(ctx, type, image, &wd, path, bytes, size);
}

ibl_status ibl__encode_texture_for_path(ibl_context *ctx, const char *path,
                                       const ibl_texture *texture, const ibl_write_desc *desc,
                                       void **bytes, size_t *size)
{
    return ibl__encode_texture_streamed(ctx, path, texture, desc, bytes, size, NULL);
}

ibl_status ibl__encode_texture_streamed(ibl_context *ctx, const char *path,
                                        const ibl_texture *texture, const ibl_write_desc *desc,
                                        void **bytes, size_t *size, ibl__levels_stream **stream)
{
    if (stream) *stream = NULL;
    *bytes = NULL;
    *size = 0;
    if (!path) return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "ibl_write_texture: missing path");
    if (!texture || !texture->data)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "%s: empty texture", path);
    ibl_file_type type = ibl_file_type_from_path(path);
    if (type == IBL_FILE_UNKNOWN) return unknown_extension(ctx, path);
    ibl_write_desc wd;
    memset(&wd, 0, sizeof wd);
    if (desc) wd = *desc;
    if (type == IBL_FILE_KTX2 && stream)
        return ibl__ktx2_encode_streamed(ctx, texture, &wd, path, bytes, size, stream);
    if (ibl_file_type_is_container(type))
        return encode_container(ctx, type, texture, &wd, path, bytes, size);
    if (texture->kind != IBL_TEXTURE_2D || texture->levels != 1)
        return ibl__fail(ctx, IBL_ERR_UNSUPPORTED,
                         "%s: .%s holds one flat image; write cubes, 3D textures and mips to "
                         ".ktx2, .ktx or .dds",
                         path, ibl_file_type_name(type));
    ibl_image view = {texture->width, texture->height, texture->data};
    return encode_flat(ctx, type, &view, &wd, path, bytes, size);
}

ibl_status ibl_write_image(ibl_context *ctx, const char *path, const ibl_image *image,
                           const ibl_write_desc *desc)
{
    void *bytes;
    size_t size;
    ibl_status s = ibl__encode_image_for_path(ctx, path, image, desc, &bytes, &size);
    if (s == IBL_OK) s = ibl_write_file_atomic(ctx, path, bytes, size);
    ibl_free(ctx, bytes);
    return s;
}

ibl_status ibl_write_texture(ibl_context *ctx, const char *path, const ibl_texture *texture,
                             const ibl_write_desc *desc)
{
    void *bytes;
    size_t size;
    ibl_status s = ibl__encode_texture_for_path(ctx, path, texture, desc, &bytes, &size);
    if (s == IBL_OK) s = ibl_write_file_atomic(ctx, path, bytes, size);
    ibl_free(ctx, bytes);
    return s;
}

ibl_status ibl_encode_image(ibl_context *ctx, ibl_file_type type, const ibl_image *image,
                            const ibl_write_desc *desc, void **bytes, size_t *size)
{
    if (!bytes || !size) return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "ibl_encode_image: missing argument");
    *bytes = NULL;
    *size = 0;
    const char *name = ibl_file_type_name(type);
    ibl_status s = check_image(ctx, name, image);
    if (s != IBL_OK) return s;
    ibl_write_desc wd;
    memset(&wd, 0, sizeof wd);
    if (desc) wd = *desc;
    if (type == IBL_FILE_UNKNOWN)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "ibl_encode_image: unknown file type");
    if (ibl_file_type_is_container(type)) {
        ibl_texture view = texture_view(image, &wd);
        return encode_container(ctx, type, &view, &wd, name, bytes, size);
    }
    return encode_flat(ctx, type, image, &wd, name, bytes, size);
}

ibl_status ibl_encode_texture(ibl_context *ctx, ibl_file_type type, const ibl_texture *texture,
                              const ibl_write_desc *desc, void **bytes, size_t *size)
{
    if (!texture || !texture->data || !bytes || !size)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "ibl_encode_texture: missing argument");
    *bytes = NULL;
    *size = 0;
    ibl_write_desc wd;
    memset(&wd, 0, sizeof wd);
    if (desc) wd = *desc;
    const char *name = ibl_file_type_name(type);
    if (ibl_file_type_is_container(type))
        return encode_container(ctx, type, texture, &wd, name, bytes, size);
    if (type == IBL_FILE_UNKNOWN)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "ibl_encode_texture: unknown file type");
    /* A flat format holds one 2D image: accept exactly that, never drop levels silently. */
    if (texture->kind != IBL_TEXTURE_2D || texture->levels != 1)
        return ibl__fail(ctx, IBL_ERR_UNSUPPORTED,
                        "%s: holds one flat image; write cubes, 3D textures and mips to "
                        ".ktx2, .ktx or .dds",
                        name);
    ibl_image view = {texture->width, texture->height, texture->data};
    return encode_flat(ctx, type, &view, &wd, name, bytes, size);
}


/* ---- tone mapping -------------------------------------------------------------------- */

float ibl_tonemap_apply(ibl_tonemap tonemap, float linear)
{
    float x = linear;
    if (!(x > 0.0f)) return 0.0f; /* negatives and NaN */
    if (tonemap == IBL_TONEMAP_NONE) return x < 1.0f ? x : 1.0f;
    /* Narkowicz, "ACES Filmic Tone Mapping Curve" (2016): a rational fit of the ACES
     * RRT+ODT, pre-exposed so that 1.0 maps to about 0.8. It reaches 1 at x = 7.24, so larger
     * inputs (and those whose square would overflow) map straight to white. */
    if (x >= 8.0f) return 1.0f;
    float y = (x * (2.51f * x + 0.03f)) / (x * (2.43f * x + 0.59f) + 0.14f);
    return y < 1.0f ? y : 1.0f;
}

float ibl_image_auto_exposure(const ibl_image *image)
{
    if (!image || !image->pixels) return 0.0f;
    double sum = 0;
    size_t n = (size_t)image->width * image->height;
    for (size_t i = 0; i < n; i++) {
        const float *p = image->pixels + i * 4;
        /* the plain mean: a log-average would favour dark images, the mean is steadier */
        sum += 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
    }
    double mean = n ? sum / (double)n : 0;
    if (!(mean > 0)) return 0.0f;
    return (float)log2(0.18 / mean);
}
