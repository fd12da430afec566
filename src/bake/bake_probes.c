/* The probe-array bake (docs/PROBES.md "The probe bake"): every local probe's capture through
 * the coverage-aware chain filter (ibl_capture_prefilter), its SH, and the whole set as one
 * KTX2 cube-map array with a std430 property buffer (and its JSON twin) in blend order, next to
 * the global probe baked as any environment, in one bake folder (the same transaction as
 * ibl_bake_write: bake_folder.c).
 *
 * Parts. Each probe's filtered chain is a "part", DIR/probe-HASH.ktx2, named by a 64-bit
 * FNV-1a hash of what determines it (the capture's texels, the preset, the storage format,
 * the part format's version): a run that finds a part skips the probe, and shards running at
 * the same time on other machines write disjoint (or identical) files, each atomically. A
 * shard (1..N) takes the probes whose index in the set file is congruent to shard - 1 modulo
 * N; the merge reads every part and writes the folder; a run without --shard or --merge does
 * both. The output depends only on the parts, so a sharded bake is byte-identical to a single
 * one. The manifest of a probe bake records no timings for the same reason. */
#include "bake/bake_internal.h"
#include "core/context_internal.h"
#include "io/json.h"
#include "ibl/probes.h"

#include <dirent.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static const char ARRAY_FILE[] = "probes.ktx2";
static const char BUFFER_FILE[] = "probes.bin";
static const char BUFFER_JSON[] = "probes.json";
static const char PART_PREFIX[] = "probe-";
enum { PART_VERSION = 1, HASH_HEX = 16 };

int ibl__bake_probe_entry(const char *name)
{
    if (!strcmp(name, ARRAY_FILE) || !strcmp(name, BUFFER_FILE) || !strcmp(name, BUFFER_JSON))
        return 1;
    size_t np = sizeof PART_PREFIX - 1;
    if (strncmp(name, PART_PREFIX, np) != 0 || strlen(name) != np + HASH_HEX + 5) return 0;
    for (int i = 0; i < HASH_HEX; i++)
        if (!strchr("0123456789abcdef", name[np + (size_t)i])) return 0;
    return strcmp(name + np + HASH_HEX, ".ktx2") == 0;
}

/* ---- content addresses -------------------------------------------------------------------- */

static uint64_t fnv(uint64_t h, const void *bytes, size_t n)
{
    const unsigned char *p = bytes;
    for (size_t i = 0; i < n; i++) h = (h ^ p[i]) * 0x100000001b3ull;
    return h;
}

static uint64_t part_hash(const ibl_cubemap *capture, const char *preset, ibl_format format)
{
    uint64_t h = 0xcbf29ce484222325ull;
    char head[96];
    int n = snprintf(head, sizeof head, "ibl-probe-part %d %s %d %d", PART_VERSION, preset,
                     (int)format, capture->size);
    h = fnv(h, head, (size_t)n);
    /* level 0 only, as little-endian float32 (this library's hosts are little-endian) */
    return fnv(h, capture->data, (size_t)6 * capture->size * capture->size * 4 * sizeof(float));
}

static void part_name(uint64_t hash, char out[32])
{
    snprintf(out, 32, "%s%016llx.ktx2", PART_PREFIX, (unsigned long long)hash);
}

/* ---- one part ------------------------------------------------------------------------------ */

/* SH (3 bands) of the premultiplied RGB in .xyz and of the coverage in .w. */
static ibl_status capture_sh(ibl_context *ctx, const ibl_cubemap *c, float sh[9][4])
{
    ibl_sh rgb, cov;
    ibl_status st = ibl_sh_project_cubemap(ctx, c, 0, 3, &rgb);
    ibl_cubemap grey;
    if (st == IBL_OK) st = ibl_cubemap_alloc(ctx, c->size, 1, &grey);
    if (st != IBL_OK) return st;
    size_t n = (size_t)6 * c->size * c->size;
    for (size_t i = 0; i < n; i++) {
        grey.data[4 * i] = grey.data[4 * i + 1] = grey.data[4 * i + 2] = c->data[4 * i + 3];
        grey.data[4 * i + 3] = 1.0f;
    }
    st = ibl_sh_project_cubemap(ctx, &grey, 0, 3, &cov);
    ibl_cubemap_free(ctx, &grey);
    for (int k = 0; k < 9 && st == IBL_OK; k++) {
        for (int ch = 0; ch < 3; ch++) sh[k][ch] = (float)rgb.c[k][ch];
        sh[k][3] = (float)cov.c[k][0];
    }
    return st;
}

