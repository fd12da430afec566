/* The bake folder's manifest.json: written from an ibl_bake_data and read back into one, through
 * jansson. The schema (docs/FORMATS.md "Bake folder") is versioned: a reader refuses a
 * manifest newer than it knows, and every field it needs is checked with its path named in
 * the message. */
#include "bake/bake_internal.h"
#include "core/context_internal.h"
#include "core/defaults.h"
#include "io/container.h"
#include "io/json.h"
#include "shade/atlas_table.h"

#include <math.h>
#include <string.h>

static const char MANIFEST_FORMAT[] = "ibl-bake";

/* ---- writing ------------------------------------------------------------------------------ */

static json_t *axis_json(const ibl_table_axis *a)
{
    json_t *o = json_object();
    ibl__json_set(o, "count", ibl__json_number(a->count));
    ibl__json_set(o, "first", ibl__json_float(a->first));
    ibl__json_set(o, "last", ibl__json_float(a->last));
    ibl__json_set(o, "spacing", ibl__json_string(a->logarithmic ? "log" : "linear"));
    return o;
}

static json_t *file_list(const ibl_bake_data *b, ibl__bake_file first, int count)
{
    json_t *a = json_array();
    for (int i = 0; i < count; i++)
        if (ibl__bake_has_file(b, (ibl__bake_file)(first + i)))
            ibl__json_append(a, ibl__json_string(ibl__bake_file_info_of((ibl__bake_file)(first + i))->name));
    return a;
}

static json_t *source_json(const ibl_bake_data *b)
{
    json_t *o = json_object();
    ibl__json_set(o, "name", ibl__json_string(b->source_name));
    ibl__json_set(o, "layout", b->source_layout ? ibl__json_string(ibl_layout_name(b->source_layout))
                                                : json_null());
    ibl__json_set(o, "yaw_degrees", ibl__json_float(b->source_orientation.yaw_degrees));
    ibl__json_set(o, "mirror_input", ibl__json_bool(b->source_orientation.mirror));
    ibl__json_set(o, "z_up", ibl__json_bool(b->source_orientation.z_up));
    if (b->has_sky) {
        json_t *sky = json_object();
        ibl__json_set(sky, "sun_elevation_degrees", ibl__json_float(b->sky.sun_elevation_deg));
        ibl__json_set(sky, "sun_azimuth_degrees", ibl__json_float(b->sky.sun_azimuth_deg));
        ibl__json_set(sky, "turbidity", ibl__json_float(b->sky.turbidity));
        ibl__json_set(sky, "ground_albedo", ibl__json_float(b->sky.ground_albedo));
        ibl__json_set(sky, "width", ibl__json_number(b->sky.width));
        ibl__json_set(o, "sky", sky);
    }
    return o;
}

static json_t *conventions_json(void)
{
    json_t *o = json_object();
    ibl__json_set(o, "frame", ibl__json_string("right-handed, +Y up"));
    ibl__json_set(o, "cube_faces", ibl__json_string("+X -X +Y -Y +Z -Z, OpenGL/Vulkan/KTX2 "
                                                    "orientation (docs/CONVENTIONS.md)"));
    ibl__json_set(o, "radiance", ibl__json_string("linear Rec.709"));
    ibl__json_set(o, "irradiance_map", ibl__json_string("E/pi"));
    ibl__json_set(o, "roughness", ibl__json_string("perceptual, alpha = roughness^2"));
    ibl__json_set(o, "shininess", ibl__json_string(
                                      "exponent of the tri-Ace 2010 normalised Blinn-Phong "
                                      "material; a Phong-kernel level of exponent n serves "
                                      "shininess blinn_factor * n"));
    return o;
}

static json_t *level_json(const ibl_specular_info *info, int l)
{
    json_t *o = json_object();
    ibl__json_set(o, "level", ibl__json_number(l));
    ibl__json_set(o, "size", ibl__json_number(ibl_level_size(info->size, l)));
    if (info->filter == IBL_FILTER_GGX) {
        ibl__json_set(o, "roughness", ibl__json_float(info->roughness[l]));
        if (!(info->roughness[l] > 0)) ibl__json_set(o, "mirror", ibl__json_bool(1));
        return o;
    }
    float s = ibl_specular_level_shininess(info, l);
    if (!(s > 0)) {
        ibl__json_set(o, "mirror", ibl__json_bool(1));
        return o;
    }
    ibl__json_set(o, "shininess", ibl__json_float(s));
    /* the kernel the level was filtered with (for blinn: the Phong fit of the Blinn lobe) */
    ibl__json_set(o, "phong_exponent", ibl__json_float(ibl_specular_level_phong_exponent(info, l)));
    return o;
}

