/* The bake folder: written as one transaction, read back through its manifest.
 *
 * Writing. A folder is swapped, never edited: the new bake is written into a staging folder
 * beside the target (".NAME.staging-PID"), flushed, and exchanged with the target in one
 * atomic renameat2(RENAME_EXCHANGE) (or, where the file system lacks it, two renames), so at
 * every instant NAME holds one complete bake, the old or the new. A lock file beside it
 * (".NAME.lock", flock) refuses a second writer while one is at work; staging and displaced
 * folders left by a killed writer are removed by the next one (holding the lock, it knows
 * they are stale). Only files the bake module names are ever deleted: a target folder that
 * holds anything else is refused, so a user's files are never lost.
 *
 * Reading. The manifest says which file holds each part; the reader opens only names from
 * the module's own table (never a path from the file) and checks each texture against what
 * the manifest says it holds. */
#define _GNU_SOURCE /* renameat2, RENAME_EXCHANGE, flock */
#include "bake/bake_internal.h"
#include "core/context_internal.h"
#include "core/defaults.h"
#include "io/json.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

/* ---- paths -------------------------------------------------------------------------------- */

static char *join(ibl_context *ctx, const char *a, const char *b)
{
    size_t na = strlen(a), nb = strlen(b);
    char *p = ibl_alloc(ctx, na + nb + 2);
    if (!p) return NULL;
    memcpy(p, a, na);
    size_t o = na;
    if (na && a[na - 1] != '/') p[o++] = '/';
    memcpy(p + o, b, nb + 1);
    return p;
}

/* The folder a bake is written to, split so that siblings can be named beside it. */
typedef struct target_folder {
    char *path;   /* as given, without trailing slashes            */
    char *parent; /* its parent folder ("." for a bare name)       */
    char *name;   /* its last component                             */
    char *lock, *staging, *displaced;
    int lock_fd;
} target_folder;

static char *sibling(ibl_context *ctx, const target_folder *t, const char *suffix)
{
    size_t n = strlen(t->parent) + strlen(t->name) + strlen(suffix) + 32;
    char *p = ibl_alloc(ctx, n);
    if (p) snprintf(p, n, "%s/.%s.%s", t->parent, t->name, suffix);
    return p;
}

static void target_release(ibl_context *ctx, target_folder *t)
{
    if (t->lock_fd >= 0) {
        unlink(t->lock); /* while still holding it: the next writer finds no stale file */
        close(t->lock_fd);
    }
    ibl_free(ctx, t->path);
    ibl_free(ctx, t->parent);
    ibl_free(ctx, t->name);
    ibl_free(ctx, t->lock);
    ibl_free(ctx, t->staging);
    ibl_free(ctx, t->displaced);
    memset(t, 0, sizeof *t);
    t->lock_fd = -1;
}

static ibl_status target_init(ibl_context *ctx, const char *dir, target_folder *t)
{
    memset(t, 0, sizeof *t);
    t->lock_fd = -1;
    size_t n = strlen(dir);
    while (n > 1 && dir[n - 1] == '/') n--;
    t->path = ibl_alloc(ctx, n + 1);
    if (!t->path) return ibl__fail(ctx, ibl_context_status(ctx), "%s: out of memory", dir);
    memcpy(t->path, dir, n);
    t->path[n] = 0;
    /* a symbolic link to the folder: the swap must happen where the folder really is, or it
     * would replace the link by a folder and treat the linked folder as the old bake */
    struct stat ls;
    if (lstat(t->path, &ls) == 0 && S_ISLNK(ls.st_mode)) {
        char *real = realpath(t->path, NULL);
        if (!real) return ibl__fail(ctx, IBL_ERR_IO, "%s: cannot follow the link: %s", dir, strerror(errno));
        ibl_free(ctx, t->path);
        t->path = ibl__strdup(ctx, real);
        free(real);
        if (!t->path) return ibl__fail(ctx, ibl_context_status(ctx), "%s: out of memory", dir);
    }
    const char *slash = strrchr(t->path, '/');
    const char *base = slash ? slash + 1 : t->path;
    if (!base[0] || strcmp(base, ".") == 0 || strcmp(base, "..") == 0)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                         "%s: name the bake folder itself (e.g. %s/bake), not . or ..", dir, dir);
    size_t plen = slash ? (size_t)(slash - t->path) : 1;
    t->parent = ibl_alloc(ctx, plen + 1);
    t->name = ibl_alloc(ctx, strlen(base) + 1);
    if (!t->parent || !t->name) return ibl__fail(ctx, ibl_context_status(ctx), "%s: out of memory", dir);
    if (slash) {
        memcpy(t->parent, t->path, plen);
        if (plen == 0) t->parent[plen++] = '/'; /* a folder at the root */
        t->parent[plen] = 0;
    } else {
        strcpy(t->parent, ".");
    }
    strcpy(t->name, base);
    char suffix[64];
    snprintf(suffix, sizeof suffix, "staging-%ld", (long)getpid());
    t->staging = sibling(ctx, t, suffix);
    snprintf(suffix, sizeof suffix, "old-%ld", (long)getpid());
    t->displaced = sibling(ctx, t, suffix);
    t->lock = sibling(ctx, t, "lock");
    if (!t->staging || !t->displaced || !t->lock)
        return ibl__fail(ctx, ibl_context_status(ctx), "%s: out of memory", dir);
    return IBL_OK;
}