static ibl_status part_info(ibl_context *ctx, const char *preset, int size, ibl_specular_info *info)
{
    ibl_specular_desc d;
    memset(&d, 0, sizeof d);
    if (!ibl_specular_preset(preset, &d))
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "unknown preset \"%s\"", preset);
    d.size = size;
    return ibl_specular_levels(ctx, &d, size, info);
}

/* Filters one capture into the bytes of its part file. */
static ibl_status make_part(ibl_context *ctx, const ibl_cubemap *capture, const char *preset,
                            ibl_format format, void **bytes, size_t *size)
{
    ibl_cubemap chain;
    ibl_specular_info info;
    float sh[9][4];
    ibl_status st = part_info(ctx, preset, capture->size, &info);
    if (st == IBL_OK) st = capture_sh(ctx, capture, sh);
    if (st == IBL_OK) st = ibl_capture_prefilter(ctx, capture, preset, &chain);
    if (st != IBL_OK) return st;
    ibl_texture tex = ibl_texture_from_cubemap(&chain);
    char text[9 * 4 * 20 + 8], *p = text;
    for (int k = 0; k < 9; k++)
        for (int c = 0; c < 4; c++) p += sprintf(p, "%s%.9g", p == text ? "" : " ", (double)sh[k][c]);
    st = ibl_specular_set_metadata(ctx, &info, &tex);
    if (st == IBL_OK) st = ibl_texture_set_metadata(ctx, &tex, "ibl.probe.sh", text);
    if (st == IBL_OK) st = ibl_texture_set_metadata(ctx, &tex, "ibl.probe.alpha", "premultiplied coverage");
    ibl_write_desc wd = {.format = format};
    if (st == IBL_OK) st = ibl_encode_texture(ctx, IBL_FILE_KTX2, &tex, &wd, bytes, size);
    ibl_texture_free(ctx, &tex);
    ibl_cubemap_free(ctx, &chain);
    return st;
}

/* A part read back: its chain and SH. */
typedef struct part {
    char file[32];
    uint64_t hash;
    void *bytes;
    size_t size;
    ibl_cubemap chain;
    float sh[9][4];
    ibl_specular_info info;
} part;

static ibl_status parse_part(ibl_context *ctx, part *p, const char *path)
{
    ibl_texture tex;
    ibl_status st = ibl_decode_texture(ctx, p->bytes, p->size, path, NULL, &tex, NULL);
    if (st != IBL_OK) return st;
    if (tex.kind != IBL_TEXTURE_CUBE) st = ibl__fail(ctx, IBL_ERR_FORMAT, "%s: not a cube", path);
    if (st == IBL_OK) st = ibl_specular_info_from_metadata(ctx, &tex, path, &p->info);
    const char *sh = NULL;
    for (int i = 0; i < tex.metadata_count; i++)
        if (!strcmp(tex.metadata[i].key, "ibl.probe.sh")) sh = tex.metadata[i].value;
    if (st == IBL_OK && !sh) st = ibl__fail(ctx, IBL_ERR_FORMAT, "%s: ibl.probe.sh: missing", path);
    for (int k = 0; k < 36 && st == IBL_OK; k++) {
        char *end;
        double v = strtod(sh, &end);
        if (end == sh) st = ibl__fail(ctx, IBL_ERR_FORMAT, "%s: ibl.probe.sh: needs 36 numbers", path);
        p->sh[k / 4][k % 4] = (float)v;
        sh = end;
    }
    ibl_cubemap view;
    if (st == IBL_OK) st = ibl_cubemap_from_texture(&tex, &view);
    if (st == IBL_OK) st = ibl_cubemap_alloc(ctx, view.size, view.levels, &p->chain);
    if (st == IBL_OK)
        memcpy(p->chain.data, view.data, ibl_cubemap_floats(view.size, view.levels) * sizeof(float));
    ibl_texture_free(ctx, &tex);
    return st;
}

