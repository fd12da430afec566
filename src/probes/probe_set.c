/* Probe-set files (docs/PROBES.md): the global probe and the local probes of a scene, read
 * with jansson through src/io/json.c so that every error names the file and the field's JSON
 * path. The set's model is the JAGE 2015 article's ("Image Based Lighting", Just Another Game
 * Engine blog): influence volumes with blend margins, parallax proxies (Lagarde and Zanuttini
 * 2012), and the article's two capture methods. */
#include "ibl/probes.h"
#include "ibl/io.h"
#include "ibl/layout.h"
#include "ibl/specular.h"
#include "core/context_internal.h"
#include "core/numeric.h"
#include "io/json.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { DEFAULT_PROBE_SIZE = 128, DEFAULT_GLOBAL_SIZE = 256, MAX_PROBES = 4096 };
static const char default_preset[] = "gltf";

const char *ibl_capture_mode_name(ibl_capture_mode mode)
{
    return mode == IBL_CAPTURE_INFINITE ? "infinite" : "far-plane";
}

int ibl_capture_mode_from_name(const char *name, ibl_capture_mode *out)
{
    if (!name) return 0;
    if (strcmp(name, "far-plane") == 0) *out = IBL_CAPTURE_FAR_PLANE;
    else if (strcmp(name, "infinite") == 0) *out = IBL_CAPTURE_INFINITE;
    else return 0;
    return 1;
}

/* ---- field readers with paths ---------------------------------------------------------- */

static void join_path(char *out, size_t cap, const char *path, const char *key)
{
    snprintf(out, cap, "%s%s%s", path, path[0] ? "." : "", key);
}

/* Refuses keys the schema does not know (a misspelt "influense" must not pass silently). */
static void check_keys(ibl__json_reader *r, json_t *obj, const char *path,
                       const char *const *allowed)
{
    const char *key;
    json_t *value;
    json_object_foreach(obj, key, value) {
        (void)value;
        int known = 0;
        for (int i = 0; allowed[i]; i++)
            if (strcmp(allowed[i], key) == 0) known = 1;
        if (!known) ibl__json_fail(r, path, key, "unknown field");
    }
}

static json_t *opt_object(ibl__json_reader *r, json_t *parent, const char *path, const char *key)
{
    json_t *v = json_object_get(parent, key);
    if (!v || json_is_null(v)) return NULL;
    if (!json_is_object(v)) {
        ibl__json_fail(r, path, key, "expected an object");
        return NULL;
    }
    return v;
}

/* [x, y, z] of finite numbers; required unless fallback is given */
static ibl_vec3 get_vec3(ibl__json_reader *r, json_t *parent, const char *path, const char *key,
                         const ibl_vec3 *fallback)
{
    ibl_vec3 v = fallback ? *fallback : ibl__v3(0.0f, 0.0f, 0.0f);
    json_t *a = json_object_get(parent, key);
    if (!a || json_is_null(a)) {
        if (!fallback) ibl__json_fail(r, path, key, "missing");
        return v;
    }
    if (!json_is_array(a) || json_array_size(a) != 3) {
        ibl__json_fail(r, path, key, "expected an array of 3 numbers");
        return v;
    }
    float c[3];
    for (int i = 0; i < 3; i++) {
        json_t *e = json_array_get(a, (size_t)i);
        double x = json_is_number(e) ? json_number_value(e) : NAN;
        if (!isfinite(x) || fabs(x) > 1e30) {
            char where[256];
            snprintf(where, sizeof where, "%s[%d]", key, i);
            ibl__json_fail(r, path, where, "expected a finite number");
            return v;
        }
        c[i] = (float)x;
    }
    v.x = c[0], v.y = c[1], v.z = c[2];
    return v;
}

static double get_positive(ibl__json_reader *r, json_t *parent, const char *path,
                           const char *key, int required, double fallback)
{
    double x = required ? ibl__json_get_number(r, parent, path, key)
                        : ibl__json_opt_number(r, parent, path, key, fallback);
    if (r->status == IBL_OK && !(x > 0.0 && x < 1e30))
        ibl__json_fail(r, path, key, "must be > 0");
    return x;
}