/* ---- the lock ----------------------------------------------------------------------------- */

static ibl_status take_lock(ibl_context *ctx, target_folder *t)
{
    for (int attempt = 0; attempt < 16; attempt++) {
        int fd = open(t->lock, O_RDWR | O_CREAT | O_CLOEXEC, 0666);
        if (fd < 0)
            return ibl__fail(ctx, IBL_ERR_IO, "%s: cannot create its lock file %s: %s", t->path,
                             t->lock, strerror(errno));
        if (flock(fd, LOCK_EX | LOCK_NB) != 0) {
            int e = errno;
            close(fd);
            if (e == EWOULDBLOCK)
                return ibl__fail(ctx, IBL_ERR_IO,
                                 "%s: is being written by another process (lock %s); wait for "
                                 "it or write elsewhere", t->path, t->lock);
            return ibl__fail(ctx, IBL_ERR_IO, "%s: cannot lock %s: %s", t->path, t->lock, strerror(e));
        }
        /* the holder before us unlinks the file before it lets go: if the name now points to
         * another file (or none), ours is an orphan and another writer may hold the real one */
        struct stat held, named;
        if (fstat(fd, &held) == 0 && stat(t->lock, &named) == 0 && held.st_dev == named.st_dev &&
            held.st_ino == named.st_ino) {
            t->lock_fd = fd;
            return IBL_OK;
        }
        close(fd);
    }
    return ibl__fail(ctx, IBL_ERR_IO, "%s: cannot take the lock %s: it keeps changing", t->path, t->lock);
}

/* ---- what may be deleted ------------------------------------------------------------------ */

/* A name the bake module may delete inside a bake folder: one of its files, or the
 * temporary of one (".NAME.tmp-..."). */
static int is_bake_entry(const char *name)
{
    if (ibl__bake_file_named(name) != IBL__BAKE_FILE_COUNT || ibl__bake_probe_entry(name) ||
        ibl__bake_target_entry(name))
        return 1;
    if (name[0] != '.') return 0;
    const char *tmp = strstr(name, ".tmp-");
    if (!tmp) return 0;
    char base[256];
    size_t n = (size_t)(tmp - name - 1);
    if (n >= sizeof base) return 0;
    memcpy(base, name + 1, n);
    base[n] = 0;
    return ibl__bake_file_named(base) != IBL__BAKE_FILE_COUNT || ibl__bake_probe_entry(base) ||
           ibl__bake_target_entry(base);
}

int ibl__bake_is_entry(const char *name)
{
    return is_bake_entry(name);
}

/* Checks that a folder holds only bake entries: 1 yes, 0 no (*stranger names the first
 * other entry), -1 it cannot be listed (errno). */
static int only_bake_entries(const char *dir, char *stranger, size_t cap)
{
    DIR *d = opendir(dir);
    if (!d) return -1;
    struct dirent *e;
    int ok = 1;
    while ((e = readdir(d)) != NULL) {
        if (strcmp(e->d_name, ".") == 0 || strcmp(e->d_name, "..") == 0) continue;
        if (!is_bake_entry(e->d_name)) {
            snprintf(stranger, cap, "%s", e->d_name);
            ok = 0;
            break;
        }
    }
    closedir(d);
    return ok;
}

/* Deletes a folder of bake entries; leaves it (and anything not ours) if it holds others. */
static void remove_bake_folder(ibl_context *ctx, const char *dir)
{
    DIR *d = opendir(dir);
    if (!d) return;
    struct dirent *e;
    while ((e = readdir(d)) != NULL) {
        if (!is_bake_entry(e->d_name)) continue;
        char *p = join(ctx, dir, e->d_name);
        if (p) unlink(p);
        ibl_free(ctx, p);
    }
    closedir(d);
    rmdir(dir);
}

/* Staging and displaced folders of writers that were killed: ".NAME.staging-*", ".NAME.old-*". */
static void remove_stale_siblings(ibl_context *ctx, const target_folder *t)
{
    DIR *d = opendir(t->parent);
    if (!d) return;
    char staging[300], old[300];
    int ns = snprintf(staging, sizeof staging, ".%s.staging-", t->name);
    int no = snprintf(old, sizeof old, ".%s.old-", t->name);
    struct dirent *e;
    while ((e = readdir(d)) != NULL) {
        if ((ns > 0 && (size_t)ns < sizeof staging && strncmp(e->d_name, staging, (size_t)ns) == 0) ||
            (no > 0 && (size_t)no < sizeof old && strncmp(e->d_name, old, (size_t)no) == 0)) {
            char *p = join(ctx, t->parent, e->d_name);
            if (p) remove_bake_folder(ctx, p);
            ibl_free(ctx, p);
        }
    }
    closedir(d);
}

/* ---- writing ------------------------------------------------------------------------------ */

