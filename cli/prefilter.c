/* ibl prefilter: the prefiltered (mipmapped) radiance environment map of an environment. */
#include "cli.h"
#include "input.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char usage[] =
    "usage: ibl prefilter IN -o OUT [options]\n"
    "\n"
    "Writes the specular prefiltered cube of an environment (any layout, or a cube texture):\n"
    "level l holds the environment convolved with the lobe of level l's roughness (GGX) or\n"
    "shininess (Phong family). OUT: .ktx2 .ktx .dds hold every face and level in one file;\n"
    ".exr .hdr .pfm .png get one image per face and level, OUT-STEM_l<level>_<face>.EXT with\n"
    "<face> in px nx py ny pz nz. manifest.json beside OUT lists the filter, the mapping and\n"
    "every level's size and roughness or shininess (also in KTX2 metadata, ibl.specular.*).\n"
    "\n"
    "  -o, --output OUT     output file (required)\n"
    "  --filter K           ggx (default), phong, blinn, box, gauss\n"
    "  --size N             output face edge (default: the source cube's)\n"
    "  --levels L           number of levels (default: down to 1x1)\n"
    "  --mapping M          level <-> roughness/shininess: triace, linear, filament, unreal,\n"
    "                       unity, babylon, table (default: linear for ggx, seed otherwise)\n"
    "  --table V,V,...      the values of --mapping table, one per level\n"
    "  --shininess-min S --shininess-max S   the triace mapping's range (default 1-1000)\n"
    "  --blinn-factor F     Blinn-to-Phong fit factor (default 4.2; cmft uses 4)\n"
    "  --preset P           dynamic-box16, dynamic-gauss32, dynamic-phong16, dynamic-phong32,\n"
    "                       static-phong32, static-phong64, gltf, filament, unreal, unity\n"
    "                       (explicit options override the preset)\n"
    "  --edge-fixup E       none (default), overlap, overlap2, bent, warp\n"
    "  --method M           fast (default) or reference (exact double integral: slow)\n"
    "  --accuracy A         fast method's quadrature step scale (default 0.35; smaller: more exact,\n"
    "                       slower)\n"
    "  --mirror             level 0 is the unfiltered source (mirror-like materials)\n"
    "  --format F           storage format (rgba16f, rgba32f, rg11b10f, rgb9e5, ...)\n"
    "  --source-size N      face edge the input is converted to first (default: automatic)\n"
    "  --layout NAME --yaw DEG --flip-input --z-up   how to read a flat input\n";

static const char *const face_names[6] = {"px", "nx", "py", "ny", "pz", "nz"};

static int parse_table(const char *v, float *table, int max)
{
    int count = 0;
    const char *p = v;
    while (*p) {
        char *end = NULL;
        double x = strtod(p, &end);
        if (end == p || count >= max) return -1;
        table[count++] = (float)x;
        p = end;
        if (*p == ',') p++;
        else if (*p) return -1;
    }
    return count;
}

/* OUT without its extension, and the extension with its dot. */
static void split_ext(const char *path, char *stem, size_t cap, const char **ext)
{
    const char *dot = strrchr(path, '.'), *slash = strrchr(path, '/');
    if (!dot || (slash && dot < slash)) dot = path + strlen(path);
    size_t n = (size_t)(dot - path);
    if (n >= cap) n = cap - 1;
    memcpy(stem, path, n);
    stem[n] = 0;
    *ext = dot;
}

static ibl_status write_manifest(ibl_context *ctx, const char *out_path,
                                 const ibl_specular_info *info, int flat)
{
    char *json = NULL;
    ibl_status st = ibl_specular_manifest_json(ctx, info, &json);
    if (st != IBL_OK) return st;
    const char *slash = strrchr(out_path, '/');
    const char *base = slash ? slash + 1 : out_path;
    size_t dir_len = slash ? (size_t)(slash - out_path) + 1 : 0;
    char path[4096], stem[1024];
    const char *ext;
    split_ext(base, stem, sizeof stem, &ext);
    snprintf(path, sizeof path, "%.*smanifest.json", (int)dir_len, out_path);
    size_t len = strlen(json) + 2 * strlen(base) + 256;
    char *full = ibl_alloc(ctx, len);
    if (!full) {
        ibl_free(ctx, json);
        return ibl_context_status(ctx);
    }
    /* the file name(s) first, then the library's manifest body */
    if (flat)
        snprintf(full, len, "{\n  \"files\": \"%s_l{level}_{face}%s\",\n  \"faces\": [\"px\", \"nx\", "
                 "\"py\", \"ny\", \"pz\", \"nz\"],\n%s", stem, ext, json + 2);
    else
        snprintf(full, len, "{\n  \"file\": \"%s\",\n%s", base, json + 2);
    st = ibl_write_file_atomic(ctx, path, full, strlen(full));
    ibl_free(ctx, full);
    ibl_free(ctx, json);
    return st;
}

