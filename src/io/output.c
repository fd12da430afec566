/* Output files that appear whole or not at all: every file of a set is written completely
 * (and flushed) under a temporary name in its own folder, and only the commit renames them
 * into place, after a last cancellation check. A failure, a Ctrl-C or a full disk before the
 * commit leaves the targets untouched and removes the temporaries; a rename cannot run out
 * of space, so a set is all or nothing except for a kill during the commit's few renames.
 *
 * Where Linux offers O_TMPFILE the data is written to an unnamed file that vanishes if the
 * process dies, and linked to its temporary name ".NAME.tmp-PID-N" once complete; elsewhere
 * it is written under that name directly. Temporaries left by a killed process are removed
 * by the next write of the same name. New files get mode 0666
 * minus the umask; a replaced file keeps its mode. */
#define _GNU_SOURCE /* O_TMPFILE, linkat's AT_SYMLINK_FOLLOW */
#include "io/io_internal.h"
#include "io/container.h"
#include "core/context_internal.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

typedef struct pending_file {
    char *path;      /* the target                                          */
    char *temp;      /* its complete temporary, beside it                   */
    int replaced;    /* the target existed (its mode is kept)                */
    mode_t mode;
} pending_file;

struct ibl_output_set {
    ibl_context *ctx;
    pending_file *files;
    int count, capacity;
    struct stat protected_files[8]; /* inputs no output may replace */
    char *protected_names[8];
    int protected_count;
    int committed;
};

ibl_status ibl_output_set_create(ibl_context *ctx, ibl_output_set **out)
{
    if (!out) return IBL_ERR_INVALID_ARGUMENT;
    *out = ibl_calloc(ctx, 1, sizeof **out);
    if (!*out) return ibl_context_status(ctx);
    (*out)->ctx = ctx;
    return IBL_OK;
}

ibl_status ibl_output_set_protect(ibl_output_set *set, const char *input)
{
    if (!set || !input) return IBL_ERR_INVALID_ARGUMENT;
    struct stat st;
    if (set->protected_count == 8 || stat(input, &st) != 0) return IBL_OK;
    size_t n = strlen(input) + 1;
    char *copy = ibl_alloc(set->ctx, n);
    if (!copy) return ibl_context_status(set->ctx);
    memcpy(copy, input, n);
    set->protected_names[set->protected_count] = copy;
    set->protected_files[set->protected_count++] = st;
    return IBL_OK;
}

static void remove_pending(pending_file *f)
{
    if (f->temp) unlink(f->temp);
}

void ibl_output_set_destroy(ibl_output_set *set)
{
    if (!set) return;
    ibl_context *ctx = set->ctx;
    for (int i = 0; i < set->count; i++) {
        if (!set->committed) remove_pending(&set->files[i]);
        ibl_free(ctx, set->files[i].path);
        ibl_free(ctx, set->files[i].temp);
    }
    for (int i = 0; i < set->protected_count; i++) ibl_free(ctx, set->protected_names[i]);
    ibl_free(ctx, set->files);
    ibl_free(ctx, set);
}

/* "dir/" of path (empty for a bare name) into a new string */
static char *folder_of(ibl_context *ctx, const char *path)
{
    const char *slash = strrchr(path, '/');
    size_t n = slash ? (size_t)(slash - path) + 1 : 0;
    char *d = ibl_alloc(ctx, n + 1);
    if (!d) return NULL;
    memcpy(d, path, n);
    d[n] = 0;
    return d;
}

/* Removes ".BASE.tmp-PID-N" files of processes that no longer exist (killed mid-write). */
static void remove_stale_temporaries(const char *folder, const char *base)
{
    DIR *d = opendir(folder[0] ? folder : ".");
    if (!d) return;
    char prefix[300];
    int plen = snprintf(prefix, sizeof prefix, ".%s.tmp-", base);
    if (plen <= 0 || (size_t)plen >= sizeof prefix) {
        closedir(d);
        return;
    }
    struct dirent *e;
    while ((e = readdir(d)) != NULL) {
        if (strncmp(e->d_name, prefix, (size_t)plen) != 0) continue;
        char *end = NULL;
        long pid = strtol(e->d_name + plen, &end, 10);
        if (end == e->d_name + plen || *end != '-' || pid <= 0) continue;
        if (kill((pid_t)pid, 0) == 0 || errno != ESRCH) continue; /* alive, or not ours to judge */
        char stale[4096];
        if (snprintf(stale, sizeof stale, "%s%s", folder, e->d_name) < (int)sizeof stale)
            unlink(stale);
    }
    closedir(d);
}

static int same_file(const struct stat *a, const struct stat *b)
{
    return a->st_dev == b->st_dev && a->st_ino == b->st_ino;
}

static ibl_status write_all(int fd, const unsigned char *p, size_t n)
{
    while (n > 0) {
        size_t chunk = n > ((size_t)1 << 30) ? ((size_t)1 << 30) : n;
        ssize_t w = write(fd, p, chunk);
        if (w < 0 && errno == EINTR) continue;
        if (w <= 0) {
            if (w == 0) errno = EIO;
            return IBL_ERR_IO;
        }
        p += w;
        n -= (size_t)w;
    }
    return IBL_OK;
}