static void get_preset(ibl__json_reader *r, json_t *parent, const char *path, char *out)
{
    const char *p = ibl__json_opt_string(r, parent, path, "preset", default_preset);
    ibl_specular_desc d;
    memset(&d, 0, sizeof d);
    if (r->status == IBL_OK && !ibl_specular_preset(p, &d)) {
        char names[512] = "";
        for (const char *const *n = ibl_specular_preset_names(); *n; n++)
            snprintf(names + strlen(names), sizeof names - strlen(names), "%s%s",
                     names[0] ? ", " : "", *n);
        ibl__json_fail(r, path, "preset", "unknown preset \"%s\" (known: %s)", p, names);
        return;
    }
    snprintf(out, IBL_PROBE_PRESET_MAX, "%s", p);
}

static int get_size(ibl__json_reader *r, json_t *parent, const char *path, int fallback)
{
    if (!json_object_get(parent, "size")) return fallback;
    int s = ibl__json_get_int(r, parent, path, "size", 1, 4096);
    if (r->status == IBL_OK && (s < 4 || (s & (s - 1)) != 0))
        ibl__json_fail(r, path, "size", "must be a power of two from 4 to 4096");
    return s;
}

/* ---- volumes ------------------------------------------------------------------------------ */

static const char *const volume_keys[] = {"shape", "center", "radius", "half_extent", "blend", NULL};

/* A sphere or a box; center defaults to the probe's position; blend only when allowed. */
static ibl_volume get_volume(ibl__json_reader *r, json_t *obj, const char *path,
                             ibl_vec3 position, int with_blend)
{
    ibl_volume v;
    memset(&v, 0, sizeof v);
    check_keys(r, obj, path, volume_keys);
    const char *shape = ibl__json_get_string(r, obj, path, "shape");
    if (r->status != IBL_OK) return v;
    if (strcmp(shape, "sphere") == 0) v.shape = IBL_VOLUME_SPHERE;
    else if (strcmp(shape, "box") == 0) v.shape = IBL_VOLUME_BOX;
    else {
        ibl__json_fail(r, path, "shape", "expected \"sphere\" or \"box\", not \"%s\"", shape);
        return v;
    }
    v.center = get_vec3(r, obj, path, "center", &position);
    float inner; /* the smallest distance from the centre to the surface */
    if (v.shape == IBL_VOLUME_SPHERE) {
        if (json_object_get(obj, "half_extent"))
            ibl__json_fail(r, path, "half_extent", "a sphere has a radius, not half_extent");
        v.radius = (float)get_positive(r, obj, path, "radius", 1, 0.0);
        inner = v.radius;
    } else {
        if (json_object_get(obj, "radius"))
            ibl__json_fail(r, path, "radius", "a box has half_extent, not a radius");
        v.half_extent = get_vec3(r, obj, path, "half_extent", NULL);
        if (r->status == IBL_OK &&
            !(v.half_extent.x > 0 && v.half_extent.y > 0 && v.half_extent.z > 0))
            ibl__json_fail(r, path, "half_extent", "every half extent must be > 0");
        inner = fminf(v.half_extent.x, fminf(v.half_extent.y, v.half_extent.z));
    }
    if (!with_blend) {
        if (json_object_get(obj, "blend"))
            ibl__json_fail(r, path, "blend", "a parallax proxy has no blend margin");
        return v;
    }
    double blend = ibl__json_opt_number(r, obj, path, "blend", 0.0);
    if (r->status == IBL_OK && !(blend >= 0.0 && blend <= inner))
        ibl__json_fail(r, path, "blend", "must be from 0 to %g (the volume's half size)",
                       (double)inner);
    v.blend_distance = (float)blend;
    return v;
}

static int inside(const ibl_volume *v, ibl_vec3 p)
{
    ibl_vec3 d = {p.x - v->center.x, p.y - v->center.y, p.z - v->center.z};
    if (v->shape == IBL_VOLUME_SPHERE) return d.x * d.x + d.y * d.y + d.z * d.z < v->radius * v->radius;
    return fabsf(d.x) < v->half_extent.x && fabsf(d.y) < v->half_extent.y &&
           fabsf(d.z) < v->half_extent.z;
}

/* ---- the two sections ---------------------------------------------------------------------- */

static const char *const probe_keys[] = {"name", "position", "influence", "proxy", "priority",
                                         "capture", "size", "preset", NULL};