int cli_cmd_prefilter(int argc, char **argv)
{
    cli_args a = {argc, argv, 0, "prefilter", usage, {0}, {0}, 0};
    const char *out_path = NULL, *preset = NULL;
    ibl_specular_desc d = {0}, set = {0};
    int has_filter = 0, has_mapping = 0, has_fixup = 0, has_size = 0, has_levels = 0;
    float table[IBL_MAX_LEVELS];
    ibl_write_desc wd = {0};
    cli_input_options io = {0};
    const char *arg;
    while ((arg = cli_next(&a))) {
        if (cli_common_option(&a, arg)) continue;
        if (cli_is(&a, arg, "--mirror", NULL)) {
            set.mirror = 1;
            continue;
        }
        if (cli_is(&a, arg, "--flip-input", NULL)) {
            io.orientation.mirror = 1;
            continue;
        }
        if (cli_input_option(&a, arg, &io)) continue;
        if (cli_is(&a, arg, "--output", "-o")) {
            out_path = cli_value(&a, arg);
        } else if (cli_is(&a, arg, "--filter", NULL)) {
            const char *v = cli_value(&a, arg);
            if (!ibl_specular_filter_from_name(v, &set.filter))
                cli_usage_error(&a, "--filter wants ggx, phong, blinn, box or gauss, not '%s'", v);
            has_filter = 1;
        } else if (cli_is(&a, arg, "--size", NULL)) {
            set.size = cli_int(&a, arg, 1, 16384);
            has_size = 1;
        } else if (cli_is(&a, arg, "--levels", NULL)) {
            set.levels = cli_int(&a, arg, 1, IBL_MAX_LEVELS);
            has_levels = 1;
        } else if (cli_is(&a, arg, "--mapping", NULL)) {
            const char *v = cli_value(&a, arg);
            if (!ibl_specular_mapping_from_name(v, &set.mapping) || set.mapping == IBL_MAPPING_DEFAULT)
                cli_usage_error(&a, "--mapping wants triace, linear, filament, unreal, unity, babylon "
                                    "or table, not '%s'", v);
            has_mapping = 1;
        } else if (cli_is(&a, arg, "--table", NULL)) {
            const char *v = cli_value(&a, arg);
            set.table_count = parse_table(v, table, IBL_MAX_LEVELS);
            if (set.table_count < 1) cli_usage_error(&a, "--table wants comma-separated numbers");
            set.table = table;
        } else if (cli_is(&a, arg, "--shininess-min", NULL)) {
            set.shininess_min = (float)cli_double(&a, arg, 1e-3, 1e7);
        } else if (cli_is(&a, arg, "--shininess-max", NULL)) {
            set.shininess_max = (float)cli_double(&a, arg, 1e-3, 1e7);
        } else if (cli_is(&a, arg, "--blinn-factor", NULL)) {
            set.blinn_factor = (float)cli_double(&a, arg, 0.1, 100);
        } else if (cli_is(&a, arg, "--accuracy", NULL)) {
            set.accuracy = (float)cli_double(&a, arg, 0.01, 2);
        } else if (cli_is(&a, arg, "--preset", NULL)) {
            preset = cli_value(&a, arg);
        } else if (cli_is(&a, arg, "--edge-fixup", NULL)) {
            const char *v = cli_value(&a, arg);
            if (!ibl_edge_fixup_from_name(v, &set.edge_fixup))
                cli_usage_error(&a, "--edge-fixup wants none, overlap, overlap2, bent or warp, not '%s'", v);
            has_fixup = 1;
        } else if (cli_is(&a, arg, "--method", NULL)) {
            const char *v = cli_value(&a, arg);
            if (strcmp(v, "fast") == 0) set.method = IBL_METHOD_FAST;
            else if (strcmp(v, "reference") == 0) set.method = IBL_METHOD_REFERENCE;
            else cli_usage_error(&a, "--method wants fast or reference, not '%s'", v);
        } else if (cli_is(&a, arg, "--source-size", NULL)) {
            io.size = cli_int(&a, arg, 1, 16384);
        } else if (cli_is(&a, arg, "--format", NULL)) {
            const char *v = cli_value(&a, arg);
            int ok = 0;
            wd.format = ibl_format_from_name(v, &ok);
            if (!ok) cli_usage_error(&a, "unknown format '%s'", v);
        } else {
            cli_positional_or_unknown(&a, arg);
        }
    }
    if (a.positional_count != 1) cli_usage_error(&a, "wants exactly one input file");
    if (!out_path) cli_usage_error(&a, "wants an output file (-o OUT)");
    if (preset && !ibl_specular_preset(preset, &d)) cli_usage_error(&a, "unknown preset '%s'", preset);
    /* explicit options override the preset */
    if (has_filter) d.filter = set.filter;
    if (has_size) d.size = set.size;
    if (has_levels) d.levels = set.levels;
    if (has_mapping) d.mapping = set.mapping;
    if (has_fixup) d.edge_fixup = set.edge_fixup;
    if (set.table) d.table = set.table, d.table_count = set.table_count;
    if (set.shininess_min > 0) d.shininess_min = set.shininess_min;
    if (set.shininess_max > 0) d.shininess_max = set.shininess_max;
    if (set.blinn_factor > 0) d.blinn_factor = set.blinn_factor;
    if (set.accuracy > 0) d.accuracy = set.accuracy;
    d.method = set.method;
    d.mirror = set.mirror;
    ibl_file_type out_type = cli_check_output(&a, out_path);
    const char *in = a.positional[0];
    ibl_context *ctx = cli_context(&a.common);
    double t0 = cli_seconds();
    ibl_cubemap cube = {0}, result = {0};
    int rc = cli_read_cubemap(ctx, &a.common, in, &io, &cube, NULL);
    if (rc != CLI_EXIT_OK) {
        ibl_context_destroy(ctx);
        return rc;
    }
    double t_read = cli_seconds();
    ibl_specular_info info;
    ibl_status st = ibl_specular_prefilter(ctx, &cube, &d, &result, &info);
    double t_filter = cli_seconds();
    int flat = !ibl_file_type_is_container(out_type);
    if (st == IBL_OK && !flat) {
        ibl_texture t = ibl_texture_from_cubemap(&result);
        t.format = wd.format;
        st = ibl_specular_set_metadata(ctx, &info, &t);
        t.owns_metadata = 1;
        if (st == IBL_OK) st = ibl_write_texture(ctx, out_path, &t, &wd);
        t.owns_data = 0;
        ibl_texture_free(ctx, &t);
    } else if (st == IBL_OK) {
        char stem[4096], path[4200];
        const char *ext;
        split_ext(out_path, stem, sizeof stem, &ext);
        for (int l = 0; st == IBL_OK && l < result.levels; l++) {
            ibl_image faces[6] = {{0}};
            st = ibl_cubemap_to_faces(ctx, &result, l, faces);
            for (int f = 0; f < 6; f++) {
                if (st == IBL_OK) {
                    snprintf(path, sizeof path, "%s_l%d_%s%s", stem, l, face_names[f], ext);
                    st = ibl_write_image(ctx, path, &faces[f], &wd);
                }
                ibl_image_free(ctx, &faces[f]);
            }
        }
    }
    if (st == IBL_OK) st = write_manifest(ctx, out_path, &info, flat);
    ibl_cubemap_free(ctx, &cube);
    ibl_cubemap_free(ctx, &result);
    if (st != IBL_OK) {
        cli_report_failure(ctx, in, st);
        ibl_context_destroy(ctx);
        return cli_exit_code(st) == CLI_EXIT_USAGE ? CLI_EXIT_BAD_INPUT : cli_exit_code(st);
    }
    double t1 = cli_seconds();
    cli_info(&a.common,
             "%s: %dx%dx6, %d levels, %s %s (%s mapping) in %.3f s (read %.3f, filter %.3f, "
             "write %.3f)\n",
             out_path, info.size, info.size, info.levels, ibl_specular_filter_name(info.filter),
             d.method == IBL_METHOD_REFERENCE ? "reference" : "fast",
             ibl_specular_mapping_name(info.mapping), t1 - t0, t_read - t0, t_filter - t_read,
             t1 - t_filter);
    ibl_context_destroy(ctx);
    return CLI_EXIT_OK;
}