/* Takes the lock and checks the target: missing, or a folder of bake entries. */
static ibl_status begin(ibl_context *ctx, const char *dir, target_folder *t)
{
    ibl_status st = target_init(ctx, dir, t);
    if (st != IBL_OK) return st;
    struct stat ps;
    if (stat(t->parent, &ps) != 0 || !S_ISDIR(ps.st_mode))
        return ibl__fail(ctx, IBL_ERR_IO, "%s: its parent folder %s does not exist", t->path, t->parent);
    struct stat ts;
    if (stat(t->path, &ts) == 0) {
        if (!S_ISDIR(ts.st_mode))
            return ibl__fail(ctx, IBL_ERR_IO, "%s: exists and is not a folder", t->path);
        char stranger[256];
        int ok = only_bake_entries(t->path, stranger, sizeof stranger);
        if (ok < 0) return ibl__fail(ctx, IBL_ERR_IO, "%s: cannot list: %s", t->path, strerror(errno));
        if (!ok)
            return ibl__fail(ctx, IBL_ERR_IO,
                             "%s: holds '%s', which is not part of a bake; write the bake to a new "
                             "or empty folder (a bake replaces its whole folder)", t->path, stranger);
    } else if (errno != ENOENT) {
        return ibl__fail(ctx, IBL_ERR_IO, "%s: %s", t->path, strerror(errno));
    }
    st = take_lock(ctx, t);
    if (st == IBL_OK) remove_stale_siblings(ctx, t);
    return st;
}