static int valid_name(const char *s)
{
    if (!s[0] || strlen(s) >= IBL_PROBE_NAME_MAX) return 0;
    for (; *s; s++)
        if (!((*s >= 'a' && *s <= 'z') || (*s >= 'A' && *s <= 'Z') || (*s >= '0' && *s <= '9') ||
              *s == '_' || *s == '-'))
            return 0;
    return 1;
}

static void read_probe(ibl__json_reader *r, json_t *obj, const char *path, ibl_local_probe *p)
{
    char sub[256];
    if (!json_is_object(obj)) {
        ibl__json_fail(r, path, NULL, "expected an object");
        return;
    }
    check_keys(r, obj, path, probe_keys);
    const char *name = ibl__json_get_string(r, obj, path, "name");
    if (r->status == IBL_OK && !valid_name(name))
        ibl__json_fail(r, path, "name", "must be 1 to %d of A-Z a-z 0-9 _ - (it names a file)",
                       IBL_PROBE_NAME_MAX - 1);
    if (r->status != IBL_OK) return;
    snprintf(p->name, sizeof p->name, "%s", name);
    p->position = get_vec3(r, obj, path, "position", NULL);
    json_t *inf = ibl__json_object(r, obj, path, "influence");
    if (r->status != IBL_OK) return;
    join_path(sub, sizeof sub, path, "influence");
    p->influence = get_volume(r, inf, sub, p->position, 1);
    json_t *proxy = opt_object(r, obj, path, "proxy");
    join_path(sub, sizeof sub, path, "proxy");
    if (proxy) p->proxy = get_volume(r, proxy, sub, p->position, 0);
    else {
        p->proxy = p->influence; /* the usual choice: the room the probe stands in */
        p->proxy.blend_distance = 0.0f;
    }
    if (r->status != IBL_OK) return;
    p->priority = json_object_get(obj, "priority")
                      ? ibl__json_get_int(r, obj, path, "priority", -1000000, 1000000) : 0;
    const char *mode = ibl__json_opt_string(r, obj, path, "capture", "far-plane");
    if (r->status == IBL_OK && !ibl_capture_mode_from_name(mode, &p->capture))
        ibl__json_fail(r, path, "capture", "expected \"far-plane\" or \"infinite\", not \"%s\"",
                       mode);
    p->size = get_size(r, obj, path, DEFAULT_PROBE_SIZE);
    get_preset(r, obj, path, p->preset);
    if (r->status != IBL_OK) return;
    if (!inside(&p->influence, p->position))
        ibl__json_fail(r, path, "position", "outside the probe's influence volume");
    else if (!inside(&p->proxy, p->position))
        ibl__json_fail(r, path, "position", "outside the probe's parallax proxy");
}

static const char *const global_keys[] = {"environment", "sky", "yaw", "size", "preset", NULL};
static const char *const sky_keys[] = {"sun_elevation", "sun_azimuth", "turbidity",
                                       "ground_albedo", NULL};