/* "<folder>.<base>.tmp-PID-N" */
static char *temporary_name(ibl_context *ctx, const char *folder, const char *base, int serial)
{
    size_t n = strlen(folder) + strlen(base) + 48;
    char *t = ibl_alloc(ctx, n);
    if (t) snprintf(t, n, "%s.%s.tmp-%ld-%d", folder, base, (long)getpid(), serial);
    return t;
}

/* A large file is written in slices of WRITEBACK_SLICE bytes, each handed to the disk
 * (sync_file_range: the writeback starts, nothing waits) as soon as it is in the page cache,
 * so the disk writes one slice while the next is copied and the fsync that makes the file
 * durable waits for the last slice only: with one write and one fsync the 256 chain's 4 MB
 * KTX2 took the write's copy plus the whole flush. The fsync still comes before the rename. */
#define WRITEBACK_SLICE ((size_t)1 << 20)

/* What a file of the set holds: bytes, of which those of a KTX2's levels may still be being
 * encoded on the pool's workers (stream): each slice is written once it is encoded, so the
 * encode of the next slices runs beside the write of this one (on two threads the 512 chain's
 * 3.4 ms encode was a stretch of its own before the 10-15 ms write, whose system calls keep
 * one thread while the other idles). */
typedef struct byte_source {
    const unsigned char *bytes;
    size_t size;
    ibl__levels_stream *stream;
} byte_source;

static ibl_status write_slices(int fd, const byte_source *src)
{
    const unsigned char *p = src->bytes;
    size_t n = src->size;
#ifdef SYNC_FILE_RANGE_WRITE
    for (size_t done = 0; done < n;) {
        size_t slice = n - done < WRITEBACK_SLICE ? n - done : WRITEBACK_SLICE;
        if (src->stream) ibl__encode_levels_wait(src->stream, p + done + slice);
        if (write_all(fd, p + done, slice) != IBL_OK) return IBL_ERR_IO;
        /* advice: where it fails (a file system without it), the fsync does all the work */
        (void)sync_file_range(fd, (off_t)done, (off_t)slice, SYNC_FILE_RANGE_WRITE);
        done += slice;
    }
    return IBL_OK;
#else
    if (src->stream) ibl__encode_levels_wait(src->stream, p + n);
    return write_all(fd, p, n);
#endif
}

/* Writes bytes to fd and flushes them; keeps the mode of a replaced file. 0 or errno, and
 * what failed. */
static int fill(int fd, const pending_file *f, const byte_source *src, const char **what)
{
    *what = "write";
    if (write_slices(fd, src) != IBL_OK) return errno;
    *what = "set the mode of";
    if (f->replaced && fchmod(fd, f->mode) != 0) return errno;
    *what = "flush";
    if (fsync(fd) != 0) return errno;
    return 0;
}

/* Writes the temporary of f. The data goes first into an unnamed O_TMPFILE file, which
 * vanishes if the process is killed while writing (the long part), and is linked to its
 * temporary name once complete; where that is not possible, into the named temporary. */
static int write_temporary(ibl_context *ctx, pending_file *f, const char *folder, const char *base,
                           int serial, const byte_source *src, const char **what)
{
    *what = "create a temporary file next to";
    f->temp = temporary_name(ctx, folder, base, serial);
    if (!f->temp) return ENOMEM;
#ifdef O_TMPFILE
    int fd = open(folder[0] ? folder : ".", O_TMPFILE | O_WRONLY | O_CLOEXEC, 0666);
    if (fd >= 0) {
        int e = fill(fd, f, src, what);
        char proc[64];
        snprintf(proc, sizeof proc, "/proc/self/fd/%d", fd);
        if (!e && linkat(AT_FDCWD, proc, AT_FDCWD, f->temp, AT_SYMLINK_FOLLOW) == 0) {
            close(fd);
            return 0;
        }
        close(fd);
        if (e) return e;
        /* no /proc, or a file system that cannot link it: write it again under the name */
    }
#endif
    int fd2 = open(f->temp, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd2 < 0) return errno;
    int e = fill(fd2, f, src, what);
    if (close(fd2) != 0 && !e) e = errno, *what = "close";
    return e;
}

static ibl_status add_source(ibl_output_set *set, const char *path, const byte_source *src);

ibl_status ibl_output_set_add(ibl_output_set *set, const char *path, const void *bytes,
                              size_t size)
{
    if (!set || !path || (!bytes && size)) return IBL_ERR_INVALID_ARGUMENT;
    byte_source src = {bytes, size, NULL};
    return add_source(set, path, &src);
}