static void part_free(ibl_context *ctx, part *p)
{
    ibl_free(ctx, p->bytes);
    ibl_cubemap_free(ctx, &p->chain);
    memset(p, 0, sizeof *p);
}

/* ---- the captures ------------------------------------------------------------------------- */

static ibl_status get_capture(ibl_context *ctx, const ibl_probe_set *set,
                              const ibl_probe_bake_desc *d, int i, ibl_cubemap *out)
{
    memset(out, 0, sizeof *out);
    if (d->cubes) {
        *out = d->cubes[i];
        out->owns_data = 0;
        return IBL_OK;
    }
    char path[4096];
    if (snprintf(path, sizeof path, "%s/%s.ktx2", d->captures, set->probes[i].name) >= (int)sizeof path)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "%s: path too long", d->captures);
    ibl_texture tex;
    ibl_status st = ibl_read_texture(ctx, path, NULL, &tex, NULL);
    if (st != IBL_OK) return st;
    ibl_cubemap view;
    if (ibl_cubemap_from_texture(&tex, &view) != IBL_OK)
        st = ibl__fail(ctx, IBL_ERR_FORMAT, "%s: not a cube map (a capture of probe %s)", path,
                       set->probes[i].name);
    if (st == IBL_OK) st = ibl_cubemap_alloc(ctx, view.size, 1, out);
    if (st == IBL_OK)
        memcpy(out->data, view.data, ibl_cubemap_floats(view.size, 1) * sizeof(float));
    ibl_texture_free(ctx, &tex);
    return st;
}

/* Every local probe must share a cube size and a preset: they become one array. */
static ibl_status check_set(ibl_context *ctx, const ibl_probe_set *set)
{
    const char *name = set->path ? set->path : "probe set";
    if (set->probe_count < 1)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "%s: probes: a probe bake needs at least one "
                         "local probe", name);
    for (int i = 1; i < set->probe_count; i++) {
        if (strcmp(set->probes[i].preset, set->probes[0].preset) != 0)
            return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "%s: probes[%d].preset: \"%s\" differs "
                             "from probes[0]'s \"%s\"; one cube-map array needs one chain", name, i,
                             set->probes[i].preset, set->probes[0].preset);
    }
    return IBL_OK;
}

/* ---- the folder outside the transaction (shards) ------------------------------------------- */

static ibl_status open_shared_folder(ibl_context *ctx, const char *dir, int *created)
{
    struct stat s;
    *created = 0;
    if (stat(dir, &s) != 0) {
        if (mkdir(dir, 0777) == 0) *created = 1;
        else if (errno != EEXIST)
            return ibl__fail(ctx, IBL_ERR_IO, "%s: cannot create the folder: %s", dir, strerror(errno));
        return IBL_OK;
    }
    if (!S_ISDIR(s.st_mode)) return ibl__fail(ctx, IBL_ERR_IO, "%s: exists and is not a folder", dir);
    DIR *d = opendir(dir);
    if (!d) return ibl__fail(ctx, IBL_ERR_IO, "%s: cannot list: %s", dir, strerror(errno));
    struct dirent *e;
    ibl_status st = IBL_OK;
    while (st == IBL_OK && (e = readdir(d)) != NULL)
        if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..") && !ibl__bake_is_entry(e->d_name))
            st = ibl__fail(ctx, IBL_ERR_IO, "%s: holds '%s', which is not part of a bake; write "
                           "the probe bake to a new or empty folder", dir, e->d_name);
    closedir(d);
    return st;
}

/* A folder this run created and failed to fill: its parts go with it. */
static void remove_created(ibl_context *ctx, const char *dir)
{
    DIR *d = opendir(dir);
    if (!d) return;
    struct dirent *e;
    char path[4096];
    while ((e = readdir(d)) != NULL)
        if (ibl__bake_is_entry(e->d_name) && snprintf(path, sizeof path, "%s/%s", dir, e->d_name) < (int)sizeof path)
            unlink(path);
    closedir(d);
    rmdir(dir);
    (void)ctx;
}

static int part_path(const char *dir, const char *file, char *out, size_t cap)
{
    return snprintf(out, cap, "%s/%s", dir, file) < (int)cap;
}