static void read_global(ibl__json_reader *r, json_t *obj, const char *dir, ibl_global_probe *g)
{
    check_keys(r, obj, "global", global_keys);
    const char *env = ibl__json_opt_string(r, obj, "global", "environment", "sky");
    if (r->status != IBL_OK) return;
    if (!env[0]) {
        ibl__json_fail(r, "global", "environment", "must be \"sky\" or a path");
        return;
    }
    json_t *sky = opt_object(r, obj, "global", "sky");
    if (strcmp(env, "sky") != 0) {
        if (sky) ibl__json_fail(r, "global", "sky", "only with \"environment\": \"sky\"");
        size_t need = strlen(dir) + strlen(env) + 2;
        g->environment = ibl_alloc(r->ctx, need);
        if (!g->environment) {
            r->status = IBL_ERR_OUT_OF_MEMORY;
            return;
        }
        if (env[0] == '/' || strcmp(dir, ".") == 0) snprintf(g->environment, need, "%s", env);
        else snprintf(g->environment, need, "%s/%s", dir, env);
    } else if (sky) {
        check_keys(r, sky, "global.sky", sky_keys);
        g->sky.sun_elevation_deg = (float)ibl__json_opt_number(r, sky, "global.sky", "sun_elevation", 35);
        g->sky.sun_azimuth_deg = (float)ibl__json_opt_number(r, sky, "global.sky", "sun_azimuth", 0);
        g->sky.turbidity = (float)ibl__json_opt_number(r, sky, "global.sky", "turbidity", 3);
        g->sky.ground_albedo = (float)ibl__json_opt_number(r, sky, "global.sky", "ground_albedo", 0.3);
        if (r->status == IBL_OK && !(g->sky.sun_elevation_deg > 0 && g->sky.sun_elevation_deg <= 90))
            ibl__json_fail(r, "global.sky", "sun_elevation", "must be in (0, 90] degrees");
        else if (r->status == IBL_OK && !(g->sky.turbidity >= 1.7f && g->sky.turbidity <= 10))
            ibl__json_fail(r, "global.sky", "turbidity", "must be from 1.7 to 10");
        else if (r->status == IBL_OK && !(g->sky.ground_albedo >= 0 && g->sky.ground_albedo <= 1))
            ibl__json_fail(r, "global.sky", "ground_albedo", "must be from 0 to 1");
        if (g->sky.ground_albedo == 0.0f) g->sky.ground_albedo = -1.0f; /* black, not default */
    }
    g->yaw_degrees = (float)ibl__json_opt_number(r, obj, "global", "yaw", 0.0);
    g->size = get_size(r, obj, "global", DEFAULT_GLOBAL_SIZE);
    get_preset(r, obj, "global", g->preset);
}

static const char *const root_keys[] = {"format", "version", "global", "probes", "view", NULL};
static const char *const view_keys[] = {"position", "target", "fov", NULL};

/* The scene's default camera for `ibl render SCENE --probes` (optional). */
static void read_view(ibl__json_reader *r, json_t *root, ibl_probe_set *out)
{
    json_t *view = opt_object(r, root, "", "view");
    if (!view || r->status != IBL_OK) return;
    check_keys(r, view, "view", view_keys);
    out->view.position = get_vec3(r, view, "view", "position", NULL);
    out->view.target = get_vec3(r, view, "view", "target", NULL);
    double fov = ibl__json_opt_number(r, view, "view", "fov", 60.0);
    if (r->status == IBL_OK && !(fov > 0.0 && fov < 180.0))
        ibl__json_fail(r, "view", "fov", "must be between 0 and 180 degrees");
    ibl_vec3 d = ibl__sub(out->view.target, out->view.position);
    if (r->status == IBL_OK && !(ibl__dot(d, d) > 0.0f))
        ibl__json_fail(r, "view", "target", "must differ from the position");
    out->view.fov_y_degrees = (float)fov;
    out->has_view = r->status == IBL_OK;
}

static void read_root(ibl__json_reader *r, json_t *root, const char *dir, ibl_probe_set *out)
{
    if (!json_is_object(root)) {
        ibl__json_fail(r, "", "", "expected an object at the top");
        return;
    }
    check_keys(r, root, "", root_keys);
    const char *format = ibl__json_get_string(r, root, "", "format");
    if (r->status == IBL_OK && strcmp(format, "ibl-probes") != 0)
        ibl__json_fail(r, "", "format", "expected \"ibl-probes\"");
    int version = ibl__json_get_int(r, root, "", "version", 1, 1000000);
    if (r->status == IBL_OK && version != 1)
        ibl__json_fail(r, "", "version", "version %d is not supported (this reader: 1)", version);
    json_t *global = ibl__json_object(r, root, "", "global");
    if (r->status != IBL_OK) return;
    read_global(r, global, dir, &out->global);
    read_view(r, root, out);
    json_t *probes = ibl__json_array(r, root, "", "probes");
    if (r->status != IBL_OK) return;
    size_t count = json_array_size(probes);
    if (count > MAX_PROBES) {
        ibl__json_fail(r, "", "probes", "more than %d probes", MAX_PROBES);
        return;
    }
    if (count) {
        out->probes = ibl_calloc(r->ctx, count, sizeof *out->probes);
        if (!out->probes) {
            r->status = IBL_ERR_OUT_OF_MEMORY;
            return;
        }
    }
    for (size_t i = 0; i < count && r->status == IBL_OK; i++) {
        char path[64];
        snprintf(path, sizeof path, "probes[%zu]", i);
        read_probe(r, json_array_get(probes, i), path, &out->probes[i]);
        for (size_t j = 0; j < i && r->status == IBL_OK; j++)
            if (strcmp(out->probes[j].name, out->probes[i].name) == 0)
                ibl__json_fail(r, path, "name", "\"%s\" is also the name of probes[%zu]",
                               out->probes[i].name, j);
        out->probe_count = (int)i + 1;
    }
}