/* Writes bytes to a new file of the private staging folder and flushes it. */
ibl_status ibl__bake_write_staged(ibl_context *ctx, const char *dir, const char *name,
                                  const void *bytes, size_t size)
{
    char *path = join(ctx, dir, name);
    if (!path) return ibl__fail(ctx, ibl_context_status(ctx), "%s: out of memory", name);
    int fd = open(path, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    int e = fd < 0 ? errno : 0;
    const unsigned char *p = bytes;
    size_t left = size;
    while (!e && left > 0) {
        ssize_t w = write(fd, p, left > ((size_t)1 << 30) ? ((size_t)1 << 30) : left);
        if (w < 0 && errno == EINTR) continue;
        if (w <= 0) e = w < 0 ? errno : EIO;
        else p += w, left -= (size_t)w;
    }
    if (!e && fsync(fd) != 0) e = errno;
    if (fd >= 0 && close(fd) != 0 && !e) e = errno;
    ibl_status st = e ? ibl__fail(ctx, IBL_ERR_IO, "%s: cannot write: %s", path, strerror(e)) : IBL_OK;
    ibl_free(ctx, path);
    return st;
}

/* One texture file of the bake in format, with the bake's encoder quality and RGBM range, and
 * its Zstandard level when the file is KTX2 (DDS has no supercompression). */
static ibl_status stage_texture(ibl_context *ctx, const char *dir, const ibl_bake_data *b,
                                ibl__bake_file file, const ibl_texture *tex, ibl_format format,
                                ibl_dds_header header)
{
    const char *name = ibl__bake_file_info_of(file)->name;
    ibl_file_type type = ibl_file_type_from_path(name);
    ibl_write_desc wd = {.format = format, .quality = b->quality, .rgbm_range = b->rgbm_range,
                         .zstd_level = type == IBL_FILE_KTX2 ? b->zstd_level : 0,
                         .dds_header = header};
    void *bytes = NULL;
    size_t size = 0;
    ibl_status st = ibl_encode_texture(ctx, type, tex, &wd, &bytes, &size);
    if (st == IBL_OK) st = ibl__bake_write_staged(ctx, dir, name, bytes, size);
    else st = ibl__fail(ctx, st, "%s/%s: %s", dir, name, ibl_context_message(ctx));
    ibl_free(ctx, bytes);
    return st;
}

static ibl_status stage_cube(ibl_context *ctx, const char *dir, const ibl_bake_data *b,
                             const ibl_cubemap *cube, ibl__bake_file ktx2, int specular)
{
    ibl_texture tex = ibl_texture_from_cubemap(cube);
    ibl_status st = specular ? ibl_specular_set_metadata(ctx, &b->specular_info, &tex)
                             : ibl_texture_set_metadata(ctx, &tex, "ibl.irradiance",
                                                        "irradiance / pi (multiply by albedo)");
    for (int i = 0; i < 2 && st == IBL_OK; i++)
        if (ibl__bake_has_file(b, (ibl__bake_file)(ktx2 + i)))
            st = stage_texture(ctx, dir, b, (ibl__bake_file)(ktx2 + i), &tex, b->format,
                               b->dds_header);
    ibl_texture_free(ctx, &tex); /* the metadata; the texels stay with the bake */
    return st;
}

static ibl_status stage_table(ibl_context *ctx, const char *dir, const ibl_bake_data *b, ibl__bake_file file,
                              const ibl_image *image, ibl_format format, const char *description)
{
    ibl_texture tex = {.kind = IBL_TEXTURE_2D, .width = image->width, .height = image->height,
                       .depth = 1, .levels = 1, .data = image->pixels};
    ibl_status st = ibl_texture_set_metadata(ctx, &tex, "ibl.brdf", description);
    if (st == IBL_OK) st = stage_texture(ctx, dir, b, file, &tex, format, IBL_DDS_HEADER_AUTO);
    ibl_texture_free(ctx, &tex);
    return st;
}

/* The atlas (Daqi 2016): a 2D KTX2 in the bake's format whose key "ibl.atlas" holds the
 * coordinate table and whose ibl.specular.* keys describe the levels, and its 8-bit RGBM PNG
 * twin for devices that take neither half floats nor KTX2. */
static ibl_status stage_atlas(ibl_context *ctx, const char *dir, const ibl_bake_data *b)
{
    ibl_texture tex = {.kind = IBL_TEXTURE_2D, .width = b->atlas.width, .height = b->atlas.height,
                       .depth = 1, .levels = 1, .data = b->atlas.pixels};
    char *table = NULL;
    ibl_status st = ibl_atlas_layout_to_json(ctx, &b->atlas_layout, &table);
    if (st == IBL_OK) st = ibl_texture_set_metadata(ctx, &tex, "ibl.atlas", table);
    if (st == IBL_OK) st = ibl_specular_set_metadata(ctx, &b->specular_info, &tex);
    if (st == IBL_OK) st = stage_texture(ctx, dir, b, IBL__BAKE_ATLAS_KTX2, &tex, b->format,
                                          IBL_DDS_HEADER_AUTO);
    ibl_texture_free(ctx, &tex);
    ibl_free(ctx, table);
    ibl_write_desc wd = {.format = IBL_FORMAT_RGBM, .rgbm_range = b->rgbm_range};
    void *bytes = NULL;
    size_t size = 0;
    const char *png = ibl__bake_file_info_of(IBL__BAKE_ATLAS_PNG)->name;
    if (st == IBL_OK) st = ibl_encode_image(ctx, IBL_FILE_PNG, &b->atlas, &wd, &bytes, &size);
    if (st == IBL_OK) st = ibl__bake_write_staged(ctx, dir, png, bytes, size);
    ibl_free(ctx, bytes);
    return st;
}

static ibl_status stage_text(ibl_context *ctx, const char *dir, ibl__bake_file file, char *text)
{
    ibl_status st = ibl__bake_write_staged(ctx, dir, ibl__bake_file_info_of(file)->name, text, strlen(text));
    ibl_free(ctx, text);
    return st;
}

static ibl_status stage_preview(ibl_context *ctx, const char *dir, const ibl_bake_data *b)
{
    ibl_write_desc wd = {.exposure_ev = ibl_image_auto_exposure(&b->preview)};
    void *bytes = NULL;
    size_t size = 0;
    ibl_status st = ibl_encode_image(ctx, IBL_FILE_PNG, &b->preview, &wd, &bytes, &size);
    if (st == IBL_OK) st = ibl__bake_write_staged(ctx, dir, ibl__bake_file_info_of(IBL__BAKE_PREVIEW)->name, bytes, size);
    ibl_free(ctx, bytes);
    return st;
}

/* Every file of the bake into the (new, empty) staging folder. */
static ibl_status stage_all(ibl_context *ctx, const char *dir, const ibl_bake_data *b,
                            const ibl__bake_extra *extra)
{
    ibl_status st = stage_cube(ctx, dir, b, &b->specular, IBL__BAKE_SPECULAR_KTX2, 1);
    if (st == IBL_OK && b->irradiance.data)
        st = stage_cube(ctx, dir, b, &b->irradiance, IBL__BAKE_IRRADIANCE_KTX2, 0);
    if (st == IBL_OK) st = ibl__progress(ctx, "write", 0.5);
    if (st == IBL_OK && b->sh.bands > 0) {
        char *text = NULL;
        st = ibl_sh_json(ctx, &b->sh, b->sh_window_requested, &b->sh_window, b->source_name, "cube", &text);
        if (st == IBL_OK) st = stage_text(ctx, dir, IBL__BAKE_SH_JSON, text);
    }
    if (st == IBL_OK && b->splitsum.pixels)
        st = stage_table(ctx, dir, b, IBL__BAKE_SPLITSUM, &b->splitsum, IBL_FORMAT_RG16F,
                         "split-sum GGX, height-correlated Smith: R = A, G = B, specular = F0*A + "
                         "F90*B; x = n.v, y = roughness, row 0 = roughness 0");
    if (st == IBL_OK && b->brdf_extra.pixels)
        st = stage_table(ctx, dir, b, IBL__BAKE_BRDF_EXTRA, &b->brdf_extra, IBL_FORMAT_RGBA16F,
                         "R = E (GGX directional albedo), G = E_avg, B = Charlie sheen albedo, "
                         "A = its average; x = n.v, y = roughness");
    if (st == IBL_OK && b->ambient_brdf.data)
        st = stage_texture(ctx, dir, b, IBL__BAKE_AMBIENT_BRDF, &b->ambient_brdf, IBL_FORMAT_RG16F,
                           IBL_DDS_HEADER_AUTO);
    if (st == IBL_OK && b->atlas.pixels) st = stage_atlas(ctx, dir, b);
    if (st == IBL_OK && b->preview.pixels) st = stage_preview(ctx, dir, b);
    if (st == IBL_OK) st = ibl__bake_stage_target(ctx, dir, b);
    if (st == IBL_OK && extra) st = extra->stage(ctx, dir, extra->user);
    if (st == IBL_OK) {
        char *manifest = NULL;
        st = ibl_bake_manifest(ctx, b, &manifest);
        if (st == IBL_OK && extra) st = extra->manifest(ctx, &manifest, extra->user);
        if (st == IBL_OK) st = stage_text(ctx, dir, IBL__BAKE_MANIFEST, manifest);
    }
    return st;
}

static int sync_folder(const char *dir)
{
    int fd = open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd < 0) return -1;
    int r = fsync(fd);
    close(fd);
    return r;
}