/* Makes (or finds) the part of probe i. */
static ibl_status ensure_part(ibl_context *ctx, const ibl_probe_set *set, const ibl_probe_bake_desc *d,
                              ibl_format format, int i, const char *dir, ibl_probe_bake_report *rep)
{
    ibl_cubemap cap;
    ibl_status st = get_capture(ctx, set, d, i, &cap);
    if (st != IBL_OK) return st;
    char file[32], path[4096];
    part_name(part_hash(&cap, set->probes[i].preset, format), file);
    if (!part_path(dir, file, path, sizeof path)) st = ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "%s: path too long", dir);
    if (st == IBL_OK && access(path, F_OK) == 0) {
        if (rep) rep->reused++;
    } else if (st == IBL_OK) {
        void *bytes = NULL;
        size_t size = 0;
        st = ibl__progress(ctx, set->probes[i].name, 0.0);
        if (st == IBL_OK) st = make_part(ctx, &cap, set->probes[i].preset, format, &bytes, &size);
        if (st == IBL_OK) st = ibl_write_file_atomic(ctx, path, bytes, size);
        ibl_free(ctx, bytes);
        if (st == IBL_OK && rep) rep->computed++;
    }
    ibl_cubemap_free(ctx, &cap);
    return st;
}

/* ---- assembling ------------------------------------------------------------------------------ */

typedef struct assembly {
    const ibl_probe_set *set;
    int *order;   /* layer -> set index */
    part *parts;  /* by layer */
    ibl_format format;
    void *array;
    size_t array_size;
    unsigned char *buffer;
    char *buffer_json;
} assembly;

static ibl_status load_part(ibl_context *ctx, const ibl_probe_set *set, const ibl_probe_bake_desc *d,
                            ibl_format format, int i, const char *dir, part *p)
{
    ibl_cubemap cap;
    ibl_status st = get_capture(ctx, set, d, i, &cap);
    if (st != IBL_OK) return st;
    p->hash = part_hash(&cap, set->probes[i].preset, format);
    ibl_cubemap_free(ctx, &cap);
    part_name(p->hash, p->file);
    char path[4096];
    if (!part_path(dir, p->file, path, sizeof path))
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "%s: path too long", dir);
    if (access(path, F_OK) != 0)
        return ibl__fail(ctx, IBL_ERR_IO, "%s: missing: the part of probe %s (probes[%d]); run its "
                         "shard first", path, set->probes[i].name, i);
    st = ibl_read_file(ctx, path, &p->bytes, &p->size);
    if (st == IBL_OK) st = parse_part(ctx, p, path);
    return st;
}

static void put_f32(unsigned char *b, float v)
{
    uint32_t u;
    memcpy(&u, &v, 4);
    for (int k = 0; k < 4; k++) b[k] = (unsigned char)(u >> (8 * k));
}

static void put_i32(unsigned char *b, int32_t v)
{
    uint32_t u = (uint32_t)v;
    for (int k = 0; k < 4; k++) b[k] = (unsigned char)(u >> (8 * k));
}

static void put_vec4(unsigned char *b, ibl_vec3 v, float w)
{
    put_f32(b, v.x), put_f32(b + 4, v.y), put_f32(b + 8, v.z), put_f32(b + 12, w);
}

static float coverage_of(const part *p)
{
    double m[4];
    ibl_cubemap_mean(&p->chain, 0, m);
    return (float)m[3];
}

/* One std430 record (docs/PROBES.md "Property buffer"). */
static void pack_record(unsigned char *b, const ibl_local_probe *p, const part *pt, int layer)
{
    put_vec4(b, p->position, ibl_volume_size(&p->influence));
    put_vec4(b + 16, p->influence.center, p->influence.radius);
    put_vec4(b + 32, p->influence.half_extent, p->influence.blend_distance);
    put_vec4(b + 48, p->proxy.center, p->proxy.radius);
    put_vec4(b + 64, p->proxy.half_extent, coverage_of(pt));
    put_i32(b + 80, (int32_t)p->influence.shape);
    put_i32(b + 84, (int32_t)p->proxy.shape);
    put_i32(b + 88, layer);
    put_i32(b + 92, p->priority);
    for (int k = 0; k < 9; k++)
        for (int c = 0; c < 4; c++) put_f32(b + 96 + 16 * k + 4 * c, pt->sh[k][c]);
}