ibl_status ibl_probe_set_parse(ibl_context *ctx, const void *bytes, size_t size,
                               const char *name, const char *dir, ibl_probe_set *out)
{
    if (!ctx || !bytes || !out) return IBL_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    if (!name) name = "<memory>";
    json_t *root = NULL;
    ibl_status st = ibl__json_parse(ctx, bytes, size, name, &root);
    if (st != IBL_OK) return st;
    ibl__json_reader r = {ctx, name, IBL_OK};
    read_root(&r, root, dir ? dir : ".", out);
    json_decref(root);
    st = r.status;
    if (st == IBL_OK) out->path = ibl__strdup(ctx, name);
    if (st == IBL_OK && !out->path) st = IBL_ERR_OUT_OF_MEMORY;
    if (st != IBL_OK) ibl_probe_set_free(ctx, out);
    return st;
}

ibl_status ibl_probe_set_load(ibl_context *ctx, const char *path, ibl_probe_set *out)
{
    if (!ctx || !path || !out) return IBL_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    void *bytes = NULL;
    size_t size = 0;
    ibl_status st = ibl_read_file(ctx, path, &bytes, &size);
    if (st != IBL_OK) return st;
    char *dir = ibl__strdup(ctx, path);
    if (!dir) {
        ibl_free(ctx, bytes);
        return IBL_ERR_OUT_OF_MEMORY;
    }
    char *slash = strrchr(dir, '/');
    if (slash == dir) slash[1] = '\0';
    else if (slash) *slash = '\0';
    else strcpy(dir, ".");
    st = ibl_probe_set_parse(ctx, bytes, size, path, dir, out);
    ibl_free(ctx, dir);
    ibl_free(ctx, bytes);
    return st;
}

void ibl_probe_set_free(ibl_context *ctx, ibl_probe_set *set)
{
    if (!set) return;
    ibl_free(ctx, set->global.environment);
    ibl_free(ctx, set->probes);
    ibl_free(ctx, set->path);
    memset(set, 0, sizeof *set);
}

void ibl_probe_set_order(const ibl_probe_set *set, int *order)
{
    int n = set->probe_count;
    for (int i = 0; i < n; i++) order[i] = i;
    /* insertion sort, as the JAGE 2015 article sorts its probes on the CPU */
    for (int i = 1; i < n; i++) {
        int k = order[i], j = i - 1;
        const ibl_local_probe *pk = &set->probes[k];
        while (j >= 0) {
            const ibl_local_probe *pj = &set->probes[order[j]];
            int before = pk->priority > pj->priority ||
                         (pk->priority == pj->priority &&
                          ibl_volume_size(&pk->influence) < ibl_volume_size(&pj->influence));
            if (!before) break;
            order[j + 1] = order[j];
            j--;
        }
        order[j + 1] = k;
    }
}

ibl_status ibl_probe_set_environment(ibl_context *ctx, const ibl_probe_set *set,
                                     ibl_cubemap *out)
{
    if (!ctx || !set || !out) return IBL_ERR_INVALID_ARGUMENT;
    ibl_image image;
    ibl_status st = set->global.environment
                        ? ibl_read_image(ctx, set->global.environment, NULL, &image, NULL)
                        : ibl_sky_render(ctx, &set->global.sky, &image);
    if (st != IBL_OK) return st;
    ibl_to_cube_desc d;
    memset(&d, 0, sizeof d);
    d.size = set->global.size ? set->global.size : DEFAULT_GLOBAL_SIZE;
    d.orientation.yaw_degrees = set->global.yaw_degrees;
    if (!set->global.environment) d.layout = IBL_LAYOUT_EQUIRECT;
    st = ibl_image_to_cubemap(ctx, &image, &d, out);
    ibl_image_free(ctx, &image);
    return st;
}