/* Puts the staging folder in place of the target in one step where the file system can. */
static ibl_status swap_in(ibl_context *ctx, target_folder *t)
{
    struct stat st;
    if (stat(t->path, &st) != 0) {
        if (rename(t->staging, t->path) != 0)
            return ibl__fail(ctx, IBL_ERR_IO, "%s: cannot move the new bake in place: %s", t->path,
                             strerror(errno));
        return IBL_OK;
    }
    if (renameat2(AT_FDCWD, t->staging, AT_FDCWD, t->path, RENAME_EXCHANGE) == 0) {
        remove_bake_folder(ctx, t->staging); /* now the old bake */
        return IBL_OK;
    }
    if (errno != EINVAL && errno != ENOSYS && errno != ENOTSUP)
        return ibl__fail(ctx, IBL_ERR_IO, "%s: cannot swap the new bake in: %s", t->path, strerror(errno));
    /* no atomic exchange here: for the instant between the renames the folder is missing
     * (never half-written) */
    if (rename(t->path, t->displaced) != 0)
        return ibl__fail(ctx, IBL_ERR_IO, "%s: cannot move the old bake aside: %s", t->path, strerror(errno));
    if (rename(t->staging, t->path) != 0) {
        int e = errno;
        rename(t->displaced, t->path);
        return ibl__fail(ctx, IBL_ERR_IO, "%s: cannot move the new bake in place: %s", t->path, strerror(e));
    }
    remove_bake_folder(ctx, t->displaced);
    return IBL_OK;
}

/* A failure of a stage whose message does not name the folder gets it in front (an
 * allocation refused by the memory budget, a cancellation): every message names a file. */
static ibl_status name_failure(ibl_context *ctx, ibl_status st, const char *dir)
{
    const char *m = ibl_context_message(ctx);
    size_t n = strlen(dir);
    if (strncmp(m, dir, n) == 0 && m[n] == ':') return st;
    char saved[400];
    snprintf(saved, sizeof saved, "%s", m[0] ? m : ibl_status_name(st));
    return ibl__fail(ctx, st, "%s: %s", dir, saved);
}

/* Writes b into the locked target: stage, flush, last cancellation point, swap. */
static ibl_status commit(ibl_context *ctx, target_folder *t, const ibl_bake_data *b,
                         const ibl__bake_extra *extra)
{
    if (mkdir(t->staging, 0777) != 0)
        return ibl__fail(ctx, IBL_ERR_IO, "%s: cannot create the staging folder %s: %s", t->path,
                         t->staging, strerror(errno));
    ibl_status st = stage_all(ctx, t->staging, b, extra);
    if (st == IBL_OK && sync_folder(t->staging) != 0)
        st = ibl__fail(ctx, IBL_ERR_IO, "%s: cannot flush %s: %s", t->path, t->staging, strerror(errno));
    if (st == IBL_OK && ibl__progress(ctx, "write", 1.0) == IBL_ERR_CANCELLED)
        st = ibl__fail(ctx, IBL_ERR_CANCELLED, "%s: cancelled; nothing written", t->path);
    if (st == IBL_OK) st = swap_in(ctx, t);
    if (st == IBL_OK) sync_folder(t->parent);
    else remove_bake_folder(ctx, t->staging);
    return st;
}

ibl_status ibl_bake_write(ibl_context *ctx, const ibl_bake_data *bake, const char *dir)
{
    return ibl__bake_write_extra(ctx, bake, dir, NULL);
}

ibl_status ibl__bake_write_extra(ibl_context *ctx, const ibl_bake_data *bake, const char *dir,
                                 const ibl__bake_extra *extra)
{
    if (!bake || !bake->specular.data || !dir)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "bake: nothing to write");
    target_folder t;
    ibl_status st = begin(ctx, dir, &t);
    if (st == IBL_OK) st = commit(ctx, &t, bake, extra);
    target_release(ctx, &t);
    return st;
}

ibl_status ibl_bake(ibl_context *ctx, const ibl_cubemap *env, const ibl_bake_desc *desc,
                    const char *dir, ibl_bake_data *result)
{
    if (result) memset(result, 0, sizeof *result);
    if (!dir) return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "bake: no folder");
    target_folder t;
    /* lock first, so that a second writer is refused before it spends the work */
    ibl_status st = begin(ctx, dir, &t);
    ibl_bake_data b;
    memset(&b, 0, sizeof b);
    if (st == IBL_OK) {
        st = ibl_bake_compute(ctx, env, desc, &b);
        if (st != IBL_OK) st = name_failure(ctx, st, t.path);
    }
    if (st == IBL_OK) st = commit(ctx, &t, &b, NULL);
    if (st == IBL_OK && result) *result = b;
    else ibl_bake_free(ctx, &b);
    target_release(ctx, &t);
    return st;
}