static json_t *volume_json(const ibl_volume *v, int influence)
{
    json_t *o = json_object();
    ibl__json_set(o, "shape", ibl__json_string(v->shape == IBL_VOLUME_BOX ? "box" : "sphere"));
    ibl__json_set(o, "center", ibl__json_vec3(v->center));
    if (v->shape == IBL_VOLUME_BOX) ibl__json_set(o, "half_extent", ibl__json_vec3(v->half_extent));
    else ibl__json_set(o, "radius", ibl__json_float(v->radius));
    if (influence) ibl__json_set(o, "blend", ibl__json_float(v->blend_distance));
    return o;
}

static json_t *record_json(const ibl_local_probe *p, const part *pt, int layer)
{
    json_t *o = json_object();
    ibl__json_set(o, "name", ibl__json_string(p->name));
    ibl__json_set(o, "layer", ibl__json_number(layer));
    ibl__json_set(o, "position", ibl__json_vec3(p->position));
    ibl__json_set(o, "influence_size", ibl__json_float(ibl_volume_size(&p->influence)));
    ibl__json_set(o, "influence", volume_json(&p->influence, 1));
    ibl__json_set(o, "proxy", volume_json(&p->proxy, 0));
    ibl__json_set(o, "priority", ibl__json_number(p->priority));
    ibl__json_set(o, "coverage", ibl__json_float(coverage_of(pt)));
    json_t *sh = json_array();
    for (int k = 0; k < 9; k++) {
        json_t *c = json_array();
        for (int ch = 0; ch < 4; ch++) ibl__json_append(c, ibl__json_float(pt->sh[k][ch]));
        ibl__json_append(sh, c);
    }
    ibl__json_set(o, "sh", sh);
    ibl__json_set(o, "part", ibl__json_string(pt->file));
    return o;
}

static const char RECORD_LAYOUT[] =
    "std430, little-endian, 240 bytes per probe, in layer (= blend) order: "
    "vec4 position_size (xyz position, w influence volume in m^3); "
    "vec4 influence_center_radius; vec4 influence_half_extent_blend; "
    "vec4 proxy_center_radius; vec4 proxy_half_extent_coverage; "
    "ivec4 shapes_layer_priority (influence shape, proxy shape: 0 sphere 1 box; array layer; priority); "
    "vec4 sh[9] (rgb: SH of the premultiplied radiance, a: SH of the coverage)";

static ibl_status build_outputs(ibl_context *ctx, assembly *a)
{
    int n = a->set->probe_count;
    a->buffer = ibl_alloc(ctx, (size_t)IBL_PROBE_RECORD_BYTES * (size_t)n);
    ibl_cubemap *chains = ibl_alloc(ctx, sizeof *chains * (size_t)n);
    if (!a->buffer || !chains) {
        ibl_free(ctx, chains);
        return ibl_context_status(ctx);
    }
    json_t *root = json_object(), *list = json_array();
    ibl__json_set(root, "format", ibl__json_string("ibl-probe-buffer"));
    ibl__json_set(root, "version", ibl__json_number(1));
    ibl__json_set(root, "stride", ibl__json_number(IBL_PROBE_RECORD_BYTES));
    ibl__json_set(root, "layout", ibl__json_string(RECORD_LAYOUT));
    for (int l = 0; l < n; l++) {
        const ibl_local_probe *p = &a->set->probes[a->order[l]];
        pack_record(a->buffer + (size_t)IBL_PROBE_RECORD_BYTES * (size_t)l, p, &a->parts[l], l);
        ibl__json_append(list, record_json(p, &a->parts[l], l));
        chains[l] = a->parts[l].chain;
    }
    ibl__json_set(root, "probes", list);
    ibl_status st = ibl__json_text(ctx, root, BUFFER_JSON, &a->buffer_json);
    ibl_key_value kv[1] = {{(char *)"ibl.probe.alpha", (char *)"premultiplied coverage"}};
    ibl_write_desc wd = {.format = a->format};
    if (st == IBL_OK)
        st = ibl_encode_cube_array(ctx, chains, n, kv, 1, &wd, &a->array, &a->array_size);
    ibl_free(ctx, chains);
    return st;
}

