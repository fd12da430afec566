/* Reading a probe bake (docs/PROBES.md "The probe bake"): the global bake through
 * ibl_bake_load, then the manifest's "probes" section, the cube-map array and the property
 * buffer, whose binary records are decoded here (the JSON twin is for people and tools). */
#include "bake/bake_internal.h"
#include "core/context_internal.h"
#include "io/json.h"
#include "ibl/probes.h"

#include <stdio.h>
#include <string.h>

static float get_f32(const unsigned char *b)
{
    uint32_t u = (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
    float v;
    memcpy(&v, &u, 4);
    return v;
}

static int32_t get_i32(const unsigned char *b)
{
    return (int32_t)((uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24);
}

static ibl_vec3 get_vec3(const unsigned char *b)
{
    ibl_vec3 v = {get_f32(b), get_f32(b + 4), get_f32(b + 8)};
    return v;
}

static void decode_record(const unsigned char *b, ibl_probe_record *r)
{
    r->position = get_vec3(b);
    r->influence_size = get_f32(b + 12);
    r->influence.center = get_vec3(b + 16);
    r->influence.radius = get_f32(b + 28);
    r->influence.half_extent = get_vec3(b + 32);
    r->influence.blend_distance = get_f32(b + 44);
    r->proxy.center = get_vec3(b + 48);
    r->proxy.radius = get_f32(b + 60);
    r->proxy.half_extent = get_vec3(b + 64);
    r->coverage = get_f32(b + 76);
    r->influence.shape = get_i32(b + 80) ? IBL_VOLUME_BOX : IBL_VOLUME_SPHERE;
    r->proxy.shape = get_i32(b + 84) ? IBL_VOLUME_BOX : IBL_VOLUME_SPHERE;
    r->layer = get_i32(b + 88);
    r->priority = get_i32(b + 92);
    for (int k = 0; k < 9; k++)
        for (int c = 0; c < 4; c++) r->sh[k][c] = get_f32(b + 96 + 16 * k + 4 * c);
}

/* The manifest's "probes": names (by layer) and the roughness of each level. */
static ibl_status read_section(ibl_context *ctx, const char *path, ibl_probe_bake_data *out)
{
    void *bytes = NULL;
    size_t size = 0;
    ibl_status st = ibl_read_file(ctx, path, &bytes, &size);
    if (st != IBL_OK) return st;
    json_t *root = NULL;
    st = ibl__json_parse(ctx, bytes, size, path, &root);
    ibl_free(ctx, bytes);
    if (st != IBL_OK) return st;
    ibl__json_reader r = {ctx, path, IBL_OK};
    json_t *p = ibl__json_object(&r, root, "", "probes");
    int count = p ? ibl__json_get_int(&r, p, "probes", "count", 1, 65536) : 0;
    json_t *list = p ? ibl__json_array(&r, p, "probes", "probes") : NULL;
    json_t *rough = p ? ibl__json_array(&r, p, "probes", "roughness") : NULL;
    if (r.status == IBL_OK && (json_array_size(list) != (size_t)count))
        ibl__json_fail(&r, "probes", "probes", "lists %zu probes, count says %d", json_array_size(list), count);
    if (r.status == IBL_OK && (json_array_size(rough) < 1 || json_array_size(rough) > IBL_MAX_LEVELS))
        ibl__json_fail(&r, "probes", "roughness", "needs 1..%d levels", IBL_MAX_LEVELS);
    if (r.status == IBL_OK) {
        out->records = ibl_calloc(ctx, (size_t)count, sizeof *out->records);
        if (!out->records) r.status = ibl_context_status(ctx);
        else out->count = count;
    }
    for (int i = 0; i < count && r.status == IBL_OK; i++) {
        char at[64];
        snprintf(at, sizeof at, "probes.probes[%d]", i);
        const char *name = ibl__json_get_string(&r, json_array_get(list, (size_t)i), at, "name");
        if (name) snprintf(out->records[i].name, sizeof out->records[i].name, "%s", name);
    }
    if (r.status == IBL_OK) {
        memset(&out->mapping, 0, sizeof out->mapping);
        out->mapping.levels = (int)json_array_size(rough);
        for (int l = 0; l < out->mapping.levels; l++)
            out->mapping.roughness[l] = (float)json_number_value(json_array_get(rough, (size_t)l));
    }
    json_decref(root);
    return r.status;
}

static ibl_status read_buffer(ibl_context *ctx, const char *path, ibl_probe_bake_data *out)
{
    void *bytes = NULL;
    size_t size = 0;
    ibl_status st = ibl_read_file(ctx, path, &bytes, &size);
    if (st != IBL_OK) return st;
    if (size != (size_t)IBL_PROBE_RECORD_BYTES * (size_t)out->count)
        st = ibl__fail(ctx, IBL_ERR_FORMAT, "%s: %zu bytes, %d records of %d expected", path, size,
                       out->count, IBL_PROBE_RECORD_BYTES);
    for (int i = 0; i < out->count && st == IBL_OK; i++) {
        decode_record((const unsigned char *)bytes + (size_t)IBL_PROBE_RECORD_BYTES * (size_t)i,
                      &out->records[i]);
        if (out->records[i].layer != i)
            st = ibl__fail(ctx, IBL_ERR_FORMAT, "%s: record %d says layer %d", path, i, out->records[i].layer);
    }
    ibl_free(ctx, bytes);
    return st;
}

static ibl_status read_array(ibl_context *ctx, const char *path, ibl_probe_bake_data *out)
{
    void *bytes = NULL;
    size_t size = 0;
    ibl_status st = ibl_read_file(ctx, path, &bytes, &size);
    if (st != IBL_OK) return st;
    int count = 0;
    st = ibl_decode_cube_array(ctx, bytes, size, path, &out->chains, &count, NULL);
    ibl_free(ctx, bytes);
    if (st == IBL_OK && count != out->count) {
        for (int i = 0; i < count; i++) ibl_cubemap_free(ctx, &out->chains[i]);
        ibl_free(ctx, out->chains);
        out->chains = NULL;
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: %d layers, the manifest says %d probes", path,
                         count, out->count);
    }
    if (st == IBL_OK && out->chains[0].levels < out->mapping.levels)
        out->mapping.levels = out->chains[0].levels;
    return st;
}

ibl_status ibl_probe_bake_load(ibl_context *ctx, const char *dir, ibl_probe_bake_data *out)
{
    if (!ctx || !dir || !out) return IBL_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    char path[4096];
    ibl_status st = ibl_bake_load(ctx, dir, NULL, &out->global);
    if (st == IBL_OK && snprintf(path, sizeof path, "%s/manifest.json", dir) >= (int)sizeof path)
        st = ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "%s: path too long", dir);
    if (st == IBL_OK) st = read_section(ctx, path, out);
    if (st == IBL_OK) {
        snprintf(path, sizeof path, "%s/probes.bin", dir);
        st = read_buffer(ctx, path, out);
    }
    if (st == IBL_OK) {
        snprintf(path, sizeof path, "%s/probes.ktx2", dir);
        st = read_array(ctx, path, out);
    }
    if (st != IBL_OK) ibl_probe_bake_free(ctx, out);
    return st;
}

void ibl_probe_bake_free(ibl_context *ctx, ibl_probe_bake_data *b)
{
    if (!b) return;
    ibl_bake_free(ctx, &b->global);
    for (int i = 0; b->chains && i < b->count; i++) ibl_cubemap_free(ctx, &b->chains[i]);
    ibl_free(ctx, b->chains);
    ibl_free(ctx, b->records);
    memset(b, 0, sizeof *b);
}