/* ---- reading ------------------------------------------------------------------------------ */

/* Reads a cube texture (or, with allow_image, a flat image in a layout) into out. */
static ibl_status read_cube(ibl_context *ctx, const char *path, const ibl_read_desc *rd,
                            int allow_image, ibl_cubemap *out, ibl_texture *metadata)
{
    ibl_texture tex;
    ibl_status st = ibl_read_texture(ctx, path, rd, &tex, NULL);
    if (st != IBL_OK) return st;
    if (tex.kind == IBL_TEXTURE_CUBE) {
        *out = (ibl_cubemap){tex.width, tex.levels, tex.data, tex.owns_data};
        tex.owns_data = 0;
        if (metadata) { /* hand the key/values over */
            *metadata = tex;
            metadata->data = NULL;
            tex.metadata = NULL;
            tex.metadata_count = 0;
        }
    } else if (allow_image && tex.kind == IBL_TEXTURE_2D) {
        ibl_image im = {tex.width, tex.height, tex.data};
        st = ibl_image_to_cubemap(ctx, &im, NULL, out);
        if (st != IBL_OK) st = ibl__fail(ctx, st, "%s: %s", path, ibl_context_message(ctx));
    } else {
        st = ibl__fail(ctx, IBL_ERR_FORMAT, "%s: not a cube texture", path);
    }
    ibl_texture_free(ctx, &tex);
    return st;
}

/* Reads a 2D or 3D table of the expected shape; its texels move into *out. */
static ibl_status read_table(ibl_context *ctx, const char *path, const ibl_read_desc *rd,
                             ibl_texture_kind kind, ibl_texture *out)
{
    ibl_status st = ibl_read_texture(ctx, path, rd, out, NULL);
    if (st != IBL_OK) return st;
    if (out->kind != kind) {
        ibl_texture_free(ctx, out);
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: expected a %s table", path,
                         kind == IBL_TEXTURE_3D ? "3D" : "2D");
    }
    return IBL_OK;
}

static int exists(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0;
}

/* The first of the listed files that exists (KTX2 first), joined to the folder. */
static char *pick(ibl_context *ctx, const char *dir, const char *const names[2])
{
    for (int i = 0; i < 2 && names[i]; i++) {
        char *p = join(ctx, dir, names[i]);
        if (!p || exists(p) || i == 1 || !names[1]) return p;
        ibl_free(ctx, p);
    }
    return NULL;
}

static ibl_status load_specular(ibl_context *ctx, const char *dir, const char *const names[2],
                                const ibl_read_desc *rd, ibl_bake_data *b)
{
    char *path = pick(ctx, dir, names);
    if (!path) return ibl__fail(ctx, IBL_ERR_OUT_OF_MEMORY, "%s: out of memory", dir);
    ibl_status st = read_cube(ctx, path, rd, 0, &b->specular, NULL);
    const ibl_specular_info *info = &b->specular_info;
    if (st == IBL_OK && (b->specular.size != info->size || b->specular.levels < info->levels))
        st = ibl__fail(ctx, IBL_ERR_FORMAT,
                       "%s: holds a %d-texel chain of %d levels; the manifest describes %d texels "
                       "and %d levels", path, b->specular.size, b->specular.levels, info->size,
                       info->levels);
    ibl_free(ctx, path);
    return st;
}

static ibl_status load_tables(ibl_context *ctx, const char *dir, const ibl__bake_manifest_files *f,
                              const ibl_read_desc *rd, ibl_bake_data *b)
{
    ibl_status st = IBL_OK;
    if (f->splitsum) {
        char *path = join(ctx, dir, f->splitsum);
        ibl_texture t;
        st = path ? read_table(ctx, path, rd, IBL_TEXTURE_2D, &t) : IBL_ERR_OUT_OF_MEMORY;
        if (st == IBL_OK) {
            b->splitsum = (ibl_image){t.width, t.height, t.data};
            t.owns_data = 0;
            if (t.width != b->splitsum_n_dot_v.count || t.height != b->splitsum_roughness.count)
                st = ibl__fail(ctx, IBL_ERR_FORMAT, "%s: is %dx%d; the manifest's axes say %dx%d", path,
                               t.width, t.height, b->splitsum_n_dot_v.count, b->splitsum_roughness.count);
            ibl_texture_free(ctx, &t);
        }
        ibl_free(ctx, path);
    }
    if (st == IBL_OK && f->ambient_brdf) {
        char *path = join(ctx, dir, f->ambient_brdf);
        st = path ? read_table(ctx, path, rd, IBL_TEXTURE_3D, &b->ambient_brdf) : IBL_ERR_OUT_OF_MEMORY;
        const ibl_texture *t = &b->ambient_brdf;
        if (st == IBL_OK && (t->width != b->ambient_n_dot_v.count || t->height != b->ambient_shininess.count ||
                             t->depth != b->ambient_f0.count))
            st = ibl__fail(ctx, IBL_ERR_FORMAT, "%s: is %dx%dx%d; the manifest's axes say %dx%dx%d",
                           path, t->width, t->height, t->depth, b->ambient_n_dot_v.count,
                           b->ambient_shininess.count, b->ambient_f0.count);
        ibl_free(ctx, path);
    }
    return st;
}