/* The chain's description; files: a JSON array of its file names (stolen). */
static json_t *specular_json(const ibl_specular_info *info, ibl_edge_fixup edge_fixup,
                             ibl_format format, json_t *files)
{
    json_t *o = json_object();
    ibl__json_set(o, "files", files);
    ibl__json_set(o, "format", ibl__json_string(ibl_format_name(format)));
    ibl__json_set(o, "filter", ibl__json_string(ibl_specular_filter_name(info->filter)));
    ibl__json_set(o, "mapping", ibl__json_string(ibl_specular_mapping_name(info->mapping)));
    ibl__json_set(o, "size", ibl__json_number(info->size));
    ibl__json_set(o, "level_count", ibl__json_number(info->levels));
    ibl__json_set(o, "mirror", ibl__json_bool(info->mirror));
    ibl__json_set(o, "edge_fixup", ibl__json_string(ibl_edge_fixup_name(edge_fixup)));
    ibl__json_set(o, "blinn_factor", ibl__json_float(info->blinn_factor));
    json_t *range = json_object();
    ibl__json_set(range, "min", ibl__json_float(info->shininess_min));
    ibl__json_set(range, "max", ibl__json_float(info->shininess_max));
    ibl__json_set(range, "unit", ibl__json_string(info->filter == IBL_FILTER_PHONG ? "phong_exponent"
                                                                                  : "shininess"));
    ibl__json_set(o, "mapping_range", range);
    if (info->mapping == IBL_MAPPING_BABYLON)
        ibl__json_set(o, "babylon_lod_scale", ibl__json_float(info->babylon_lod_scale));
    if (info->mapping == IBL_MAPPING_TRIACE) {
        ibl__json_set(o, "lod_offset", ibl__json_float(info->lod_offset));
        ibl__json_set(o, "lod_formula", ibl__json_string("lod = lod_offset - 0.5 * log2(s), s in "
                                                         "mapping_range's unit"));
    }
    json_t *levels = json_array();
    for (int l = 0; l < info->levels; l++) ibl__json_append(levels, level_json(info, l));
    ibl__json_set(o, "levels", levels);
    return o;
}

static json_t *table_json(const char *file, const char *format, const char *channels)
{
    json_t *o = json_object();
    ibl__json_set(o, "file", ibl__json_string(file));
    ibl__json_set(o, "format", ibl__json_string(format));
    ibl__json_set(o, "channels", ibl__json_string(channels));
    return o;
}

static json_t *brdf_json(const ibl_bake_data *b)
{
    json_t *o = json_object();
    if (b->splitsum.pixels) {
        json_t *t = table_json(ibl__bake_file_info_of(IBL__BAKE_SPLITSUM)->name, "rg16f",
                               "R = A, G = B: specular = F0 * A + F90 * B (GGX, height-correlated "
                               "Smith); row 0 = roughness ~ 0");
        ibl__json_set(t, "n_dot_v", axis_json(&b->splitsum_n_dot_v));
        ibl__json_set(t, "roughness", axis_json(&b->splitsum_roughness));
        ibl__json_set(o, "splitsum", t);
    }
    if (b->brdf_extra.pixels) {
        json_t *t = table_json(ibl__bake_file_info_of(IBL__BAKE_BRDF_EXTRA)->name, "rgba16f",
                               "R = E (GGX directional albedo), G = E_avg, B = Charlie sheen "
                               "albedo, A = its average");
        ibl__json_set(t, "n_dot_v", axis_json(&b->splitsum_n_dot_v));
        ibl__json_set(t, "roughness", axis_json(&b->splitsum_roughness));
        ibl__json_set(o, "multiscatter_sheen", t);
    }
    if (b->ambient_brdf.data) {
        json_t *t = table_json(ibl__bake_file_info_of(IBL__BAKE_AMBIENT_BRDF)->name, "rg16f",
                               "R = AmbientBRDF (tri-Ace 2010), G = 1 - F0; volume [F0][shininess][n.v]");
        ibl__json_set(t, "normalization", ibl__json_string(b->ambient_normalization == IBL_BLINN_EXACT
                                                               ? "exact" : "triace"));
        ibl__json_set(t, "n_dot_v", axis_json(&b->ambient_n_dot_v));
        ibl__json_set(t, "shininess", axis_json(&b->ambient_shininess));
        ibl__json_set(t, "f0", axis_json(&b->ambient_f0));
        ibl__json_set(o, "ambient_brdf", t);
    }
    return o;
}