static ibl_status stage_probes(ibl_context *ctx, const char *dir, void *user)
{
    assembly *a = user;
    ibl_status st = ibl__bake_write_staged(ctx, dir, ARRAY_FILE, a->array, a->array_size);
    if (st == IBL_OK)
        st = ibl__bake_write_staged(ctx, dir, BUFFER_FILE, a->buffer,
                                    (size_t)IBL_PROBE_RECORD_BYTES * (size_t)a->set->probe_count);
    if (st == IBL_OK)
        st = ibl__bake_write_staged(ctx, dir, BUFFER_JSON, a->buffer_json, strlen(a->buffer_json));
    /* the parts go along, so that the next run finds them */
    for (int l = 0; l < a->set->probe_count && st == IBL_OK; l++) {
        int dup = 0;
        for (int k = 0; k < l; k++) dup |= a->parts[k].hash == a->parts[l].hash;
        if (!dup) st = ibl__bake_write_staged(ctx, dir, a->parts[l].file, a->parts[l].bytes, a->parts[l].size);
    }
    return st;
}

static json_t *probes_manifest(const assembly *a)
{
    const part *p0 = &a->parts[0];
    json_t *o = json_object();
    ibl__json_set(o, "version", ibl__json_number(1));
    ibl__json_set(o, "count", ibl__json_number(a->set->probe_count));
    ibl__json_set(o, "size", ibl__json_number(p0->chain.size));
    ibl__json_set(o, "levels", ibl__json_number(p0->chain.levels));
    ibl__json_set(o, "preset", ibl__json_string(a->set->probes[0].preset));
    ibl__json_set(o, "filter", ibl__json_string(ibl_specular_filter_name(p0->info.filter)));
    json_t *r = json_array();
    for (int l = 0; l < p0->info.levels; l++) ibl__json_append(r, ibl__json_float(p0->info.roughness[l]));
    ibl__json_set(o, "roughness", r);
    ibl__json_set(o, "format", ibl__json_string(ibl_format_name(a->format)));
    ibl__json_set(o, "alpha", ibl__json_string("premultiplied coverage"));
    ibl__json_set(o, "array", ibl__json_string(ARRAY_FILE));
    ibl__json_set(o, "buffer", ibl__json_string(BUFFER_FILE));
    ibl__json_set(o, "buffer_json", ibl__json_string(BUFFER_JSON));
    ibl__json_set(o, "stride", ibl__json_number(IBL_PROBE_RECORD_BYTES));
    ibl__json_set(o, "order", ibl__json_string("priority descending, then influence volume "
                                                "ascending, then set file order"));
    json_t *list = json_array();
    for (int l = 0; l < a->set->probe_count; l++) {
        json_t *e = json_object();
        ibl__json_set(e, "name", ibl__json_string(a->set->probes[a->order[l]].name));
        ibl__json_set(e, "layer", ibl__json_number(l));
        ibl__json_set(e, "part", ibl__json_string(a->parts[l].file));
        ibl__json_append(list, e);
    }
    ibl__json_set(o, "probes", list);
    return o;
}

static ibl_status rewrite_manifest(ibl_context *ctx, char **text, void *user)
{
    assembly *a = user;
    json_error_t err;
    json_t *root = json_loads(*text, 0, &err);
    if (!root) return ibl__fail(ctx, IBL_ERR_FORMAT, "manifest.json: %s", err.text);
    json_object_del(root, "timings_ms"); /* equal inputs, equal bytes (shards vs one run) */
    ibl__json_set(root, "probes", probes_manifest(a));
    char *out = NULL;
    ibl_status st = ibl__json_text(ctx, root, "manifest.json", &out);
    if (st != IBL_OK) return st;
    ibl_free(ctx, *text);
    *text = out;
    return IBL_OK;
}

static ibl_status global_desc(ibl_context *ctx, const ibl_probe_set *set, const ibl_probe_bake_desc *d,
                              ibl_bake_desc *out)
{
    if (d->global) {
        *out = *d->global;
        return IBL_OK;
    }
    memset(out, 0, sizeof *out);
    if (!ibl_specular_preset(set->global.preset, &out->specular))
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "%s: global.preset: unknown \"%s\"",
                         set->path ? set->path : "probe set", set->global.preset);
    out->specular.size = set->global.size;
    out->preset = set->global.preset;
    out->preview_width = -1;
    out->lut_size = d->lut_size;
    out->source.name = set->global.environment;
    out->source.sky = set->global.environment ? NULL : &set->global.sky;
    return IBL_OK;
}