/* The atlas KTX2: a 2D texture of the manifest's size whose own table (key "ibl.atlas")
 * is the manifest's. */
static ibl_status load_atlas(ibl_context *ctx, const char *dir, const char *name,
                             const ibl_read_desc *rd, ibl_bake_data *b)
{
    char *path = join(ctx, dir, name);
    if (!path) return ibl__fail(ctx, IBL_ERR_OUT_OF_MEMORY, "%s: out of memory", dir);
    ibl_texture t;
    ibl_status st = read_table(ctx, path, rd, IBL_TEXTURE_2D, &t);
    if (st == IBL_OK) {
        b->atlas = (ibl_image){t.width, t.height, t.data};
        t.owns_data = 0;
        const ibl_atlas_layout *want = &b->atlas_layout;
        const char *text = ibl_texture_get_metadata(&t, "ibl.atlas");
        ibl_atlas_layout own;
        if (t.width != want->width || t.height != want->height)
            st = ibl__fail(ctx, IBL_ERR_FORMAT, "%s: is %dx%d; the manifest's atlas is %dx%d", path,
                           t.width, t.height, want->width, want->height);
        else if (!text)
            st = ibl__fail(ctx, IBL_ERR_FORMAT, "%s: has no ibl.atlas table", path);
        else if ((st = ibl_atlas_layout_from_json(ctx, text, path, &own)) == IBL_OK &&
                 memcmp(&own, want, sizeof own) != 0)
            st = ibl__fail(ctx, IBL_ERR_FORMAT, "%s: its ibl.atlas table differs from the manifest's", path);
        ibl_texture_free(ctx, &t);
    }
    ibl_free(ctx, path);
    return st;
}

/* "path" as given: a bake folder or its manifest.json. */
static ibl_status locate_manifest(ibl_context *ctx, const char *path, char **dir, char **manifest)
{
    struct stat st;
    *dir = *manifest = NULL;
    if (stat(path, &st) == 0 && S_ISDIR(st.st_mode)) {
        *dir = join(ctx, path, "");
        *manifest = join(ctx, path, ibl__bake_file_info_of(IBL__BAKE_MANIFEST)->name);
    } else {
        const char *slash = strrchr(path, '/');
        size_t n = slash ? (size_t)(slash - path) + 1 : 0;
        *dir = ibl_alloc(ctx, n + 2);
        if (*dir) {
            memcpy(*dir, path, n);
            strcpy(*dir + n, n ? "" : "./");
        }
        *manifest = join(ctx, "", path);
    }
    if (!*dir || !*manifest) {
        ibl_free(ctx, *dir);
        ibl_free(ctx, *manifest);
        return ibl__fail(ctx, IBL_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
    }
    return IBL_OK;
}

ibl_status ibl_bake_load(ibl_context *ctx, const char *path, const ibl_read_desc *rd,
                         ibl_bake_data *out)
{
    if (!out) return IBL_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    if (!path) return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "bake: no folder");
    char *dir, *manifest;
    ibl_status st = locate_manifest(ctx, path, &dir, &manifest);
    if (st != IBL_OK) return st;
    void *bytes = NULL, *root = NULL;
    size_t size = 0;
    ibl__bake_manifest_files files;
    st = ibl_read_file(ctx, manifest, &bytes, &size);
    if (st == IBL_OK) st = ibl__bake_manifest_parse(ctx, bytes, size, manifest, out, &files, &root);
    ibl_free(ctx, bytes);
    if (st == IBL_OK) st = load_specular(ctx, dir, files.specular, rd, out);
    if (st == IBL_OK && files.irradiance[0]) {
        char *p = pick(ctx, dir, files.irradiance);
        st = p ? read_cube(ctx, p, rd, 0, &out->irradiance, NULL) : IBL_ERR_OUT_OF_MEMORY;
        ibl_free(ctx, p);
    }
    if (st == IBL_OK) st = load_tables(ctx, dir, &files, rd, out);
    if (st == IBL_OK && files.atlas) st = load_atlas(ctx, dir, files.atlas, rd, out);
    ibl__bake_manifest_release(root);
    ibl_free(ctx, dir);
    ibl_free(ctx, manifest);
    if (st != IBL_OK) ibl_bake_free(ctx, out);
    return st;
}

/* The chain's description: its own KTX2 metadata when ibl wrote it, else the caller's
 * mapping (in the probe's units: roughness, or material shininess as a Blinn chain). */