static json_t *files_json(const ibl_bake_data *b)
{
    json_t *a = json_array();
    for (int i = 0; i < IBL__BAKE_FILE_COUNT; i++) {
        if (i == IBL__BAKE_MANIFEST || !ibl__bake_has_file(b, (ibl__bake_file)i)) continue;
        const ibl__bake_file_info *f = ibl__bake_file_info_of((ibl__bake_file)i);
        json_t *o = json_object();
        ibl__json_set(o, "file", ibl__json_string(f->name));
        ibl__json_set(o, "kind", ibl__json_string(f->kind));
        ibl__json_set(o, "layout", ibl__json_string(f->layout));
        ibl__json_append(a, o);
    }
    return a;
}

static json_t *timing_json(const ibl_bake_timing *t)
{
    json_t *o = json_object();
    ibl__json_set(o, "specular", ibl__json_number(round(t->specular * 10) / 10));
    ibl__json_set(o, "diffuse", ibl__json_number(round(t->diffuse * 10) / 10));
    ibl__json_set(o, "brdf", ibl__json_number(round(t->brdf * 10) / 10));
    ibl__json_set(o, "preview", ibl__json_number(round(t->preview * 10) / 10));
    ibl__json_set(o, "total", ibl__json_number(round(t->total * 10) / 10));
    return o;
}

ibl_status ibl_bake_manifest(ibl_context *ctx, const ibl_bake_data *b, char **json)
{
    if (!json) return IBL_ERR_INVALID_ARGUMENT;
    *json = NULL;
    if (!b || !b->specular.data) return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "bake: empty");
    json_t *root = json_object();
    ibl__json_set(root, "format", ibl__json_string(MANIFEST_FORMAT));
    ibl__json_set(root, "version", ibl__json_number(IBL_BAKE_MANIFEST_VERSION));
    ibl__json_set(root, "generator", ibl__json_string("ibl " IBL_VERSION_STRING));
    ibl__json_set(root, "source", source_json(b));
    ibl__json_set(root, "conventions", conventions_json());
    json_t *params = json_object();
    ibl__json_set(params, "preset", ibl__json_string(b->preset));
    ibl__json_set(params, "working_size", ibl__json_number(b->working_size));
    ibl__json_set(params, "lut_size", ibl__json_number(b->lut_size));
    if (b->target != IBL_TARGET_NONE)
        ibl__json_set(params, "target", ibl__json_string(ibl_target_name(b->target)));
    if (b->units) ibl__json_set(params, "units", ibl__json_string(b->units));
    ibl__json_set(root, "parameters", params);
    ibl__json_set(root, "timings_ms", timing_json(&b->timing_ms));
    ibl__json_set(root, "specular", specular_json(&b->specular_info, b->edge_fixup, b->format,
                                                  file_list(b, IBL__BAKE_SPECULAR_KTX2, 2)));
    /* how the cube textures are stored beyond their format (read back into ibl_bake_data) */
    json_t *storage = json_object();
    if (ibl__format_is_block(b->format)) ibl__json_set(storage, "quality", ibl__json_string(ibl_quality_name(b->quality)));
    ibl__json_set(storage, "zstd_level", ibl__json_number(b->zstd_level));
    if (b->format == IBL_FORMAT_RGBM) ibl__json_set(storage, "rgbm_range", ibl__json_float(b->rgbm_range));
    ibl__json_set(root, "storage", storage);
    if (b->irradiance.data) {
        json_t *irr = json_object();
        ibl__json_set(irr, "files", file_list(b, IBL__BAKE_IRRADIANCE_KTX2, 2));
        ibl__json_set(irr, "format", ibl__json_string(ibl_format_name(b->format)));
        ibl__json_set(irr, "size", ibl__json_number(b->irradiance.size));
        ibl__json_set(irr, "value", ibl__json_string("E/pi: the radiance a white Lambertian "
                                                     "surface reflects; multiply by albedo"));
        ibl__json_set(root, "irradiance", irr);
    }
    if (b->sh.bands > 0) {
        char *text = NULL;
        ibl_status st = ibl_sh_json(ctx, &b->sh, b->sh_window_requested, &b->sh_window, NULL,
                                    "cube", &text);
        if (st != IBL_OK) {
            json_decref(root);
            return st;
        }
        json_t *sh = NULL;
        st = ibl__json_parse(ctx, text, strlen(text), "sh", &sh);
        ibl_free(ctx, text);
        if (st != IBL_OK) {
            json_decref(root);
            return st;
        }
        ibl__json_set(sh, "file", ibl__json_string(ibl__bake_file_info_of(IBL__BAKE_SH_JSON)->name));
        ibl__json_set(root, "sh", sh);
    }
    ibl__json_set(root, "brdf", brdf_json(b));
    if (b->atlas.pixels) {
        /* Daqi 2016's 2D mip atlas: the coordinate table beside its files (docs/ATLAS.md) */
        json_t *at = ibl__atlas_layout_json(&b->atlas_layout);
        ibl__json_set(at, "files", file_list(b, IBL__BAKE_ATLAS_KTX2, 2));
        ibl__json_set(at, "format", ibl__json_string(ibl_format_name(b->format)));
        ibl__json_set(at, "png_encoding", ibl__json_string("rgbm"));
        ibl__json_set(at, "rgbm_range", ibl__json_float(b->rgbm_range));
        ibl__json_set(root, "atlas", at);
    }
    if (b->preview.pixels) {
        json_t *pv = json_object();
        ibl__json_set(pv, "file", ibl__json_string(ibl__bake_file_info_of(IBL__BAKE_PREVIEW)->name));
        ibl__json_set(pv, "width", ibl__json_number(b->preview.width));
        ibl__json_set(root, "preview", pv);
    }
    ibl__json_set(root, "files", files_json(b));
    return ibl__json_text(ctx, root, "manifest.json", json);
}