static ibl_status merge(ibl_context *ctx, const ibl_probe_set *set, const ibl_cubemap *env,
                        const ibl_probe_bake_desc *d, ibl_format format, const char *dir)
{
    int n = set->probe_count;
    assembly a;
    memset(&a, 0, sizeof a);
    a.set = set;
    a.format = format;
    a.order = ibl_alloc(ctx, sizeof *a.order * (size_t)n);
    a.parts = ibl_alloc(ctx, sizeof *a.parts * (size_t)n);
    ibl_status st = a.order && a.parts ? IBL_OK : ibl_context_status(ctx);
    if (st == IBL_OK) {
        memset(a.parts, 0, sizeof *a.parts * (size_t)n);
        ibl_probe_set_order(set, a.order);
    }
    for (int l = 0; l < n && st == IBL_OK; l++) st = load_part(ctx, set, d, format, a.order[l], dir, &a.parts[l]);
    for (int l = 1; l < n && st == IBL_OK; l++)
        if (a.parts[l].chain.size != a.parts[0].chain.size || a.parts[l].chain.levels != a.parts[0].chain.levels)
            st = ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "%s: probes[%d]: captured at %d texels, "
                           "probes[%d] at %d; one cube-map array needs one size (capture with --size)",
                           set->path ? set->path : "probe set", a.order[l], a.parts[l].chain.size,
                           a.order[0], a.parts[0].chain.size);
    if (st == IBL_OK) st = build_outputs(ctx, &a);
    ibl_bake_desc gd;
    ibl_bake_data b;
    memset(&b, 0, sizeof b);
    if (st == IBL_OK) st = global_desc(ctx, set, d, &gd);
    if (st == IBL_OK) st = ibl_bake_compute(ctx, env, &gd, &b);
    if (st == IBL_OK) {
        ibl__bake_extra extra = {stage_probes, rewrite_manifest, &a};
        st = ibl__bake_write_extra(ctx, &b, dir, &extra);
    }
    ibl_bake_free(ctx, &b);
    for (int l = 0; a.parts && l < n; l++) part_free(ctx, &a.parts[l]);
    ibl_free(ctx, a.parts);
    ibl_free(ctx, a.order);
    ibl_free(ctx, a.array);
    ibl_free(ctx, a.buffer);
    ibl_free(ctx, a.buffer_json);
    return st;
}

ibl_status ibl_probe_bake(ibl_context *ctx, const ibl_probe_set *set, const ibl_cubemap *environment,
                          const ibl_probe_bake_desc *desc, const char *dir, ibl_probe_bake_report *report)
{
    if (report) memset(report, 0, sizeof *report);
    if (!ctx || !set || !desc || !dir || (!desc->captures && !desc->cubes))
        return IBL_ERR_INVALID_ARGUMENT;
    const ibl_probe_bake_desc *d = desc;
    if (d->shards < 0 || (d->shards > 0 && (d->shard < 1 || d->shard > d->shards)))
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "%s: shard %d of %d: wants 1..N of N", dir,
                         d->shard, d->shards);
    if (d->shards > 0 && d->merge)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "%s: a shard does not merge", dir);
    if (!d->shards && !environment)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "%s: the merge needs the global environment", dir);
    ibl_format format = d->format ? d->format : IBL_FORMAT_RGBA16F;
    int created = 0;
    ibl_status st = check_set(ctx, set);
    if (st == IBL_OK && !d->merge) st = open_shared_folder(ctx, dir, &created);
    for (int i = 0; i < set->probe_count && st == IBL_OK && !d->merge; i++)
        if (d->shards == 0 || i % d->shards == d->shard - 1)
            st = ensure_part(ctx, set, d, format, i, dir, report);
    if (st == IBL_OK && d->shards == 0) st = merge(ctx, set, environment, d, format, dir);
    if (st != IBL_OK && created) remove_created(ctx, dir); /* no output from a failed run */
    return st;
}