static ibl_status describe_chain(ibl_context *ctx, const ibl_bake_parts *parts,
                                 const ibl_texture *metadata, ibl_bake_data *b)
{
    ibl_specular_info *info = &b->specular_info;
    if (ibl_texture_get_metadata(metadata, "ibl.specular.filter"))
        return ibl_specular_info_from_metadata(ctx, metadata, parts->specular, info);
    const ibl_level_mapping *m = &parts->mapping;
    int n = b->specular.levels;
    memset(info, 0, sizeof *info);
    info->size = b->specular.size;
    info->mapping = IBL_MAPPING_TABLE;
    info->blinn_factor = IBL_DEFAULT_BLINN_FACTOR;
    info->shininess_min = IBL_DEFAULT_SHININESS_MIN;
    info->shininess_max = IBL_DEFAULT_SHININESS_MAX;
    if (m->levels <= 0) {
        info->filter = IBL_FILTER_GGX;
        info->mapping = IBL_MAPPING_LINEAR;
        info->levels = n;
        for (int k = 0; k < n; k++) info->roughness[k] = n > 1 ? (float)k / (float)(n - 1) : 0.0f;
        return IBL_OK;
    }
    if (m->levels > n)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "%s: has %d levels; the mapping describes %d",
                         parts->specular, n, m->levels);
    info->levels = m->levels;
    int shininess = 0;
    for (int k = 0; k < m->levels; k++) shininess |= m->shininess[k] != 0.0f;
    info->filter = shininess ? IBL_FILTER_BLINN : IBL_FILTER_GGX;
    for (int k = 0; k < m->levels; k++) {
        info->roughness[k] = m->roughness[k];
        info->shininess[k] = m->shininess[k] >= IBL_MIRROR_SHININESS ? 0.0f : m->shininess[k];
    }
    return IBL_OK;
}

ibl_status ibl_bake_load_parts(ibl_context *ctx, const ibl_bake_parts *parts,
                               const ibl_read_desc *rd, ibl_bake_data *b)
{
    if (!b) return IBL_ERR_INVALID_ARGUMENT;
    memset(b, 0, sizeof *b);
    if (!parts || !parts->specular)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "bake: no prefiltered chain file");
    ibl_texture metadata = {0};
    ibl_status st = read_cube(ctx, parts->specular, rd, 0, &b->specular, &metadata);
    if (st == IBL_OK) st = describe_chain(ctx, parts, &metadata, b);
    ibl_texture_free(ctx, &metadata);
    if (st == IBL_OK && parts->environment)
        st = read_cube(ctx, parts->environment, rd, 1, &b->environment, NULL);
    if (st == IBL_OK && parts->irradiance)
        st = read_cube(ctx, parts->irradiance, rd, 1, &b->irradiance, NULL);
    if (st == IBL_OK && !parts->irradiance) {
        /* SH9 of the sharpest radiance at hand, at a level of at most 32 texels */
        const ibl_cubemap *src = b->environment.data ? &b->environment : &b->specular;
        int level = 0;
        while (level + 1 < src->levels && ibl_level_size(src->size, level) > 32) level++;
        st = ibl_sh_project_cubemap(ctx, src, level, 3, &b->sh);
    }
    if (st == IBL_OK && parts->splitsum) {
        ibl_texture t;
        st = read_table(ctx, parts->splitsum, rd, IBL_TEXTURE_2D, &t);
        if (st == IBL_OK) {
            b->splitsum = (ibl_image){t.width, t.height, t.data};
            t.owns_data = 0;
            /* as brdf.h writes them: texel centres over [0, 1] on both axes */
            b->splitsum_n_dot_v = (ibl_table_axis){t.width, 0.5f / t.width, 1.0f - 0.5f / t.width, 0};
            b->splitsum_roughness = (ibl_table_axis){t.height, 0.5f / t.height, 1.0f - 0.5f / t.height, 0};
            ibl_texture_free(ctx, &t);
        }
    }
    if (st == IBL_OK && parts->ambient_brdf) {
        st = read_table(ctx, parts->ambient_brdf, rd, IBL_TEXTURE_3D, &b->ambient_brdf);
        if (st == IBL_OK) {
            double lo = parts->ambient_shininess_min > 0 ? parts->ambient_shininess_min : IBL_DEFAULT_AMBIENT_TABLE_MIN;
            double hi = parts->ambient_shininess_max > lo ? parts->ambient_shininess_max : IBL_DEFAULT_AMBIENT_TABLE_MAX;
            const ibl_texture *t = &b->ambient_brdf;
            ibl_ambient_brdf_desc ad = {.size_shininess = t->height, .shininess_min = lo,
                                        .shininess_max = hi,
                                        .spacing = parts->ambient_linear ? IBL_SHININESS_LINEAR : IBL_SHININESS_LOG};
            b->ambient_n_dot_v = (ibl_table_axis){t->width, 0.5f / t->width, 1.0f - 0.5f / t->width, 0};
            b->ambient_shininess = (ibl_table_axis){t->height, (float)ibl_ambient_brdf_row_shininess(&ad, 0),
                                                    (float)ibl_ambient_brdf_row_shininess(&ad, t->height - 1),
                                                    !parts->ambient_linear};
            b->ambient_f0 = (ibl_table_axis){t->depth, 0.5f / t->depth, 1.0f - 0.5f / t->depth, 0};
        }
    }
    if (st == IBL_OK) {
        const char *name = parts->specular;
        size_t n = strlen(name) + 1;
        b->source_name = ibl_alloc(ctx, n);
        if (b->source_name) memcpy(b->source_name, name, n);
        else st = ibl_context_status(ctx);
    }
    if (st != IBL_OK) ibl_bake_free(ctx, b);
    return st;
}