static ibl_status chain_manifest(ibl_context *ctx, const ibl_specular_info *info,
                                 ibl_edge_fixup edge_fixup, ibl_format format,
                                 const ibl_atlas_layout *layout, const char *const *files,
                                 int file_count, char **json)
{
    if (!json) return IBL_ERR_INVALID_ARGUMENT;
    *json = NULL;
    if (!info || !files || file_count < 1)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "chain manifest: no files");
    json_t *list = json_array();
    for (int i = 0; i < file_count; i++) ibl__json_append(list, ibl__json_string(files[i]));
    json_t *root = json_object();
    ibl__json_set(root, "format", ibl__json_string("ibl-chain"));
    ibl__json_set(root, "version", ibl__json_number(IBL_BAKE_MANIFEST_VERSION));
    ibl__json_set(root, "generator", ibl__json_string("ibl " IBL_VERSION_STRING));
    ibl__json_set(root, "conventions", conventions_json());
    if (layout) {
        json_t *at = ibl__atlas_layout_json(layout);
        ibl__json_set(at, "files", json_deep_copy(list));
        ibl__json_set(root, "atlas", at);
    }
    ibl__json_set(root, "specular", specular_json(info, edge_fixup, format, list));
    return ibl__json_text(ctx, root, "chain manifest", json);
}

ibl_status ibl_chain_manifest(ibl_context *ctx, const ibl_specular_info *info,
                              ibl_edge_fixup edge_fixup, ibl_format format,
                              const char *const *files, int file_count, char **json)
{
    return chain_manifest(ctx, info, edge_fixup, format, NULL, files, file_count, json);
}

ibl_status ibl_atlas_chain_manifest(ibl_context *ctx, const ibl_specular_info *info,
                                    ibl_edge_fixup edge_fixup, ibl_format format,
                                    const ibl_atlas_layout *layout, const char *const *files,
                                    int file_count, char **json)
{
    if (!layout) return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "chain manifest: no atlas table");
    return chain_manifest(ctx, info, edge_fixup, format, layout, files, file_count, json);
}

/* ---- reading ------------------------------------------------------------------------------ */