static ibl_status add_source(ibl_output_set *set, const char *path, const byte_source *src)
{
    ibl_context *ctx = set->ctx;
    const char *slash = strrchr(path, '/');
    const char *base = slash ? slash + 1 : path;
    if (!base[0] || strcmp(base, ".") == 0 || strcmp(base, "..") == 0)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "%s: not a file name", path);
    if (set->committed)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "%s: the output set is already written", path);
    struct stat target;
    int exists = stat(path, &target) == 0;
    if (exists && S_ISDIR(target.st_mode))
        return ibl__fail(ctx, IBL_ERR_IO, "%s: is a folder", path);
    for (int i = 0; exists && i < set->protected_count; i++)
        if (same_file(&target, &set->protected_files[i]))
            return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                             "%s: this output would replace the input %s; choose another name", path,
                             set->protected_names[i]);
    for (int i = 0; i < set->count; i++)
        if (strcmp(set->files[i].path, path) == 0)
            return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "%s: written twice by one command", path);
    if (set->count == set->capacity) {
        int cap = set->capacity ? 2 * set->capacity : 8;
        pending_file *grown = ibl_alloc(ctx, (size_t)cap * sizeof *grown);
        if (!grown) return ibl__fail(ctx, ibl_context_status(ctx), "%s: out of memory", path);
        if (set->count) memcpy(grown, set->files, (size_t)set->count * sizeof *grown);
        ibl_free(ctx, set->files);
        set->files = grown;
        set->capacity = cap;
    }
    pending_file *f = &set->files[set->count];
    memset(f, 0, sizeof *f);
    f->replaced = exists && S_ISREG(target.st_mode);
    f->mode = f->replaced ? target.st_mode & 07777 : 0;
    f->path = ibl__strdup(ctx, path);
    char *folder = folder_of(ctx, path);
    if (!f->path || !folder) {
        ibl_free(ctx, f->path);
        ibl_free(ctx, folder);
        return ibl__fail(ctx, ibl_context_status(ctx), "%s: out of memory", path);
    }
    remove_stale_temporaries(folder, base);
    const char *what;
    int err = write_temporary(ctx, f, folder, base, set->count, src, &what);
    ibl_free(ctx, folder);
    if (err) {
        remove_pending(f);
        ibl_free(ctx, f->path);
        ibl_free(ctx, f->temp);
        return ibl__fail(ctx, IBL_ERR_IO, "%s: cannot %s it: %s", path, what, strerror(err));
    }
    set->count++;
    return IBL_OK;
}

ibl_status ibl_output_set_commit(ibl_output_set *set)
{
    if (!set) return IBL_ERR_INVALID_ARGUMENT;
    ibl_context *ctx = set->ctx;
    if (set->count == 0) return IBL_OK;
    /* the last chance to cancel (Ctrl-C in the CLI): every target is still untouched */
    if (ibl__progress(ctx, "write", 1.0) == IBL_ERR_CANCELLED)
        return ibl__fail(ctx, IBL_ERR_CANCELLED, "%s%s: cancelled; nothing written",
                         set->files[0].path, set->count > 1 ? " and the other outputs" : "");
    set->committed = 1;
    for (int i = 0; i < set->count; i++) {
        pending_file *f = &set->files[i];
        if (rename(f->temp, f->path) != 0) {
            int e = errno;
            for (int j = i; j < set->count; j++) unlink(set->files[j].temp);
            return ibl__fail(ctx, IBL_ERR_IO, "%s: cannot replace: %s", f->path, strerror(e));
        }
    }
    /* the folders are not fsync'ed after the renames: the data was, so after a power cut each
     * name holds the old file or the new one, each complete */
    return IBL_OK;
}

ibl_status ibl_output_set_add_image(ibl_output_set *set, const char *path,
                                    const ibl_image *image, const ibl_write_desc *desc)
{
    if (!set) return IBL_ERR_INVALID_ARGUMENT;
    void *bytes;
    size_t size;
    ibl_status s = ibl__encode_image_for_path(set->ctx, path, image, desc, &bytes, &size);
    if (s == IBL_OK) s = ibl_output_set_add(set, path, bytes, size);
    ibl_free(set->ctx, bytes);
    return s;
}

ibl_status ibl_output_set_add_texture(ibl_output_set *set, const char *path,
                                      const ibl_texture *texture, const ibl_write_desc *desc)
{
    if (!set) return IBL_ERR_INVALID_ARGUMENT;
    void *bytes;
    size_t size;
    ibl__levels_stream *stream;
    ibl_status s = ibl__encode_texture_streamed(set->ctx, path, texture, desc, &bytes, &size, &stream);
    byte_source src = {bytes, size, stream};
    if (s == IBL_OK) s = add_source(set, path, &src);
    /* the levels' encode is over before their buffer goes, whatever happened to the write */
    size_t clamped = ibl__encode_levels_end(stream);
    if (desc && desc->report) desc->report->clamped_texels += clamped;
    ibl_free(set->ctx, bytes);
    return s;
}

ibl_status ibl_write_file_atomic(ibl_context *ctx, const char *path, const void *bytes,
                                 size_t size)
{
    if (!path || !path[0] || (!bytes && size))
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "ibl_write_file_atomic: missing argument");
    ibl_output_set *set;
    ibl_status st = ibl_output_set_create(ctx, &set);
    if (st != IBL_OK) return ibl__fail(ctx, st, "%s: out of memory", path);
    st = ibl_output_set_add(set, path, bytes, size);
    if (st == IBL_OK) st = ibl_output_set_commit(set);
    ibl_output_set_destroy(set);
    return st;
}
