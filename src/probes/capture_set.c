/* The captures folder (docs/PROBES.md "The captures folder"): every local probe of a set
 * captured and written with captures.json as one output set (src/io/output.c), so the folder
 * gets all of its files or none. */
#include "ibl/io.h"
#include "ibl/probes.h"
#include "core/context_internal.h"
#include "io/json.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static ibl_status make_folder(ibl_context *ctx, const char *dir, int *created)
{
    *created = 0;
    struct stat st;
    if (stat(dir, &st) == 0) {
        if (S_ISDIR(st.st_mode)) return IBL_OK;
        return ibl__fail(ctx, IBL_ERR_IO, "%s: exists and is not a folder", dir);
    }
    if (mkdir(dir, 0777) != 0)
        return ibl__fail(ctx, IBL_ERR_IO, "%s: cannot create the folder: %s", dir, strerror(errno));
    *created = 1;
    return IBL_OK;
}

static json_t *probe_json(const ibl_local_probe *p, const char *file, int size, double coverage)
{
    json_t *o = json_object();
    ibl__json_set(o, "name", ibl__json_string(p->name));
    ibl__json_set(o, "file", ibl__json_string(file));
    ibl__json_set(o, "size", ibl__json_number(size));
    ibl__json_set(o, "capture", ibl__json_string(ibl_capture_mode_name(p->capture)));
    ibl__json_set(o, "position", ibl__json_vec3(p->position));
    ibl__json_set(o, "coverage", ibl__json_number(coverage));
    return o;
}

static double mean_alpha(const ibl_cubemap *c)
{
    double m[4];
    ibl_cubemap_mean(c, 0, m);
    return m[3];
}

static ibl_status capture_all(ibl_context *ctx, const ibl_scene *scene, const ibl_cubemap *env,
                              const ibl_probe_set *set, const ibl_capture_desc *desc,
                              const char *dir, ibl_output_set *out, json_t *list)
{
    for (int i = 0; i < set->probe_count; i++) {
        const ibl_local_probe *p = &set->probes[i];
        ibl_cubemap cube;
        ibl_status st = ibl_capture_probe(ctx, scene, env, p, i, desc, &cube);
        if (st != IBL_OK) return st;
        char file[IBL_PROBE_NAME_MAX + 8], path[4096];
        snprintf(file, sizeof file, "%s.ktx2", p->name);
        if (snprintf(path, sizeof path, "%s/%s", dir, file) >= (int)sizeof path) {
            ibl_cubemap_free(ctx, &cube);
            return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "%s: path too long", dir);
        }
        ibl_texture tex = ibl_texture_from_cubemap(&cube);
        ibl_write_desc wd;
        memset(&wd, 0, sizeof wd);
        wd.format = IBL_FORMAT_RGBA32F;
        st = ibl_output_set_add_texture(out, path, &tex, &wd);
        json_t *entry = probe_json(p, file, cube.size, mean_alpha(&cube));
        ibl_cubemap_free(ctx, &cube);
        ibl__json_append(list, entry);
        if (st != IBL_OK) return st;
    }
    return IBL_OK;
}

static json_t *manifest_head(const ibl_probe_set *set, const ibl_capture_desc *d)
{
    json_t *root = json_object();
    ibl__json_set(root, "format", ibl__json_string("ibl-captures"));
    ibl__json_set(root, "version", ibl__json_number(1));
    ibl__json_set(root, "generator", ibl__json_string("ibl " IBL_VERSION_STRING));
    ibl__json_set(root, "probe_set", ibl__json_string(set->path));
    ibl__json_set(root, "environment", ibl__json_string(set->global.environment
                                                            ? set->global.environment : "sky"));
    ibl__json_set(root, "bounces", ibl__json_number(d->bounces == IBL_CAPTURE_NO_BOUNCE ? 0
                                                    : d->bounces ? d->bounces : 2));
    ibl__json_set(root, "samples", ibl__json_number(d->samples ? d->samples : 64));
    ibl__json_set(root, "seed", ibl__json_number(d->seed));
    ibl__json_set(root, "light_sampling", ibl__json_bool(!d->no_light_sampling));
    ibl__json_set(root, "alpha", ibl__json_string("premultiplied coverage"));
    ibl__json_set(root, "format_of_files", ibl__json_string("ktx2 cube, one level, rgba32f"));
    return root;
}

ibl_status ibl_capture_set(ibl_context *ctx, const ibl_scene *scene,
                           const ibl_cubemap *environment, const ibl_probe_set *set,
                           const ibl_capture_desc *desc, const char *dir)
{
    if (!ctx || !scene || !environment || !set || !dir || !dir[0]) return IBL_ERR_INVALID_ARGUMENT;
    ibl_capture_desc d;
    memset(&d, 0, sizeof d);
    if (desc) d = *desc;
    int created;
    ibl_status st = make_folder(ctx, dir, &created);
    if (st != IBL_OK) return st;
    ibl_output_set *out = NULL;
    st = ibl_output_set_create(ctx, &out);
    json_t *root = manifest_head(set, &d), *list = json_array();
    if (st == IBL_OK) st = capture_all(ctx, scene, environment, set, &d, dir, out, list);
    ibl__json_set(root, "probes", list);
    char *text = NULL, path[4096];
    if (st == IBL_OK && snprintf(path, sizeof path, "%s/captures.json", dir) >= (int)sizeof path)
        st = ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "%s: path too long", dir);
    if (st == IBL_OK) st = ibl__json_text(ctx, root, path, &text);
    else json_decref(root);
    if (st == IBL_OK) st = ibl_output_set_add(out, path, text, strlen(text));
    if (st == IBL_OK) st = ibl_output_set_commit(out);
    ibl_free(ctx, text);
    ibl_output_set_destroy(out);
    if (st != IBL_OK && created) rmdir(dir); /* nothing partial: not even the new folder */
    return st;
}