static ibl_table_axis read_axis(ibl__json_reader *r, json_t *parent, const char *path,
                                const char *key)
{
    ibl_table_axis a = {1, 0, 0, 0};
    char here[128];
    snprintf(here, sizeof here, "%s.%s", path, key);
    json_t *o = ibl__json_object(r, parent, path, key);
    if (!o) return a;
    a.count = ibl__json_get_int(r, o, here, "count", 1, 1 << 16);
    a.first = (float)ibl__json_get_number(r, o, here, "first");
    a.last = (float)ibl__json_get_number(r, o, here, "last");
    const char *spacing = ibl__json_get_string(r, o, here, "spacing");
    if (strcmp(spacing, "log") == 0) a.logarithmic = 1;
    else if (strcmp(spacing, "linear") != 0) ibl__json_fail(r, here, "spacing", "expected \"log\" or \"linear\"");
    if (r->status == IBL_OK && (!isfinite(a.first) || !isfinite(a.last) ||
                                (a.logarithmic && !(a.first > 0 && a.last > 0))))
        ibl__json_fail(r, path, key, "first and last must be finite (and positive on a log axis)");
    return a;
}

/* A file name the manifest names for a part: one of the module's own names, never a path. */
static const char *part_file(ibl__json_reader *r, json_t *value, const char *path, const char *key,
                             ibl__bake_file expect_a, ibl__bake_file expect_b)
{
    if (!json_is_string(value)) {
        ibl__json_fail(r, path, key, "expected a file name");
        return NULL;
    }
    const char *name = json_string_value(value);
    ibl__bake_file f = ibl__bake_file_named(name);
    if (f != expect_a && f != expect_b) {
        ibl__json_fail(r, path, key, "'%s' is not a file of this part of a bake", name);
        return NULL;
    }
    return name;
}

static void read_file_pair(ibl__json_reader *r, json_t *part, const char *path,
                           ibl__bake_file ktx2, ibl__bake_file dds, const char *out[2])
{
    json_t *list = ibl__json_array(r, part, path, "files");
    size_t i;
    json_t *v;
    int n = 0;
    if (!list) return;
    json_array_foreach(list, i, v)
    {
        const char *name = part_file(r, v, path, "files", ktx2, dds);
        if (name && n < 2) out[n++] = name;
    }
    /* KTX2 first: it also carries the chain's own description */
    if (n == 2 && ibl__bake_file_named(out[1]) == ktx2) {
        const char *t = out[0];
        out[0] = out[1];
        out[1] = t;
    }
    if (n == 0 && r->status == IBL_OK) ibl__json_fail(r, path, "files", "lists no file");
}

static void read_specular(ibl__json_reader *r, json_t *root, ibl_bake_data *b,
                          ibl__bake_manifest_files *files)
{
    json_t *spec = ibl__json_object(r, root, "", "specular");
    if (!spec) return;
    const char *P = "specular";
    ibl_specular_info *info = &b->specular_info;
    read_file_pair(r, spec, P, IBL__BAKE_SPECULAR_KTX2, IBL__BAKE_SPECULAR_DDS, files->specular);
    const char *filter = ibl__json_get_string(r, spec, P, "filter");
    if (r->status == IBL_OK && !ibl_specular_filter_from_name(filter, &info->filter))
        ibl__json_fail(r, P, "filter", "unknown filter '%s'", filter);
    const char *mapping = ibl__json_get_string(r, spec, P, "mapping");
    if (r->status == IBL_OK && !ibl_specular_mapping_from_name(mapping, &info->mapping))
        ibl__json_fail(r, P, "mapping", "unknown mapping '%s'", mapping);
    const char *fixup = ibl__json_opt_string(r, spec, P, "edge_fixup", "none");
    if (r->status == IBL_OK && !ibl_edge_fixup_from_name(fixup, &b->edge_fixup))
        ibl__json_fail(r, P, "edge_fixup", "unknown edge fixup '%s'", fixup);
    const char *format = ibl__json_opt_string(r, spec, P, "format", "rgba16f");
    if (r->status == IBL_OK && !ibl_format_from_name(format, &b->format))
        ibl__json_fail(r, P, "format", "unknown pixel format '%s'", format);
    info->size = ibl__json_get_int(r, spec, P, "size", 1, 65536);
    info->mirror = ibl__json_opt_bool(r, spec, P, "mirror", 0);
    info->blinn_factor = (float)ibl__json_opt_number(r, spec, P, "blinn_factor", IBL_DEFAULT_BLINN_FACTOR);
    if (r->status == IBL_OK && !(info->blinn_factor > 0 && info->blinn_factor < 1e3))
        ibl__json_fail(r, P, "blinn_factor", "must be a positive number");
    info->lod_offset = (float)ibl__json_opt_number(r, spec, P, "lod_offset", 0.0);
    info->babylon_lod_scale = (float)ibl__json_opt_number(r, spec, P, "babylon_lod_scale", 0.0);
    json_t *range = json_object_get(spec, "mapping_range");
    if (range) {
        info->shininess_min = (float)ibl__json_get_number(r, range, "specular.mapping_range", "min");
        info->shininess_max = (float)ibl__json_get_number(r, range, "specular.mapping_range", "max");
    }
    json_t *levels = ibl__json_array(r, spec, P, "levels");
    if (!levels) return;
    size_t count = json_array_size(levels);
    if (count < 1 || count > IBL_MAX_LEVELS) {
        ibl__json_fail(r, P, "levels", "has %zu entries; 1 to %d expected", count, IBL_MAX_LEVELS);
        return;
    }
    info->levels = (int)count;
    for (size_t k = 0; k < count && r->status == IBL_OK; k++) {
        char here[64];
        snprintf(here, sizeof here, "specular.levels[%zu]", k);
        json_t *lv = json_array_get(levels, k);
        if (!json_is_object(lv)) {
            ibl__json_fail(r, here, NULL, "expected an object");
            break;
        }
        int mirror = ibl__json_opt_bool(r, lv, here, "mirror", 0);
        if (info->filter == IBL_FILTER_GGX) {
            double rough = ibl__json_get_number(r, lv, here, "roughness");
            if (r->status == IBL_OK && !(rough >= 0 && rough <= 1))
                ibl__json_fail(r, here, "roughness", "must lie in [0, 1]");
            info->roughness[k] = (float)rough;
        } else if (!mirror) {
            /* the chain's own units (ibl_specular_level_shininess): kernel exponents for
             * phong, the material's Blinn-Phong shininess for blinn, box and gauss */
            const char *key = info->filter == IBL_FILTER_PHONG ? "phong_exponent" : "shininess";
            double s = ibl__json_get_number(r, lv, here, key);
            if (r->status == IBL_OK && !(s > 0 && s < 1e9))
                ibl__json_fail(r, here, key, "must be a positive number");
            info->shininess[k] = (float)s;
        }
    }
}

static void read_brdf(ibl__json_reader *r, json_t *root, ibl_bake_data *b,
                      ibl__bake_manifest_files *files)
{
    json_t *brdf = json_object_get(root, "brdf");
    if (!brdf) return;
    if (!json_is_object(brdf)) {
        ibl__json_fail(r, "", "brdf", "expected an object");
        return;
    }
    json_t *ss = json_object_get(brdf, "splitsum");
    if (ss) {
        files->splitsum = part_file(r, json_object_get(ss, "file"), "brdf.splitsum", "file",
                                    IBL__BAKE_SPLITSUM, IBL__BAKE_SPLITSUM);
        b->splitsum_n_dot_v = read_axis(r, ss, "brdf.splitsum", "n_dot_v");
        b->splitsum_roughness = read_axis(r, ss, "brdf.splitsum", "roughness");
    }
    json_t *ab = json_object_get(brdf, "ambient_brdf");
    if (ab) {
        files->ambient_brdf = part_file(r, json_object_get(ab, "file"), "brdf.ambient_brdf",
                                        "file", IBL__BAKE_AMBIENT_BRDF, IBL__BAKE_AMBIENT_BRDF);
        b->ambient_n_dot_v = read_axis(r, ab, "brdf.ambient_brdf", "n_dot_v");
        b->ambient_shininess = read_axis(r, ab, "brdf.ambient_brdf", "shininess");
        b->ambient_f0 = read_axis(r, ab, "brdf.ambient_brdf", "f0");
        const char *norm = ibl__json_opt_string(r, ab, "brdf.ambient_brdf", "normalization", "triace");
        b->ambient_normalization = strcmp(norm, "exact") == 0 ? IBL_BLINN_EXACT : IBL_BLINN_TRIACE_FIT;
    }
}

static void read_sh(ibl__json_reader *r, json_t *root, ibl_bake_data *b)
{
    json_t *sh = json_object_get(root, "sh");
    if (!sh) return;
    int bands = ibl__json_get_int(r, sh, "sh", "bands", 1, IBL_SH_MAX_BANDS);
    json_t *coeffs = ibl__json_array(r, sh, "sh", "radiance");
    if (!coeffs || r->status != IBL_OK) return;
    if (json_array_size(coeffs) != (size_t)(bands * bands)) {
        ibl__json_fail(r, "sh", "radiance", "has %zu coefficients for %d bands",
                       json_array_size(coeffs), bands);
        return;
    }
    b->sh.bands = bands;
    for (int i = 0; i < bands * bands; i++) {
        json_t *rgb = json_array_get(coeffs, (size_t)i);
        for (int c = 0; c < 3; c++) {
            json_t *v = json_array_get(rgb, (size_t)c);
            if (!json_is_number(v) || json_array_size(rgb) != 3) {
                char here[48];
                snprintf(here, sizeof here, "sh.radiance[%d]", i);
                ibl__json_fail(r, here, NULL, "expected three numbers");
                return;
            }
            b->sh.c[i][c] = json_number_value(v);
        }
    }
}

static void read_source(ibl__json_reader *r, json_t *root, ibl_bake_data *b, const char **name,
                        const char **preset)
{
    json_t *src = json_object_get(root, "source");
    *name = src ? ibl__json_opt_string(r, src, "source", "name", NULL) : NULL;
    if (src) {
        const char *layout = ibl__json_opt_string(r, src, "source", "layout", NULL);
        if (layout && !ibl_layout_from_name(layout, &b->source_layout))
            ibl__json_fail(r, "source", "layout", "unknown layout '%s'", layout);
        b->source_orientation.yaw_degrees = (float)ibl__json_opt_number(r, src, "source", "yaw_degrees", 0);
        b->source_orientation.mirror = ibl__json_opt_bool(r, src, "source", "mirror_input", 0);
        b->source_orientation.z_up = ibl__json_opt_bool(r, src, "source", "z_up", 0);
    }
    json_t *params = json_object_get(root, "parameters");
    *preset = params ? ibl__json_opt_string(r, params, "parameters", "preset", NULL) : NULL;
    if (params) {
        b->working_size = (int)ibl__json_opt_number(r, params, "parameters", "working_size", 0);
        b->lut_size = (int)ibl__json_opt_number(r, params, "parameters", "lut_size", 0);
        const char *target = ibl__json_opt_string(r, params, "parameters", "target", NULL);
        if (target && !ibl_target_from_name(target, &b->target))
            ibl__json_fail(r, "parameters", "target", "unknown target '%s'", target);
        const char *units = ibl__json_opt_string(r, params, "parameters", "units", NULL);
        if (units && r->status == IBL_OK && !(b->units = ibl__strdup(r->ctx, units)))
            r->status = ibl__fail(r->ctx, IBL_ERR_OUT_OF_MEMORY, "%s: out of memory", r->name);
    }
    json_t *storage = json_object_get(root, "storage"); /* absent in older bakes */
    if (storage) {
        const char *q = ibl__json_opt_string(r, storage, "storage", "quality", "default");
        if (r->status == IBL_OK && !ibl_quality_from_name(q, &b->quality))
            ibl__json_fail(r, "storage", "quality", "unknown quality '%s'", q);
        b->zstd_level = (int)ibl__json_opt_number(r, storage, "storage", "zstd_level", 0);
        if (json_object_get(storage, "rgbm_range"))
            b->rgbm_range = (float)ibl__json_opt_number(r, storage, "storage", "rgbm_range", 0);
    }
}

/* The optional "atlas": its table, its KTX2 file (the PNG is the same texels in RGBM). */
static void read_atlas(ibl__json_reader *r, json_t *root, ibl_bake_data *b,
                       ibl__bake_manifest_files *files)
{
    json_t *at = json_object_get(root, "atlas");
    if (!at) return;
    if (!json_is_object(at)) {
        ibl__json_fail(r, "", "atlas", "expected an object");
        return;
    }
    ibl__atlas_layout_read(r, at, "atlas", &b->atlas_layout);
    if (r->status == IBL_OK && b->atlas_layout.levels != b->specular_info.levels)
        ibl__json_fail(r, "atlas", "levels", "%d; the chain has %d", b->atlas_layout.levels,
                       b->specular_info.levels);
    if (r->status == IBL_OK && b->atlas_layout.face_size[0] != b->specular_info.size)
        ibl__json_fail(r, "atlas", "rects", "level 0 is %d texels; the chain's is %d",
                       b->atlas_layout.face_size[0], b->specular_info.size);
    b->rgbm_range = (float)ibl__json_opt_number(r, at, "atlas", "rgbm_range", IBL_RGBM_DEFAULT_RANGE);
    json_t *list = ibl__json_array(r, at, "atlas", "files");
    size_t i;
    json_t *v;
    if (!list) return;
    json_array_foreach(list, i, v)
    {
        const char *name = part_file(r, v, "atlas", "files", IBL__BAKE_ATLAS_KTX2, IBL__BAKE_ATLAS_PNG);
        if (name && ibl__bake_file_named(name) == IBL__BAKE_ATLAS_KTX2) files->atlas = name;
    }
    if (r->status == IBL_OK && !files->atlas)
        ibl__json_fail(r, "atlas", "files", "lists no %s", ibl__bake_file_info_of(IBL__BAKE_ATLAS_KTX2)->name);
}

ibl_status ibl__bake_manifest_parse(ibl_context *ctx, const void *bytes, size_t size,
                                    const char *name, ibl_bake_data *b,
                                    ibl__bake_manifest_files *files, void **root_out)
{
    memset(b, 0, sizeof *b);
    memset(files, 0, sizeof *files);
    *root_out = NULL;
    json_t *root;
    ibl_status st = ibl__json_parse(ctx, bytes, size, name, &root);
    if (st != IBL_OK) return st;
    ibl__json_reader r = {ctx, name, IBL_OK};
    const char *format = ibl__json_opt_string(&r, root, "", "format", NULL);
    if (r.status == IBL_OK && !format && json_object_get(root, "generator"))
        ibl__json_fail(&r, "", "format", "missing: a manifest of an ibl before 0.2 (bake again)");
    if (r.status == IBL_OK && (!format || strcmp(format, MANIFEST_FORMAT) != 0))
        ibl__json_fail(&r, "", "format", "not an ibl bake manifest (\"format\": \"%s\" expected)",
                       MANIFEST_FORMAT);
    int version = ibl__json_get_int(&r, root, "", "version", 1, 1 << 20);
    if (r.status == IBL_OK && version > IBL_BAKE_MANIFEST_VERSION)
        ibl__json_fail(&r, "", "version", "%d is newer than this ibl reads (%d); update ibl",
                       version, IBL_BAKE_MANIFEST_VERSION);
    const char *source_name = NULL, *preset = NULL;
    if (r.status == IBL_OK) read_source(&r, root, b, &source_name, &preset);
    if (r.status == IBL_OK) read_specular(&r, root, b, files);
    json_t *irr = r.status == IBL_OK ? json_object_get(root, "irradiance") : NULL;
    if (irr) read_file_pair(&r, irr, "irradiance", IBL__BAKE_IRRADIANCE_KTX2, IBL__BAKE_IRRADIANCE_DDS,
                            files->irradiance);
    if (r.status == IBL_OK) read_sh(&r, root, b);
    if (r.status == IBL_OK) read_brdf(&r, root, b, files);
    if (r.status == IBL_OK) read_atlas(&r, root, b, files);
    if (r.status == IBL_OK) {
        b->source_name = ibl__strdup(ctx, source_name ? source_name : "unknown");
        b->preset = ibl__strdup(ctx, preset);
        if (!b->source_name || (preset && !b->preset))
            r.status = ibl__fail(ctx, IBL_ERR_OUT_OF_MEMORY, "%s: out of memory", name);
    }
    if (r.status != IBL_OK) {
        ibl_free(ctx, b->source_name);
        ibl_free(ctx, b->preset);
        ibl_free(ctx, b->units);
        memset(b, 0, sizeof *b);
        memset(files, 0, sizeof *files);
        json_decref(root);
        return r.status;
    }
    *root_out = root;
    return IBL_OK;
}

void ibl__bake_manifest_release(void *root)
{
    json_decref((json_t *)root);
}
